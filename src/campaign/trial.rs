//! One trial of a campaign: its seed, the perturbation drawn from it, and
//! what the run gave, as written to the campaign's journal.

use std::path::{Path, PathBuf};
use std::time::Instant;

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use rand::RngExt;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::cell::CellFile;
use crate::detector::config::{DetectorBackend, OracleConfig};
use crate::geometry::{LineInSensor, PoseError};
use crate::hw::arm::config::ArmBackend;
use crate::hw::camera::config::{CameraBackend, OcclusionConfig};
use crate::orchestrator::Runner;
use crate::perception::tactile::Estimator;
use crate::record::{RunOutcome, ShapeErrors};
use crate::schema::FrameConfig;
use crate::sim::{Stream, rng};
use crate::task::TaskFile;
use crate::task::campaign_file::{ErrorSource, Perturbations, Policy, Sensing, TrialStart};

/// The seed of trial `index`: the same for every policy, and independent
/// of the order and the thread the trials run in.
pub fn trial_seed(campaign_seed: u64, index: usize) -> u64 {
    // SplitMix64 of the pair: neighbouring trials get unrelated streams.
    let mut z = campaign_seed ^ (index as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The values one trial runs with.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct Perturbation {
    pub start_offset_mm: f64,
    pub start_angle_rad: f64,
    pub cable_diameter_mm: f64,
    pub cable_stiffness_n_mm2: f64,
    pub sensor_noise_fraction: f64,
}

impl Perturbation {
    pub fn draw(ranges: &Perturbations, seed: u64) -> Self {
        let mut rng = rng(seed, Stream::Perturbation);
        let uniform = |rng: &mut rand_chacha::ChaCha8Rng, [low, high]: [f64; 2]| {
            if high > low {
                rng.random_range(low..=high)
            } else {
                low
            }
        };
        let (offset_mm, angle_rad) = (ranges.start_offset_max_mm, ranges.start_angle_max_rad);
        Self {
            start_offset_mm: uniform(&mut rng, [-offset_mm, offset_mm]),
            start_angle_rad: uniform(&mut rng, [-angle_rad, angle_rad]),
            cable_diameter_mm: uniform(&mut rng, ranges.cable_diameter_mm),
            cable_stiffness_n_mm2: uniform(&mut rng, ranges.cable_stiffness_n_mm2),
            sensor_noise_fraction: uniform(&mut rng, ranges.sensor_noise_fraction),
        }
    }

    /// The cell of this trial: the base cell with these values set.
    pub fn apply(&self, cell: &CellFile, start: TrialStart) -> CellFile {
        let mut cell = cell.clone();
        // The paper's experiment starts each trial from a chosen offset: an
        // oracle detector sets it, whatever detector the cell has.
        if start == TrialStart::Oracle {
            cell.detector.backend = DetectorBackend::Oracle(OracleConfig {
                position_noise_mm: 0.0,
                angle_noise_rad: 0.0,
                offset_across_mm: self.start_offset_mm,
                offset_angle_rad: self.start_angle_rad,
            });
        }
        if let Some(tactile) = cell.tactile.backend.sim_pad_mut() {
            tactile.noise_fraction = self.sensor_noise_fraction;
        }
        cell.world.cable_diameter_mm = self.cable_diameter_mm;
        cell.world.bending_stiffness_n_mm2 = self.cable_stiffness_n_mm2;
        cell
    }

    /// A touch-only trial starts from its prior as the others start from
    /// the oracle's detection: its mean is the true grasp frame moved by
    /// this trial's start offset and angle.
    fn place_prior(&self, task: &mut TaskFile, cell: &CellFile) {
        if let Some(prior) = &mut task.prior {
            let cable_from_start = Isometry3::from_parts(
                Translation3::new(0.0, self.start_offset_mm, 0.0),
                UnitQuaternion::from_axis_angle(&Vector3::z_axis(), self.start_angle_rad),
            );
            prior.base_from_cable =
                FrameConfig::from_isometry(&(cell.world.base_from_cable() * cable_from_start));
        }
    }
}

/// A trial as the journal keeps it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct TrialEntry {
    pub campaign_seed: u64,
    pub trial: usize,
    pub policy: String,
    pub seed: u64,
    pub perturbation: Perturbation,
    pub outcome: TrialOutcome,
    /// Why the trial failed or faulted.
    pub detail: Option<String>,
    /// The trial grasp, then each regrasp.
    pub grasps: Vec<GraspResult>,
    /// Time spent in each state, in order, on the cell's clock.
    pub states: Vec<(String, f64)>,
    /// The trial's duration on the cell's clock (simulated time).
    pub cell_time_s: f64,
    /// Computation time of the trial (not reproducible: wall clock).
    pub compute_time_s: f64,
    /// The trial's recording, if one was written: its file name in the
    /// campaign's recordings folder (so the output folder can move).
    #[serde(default)]
    pub recording: Option<String>,
    /// Grasps a search by touch made, when the trial searched (`grasps`
    /// then begins at the first that felt the cable).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub search_moves: Option<u32>,
    /// How far the shapes of the cable at the first grasp that held it lay
    /// from the true cable (simulated cells).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shape_errors: Option<ShapeErrors>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum TrialOutcome {
    Success,
    Failed,
    Fault,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct GraspResult {
    pub estimate: Option<LineInSensor>,
    pub truth: Option<LineInSensor>,
    /// The true pose against the target.
    pub error: Option<PoseError>,
    /// The estimate against the true pose.
    pub estimate_error: Option<PoseError>,
}

/// The task and cell of a trial with `perturbation` as `policy` runs them.
fn apply_policy(
    policy: &Policy,
    perturbation: &Perturbation,
    start: TrialStart,
    task: &TaskFile,
    cell: &CellFile,
) -> (TaskFile, CellFile) {
    let (mut task, mut cell) = (task.clone(), perturbation.apply(cell, start));
    match policy.sensing {
        Sensing::Both => {}
        Sensing::Vision => task.prior = None,
        Sensing::Touch => {
            task.task.touch_only = true;
            perturbation.place_prior(&mut task, &cell);
        }
    }
    task.tactile.estimator = policy.estimator;
    task.regrasp.max_regrasps = policy.max_regrasps;
    if let Some(tolerance) = policy.tolerance {
        task.tolerance = tolerance;
    }
    if let Some(gain) = policy.correction_gain {
        task.regrasp.correction_gain = gain;
    }
    for source in &policy.perfect {
        match source {
            ErrorSource::Estimator => task.tactile.estimator = Estimator::Oracle,
            ErrorSource::Arm => {
                // Only a simulated arm has a repeatability to switch off.
                if let ArmBackend::Sim(arm) = &mut cell.arm.backend {
                    arm.repeatability_mm = 0.0;
                }
            }
            ErrorSource::SensorNoise => {
                if let Some(tactile) = cell.tactile.backend.sim_pad_mut() {
                    tactile.noise_fraction = 0.0;
                }
            }
            ErrorSource::SpringBack => cell.world.spring_back_fraction = 0.0,
        }
    }
    // Only a simulated camera has a board to lay over the cable.
    if let Some(fraction) = policy.occlusion_fraction
        && let CameraBackend::Sim(camera) = &mut cell.camera.backend
    {
        camera
            .occlusion
            .get_or_insert_with(OcclusionConfig::default)
            .hidden_fraction = fraction;
    }
    (task, cell)
}

/// Where trial `index` of `policy` is recorded in `folder`.
pub fn recording_path(folder: &Path, policy: &str, index: usize) -> PathBuf {
    folder.join(format!("trial-{index:06}-{policy}.mcap"))
}

/// Runs trial `index` of a campaign with one policy, recording it in
/// `recordings` (a folder) if given. A recording that cannot be written is
/// logged and the trial goes on without it.
pub fn run_trial(
    task: &TaskFile,
    cell: &CellFile,
    policy: &Policy,
    ranges: &Perturbations,
    campaign_seed: u64,
    index: usize,
    recordings: Option<&Path>,
) -> TrialEntry {
    let started = Instant::now();
    let seed = trial_seed(campaign_seed, index);
    let perturbation = Perturbation::draw(ranges, seed);
    let (task, cell) = apply_policy(policy, &perturbation, ranges.start, task, cell);
    let mut runner = match Runner::for_task(&task, &cell, seed) {
        Ok(runner) => runner,
        Err(error) => {
            return TrialEntry {
                campaign_seed,
                trial: index,
                policy: policy.name.clone(),
                seed,
                perturbation,
                outcome: TrialOutcome::Fault,
                detail: Some(error.to_string()),
                grasps: Vec::new(),
                states: Vec::new(),
                cell_time_s: 0.0,
                compute_time_s: started.elapsed().as_secs_f64(),
                recording: None,
                search_moves: None,
                shape_errors: None,
            };
        }
    };
    let path = recordings.map(|folder| recording_path(folder, &policy.name, index));
    let recorded = path
        .as_deref()
        .map(|path| runner.record_to(path, false))
        .transpose()
        .and_then(|_| runner.run_to_end())
        .and_then(|()| runner.finish_recording());
    let recording = match recorded {
        Ok(path) => path.and_then(|p| Some(p.file_name()?.to_string_lossy().into_owned())),
        Err(error) => {
            tracing::warn!(
                trial = index,
                policy = policy.name,
                "{error}; the trial goes on unrecorded"
            );
            None
        }
    };
    let record = runner.into_record();
    let (outcome, detail) = match &record.outcome {
        Some(RunOutcome::Success { .. }) => (TrialOutcome::Success, None),
        Some(RunOutcome::Failed { reason }) => (TrialOutcome::Failed, Some(reason.to_string())),
        Some(RunOutcome::Fault { error, .. }) => (TrialOutcome::Fault, Some(error.clone())),
        None => (
            TrialOutcome::Fault,
            Some("the run stopped before it ended".into()),
        ),
    };
    let grasps = record
        .grasps
        .iter()
        .map(|grasp| GraspResult {
            estimate: grasp.fit.as_ref().map(|fit| fit.line()),
            truth: grasp.truth.as_ref().map(|truth| truth.line),
            error: grasp.truth.as_ref().map(|truth| truth.error),
            estimate_error: grasp.truth.as_ref().and_then(|truth| truth.estimate_error),
        })
        .collect();
    let states = record
        .state_timings()
        .iter()
        .filter_map(|t| t.duration_s.map(|d| (t.state.to_owned(), d)))
        .collect();
    TrialEntry {
        campaign_seed,
        trial: index,
        policy: policy.name.clone(),
        seed,
        perturbation,
        outcome,
        detail,
        grasps,
        states,
        cell_time_s: record.transitions.last().map_or(0.0, |t| t.t_s),
        compute_time_s: started.elapsed().as_secs_f64(),
        recording,
        search_moves: record.touch_only.as_ref().map(|t| t.search_moves),
        shape_errors: record.grasps.iter().find_map(|g| g.shapes.as_ref()?.errors),
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;
    use crate::cell::load_cell;
    use crate::hw::camera::config::SimCameraConfig;
    use crate::task::load_task;

    fn shipped() -> (TaskFile, CellFile) {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let task = load_task(&root.join("tasks/regrasp.toml")).expect("the shipped task");
        let cell = load_cell(&root.join("config/cell.sim.toml")).expect("the shipped cell");
        (task, cell)
    }

    fn policy(extra: &str) -> Policy {
        toml::from_str(&format!(
            "name = \"p\"\nestimator = \"ridge\"\nmax_regrasps = 1\n{extra}"
        ))
        .expect("a policy")
    }

    /// A trial 2 mm and 0.1 rad off at the start.
    fn perturbation() -> Perturbation {
        Perturbation {
            start_offset_mm: 2.0,
            start_angle_rad: 0.1,
            cable_diameter_mm: 2.5,
            cable_stiffness_n_mm2: 60.0,
            sensor_noise_fraction: 0.02,
        }
    }

    #[test]
    fn a_policy_s_sensing_keeps_drops_or_forces_the_search_by_touch() {
        let (task, cell) = shipped();
        assert!(task.prior.is_some() && !task.task.touch_only);
        let trial = |sensing: &str| {
            let policy = policy(&format!("sensing = \"{sensing}\""));
            apply_policy(&policy, &perturbation(), TrialStart::Oracle, &task, &cell).0
        };
        let both = trial("both");
        assert!(both.prior.is_some() && !both.task.touch_only);
        assert!(trial("vision").prior.is_none());
        let touch = trial("touch");
        assert!(touch.task.touch_only);
        let moved = touch.prior.expect("a prior").base_from_cable;
        assert_ne!(
            moved.translation_mm,
            task.prior.as_ref().unwrap().base_from_cable.translation_mm
        );
    }

    #[test]
    fn a_trial_starts_from_the_oracle_unless_the_campaign_keeps_the_cells_detector() {
        let (_, cell) = shipped();
        assert!(matches!(cell.detector.backend, DetectorBackend::Vision(_)));
        let perturbation = Perturbation {
            start_offset_mm: 2.0,
            start_angle_rad: 0.1,
            cable_diameter_mm: 2.5,
            cable_stiffness_n_mm2: 60.0,
            sensor_noise_fraction: 0.02,
        };
        match perturbation
            .apply(&cell, TrialStart::Oracle)
            .detector
            .backend
        {
            DetectorBackend::Oracle(oracle) => {
                assert_eq!(
                    (oracle.offset_across_mm, oracle.offset_angle_rad),
                    (2.0, 0.1)
                )
            }
            other => panic!("{other:?}"),
        }
        assert!(matches!(
            perturbation
                .apply(&cell, TrialStart::Detector)
                .detector
                .backend,
            DetectorBackend::Vision(_)
        ));
    }

    fn camera(cell: &CellFile) -> &SimCameraConfig {
        match &cell.camera.backend {
            CameraBackend::Sim(sim) => sim,
            CameraBackend::Opencv(_) => panic!("the shipped cell's camera is simulated"),
        }
    }

    #[test]
    fn a_policy_s_occlusion_reaches_its_trials_cell_at_the_same_place_for_every_policy() {
        let (task, cell) = shipped();
        let oracle = TrialStart::Oracle;
        let (_, untouched) = apply_policy(&policy(""), &perturbation(), oracle, &task, &cell);
        assert!(camera(&untouched).occlusion.is_none());

        let seed = trial_seed(1, 3);
        let position = |fraction: f64| {
            let policy = policy(&format!("occlusion_fraction = {fraction}"));
            let (_, cell) = apply_policy(&policy, &perturbation(), oracle, &task, &cell);
            let camera = camera(&cell);
            let occlusion = camera.occlusion.as_ref().expect("an occlusion table");
            assert_eq!(occlusion.hidden_fraction, fraction);
            let appearance = camera.appearance(&mut rng(seed, Stream::Camera));
            appearance.occlusion.board.expect("a board").position
        };
        assert_eq!(position(0.4), position(0.7));
    }
}
