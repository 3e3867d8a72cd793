//! Frames and transforms of the cell.
//!
//! Transforms are named by their frames, `base_from_tcp` maps points given
//! in the TCP frame into the base frame (it is the TCP's pose in the base).
//! Lengths are in millimetres throughout, angles in radians.
//!
//! The sensor frame is the paper's (Section III): origin at the centre of
//! taxel c33, x towards c35, y towards c13, z the pad's outward normal. A
//! cable pressed on the pad is a line in its x–y plane.

use std::f64::consts::{FRAC_PI_2, PI};

use nalgebra::{Isometry2, Isometry3, Translation3, UnitQuaternion, Vector2, Vector3};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// A straight cable on the pad, as angle and signed offset.
///
/// The paper fits `y = m x + n`; a slope blows up for a cable lying along y,
/// so cablecell keeps the line as its direction angle `alpha_rad` in
/// (-π/2, π/2] (the paper's `atan m`) and its signed perpendicular distance
/// `n_mm` from the sensor's origin along the normal (-sin α, cos α):
/// cablecell's n, which for a cable near the x-axis is the paper's `n`
/// (exactly `n cos α`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct LineInSensor {
    pub alpha_rad: f64,
    /// Recordings of cablecell 0.1 wrote it `offset_mm`.
    #[serde(alias = "offset_mm")]
    pub n_mm: f64,
}

impl LineInSensor {
    /// The line of direction angle `alpha_rad` (any value, taken modulo π)
    /// at signed distance `n_mm` along the normal (-sin α, cos α).
    pub fn new(alpha_rad: f64, n_mm: f64) -> Self {
        // Subtract k half-turns to land in (-π/2, π/2]; an odd k reverses
        // the direction, and with it the normal and the offset's sign.
        let mut k = ((alpha_rad - FRAC_PI_2) / PI).ceil();
        let mut alpha = alpha_rad - k * PI;
        // The quotient rounds: an angle within an ulp or so of a half-turn
        // boundary can land one step outside, which one more step mends.
        if alpha > FRAC_PI_2 {
            alpha -= PI;
            k += 1.0;
        } else if alpha <= -FRAC_PI_2 {
            alpha += PI;
            k -= 1.0;
        }
        let n_mm = if k.rem_euclid(2.0) == 1.0 {
            -n_mm
        } else {
            n_mm
        };
        Self {
            alpha_rad: alpha,
            n_mm,
        }
    }

    /// The line through `point_mm` along `direction` (need not be unit,
    /// must not be zero).
    pub fn through(point_mm: Vector2<f64>, direction: Vector2<f64>) -> Self {
        // Turned to point into x > 0 (or along +y), the direction's angle
        // already lies in (-π/2, π/2] and its normal is the direction
        // rotated by a quarter turn: one atan2 and one square root, no
        // sine or cosine (this is on every tactile frame's path).
        let flip = direction.x < 0.0 || (direction.x == 0.0 && direction.y < 0.0);
        let d = if flip { -direction } else { direction };
        let length = d.norm();
        if !(length > 0.0 && length.is_finite()) {
            // No direction (or an infinite one): the angle atan2 gives it.
            let alpha = direction.y.atan2(direction.x);
            let normal = Vector2::new(-alpha.sin(), alpha.cos());
            return Self::new(alpha, normal.dot(&point_mm));
        }
        let normal = Vector2::new(-d.y, d.x) / length;
        // `new` still wraps an angle that rounded to -π/2 exactly.
        Self::new(d.y.atan2(d.x), normal.dot(&point_mm))
    }

    /// The paper's slope and intercept `(m, n)` of `y = m x + n`; `None`
    /// for a line too close to the y-axis to have them.
    pub fn slope_intercept(&self) -> Option<(f64, f64)> {
        let (sin, cos) = self.alpha_rad.sin_cos();
        (cos.abs() > 1e-9).then(|| (sin / cos, self.n_mm / cos))
    }

    /// Unit normal (-sin α, cos α) along which `offset_mm` is measured.
    pub fn normal(&self) -> Vector2<f64> {
        Vector2::new(-self.alpha_rad.sin(), self.alpha_rad.cos())
    }

    /// Signed distance of a point from the line, along the normal.
    pub fn distance_mm(&self, point_mm: Vector2<f64>) -> f64 {
        self.normal().dot(&point_mm) - self.n_mm
    }

    /// A frame on the line: origin at the foot of the perpendicular from the
    /// sensor's origin, x along the line.
    pub fn sensor_from_line(&self) -> Isometry2<f64> {
        let foot = self.normal() * self.n_mm;
        Isometry2::new(foot, self.alpha_rad)
    }

    /// How far this line is from `target`: angle difference wrapped into
    /// (-π/2, π/2], and offset difference measured along the target's
    /// normal (near ±π/2 the two normals can point opposite ways).
    pub fn error_to(&self, target: &LineInSensor) -> PoseError {
        let seen_from_target = LineInSensor::new(self.alpha_rad - target.alpha_rad, self.n_mm);
        let same_normal = seen_from_target.n_mm == self.n_mm;
        let offset_mm = if same_normal { self.n_mm } else { -self.n_mm };
        PoseError {
            n_mm: offset_mm - target.n_mm,
            alpha_rad: seen_from_target.alpha_rad,
        }
    }

