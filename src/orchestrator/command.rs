//! What the machine asks the cell to do, and what the cell answers.

use nalgebra::Isometry3;

use crate::detector::Detections;
use crate::geometry::LineInSensor;
use crate::hw::DeviceError;
use crate::hw::gripper::GripOutcome;
use crate::hw::tactile::TactileFrame;

/// A step for the cell, set by a state's entry action and carried out by
/// the executor. Each is answered by one `Event`.
#[derive(Debug, Clone, PartialEq)]
pub enum Command {
    /// Reference and open the gripper, then read `bias_frames` frames with
    /// nothing on the pad. Answered by `Tactile`.
    Prepare { open_mm: f64, bias_frames: usize },
    /// Look for the cable. Answered by `Detected`.
    Detect,
    /// Move the TCP to `base_from_tcp`. Answered by `Arrived`.
    MoveTo {
        base_from_tcp: Isometry3<f64>,
        speed_mm_s: f64,
    },
    /// Descend to `base_from_tcp` and close the jaws. Answered by `Grasped`.
    Grasp {
        base_from_tcp: Isometry3<f64>,
        speed_mm_s: f64,
        grip_current_a: f64,
    },
    /// Read `frames` consecutive frames. Answered by `Tactile`.
    ReadTactile { frames: usize },
    /// Open to `open_mm`, back off `retreat_mm` along the approach axis,
    /// move over `base_from_tcp`, descend onto it and close. Answered by
    /// `Grasped`.
    Regrasp {
        base_from_tcp: Isometry3<f64>,
        speed_mm_s: f64,
        open_mm: f64,
        retreat_mm: f64,
        grip_current_a: f64,
    },
    /// As `Regrasp`, to the next pose of a search by touch. Answered by
    /// `Grasped`.
    Probe {
        base_from_tcp: Isometry3<f64>,
        speed_mm_s: f64,
        open_mm: f64,
        retreat_mm: f64,
        grip_current_a: f64,
    },
    /// Stop the arm and the jaws, then open the jaws. Answered by `Stopped`.
    SafeStop { open_mm: f64 },
}

/// An input to the machine.
#[derive(Debug, Clone, PartialEq)]
pub enum Event {
    /// Begin the task.
    Start,
    Tactile {
        frames: Vec<TactileFrame>,
        /// Where the cable really lies on the pad, when the cell knows (a
        /// simulation): kept in the record beside the estimate.
        true_line: Option<LineInSensor>,
    },
    /// The cables found, best first, and the image they were found in.
    Detected(Detections),
    Arrived,
    Grasped {
        /// The arm's measured pose with the jaws closed.
        base_from_tcp: Isometry3<f64>,
        grip: GripOutcome,
    },
    /// The safe stop is done; `problems` lists what could not be stopped.
    Stopped {
        problems: Vec<DeviceError>,
    },
    /// A device failed while carrying out a command.
    DeviceFault(DeviceError),
    /// The operator asks to stop.
    Abort,
}
