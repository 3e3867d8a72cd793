//! Scoring the pipeline against the labels: masks, instances, centre lines
//! and grasp points, and the labels' own consistency.

use std::collections::BTreeMap;
use std::path::Path;

use cablecell::campaign::stats::{Rate, Summary};
use cablecell::perception::vision::eval::{
    GroundTruth, ImageScore, label_consistency, score, score_cables,
};
use cablecell::perception::vision::{
    CableInstance, MaskMethod, MaskNetwork, Pipeline, VisionError, union_mask,
};
use opencv::core::{Mat, Point, Rect, Scalar};
use opencv::imgproc;
use opencv::prelude::*;

use crate::cli::Status;
use crate::cli::labelled_folder::LabelledImage;
use crate::cli::vision_io::{VisionArgs, create_dir, draw_line, draw_overlay, write_png};

use super::{Evaluation, LabelsOwnDice, LengthShare, MaskUse};
use indicatif::ProgressBar;

pub(super) fn labels_own_dice(samples: &[LabelledImage]) -> Result<Option<LabelsOwnDice>, String> {
    let truths: Vec<&GroundTruth> = samples.iter().map(|s| &s.truth).collect();
    let consistency = label_consistency(&truths)
        .map_err(|error| format!("drawing the labelled centre lines: {error}"))?;
    Ok(consistency.and_then(|c| {
        Summary::of(&c.union_dice).map(|union_dice| LabelsOwnDice {
            width_px: c.width_px,
            union_dice,
        })
    }))
}

/// Why an evaluation stopped, and the exit status that says whose fault it
/// is: the command line's (2) when the pipeline's set-up failed (a model
/// that is missing or no network, no runtime), as every image would fail
/// alike; else an image's (1).
pub(super) struct Failure {
    pub(super) message: String,
    pub(super) status: Status,
}

impl From<String> for Failure {
    fn from(message: String) -> Self {
        Failure {
            message,
            status: Status::TaskFailed,
        }
    }
}

/// Runs the pipeline configured by `vision` on every sample and scores it,
/// drawing each result into `overlay` when given; with `labelled_mask`,
/// its instance stages on each sample's labelled mask instead (see
/// `EvalVisionArgs::labelled_mask`). The first image is run
/// once untimed before the loop, so that loading the network and first-use
/// allocations are not counted as its time. `bar` ticks once an image.
pub(super) fn evaluate(
    vision: &VisionArgs,
    samples: &[LabelledImage],
    labelled_mask: bool,
    overlay: Option<&Path>,
    bar: &ProgressBar,
) -> Result<Evaluation, Failure> {
    let failed = |sample: &LabelledImage, error: &VisionError| Failure {
        message: format!("{}: {error}", sample.path.display()),
        status: if error.is_in_setup() {
            Status::BadInput
        } else {
            Status::TaskFailed
        },
    };
    if let Some(dir) = overlay {
        create_dir(dir)?;
    }
    let mut pipeline = vision.pipeline(true);
    let mut network = vision.network();
    let mut per_image = Vec::new();
    let mut notes = Vec::new();
    let mut mask_used = MaskUse::default();
    let mut stage_ms: BTreeMap<&'static str, Vec<f64>> = BTreeMap::new();
    for (k, sample) in samples.iter().enumerate() {
        bar.inc(1);
        let mut run = |pipeline: &mut Pipeline| -> Result<Run, VisionError> {
            if labelled_mask {
                let found =
                    pipeline.instances_from_mask(&sample.truth.union_mask, Some(&sample.image))?;
                let mask = &sample.truth.union_mask;
                let full = Rect::new(0, 0, mask.cols(), mask.rows());
                let union_mask = union_mask(&found.cables, full)?;
                Ok(Run {
                    score: score_cables(&found.cables, &union_mask, &sample.truth)?,
                    timings_ms: found.timings_ms,
                    notes: Vec::new(),
                    cables: found.cables,
                    mask_used: None,
                })
            } else {
                let output =
                    pipeline.detect(&sample.image, Some(&mut network as &mut dyn MaskNetwork))?;
                Ok(Run {
                    score: score(&output, &sample.truth)?,
                    timings_ms: output.timings_ms,
                    notes: output.notes,
                    cables: output.cables,
                    mask_used: Some(output.mask_used),
                })
            }
        };
        if k == 0 {
            run(&mut pipeline).map_err(|error| failed(sample, &error))?;
        }
        let run = run(&mut pipeline).map_err(|error| failed(sample, &error))?;
        for (stage, ms) in &run.timings_ms {
            stage_ms.entry(stage).or_default().push(*ms);
        }
        stage_ms
            .entry("total")
            .or_default()
            .push(run.timings_ms.iter().map(|(_, ms)| ms).sum());
        if let Some(dir) = overlay {
            let drawn = draw_comparison(&sample.image, &run.cables, &sample.truth, &run.score)
                .map_err(|e| format!("cannot draw the overlay of {}: {e}", sample.stem))?;
            write_png(&dir.join(format!("{}.png", sample.stem)), &drawn)?;
        }
        per_image.push((sample.stem.clone(), run.score));
        match run.mask_used {
            None => mask_used.labelled += 1,
            Some(MaskMethod::Network) => mask_used.network += 1,
            Some(_) => mask_used.classical += 1,
        }
        notes.extend(
            run.notes
                .into_iter()
                .map(|note| (sample.stem.clone(), note)),
        );
    }
    let of = |f: &dyn Fn(&ImageScore) -> Option<f64>| {
        Summary::of(
            &per_image
                .iter()
                .filter_map(|(_, s)| f(s))
                .collect::<Vec<_>>(),
        )
    };
    Ok(Evaluation {
        images: per_image.len(),
        union_iou: of(&|s| Some(s.union_iou)),
        union_dice: of(&|s| Some(s.union_dice)),
        union_dice_at_offset: of(&|s| Some(s.union_dice_at_offset)),
        instance_dice: of(&|s| Some(s.instance_dice)),
        count_right: Rate::wilson(
            per_image.iter().filter(|(_, s)| s.count_right).count(),
            per_image.len(),
        ),
        labels_found: matched_rate(&per_image, |s| (s.truth_count, s.missed.len())),
        found_labelled: matched_rate(&per_image, |s| (s.predicted_count, s.unlabelled.len())),
        labels_in_pieces: Rate::wilson(
            per_image.iter().map(|(_, s)| s.in_pieces.len()).sum(),
            per_image.iter().map(|(_, s)| s.truth_count).sum(),
        ),
        labelled_length_found: length_share(&per_image, labelled_length_found),
        found_length_labelled: length_share(&per_image, found_length_labelled),
        centerline_px: of(&|s| s.centerline_px),
        grasp_error_px: of(&|s| s.grasp_error_px),
        grasps_near_label: Rate::wilson(
            per_image.iter().map(|(_, s)| s.grasps_near).sum(),
            per_image.iter().map(|(_, s)| s.predicted_count).sum(),
        ),
        first_grasps_near_label: Rate::wilson(
            per_image
                .iter()
                .filter(|(_, s)| s.first_grasp_near == Some(true))
                .count(),
            per_image
                .iter()
                .filter(|(_, s)| s.first_grasp_near.is_some())
                .count(),
        ),
        stage_ms: stage_ms
            .iter()
            .filter_map(|(stage, ms)| Summary::of(ms).map(|s| (*stage, s)))
            .collect(),
        total_ms: stage_ms.remove("total").unwrap_or_default(),
        per_image,
        mask_used,
        notes,
    })
}

