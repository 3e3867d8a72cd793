//! The grasp when the camera cannot see: a search by touch from the task's
//! `[prior]` on the simulated cell, forced by the task, after a detector
//! that found no cable or could not look, and as a campaign's policy.

mod common;

use std::path::{Path, PathBuf};

use common::{cablecell, json_of, sim_cell_copy, text};
use serde_json::Value;

/// The simulated cable's grasp frame is at z = 250 mm; the shipped prior
/// says 255 mm.
const SHIPPED_PRIOR: &str = "translation_mm = [450.0, 0.0, 255.0]";

/// The shipped task after `edit`, written into `dir`.
fn task_copy(dir: &Path, name: &str, edit: impl Fn(String) -> String) -> PathBuf {
    let shipped = std::fs::read_to_string(common::root().join("tasks/regrasp.toml")).unwrap();
    let edited = edit(shipped.clone());
    assert_ne!(edited, shipped, "the edit changed nothing");
    let path = dir.join(name);
    std::fs::write(&path, edited).unwrap();
    path
}

fn touch_only(task: String) -> String {
    task.replace("# touch_only = true", "touch_only = true")
}

/// The prior's mean at height `z_mm`, its σ across and its limit of moves.
fn prior(task: String, z_mm: f64, sigma_mm: f64, max_moves: usize) -> String {
    task.replace(
        SHIPPED_PRIOR,
        &format!("translation_mm = [450.0, 0.0, {z_mm:.1}]"),
    )
    .replace(
        "position_sigma_mm = 5.0",
        &format!("position_sigma_mm = {sigma_mm:.1}"),
    )
    .replace(
        "max_search_moves = 5",
        &format!("max_search_moves = {max_moves}"),
    )
}

fn run_json(task: &Path, cell: &str, seed: &str) -> (Option<i32>, Value) {
    let out = cablecell(&[
        "run",
        text(task),
        "--cell",
        cell,
        "--seed",
        seed,
        "--json",
        "--no-record",
    ]);
    let report = serde_json::from_slice(&out.stdout).unwrap_or_else(|e| {
        panic!("{e}: {}", String::from_utf8_lossy(&out.stderr));
    });
    (out.status.code(), report)
}

fn states(report: &Value) -> Vec<&str> {
    report["transitions"]
        .as_array()
        .expect("transitions")
        .iter()
        .map(|t| t["to"].as_str().expect("a state"))
        .collect()
}

/// The last grasp's true error is within the task's tolerance (1 mm,
/// 0.1 rad).
fn assert_within_tolerance(report: &Value) {
    let grasps = report["grasps"].as_array().expect("grasps");
    let error = &grasps.last().expect("a grasp")["truth"]["error"];
    let (n, alpha) = (error["n_mm"].as_f64(), error["alpha_rad"].as_f64());
    assert!(n.is_some_and(|n| n.abs() <= 1.0), "{error}");
    assert!(alpha.is_some_and(|a| a.abs() <= 0.1), "{error}");
}

#[test]
fn a_touch_only_run_finds_the_cable_three_pads_off_and_reaches_tolerance() {
    let dir = tempfile::tempdir().unwrap();
    // 53 mm above the cable: three pad widths (5 × 3.55 mm); ±3σ reaches it.
    let task = task_copy(dir.path(), "far.toml", |t| {
        prior(touch_only(t), 303.0, 18.0, 20)
    });
    let (status, report) = run_json(&task, "config/cell.sim.toml", "3");
    assert_eq!(status, Some(0), "{report}");
    assert_eq!(report["outcome"]["kind"], "success");
    let touch_only = &report["touch_only"];
    assert_eq!(touch_only["why"], "forced");
    // The poses alternate 0, +10.65, −10.65, …: the cable, 53 mm below,
    // is caught from −42.6 mm, the ninth.
    assert_eq!(touch_only["search_moves"], 9, "{touch_only}");
    let states = states(&report);
    assert!(!states.contains(&"detect"), "{states:?}");
    assert_eq!(states.iter().filter(|s| **s == "search").count(), 8);
    assert_within_tolerance(&report);
    // What the pad felt is judged as after any trial grasp: regrasps by
    // T_corr, as many as the outcome says.
    let regrasps = report["outcome"]["regrasps"].as_u64().expect("regrasps");
    assert_eq!(
        report["grasps"].as_array().unwrap().len() as u64,
        regrasps + 1
    );
}

