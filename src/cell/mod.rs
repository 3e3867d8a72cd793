//! A cell: its file (which backend each device uses, with its limits and
//! calibration) and the devices built from it.

mod build;
pub mod file;
pub mod load;

pub use build::{CellDevices, Emulators};
pub use file::CellFile;
pub use load::{load_cell, load_cell_uncalibrated};
