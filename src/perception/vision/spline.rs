//! The cable model of the paper's Section II: a cubic B-spline through the
//! cable's centreline, parameterised by s ∈ [0, 1] from one end to the
//! other, whose middle (s = 0.5) is the grasp point and whose direction
//! there comes from the points at s = 0.45 and s = 0.55.

use nalgebra::{Cholesky, DMatrix, DVector, Dyn};
use schemars::JsonSchema;

/// Length of cable, in pixels, per control point: fine enough to follow a
/// bend of a few cable widths, coarse enough to smooth pixel staircases.
const PX_PER_CONTROL_POINT: f64 = 30.0;
/// Most control points a spline gets, whatever its length.
const MAX_CONTROL_POINTS: usize = 24;
/// Weight of the second-difference penalty on the control points, relative
/// to the data term's scale: it only keeps the least-squares system well
/// posed where a knot span holds few points (across a crossing gap).
const SMOOTHING: f64 = 1e-6;

/// A clamped B-spline curve in the image plane.
#[derive(Clone, Debug, PartialEq, serde::Serialize, JsonSchema)]
pub struct BSpline {
    /// Polynomial degree (3, lower only when fitted to very few points).
    pub degree: usize,
    /// Control points in the units of the points fitted: image
    /// coordinates (x right, y down, pixels) for a cable in an image,
    /// millimetres in a plane for a fused shape.
    #[serde(rename = "control_points_px")]
    pub control_points: Vec<[f64; 2]>,
    /// Clamped knot vector on [0, 1], `control_points + degree + 1` long.
    pub knots: Vec<f64>,
}

/// How many control points a cable of `length_px` gets.
pub fn control_points_for_length(length_px: f64) -> usize {
    let n = (length_px / PX_PER_CONTROL_POINT).round();
    (n.max(4.0) as usize).min(MAX_CONTROL_POINTS)
}

/// The knot span holding `u` (The NURBS Book, A2.1).
fn find_span(knots: &[f64], degree: usize, n_control: usize, u: f64) -> usize {
    if u >= knots[n_control] {
        return n_control - 1;
    }
    if u <= knots[degree] {
        return degree;
    }
    let (mut low, mut high) = (degree, n_control);
    let mut mid = (low + high) / 2;
    while u < knots[mid] || u >= knots[mid + 1] {
        if u < knots[mid] {
            high = mid;
        } else {
            low = mid;
        }
        mid = (low + high) / 2;
    }
    mid
}

/// The `degree + 1` non-zero basis functions at `u` in `span` (The NURBS
/// Book, A2.2).
fn basis(knots: &[f64], degree: usize, span: usize, u: f64) -> Vec<f64> {
    let mut n = vec![0.0; degree + 1];
    let mut left = vec![0.0; degree + 1];
    let mut right = vec![0.0; degree + 1];
    n[0] = 1.0;
    for j in 1..=degree {
        left[j] = u - knots[span + 1 - j];
        right[j] = knots[span + j] - u;
        let mut saved = 0.0;
        for r in 0..j {
            let denom = right[r + 1] + left[j - r];
            let temp = if denom.abs() > 0.0 { n[r] / denom } else { 0.0 };
            n[r] = saved + right[r + 1] * temp;
            saved = left[j - r] * temp;
        }
        n[j] = saved;
    }
    n
}

impl BSpline {
    /// Least-squares fit with chord-length parameterisation: the points'
    /// cumulative distance, scaled to [0, 1], is their parameter, so s is
    /// close to the fraction of length from the first point. Degree 3 when
    /// there are enough points; `None` for fewer than two distinct points.
    /// At most one control point per two points, so that sparse points (a
    /// superpixel walk's nodes) cannot make the curve swing between them.
    pub fn fit(points_px: &[[f64; 2]], control_points: usize) -> Option<BSpline> {
        let finite: Vec<[f64; 2]> = points_px
            .iter()
            .copied()
            .filter(|p| p[0].is_finite() && p[1].is_finite())
            .collect();
        let u = arc_lengths_px(&finite);
        let acc = u.last().copied().unwrap_or(0.0);
        if finite.len() < 2 || acc <= 0.0 {
            return None;
        }
        let samples: Vec<Sample> = finite
            .iter()
            .zip(&u)
            .map(|(&point, &u)| Sample {
                point,
                s: u / acc,
                weight: 1.0,
            })
            .collect();
        least_squares(&samples, control_points, 0.0).map(|fit| fit.spline)
    }

