//! A task file and a cell file merged into what the machine needs.

use nalgebra::Isometry3;

use crate::cell::CellFile;
use crate::geometry::{CorrectionGain, LineInSensor, PoseError};
use crate::perception::tactile::search::Prior;
use crate::perception::tactile::{Estimator, FitConfig};
use crate::recording::CellView;
use crate::task::TaskFile;

#[derive(Debug, Clone)]
pub struct Plan {
    pub target: LineInSensor,
    pub tolerance: PoseError,
    pub standoff_mm: f64,
    pub speed_mm_s: f64,
    pub open_mm: f64,
    pub grip_current_a: f64,
    pub max_regrasps: u32,
    pub retreat_mm: f64,
    pub correction_gain: CorrectionGain,
    pub bias_frames: usize,
    pub average_frames: usize,
    pub fit: FitConfig,
    pub estimator: Estimator,
    /// Where the pad sits on the hand.
    pub tcp_from_sensor: Isometry3<f64>,
    /// Where a search by touch starts when the camera cannot place the
    /// cable; without one such a run fails.
    pub prior: Option<Prior>,
    /// Search from the prior without looking; only with a prior.
    pub touch_only: bool,
    /// The cell's frames and camera, as recordings draw them.
    pub view: CellView,
}

impl Plan {
    pub fn new(task: &TaskFile, cell: &CellFile) -> Self {
        Self {
            target: task.target.line(),
            tolerance: task.tolerance.as_error_bound(),
            standoff_mm: task.approach.standoff_mm,
            speed_mm_s: task.approach.speed_mm_s,
            open_mm: task.grasp.open_mm,
            grip_current_a: task.grasp.grip_current_a,
            max_regrasps: task.regrasp.max_regrasps,
            retreat_mm: task.regrasp.retreat_mm,
            correction_gain: task.regrasp.correction_gain,
            bias_frames: task.tactile.bias_samples,
            average_frames: task.tactile.average_frames,
            fit: FitConfig {
                pitch_mm: cell.tactile.pitch_mm,
                contact_threshold_v: task.tactile.contact_threshold_v,
            },
            estimator: task.tactile.estimator,
            tcp_from_sensor: cell.tactile.tcp_from_sensor.isometry(),
            prior: task.prior.as_ref().map(|prior| prior.prior()),
            touch_only: task.task.touch_only && task.prior.is_some(),
            view: CellView::of(cell),
        }
    }
}
