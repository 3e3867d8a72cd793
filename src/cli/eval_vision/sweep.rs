//! The sweep: the main settings one after another, in rounds, as a table of
//! run time against error.

use crate::cli::output::outln;
use std::path::PathBuf;

use cablecell::campaign::stats::Summary;
use cablecell::perception::vision::network::{FLOAT_MODEL, MIRRORED_MODEL};
use schemars::JsonSchema;
use serde::Serialize;

use crate::cli::Status;
use crate::cli::labelled_folder::LabelledImage;
use crate::cli::vision_io::{InstancesArg, MaskArg, VisionArgs};

use super::score::{Failure, evaluate, labels_own_dice};
use super::{EvalVisionArgs, Evaluation};
use crate::cli::progress;

/// What `eval-vision --sweep --json` prints.
#[derive(Serialize, JsonSchema)]
pub struct Sweep {
    /// The command line's settings first, then one row per change.
    rows: Vec<SweepRow>,
}

/// One row of the sweep: what it changes and what it scored (`None`:
/// not measured for this row).
#[derive(Serialize, Default, JsonSchema)]
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
/// size, the shipped 8-bit network, the float one it came from or the
/// mirrored one that wraps it, the instance method and the superpixels'
/// size, each varied from the command line's settings. Each row names the
/// network's one input size, so it runs at that size on varied and dark
/// backgrounds too.
fn sweep_settings(base: &VisionArgs) -> Vec<(String, VisionArgs)> {
    let with = |change: &dyn Fn(&mut VisionArgs)| {
        let mut args = base.clone();
        change(&mut args);
        args.close_net_scale = Some(args.net_scale);
        args.busy_net_scale = Some(args.net_scale);
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
    for (kind, model) in [("float", FLOAT_MODEL), ("mirrored", MIRRORED_MODEL)] {
        let model = PathBuf::from(model);
        let file = model.file_name().unwrap_or_default().to_string_lossy();
        settings.push((
            format!("{kind} network at {}×, skeleton ({file})", base.net_scale),
            with(&|a| {
                a.mask = MaskArg::Network;
                a.model = Some(model.clone());
                a.instances = InstancesArg::Skeleton;
            }),
        ));
    }
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

pub(super) fn sweep(args: &EvalVisionArgs, samples: &[LabelledImage]) -> Status {
    let settings = sweep_settings(&args.vision);
    // The first round's evaluations (the pipeline is deterministic, so
    // later rounds score alike), gathering every round's end-to-end times.
    let mut evaluations: Vec<Evaluation> = Vec::with_capacity(settings.len());
    let runs = args.rounds as usize * settings.len() * samples.len();
    let bar = progress::bar(runs, "images (all settings, all rounds)");
    for round in 0..args.rounds {
        for (k, (setting, vision)) in settings.iter().enumerate() {
            bar.set_message(setting.clone());
            let evaluation = match evaluate(vision, samples, false, None, &bar) {
                Ok(evaluation) => evaluation,
                Err(Failure { message, status }) => {
                    bar.finish_and_clear();
                    eprintln!("error: {setting}: {message}");
                    return status;
                }
            };
            if round == 0 {
                evaluations.push(evaluation);
            } else {
                evaluations[k].total_ms.extend(evaluation.total_ms);
            }
        }
    }
    bar.finish_and_clear();
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
        return crate::cli::json::print(Sweep { rows });
    }
    outln!(
        "{}: {} images, timed in {} round(s)",
        args.dir.display(),
        samples.len(),
        args.rounds
    );
    outln!(
        "| setting | median ms | p95 ms | union DICE | count right | labels found | found labelled | length found | found length labelled | grasp px mean | grasp px median | centre line px |"
    );
    outln!("|---|---|---|---|---|---|---|---|---|---|---|---|");
    let cell =
        |v: Option<f64>, digits: usize| v.map_or("–".to_owned(), |v| format!("{v:.digits$}"));
    let percent = |v: Option<f64>| v.map_or("–".to_owned(), |r| format!("{:.0} %", 100.0 * r));
    for row in &rows {
        outln!(
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
