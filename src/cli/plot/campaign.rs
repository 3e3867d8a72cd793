//! `cablecell plot campaign FOLDER`: a campaign's journal as
//! distributions, with the campaign's own statistics (the Wilson interval
//! of the success rate, the regrasps per trial).

use std::path::{Path, PathBuf};

use cablecell::campaign::journal;
use cablecell::campaign::stats::five_numbers;
use cablecell::campaign::summary::summarise;
use cablecell::campaign::trial::TrialEntry;
use cablecell::geometry::PoseError;
use cablecell::plot::campaign::{CampaignFigure, PolicyResults, Spread, SuccessRate};

use super::{Failure, write};

/// The journal a campaign writes into its output folder.
const JOURNAL: &str = "trials.jsonl";

pub(super) fn campaign(folder: &Path, out: Option<&Path>) -> Result<PathBuf, Failure> {
    if !folder.is_dir() {
        return Err(Failure::BadInput(format!(
            "{}: not a folder: give a campaign's output folder (`cablecell campaign` writes its {JOURNAL} there)",
            folder.display()
        )));
    }
    let path = folder.join(JOURNAL);
    if !path.is_file() {
        return Err(Failure::BadInput(format!(
            "{}: no {JOURNAL}: not a campaign's output folder",
            folder.display()
        )));
    }
    let entries = journal::read::<TrialEntry>(&path)
        .map_err(|e| Failure::BadInput(e.to_string()))?
        .entries;
    let Some(first) = entries.first() else {
        return Err(Failure::BadInput(format!(
            "{}: holds no finished trial yet",
            path.display()
        )));
    };
    // The policies as the journal first names them: the campaign file's
    // order, unless threads finished trial 0 of a later policy first.
    let mut policies: Vec<String> = Vec::new();
    for entry in &entries {
        if !policies.contains(&entry.policy) {
            policies.push(entry.policy.clone());
        }
    }
    let trials = entries.iter().map(|e| e.trial + 1).max().unwrap_or(0);
    let name = folder.file_name().map_or_else(
        || folder.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    );
    let summary = summarise(&name, first.campaign_seed, trials, &policies, &entries);
    let results = summary
        .policies
        .iter()
        .map(|policy| {
            let mine: Vec<&TrialEntry> = entries
                .iter()
                .filter(|e| e.policy == policy.policy)
                .collect();
            let stages = mine.iter().map(|e| e.grasps.len()).max().unwrap_or(0);
            let spread = |k: usize, part: fn(&PoseError) -> f64| {
                let values: Vec<f64> = mine
                    .iter()
                    .filter_map(|e| e.grasps.get(k)?.error.as_ref())
                    .map(|error| part(error).abs())
                    .collect();
                five_numbers(&values).map(|five| Spread { values, five })
            };
            PolicyResults {
                policy: policy.policy.clone(),
                n_mm: (0..stages).map(|k| spread(k, |e| e.n_mm)).collect(),
                alpha_rad: (0..stages).map(|k| spread(k, |e| e.alpha_rad)).collect(),
                success: policy.success.map(|rate| SuccessRate {
                    successes: rate.successes,
                    trials: rate.trials,
                    ci95: [rate.ci95_low, rate.ci95_high],
                }),
                regrasps_mean_max: policy.regrasps_per_trial.map(|s| (s.mean, s.max)),
            }
        })
        .collect();
    let title = format!(
        "Campaign {name}: {trials} trials per policy, seed {}",
        summary.seed
    );
    let figure = CampaignFigure::new(results, title)
        .map_err(|e| Failure::BadInput(format!("{}: {e}", path.display())))?;
    write(
        &figure,
        out.map_or_else(|| folder.join("campaign.png"), Path::to_owned),
    )
}
