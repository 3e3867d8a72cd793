//! Runs a campaign: every (trial, policy) not yet in the journal, on as
//! many threads as asked, each finished trial appended to the journal as
//! soon as it is done.

use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc;

use super::journal::{Journal, JournalError, Recovered};
use super::trial::{TrialEntry, run_trial};
use crate::cell::CellFile;
use crate::schema::ConfigError;
use crate::task::campaign_file::CampaignFile;
use crate::task::{TaskFile, load_campaign};

#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CampaignError {
    /// The campaign, task or cell file is unusable.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// The journal could not be read or written.
    #[error(transparent)]
    Journal(#[from] JournalError),
    /// The output folder already holds trials: resume them, or choose
    /// another folder.
    #[error("{}: already holds trials of a campaign: use --resume to continue it, or --out for a new one", path.display())]
    Exists { path: PathBuf },
    /// `--resume` of a journal written with another seed would mix trials
    /// of two campaigns.
    #[error("{}:{line}: its trials were run with seed {found}, not {expected}: resume with --seed {found}, or use another --out", path.display())]
    SeedMismatch {
        path: PathBuf,
        /// 1-based line of the first trial of another seed.
        line: usize,
        found: u64,
        expected: u64,
    },
    /// `--resume` found a trial this campaign does not run: one beyond its
    /// trials, or of a policy its file lacks. Resume with the campaign file
    /// and `--trials` that wrote the journal, or use another output folder.
    #[error("{}:{line}: {reason}; or use another --out", path.display())]
    Foreign {
        path: PathBuf,
        /// 1-based line of the trial.
        line: usize,
        reason: String,
    },
}

/// What the command line may override in a campaign file.
#[derive(Debug, Default, Clone)]
pub struct Overrides {
    pub trials: Option<usize>,
    pub seed: Option<u64>,
    pub out: Option<PathBuf>,
    /// Write no recording of the trials.
    pub no_record: bool,
}

/// A campaign file with its task and cell loaded and overrides applied.
#[derive(Debug, Clone)]
pub struct Campaign {
    pub file: CampaignFile,
    pub task: TaskFile,
    pub cell: CellFile,
    pub trials: usize,
    pub seed: u64,
    pub out: PathBuf,
    /// Whether each trial is recorded in `recordings_folder`.
    pub record: bool,
}

impl Campaign {
    pub fn load(path: &Path, overrides: Overrides) -> Result<Self, CampaignError> {
        let (file, task, cell) = load_campaign(path)?;
        Ok(Self {
            trials: overrides.trials.unwrap_or(file.campaign.trials),
            seed: overrides.seed.unwrap_or(file.campaign.seed),
            out: overrides.out.unwrap_or_else(|| file.campaign.out.clone()),
            record: !overrides.no_record,
            file,
            task,
            cell,
        })
    }

    pub fn journal_path(&self) -> PathBuf {
        self.out.join("trials.jsonl")
    }

    /// Where each trial's recording goes (`trial-NNNNNN-POLICY.mcap`).
    pub fn recordings_folder(&self) -> PathBuf {
        self.out.join("recordings")
    }

    pub fn policy_names(&self) -> Vec<String> {
        self.file.policies.iter().map(|p| p.name.clone()).collect()
    }

