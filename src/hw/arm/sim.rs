//! A simulated arm: reaches commanded poses within its repeatability and
//! takes the time a jerk-limited Cartesian profile would (Ruckig, with the
//! Panda's Cartesian limits), added to the simulated clock.

use nalgebra::{Isometry3, Translation3, Vector3};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

use super::Arm;
use crate::hw::{DeviceError, DeviceKind};
use crate::sim::motion::{CartesianLimits, move_duration_s};
use crate::sim::world::{SharedWorld, lock};

pub struct SimArm {
    world: SharedWorld,
    limits: CartesianLimits,
    repeatability_mm: f64,
    rng: ChaCha8Rng,
}

impl SimArm {
    pub fn new(
        world: SharedWorld,
        limits: CartesianLimits,
        repeatability_mm: f64,
        rng: ChaCha8Rng,
    ) -> Self {
        Self {
            world,
            limits,
            repeatability_mm,
            rng,
        }
    }

    fn refuse(&self, reason: String) -> DeviceError {
        DeviceError::Refused {
            device: DeviceKind::Arm,
            command: "move_linear",
            reason,
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
        // Drawn on every move, so that switching repeatability off leaves
        // every other draw of the stream where it was.
        let error = Vector3::from_fn(|_, _| self.rng.sample::<f64, _>(StandardNormal))
            * self.repeatability_mm;
        let mut world = lock(&self.world);
        let from = world.base_from_tcp;
        let distance_mm = (base_from_tcp.translation.vector - from.translation.vector).norm();
        let angle_rad = from.rotation.angle_to(&base_from_tcp.rotation);
        let Some(duration_s) = move_duration_s(distance_mm, angle_rad, speed_mm_s, &self.limits)
        else {
            return Err(self.refuse(format!(
                "no jerk-limited profile for {distance_mm} mm and {angle_rad} rad"
            )));
        };
        world.now_s += duration_s;
        world.base_from_tcp = Translation3::from(error) * base_from_tcp;
        Ok(())
    }

    fn stop(&mut self) -> Result<(), DeviceError> {
        Ok(())
    }
}
