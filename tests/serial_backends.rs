//! The serial devices' cell-file backends: the real ones opened by their
//! port's path (here the path of an emulator's pseudo-terminal), refusals
//! of bad tables with file, line and field, and a port that is not there.

mod common;

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

use cablecell::cell::CellDevices;
use cablecell::cell::load_cell;
use cablecell::hw::emulator::PtyEmulator;
use cablecell::hw::gripper::config::GripperBackend;
use cablecell::hw::gripper::pg70_emulator::{FreeJaws, Pg70Emulator};
use cablecell::hw::tactile::config::TactileBackend;
use cablecell::hw::tactile::remodel_emulator::TactileEmulator;
use cablecell::hw::{DeviceError, DeviceKind};
use cablecell::perception::tactile::{RawFrame, TAXEL_COUNT};
use serialport::TTYPort;

/// An emulator serving a pseudo-terminal whose slave end stays open (so
/// the master's reads keep working) for a driver to open by path.
struct Served {
    emulator: PtyEmulator,
    _slave: TTYPort,
}

impl Served {
    fn start(serve: impl FnOnce(TTYPort, &AtomicBool) + Send + 'static) -> Self {
        let (emulator, slave) = PtyEmulator::start(serve).expect("a pseudo-terminal");
        Self {
            emulator,
            _slave: slave,
        }
    }

    fn path(&self) -> &str {
        self.emulator.path()
    }
}

/// Frame n: taxel k reads 100·k + n.
fn frame(n: u16) -> RawFrame {
    std::array::from_fn(|k| 100 * k as u16 + n)
}

/// `config/cell.sim.toml` with its gripper and tactile tables replaced.
fn cell_text(gripper: &str, tactile: &str) -> String {
    let text = common::sim_cell_text();
    let gripper_at = text.find("[gripper.backend.sim]").expect("gripper table");
    let tactile_table = text.find("[tactile.backend.sim]").expect("tactile table");
    let camera_at = text.find("[camera]").expect("camera table");
    let tactile_at = text.find("[tactile]").expect("tactile section");
    format!(
        "{}{gripper}\n\n{}{tactile}\n\n{}",
        &text[..gripper_at],
        &text[tactile_at..tactile_table],
        &text[camera_at..]
    )
}

fn write(dir: &Path, text: &str) -> PathBuf {
    let path = dir.join("cell.toml");
    std::fs::write(&path, text).expect("write");
    path
}

#[test]
fn the_real_backends_open_their_ports_and_speak_through_the_drivers() {
    let gripper = Served::start(|master, stop| {
        Pg70Emulator::new(7, FreeJaws::new(Some(2.5))).serve(master, stop)
    });
    // The emulated pad sends taxel k on channel 24 − k.
    let reversed: [usize; TAXEL_COUNT] = std::array::from_fn(|k| TAXEL_COUNT - 1 - k);
    let tactile = Served::start(move |master, stop| {
        let mut n = 0;
        TactileEmulator::new(reversed, move || {
            n += 1;
            Some(frame(n))
        })
        .serve(master, stop)
    });
    let layout: Vec<String> = reversed.iter().map(usize::to_string).collect();
    let text = cell_text(
        &format!(
            "[gripper.backend.pg70]\nport = \"{}\"\nmodule_id = 7\nmotion = {{ speed_mm_s = 50.0, accel_mm_s2 = 200.0 }}",
            gripper.path()
        ),
        &format!(
            "[tactile.backend.remodel]\nport = \"{}\"\nlayout = [{}]\ndeadline_ms = 200",
            tactile.path(),
            layout.join(", ")
        ),
    );
    let dir = tempfile::tempdir().expect("scratch");
    let file = load_cell(&write(dir.path(), &text)).expect("a cell with real backends");
    let mut cell = CellDevices::build(&file, 1).expect("the ports open");
    cell.gripper.reference().expect("reference");
    cell.gripper.move_to(20.0).expect("open");
    assert!(matches!(
        cell.gripper.grip(1.0),
        Ok(cablecell::hw::gripper::GripOutcome::Holding { .. })
    ));
    // Polled on its own thread: consecutive reads give later and later
    // frames, each in taxel order.
    let first = cell.tactile.read().expect("a frame");
    let second = cell.tactile.read().expect("a frame");
    let n = first.raw[0];
    assert_eq!(first.raw, frame(n));
    assert!(second.raw[0] > n);
    assert_eq!(second.raw, frame(second.raw[0]));
}

