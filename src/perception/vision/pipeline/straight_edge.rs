//! Straight detections dropped as edges: the network takes edges of
//! paper, folders and tables for cables, and a cable lying loose is never
//! that straight (see [`VisionConfig::straight_edge_radius_px`]). On a
//! background plain around each pixel, a straight detection whose two
//! sides are alike is a taut cable, kept; on a busy one (paint, prints,
//! mosaics) every straight detection is, since the edges lie on tables.
//!
//! [`VisionConfig::straight_edge_radius_px`]: super::VisionConfig::straight_edge_radius_px

use opencv::core::Mat;
use opencv::prelude::*;

use crate::perception::vision::error::VisionError;
use crate::perception::vision::{mask, paths, spline};

/// How far from straight an edge's detection can be: mask noise and lens
/// distortion bend a paper edge's by up to 2 px in cables-dev; a cable that
/// departs more from its chord is visibly bent, however long.
const EDGE_MAX_SAGITTA_PX: f64 = 3.0;

/// Within this of straight, a detection's shape cannot tell it from an
/// edge, however short: mask noise alone bends edges' detections this much
/// (0.6 to 1.7 px in cables-dev; its wire pieces depart 2.2 px or more).
pub(super) const EDGE_NOISE_SAGITTA_PX: f64 = 1.5;

/// The share of an edge's detection, at each end, that may hook away
/// from the edge: where a folder's edge meets its corner, the detection
/// turns along the other edge for a few widths.
const EDGE_HOOK_SHARE: f64 = 0.1;

/// Whether a detection (points along it, evenly spaced, `length_px` long)
/// is straight enough to be an edge (never when `radius_px` is 0): within
/// [`EDGE_MAX_SAGITTA_PX`] of its chord and bending less than an arc of
/// `radius_px`, or within [`EDGE_NOISE_SAGITTA_PX`] of its chord; or so
/// between hooks at its ends (see [`EDGE_HOOK_SHARE`]), judged by the bend
/// alone, since a piece of a bending cable is as near its own chord.
pub(super) fn looks_like_edge(points_px: &[[f64; 2]], length_px: f64, radius_px: f64) -> bool {
    let bends_less = |points: &[[f64; 2]], length_px: f64| {
        let sagitta_px = spline::chord_sagitta_px(points);
        sagitta_px < EDGE_MAX_SAGITTA_PX && spline::arc_radius_px(length_px, sagitta_px) > radius_px
    };
    let hook = (EDGE_HOOK_SHARE * points_px.len() as f64).round() as usize;
    let middle = &points_px[hook..points_px.len() - hook];
    radius_px > 0.0
        && (spline::chord_sagitta_px(points_px) < EDGE_NOISE_SAGITTA_PX
            || bends_less(points_px, length_px)
            || bends_less(middle, (1.0 - 2.0 * EDGE_HOOK_SHARE) * length_px))
}

/// On a background plain around each pixel, a straight detection is a
/// cable, not an edge, when the background's colours either side of it
/// differ by less than this share of the smaller difference between the
/// detection and either side. An edge's sides differ: the paper and table
/// edges taken for cables in cables-dev's photographs (on busy
/// backgrounds) score 1.0 and 1.25. A cable's do not: about as many
/// rendered straight detections are kept at any share from 0.3 to 1.5
/// (docs/vision-record.md, "Straight cables on a plain table").
pub(super) const EDGE_SIDES_RATIO: f64 = 0.5;
/// Where each side's background is read, in cable widths from the
/// detection's centre line: clear of the cable and its shading.
const SIDE_OFFSETS_WIDTHS: [f64; 2] = [1.0, 1.5];

/// Whether a straight detection (points along it, cables `width_px`
/// wide) is a cable, not an edge: the BGR `image`'s background is alike
/// on the detection's two sides and plain around each pixel off the
/// cables of `mask` and a width around them ([`mask::plain_locally`], the
/// dearer test, asked second and kept in `plain_around` for the image
/// once asked). Not when the image's colour is unknown.
pub(super) fn straight_cable(
    image: &Mat,
    mask: &Mat,
    points_px: &[[f64; 2]],
    width_px: f64,
    plain_around: &mut Option<bool>,
) -> Result<bool, VisionError> {
    if image.channels() != 3 {
        return Ok(false);
    }
    if !sides_alike(image, mask, points_px, width_px)? {
        return Ok(false);
    }
    match *plain_around {
        Some(plain) => Ok(plain),
        None => Ok(*plain_around.insert(mask::plain_locally(image, mask, width_px)?)),
    }
}

