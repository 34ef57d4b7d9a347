//! The torques the drives applied over a segment, per joint type and for the wheels: their peak
//! and their root mean square, the figures a drive's rating is checked against (the peak
//! against its peak torque, the RMS against its continuous torque).

use serde::Serialize;

use crate::session::simulator::Simulator;

/// Peak and RMS torque of one kind of joint, N·m.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct TorqueFigure {
    /// Largest |torque| any of these joints applied, N·m.
    pub peak_nm: f64,
    /// Root mean square over the segment of the most loaded of these joints, N·m.
    pub rms_nm: f64,
}

/// The segment's torque figures (in `summary.json`).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct TorqueFigures {
    /// Hip abduction, all four legs.
    pub hip_abduction: TorqueFigure,
    /// Hip pitch.
    pub hip_pitch: TorqueFigure,
    /// Knee.
    pub knee: TorqueFigure,
    /// Ankle.
    pub ankle: TorqueFigure,
    /// Wheels.
    pub wheel: TorqueFigure,
    /// Physics steps in which some drive cut a torque to its rating.
    pub saturated_steps: u64,
}

/// Accumulates [`TorqueFigures`] cycle by cycle.
#[derive(Debug, Clone, Default)]
pub struct TorqueTracker {
    peak_nm: [f64; 5],
    /// Sum of squares per joint (16 leg joints, then 2 wheels).
    squares: [f64; 18],
    cycles: u64,
    saturated_at_start: u64,
    saturated_now: u64,
}

impl TorqueTracker {
    /// Starts on the simulator's present state (its saturation count so far).
    pub fn start(sim: &Simulator) -> Self {
        let saturated = sim.hardware().saturated_steps();
        Self {
            saturated_at_start: saturated,
            saturated_now: saturated,
            ..Self::default()
        }
    }

    /// Takes one cycle: the torques applied over the period that just ended.
    pub fn observe(&mut self, sim: &Simulator) {
        let legs = sim.physics().leg_efforts_nm();
        for (i, torque) in legs.iter().enumerate() {
            self.peak_nm[i % 4] = self.peak_nm[i % 4].max(torque.abs());
            self.squares[i] += torque * torque;
        }
        for (i, torque) in sim.hardware().wheel_torque_nm().iter().enumerate() {
            self.peak_nm[4] = self.peak_nm[4].max(torque.abs());
            self.squares[16 + i] += torque * torque;
        }
        self.cycles += 1;
        self.saturated_now = sim.hardware().saturated_steps();
    }

    /// The figures so far.
    pub fn figures(&self) -> TorqueFigures {
        let n = self.cycles.max(1) as f64;
        let rms = |joints: &[usize]| {
            joints
                .iter()
                .map(|&i| (self.squares[i] / n).sqrt())
                .fold(0.0, f64::max)
        };
        let leg_joint = |k: usize| TorqueFigure {
            peak_nm: self.peak_nm[k],
            rms_nm: rms(&[k, k + 4, k + 8, k + 12]),
        };
        TorqueFigures {
            hip_abduction: leg_joint(0),
            hip_pitch: leg_joint(1),
            knee: leg_joint(2),
            ankle: leg_joint(3),
            wheel: TorqueFigure {
                peak_nm: self.peak_nm[4],
                rms_nm: rms(&[16, 17]),
            },
            saturated_steps: self.saturated_now - self.saturated_at_start,
        }
    }
}
