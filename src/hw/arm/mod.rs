//! The arm: Cartesian poses of the tool centre point (TCP) in the base
//! frame, as the Panda takes them.

pub mod config;
#[cfg(feature = "panda")]
pub mod panda;
#[cfg(feature = "panda")]
pub mod panda_emulator;
mod sim;
mod workspace_limited;

#[cfg(feature = "panda")]
pub use panda::Panda;
pub use sim::SimArm;
pub use workspace_limited::{WorkspaceBox, WorkspaceLimited};

use nalgebra::Isometry3;

use super::DeviceError;

pub trait Arm: Send {
    /// The TCP's measured pose in the base frame.
    fn base_from_tcp(&mut self) -> Result<Isometry3<f64>, DeviceError>;

    /// Moves the TCP in a straight line to `base_from_tcp` at no more than
    /// `speed_mm_s`, returning once it has arrived.
    fn move_linear(
        &mut self,
        base_from_tcp: &Isometry3<f64>,
        speed_mm_s: f64,
    ) -> Result<(), DeviceError>;

    /// Stops any motion; the fault path calls it.
    fn stop(&mut self) -> Result<(), DeviceError>;
}
