//! The process's resident memory as a run goes, sampled once a simulated minute: a long run's
//! growth shows in its report (and `cargo xtask bench` compares the 60th minute with the 5th).
//! A sample reads a line of the kernel's and keeps 16 bytes: the one allocation of the
//! simulation's thread that is not made once per run, once a simulated minute.

/// Simulated seconds between samples.
pub const EVERY_S: u32 = 60;

/// The resident size at one moment of a run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ResidentSample {
    /// Simulated time, s.
    pub time_s: f64,
    /// Resident set size, bytes.
    pub bytes: u64,
}

/// Samples taken so far.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Resident {
    samples: Vec<ResidentSample>,
}

impl Resident {
    /// Samples the process's resident size if `cycle` (at `control_hz`) is on a whole
    /// simulated minute; a platform that cannot tell is not sampled.
    pub fn cycle(&mut self, cycle: u32, control_hz: u32, time_s: f64) {
        let every = EVERY_S.saturating_mul(control_hz.max(1));
        if cycle == 0 || cycle % every != 0 {
            return;
        }
        if let Some(stats) = memory_stats::memory_stats() {
            self.samples.push(ResidentSample {
                time_s,
                bytes: u64::try_from(stats.physical_mem).unwrap_or(u64::MAX),
            });
        }
    }

    /// The samples, in time order.
    pub fn samples(&self) -> &[ResidentSample] {
        &self.samples
    }

    /// The first sample at or after `time_s`.
    pub fn at(&self, time_s: f64) -> Option<ResidentSample> {
        self.samples.iter().copied().find(|s| s.time_s >= time_s)
    }

    /// The last sample.
    pub fn last(&self) -> Option<ResidentSample> {
        self.samples.last().copied()
    }

    /// `"48.1 MB at 5.0 min, 48.3 MB at 60.0 min (+0.2 MB)"` from the 5th minute to the last,
    /// or the last alone for a shorter run; `None` before the first minute.
    pub fn describe(&self) -> Option<String> {
        let last = self.last()?;
        let mb = |bytes: u64| bytes as f64 / 1e6;
        let at = |s: ResidentSample| format!("{:.1} MB at {:.1} min", mb(s.bytes), s.time_s / 60.0);
        Some(
            match self.at(300.0).filter(|early| early.time_s < last.time_s) {
                Some(early) => format!(
                    "{}, {} ({:+.1} MB)",
                    at(early),
                    at(last),
                    mb(last.bytes) - mb(early.bytes)
                ),
                None => at(last),
            },
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_once_a_simulated_minute_and_describes_the_growth_from_the_fifth() {
        let mut resident = Resident::default();
        for cycle in 0..=(61 * 60 * 250) {
            resident.cycle(cycle, 250, f64::from(cycle) / 250.0);
        }
        assert_eq!(resident.samples().len(), 61);
        assert_eq!(resident.at(300.0).map(|s| s.time_s), Some(300.0));
        let text = resident.describe().unwrap();
        assert!(
            text.contains("at 5.0 min") && text.contains("at 61.0 min"),
            "{text}"
        );
        assert!(Resident::default().describe().is_none());
    }
}
