//! A campaign cut into shards that run apart (a Slurm array, a Kubernetes
//! Indexed Job) and are merged afterwards: which trials a shard holds, and
//! the metadata each output folder keeps (`OUT/campaign.json`) so that a
//! merge can tell that its shards belong together.

use std::fmt;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use super::run::CampaignError;
use super::trial::TrialEntry;

/// Slice `index` of `count`: trial i belongs to shard i mod `count`, so
/// every shard gets trials from the whole range (of alike cost, whatever
/// `--trials` is) and no shard needs to know the others' sizes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Shard {
    pub index: usize,
    pub count: usize,
}

/// At most as many shards as a campaign has trials at most.
pub const SHARDS: std::ops::RangeInclusive<usize> = crate::task::campaign_file::TRIALS;

impl Shard {
    /// The whole campaign, as one shard.
    pub const WHOLE: Shard = Shard { index: 0, count: 1 };

    pub fn holds(&self, trial: usize) -> bool {
        trial % self.count == self.index
    }

    /// The shard that holds `trial`, among as many as this one's.
    pub fn of(&self, trial: usize) -> Shard {
        Shard {
            index: trial % self.count,
            count: self.count,
        }
    }

    /// The folder a shard writes to when `--out` is not given: beside the
    /// others, inside the campaign's own.
    pub fn folder_in(&self, out: &Path) -> PathBuf {
        out.join(format!("shard-{}-of-{}", self.index, self.count))
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl FromStr for Shard {
    type Err = CampaignError;

    /// `K/N`, 0 ≤ K < N: K counts from 0, as `JOB_COMPLETION_INDEX` and
    /// `SLURM_ARRAY_TASK_ID` (with `--array=0-N-1`) do.
    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let malformed = |reason: &'static str| CampaignError::BadShard {
            text: text.to_owned(),
            reason,
        };
        let (index, count) = text
            .split_once('/')
            .ok_or(malformed("expected K/N, e.g. 0/3"))?;
        let number = |part: &str| part.trim().parse::<usize>();
        let (index, count) = (number(index), number(count));
        let (Ok(index), Ok(count)) = (index, count) else {
            return Err(malformed("K and N must be whole numbers, e.g. 0/3"));
        };
        if !SHARDS.contains(&count) {
            return Err(malformed("N must be 1 to 10000"));
        }
        if index >= count {
            return Err(malformed("K counts from 0 and must be below N"));
        }
        Ok(Shard { index, count })
    }
}

/// What an output folder holds: which shard of which campaign. Written to
/// `OUT/campaign.json` when a campaign starts or resumes.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShardMeta {
    pub name: String,
    /// The campaign's identity: CRC-64 of its campaign, task and cell files'
    /// text, so that shards of edited files do not merge.
    pub identity: String,
    pub seed: u64,
    /// Trials per policy of the whole campaign.
    pub trials: usize,
    pub policies: Vec<String>,
    pub shard: Shard,
}

/// Why a journal entry is not one of a shard's trials.
#[derive(Debug, Clone, PartialEq)]
pub enum Stray {
    OtherSeed { found: u64 },
    Beyond { trial: usize },
    UnknownPolicy { policy: String },
    OtherShard { trial: usize, shard: Shard },
}

impl ShardMeta {
    /// The metadata file of the output folder `out`.
    pub fn path_in(out: &Path) -> PathBuf {
        out.join("campaign.json")
    }

    /// Whether `entry` is one of this shard's trials, and if not, why.
    pub fn stray(&self, entry: &TrialEntry) -> Option<Stray> {
        if entry.campaign_seed != self.seed {
            Some(Stray::OtherSeed {
                found: entry.campaign_seed,
            })
        } else if entry.trial >= self.trials {
            Some(Stray::Beyond { trial: entry.trial })
        } else if !self.policies.contains(&entry.policy) {
            Some(Stray::UnknownPolicy {
                policy: entry.policy.clone(),
            })
        } else if !self.shard.holds(entry.trial) {
            Some(Stray::OtherShard {
                trial: entry.trial,
                shard: self.shard.of(entry.trial),
            })
        } else {
            None
        }
    }

