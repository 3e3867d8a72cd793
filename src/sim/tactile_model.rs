//! The simulated pad: from a cable pressed on it to the 25 raw readings.
//!
//! The model, each step with its reason (docs/simulated-cell.md has the
//! values):
//! - **Dent.** The jaws squeeze the cable by a fraction of its diameter
//!   that grows with the grip current; each pad takes half, so a thicker
//!   cable, or a harder grip, dents the cap deeper. Depth 1 is the dent of
//!   the paper's 2.5 mm cable under the nominal squeeze.
//! - **Line spread.** The cap spreads a point load over a Gaussian of
//!   width σ = `line_spread_pitch` × pitch (0.55 pitch, about 2 mm: the cap
//!   is a few millimetres thick). The deformation under a taxel is that
//!   kernel summed along the part of the cable that lies on the cap, so a
//!   cable across the whole pad gives a Gaussian ridge of full depth, and
//!   one over a corner only a short, weak patch.
//! - **Extent.** The cap ends half a pitch beyond the outer taxels, and
//!   its rim is rounded: the load a cable puts on it falls from full at
//!   the outer taxels' line to nothing at the edge. A cable beyond the
//!   edge touches nothing.
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
use serde::Deserialize;

use crate::geometry::LineInSensor;
use crate::perception::tactile::{ADC_MAX, PAD_HALF_SIDE_PITCH, RawFrame, TAXEL_COLS, TAXEL_COUNT};
use crate::schema::validate::{fraction, positive, voltage_range};

/// The first simulated pad: a line-spread response, per-taxel offsets and
/// gains, a saturating photo-reflector and noise. See `sim::tactile_model`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SimTactileConfig {
    /// Width (σ) of the cap's deformation across the cable, in pitches.
    #[serde(deserialize_with = "positive")]
    pub line_spread_pitch: f64,
    /// Voltage swing of a taxel from rest to full deformation.
    #[serde(deserialize_with = "positive")]
    pub span_v: f64,
    /// Range of the taxels' resting voltages (drawn once per cell).
    #[serde(deserialize_with = "voltage_range")]
    pub rest_v: [f64; 2],
    /// Relative spread of the taxels' gains (drawn once per cell).
    #[serde(deserialize_with = "fraction")]
    pub gain_spread: f64,
    /// Noise standard deviation as a fraction of `span_v`.
    #[serde(deserialize_with = "fraction")]
    pub noise_fraction: f64,
    /// Fault injection: the sensor stops answering after this many frames.
    #[serde(default)]
    pub silent_after_frames: Option<u64>,
}

/// ADC full scale of the sensor's microcontroller.
const ADC_FULL_SCALE_V: f64 = 3.3;
/// Curvature of the photo-reflector's saturating response.
const SATURATION_K: f64 = 2.0;
/// The squeeze (of the diameter, both pads together) of the paper's
/// cable under a 1 A grip: the jaws stop at 90 % of the diameter.
pub const NOMINAL_SQUEEZE_FRACTION: f64 = 0.1;
/// The dent of one pad that gives a full response: the paper's 2.5 mm
/// cable at the nominal squeeze, half of it per pad.
const FULL_DENT_MM: f64 = NOMINAL_SQUEEZE_FRACTION * 2.5 / 2.0;
/// Width of the cap's rounded rim, in pitches: from the outer taxels' line
/// to the edge.
const RIM_WIDTH_PITCH: f64 = 0.5;
/// Step of the sum along the cable: fine against σ ≈ 2 mm.
const ALONG_STEP_MM: f64 = 0.1;

/// A cable pressed on the pad.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    pub line: LineInSensor,
    pub diameter_mm: f64,
    /// How much the jaws squeeze the cable, as a fraction of its diameter.
    pub squeeze_fraction: f64,
}

/// The cap's deformation under each taxel (1 = a full dent).
pub type Dents = [f64; TAXEL_COUNT];

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
    /// diameter, gripped at the nominal squeeze.
    pub fn frame(&self, pressed: Option<(LineInSensor, f64)>, rng: &mut impl Rng) -> RawFrame {
        let dents = pressed.map_or([0.0; TAXEL_COUNT], |(line, diameter_mm)| {
            self.dents(&Contact {
                line,
                diameter_mm,
                squeeze_fraction: NOMINAL_SQUEEZE_FRACTION,
            })
        });
        self.frame_from_dents(&dents, rng)
    }

    /// One reading of the pad deformed by `dents`.
    pub fn frame_from_dents(&self, dents: &Dents, rng: &mut impl Rng) -> RawFrame {
        std::array::from_fn(|k| {
            let response = (1.0 - (-SATURATION_K * dents[k]).exp()) / (1.0 - (-SATURATION_K).exp());
            let noise_v = self.noise_v * rng.sample::<f64, _>(StandardNormal);
            let volts = self.rest_v[k] + self.gain[k] * self.span_v * response + noise_v;
            let counts = (volts / ADC_FULL_SCALE_V * 4096.0).round();
            counts.clamp(0.0, f64::from(ADC_MAX)) as u16
        })
    }

    /// The cap's deformation under each taxel with `contact` pressed on it:
    /// the line-spread kernel summed along the part of the cable on the
    /// cap, weighted by the rim's taper.
    pub fn dents(&self, contact: &Contact) -> Dents {
        let depth = contact.squeeze_fraction * contact.diameter_mm / 2.0 / FULL_DENT_MM;
        let half_side_mm = PAD_HALF_SIDE_PITCH * self.pitch_mm;
        let rim_mm = RIM_WIDTH_PITCH * self.pitch_mm;
        let Some((start, end)) = clip_to_square(&contact.line, half_side_mm) else {
            return [0.0; TAXEL_COUNT];
        };
        let along = contact.line.sensor_from_line().rotation * Vector2::x();
        let foot = contact.line.normal() * contact.line.n_mm;
        let steps = ((end - start) / ALONG_STEP_MM).ceil().max(1.0) as usize;
        let step_mm = (end - start) / steps as f64;
        // Midpoints of the steps, with the load each carries.
        let loads: Vec<(Vector2<f64>, f64)> = (0..steps)
            .map(|i| {
                let point = foot + along * (start + (i as f64 + 0.5) * step_mm);
                let to_edge_mm = half_side_mm - point.x.abs().max(point.y.abs());
                (point, (to_edge_mm / rim_mm).clamp(0.0, 1.0) * step_mm)
            })
            .collect();
        let norm = depth / ((2.0 * std::f64::consts::PI).sqrt() * self.sigma_mm);
        let two_var = 2.0 * self.sigma_mm * self.sigma_mm;
        std::array::from_fn(|k| {
            let taxel = taxel_position(k, self.pitch_mm);
            norm * loads
                .iter()
                .map(|(point, load)| load * (-(taxel - point).norm_squared() / two_var).exp())
                .sum::<f64>()
        })
    }
}

