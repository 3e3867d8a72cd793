//! The task on the emulated cell (`config/cell.emulated.toml`): the real
//! PG70 and tactile drivers talking over pseudo-terminals to emulators that
//! act on the simulated world; and every fault the devices can show, each
//! taken through the state machine to its fault state, with the cell made
//! safe and the record kept up to the fault.

mod common;

use std::path::Path;

use cablecell::cell::CellDevices;
use cablecell::cell::CellFile;
use cablecell::cell::load_cell;
use cablecell::hw::DeviceKind;
use cablecell::hw::emulator::{Fault, FaultSwitch};
use cablecell::hw::gripper::config::GripperBackend;
use cablecell::hw::gripper::pg70_emulator as pg70;
use cablecell::hw::tactile::remodel_emulator as tactile;
use cablecell::orchestrator::{Plan, Runner};
use cablecell::record::{RunOutcome, RunRecord};
use cablecell::sim::world::{SharedWorld, lock};
use cablecell::task::{TaskFile, load_task};

const SEED: u64 = 3;

fn shipped() -> (TaskFile, CellFile) {
    let task = load_task(&common::root().join("tasks/regrasp.toml")).expect("task");
    let cell = load_cell(&common::root().join("config/cell.emulated.toml")).expect("cell");
    (task, cell)
}

/// The fault switches of a running emulated cell.
struct Switches {
    gripper: FaultSwitch<pg70::Misbehaviour>,
    tactile: FaultSwitch<tactile::Misbehaviour>,
}

/// Runs `task` on the cell of `cell_file`; when the machine enters state
/// `switch_in`, `switch` may make a device fail there.
fn run(
    task: &TaskFile,
    cell_file: &CellFile,
    switch_in: &str,
    switch: impl FnOnce(&Switches),
) -> (RunRecord, SharedWorld) {
    let cell = CellDevices::build(cell_file, SEED).expect("the emulated cell starts");
    let world = cell.world();
    let switches = Switches {
        gripper: cell
            .emulators
            .gripper_fault
            .clone()
            .expect("an emulated PG70"),
        tactile: cell
            .emulators
            .tactile_fault
            .clone()
            .expect("an emulated pad"),
    };
    let mut runner = Runner::new(Plan::new(task, cell_file), cell, &task.task.name, SEED);
    let mut switch = Some(switch);
    while runner
        .step()
        .expect("an unrecorded run has no recording to fail")
    {
        if runner.record().current_state() == Some(switch_in)
            && let Some(switch) = switch.take()
        {
            switch(&switches);
        }
    }
    assert!(runner.state().is_final(), "ended in {:?}", runner.state());
    (runner.into_record(), world)
}

/// The fault's state, device and message, after checking what every
/// fault must leave: the fault state, its safe stop done, and the record
/// of every transition up to it.
fn fault_of(record: &RunRecord) -> (&'static str, Option<DeviceKind>, String) {
    assert_eq!(record.current_state(), Some("fault"));
    let Some(RunOutcome::Fault {
        state,
        device,
        error,
    }) = record.outcome.clone()
    else {
        panic!("not a fault: {:?}", record.outcome);
    };
    let path: Vec<&str> = record.transitions.iter().map(|t| t.to).collect();
    let faulted_at = path.len() - 1;
    assert_eq!(path[faulted_at], "fault");
    assert_eq!(record.transitions[faulted_at].from, state, "{path:?}");
    assert_eq!(path[0], "prepare", "{path:?}");
    for problem in &record.safe_stop_problems {
        assert!(!problem.starts_with("arm"), "the arm must stop: {problem}");
    }
    (state, device, error)
}

fn jaws(world: &SharedWorld) -> (f64, bool) {
    let world = lock(world);
    (world.opening_mm, world.grasp.is_some())
}