#[test]
fn a_prior_where_no_cable_lies_fails_after_its_last_move() {
    let dir = tempfile::tempdir().unwrap();
    // 100 mm above the cable; σ 10 mm would take 7 poses, 5 are allowed.
    let task = task_copy(dir.path(), "nowhere.toml", |t| {
        prior(touch_only(t), 350.0, 10.0, 5)
    });
    let (status, report) = run_json(&task, "config/cell.sim.toml", "3");
    assert_eq!(status, Some(1), "{report}");
    let reason = &report["outcome"]["reason"];
    assert_eq!(reason["reason"], "search_exhausted", "{reason}");
    assert_eq!(reason["search_moves"], 5);
    assert_eq!(reason["prior_in_base_mm"][2], 350.0);
    assert_eq!(report["touch_only"]["search_moves"], 5);
    assert!(report["grasps"].as_array().unwrap().is_empty());
    // The text says what was tried, and where.
    let out = cablecell(&["run", text(&task), "--seed", "3", "--no-record"]);
    assert_eq!(out.status.code(), Some(1));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("vision not used (the task is touch only)"),
        "{stdout}"
    );
    assert!(
        stdout.contains(
            "task failed: no cable felt in 5 search move(s) reaching ±28.4 mm across \
             the prior's grasp frame at (450.0, 0.0, 350.0) mm (σ 10 mm, 0.1 rad)"
        ),
        "{stdout}"
    );
}

#[test]
fn no_cable_in_the_cameras_view_searches_from_the_prior() {
    let dir = tempfile::tempdir().unwrap();
    // The cable 50 mm lower, below the detector's region of interest; the
    // prior knows.
    let cell = sim_cell_copy(dir.path(), |t| {
        t.replace(
            "cable_center_mm = [450.0, 0.0, 250.0]",
            "cable_center_mm = [450.0, 0.0, 200.0]",
        )
    });
    let task = task_copy(dir.path(), "low.toml", |t| prior(t, 205.0, 5.0, 5));
    let (status, report) = run_json(&task, text(&cell), "3");
    assert_eq!(status, Some(0), "{report}");
    assert_eq!(report["touch_only"]["why"], "no_cable_detected");
    assert_eq!(report["touch_only"]["search_moves"], 1);
    assert_eq!(&states(&report)[..3], ["prepare", "detect", "approach"]);
    assert_within_tolerance(&report);
    // Without a prior, the run fails as it always did.
    let no_prior = task_copy(dir.path(), "no-prior.toml", |t| {
        let prior = t
            .find("\n# Where the cable roughly lies")
            .expect("the prior");
        t[..prior].to_owned()
    });
    let (status, report) = run_json(&no_prior, text(&cell), "3");
    assert_eq!(status, Some(1));
    assert_eq!(report["outcome"]["reason"]["reason"], "nothing_detected");
    assert!(report.get("touch_only").is_none());
}

#[test]
fn an_unusable_detector_searches_from_the_prior() {
    let dir = tempfile::tempdir().unwrap();
    // A model file that is no network: the cell loads, the pipeline fails.
    let model = dir.path().join("no-network.onnx");
    std::fs::write(&model, "not a network\n").unwrap();
    let cell = sim_cell_copy(dir.path(), |t| {
        let models = common::root().join("models/cable_segmentation.onnx");
        t.replace(text(&models), text(&model))
    });
    let (status, report) = run_json(&common::root().join("tasks/regrasp.toml"), text(&cell), "3");
    assert_eq!(status, Some(0), "{report}");
    let touch_only = &report["touch_only"];
    assert_eq!(touch_only["why"], "detector_unusable");
    let error = touch_only["error"].as_str().expect("the detector's error");
    assert!(
        error.starts_with("detector: segmentation network"),
        "{error}"
    );
}

