//! Summary statistics of a campaign: how a measured value spreads over the
//! trials, and how sure a success rate is given the number of trials.

use schemars::JsonSchema;

/// z for a two-sided 95 % interval: the 0.975 quantile of the standard
/// normal distribution.
const Z_95: f64 = 1.959963984540054;

/// Summary of a sample of values (e.g. |n| in mm over trials).
///
/// The quantiles (`median`, `p95`) use linear interpolation between order
/// statistics, the "type 7" definition (Hyndman & Fan 1996) that is the
/// default of numpy's `percentile` and R's `quantile`: for sorted values
/// x₀ ≤ … ≤ xₙ₋₁ and a probability p, h = (n − 1)·p and
/// Q(p) = x⌊h⌋ + (h − ⌊h⌋)·(x⌊h⌋₊₁ − x⌊h⌋). Reports can then be checked
/// against either tool.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, JsonSchema)]
pub struct Summary {
    pub count: usize,
    pub mean: f64,
    /// Sample standard deviation (divisor n − 1), the estimate of the spread
    /// of the process rather than of these trials alone; 0 for one value.
    pub std_dev: f64,
    pub median: f64,
    pub p95: f64,
    pub max: f64,
    /// The mean's 95 % confidence interval, Student's t with n − 1 degrees
    /// of freedom (the trials' spread estimated from the trials
    /// themselves); `None` for a single value.
    pub mean_ci95: Option<[f64; 2]>,
}

impl Summary {
    /// Summarises `values`, in any order.
    ///
    /// Returns `None` if `values` is empty or holds a non-finite value (NaN
    /// or ±∞). Non-finite values are refused rather than skipped: a
    /// measurement that is not a number is a bug upstream, and skipping it
    /// would quietly report a count and a spread that leave that trial out.
    /// A trial that has no measurement (e.g. it failed before measuring)
    /// should be left out by the caller, visibly.
    pub fn of(values: &[f64]) -> Option<Summary> {
        if values.is_empty() || values.iter().any(|v| !v.is_finite()) {
            return None;
        }
        // Welford's running mean and sum of squared deviations: stable for
        // values far from zero and free of overflow in a naive Σx².
        let (mut mean, mut sum_sq_dev) = (0.0_f64, 0.0_f64);
        for (i, &v) in values.iter().enumerate() {
            let delta = v - mean;
            mean += delta / (i + 1) as f64;
            sum_sq_dev += delta * (v - mean);
        }
        let count = values.len();
        let std_dev = if count > 1 {
            (sum_sq_dev / (count - 1) as f64).sqrt()
        } else {
            0.0
        };
        let mut sorted = values.to_vec();
        sorted.sort_by(f64::total_cmp);
        let max = sorted[count - 1];
        Some(Summary {
            count,
            mean,
            std_dev,
            median: quantile_type7(&sorted, 0.5),
            p95: quantile_type7(&sorted, 0.95),
            max,
            mean_ci95: mean_ci95(mean, std_dev, count),
        })
    }
}

/// The 95 % interval of a mean of `count` values with sample standard
/// deviation `std_dev`: mean ± t₀.₉₇₅,ₙ₋₁ · std_dev / √n.
fn mean_ci95(mean: f64, std_dev: f64, count: usize) -> Option<[f64; 2]> {
    use statrs::distribution::{ContinuousCDF, StudentsT};
    let degrees = count.checked_sub(1).filter(|&d| d > 0)? as f64;
    let t = StudentsT::new(0.0, 1.0, degrees).ok()?.inverse_cdf(0.975);
    let half = t * std_dev / (count as f64).sqrt();
    Some([mean - half, mean + half])
}

/// The least value, the quartiles (type 7, as [`Summary`]'s) and the
/// greatest: what a box plot draws. `None` as [`Summary::of`] gives it.
pub fn five_numbers(values: &[f64]) -> Option<[f64; 5]> {
    if values.is_empty() || values.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    Some([0.0, 0.25, 0.5, 0.75, 1.0].map(|p| quantile_type7(&sorted, p)))
}

/// The type-7 quantile of non-empty, ascending `sorted` at `p` in [0, 1].
fn quantile_type7(sorted: &[f64], p: f64) -> f64 {
    let last = sorted.len() - 1;
    let h = last as f64 * p;
    let lo = (h.floor() as usize).min(last);
    let hi = (lo + 1).min(last);
    sorted[lo] + (h - lo as f64) * (sorted[hi] - sorted[lo])
}

