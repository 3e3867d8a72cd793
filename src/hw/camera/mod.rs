//! The 2D camera that watches the cable: one image per capture, 8-bit BGR,
//! of the size its intrinsics give.

mod opencv_camera;
mod sim;

pub use opencv_camera::OpencvCamera;
pub use sim::SimCamera;

use opencv::core::Mat;

use super::DeviceError;

pub trait Camera: Send {
    /// The camera's next image (CV_8UC3, BGR).
    fn capture(&mut self) -> Result<Mat, DeviceError>;
}