#[test]
fn a_port_that_is_not_there_is_named_and_nothing_runs() {
    let text = cell_text(
        "[gripper.backend.pg70]\nport = \"/dev/no-such-pg70\"\nmodule_id = 12",
        "[tactile.backend.sim]\nline_spread_pitch = 0.55\nspan_v = 1.2\nrest_v = [0.9, 1.5]\ngain_spread = 0.1\nnoise_fraction = 0.02",
    );
    let dir = tempfile::tempdir().expect("scratch");
    let path = write(dir.path(), &text);
    let file = load_cell(&path).expect("a valid cell file");
    match CellDevices::build(&file, 1) {
        Err(DeviceError::Disconnected {
            device,
            port,
            reason,
        }) => {
            assert_eq!(
                (device, port.as_str()),
                (DeviceKind::Gripper, "/dev/no-such-pg70")
            );
            assert!(reason.contains("cannot open the port"), "{reason}");
        }
        Err(other) => panic!("{other:?}"),
        Ok(_) => panic!("a cell on a missing port"),
    }
    let out = common::command()
        .args(["run", "tasks/regrasp.toml", "--cell"])
        .arg(&path)
        .output()
        .expect("runs");
    assert_eq!(out.status.code(), Some(3), "a device fault");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("gripper on /dev/no-such-pg70: link lost: cannot open the port"),
        "{err}"
    );
}

/// `cablecell check` on the emulated cell with `from` replaced by `to`:
/// its error message, which must point at the last line of `to`.
fn check_error(from: &str, to: &str) -> String {
    let text =
        std::fs::read_to_string(common::root().join("config/cell.emulated.toml")).expect("cell");
    assert!(text.contains(from), "{from}");
    let text = text.replacen(from, to, 1);
    let last = to.lines().last().unwrap_or(to);
    let line = text.lines().position(|l| l.contains(last)).expect("line") + 1;
    let dir = tempfile::tempdir().expect("scratch");
    let path = write(dir.path(), &text);
    let out = common::command()
        .args(["check"])
        .arg(&path)
        .output()
        .expect("runs");
    assert_eq!(out.status.code(), Some(2), "bad input");
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(
        err.contains(&format!("{}:{line}:", path.display())),
        "line {line}: {err}"
    );
    err
}

#[test]
fn a_taxel_layout_that_is_not_a_permutation_is_refused_at_its_line() {
    let err = check_error("layout = [20, 21,", "layout = [20, 20,");
    assert!(
        err.contains("tactile.backend.emulated_remodel.layout"),
        "{err}"
    );
    assert!(err.contains("found 20 twice"), "{err}");
    let err = check_error("layout = [20, 21,", "layout = [25, 21,");
    assert!(err.contains("found 25 out of range"), "{err}");
}

#[test]
fn an_inverted_workspace_box_is_refused_at_its_line() {
    let err = check_error("min_mm = [250.0,", "min_mm = [700.0,");
    assert!(err.contains("arm.workspace"), "{err}");
    assert!(err.contains("min_mm below max_mm"), "{err}");
}

#[test]
fn an_unknown_fault_is_refused_with_the_known_ones() {
    let err = check_error(
        "module_id = 12",
        "module_id = 12\nfault = { misbehaviour = \"explode\" }",
    );
    assert!(
        err.contains("gripper.backend.emulated_pg70.fault.misbehaviour"),
        "{err}"
    );
    assert!(err.contains("unknown variant `explode`"), "{err}");
    assert!(err.contains("`vanish`"), "{err}");
}

#[test]
fn the_real_backends_defaults_are_the_devices_own() {
    let text = cell_text(
        "[gripper.backend.pg70]\nport = \"/dev/ttyUSB0\"\nmodule_id = 12",
        "[tactile.backend.remodel]\nport = \"/dev/ttyACM0\"",
    );
    let dir = tempfile::tempdir().expect("scratch");
    let file = load_cell(&write(dir.path(), &text)).expect("a lab cell");
    let GripperBackend::Pg70(pg70) = &file.gripper.backend else {
        panic!("{:?}", file.gripper.backend);
    };
    assert_eq!(
        (pg70.baud, pg70.reply_timeout_ms, pg70.move_timeout_ms),
        (9600, 500, 10_000)
    );
    assert!(pg70.motion.is_none());
    let TactileBackend::Remodel(remodel) = &file.tactile.backend else {
        panic!("{:?}", file.tactile.backend);
    };
    assert_eq!((remodel.baud, remodel.deadline_ms), (1_000_000, 20));
    assert_eq!(remodel.layout, std::array::from_fn(|k| k));
    assert_eq!(file.tactile.rate_hz, 500.0);
}
