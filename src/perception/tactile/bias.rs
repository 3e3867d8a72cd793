//! Bias removal (paper, Section III.1): each taxel's offset is the mean of
//! its first samples, and Δv is the voltage minus that offset.
//!
//! The offsets differ from taxel to taxel because every silicone cap is
//! moulded a little differently; subtracting them makes the taxels
//! comparable, so that the fit can weigh them against each other.

use serde::Serialize;

use super::map::{
    ADC_MAX, TAXEL_COLS, TAXEL_COUNT, TAXEL_ROWS, TactileMap, VOLTS_PER_COUNT, raw_to_volts,
};

/// One reading of all 25 taxels as the MCU sends them: 12-bit counts,
/// row-major c11..c55 (after the layout mapping).
pub type RawFrame = [u16; TAXEL_COUNT];

/// How many samples the paper averages for the offsets.
pub const PAPER_BIAS_SAMPLES: usize = 50;

/// Averages the first frames of a run into a [`Bias`].
///
/// Only the first `samples_required` frames count; later ones are ignored,
/// so that a cable pressed on the pad after start-up never leaks into the
/// offsets.
#[derive(Clone, Debug)]
pub struct BiasEstimator {
    samples_required: usize,
    samples_taken: usize,
    /// Sums of the masked counts: exact in integers for any run length.
    count_sums: [u64; TAXEL_COUNT],
    bias: Option<Bias>,
}

impl BiasEstimator {
    /// An estimator averaging `samples_required` frames; 0 is taken as 1,
    /// since a mean of nothing is no offset.
    pub fn new(samples_required: usize) -> Self {
        Self {
            samples_required: samples_required.max(1),
            samples_taken: 0,
            count_sums: [0; TAXEL_COUNT],
            bias: None,
        }
    }

    /// Adds a frame while the offsets are still being measured; returns the
    /// bias once enough frames were seen, and the same bias ever after.
    pub fn push(&mut self, frame: &RawFrame) -> Option<Bias> {
        if self.bias.is_none() {
            for (sum, &raw) in self.count_sums.iter_mut().zip(frame) {
                *sum += u64::from(raw & ADC_MAX);
            }
            self.samples_taken += 1;
            if self.samples_taken == self.samples_required {
                let mut offset_v = [[0.0; TAXEL_COLS]; TAXEL_ROWS];
                for (k, offset) in offset_v.iter_mut().flatten().enumerate() {
                    *offset = mean_volts(self.count_sums[k], self.samples_taken);
                }
                self.bias = Some(Bias { offset_v });
            }
        }
        self.bias.clone()
    }

    pub fn is_complete(&self) -> bool {
        self.bias.is_some()
    }

    /// The bias, once complete.
    pub fn bias(&self) -> Option<&Bias> {
        self.bias.as_ref()
    }
}

impl Default for BiasEstimator {
    /// The paper's estimator: the first 50 samples.
    fn default() -> Self {
        Self::new(PAPER_BIAS_SAMPLES)
    }
}

/// Volts of the mean of `samples` counts summing to `count_sum`.
fn mean_volts(count_sum: u64, samples: usize) -> f64 {
    count_sum as f64 / samples as f64 * VOLTS_PER_COUNT
}

/// Each taxel's offset voltage, `[row][col]`, as in [`TactileMap`].
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Bias {
    pub offset_v: [[f64; TAXEL_COLS]; TAXEL_ROWS],
}

impl Bias {
    /// Δv of one frame. A taxel reading the ADC's full scale is flagged as
    /// saturated: the true voltage may be higher.
    pub fn remove(&self, frame: &RawFrame) -> TactileMap {
        let mut map = TactileMap::from_fn(|row, col| {
            raw_to_volts(frame[row * TAXEL_COLS + col]) - self.offset_v[row][col]
        });
        for (k, saturated) in map.saturated.iter_mut().flatten().enumerate() {
            *saturated = is_saturated(frame[k]);
        }
        map
    }

