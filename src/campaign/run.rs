//! Runs a campaign: every (trial, policy) not yet in the journal, on as
//! many threads as asked, each finished trial appended to the journal as
//! soon as it is done.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc;

use super::journal::{Journal, JournalError};
use super::trial::{TrialEntry, run_trial};
use crate::cell::CellFile;
use crate::cell::load_cell;
use crate::schema::ConfigError;
use crate::schema::toml_file::{key_position, read};
use crate::task::campaign_file::{CampaignFile, Sensing};
use crate::task::{TaskFile, load_task};

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
    #[error("{}: its trials were run with seed {found}, not {expected}: resume with --seed {found}, or use another --out", path.display())]
    SeedMismatch {
        path: PathBuf,
        found: u64,
        expected: u64,
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
        let file = CampaignFile::load(path)?;
        let task = load_task(&file.task_path(path))?;
        if let Some(policy) = file.policies.iter().find(|p| p.sensing == Sensing::Touch)
            && task.prior.is_none()
        {
            let (line, column) = key_position(&read(path)?, &["campaign", "task"]);
            return Err(ConfigError::Invalid {
                path: path.to_owned(),
                line,
                column,
                field: "campaign.task".to_owned(),
                message: format!(
                    "policy `{}` is touch only, but the task has no [prior] to search from",
                    policy.name
                ),
            }
            .into());
        }
        let cell = load_cell(&file.cell_path(path))?;
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
            if let Some(other) = recovered
                .entries
                .iter()
                .find(|e| e.campaign_seed != self.seed)
            {
                return Err(CampaignError::SeedMismatch {
                    path,
                    found: other.campaign_seed,
                    expected: self.seed,
                });
            }
            if recovered.truncated_tail_bytes > 0 {
                tracing::warn!(
                    bytes = recovered.truncated_tail_bytes,
                    "dropped a trial cut short when the campaign was stopped; it runs again"
                );
            }
            (journal, recovered.entries)
        } else {
            if std::fs::metadata(&path).is_ok_and(|m| m.len() > 0) {
                return Err(CampaignError::Exists { path });
            }
            (Journal::create(&path)?, Vec::new())
        };
        let policies = &self.file.policies;
        entries.retain(|e| e.trial < self.trials && policies.iter().any(|p| p.name == e.policy));
        let jobs: Vec<(usize, usize)> = (0..self.trials)
            .flat_map(|trial| (0..policies.len()).map(move |policy| (trial, policy)))
            .filter(|&(trial, policy)| {
                !entries
                    .iter()
                    .any(|e| e.trial == trial && e.policy == policies[policy].name)
            })
            .collect();
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
