//! `cablecell detect IMAGE...`

use std::path::{Path, PathBuf};

use cablecell::detector::config::VisionDetectorConfig;
use cablecell::hw::camera::read_image;
use cablecell::perception::vision::grasp_frame::ImageToBase;
use cablecell::perception::vision::{CableInstance, MaskNetwork, VisionOutput};
use cablecell::schema::FrameConfig;
use opencv::core::Mat;
use schemars::JsonSchema;
use serde::Serialize;

use super::output::outln;
use super::progress;
use super::vision_io::{
    VisionArgs, cell_vision_detector, create_dir, draw_overlay, warm_up, write_png,
};
use super::{Status, output};

/// What `detect --json` prints.
#[derive(Serialize, JsonSchema)]
pub struct DetectReport {
    /// One report per image read, in the order given.
    pub images: Vec<ImageReport>,
}

/// What `detect` found in one image.
#[derive(Serialize, JsonSchema)]
pub struct ImageReport {
    image: String,
    mask_used: cablecell::perception::vision::MaskMethod,
    plain_background: bool,
    /// Whether the background is busy (paint, prints, mosaics, a wood's
    /// grain): scraps and straight detections are judged otherwise there.
    busy_background: bool,
    /// Whether the background is painted (busy and of many colours), where
    /// the network for busy scenes (`--busy-model`, a cell's `busy_model`)
    /// makes the network's mask.
    painted_background: bool,
    /// The image's size as worked on over its own.
    work_scale: f64,
    cables: Vec<CableInstance>,
    /// Per cable, its grasp frame in the base frame, when the cell's camera
    /// is calibrated.
    grasp_frames_in_base: Vec<Option<GraspInBase>>,
    /// Each stage's time, in the order run.
    stages: Vec<StageTime>,
    total_ms: f64,
    notes: Vec<String>,
}

/// How long one stage of the pipeline took.
#[derive(Serialize, JsonSchema)]
struct StageTime {
    stage: &'static str,
    ms: f64,
}

/// A grasp frame in the base frame, as cell files write poses (roll,
/// pitch, yaw about the fixed x, y, z axes).
#[derive(Serialize, JsonSchema)]
struct GraspInBase {
    translation_mm: [f64; 3],
    rotation_rpy_rad: [f64; 3],
}

/// The cell at `cell_path`'s vision detector, and how it places image
/// points in the base frame: its calibrated camera and the cable's plane.
fn cell_vision(cell_path: &Path) -> Result<(VisionDetectorConfig, ImageToBase), String> {
    let (file, vision) = cell_vision_detector(cell_path)?;
    let name = cell_path.display();
    let calibration = file.camera.calibration.as_ref().ok_or_else(|| {
        format!(
            "{name}: the camera is not calibrated: run `cablecell calibrate-camera --cell {name}`"
        )
    })?;
    let to_base = vision.image_to_base(file.camera.intrinsics, calibration);
    Ok((vision, to_base))
}

pub fn detect(
    images: &[PathBuf],
    args: &VisionArgs,
    cell: Option<&Path>,
    json: bool,
    masks: Option<&Path>,
    overlay: Option<&Path>,
) -> Status {
    let cell_vision = match cell.map(cell_vision).transpose() {
        Ok(cell_vision) => cell_vision,
        Err(error) => {
            eprintln!("error: {error}");
            return Status::BadInput;
        }
    };
    // With a cell, its detector's own settings: the cables the task's
    // detect state would find.
    let (mut pipeline, mut network, to_base) = match cell_vision {
        Some((vision, to_base)) => (
            vision.pipeline(masks.is_some()),
            vision.network(),
            Some(to_base),
        ),
        None => (args.pipeline(masks.is_some()), args.network(), None),
    };
    let mut reports = Vec::new();
    let mut status = Status::Success;
    let mut warmed_up = false;
    let bar = progress::bar(images.len(), "images");
    for path in images {
        bar.inc(1);
        if output::closed() {
            break;
        }
        let image = match read_image(path) {
            Ok(image) => image,
            Err(error) => {
                eprintln!("error: {error}");
                status = Status::BadInput;
                continue;
            }
        };
        if !warmed_up {
            warmed_up = true;
            let line = warm_up(&mut pipeline, &mut network, &image);
            if !json {
                bar.suspend(|| outln!("{line}"));
            }
        }
        let output = match pipeline.detect(&image, Some(&mut network as &mut dyn MaskNetwork)) {
            Ok(output) => output,
            Err(error) => {
                eprintln!("error: {}: {error}", path.display());
                status = if error.is_in_setup() {
                    Status::BadInput
                } else {
                    Status::TaskFailed
                };
                continue;
            }
        };
        let stem = path
            .file_stem()
            .map_or_else(|| "image".into(), |s| s.to_string_lossy().into_owned());
        if let Err(error) = write_outputs(&stem, &image, &output, masks, overlay) {
            eprintln!("error: {error}");
            status = Status::OutputFailed;
        }
        let report = ImageReport {
            image: path.display().to_string(),
            mask_used: output.mask_used,
            plain_background: output.plain_background,
            busy_background: output.background.busy(),
            painted_background: output.background.painted(),
            work_scale: output.work_scale,
            cables: output.cables.clone(),
            grasp_frames_in_base: output
                .cables
                .iter()
                .map(|cable| {
                    let frame = FrameConfig::from_isometry(
                        &to_base.as_ref()?.base_from_cable(&cable.spline)?,
                    );
                    Some(GraspInBase {
                        translation_mm: frame.translation_mm,
                        rotation_rpy_rad: frame.rotation_rpy_rad,
                    })
                })
                .collect(),
            stages: output
                .timings_ms
                .iter()
                .map(|&(stage, ms)| StageTime { stage, ms })
                .collect(),
            total_ms: output.timings_ms.iter().map(|(_, ms)| ms).sum(),
            notes: output.notes.clone(),
        };
        if json {
            reports.push(report);
        } else {
            bar.suspend(|| print_report(&report));
        }
    }
    bar.finish_and_clear();
    if json {
        let printed = super::json::print(DetectReport { images: reports });
        if status == Status::Success {
            status = printed;
        }
    }
    status
}

