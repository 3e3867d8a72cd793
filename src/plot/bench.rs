//! The bench's figure: each setting's error against its cost, the Pareto
//! front (the settings no other beats on both) joined by a line.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::{Axes, Figure, chart, colour, drawing_error};

/// One setting on the figure.
pub struct ParetoPoint {
    pub label: String,
    pub cost: f64,
    pub error: f64,
    pub on_front: bool,
}

/// Error against cost, front joined.
pub struct ParetoFigure {
    pub title: String,
    pub cost_desc: String,
    pub error_desc: String,
    pub points: Vec<ParetoPoint>,
}

/// `values`' range widened by a tenth on each side (and to 1 when flat),
/// so no point sits on an axis.
fn padded(values: impl Iterator<Item = f64> + Clone) -> std::ops::Range<f64> {
    let low = values.clone().fold(f64::INFINITY, f64::min);
    let high = values.fold(f64::NEG_INFINITY, f64::max);
    if !low.is_finite() || !high.is_finite() {
        return 0.0..1.0;
    }
    let pad = ((high - low) * 0.1).max(1e-3 * high.abs()).max(1e-9);
    (low - pad).min(0.0_f64.max(low - pad))..high + pad
}

impl Figure for ParetoFigure {
    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<(), String> {
        let below = area
            .titled(&self.title, (super::FONT, super::TITLE_SIZE))
            .map_err(drawing_error)?;
        let label = |v: &f64| format!("{v:.2}");
        let mut chart = chart(
            &below,
            &Axes {
                x: padded(self.points.iter().map(|p| p.cost)),
                y: padded(self.points.iter().map(|p| p.error)),
                x_desc: &self.cost_desc,
                y_desc: &self.error_desc,
                x_label: &label,
                y_label: &label,
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
        for point in &self.points {
            let style = if point.on_front {
                colour::FUSED.filled()
            } else {
                colour::TRUTH.filled()
            };
            chart
                .draw_series(std::iter::once(Circle::new(
                    (point.cost, point.error),
                    5,
                    style,
                )))
                .map_err(drawing_error)?;
            chart
                .draw_series(std::iter::once(Text::new(
                    point.label.clone(),
                    (point.cost, point.error),
                    (super::FONT, super::TICK_SIZE),
                )))
                .map_err(drawing_error)?;
        }
        Ok(())
    }
}
