//! The run cut into the scenario's segments: one [`SegmentTracker`] at a time, a new one each
//! time the simulated clock passes the next segment's start.

use crate::output::metrics::{BusCounters, SegmentSummary, SegmentTracker};
use crate::scene::Feature;
use crate::session::config::SegmentSpec;
use crate::session::simulator::Simulator;

/// The segments of a run, summarised as it goes.
#[derive(Debug)]
pub(crate) struct Segments {
    specs: Vec<SegmentSpec>,
    /// The scene's obstacles, for each segment's crossings.
    obstacles: Vec<Feature>,
    done: Vec<SegmentSummary>,
    current: Option<(usize, SegmentTracker)>,
}

impl Segments {
    /// Segments starting where `specs` say (none: the whole run is one segment, `run`), in a
    /// scene with `obstacles`.
    pub(crate) fn new(specs: &[SegmentSpec], obstacles: Vec<Feature>) -> Self {
        let specs = if specs.is_empty() {
            vec![SegmentSpec {
                start_s: 0.0,
                label: "run".into(),
                mode: String::new(),
            }]
        } else {
            specs.to_vec()
        };
        Self {
            specs,
            obstacles,
            done: Vec::new(),
            current: None,
        }
    }

    /// Takes one cycle into the segment it belongs to, closing the one before if it ended.
    pub(crate) fn observe(&mut self, sim: &Simulator, counters: BusCounters) {
        let due = self
            .specs
            .iter()
            .rposition(|spec| spec.start_s <= sim.time_s() + 1e-9)
            .unwrap_or(0);
        match &mut self.current {
            Some((index, current)) if *index == due => current.observe(sim, counters),
            _ => {
                if let Some((_, done)) = self.current.take() {
                    self.done.push(done.finish());
                }
                let spec = &self.specs[due];
                let mut fresh =
                    SegmentTracker::start(&spec.label, &spec.mode, sim, counters, &self.obstacles);
                fresh.observe(sim, counters);
                self.current = Some((due, fresh));
            }
        }
    }

    /// Every segment's figures, the running one closed.
    pub(crate) fn finish(mut self) -> Vec<SegmentSummary> {
        if let Some((_, done)) = self.current.take() {
            self.done.push(done.finish());
        }
        self.done
    }
}
