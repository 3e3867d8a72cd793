//! A straight-line Cartesian move as a jerk-limited, time-optimal profile
//! (Ruckig) of two synchronised degrees of freedom, the distance along the
//! path and the angle of the rotation, from rest to rest: how long the
//! simulated arm takes, and the poses the Panda driver streams.

use rsruckig::prelude::{InputParameter, Ruckig, ThrowErrorHandler, Trajectory};

/// Limits of the TCP's Cartesian motion, one set for translation and one
/// for rotation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CartesianLimits {
    pub accel_mm_s2: f64,
    pub jerk_mm_s3: f64,
    pub angular_speed_rad_s: f64,
    pub angular_accel_rad_s2: f64,
    pub angular_jerk_rad_s3: f64,
}

/// The jerk-limited profile of a move of `distance_mm` along a straight
/// line while turning by `angle_rad`, translating at no more than
/// `speed_mm_s`; both start and end together, at rest. Its first degree of
/// freedom is the distance travelled (mm), its second the angle turned
/// (rad). `None` if Ruckig finds no profile (limits not positive and
/// finite).
pub fn straight_line_profile(
    distance_mm: f64,
    angle_rad: f64,
    speed_mm_s: f64,
    limits: &CartesianLimits,
) -> Option<Trajectory<2>> {
    let mut input = InputParameter::<2>::new(None);
    input.target_position[0] = distance_mm;
    input.target_position[1] = angle_rad;
    input.max_velocity[0] = speed_mm_s;
    input.max_velocity[1] = limits.angular_speed_rad_s;
    input.max_acceleration[0] = limits.accel_mm_s2;
    input.max_acceleration[1] = limits.angular_accel_rad_s2;
    input.max_jerk[0] = limits.jerk_mm_s3;
    input.max_jerk[1] = limits.angular_jerk_rad_s3;
    let mut trajectory = Trajectory::<2>::new(None);
    // The control period only matters for Ruckig's own stepping, which is
    // not used: callers sample the trajectory at the times they need.
    Ruckig::<2, ThrowErrorHandler>::new(None, 0.001)
        .calculate(&input, &mut trajectory)
        .ok()
        .map(|_| trajectory)
}

/// The duration of the move of [`straight_line_profile`].
pub fn move_duration_s(
    distance_mm: f64,
    angle_rad: f64,
    speed_mm_s: f64,
    limits: &CartesianLimits,
) -> Option<f64> {
    straight_line_profile(distance_mm, angle_rad, speed_mm_s, limits).map(|t| t.get_duration())
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    /// A Panda's Cartesian limits.
    const PANDA: CartesianLimits = CartesianLimits {
        accel_mm_s2: 13_000.0,
        jerk_mm_s3: 6_500_000.0,
        angular_speed_rad_s: 2.5,
        angular_accel_rad_s2: 25.0,
        angular_jerk_rad_s3: 12_500.0,
    };

    #[test]
    fn a_long_move_cruises_at_the_speed_cap() {
        // v = 100 mm/s, a = 13 000 mm/s², j = 6.5e6 mm/s³: the speed is
        // reached without touching the acceleration limit (v/a_max > ...;
        // a_peak = √(v j) = 25 495 > a, so the ramp is a = 13 000 with jerk
        // phases of a/j = 2 ms). A rest-to-rest move with a trapezoidal
        // acceleration takes d/v + v/a + a/j.
        let duration = move_duration_s(200.0, 0.0, 100.0, &PANDA).expect("profile");
        let expected = 200.0 / 100.0 + 100.0 / 13_000.0 + 13_000.0 / 6_500_000.0;
        assert_relative_eq!(duration, expected, epsilon = 1e-6);
    }

    #[test]
    fn a_short_move_never_reaches_the_speed_cap() {
        // Too short to reach the speed or the acceleration limit: a pure
        // jerk profile, four phases of T = (d / 2j)^(1/3), 4T in all.
        let distance_mm = 0.01;
        let duration = move_duration_s(distance_mm, 0.0, 100.0, &PANDA).expect("profile");
        let phase_s = (distance_mm / (2.0 * PANDA.jerk_mm_s3)).cbrt();
        assert_relative_eq!(duration, 4.0 * phase_s, epsilon = 1e-9);
        // Its peak speed j T² stays below the cap.
        assert!(PANDA.jerk_mm_s3 * phase_s * phase_s < 100.0);
    }

    #[test]
    fn a_large_turn_sets_the_pace_of_a_short_move() {
        let turn = move_duration_s(1.0, 1.0, 100.0, &PANDA).expect("profile");
        // 1 rad at 2.5 rad/s, 25 rad/s²: at least 1/2.5 + 2.5/25 s.
        assert!(turn >= 0.5, "{turn}");
        let straight = move_duration_s(1.0, 0.0, 100.0, &PANDA).expect("profile");
        assert!(straight < 0.05, "{straight}");
    }

    #[test]
    fn no_move_takes_no_time() {
        assert_eq!(move_duration_s(0.0, 0.0, 100.0, &PANDA), Some(0.0));
    }
}
