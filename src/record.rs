//! The run record: everything a run did, kept as it happens so that a run
//! that ends in a fault still has all it recorded up to the fault.

use nalgebra::{Isometry3, Point3};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::geometry::{LineInSensor, PoseError, PoseMm, pose_mm};
use crate::hw::DeviceKind;
use crate::perception::shape::{ShapePoint, StretchErrors};
use crate::perception::tactile::{Estimate, TactileMap};
use crate::perception::vision::VisionSkip;

#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct RunRecord {
    pub task: String,
    pub cell: String,
    pub seed: u64,
    pub target: LineInSensor,
    pub tolerance: PoseError,
    /// Every state change, logged by the machine's transition hook.
    pub transitions: Vec<TransitionRecord>,
    /// The trial grasp, then each regrasp.
    pub grasps: Vec<GraspRecord>,
    /// How the run ended; `None` while it runs.
    pub outcome: Option<RunOutcome>,
    /// Devices that could not be made safe after a fault.
    pub safe_stop_problems: Vec<String>,
    /// Every cable the detector reported, best (most confident) first:
    /// the task grasps the first.
    pub detected: Vec<DetectedCable>,
    /// How the cable was found without the camera; `None` (and left out
    /// of the JSON) when the detector placed it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub touch_only: Option<TouchOnlyRecord>,
    /// Work the run left out because the scene did not need it, in the
    /// order it was decided.
    pub skipped: Vec<Skip>,
}

impl RunRecord {
    pub fn new(
        task: &str,
        cell: &str,
        seed: u64,
        target: LineInSensor,
        tolerance: PoseError,
    ) -> Self {
        Self {
            task: task.to_owned(),
            cell: cell.to_owned(),
            seed,
            target,
            tolerance,
            transitions: Vec::new(),
            grasps: Vec::new(),
            outcome: None,
            safe_stop_problems: Vec::new(),
            detected: Vec::new(),
            touch_only: None,
            skipped: Vec::new(),
        }
    }

    /// The latest grasp whose pad was read, a search's miss included (a
    /// search ends at the first grasp that feels the cable, so its misses
    /// come before every grasp of `grasps`).
    pub fn latest_grasp(&self) -> Option<&GraspRecord> {
        self.grasps
            .last()
            .or_else(|| self.touch_only.as_ref()?.misses.last())
    }

    /// The state the machine entered last, as recorded; `None` before
    /// its first transition.
    pub fn current_state(&self) -> Option<&'static str> {
        self.transitions.last().map(|t| t.to)
    }

    /// How long each visited state lasted; the last one is still open.
    pub fn state_timings(&self) -> Vec<StateTiming> {
        self.transitions
            .iter()
            .enumerate()
            .map(|(i, entered)| StateTiming {
                state: entered.to,
                entered_s: entered.t_s,
                duration_s: self
                    .transitions
                    .get(i + 1)
                    .map(|left| left.t_s - entered.t_s),
            })
            .collect()
    }
}

/// Work a run left out because the scene did not need it, and why: so
/// that a report says where time was saved, not only where it went.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct Skip {
    pub what: Skipped,
    /// Why it was not needed, with the values that decided it.
    pub why: String,
}

/// What a run can leave out.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Skipped {
    /// The segmentation network (a plain background).
    Network,
    /// Pairing branches at crossings (one cable, or none crossing).
    CrossingResolution,
    /// The image outside the region of interest.
    ImageOutsideRoi,
    /// Drawing each cable's mask (the cell's detector needs none).
    CableMasks,
    /// The search by touch from the task's prior (the camera placed the
    /// cable).
    TouchSearch,
    /// Regrasps the task allows but did not need (a grasp within
    /// tolerance).
    Regrasp,
}

impl std::fmt::Display for Skipped {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Skipped::Network => "no network",
            Skipped::CrossingResolution => "no crossing resolution",
            Skipped::ImageOutsideRoi => "less image",
            Skipped::CableMasks => "no cable masks",
            Skipped::TouchSearch => "no search by touch",
            Skipped::Regrasp => "no regrasp",
        })
    }
}