/// Points printed along each cable for a person (`--json` gives
/// [`CableInstance::samples_px`]): s in steps of 0.1.
const SAMPLES_PRINTED: usize = 11;

/// `(x, y) (x, y) ...`, to a tenth of a pixel.
fn points_text(points_px: &[[f64; 2]]) -> String {
    points_px
        .iter()
        .map(|p| format!("({:.1}, {:.1})", p[0], p[1]))
        .collect::<Vec<_>>()
        .join(" ")
}

fn print_report(report: &ImageReport) {
    let stages: Vec<String> = report
        .stages
        .iter()
        .map(|StageTime { stage, ms }| format!("{stage} {ms:.1}"))
        .collect();
    outln!(
        "{}: {} cable(s), {:?} mask{}{}, {:.1} ms ({} ms)",
        report.image,
        report.cables.len(),
        report.mask_used,
        if report.plain_background {
            " (plain background)"
        } else if report.painted_background {
            " (painted background)"
        } else if report.busy_background {
            " (busy background)"
        } else {
            ""
        },
        if report.work_scale != 1.0 {
            format!(", worked on at {:.0} % size", 100.0 * report.work_scale)
        } else {
            String::new()
        },
        report.total_ms,
        stages.join(", ")
    );
    for (k, cable) in report.cables.iter().enumerate() {
        outln!(
            "  cable {k}: grasp at ({:.1}, {:.1}) px, direction {:+.3} rad, {} control points, confidence {:.2}",
            cable.grasp_px[0],
            cable.grasp_px[1],
            cable.direction_rad,
            cable.spline.control_points.len(),
            cable.confidence
        );
        outln!(
            "    control points (px): {}",
            points_text(&cable.spline.control_points)
        );
        outln!(
            "    along it (px), s = 0, 0.1, ..., 1: {}",
            points_text(&cable.spline.sample(SAMPLES_PRINTED))
        );
        if let Some(Some(frame)) = report.grasp_frames_in_base.get(k) {
            let [x, y, z] = frame.translation_mm;
            let [roll, pitch, yaw] = frame.rotation_rpy_rad;
            outln!(
                "    grasp frame in base: [{x:.1}, {y:.1}, {z:.1}] mm, rpy [{roll:+.4}, {pitch:+.4}, {yaw:+.4}] rad"
            );
        }
    }
    for note in &report.notes {
        outln!("  note: {note}");
    }
}

fn write_outputs(
    stem: &str,
    image: &Mat,
    output: &VisionOutput,
    masks: Option<&Path>,
    overlay: Option<&Path>,
) -> Result<(), String> {
    if let Some(dir) = masks {
        create_dir(dir)?;
        let not_drawn = || format!("{stem}: the pipeline drew no cable masks to write");
        for (k, cable) in output.cables.iter().enumerate() {
            let own = cable.mask.as_ref().ok_or_else(not_drawn)?;
            write_png(&dir.join(format!("{stem}_mask_{k}.png")), own)?;
        }
        let union_mask = output.union_mask.as_ref().ok_or_else(not_drawn)?;
        write_png(&dir.join(format!("{stem}_mask_all.png")), union_mask)?;
    }
    if let Some(dir) = overlay {
        create_dir(dir)?;
        let drawn = draw_overlay(image, &output.cables)
            .map_err(|e| format!("cannot draw the overlay of {stem}: {e}"))?;
        write_png(&dir.join(format!("{stem}.png")), &drawn)?;
    }
    Ok(())
}
