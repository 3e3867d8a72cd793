//! Cost of cablecell's ridge fit against the paper's centroids, on the
//! same noisy map: the campaign fits thousands of maps, the sensor sends
//! one every 2 ms.

use std::hint::black_box;

use cablecell::geometry::LineInSensor;
use cablecell::perception::tactile::map::{taxel_x_mm, taxel_y_mm};
use cablecell::perception::tactile::ridge_fit::fit_ridge;
use cablecell::perception::tactile::{FitConfig, PAPER_PITCH_MM, TactileMap, fit_wire};
use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::Vector2;

/// The simulated pad's map of a cable `line`: Gaussian dent of σ = 0.55
/// pitch, saturating response of a 1.2 V span, gains and noise of a few
/// per cent from a fixed pattern.
fn cable_map(line: LineInSensor) -> TactileMap {
    let sigma_mm = 0.55 * PAPER_PITCH_MM;
    let mut k = 0.0;
    TactileMap::from_fn(|row, col| {
        k += 1.0;
        let p = Vector2::new(
            taxel_x_mm(col, PAPER_PITCH_MM),
            taxel_y_mm(row, PAPER_PITCH_MM),
        );
        let d = line.distance_mm(p);
        let dent = (-d * d / (2.0 * sigma_mm * sigma_mm)).exp();
        let response = (1.0 - (-2.0 * dent).exp()) / (1.0 - (-2.0_f64).exp());
        let gain = 1.0 + 0.08 * (k * 0.7_f64).sin();
        1.2 * gain * response + 0.024 * (k * 1.3_f64).cos()
    })
}

fn fits(c: &mut Criterion) {
    let config = FitConfig::default();
    let cases = [
        ("centred, 20°", LineInSensor::new(20_f64.to_radians(), 1.2)),
        ("corner, 45°", LineInSensor::new(45_f64.to_radians(), 5.3)),
    ];
    for (name, line) in cases {
        let map = cable_map(line);
        assert!(fit_ridge(&map, &config).is_ok() && fit_wire(&map, &config).is_ok());
        c.bench_function(&format!("fit_ridge, {name}"), |b| {
            b.iter(|| fit_ridge(black_box(&map), black_box(&config)))
        });
        c.bench_function(&format!("fit_wire, {name}"), |b| {
            b.iter(|| fit_wire(black_box(&map), black_box(&config)))
        });
    }
}

criterion_group!(benches, fits);
criterion_main!(benches);
