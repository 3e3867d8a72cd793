//! `cablecell eval-vision DIR [--from STEM] [--to STEM] [--sweep [--rounds N]]`

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use cablecell::campaign::stats::{Rate, Summary};
use cablecell::hw::camera::read_image;
use cablecell::perception::vision::eval::{
    CENTRELINE_NEAR_PX, GroundTruth, ImageScore, MASK_OFFSET_SEARCH_PX, Unmatched,
    label_consistency, score,
};
use cablecell::perception::vision::network::FLOAT_MODEL;
use cablecell::perception::vision::{MaskMethod, MaskNetwork, VisionOutput};
use clap::Args;
use opencv::core::{Mat, Point, Scalar};
use opencv::imgproc;
use opencv::prelude::*;
use serde::Serialize;

use super::Status;
use super::vision_io::{
    InstancesArg, MaskArg, VisionArgs, create_dir, draw_line, draw_overlay, write_png,
};

#[derive(Args, Debug, Clone)]
pub struct EvalVisionArgs {
    pub dir: PathBuf,
    #[command(flatten)]
    pub vision: VisionArgs,
    /// Score only images whose name sorts at or after this, e.g. 00030.
    #[arg(long)]
    pub from: Option<String>,
    /// Score only images whose name sorts at or before this, e.g. 00044.
    #[arg(long)]
    pub to: Option<String>,
    /// Score the main settings (mask method, network input size, 8-bit or
    /// float network, instance method, superpixel size) one after another
    /// and print a table of run time against error; the other vision
    /// options set what a row does not.
    #[arg(long)]
    pub sweep: bool,
    /// With --sweep: time the settings in this many rounds, taking turns,
    /// and give each one's median and 95th percentile over all rounds. A
    /// machine's speed drifts over minutes; rounds spread the drift over
    /// every setting instead of loading it onto a few.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..))]
    pub rounds: u32,
    /// Write each image, as DIR/NAME.png, with the cables found drawn on
    /// it as `detect --overlay` draws them, the labelled centre lines in
    /// white, and in red the labelled cables not found and the found ones
    /// not labelled.
    #[arg(long, value_name = "DIR", conflicts_with = "sweep")]
    pub overlay: Option<PathBuf>,
    #[arg(long)]
    pub json: bool,
}

#[derive(Serialize)]
struct Evaluation {
    images: usize,
    union_iou: Option<Summary>,
    union_dice: Option<Summary>,
    /// The union DICE with each image's found mask moved by its
    /// [`ImageScore::mask_offset_px`].
    union_dice_at_offset: Option<Summary>,
    instance_dice: Option<Summary>,
    count_right: Option<Rate>,
    /// Labelled cables that a detection matches, over all images.
    labels_found: Option<Rate>,
    /// Detections that match a labelled cable, over all images.
    found_labelled: Option<Rate>,
    /// The labelled centre lines' length near a found one, over all images.
    labelled_length_found: Option<LengthShare>,
    /// The found centre lines' length near a labelled one, over all images.
    found_length_labelled: Option<LengthShare>,
    centerline_px: Option<Summary>,
    grasp_error_px: Option<Summary>,
    /// Per stage, and "total": median and 95th percentile among the rest.
    stage_ms: BTreeMap<&'static str, Summary>,
    /// Each image's end-to-end time, in order; the sweep adds its later
    /// rounds' times here.
    #[serde(skip)]
    total_ms: Vec<f64>,
    per_image: Vec<(String, ImageScore)>,
    /// How many images each mask ran on: `auto` chooses per image.
    mask_used: MaskUse,
    /// What the pipeline said about an image (fallbacks taken, detections
    /// dropped as edges or as cables too little in view), by image.
    notes: Vec<(String, String)>,
}

/// Images by the mask that ran on them.
#[derive(Serialize, Default)]
struct MaskUse {
    classical: usize,
    network: usize,
}

/// The labels' own union DICE: their centre lines drawn `width_px` wide
/// against their masks, a reference for the pipeline's union DICE.
#[derive(Serialize)]
struct LabelsOwnDice {
    width_px: f64,
    union_dice: Summary,
}