    /// Weighted least-squares fit at parameters the caller chose (a fusion
    /// of several sources, whose points interleave along the curve, cannot
    /// take chord lengths): each sample counts `weight` times (1/σ² for
    /// points of standard deviation σ). Samples with a parameter outside
    /// [0, 1], a weight that is not positive, or anything not finite are
    /// left out. `bending_weight` weighs the control points' squared second
    /// differences against the samples (in the weights' units), on top of
    /// the light penalty every fit has: a prior on how much the curve
    /// bends, which holds it where samples are few. Otherwise as
    /// [`BSpline::fit`]; with the fit comes what gives the curve's standard
    /// deviation.
    pub fn fit_weighted(
        samples: &[Sample],
        control_points: usize,
        bending_weight: f64,
    ) -> Option<WeightedFit> {
        let kept: Vec<Sample> = samples
            .iter()
            .copied()
            .filter(|sample| {
                sample.point.iter().all(|v| v.is_finite())
                    && (0.0..=1.0).contains(&sample.s)
                    && sample.weight.is_finite()
                    && sample.weight > 0.0
            })
            .collect();
        least_squares(&kept, control_points, bending_weight.max(0.0))
    }

    /// The curve's point at `s` (clamped to [0, 1]), by de Boor's
    /// algorithm.
    pub fn point(&self, s: f64) -> [f64; 2] {
        let n = self.control_points.len();
        if n == 0 || self.knots.len() != n + self.degree + 1 {
            return [f64::NAN, f64::NAN];
        }
        let s = if s.is_nan() { 0.0 } else { s.clamp(0.0, 1.0) };
        let span = find_span(&self.knots, self.degree, n, s);
        let b = basis(&self.knots, self.degree, span, s);
        let first = span - self.degree;
        b.iter().enumerate().fold([0.0, 0.0], |acc, (k, &w)| {
            let c = self.control_points[first + k];
            [acc[0] + w * c[0], acc[1] + w * c[1]]
        })
    }

    /// `count` points at uniform s from 0 to 1 inclusive.
    pub fn sample(&self, count: usize) -> Vec<[f64; 2]> {
        match count {
            0 => Vec::new(),
            1 => vec![self.point(0.5)],
            _ => (0..count)
                .map(|i| self.point(i as f64 / (count - 1) as f64))
                .collect(),
        }
    }

    /// The image-plane angle (atan2(dy, dx), y down) of the chord from
    /// s = 0.45 to s = 0.55: the paper's grasp direction.
    pub fn grasp_direction_rad(&self) -> f64 {
        let a = self.point(0.45);
        let b = self.point(0.55);
        (b[1] - a[1]).atan2(b[0] - a[0])
    }
}

/// A point to fit at its parameter, with its weight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    pub point: [f64; 2],
    /// Where on the curve, in [0, 1].
    pub s: f64,
    pub weight: f64,
}

/// A weighted fit and its normal equations, which give the curve's
/// standard deviation where it was fitted.
#[derive(Clone, Debug)]
pub struct WeightedFit {
    pub spline: BSpline,
    /// The factored normal matrix (data and smoothing), the inverse of the
    /// control points' covariance when the weights are 1/σ².
    normal: Cholesky<f64, Dyn>,
}

