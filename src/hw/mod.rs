//! The cell's devices: one trait per kind, each with its simulated
//! implementation beside it (`arm/sim.rs`, ...). Real drivers go beside
//! them and implement the same traits.

pub mod arm;
pub mod camera;
pub mod clock;
pub mod emulator;
pub mod gripper;
pub mod tactile;

use std::sync::Arc;

use schemars::JsonSchema;
use serde::Serialize;

use crate::perception::vision::VisionError;
use camera::ImageError;

/// Which device of the cell, as named in errors and records.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum DeviceKind {
    Arm,
    Gripper,
    Tactile,
    Camera,
    Detector,
}

impl std::fmt::Display for DeviceKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            DeviceKind::Arm => "arm",
            DeviceKind::Gripper => "gripper",
            DeviceKind::Tactile => "tactile sensor",
            DeviceKind::Camera => "camera",
            DeviceKind::Detector => "detector",
        })
    }
}

/// A device failed to do what it was asked.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum DeviceError {
    /// The device did not answer in time (a simulated device, or the
    /// tactile polling thread whose sensor is stuck): check its cable,
    /// power and port.
    #[error("{device}: no answer within {waited_ms} ms")]
    Timeout { device: DeviceKind, waited_ms: u64 },
    /// The device on a serial port did not answer in time: check its
    /// cable, power and baud rate, and that the port is this device's.
    #[error("{device} on {port}: no answer to {command} within {waited_ms} ms")]
    NoAnswer {
        device: DeviceKind,
        port: String,
        command: &'static str,
        waited_ms: u64,
    },
    /// The device refused the command; `reason` is its own explanation.
    #[error("{device}: refused {command}: {reason}")]
    Refused {
        device: DeviceKind,
        command: &'static str,
        reason: String,
    },
    /// The link to the device failed (unplugged, powered off, port
    /// closed): check the cable and that the port still exists.
    #[error("{device} on {port}: link lost: {reason}")]
    Disconnected {
        device: DeviceKind,
        port: String,
        reason: String,
    },
    /// The device's answer cannot be what it sent (noise on the line, a
    /// wrong baud rate): the request may be repeated.
    #[error("{device} on {port}: garbled answer: {detail}")]
    Garbled {
        device: DeviceKind,
        port: String,
        detail: String,
    },
    /// The device cannot do its job as set up: a missing model file or
    /// ONNX Runtime library, a camera source that cannot be opened, an
    /// uncalibrated camera. Fix the cell file or the installation.
    #[error("{device}: {reason}")]
    Unusable { device: DeviceKind, reason: String },
    /// The vision pipeline failed on the camera's image; `source` says
    /// how (the segmentation network's model file or ONNX Runtime library,
    /// its inference, an OpenCV failure, an image the pipeline cannot
    /// take), and its variant's documentation how to fix it.
    #[error("{device}: {source}")]
    Vision {
        device: DeviceKind,
        #[source]
        source: SharedError<VisionError>,
    },
    /// The camera's next image could not be read (a folder camera's file
    /// missing, unreadable, truncated or not an image); `source` names the
    /// file and says which.
    #[error("{device}: {source}")]
    Image {
        device: DeviceKind,
        #[source]
        source: SharedError<ImageError>,
    },
    /// A pose outside the cell's workspace box was asked for, and refused
    /// before the device moved: check the task's poses, the detection or
    /// the tactile correction that produced it, or widen the box in the
    /// cell file if the cell really allows it.
    #[error(
        "{device}: refused {command} to ({:.1}, {:.1}, {:.1}) mm: outside the workspace box \
         ({:.1}, {:.1}, {:.1})..({:.1}, {:.1}, {:.1}) mm",
        target_mm[0], target_mm[1], target_mm[2],
        min_mm[0], min_mm[1], min_mm[2],
        max_mm[0], max_mm[1], max_mm[2]
    )]
    OutsideWorkspace {
        device: DeviceKind,
        command: &'static str,
        target_mm: [f64; 3],
        min_mm: [f64; 3],
        max_mm: [f64; 3],
    },
    /// A speed above the cell's limit (or not a positive number) was asked
    /// for, and refused before the device moved: lower the task's speed.
    #[error(
        "{device}: refused {command} at {speed_mm_s} mm/s: the cell allows (0, {limit_mm_s}] mm/s"
    )]
    TooFast {
        device: DeviceKind,
        command: &'static str,
        speed_mm_s: f64,
        limit_mm_s: f64,
    },
}

/// Whether a read error only means that nothing arrived before the port's
/// own timeout: the caller keeps its deadline and reads again.
pub fn nothing_arrived(error: &std::io::Error) -> bool {
    use std::io::ErrorKind;
    matches!(
        error.kind(),
        ErrorKind::TimedOut | ErrorKind::WouldBlock | ErrorKind::Interrupted
    )
}

impl DeviceError {
    pub fn device(&self) -> DeviceKind {
        match self {
            DeviceError::Timeout { device, .. }
            | DeviceError::NoAnswer { device, .. }
            | DeviceError::Refused { device, .. }
            | DeviceError::Disconnected { device, .. }
            | DeviceError::Garbled { device, .. }
            | DeviceError::Unusable { device, .. }
            | DeviceError::Vision { device, .. }
            | DeviceError::Image { device, .. }
            | DeviceError::OutsideWorkspace { device, .. }
            | DeviceError::TooFast { device, .. } => *device,
        }
    }
}

/// An error shared, behind an [`Arc`], by the copies of the
/// [`DeviceError`] that carries it: device errors are cloned into the
/// machine's events and the run record, and the errors of the layers
/// below (OpenCV's, ONNX Runtime's, I/O) cannot be cloned. It displays as
/// the error, and its source is the error's. Two are equal when they are
/// the same error or say the same, as the message-only errors it replaces
/// compared.
#[derive(Debug)]
pub struct SharedError<E>(pub Arc<E>);

impl<E> SharedError<E> {
    pub fn new(error: E) -> Self {
        SharedError(Arc::new(error))
    }
}

impl<E> From<E> for SharedError<E> {
    fn from(error: E) -> Self {
        SharedError::new(error)
    }
}

impl<E> Clone for SharedError<E> {
    fn clone(&self) -> Self {
        SharedError(Arc::clone(&self.0))
    }
}

impl<E> std::ops::Deref for SharedError<E> {
    type Target = E;

    fn deref(&self) -> &E {
        &self.0
    }
}

impl<E: std::fmt::Display> PartialEq for SharedError<E> {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.0, &other.0) || self.0.to_string() == other.0.to_string()
    }
}

impl<E: std::fmt::Display> std::fmt::Display for SharedError<E> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.0.fmt(f)
    }
}

impl<E: std::error::Error> std::error::Error for SharedError<E> {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        self.0.source()
    }
}
