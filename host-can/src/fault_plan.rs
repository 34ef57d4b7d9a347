//! What to break on a bus, per direction: the settings of a [`crate::faulty_bus::FaultyBus`].
//!
//! A plan is written on the command line of `sim-host` and `firmware-host` as
//! comma-separated `direction.fault=value` items, e.g.
//! `tx.drop=0.05,rx.delay=3,tx.flip=0.01,seed=7`:
//!
//! | item               | meaning                                                                |
//! |--------------------|------------------------------------------------------------------------|
//! | `D.drop=P`         | drop each frame with probability `P` (0…1)                             |
//! | `D.burst=N`        | with `drop`: lose whole control cycles in bursts of `N` on average, `P` of the cycles in the long run (a Gilbert–Elliott channel) |
//! | `D.delay=N`        | deliver every frame `N` control cycles late (order kept)               |
//! | `D.duplicate=P`    | send a frame twice with probability `P`                                |
//! | `D.reorder=P`      | hold a frame back behind the next one with probability `P`             |
//! | `D.flip=P`         | flip one bit of the E2E-protected bytes with probability `P`           |
//! | `D.replay=P`       | after a frame, send an older frame of the same id with probability `P` |
//! | `D.silence=NODE`   | drop every frame a node sends (`LegDrive_FL`, `Imu`, `Controller`, …, or `feedback` for all drives and the IMU) |
//! | `D.flood=N`        | send `N` extra copies of the last TeleopCommand per cycle, counters in sequence |
//! | `seed=S`           | the random generator's seed (default 1): runs are repeatable           |
//!
//! `D` is `tx` (frames this node sends) or `rx` (frames it receives). SYNC, the simulator's
//! clock, is never faulted: it stands for time itself, which a bus cannot lose. Counts of cycles
//! and frames are at most [`MAX_CYCLES`] (a delay holds every frame in memory meanwhile).

use std::fmt;
use std::str::FromStr;

use protocol::{Drive, MessageId, NodeId};

/// Largest `delay`, `burst` and `flood`: 1,000 cycles are 4 s at 250 Hz, and a delay keeps
/// every frame of that span in memory.
pub const MAX_CYCLES: u32 = 1000;

/// The faults of one direction.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FaultPlan {
    /// Probability of dropping a frame, 0…1; with [`FaultPlan::burst_cycles`], the long-run
    /// fraction of control cycles lost.
    pub drop: f64,
    /// Mean length of a loss burst, control cycles (0: frames are dropped independently).
    pub burst_cycles: u32,
    /// Control cycles every frame is held back.
    pub delay_cycles: u32,
    /// Probability of sending a frame twice, 0…1.
    pub duplicate: f64,
    /// Probability of holding a frame back behind the next one, 0…1.
    pub reorder: f64,
    /// Probability of flipping one protected bit, 0…1.
    pub flip: f64,
    /// Probability of following a frame with an older one of its id, 0…1.
    pub replay: f64,
    /// Nodes whose every frame is dropped (empty: none).
    pub silence: Vec<NodeId>,
    /// Extra TeleopCommand frames per cycle (0: no flood).
    pub flood_per_cycle: u32,
}

impl FaultPlan {
    /// Whether this plan changes anything.
    pub fn is_clean(&self) -> bool {
        *self == Self::default()
    }
}

/// Faults in both directions of one node's bus connection.
#[derive(Debug, Clone, PartialEq)]
pub struct Faults {
    /// Frames the node sends.
    pub tx: FaultPlan,
    /// Frames the node receives.
    pub rx: FaultPlan,
    /// Seed of the random choices.
    pub seed: u64,
}

impl Default for Faults {
    fn default() -> Self {
        Self {
            tx: FaultPlan::default(),
            rx: FaultPlan::default(),
            seed: 1,
        }
    }
}

/// Why a fault plan could not be read.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum FaultPlanError {
    /// An item is not `name=value`.
    #[error("`{0}`: write faults as `tx.drop=0.05` or `rx.delay=3` (comma-separated)")]
    NotAnItem(String),
    /// The direction is not `tx` or `rx`.
    #[error("`{0}`: the direction is `tx` (frames sent) or `rx` (frames received)")]
    Direction(String),
    /// The fault is unknown.
    #[error(
        "`{0}`: unknown fault; use drop, burst, delay, duplicate, reorder, flip, replay, silence or flood"
    )]
    UnknownFault(String),
    /// A probability outside 0…1 or not a number.
    #[error("`{0}`: a probability is a number from 0 to 1")]
    Probability(String),
    /// A count that is not a whole number.
    #[error("`{0}`: needs a whole number")]
    Count(String),
    /// A count above [`MAX_CYCLES`].
    #[error("`{0}`: at most {MAX_CYCLES}")]
    TooLarge(String),
    /// A node name nobody has.
    #[error("`{0}`: unknown node; use one of {names} or `feedback`", names = node_names())]
    Node(String),
}

fn node_names() -> String {
    NodeId::ALL
        .iter()
        .map(|n| n.name())
        .collect::<Vec<_>>()
        .join(", ")
}

/// The nodes `feedback` stands for: every drive and the IMU.
pub fn feedback_nodes() -> Vec<NodeId> {
    Drive::ALL
        .iter()
        .map(|drive| drive.node())
        .chain([NodeId::Imu])
        .collect()
}

