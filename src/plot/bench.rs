//! The bench's figure: one panel per comparison (the cell's settings,
//! the vision's on each set of images), each setting's error against its
//! cost, the Pareto front (the settings no other beats on both) joined by
//! a line. Points are numbered; the legend column names them, so that no
//! label covers another.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::{
    Axes, Figure, LegendEntry, Sample, TITLE_SIZE, chart, colour, draw_legend, drawing_error,
};

/// One setting on a panel.
pub struct ParetoPoint {
    pub label: String,
    pub cost: f64,
    pub error: f64,
    pub on_front: bool,
}

/// Error against cost, front joined.
pub struct ParetoPanel {
    /// Names the panel in the legend.
    pub title: String,
    pub cost_desc: String,
    pub error_desc: String,
    pub points: Vec<ParetoPoint>,
}

/// The panels stacked on the left, the legend on the right.
pub struct ParetoFigure {
    pub title: String,
    pub panels: Vec<ParetoPanel>,
}

/// Height of one panel, pixels.
const PANEL_HEIGHT: u32 = 380;
/// Width of the panels' column and of the legend's.
const PANELS_WIDTH: u32 = 860;
const LEGEND_WIDTH: u32 = 640;

/// A point's number's room, pixels.
const NUMBER_WIDTH: i32 = 24;
const NUMBER_HEIGHT: i32 = 18;

/// Where a point's number goes, its top left from the point, pixels: up
/// right, down right, up left, down left.
const NUMBER_PLACES: [(i32, i32); 4] = [(6, -20), (6, 4), (-28, -20), (-28, 4)];

/// Those places, then the same farther out, ring after ring.
fn number_places() -> impl Iterator<Item = (i32, i32)> {
    (0..6).flat_map(|ring| NUMBER_PLACES.map(|(x, y)| (x, y + y.signum() * ring * NUMBER_HEIGHT)))
}

/// Decimals that tell a range's ticks apart: two for a range of about 1,
/// one more for each tenth as short.
fn digits(range: &std::ops::Range<f64>) -> usize {
    let span = range.end - range.start;
    if span > 0.0 {
        (1.0 - span.log10()).ceil().clamp(0.0, 6.0) as usize
    } else {
        2
    }
}

/// `values`' range widened by a tenth on each side, and by at least a
/// twentieth of its top (to 1 when flat), so that no point sits on an axis
/// and a few points in a narrow range do not look far apart.
fn padded(values: impl Iterator<Item = f64> + Clone) -> std::ops::Range<f64> {
    let low = values.clone().fold(f64::INFINITY, f64::min);
    let high = values.fold(f64::NEG_INFINITY, f64::max);
    if !low.is_finite() || !high.is_finite() {
        return 0.0..1.0;
    }
    let pad = ((high - low) * 0.1).max(0.05 * high.abs()).max(1e-9);
    (low - pad).min(0.0_f64.max(low - pad))..high + pad
}

/// A point's colour: the front's or the rest's.
fn point_colour(point: &ParetoPoint) -> RGBColor {
    if point.on_front {
        colour::FUSED
    } else {
        colour::TRUTH
    }
}

