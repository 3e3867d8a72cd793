//! A campaign's grasps as distributions (the paper's Section IV-A
//! experiment): per policy, |n| and |α| of the true cable against the
//! target at the trial grasp and after each regrasp, as box plots with
//! every trial's point, the paper's means marked; the success rate with
//! its 95 % interval and the regrasps per trial in the legend.
//!
//! The numbers come ready from the caller (the campaign's own statistics),
//! so this draws and computes nothing of its own.

use plotters::coord::Shift;
use plotters::prelude::{
    Circle, DashedLineSeries, DrawingArea, DrawingBackend, PathElement, Rectangle,
};
use plotters::style::{Color, RGBColor};

use super::regrasp::grasp_name;
use super::{
    Axes, Chart, Figure, LegendEntry, PlotError, Sample, chart, colour, draw_legend, drawing_error,
};

/// The paper's mean errors (Section IV-A, 20 trials): |n| (mm) and |α|
/// (rad) at the trial grasp and after its one regrasp.
pub const PAPER_TRIAL_GRASP: (f64, f64) = (4.0, 0.32);
pub const PAPER_AFTER_REGRASP: (f64, f64) = (1.9, 0.11);

/// Share of a stage's slot the boxes of all policies take.
const GROUP_WIDTH: f64 = 0.8;

/// Values of one stage of one policy with their five-number summary.
#[derive(Debug, Clone, PartialEq)]
pub struct Spread {
    pub values: Vec<f64>,
    /// Least, first quartile, median, third quartile, greatest.
    pub five: [f64; 5],
}

/// A rate with its 95 % interval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SuccessRate {
    pub successes: usize,
    pub trials: usize,
    pub ci95: [f64; 2],
}

/// One policy's results.
#[derive(Debug, Clone, PartialEq)]
pub struct PolicyResults {
    pub policy: String,
    /// |n| (mm) at the trial grasp, then after each regrasp, over the
    /// trials that reached it; `None` where none did.
    pub n_mm: Vec<Option<Spread>>,
    /// |α| (rad), likewise.
    pub alpha_rad: Vec<Option<Spread>>,
    pub success: Option<SuccessRate>,
    /// Mean and greatest regrasps per trial.
    pub regrasps_mean_max: Option<(f64, f64)>,
}

/// A campaign's policies, titled, ready to draw.
pub struct CampaignFigure {
    title: String,
    policies: Vec<PolicyResults>,
    stages: usize,
}

impl CampaignFigure {
    /// The figure of `policies`; refused if no trial measured a grasp.
    pub fn new(policies: Vec<PolicyResults>, title: String) -> Result<Self, PlotError> {
        let stages = policies
            .iter()
            .map(|p| p.n_mm.len().max(p.alpha_rad.len()))
            .max()
            .unwrap_or(0);
        let measured = policies
            .iter()
            .any(|p| p.n_mm.iter().chain(&p.alpha_rad).any(Option::is_some));
        if !measured {
            return Err(PlotError::Empty(
                "no trial of the campaign measured a grasp".into(),
            ));
        }
        Ok(Self {
            title,
            policies,
            stages,
        })
    }

    /// One panel: the boxes of `pick` for every stage and policy, with the
    /// paper's mean (`reference` picks it from a pair) over the trial
    /// grasp and the first regrasp.
    fn panel<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        y_desc: &str,
        pick: fn(&PolicyResults) -> &[Option<Spread>],
        reference: fn((f64, f64)) -> f64,
        decimals: usize,
    ) -> Result<(), String> {
        let highest = self
            .policies
            .iter()
            .flat_map(|p| pick(p).iter().flatten())
            .map(|s| s.five[4])
            .fold(reference(PAPER_TRIAL_GRASP), f64::max);
        let stage_label = |x: &f64| {
            let stage = x.round();
            let on_stage = (x - stage).abs() < 1e-6 && stage >= 0.0;
            if on_stage && (stage as usize) < self.stages {
                grasp_name(stage as u32)
            } else {
                String::new()
            }
        };
        let y_label = |y: &f64| format!("{y:.decimals$}");
        let mut chart = chart(
            area,
            &Axes {
                x: -0.5..self.stages as f64 - 0.5,
                y: 0.0..highest * 1.08,
                x_desc: "",
                y_desc,
                x_label: &stage_label,
                y_label: &y_label,
                x_ticks: 2 * self.stages + 2,
            },
        )?;
        for (stage, paper) in [(0.0, PAPER_TRIAL_GRASP), (1.0, PAPER_AFTER_REGRASP)] {
            if stage < self.stages as f64 {
                let y = reference(paper);
                let half = GROUP_WIDTH / 2.0 + 0.05;
                chart
                    .draw_series(DashedLineSeries::new(
                        [(stage - half, y), (stage + half, y)],
                        10,
                        6,
                        colour::TARGET.stroke_width(2),
                    ))
                    .map_err(drawing_error)?;
            }
        }
        let slot = GROUP_WIDTH / self.policies.len().max(1) as f64;
        for (p, policy) in self.policies.iter().enumerate() {
            let policy_colour = colour::nth(&colour::POLICIES, p);
            for (stage, spread) in pick(policy).iter().enumerate() {
                let Some(spread) = spread else { continue };
                let x = stage as f64 - GROUP_WIDTH / 2.0 + slot * (p as f64 + 0.5);
                draw_box(&mut chart, spread, x, 0.3 * slot, policy_colour)?;
            }
        }
        Ok(())
    }
}

