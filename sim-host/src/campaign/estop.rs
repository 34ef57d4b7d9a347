//! The E-stop's figures, from the latch on, for the campaign's E-stop scenario and
//! `tests/estop_ss1.rs` alike (an SS1 stop: under control to rest, then every drive torque-free
//! by the deadline and ever after, the stop reported throughout).

use firmware::control::fsm::State;
use protocol::FaultFlags;

use crate::faults::rig::{CycleRecord, Rig, PERIOD_US};

/// What one E-stop did, from the latch on.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StopFigures {
    /// Horizontal torso speed when the latch went out, m/s.
    pub speed_at_latch_m_s: f64,
    /// From the latch until the torso's horizontal speed first fell below 2 cm/s, s.
    pub rest_after_s: Option<f64>,
    /// Largest tilt from the latch until rest (or torque-off if never at rest), degrees.
    pub max_tilt_to_rest_deg: f64,
    /// From the latch until the controller disabled every drive and every drive was
    /// torque-free, s.
    pub off_after_s: Option<f64>,
    /// Whether every cycle from the latch on reported `EStop` and `ESTOP_LATCHED`.
    pub reported: bool,
    /// Whether every drive stayed torque-free from torque-off to the end.
    pub held: bool,
    /// Fastest downward torso speed from the latch until torque-off, m/s.
    pub max_drop_before_off_m_s: f64,
    /// … from torque-off to the end, m/s.
    pub max_drop_after_off_m_s: f64,
    /// Tilt at the end, degrees.
    pub final_tilt_deg: f64,
}

/// Accumulates [`StopFigures`] cycle by cycle.
#[derive(Debug, Clone)]
pub struct StopTracker {
    figures: StopFigures,
    /// Cycles observed since the latch (time from whole cycles: a sum of 4 ms steps would put
    /// a torque-off at the deadline 1e-15 s past it).
    cycles: u64,
}

impl StopTracker {
    /// Starts at the latch, on the rig's present state.
    pub fn start(rig: &Rig) -> Self {
        let torso = rig.sim().physics().torso();
        Self {
            figures: StopFigures {
                speed_at_latch_m_s: torso.vel_m_s[0].hypot(torso.vel_m_s[1]),
                reported: true,
                held: true,
                ..StopFigures::default()
            },
            cycles: 0,
        }
    }

    /// Takes the cycle the rig just ran (`record`, its last).
    pub fn observe(&mut self, rig: &Rig, record: &CycleRecord) {
        self.cycles += 1;
        let elapsed_s = (self.cycles * PERIOD_US) as f64 / 1e6;
        let f = &mut self.figures;
        let torso = rig.sim().physics().torso();
        let tilt = record.tilt_deg;
        let drop = -torso.vel_m_s[2];
        f.reported &=
            record.state == Some(State::EStop) && record.faults.contains(FaultFlags::ESTOP_LATCHED);
        let drives_off = record.torque_off.iter().all(|&o| o);
        let controller_off = record.leg_targets_rad.is_some_and(|(_, enabled)| !enabled)
            && record.wheel_torque_nm == Some([0.0; 2]);
        if f.off_after_s.is_none() {
            f.max_drop_before_off_m_s = f.max_drop_before_off_m_s.max(drop);
            if f.rest_after_s.is_none() {
                f.max_tilt_to_rest_deg = f.max_tilt_to_rest_deg.max(tilt);
            }
            if drives_off && controller_off {
                f.off_after_s = Some(elapsed_s);
            }
        } else {
            f.held &= drives_off && controller_off;
            f.max_drop_after_off_m_s = f.max_drop_after_off_m_s.max(drop);
        }
        if f.rest_after_s.is_none() && torso.vel_m_s[0].hypot(torso.vel_m_s[1]) < 0.02 {
            f.rest_after_s = Some(elapsed_s);
        }
        f.final_tilt_deg = tilt;
    }

    /// The figures.
    pub fn finish(self) -> StopFigures {
        self.figures
    }
}
