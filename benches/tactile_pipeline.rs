//! Per-frame cost of the tactile pipeline at the sensor's rate (500 Hz in
//! the paper, so 2 ms per frame of budget): bias removal plus both fits,
//! and the fit alone.

use std::hint::black_box;

use cablecell::perception::tactile::map::{taxel_x_mm, taxel_y_mm};
use cablecell::perception::tactile::{
    BiasEstimator, FitConfig, PAPER_PITCH_MM, RawFrame, TAXEL_COLS, fit_wire,
};
use criterion::{Criterion, criterion_group, criterion_main};

/// Volts of one ADC count.
const VOLTS_PER_COUNT: f64 = 3.3 / 4096.0;

/// A frame of a 2.5 mm cable pressed at 20°, 1.2 mm off centre, peak Δv
/// 0.6 V, over taxel offsets around 1.2 V that differ by up to 0.1 V, with
/// a few counts of deterministic noise.
fn cable_frame(noise_phase: u32) -> RawFrame {
    let sigma_mm = 0.55 * PAPER_PITCH_MM;
    let alpha = 20_f64.to_radians();
    std::array::from_fn(|k| {
        let (row, col) = (k / TAXEL_COLS, k % TAXEL_COLS);
        let (x, y) = (
            taxel_x_mm(col, PAPER_PITCH_MM),
            taxel_y_mm(row, PAPER_PITCH_MM),
        );
        let d = -alpha.sin() * x + alpha.cos() * y - 1.2;
        let dv = 0.6 * (-d * d / (2.0 * sigma_mm * sigma_mm)).exp();
        let offset = 1.2 + 0.1 * (k as f64 * 0.7).sin();
        let noise = 3.0 * (f64::from(noise_phase) * 1.3 + k as f64).sin();
        ((offset + dv) / VOLTS_PER_COUNT + noise).round() as u16
    })
}

fn pipeline(c: &mut Criterion) {
    // The pad is free while the offsets are measured.
    let free = |phase: u32| -> RawFrame {
        std::array::from_fn(|k| {
            let offset = 1.2 + 0.1 * (k as f64 * 0.7).sin();
            (offset / VOLTS_PER_COUNT + 3.0 * (f64::from(phase) + k as f64).sin()).round() as u16
        })
    };
    let mut estimator = BiasEstimator::default();
    let Some(bias) = (0..50)
        .filter_map(|phase| estimator.push(&free(phase)))
        .last()
    else {
        panic!("50 frames complete the paper's bias");
    };
    let frame = cable_frame(7);
    let config = FitConfig::default();
    let map = bias.remove(&frame);
    assert!(fit_wire(&map, &config).is_ok_and(|fit| fit.quadratic.is_some()));

    c.bench_function("bias removal + fit_wire", |b| {
        b.iter(|| fit_wire(&bias.remove(black_box(&frame)), black_box(&config)))
    });
    c.bench_function("fit_wire", |b| {
        b.iter(|| fit_wire(black_box(&map), black_box(&config)))
    });
}

criterion_group!(benches, pipeline);
criterion_main!(benches);
