//! Finding the cable: grasp frames in the base frame, one per cable seen.
//! The vision detector looks through the cell's camera; the oracle, for
//! campaigns that need controlled start offsets, reads the simulated
//! world instead.

pub mod config;
mod oracle;
mod vision;

pub use oracle::OracleDetector;
pub use vision::VisionDetector;

use nalgebra::Isometry3;

use crate::hw::DeviceError;
use crate::hw::camera::{Camera, CameraImage};
use crate::perception::shape::ShapePoint;
use crate::perception::vision::VisionSkip;

/// A cable found in the scene.
#[derive(Debug, Clone, PartialEq)]
pub struct CableDetection {
    /// Grasp frame at the cable's midpoint (s = 0.5): x along the cable,
    /// y across it in the image plane, towards the side the hand comes
    /// from, z towards the camera. It is the sensor frame that puts the
    /// cable on the pad's x-axis.
    pub base_from_cable: Isometry3<f64>,
    /// The cable's centre line in the base frame, from end to end of what
    /// was seen of it (nothing of a stretch hidden from the camera), each
    /// point with its σ: the vision shape a fusion starts from.
    pub centre_line: Vec<ShapePoint>,
    /// How much the detection looks like a cable, 0 to 1 (the vision
    /// pipeline's; 1 for the oracle, which knows).
    pub confidence: f64,
}

/// What a detector found, and the image it looked at, if it looked.
#[derive(Debug, Clone, PartialEq)]
pub struct Detections {
    /// Every cable in view, best first (the most confident).
    pub cables: Vec<CableDetection>,
    pub image: Option<CameraImage>,
    /// What the vision pipeline left out because the scene did not need
    /// it (none for the oracle, which does not look).
    pub skipped: Vec<VisionSkip>,
}

pub trait CableDetector: Send {
    /// Every cable in view, best first, looking through `camera` if the
    /// detector needs to.
    fn detect(&mut self, camera: &mut dyn Camera) -> Result<Detections, DeviceError>;
}