    /// The first field in which `other` is not a shard of this campaign:
    /// its name, `found` and `expected` values.
    pub fn differs(&self, other: &ShardMeta) -> Option<(&'static str, String, String)> {
        let fields: [(&'static str, String, String); 6] = [
            ("campaign", other.name.clone(), self.name.clone()),
            ("identity", other.identity.clone(), self.identity.clone()),
            ("seed", other.seed.to_string(), self.seed.to_string()),
            ("trials", other.trials.to_string(), self.trials.to_string()),
            (
                "policies",
                other.policies.join(", "),
                self.policies.join(", "),
            ),
            (
                "shard count",
                other.shard.count.to_string(),
                self.shard.count.to_string(),
            ),
        ];
        fields
            .into_iter()
            .find(|(_, found, expected)| found != expected)
    }

    /// Reads `OUT/campaign.json`; `None` if the folder has none (a campaign
    /// started before shards were recorded).
    pub fn read(out: &Path) -> Result<Option<ShardMeta>, CampaignError> {
        let path = Self::path_in(out);
        let text = match std::fs::read_to_string(&path) {
            Ok(text) => text,
            Err(error) if error.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(source) => return Err(CampaignError::FolderIo { path, source }),
        };
        serde_json::from_str(&text)
            .map(Some)
            .map_err(|source| CampaignError::BadMeta { path, source })
    }

    /// Writes `OUT/campaign.json` in one line, through a temporary file
    /// renamed over it, so that a kill leaves the old or the new one.
    pub fn write(&self, out: &Path) -> Result<(), CampaignError> {
        let path = Self::path_in(out);
        let temporary = out.join("campaign.json.new");
        let io = |source| CampaignError::FolderIo {
            path: path.clone(),
            source,
        };
        let mut line = serde_json::to_vec(self).map_err(|source| CampaignError::BadMeta {
            path: path.clone(),
            source,
        })?;
        line.push(b'\n');
        std::fs::create_dir_all(out).map_err(io)?;
        let mut file = std::fs::File::create(&temporary).map_err(io)?;
        file.write_all(&line)
            .and_then(|()| file.sync_data())
            .map_err(io)?;
        std::fs::rename(&temporary, &path).map_err(io)
    }
}

impl fmt::Display for Stray {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Stray::OtherSeed { found } => write!(f, "its trial was run with seed {found}"),
            Stray::Beyond { trial } => write!(f, "trial {trial} is beyond the campaign's trials"),
            Stray::UnknownPolicy { policy } => {
                write!(f, "policy `{policy}` is not one of the campaign's")
            }
            Stray::OtherShard { trial, shard } => {
                write!(f, "trial {trial} belongs to shard {shard}")
            }
        }
    }
}

/// The campaign's identity from its files' text: CRC-64 (XZ) of each,
/// in order, each preceded by its length so that no two lists of texts
/// collide by where one ends.
pub fn identity(texts: &[&[u8]]) -> String {
    let crc = crc::Crc::<u64>::new(&crc::CRC_64_XZ);
    let mut digest = crc.digest();
    for text in texts {
        digest.update(&(text.len() as u64).to_le_bytes());
        digest.update(text);
    }
    format!("crc64:{:016x}", digest.finalize())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn k_of_n_parses_and_bad_ones_are_refused() {
        assert_eq!(
            "2/3".parse::<Shard>().ok(),
            Some(Shard { index: 2, count: 3 })
        );
        for bad in [
            "3/3", "4/3", "1", "a/3", "1/b", "-1/3", "0/0", "0/10001", "1/2/3",
        ] {
            assert!(
                matches!(bad.parse::<Shard>(), Err(CampaignError::BadShard { .. })),
                "{bad}"
            );
        }
    }

    #[test]
    fn every_trial_is_in_exactly_one_shard() {
        for count in 1..=5 {
            for trial in 0..20 {
                let holders: Vec<usize> = (0..count)
                    .filter(|&index| Shard { index, count }.holds(trial))
                    .collect();
                assert_eq!(holders, vec![trial % count]);
            }
        }
    }

    #[test]
    fn identity_depends_on_every_text_and_where_each_ends() {
        let one = identity(&[b"ab", b"c"]);
        assert_eq!(one, identity(&[b"ab", b"c"]));
        assert_ne!(one, identity(&[b"a", b"bc"]));
        assert_ne!(one, identity(&[b"ab", b"d"]));
    }
}
