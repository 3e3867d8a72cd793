//! The cell's settings on the campaign's seeded trials, each one's error
//! against what it costs (computation and the cell's own, simulated,
//! time), with the Pareto fronts; and the latency of each stage of a
//! trial's computation. Trials are the campaign's (`run_trial`), so a
//! bench row is what a campaign with that policy would give.

use std::time::Instant;

use schemars::JsonSchema;
use serde::Serialize;

use super::{StageLatency, mean, pareto_front, time_us};
use crate::campaign::stats::Summary;
use crate::campaign::trial::{TrialEntry, TrialOutcome, run_trial};
use crate::cell::CellFile;
use crate::detector::config::DetectorBackend;
use crate::geometry::PoseError;
use crate::orchestrator::shapes::grasp_shapes;
use crate::orchestrator::{Command, Runner};
use crate::perception::shape::StretchErrors;
use crate::perception::tactile::Estimator;
use crate::record::ShapeErrors;
use crate::task::TaskFile;
use crate::task::campaign_file::{Perturbations, Policy, Sensing, TrialStart};
use crate::task::task_file::Tolerance;

use super::BenchSize;

/// One setting: a campaign policy, the task's averaging window and what
/// finds the cable at the trial's start.
#[derive(Debug, Clone)]
pub struct Setting {
    /// What the setting varies: "estimator", "regrasp", "averaging",
    /// "fusion".
    pub group: &'static str,
    pub name: String,
    pub policy: Policy,
    /// Frames averaged per tactile evaluation, if not the task's.
    pub average_frames: Option<usize>,
    /// What finds the cable at the trial's start, if not the campaign's.
    pub start: Option<TrialStart>,
}

/// The settings the bench compares, each varied from cablecell's policy
/// (ridge, up to 4 regrasps towards the task's tolerance): the estimator,
/// the regrasp budget and tolerance (a tolerance of almost nothing
/// regrasps every time: what the in-tolerance skip saves), the tactile
/// averaging window; and cablecell's policy started from the cell's camera
/// and vision pipeline instead of the campaign's oracle, so that the
/// camera's own shape is fused with the pad's (the oracle's shape is the
/// true cable moved by the start offset, with a σ of 0 that the fusion
/// trusts over any touch).
pub fn settings() -> Vec<Setting> {
    let policy = |name: &str, estimator, max_regrasps, tolerance| Policy {
        name: name.to_owned(),
        estimator,
        max_regrasps,
        tolerance,
        correction_gain: None,
        perfect: Vec::new(),
        occlusion_fraction: None,
        sensing: Sensing::Both,
    };
    let never_within = Some(Tolerance {
        n_mm: 1e-9,
        alpha_rad: 1e-9,
    });
    let fine = Some(Tolerance {
        n_mm: 0.25,
        alpha_rad: 0.02,
    });
    let setting = |group, name: &str, policy: Policy, average_frames| Setting {
        group,
        name: name.to_owned(),
        policy,
        average_frames,
        start: None,
    };
    let mut settings = vec![
        setting(
            "estimator",
            "centroids (paper), 1 regrasp",
            policy("centroids", Estimator::Centroids, 1, None),
            None,
        ),
        setting(
            "estimator",
            "ridge, 1 regrasp",
            policy("ridge", Estimator::Ridge, 1, None),
            None,
        ),
        setting(
            "regrasp",
            "ridge, no regrasp",
            policy("no-regrasp", Estimator::Ridge, 0, None),
            None,
        ),
        setting(
            "regrasp",
            "ridge, 1 regrasp always (no in-tolerance skip)",
            policy("always", Estimator::Ridge, 1, never_within),
            None,
        ),
        setting(
            "regrasp",
            "ridge, up to 4 regrasps to 0.25 mm / 0.02 rad",
            policy("fine", Estimator::Ridge, 4, fine),
            None,
        ),
    ];
    for frames in [1, 10, 50] {
        settings.push(setting(
            "averaging",
            &format!("ridge, 1 regrasp, {frames} frame(s) averaged"),
            policy(&format!("average-{frames}"), Estimator::Ridge, 1, None),
            Some(frames),
        ));
    }
    settings.push(Setting {
        start: Some(TrialStart::Detector),
        ..setting(
            "fusion",
            "ridge, up to 4 regrasps to 0.25 mm / 0.02 rad, started from the camera",
            policy("camera-start", Estimator::Ridge, 4, fine),
            None,
        )
    });
    settings
}

