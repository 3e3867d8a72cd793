//! The wire parameters (paper, Section III.2): direction test, centroids
//! (eq. 5 / 6), linear fit (eq. 2) and quadratic fit (eq. 3 / 4).
//!
//! Where the paper is explicit this follows it; beyond it:
//! - Negative Δv are clamped to 0 before everything else. A taxel reading
//!   below its offset carries no contact, and a negative weight in eq. 5/6
//!   could push a centroid outside the pad (the denominator can even
//!   vanish). They are counted in [`WireFit::negative_taxels`].
//! - Non-finite Δv (only possible in a map built by hand) are treated as 0
//!   and counted in [`WireFit::non_finite_taxels`], so the fit never turns
//!   into NaN.
//! - The one deliberate deviation from eq. 5/6: a column (row) whose
//!   clamped sum is below `contact_threshold_v` gets no centroid. Such a
//!   line of taxels holds only noise, and its centroid would be a random
//!   point that drags both fits; with a zero sum it would be 0/0.
//! - The linear fit is kept as a [`LineInSensor`] (angle and offset), since
//!   the paper's `y = m x + n` cannot hold a cable along y. For a vertical
//!   cable it regresses x on y, the well-posed direction.
//! - Saturated taxels keep their value, a lower bound of the true Δv: they
//!   weigh too little, which pulls the centroids slightly away from the
//!   hardest-pressed spot. They are counted so that the caller can tell
//!   the gripper squeezes too hard.
//!
//! All arithmetic runs on weights divided by the peak and on coordinates in
//! pitches, so that neither huge nor tiny voltages or pitches overflow or
//! underflow; the scale is put back at the end.

use std::fmt;

use arrayvec::ArrayVec;
use nalgebra::Vector2;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::map::{TAXEL_COLS, TAXEL_ROWS, TactileMap, taxel_x_mm, taxel_y_mm};
use crate::geometry::LineInSensor;

/// The paper's taxel pitch.
pub const PAPER_PITCH_MM: f64 = 3.55;

/// Which way the cable mainly runs across the pad.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Direction {
    /// Along x: one centroid per column, eq. 5, and `y = a x² + b x + c`.
    Horizontal,
    /// Along y: one centroid per row, eq. 6, and `x = a y² + b y + c`.
    Vertical,
}

impl fmt::Display for Direction {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Direction::Horizontal => "horizontal",
            Direction::Vertical => "vertical",
        })
    }
}

/// Contact thresholds that can tell touch from none: from 1 mV (the 12-bit
/// ADC's step is 0.8 mV) to 3.3 V, the ADC's whole span.
pub const CONTACT_THRESHOLD_V: std::ops::RangeInclusive<f64> = 0.001..=3.3;

/// The pad's geometry and when a taxel counts as touched.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct FitConfig {
    /// Distance between neighbouring taxel centres.
    pub pitch_mm: f64,
    /// Below this peak Δv there is no contact; a column (row) whose Δv sum
    /// is below it gets no centroid.
    pub contact_threshold_v: f64,
}

impl Default for FitConfig {
    fn default() -> Self {
        Self {
            pitch_mm: PAPER_PITCH_MM,
            contact_threshold_v: 0.05,
        }
    }
}

/// Smallest and largest pitch accepted: outside, it is a unit mistake.
const PITCH_RANGE_MM: (f64, f64) = (1e-6, 1e6);

/// Columns and rows are treated alike, so the pad must be square.
const LINES: usize = TAXEL_COLS;
const _: () = assert!(TAXEL_ROWS == TAXEL_COLS);

/// One centroid of eq. 5 (a column's) or eq. 6 (a row's).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, JsonSchema)]
pub struct Centroid {
    pub x_mm: f64,
    pub y_mm: f64,
    /// The clamped Δv sum of its column (row): how much it is worth.
    pub weight_v: f64,
}

/// `y = a x² + b x + c` for a horizontal cable (eq. 3), `x = a y² + b y + c`
/// for a vertical one (eq. 4); lengths in mm, so `a` is in 1/mm.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, JsonSchema)]
pub struct Quadratic {
    #[serde(rename = "a_per_mm")]
    pub a: f64,
    pub b: f64,
    #[serde(rename = "c_mm")]
    pub c: f64,
}

