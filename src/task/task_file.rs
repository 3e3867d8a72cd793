//! The task file: what the cell is asked to do.

use serde::Deserialize;

use crate::geometry::{CorrectionGain, LineInSensor, PoseError};
use crate::perception::tactile::Estimator;
use crate::perception::tactile::search::Prior;
use crate::schema::FrameConfig;
use crate::schema::validate::{angle_spread, at_least_one, finite, line_angle, moves, positive};

/// A task file, e.g. `tasks/regrasp.toml`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TaskFile {
    pub task: TaskSection,
    /// The cable pose on the pad wanted at the end.
    pub target: PoseOnPad,
    /// How far from the target a grasp may end and still succeed.
    pub tolerance: Tolerance,
    pub approach: Approach,
    pub grasp: Grasp,
    pub regrasp: Regrasp,
    pub tactile: TactileEvaluation,
    /// Where the cable roughly lies: without it a run the camera cannot
    /// help fails; with it the run searches by touch.
    #[serde(default)]
    pub prior: Option<PriorTable>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TaskSection {
    pub name: String,
    #[serde(default)]
    pub description: String,
    /// Seed of the simulated cell's randomness; `--seed` overrides it.
    #[serde(default)]
    pub seed: Option<u64>,
    /// Search by touch from the `[prior]` without looking (for
    /// experiments: the paper's tactile-only case).
    #[serde(default)]
    pub touch_only: bool,
}

/// The cable's rough grasp frame and its uncertainty, for a search by
/// touch when the camera cannot place the cable.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PriorTable {
    /// In the base frame, as a detector gives it: x along the cable, y
    /// across it on the side the hand comes from, z the closing axis.
    pub base_from_cable: FrameConfig,
    /// σ of the cable's position across it (the frame's y).
    #[serde(deserialize_with = "positive")]
    pub position_sigma_mm: f64,
    /// σ of its direction about the closing axis (the frame's z).
    #[serde(deserialize_with = "angle_spread")]
    pub angle_sigma_rad: f64,
    /// Grasps the search may make, the first at the prior's mean included.
    #[serde(deserialize_with = "moves")]
    pub max_search_moves: usize,
}

impl PriorTable {
    pub fn prior(&self) -> Prior {
        Prior {
            base_from_cable: self.base_from_cable.isometry(),
            position_sigma_mm: self.position_sigma_mm,
            angle_sigma_rad: self.angle_sigma_rad,
            max_moves: self.max_search_moves,
        }
    }
}

/// A cable pose on the pad in the paper's sensor frame.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PoseOnPad {
    #[serde(deserialize_with = "finite")]
    pub n_mm: f64,
    #[serde(deserialize_with = "line_angle")]
    pub alpha_rad: f64,
}

impl PoseOnPad {
    pub fn line(&self) -> LineInSensor {
        LineInSensor::new(self.alpha_rad, self.n_mm)
    }
}

#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Tolerance {
    #[serde(deserialize_with = "positive")]
    pub n_mm: f64,
    #[serde(deserialize_with = "positive")]
    pub alpha_rad: f64,
}

impl Tolerance {
    pub fn as_error_bound(&self) -> PoseError {
        PoseError {
            n_mm: self.n_mm,
            alpha_rad: self.alpha_rad,
        }
    }
}

#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Approach {
    /// Distance back from the grasp pose, along the approach axis, at which
    /// the arm stops before descending onto the cable.
    #[serde(deserialize_with = "positive")]
    pub standoff_mm: f64,
    /// Cartesian speed of every arm motion of the task.
    #[serde(deserialize_with = "positive")]
    pub speed_mm_s: f64,
}

#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Grasp {
    /// Jaw opening before closing on the cable.
    #[serde(deserialize_with = "positive")]
    pub open_mm: f64,
    /// Motor current of the gripper's grip command (PG70 MOVE_GRIP).
    #[serde(deserialize_with = "positive")]
    pub grip_current_a: f64,
}

#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Regrasp {
    /// Regrasps allowed after the trial grasp (the paper makes one).
    pub max_regrasps: u32,
    /// How far the open fingers back off along the approach axis before
    /// moving by T_corr, so that they do not drag the cable.
    #[serde(deserialize_with = "positive")]
    pub retreat_mm: f64,
    /// How much of T_corr each regrasp applies (default: all of it, as the
    /// paper does); above 1 it makes up for a cable that springs back.
    #[serde(default = "paper_gain")]
    pub correction_gain: CorrectionGain,
}

fn paper_gain() -> CorrectionGain {
    CorrectionGain::PAPER
}

#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TactileEvaluation {
    /// Frames averaged for the bias (the paper: the first 50).
    #[serde(deserialize_with = "at_least_one")]
    pub bias_samples: usize,
    /// Frames averaged for each evaluation of a grasp.
    #[serde(deserialize_with = "at_least_one")]
    pub average_frames: usize,
    /// Peak Δv below which the pad is taken to touch nothing.
    #[serde(deserialize_with = "positive")]
    pub contact_threshold_v: f64,
    /// `centroids` (the paper's) or `ridge` (cablecell's).
    pub estimator: Estimator,
}
