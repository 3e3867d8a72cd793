//! Where to grasp when the camera cannot say where the cable is (an
//! occlusion, no cable detected, no usable detector): the paper's
//! "correction of the cable grasping pose based on the output of the
//! tactile sensor only", from a prior on the cable's grasp frame.
//!
//! A closing grasp catches a cable that lies across the pad, and the pad
//! feels it, within the band spanned by its rows of taxels: a search grasps
//! at the prior's mean first, then steps across the cable (the prior
//! frame's y) on alternating sides, each step shorter than that band so
//! that the bands overlap, out to a few σ of the prior. A probe reads a
//! cable within ±π/4 of its x-axis along its columns, the paper's case
//! (beyond, the direction test reads it along the rows); when the prior's
//! angle is that uncertain, each offset is also tried turned by a step
//! either way. Poses are tried most likely first, at most `max_moves`.

use std::f64::consts::{FRAC_PI_2, FRAC_PI_4};

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

use super::map::TAXEL_ROWS;

/// How many σ of the prior, each side, a search covers.
pub const COVERED_SIGMAS: f64 = 3.0;

/// A step between probes as a fraction of the band one probe covers: the
/// bands overlap by a quarter, which takes up the arm's repeatability and
/// a cable that lands on the outer row.
const STEP_FRACTION: f64 = 0.75;

/// The angle either side of a probe's x-axis at which the pad still reads
/// the cable along its columns.
pub const ANGLE_HALF_BAND_RAD: f64 = FRAC_PI_4;

/// Where the cable roughly lies, and how sure that is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Prior {
    /// The cable's grasp frame, as a detector would give it: x along the
    /// cable, y across it in the pad's plane, z the closing axis.
    pub base_from_cable: Isometry3<f64>,
    /// σ of the cable's position across it (along the frame's y).
    pub position_sigma_mm: f64,
    /// σ of the cable's direction about the closing axis (the frame's z).
    pub angle_sigma_rad: f64,
    /// Grasps a search may make, the first at the mean included.
    pub max_moves: usize,
}

/// One grasp of a search, relative to the prior's mean.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SearchPose {
    /// Along the prior frame's y, across the cable.
    pub across_mm: f64,
    /// About the prior frame's z, the closing axis.
    pub angle_rad: f64,
}

impl SearchPose {
    /// The grasp frame this pose aims at.
    pub fn base_from_cable(&self, prior: &Prior) -> Isometry3<f64> {
        prior.base_from_cable
            * Isometry3::from_parts(
                Translation3::new(0.0, self.across_mm, 0.0),
                UnitQuaternion::from_axis_angle(&Vector3::z_axis(), self.angle_rad),
            )
    }
}

/// Half the band across the pad in which a grasp catches the cable and the
/// pad feels it: from the centre to the outer rows of taxels.
pub fn probe_half_width_mm(pitch_mm: f64) -> f64 {
    (TAXEL_ROWS - 1) as f64 / 2.0 * pitch_mm
}

/// The grasps a search tries, in order: the prior's mean first, then the
/// others by their distance from it in σ, a side's step before the other
/// side's; at most `max_moves` of them, and at least the mean. `pitch_mm`
/// is the pad's taxel pitch.
pub fn search_poses(prior: &Prior, pitch_mm: f64) -> Vec<SearchPose> {
    let half_mm = probe_half_width_mm(pitch_mm);
    let across = steps(
        half_mm,
        COVERED_SIGMAS * prior.position_sigma_mm,
        prior.max_moves,
    );
    // A line's angle is taken modulo π: no turn beyond a quarter turn.
    let angles = steps(
        ANGLE_HALF_BAND_RAD,
        (COVERED_SIGMAS * prior.angle_sigma_rad).min(FRAC_PI_2),
        prior.max_moves,
    );
    let mut poses: Vec<SearchPose> = angles
        .iter()
        .flat_map(|&angle_rad| {
            across.iter().map(move |&across_mm| SearchPose {
                across_mm,
                angle_rad,
            })
        })
        .collect();
    let sigmas = |value: f64, sigma: f64| if value == 0.0 { 0.0 } else { value / sigma };
    let distance = |pose: &SearchPose| {
        sigmas(pose.across_mm, prior.position_sigma_mm).powi(2)
            + sigmas(pose.angle_rad, prior.angle_sigma_rad).powi(2)
    };
    // Stable: equal distances keep the alternating order of `steps`.
    poses.sort_by(|a, b| distance(a).total_cmp(&distance(b)));
    poses.truncate(prior.max_moves.max(1));
    poses
}

/// 0, +s, −s, +2s, −2s, … with s = `STEP_FRACTION` of the band
/// 2 `half_band`, until the bands reach `reach` either side (at most `most`
/// steps each side).
fn steps(half_band: f64, reach: f64, most: usize) -> Vec<f64> {
    let step = STEP_FRACTION * 2.0 * half_band;
    let mut out = vec![0.0];
    for k in 1..=most {
        let offset = k as f64 * step;
        if offset - step + half_band >= reach {
            break;
        }
        out.extend([offset, -offset]);
    }
    out
}

