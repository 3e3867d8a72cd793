//! The paper's Fig. 12 from a recorded grasp: in the pad's plane at the
//! grasp (x along the pad from its centre, y across it, mm), the vision
//! shape, the pad's linear and quadratic fits (and the ridge's line), the
//! fused shape, and on a simulated cell the true cable, with the grasped
//! stretch shaded and each shape's distance to the truth in the legend.

use nalgebra::Point3;
use plotters::coord::Shift;
use plotters::prelude::{
    DrawingArea, DrawingBackend, IntoFont, LineSeries, PathElement, Rectangle, SeriesLabelPosition,
};
use plotters::style::{Color, RGBColor, ShapeStyle};

use super::{
    Axes, FONT, Figure, LABEL_SIZE, PlotError, TITLE_SIZE, chart, colour, drawing_error, whole,
};
use crate::perception::shape::{BEYOND_PAD_MM, ShapePoint, StretchErrors};
use crate::record::{GraspShapes, TactileShape};

/// Drawn beyond the measured stretch on either side, mm.
const MARGIN_MM: f64 = 10.0;

/// A grasp's shapes, titled, ready to draw.
pub struct FusionFigure {
    title: String,
    pad_half_side_mm: f64,
    /// How far along the pad's x the figure reaches each way.
    reach_mm: f64,
    /// The range across, room for the legend included.
    y_range_mm: (f64, f64),
    curves: Vec<Curve>,
}

/// One curve of the figure.
struct Curve {
    label: String,
    colour: RGBColor,
    width: u32,
    points: Vec<(f64, f64)>,
}

impl FusionFigure {
    /// The figure of `shapes`; refused if no shape comes near the pad.
    pub fn new(shapes: &GraspShapes, title: String) -> Result<Self, PlotError> {
        let reach_mm = shapes.pad_half_side_mm + BEYOND_PAD_MM + MARGIN_MM;
        let mut curves = curves(shapes);
        for curve in &mut curves {
            curve.points.retain(|(x, _)| x.abs() <= reach_mm);
        }
        curves.retain(|curve| !curve.points.is_empty());
        let across = curves.iter().flat_map(|c| c.points.iter()).map(|&(_, y)| y);
        let low = across.clone().fold(f64::INFINITY, f64::min);
        let high = across.fold(f64::NEG_INFINITY, f64::max);
        if curves.is_empty() {
            return Err(PlotError::Empty(
                "the grasp has no shape within reach of the pad".into(),
            ));
        }
        // Room for the legend above the curves.
        let margin = (0.15 * (high - low)).max(0.5);
        Ok(Self {
            title,
            pad_half_side_mm: shapes.pad_half_side_mm,
            reach_mm,
            y_range_mm: (low - margin, high + (high - low).max(1.0) + margin),
            curves,
        })
    }
}

/// The curves of `shapes` in the pad's plane, in drawing order (the truth
/// below the rest, the fused shape on top), each shape's label with its
/// distances to the truth when they are known.
fn curves(shapes: &GraspShapes) -> Vec<Curve> {
    let sensor_from_base = shapes.base_from_sensor.inverse();
    let in_plane = |points: &mut dyn Iterator<Item = Point3<f64>>| -> Vec<(f64, f64)> {
        points
            .map(|p| {
                let p = sensor_from_base * p;
                (p.x, p.y)
            })
            .collect()
    };
    let mut curves = Vec::new();
    if let Some(truth) = &shapes.truth {
        curves.push(Curve {
            label: "true cable".into(),
            colour: colour::TRUTH,
            width: 5,
            points: in_plane(&mut truth.iter().copied()),
        });
    }
    let errors = shapes.errors.as_ref();
    let mut add = |label: &str,
                   colour: RGBColor,
                   width: u32,
                   shape: &Option<Vec<ShapePoint>>,
                   error: Option<StretchErrors>| {
        let Some(shape) = shape else { return };
        curves.push(Curve {
            label: match error {
                Some(error) => format!("{label}  {}", errors_text(&error)),
                None => label.to_owned(),
            },
            colour,
            width,
            points: in_plane(&mut shape.iter().map(|p| p.in_base_mm)),
        });
    };
    let vision = errors.and_then(|e| e.vision);
    add("vision (camera)", colour::VISION, 2, &shapes.vision, vision);
    let linear = errors.and_then(|e| e.tactile_linear);
    add(
        "touch: linear fit",
        colour::TACTILE_LINEAR,
        3,
        &shapes.tactile_linear,
        linear,
    );
    let quadratic = errors.and_then(|e| e.tactile_quadratic);
    add(
        "touch: quadratic fit",
        colour::TACTILE_QUADRATIC,
        3,
        &shapes.tactile_quadratic,
        quadratic,
    );
    let ridge = errors.and_then(|e| e.tactile_ridge);
    add(
        "touch: ridge line",
        colour::TACTILE_RIDGE,
        3,
        &shapes.tactile_ridge,
        ridge,
    );
    let fused_from = match shapes.fused_from {
        Some(TactileShape::Linear) => "linear fit",
        Some(TactileShape::Quadratic) => "quadratic fit",
        Some(TactileShape::Ridge) => "ridge line",
        None => "",
    };
    let fused = errors.and_then(|e| e.fused);
    add(
        &format!("fused: vision + {fused_from}"),
        colour::FUSED,
        2,
        &shapes.fused,
        fused,
    );
    curves
}