impl FromStr for Faults {
    type Err = FaultPlanError;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let mut faults = Faults::default();
        for item in text.split(',').map(str::trim).filter(|i| !i.is_empty()) {
            let (key, value) = item
                .split_once('=')
                .ok_or_else(|| FaultPlanError::NotAnItem(item.to_owned()))?;
            if key == "seed" {
                faults.seed = value
                    .parse()
                    .map_err(|_| FaultPlanError::Count(item.to_owned()))?;
                continue;
            }
            let (direction, fault) = key
                .split_once('.')
                .ok_or_else(|| FaultPlanError::NotAnItem(item.to_owned()))?;
            let plan = match direction {
                "tx" => &mut faults.tx,
                "rx" => &mut faults.rx,
                _ => return Err(FaultPlanError::Direction(item.to_owned())),
            };
            let probability = || {
                value
                    .parse::<f64>()
                    .ok()
                    .filter(|p| (0.0..=1.0).contains(p))
                    .ok_or_else(|| FaultPlanError::Probability(item.to_owned()))
            };
            let count = || match value.parse::<u32>() {
                Ok(n) if n <= MAX_CYCLES => Ok(n),
                Ok(_) => Err(FaultPlanError::TooLarge(item.to_owned())),
                Err(_) => Err(FaultPlanError::Count(item.to_owned())),
            };
            match fault {
                "drop" => plan.drop = probability()?,
                "delay" => plan.delay_cycles = count()?,
                "burst" => plan.burst_cycles = count()?,
                "duplicate" => plan.duplicate = probability()?,
                "reorder" => plan.reorder = probability()?,
                "flip" => plan.flip = probability()?,
                "replay" => plan.replay = probability()?,
                "flood" => plan.flood_per_cycle = count()?,
                "silence" if value == "feedback" => plan.silence.extend(feedback_nodes()),
                "silence" => plan.silence.push(
                    NodeId::ALL
                        .into_iter()
                        .find(|n| n.name().eq_ignore_ascii_case(value))
                        .ok_or_else(|| FaultPlanError::Node(item.to_owned()))?,
                ),
                _ => return Err(FaultPlanError::UnknownFault(item.to_owned())),
            }
        }
        Ok(faults)
    }
}

impl fmt::Display for Faults {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut items = Vec::new();
        for (direction, plan) in [("tx", &self.tx), ("rx", &self.rx)] {
            let probabilities = [
                ("drop", plan.drop),
                ("duplicate", plan.duplicate),
                ("reorder", plan.reorder),
                ("flip", plan.flip),
                ("replay", plan.replay),
            ];
            for (name, p) in probabilities {
                if p > 0.0 {
                    items.push(format!("{direction}.{name}={p}"));
                }
            }
            if plan.burst_cycles > 0 {
                items.push(format!("{direction}.burst={}", plan.burst_cycles));
            }
            if plan.delay_cycles > 0 {
                items.push(format!("{direction}.delay={}", plan.delay_cycles));
            }
            if plan.flood_per_cycle > 0 {
                items.push(format!("{direction}.flood={}", plan.flood_per_cycle));
            }
            if plan.silence == feedback_nodes() {
                items.push(format!("{direction}.silence=feedback"));
            } else {
                for node in &plan.silence {
                    items.push(format!("{direction}.silence={}", node.name()));
                }
            }
        }
        if items.is_empty() {
            return f.write_str("none");
        }
        items.push(format!("seed={}", self.seed));
        f.write_str(&items.join(","))
    }
}

/// Whether faults may touch frames on `raw_id`: everything but SYNC.
pub fn faultable(raw_id: u16) -> bool {
    raw_id != MessageId::Sync.raw()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_every_fault_and_writes_it_back() {
        let text = "tx.drop=0.05,rx.delay=3,tx.flip=0.01,rx.replay=0.2,tx.duplicate=0.1,\
                    rx.reorder=0.3,tx.flood=40,tx.silence=Imu,rx.drop=0.2,rx.burst=5,seed=7";
        let faults: Faults = text.parse().unwrap();
        assert_eq!(faults.tx.drop, 0.05);
        assert_eq!(faults.rx.delay_cycles, 3);
        assert_eq!(faults.tx.flood_per_cycle, 40);
        assert_eq!(faults.rx.burst_cycles, 5);
        assert_eq!(faults.tx.silence, [NodeId::Imu]);
        assert_eq!(faults.seed, 7);
        assert_eq!(faults.to_string().parse::<Faults>().unwrap(), faults);
    }

    #[test]
    fn feedback_silences_every_drive_and_the_imu() {
        let faults: Faults = "tx.silence=feedback".parse().unwrap();
        assert_eq!(faults.tx.silence, feedback_nodes());
        assert_eq!(faults.tx.silence.len(), 6);
        assert!(faults.rx.is_clean());
    }

    #[test]
    fn bad_items_say_what_to_write() {
        let cases = [
            ("tx.drop", "write faults as"),
            ("up.drop=0.1", "direction"),
            ("tx.melt=1", "unknown fault"),
            ("tx.drop=1.5", "probability"),
            ("tx.drop=x", "probability"),
            ("rx.delay=-1", "whole number"),
            ("rx.delay=4294967295", "at most 1000"),
            ("tx.burst=1001", "at most 1000"),
            ("tx.flood=100000", "at most 1000"),
            ("tx.silence=Toaster", "unknown node"),
            ("seed=abc", "whole number"),
        ];
        for (text, expected) in cases {
            let error = text.parse::<Faults>().unwrap_err().to_string();
            assert!(error.contains(expected), "{text}: {error}");
            assert!(error.contains(text.split(',').next().unwrap()), "{error}");
        }
    }

    #[test]
    fn sync_is_never_faulted() {
        assert!(!faultable(MessageId::Sync.raw()));
        assert!(faultable(MessageId::LegTargets.raw()));
    }
}
