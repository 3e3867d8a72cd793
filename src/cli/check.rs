//! `cablecell check FILE...`

use crate::cli::output::outln;
use std::path::PathBuf;

use cablecell::task::check_file;

use super::Status;

pub fn check(files: &[PathBuf]) -> Status {
    let mut status = Status::Success;
    for file in files {
        match check_file(file) {
            Ok(kind) => outln!("{}: ok ({kind})", file.display()),
            Err(error) => {
                eprintln!("error: {error}");
                status = Status::BadInput;
            }
        }
    }
    status
}
