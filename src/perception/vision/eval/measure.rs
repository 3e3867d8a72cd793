//! Measures that the label checks and the scores share: pixel counts
//! and overlaps of masks, and distances to polylines.

use opencv::core::{self, Mat, Size};
use opencv::prelude::*;

pub(super) fn size_of(m: &Mat) -> Size {
    Size::new(m.cols(), m.rows())
}

pub(super) fn count(m: &Mat) -> f64 {
    f64::from(core::count_non_zero(m).unwrap_or(0))
}

/// (|A∩B|, |A|, |B|) of two masks; zeros when they cannot be compared
/// (different sizes).
pub(super) fn overlap(a: &Mat, b: &Mat) -> (f64, f64, f64) {
    let mut both = Mat::default();
    if core::bitwise_and(a, b, &mut both, &core::no_array()).is_err() {
        return (0.0, count(a), count(b));
    }
    (count(&both), count(a), count(b))
}

pub(super) fn dice(a: &Mat, b: &Mat) -> f64 {
    let (i, na, nb) = overlap(a, b);
    if na + nb > 0.0 {
        2.0 * i / (na + nb)
    } else {
        1.0
    }
}

/// Distance from `p` to the nearest segment of any of `polylines`.
pub fn distance_to_polylines(p: [f64; 2], polylines: &[Vec<[f64; 2]>]) -> f64 {
    let mut best = f64::INFINITY;
    for line in polylines {
        if let [only] = line.as_slice() {
            best = best.min((p[0] - only[0]).hypot(p[1] - only[1]));
        }
        for w in line.windows(2) {
            let (a, b) = (w[0], w[1]);
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let len2 = dx * dx + dy * dy;
            let t = if len2 > 0.0 {
                (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let (cx, cy) = (a[0] + t * dx, a[1] + t * dy);
            best = best.min((p[0] - cx).hypot(p[1] - cy));
        }
    }
    best
}

pub(super) fn mean(values: impl Iterator<Item = f64>) -> Option<f64> {
    let (sum, n) = values.fold((0.0, 0usize), |(s, n), v| (s + v, n + 1));
    (n > 0).then(|| sum / n as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distance_to_a_polyline_is_to_its_nearest_segment() {
        let lines = vec![vec![[0.0, 0.0], [10.0, 0.0], [10.0, 10.0]]];
        assert!((distance_to_polylines([5.0, 3.0], &lines) - 3.0).abs() < 1e-12);
        assert!((distance_to_polylines([13.0, 5.0], &lines) - 3.0).abs() < 1e-12);
        assert!((distance_to_polylines([-3.0, -4.0], &lines) - 5.0).abs() < 1e-12);
    }
}
