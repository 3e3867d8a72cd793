//! Loading a cell file: its schema, its paths made relative to its folder,
//! and the checks that span several tables.

use std::path::Path;

use super::CellFile;
use crate::detector::config::DetectorBackend;
use crate::hw::tactile::config::{SAMPLE_EXCHANGE_BYTES, TactileBackend, link_rate_hz};
use crate::perception::vision::MaskMethod;
use crate::schema::toml_file::{ConfigError, invalid_at_key, parse, read};

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

/// A cell file's schema, the checks of its devices' tables that span two
/// keys, and its paths made relative to its folder.
fn parse_resolved(path: &Path, text: &str) -> Result<CellFile, ConfigError> {
    let mut cell: CellFile = parse(path, text)?;
    check_devices(&cell)
        .map_err(|(keys, message)| invalid_at_key(path, text, keys, &keys.join("."), message))?;
    cell.resolve_paths(path.parent().unwrap_or(Path::new("")));
    Ok(cell)
}

/// What a value of one key cannot be given another's: the marker's id in
/// its dictionary, the tactile polling rate on its serial link. The error
/// is the offending key's path and the message.
fn check_devices(cell: &CellFile) -> Result<(), (&'static [&'static str], String)> {
    let marker = &cell.camera.marker;
    let count = marker.dictionary.marker_count();
    if !(0..count).contains(&marker.id) {
        return Err((
            &["camera", "marker", "id"],
            format!(
                "expected a marker id in [0, {}] (the dictionary holds {count} markers), found {}",
                count - 1,
                marker.id
            ),
        ));
    }
    if let TactileBackend::Remodel(remodel) = &cell.tactile.backend {
        let top_hz = link_rate_hz(remodel.baud);
        if cell.tactile.rate_hz > top_hz {
            return Err((
                &["tactile", "rate_hz"],
                format!(
                    "{} Hz is more than the link at {} baud carries: {top_hz:.0} samples/s of {SAMPLE_EXCHANGE_BYTES} bytes",
                    cell.tactile.rate_hz, remodel.baud
                ),
            ));
        }
    }
    Ok(())
}

/// A cell file's schema, its paths made relative to its folder, and the
/// checks that span several tables. The vision detector's are made here,
/// before the cell moves, rather than when it first looks at the camera.
pub fn parse_cell(path: &Path, text: &str) -> Result<CellFile, ConfigError> {
    let cell = parse_resolved(path, text)?;
    let DetectorBackend::Vision(vision) = &cell.detector.backend else {
        return Ok(cell);
    };
    let refuse = |keys: &[&str], field: &str, message: String| {
        Err(invalid_at_key(path, text, keys, field, message))
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
        let models = [
            ("model", Some(&vision.model)),
            ("busy_model", vision.busy_model.as_ref()),
        ];
        for (key, model) in models {
            let Some(model) = model else { continue };
            let unreadable = match std::fs::metadata(model) {
                Ok(meta) if meta.is_file() => None,
                Ok(_) => Some("not a file".to_owned()),
                Err(error) => Some(error.to_string()),
            };
            if let Some(reason) = unreadable {
                return refuse(
                    &["detector", "backend", "vision", key],
                    &format!("detector.backend.vision.{key}"),
                    format!(
                        "segmentation model {} is missing or unreadable: {reason}",
                        model.display()
                    ),
                );
            }
        }
    }
    Ok(cell)
}
