//! `cablecell check FILE...`

use std::path::PathBuf;

use cablecell::task::check_file;

use super::Status;

pub fn check(files: &[PathBuf]) -> Status {
    let mut status = Status::Success;
    for file in files {
        match check_file(file) {
            Ok(kind) => println!("{}: ok ({kind})", file.display()),
            Err(error) => {
                eprintln!("error: {error}");
                status = Status::BadInput;
            }
        }
    }
    status
}
