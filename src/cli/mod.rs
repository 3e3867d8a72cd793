//! The subcommands, each in its own file; `Status` is the exit status
//! they share.

pub mod calibrate_camera;
pub mod campaign;
pub mod check;
pub mod detect;
pub mod device;
pub mod emulate;
pub mod eval_vision;
pub mod graph;
pub mod plot;
pub mod render_dataset;
pub mod repl;
pub mod replay;
pub mod run;
pub mod tactile_fit;
pub mod vision_io;

use std::process::ExitCode;

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
