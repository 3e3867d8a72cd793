//! The regrasp task end to end on the simulated cell, through the library
//! and through the `cablecell run` command.

mod common;

use common::root;

use cablecell::cell::CellFile;
use cablecell::cell::load_cell;
use cablecell::orchestrator::{Runner, State};
use cablecell::record::{RunOutcome, RunRecord};
use cablecell::task::{TaskFile, load_task};

fn shipped() -> (TaskFile, CellFile) {
    let task = load_task(&root().join("tasks/regrasp.toml")).expect("task");
    let cell = load_cell(&root().join("config/cell.sim.toml")).expect("cell");
    (task, cell)
}

fn shipped_with_oracle() -> (TaskFile, CellFile) {
    let (task, _) = shipped();
    (task, common::sim_cell_with_oracle())
}

fn run(task: &TaskFile, cell: &CellFile, seed: u64) -> RunRecord {
    let mut runner = Runner::for_task(task, cell, seed).expect("a simulated cell builds");
    runner
        .run_to_end()
        .expect("an unrecorded run has no recording to fail");
    assert!(
        runner.state().is_final(),
        "seed {seed}: ended in {:?}",
        runner.state()
    );
    runner.into_record()
}

#[test]
fn the_task_reaches_tolerance_in_truth_for_every_seed() {
    let (task, cell) = shipped();
    for seed in 0..30 {
        let record = run(&task, &cell, seed);
        assert!(
            matches!(record.outcome, Some(RunOutcome::Success { .. })),
            "seed {seed}: {:?}",
            record.outcome
        );
        // Success is judged on the estimate; the simulation knows the truth.
        let last = record.grasps.last().expect("a grasp");
        let truth = last
            .truth
            .as_ref()
            .expect("the simulated cell knows the truth");
        assert!(
            truth.error.n_mm.abs() <= task.tolerance.n_mm
                && truth.error.alpha_rad.abs() <= task.tolerance.alpha_rad,
            "seed {seed}: true error {:?}",
            truth.error
        );
    }
}

#[test]
fn the_regrasp_reduces_the_true_error() {
    let (task, cell) = shipped_with_oracle();
    let (mut trial, mut last) = (0.0, 0.0);
    for seed in 0..30 {
        let record = run(&task, &cell, seed);
        let error = |i: usize| {
            record.grasps[i]
                .truth
                .as_ref()
                .expect("truth")
                .error
                .n_mm
                .abs()
        };
        trial += error(0);
        last += error(record.grasps.len() - 1);
    }
    assert!(
        last < 0.3 * trial,
        "mean |n| {trial} → {last} over 30 seeds"
    );
}

#[test]
fn the_sequence_visits_every_state_in_order() {
    let (task, cell) = shipped_with_oracle();
    // Seed 3 gives a trial grasp out of tolerance (checked below).
    let record = run(&task, &cell, 3);
    let states: Vec<_> = record.transitions.iter().map(|t| t.to).collect();
    let sequence: Vec<_> = common::ONE_REGRASP_PATH[..6]
        .iter()
        .map(|s| s.name())
        .collect();
    assert_eq!(&states[..6], sequence.as_slice());
    assert_eq!(states.last(), Some(&State::Done {}.name()));
    assert_eq!(states[states.len() - 2], State::Verify {}.name());
    // Simulated time only moves forward, and motions take time.
    assert!(record.transitions.windows(2).all(|w| w[0].t_s <= w[1].t_s));
    let timings = record.state_timings();
    let approach = timings
        .iter()
        .find(|t| t.state == State::Approach {}.name())
        .expect("approach");
    assert!(approach.duration_s.expect("closed") > 0.1);
}