    /// Refuses a resumed journal whose entries are not this campaign's
    /// trials, naming the first offending line: another seed, a trial
    /// beyond `trials`, a policy the campaign file lacks, or a trial
    /// recorded twice (which no campaign writes).
    fn check_resumed(
        &self,
        path: &Path,
        recovered: &Recovered<TrialEntry>,
    ) -> Result<(), CampaignError> {
        let mut seen = HashMap::new();
        for (entry, &line) in recovered.entries.iter().zip(&recovered.lines) {
            let foreign = |reason: String| CampaignError::Foreign {
                path: path.to_owned(),
                line,
                reason,
            };
            if entry.campaign_seed != self.seed {
                return Err(CampaignError::SeedMismatch {
                    path: path.to_owned(),
                    line,
                    found: entry.campaign_seed,
                    expected: self.seed,
                });
            }
            if entry.trial >= self.trials {
                return Err(foreign(format!(
                    "trial {} is beyond the campaign's {} trials: resume with --trials {} or more",
                    entry.trial,
                    self.trials,
                    entry.trial + 1
                )));
            }
            if !self.file.policies.iter().any(|p| p.name == entry.policy) {
                return Err(foreign(format!(
                    "policy `{}` is not one of the campaign file's ({})",
                    entry.policy,
                    self.policy_names().join(", ")
                )));
            }
            if let Some(first) = seen.insert((entry.trial, entry.policy.as_str()), line) {
                return Err(JournalError::Corrupt {
                    path: path.to_owned(),
                    line,
                    message: format!(
                        "trial {} of policy `{}` is already recorded on line {first}",
                        entry.trial, entry.policy
                    ),
                }
                .into());
            }
        }
        Ok(())
    }

    /// Runs every trial the journal lacks (all of them unless `resume`),
    /// calling `on_entry` as each one is recorded. Returns the campaign's
    /// entries, old and new, ordered by policy and trial.
    pub fn run(
        &self,
        resume: bool,
        threads: usize,
        mut on_entry: impl FnMut(&TrialEntry),
    ) -> Result<Vec<TrialEntry>, CampaignError> {
        let path = self.journal_path();
        let (mut journal, mut entries) = if resume {
            let (journal, recovered) = Journal::resume::<TrialEntry>(&path)?;
            if recovered.truncated_tail_bytes > 0 {
                tracing::warn!(
                    bytes = recovered.truncated_tail_bytes,
                    "dropped a trial cut short when the campaign was stopped; it runs again"
                );
            }
            self.check_resumed(&path, &recovered)?;
            (journal, recovered.entries)
        } else {
            if std::fs::metadata(&path).is_ok_and(|m| m.is_file() && m.len() > 0) {
                return Err(CampaignError::Exists { path });
            }
            (Journal::create(&path)?, Vec::new())
        };
        let policies = &self.file.policies;
        let jobs: Vec<(usize, usize)> = {
            let done: HashSet<(usize, &str)> = entries
                .iter()
                .map(|e| (e.trial, e.policy.as_str()))
                .collect();
            (0..self.trials)
                .flat_map(|trial| (0..policies.len()).map(move |policy| (trial, policy)))
                .filter(|&(trial, policy)| !done.contains(&(trial, policies[policy].name.as_str())))
                .collect()
        };
        entries.iter().for_each(&mut on_entry);

        let recordings = self.record.then(|| self.recordings_folder());
        let next_job = AtomicUsize::new(0);
        let stop = AtomicBool::new(false);
        let (sender, receiver) = mpsc::channel::<TrialEntry>();
        let mut write_error = None;
        std::thread::scope(|scope| {
            for _ in 0..threads.max(1) {
                let sender = sender.clone();
                let (next_job, stop, jobs) = (&next_job, &stop, &jobs);
                let recordings = recordings.as_deref();
                scope.spawn(move || {
                    while !stop.load(Ordering::Relaxed) {
                        let Some(&(trial, policy)) =
                            jobs.get(next_job.fetch_add(1, Ordering::Relaxed))
                        else {
                            break;
                        };
                        let entry = run_trial(
                            &self.task,
                            &self.cell,
                            &policies[policy],
                            &self.file.perturbation,
                            self.seed,
                            trial,
                            recordings,
                        );
                        if sender.send(entry).is_err() {
                            break;
                        }
                    }
                });
            }
            drop(sender);
            for entry in receiver {
                if let Err(error) = journal.append(&entry) {
                    stop.store(true, Ordering::Relaxed);
                    write_error = Some(error);
                    break;
                }
                on_entry(&entry);
                entries.push(entry);
            }
        });
        if let Some(error) = write_error {
            return Err(error.into());
        }
        let policy_index = |name: &str| policies.iter().position(|p| p.name == name);
        entries.sort_by_key(|e| (policy_index(&e.policy), e.trial));
        Ok(entries)
    }
}