/// What one setting reached and what it cost.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct SettingRow {
    pub group: String,
    pub setting: String,
    pub trials: usize,
    pub success_rate: f64,
    /// Mean |n| and |α| of the last grasp against the target, over the
    /// trials that grasped.
    pub final_n_mm_mean: Option<f64>,
    pub final_alpha_rad_mean: Option<f64>,
    /// Mean distance from the true cable, at the first grasp, over the
    /// stretch the pad holds, of the camera's shape (the detector's centre
    /// line: fusion off), the pad's (the estimator's own curve) and the
    /// two fused (fusion on; it runs at every grasp).
    pub shape_on_pad: ShapeColumns,
    /// The same over the stretches beyond the pad's ends
    /// ([`ShapeErrors::beyond_mm`] each), the pad's curve extended.
    pub shape_beyond_pad: ShapeColumns,
    pub regrasps_mean: f64,
    /// Computation per trial (wall clock), median.
    pub compute_ms_median: Option<f64>,
    /// The cell's time per trial (simulated clock: each regrasp costs the
    /// arm about a second of motion), mean.
    pub cell_s_mean: f64,
    /// The trials started from the cell's camera and vision pipeline, not
    /// from the oracle off by the campaign's drawn offset: its fronts are
    /// its own.
    pub started_from_camera: bool,
    /// No other row of the same start is both faster on the cell's clock
    /// and closer (|n|).
    pub front_cell_time: bool,
    /// No other row of the same start is both faster to compute and closer
    /// (|n|).
    pub front_compute_time: bool,
}

/// Mean distances (mm) of each shape from the true cable over one stretch.
#[derive(Debug, Clone, Copy, Default, Serialize, JsonSchema)]
pub struct ShapeColumns {
    pub vision_mm_mean: Option<f64>,
    pub touch_mm_mean: Option<f64>,
    pub fused_mm_mean: Option<f64>,
}

impl ShapeColumns {
    /// Over the trials' `errors`, on the pad (`beyond` false) or beyond it.
    fn of(errors: &[ShapeErrors], beyond: bool) -> Self {
        let stretch = |e: Option<StretchErrors>| {
            let e = e?;
            Some(if beyond { e.beyond? } else { e.grasped? }.mean_mm)
        };
        let column = |shape: fn(&ShapeErrors) -> Option<StretchErrors>| {
            mean(errors.iter().filter_map(|e| stretch(shape(e))))
        };
        ShapeColumns {
            vision_mm_mean: column(|e| e.vision),
            // The estimator's own curve, as the fusion takes it.
            touch_mm_mean: column(|e| e.tactile_ridge.or(e.tactile_quadratic).or(e.tactile_linear)),
            fused_mm_mean: column(|e| e.fused),
        }
    }
}

/// Runs every setting on trials 0..`size.trials` of `seed`, with the
/// campaign's perturbations.
pub fn run_settings(
    task: &TaskFile,
    cell: &CellFile,
    ranges: &Perturbations,
    settings: &[Setting],
    size: BenchSize,
    mut on_trial: impl FnMut(),
) -> Vec<SettingRow> {
    let mut rows: Vec<SettingRow> = settings
        .iter()
        .map(|setting| {
            let mut task = task.clone();
            if let Some(frames) = setting.average_frames {
                task.tactile.average_frames = frames;
            }
            let ranges = Perturbations {
                start: setting.start.unwrap_or(ranges.start),
                ..ranges.clone()
            };
            let entries: Vec<TrialEntry> = (0..size.trials)
                .map(|index| {
                    let entry = run_trial(
                        &task,
                        cell,
                        &setting.policy,
                        &ranges,
                        size.seed,
                        index,
                        None,
                    );
                    on_trial();
                    entry
                })
                .collect();
            row(setting, &entries)
        })
        .collect();
    mark_fronts(&mut rows);
    rows
}

