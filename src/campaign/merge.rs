//! `campaign merge`: the output folders of a sharded campaign's shards,
//! checked to be every shard of one campaign once, each holding exactly its
//! own trials, gathered into the entries the whole campaign would have
//! (and, if asked, into one output folder as the whole campaign writes it).

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use super::journal::{self, Journal};
use super::run::CampaignError;
use super::shard::{Shard, ShardMeta};
use super::trial::TrialEntry;

/// A sharded campaign gathered back.
#[derive(Debug, Clone)]
pub struct Merged {
    /// The campaign's metadata, as the whole campaign's own folder says.
    pub meta: ShardMeta,
    /// Every trial of every policy, ordered by policy and trial as a whole
    /// campaign's summary takes them.
    pub entries: Vec<TrialEntry>,
    /// Each entry's shard folder, where its recording lies.
    folders: Vec<PathBuf>,
}

/// Reads and checks the shard folders `folders`: each one's
/// `campaign.json` names the same campaign (identity, seed, trials,
/// policies, shard count), each shard comes once and none is missing, and
/// each journal holds exactly its shard's trials, once. A journal's tail
/// cut by a kill counts as missing trials.
pub fn merge(folders: &[PathBuf]) -> Result<Merged, CampaignError> {
    let mut metas: Vec<(ShardMeta, &PathBuf)> = Vec::with_capacity(folders.len());
    for folder in folders {
        let meta = ShardMeta::read(folder)?.ok_or_else(|| CampaignError::NotAShard {
            path: folder.clone(),
        })?;
        if let Some((first, first_folder)) = metas.first()
            && let Some((field, found, expected)) = first.differs(&meta)
        {
            return Err(CampaignError::OtherCampaign {
                path: ShardMeta::path_in(folder),
                field,
                found,
                expected,
                against: ShardMeta::path_in(first_folder).display().to_string(),
            });
        }
        if let Some((_, first)) = metas.iter().find(|(m, _)| m.shard == meta.shard) {
            return Err(CampaignError::ShardTwice {
                path: folder.clone(),
                first: (*first).clone(),
                shard: meta.shard,
            });
        }
        metas.push((meta, folder));
    }
    let Some((first, _)) = metas.first() else {
        return Err(CampaignError::ShardsMissing {
            missing: Vec::new(),
            count: 0,
            given: Vec::new(),
        });
    };
    let count = first.shard.count;
    let missing: Vec<usize> = (0..count)
        .filter(|&index| !metas.iter().any(|(m, _)| m.shard.index == index))
        .collect();
    if !missing.is_empty() {
        return Err(CampaignError::ShardsMissing {
            missing,
            count,
            given: folders.to_vec(),
        });
    }

    let policies = first.policies.clone();
    let mut found: HashMap<(usize, String), (usize, PathBuf, usize)> = HashMap::new();
    let mut entries = Vec::new();
    let mut entry_folders = Vec::new();
    for (meta, folder) in &metas {
        let path = folder.join("trials.jsonl");
        let recovered = journal::read::<TrialEntry>(&path)?;
        for (entry, line) in recovered.entries.into_iter().zip(recovered.lines) {
            if let Some(stray) = meta.stray(&entry) {
                return Err(CampaignError::Stray { path, line, stray });
            }
            let key = (entry.trial, entry.policy.clone());
            if let Some((_, first, first_line)) = found.get(&key) {
                return Err(CampaignError::TrialTwice {
                    path,
                    line,
                    first: first.clone(),
                    first_line: *first_line,
                    trial: entry.trial,
                    policy: entry.policy,
                });
            }
            found.insert(key, (entries.len(), path.clone(), line));
            entries.push(entry);
            entry_folders.push((*folder).clone());
        }
        let lacking: Vec<(usize, &String)> = (0..meta.trials)
            .filter(|&trial| meta.shard.holds(trial))
            .flat_map(|trial| policies.iter().map(move |policy| (trial, policy)))
            .filter(|&(trial, policy)| !found.contains_key(&(trial, policy.clone())))
            .collect();
        if let Some(&(trial, policy)) = lacking.first() {
            return Err(CampaignError::TrialsMissing {
                path,
                folder: (*folder).clone(),
                shard: meta.shard,
                trial,
                policy: policy.clone(),
                more: lacking.len() - 1,
            });
        }
    }

    let policy_index = |name: &str| policies.iter().position(|p| p == name);
    let mut order: Vec<usize> = (0..entries.len()).collect();
    order.sort_by_key(|&i| (policy_index(&entries[i].policy), entries[i].trial));
    let mut slots: Vec<Option<TrialEntry>> = entries.into_iter().map(Some).collect();
    let entries = order.iter().filter_map(|&i| slots[i].take()).collect();
    let folders = order.iter().map(|&i| entry_folders[i].clone()).collect();
    Ok(Merged {
        meta: ShardMeta {
            shard: Shard::WHOLE,
            ..first.clone()
        },
        entries,
        folders,
    })
}

impl Merged {
    /// Writes the merged campaign to `out` as the whole campaign writes its
    /// folder: `campaign.json` (shard 0/1), `trials.jsonl` and the
    /// recordings (hard links to the shards' files where the file system
    /// allows, else copies). A folder that already holds trials is refused.
    pub fn write(&self, out: &Path) -> Result<(), CampaignError> {
        let journal_path = out.join("trials.jsonl");
        if std::fs::metadata(&journal_path).is_ok_and(|m| m.is_file() && m.len() > 0) {
            return Err(CampaignError::Exists { path: journal_path });
        }
        let mut journal = Journal::create(&journal_path)?;
        let recordings = out.join("recordings");
        for (entry, folder) in self.entries.iter().zip(&self.folders) {
            if let Some(name) = &entry.recording {
                let from = folder.join("recordings").join(name);
                let to = recordings.join(name);
                let io = |source| CampaignError::FolderIo {
                    path: to.clone(),
                    source,
                };
                std::fs::create_dir_all(&recordings).map_err(io)?;
                if std::fs::hard_link(&from, &to).is_err() {
                    std::fs::copy(&from, &to).map_err(io)?;
                }
            }
            journal.append(entry)?;
        }
        self.meta.write(out)
    }
}
