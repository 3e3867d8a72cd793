//! `cablecell campaign FILE` and `cablecell campaign merge DIR…`

use std::path::{Path, PathBuf};

use super::output::{out, outln};
use super::{Status, progress};
use cablecell::campaign::journal::JournalError;
use cablecell::campaign::merge::merge as merge_shards;
use cablecell::campaign::run::{Campaign, CampaignError, Overrides};
use cablecell::campaign::summary::{render_table, summarise};
use cablecell::campaign::trial::TrialEntry;

pub fn campaign(
    path: &Path,
    overrides: Overrides,
    resume: bool,
    json: bool,
    threads: usize,
) -> Status {
    let campaign = match Campaign::load(path, overrides) {
        Ok(campaign) => campaign,
        Err(error) => {
            eprintln!("error: {error}");
            return Status::BadInput;
        }
    };
    let policies = campaign.policy_names();
    let bar = progress::bar(campaign.trials * policies.len(), "trials");
    let mut means = RunningMeans::new(&policies);
    let result = campaign.run(resume, threads, |entry| {
        means.add(entry);
        bar.set_message(means.to_string());
        bar.inc(1);
    });
    bar.finish_and_clear();
    let entries = match result {
        Ok(entries) => entries,
        Err(error) => {
            eprintln!("error: {error}");
            return match error {
                CampaignError::Config(_)
                | CampaignError::Exists { .. }
                | CampaignError::SeedMismatch { .. }
                | CampaignError::Foreign { .. }
                | CampaignError::OtherCampaign { .. }
                | CampaignError::BadMeta { .. } => Status::BadInput,
                _ => Status::OutputFailed,
            };
        }
    };
    let summary = summarise(
        &campaign.file.campaign.name,
        campaign.seed,
        campaign.trials,
        &policies,
        &entries,
    );
    if json {
        return super::json::print(&summary);
    }
    out!("{}", render_table(&summary));
    if campaign.shard.count > 1 {
        outln!(
            "shard {} of the campaign (its trials i with i mod {} = {})",
            campaign.shard,
            campaign.shard.count,
            campaign.shard.index
        );
    }
    outln!("trials recorded in {}", campaign.journal_path().display());
    if campaign.record {
        outln!(
            "each trial's recording in {}",
            campaign.recordings_folder().display()
        );
    }
    Status::Success
}

/// Checks that `folders` are the shards of one campaign and prints its
/// summary, the same as the whole campaign's; writes the merged folder to
/// `out` if given. Anything wrong with the shards is bad input (2); only
/// writing `out` can fail with 4.
pub fn merge(folders: &[PathBuf], out: Option<&Path>, json: bool) -> Status {
    let merged = match merge_shards(folders) {
        Ok(merged) => merged,
        Err(error) => {
            eprintln!("error: {error}");
            return Status::BadInput;
        }
    };
    if let Some(out) = out
        && let Err(error) = merged.write(out)
    {
        eprintln!("error: {error}");
        return match error {
            CampaignError::Exists { .. }
            | CampaignError::Journal(JournalError::AlreadyExists { .. }) => Status::BadInput,
            _ => Status::OutputFailed,
        };
    }
    let meta = &merged.meta;
    let summary = summarise(
        &meta.name,
        meta.seed,
        meta.trials,
        &meta.policies,
        &merged.entries,
    );
    if json {
        return super::json::print(&summary);
    }
    out!("{}", render_table(&summary));
    outln!(
        "merged {} shards of campaign {} ({})",
        folders.len(),
        meta.name,
        meta.identity
    );
    if let Some(out) = out {
        outln!("trials recorded in {}", out.join("trials.jsonl").display());
    }
    Status::Success
}

/// Mean final |n| and |α| per policy, for the progress bar.
struct RunningMeans {
    sums: Vec<(String, f64, f64, usize)>,
}

impl RunningMeans {
    fn new(policies: &[String]) -> Self {
        Self {
            sums: policies.iter().map(|p| (p.clone(), 0.0, 0.0, 0)).collect(),
        }
    }

    fn add(&mut self, entry: &TrialEntry) {
        let error = entry.grasps.last().and_then(|g| g.error);
        if let (Some(sum), Some(error)) =
            (self.sums.iter_mut().find(|s| s.0 == entry.policy), error)
        {
            sum.1 += error.n_mm.abs();
            sum.2 += error.alpha_rad.abs();
            sum.3 += 1;
        }
    }
}

impl std::fmt::Display for RunningMeans {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        for (name, n, alpha, count) in self.sums.iter().filter(|s| s.3 > 0) {
            let count = *count as f64;
            write!(
                f,
                "{name}: |n| {:.2} mm |α| {:.3} rad  ",
                n / count,
                alpha / count
            )?;
        }
        Ok(())
    }
}
