//! The tactile pad: raw 12-bit readings of its 25 taxels, polled at the
//! sensor's rate (500 Hz in the paper).

pub mod config;
mod polled;
mod remodel;
pub mod remodel_emulator;
mod sim;

pub use polled::PolledTactile;
pub use remodel::{RemodelTactile, SerialLink};
pub use sim::SimTactile;

use crate::perception::tactile::RawFrame;

use super::DeviceError;

/// One reading of the pad, in taxel order c11..c55.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TactileFrame {
    /// When it was sampled, on the cell's clock.
    pub t_s: f64,
    pub raw: RawFrame,
}

pub trait TactileSensor: Send {
    /// The next frame at the sensor's polling rate.
    fn read(&mut self) -> Result<TactileFrame, DeviceError>;
}
