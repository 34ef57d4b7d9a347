//! `summary.json`: a run's figures per segment, for people and for scripts, and the short table
//! printed at the end of a run.

use std::path::Path;

use serde::Serialize;

use crate::output::metrics::SegmentSummary;
use crate::output::output_error::OutputError;
use crate::session::run_stats::RunStats;

/// The whole file.
#[derive(Debug, Serialize)]
pub struct Summary<'a> {
    /// Scenario name.
    pub scenario: &'a str,
    /// Bus: `inproc` or an interface name.
    pub bus: &'a str,
    /// `lockstep` or `wall`.
    pub clock: &'a str,
    /// Simulated time, s.
    pub simulated_s: f64,
    /// Wall-clock time, s.
    pub wall_s: f64,
    /// Simulated s per wall s.
    pub real_time_factor: f64,
    /// Control cycles (= MuJoCo steps at 250 Hz) per wall-clock second.
    pub steps_per_s: f64,
    /// Lockstep cycles whose command came late.
    pub missed_cycles: u64,
    /// Real-time cycles past their deadline.
    pub overruns: u64,
    /// Per segment.
    pub segments: &'a [SegmentSummary],
}

impl Summary<'_> {
    /// Counters of the run.
    pub fn from_stats<'a>(
        scenario: &'a str,
        bus: &'a str,
        clock: &'a str,
        stats: &RunStats,
        segments: &'a [SegmentSummary],
    ) -> Summary<'a> {
        Summary {
            scenario,
            bus,
            clock,
            simulated_s: stats.sim_s,
            wall_s: stats.wall_s,
            real_time_factor: stats.real_time_factor(),
            steps_per_s: if stats.wall_s > 0.0 {
                stats.cycles as f64 / stats.wall_s
            } else {
                0.0
            },
            missed_cycles: stats.missed_cycles,
            overruns: stats.overruns,
            segments,
        }
    }

    /// Writes the file, pretty-printed.
    pub fn write(&self, path: &Path) -> Result<(), OutputError> {
        let text = serde_json::to_string_pretty(self).map_err(|e| OutputError::Io {
            path: path.to_owned(),
            source: std::io::Error::other(e),
        })?;
        std::fs::write(path, text + "\n").map_err(|source| OutputError::Io {
            path: path.to_owned(),
            source,
        })
    }
}

/// The segments as a fixed-width text table.
pub fn table(segments: &[SegmentSummary]) -> String {
    let mut out = format!(
        "{:<14} {:>5} {:>6} {:>6} {:>8} {:>8} {:>8} {:>8} {:>5} {:>7} {:>8}\n",
        "segment",
        "mode",
        "from s",
        "to s",
        "fwd m",
        "side m",
        "yaw °",
        "tilt °",
        "fell",
        "limits",
        "rejected"
    );
    for s in segments {
        let rejected: u64 = s.bus.firmware_rejected.iter().sum::<u64>() + s.bus.drives_rejected;
        out.push_str(&format!(
            "{:<14} {:>5} {:>6.1} {:>6.1} {:>8.3} {:>8.3} {:>8.1} {:>8.1} {:>5} {:>7} {:>8}\n",
            truncate(&s.label, 14),
            s.mode,
            s.start_s,
            s.end_s,
            s.forward_m,
            s.lateral_m,
            s.dyaw_deg,
            s.max_tilt_deg,
            if s.fell { "YES" } else { "no" },
            s.joint_limit_violations + s.torque_limit_violations,
            rejected
        ));
    }
    out
}

fn truncate(text: &str, width: usize) -> String {
    text.chars().take(width).collect()
}
