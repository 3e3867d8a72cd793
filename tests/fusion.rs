//! Vision and touch fused (the paper's Fig. 12) on the simulated cell:
//! every grasp's shapes in the run record, their distances to the true
//! cable, the recording's channel, and `cablecell plot fusion`.

use std::path::Path;

mod common;

use common::{root, text};

use cablecell::orchestrator::Runner;
use cablecell::perception::shape::StretchErrors;
use cablecell::perception::tactile::Estimator;
use cablecell::record::{RunRecord, ShapeErrors, TactileShape};
use cablecell::recording::schema::CableShapesMessage;
use cablecell::recording::{Recording, Topic};
use cablecell::task::{TaskFile, load_task};

fn task() -> TaskFile {
    load_task(&root().join("tasks/regrasp.toml")).expect("the shipped task")
}

/// The regrasp task with `seed` on the simulated cell whose detector is
/// the oracle that misses by σ = 3 mm and 0.2 rad, recorded to `path` if
/// given.
fn run(task: &TaskFile, seed: u64, path: Option<&Path>) -> RunRecord {
    let cell = common::sim_cell_with_oracle();
    let mut runner = Runner::for_task(task, &cell, seed).expect("a simulated cell builds");
    if let Some(path) = path {
        runner.record_to(path, false).expect("a recording");
    }
    runner.run_to_end().expect("the run is recorded");
    runner.finish_recording().expect("the recording ends");
    runner.into_record()
}

/// Mean over the grasps of one stretch's mean distance.
fn mean(
    errors: &[ShapeErrors],
    pick: impl Fn(&ShapeErrors) -> Option<StretchErrors>,
    beyond: bool,
) -> f64 {
    let values: Vec<f64> = errors
        .iter()
        .filter_map(&pick)
        .filter_map(|e| if beyond { e.beyond } else { e.grasped })
        .map(|d| d.mean_mm)
        .collect();
    assert_eq!(values.len(), errors.len());
    values.iter().sum::<f64>() / values.len() as f64
}

#[test]
fn every_grasp_has_its_shapes_and_fusion_beats_vision_where_touch_is() {
    let task = task();
    let mut errors = Vec::new();
    for seed in 1..=8 {
        let record = run(&task, seed, None);
        assert!(!record.grasps.is_empty(), "seed {seed}");
        for grasp in &record.grasps {
            let shapes = grasp.shapes.as_ref().expect("shapes");
            // The oracle's centre line from support to support, the
            // pad's fits over the pad, the fused curve over all.
            assert_eq!(shapes.vision.as_ref().map(Vec::len), Some(151));
            let linear = shapes.tactile_linear.as_ref().expect("linear");
            assert!((15..=25).contains(&linear.len()), "{}", linear.len());
            assert!(shapes.tactile_quadratic.is_some());
            assert!(shapes.tactile_ridge.is_none());
            assert_eq!(shapes.fused_from, Some(TactileShape::Quadratic));
            // (As long as the vision shape along the pad's x, which it crosses
            // at the grasp's angle.)
            assert!(shapes.fused.as_ref().expect("fused").len() > 120);
            assert!(shapes.truth.is_some());
            // Surer on the pad than anywhere else.
            let fused = shapes.fused.as_ref().unwrap();
            let sigma_on_pad = fused
                .iter()
                .map(|p| (shapes.base_from_sensor.translation.vector - p.in_base_mm.coords).norm())
                .zip(fused)
                .min_by(|a, b| a.0.total_cmp(&b.0))
                .map(|(_, p)| p.sigma_mm)
                .unwrap();
            assert!(sigma_on_pad < 0.2, "{sigma_on_pad}");
            errors.push(shapes.errors.expect("a simulated cell knows the truth"));
        }
    }
    let vision = (
        mean(&errors, |e| e.vision, false),
        mean(&errors, |e| e.vision, true),
    );
    let quadratic = mean(&errors, |e| e.tactile_quadratic, false);
    let fused = (
        mean(&errors, |e| e.fused, false),
        mean(&errors, |e| e.fused, true),
    );
    // On the pad touch is millimetres better than this oracle's vision,
    // and the fusion follows it; beyond, the fusion still gains on vision
    // alone from touch's direction.
    assert!(fused.0 < 2.0 * quadratic, "{fused:?} {quadratic}");
    assert!(fused.0 < 0.2 * vision.0, "{fused:?} {vision:?}");
    assert!(fused.1 < vision.1, "{fused:?} {vision:?}");
}

#[test]
fn with_the_ridge_estimator_its_line_is_fused() {
    let mut task = task();
    task.tactile.estimator = Estimator::Ridge;
    let record = run(&task, 3, None);
    for grasp in &record.grasps {
        let shapes = grasp.shapes.as_ref().expect("shapes");
        assert_eq!(shapes.fused_from, Some(TactileShape::Ridge));
        assert!(shapes.tactile_ridge.is_some());
        // The paper's fits are there all the same.
        assert!(shapes.tactile_linear.is_some() && shapes.tactile_quadratic.is_some());
        let errors = shapes.errors.expect("errors");
        let ridge = errors.tactile_ridge.and_then(|e| e.grasped).expect("ridge");
        assert!(ridge.mean_mm < 0.5, "{ridge:?}");
    }
}

#[test]
fn the_recording_holds_the_shapes_and_plot_fusion_draws_them() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("run.mcap");
    let record = run(&task(), 3, Some(&path));
    assert!(record.grasps.len() >= 2, "seed 3 regrasps");
    let recording = Recording::read(&path).unwrap();
    let messages: Vec<CableShapesMessage> = recording.decode(Topic::CableShapes).unwrap();
    assert_eq!(messages.len(), record.grasps.len());
    for (message, grasp) in messages.iter().zip(&record.grasps) {
        assert_eq!(message.attempt, grasp.attempt);
        let recorded = message.shapes.fused.as_ref().unwrap();
        let kept = grasp.shapes.as_ref().unwrap().fused.as_ref().unwrap();
        assert_eq!(recorded.len(), kept.len());
        // Rounded to 0.1 µm.
        for (a, b) in recorded.iter().zip(kept) {
            assert!((a.in_base_mm - b.in_base_mm).norm() < 1e-4);
        }
    }

    let svg = dir.path().join("fig12.svg");
    let out = common::cablecell(&[
        "plot",
        "fusion",
        text(&path),
        "--grasp",
        "1",
        "--out",
        text(&svg),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let drawn = std::fs::read_to_string(&svg).unwrap();
    assert!(drawn.contains("Vision and touch fused at the regrasp 1, regrasp seed 3"));
    for label in [
        "true cable",
        "vision (camera)",
        "touch: linear fit",
        "fused: vision",
    ] {
        assert!(drawn.contains(label), "no {label:?}");
    }
    // By default a PNG beside the recording, of the trial grasp.
    let out = common::cablecell(&["plot", "fusion", text(&path)]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let png = dir.path().join("run-fusion-0.png");
    assert!(std::fs::metadata(&png).unwrap().len() > 10_000);

    // A grasp the run did not make, or a format that is not drawn: bad
    // input.
    for args in [
        vec!["plot", "fusion", text(&path), "--grasp", "7"],
        vec!["plot", "fusion", text(&path), "--out", "fig.pdf"],
    ] {
        let out = common::cablecell(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(stderr.starts_with("error: "), "{stderr}");
    }
}