    /// Mean Δv over `frames` (`None` for no frames), to average out noise
    /// while the gripper holds still. A taxel saturated in any frame is
    /// flagged, since its mean is then a lower bound too.
    pub fn remove_mean(&self, frames: &[RawFrame]) -> Option<TactileMap> {
        if frames.is_empty() {
            return None;
        }
        let mut count_sums = [0_u64; TAXEL_COUNT];
        let mut saturated = [false; TAXEL_COUNT];
        for frame in frames {
            for k in 0..TAXEL_COUNT {
                count_sums[k] += u64::from(frame[k] & ADC_MAX);
                saturated[k] |= is_saturated(frame[k]);
            }
        }
        let mut map = TactileMap::from_fn(|row, col| {
            let k = row * TAXEL_COLS + col;
            mean_volts(count_sums[k], frames.len()) - self.offset_v[row][col]
        });
        for (flag, &was) in map.saturated.iter_mut().flatten().zip(&saturated) {
            *flag = was;
        }
        Some(map)
    }
}

/// Whether a count is the ADC's full scale (after masking the high nibble,
/// like [`raw_to_volts`], so that both agree on what the taxel read).
fn is_saturated(raw: u16) -> bool {
    raw & ADC_MAX == ADC_MAX
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(raw: u16) -> RawFrame {
        [raw; TAXEL_COUNT]
    }

    #[test]
    fn bias_is_the_mean_of_the_first_frames_only() {
        let mut estimator = BiasEstimator::new(3);
        assert_eq!(estimator.push(&frame(100)), None);
        assert_eq!(estimator.push(&frame(200)), None);
        assert!(!estimator.is_complete());
        let bias = estimator.push(&frame(0x3000 | 300)).unwrap();
        assert!(estimator.is_complete());
        assert_eq!(bias.offset_v[2][3], raw_to_volts(200));
        // A cable pressed later does not move the offsets.
        assert_eq!(estimator.push(&frame(4000)), Some(bias.clone()));
        assert_eq!(estimator.bias(), Some(&bias));
    }

    #[test]
    fn each_taxel_has_its_own_offset() {
        let mut estimator = BiasEstimator::new(2);
        let ramp: RawFrame = std::array::from_fn(|k| 1000 + k as u16);
        estimator.push(&ramp);
        let bias = estimator.push(&ramp).unwrap();
        // c21 is the sixth value of a frame.
        assert_eq!(bias.offset_v[1][0], raw_to_volts(1005));
        assert_eq!(bias.remove(&ramp).peak_dv_v(), 0.0);
    }

    #[test]
    fn zero_samples_means_one() {
        let mut estimator = BiasEstimator::new(0);
        assert!(estimator.push(&frame(10)).is_some());
        assert_eq!(
            BiasEstimator::default().samples_required,
            PAPER_BIAS_SAMPLES
        );
    }

    #[test]
    fn remove_subtracts_and_flags_full_scale() {
        let bias = Bias {
            offset_v: [[raw_to_volts(1000); TAXEL_COLS]; TAXEL_ROWS],
        };
        let mut raw = frame(1000);
        raw[0] = 1500;
        raw[6] = 500;
        raw[12] = ADC_MAX;
        raw[24] = 0xFFFF;
        let map = bias.remove(&raw);
        assert_eq!(map.dv_v[0][0], raw_to_volts(1500) - raw_to_volts(1000));
        assert!(map.dv_v[1][1] < 0.0);
        assert_eq!(map.dv_v[0][1], 0.0);
        let flagged: Vec<(usize, usize)> = (0..TAXEL_ROWS)
            .flat_map(|i| (0..TAXEL_COLS).map(move |j| (i, j)))
            .filter(|&(i, j)| map.saturated[i][j])
            .collect();
        assert_eq!(flagged, [(2, 2), (4, 4)]);
    }

    #[test]
    fn remove_mean_averages_and_keeps_any_saturation() {
        let bias = Bias {
            offset_v: [[raw_to_volts(1000); TAXEL_COLS]; TAXEL_ROWS],
        };
        assert_eq!(bias.remove_mean(&[]), None);
        let mut hot = frame(1100);
        hot[3] = ADC_MAX;
        let map = bias.remove_mean(&[frame(1000), hot, frame(1200)]).unwrap();
        assert_eq!(map.dv_v[4][4], raw_to_volts(1100) - raw_to_volts(1000));
        assert!(map.saturated[0][3]);
        assert_eq!(map.saturated.iter().flatten().filter(|&&s| s).count(), 1);
        assert_eq!(bias.remove_mean(&[hot]), Some(bias.remove(&hot)));
    }
}