/// Everything the wire-parameter step found in one tactile map.
#[derive(Clone, Debug, PartialEq, Serialize, JsonSchema)]
pub struct WireFit {
    pub direction: Direction,
    /// The paper's h: the smallest column sum of (clamped) Δv.
    pub h_v: f64,
    /// The paper's v: the smallest row sum of (clamped) Δv.
    pub v_v: f64,
    /// One per column (row) that carries the cable.
    pub centroids: ArrayVec<Centroid, LINES>,
    /// Least-squares line through the centroids (eq. 2).
    pub line: LineInSensor,
    /// The paper's m of eq. 2; `None` for a cable along y.
    pub slope_m: Option<f64>,
    /// The paper's n of eq. 2; `None` for a cable along y.
    pub intercept_n_mm: Option<f64>,
    /// `None` with fewer than 3 centroids.
    pub quadratic: Option<Quadratic>,
    /// How well the line's and the parabola's least squares are
    /// conditioned.
    pub condition: FitCondition,
    /// The largest clamped Δv.
    pub peak_dv_v: f64,
    /// Taxels below their offset, clamped to 0.
    pub negative_taxels: usize,
    /// Taxels at the ADC's full scale, their Δv a lower bound.
    pub saturated_taxels: usize,
    /// NaN or infinite Δv, treated as 0 (a map built by hand).
    pub non_finite_taxels: usize,
}

/// The condition numbers (2-norm) of the least-squares fits, each that of
/// its design matrix in the basis the fit is solved in: polynomials
/// orthogonal over the centroids' positions in pitches, so
/// √(largest / smallest of the basis columns' squared norms), from n and
/// Σs² for the line and Σp₂² too for the parabola. Rounding moves a fitted
/// coefficient by about κ · ε · the operations that made the data,
/// relative to the data; 1 is perfect. Five centroids a pitch apart give
/// the line √2 and the parabola √(14/5); two centroids a pitch apart 2.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, JsonSchema)]
pub struct FitCondition {
    pub line: f64,
    /// `None` with fewer than 3 centroids.
    pub quadratic: Option<f64>,
}

/// √(largest / smallest) of squared norms.
fn condition(squared_norms: &[f64]) -> f64 {
    let largest = squared_norms.iter().copied().fold(0.0, f64::max);
    let smallest = squared_norms.iter().copied().fold(f64::INFINITY, f64::min);
    (largest / smallest).sqrt()
}

/// Why no wire parameters came out of a map.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum FitError {
    /// Nothing presses on the pad: the grasp missed the cable, or the
    /// threshold is above the signal (check the bias was taken with the
    /// pad free).
    #[error("no contact: peak Δv {peak_dv_v} V is below the threshold {threshold_v} V")]
    NoContact { peak_dv_v: f64, threshold_v: f64 },
    /// The cable touches fewer than two columns (rows): a single spot, such
    /// as a cable end or a knot, gives no direction to fit.
    #[error("only {found} {direction} centroid(s) above the threshold, a line needs 2")]
    TooFewCentroids { found: usize, direction: Direction },
    /// The configuration is not physical: the pitch must lie within
    /// 1e-6..=1e6 mm, the threshold must be finite and not negative.
    #[error(
        "invalid fit configuration: pitch {pitch_mm} mm, contact threshold {contact_threshold_v} V"
    )]
    InvalidConfig {
        pitch_mm: f64,
        contact_threshold_v: f64,
    },
    /// The oracle estimator was asked on a cell that cannot know where the
    /// cable really lies: use it on simulated cells only.
    #[error("the oracle estimator needs the cable's true pose, which only a simulated cell knows")]
    NoTruth,
}

/// The clamped weights of a map, divided by their peak.
struct Weights {
    /// In [0, 1] to a rounding, the peak taxel at 1.
    w: [[f64; TAXEL_COLS]; TAXEL_ROWS],
    peak_v: f64,
    negative: usize,
    non_finite: usize,
    saturated: usize,
}

impl Weights {
    fn of(map: &TactileMap) -> Self {
        let mut w = [[0.0; TAXEL_COLS]; TAXEL_ROWS];
        let (mut negative, mut non_finite) = (0, 0);
        let mut peak_v: f64 = 0.0;
        for (w, &dv) in w.iter_mut().flatten().zip(map.dv_v.iter().flatten()) {
            if !dv.is_finite() {
                non_finite += 1;
            } else if dv < 0.0 {
                negative += 1;
            } else {
                *w = dv;
                peak_v = peak_v.max(dv);
            }
        }
        if peak_v > 0.0 {
            // Scaling by the (finite, positive) peak never overflows, and
            // keeps the sums below 5 whatever the voltages. The reciprocal
            // of a subnormal peak is infinite: then divide.
            let per_v = peak_v.recip();
            for w in w.iter_mut().flatten() {
                *w = if per_v.is_finite() {
                    *w * per_v
                } else {
                    *w / peak_v
                };
            }
        }
        let saturated = map.saturated.iter().flatten().filter(|&&s| s).count();
        Self {
            w,
            peak_v,
            negative,
            non_finite,
            saturated,
        }
    }

