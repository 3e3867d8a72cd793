//! The parallel gripper: jaw opening in mm and grip by motor current, as
//! the Schunk PG70 takes them.

pub mod config;
mod pg70;
pub mod pg70_emulator;
mod sim;
pub mod smp;

pub use pg70::Pg70;
pub use sim::SimGripper;

use serde::Serialize;

use super::DeviceError;

/// How a grip ended.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "outcome", rename_all = "snake_case")]
pub enum GripOutcome {
    /// The jaws were blocked by an object at this opening.
    Holding { opening_mm: f64 },
    /// The jaws closed fully: there was nothing between them.
    Empty,
}

pub trait Gripper: Send {
    /// Homes the jaws; the PG70 refuses moves until this is done.
    fn reference(&mut self) -> Result<(), DeviceError>;

    /// Moves the jaws to `opening_mm` and returns once they are there.
    fn move_to(&mut self, opening_mm: f64) -> Result<(), DeviceError>;

    /// Closes with `current_a` until the jaws are blocked or closed.
    fn grip(&mut self, current_a: f64) -> Result<GripOutcome, DeviceError>;

    /// Stops the jaws where they are; the fault path calls it.
    fn stop(&mut self) -> Result<(), DeviceError>;
}
