//! A run says what it left out because the scene did not need it: the
//! network on a plain background, the regrasp after a trial grasp within
//! tolerance.

use std::path::Path;

use cablecell::cell::{CellFile, load_cell};
use cablecell::detector::config::DetectorBackend;
use cablecell::hw::camera::config::CameraBackend;
use cablecell::orchestrator::Runner;
use cablecell::perception::vision::MaskMethod;
use cablecell::record::{RunOutcome, RunRecord, Skipped};
use cablecell::sim::render::Background;
use cablecell::task::load_task;

fn shipped_cell() -> CellFile {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    load_cell(&root.join("config/cell.sim.toml")).expect("the shipped cell")
}

fn run(cell: &CellFile, seed: u64) -> RunRecord {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let task = load_task(&root.join("tasks/regrasp.toml")).expect("the shipped task");
    let mut runner = Runner::for_task(&task, cell, seed).expect("a simulated cell");
    runner.run_to_end().expect("no recording to fail");
    runner.into_record()
}

fn skipped(record: &RunRecord) -> Vec<Skipped> {
    record.skipped.iter().map(|s| s.what).collect()
}

#[test]
fn a_trial_grasp_within_tolerance_lists_no_regrasp() {
    let record = run(&shipped_cell(), 1);
    assert!(matches!(
        record.outcome,
        Some(RunOutcome::Success { regrasps: 0 })
    ));
    let regrasp = record
        .skipped
        .iter()
        .find(|s| s.what == Skipped::Regrasp)
        .expect("the regrasp skipped");
    assert!(regrasp.why.contains("within tolerance"), "{}", regrasp.why);
    // The shipped cell's camera sees a workbench through a region of
    // interest, one cable: its network runs, crossings and the image
    // outside the region do not.
    let skips = skipped(&record);
    assert!(!skips.contains(&Skipped::Network), "{skips:?}");
    assert!(skips.contains(&Skipped::CrossingResolution), "{skips:?}");
    assert!(skips.contains(&Skipped::ImageOutsideRoi), "{skips:?}");
    let json = serde_json::to_value(&record).expect("JSON");
    assert!(
        json["skipped"]
            .as_array()
            .expect("a list")
            .iter()
            .any(|s| s["what"] == "regrasp")
    );
}

#[test]
fn a_run_on_a_plain_background_lists_no_network() {
    let mut cell = shipped_cell();
    let CameraBackend::Sim(camera) = &mut cell.camera.backend else {
        panic!("the shipped camera is simulated");
    };
    camera.background = Background::Plain {
        bgr: [200, 200, 200],
    };
    let DetectorBackend::Vision(vision) = &mut cell.detector.backend else {
        panic!("the shipped detector is the vision pipeline");
    };
    vision.mask = MaskMethod::Auto;
    let record = run(&cell, 1);
    assert!(matches!(record.outcome, Some(RunOutcome::Success { .. })));
    let network = record
        .skipped
        .iter()
        .find(|s| s.what == Skipped::Network)
        .expect("the network skipped");
    assert!(network.why.contains("plain background"), "{}", network.why);
}