impl ParetoPanel {
    /// Draws the panel on `area`, its points numbered from `first`.
    fn draw<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        first: usize,
    ) -> Result<(), String> {
        let (x, y) = (
            padded(self.points.iter().map(|p| p.cost)),
            padded(self.points.iter().map(|p| p.error)),
        );
        let (x_digits, y_digits) = (digits(&x), digits(&y));
        let mut chart = chart(
            area,
            &Axes {
                x,
                y,
                x_desc: &self.cost_desc,
                y_desc: &self.error_desc,
                x_label: &|v: &f64| format!("{v:.x_digits$}"),
                y_label: &|v: &f64| format!("{v:.y_digits$}"),
                x_ticks: 8,
            },
        )?;
        let mut front: Vec<(f64, f64)> = self
            .points
            .iter()
            .filter(|p| p.on_front)
            .map(|p| (p.cost, p.error))
            .collect();
        front.sort_by(|a, b| a.0.total_cmp(&b.0));
        chart
            .draw_series(LineSeries::new(front, colour::FUSED.stroke_width(2)))
            .map_err(drawing_error)?;
        // Where each number went, pixels: a number that would cover one
        // already drawn takes the next free place around its point.
        let mut placed: Vec<(i32, i32)> = Vec::new();
        for (k, point) in self.points.iter().enumerate() {
            let at = (point.cost, point.error);
            let (px, py) = chart.backend_coord(&at);
            let free = |offset: &(i32, i32)| {
                !placed.iter().any(|&(x, y)| {
                    (x - (px + offset.0)).abs() < NUMBER_WIDTH
                        && (y - (py + offset.1)).abs() < NUMBER_HEIGHT
                })
            };
            let offset = number_places().find(free).unwrap_or(NUMBER_PLACES[0]);
            placed.push((px + offset.0, py + offset.1));
            chart
                .draw_series(std::iter::once(Circle::new(
                    at,
                    5,
                    point_colour(point).filled(),
                )))
                .map_err(drawing_error)?;
            // The number up and right of its point, offset in pixels.
            let number = EmptyElement::at(at)
                + Text::new(
                    (first + k).to_string(),
                    offset,
                    (super::FONT, super::LABEL_SIZE),
                );
            chart
                .draw_series(std::iter::once(number))
                .map_err(drawing_error)?;
        }
        Ok(())
    }
}

impl Figure for ParetoFigure {
    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<(), String> {
        let below = area
            .titled(&self.title, (super::FONT, TITLE_SIZE))
            .map_err(drawing_error)?;
        let (panels_area, legend_area) = below.split_horizontally(PANELS_WIDTH);
        let rows = self.panels.len().max(1);
        let mut legend = Vec::new();
        let mut first = 1;
        for (panel, panel_area) in self.panels.iter().zip(panels_area.split_evenly((rows, 1))) {
            panel.draw(&panel_area, first)?;
            legend.push(LegendEntry::new(Sample::None, format!("{}:", panel.title)));
            for (k, point) in panel.points.iter().enumerate() {
                legend.push(LegendEntry::new(
                    Sample::Dot {
                        colour: point_colour(point),
                    },
                    format!("{} {}", first + k, point.label),
                ));
            }
            first += panel.points.len();
        }
        legend.push(LegendEntry::new(
            Sample::Line {
                colour: colour::FUSED,
                width: 2,
            },
            "the Pareto front (red points): no other is both cheaper and closer",
        ));
        draw_legend(&legend_area, &legend)
    }

    fn size(&self) -> (u32, u32) {
        let panels = self.panels.len().max(1) as u32;
        (PANELS_WIDTH + LEGEND_WIDTH, 40 + panels * PANEL_HEIGHT)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tick_labels_have_the_decimals_their_range_needs() {
        assert_eq!(digits(&(3.3..6.1)), 1);
        assert_eq!(digits(&(0.055..0.085)), 3);
        assert_eq!(digits(&(55.0..92.0)), 0);
        assert_eq!(digits(&(1.0..1.0)), 2);
    }

    #[test]
    fn points_are_numbered_on_the_panels_and_named_in_the_legend() {
        let point = |label: &str, cost, error, on_front| ParetoPoint {
            label: label.to_owned(),
            cost,
            error,
            on_front,
        };
        let figure = ParetoFigure {
            title: "bench".to_owned(),
            panels: vec![
                ParetoPanel {
                    title: "cell".to_owned(),
                    cost_desc: "s".to_owned(),
                    error_desc: "mm".to_owned(),
                    points: vec![
                        point("fast", 1.0, 2.0, true),
                        point("slow", 2.0, 3.0, false),
                    ],
                },
                ParetoPanel {
                    title: "vision".to_owned(),
                    cost_desc: "ms".to_owned(),
                    error_desc: "1 - DICE".to_owned(),
                    points: vec![point("network", 30.0, 0.1, true)],
                },
            ],
        };
        assert_eq!(figure.size(), (1500, 800));
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bench.svg");
        super::super::save(&figure, &path).unwrap();
        let svg = std::fs::read_to_string(&path).unwrap();
        // Each text on its own line of the SVG.
        for text in [
            "1",
            "2",
            "3",
            "1 fast",
            "2 slow",
            "3 network",
            "cell:",
            "vision:",
        ] {
            assert!(
                svg.lines().any(|line| line.trim() == text),
                "{text} missing"
            );
        }
    }
}