impl From<&VisionSkip> for Skip {
    fn from(skip: &VisionSkip) -> Self {
        let what = match skip {
            VisionSkip::Network { .. } => Skipped::Network,
            VisionSkip::CrossingResolution => Skipped::CrossingResolution,
            VisionSkip::ImageOutsideRoi { .. } => Skipped::ImageOutsideRoi,
            VisionSkip::CableMasks => Skipped::CableMasks,
        };
        Skip {
            what,
            why: skip.why(),
        }
    }
}

/// A run that looked for the cable by touch alone, from the task's prior.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct TouchOnlyRecord {
    #[serde(flatten)]
    pub why: WhyTouchOnly,
    /// Grasps made at the search's poses, the one that felt the cable
    /// included (it is also the trial grasp of `grasps`).
    pub search_moves: u32,
    /// The search's grasps whose pad felt nothing, in order (a grasp whose
    /// jaws closed on nothing is counted, not read).
    pub misses: Vec<GraspRecord>,
}

/// Why the camera was not used.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
#[serde(tag = "why", rename_all = "snake_case")]
pub enum WhyTouchOnly {
    /// The task asks for it (`[task] touch_only = true`).
    Forced,
    /// The detector found no cable.
    NoCableDetected,
    /// The detector could not look: `error` says why.
    DetectorUnusable { error: String },
}

impl std::fmt::Display for WhyTouchOnly {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            WhyTouchOnly::Forced => write!(f, "the task is touch only"),
            WhyTouchOnly::NoCableDetected => write!(f, "no cable detected"),
            // The device's error names the device: `detector: …`.
            WhyTouchOnly::DetectorUnusable { error } => f.write_str(error),
        }
    }
}

#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct TransitionRecord {
    pub from: &'static str,
    pub to: &'static str,
    /// On the cell's clock.
    pub t_s: f64,
}

#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct StateTiming {
    pub state: &'static str,
    pub entered_s: f64,
    pub duration_s: Option<f64>,
}

/// A cable the detector reported.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct DetectedCable {
    /// How much it looks like a cable, 0 to 1 (1 from the oracle).
    pub confidence: f64,
    /// Its grasp frame at s = 0.5.
    #[serde(with = "pose_mm")]
    #[schemars(with = "PoseMm")]
    pub base_from_cable: Isometry3<f64>,
}

/// One grasp and what the pad said of it.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct GraspRecord {
    /// 0 for the trial grasp, k for the k-th regrasp.
    pub attempt: u32,
    pub t_s: f64,
    /// The arm's measured pose with the jaws closed.
    #[serde(with = "pose_mm")]
    #[schemars(with = "PoseMm")]
    pub base_from_tcp: Isometry3<f64>,
    /// Mean Δv over the evaluated frames.
    pub map: TactileMap,
    /// The cable as the pad estimates it; `None` if the fit failed.
    pub fit: Option<Estimate>,
    /// The estimate against the target.
    pub estimated_error: Option<PoseError>,
    /// Where the cable really lay, when the cell knows (a simulation).
    pub truth: Option<Truth>,
    /// The cable's shape in the base frame, seen, felt and fused; set by
    /// the runner once the machine has recorded the grasp.
    pub shapes: Option<GraspShapes>,
}

/// The cable's shape at a grasp (the paper's Fig. 12): what the camera saw
/// before the trial grasp, what the pad says now, both fused, as points in
/// the base frame with their σ; on a simulated cell, the true cable and
/// how far each shape lies from it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct GraspShapes {
    /// The pad's frame at the grasp (the arm's measured pose): the fusion
    /// and its plot work in its x–y plane, x along the pad.
    #[serde(with = "pose_mm")]
    #[schemars(with = "PoseMm")]
    pub base_from_sensor: Isometry3<f64>,
    /// Half the pad's side: the grasped stretch is `|x| ≤` this.
    pub pad_half_side_mm: f64,
    /// The detected cable's centre line, where the camera saw it.
    pub vision: Option<Vec<ShapePoint>>,
    /// The paper's linear fit (eq. 2) over the pad.
    pub tactile_linear: Option<Vec<ShapePoint>>,
    /// The paper's quadratic fit (eq. 3 / 4) over the pad.
    pub tactile_quadratic: Option<Vec<ShapePoint>>,
    /// cablecell's ridge line over the pad, when the task's estimator is
    /// the ridge.
    pub tactile_ridge: Option<Vec<ShapePoint>>,
    /// The tactile shape fused with the vision shape.
    pub fused_from: Option<TactileShape>,
    pub fused: Option<Vec<ShapePoint>>,
    /// The true centre line from support to support (simulated cells).
    #[serde(rename = "truth_in_base_mm")]
    #[schemars(with = "Option<Vec<[f64; 3]>>")]
    pub truth: Option<Vec<Point3<f64>>>,
    pub errors: Option<ShapeErrors>,
}

