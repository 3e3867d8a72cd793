//! The simulated camera: the simulated world drawn by the renderer from the
//! camera's true pose, the finger's marker included.

use nalgebra::Isometry3;
use opencv::core::Mat;
use rand_chacha::ChaCha8Rng;

use super::Camera;
use crate::hw::{DeviceError, DeviceKind};
use crate::perception::vision::calibration::{CameraModel, MarkerOnFinger};
use crate::sim::render::{Appearance, render_world};
use crate::sim::world::{SharedWorld, lock};

pub struct SimCamera {
    world: SharedWorld,
    intrinsics: CameraModel,
    /// Where the camera really is (calibration estimates it).
    base_from_camera: Isometry3<f64>,
    marker: MarkerOnFinger,
    appearance: Appearance,
    rng: ChaCha8Rng,
}

impl SimCamera {
    pub fn new(
        world: SharedWorld,
        intrinsics: CameraModel,
        base_from_camera: Isometry3<f64>,
        marker: MarkerOnFinger,
        appearance: Appearance,
        rng: ChaCha8Rng,
    ) -> Self {
        Self {
            world,
            intrinsics,
            base_from_camera,
            marker,
            appearance,
            rng,
        }
    }
}

impl Camera for SimCamera {
    fn capture(&mut self) -> Result<Mat, DeviceError> {
        let world = lock(&self.world).clone();
        render_world(
            &world,
            &self.intrinsics,
            &self.base_from_camera,
            Some(&self.marker),
            &self.appearance,
            &mut self.rng,
        )
        .map(|scene| scene.bgr)
        .map_err(|error| DeviceError::Unusable {
            device: DeviceKind::Camera,
            reason: format!("cannot render the simulated scene: {error}"),
        })
    }
}