fn row(setting: &Setting, entries: &[TrialEntry]) -> SettingRow {
    let finals: Vec<PoseError> = entries
        .iter()
        .filter_map(|e| e.grasps.last()?.error)
        .collect();
    let shapes: Vec<ShapeErrors> = entries.iter().filter_map(|e| e.shape_errors).collect();
    let compute_ms: Vec<f64> = entries.iter().map(|e| e.compute_time_s * 1e3).collect();
    let successes = entries
        .iter()
        .filter(|e| e.outcome == TrialOutcome::Success)
        .count();
    SettingRow {
        group: setting.group.to_owned(),
        setting: setting.name.clone(),
        trials: entries.len(),
        success_rate: successes as f64 / entries.len().max(1) as f64,
        final_n_mm_mean: mean(finals.iter().map(|e| e.n_mm.abs())),
        final_alpha_rad_mean: mean(finals.iter().map(|e| e.alpha_rad.abs())),
        shape_on_pad: ShapeColumns::of(&shapes, false),
        shape_beyond_pad: ShapeColumns::of(&shapes, true),
        regrasps_mean: mean(
            entries
                .iter()
                .map(|e| e.grasps.len().saturating_sub(1) as f64),
        )
        .unwrap_or(0.0),
        compute_ms_median: Summary::of(&compute_ms).map(|s| s.median),
        cell_s_mean: mean(entries.iter().map(|e| e.cell_time_s)).unwrap_or(0.0),
        started_from_camera: setting.start == Some(TrialStart::Detector),
        front_cell_time: false,
        front_compute_time: false,
    }
}

/// Marks the fronts among the rows of each trial start: a trial started
/// from the camera begins closer than one the oracle puts off by the
/// drawn offset, so the two are not the same trials.
fn mark_fronts(rows: &mut [SettingRow]) {
    for camera in [false, true] {
        let mut same: Vec<&mut SettingRow> = rows
            .iter_mut()
            .filter(|r| r.started_from_camera == camera)
            .collect();
        let error = |r: &SettingRow| r.final_n_mm_mean.unwrap_or(f64::INFINITY);
        let by_cell: Vec<_> = same.iter().map(|r| (r.cell_s_mean, error(r))).collect();
        let by_compute: Vec<_> = same
            .iter()
            .map(|r| (r.compute_ms_median.unwrap_or(f64::INFINITY), error(r)))
            .collect();
        for ((row, cell), compute) in same
            .iter_mut()
            .zip(pareto_front(&by_cell))
            .zip(pareto_front(&by_compute))
        {
            row.front_cell_time = cell;
            row.front_compute_time = compute;
        }
    }
}