/// How far either side of the prior's mean, across the cable, `poses`
/// reach with their bands.
pub fn covered_half_width_mm(poses: &[SearchPose], pitch_mm: f64) -> f64 {
    let farthest = poses.iter().map(|p| p.across_mm.abs()).fold(0.0, f64::max);
    farthest + probe_half_width_mm(pitch_mm)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    const PITCH_MM: f64 = 3.55;

    fn prior(position_sigma_mm: f64, angle_sigma_rad: f64, max_moves: usize) -> Prior {
        Prior {
            base_from_cable: Isometry3::translation(450.0, 0.0, 250.0),
            position_sigma_mm,
            angle_sigma_rad,
            max_moves,
        }
    }

    fn across(poses: &[SearchPose]) -> Vec<f64> {
        poses.iter().map(|p| p.across_mm).collect()
    }

    #[test]
    fn the_band_is_the_pads_rows() {
        // 5 rows 3.55 mm apart: ±7.1 mm.
        assert_relative_eq!(probe_half_width_mm(PITCH_MM), 7.1, epsilon = 1e-12);
    }

    #[test]
    fn a_sure_prior_is_tried_once_at_its_mean() {
        let poses = search_poses(&prior(2.0, 0.05, 10), PITCH_MM);
        assert_eq!(
            poses,
            [SearchPose {
                across_mm: 0.0,
                angle_rad: 0.0
            }]
        );
    }

    #[test]
    fn the_mean_first_then_alternating_sides_covering_three_sigma_without_gaps() {
        let sigma_mm = 10.0;
        let poses = search_poses(&prior(sigma_mm, 0.1, 50), PITCH_MM);
        let offsets = across(&poses);
        let step = 0.75 * 2.0 * 7.1;
        assert_eq!(offsets[0], 0.0);
        for (k, pair) in offsets[1..].chunks(2).enumerate() {
            let expected = (k + 1) as f64 * step;
            assert_relative_eq!(pair[0], expected, epsilon = 1e-9);
            assert_relative_eq!(pair[1], -expected, epsilon = 1e-9);
        }
        assert!(poses.iter().all(|p| p.angle_rad == 0.0));
        // No gap: neighbouring probes' bands overlap.
        let mut sorted = offsets.clone();
        sorted.sort_by(f64::total_cmp);
        for pair in sorted.windows(2) {
            assert!(pair[1] - pair[0] < 2.0 * 7.1, "{sorted:?}");
        }
        // They cover ±3σ, and not a step more.
        let covered = covered_half_width_mm(&poses, PITCH_MM);
        assert!(covered >= 3.0 * sigma_mm, "{covered}");
        assert!(covered - step < 3.0 * sigma_mm, "{covered}");
        assert_eq!(poses.len(), 7);
    }

    #[test]
    fn the_limit_cuts_the_search_short_keeping_the_likeliest() {
        let poses = search_poses(&prior(30.0, 0.1, 4), PITCH_MM);
        assert_eq!(poses.len(), 4);
        let offsets = across(&poses);
        assert_eq!(offsets[0], 0.0);
        assert!(offsets[1] > 0.0 && offsets[2] < 0.0 && offsets[3] > offsets[1]);
        assert_eq!(search_poses(&prior(30.0, 0.1, 1), PITCH_MM).len(), 1);
        assert_eq!(search_poses(&prior(30.0, 0.1, 0), PITCH_MM).len(), 1);
    }

    #[test]
    fn an_uncertain_angle_adds_turned_probes_after_the_unturned_ones() {
        // 3σ = 0.9 rad, beyond the ±π/4 a probe reads along its columns.
        let poses = search_poses(&prior(5.0, 0.3, 20), PITCH_MM);
        let step_rad = 0.75 * 2.0 * FRAC_PI_4;
        let turned: Vec<_> = poses.iter().filter(|p| p.angle_rad != 0.0).collect();
        assert_eq!(poses.len(), 9, "3 offsets, each at 3 angles: {poses:?}");
        assert_eq!(turned.len(), 6);
        for pose in &turned {
            assert_relative_eq!(pose.angle_rad.abs(), step_rad, epsilon = 1e-12);
        }
        // The three unturned offsets come first, the mean leading.
        assert!(poses[..3].iter().all(|p| p.angle_rad == 0.0));
        assert_eq!(poses[0].across_mm, 0.0);
        // Then the mean turned either way.
        assert_eq!(poses[3].across_mm, 0.0);
        assert_eq!(poses[3].angle_rad, -poses[4].angle_rad);
        // An angle σ of 0 turns nothing.
        let sure = search_poses(&prior(5.0, 0.0, 20), PITCH_MM);
        assert!(sure.iter().all(|p| p.angle_rad == 0.0));
    }

    #[test]
    fn a_pose_is_the_prior_moved_across_and_turned_about_the_closing_axis() {
        let p = Prior {
            base_from_cable: Isometry3::from_parts(
                Translation3::new(450.0, 0.0, 250.0),
                UnitQuaternion::from_euler_angles(-FRAC_PI_2, 0.0, 0.0),
            ),
            ..prior(5.0, 0.1, 3)
        };
        let pose = SearchPose {
            across_mm: 10.0,
            angle_rad: 0.2,
        };
        let frame = pose.base_from_cable(&p);
        let moved = frame.translation.vector - p.base_from_cable.translation.vector;
        let y_axis = p.base_from_cable.rotation * Vector3::y();
        assert_relative_eq!(moved, y_axis * 10.0, epsilon = 1e-9);
        let z_axis = p.base_from_cable.rotation * Vector3::z();
        assert_relative_eq!(frame.rotation * Vector3::z(), z_axis, epsilon = 1e-9);
        let turn = p.base_from_cable.rotation.inverse() * frame.rotation;
        assert_relative_eq!(turn.angle(), 0.2, epsilon = 1e-9);
    }
}