/// Which of the pad's shapes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum TactileShape {
    Linear,
    Quadratic,
    Ridge,
}

/// How far each shape lies from the true cable over the grasped stretch
/// and beyond it (simulated cells). A tactile fit is measured along its
/// curve extended past the pad: touch alone, extrapolated.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct ShapeErrors {
    /// The length measured beyond each end of the pad.
    pub beyond_mm: f64,
    pub vision: Option<StretchErrors>,
    pub tactile_linear: Option<StretchErrors>,
    pub tactile_quadratic: Option<StretchErrors>,
    pub tactile_ridge: Option<StretchErrors>,
    pub fused: Option<StretchErrors>,
}

#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct Truth {
    pub line: LineInSensor,
    /// The true pose against the target: the error the grasp really has.
    pub error: PoseError,
    /// The estimate against the true pose: the estimator's own error.
    pub estimate_error: Option<PoseError>,
}

#[derive(Debug, Clone, Serialize, JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum RunOutcome {
    /// The cable lies within tolerance of the target.
    Success { regrasps: u32 },
    /// The task could not reach its goal; the cell is fine.
    Failed { reason: Failure },
    /// A device failed or the operator aborted; the cell was made safe.
    Fault {
        state: &'static str,
        device: Option<DeviceKind>,
        error: String,
    },
}

#[derive(Debug, Clone, Serialize, JsonSchema)]
#[serde(tag = "reason", rename_all = "snake_case")]
pub enum Failure {
    /// The detector found no cable.
    NothingDetected,
    /// The jaws closed on nothing.
    GraspedNothing { attempt: u32 },
    /// The pad feels no cable after a grasp.
    NoContact { attempt: u32, peak_dv_v: f64 },
    /// The pad's map could not be fitted.
    FitFailed { attempt: u32, error: String },
    /// Still out of tolerance after every allowed regrasp.
    ToleranceNotReached { regrasps: u32, error: PoseError },
    /// A search by touch felt no cable at any of its poses, which reached
    /// `covered_across_mm` either side of the prior's grasp frame.
    SearchExhausted {
        search_moves: u32,
        prior_in_base_mm: [f64; 3],
        position_sigma_mm: f64,
        angle_sigma_rad: f64,
        covered_across_mm: f64,
    },
}

impl std::fmt::Display for Failure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Failure::NothingDetected => write!(f, "no cable detected"),
            Failure::GraspedNothing { attempt } => {
                write!(f, "grasp {attempt}: the jaws closed on nothing")
            }
            Failure::NoContact { attempt, peak_dv_v } => write!(
                f,
                "grasp {attempt}: no cable on the pad (peak Δv {peak_dv_v:.3} V)"
            ),
            Failure::FitFailed { attempt, error } => {
                write!(f, "grasp {attempt}: tactile fit failed: {error}")
            }
            Failure::ToleranceNotReached { regrasps, error } => write!(
                f,
                "out of tolerance after {regrasps} regrasp(s): n {:+.3} mm, α {:+.4} rad",
                error.n_mm, error.alpha_rad
            ),
            Failure::SearchExhausted {
                search_moves,
                prior_in_base_mm: [x, y, z],
                position_sigma_mm,
                angle_sigma_rad,
                covered_across_mm,
            } => write!(
                f,
                "no cable felt in {search_moves} search move(s) reaching ±{covered_across_mm:.1} mm \
                 across the prior's grasp frame at ({x:.1}, {y:.1}, {z:.1}) mm \
                 (σ {position_sigma_mm} mm, {angle_sigma_rad} rad)"
            ),
        }
    }
}

/// The record with the per-state timings, as `--json` prints it.
#[derive(Debug, Serialize, JsonSchema)]
pub struct RunReport<'a> {
    #[serde(flatten)]
    pub record: &'a RunRecord,
    pub states: Vec<StateTiming>,
}

impl<'a> RunReport<'a> {
    pub fn new(record: &'a RunRecord) -> Self {
        Self {
            record,
            states: record.state_timings(),
        }
    }
}