impl WeightedFit {
    /// The standard deviation of the curve's point at `s` (each
    /// coordinate), from the weights taken as 1/σ²: small where many sure
    /// points pull, large across a stretch only the smoothing holds.
    pub fn sigma(&self, s: f64) -> f64 {
        let spline = &self.spline;
        let n = spline.control_points.len();
        let s = if s.is_nan() { 0.0 } else { s.clamp(0.0, 1.0) };
        let span = find_span(&spline.knots, spline.degree, n, s);
        let mut phi = DVector::<f64>::zeros(n);
        for (k, b) in basis(&spline.knots, spline.degree, span, s)
            .into_iter()
            .enumerate()
        {
            phi[span - spline.degree + k] = b;
        }
        phi.dot(&self.normal.solve(&phi)).max(0.0).sqrt()
    }
}

/// The least-squares B-spline through `samples` at their parameters, with
/// uniform interior knots and a second-difference penalty: a light one,
/// and `bending_weight` more.
fn least_squares(
    samples: &[Sample],
    control_points: usize,
    bending_weight: f64,
) -> Option<WeightedFit> {
    let m = samples.len();
    if m < 2 {
        return None;
    }
    let degree = 3.min(m - 1);
    let n = control_points.clamp(degree + 1, (m / 2).max(degree + 1));
    let interior = n - degree - 1;
    let mut knots = vec![0.0; degree + 1];
    knots.extend((1..=interior).map(|i| i as f64 / (interior + 1) as f64));
    knots.extend(std::iter::repeat_n(1.0, degree + 1));

    let mut ata = DMatrix::<f64>::zeros(n, n);
    let mut atb = DMatrix::<f64>::zeros(n, 2);
    let mut total_weight = 0.0;
    for sample in samples {
        let (p, w) = (sample.point, sample.weight);
        total_weight += w;
        let span = find_span(&knots, degree, n, sample.s);
        let b = basis(&knots, degree, span, sample.s);
        let first = span - degree;
        for (a, &ba) in b.iter().enumerate() {
            for (c, &bc) in b.iter().enumerate() {
                ata[(first + a, first + c)] += w * ba * bc;
            }
            atb[(first + a, 0)] += w * ba * p[0];
            atb[(first + a, 1)] += w * ba * p[1];
        }
    }
    // Second-difference penalty, the light one scaled to the data's weight.
    let lambda = SMOOTHING * total_weight / n as f64 + bending_weight;
    for i in 0..n.saturating_sub(2) {
        let d = [1.0, -2.0, 1.0];
        for a in 0..3 {
            for c in 0..3 {
                ata[(i + a, i + c)] += lambda * d[a] * d[c];
            }
        }
    }
    let normal = ata.cholesky()?;
    let solution = normal.solve(&atb);
    let spline = BSpline {
        degree,
        control_points: (0..n)
            .map(|i| [solution[(i, 0)], solution[(i, 1)]])
            .collect(),
        knots,
    };
    Some(WeightedFit { spline, normal })
}

/// The largest distance of `points_px` from the chord joining their ends:
/// an arc's sagitta, 0 for a straight line.
pub fn chord_sagitta_px(points_px: &[[f64; 2]]) -> f64 {
    let (Some(a), Some(b)) = (points_px.first(), points_px.last()) else {
        return 0.0;
    };
    let chord = [b[0] - a[0], b[1] - a[1]];
    let chord_px = chord[0].hypot(chord[1]);
    points_px
        .iter()
        .map(|p| {
            let (dx, dy) = (p[0] - a[0], p[1] - a[1]);
            if chord_px > 0.0 {
                (dx * chord[1] - dy * chord[0]).abs() / chord_px
            } else {
                dx.hypot(dy)
            }
        })
        .fold(0.0, f64::max)
}

/// The radius of the circular arc `length_px` long whose sagitta is
/// `sagitta_px` (L²/8h, for arcs much shorter than their circle).
pub fn arc_radius_px(length_px: f64, sagitta_px: f64) -> f64 {
    length_px * length_px / (8.0 * sagitta_px)
}