/// The latency of the tactile stages on a real trial's grasp (each
/// estimator's fit of the averaged map, the grasp's shapes and their
/// fusion), of one state-machine step with the simulated devices' work
/// (each step of seeded runs of the task on the cell as given), with two
/// kinds of step timed apart: the detect step (on the shipped cell the
/// simulated camera's image is rendered and the vision pipeline run on
/// it, a hundred milliseconds where the other steps take microseconds; a
/// campaign's trial has the oracle in its place) and the tactile reads
/// (the one that records a grasp also fuses its shapes), and of a whole
/// simulated trial's computation.
pub fn stage_latencies(
    task: &TaskFile,
    cell: &CellFile,
    ranges: &Perturbations,
    size: BenchSize,
) -> Vec<StageLatency> {
    let mut stages = Vec::new();
    let (mut step_us, mut detect_us, mut read_us) = (Vec::new(), Vec::new(), Vec::new());
    let runs = (size.repetitions / 40).max(1) as u64;
    for seed in size.seed..size.seed + runs {
        let Ok(mut runner) = Runner::for_task(task, cell, seed) else {
            break;
        };
        loop {
            let times = match runner.pending_command() {
                Some(Command::Detect) => &mut detect_us,
                Some(Command::ReadTactile { .. }) => &mut read_us,
                _ => &mut step_us,
            };
            let start = Instant::now();
            let stepped = runner.step();
            times.push(start.elapsed().as_secs_f64() * 1e6);
            if !matches!(stepped, Ok(true)) {
                break;
            }
        }
        if seed > size.seed {
            continue;
        }
        let plan = runner.plan().clone();
        let record = runner.into_record();
        if let Some(grasp) = record.grasps.first() {
            let map = &grasp.map;
            for (name, estimator) in [
                ("tactile fit: centroids (paper)", Estimator::Centroids),
                ("tactile fit: ridge", Estimator::Ridge),
            ] {
                stages.extend(time_us(name, size.repetitions, || {
                    let _ = std::hint::black_box(estimator.estimate(map, &plan.fit, None));
                }));
            }
            if let Some(shapes) = &grasp.shapes {
                let (vision, truth) = (shapes.vision.as_deref(), shapes.truth.as_deref());
                stages.extend(time_us(
                    "a grasp's shapes: the pad's curves, fused with the detector's centre line, against the truth",
                    size.repetitions,
                    || {
                        let _ = std::hint::black_box(grasp_shapes(grasp, &plan, vision, truth));
                    },
                ));
            }
        }
    }
    stages.extend(StageLatency::of(
        "state-machine step but detect and tactile reads (with the simulated devices)",
        &step_us,
    ));
    stages.extend(StageLatency::of(
        "tactile read step (frames, the fit, the grasp's shapes fused)",
        &read_us,
    ));
    let detector = match cell.detector.backend {
        DetectorBackend::Oracle(_) => "the oracle",
        DetectorBackend::Vision(_) => "the camera's image rendered, the vision pipeline",
    };
    stages.extend(StageLatency::of(
        format!("detect step ({detector})"),
        &detect_us,
    ));
    let policy = &settings()[1].policy;
    let mut index = 0;
    stages.extend(time_us(
        "whole simulated trial (ridge, 1 regrasp; oracle start)",
        size.repetitions.min(size.trials.max(1)),
        || {
            let _ = run_trial(task, cell, policy, ranges, size.seed, index, None);
            index += 1;
        },
    ));
    stages
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_tiny_bench_gives_a_row_per_setting_and_a_front() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let (file, task, cell) =
            crate::task::load_campaign(&root.join("tasks/paper-regrasp-campaign.toml"))
                .expect("the shipped campaign");
        let size = BenchSize {
            trials: 1,
            seed: 1,
            repetitions: 1,
            images: 1,
        };
        let all = settings();
        let chosen = [all[2].clone(), all[4].clone()];
        let mut trials = 0;
        let rows = run_settings(&task, &cell, &file.perturbation, &chosen, size, || {
            trials += 1
        });
        assert_eq!(trials, 2);
        assert_eq!(rows.len(), 2);
        let (none, fine) = (&rows[0], &rows[1]);
        assert_eq!((none.group.as_str(), none.trials), ("regrasp", 1));
        assert_eq!(none.regrasps_mean, 0.0);
        // Regrasping costs the cell time and buys accuracy: both on the
        // front of the cell's clock.
        assert!(fine.cell_s_mean > none.cell_s_mean);
        assert!(fine.final_n_mm_mean < none.final_n_mm_mean);
        assert!(none.front_cell_time && fine.front_cell_time);
    }

    #[test]
    fn fusion_follows_the_pad_on_it_and_the_camera_beyond_unless_the_oracle_claims_to_be_exact() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let (file, task, cell) =
            crate::task::load_campaign(&root.join("tasks/paper-regrasp-campaign.toml"))
                .expect("the shipped campaign");
        let size = BenchSize {
            trials: 2,
            seed: 1,
            repetitions: 1,
            images: 1,
        };
        let all = settings();
        let oracle = all[1].clone();
        let camera = all.last().expect("the fusion row").clone();
        let rows = run_settings(
            &task,
            &cell,
            &file.perturbation,
            &[oracle, camera],
            size,
            || {},
        );
        let (oracle, camera) = (&rows[0], &rows[1]);
        assert!(!oracle.started_from_camera && camera.started_from_camera);
        // Each start has its own front.
        assert!(oracle.front_cell_time && camera.front_cell_time);
        let value = |v: Option<f64>| v.expect("a shape error");
        // The oracle's exact σ: the fused shape is its own, however far
        // off, and the pad's is closer.
        let pad = &oracle.shape_on_pad;
        assert!(
            (value(pad.fused_mm_mean) - value(pad.vision_mm_mean)).abs() < 0.1,
            "{pad:?}"
        );
        assert!(
            value(pad.touch_mm_mean) < value(pad.vision_mm_mean),
            "{pad:?}"
        );
        // The camera's σ: on the pad the fused shape follows the pad, beyond
        // it the camera.
        let (pad, beyond) = (&camera.shape_on_pad, &camera.shape_beyond_pad);
        assert!(
            value(pad.fused_mm_mean) < value(pad.vision_mm_mean),
            "{pad:?}"
        );
        assert!(
            value(beyond.fused_mm_mean) < value(beyond.touch_mm_mean),
            "{beyond:?}"
        );
    }
}
