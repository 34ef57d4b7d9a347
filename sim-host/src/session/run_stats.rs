//! What a run reports about itself, and why a run stops early.

use std::time::Duration;

use crate::output::output_error::OutputError;
use host_can::bus::BusError;

/// Counters of one run.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RunStats {
    /// Control cycles simulated.
    pub cycles: u64,
    /// Lockstep: cycles in which the controller's wheel command did not arrive in time (the
    /// simulation stepped on the drives' previous commands).
    pub missed_cycles: u64,
    /// Real time: cycles that finished after their deadline.
    pub overruns: u64,
    /// Frames the simulator sent.
    pub frames_sent: u64,
    /// Frames the simulator received.
    pub frames_received: u64,
    /// Simulated time, s.
    pub sim_s: f64,
    /// Wall-clock time, s.
    pub wall_s: f64,
}

impl RunStats {
    /// Simulated seconds per wall-clock second.
    pub fn real_time_factor(&self) -> f64 {
        if self.wall_s > 0.0 {
            self.sim_s / self.wall_s
        } else {
            0.0
        }
    }

    pub(crate) fn set_wall(&mut self, wall: Duration) {
        self.wall_s = wall.as_secs_f64();
    }
}

/// Why a run stopped before its end.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RunError {
    /// The bus failed.
    #[error(transparent)]
    Bus(#[from] BusError),
    /// A frame could not be encoded (a bug: message sizes are checked at compile time).
    #[error("could not encode a frame: {0:?}")]
    Encode(protocol::EncodeError),
    /// Writing an output failed.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// The physics diverged (NaN): the model or a command is wrong.
    #[error("the simulation diverged at t = {time_s:.3} s (non-finite state)")]
    Diverged {
        /// When, s.
        time_s: f64,
    },
}

impl From<protocol::EncodeError> for RunError {
    fn from(e: protocol::EncodeError) -> Self {
        RunError::Encode(e)
    }
}
