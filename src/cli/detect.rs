//! `cablecell detect IMAGE...`

use std::path::{Path, PathBuf};
use std::time::Instant;

use cablecell::cell::CellFile;

use cablecell::detector::config::DetectorBackend;

use cablecell::cell::load_cell_uncalibrated;
use cablecell::hw::camera::read_image;
use cablecell::perception::vision::grasp_frame::ImageToBase;
use cablecell::perception::vision::{CableInstance, MaskNetwork, VisionOutput};
use cablecell::schema::FrameConfig;
use opencv::core::Mat;
use serde::Serialize;

use super::Status;
use super::vision_io::{VisionArgs, create_dir, draw_overlay, write_png};

/// What `detect --json` prints per image.
#[derive(Serialize)]
struct ImageReport<'a> {
    image: String,
    mask_used: cablecell::perception::vision::MaskMethod,
    plain_background: bool,
    /// The image's size as worked on over its own.
    work_scale: f64,
    cables: &'a [CableInstance],
    /// Per cable, its grasp frame in the base frame, when the cell's camera
    /// is calibrated.
    grasp_frames_in_base: Vec<Option<GraspInBase>>,
    timings_ms: Vec<(&'static str, f64)>,
    total_ms: f64,
    notes: &'a [String],
}

/// A grasp frame in the base frame, as cell files write poses.
#[derive(Serialize)]
struct GraspInBase {
    translation_mm: [f64; 3],
    rotation_rpy_rad: [f64; 3],
}

/// How the cell at `cell_path` places image points in the base frame: its
/// calibrated camera and the vision detector's cable plane.
fn image_to_base(cell_path: &Path) -> Result<ImageToBase, String> {
    let file: CellFile = load_cell_uncalibrated(cell_path).map_err(|e| e.to_string())?;
    let name = cell_path.display();
    let calibration = file.camera.calibration.as_ref().ok_or_else(|| {
        format!(
            "{name}: the camera is not calibrated: run `cablecell calibrate-camera --cell {name}`"
        )
    })?;
    match &file.detector.backend {
        DetectorBackend::Vision(vision) => {
            Ok(vision.image_to_base(file.camera.intrinsics, calibration))
        }
        DetectorBackend::Oracle(_) => Err(format!(
            "{name}: detector.backend: the cell has no vision detector, so no cable plane to place grasp points on"
        )),
    }
}

pub fn detect(
    images: &[PathBuf],
    args: &VisionArgs,
    cell: Option<&Path>,
    json: bool,
    masks: Option<&Path>,
    overlay: Option<&Path>,
) -> Status {
    let to_base = match cell.map(image_to_base).transpose() {
        Ok(to_base) => to_base,
        Err(error) => {
            eprintln!("error: {error}");
            return Status::BadInput;
        }
    };
    let mut pipeline = args.pipeline(masks.is_some());
    let mut network = args.network();
    let mut reports = Vec::new();
    let mut status = Status::Success;
    let mut warmed_up = false;
    for path in images {
        let image = match read_image(path) {
            Ok(image) => image,
            Err(error) => {
                eprintln!("error: {error}");
                status = Status::BadInput;
                continue;
            }
        };
        if !warmed_up {
            // One untimed run, so that the times reported are a warmed-up
            // pipeline's, as in `eval-vision` and the benchmarks. An error
            // here recurs in the timed run, which reports it.
            warmed_up = true;
            let start = Instant::now();
            let _ = pipeline.detect(&image, Some(&mut network as &mut dyn MaskNetwork));
            if !json {
                println!(
                    "start-up: {:.1} ms (the first image run once, untimed: one-off set-up such as loading the network)",
                    start.elapsed().as_secs_f64() * 1e3
                );
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
            work_scale: output.work_scale,
            cables: &output.cables,
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
            timings_ms: output.timings_ms.clone(),
            total_ms: output.timings_ms.iter().map(|(_, ms)| ms).sum(),
            notes: &output.notes,
        };
        if json {
            match serde_json::to_value(&report) {
                Ok(value) => reports.push(value),
                Err(error) => eprintln!("error: cannot write the report as JSON: {error}"),
            }
        } else {
            print_report(&report);
        }
    }
    if json {
        match serde_json::to_string_pretty(&reports) {
            Ok(text) => println!("{text}"),
            Err(error) => eprintln!("error: cannot write the report as JSON: {error}"),
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
        .timings_ms
        .iter()
        .map(|(stage, ms)| format!("{stage} {ms:.1}"))
        .collect();
    println!(
        "{}: {} cable(s), {:?} mask{}{}, {:.1} ms ({} ms)",
        report.image,
        report.cables.len(),
        report.mask_used,
        if report.plain_background {
            " (plain background)"
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
        println!(
            "  cable {k}: grasp at ({:.1}, {:.1}) px, direction {:+.3} rad, {} control points",
            cable.grasp_px[0],
            cable.grasp_px[1],
            cable.direction_rad,
            cable.spline.control_points.len()
        );
        println!(
            "    control points (px): {}",
            points_text(&cable.spline.control_points)
        );
        println!(
            "    along it (px), s = 0, 0.1, ..., 1: {}",
            points_text(&cable.spline.sample(SAMPLES_PRINTED))
        );
        if let Some(Some(frame)) = report.grasp_frames_in_base.get(k) {
            let [x, y, z] = frame.translation_mm;
            let [roll, pitch, yaw] = frame.rotation_rpy_rad;
            println!(
                "    grasp frame in base: [{x:.1}, {y:.1}, {z:.1}] mm, rpy [{roll:+.4}, {pitch:+.4}, {yaw:+.4}] rad"
            );
        }
    }
    for note in report.notes {
        println!("  note: {note}");
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
        let drawn = draw_overlay(image, output)
            .map_err(|e| format!("cannot draw the overlay of {stem}: {e}"))?;
        write_png(&dir.join(format!("{stem}.png")), &drawn)?;
    }
    Ok(())
}