#[test]
fn a_touch_only_task_without_a_prior_is_refused_at_its_line() {
    let dir = tempfile::tempdir().unwrap();
    let task = task_copy(dir.path(), "bad.toml", |t| {
        let prior = t
            .find("\n# Where the cable roughly lies")
            .expect("the prior");
        touch_only(t[..prior].to_owned())
    });
    let out = cablecell(&["check", text(&task)]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("bad.toml:8:1: task.touch_only: a touch-only task searches"),
        "{stderr}"
    );
    // The prior's values are range-checked at their line.
    let task = task_copy(dir.path(), "bad-sigma.toml", |t| {
        t.replace("position_sigma_mm = 5.0", "position_sigma_mm = -5.0")
    });
    let written = std::fs::read_to_string(&task).unwrap();
    let line = 1 + written
        .lines()
        .position(|l| l.starts_with("position_sigma_mm"))
        .unwrap();
    let out = cablecell(&["check", text(&task)]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains(&format!(
            "bad-sigma.toml:{line}:21: prior.position_sigma_mm: expected a number > 0"
        )),
        "{stderr}"
    );
}

#[test]
fn the_touch_only_campaign_counts_search_moves() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let summary = json_of(&[
        "campaign",
        "tasks/touch-only-campaign.toml",
        "--trials",
        "4",
        "--out",
        text(&out),
        "--no-record",
        "--json",
    ]);
    for policy in summary["policies"].as_array().expect("policies") {
        assert_eq!(policy["success"]["successes"], 4, "{policy}");
        // Within ±5 mm the prior's mean is within the pad's band.
        assert_eq!(policy["search_moves_per_trial"]["mean"], 1.0, "{policy}");
    }
    let journal = std::fs::read_to_string(out.join("trials.jsonl")).unwrap();
    assert!(
        journal
            .lines()
            .all(|line| line.contains("\"search_moves\":1")),
        "{journal}"
    );
}

#[test]
fn a_miss_is_recorded_as_a_grasp_that_a_replay_fits_again() {
    use cablecell::orchestrator::Runner;
    use cablecell::perception::tactile::{Estimator, FitError};
    use cablecell::recording::replay::Replay;
    use cablecell::recording::{Recording, Topic};

    let dir = tempfile::tempdir().unwrap();
    // A threshold above any Δv: the pad feels nothing even when the jaws
    // hold the cable. The prior's poses are 0, +10.65 and −10.65 mm; the
    // cable, 5 mm below the mean, is caught by the first and the third.
    let mut task = cablecell::task::load_task(&common::root().join("tasks/regrasp.toml")).unwrap();
    task.task.touch_only = true;
    task.tactile.contact_threshold_v = 3.0;
    let cell = cablecell::cell::load_cell(&common::root().join("config/cell.sim.toml")).unwrap();
    let mut runner = Runner::for_task(&task, &cell, 3).unwrap();
    let path = dir.path().join("misses.mcap");
    runner.record_to(&path, false).unwrap();
    runner.run_to_end().unwrap();
    runner.finish_recording().unwrap();
    let record = runner.into_record();
    let touch_only = record.touch_only.as_ref().expect("searched");
    assert_eq!(touch_only.search_moves, 3);
    assert_eq!(touch_only.misses.len(), 2);
    let recording = Recording::read(&path).unwrap();
    assert_eq!(recording.count(Topic::TactileFit), 2);
    let refits = Replay::of(&recording).unwrap().refit(Estimator::Centroids);
    assert_eq!(refits.len(), 2);
    for refit in refits {
        assert_eq!(refit.frames, task.tactile.average_frames);
        assert!(matches!(refit.line, Err(FitError::NoContact { .. })));
    }
}