/// The length along `points` up to each of them, from 0 at the first.
pub(super) fn arc_lengths_px(points: &[[f64; 2]]) -> Vec<f64> {
    let mut total_px = 0.0;
    let mut lengths = Vec::with_capacity(points.len());
    for (i, p) in points.iter().enumerate() {
        if i > 0 {
            total_px += (p[0] - points[i - 1][0]).hypot(p[1] - points[i - 1][1]);
        }
        lengths.push(total_px);
    }
    lengths
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn a_straight_line_is_reproduced_with_s_as_length_fraction() {
        let pts: Vec<[f64; 2]> = (0..=100).map(|i| [i as f64, 2.0 * i as f64]).collect();
        let spline = BSpline::fit(&pts, 5).unwrap();
        let mid = spline.point(0.5);
        assert!(
            (mid[0] - 50.0).abs() < 1e-3 && (mid[1] - 100.0).abs() < 1e-3,
            "{mid:?}"
        );
        let ends = (spline.point(0.0), spline.point(1.0));
        assert!(
            (ends.0[0]).abs() < 1e-3 && (ends.1[0] - 100.0).abs() < 1e-3,
            "{ends:?}"
        );
        let dir = spline.grasp_direction_rad();
        assert!((dir - 2.0f64.atan2(1.0)).abs() < 1e-6);
    }

    #[test]
    fn a_circle_arc_is_followed_within_a_tenth_of_a_pixel() {
        let pts: Vec<[f64; 2]> = (0..=300)
            .map(|i| {
                let t = std::f64::consts::PI * i as f64 / 300.0;
                [200.0 + 100.0 * t.cos(), 200.0 + 100.0 * t.sin()]
            })
            .collect();
        let spline = BSpline::fit(&pts, control_points_for_length(314.0)).unwrap();
        for p in spline.sample(50) {
            let r = (p[0] - 200.0).hypot(p[1] - 200.0);
            assert!((r - 100.0).abs() < 0.1, "r = {r}");
        }
        let mid = spline.point(0.5);
        assert!(
            (mid[0] - 200.0).abs() < 0.5 && (mid[1] - 300.0).abs() < 0.5,
            "{mid:?}"
        );
    }

    #[test]
    fn degenerate_inputs_give_none_or_lower_degree() {
        assert!(BSpline::fit(&[], 4).is_none());
        assert!(BSpline::fit(&[[1.0, 1.0]], 4).is_none());
        assert!(BSpline::fit(&[[1.0, 1.0], [1.0, 1.0]], 4).is_none());
        assert!(BSpline::fit(&[[f64::NAN, 1.0], [2.0, 1.0]], 4).is_none());
        let two = BSpline::fit(&[[0.0, 0.0], [10.0, 0.0]], 4).unwrap();
        assert_eq!(two.degree, 1);
        let mid = two.point(0.5);
        assert!((mid[0] - 5.0).abs() < 1e-6, "{mid:?}");
    }

    #[test]
    fn an_arcs_sagitta_gives_back_its_radius_and_a_line_has_none() {
        for radius_px in [300.0, 1000.0, 3000.0] {
            let angle_rad: f64 = 150.0 / radius_px;
            let arc: Vec<[f64; 2]> = (0..=50)
                .map(|i| {
                    let t = angle_rad * (i as f64 / 50.0 - 0.5);
                    [radius_px * t.sin(), radius_px * t.cos()]
                })
                .collect();
            let found = arc_radius_px(radius_px * angle_rad, chord_sagitta_px(&arc));
            assert!(
                (found / radius_px - 1.0).abs() < 0.02,
                "radius {radius_px}: {found}"
            );
        }
        let line: Vec<[f64; 2]> = (0..10).map(|i| [i as f64, 2.0 * i as f64]).collect();
        assert_eq!(chord_sagitta_px(&line), 0.0);
        assert_eq!(arc_radius_px(20.0, 0.0), f64::INFINITY);
        assert_eq!(chord_sagitta_px(&[]), 0.0);
        // A closed loop: the distance from its ends.
        assert_eq!(chord_sagitta_px(&[[1.0, 1.0], [4.0, 5.0], [1.0, 1.0]]), 5.0);
    }

    #[test]
    fn unit_weights_at_chord_lengths_give_the_plain_fit() {
        let pts: Vec<[f64; 2]> = (0..=60)
            .map(|i| {
                let t = i as f64 / 60.0;
                [100.0 * t, 20.0 * (3.0 * t).sin()]
            })
            .collect();
        let plain = BSpline::fit(&pts, 6).unwrap();
        let lengths = arc_lengths_px(&pts);
        let total = lengths[lengths.len() - 1];
        let samples: Vec<Sample> = pts
            .iter()
            .zip(&lengths)
            .map(|(&point, &u)| Sample {
                point,
                s: u / total,
                weight: 1.0,
            })
            .collect();
        let weighted = BSpline::fit_weighted(&samples, 6, 0.0).unwrap();
        assert_eq!(weighted.spline, plain);
    }

    /// Samples along x in [0, 100] at `y`, s = x / 100.
    fn level(y: f64, weight: f64, xs: impl Iterator<Item = f64>) -> Vec<Sample> {
        xs.map(|x| Sample {
            point: [x, y],
            s: x / 100.0,
            weight,
        })
        .collect()
    }

    #[test]
    fn the_heavier_points_pull_the_curve_by_their_weight() {
        // Two interleaved rows, y = 0 at weight 1 and y = 1 at weight 3:
        // the weighted mean, 0.75, away from the ends (where one row's
        // last point has the end to itself).
        let mut samples = level(0.0, 1.0, (0..=50).map(|i| 2.0 * i as f64));
        samples.extend(level(1.0, 3.0, (0..50).map(|i| 2.0 * i as f64 + 1.0)));
        let fit = BSpline::fit_weighted(&samples, 8, 0.0).unwrap();
        for k in 1..10 {
            let p = fit.spline.point(f64::from(k) / 10.0);
            assert!((p[1] - 0.75).abs() < 0.02, "{p:?}");
        }
        // Points of σ = 1 at weight 1: 101 of them leave about 1/√(101/8)
        // on the curve, far less than one point's.
        let sigma = fit.sigma(0.5);
        assert!(sigma > 0.05 && sigma < 0.5, "{sigma}");
    }

    #[test]
    fn the_curve_is_sure_where_points_are_and_unsure_across_a_gap() {
        // Points on y = 0 but for x in (30, 70).
        let xs = (0..=100)
            .map(f64::from)
            .filter(|x| !(30.0..=70.0).contains(x));
        let fit = BSpline::fit_weighted(&level(0.0, 1.0, xs), 10, 0.0).unwrap();
        let (seen, hidden) = (fit.sigma(0.15), fit.sigma(0.5));
        assert!(hidden > 3.0 * seen, "seen {seen}, hidden {hidden}");
        // The smoothing carries the curve straight across.
        assert!(fit.spline.point(0.5)[1].abs() < 1e-3);
        // Nothing usable: no curve.
        let bad = [Sample {
            point: [f64::NAN, 0.0],
            s: 0.5,
            weight: 1.0,
        }; 4];
        assert!(BSpline::fit_weighted(&bad, 4, 0.0).is_none());
        let outside = level(0.0, 1.0, [120.0, 150.0, 180.0].into_iter());
        assert!(BSpline::fit_weighted(&outside, 4, 0.0).is_none());
    }

    proptest! {
        #[test]
        fn fitted_points_stay_near_a_smooth_curve(
            a in -0.002f64..0.002, b in -1.0f64..1.0, c in 0.0f64..400.0, n in 20usize..400
        ) {
            let pts: Vec<[f64; 2]> = (0..n).map(|i| {
                let x = i as f64;
                [x, a * x * x + b * x + c]
            }).collect();
            let spline = BSpline::fit(&pts, control_points_for_length(n as f64)).unwrap();
            for (k, p) in spline.sample(20).iter().enumerate() {
                let y = a * p[0] * p[0] + b * p[0] + c;
                prop_assert!((p[1] - y).abs() < 0.5, "sample {} at {:?}: curve y {}", k, p, y);
                prop_assert!(p[0] >= -0.5 && p[0] <= n as f64, "x {}", p[0]);
            }
        }
    }
}
