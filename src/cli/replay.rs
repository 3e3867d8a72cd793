//! `cablecell replay FILE`

use crate::cli::output::{out, outln};
use std::path::Path;

use cablecell::geometry::LineInSensor;
use cablecell::perception::tactile::Estimator;
use cablecell::perception::vision::Pipeline;
use cablecell::perception::vision::network::LazyNetwork;
use cablecell::recording::replay::{Refit, Replay};
use cablecell::recording::schema::CompressedImageMessage;
use cablecell::recording::{Recording, Topic};
use opencv::imgcodecs;
use opencv::prelude::*;

use super::Status;
use super::run::print_timeline_line;
use super::vision_io::{VisionArgs, cell_vision_detector, warm_up};

pub fn replay(
    path: &Path,
    estimators: &[Estimator],
    vision: Option<&VisionArgs>,
    cell: Option<&Path>,
) -> Status {
    let recording = match Recording::read(path) {
        Ok(recording) => recording,
        Err(error) => {
            eprintln!("error: {error}");
            return Status::BadInput;
        }
    };
    if let Some(why) = &recording.truncated {
        outln!(
            "truncated recording ({why}): showing the {} messages before the cut",
            recording.messages.len()
        );
    }
    let replay = match Replay::of(&recording) {
        Ok(replay) => replay,
        Err(error) => {
            eprintln!("error: {error}");
            return Status::BadInput;
        }
    };
    let run = &replay.run;
    outln!(
        "task {} on {} (seed {}), estimator {}; {} messages",
        run.task,
        run.cell,
        run.seed,
        estimator_name(run.estimator),
        recording.messages.len()
    );
    let counts: Vec<String> = Topic::ALL
        .iter()
        .map(|topic| format!("{} {}", topic.name(), recording.count(*topic)))
        .collect();
    outln!("channels: {}", counts.join(", "));
    outln!("timeline:");
    let mut entered_s = 0.0;
    for t in &replay.transitions {
        print_timeline_line(t.t_s, &t.from, &t.to, entered_s);
        entered_s = t.t_s;
    }
    for estimator in estimators {
        let refits = replay.refit(*estimator);
        outln!(
            "{} again on the recorded frames ({} grasps):",
            estimator_name(*estimator),
            refits.len()
        );
        refits.iter().for_each(print_refit);
    }
    let Some(args) = vision else {
        return Status::Success;
    };
    // With a cell, its detector's own settings: what the task's detect
    // state ran.
    let (pipeline, network, settings) = match cell {
        None => (
            args.pipeline(false),
            args.network(),
            "the options given".to_owned(),
        ),
        Some(cell) => match cell_vision_detector(cell) {
            Ok((_, vision)) => (
                vision.pipeline(false),
                vision.network(),
                format!("{}'s detector", cell.display()),
            ),
            Err(error) => {
                eprintln!("error: {error}");
                return Status::BadInput;
            }
        },
    };
    detect_again(&recording, pipeline, network, &settings)
}

/// Runs `pipeline` on every recorded camera image.
fn detect_again(
    recording: &Recording,
    mut pipeline: Pipeline,
    mut network: LazyNetwork,
    settings: &str,
) -> Status {
    let images: Vec<CompressedImageMessage> = match recording.decode(Topic::CameraImage) {
        Ok(images) => images,
        Err(error) => {
            eprintln!("error: {error}");
            return Status::BadInput;
        }
    };
    outln!(
        "vision again on the recorded images ({}), with {settings}:",
        images.len()
    );
    let mut status = Status::Success;
    let mut warmed_up = false;
    // Times from the recording's start (its times are dates).
    let start_ns = recording.messages.first().map_or(0, |m| m.log_time_ns);
    for message in &images {
        let t_s = message.timestamp.ns().saturating_sub(start_ns) as f64 * 1e-9;
        let bytes = opencv::core::Vector::<u8>::from_slice(&message.data);
        let image = match imgcodecs::imdecode(&bytes, imgcodecs::IMREAD_COLOR) {
            Ok(image) if !image.empty() => image,
            _ => {
                eprintln!(
                    "error: the image at {t_s:.3} s is not a {} OpenCV can decode",
                    message.format
                );
                status = Status::BadInput;
                continue;
            }
        };
        if !warmed_up {
            warmed_up = true;
            outln!("{}", warm_up(&mut pipeline, &mut network, &image));
        }
        match pipeline.detect(&image, Some(&mut network)) {
            Ok(output) => {
                let total_ms: f64 = output.timings_ms.iter().map(|(_, ms)| ms).sum();
                outln!(
                    "{t_s:9.3} s  {} cable(s), {:?} mask, {total_ms:.1} ms",
                    output.cables.len(),
                    output.mask_used
                );
                for (k, cable) in output.cables.iter().enumerate() {
                    outln!(
                        "    cable {k}: grasp at ({:.1}, {:.1}) px, direction {:+.3} rad, {:.0} px long, confidence {:.2}",
                        cable.grasp_px[0],
                        cable.grasp_px[1],
                        cable.direction_rad,
                        cable.length_px,
                        cable.confidence
                    );
                }
            }
            Err(error) => {
                eprintln!("error: the image at {t_s:.3} s: {error}");
                status = Status::TaskFailed;
            }
        }
    }
    status
}

fn print_refit(refit: &Refit) {
    let name = match refit.attempt {
        0 => "trial grasp".to_owned(),
        k => format!("regrasp {k}"),
    };
    let line_text =
        |line: &LineInSensor| format!("n {:+7.3} mm  α {:+.4} rad", line.n_mm, line.alpha_rad);
    match &refit.line {
        Ok(line) => out!("{name:>13}  now      {}", line_text(line)),
        Err(error) => out!("{name:>13}  now      no estimate: {error}"),
    }
    match refit.error() {
        Some(e) => outln!(
            "   vs truth n {:+7.3} mm  α {:+.4} rad",
            e.n_mm,
            e.alpha_rad
        ),
        None => outln!(),
    }
    if let Some(recorded) = &refit.recorded {
        out!("{:>13}  recorded {}", "", line_text(recorded));
        match refit.recorded_error() {
            Some(e) => outln!(
                "   vs truth n {:+7.3} mm  α {:+.4} rad",
                e.n_mm,
                e.alpha_rad
            ),
            None => outln!(),
        }
    }
}

fn estimator_name(estimator: Estimator) -> &'static str {
    match estimator {
        Estimator::Centroids => "centroids",
        Estimator::Ridge => "ridge",
        Estimator::Oracle => "oracle",
    }
}
