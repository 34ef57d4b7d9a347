//! The moves between standing on the legs and balancing on the wheels, within the drives'
//! ratings and without throwing the robot.
//!
//! # Why not straight into the fold
//!
//! The report's fold blends every joint toward the fold pose at 6 /s: the feet leave the ground
//! at once, the torso drops onto the wheels (1.3 m/s measured) and lunges 0.4 m forward, and the
//! hips need 76 N·m, twice what a leg actuator of this robot's class gives. With 33.5 N·m the
//! legs fold under the torso, it falls onto its wheels and the robot runs away.
//!
//! # The moves
//!
//! The legs cannot put the feet under the hips lower than 2 cm above the wheels' reach (the
//! knees bend backward): the torso reaches the wheels only with the feet 0.10 m behind the hips,
//! the touchdown pose ([`TransferConfig::touchdown`]). So the fold is two joint-space ramps:
//!
//! 1. **Carry** — the planted feet carry the torso down into the touchdown pose, slowly
//!    ([`TransferConfig::carry_rate_rad_s`]): the torso moves forward over the feet as it
//!    sinks, and the wheels take it as it reaches their contact height.
//! 2. **Tuck** — the legs, unloaded, lift into the fold ([`TransferConfig::tuck_rate_rad_s`])
//!    while the balance law holds the robot on its wheels.
//!
//! Standing up runs them backward: the legs untuck to the touchdown pose (the feet reach the
//! ground behind the hips), then carry the torso up into the stance. A robot whose legs already
//! carry it (not on its wheels) goes straight to the stance; one already on its wheels starts
//! the fold at the tuck.

use protocol::Joints;

use crate::legs::kinematics::LegJoints;
use crate::legs::ramp::Ramp;
use crate::math::deg_to_rad;
use crate::time::{Tick, TickRate};

/// Tunables of the moves between legs and wheels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TransferConfig {
    /// The legs' pose when the wheels take the robot: the feet on the ground 0.10 m behind the
    /// hips with the torso at the wheels' contact height.
    pub touchdown: LegJoints,
    /// Largest joint rate while the legs carry the torso down or up, rad/s (reached mid-ramp).
    pub carry_rate_rad_s: f32,
    /// Largest joint rate between the touchdown pose and the fold, rad/s.
    pub tuck_rate_rad_s: f32,
}

impl TransferConfig {
    /// The robot. The touchdown pose puts the foot centre 0.232 m below the hip, 0.10 m behind
    /// it, every joint at least 10° inside its range; from the stance the torso sinks 0.12 m.
    pub const ROBOT: Self = Self {
        touchdown: LegJoints {
            hip_abduction_rad: 0.0,
            hip_pitch_rad: deg_to_rad(40.0),
            knee_rad: deg_to_rad(-84.0),
            ankle_rad: deg_to_rad(-28.0),
        },
        carry_rate_rad_s: 0.6,
        tuck_rate_rad_s: 1.5,
    };

    fn touchdown_pose(&self) -> Joints<f32> {
        let pose = self.touchdown.to_array();
        Joints::from_leg_fn(|_| pose)
    }
}

/// Which way the robot goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Toward {
    /// From the legs onto the wheels (the fold).
    Wheels,
    /// From the wheels onto the legs (standing up).
    Legs,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Phase {
    /// The first ramp; the second follows it toward `then`.
    First { ramp: Ramp, then: Joints<f32> },
    /// The last ramp.
    Last(Ramp),
}

/// A move between legs and wheels, under way.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Transfer {
    config: TransferConfig,
    rate: TickRate,
    toward: Toward,
    phase: Phase,
}

impl Transfer {
    /// A move `toward` the wheels (ending in `goal`, the fold) or the legs (ending in `goal`,
    /// the stance), starting at `now` from the legs at `from`; `on_wheels`: whether the wheels
    /// carry the robot now.
    pub fn new(
        config: TransferConfig,
        rate: TickRate,
        now: Tick,
        toward: Toward,
        from: Joints<f32>,
        goal: Joints<f32>,
        on_wheels: bool,
    ) -> Self {
        let touchdown = config.touchdown_pose();
        let phase = match (toward, on_wheels) {
            (Toward::Wheels, false) => Phase::First {
                ramp: Ramp::new(from, touchdown, now, config.carry_rate_rad_s, rate),
                then: goal,
            },
            (Toward::Wheels, true) => {
                Phase::Last(Ramp::new(from, goal, now, config.tuck_rate_rad_s, rate))
            }
            (Toward::Legs, true) => Phase::First {
                ramp: Ramp::new(from, touchdown, now, config.tuck_rate_rad_s, rate),
                then: goal,
            },
            (Toward::Legs, false) => {
                Phase::Last(Ramp::new(from, goal, now, config.carry_rate_rad_s, rate))
            }
        };
        Self {
            config,
            rate,
            toward,
            phase,
        }
    }

    /// Which way it goes.
    pub fn toward(&self) -> Toward {
        self.toward
    }

    /// Whether the move is in its part on the wheels (the tuck or the untuck), where the
    /// balance law must hold the robot whatever the legs' kinematics say.
    pub fn on_wheels(&self) -> bool {
        matches!(
            (self.toward, self.phase),
            (Toward::Wheels, Phase::Last(_)) | (Toward::Legs, Phase::First { .. })
        )
    }

    /// The leg targets at `now`, and whether the move is over.
    pub fn step(&mut self, now: Tick) -> (Joints<f32>, bool) {
        match self.phase {
            Phase::First { ramp, then } => {
                let (pose, done) = ramp.at(now);
                if done {
                    let peak = match self.toward {
                        Toward::Wheels => self.config.tuck_rate_rad_s,
                        Toward::Legs => self.config.carry_rate_rad_s,
                    };
                    self.phase = Phase::Last(Ramp::new(pose, then, now, peak, self.rate));
                }
                (pose, false)
            }
            Phase::Last(ramp) => ramp.at(now),
        }
    }
}
