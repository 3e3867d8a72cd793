//! Runs a campaign: every (trial, policy) not yet in the journal, on as
//! many threads as asked, each finished trial appended to the journal as
//! soon as it is done.

use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc;

use super::journal::{Journal, JournalError, Recovered};
use super::shard::{Shard, ShardMeta, Stray, identity};
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
    /// `--shard` is not `K/N` with 0 ≤ K < N ≤ 10 000.
    #[error("`{text}` is no shard K/N: {reason}")]
    BadShard { text: String, reason: &'static str },
    /// A file of an output folder (its `campaign.json`, a recording a merge
    /// links or copies) could not be read or written.
    #[error("{}: {source}", path.display())]
    FolderIo {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// An output folder's `campaign.json` is not what a campaign writes.
    #[error("{}:{}: not a campaign's metadata: {source}", path.display(), source.line())]
    BadMeta {
        path: PathBuf,
        #[source]
        source: serde_json::Error,
    },
    /// An output folder belongs to another campaign (or another shard) than
    /// the one it is resumed or merged with.
    #[error("{}:1: {field} is {found}, but {against} has {expected}", path.display())]
    OtherCampaign {
        path: PathBuf,
        field: &'static str,
        found: String,
        expected: String,
        /// What it was compared with: this command, or another folder.
        against: String,
    },
    /// `campaign merge` was given a folder without `campaign.json`: not the
    /// output folder of a campaign run since shards were recorded.
    #[error("{}: no campaign.json here, so not a campaign's output folder", path.display())]
    NotAShard { path: PathBuf },
    /// Two folders given to `campaign merge` hold the same shard.
    #[error("{}: shard {shard} again, already merged from {}", path.display(), first.display())]
    ShardTwice {
        path: PathBuf,
        first: PathBuf,
        shard: Shard,
    },
    /// `campaign merge` lacks shards of the campaign.
    #[error("shard(s) {} of {count} missing: only {} given", missing.iter().map(ToString::to_string).collect::<Vec<_>>().join(", "), given.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", "))]
    ShardsMissing {
        missing: Vec<usize>,
        count: usize,
        given: Vec<PathBuf>,
    },
    /// A shard's journal is not its shard's trials.
    #[error("{}:{line}: {stray}", path.display())]
    Stray {
        path: PathBuf,
        /// 1-based line of the entry.
        line: usize,
        stray: Stray,
    },
    /// A trial is recorded twice among the merged journals.
    #[error("{}:{line}: trial {trial} of policy `{policy}` is already recorded at {}:{first_line}", path.display(), first.display())]
    TrialTwice {
        path: PathBuf,
        line: usize,
        first: PathBuf,
        first_line: usize,
        trial: usize,
        policy: String,
    },
    /// A shard's journal lacks trials: the shard did not finish (or its
    /// last trial was cut short by a kill). Resume it, then merge again.
    #[error("{}: lacks trial {trial} of policy `{policy}`{}: finish it with `cablecell campaign FILE --shard {shard} --out {} --resume`", path.display(), if *more > 0 { format!(" and {more} more") } else { String::new() }, folder.display())]
    TrialsMissing {
        path: PathBuf,
        folder: PathBuf,
        shard: Shard,
        trial: usize,
        policy: String,
        more: usize,
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
    /// Run only this shard's trials (by default into `OUT/shard-K-of-N`).
    pub shard: Option<Shard>,
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
    /// The trials this run holds: all of them, or one shard's.
    pub shard: Shard,
    /// CRC-64 of the campaign, task and cell files' text (`ShardMeta`).
    pub identity: String,
}

impl Campaign {
    pub fn load(path: &Path, overrides: Overrides) -> Result<Self, CampaignError> {
        let (file, task, cell) = load_campaign(path)?;
        let texts = [path.to_owned(), file.task_path(path), file.cell_path(path)]
            .iter()
            .map(|path| {
                std::fs::read(path).map_err(|source| ConfigError::Read {
                    path: path.clone(),
                    source,
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        let shard = overrides.shard.unwrap_or(Shard::WHOLE);
        let out = match (overrides.out, overrides.shard) {
            (Some(out), _) => out,
            (None, Some(shard)) => shard.folder_in(&file.campaign.out),
            (None, None) => file.campaign.out.clone(),
        };
        Ok(Self {
            trials: overrides.trials.unwrap_or(file.campaign.trials),
            seed: overrides.seed.unwrap_or(file.campaign.seed),
            out,
            record: !overrides.no_record,
            shard,
            identity: identity(&texts.iter().map(Vec::as_slice).collect::<Vec<_>>()),
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

    /// What `OUT/campaign.json` says of this run.
    pub fn meta(&self) -> ShardMeta {
        ShardMeta {
            name: self.file.campaign.name.clone(),
            identity: self.identity.clone(),
            seed: self.seed,
            trials: self.trials,
            policies: self.policy_names(),
            shard: self.shard,
        }
    }

    /// Refuses an output folder whose `campaign.json` is another campaign's
    /// (its files edited since) or another shard's. Its trials may differ:
    /// a resume may run more of them.
    fn check_resumed_meta(&self) -> Result<(), CampaignError> {
        let Some(found) = ShardMeta::read(&self.out)? else {
            return Ok(());
        };
        let expected = self.meta();
        let mismatch = [
            ("identity", found.identity, expected.identity),
            ("shard", found.shard.to_string(), expected.shard.to_string()),
        ]
        .into_iter()
        .find(|(_, found, expected)| found != expected);
        match mismatch {
            Some((field, found, expected)) => Err(CampaignError::OtherCampaign {
                path: ShardMeta::path_in(&self.out),
                field,
                found,
                expected,
                against: "this command (its campaign, task and cell files, --shard)".to_owned(),
            }),
            None => Ok(()),
        }
    }

    /// Refuses a resumed journal whose entries are not this campaign's
    /// trials, naming the first offending line: another seed, a trial
    /// beyond `trials`, a policy the campaign file lacks, another shard's
    /// trial, or a trial recorded twice (which no campaign writes).
    fn check_resumed(
        &self,
        path: &Path,
        recovered: &Recovered<TrialEntry>,
    ) -> Result<(), CampaignError> {
        let meta = self.meta();
        let mut seen = HashMap::new();
        for (entry, &line) in recovered.entries.iter().zip(&recovered.lines) {
            let foreign = |reason: String| CampaignError::Foreign {
                path: path.to_owned(),
                line,
                reason,
            };
            match meta.stray(entry) {
                Some(Stray::OtherSeed { found }) => {
                    return Err(CampaignError::SeedMismatch {
                        path: path.to_owned(),
                        line,
                        found,
                        expected: self.seed,
                    });
                }
                Some(Stray::Beyond { trial }) => {
                    return Err(foreign(format!(
                        "trial {trial} is beyond the campaign's {} trials: resume with --trials {} or more",
                        self.trials,
                        trial + 1
                    )));
                }
                Some(Stray::UnknownPolicy { policy }) => {
                    return Err(foreign(format!(
                        "policy `{policy}` is not one of the campaign file's ({})",
                        self.policy_names().join(", ")
                    )));
                }
                Some(stray @ Stray::OtherShard { .. }) => {
                    return Err(foreign(format!(
                        "{stray}, not to shard {}: resume with the --shard that wrote it",
                        self.shard
                    )));
                }
                None => {}
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

    /// Runs every trial of its shard the journal lacks (all of them unless
    /// `resume`),
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
            self.check_resumed_meta()?;
            self.check_resumed(&path, &recovered)?;
            (journal, recovered.entries)
        } else {
            if std::fs::metadata(&path).is_ok_and(|m| m.is_file() && m.len() > 0) {
                return Err(CampaignError::Exists { path });
            }
            (Journal::create(&path)?, Vec::new())
        };
        self.meta().write(&self.out)?;
        let policies = &self.file.policies;
        let jobs: Vec<(usize, usize)> = {
            let done: HashSet<(usize, &str)> = entries
                .iter()
                .map(|e| (e.trial, e.policy.as_str()))
                .collect();
            (0..self.trials)
                .filter(|&trial| self.shard.holds(trial))
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
