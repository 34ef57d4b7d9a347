//! The fold: from standing on the legs to balancing on the wheels, within the drives' ratings
//! and without throwing the robot.
//!
//! # Why not straight into the fold
//!
//! The report's fold blends every joint toward the fold pose at 6 /s: the feet leave the ground
//! at once, the torso drops onto the wheels (1.3 m/s measured) and lunges 0.4 m forward, and the
//! hips need 76 N·m, twice what a leg actuator of this robot's class gives. With 33.5 N·m the
//! legs fold under the torso, it falls onto its wheels and the robot runs away.
//!
//! # The move
//!
//! The legs cannot put the feet under the hips lower than 2 cm above the wheels' reach (the
//! knees bend backward): the torso reaches the wheels only with the feet 0.10 m behind the hips,
//! the touchdown pose ([`TransferConfig::touchdown`]). So the fold is joint-space ramps:
//!
//! 0. **Settle** — from a trot, the feet come down under the hips into the stance first, so
//!    that all four are planted before they carry the torso (folding straight from mid-stride,
//!    a foot still in the air landed late and the robot ran backward a metre).
//! 1. **Carry** — the planted feet carry the torso down toward the touchdown pose, slowly
//!    ([`TransferConfig::carry_rate_rad_s`]): the torso moves forward over the feet as it
//!    sinks, levelled by the legs at its low end ([`TransferConfig::level_per_rad`]), and the
//!    carry ends where the wheels take it, at the latest in the touchdown pose.
//! 2. **Tuck** — the legs, unloaded, lift into the fold ([`TransferConfig::tuck_rate_rad_s`])
//!    while the balance law holds the robot on its wheels.
//!
//! A robot already on its wheels starts at the tuck. Standing up does not run this backward:
//! from the touchdown pose the feet, 0.10 m behind the hips, put 73 % of the weight on the
//! front legs, which saturate and tip the robot over nose first (measured, on ideal and on
//! rated drives); the report's smoothed stand-up lifts it within the rating.

use protocol::{Joints, Leg};

use crate::legs::kinematics::LegJoints;
use crate::legs::ramp::Ramp;
use crate::math::deg_to_rad;
use crate::time::{Tick, TickRate};

/// Tunables of the fold.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TransferConfig {
    /// The legs' pose when the wheels take the robot: the feet on the ground 0.10 m behind the
    /// hips with the torso at the wheels' contact height.
    pub touchdown: LegJoints,
    /// Largest joint rate while the feet come down into the stance, rad/s.
    pub settle_rate_rad_s: f32,
    /// Largest joint rate while the legs carry the torso down, rad/s (reached mid-ramp).
    pub carry_rate_rad_s: f32,
    /// Largest joint rate between the touchdown pose and the fold, rad/s.
    pub tuck_rate_rad_s: f32,
    /// How far the carry moves the legs at the low end of the torso back toward the stance,
    /// as a share of the way per rad of pitch (see [`Transfer::step`]).
    pub level_per_rad: f32,
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
        settle_rate_rad_s: 2.0,
        carry_rate_rad_s: 0.6,
        tuck_rate_rad_s: 2.5,
        level_per_rad: 4.0,
    };

    fn touchdown_pose(&self) -> Joints<f32> {
        let pose = self.touchdown.to_array();
        Joints::from_leg_fn(|_| pose)
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Phase {
    /// Into the stance; the carry and the tuck into `fold` follow.
    Settle { ramp: Ramp, fold: Joints<f32> },
    /// The carry from the stance (where its ramp starts); the tuck into `fold` follows it.
    Carry { ramp: Ramp, fold: Joints<f32> },
    /// The tuck.
    Tuck(Ramp),
}

/// A fold under way.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Transfer {
    config: TransferConfig,
    rate: TickRate,
    phase: Phase,
}

impl Transfer {
    /// A fold into `fold`, starting at `now` from the legs at `from`, through `stance` (the
    /// legs' pose standing); `on_wheels`: whether the wheels carry the robot already (then only
    /// the tuck is left).
    pub fn new(
        config: TransferConfig,
        rate: TickRate,
        now: Tick,
        from: Joints<f32>,
        stance: Joints<f32>,
        fold: Joints<f32>,
        on_wheels: bool,
    ) -> Self {
        let phase = if on_wheels {
            Phase::Tuck(Ramp::new(from, fold, now, config.tuck_rate_rad_s, rate))
        } else {
            Phase::Settle {
                ramp: Ramp::new(from, stance, now, config.settle_rate_rad_s, rate),
                fold,
            }
        };
        Self {
            config,
            rate,
            phase,
        }
    }

    /// Whether the feet are still on the ground (settling into the stance or carrying the
    /// torso down; the tuck not begun).
    pub fn on_feet(&self) -> bool {
        matches!(self.phase, Phase::Settle { .. } | Phase::Carry { .. })
    }

    /// The leg targets at `now`, and whether the fold is over.
    ///
    /// `wheels_down`: whether the planted feet have let the torso down onto its wheels. The
    /// carry ends there: carried on past the wheels' touchdown, the legs tipped the torso
    /// forward onto its front feet (10° and more) and held it there, and the tuck started
    /// 0.6 s later.
    ///
    /// `pitch_rad`: the torso's pitch, positive nose down. The feet behind the hips put most of
    /// the weight on the front legs, whose servos sag more and tip the torso nose down as it
    /// sinks; the carry keeps the legs at its low end that share nearer the stance
    /// ([`TransferConfig::level_per_rad`] per rad), so that the wheels take it level.
    pub fn step(&mut self, now: Tick, wheels_down: bool, pitch_rad: f32) -> (Joints<f32>, bool) {
        match self.phase {
            Phase::Settle { ramp, fold } => {
                let (pose, done) = ramp.at(now);
                if done {
                    let (touchdown, peak) =
                        (self.config.touchdown_pose(), self.config.carry_rate_rad_s);
                    let ramp = Ramp::new(pose, touchdown, now, peak, self.rate);
                    self.phase = Phase::Carry { ramp, fold };
                }
                (pose, false)
            }
            Phase::Carry { ramp, fold } => {
                let (planned, done) = ramp.at(now);
                let pose = self.level(planned, ramp.from(), pitch_rad);
                if done || wheels_down {
                    let peak = self.config.tuck_rate_rad_s;
                    self.phase = Phase::Tuck(Ramp::new(pose, fold, now, peak, self.rate));
                }
                (pose, false)
            }
            Phase::Tuck(ramp) => ramp.at(now),
        }
    }

    /// `planned` with the legs at the low end of the torso moved back toward `stance` by
    /// `pitch_rad` (the front legs for nose down, the back legs for nose up).
    fn level(&self, planned: Joints<f32>, stance: &Joints<f32>, pitch_rad: f32) -> Joints<f32> {
        let share = self.config.level_per_rad * pitch_rad;
        if !share.is_finite() {
            return planned;
        }
        let (front, back) = (share.clamp(0.0, 1.0), (-share).clamp(0.0, 1.0));
        let mut pose = planned;
        for leg in Leg::ALL {
            let amount = if leg.is_front() { front } else { back };
            for (angle, target) in pose.leg_mut(leg).iter_mut().zip(stance.leg(leg)) {
                *angle += amount * (target - *angle);
            }
        }
        pose
    }
}