    /// A normalised sum back in volts; saturates at `f64::MAX`, reachable
    /// only for a hand-built map with Δv above 3.6e307 V.
    fn volts(&self, normalised: f64) -> f64 {
        (normalised * self.peak_v).min(f64::MAX)
    }
}

/// Centroids as (grid coordinate, centroid coordinate) in pitches: for a
/// horizontal cable (x_j, y_j^c), for a vertical one (y_i, x_i^c).
struct Samples {
    u: [f64; LINES],
    t: [f64; LINES],
    len: usize,
}

impl FitConfig {
    /// Refuses a configuration that is not physical, for every estimator.
    pub fn validate(&self) -> Result<(), FitError> {
        let pitch_ok = (PITCH_RANGE_MM.0..=PITCH_RANGE_MM.1).contains(&self.pitch_mm);
        let threshold_ok = self.contact_threshold_v.is_finite() && self.contact_threshold_v >= 0.0;
        if pitch_ok && threshold_ok {
            Ok(())
        } else {
            Err(FitError::InvalidConfig {
                pitch_mm: self.pitch_mm,
                contact_threshold_v: self.contact_threshold_v,
            })
        }
    }

    /// The contact rule of every estimator: a map whose peak Δv is not
    /// positive (a zero peak is no contact even with a zero threshold) or
    /// is below the threshold holds no cable.
    pub(crate) fn contact(&self, peak_dv_v: f64) -> Result<(), FitError> {
        if peak_dv_v <= 0.0 || peak_dv_v < self.contact_threshold_v {
            Err(FitError::NoContact {
                peak_dv_v,
                threshold_v: self.contact_threshold_v,
            })
        } else {
            Ok(())
        }
    }
}

/// The wire parameters of one tactile map.
pub fn fit_wire(map: &TactileMap, config: &FitConfig) -> Result<WireFit, FitError> {
    config.validate()?;
    let FitConfig {
        pitch_mm,
        contact_threshold_v,
    } = *config;

    let weights = Weights::of(map);
    let peak_v = weights.peak_v;
    config.contact(peak_v)?;
    let w = &weights.w;
    // At most 1, as the peak passed the threshold.
    let threshold = contact_threshold_v / peak_v;

    let mut col_sums = [0.0; TAXEL_COLS];
    let mut row_sums = [0.0; TAXEL_ROWS];
    for (row, values) in w.iter().enumerate() {
        for (col, &value) in values.iter().enumerate() {
            col_sums[col] += value;
            row_sums[row] += value;
        }
    }
    let h = col_sums.iter().copied().fold(f64::INFINITY, f64::min);
    let v = row_sums.iter().copied().fold(f64::INFINITY, f64::min);
    let touched = |sums: &[f64; LINES]| {
        sums.iter()
            .filter(|&&s| carries_contact(s, threshold))
            .count()
    };
    // The paper leaves h = v open. It happens in clean maps whenever the
    // cable spans neither all columns nor all rows (h = v = 0, a short
    // piece or a single spot) and for symmetric diagonals. The direction
    // with more centroids gives the better-determined fit; on a further
    // tie, Vertical.
    let direction = if h > v || (h == v && touched(&col_sums) > touched(&row_sums)) {
        Direction::Horizontal
    } else {
        Direction::Vertical
    };

    // Coordinates in pitches are those in mm at a pitch of 1.
    let mut samples = Samples {
        u: [0.0; LINES],
        t: [0.0; LINES],
        len: 0,
    };
    let mut centroids = ArrayVec::new();
    for k in 0..LINES {
        let (sum, moment, u) = match direction {
            Direction::Horizontal => {
                let moment: f64 = (0..TAXEL_ROWS).map(|i| taxel_y_mm(i, 1.0) * w[i][k]).sum();
                (col_sums[k], moment, taxel_x_mm(k, 1.0))
            }
            Direction::Vertical => {
                let moment: f64 = (0..TAXEL_COLS).map(|j| taxel_x_mm(j, 1.0) * w[k][j]).sum();
                (row_sums[k], moment, taxel_y_mm(k, 1.0))
            }
        };
        if !carries_contact(sum, threshold) {
            continue;
        }
        let t = moment / sum;
        samples.u[samples.len] = u;
        samples.t[samples.len] = t;
        samples.len += 1;
        let (x, y) = match direction {
            Direction::Horizontal => (u, t),
            Direction::Vertical => (t, u),
        };
        centroids.push(Centroid {
            x_mm: x * pitch_mm,
            y_mm: y * pitch_mm,
            weight_v: weights.volts(sum),
        });
    }
    if samples.len < 2 {
        return Err(FitError::TooFewCentroids {
            found: samples.len,
            direction,
        });
    }

    let Fits {
        line,
        slope_intercept,
        quadratic,
        condition,
    } = Fits::of(&samples, direction, pitch_mm);
    let (slope_m, intercept_n_mm) = slope_intercept.unzip();
    Ok(WireFit {
        direction,
        h_v: weights.volts(h),
        v_v: weights.volts(v),
        centroids,
        line,
        slope_m,
        intercept_n_mm,
        quadratic,
        condition,
        peak_dv_v: peak_v,
        negative_taxels: weights.negative,
        saturated_taxels: weights.saturated,
        non_finite_taxels: weights.non_finite,
    })
}

