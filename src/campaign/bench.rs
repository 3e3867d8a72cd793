//! The bench: the cell's settings run on the same seeded trials, each
//! one's error against what it costs (computation and the cell's own,
//! simulated, time), the settings no other beats on both marked as the
//! Pareto front; and the latency of each stage of a trial's computation.
//! Trials are the campaign's (`run_trial`), so a bench row is what a
//! campaign with that policy would give.

use std::time::Instant;

use schemars::JsonSchema;
use serde::Serialize;

use super::stats::Summary;
use super::trial::{TrialEntry, TrialOutcome, run_trial};
use crate::cell::CellFile;
use crate::geometry::PoseError;
use crate::orchestrator::Runner;
use crate::perception::tactile::Estimator;
use crate::task::TaskFile;
use crate::task::campaign_file::{Perturbations, Policy, Sensing};
use crate::task::task_file::Tolerance;

/// How many trials each setting runs, from which campaign seed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BenchSize {
    pub trials: usize,
    pub seed: u64,
    /// Repetitions of each timed stage.
    pub repetitions: usize,
}

impl BenchSize {
    /// What the docs quote.
    pub const FULL: BenchSize = BenchSize {
        trials: 100,
        seed: 1,
        repetitions: 200,
    };
    /// About a minute in a release build.
    pub const QUICK: BenchSize = BenchSize {
        trials: 20,
        seed: 1,
        repetitions: 50,
    };
}

/// One setting: a campaign policy and the task's averaging window.
#[derive(Debug, Clone)]
pub struct Setting {
    /// What the setting varies: "estimator", "regrasp", "averaging".
    pub group: &'static str,
    pub name: String,
    pub policy: Policy,
    /// Frames averaged per tactile evaluation, if not the task's.
    pub average_frames: Option<usize>,
}

/// The settings the bench compares, each varied from cablecell's policy
/// (ridge, up to 4 regrasps towards the task's tolerance): the estimator,
/// the regrasp budget and tolerance (a tolerance of almost nothing
/// regrasps every time: what the in-tolerance skip saves), and the tactile
/// averaging window.
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
    /// Mean distance of the fused shape from the true cable over the pad,
    /// at the first grasp
    /// (fusion runs at every grasp; it has no switch in the task file).
    pub fused_shape_mm_mean: Option<f64>,
    /// And of the camera's shape alone, for scale.
    pub vision_shape_mm_mean: Option<f64>,
    pub regrasps_mean: f64,
    /// Computation per trial (wall clock), median.
    pub compute_ms_median: Option<f64>,
    /// The cell's time per trial (simulated clock: each regrasp costs the
    /// arm about a second of motion), mean.
    pub cell_s_mean: f64,
    /// No other row is both faster on the cell's clock and closer (|n|).
    pub front_cell_time: bool,
    /// No other row is both faster to compute and closer (|n|).
    pub front_compute_time: bool,
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
            let entries: Vec<TrialEntry> = (0..size.trials)
                .map(|index| {
                    let entry =
                        run_trial(&task, cell, &setting.policy, ranges, size.seed, index, None);
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

/// The campaign statistics' mean of `values`; `None` for none.
fn mean(values: impl Iterator<Item = f64>) -> Option<f64> {
    Summary::of(&values.collect::<Vec<_>>()).map(|s| s.mean)
}

fn row(setting: &Setting, entries: &[TrialEntry]) -> SettingRow {
    let finals: Vec<PoseError> = entries
        .iter()
        .filter_map(|e| e.grasps.last()?.error)
        .collect();
    let shapes = || entries.iter().filter_map(|e| e.shape_errors);
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
        fused_shape_mm_mean: mean(shapes().filter_map(|s| Some(s.fused?.grasped?.mean_mm))),
        vision_shape_mm_mean: mean(shapes().filter_map(|s| Some(s.vision?.grasped?.mean_mm))),
        regrasps_mean: mean(
            entries
                .iter()
                .map(|e| e.grasps.len().saturating_sub(1) as f64),
        )
        .unwrap_or(0.0),
        compute_ms_median: Summary::of(&compute_ms).map(|s| s.median),
        cell_s_mean: mean(entries.iter().map(|e| e.cell_time_s)).unwrap_or(0.0),
        front_cell_time: false,
        front_compute_time: false,
    }
}

fn mark_fronts(rows: &mut [SettingRow]) {
    let error = |r: &SettingRow| r.final_n_mm_mean.unwrap_or(f64::INFINITY);
    let by_cell: Vec<_> = rows.iter().map(|r| (r.cell_s_mean, error(r))).collect();
    let by_compute: Vec<_> = rows
        .iter()
        .map(|r| (r.compute_ms_median.unwrap_or(f64::INFINITY), error(r)))
        .collect();
    for ((row, cell), compute) in rows
        .iter_mut()
        .zip(pareto_front(&by_cell))
        .zip(pareto_front(&by_compute))
    {
        row.front_cell_time = cell;
        row.front_compute_time = compute;
    }
}

/// Whether each (cost, error) point is on the Pareto front: no other point
/// is at least as cheap and as accurate and better in one of the two.
/// Equal points are both on it.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<bool> {
    points
        .iter()
        .map(|&(cost, error)| {
            !points
                .iter()
                .any(|&(c, e)| c <= cost && e <= error && (c < cost || e < error))
        })
        .collect()
}

