//! Loading a task file, and checking any file by its top table.

use std::path::Path;

use super::{CampaignFile, TaskFile};
use crate::cell::CellFile;
use crate::cell::load::parse_cell;
use crate::schema::toml_file::{ConfigError, invalid_at_key, parse, read};
use crate::task::campaign_file::Sensing;

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
        return Err(invalid_at_key(
            path,
            text,
            &["task", "touch_only"],
            "task.touch_only",
            "a touch-only task searches from where the cable roughly lies: \
             add a [prior] table (docs/files.md)"
                .to_owned(),
        ));
    }
    Ok(task)
}

/// Loads a task file for the cell it is to run on (`check_on_cell`).
pub fn load_task_on_cell(
    path: &Path,
    cell_path: &Path,
    cell: &CellFile,
) -> Result<TaskFile, ConfigError> {
    let text = read(path)?;
    let task = parse_task(path, &text)?;
    check_on_cell(path, &text, &task, cell_path, cell)?;
    Ok(task)
}

/// The checks between a task and its cell, so that a task the cell would
/// refuse mid-run is refused at load, at the task file's line: its arm
/// speed within the cell's `max_speed_mm_s` (else the arm refuses the
/// first move, a device fault after the run had begun).
pub fn check_on_cell(
    path: &Path,
    text: &str,
    task: &TaskFile,
    cell_path: &Path,
    cell: &CellFile,
) -> Result<(), ConfigError> {
    let (speed_mm_s, max_mm_s) = (task.approach.speed_mm_s, cell.arm.max_speed_mm_s);
    if speed_mm_s > max_mm_s {
        return Err(invalid_at_key(
            path,
            text,
            &["approach", "speed_mm_s"],
            "approach.speed_mm_s",
            format!(
                "expected a value in (0, {max_mm_s}] mm/s (arm.max_speed_mm_s of {}), found {speed_mm_s}",
                cell_path.display()
            ),
        ));
    }
    Ok(())
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
        parse_campaign(path, &text).map(|_| FileKind::Campaign)
    } else {
        Err(ConfigError::UnknownKind {
            path: path.to_owned(),
        })
    }
}

/// Loads a campaign file with the task and cell files it names. A task or
/// cell file that cannot be read is reported at the campaign file's line
/// that names it; one that is invalid, at its own line.
pub fn load_campaign(path: &Path) -> Result<(CampaignFile, TaskFile, CellFile), ConfigError> {
    parse_campaign(path, &read(path)?)
}

fn parse_campaign(
    path: &Path,
    text: &str,
) -> Result<(CampaignFile, TaskFile, CellFile), ConfigError> {
    let file: CampaignFile = parse(path, text)?;
    let named_here = |key: &'static str| {
        move |error: ConfigError| match error {
            ConfigError::Read { .. } => invalid_at_key(
                path,
                text,
                &["campaign", key],
                &format!("campaign.{key}"),
                error.to_string(),
            ),
            other => other,
        }
    };
    let task_path = file.task_path(path);
    let task_text = read(&task_path).map_err(named_here("task"))?;
    let task = parse_task(&task_path, &task_text)?;
    if let Some(policy) = file.policies.iter().find(|p| p.sensing == Sensing::Touch)
        && task.prior.is_none()
    {
        return Err(invalid_at_key(
            path,
            text,
            &["campaign", "task"],
            "campaign.task",
            format!(
                "policy `{}` is touch only, but the task has no [prior] to search from",
                policy.name
            ),
        ));
    }
    let cell_path = file.cell_path(path);
    let cell = read(&cell_path)
        .and_then(|cell_text| parse_cell(&cell_path, &cell_text))
        .map_err(named_here("cell"))?;
    check_on_cell(&task_path, &task_text, &task, &cell_path, &cell)?;
    Ok((file, task, cell))
}