/// A success rate with its 95 % Wilson score interval.
///
/// Wilson rather than the normal approximation p ± z·√(p(1−p)/n): the latter
/// collapses to a zero-width interval at 0/n and n/n and leaves [0, 1] for
/// small n, which is exactly where a short campaign lands.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, JsonSchema)]
pub struct Rate {
    pub successes: usize,
    pub trials: usize,
    /// successes / trials.
    pub rate: f64,
    pub ci95_low: f64,
    pub ci95_high: f64,
}

impl Rate {
    /// The rate of `successes` in `trials` and its Wilson interval
    /// (center ± half-width, with p = successes / trials and z = 1.96):
    /// center = (p + z²/2n) / (1 + z²/n),
    /// half = z / (1 + z²/n) · √(p(1 − p)/n + z²/4n²).
    ///
    /// Returns `None` if `trials` is 0 (no rate) or `successes > trials`.
    pub fn wilson(successes: usize, trials: usize) -> Option<Rate> {
        if trials == 0 || successes > trials {
            return None;
        }
        let n = trials as f64;
        let p = successes as f64 / n;
        let z2 = Z_95 * Z_95;
        let denominator = 1.0 + z2 / n;
        let center = (p + z2 / (2.0 * n)) / denominator;
        let half = Z_95 / denominator * (p * (1.0 - p) / n + z2 / (4.0 * n * n)).sqrt();
        // At 0/n and n/n the bound is 0 or 1 exactly in real arithmetic;
        // clamping removes the rounding residue (e.g. -1e-17).
        Some(Rate {
            successes,
            trials,
            rate: p,
            ci95_low: (center - half).clamp(0.0, 1.0),
            ci95_high: (center + half).clamp(0.0, 1.0),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn five_numbers_are_the_box_plots() {
        // [1, 2, 3, 4, 10]: h = 4 · p lands on x₁, x₂, x₃ exactly.
        assert_eq!(
            five_numbers(&[10.0, 1.0, 4.0, 2.0, 3.0]),
            Some([1.0, 2.0, 3.0, 4.0, 10.0])
        );
        assert_eq!(five_numbers(&[]), None);
        assert_eq!(five_numbers(&[1.0, f64::NAN]), None);
    }

    #[test]
    fn summary_matches_hand_computation() {
        // values [1, 2, 3, 4, 10]:
        // mean = 20 / 5 = 4
        // squared deviations 9 + 4 + 1 + 0 + 36 = 50; sample sd = √(50 / 4) = √12.5 = 3.5355339…
        // median: h = 4 · 0.5 = 2 → x₂ = 3
        // p95: h = 4 · 0.95 = 3.8 → x₃ + 0.8 · (x₄ − x₃) = 4 + 0.8 · 6 = 8.8
        // max = 10
        // 95 % CI of the mean: t₀.₉₇₅,₄ = 2.7764451… (R's qt(0.975, 4)),
        // 4 ± 2.7764451 · 3.5355339 / √5 = 4 ± 4.3899…
        let s = Summary::of(&[1.0, 2.0, 3.0, 4.0, 10.0]).unwrap();
        assert_eq!(s.count, 5);
        assert_relative_eq!(s.mean, 4.0, epsilon = 1e-12);
        assert_relative_eq!(s.std_dev, 12.5_f64.sqrt(), epsilon = 1e-12);
        assert_relative_eq!(s.median, 3.0, epsilon = 1e-12);
        assert_relative_eq!(s.p95, 8.8, epsilon = 1e-12);
        assert_eq!(s.max, 10.0);
        let [low, high] = s.mean_ci95.expect("an interval for 5 values");
        let half = 2.776_445_105_2 * 12.5_f64.sqrt() / 5.0_f64.sqrt();
        assert_relative_eq!(low, 4.0 - half, epsilon = 1e-8);
        assert_relative_eq!(high, 4.0 + half, epsilon = 1e-8);
    }

    #[test]
    fn summary_ignores_input_order() {
        let sorted = Summary::of(&[1.0, 2.0, 3.0, 4.0, 10.0]).unwrap();
        let shuffled = Summary::of(&[10.0, 3.0, 1.0, 4.0, 2.0]).unwrap();
        assert_relative_eq!(shuffled.mean, sorted.mean, epsilon = 1e-12);
        assert_relative_eq!(shuffled.std_dev, sorted.std_dev, epsilon = 1e-12);
        assert_eq!(shuffled.median, sorted.median);
        assert_eq!(shuffled.p95, sorted.p95);
        assert_eq!(shuffled.max, sorted.max);
    }

    #[test]
    fn summary_of_one_value_has_no_spread() {
        let s = Summary::of(&[2.5]).unwrap();
        assert_eq!(
            s,
            Summary {
                count: 1,
                mean: 2.5,
                std_dev: 0.0,
                median: 2.5,
                p95: 2.5,
                max: 2.5,
                mean_ci95: None,
            }
        );
    }

    #[test]
    fn summary_of_two_values_interpolates() {
        // [3, 1] sorted [1, 3]: mean 2; sd = √((1 + 1) / 1) = √2;
        // median: h = 0.5 → 1 + 0.5 · 2 = 2; p95: h = 0.95 → 1 + 0.95 · 2 = 2.9.
        let s = Summary::of(&[3.0, 1.0]).unwrap();
        assert_relative_eq!(s.mean, 2.0, epsilon = 1e-12);
        assert_relative_eq!(s.std_dev, 2.0_f64.sqrt(), epsilon = 1e-12);
        assert_relative_eq!(s.median, 2.0, epsilon = 1e-12);
        assert_relative_eq!(s.p95, 2.9, epsilon = 1e-12);
        assert_eq!(s.max, 3.0);
    }

    #[test]
    fn summary_of_equal_values_and_negatives() {
        let s = Summary::of(&[-1.0, -1.0, -1.0]).unwrap();
        assert_eq!(s.std_dev, 0.0);
        assert_eq!((s.mean, s.median, s.p95, s.max), (-1.0, -1.0, -1.0, -1.0));
    }

    #[test]
    fn summary_refuses_empty_and_non_finite() {
        assert_eq!(Summary::of(&[]), None);
        assert_eq!(Summary::of(&[1.0, f64::NAN]), None);
        assert_eq!(Summary::of(&[f64::INFINITY, 1.0]), None);
        assert_eq!(Summary::of(&[f64::NEG_INFINITY]), None);
    }

    #[test]
    fn summary_is_stable_far_from_zero() {
        // A naive Σx² − n·mean² loses every digit here; Welford keeps them.
        let s = Summary::of(&[1e9 + 1.0, 1e9 + 2.0, 1e9 + 3.0]).unwrap();
        assert_relative_eq!(s.mean, 1e9 + 2.0, epsilon = 1e-6);
        assert_relative_eq!(s.std_dev, 1.0, epsilon = 1e-9);
    }

    // Wilson with z = 1.959963984540054, z² = 3.841458820694124, n = 20:
    // z²/n = 0.192073, 1 + z²/n = 1.192073, z²/2n = 0.096036, z²/4n² = 0.0024009.
    #[test]
    fn wilson_15_of_20() {
        // p = 0.75: center = (0.75 + 0.096036) / 1.192073 = 0.709719
        // half = 1.959964 / 1.192073 · √(0.1875 / 20 + 0.0024009)
        //      = 1.644166 · √0.0117759 = 1.644166 · 0.108517 = 0.178420
        // → [0.531299, 0.888138]
        let r = Rate::wilson(15, 20).unwrap();
        assert_eq!((r.successes, r.trials), (15, 20));
        assert_relative_eq!(r.rate, 0.75);
        assert_relative_eq!(r.ci95_low, 0.531299, epsilon = 1e-6);
        assert_relative_eq!(r.ci95_high, 0.888138, epsilon = 1e-6);
    }

    #[test]
    fn wilson_0_of_20() {
        // p = 0: center = 0.096036 / 1.192073 = 0.080563,
        // half = 1.644166 · √0.0024009 = 1.644166 · 0.048999 = 0.080563
        // → [0, 0.161125]: not the degenerate [0, 0] of the normal approximation.
        let r = Rate::wilson(0, 20).unwrap();
        assert_eq!(r.rate, 0.0);
        assert_eq!(r.ci95_low, 0.0);
        assert_relative_eq!(r.ci95_high, 0.161125, epsilon = 1e-6);
    }

    #[test]
    fn wilson_20_of_20() {
        // Mirror of 0/20: [1 − 0.161125, 1] = [0.838875, 1].
        let r = Rate::wilson(20, 20).unwrap();
        assert_eq!(r.rate, 1.0);
        assert_relative_eq!(r.ci95_low, 0.838875, epsilon = 1e-6);
        assert_eq!(r.ci95_high, 1.0);
    }

    #[test]
    fn wilson_single_trial_stays_in_unit_interval() {
        // n = 1, p = 1: center = (1 + 1.920729) / 4.841459 = 0.603275,
        // half = 1.959964 / 4.841459 · √(3.841459 / 4) = 0.404829 · 0.979982 = 0.396725
        // → [0.206549, 1].
        let r = Rate::wilson(1, 1).unwrap();
        assert_relative_eq!(r.ci95_low, 0.206549, epsilon = 1e-6);
        assert_eq!(r.ci95_high, 1.0);
    }

    #[test]
    fn wilson_refuses_no_trials_and_impossible_counts() {
        assert_eq!(Rate::wilson(0, 0), None);
        assert_eq!(Rate::wilson(21, 20), None);
    }
}