    /// The line seen from another frame of the pad's plane:
    /// `other_from_sensor` maps sensor coordinates into that frame.
    pub fn transformed(&self, other_from_sensor: &Isometry2<f64>) -> LineInSensor {
        let frame = other_from_sensor * self.sensor_from_line();
        LineInSensor::through(frame.translation.vector, frame.rotation * Vector2::x())
    }
}

/// Signed error of a cable pose on the pad against the target pose.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct PoseError {
    pub n_mm: f64,
    pub alpha_rad: f64,
}

impl PoseError {
    /// Whether both components are within the tolerance (inclusive).
    pub fn within(&self, tolerance: &PoseError) -> bool {
        self.n_mm.abs() <= tolerance.n_mm && self.alpha_rad.abs() <= tolerance.alpha_rad
    }
}

/// A rigid transform as JSON outputs and recordings write it: the
/// translation in millimetres and the rotation as a unit quaternion in the
/// order x, y, z, w (nalgebra's own serialization names neither).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct PoseMm {
    pub translation_mm: [f64; 3],
    pub rotation_xyzw: [f64; 4],
}

impl From<&Isometry3<f64>> for PoseMm {
    fn from(pose: &Isometry3<f64>) -> Self {
        let t = pose.translation.vector;
        let q = pose.rotation.coords;
        Self {
            translation_mm: [t.x, t.y, t.z],
            rotation_xyzw: [q.x, q.y, q.z, q.w],
        }
    }
}

impl From<PoseMm> for Isometry3<f64> {
    fn from(pose: PoseMm) -> Self {
        let [x, y, z] = pose.translation_mm;
        let [qx, qy, qz, qw] = pose.rotation_xyzw;
        Isometry3::from_parts(
            Translation3::new(x, y, z),
            UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(qw, qx, qy, qz)),
        )
    }
}

/// `#[serde(with = "pose_mm")]`: an `Isometry3` field written as [`PoseMm`].
pub mod pose_mm {
    use nalgebra::Isometry3;
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    use super::PoseMm;

    pub fn serialize<S: Serializer>(pose: &Isometry3<f64>, s: S) -> Result<S::Ok, S::Error> {
        PoseMm::from(pose).serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Isometry3<f64>, D::Error> {
        PoseMm::deserialize(d).map(Isometry3::from)
    }
}

/// A planar isometry of the pad's x–y plane as a rigid transform about z.
pub fn planar_to_spatial(planar: &Isometry2<f64>) -> Isometry3<f64> {
    let t = planar.translation.vector;
    Isometry3::from_parts(
        Translation3::new(t.x, t.y, 0.0),
        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), planar.rotation.angle()),
    )
}

/// The paper's correction T_corr (eq. 7), generalised to a target pose.
///
/// Returns `old_sensor_from_new_sensor`: the pose, in the trial grasp's
/// sensor frame, that the sensor must take so that the cable measured at
/// `measured` lies at `target` in the new frame. With a zero target it is
/// eq. 7 exactly, but for the translation: eq. 7 moves to the intercept
/// (0, n); this moves to the foot of the perpendicular, which differs by a
/// slide along the cable and stays finite for a cable along y.
pub fn t_corr(measured: &LineInSensor, target: &LineInSensor) -> Isometry3<f64> {
    t_corr_with_gain(measured, target, &CorrectionGain::PAPER)
}

/// How much of T_corr a regrasp applies: the paper applies all of it. A
/// cable that springs back towards where it was caught undoes part of each
/// correction, and a gain above 1 makes up for it. Files write it as
/// `task::task_file` reads it, with its range.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CorrectionGain {
    /// Scales the correction's translation.
    pub n: f64,
    /// Scales the correction's rotation.
    pub alpha: f64,
}

impl CorrectionGain {
    pub const PAPER: CorrectionGain = CorrectionGain { n: 1.0, alpha: 1.0 };
}

