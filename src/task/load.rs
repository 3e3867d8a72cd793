//! Loading a task file, and checking any file by its top table.

use std::path::Path;

use super::{CampaignFile, TaskFile};
use crate::cell::load::parse_cell;
use crate::schema::toml_file::{ConfigError, parse, read};

/// What `check_file` found a file to be.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FileKind {
    Task,
    Cell,
    Campaign,
}

impl std::fmt::Display for FileKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            FileKind::Task => "task file",
            FileKind::Cell => "cell file",
            FileKind::Campaign => "campaign file",
        })
    }
}

pub fn load_task(path: &Path) -> Result<TaskFile, ConfigError> {
    parse(path, &read(path)?)
}

/// Validates a task, cell or campaign file, telling which by its top table.
pub fn check_file(path: &Path) -> Result<FileKind, ConfigError> {
    let text = read(path)?;
    let table: toml::Table = parse(path, &text)?;
    if table.contains_key("task") {
        parse::<TaskFile>(path, &text).map(|_| FileKind::Task)
    } else if table.contains_key("cell") {
        parse_cell(path, &text).map(|_| FileKind::Cell)
    } else if table.contains_key("campaign") {
        parse::<CampaignFile>(path, &text).map(|_| FileKind::Campaign)
    } else {
        Err(ConfigError::UnknownKind {
            path: path.to_owned(),
        })
    }
}