#[test]
fn a_trial_grasp_within_tolerance_skips_the_regrasp() {
    let (task, cell) = shipped();
    let mut cell = common::with_oracle(cell, 0.0, 0.0);
    cell.world.cable_tilt_rad = 0.0;
    let record = run(&task, &cell, 5);
    assert!(
        matches!(record.outcome, Some(RunOutcome::Success { regrasps: 0 })),
        "{:?}",
        record.outcome
    );
    assert!(
        record
            .transitions
            .iter()
            .all(|t| t.to != State::Regrasp {}.name())
    );
    assert_eq!(record.grasps.len(), 1);
}

#[test]
fn a_seed_reproduces_the_run_exactly() {
    let (task, cell) = shipped();
    let a = serde_json::to_string(&run(&task, &cell, 11)).expect("json");
    let b = serde_json::to_string(&run(&task, &cell, 11)).expect("json");
    let c = serde_json::to_string(&run(&task, &cell, 12)).expect("json");
    assert_eq!(a, b);
    assert_ne!(a, c);
}

#[test]
fn no_regrasp_allowed_fails_the_task_when_the_trial_is_off() {
    let (mut task, cell) = shipped_with_oracle();
    task.regrasp.max_regrasps = 0;
    let record = run(&task, &cell, 3);
    match &record.outcome {
        Some(RunOutcome::Failed { reason }) => {
            assert!(
                reason
                    .to_string()
                    .starts_with("out of tolerance after 0 regrasp(s)"),
                "{reason}"
            )
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn run_prints_transitions_poses_and_exits_zero() {
    let out = common::cablecell(&["run", "tasks/regrasp.toml", "--seed", "3"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{text}");
    assert!(
        text.contains("task regrasp on simulated cell (seed 3)"),
        "{text}"
    );
    assert!(text.contains("detect → approach"), "{text}");
    assert!(text.contains("trial_grasp → evaluate"), "{text}");
    assert!(text.contains("(approach took"), "{text}");
    assert!(text.contains("trial grasp  estimate n "), "{text}");
    assert!(text.contains("success: within tolerance"), "{text}");
}

#[test]
fn run_json_is_one_report_with_outcome_timings_errors_and_seed() {
    let out = common::cablecell(&["run", "tasks/regrasp.toml", "--seed", "3", "--json"]);
    assert_eq!(out.status.code(), Some(0));
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON document");
    common::assert_follows_schema("run", &report);
    assert_eq!(report["schema_version"], 1);
    assert_eq!(report["seed"], 3);
    assert_eq!(report["outcome"]["kind"], "success");
    let states = report["states"].as_array().expect("states");
    assert!(
        states
            .iter()
            .any(|s| s["state"] == State::Evaluate {}.name() && s["duration_s"].as_f64().is_some())
    );
    let grasps = report["grasps"].as_array().expect("grasps");
    assert!(!grasps.is_empty());
    assert!(grasps[0]["estimated_error"]["n_mm"].as_f64().is_some());
    assert!(grasps[0]["truth"]["error"]["alpha_rad"].as_f64().is_some());
}

#[test]
fn a_silent_tactile_sensor_is_a_device_fault_and_keeps_the_record() {
    let dir = tempfile::tempdir().expect("tempdir");
    let cell = common::sim_cell_copy(dir.path(), |text| {
        text.replace(
            "noise_fraction = 0.02",
            "noise_fraction = 0.02\nsilent_after_frames = 55",
        )
    });
    let report = common::regrasp_fault_report(&cell);
    assert_eq!(report["outcome"]["device"], "tactile");
    assert_eq!(report["outcome"]["state"], State::Evaluate {}.name());
    let to: Vec<_> = report["transitions"]
        .as_array()
        .expect("transitions")
        .iter()
        .map(|t| t["to"].clone())
        .collect();
    let expected = [
        State::Prepare {},
        State::Detect {},
        State::Approach {},
        State::TrialGrasp {},
        State::Evaluate {},
        State::Fault {},
    ];
    assert_eq!(to, expected.map(|s| s.name()));
    // The safe stop opened the jaws without trouble.
    assert_eq!(
        report["safe_stop_problems"].as_array().map(Vec::len),
        Some(0)
    );
}
