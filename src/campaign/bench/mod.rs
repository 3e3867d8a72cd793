//! The bench: the cell's settings run on the same seeded inputs, each
//! one's error against what it costs, the settings no other beats on both
//! marked as the Pareto front; and the latency of each stage.
//!
//! - `cell.rs`: the tactile and regrasp settings on the campaign's trials
//!   (computation and the cell's own, simulated, time), the shapes fused
//!   with the camera's, and the latency of a trial's stages;
//! - `vision.rs`: the vision pipeline's settings on rendered scenes with
//!   exact labels (and photographs when given), the skips on plain
//!   backgrounds with and without them, and the pipeline's stage latencies.

pub mod cell;
pub mod vision;

use std::time::Instant;

use schemars::JsonSchema;
use serde::Serialize;

use super::stats::Summary;

pub use cell::{SettingRow, run_settings, settings, stage_latencies};

/// How many trials and images each setting runs, from which seed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BenchSize {
    pub trials: usize,
    /// Campaign seed of the trials, and the renderer's seed of the images.
    pub seed: u64,
    /// Repetitions of each timed stage.
    pub repetitions: usize,
    /// Rendered images each vision setting runs on.
    pub images: usize,
}

impl BenchSize {
    /// What the docs quote.
    pub const FULL: BenchSize = BenchSize {
        trials: 100,
        seed: 1,
        repetitions: 200,
        images: 40,
    };
    /// About a minute in a release build.
    pub const QUICK: BenchSize = BenchSize {
        trials: 20,
        seed: 1,
        repetitions: 50,
        images: 10,
    };
}

/// Whether each (cost, error) point is on the Pareto front: no other point
/// is at least as cheap and as accurate and better in one of the two.
/// Equal points are both on it.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<bool> {
    points
        .iter()
        .map(|&(cost, error)| {
            !points
                .iter()
                .any(|&(c, e)| c <= cost && e <= error && (c < cost || e < error))
        })
        .collect()
}

/// The latency of one stage.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct StageLatency {
    pub stage: String,
    pub median_us: f64,
    pub p95_us: f64,
}

impl StageLatency {
    /// `stage`'s median and 95th percentile of `times_us`; `None` for none.
    fn of(stage: impl Into<String>, times_us: &[f64]) -> Option<Self> {
        Summary::of(times_us).map(|s| StageLatency {
            stage: stage.into(),
            median_us: s.median,
            p95_us: s.p95,
        })
    }
}

/// Times `f` `repetitions` times, in microseconds.
fn time_us(name: &str, repetitions: usize, mut f: impl FnMut()) -> Option<StageLatency> {
    let times: Vec<f64> = (0..repetitions.max(1))
        .map(|_| {
            let start = Instant::now();
            f();
            start.elapsed().as_secs_f64() * 1e6
        })
        .collect();
    StageLatency::of(name, &times)
}

/// The campaign statistics' mean of `values`; `None` for none.
fn mean(values: impl Iterator<Item = f64>) -> Option<f64> {
    Summary::of(&values.collect::<Vec<_>>()).map(|s| s.mean)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_front_holds_the_points_no_other_beats_on_both() {
        let points = [
            (1.0, 5.0), // cheapest
            (2.0, 3.0), // on the front
            (3.0, 3.0), // as accurate as the one before, dearer: off
            (2.5, 4.0), // beaten by (2, 3)
            (4.0, 1.0), // most accurate
            (4.0, 1.0), // its equal: both on
            (5.0, 2.0), // beaten by (4, 1)
        ];
        assert_eq!(
            pareto_front(&points),
            [true, true, false, false, true, true, false]
        );
        assert!(pareto_front(&[]).is_empty());
    }
}