#[test]
fn the_task_runs_through_the_real_drivers_on_the_emulated_cell() {
    let (task, cell) = shipped();
    let (record, world) = run(&task, &cell, "", |_| {});
    assert!(
        matches!(record.outcome, Some(RunOutcome::Success { .. })),
        "{:?}",
        record.outcome
    );
    assert!(record.grasps.len() >= 2, "a trial grasp and a regrasp");
    // The maps came through the driver, the taxel layout undone: each
    // estimate agrees with where the simulated cable really lay.
    for grasp in &record.grasps {
        let truth = grasp.truth.as_ref().expect("the simulated truth");
        let error = truth.estimate_error.expect("an estimate");
        assert!(error.n_mm.abs() < 0.5, "{error:?}");
        assert!(error.alpha_rad.abs() < 0.1, "{error:?}");
    }
    // The emulated PG70 moved the simulated jaws: they hold the cable.
    let (_, holding) = jaws(&world);
    assert!(holding);
}

#[test]
fn a_gripper_that_misbehaves_mid_task_is_a_clear_fault_with_the_arm_stopped() {
    let (task, cell) = shipped();
    for (misbehaviour, expected) in [
        (
            pg70::Misbehaviour::Garbage,
            "garbled answer: no whole answer to grip",
        ),
        (pg70::Misbehaviour::Truncated, "unfinished frame"),
        (
            pg70::Misbehaviour::Silent,
            "no answer to grip within 500 ms",
        ),
        (pg70::Misbehaviour::BadCrc, "wrong CRC"),
        (
            pg70::Misbehaviour::ErrorFrame(0xD9),
            "refused grip: error 0xD9: emergency stop",
        ),
        (pg70::Misbehaviour::Vanish, "link lost"),
    ] {
        // Switched on as the trial grasp begins: its grip is the first
        // request to suffer.
        let (record, _) = run(&task, &cell, "trial_grasp", |switches| {
            switches.gripper.set(Some(Fault::now(misbehaviour)))
        });
        let (state, device, error) = fault_of(&record);
        assert_eq!(state, "trial_grasp", "{misbehaviour:?}");
        assert_eq!(device, Some(DeviceKind::Gripper), "{misbehaviour:?}");
        assert!(error.contains(expected), "{misbehaviour:?}: {error}");
        // The gripper cannot be made safe through a broken link; the
        // record says so.
        assert!(
            record
                .safe_stop_problems
                .iter()
                .any(|p| p.starts_with("gripper")),
            "{misbehaviour:?}: {:?}",
            record.safe_stop_problems
        );
        assert!(record.grasps.is_empty());
    }
}

#[test]
fn a_device_error_frame_from_the_start_faults_before_the_arm_moves() {
    // A device error frame from the first request on: the task never
    // moves the arm.
    let (task, mut cell) = shipped();
    let GripperBackend::EmulatedPg70(emulated) = &mut cell.gripper.backend else {
        panic!("the emulated cell's gripper is emulated");
    };
    emulated.fault = Some(Fault::now(pg70::Misbehaviour::ErrorFrame(0x74)));
    let (record, world) = run(&task, &cell, "", |_| {});
    let (state, device, error) = fault_of(&record);
    assert_eq!((state, device), ("prepare", Some(DeviceKind::Gripper)));
    assert!(error.contains("motor voltage low"), "{error}");
    let path: Vec<&str> = record.transitions.iter().map(|t| t.to).collect();
    assert_eq!(path, ["prepare", "fault"]);
    let (_, holding) = jaws(&world);
    assert!(!holding);
}

#[test]
fn the_gripper_port_vanishing_set_in_the_cell_file_ends_the_task_in_its_fault_state() {
    // The cell file's own fault knob: the module vanishes after the two
    // requests of `prepare` (reference, open).
    let text =
        std::fs::read_to_string(common::root().join("config/cell.emulated.toml")).expect("cell");
    let text = text.replacen(
        "module_id = 12",
        "module_id = 12\nfault = { misbehaviour = \"vanish\", after_requests = 2 }",
        1,
    );
    let dir = tempfile::tempdir().expect("scratch");
    let path = dir.path().join("cell.toml");
    std::fs::write(&path, text).expect("write");
    let cell = load_cell(&path).expect("the fault knob parses");
    let task = load_task(&common::root().join("tasks/regrasp.toml")).expect("task");
    let (record, _) = run(&task, &cell, "", |_| {});
    let (state, device, error) = fault_of(&record);
    assert_eq!((state, device), ("trial_grasp", Some(DeviceKind::Gripper)));
    assert!(error.contains("link lost"), "{error}");
    assert!(error.contains("/dev/pts/"), "names the port: {error}");
}

