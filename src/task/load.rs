//! Loading a task file, and checking any file by its top table.

use std::path::Path;

use super::{CampaignFile, TaskFile};
use crate::cell::load::parse_cell;
use crate::schema::toml_file::{ConfigError, key_position, parse, read};

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
    parse_task(path, &read(path)?)
}

/// A task file's schema and the checks that span its tables: a
/// touch-only task needs a prior to search from.
pub fn parse_task(path: &Path, text: &str) -> Result<TaskFile, ConfigError> {
    let task: TaskFile = parse(path, text)?;
    if task.task.touch_only && task.prior.is_none() {
        let (line, column) = key_position(text, &["task", "touch_only"]);
        return Err(ConfigError::Invalid {
            path: path.to_owned(),
            line,
            column,
            field: "task.touch_only".to_owned(),
            message: "a touch-only task searches from where the cable roughly lies: \
                      add a [prior] table (docs/files.md)"
                .to_owned(),
        });
    }
    Ok(task)
}

/// Validates a task, cell or campaign file, telling which by its top table.
pub fn check_file(path: &Path) -> Result<FileKind, ConfigError> {
    let text = read(path)?;
    let table: toml::Table = parse(path, &text)?;
    if table.contains_key("task") {
        parse_task(path, &text).map(|_| FileKind::Task)
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
