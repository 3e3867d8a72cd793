//! Standard output that a closed pipe does not break: `cablecell detect
//! IMG | head -1` ends quietly instead of panicking as `println!` does, and
//! a run whose reader went away keeps driving the cell to its end (a
//! killed orchestrator would leave the arm mid-move). Commands that loop
//! over many inputs ask [`closed`] and stop early.

use std::fmt::Arguments;
use std::io::{ErrorKind, Write};
use std::sync::atomic::{AtomicBool, Ordering};

static CLOSED: AtomicBool = AtomicBool::new(false);

/// Writes `text` to standard output as it is; once the reader is gone,
/// writes nothing.
pub fn text(text: Arguments) {
    if CLOSED.load(Ordering::Relaxed) {
        return;
    }
    let mut stdout = std::io::stdout().lock();
    if let Err(error) = stdout.write_fmt(text).and_then(|()| stdout.flush()) {
        if error.kind() != ErrorKind::BrokenPipe {
            eprintln!("warning: cannot write to standard output: {error}");
        }
        CLOSED.store(true, Ordering::Relaxed);
    }
}

/// [`text`] and a newline.
pub fn line(line: Arguments) {
    text(format_args!("{line}\n"));
}

/// Whether standard output's reader has gone (or it failed).
pub fn closed() -> bool {
    CLOSED.load(Ordering::Relaxed)
}

/// `println!` through [`line`].
macro_rules! outln {
    () => { $crate::cli::output::line(format_args!("")) };
    ($($arg:tt)*) => { $crate::cli::output::line(format_args!($($arg)*)) };
}

/// `print!` through [`text`].
macro_rules! out {
    ($($arg:tt)*) => { $crate::cli::output::text(format_args!($($arg)*)) };
}

pub(crate) use {out, outln};
