//! `cablecell graph TASK`

use crate::cli::output::out;
use std::path::Path;

use cablecell::orchestrator::graph::dot;
use cablecell::task::load_task;

use super::Status;

pub fn graph(task_path: &Path) -> Status {
    match load_task(task_path) {
        Ok(task) => {
            out!("{}", dot(&task));
            Status::Success
        }
        Err(error) => {
            eprintln!("error: {error}");
            Status::BadInput
        }
    }
}
