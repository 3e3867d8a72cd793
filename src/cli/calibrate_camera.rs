//! `cablecell calibrate-camera`: the camera's pose in the base frame from
//! the marker on the finger (the paper's Fig. 2), stored in the cell file.

use crate::cli::output::outln;
use std::path::Path;

use cablecell::cell::CellDevices;
use cablecell::cell::load_cell_uncalibrated;
use cablecell::hw::camera::config::CameraBackend;
use cablecell::perception::vision::calibration::{CameraCalibration, MarkerView, calibrate_views};
use cablecell::schema::FrameConfig;
use nalgebra::Isometry3;
use opencv::core::Mat;

use super::{Status, device_error_status};

/// Moves the arm through the cell file's `camera.calibration_poses`,
/// captures the marker at each, solves for `base_from_camera`, prints it,
/// and (unless `dry_run`) writes it into the file's `[camera.calibration]`,
/// keeping the rest of the file as it was.
pub fn calibrate_camera(cell_path: &Path, seed: u64, speed_mm_s: f64, dry_run: bool) -> Status {
    let file = match load_cell_uncalibrated(cell_path) {
        Ok(file) => file,
        Err(error) => {
            eprintln!("error: {error}");
            return Status::BadInput;
        }
    };
    let poses = &file.camera.calibration_poses;
    if poses.is_empty() {
        eprintln!(
            "error: {}: camera.calibration_poses: no poses to show the marker from",
            cell_path.display()
        );
        return Status::BadInput;
    }
    let mut cell = match CellDevices::build(&file, seed) {
        Ok(cell) => cell,
        Err(error) => {
            eprintln!("error: {error}");
            return Status::DeviceFault;
        }
    };
    let mut views: Vec<(Mat, Isometry3<f64>)> = Vec::with_capacity(poses.len());
    for (index, pose) in poses.iter().enumerate() {
        let captured = cell
            .arm
            .move_linear(&pose.isometry(), speed_mm_s)
            .and_then(|()| cell.arm.base_from_tcp())
            .and_then(|base_from_tcp| Ok((cell.camera.capture()?, base_from_tcp)));
        match captured {
            Ok(view) => views.push(view),
            Err(error) => {
                eprintln!("error: calibration pose {index}: {error}");
                // Best effort: the arm is left where it stopped.
                let _ = cell.arm.stop();
                return device_error_status(&error);
            }
        }
    }
    let marker_views: Vec<MarkerView<'_>> = views
        .iter()
        .map(|(bgr, base_from_tcp)| MarkerView {
            bgr,
            base_from_tcp: *base_from_tcp,
        })
        .collect();
    let calibration = match calibrate_views(
        &marker_views,
        &file.camera.intrinsics,
        &file.camera.marker.on_finger(),
    ) {
        Ok(calibration) => calibration,
        Err(error) => {
            eprintln!("error: calibration failed: {error}");
            return Status::TaskFailed;
        }
    };
    print_calibration(&calibration, poses.len());
    if let CameraBackend::Sim(sim) = &file.camera.backend {
        let truth = sim.base_from_camera.isometry();
        let estimate = calibration.base_from_camera;
        outln!(
            "  against the simulated camera's true pose: {:.3} mm, {:.4}°",
            (estimate.translation.vector - truth.translation.vector).norm(),
            (truth.rotation.inverse() * estimate.rotation)
                .angle()
                .to_degrees()
        );
    }
    if dry_run {
        return Status::Success;
    }
    match store(cell_path, &calibration) {
        Ok(()) => {
            outln!("stored in {} [camera.calibration]", cell_path.display());
            Status::Success
        }
        Err(error) => {
            eprintln!(
                "error: {}: cannot store the calibration: {error}",
                cell_path.display()
            );
            Status::OutputFailed
        }
    }
}

fn print_calibration(calibration: &CameraCalibration, views: usize) {
    let frame = FrameConfig::from_isometry(&calibration.base_from_camera);
    let [x, y, z] = frame.translation_mm;
    let [roll, pitch, yaw] = frame.rotation_rpy_rad;
    outln!("camera calibrated from {views} view(s) of the marker");
    outln!("  base_from_camera translation [{x:.3}, {y:.3}, {z:.3}] mm");
    outln!("                   rotation rpy [{roll:.6}, {pitch:.6}, {yaw:.6}] rad");
    outln!(
        "  reprojection error {:.3} px (RMS over the marker's corners)",
        calibration.reprojection_error_px
    );
}

/// Rounded to what a calibration can tell: a micrometre, a microradian.
fn rounded(values: [f64; 3], decimals: i32) -> toml_edit::Array {
    let scale = 10f64.powi(decimals);
    values.iter().map(|v| (v * scale).round() / scale).collect()
}

/// Writes `[camera.calibration]` into the cell file, replacing any earlier
/// one and keeping every other line and comment.
fn store(cell_path: &Path, calibration: &CameraCalibration) -> Result<(), String> {
    let text = std::fs::read_to_string(cell_path).map_err(|e| e.to_string())?;
    let mut document: toml_edit::DocumentMut = text.parse().map_err(|e| format!("{e}"))?;
    let frame = FrameConfig::from_isometry(&calibration.base_from_camera);
    let mut pose = toml_edit::InlineTable::new();
    pose.insert("translation_mm", rounded(frame.translation_mm, 3).into());
    pose.insert(
        "rotation_rpy_rad",
        rounded(frame.rotation_rpy_rad, 6).into(),
    );
    let mut table = toml_edit::Table::new();
    table.decor_mut().set_prefix(
        "\n# Written by `cablecell calibrate-camera`: the camera's pose estimated from\n\
         # the finger's marker. Run it again after moving the camera.\n",
    );
    table.insert("base_from_camera", toml_edit::value(pose));
    table.insert(
        "reprojection_error_px",
        toml_edit::value((calibration.reprojection_error_px * 1000.0).round() / 1000.0),
    );
    let camera = document
        .get_mut("camera")
        .and_then(toml_edit::Item::as_table_mut)
        .ok_or("the file has no [camera] table")?;
    camera.insert("calibration", toml_edit::Item::Table(table));
    std::fs::write(cell_path, document.to_string()).map_err(|e| e.to_string())
}
