//! `cablecell bench [--quick] [--json] [--plot FILE]`: the cell's settings
//! on fixed seeds, error against cost with the Pareto front marked, and
//! the latency of each stage of a trial.

use std::path::{Path, PathBuf};

use cablecell::campaign::bench::{
    BenchSize, SettingRow, StageLatency, run_settings, settings, stage_latencies,
};
use cablecell::campaign::run::{Campaign, Overrides};
use cablecell::plot::bench::{ParetoFigure, ParetoPoint};
use schemars::JsonSchema;
use serde::Serialize;

use super::output::outln;
use super::{Status, progress};

/// The campaign whose task, cell and perturbations every setting runs on.
const CAMPAIGN: &str = "tasks/paper-regrasp-campaign.toml";

/// What `bench --json` prints.
#[derive(Serialize, JsonSchema)]
pub struct BenchReport {
    /// The campaign file the trials come from.
    campaign: String,
    /// Campaign seed: trial i of every setting runs with the same seed.
    seed: u64,
    trials_per_setting: usize,
    /// Whether the machine's optimised build ran it (timings of a debug
    /// build are many times slower).
    release_build: bool,
    stages: Vec<StageLatency>,
    settings: Vec<SettingRow>,
}

pub fn bench(quick: bool, json: bool, plot: Option<&Path>) -> Status {
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
    let settings = settings();
    let bar = progress::bar(settings.len() * size.trials, "trials (all settings)");
    let (task, cell, ranges) = (&campaign.task, &campaign.cell, &campaign.file.perturbation);
    let rows = run_settings(task, cell, ranges, &settings, size, || bar.inc(1));
    bar.finish_and_clear();
    let report = BenchReport {
        campaign: CAMPAIGN.to_owned(),
        seed: size.seed,
        trials_per_setting: size.trials,
        release_build: !cfg!(debug_assertions),
        stages: stage_latencies(task, cell, ranges, size),
        settings: rows,
    };
    if let Some(path) = plot {
        let figure = ParetoFigure {
            title: format!(
                "Settings: final |n| against the cell's time ({} trials, seed {})",
                size.trials, size.seed
            ),
            cost_desc: "cell time per trial (s, simulated)".to_owned(),
            error_desc: "final |n| (mm), mean".to_owned(),
            points: report
                .settings
                .iter()
                .filter_map(|row| {
                    Some(ParetoPoint {
                        label: row.setting.clone(),
                        cost: row.cell_s_mean,
                        error: row.final_n_mm_mean?,
                        on_front: row.front_cell_time,
                    })
                })
                .collect(),
        };
        if let Err(error) = cablecell::plot::save(&figure, path) {
            eprintln!("error: {error}");
            return Status::OutputFailed;
        }
    }
    if json {
        return super::json::print(&report);
    }
    print_report(&report);
    Status::Success
}

fn print_report(report: &BenchReport) {
    outln!(
        "{} trials per setting from {} (campaign seed {}; trial i has seed trial_seed({}, i) in every setting), {} build",
        report.trials_per_setting,
        report.campaign,
        report.seed,
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
    outln!();
    outln!(
        "| setting | success | final |n| mm | final |α| rad | fused shape mm | vision shape mm | regrasps | compute ms | cell s | front (cell time) | front (compute) |"
    );
    outln!("|---|---|---|---|---|---|---|---|---|---|---|");
    let cell =
        |v: Option<f64>, digits: usize| v.map_or("–".to_owned(), |v| format!("{v:.digits$}"));
    let mark = |on: bool| if on { "●" } else { "" };
    for row in &report.settings {
        outln!(
            "| {}: {} | {:.0} % | {} | {} | {} | {} | {:.2} | {} | {:.2} | {} | {} |",
            row.group,
            row.setting,
            100.0 * row.success_rate,
            cell(row.final_n_mm_mean, 3),
            cell(row.final_alpha_rad_mean, 4),
            cell(row.fused_shape_mm_mean, 3),
            cell(row.vision_shape_mm_mean, 3),
            row.regrasps_mean,
            cell(row.compute_ms_median, 3),
            row.cell_s_mean,
            mark(row.front_cell_time),
            mark(row.front_compute_time),
        );
    }
    outln!();
    outln!(
        "● on the Pareto front: no other setting is both faster (on that clock) and closer (final |n|)."
    );
}
