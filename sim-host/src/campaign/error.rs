//! Why a campaign could not produce its table: one variant per cause, each saying what to do.
//! (A run that fails is a result, not an error: it is in the table.)

use std::path::PathBuf;

use crate::session::SessionError;

/// Why a campaign failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CampaignError {
    /// The closed loop does not start on the nominal plant: nothing would run.
    #[error(
        "the closed loop does not start on {model}: {source}; check that --model names the \
         robot's MJCF (the default is the shipped one)"
    )]
    Setup {
        /// The model.
        model: PathBuf,
        /// Why.
        source: SessionError,
    },
    /// `--shard` is not `I/N` with `I < N`.
    #[error("--shard {0}: give I/N with 0 ≤ I < N, e.g. 0/4 for the first of four shards")]
    Shard(String),
    /// A results file could not be read or written.
    #[error("{path}: {source}; check the path (a shard writes its file with --results FILE)")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A results file is not a campaign's JSON.
    #[error("{path} is not a campaign results file ({source}); pass the files `--results` wrote")]
    Parse {
        /// The file.
        path: PathBuf,
        /// Why.
        source: serde_json::Error,
    },
    /// Results of different campaigns given to one merge.
    #[error(
        "{path} is from another campaign ({what}); merge only the shards of one command line \
         (the same --trials, --drives and --scenario)"
    )]
    Mismatch {
        /// The file that differs from the first.
        path: PathBuf,
        /// What differs.
        what: String,
    },
    /// One run found in two files.
    #[error(
        "seed {seed} {scenario} is in two of the files (the last: {path}); each shard's \
         --shard I/N must be different"
    )]
    Duplicate {
        /// The run's seed.
        seed: u64,
        /// The run's scenario.
        scenario: String,
        /// The second file that holds it.
        path: PathBuf,
    },
    /// The merged files miss runs.
    #[error(
        "the files hold {held} of the campaign's {expected} runs (seed {first_missing} {scenario} \
         is missing); merge every shard I/N for I = 0…N−1"
    )]
    Incomplete {
        /// Runs the files hold.
        held: usize,
        /// Runs the campaign has.
        expected: usize,
        /// The first missing run's seed.
        first_missing: u64,
        /// … and its scenario.
        scenario: String,
    },
    /// No file to merge.
    #[error("nothing to merge: give the shards' results files, e.g. --merge a.json b.json")]
    NothingToMerge,
}