#[derive(Serialize)]
struct Report {
    #[serde(flatten)]
    evaluation: Evaluation,
    labels_own_union_dice: Option<LabelsOwnDice>,
}

/// An image with its ground truth, read once for all settings.
struct Sample {
    stem: String,
    path: PathBuf,
    image: Mat,
    truth: GroundTruth,
}

pub fn eval_vision(args: &EvalVisionArgs) -> Status {
    let samples = match load_samples(args) {
        Ok(samples) => samples,
        Err(messages) => {
            for message in messages {
                eprintln!("error: {message}");
            }
            return Status::BadInput;
        }
    };
    if args.sweep {
        return sweep(args, &samples);
    }
    let report = evaluate(&args.vision, &samples, args.overlay.as_deref()).and_then(|evaluation| {
        Ok(Report {
            evaluation,
            labels_own_union_dice: labels_own_dice(&samples)?,
        })
    });
    let report = match report {
        Ok(report) => report,
        Err(message) => {
            eprintln!("error: {message}");
            return Status::TaskFailed;
        }
    };
    if args.json {
        print_json(&report)
    } else {
        print_evaluation(&args.dir, &report);
        Status::Success
    }
}

fn labels_own_dice(samples: &[Sample]) -> Result<Option<LabelsOwnDice>, String> {
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

fn print_json(value: &impl Serialize) -> Status {
    match serde_json::to_string_pretty(value) {
        Ok(text) => {
            println!("{text}");
            Status::Success
        }
        Err(error) => {
            eprintln!("error: cannot write the evaluation as JSON: {error}");
            Status::OutputFailed
        }
    }
}

/// The selected images of the folder and their truth, or what is wrong:
/// with every image that cannot be read or whose truth is malformed, so
/// that one run lists all there is to mend.
fn load_samples(args: &EvalVisionArgs) -> Result<Vec<Sample>, Vec<String>> {
    let dir = &args.dir;
    let stems = image_stems(dir).map_err(|error| {
        vec![format!(
            "{}: cannot list the folder: {error}",
            dir.display()
        )]
    })?;
    let selected: Vec<_> = stems
        .into_iter()
        .filter(|(stem, _)| args.from.as_ref().is_none_or(|from| stem >= from))
        .filter(|(stem, _)| args.to.as_ref().is_none_or(|to| stem <= to))
        .collect();
    if selected.is_empty() {
        return Err(vec![format!(
            "{}: no NNNNN.jpg images with NNNNN_mask_all.png beside them{}",
            dir.display(),
            match (&args.from, &args.to) {
                (None, None) => String::new(),
                (from, to) => format!(
                    " between {} and {}",
                    from.as_deref().unwrap_or("the first"),
                    to.as_deref().unwrap_or("the last")
                ),
            }
        )]);
    }
    let mut samples = Vec::new();
    let mut errors = Vec::new();
    for (stem, path) in selected {
        let image = read_image(&path);
        let truth = GroundTruth::load(dir, &stem).and_then(|truth| match &image {
            Ok(image) => truth.check_fits(image, &path, dir, &stem).map(|()| truth),
            Err(_) => Ok(truth),
        });
        let truth = truth.map_err(|error| format!("{}: {stem}: {error}", dir.display()));
        match (image, truth) {
            (Ok(image), Ok(truth)) => samples.push(Sample {
                stem,
                path,
                image,
                truth,
            }),
            (image, truth) => errors.extend(
                image
                    .err()
                    .map(|error| error.to_string())
                    .into_iter()
                    .chain(truth.err()),
            ),
        }
    }
    if errors.is_empty() {
        Ok(samples)
    } else {
        Err(errors)
    }
}

/// Runs the pipeline configured by `vision` on every sample and scores it,
/// drawing each result into `overlay` when given. The first image is run
/// once untimed before the loop, so that loading the network and first-use
/// allocations are not counted as its time.
fn evaluate(
    vision: &VisionArgs,
    samples: &[Sample],
    overlay: Option<&Path>,
) -> Result<Evaluation, String> {
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
        if k == 0 {
            pipeline
                .detect(&sample.image, Some(&mut network as &mut dyn MaskNetwork))
                .map_err(|error| format!("{}: {error}", sample.path.display()))?;
        }
        let output = pipeline
            .detect(&sample.image, Some(&mut network as &mut dyn MaskNetwork))
            .map_err(|error| format!("{}: {error}", sample.path.display()))?;
        for (stage, ms) in &output.timings_ms {
            stage_ms.entry(stage).or_default().push(*ms);
        }
        stage_ms
            .entry("total")
            .or_default()
            .push(output.timings_ms.iter().map(|(_, ms)| ms).sum());
        let image_score = score(&output, &sample.truth)
            .map_err(|error| format!("{}: {error}", sample.path.display()))?;
        if let Some(dir) = overlay {
            let drawn = draw_comparison(&sample.image, &output, &sample.truth, &image_score)
                .map_err(|e| format!("cannot draw the overlay of {}: {e}", sample.stem))?;
            write_png(&dir.join(format!("{}.png", sample.stem)), &drawn)?;
        }
        per_image.push((sample.stem.clone(), image_score));
        match output.mask_used {
            MaskMethod::Network => mask_used.network += 1,
            _ => mask_used.classical += 1,
        }
        notes.extend(
            output
                .notes
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
        labelled_length_found: length_share(&per_image, labelled_length_found),
        found_length_labelled: length_share(&per_image, found_length_labelled),
        centerline_px: of(&|s| s.centerline_px),
        grasp_error_px: of(&|s| s.grasp_error_px),
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

/// `image` with the cables found drawn as `detect --overlay` draws them,
/// the labelled centre lines in white over them, and in red, each with its
/// number, the labelled cables that no detection matches (drawn thick) and
/// the detections that match no label.
fn draw_comparison(
    image: &Mat,
    output: &VisionOutput,
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
    let mut drawn = draw_overlay(image, output)?;
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
        let cable = &output.cables[unlabelled.index];
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

/// How much of one side's centre-line length lies within
/// [`CENTRELINE_NEAR_PX`] of the other side's.
#[derive(Serialize)]
struct LengthShare {
    share: f64,
    length_px: f64,
}

/// The labelled length of an image, and how much of it was found.
fn labelled_length_found(s: &ImageScore) -> (f64, f64) {
    (s.labelled_length_px, s.labelled_length_found_px)
}

/// The found length of an image, and how much of it is labelled.
fn found_length_labelled(s: &ImageScore) -> (f64, f64) {
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

/// One row of the sweep: what it changes and what it scored (`None`:
/// not measured for this row).
#[derive(Serialize, Default)]
struct SweepRow {
    setting: String,
    total_ms_median: Option<f64>,
    total_ms_p95: Option<f64>,
    union_dice: Option<f64>,
    count_right: Option<f64>,
    labels_found: Option<f64>,
    found_labelled: Option<f64>,
    labelled_length_found: Option<f64>,
    found_length_labelled: Option<f64>,
    grasp_error_px_mean: Option<f64>,
    grasp_error_px_median: Option<f64>,
    centerline_px: Option<f64>,
}

/// The settings the sweep compares: the mask method, the network's input
/// size, the shipped 8-bit network or the float one it came from, the
/// instance method and the superpixels' size, each varied from
/// the command line's settings.
fn sweep_settings(base: &VisionArgs) -> Vec<(String, VisionArgs)> {
    let with = |change: &dyn Fn(&mut VisionArgs)| {
        let mut args = base.clone();
        change(&mut args);
        args
    };
    let mut settings = vec![(
        "classical mask, skeleton".to_owned(),
        with(&|a| {
            a.mask = MaskArg::Classical;
            a.instances = InstancesArg::Skeleton;
        }),
    )];
    for scale in [0.375, 0.5, 0.75] {
        settings.push((
            format!("network at {scale}×, skeleton"),
            with(&|a| {
                a.mask = MaskArg::Network;
                a.net_scale = scale;
                a.instances = InstancesArg::Skeleton;
            }),
        ));
    }
    settings.push((
        format!(
            "float network at {}×, skeleton (cable_segmentation_float.onnx)",
            base.net_scale
        ),
        with(&|a| {
            a.mask = MaskArg::Network;
            a.model = PathBuf::from(FLOAT_MODEL);
            a.instances = InstancesArg::Skeleton;
        }),
    ));
    for widths in [1.5, 2.0, 3.0] {
        settings.push((
            format!(
                "network at {}×, superpixels {widths} widths",
                base.net_scale
            ),
            with(&|a| {
                a.mask = MaskArg::Network;
                a.instances = InstancesArg::Superpixels;
                a.superpixel_widths = widths;
            }),
        ));
    }
    settings
}

fn sweep(args: &EvalVisionArgs, samples: &[Sample]) -> Status {
    let settings = sweep_settings(&args.vision);
    // The first round's evaluations (the pipeline is deterministic, so
    // later rounds score alike), gathering every round's end-to-end times.
    let mut evaluations: Vec<Evaluation> = Vec::with_capacity(settings.len());
    for round in 0..args.rounds {
        for (k, (setting, vision)) in settings.iter().enumerate() {
            let evaluation = match evaluate(vision, samples, None) {
                Ok(evaluation) => evaluation,
                Err(message) => {
                    eprintln!("error: {setting}: {message}");
                    return Status::TaskFailed;
                }
            };
            if round == 0 {
                evaluations.push(evaluation);
            } else {
                evaluations[k].total_ms.extend(evaluation.total_ms);
            }
        }
    }
    let mut rows = Vec::new();
    for ((setting, _), evaluation) in settings.into_iter().zip(evaluations) {
        let total = Summary::of(&evaluation.total_ms);
        rows.push(SweepRow {
            setting,
            total_ms_median: total.as_ref().map(|s| s.median),
            total_ms_p95: total.as_ref().map(|s| s.p95),
            union_dice: evaluation.union_dice.map(|s| s.mean),
            count_right: evaluation.count_right.map(|r| r.rate),
            labels_found: evaluation.labels_found.map(|r| r.rate),
            found_labelled: evaluation.found_labelled.map(|r| r.rate),
            labelled_length_found: evaluation.labelled_length_found.map(|l| l.share),
            found_length_labelled: evaluation.found_length_labelled.map(|l| l.share),
            grasp_error_px_mean: evaluation.grasp_error_px.as_ref().map(|s| s.mean),
            grasp_error_px_median: evaluation.grasp_error_px.as_ref().map(|s| s.median),
            centerline_px: evaluation.centerline_px.map(|s| s.mean),
        });
    }
    // The labels' agreement with themselves, for scale in the DICE column.
    match labels_own_dice(samples) {
        Ok(Some(labels)) => rows.push(SweepRow {
            setting: format!(
                "labels' own centre lines, smoothed, drawn {:.1} px wide",
                labels.width_px
            ),
            union_dice: Some(labels.union_dice.mean),
            ..SweepRow::default()
        }),
        Ok(None) => {}
        Err(message) => {
            eprintln!("error: {message}");
            return Status::TaskFailed;
        }
    }
    if args.json {
        return print_json(&rows);
    }
    println!(
        "{}: {} images, timed in {} round(s)",
        args.dir.display(),
        samples.len(),
        args.rounds
    );
    println!(
        "| setting | median ms | p95 ms | union DICE | count right | labels found | found labelled | length found | found length labelled | grasp px mean | grasp px median | centre line px |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|");
    let cell =
        |v: Option<f64>, digits: usize| v.map_or("–".to_owned(), |v| format!("{v:.digits$}"));
    let percent = |v: Option<f64>| v.map_or("–".to_owned(), |r| format!("{:.0} %", 100.0 * r));
    for row in &rows {
        println!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            row.setting,
            cell(row.total_ms_median, 1),
            cell(row.total_ms_p95, 1),
            cell(row.union_dice, 3),
            percent(row.count_right),
            percent(row.labels_found),
            percent(row.found_labelled),
            percent(row.labelled_length_found),
            percent(row.found_length_labelled),
            cell(row.grasp_error_px_mean, 1),
            cell(row.grasp_error_px_median, 1),
            cell(row.centerline_px, 1),
        );
    }
    Status::Success
}

/// Images whose share is lower than this are named, lowest first.
const LOW_LENGTH_SHARE: f64 = 0.9;

/// A [`LengthShare`] and the images where it was lowest.
fn print_length_share(
    name: &str,
    what: &str,
    share: &Option<LengthShare>,
    per_image: &[(String, ImageScore)],
    side: fn(&ImageScore) -> (f64, f64),
) {
    let Some(share) = share else {
        return;
    };
    let mut low: Vec<(&str, f64)> = per_image
        .iter()
        .filter_map(|(stem, s)| {
            let (length_px, near_px) = side(s);
            (length_px > 0.0)
                .then(|| near_px / length_px)
                .filter(|&image_share| image_share < LOW_LENGTH_SHARE)
                .map(|image_share| (stem.as_str(), image_share))
        })
        .collect();
    low.sort_by(|a, b| a.1.total_cmp(&b.1));
    let low: Vec<String> = low
        .iter()
        .map(|(stem, image_share)| format!("{stem} {:.0} %", 100.0 * image_share))
        .collect();
    let lowest = if low.is_empty() {
        String::new()
    } else {
        format!(
            "; under {:.0} % in {}",
            100.0 * LOW_LENGTH_SHARE,
            low.join(", ")
        )
    };
    println!(
        "  {name:<22} {:.1} % of {:.0} px {what} (within {CENTRELINE_NEAR_PX} px){lowest}",
        100.0 * share.share,
        share.length_px
    );
}

/// A summary as printed: mean, median, 95th percentile and maximum.
fn summary(s: &Summary) -> String {
    format!(
        "mean {:.3}  median {:.3}  p95 {:.3}  max {:.3}",
        s.mean, s.median, s.p95, s.max
    )
}

fn print_evaluation(dir: &Path, report: &Report) {
    let e = &report.evaluation;
    println!("{}: {} images", dir.display(), e.images);
    let line = |name: &str, s: &Option<Summary>| {
        if let Some(s) = s {
            println!("  {name:<22} {}", summary(s));
        }
    };
    line("union IoU", &e.union_iou);
    line("union DICE", &e.union_dice);
    print_offsets(&e.union_dice_at_offset, &e.per_image);
    if let Some(labels) = &report.labels_own_union_dice {
        println!(
            "  {:<22} {}  (the labelled centre lines, smoothed as the masks were drawn, {:.1} px wide against the labelled masks)",
            "labels' own union DICE",
            summary(&labels.union_dice),
            labels.width_px
        );
    }
    line("instance DICE", &e.instance_dice);
    if let Some(rate) = &e.count_right {
        println!(
            "  {:<22} {}/{} = {:.0} % [{:.0}, {:.0}] (95 % CI)",
            "instance count right",
            rate.successes,
            rate.trials,
            100.0 * rate.rate,
            100.0 * rate.ci95_low,
            100.0 * rate.ci95_high
        );
    }
    let miscounted: Vec<String> = e
        .per_image
        .iter()
        .filter(|(_, score)| !score.count_right)
        .map(|(stem, score)| {
            format!(
                "{stem} ({} found, {} labelled)",
                score.predicted_count, score.truth_count
            )
        })
        .collect();
    if !miscounted.is_empty() {
        println!("  {:<22} {}", "count wrong in", miscounted.join(", "));
    }
    print_unmatched(
        "labelled, not found",
        e.per_image
            .iter()
            .map(|(stem, s)| (stem, s.truth_count, &s.missed)),
    );
    print_unmatched(
        "found, not labelled",
        e.per_image
            .iter()
            .map(|(stem, s)| (stem, s.predicted_count, &s.unlabelled)),
    );
    print_length_share(
        "labelled length found",
        "of the labelled centre lines, near a found one",
        &e.labelled_length_found,
        &e.per_image,
        labelled_length_found,
    );
    print_length_share(
        "found length labelled",
        "of the found centre lines, near a labelled one",
        &e.found_length_labelled,
        &e.per_image,
        found_length_labelled,
    );
    line("centerline px", &e.centerline_px);
    line("grasp error px", &e.grasp_error_px);
    println!(
        "  {:<22} classical in {}, network in {} of the images",
        "mask used", e.mask_used.classical, e.mask_used.network
    );
    for (stage, s) in &e.stage_ms {
        println!(
            "  {:<22} median {:.2} ms  p95 {:.2} ms",
            format!("{stage} time"),
            s.median,
            s.p95
        );
    }
    for (stem, note) in &e.notes {
        println!("  note: {stem}: {note}");
    }
}

/// Images whose found mask moves this far (px, along either axis) to
/// match its labels best are named.
const LARGE_OFFSET_PX: i32 = 2;

/// The union DICE with the found masks moved onto the labels, the median
/// move, and the images moved [`LARGE_OFFSET_PX`] or more.
fn print_offsets(dice: &Option<Summary>, per_image: &[(String, ImageScore)]) {
    let Some(dice) = dice else {
        return;
    };
    let median_px = |axis: usize| {
        let moves: Vec<f64> = per_image
            .iter()
            .map(|(_, s)| f64::from(s.mask_offset_px[axis]))
            .collect();
        Summary::of(&moves).map_or(0.0, |s| s.median)
    };
    let large: Vec<String> = per_image
        .iter()
        .filter(|(_, s)| s.mask_offset_px.iter().any(|d| d.abs() >= LARGE_OFFSET_PX))
        .map(|(stem, s)| format!("{stem} ({}, {})", s.mask_offset_px[0], s.mask_offset_px[1]))
        .collect();
    let large = if large.is_empty() {
        String::new()
    } else {
        format!("; {LARGE_OFFSET_PX} px or more in {}", large.join(", "))
    };
    println!(
        "  {:<22} {}  (each image's found mask moved by the whole pixels, up to {MASK_OFFSET_SEARCH_PX}, that match its labels best; median move (dx, dy) ({}, {}) px{large})",
        "union DICE, moved",
        summary(dice),
        median_px(0),
        median_px(1),
    );
}

/// One line listing the cables of one side that none of the other side
/// matches, from (image, cables on that side, unmatched ones) per image:
/// "3 of 83: 00034 #7 (52 px, at the border), ...".
fn print_unmatched<'a>(
    what: &str,
    per_image: impl Iterator<Item = (&'a String, usize, &'a Vec<Unmatched>)>,
) {
    let (mut total, mut listed) = (0, Vec::new());
    for (stem, count, unmatched) in per_image {
        total += count;
        listed.extend(unmatched.iter().map(|u| {
            let length = u
                .length_px
                .map_or("no line".to_string(), |l| format!("{l:.0} px"));
            let border = if u.at_border { ", at the border" } else { "" };
            format!("{stem} #{} ({length}{border})", u.index)
        }));
    }
    if total > 0 {
        let of = format!("{} of {total}", listed.len());
        let list = if listed.is_empty() {
            String::new()
        } else {
            format!(": {}", listed.join(", "))
        };
        println!("  {what:<22} {of}{list}");
    }
}

/// (stem, image path) of every image with a union mask beside it, sorted.
fn image_stems(dir: &Path) -> std::io::Result<Vec<(String, PathBuf)>> {
    let mut stems = Vec::new();
    for entry in std::fs::read_dir(dir)? {
        let path = entry?.path();
        let is_image = path.extension().is_some_and(|e| e == "jpg" || e == "png");
        let Some(stem) = path.file_stem().map(|s| s.to_string_lossy().into_owned()) else {
            continue;
        };
        if is_image
            && !stem.contains("_mask_")
            && dir.join(format!("{stem}_mask_all.png")).is_file()
        {
            stems.push((stem, path));
        }
    }
    stems.sort();
    Ok(stems)
}
