//! The task file: what the cell is asked to do.

use serde::{Deserialize, Deserializer};

use crate::geometry::{CorrectionGain, LineInSensor, PoseError};
use crate::hw::gripper::config::{GRIP_CURRENT_A, OPENING_MM};
use crate::perception::tactile::search::Prior;
use crate::perception::tactile::{CONTACT_THRESHOLD_V, Estimator};
use crate::schema::FrameConfig;
use crate::schema::validate::{angle_spread, finite, line_angle, moves, positive, within};

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
    #[serde(deserialize_with = "travel_mm")]
    pub standoff_mm: f64,
    /// Cartesian speed of every arm motion of the task.
    #[serde(deserialize_with = "positive")]
    pub speed_mm_s: f64,
}

#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Grasp {
    /// Jaw opening before closing on the cable.
    #[serde(deserialize_with = "open_mm")]
    pub open_mm: f64,
    /// Motor current of the gripper's grip command (PG70 MOVE_GRIP).
    #[serde(deserialize_with = "grip_current_a")]
    pub grip_current_a: f64,
}

#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Regrasp {
    /// Regrasps allowed after the trial grasp (the paper makes one).
    #[serde(deserialize_with = "regrasp_count")]
    pub max_regrasps: u32,
    /// How far the open fingers back off along the approach axis before
    /// moving by T_corr, so that they do not drag the cable.
    #[serde(deserialize_with = "travel_mm")]
    pub retreat_mm: f64,
    /// How much of T_corr each regrasp applies (default: all of it, as the
    /// paper does); above 1 it makes up for a cable that springs back.
    #[serde(
        default = "paper_gain",
        deserialize_with = "CorrectionGainInFile::deserialize"
    )]
    pub correction_gain: CorrectionGain,
}

fn paper_gain() -> CorrectionGain {
    CorrectionGain::PAPER
}

/// 0 to 100 regrasps: the correction converges in one or two, and each
/// regrasp's maps and fits stay in the run's record.
pub(crate) fn regrasp_count<'de, D: Deserializer<'de>>(d: D) -> Result<u32, D::Error> {
    within(d, 0..=100, "regrasps")
}

/// A correction gain as a file writes it, `{ n = …, alpha = … }`.
#[derive(Deserialize)]
#[serde(remote = "CorrectionGain", deny_unknown_fields)]
struct CorrectionGainInFile {
    #[serde(deserialize_with = "gain")]
    n: f64,
    #[serde(deserialize_with = "gain")]
    alpha: f64,
}

/// 0 to 2: a regrasp with gain g leaves 1 − g of the error it corrects, so
/// 0 corrects nothing, 1 is the paper's whole T_corr, and beyond 2 each
/// regrasp overshoots by more than the error and repeated regrasps diverge.
fn gain<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    within(d, 0.0..=2.0, "")
}

/// An optional correction gain (a campaign's policy), checked as the task
/// file's.
pub(crate) fn optional_correction_gain<'de, D: Deserializer<'de>>(
    d: D,
) -> Result<Option<CorrectionGain>, D::Error> {
    CorrectionGainInFile::deserialize(d).map(Some)
}

#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TactileEvaluation {
    /// Frames averaged for the bias (the paper: the first 50).
    #[serde(deserialize_with = "frame_count")]
    pub bias_samples: usize,
    /// Frames averaged for each evaluation of a grasp.
    #[serde(deserialize_with = "frame_count")]
    pub average_frames: usize,
    /// Peak Δv below which the pad is taken to touch nothing.
    #[serde(deserialize_with = "contact_threshold_v")]
    pub contact_threshold_v: f64,
    /// `centroids` (the paper's) or `ridge` (cablecell's).
    pub estimator: Estimator,
}

/// 1 to 1000 frames: 2 s at the paper's 500 Hz (it averages 10 and 50),
/// 10 s at the slowest polling rate a cell file allows.
fn frame_count<'de, D: Deserializer<'de>>(d: D) -> Result<usize, D::Error> {
    within(d, 1..=1000, "frames")
}

/// 1 to 500 mm of travel back from the cable: beyond half a metre the hand
/// leaves any cell's workspace.
fn travel_mm<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    within(d, 1.0..=500.0, "mm")
}

/// At least 1 mm (the thinnest cable) and within the PG70's stroke.
fn open_mm<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    within(d, 1.0..=*OPENING_MM.end(), "mm")
}

fn grip_current_a<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    within(d, GRIP_CURRENT_A, "A")
}

fn contact_threshold_v<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    within(d, CONTACT_THRESHOLD_V, "V")
}
