//! The PG70 driver against the emulated module on a pseudo-terminal,
//! including the module misbehaving and the port vanishing.

use std::time::Duration;

use cablecell::hw::DeviceError;
use cablecell::hw::emulator::Fault;
use cablecell::hw::emulator::PtyEmulator;
use cablecell::hw::gripper::pg70_emulator::{FreeJaws, Misbehaviour, Pg70Emulator};
use cablecell::hw::gripper::{GripOutcome, Gripper, Pg70};
use serialport::{SerialPort, TTYPort};

struct Bench {
    driver: Pg70<TTYPort>,
    emulator: PtyEmulator,
}

impl Bench {
    fn new(misbehaviour: Option<Misbehaviour>, object_mm: Option<f64>) -> Self {
        let (emulator, mut slave) = PtyEmulator::start(move |master, stop| {
            let mut module = Pg70Emulator::new(12, FreeJaws::new(object_mm));
            module.fault.set(misbehaviour.map(Fault::now));
            module.serve(master, stop);
        })
        .expect("a pseudo-terminal");
        slave
            .set_timeout(Duration::from_millis(5))
            .expect("timeout");
        Self {
            driver: Pg70::new(slave, emulator.path(), 12),
            emulator,
        }
    }

    /// Closes the emulator's end: the device is unplugged.
    fn unplug(&mut self) {
        self.emulator
            .unplug()
            .expect("the emulator thread ends well");
    }
}

#[test]
fn a_grasp_refuses_moves_before_referencing_then_holds_the_cable() {
    let mut bench = Bench::new(None, Some(2.5));
    match bench.driver.move_to(20.0) {
        Err(DeviceError::Refused { reason, .. }) => {
            assert!(reason.contains("0x06: not referenced"), "{reason}")
        }
        other => panic!("{other:?}"),
    }
    bench.driver.reference().expect("reference");
    bench.driver.move_to(20.0).expect("open");
    match bench.driver.grip(1.0).expect("grip") {
        GripOutcome::Holding { opening_mm } => assert!((opening_mm - 2.5).abs() < 1e-6),
        GripOutcome::Empty => panic!("the cable was between the jaws"),
    }
    bench.driver.move_to(20.0).expect("release");
    bench.driver.stop().expect("stop");
}

#[test]
fn closing_on_nothing_is_an_empty_grip() {
    let mut bench = Bench::new(None, None);
    bench.driver.reference().expect("reference");
    bench.driver.move_to(20.0).expect("open");
    assert_eq!(bench.driver.grip(1.0).expect("grip"), GripOutcome::Empty);
}

#[test]
fn a_move_beyond_the_stroke_is_refused_with_its_meaning() {
    let mut bench = Bench::new(None, None);
    bench.driver.reference().expect("reference");
    match bench.driver.move_to(90.0) {
        Err(DeviceError::Refused { reason, .. }) => {
            assert!(reason.contains("soft limit high"), "{reason}")
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn garbage_on_the_line_is_skipped() {
    let mut bench = Bench::new(Some(Misbehaviour::GarbageFirst), Some(3.0));
    bench.driver.reference().expect("reference through garbage");
    bench.driver.move_to(20.0).expect("open through garbage");
    assert!(matches!(
        bench.driver.grip(1.0),
        Ok(GripOutcome::Holding { .. })
    ));
}

#[test]
fn silence_times_out() {
    let mut bench = Bench::new(Some(Misbehaviour::Silent), None);
    match bench.driver.reference() {
        Err(DeviceError::NoAnswer {
            command, waited_ms, ..
        }) => assert_eq!((command, waited_ms), ("reference", 500)),
        other => panic!("{other:?}"),
    }
}

#[test]
fn garbage_bad_crcs_and_truncated_answers_are_garbled_and_say_what_came() {
    for (misbehaviour, expected) in [
        (Misbehaviour::Garbage, "byte(s) discarded"),
        (Misbehaviour::BadCrc, "wrong CRC"),
        (Misbehaviour::Truncated, "unfinished frame"),
    ] {
        let mut bench = Bench::new(Some(misbehaviour), None);
        match bench.driver.reference() {
            Err(DeviceError::Garbled { detail, .. }) => {
                assert!(detail.contains("no whole answer to reference within 500 ms"));
                assert!(detail.contains(expected), "{misbehaviour:?}: {detail}")
            }
            other => panic!("{misbehaviour:?}: {other:?}"),
        }
    }
}

#[test]
fn an_error_message_ends_the_wait_with_its_meaning() {
    let mut bench = Bench::new(Some(Misbehaviour::ErrorFrame(0xD9)), None);
    match bench.driver.reference() {
        Err(DeviceError::Refused { reason, .. }) => {
            assert!(reason.contains("0xD9: emergency stop"), "{reason}")
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn an_unplugged_module_is_a_lost_link_that_names_the_port() {
    let mut bench = Bench::new(None, None);
    bench.driver.reference().expect("reference");
    bench.unplug();
    match bench.driver.move_to(10.0) {
        Err(DeviceError::Disconnected { port, .. }) => {
            assert!(port.starts_with("/dev/pts/"), "{port}")
        }
        other => panic!("{other:?}"),
    }
}
