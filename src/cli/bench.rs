//! `cablecell bench [--quick] [--json] [--plot FILE] [--photos DIR]`: the
//! cell's settings on fixed seeds and the vision pipeline's on fixed
//! rendered images (and photographs when given), error against cost with
//! the Pareto fronts marked, and the latency of each stage.

use std::path::{Path, PathBuf};

use cablecell::campaign::bench::cell::ShapeColumns;
use cablecell::campaign::bench::vision::{
    DEFAULT_SETTING, ImageSet, SkipSaving, VisionBenchError, VisionRow, photographs, rendered_set,
    run_vision, skip_saving, skip_settings, vision_settings,
};
use cablecell::campaign::bench::{
    BenchSize, SettingRow, StageLatency, run_settings, settings, stage_latencies,
};
use cablecell::campaign::run::{Campaign, Overrides};
use cablecell::perception::vision::network::{BUSY_MODEL, DEFAULT_MODEL, runtime_library};
use cablecell::plot::bench::{ParetoFigure, ParetoPanel, ParetoPoint};
use cablecell::sim::render::BackgroundChoice;
use schemars::JsonSchema;
use serde::Serialize;

use super::output::outln;
use super::{Status, progress};

/// The campaign whose task, cell and perturbations every setting runs on.
const CAMPAIGN: &str = "tasks/paper-regrasp-campaign.toml";

/// The vision rows' image sets.
const RENDERED: &str = "rendered, any background";
const RENDERED_PLAIN: &str = "rendered, plain backgrounds";

/// What `bench --json` prints.
#[derive(Serialize, JsonSchema)]
pub struct BenchReport {
    /// The campaign file the trials come from.
    campaign: String,
    /// Campaign seed: trial i of every setting runs with the same seed.
    /// Also the renderer's seed: rendered image i is stream i of it.
    seed: u64,
    trials_per_setting: usize,
    /// Rendered images per vision setting and image set.
    rendered_images: usize,
    /// Whether the machine's optimised build ran it (timings of a debug
    /// build are many times slower).
    release_build: bool,
    stages: Vec<StageLatency>,
    settings: Vec<SettingRow>,
    /// The vision pipeline's settings, by image set: rendered scenes on
    /// any background, rendered plain ones with each skip taken and
    /// forced off, and the photographs given with `--photos`.
    vision: Vec<VisionRow>,
    /// On the plain rendered images, each skip's time saved and the error
    /// with and without it, image by image where it was taken.
    skip_savings: Vec<SkipSaving>,
}

pub fn bench(quick: bool, json: bool, plot: Option<&Path>, photos: Option<&Path>) -> Status {
    let size = if quick {
        BenchSize::QUICK
    } else {
        BenchSize::FULL
    };
    let overrides = Overrides {
        trials: Some(size.trials),
        seed: Some(size.seed),
        out: Some(PathBuf::from("unused")),
        no_record: true,
        shard: None,
    };
    let campaign = match Campaign::load(Path::new(CAMPAIGN), overrides) {
        Ok(campaign) => campaign,
        Err(error) => {
            eprintln!("error: {error} (run bench from the repository's root)");
            return Status::BadInput;
        }
    };
    let photographs = match photos.map(photographs).transpose() {
        Ok(set) => set,
        Err(error) => {
            eprintln!("error: {error}");
            return Status::BadInput;
        }
    };
    let settings = settings();
    let bar = progress::bar(settings.len() * size.trials, "trials (all settings)");
    let (task, cell, ranges) = (&campaign.task, &campaign.cell, &campaign.file.perturbation);
    let rows = run_settings(task, cell, ranges, &settings, size, || bar.inc(1));
    bar.finish_and_clear();
    let mut stages = stage_latencies(task, cell, ranges, size);
    let vision = match vision_rows(size, photographs.as_ref()) {
        Ok(vision) => vision,
        Err(error) => {
            eprintln!("error: {error}");
            return match error {
                VisionBenchError::Pipeline { source, .. } if !source.is_in_setup() => {
                    Status::TaskFailed
                }
                _ => Status::BadInput,
            };
        }
    };
    // The default pipeline's stages, on the rendered images.
    if let Some(default) = vision
        .iter()
        .find(|row| row.images == RENDERED && row.setting.starts_with(DEFAULT_SETTING))
    {
        stages.extend(default.stages.iter().map(|stage| StageLatency {
            stage: format!("vision (default): {}", stage.stage),
            ..stage.clone()
        }));
    }
    // The plain set's rows are `skip_settings`' in order: auto, the
    // network on every image (the default), the default on a region of
    // interest.
    let plain: Vec<&VisionRow> = vision
        .iter()
        .filter(|row| row.images == RENDERED_PLAIN)
        .collect();
    let skip_savings = match plain[..] {
        [auto, default, roi] => [
            skip_saving("network", auto, default),
            skip_saving("image_outside_roi", roi, default),
        ]
        .into_iter()
        .flatten()
        .collect(),
        _ => Vec::new(),
    };
    let report = BenchReport {
        campaign: CAMPAIGN.to_owned(),
        seed: size.seed,
        trials_per_setting: size.trials,
        rendered_images: size.images,
        release_build: !cfg!(debug_assertions),
        stages,
        settings: rows,
        vision,
        skip_savings,
    };
    if let Some(path) = plot
        && let Err(error) = cablecell::plot::save(&figure(&report), path)
    {
        eprintln!("error: {error}");
        return Status::OutputFailed;
    }
    if json {
        return super::json::print(&report);
    }
    print_report(&report);
    Status::Success
}

