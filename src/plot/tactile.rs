//! The paper's Fig. 7 from one tactile map: in the sensor frame (mm, x
//! towards c35, y towards c13), each taxel a circle whose radius follows
//! its Δv, the centroids, the linear and the quadratic fit; on a
//! simulated cell also the true cable, the paper's Fig. 9 comparison.

use plotters::coord::Shift;
use plotters::prelude::{Circle, DrawingArea, DrawingBackend, LineSeries};
use plotters::style::Color;

use super::{
    Figure, LegendEntry, PadChart, PlotError, Sample, colour, draw_legend, drawing_error,
    line_in_square, titled_square, whole,
};
use crate::geometry::LineInSensor;
use crate::perception::tactile::map::{taxel_x_mm, taxel_y_mm};
use crate::perception::tactile::{
    Direction, FitConfig, FitError, TAXEL_COLS, TAXEL_ROWS, TactileMap, WireFit, fit_wire,
};

/// Width of the true cable's line, pixels: under the fits, visible around
/// them.
const TRUTH_WIDTH: u32 = 8;
/// A taxel without contact still shows, this small (pixels).
const MIN_RADIUS_PX: f64 = 2.0;
/// The largest circle's radius, in pitches: neighbours never touch.
const MAX_RADIUS_PITCH: f64 = 0.47;
/// Points along the quadratic fit.
const CURVE_POINTS: usize = 81;

/// A tactile map with the paper's fits of it, titled, ready to draw.
pub struct TactileFigure {
    title: String,
    map: TactileMap,
    pitch_mm: f64,
    /// The paper's fit of the map, or why there is none (no contact, say):
    /// the map is drawn all the same.
    fit: Result<WireFit, FitError>,
    truth: Option<LineInSensor>,
}

impl TactileFigure {
    /// The figure of `map`, fitted as the paper does with `config`; `truth`
    /// is where the cable really lay, when the cell knows. Refused only
    /// for a geometry that is not physical.
    pub fn new(
        map: TactileMap,
        config: &FitConfig,
        truth: Option<LineInSensor>,
        title: String,
    ) -> Result<Self, PlotError> {
        config
            .validate()
            .map_err(|source| PlotError::Config { source })?;
        Ok(Self {
            title,
            fit: fit_wire(&map, config),
            map,
            pitch_mm: config.pitch_mm,
            truth,
        })
    }

    /// The legend's rows, in drawing order.
    fn legend(&self) -> Vec<LegendEntry> {
        let line_text =
            |line: &LineInSensor| format!("n {:+.2} mm, α {:+.3} rad", line.n_mm, line.alpha_rad);
        let mut entries = vec![LegendEntry::new(
            Sample::Ring {
                colour: colour::TAXEL,
            },
            format!(
                "taxels c11…c55, radius ∝ Δv (peak {:.3} V)",
                self.map.peak_dv_v()
            ),
        )];
        match &self.fit {
            Ok(fit) => {
                let per = match fit.direction {
                    Direction::Horizontal => "one per column (eq. 5)",
                    Direction::Vertical => "one per row (eq. 6)",
                };
                entries.push(LegendEntry::new(
                    Sample::Dot {
                        colour: colour::CENTROID,
                    },
                    format!("centroids, {per}"),
                ));
                entries.push(LegendEntry::new(
                    Sample::Line {
                        colour: colour::TACTILE_LINEAR,
                        width: 3,
                    },
                    format!("linear fit (eq. 2): {}", line_text(&fit.line)),
                ));
                if let Some(q) = fit.quadratic {
                    let (along, across) = match fit.direction {
                        Direction::Horizontal => ("x", "y"),
                        Direction::Vertical => ("y", "x"),
                    };
                    entries.push(LegendEntry::new(
                        Sample::Line {
                            colour: colour::TACTILE_QUADRATIC,
                            width: 3,
                        },
                        format!(
                            "quadratic fit (eq. {}): {across} = {:.4} {along}² {:+.3} {along} {:+.2}",
                            if fit.direction == Direction::Horizontal { 3 } else { 4 },
                            q.a,
                            q.b,
                            q.c
                        ),
                    ));
                }
            }
            Err(error) => entries.push(LegendEntry::new(Sample::None, format!("no fit: {error}"))),
        }
        if let Some(truth) = &self.truth {
            entries.push(LegendEntry::new(
                Sample::Line {
                    colour: colour::TRUTH,
                    width: TRUTH_WIDTH,
                },
                format!("true cable: {}", line_text(truth)),
            ));
        }
        entries
    }
}

