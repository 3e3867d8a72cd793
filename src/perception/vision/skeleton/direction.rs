//! A branch's direction where it leaves its junction, measured past the
//! junction's distortion, and the bend of going on from one branch into
//! another.

use crate::perception::vision::paths::unit;

/// A branch's direction at the junction's centre, given its pixels `pts`
/// going out of it: its direction past the junction's distortion, turned
/// on towards the centre by as much as it turns over the next two widths,
/// so that a cable bending through a crossing is judged by its curve
/// rather than its chord, and branches leaving a shallow crossing's two
/// junctions, far apart, are compared at one point.
pub(super) fn tangent_at_centre(pts: &[[f64; 2]], centre: [f64; 2], width_px: f64) -> [f64; 2] {
    let near = direction_leaving(pts, centre, width_px);
    let (skip, span) = direction_stretch(width_px);
    let (i1, i2) = (skip + span, skip + 2 * span);
    if i2 >= pts.len() {
        return near;
    }
    let far = [pts[i2][0] - pts[i1][0], pts[i2][1] - pts[i1][1]];
    let near_rad = near[1].atan2(near[0]);
    let turn_rad = near_rad - far[1].atan2(far[0]);
    let turn_rad = turn_rad.sin().atan2(turn_rad.cos());
    // From the middle of the far stretch to the middle of the near one
    // is one span; from there to the branch's start, skip + span / 2,
    // and on to the junction's centre.
    let to_centre_px = (pts[0][0] - centre[0]).hypot(pts[0][1] - centre[1]);
    let back_px = skip as f64 + 0.5 * span as f64 + to_centre_px;
    let back_rad = near_rad + turn_rad * back_px / span as f64;
    [back_rad.cos(), back_rad.sin()]
}

/// The direction of a branch's pixels `pts` (going out of a junction at
/// `centre`) over the stretch of [`direction_stretch`], or from the centre
/// to its last pixel when it is shorter.
pub(super) fn direction_leaving(pts: &[[f64; 2]], centre: [f64; 2], width_px: f64) -> [f64; 2] {
    let Some(last) = pts.len().checked_sub(1) else {
        return [0.0, 0.0];
    };
    let (skip, span) = direction_stretch(width_px);
    let i0 = skip.min(last);
    let i1 = (skip + span).min(last);
    let (from, to) = if i1 > i0 {
        (pts[i0], pts[i1])
    } else {
        (centre, pts[last])
    };
    unit(from, to).unwrap_or([0.0, 0.0])
}

/// Where a branch's direction is measured, in pixels along it from its
/// junction: past the junction's distortion (about one width out), over two
/// widths.
pub(super) fn direction_stretch(width_px: f64) -> (usize, usize) {
    let skip = (0.75 * width_px).round() as usize;
    let span = (2.0 * width_px).max(8.0).round() as usize;
    (skip, span)
}

/// Bending, in radians, of going in along `a` (pointing out of the
/// junction) and out along `b`: 0 for a straight continuation.
pub(super) fn bend_rad(a: [f64; 2], b: [f64; 2]) -> f64 {
    let cos = -(a[0] * b[0] + a[1] * b[1]);
    cos.clamp(-1.0, 1.0).acos()
}
