//! The values of a run a breakpoint's condition may use, by name.

use crate::orchestrator::machine::State;
use crate::record::RunRecord;

/// The values of a run a condition may use, read from its record. A value
/// the run does not have yet (no grasp, no truth on a real cell) is
/// missing, and a condition that needs it is false.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RunValues {
    values: [Option<f64>; RunValues::NAMES.len()],
}

impl RunValues {
    /// Every name a condition may use, with `describe`'s meaning.
    pub const NAMES: [&'static str; 13] = [
        "n_mm",
        "alpha_rad",
        "error_n_mm",
        "error_alpha_rad",
        "true_n_mm",
        "true_alpha_rad",
        "true_error_n_mm",
        "true_error_alpha_rad",
        "peak_dv_v",
        "grasps",
        "regrasps",
        "search_moves",
        "t_s",
    ];

    /// What each name means, for `help`.
    pub fn describe(name: &str) -> &'static str {
        match name {
            "n_mm" => "the latest grasp's estimated offset of the cable on the pad",
            "alpha_rad" => "the latest grasp's estimated angle of the cable on the pad",
            "error_n_mm" | "error_alpha_rad" => "the latest estimate against the target",
            "true_n_mm" | "true_alpha_rad" => "where the cable really lies (simulated cells)",
            "true_error_n_mm" | "true_error_alpha_rad" => "the true pose against the target",
            "peak_dv_v" => "the largest Δv of the latest grasp's map (a search's miss included)",
            "grasps" => "grasps evaluated so far (trial grasp included)",
            "regrasps" => "regrasps started so far",
            "search_moves" => "grasps a search by touch made so far (touch-only runs)",
            "t_s" => "the cell's clock at the latest transition",
            _ => "",
        }
    }

    pub fn of(record: &RunRecord) -> Self {
        let grasp = record.latest_grasp();
        let line = grasp.and_then(|g| g.fit.as_ref()).map(|fit| fit.line());
        let error = grasp.and_then(|g| g.estimated_error);
        let truth = grasp.and_then(|g| g.truth.as_ref());
        let count = |state| record.transitions.iter().filter(|t| t.to == state).count();
        Self {
            values: [
                line.map(|l| l.n_mm),
                line.map(|l| l.alpha_rad),
                error.map(|e| e.n_mm),
                error.map(|e| e.alpha_rad),
                truth.map(|t| t.line.n_mm),
                truth.map(|t| t.line.alpha_rad),
                truth.map(|t| t.error.n_mm),
                truth.map(|t| t.error.alpha_rad),
                grasp.map(|g| g.map.peak_dv_v()),
                Some(record.grasps.len() as f64),
                Some(count(State::Regrasp {}.name()) as f64),
                record
                    .touch_only
                    .as_ref()
                    .map(|t| f64::from(t.search_moves)),
                Some(record.transitions.last().map_or(0.0, |t| t.t_s)),
            ],
        }
    }

    /// The value called `name`; `None` if unknown or missing.
    pub fn get(&self, name: &str) -> Option<f64> {
        let index = Self::NAMES.iter().position(|n| *n == name)?;
        self.values[index]
    }
}

#[cfg(test)]
impl RunValues {
    /// Values with `pairs` set and every other one missing.
    pub(super) fn with(pairs: &[(&str, f64)]) -> Self {
        let mut v = Self::default();
        for (name, value) in pairs {
            let index = Self::NAMES.iter().position(|n| n == name).unwrap();
            v.values[index] = Some(*value);
        }
        v
    }
}