/// The stretch of `line` inside the square of half side `half_side_mm`
/// about the pad's centre, as distances along the line from the foot of
/// its perpendicular; `None` if the line misses the square.
fn clip_to_square(line: &LineInSensor, half_side_mm: f64) -> Option<(f64, f64)> {
    let along = line.sensor_from_line().rotation * Vector2::x();
    let foot = line.normal() * line.n_mm;
    let (mut start, mut end) = (f64::NEG_INFINITY, f64::INFINITY);
    for axis in 0..2 {
        if along[axis].abs() < 1e-12 {
            if foot[axis].abs() > half_side_mm {
                return None;
            }
            continue;
        }
        let a = (-half_side_mm - foot[axis]) / along[axis];
        let b = (half_side_mm - foot[axis]) / along[axis];
        start = start.max(a.min(b));
        end = end.min(a.max(b));
    }
    (end > start).then_some((start, end))
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

    fn model() -> TactileModel {
        TactileModel::new(&config(0.0), 3.55, &mut rng(3, Stream::TactileCalibration))
    }

    fn contact(line: LineInSensor, diameter_mm: f64) -> Contact {
        Contact {
            line,
            diameter_mm,
            squeeze_fraction: NOMINAL_SQUEEZE_FRACTION,
        }
    }

    #[test]
    fn a_cable_across_the_middle_dents_its_row_fully() {
        let dents = model().dents(&contact(LineInSensor::new(0.0, 0.0), 2.5));
        assert!((dents[12] - 1.0).abs() < 1e-3, "{}", dents[12]);
        // One pitch away: e^(-1 / (2 · 0.55²)).
        let expected = (-1.0 / (2.0 * 0.55 * 0.55_f64)).exp();
        assert!((dents[7] - expected).abs() < 1e-3, "{}", dents[7]);
    }

    #[test]
    fn a_thicker_cable_or_a_harder_grip_dents_more() {
        let model = model();
        let line = LineInSensor::new(0.1, 0.5);
        let thin = model.dents(&contact(line, 1.5));
        let thick = model.dents(&contact(line, 4.0));
        let hard = model.dents(&Contact {
            squeeze_fraction: 0.2,
            ..contact(line, 1.5)
        });
        assert!(thick[12] > thin[12] * 2.0);
        assert!(hard[12] > thin[12] * 1.9);
    }

    #[test]
    fn a_cable_beyond_the_caps_edge_touches_nothing() {
        let model = model();
        // The cap's edge is 2.5 pitches (8.875 mm) from the centre.
        let beyond = model.dents(&contact(LineInSensor::new(0.0, 9.0), 2.5));
        assert!(beyond.iter().all(|&d| d == 0.0));
        let diagonal_beyond = model.dents(&contact(LineInSensor::new(0.785, 12.6), 2.5));
        assert!(diagonal_beyond.iter().all(|&d| d == 0.0));
        // On the rim, beyond the outer taxels: a weak top row.
        let rim = model.dents(&contact(LineInSensor::new(0.0, 8.0), 2.5));
        assert!(rim[2] > 0.2 && rim[2] < 0.6, "{}", rim[2]);
    }

    #[test]
    fn a_cable_over_a_corner_gives_a_weak_partial_map() {
        let model = model();
        // Across the diagonal at 3.1 pitches from the centre: beyond c15
        // (2 √2 = 2.83 pitches out), short of the cap's corner (3.54).
        let corner = LineInSensor::new(-std::f64::consts::FRAC_PI_4, 3.1 * 3.55);
        let dents = model.dents(&contact(corner, 2.5));
        let strongest = dents.iter().cloned().fold(0.0, f64::max);
        assert!(strongest > 0.05 && strongest < 0.5, "{strongest}");
        // Only the corner taxel and its neighbours feel it.
        let felt = dents.iter().filter(|&&d| d > 0.05).count();
        assert!((1..=3).contains(&felt), "{dents:?}");
        assert!(dents[4] >= strongest - 1e-12, "c15 feels most: {dents:?}");
    }
}