/// Whether a column (row) sum, normalised like the threshold, carries the
/// cable rather than noise; a zero threshold still needs some signal.
fn carries_contact(sum: f64, threshold: f64) -> bool {
    sum >= threshold && sum > 0.0
}

/// The least-squares line and parabola of t on u, both from one set of
/// polynomials orthogonal over the samples' u (Forsythe's three-term
/// recurrence): each coefficient is one projection, so the fits cost a few
/// sums (no QR, no normal equations) and stay as well conditioned as the
/// data, whatever the pitch. The line needs 2 distinct u, the parabola 3.
struct Fits {
    line: LineInSensor,
    /// The paper's m and n of eq. 2; `None` for a line within 1e-9 rad of
    /// the y-axis, as [`LineInSensor::slope_intercept`] says.
    slope_intercept: Option<(f64, f64)>,
    /// `None` with fewer than 3 samples.
    quadratic: Option<Quadratic>,
    condition: FitCondition,
}

impl Fits {
    fn of(samples: &Samples, direction: Direction, pitch_mm: f64) -> Self {
        let (u, t) = (&samples.u[..samples.len], &samples.t[..samples.len]);
        let n = samples.len as f64;
        let u_mean = u.iter().sum::<f64>() / n;
        let t_mean = t.iter().sum::<f64>() / n;
        // p0 = 1, p1 = s, p2 = s (s - α2) - β1, with s = u - ū.
        let (mut s_ss, mut s_st, mut s_sss) = (0.0, 0.0, 0.0);
        for (&u, &t) in u.iter().zip(t) {
            let s = u - u_mean;
            s_ss += s * s;
            s_st += s * (t - t_mean);
            s_sss += s * s * s;
        }
        // u are distinct whole pitches, so Σs² ≥ 1/2.
        let slope = s_st / s_ss;
        let (point, dir) = match direction {
            Direction::Horizontal => (Vector2::new(u_mean, t_mean), Vector2::new(1.0, slope)),
            Direction::Vertical => (Vector2::new(t_mean, u_mean), Vector2::new(slope, 1.0)),
        };
        let line = LineInSensor::through(point * pitch_mm, dir);
        // The regression's own intercept, with no trigonometry: along x,
        // t = slope u + t0; along y, x = slope y + x0, so y = x / slope -
        // x0 / slope, where |cos α| = |slope| / √(1 + slope²).
        let t0_mm = (t_mean - slope * u_mean) * pitch_mm;
        let slope_intercept = match direction {
            Direction::Horizontal => Some((slope, t0_mm)),
            Direction::Vertical => (slope.abs() > 1e-9 * (1.0 + slope * slope).sqrt())
                .then(|| (slope.recip(), -t0_mm / slope)),
        };
        let line_condition = condition(&[n, s_ss]);
        if samples.len < 3 {
            return Self {
                line,
                slope_intercept,
                quadratic: None,
                condition: FitCondition {
                    line: line_condition,
                    quadratic: None,
                },
            };
        }
        let alpha2 = s_sss / s_ss;
        let beta1 = s_ss / n;
        let (mut p2_p2, mut p2_t) = (0.0, 0.0);
        for (&u, &t) in u.iter().zip(t) {
            let s = u - u_mean;
            let p2 = s * (s - alpha2) - beta1;
            p2_p2 += p2 * p2;
            p2_t += p2 * t;
        }
        // 3 distinct whole pitches keep p2 away from 0 at one of them.
        let a = p2_t / p2_p2;
        // t = a s² + b s + c in pitches, expanding p2.
        let (b, c) = (slope - a * alpha2, t_mean - a * beta1);
        // Back in mm, with s = u - ū, u = U/p and t = T/p:
        // T = (a/p) U² + (b - 2aū) U + p (aū² - bū + c).
        Self {
            line,
            slope_intercept,
            quadratic: Some(Quadratic {
                a: a / pitch_mm,
                b: b - 2.0 * a * u_mean,
                c: pitch_mm * (a * u_mean * u_mean - b * u_mean + c),
            }),
            condition: FitCondition {
                line: line_condition,
                quadratic: Some(condition(&[n, s_ss, p2_p2])),
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use std::f64::consts::{FRAC_PI_2, FRAC_PI_6};

    use super::*;
    use approx::assert_relative_eq;

    const PITCH: f64 = PAPER_PITCH_MM;
    /// The test maps' line spread: a cable of a couple of mm pressed into
    /// silicone lights up about one neighbour on each side.
    const SIGMA_MM: f64 = 0.55 * PITCH;

    fn config() -> FitConfig {
        FitConfig::default()
    }

    /// Δv = A·exp(-d²/2σ²), d the taxel centre's distance to the cable.
    fn render(amplitude_v: f64, distance_mm: impl Fn(Vector2<f64>) -> f64) -> TactileMap {
        TactileMap::from_fn(|row, col| {
            let p = Vector2::new(taxel_x_mm(col, PITCH), taxel_y_mm(row, PITCH));
            let d = distance_mm(p);
            amplitude_v * (-d * d / (2.0 * SIGMA_MM * SIGMA_MM)).exp()
        })
    }

    fn render_line(line: LineInSensor, amplitude_v: f64) -> TactileMap {
        render(amplitude_v, |p| line.distance_mm(p))
    }

    /// A parabola t = a u² + b u + c, (u, t) = (x, y) if horizontal, else
    /// (y, x); the distance is found by dense sampling well beyond the pad.
    fn render_parabola(q: Quadratic, direction: Direction, amplitude_v: f64) -> TactileMap {
        render(amplitude_v, |p| {
            let (pu, pt) = match direction {
                Direction::Horizontal => (p.x, p.y),
                Direction::Vertical => (p.y, p.x),
            };
            (-8000..=8000)
                .map(|k| {
                    let u = f64::from(k) * 0.001;
                    let t = q.a * u * u + q.b * u + q.c;
                    (u - pu).hypot(t - pt)
                })
                .fold(f64::INFINITY, f64::min)
        })
    }

    fn line_at(alpha_rad: f64, offset_mm: f64) -> LineInSensor {
        LineInSensor::new(alpha_rad, offset_mm)
    }

    #[test]
    fn centred_horizontal_cable_is_the_x_axis() {
        let fit = fit_wire(&render_line(line_at(0.0, 0.0), 1.0), &config()).unwrap();
        assert_eq!(fit.direction, Direction::Horizontal);
        assert!(fit.h_v > fit.v_v);
        assert_eq!(fit.centroids.len(), 5);
        for (j, c) in fit.centroids.iter().enumerate() {
            assert_relative_eq!(c.x_mm, taxel_x_mm(j, PITCH));
            assert_relative_eq!(c.y_mm, 0.0, epsilon = 1e-12);
        }
        assert_relative_eq!(fit.line.alpha_rad, 0.0, epsilon = 1e-12);
        assert_relative_eq!(fit.line.n_mm, 0.0, epsilon = 1e-12);
        assert_relative_eq!(fit.slope_m.unwrap(), 0.0, epsilon = 1e-12);
        assert_relative_eq!(fit.intercept_n_mm.unwrap(), 0.0, epsilon = 1e-12);
        let q = fit.quadratic.unwrap();
        for coeff in [q.a, q.b, q.c] {
            assert_relative_eq!(coeff, 0.0, epsilon = 1e-12);
        }
        assert_relative_eq!(fit.peak_dv_v, 1.0);
        // Five centroids at u = -2..2 pitches: n = 5, Σs² = 10, and
        // p2 = s² - 2 gives Σp2² = 14.
        assert_relative_eq!(fit.condition.line, 2f64.sqrt(), epsilon = 1e-12);
        assert_relative_eq!(
            fit.condition.quadratic.unwrap(),
            (14.0f64 / 5.0).sqrt(),
            epsilon = 1e-12
        );
        assert_eq!(
            (
                fit.negative_taxels,
                fit.saturated_taxels,
                fit.non_finite_taxels
            ),
            (0, 0, 0)
        );
    }

    /// Max |Δα| and |Δoffset| of the fit against the truth.
    fn line_error(fit: &LineInSensor, truth: &LineInSensor) -> (f64, f64) {
        let err = fit.error_to(truth);
        (err.alpha_rad.abs(), err.n_mm.abs())
    }

    #[test]
    fn cable_exactly_along_y_is_finite_at_a_right_angle() {
        for x_mm in [0.0, 2.0, -1.5] {
            let truth = LineInSensor::through(Vector2::new(x_mm, 0.0), Vector2::new(0.0, 1.0));
            let fit = fit_wire(&render_line(truth, 0.8), &config()).unwrap();
            assert_eq!(fit.direction, Direction::Vertical);
            assert_eq!(fit.line.alpha_rad, FRAC_PI_2);
            // The normal at +π/2 is -x; the sampling bias of the grid is
            // below 0.035 mm (see tests/tactile_fit_properties.rs).
            assert_relative_eq!(fit.line.n_mm, -x_mm, epsilon = 0.035);
            assert_eq!((fit.slope_m, fit.intercept_n_mm), (None, None));
            for c in &fit.centroids {
                assert_relative_eq!(c.x_mm, fit.centroids[0].x_mm, epsilon = 1e-12);
            }
            let q = fit.quadratic.unwrap();
            assert_relative_eq!(q.c, x_mm, epsilon = 0.035);
            assert_relative_eq!(q.a, 0.0, epsilon = 1e-12);
        }
    }

    #[test]
    fn offset_horizontal_cable_gives_intercept() {
        let fit = fit_wire(&render_line(line_at(0.0, 2.0), 1.0), &config()).unwrap();
        assert_eq!(fit.direction, Direction::Horizontal);
        assert_relative_eq!(fit.line.alpha_rad, 0.0, epsilon = 1e-12);
        // 2 mm sits between rows, where the sampled spread's centroid is
        // 0.013 mm off.
        assert_relative_eq!(fit.line.n_mm, 2.0, epsilon = 0.02);
        assert_relative_eq!(fit.intercept_n_mm.unwrap(), fit.line.n_mm, epsilon = 1e-12);
    }

    #[test]
    fn diagonals_at_thirty_degrees() {
        for alpha in [FRAC_PI_6, -FRAC_PI_6] {
            let truth = line_at(alpha, 0.0);
            let fit = fit_wire(&render_line(truth, 1.0), &config()).unwrap();
            assert_eq!(fit.direction, Direction::Horizontal);
            // The edge columns see the ridge cut by the pad's edge, which
            // pulls their centroids in: 5.7 mrad measured.
            let (d_alpha, d_offset) = line_error(&fit.line, &truth);
            assert!(d_alpha < 0.007, "{d_alpha}");
            assert!(d_offset < 1e-9, "{d_offset}");
            let (m, n) = (fit.slope_m.unwrap(), fit.intercept_n_mm.unwrap());
            assert_relative_eq!(m, fit.line.alpha_rad.tan(), epsilon = 1e-12);
            assert_relative_eq!(n, 0.0, epsilon = 1e-9);
        }
        // At 60° the cable runs closer to y: row centroids.
        let truth = line_at(2.0 * FRAC_PI_6, 1.0);
        let fit = fit_wire(&render_line(truth, 1.0), &config()).unwrap();
        assert_eq!(fit.direction, Direction::Vertical);
        let (d_alpha, d_offset) = line_error(&fit.line, &truth);
        assert!(d_alpha < 0.015 && d_offset < 0.05, "{d_alpha} {d_offset}");
    }

    /// A map whose centroids are exactly `t(u)`: each column (row) holds
    /// its unit of Δv on the two taxels around `t`, split so that eq. 5/6
    /// returns `t` exactly.
    fn render_exact(direction: Direction, t_mm: impl Fn(f64) -> f64) -> TactileMap {
        TactileMap::from_fn(|row, col| {
            // Taxel m along its column (row), counted from the top (from
            // the left), and where t falls along it, in pitches.
            let (m, along) = match direction {
                Direction::Horizontal => (row, 2.0 - t_mm(taxel_x_mm(col, PITCH)) / PITCH),
                Direction::Vertical => (col, 2.0 + t_mm(taxel_y_mm(row, PITCH)) / PITCH),
            };
            let low = (along.floor() as usize).min(3);
            let frac = along - low as f64;
            if m == low {
                1.0 - frac
            } else if m == low + 1 {
                frac
            } else {
                0.0
            }
        })
    }

    #[test]
    fn quadratic_is_exact_on_exact_centroids() {
        let truth = Quadratic {
            a: 0.05,
            b: -0.2,
            c: -1.0,
        };
        for direction in [Direction::Horizontal, Direction::Vertical] {
            let map = render_exact(direction, |u| truth.a * u * u + truth.b * u + truth.c);
            let fit = fit_wire(&map, &config()).unwrap();
            assert_eq!(fit.direction, direction);
            let q = fit.quadratic.unwrap();
            assert_relative_eq!(q.a, truth.a, epsilon = 1e-12);
            assert_relative_eq!(q.b, truth.b, epsilon = 1e-12);
            assert_relative_eq!(q.c, truth.c, epsilon = 1e-12);
        }
    }

    #[test]
    fn line_is_exact_on_exact_centroids() {
        let (m, n) = (0.3, 1.2);
        let fit = fit_wire(
            &render_exact(Direction::Horizontal, |x| m * x + n),
            &config(),
        )
        .unwrap();
        assert_relative_eq!(fit.slope_m.unwrap(), m, epsilon = 1e-12);
        assert_relative_eq!(fit.intercept_n_mm.unwrap(), n, epsilon = 1e-12);
        // x = 0.3 y + 1.2 is the line through (1.2, 0) along (0.3, 1).
        let fit = fit_wire(&render_exact(Direction::Vertical, |y| m * y + n), &config()).unwrap();
        let truth = LineInSensor::through(Vector2::new(n, 0.0), Vector2::new(m, 1.0));
        let (d_alpha, d_offset) = line_error(&fit.line, &truth);
        assert!(d_alpha < 1e-12 && d_offset < 1e-12, "{d_alpha} {d_offset}");
    }

    /// On a rendered parabola the quadratic's only error is the centroids'
    /// bias, passed through the least squares linearly. That bias is
    /// measured here (a tilted column sees the ridge wider and skewed
    /// towards the concave side, and the edge cuts it), then bounded: with
    /// centroids at u = -2..2 pitches, `a` is Σ (u²-2)/14 · t / pitch², so
    /// |Δa| ≤ (8/14) δ / pitch², and a fitted value is a hat-matrix row
    /// times the centroids, whose absolute sum is at most 51/35.
    #[test]
    fn curved_cable_recovers_the_parabola_up_to_centroid_bias() {
        let cases = [
            (
                Quadratic {
                    a: 0.06,
                    b: 0.0,
                    c: -1.5,
                },
                Direction::Horizontal,
            ),
            (
                Quadratic {
                    a: -0.04,
                    b: 0.2,
                    c: 0.5,
                },
                Direction::Vertical,
            ),
        ];
        for (truth, direction) in cases {
            let eval = |u: f64| truth.a * u * u + truth.b * u + truth.c;
            let fit = fit_wire(&render_parabola(truth, direction, 1.0), &config()).unwrap();
            assert_eq!(fit.direction, direction);
            assert_eq!(fit.centroids.len(), 5);
            type Coordinate = fn(&Centroid) -> f64;
            let (u_of, t_of): (Coordinate, Coordinate) = match direction {
                Direction::Horizontal => (|c: &Centroid| c.x_mm, |c: &Centroid| c.y_mm),
                Direction::Vertical => (|c: &Centroid| c.y_mm, |c: &Centroid| c.x_mm),
            };
            let bias_mm = fit
                .centroids
                .iter()
                .map(|c| (t_of(c) - eval(u_of(c))).abs())
                .fold(0.0, f64::max);
            // 0.137 mm measured for curvature 0.12/mm, σ = 1.95 mm.
            assert!(bias_mm < 0.14, "{bias_mm}");
            let q = fit.quadratic.unwrap();
            assert!((q.a - truth.a).abs() <= 8.0 / 14.0 * bias_mm / (PITCH * PITCH));
            for c in &fit.centroids {
                let u = u_of(c);
                let fitted = q.a * u * u + q.b * u + q.c;
                assert!((fitted - eval(u)).abs() <= 51.0 / 35.0 * bias_mm);
            }
        }
    }

    #[test]
    fn noise_alone_is_no_contact() {
        // Deterministic noise within ±0.03 V, below the 0.05 V threshold.
        let map = TactileMap::from_fn(|row, col| 0.03 * ((row * 7 + col * 13) as f64).sin());
        match fit_wire(&map, &config()) {
            Err(FitError::NoContact {
                peak_dv_v,
                threshold_v,
            }) => {
                assert!(peak_dv_v < 0.03 && peak_dv_v > 0.0);
                assert_eq!(threshold_v, 0.05);
            }
            other => panic!("{other:?}"),
        }
        let empty = TactileMap::from_fn(|_, _| 0.0);
        let zero_threshold = FitConfig {
            contact_threshold_v: 0.0,
            ..config()
        };
        assert!(matches!(
            fit_wire(&empty, &zero_threshold),
            Err(FitError::NoContact { peak_dv_v: 0.0, .. })
        ));
    }

    /// One pressed taxel has h = v = 0 and one centroid either way: no line.
    /// Two neighbours in a row tie the same way, but the tie goes to the
    /// direction with more centroids, which gives the line through them.
    #[test]
    fn single_taxel_has_no_direction_but_two_make_a_line() {
        let single = TactileMap::from_fn(|row, col| if (row, col) == (2, 2) { 0.5 } else { 0.0 });
        assert_eq!(
            fit_wire(&single, &config()),
            Err(FitError::TooFewCentroids {
                found: 1,
                direction: Direction::Vertical
            })
        );
        let pair = TactileMap::from_fn(|row, col| {
            if row == 1 && (2..=3).contains(&col) {
                0.5
            } else {
                0.0
            }
        });
        let fit = fit_wire(&pair, &config()).unwrap();
        assert_eq!((fit.h_v, fit.v_v), (0.0, 0.0));
        assert_eq!(fit.direction, Direction::Horizontal);
        assert_relative_eq!(fit.line.alpha_rad, 0.0);
        assert_relative_eq!(fit.line.n_mm, PITCH);
        assert_eq!(fit.quadratic, None);
    }

    /// Clipping the hardest-pressed taxels of an offset cable weighs the
    /// cable's own row too little: the centroids move towards the other
    /// neighbours, here towards the centre.
    #[test]
    fn saturated_taxels_are_counted_and_pull_the_centroids() {
        let truth = line_at(0.0, 0.8 * PITCH);
        let map = render_line(truth, 2.0);
        let mut clipped = map;
        for (dv, saturated) in clipped
            .dv_v
            .iter_mut()
            .flatten()
            .zip(clipped.saturated.iter_mut().flatten())
        {
            if *dv > 1.5 {
                *dv = 1.5;
                *saturated = true;
            }
        }
        let fit = fit_wire(&map, &config()).unwrap();
        let clipped_fit = fit_wire(&clipped, &config()).unwrap();
        assert_eq!(clipped_fit.saturated_taxels, 5);
        assert_eq!(clipped_fit.peak_dv_v, 1.5);
        assert!(clipped_fit.line.n_mm < fit.line.n_mm);
        assert_relative_eq!(clipped_fit.line.alpha_rad, 0.0, epsilon = 1e-12);
    }

    #[test]
    fn negative_taxels_weigh_nothing() {
        let map = render_line(line_at(0.2, 1.0), 1.0);
        let mut with_negatives = map;
        // The bottom row reads below its offset, e.g. the cap lifted there.
        for dv in &mut with_negatives.dv_v[4] {
            *dv = -0.3;
        }
        let mut zeroed = map;
        zeroed.dv_v[4] = [0.0; TAXEL_COLS];
        let fit = fit_wire(&with_negatives, &config()).unwrap();
        assert_eq!(fit.negative_taxels, 5);
        let reference = fit_wire(&zeroed, &config()).unwrap();
        assert_eq!(fit.line, reference.line);
        assert_eq!(fit.centroids, reference.centroids);
        assert_eq!(reference.negative_taxels, 0);
    }

    #[test]
    fn non_finite_taxels_weigh_nothing() {
        let map = render_line(line_at(0.0, 0.0), 1.0);
        let mut broken = map;
        broken.dv_v[0][0] = f64::NAN;
        broken.dv_v[4][4] = f64::INFINITY;
        let fit = fit_wire(&broken, &config()).unwrap();
        assert_eq!(fit.non_finite_taxels, 2);
        assert!(fit.line.alpha_rad.is_finite() && fit.line.n_mm.is_finite());
        assert_relative_eq!(fit.peak_dv_v, 1.0);
    }

    /// Weights are divided by their peak before any sum, so a map scaled
    /// to the ends of f64 fits the same line.
    #[test]
    fn extreme_voltages_stay_finite() {
        let zero_threshold = FitConfig {
            contact_threshold_v: 0.0,
            ..config()
        };
        let map = render_line(line_at(0.3, 1.0), 1.0);
        let reference = fit_wire(&map, &zero_threshold).unwrap();
        for scale in [1e-300, 1e300, f64::MAX] {
            let scaled = TactileMap::from_fn(|row, col| map.dv_v[row][col] * scale);
            let fit = fit_wire(&scaled, &zero_threshold).unwrap();
            assert!(fit.h_v.is_finite() && fit.v_v.is_finite());
            let (d_alpha, d_offset) = line_error(&fit.line, &reference.line);
            assert!(
                d_alpha < 1e-9 && d_offset < 1e-9,
                "{scale}: {d_alpha} {d_offset}"
            );
        }
    }

    #[test]
    fn unphysical_config_is_refused() {
        let map = render_line(line_at(0.0, 0.0), 1.0);
        for (pitch_mm, contact_threshold_v) in [
            (0.0, 0.05),
            (-3.55, 0.05),
            (f64::NAN, 0.05),
            (3.55, -0.1),
            (3.55, f64::INFINITY),
        ] {
            let config = FitConfig {
                pitch_mm,
                contact_threshold_v,
            };
            assert!(matches!(
                fit_wire(&map, &config),
                Err(FitError::InvalidConfig { .. })
            ));
        }
    }
}
