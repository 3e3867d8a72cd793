//! The 2D camera that watches the cable: one image per capture, 8-bit BGR,
//! of the size its intrinsics give.

pub mod config;
mod image_file;
mod jpeg;
mod opencv_camera;
mod sim;

pub use image_file::{ImageError, read_image};
pub use opencv_camera::OpencvCamera;
pub use sim::SimCamera;

use std::sync::Arc;

use opencv::core::Mat;

use super::DeviceError;

/// An image the camera took, shared rather than copied as the event that
/// carries it travels to the machine and the recorder. Two are equal when
/// they are the same capture.
#[derive(Clone, Debug)]
pub struct CameraImage(pub Arc<Mat>);

impl PartialEq for CameraImage {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }
}

pub trait Camera: Send {
    /// The camera's next image (CV_8UC3, BGR).
    fn capture(&mut self) -> Result<Mat, DeviceError>;
}