/// One image's run: its score, the stages' times, what the pipeline said
/// of it, the cables it found, and the mask it used when it found one (on
/// a labelled mask, none).
struct Run {
    score: ImageScore,
    timings_ms: Vec<(&'static str, f64)>,
    notes: Vec<String>,
    cables: Vec<CableInstance>,
    mask_used: Option<MaskMethod>,
}

/// `image` with the cables found drawn as `detect --overlay` draws them,
/// the labelled centre lines in white over them, and in red, each with its
/// number, the labelled cables that no detection matches (drawn thick) and
/// the detections that match no label.
fn draw_comparison(
    image: &Mat,
    cables: &[CableInstance],
    truth: &GroundTruth,
    image_score: &ImageScore,
) -> opencv::Result<Mat> {
    let red = Scalar::new(0.0, 0.0, 255.0, 0.0);
    let label = |drawn: &mut Mat, text: &str, at: [f64; 2]| {
        // Beside the point, kept inside the image.
        let x = (at[0].round() as i32 + 8).clamp(0, (drawn.cols() - 150).max(0));
        let y = (at[1].round() as i32 - 8).clamp(16, drawn.rows().max(16));
        let at = Point::new(x, y);
        imgproc::put_text(
            drawn,
            text,
            at,
            imgproc::FONT_HERSHEY_SIMPLEX,
            0.6,
            red,
            2,
            imgproc::LINE_AA,
            false,
        )
    };
    let mut drawn = draw_overlay(image, cables)?;
    for line in &truth.polylines_px {
        draw_line(&mut drawn, line, Scalar::all(255.0), 1)?;
    }
    for missed in &image_score.missed {
        let Some(line) = truth.polylines_px.get(missed.index) else {
            continue;
        };
        draw_line(&mut drawn, line, red, 3)?;
        if let Some(&middle) = line.get(line.len() / 2) {
            label(&mut drawn, &format!("#{} not found", missed.index), middle)?;
        }
    }
    for unlabelled in &image_score.unlabelled {
        let cable = &cables[unlabelled.index];
        label(
            &mut drawn,
            &format!("#{} not labelled", unlabelled.index),
            cable.grasp_px,
        )?;
    }
    Ok(drawn)
}

/// The share of one side's cables that the other side matches, from
/// (cables on that side, unmatched ones) per image.
fn matched_rate(
    per_image: &[(String, ImageScore)],
    side: impl Fn(&ImageScore) -> (usize, usize),
) -> Option<Rate> {
    let (all, unmatched) = per_image
        .iter()
        .map(|(_, s)| side(s))
        .fold((0, 0), |(a, u), (n, m)| (a + n, u + m));
    Rate::wilson(all - unmatched, all)
}

/// The labelled length of an image, and how much of it was found.
pub(super) fn labelled_length_found(s: &ImageScore) -> (f64, f64) {
    (s.labelled_length_px, s.labelled_length_found_px)
}

/// The found length of an image, and how much of it is labelled.
pub(super) fn found_length_labelled(s: &ImageScore) -> (f64, f64) {
    (s.found_length_px, s.found_length_labelled_px)
}

fn length_share(
    per_image: &[(String, ImageScore)],
    side: fn(&ImageScore) -> (f64, f64),
) -> Option<LengthShare> {
    let (length_px, near_px) = per_image
        .iter()
        .map(|(_, s)| side(s))
        .fold((0.0, 0.0), |(a, n), (l, m)| (a + l, n + m));
    (length_px > 0.0).then(|| LengthShare {
        share: near_px / length_px,
        length_px,
    })
}
