//! The oracle detector: the simulated cable's true grasp frame, disturbed
//! in the image plane as a vision pipeline would be. It stands in for the
//! vision pipeline until that exists, and is named for what it is.

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

use super::{CableDetection, CableDetector, Detections};
use crate::detector::config::OracleConfig;
use crate::hw::DeviceError;
use crate::hw::camera::Camera;
use crate::sim::world::{SharedWorld, lock};

pub struct OracleDetector {
    world: SharedWorld,
    config: OracleConfig,
    rng: ChaCha8Rng,
}

impl OracleDetector {
    pub fn new(world: SharedWorld, config: OracleConfig, rng: ChaCha8Rng) -> Self {
        Self { world, config, rng }
    }
}

impl CableDetector for OracleDetector {
    /// The true grasp frame, disturbed; the camera is not needed.
    fn detect(&mut self, _camera: &mut dyn Camera) -> Result<Detections, DeviceError> {
        let config = &self.config;
        let across_mm = config.offset_across_mm
            + config.position_noise_mm * self.rng.sample::<f64, _>(StandardNormal);
        let turn_rad = config.offset_angle_rad
            + config.angle_noise_rad * self.rng.sample::<f64, _>(StandardNormal);
        let cable_from_detected = Isometry3::from_parts(
            Translation3::new(0.0, across_mm, 0.0),
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), turn_rad),
        );
        let base_from_cable = lock(&self.world).base_from_cable * cable_from_detected;
        Ok(Detections {
            cables: vec![CableDetection { base_from_cable }],
            image: None,
        })
    }
}
