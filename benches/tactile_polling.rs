//! The tactile polling loop through a pseudo-terminal: the real driver
//! against the emulated microcontroller sampling the simulated pad (seed 1,
//! a 2.5 mm cable across it). A pseudo-terminal has no baud rate, so these
//! are the host's share of each frame; at 1 Mbaud the link itself needs
//! 0.51 ms per frame (51 bytes × 10 bits), 1.96 kHz at most.
//!
//! - `exchange`: flush, request, read and decode one frame;
//! - `frame`: the same, then bias removal and the paper's fits;
//! - `polled read`: a frame from the polling thread running as fast as it
//!   can, the highest sustained rate (one frame per iteration);
//! - `in memory`: `frame` on a link that answers from memory, the driver's
//!   and the algorithm's own share without the kernel's pseudo-terminal
//!   round trip and the emulator thread's wake-up.

use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

use cablecell::cell::load_cell;
use cablecell::geometry::LineInSensor;
use cablecell::hw::clock::MonotonicClock;
use cablecell::hw::emulator::PtyEmulator;
use cablecell::hw::tactile::remodel_emulator::TactileEmulator;
use cablecell::hw::tactile::{PolledTactile, RemodelTactile, SerialLink, TactileSensor};
use cablecell::perception::tactile::{BiasEstimator, FitConfig, fit_wire};
use cablecell::perception::tactile::{RawFrame, TAXEL_COUNT};
use cablecell::sim::tactile_model::TactileModel;
use cablecell::sim::{Stream, rng};
use criterion::{Criterion, criterion_group, criterion_main};
use serialport::{SerialPort, TTYPort};

/// The driver on a pseudo-terminal to an emulated pad with a cable on it
/// (or none).
fn driver(cable: bool) -> (RemodelTactile<TTYPort>, PtyEmulator) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut file = load_cell(&root.join("config/cell.sim.toml")).expect("the simulated cell");
    let pitch_mm = file.tactile.pitch_mm;
    let pad = file.tactile.backend.sim_pad_mut().expect("a simulated pad");
    let model = TactileModel::new(pad, pitch_mm, &mut rng(1, Stream::TactileCalibration));
    let mut noise = rng(1, Stream::Tactile);
    let on_pad = cable.then_some((LineInSensor::new(0.1, 1.0), 2.5));
    let layout = std::array::from_fn(|k| k);
    let (emulator, mut slave) = PtyEmulator::start(move |master, stop| {
        TactileEmulator::new(layout, move || Some(model.frame(on_pad, &mut noise)))
            .serve(master, stop)
    })
    .expect("a pseudo-terminal");
    slave
        .set_timeout(Duration::from_millis(2))
        .expect("timeout");
    let driver = RemodelTactile::new(
        slave,
        emulator.path(),
        layout,
        Box::new(MonotonicClock::new()),
    )
    .with_deadline(Duration::from_millis(200));
    (driver, emulator)
}

/// A link that answers every `'a'` with the same 50 bytes, from memory.
struct InMemory {
    answer: Vec<u8>,
    unread: usize,
}

impl std::io::Read for InMemory {
    fn read(&mut self, buffer: &mut [u8]) -> std::io::Result<usize> {
        let start = self.answer.len() - self.unread;
        let n = self.unread.min(buffer.len());
        buffer[..n].copy_from_slice(&self.answer[start..start + n]);
        self.unread -= n;
        Ok(n)
    }
}

impl std::io::Write for InMemory {
    fn write(&mut self, request: &[u8]) -> std::io::Result<usize> {
        if request.contains(&b'a') {
            self.unread = self.answer.len();
        }
        Ok(request.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

impl SerialLink for InMemory {
    fn discard_input(&mut self) -> std::io::Result<()> {
        self.unread = 0;
        Ok(())
    }
}

fn in_memory(frame: &RawFrame) -> RemodelTactile<InMemory> {
    let answer = frame
        .iter()
        .flat_map(|raw| [(raw & 0xFF) as u8, (raw >> 8) as u8])
        .collect();
    let identity: [usize; TAXEL_COUNT] = std::array::from_fn(|k| k);
    RemodelTactile::new(
        InMemory { answer, unread: 0 },
        "memory",
        identity,
        Box::new(MonotonicClock::new()),
    )
}

fn polling(c: &mut Criterion) {
    let (mut free, _free_pad) = driver(false);
    let mut estimator = BiasEstimator::default();
    let bias = (0..50)
        .find_map(|_| estimator.push(&free.sample().expect("a frame of the free pad")))
        .expect("50 frames complete the paper's bias");
    drop(free);

    let (mut sensor, _pad) = driver(true);
    let config = FitConfig::default();
    let frame = sensor.sample().expect("a frame");
    assert!(
        fit_wire(&bias.remove(&frame), &config).is_ok(),
        "the cable is on the pad"
    );

    let mut group = c.benchmark_group("tactile_polling");
    group.bench_function("exchange (request, read, decode)", |b| {
        b.iter(|| sensor.sample().expect("a frame"))
    });
    group.bench_function("frame (request, read, decode, bias, fit)", |b| {
        b.iter(|| {
            let frame = sensor.sample().expect("a frame");
            fit_wire(&bias.remove(black_box(&frame)), black_box(&config))
        })
    });
    drop(sensor);

    let mut memory = in_memory(&frame);
    assert_eq!(memory.sample().expect("a frame"), frame);
    group.bench_function("in memory: frame (request, read, decode, bias, fit)", |b| {
        b.iter(|| {
            let frame = memory.sample().expect("a frame");
            fit_wire(&bias.remove(black_box(&frame)), black_box(&config))
        })
    });

    let (sensor, _pad) = driver(true);
    // A rate no link reaches: the thread polls back to back.
    let mut polled = PolledTactile::start(sensor, 1.0e6);
    group.bench_function("polled read, highest sustained rate", |b| {
        b.iter(|| polled.read().expect("a frame"))
    });
    group.finish();
}

criterion_group!(benches, polling);
criterion_main!(benches);
