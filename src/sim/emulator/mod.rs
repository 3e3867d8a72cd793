//! Emulators of the cell's serial devices: they speak the devices' real
//! protocols on a byte stream (a pseudo-terminal in the tests), and can
//! misbehave on purpose, so that the real drivers are tested end to end.

#[cfg(feature = "panda")]
pub mod panda;
pub mod pg70;
pub mod tactile;
