//! What the cells judge from a run's records: ground truth per cycle.

use crate::faults::rig::CycleRecord;

pub(super) fn fell(records: &[CycleRecord]) -> bool {
    records.iter().any(CycleRecord::fallen)
}

pub(super) fn max_tilt_deg(records: &[CycleRecord]) -> f64 {
    records.iter().map(|r| r.tilt_deg).fold(0.0, f64::max)
}

pub(super) fn forward_m(records: &[CycleRecord]) -> f64 {
    match (records.first(), records.last()) {
        (Some(a), Some(b)) => b.torso_pos_m[0] - a.torso_pos_m[0],
        _ => 0.0,
    }
}

pub(super) fn records_from(records: &[CycleRecord], from_s: f64) -> &[CycleRecord] {
    let from_us = (from_s * 1e6) as u64;
    let start = records.partition_point(|r| r.time_us < from_us);
    records.get(start..).unwrap_or_default()
}

/// Largest change of any leg target from one tick to the next, rad.
pub(super) fn max_target_step(records: &[CycleRecord]) -> f32 {
    records
        .windows(2)
        .filter_map(|w| match (&w[0].leg_targets_rad, &w[1].leg_targets_rad) {
            (Some((a, _)), Some((b, _))) => Some(
                a.iter()
                    .zip(b)
                    .map(|(x, y)| (x - y).abs())
                    .fold(0.0, f32::max),
            ),
            _ => None,
        })
        .fold(0.0, f32::max)
}