/// The quadratic fit over the pad as runs of points inside it (a curve
/// that leaves the pad and comes back is two runs).
fn quadratic_runs(fit: &WireFit, pad_mm: f64) -> Vec<Vec<(f64, f64)>> {
    let Some(q) = fit.quadratic else {
        return Vec::new();
    };
    let mut runs = vec![Vec::new()];
    for i in 0..CURVE_POINTS {
        let along = -pad_mm + 2.0 * pad_mm * i as f64 / (CURVE_POINTS - 1) as f64;
        let across = q.a * along * along + q.b * along + q.c;
        let point = match fit.direction {
            Direction::Horizontal => (along, across),
            Direction::Vertical => (across, along),
        };
        match runs.last_mut() {
            Some(run) if across.abs() <= pad_mm => run.push(point),
            Some(run) if !run.is_empty() => runs.push(Vec::new()),
            _ => {}
        }
    }
    runs.retain(|run| run.len() > 1);
    runs
}

impl Figure for TactileFigure {
    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<(), String> {
        let (chart_area, legend_area) = titled_square(area, &self.title)?;
        let pitch = self.pitch_mm;
        let decimals = |v: &f64| {
            if pitch >= 2.0 {
                whole(v)
            } else {
                format!("{v:.1}")
            }
        };
        let PadChart {
            mut chart,
            pad_mm,
            view_mm,
        } = PadChart::on(&chart_area, pitch, &decimals)?;
        if let Some(ends) = self.truth.and_then(|t| line_in_square(&t, view_mm)) {
            chart
                .draw_series(LineSeries::new(
                    ends,
                    colour::TRUTH.mix(0.6).stroke_width(TRUTH_WIDTH),
                ))
                .map_err(drawing_error)?;
        }
        let px_per_mm =
            f64::from(chart.backend_coord(&(1.0, 0.0)).0 - chart.backend_coord(&(0.0, 0.0)).0);
        let max_radius_px = MAX_RADIUS_PITCH * pitch * px_per_mm;
        let peak_v = self.map.peak_dv_v();
        let taxels = (0..TAXEL_ROWS).flat_map(|row| (0..TAXEL_COLS).map(move |col| (row, col)));
        chart
            .draw_series(taxels.map(|(row, col)| {
                let share = self.map.dv_v[row][col] / peak_v;
                let share = if share.is_finite() {
                    share.clamp(0.0, 1.0)
                } else {
                    0.0
                };
                let radius_px = (share * max_radius_px).max(MIN_RADIUS_PX).round() as u32;
                Circle::new(
                    (taxel_x_mm(col, pitch), taxel_y_mm(row, pitch)),
                    radius_px,
                    colour::TAXEL.mix(0.85).filled(),
                )
            }))
            .map_err(drawing_error)?;
        if let Ok(fit) = &self.fit {
            for run in quadratic_runs(fit, pad_mm) {
                chart
                    .draw_series(LineSeries::new(
                        run,
                        colour::TACTILE_QUADRATIC.stroke_width(3),
                    ))
                    .map_err(drawing_error)?;
            }
            if let Some(ends) = line_in_square(&fit.line, pad_mm) {
                chart
                    .draw_series(LineSeries::new(
                        ends,
                        colour::TACTILE_LINEAR.stroke_width(3),
                    ))
                    .map_err(drawing_error)?;
            }
            chart
                .draw_series(
                    fit.centroids
                        .iter()
                        .map(|c| Circle::new((c.x_mm, c.y_mm), 5, colour::CENTROID.filled())),
                )
                .map_err(drawing_error)?;
        }
        draw_legend(&legend_area, &self.legend())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_curve_leaving_the_pad_is_cut_into_runs() {
        let map = TactileMap::from_fn(|row, _| if row == 2 { 0.5 } else { 0.0 });
        let mut fit = fit_wire(&map, &FitConfig::default()).unwrap();
        // A U that leaves the pad's top in the middle.
        fit.quadratic = Some(crate::perception::tactile::Quadratic {
            a: -0.2,
            b: 0.0,
            c: 12.0,
        });
        let runs = quadratic_runs(&fit, 8.875);
        assert_eq!(runs.len(), 2, "{runs:?}");
        assert!(runs.iter().flatten().all(|(_, y)| y.abs() <= 8.875));
        fit.quadratic = None;
        assert!(quadratic_runs(&fit, 8.875).is_empty());
    }
}
