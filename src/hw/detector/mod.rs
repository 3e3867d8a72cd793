//! Finding the cable: grasp frames in the base frame, one per cable seen.
//! The vision pipeline (camera + network) implements this trait; until
//! then the simulated cell uses an oracle.

mod oracle;

pub use oracle::OracleDetector;

use nalgebra::Isometry3;

use super::DeviceError;

/// A cable found in the scene.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CableDetection {
    /// Grasp frame at the cable's midpoint (s = 0.5): x along the cable,
    /// y across it in the image plane, towards the side the hand comes
    /// from, z towards the camera. It is the sensor frame that puts the
    /// cable on the pad's x-axis.
    pub base_from_cable: Isometry3<f64>,
}

pub trait CableDetector: Send {
    /// Every cable in view, best first.
    fn detect(&mut self) -> Result<Vec<CableDetection>, DeviceError>;
}
