//! The paper's Fig. 11 from a run: the cable on the pad (a line in the
//! pad's plane, sensor frame, mm) as the pad's fit found it at the trial
//! grasp and after each regrasp, on a simulated cell where it really lay,
//! and the target pose the regrasps aim at with its tolerance.

use plotters::coord::Shift;
use plotters::prelude::{DashedLineSeries, DrawingArea, DrawingBackend, LineSeries};
use plotters::style::Color;

use super::{
    Figure, LegendEntry, PadChart, PlotError, Sample, colour, draw_legend, drawing_error,
    line_in_square, titled_square, whole,
};
use crate::geometry::{LineInSensor, PoseError};

/// Width of each grasp's fitted line, pixels; its true line is thinner
/// and dashed.
pub const FIT_WIDTH: u32 = 3;
const TRUTH_WIDTH: u32 = 2;

/// One grasp's cable on the pad.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GraspLines {
    /// 0 for the trial grasp, k for the k-th regrasp.
    pub attempt: u32,
    /// The pad's estimate; `None` if its fit failed.
    pub estimate: Option<LineInSensor>,
    /// Where the cable really lay (simulated cells).
    pub truth: Option<LineInSensor>,
}

/// A run's grasps with the target pose, titled, ready to draw.
pub struct RegraspFigure {
    title: String,
    pitch_mm: f64,
    target: LineInSensor,
    tolerance: PoseError,
    grasps: Vec<GraspLines>,
}

impl RegraspFigure {
    /// The figure of `grasps` (in order) against `target`; refused if no
    /// grasp has a line to draw.
    pub fn new(
        grasps: Vec<GraspLines>,
        target: LineInSensor,
        tolerance: PoseError,
        pitch_mm: f64,
        title: String,
    ) -> Result<Self, PlotError> {
        if !grasps
            .iter()
            .any(|g| g.estimate.is_some() || g.truth.is_some())
        {
            return Err(PlotError::Empty(
                "no grasp of the run has a fitted or a true line".into(),
            ));
        }
        Ok(Self {
            title,
            pitch_mm,
            target,
            tolerance,
            grasps,
        })
    }
}

/// "trial grasp", "regrasp k".
pub fn grasp_name(attempt: u32) -> String {
    match attempt {
        0 => "trial grasp".to_owned(),
        k => format!("regrasp {k}"),
    }
}

fn line_text(line: &LineInSensor) -> String {
    format!("n {:+.2} mm, α {:+.3} rad", line.n_mm, line.alpha_rad)
}

impl Figure for RegraspFigure {
    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<(), String> {
        let (chart_area, legend_area) = titled_square(area, &self.title)?;
        let PadChart {
            mut chart,
            pad_mm,
            view_mm,
        } = PadChart::on(&chart_area, self.pitch_mm, &whole)?;
        let mut legend = vec![LegendEntry::new(
            Sample::Line {
                colour: colour::TARGET,
                width: 2,
            },
            format!("target: {}", line_text(&self.target)),
        )];
        if let Some(ends) = line_in_square(&self.target, view_mm) {
            chart
                .draw_series(LineSeries::new(ends, colour::TARGET.stroke_width(2)))
                .map_err(drawing_error)?;
        }
        legend.push(LegendEntry::new(
            Sample::Dashed {
                colour: colour::TRUTH,
                width: 1,
            },
            format!(
                "tolerance: |n| ≤ {:.2} mm (and |α| ≤ {:.3} rad)",
                self.tolerance.n_mm, self.tolerance.alpha_rad
            ),
        ));
        for side in [-1.0, 1.0] {
            let edge = LineInSensor::new(
                self.target.alpha_rad,
                self.target.n_mm + side * self.tolerance.n_mm,
            );
            if let Some(ends) = line_in_square(&edge, view_mm) {
                chart
                    .draw_series(DashedLineSeries::new(
                        ends,
                        6,
                        4,
                        colour::TRUTH.stroke_width(1),
                    ))
                    .map_err(drawing_error)?;
            }
        }
        for (i, grasp) in self.grasps.iter().enumerate() {
            let grasp_colour = colour::nth(&colour::GRASPS, i);
            let name = grasp_name(grasp.attempt);
            if let Some(ends) = grasp.truth.and_then(|t| line_in_square(&t, view_mm)) {
                chart
                    .draw_series(DashedLineSeries::new(
                        ends,
                        10,
                        6,
                        grasp_colour.stroke_width(TRUTH_WIDTH),
                    ))
                    .map_err(drawing_error)?;
            }
            if let Some(ends) = grasp.estimate.and_then(|e| line_in_square(&e, pad_mm)) {
                chart
                    .draw_series(LineSeries::new(ends, grasp_colour.stroke_width(FIT_WIDTH)))
                    .map_err(drawing_error)?;
            }
            legend.push(LegendEntry::new(
                Sample::Line {
                    colour: grasp_colour,
                    width: FIT_WIDTH,
                },
                match &grasp.estimate {
                    Some(line) => format!("{name}, the pad's fit: {}", line_text(line)),
                    None => format!("{name}: the pad's fit failed"),
                },
            ));
            if let Some(truth) = &grasp.truth {
                legend.push(LegendEntry::new(
                    Sample::Dashed {
                        colour: grasp_colour,
                        width: TRUTH_WIDTH,
                    },
                    format!("{name}, the true cable: {}", line_text(truth)),
                ));
            }
        }
        draw_legend(&legend_area, &legend)
    }
}