#[test]
fn a_tactile_sensor_that_fails_during_the_grasp_faults_and_the_jaws_let_go() {
    let (task, cell) = shipped();
    for (misbehaviour, expected) in [
        (
            tactile::Misbehaviour::Silent,
            "no answer to sample within 200 ms",
        ),
        (
            tactile::Misbehaviour::Truncated,
            "answer cut short: 25 of 50 bytes",
        ),
        (tactile::Misbehaviour::Garbage, "is not 12-bit"),
        (tactile::Misbehaviour::StrayByte, "is not 12-bit"),
        (tactile::Misbehaviour::Vanish, "link lost"),
    ] {
        // Switched on once the jaws have closed on the cable, before the
        // pad is read.
        let (record, world) = run(&task, &cell, "evaluate", |switches| {
            switches.tactile.set(Some(Fault::now(misbehaviour)))
        });
        let (state, device, error) = fault_of(&record);
        assert_eq!(state, "evaluate", "{misbehaviour:?}");
        assert_eq!(device, Some(DeviceKind::Tactile), "{misbehaviour:?}");
        assert!(error.contains(expected), "{misbehaviour:?}: {error}");
        // Made safe: the jaws stopped and opened, the cable let go.
        assert!(
            record.safe_stop_problems.is_empty(),
            "{:?}",
            record.safe_stop_problems
        );
        let (opening_mm, holding) = jaws(&world);
        assert_eq!(opening_mm, task.grasp.open_mm);
        assert!(!holding);
        // Everything up to the fault is in the record.
        let path: Vec<&str> = record.transitions.iter().map(|t| t.to).collect();
        assert_eq!(
            path,
            [
                "prepare",
                "detect",
                "approach",
                "trial_grasp",
                "evaluate",
                "fault"
            ]
        );
    }
}

#[test]
fn a_wild_regrasp_correction_is_refused_by_the_workspace_box() {
    // A correction a hundred times too large, as a bad tactile map could
    // give: the regrasp's target lies far outside the cell's box.
    let (mut task, cell) = shipped();
    task.regrasp.correction_gain.n = 100.0;
    let (record, world) = run(&task, &cell, "", |_| {});
    let (state, device, error) = fault_of(&record);
    assert_eq!((state, device), ("regrasp", Some(DeviceKind::Arm)));
    assert!(error.contains("outside the workspace box"), "{error}");
    assert_eq!(record.grasps.len(), 1, "the trial grasp is kept");
    let (opening_mm, holding) = jaws(&world);
    assert_eq!(opening_mm, task.grasp.open_mm);
    assert!(!holding);
}

#[test]
fn cablecell_run_on_the_emulated_cell_succeeds_and_a_device_fault_exits_with_3() {
    let run = |cell: &Path| {
        common::command()
            .args(["run", "tasks/regrasp.toml", "--seed", "3", "--cell"])
            .arg(cell)
            .output()
            .expect("runs")
    };
    let out = run(Path::new("config/cell.emulated.toml"));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{stdout}");
    assert!(
        stdout.contains("task regrasp on emulated cell (seed 3)"),
        "{stdout}"
    );
    assert!(stdout.contains("success: within tolerance"), "{stdout}");

    let text =
        std::fs::read_to_string(common::root().join("config/cell.emulated.toml")).expect("cell");
    let text = text.replacen(
        "module_id = 12",
        "module_id = 12\nfault = { misbehaviour = { error_frame = 0xDA }, after_requests = 2 }",
        1,
    );
    let dir = tempfile::tempdir().expect("scratch");
    let path = dir.path().join("cell.toml");
    std::fs::write(&path, text).expect("write");
    let out = run(&path);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(3), "{stdout}");
    assert!(
        stdout.contains(
            "device fault in trial_grasp (gripper): gripper: refused grip: error 0xDA: tow error"
        ),
        "{stdout}"
    );
}