/// A box from the first to the third quartile with the median across,
/// whiskers to the least and greatest value, and every value as a dot
/// jittered across the box (deterministically: the same figure each time).
fn draw_box<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    spread: &Spread,
    x: f64,
    half_width: f64,
    box_colour: RGBColor,
) -> Result<(), String> {
    let [low, q1, median, q3, high] = spread.five;
    let (left, right) = (x - half_width, x + half_width);
    let cap = 0.5 * half_width;
    chart
        .draw_series([
            Rectangle::new([(left, q1), (right, q3)], box_colour.mix(0.2).filled()),
            Rectangle::new([(left, q1), (right, q3)], box_colour.stroke_width(2)),
        ])
        .map_err(drawing_error)?;
    chart
        .draw_series(
            [
                [(x, q3), (x, high)],
                [(x, q1), (x, low)],
                [(x - cap, high), (x + cap, high)],
                [(x - cap, low), (x + cap, low)],
            ]
            .map(|ends| PathElement::new(ends, box_colour.stroke_width(2))),
        )
        .map_err(drawing_error)?;
    chart
        .draw_series([PathElement::new(
            [(left, median), (right, median)],
            box_colour.stroke_width(4),
        )])
        .map_err(drawing_error)?;
    // The golden ratio's fractional parts spread the dots evenly.
    let jitter = |i: usize| ((i as f64 * 0.618_033_988_75).fract() * 2.0 - 1.0) * 0.8 * half_width;
    chart
        .draw_series(
            spread
                .values
                .iter()
                .enumerate()
                .map(|(i, &v)| Circle::new((x + jitter(i), v), 3, box_colour.mix(0.75).filled())),
        )
        .map_err(drawing_error)?;
    Ok(())
}

/// "18/20 = 90 % (95 % CI 70–97 %)".
fn success_text(success: &SuccessRate) -> String {
    let percent = |share: f64| 100.0 * share;
    format!(
        "{}/{} = {:.0} % (95 % CI {:.0}–{:.0} %)",
        success.successes,
        success.trials,
        percent(success.successes as f64 / success.trials.max(1) as f64),
        percent(success.ci95[0]),
        percent(success.ci95[1])
    )
}

impl Figure for CampaignFigure {
    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<(), String> {
        let below = area
            .titled(&self.title, (super::FONT, super::TITLE_SIZE))
            .map_err(drawing_error)?;
        let (_, height) = below.dim_in_pixel();
        // Each policy's line of text and the notes below the panels.
        let legend_px = (3 + self.policies.len()) as u32 * 36;
        let (panels, legend_area) = below.split_vertically(height.saturating_sub(legend_px));
        let (width, _) = panels.dim_in_pixel();
        let (left, right) = panels.split_horizontally(width / 2);
        self.panel(
            &left,
            "|n|, true against the target (mm)",
            |p| &p.n_mm,
            |m| m.0,
            1,
        )?;
        self.panel(
            &right,
            "|α|, true against the target (rad)",
            |p| &p.alpha_rad,
            |m| m.1,
            2,
        )?;
        let mut legend: Vec<LegendEntry> = self
            .policies
            .iter()
            .enumerate()
            .map(|(p, policy)| {
                let success = policy
                    .success
                    .as_ref()
                    .map_or("no trials".to_owned(), success_text);
                let regrasps = policy
                    .regrasps_mean_max
                    .map_or(String::new(), |(mean, max)| {
                        format!("; regrasps per trial {mean:.2} (at most {max:.0})")
                    });
                LegendEntry::new(
                    Sample::Patch {
                        colour: colour::nth(&colour::POLICIES, p),
                    },
                    format!("{}: success {success}{regrasps}", policy.policy),
                )
            })
            .collect();
        legend.push(LegendEntry::new(
            Sample::Dashed {
                colour: colour::TARGET,
                width: 2,
            },
            format!(
                "the paper's means: {:.1} mm, {:.2} rad at the trial grasp; {:.1} mm, {:.2} rad after its regrasp",
                PAPER_TRIAL_GRASP.0, PAPER_TRIAL_GRASP.1, PAPER_AFTER_REGRASP.0, PAPER_AFTER_REGRASP.1
            ),
        ));
        legend.push(LegendEntry::new(
            Sample::None,
            "boxes: quartiles and median; whiskers: least to greatest; dots: the trials",
        ));
        draw_legend(&legend_area, &legend)
    }
}