/// "0.05 | 0.13 mm": mean distance to the truth on the pad and beyond.
fn errors_text(errors: &StretchErrors) -> String {
    let mm = |d: Option<crate::perception::shape::Distances>| {
        d.map_or("–".to_owned(), |d| format!("{:.2}", d.mean_mm))
    };
    format!("{} | {} mm", mm(errors.grasped), mm(errors.beyond))
}

impl Figure for FusionFigure {
    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<(), String> {
        let (half_mm, reach_mm) = (self.pad_half_side_mm, self.reach_mm);
        let (y_low, y_high) = self.y_range_mm;
        // As few decimals as the range allows.
        let decimals = if y_high - y_low > 10.0 { 0 } else { 1 };

        let below = area
            .titled(&self.title, (FONT, TITLE_SIZE).into_font())
            .map_err(drawing_error)?;
        let y_label = |y: &f64| format!("{y:.decimals$}");
        let mut chart = chart(
            &below,
            &Axes {
                x: -reach_mm..reach_mm,
                y: y_low..y_high,
                x_desc: "along the pad's x, from its centre (mm)",
                y_desc: "across, in the pad's plane (mm)",
                x_label: &whole,
                y_label: &y_label,
                x_ticks: 10,
            },
        )?;
        chart
            .draw_series([Rectangle::new(
                [(-half_mm, y_low), (half_mm, y_high)],
                colour::REGION.mix(0.7).filled(),
            )])
            .map_err(drawing_error)?
            .label(format!(
                "the pad; each curve's mean distance to the true cable on it | up to {BEYOND_PAD_MM:.0} mm beyond"
            ))
            .legend(|(x, y)| Rectangle::new([(x, y - 6), (x + 20, y + 6)], colour::REGION.filled()));
        for curve in &self.curves {
            let style = ShapeStyle::from(curve.colour).stroke_width(curve.width);
            chart
                .draw_series(LineSeries::new(curve.points.iter().copied(), style))
                .map_err(drawing_error)?
                .label(&curve.label)
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], style));
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .label_font((FONT, LABEL_SIZE))
            .background_style(super::BACKGROUND.mix(0.85))
            .border_style(colour::TRUTH.mix(0.5))
            .draw()
            .map_err(drawing_error)?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::{Isometry3, Translation3, UnitQuaternion};
    use opencv::core::Vec3b;
    use opencv::prelude::*;

    use super::*;
    use crate::perception::shape::Distances;
    use crate::plot::save;
    use crate::record::ShapeErrors;

    /// A sagging cable seen 0.6 mm high, felt where it is, fused, and true;
    /// the pad at (450, 0, 250) facing base y, its x along base x.
    fn shapes() -> GraspShapes {
        let base_from_sensor = Isometry3::from_parts(
            Translation3::new(450.0, 0.0, 250.0),
            UnitQuaternion::from_axis_angle(
                &nalgebra::Vector3::x_axis(),
                std::f64::consts::FRAC_PI_2,
            ),
        );
        let line = |from: i32, to: i32, y: &dyn Fn(f64) -> f64, sigma_mm: f64| {
            Some(
                (from..=to)
                    .map(|x| {
                        let x = f64::from(x);
                        ShapePoint {
                            in_base_mm: base_from_sensor * Point3::new(x, y(x), 0.0),
                            sigma_mm,
                        }
                    })
                    .collect::<Vec<_>>(),
            )
        };
        let sag = |x: f64| 0.002 * x * x;
        let stretch = StretchErrors {
            grasped: Some(Distances {
                mean_mm: 0.05,
                max_mm: 0.1,
            }),
            beyond: Some(Distances {
                mean_mm: 0.2,
                max_mm: 0.4,
            }),
        };
        GraspShapes {
            base_from_sensor,
            pad_half_side_mm: 8.875,
            vision: line(-75, 75, &|x| sag(x) + 0.6, 0.5),
            tactile_linear: line(-8, 8, &|_| 0.05, 0.2),
            tactile_quadratic: line(-8, 8, &sag, 0.2),
            tactile_ridge: None,
            fused_from: Some(TactileShape::Quadratic),
            fused: line(
                -75,
                75,
                &|x| sag(x) + 0.3 * (1.0 - (-x * x / 400.0).exp()),
                0.1,
            ),
            truth: line(-75, 75, &sag, 0.0)
                .map(|points| points.iter().map(|p| p.in_base_mm).collect()),
            errors: Some(ShapeErrors {
                beyond_mm: BEYOND_PAD_MM,
                vision: Some(stretch),
                tactile_linear: Some(stretch),
                tactile_quadratic: Some(stretch),
                tactile_ridge: None,
                fused: Some(stretch),
            }),
        }
    }

    fn figure(shapes: &GraspShapes) -> FusionFigure {
        FusionFigure::new(shapes, "Vision and touch fused at the trial grasp".into()).unwrap()
    }

    #[test]
    fn the_svg_holds_every_curve_and_its_legend() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("fusion.svg");
        let shapes = shapes();
        save(&figure(&shapes), &path).unwrap();
        let svg = std::fs::read_to_string(&path).unwrap();
        // Five curves, each with its legend's sample line.
        assert!(svg.matches("<polyline").count() >= 5, "{svg}");
        for text in [
            "true cable",
            "vision (camera)  0.05 | 0.20 mm",
            "touch: linear fit",
            "touch: quadratic fit",
            "fused: vision + quadratic fit",
            "Vision and touch fused at the trial grasp",
            "along the pad&apos;s x, from its centre (mm)",
        ] {
            assert!(svg.contains(text), "no {text:?} in the SVG");
        }
        assert!(!svg.contains("touch: ridge line"));
        // Each curve in its colour.
        for colour in [colour::VISION, colour::FUSED, colour::TACTILE_QUADRATIC] {
            let RGBColor(r, g, b) = colour;
            let hex = format!("#{r:02X}{g:02X}{b:02X}");
            assert!(svg.contains(&hex), "no {hex} in the SVG");
        }
    }

    #[test]
    fn the_png_has_its_size_and_shows_the_curves() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("fusion.png");
        let shapes = shapes();
        save(&figure(&shapes), &path).unwrap();
        let image =
            opencv::imgcodecs::imread(path.to_str().unwrap(), opencv::imgcodecs::IMREAD_COLOR)
                .unwrap();
        assert_eq!((image.cols(), image.rows()), (1000, 620));
        // Not blank: the fused curve's red is drawn, and text in black-ish
        // grey.
        let (mut red, mut dark) = (0, 0);
        for row in 0..image.rows() {
            for col in 0..image.cols() {
                let [b, g, r] = image.at_2d::<Vec3b>(row, col).unwrap().0;
                let RGBColor(fr, fg, fb) = colour::FUSED;
                if (r, g, b) == (fr, fg, fb) {
                    red += 1;
                }
                if r < 80 && g < 80 && b < 80 {
                    dark += 1;
                }
            }
        }
        assert!(red > 200, "{red} red pixels");
        assert!(dark > 1000, "{dark} dark pixels: no text?");
    }

    #[test]
    fn a_grasp_without_shapes_near_the_pad_is_refused() {
        let mut shapes = shapes();
        for shape in [
            &mut shapes.vision,
            &mut shapes.tactile_linear,
            &mut shapes.tactile_quadratic,
            &mut shapes.fused,
        ] {
            *shape = None;
        }
        shapes.truth = None;
        let error = FusionFigure::new(&shapes, String::new()).err().unwrap();
        assert!(matches!(error, PlotError::Empty(_)), "{error}");
    }
}
