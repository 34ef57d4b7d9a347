//! The robustness campaign: the acceptance scenarios on many robots as built, each drawn from
//! a seed, judged by the acceptance figures. A measuring instrument: it changes nothing in the
//! controller and reports what fraction of plausible robots the controller carries through
//! each scenario, and how the rest fail.
//!
//! - [`draw`]: a trial's plant from its seed (body, delay, drive ratings, sensors), [`imu`]:
//!   its IMU chip;
//! - [`scenario`]: the scenarios' plans; [`observe`]: one run on the rig; [`judge`]: its verdict;
//! - [`pool`]: runs on every core; [`results`]: the JSON file, shards and their merge;
//!   [`table`]: the Markdown table of `docs/campaign.md`; [`sweep`]: one parameter at a time;
//!   [`error`]: why a campaign failed.
//!
//! A trial is one seed: its plant runs every scenario, each run its own MuJoCo instance. The
//! seed alone fixes the run (lockstep, seeded noise and delays), so results do not depend on
//! the number of workers or on which shard ran them.

pub mod draw;
pub mod error;
pub mod estop;
pub mod imu;
pub mod judge;
pub mod observe;
pub mod pool;
pub mod results;
pub mod scenario;
pub mod sweep;
pub mod table;

use std::path::Path;

use protocol::signal::WireField;
use protocol::FaultFlags;
use serde::{Deserialize, Serialize};

use crate::campaign::draw::Draws;
use crate::campaign::judge::{Outcome, Verdict};
use crate::campaign::observe::Observation;
use crate::campaign::scenario::Scenario;
use crate::robot::plant::DriveRatings;

pub use error::CampaignError;

/// The drives the ratings are drawn around.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Drives {
    /// [`DriveRatings::RATED`]: real parts (the honest plant).
    Rated,
    /// [`DriveRatings::IDEAL`]: unlimited leg servos, flat 30 N·m wheels (what the acceptance
    /// tests run on today).
    Ideal,
}

impl Drives {
    /// The nominal ratings.
    pub fn ratings(self) -> DriveRatings {
        match self {
            Drives::Rated => DriveRatings::RATED,
            Drives::Ideal => DriveRatings::IDEAL,
        }
    }

    /// The name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Drives::Rated => "rated",
            Drives::Ideal => "ideal",
        }
    }
}

/// One run: a trial's plant in one scenario.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunResult {
    /// The trial's seed (trial `i` has seed `i`).
    pub seed: u64,
    /// The scenario.
    pub scenario: Scenario,
    /// Its verdict.
    pub verdict: Verdict,
    /// The drawn plant, parameter by parameter (for readers of the JSON; the seed alone
    /// reproduces it).
    pub plant: Vec<(String, f64)>,
}

/// Runs `scenario` on the plant of `seed` built around `drives`; a panic or an error of the
/// closed loop becomes the run's verdict, so one bad run does not stop a campaign.
pub fn run_one(model: &Path, drives: Drives, seed: u64, scenario: Scenario) -> RunResult {
    let draws = Draws::of(seed);
    RunResult {
        seed,
        scenario,
        verdict: judged(scenario, || observe_one(model, drives, &draws, scenario)),
        plant: draw::parameters()
            .map(|p| (p.name.to_owned(), draws.value(p.name)))
            .collect(),
    }
}

/// The verdict of the run `observe` makes; its panic or error is the verdict.
pub fn judged(
    scenario: Scenario,
    observe: impl FnOnce() -> Result<Observation, crate::session::SessionError>,
) -> Verdict {
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(observe)) {
        Ok(Ok(obs)) => judge::judge(scenario, &obs),
        Ok(Err(e)) => failed(Outcome::Error, "the closed loop ran", e.to_string()),
        Err(panic) => failed(Outcome::Panic, "no panic", panic_text(panic.as_ref())),
    }
}

/// The run itself, for a close look at one (`sim-host campaign --seed S --scenario W`).
pub fn observe_one(
    model: &Path,
    drives: Drives,
    draws: &Draws,
    scenario: Scenario,
) -> Result<Observation, crate::session::SessionError> {
    observe::run(
        model,
        scenario,
        draws.plant(drives.ratings()),
        &host_can::fault_plan::Faults::default(),
    )
}

fn failed(outcome: Outcome, check: &str, detail: String) -> Verdict {
    Verdict {
        outcome,
        check: check.into(),
        detail,
        shortfall: 1.0,
    }
}

fn panic_text(panic: &(dyn std::any::Any + Send)) -> String {
    panic
        .downcast_ref::<&str>()
        .map(|s| (*s).to_owned())
        .or_else(|| panic.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "a panic without a message".into())
}

/// The names of the set flags, `+`-joined (`wheel_stall+runaway`), or `none`.
pub fn flag_names(flags: FaultFlags) -> String {
    let names: Vec<&str> = <FaultFlags as WireField>::FLAGS
        .iter()
        .enumerate()
        .filter(|(bit, _)| flags.bits() & (1 << bit) != 0)
        .map(|(_, name)| *name)
        .collect();
    if names.is_empty() {
        "none".into()
    } else {
        names.join("+")
    }
}

/// The command that reruns one run, for the table.
pub fn rerun_command(seed: u64, scenario: Scenario, drives: Drives) -> String {
    let drives = match drives {
        Drives::Rated => "",
        Drives::Ideal => " --drives ideal",
    };
    format!("cargo xtask campaign --seed {seed} --scenario {scenario}{drives}")
}
