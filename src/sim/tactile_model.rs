//! The simulated pad: from a cable pressed on it to the 25 raw readings.
//!
//! First version of the model, each step with its reason:
//! - **Deformation.** A cable pressed into the silicone cap dents it over a
//!   band wider than the cable; across the cable the dent falls off as a
//!   Gaussian of width σ = `line_spread_pitch` × pitch (0.55 pitch, about
//!   2 mm: the cap is a few millimetres thick, so a 2.5 mm cable spreads
//!   over roughly its own width on each side). Its depth grows with the
//!   cable's diameter, relative to the paper's 2.5 mm cable.
//! - **Photo-reflector.** Light returned to a taxel rises with the local
//!   deformation and saturates: v = rest + gain · span · (1 − e^(−k d)) /
//!   (1 − e^(−k)), k = 2, so that a full dent (d = 1) gives `span_v`.
//! - **Per-taxel differences.** Each taxel has its own resting voltage
//!   (drawn in `rest_v`: manufacturing of the cap, which is why the paper
//!   removes a bias) and gain (± `gain_spread`).
//! - **Noise.** Gaussian, σ = `noise_fraction` × `span_v` (1–3 % seen on
//!   such sensors), then 12-bit quantisation of 0–3.3 V and clipping.

use nalgebra::Vector2;
use rand::{Rng, RngExt};
use rand_distr::StandardNormal;

use crate::geometry::LineInSensor;
use crate::perception::tactile::{ADC_MAX, RawFrame, TAXEL_COLS, TAXEL_COUNT};
use crate::task::cell_file::SimTactileConfig;

/// ADC full scale of the sensor's microcontroller.
const ADC_FULL_SCALE_V: f64 = 3.3;
/// Curvature of the photo-reflector's saturating response.
const SATURATION_K: f64 = 2.0;
/// The cable diameter that gives a full dent.
const REFERENCE_DIAMETER_MM: f64 = 2.5;

#[derive(Debug, Clone)]
pub struct TactileModel {
    pitch_mm: f64,
    sigma_mm: f64,
    span_v: f64,
    noise_v: f64,
    rest_v: [f64; TAXEL_COUNT],
    gain: [f64; TAXEL_COUNT],
}

impl TactileModel {
    /// A pad with its per-taxel rest voltages and gains drawn from `rng`.
    pub fn new(config: &SimTactileConfig, pitch_mm: f64, rng: &mut impl Rng) -> Self {
        let [rest_low, rest_high] = config.rest_v;
        let rest_v = std::array::from_fn(|_| rng.random_range(rest_low..=rest_high));
        let gain = std::array::from_fn(|_| {
            1.0 + rng.random_range(-config.gain_spread..=config.gain_spread)
        });
        Self {
            pitch_mm,
            sigma_mm: config.line_spread_pitch * pitch_mm,
            span_v: config.span_v,
            noise_v: config.noise_fraction * config.span_v,
            rest_v,
            gain,
        }
    }

    /// One reading, with `pressed` the cable on the pad (if any) and its
    /// diameter.
    pub fn frame(&self, pressed: Option<(LineInSensor, f64)>, rng: &mut impl Rng) -> RawFrame {
        std::array::from_fn(|k| {
            let dent = pressed.map_or(0.0, |(line, diameter_mm)| {
                self.dent(&line, diameter_mm, taxel_position(k, self.pitch_mm))
            });
            let response = (1.0 - (-SATURATION_K * dent).exp()) / (1.0 - (-SATURATION_K).exp());
            let noise_v = self.noise_v * rng.sample::<f64, _>(StandardNormal);
            let volts = self.rest_v[k] + self.gain[k] * self.span_v * response + noise_v;
            let counts = (volts / ADC_FULL_SCALE_V * 4096.0).round();
            counts.clamp(0.0, f64::from(ADC_MAX)) as u16
        })
    }

    /// Depth of the cap's dent (1 = full) at a taxel.
    fn dent(&self, line: &LineInSensor, diameter_mm: f64, taxel_mm: Vector2<f64>) -> f64 {
        let distance_mm = line.distance_mm(taxel_mm);
        let depth = diameter_mm / REFERENCE_DIAMETER_MM;
        depth * (-distance_mm * distance_mm / (2.0 * self.sigma_mm * self.sigma_mm)).exp()
    }
}

/// Centre of taxel `k` (row-major c11..c55) in the sensor frame.
fn taxel_position(k: usize, pitch_mm: f64) -> Vector2<f64> {
    let (row, col) = (k / TAXEL_COLS, k % TAXEL_COLS);
    Vector2::new((col as f64 - 2.0) * pitch_mm, (2.0 - row as f64) * pitch_mm)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::{Stream, rng};

    fn config(noise_fraction: f64) -> SimTactileConfig {
        SimTactileConfig {
            line_spread_pitch: 0.55,
            span_v: 1.2,
            rest_v: [0.9, 1.5],
            gain_spread: 0.1,
            noise_fraction,
            silent_after_frames: None,
        }
    }

    #[test]
    fn taxel_positions_follow_the_papers_frame() {
        // c13 (row 1, column 3) is on +y, c35 (row 3, column 5) on +x.
        assert_eq!(taxel_position(2, 3.55), Vector2::new(0.0, 7.1));
        assert_eq!(taxel_position(14, 3.55), Vector2::new(7.1, 0.0));
        assert_eq!(taxel_position(12, 3.55), Vector2::new(0.0, 0.0));
    }

    #[test]
    fn a_cable_along_x_lights_the_middle_row_most() {
        let mut r = rng(1, Stream::Tactile);
        let model = TactileModel::new(&config(0.0), 3.55, &mut r);
        let rest = model.frame(None, &mut r);
        let pressed = model.frame(Some((LineInSensor::new(0.0, 0.0), 2.5)), &mut r);
        let rise = |k: usize| f64::from(pressed[k]) - f64::from(rest[k]);
        for col in 0..5 {
            let middle = rise(10 + col);
            assert!(middle > 1000.0, "middle row rises by a full span");
            assert!(rise(col) < 0.1 * middle, "outer rows barely move");
            assert!(rise(5 + col) < middle && rise(5 + col) > rise(col));
        }
    }

    #[test]
    fn readings_stay_within_twelve_bits() {
        let mut r = rng(2, Stream::Tactile);
        let mut hot = config(0.5);
        hot.rest_v = [3.0, 3.3];
        let model = TactileModel::new(&hot, 3.55, &mut r);
        let frame = model.frame(Some((LineInSensor::new(0.3, 1.0), 4.0)), &mut r);
        assert!(frame.iter().all(|&c| c <= ADC_MAX));
        assert!(frame.contains(&ADC_MAX), "a hot pad saturates");
    }
}
