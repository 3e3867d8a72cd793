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
use crate::perception::shape::{SHAPE_SPACING_MM, ShapePoint};
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
    /// The true grasp frame, disturbed; the camera is not needed. The
    /// centre line is the true one, moved with the grasp frame, each point
    /// with the σ the noise gives it (the position's, and the angle's at
    /// its distance from the grasp point).
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
        let world = lock(&self.world);
        let base_from_cable = world.base_from_cable * cable_from_detected;
        let centre_line = world
            .cable
            .centre_line_mm(SHAPE_SPACING_MM)
            .into_iter()
            .map(|p| ShapePoint {
                in_base_mm: base_from_cable * p,
                sigma_mm: config.position_noise_mm.hypot(p.x * config.angle_noise_rad),
            })
            .collect();
        Ok(Detections {
            cables: vec![CableDetection {
                base_from_cable,
                centre_line,
                confidence: 1.0,
            }],
            image: None,
            skipped: Vec::new(),
        })
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::{Point3, Vector3};
    use opencv::core::Mat;

    use super::*;
    use crate::sim::cable::tests::config;
    use crate::sim::world::SimWorld;
    use crate::sim::{Stream, rng};

    /// The oracle does not look.
    struct Blind;

    impl Camera for Blind {
        fn capture(&mut self) -> Result<Mat, DeviceError> {
            Ok(Mat::default())
        }
    }

    #[test]
    fn the_centre_line_is_the_true_one_moved_with_the_grasp_frame() {
        let world = SimWorld::new(&config(), Isometry3::identity());
        let truth = world.base_from_cable;
        let cable = world.cable;
        let oracle_config = OracleConfig {
            position_noise_mm: 0.5,
            angle_noise_rad: 0.01,
            offset_across_mm: 0.0,
            offset_angle_rad: 0.0,
        };
        let mut oracle =
            OracleDetector::new(world.shared(), oracle_config, rng(1, Stream::Detector));
        let detections = oracle.detect(&mut Blind).unwrap();
        let detection = &detections.cables[0];
        // A point every millimetre from one support to the other.
        assert_eq!(detection.centre_line.len(), 151);
        let detected_from_true = detection.base_from_cable.inverse() * truth;
        for point in &detection.centre_line {
            // In the detected frame, where the truth is in its own.
            let in_detected = detection.base_from_cable.inverse() * point.in_base_mm;
            let (height_mm, _) = cable.height_and_slope(in_detected.x);
            assert!((in_detected.y - height_mm).abs() < 1e-9, "{in_detected}");
            assert!(in_detected.z.abs() < 1e-9);
            // σ: the position's, and the angle's at the distance.
            let expected = 0.5f64.hypot(0.01 * in_detected.x);
            assert!((point.sigma_mm - expected).abs() < 1e-12);
        }
        // The noise moved it: the detected frame is not the true one.
        let moved = detected_from_true * Point3::origin();
        assert!((moved.coords - Vector3::zeros()).norm() > 1e-3, "{moved}");
    }
}