/// Whether the BGR `image`'s background, off `mask`, is alike on the two
/// sides of a detection (points along it, cables `width_px` wide; see
/// [`EDGE_SIDES_RATIO`]). Not when a side is unknown.
fn sides_alike(
    image: &Mat,
    mask: &Mat,
    points_px: &[[f64; 2]],
    width_px: f64,
) -> Result<bool, VisionError> {
    let in_background = |p: [f64; 2]| {
        paths::pixel_in(image, p)
            .is_some_and(|(row, col)| mask.at_2d::<u8>(row, col).is_ok_and(|&v| v == 0))
    };
    let mut sides = [Vec::new(), Vec::new()];
    for w in points_px.windows(3) {
        let Some(along) = paths::unit(w[0], w[2]) else {
            continue;
        };
        let across = [-along[1], along[0]];
        for offset in SIDE_OFFSETS_WIDTHS.map(|k| k * width_px) {
            for (side, sign) in sides.iter_mut().zip([1.0, -1.0]) {
                let p = [
                    w[1][0] + sign * offset * across[0],
                    w[1][1] + sign * offset * across[1],
                ];
                if in_background(p) {
                    side.push(p);
                }
            }
        }
    }
    let [left, right] = &sides;
    let colours = (
        paths::median_colour_lab(image, left)?,
        paths::median_colour_lab(image, right)?,
        paths::median_colour_lab(image, points_px)?,
    );
    let (Some(left), Some(right), Some(middle)) = colours else {
        return Ok(false);
    };
    let to_middle = paths::delta_e(middle, left).min(paths::delta_e(middle, right));
    Ok(paths::delta_e(left, right) < EDGE_SIDES_RATIO * to_middle)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::perception::vision::curves::arc_px;

    #[test]
    fn an_edge_bends_less_than_the_radius_or_no_more_than_mask_noise() {
        use std::f64::consts::FRAC_PI_2;
        // A piece of a circle, `length_px` long, as points.
        let piece = |length_px: f64, radius_px: f64| {
            let half_rad = length_px / radius_px / 2.0;
            let points = arc_px(
                [0.0, radius_px],
                radius_px,
                -FRAC_PI_2 - half_rad,
                -FRAC_PI_2 + half_rad,
            );
            (points, length_px)
        };
        let edge = |(points, length_px): (Vec<[f64; 2]>, f64), radius_px| {
            looks_like_edge(&points, length_px, radius_px)
        };
        // 300 px, 2.25 px from straight: a paper edge, unless kept.
        assert!(edge(piece(300.0, 5000.0), 1500.0));
        assert!(!edge(piece(300.0, 5000.0), 0.0));
        // 300 px, 11 px from straight: a cable.
        assert!(!edge(piece(300.0, 1000.0), 1500.0));
        // 70 px, 1.2 px from straight (a 500 px arc): too short for its bend
        // to tell it from an edge's noisy detection.
        assert!(edge(piece(70.0, 500.0), 1500.0));
        // 110 px, 2.5 px from straight: a piece of cable.
        assert!(!edge(piece(110.0, 600.0), 1500.0));
        // 300 px straight, hooking off along a corner for its last 30 px:
        // an edge; a cable's arc as long and hooked alike is none.
        let hooked = |(mut points, length_px): (Vec<[f64; 2]>, f64)| {
            let end = *points.last().unwrap();
            let step = length_px / (points.len() - 1) as f64;
            let more = (30.0 / step).round() as usize;
            for k in 1..=more {
                let along = k as f64 * step * std::f64::consts::FRAC_1_SQRT_2;
                points.push([end[0] + along, end[1] + along]);
            }
            let n = points.len();
            let resampled: Vec<[f64; 2]> = (0..50).map(|i| points[i * (n - 1) / 49]).collect();
            (resampled, length_px + 30.0)
        };
        assert!(!edge(hooked(piece(300.0, 1e9)), 0.0));
        assert!(!looks_like_edge(&hooked(piece(300.0, 1e9)).0, 330.0, 1e12));
        assert!(edge(hooked(piece(300.0, 1e9)), 1500.0));
        assert!(!edge(hooked(piece(300.0, 1000.0)), 1500.0));
    }
}
