//! Loading a cell file: its schema, its paths made relative to its folder,
//! and the checks that span several tables.

use std::path::Path;

use super::CellFile;
use crate::detector::config::DetectorBackend;
use crate::perception::vision::MaskMethod;
use crate::schema::toml_file::{ConfigError, key_position, parse, read};

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
pub(crate) fn parse_cell(path: &Path, text: &str) -> Result<CellFile, ConfigError> {
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