/// The vision settings on the rendered images, the skips on plain ones,
/// and the settings on the photographs when given.
fn vision_rows(
    size: BenchSize,
    photographs: Option<&ImageSet>,
) -> Result<Vec<VisionRow>, VisionBenchError> {
    let rendered = rendered_set(RENDERED, size.images, size.seed, BackgroundChoice::Any)?;
    let plain = rendered_set(
        RENDERED_PLAIN,
        size.images,
        size.seed,
        BackgroundChoice::Plain,
    )?;
    let (settings, skips) = (vision_settings(), skip_settings());
    let mut runs: Vec<(&ImageSet, &[_])> = vec![(&rendered, &settings), (&plain, &skips)];
    runs.extend(photographs.map(|set| (set, &settings[..])));
    let images: usize = runs.iter().map(|(set, s)| set.images.len() * s.len()).sum();
    let bar = progress::bar(images, "images (all vision settings)");
    let model = Path::new(DEFAULT_MODEL);
    let runtime = runtime_library(None);
    let mut rows = Vec::new();
    for (set, settings) in runs {
        rows.extend(run_vision(
            set,
            settings,
            model,
            Some(Path::new(BUSY_MODEL)),
            &runtime,
            || bar.inc(1),
        )?);
    }
    bar.finish_and_clear();
    Ok(rows)
}

fn figure(report: &BenchReport) -> ParetoFigure {
    let cell = ParetoPanel {
        title: "the cell's settings: final |n| (mm, mean) against the cell's time per trial (s)"
            .to_owned(),
        cost_desc: "cell time per trial (s, simulated)".to_owned(),
        error_desc: "final |n| (mm), mean".to_owned(),
        // The camera-started trials are other trials, with their own front.
        points: report
            .settings
            .iter()
            .filter(|row| !row.started_from_camera)
            .filter_map(|row| {
                Some(ParetoPoint {
                    label: format!("{}: {}", row.group, row.setting),
                    cost: row.cell_s_mean,
                    error: row.final_n_mm_mean?,
                    on_front: row.front_cell_time,
                })
            })
            .collect(),
    };
    let mut sets: Vec<&str> = Vec::new();
    for row in &report.vision {
        if !sets.contains(&row.images.as_str()) {
            sets.push(&row.images);
        }
    }
    let vision = sets.into_iter().map(|set| ParetoPanel {
        title: format!("vision on {set}: 1 − union DICE against the time per image (ms)"),
        cost_desc: "time per image (ms, median)".to_owned(),
        error_desc: "1 − union DICE, mean".to_owned(),
        points: report
            .vision
            .iter()
            .filter(|row| row.images == set)
            .filter_map(|row| {
                Some(ParetoPoint {
                    label: format!("{}: {}", row.group, row.setting),
                    cost: row.ms_median?,
                    error: 1.0 - row.union_dice_mean,
                    on_front: row.front,
                })
            })
            .collect(),
    });
    ParetoFigure {
        title: format!(
            "Bench: error against cost ({} trials a setting, {} rendered images, seed {})",
            report.trials_per_setting, report.rendered_images, report.seed
        ),
        panels: std::iter::once(cell).chain(vision).collect(),
    }
}