/// The latency of one stage of a trial's computation.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct StageLatency {
    pub stage: String,
    pub median_us: f64,
    pub p95_us: f64,
}

/// Times `f` `repetitions` times, in microseconds.
fn time_us(name: &str, repetitions: usize, mut f: impl FnMut()) -> Option<StageLatency> {
    let times: Vec<f64> = (0..repetitions.max(1))
        .map(|_| {
            let start = Instant::now();
            f();
            start.elapsed().as_secs_f64() * 1e6
        })
        .collect();
    Summary::of(&times).map(|s| StageLatency {
        stage: name.to_owned(),
        median_us: s.median,
        p95_us: s.p95,
    })
}

/// The latency of the tactile stages on a real trial's grasp (bias
/// removal of one frame and each estimator's fit of the averaged map), of
/// one state-machine step with the simulated devices' work (each step of
/// a seeded run), and of a whole simulated trial's computation.
pub fn stage_latencies(
    task: &TaskFile,
    cell: &CellFile,
    ranges: &Perturbations,
    size: BenchSize,
) -> Vec<StageLatency> {
    let mut stages = Vec::new();
    let mut step_us = Vec::new();
    if let Ok(mut runner) = Runner::for_task(task, cell, size.seed) {
        loop {
            let start = Instant::now();
            let stepped = runner.step();
            step_us.push(start.elapsed().as_secs_f64() * 1e6);
            if !matches!(stepped, Ok(true)) {
                break;
            }
        }
        let fit = &runner.plan().fit.clone();
        let record = runner.into_record();
        if let Some(grasp) = record.grasps.first() {
            let map = &grasp.map;
            for (name, estimator) in [
                ("tactile fit: centroids (paper)", Estimator::Centroids),
                ("tactile fit: ridge", Estimator::Ridge),
            ] {
                stages.extend(time_us(name, size.repetitions, || {
                    let _ = std::hint::black_box(estimator.estimate(map, fit, None));
                }));
            }
        }
    }
    if let Some(s) = Summary::of(&step_us) {
        stages.push(StageLatency {
            stage: "state-machine step (with the simulated devices)".to_owned(),
            median_us: s.median,
            p95_us: s.p95,
        });
    }
    let policy = &settings()[1].policy;
    let mut index = 0;
    stages.extend(time_us(
        "whole simulated trial (ridge, 1 regrasp)",
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
    fn the_front_holds_the_points_no_other_beats_on_both() {
        let points = [
            (1.0, 5.0), // cheapest
            (2.0, 3.0), // on the front
            (3.0, 3.0), // as accurate as the one before, dearer: off
            (2.5, 4.0), // beaten by (2, 3)
            (4.0, 1.0), // most accurate
            (4.0, 1.0), // its equal: both on
            (5.0, 2.0), // beaten by (4, 1)
        ];
        assert_eq!(
            pareto_front(&points),
            [true, true, false, false, true, true, false]
        );
        assert!(pareto_front(&[]).is_empty());
    }

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
}
