//! A campaign's results as a JSON file: which campaign (trials, drives, scenarios), which part
//! of it (a shard), and every run's verdict. Shards of one campaign merge into the results of
//! one whole run: the same runs, the same order, the same table.

use std::collections::BTreeSet;
use std::fmt;
use std::path::{Path, PathBuf};
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use crate::campaign::scenario::Scenario;
use crate::campaign::{CampaignError, Drives, RunResult};

/// The results file's format; a change that old files cannot be read as bumps it.
pub const FORMAT: u32 = 1;

/// A part of a campaign: trials `index`, `index + count`, `index + 2·count`, …
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    /// Which part, `0…count−1`.
    pub index: u64,
    /// Into how many parts the campaign is split.
    pub count: u64,
}

impl Shard {
    /// The whole campaign.
    pub const WHOLE: Shard = Shard { index: 0, count: 1 };

    /// Whether trial `seed` is in this part.
    pub fn holds(self, seed: u64) -> bool {
        seed % self.count == self.index
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl FromStr for Shard {
    type Err = CampaignError;

    /// `I/N`.
    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let bad = || CampaignError::Shard(text.to_owned());
        let (i, n) = text.split_once('/').ok_or_else(bad)?;
        let index: u64 = i.trim().parse().map_err(|_| bad())?;
        let count: u64 = n.trim().parse().map_err(|_| bad())?;
        if count == 0 || index >= count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }
}

/// What was asked for: the same for every shard of one campaign.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Campaign {
    /// Trials, seeds `0…trials−1`.
    pub trials: u64,
    /// The drives the ratings are drawn around.
    pub drives: Drives,
    /// The scenarios each trial runs, in table order.
    pub scenarios: Vec<Scenario>,
}

impl Campaign {
    /// The runs of `shard`, in results order: by seed, then scenario.
    pub fn runs(&self, shard: Shard) -> Vec<(u64, Scenario)> {
        (0..self.trials)
            .filter(|seed| shard.holds(*seed))
            .flat_map(|seed| self.scenarios.iter().map(move |s| (seed, *s)))
            .collect()
    }
}

/// A results file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Results {
    /// [`FORMAT`].
    pub format: u32,
    /// The campaign.
    pub campaign: Campaign,
    /// Which part of it these are ([`Shard::WHOLE`] for a whole run or a merge).
    pub shard: Shard,
    /// Every run, by seed then scenario.
    pub runs: Vec<RunResult>,
}

impl Results {
    /// `runs` of `campaign`'s `shard`, put in results order.
    pub fn new(campaign: Campaign, shard: Shard, mut runs: Vec<RunResult>) -> Self {
        runs.sort_by_key(|r| (r.seed, r.scenario));
        Self {
            format: FORMAT,
            campaign,
            shard,
            runs,
        }
    }

    /// Writes the file.
    pub fn write(&self, path: &Path) -> Result<(), CampaignError> {
        let io = |source| CampaignError::Io {
            path: path.to_owned(),
            source,
        };
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(io)?;
        }
        let text = serde_json::to_string_pretty(self).map_err(|e| io(e.into()))?;
        std::fs::write(path, text + "\n").map_err(io)
    }

    /// Reads a file `write` wrote.
    pub fn read(path: &Path) -> Result<Self, CampaignError> {
        let text = std::fs::read_to_string(path).map_err(|source| CampaignError::Io {
            path: path.to_owned(),
            source,
        })?;
        let results: Results =
            serde_json::from_str(&text).map_err(|source| CampaignError::Parse {
                path: path.to_owned(),
                source,
            })?;
        if results.format != FORMAT {
            return Err(CampaignError::Mismatch {
                path: path.to_owned(),
                what: format!(
                    "format {} where this sim-host reads {FORMAT}",
                    results.format
                ),
            });
        }
        Ok(results)
    }
}

/// Joins the shards in `files` (path, results) into the results of the whole campaign:
/// refused if they come from different campaigns, overlap, or leave runs out.
pub fn merge(files: Vec<(PathBuf, Results)>) -> Result<Results, CampaignError> {
    let campaign = files
        .first()
        .map(|(_, results)| results.campaign.clone())
        .ok_or(CampaignError::NothingToMerge)?;
    let mut seen: BTreeSet<(u64, Scenario)> = BTreeSet::new();
    let mut runs = Vec::new();
    let mut add = |path: &Path, results: Results| -> Result<(), CampaignError> {
        if results.campaign != campaign {
            return Err(CampaignError::Mismatch {
                path: path.to_owned(),
                what: format!("{:?} vs {:?}", results.campaign, campaign),
            });
        }
        for run in results.runs {
            if !seen.insert((run.seed, run.scenario)) {
                return Err(CampaignError::Duplicate {
                    seed: run.seed,
                    scenario: run.scenario.to_string(),
                    path: path.to_owned(),
                });
            }
            runs.push(run);
        }
        Ok(())
    };
    for (path, results) in files {
        add(&path, results)?;
    }
    let expected = campaign.runs(Shard::WHOLE);
    if let Some(&(seed, scenario)) = expected.iter().find(|key| !seen.contains(key)) {
        return Err(CampaignError::Incomplete {
            held: seen.len(),
            expected: expected.len(),
            first_missing: seed,
            scenario: scenario.to_string(),
        });
    }
    Ok(Results::new(campaign, Shard::WHOLE, runs))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_parse_and_split_the_trials_without_overlap() {
        assert_eq!(
            "1/4".parse::<Shard>().unwrap(),
            Shard { index: 1, count: 4 }
        );
        for bad in ["4/4", "1", "a/2", "0/0"] {
            assert!(bad.parse::<Shard>().is_err(), "{bad}");
        }
        let campaign = Campaign {
            trials: 10,
            drives: Drives::Rated,
            scenarios: vec![Scenario::W, Scenario::L],
        };
        let mut all: Vec<_> = (0..3)
            .flat_map(|i| campaign.runs(Shard { index: i, count: 3 }))
            .collect();
        all.sort();
        assert_eq!(all, campaign.runs(Shard::WHOLE));
    }
}