/// T_corr with its translation and rotation scaled by `gain`.
pub fn t_corr_with_gain(
    measured: &LineInSensor,
    target: &LineInSensor,
    gain: &CorrectionGain,
) -> Isometry3<f64> {
    let old_from_new = measured.sensor_from_line() * target.sensor_from_line().inverse();
    let scaled = Isometry2::new(
        old_from_new.translation.vector * gain.n,
        old_from_new.rotation.angle() * gain.alpha,
    );
    planar_to_spatial(&scaled)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn new_normalises_angle_and_flips_offset() {
        let line = LineInSensor::new(PI - 0.1, 2.0);
        assert_relative_eq!(line.alpha_rad, -0.1, epsilon = 1e-12);
        assert_relative_eq!(line.n_mm, -2.0, epsilon = 1e-12);
        let vertical = LineInSensor::new(-FRAC_PI_2, 1.0);
        assert_relative_eq!(vertical.alpha_rad, FRAC_PI_2, epsilon = 1e-12);
        assert_relative_eq!(vertical.n_mm, -1.0, epsilon = 1e-12);
    }

    #[test]
    fn new_lands_in_the_half_turn_for_angles_an_ulp_from_its_ends() {
        // -π/2 plus one ulp once came back as π/2 plus one ulp.
        for m in -400..=400 {
            let mut alpha_rad = f64::from(m) * FRAC_PI_2;
            for _ in 0..4 {
                alpha_rad = alpha_rad.next_down();
            }
            for _ in 0..8 {
                let line = LineInSensor::new(alpha_rad, 1.0);
                assert!(
                    line.alpha_rad > -FRAC_PI_2 && line.alpha_rad <= FRAC_PI_2,
                    "{alpha_rad:e} -> {line:?}"
                );
                let turned_by_rad = alpha_rad - line.alpha_rad;
                let half_turns = (turned_by_rad / PI).round();
                assert!(
                    (turned_by_rad - half_turns * PI).abs() < 1e-12,
                    "{alpha_rad:e}"
                );
                let flipped = half_turns.rem_euclid(2.0) == 1.0;
                assert_eq!(line.n_mm, if flipped { -1.0 } else { 1.0 }, "{alpha_rad:e}");
                alpha_rad = alpha_rad.next_up();
            }
        }
    }

    #[test]
    fn slope_intercept_matches_paper_form_and_refuses_vertical() {
        let m: f64 = 0.3;
        let n = 1.5;
        let line = LineInSensor::through(Vector2::new(0.0, n), Vector2::new(1.0, m));
        let (m_fit, n_fit) = line.slope_intercept().unwrap();
        assert_relative_eq!(m_fit, m, epsilon = 1e-12);
        assert_relative_eq!(n_fit, n, epsilon = 1e-12);
        assert_relative_eq!(line.n_mm, n * m.atan().cos(), epsilon = 1e-12);
        let vertical = LineInSensor::through(Vector2::new(2.0, 0.0), Vector2::new(0.0, 1.0));
        assert!(vertical.slope_intercept().is_none());
        assert_relative_eq!(vertical.n_mm, -2.0, epsilon = 1e-12);
    }

    #[test]
    fn t_corr_with_zero_target_is_eq_7() {
        let alpha = 0.2_f64;
        let n = 3.0;
        let measured =
            LineInSensor::through(Vector2::new(0.0, n), Vector2::new(alpha.cos(), alpha.sin()));
        let t = t_corr(&measured, &LineInSensor::new(0.0, 0.0));
        let (_, _, yaw) = t.rotation.euler_angles();
        assert_relative_eq!(yaw, alpha, epsilon = 1e-12);
        // Eq. 7 translates by (0, n); ours lands on the same line, at the foot.
        let p = t.translation.vector;
        assert_relative_eq!(
            measured.distance_mm(Vector2::new(p.x, p.y)),
            0.0,
            epsilon = 1e-12
        );
        assert_relative_eq!(p.z, 0.0);
    }

    #[test]
    fn t_corr_moves_the_cable_onto_the_target() {
        let measured = LineInSensor::new(1.4, -2.5);
        let target = LineInSensor::new(0.1, 0.7);
        let old_from_new = t_corr(&measured, &target);
        // Express the measured line in the new frame.
        let (_, _, yaw) = old_from_new.rotation.euler_angles();
        let t = old_from_new.translation.vector;
        let new_from_old = Isometry2::new(Vector2::new(t.x, t.y), yaw).inverse();
        let seen = measured.transformed(&new_from_old);
        let err = seen.error_to(&target);
        assert_relative_eq!(err.n_mm, 0.0, epsilon = 1e-9);
        assert_relative_eq!(err.alpha_rad, 0.0, epsilon = 1e-9);
    }

    #[test]
    fn a_gain_scales_the_correction_and_one_is_the_paper() {
        let measured = LineInSensor::new(0.1, 2.0);
        let target = LineInSensor::new(0.0, 0.0);
        let plain = t_corr(&measured, &target);
        let gained = t_corr_with_gain(&measured, &target, &CorrectionGain { n: 1.5, alpha: 0.5 });
        assert_relative_eq!(
            gained.translation.vector,
            plain.translation.vector * 1.5,
            epsilon = 1e-12
        );
        assert_relative_eq!(
            gained.rotation.angle(),
            plain.rotation.angle() * 0.5,
            epsilon = 1e-12
        );
    }

    #[test]
    fn error_wraps_angle_and_aligns_normals_across_vertical() {
        // Two nearly identical lines along y, on either side of ±π/2.
        let a = LineInSensor::new(FRAC_PI_2 - 0.01, 2.0);
        let b = LineInSensor::new(-FRAC_PI_2 + 0.01, -2.0);
        let err = a.error_to(&b);
        assert_relative_eq!(err.alpha_rad, -0.02, epsilon = 1e-9);
        assert_relative_eq!(err.n_mm, 0.0, epsilon = 1e-9);
        let shifted = LineInSensor::new(-FRAC_PI_2 + 0.01, -2.5);
        assert_relative_eq!(a.error_to(&shifted).n_mm, 0.5, epsilon = 1e-9);
    }
}
