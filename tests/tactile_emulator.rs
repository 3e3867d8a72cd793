//! The tactile driver against the emulated microcontroller on a
//! pseudo-terminal: the taxel layout, 12-bit samples, and the sensor
//! misbehaving or unplugged.

use std::time::Duration;

use cablecell::hw::DeviceError;
use cablecell::hw::clock::MonotonicClock;
use cablecell::hw::emulator::Fault;
use cablecell::hw::emulator::PtyEmulator;
use cablecell::hw::tactile::remodel_emulator::{Misbehaviour, TactileEmulator};
use cablecell::hw::tactile::{RemodelTactile, TactileSensor};
use cablecell::perception::tactile::{RawFrame, TAXEL_COUNT};
use serialport::{SerialPort, TTYPort};

/// A layout that is not the identity: channel = 24 − taxel.
fn reversed() -> [usize; TAXEL_COUNT] {
    std::array::from_fn(|taxel| TAXEL_COUNT - 1 - taxel)
}

/// Frame n: taxel k reads 0x0F0 + 100·k + n, up to the 12-bit maximum.
fn frame(n: u16) -> RawFrame {
    std::array::from_fn(|k| (0x0F0 + 100 * k as u16 + n).min(4095))
}

struct Bench {
    driver: RemodelTactile<TTYPort>,
    emulator: PtyEmulator,
}

impl Bench {
    fn new(fault: Option<Fault<Misbehaviour>>) -> Self {
        let (emulator, mut slave) = PtyEmulator::start(move |master, stop| {
            let mut n = 0;
            let mut mcu = TactileEmulator::new(reversed(), move || {
                n += 1;
                Some(frame(n))
            });
            mcu.fault.set(fault);
            mcu.serve(master, stop);
        })
        .expect("a pseudo-terminal");
        slave
            .set_timeout(Duration::from_millis(2))
            .expect("timeout");
        let driver = RemodelTactile::new(
            slave,
            emulator.path(),
            reversed(),
            Box::new(MonotonicClock::new()),
        );
        Self { driver, emulator }
    }

    fn unplug(&mut self) {
        self.emulator
            .unplug()
            .expect("the emulator thread ends well");
    }
}

#[test]
fn id_count_and_samples_in_taxel_order() {
    let mut bench = Bench::new(None);
    assert_eq!(bench.driver.id().expect("id"), "F001");
    assert_eq!(bench.driver.count().expect("count"), 25);
    let first = bench.driver.read().expect("sample");
    assert_eq!(first.raw, frame(1));
    let second = bench.driver.read().expect("sample");
    assert_eq!(second.raw, frame(2));
    assert!(second.t_s >= first.t_s);
    assert_eq!(
        first.raw[24],
        0x0F0 + 2400 + 1,
        "12-bit values above 255 survive"
    );
}

#[test]
fn a_truncated_answer_is_garbled_and_says_how_much_came() {
    let mut bench = Bench::new(Some(Fault::now(Misbehaviour::Truncated)));
    match bench.driver.read() {
        Err(DeviceError::Garbled { detail, .. }) => {
            assert!(detail.contains("25 of 50 bytes within 20 ms"), "{detail}")
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn bytes_that_are_not_samples_are_garbled() {
    let mut bench = Bench::new(Some(Fault::now(Misbehaviour::Garbage)));
    match bench.driver.read() {
        Err(DeviceError::Garbled { detail, .. }) => {
            assert!(detail.contains("not 12-bit"), "{detail}")
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_sensor_that_vanishes_is_a_lost_link() {
    let mut bench = Bench::new(Some(Fault {
        misbehaviour: Misbehaviour::Vanish,
        after_requests: 2,
    }));
    bench.driver.read().expect("sample");
    bench.driver.read().expect("sample");
    assert!(matches!(
        bench.driver.read(),
        Err(DeviceError::Disconnected { .. } | DeviceError::NoAnswer { .. })
    ));
}

#[test]
fn a_sensor_that_falls_silent_times_out_and_earlier_samples_were_fine() {
    let mut bench = Bench::new(Some(Fault {
        misbehaviour: Misbehaviour::Silent,
        after_requests: 3,
    }));
    for n in 1..=3 {
        assert_eq!(bench.driver.read().expect("sample").raw, frame(n));
    }
    match bench.driver.read() {
        Err(DeviceError::NoAnswer { port, command, .. }) => {
            assert!(port.starts_with("/dev/pts/"), "{port}");
            assert_eq!(command, "sample");
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_stray_byte_is_caught_as_a_garbled_answer() {
    let mut bench = Bench::new(Some(Fault::now(Misbehaviour::StrayByte)));
    match bench.driver.read() {
        Err(DeviceError::Garbled { detail, .. }) => {
            assert!(detail.contains("not 12-bit"), "{detail}")
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn an_unplugged_sensor_is_a_lost_link() {
    let mut bench = Bench::new(None);
    bench.driver.read().expect("sample");
    bench.unplug();
    assert!(matches!(
        bench.driver.read(),
        Err(DeviceError::Disconnected { .. })
    ));
}
