//! The trot: diagonal pairs FL+BR and FR+BL half a cycle apart (report section 6.3), driven by
//! an integer [`Phase`] so the gait after ten hours is the gait after ten seconds.
//!
//! Walking backward runs the phase backward in time. (The report's `leg_backward` only swapped
//! which pair leads, which is the forward gait shifted by half a cycle: its robot could not
//! have walked backward.)

use protocol::Leg;

use crate::control::fsm::Direction;
use crate::legs::foot_trajectory::FootTrajectory;
use crate::legs::kinematics::{IkError, LegGeometry, LegJoints};
use crate::legs::phase::{Phase, PhaseStep, HALF_CYCLE};
use crate::legs::posture::Posture;
use crate::legs::sine_gait::SineGait;
use crate::limits::JointLimits;
use crate::time::TickRate;

/// Which foot-motion generator drives the trot.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Generator {
    /// The report's joint-space sinusoids (reproduction).
    Sine(SineGait),
    /// Stance line and swing arc through the IK (the default walking gait).
    Cartesian(FootTrajectory),
}

/// Trot settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrotParams {
    /// Stride frequency, mHz (the report's 1 Hz = 1000).
    pub frequency_millihz: u32,
    /// Foot-motion generator.
    pub generator: Generator,
}

impl TrotParams {
    /// The default walking gait: 1 Hz, Cartesian foot path.
    pub const DEFAULT: Self = Self {
        frequency_millihz: 1000,
        generator: Generator::Cartesian(FootTrajectory::DEFAULT),
    };
    /// The report's gait: 1 Hz joint-space sinusoids.
    pub const REPORT: Self = Self {
        frequency_millihz: 1000,
        generator: Generator::Sine(SineGait::REPORT),
    };
}

/// Phase offset of a leg within the trot: FL and BR lead, FR and BL follow half a cycle later.
pub const fn pair_offset(leg: Leg) -> u32 {
    match leg {
        Leg::Fl | Leg::Br => 0,
        Leg::Fr | Leg::Bl => HALF_CYCLE,
    }
}

/// A running trot.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Trot {
    params: TrotParams,
    step: PhaseStep,
    phase: Phase,
}

impl Trot {
    /// `None` if the frequency is zero or not below the tick rate.
    pub const fn new(params: TrotParams, rate: TickRate) -> Option<Self> {
        match PhaseStep::new(params.frequency_millihz, rate) {
            Some(step) => Some(Self {
                params,
                step,
                phase: Phase::from_count(0),
            }),
            None => None,
        }
    }

    /// Back to the start of a cycle.
    pub fn restart(&mut self) {
        self.phase = Phase::default();
    }

    /// One tick forward.
    pub fn advance(&mut self) {
        self.phase.advance(self.step);
    }

    /// The cycle phase.
    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// Sets the cycle phase (for tests and replays).
    pub fn set_phase(&mut self, phase: Phase) {
        self.phase = phase;
    }

    /// The phase step per tick.
    pub fn step(&self) -> PhaseStep {
        self.step
    }

    /// The phase `leg` sees when walking in `direction`.
    pub fn leg_phase(&self, leg: Leg, direction: Direction) -> Phase {
        let base = match direction {
            Direction::Forward => self.phase,
            Direction::Backward => self.phase.reversed(),
        };
        base.shifted(pair_offset(leg))
    }

    /// Joint targets of all four legs (in [`Leg::ALL`] order) at the present phase, for a
    /// stance `depth_m` below the hips and a stride scaled by `scale` (0…1).
    pub fn targets(
        &self,
        direction: Direction,
        depth_m: f32,
        scale: f32,
        geometry: &LegGeometry,
        limits: &JointLimits,
        posture: &Posture,
    ) -> [Result<LegJoints, IkError>; 4] {
        Leg::ALL.map(|leg| {
            let phase = self.leg_phase(leg, direction);
            match self.params.generator {
                Generator::Sine(sine) => Ok(sine.joints(phase, scale)),
                Generator::Cartesian(path) => {
                    let (x_m, z_m) = path.foot(phase, depth_m, scale);
                    posture.foot_ik(geometry, limits, x_m, -z_m)
                }
            }
        })
    }
}
