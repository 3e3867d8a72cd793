//! A simulated arm: reaches commanded poses within its repeatability and
//! takes the time a trapezoidal speed profile would.

use nalgebra::{Isometry3, Translation3, Vector3};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

use super::Arm;
use crate::hw::{DeviceError, DeviceKind};
use crate::sim::world::{SharedWorld, lock};

/// Angular speed limit of the simulated wrist.
const MAX_ANGULAR_SPEED_RAD_S: f64 = 1.0;

pub struct SimArm {
    world: SharedWorld,
    max_speed_mm_s: f64,
    accel_mm_s2: f64,
    repeatability_mm: f64,
    rng: ChaCha8Rng,
}

impl SimArm {
    pub fn new(
        world: SharedWorld,
        max_speed_mm_s: f64,
        accel_mm_s2: f64,
        repeatability_mm: f64,
        rng: ChaCha8Rng,
    ) -> Self {
        Self {
            world,
            max_speed_mm_s,
            accel_mm_s2,
            repeatability_mm,
            rng,
        }
    }
}

impl Arm for SimArm {
    fn base_from_tcp(&mut self) -> Result<Isometry3<f64>, DeviceError> {
        Ok(lock(&self.world).base_from_tcp)
    }

    fn move_linear(
        &mut self,
        base_from_tcp: &Isometry3<f64>,
        speed_mm_s: f64,
    ) -> Result<(), DeviceError> {
        if !(speed_mm_s > 0.0 && speed_mm_s <= self.max_speed_mm_s) {
            return Err(DeviceError::Refused {
                device: DeviceKind::Arm,
                command: "move_linear",
                reason: format!(
                    "speed {speed_mm_s} mm/s is outside (0, {}] mm/s",
                    self.max_speed_mm_s
                ),
            });
        }
        let error = Vector3::from_fn(|_, _| self.rng.sample::<f64, _>(StandardNormal))
            * self.repeatability_mm;
        let mut world = lock(&self.world);
        let from = world.base_from_tcp;
        let distance_mm = (base_from_tcp.translation.vector - from.translation.vector).norm();
        let angle_rad = from.rotation.angle_to(&base_from_tcp.rotation);
        let duration_s = trapezoid_s(distance_mm, speed_mm_s, self.accel_mm_s2)
            .max(angle_rad / MAX_ANGULAR_SPEED_RAD_S);
        world.now_s += duration_s;
        world.base_from_tcp = Translation3::from(error) * base_from_tcp;
        Ok(())
    }

    fn stop(&mut self) -> Result<(), DeviceError> {
        Ok(())
    }
}

/// Time to travel `distance` from rest to rest with a trapezoidal profile.
fn trapezoid_s(distance_mm: f64, speed_mm_s: f64, accel_mm_s2: f64) -> f64 {
    let ramp_mm = speed_mm_s * speed_mm_s / accel_mm_s2;
    if distance_mm >= ramp_mm {
        distance_mm / speed_mm_s + speed_mm_s / accel_mm_s2
    } else {
        2.0 * (distance_mm / accel_mm_s2).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn trapezoid_is_continuous_at_the_triangle_limit() {
        // v = 100, a = 1000: ramps cover 10 mm.
        assert_relative_eq!(trapezoid_s(10.0, 100.0, 1000.0), 0.2, epsilon = 1e-12);
        assert_relative_eq!(trapezoid_s(10.0 - 1e-9, 100.0, 1000.0), 0.2, epsilon = 1e-6);
        assert_relative_eq!(trapezoid_s(110.0, 100.0, 1000.0), 1.2, epsilon = 1e-12);
        assert_eq!(trapezoid_s(0.0, 100.0, 1000.0), 0.0);
    }
}
