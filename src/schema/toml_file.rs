//! Reading TOML files into their schemas, with positions in every error.

use std::path::{Path, PathBuf};

use serde::de::DeserializeOwned;

use super::{CampaignFile, TaskFile};
use crate::cell::CellFile;
use crate::cell::file::DetectorBackend;
use crate::perception::vision::MaskMethod;

/// Why a task or cell file could not be used.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ConfigError {
    /// The file could not be read: check the path and its permissions.
    #[error("{}: cannot read the file: {source}", path.display())]
    Read {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The file is not TOML, or a value does not fit the schema: the message
    /// says what was expected at that place.
    #[error("{}:{line}:{column}: {field}: {message}", path.display(), field = if field.is_empty() { "(file)" } else { field })]
    Invalid {
        path: PathBuf,
        line: usize,
        column: usize,
        /// Dotted path of the offending key, e.g. `tolerance.n_mm`.
        field: String,
        message: String,
    },
    /// The file has no `[task]`, `[cell]` or `[campaign]` table, so it is
    /// not known what to check it against.
    #[error("{}: not a task, cell or campaign file: expected a [task], [cell] or [campaign] table", path.display())]
    UnknownKind { path: PathBuf },
}

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

/// Loads a cell file: its schema, the checks that span several tables,
/// and its paths made relative to the file's folder.
pub fn load_cell(path: &Path) -> Result<CellFile, ConfigError> {
    parse_cell(path, &read(path)?)
}

/// Loads a cell file that may still lack its camera's calibration, for
/// the command that makes it.
pub fn load_cell_uncalibrated(path: &Path) -> Result<CellFile, ConfigError> {
    parse_resolved(path, &read(path)?)
}

/// A cell file's schema, its paths made relative to its folder.
fn parse_resolved(path: &Path, text: &str) -> Result<CellFile, ConfigError> {
    let mut cell: CellFile = parse(path, text)?;
    cell.resolve_paths(path.parent().unwrap_or(Path::new("")));
    Ok(cell)
}

/// A cell file's schema, its paths made relative to its folder, and the
/// checks that span several tables. The vision detector's are made here,
/// before the cell moves, rather than when it first looks at the camera.
fn parse_cell(path: &Path, text: &str) -> Result<CellFile, ConfigError> {
    let cell = parse_resolved(path, text)?;
    let DetectorBackend::Vision(vision) = &cell.detector.backend else {
        return Ok(cell);
    };
    let refuse = |keys: &[&str], field: &str, message: String| {
        let (line, column) = key_position(text, keys);
        Err(ConfigError::Invalid {
            path: path.to_owned(),
            line,
            column,
            field: field.to_owned(),
            message,
        })
    };
    if cell.camera.calibration.is_none() {
        return refuse(
            &["detector", "backend", "vision"],
            "camera.calibration",
            format!(
                "the vision detector needs the camera's pose in the base frame: \
                 run `cablecell calibrate-camera --cell {}`",
                path.display()
            ),
        );
    }
    if let Some([x, y, width, height]) = vision.roi_px {
        let image = &cell.camera.intrinsics;
        let inside = width > 0
            && height > 0
            && x >= 0
            && y >= 0
            && i64::from(x) + i64::from(width) <= i64::from(image.width_px)
            && i64::from(y) + i64::from(height) <= i64::from(image.height_px);
        if !inside {
            return refuse(
                &["detector", "backend", "vision", "roi_px"],
                "detector.backend.vision.roi_px",
                format!(
                    "the region of interest x={x} y={y} {width}x{height} px must have an area \
                     and lie within the camera's {}x{} px image (camera.intrinsics)",
                    image.width_px, image.height_px
                ),
            );
        }
    }
    if vision.mask != MaskMethod::Classical {
        let unreadable = match std::fs::metadata(&vision.model) {
            Ok(meta) if meta.is_file() => None,
            Ok(_) => Some("not a file".to_owned()),
            Err(error) => Some(error.to_string()),
        };
        if let Some(reason) = unreadable {
            return refuse(
                &["detector", "backend", "vision", "model"],
                "detector.backend.vision.model",
                format!(
                    "segmentation model {} is missing or unreadable: {reason}",
                    vision.model.display()
                ),
            );
        }
    }
    Ok(cell)
}

/// Line and column of the last key of `keys` (a path of tables), or of the
/// file's start if it cannot be found.
fn key_position(text: &str, keys: &[&str]) -> (usize, usize) {
    let offset = toml_edit::Document::parse(text).ok().and_then(|document| {
        let (last, tables) = keys.split_last()?;
        let mut table: &dyn toml_edit::TableLike = document.as_table();
        for key in tables {
            table = table.get(key)?.as_table_like()?;
        }
        table.key(last)?.span().map(|span| span.start)
    });
    line_column(text, offset.unwrap_or(0))
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

pub(crate) fn read(path: &Path) -> Result<String, ConfigError> {
    std::fs::read_to_string(path).map_err(|source| ConfigError::Read {
        path: path.to_owned(),
        source,
    })
}

/// Deserialises `text`; an error carries the key path (serde_path_to_error)
/// and the span (toml) turned into a 1-based line and column.
pub(crate) fn parse<T: DeserializeOwned>(path: &Path, text: &str) -> Result<T, ConfigError> {
    let deserializer = match toml::Deserializer::parse(text) {
        Ok(d) => d,
        Err(e) => return Err(invalid(path, text, String::new(), &e)),
    };
    serde_path_to_error::deserialize(deserializer).map_err(|e| {
        let field = e.path().to_string();
        invalid(
            path,
            text,
            if field == "." { String::new() } else { field },
            e.inner(),
        )
    })
}

fn invalid(path: &Path, text: &str, field: String, error: &toml::de::Error) -> ConfigError {
    let offset = error.span().map_or(0, |span| span.start);
    let (line, column) = line_column(text, offset);
    ConfigError::Invalid {
        path: path.to_owned(),
        line,
        column,
        field,
        message: error.message().to_owned(),
    }
}

/// 1-based line and column (in characters) of a byte offset.
fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    (line, before[line_start..].chars().count() + 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_column_counts_from_one() {
        let text = "a = 1\nbb = 2\n";
        assert_eq!(line_column(text, 0), (1, 1));
        assert_eq!(line_column(text, 6), (2, 1));
        assert_eq!(line_column(text, 11), (2, 6));
        assert_eq!(line_column(text, 999), (3, 1));
    }
}