fn print_report(report: &BenchReport) {
    outln!(
        "{} trials per setting from {} (campaign seed {}; trial i has seed trial_seed({}, i) in every setting), {} rendered images per vision setting (renderer seed {}), {} build",
        report.trials_per_setting,
        report.campaign,
        report.seed,
        report.seed,
        report.rendered_images,
        report.seed,
        if report.release_build {
            "release"
        } else {
            "debug"
        }
    );
    outln!();
    outln!("| stage | median µs | p95 µs |");
    outln!("|---|---|---|");
    for stage in &report.stages {
        outln!(
            "| {} | {:.1} | {:.1} |",
            stage.stage,
            stage.median_us,
            stage.p95_us
        );
    }
    let cell =
        |v: Option<f64>, digits: usize| v.map_or("–".to_owned(), |v| format!("{v:.digits$}"));
    let mark = |on: bool| if on { "●" } else { "" };
    outln!();
    outln!(
        "| setting | success | final |n| mm | final |α| rad | shape on pad mm: vision / touch / fused | beyond pad mm: vision / touch / fused | regrasps | compute ms | cell s | front (cell time) | front (compute) |"
    );
    outln!("|---|---|---|---|---|---|---|---|---|---|---|");
    let shapes = |s: &ShapeColumns| {
        format!(
            "{} / {} / {}",
            cell(s.vision_mm_mean, 2),
            cell(s.touch_mm_mean, 2),
            cell(s.fused_mm_mean, 2)
        )
    };
    for row in &report.settings {
        outln!(
            "| {}: {} | {:.0} % | {} | {} | {} | {} | {:.2} | {} | {:.2} | {} | {} |",
            row.group,
            row.setting,
            100.0 * row.success_rate,
            cell(row.final_n_mm_mean, 3),
            cell(row.final_alpha_rad_mean, 4),
            shapes(&row.shape_on_pad),
            shapes(&row.shape_beyond_pad),
            row.regrasps_mean,
            cell(row.compute_ms_median, 3),
            row.cell_s_mean,
            mark(row.front_cell_time),
            mark(row.front_compute_time),
        );
    }
    outln!();
    outln!(
        "● on the Pareto front: no other setting of the same start (the oracle's offset, or the camera) is both faster (on that clock) and closer (final |n|)."
    );
    outln!();
    outln!(
        "| images | setting | union DICE | count right | grasp px | median ms | p95 ms | skipped (images) | front |"
    );
    outln!("|---|---|---|---|---|---|---|---|---|");
    for row in &report.vision {
        let skipped: Vec<String> = row
            .skipped
            .iter()
            .map(|(skip, images)| format!("{skip} {images}"))
            .collect();
        outln!(
            "| {} | {}: {} | {:.3} | {:.0} % | {} | {} | {} | {} | {} |",
            row.images,
            row.group,
            row.setting,
            row.union_dice_mean,
            100.0 * row.count_right_rate,
            cell(row.grasp_error_px_mean, 1),
            cell(row.ms_median, 1),
            cell(row.ms_p95, 1),
            skipped.join(", "),
            mark(row.front),
        );
    }
    outln!();
    outln!(
        "● on the Pareto front of its images: no other setting is both faster (median) and closer (union DICE)."
    );
    outln!();
    outln!(
        "| skip, on the images that took it | images | median ms with / without | saved ms (median) | union DICE with / without | count right with / without |"
    );
    outln!("|---|---|---|---|---|---|");
    for saving in &report.skip_savings {
        outln!(
            "| {} ({}) | {} | {:.1} / {:.1} | {:.1} | {:.3} / {:.3} | {} / {} |",
            saving.skip,
            saving.images,
            saving.image_count,
            saving.ms_with_median,
            saving.ms_without_median,
            saving.ms_saved_median,
            saving.union_dice_with_mean,
            saving.union_dice_without_mean,
            saving.count_right_with,
            saving.count_right_without,
        );
    }
}
