//! The subcommands, each in its own file; `Status` is the exit status
//! they share.

pub mod bench;
pub mod calibrate_camera;
pub mod campaign;
pub mod check;
pub mod detect;
pub mod device;
pub mod emulate;
pub mod eval_vision;
pub mod graph;
pub mod json;
pub mod labelled_folder;
pub mod output;
pub mod plot;
pub mod progress;
pub mod render_dataset;
pub mod repl;
pub mod replay;
pub mod run;
pub mod tactile_fit;
pub mod vision_io;

use std::ops::RangeInclusive;
use std::process::ExitCode;
use std::str::FromStr;

use cablecell::hw::DeviceError;
use cablecell::schema::validate::{Bound, check_within};

/// The documented exit statuses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    Success = 0,
    TaskFailed = 1,
    BadInput = 2,
    DeviceFault = 3,
    OutputFailed = 4,
}

impl From<Status> for ExitCode {
    fn from(status: Status) -> Self {
        ExitCode::from(status as u8)
    }
}

/// A command-line number in `range` (`unit` its unit), for clap's
/// `value_parser`: refused, with exit status 2, as a file's value out of
/// its range is.
pub fn number_within<T: FromStr + Bound>(
    text: &str,
    range: RangeInclusive<T>,
    unit: &str,
) -> Result<T, String> {
    let value: T = text
        .parse()
        .map_err(|_| format!("`{text}` is not a number"))?;
    check_within(value, &range, unit)
}

/// The exit status of a device error: a move that the cell's limits refused
/// before the device was asked is bad input (the command line or the file
/// asked for too much); anything else is a device fault.
pub fn device_error_status(error: &DeviceError) -> Status {
    match error {
        DeviceError::TooFast { .. } | DeviceError::OutsideWorkspace { .. } => Status::BadInput,
        _ => Status::DeviceFault,
    }
}
