//! The legs' goal each tick: the trot's targets, or the stance when they neither trot nor walk,
//! and its pitch levelling after a stand-up from the wheels.
//!
//! Unfolded from the wheels, the feet land 8.5 cm behind the front hips and 24.5 cm behind
//! the back ones, and the front legs carry most of the weight on the way up. On robots with
//! heavy legs or drives rated low the front hips reached their peak torque as the stand-up
//! ended, the legs swung back under the torso and the robot tipped 30° nose down onto its
//! front feet, or over. Standing, the torso tells: it pitches nose down as the front legs
//! give way. So the legs at the high end stand shallower by what the torso pitches past a
//! deadband, which moves the weight back onto them. Recomputed every tick from the measured
//! pitch, it is a proportional correction: a torso that would pitch θ₀ ends halfway between θ₀
//! and the deadband (within the posture's depths). Only after a stand-up from the wheels:
//! levelled, a stand after a trot swayed past the 5 cm an `X` allows.

use super::Controller;
use crate::control::fsm::{LegMotion, State};
use crate::legs::kinematics::{IkError, LegJoints};
use crate::time::Tick;
use protocol::Leg;

/// How far the torso may pitch from level before the legs at its high end lower it, rad: past
/// the attitude estimate's error and a stand's sway.
const LEVEL_DEADBAND_RAD: f32 = 0.05;

/// A stand after a stand-up from the wheels whose torso stays pitched further than this,
/// rad (15°), …
const TILT_REPORT_RAD: f32 = 0.26;

/// … for this long, ms, is reported ([`protocol::FaultFlags::STAND_TILTED`]): the levelling
/// has reached its depths, or the legs at the low end give way. The operator's request clears
/// the report; a stand still tilted is reported again after as long.
const TILT_REPORT_MS: u32 = 1_000;

/// The watch on a stand after a stand-up from the wheels that stays tilted.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(super) struct StandTilt {
    /// Since when the torso has been pitched past [`TILT_REPORT_RAD`].
    since: Option<Tick>,
    /// Whether it has stayed so for [`TILT_REPORT_MS`]: kept until the operator's next
    /// request, even if the torso comes level meanwhile.
    reported: bool,
}

impl StandTilt {
    /// Whether the stand is reported tilted.
    pub(super) fn reported(&self) -> bool {
        self.reported
    }
}

impl Controller {
    /// Each leg's stance goal `[FL, FR, BL, BR]` at `depth_m` below its hip, the legs at the
    /// torso's high end shallower by as much as would turn it by what it pitches past
    /// [`LEVEL_DEADBAND_RAD`] (within the posture's depths), once the legs alone carry a robot
    /// that stood up from its wheels and its attitude is known at `now`.
    pub(super) fn stance_goals(&self, now: Tick, depth_m: f32) -> [Result<LegJoints, IkError>; 4] {
        let config = &self.config;
        let posture = &config.posture;
        let pitch_rad = self.sensors.attitude.pitch_rad;
        let over_rad =
            pitch_rad - crate::math::clamp(pitch_rad, -LEVEL_DEADBAND_RAD, LEVEL_DEADBAND_RAD);
        let levelling = self.risen
            && !self.wheels_carry()
            && self.sensors.attitude_known(now)
            && over_rad.is_finite();
        if !levelling {
            return [posture.stance(&config.geometry, &config.limits, depth_m); 4];
        }
        // Pitch is positive nose down: the back hips are then the high end.
        let span_m = 2.0 * config.trot.hips.x_m;
        let raised = |by_m: f32| {
            let depth = depth_m - by_m.max(0.0);
            crate::math::clamp(depth, posture.depth_min_m, posture.depth_max_m)
        };
        let front = posture.stance(&config.geometry, &config.limits, raised(-over_rad * span_m));
        let back = posture.stance(&config.geometry, &config.limits, raised(over_rad * span_m));
        [front, front, back, back]
    }

    /// One tick of the watch on the stand after a stand-up from the wheels: a torso its legs
    /// carry, pitched past [`TILT_REPORT_RAD`] for [`TILT_REPORT_MS`], is reported. Robots
    /// whose front legs gave way on the way up stood 30–32° nose down on their front feet,
    /// their front drives at their rating, and nothing said so. Nothing moves for it: the
    /// operator decides.
    pub(super) fn watch_stand_tilt(&mut self, now: Tick) {
        let standing = matches!(
            self.state,
            State::Standing(_) | State::Legs(LegMotion::Stand)
        ) && self.risen
            && !self.wheels_carry()
            && self.sensors.attitude_known(now);
        let tilted = standing && self.sensors.attitude.pitch_rad.abs() > TILT_REPORT_RAD;
        if !tilted {
            self.stand_tilt.since = None;
            return;
        }
        let since = *self.stand_tilt.since.get_or_insert(now);
        if now.since(since) >= self.config.rate.ticks_from_ms(TILT_REPORT_MS) {
            self.stand_tilt.reported = true;
        }
    }

    /// Whether the legs will stand after a stand-up from the wheels once in `next`: into a
    /// stand-up from the wheels or a fold, or from a state whose legs this tick has already
    /// found on the wheels, through it into the stand, and no further. (A fold stopped before
    /// its feet left the ground counts as from the wheels: its stand is levelled as well.
    /// Finding the stance on the transition's tick for it cost 1,200 instructions at the MCU's
    /// worst tick.)
    pub(super) fn risen_into(&mut self, next: State) {
        let standing = matches!(self.state, State::Standing(_));
        self.risen = match next {
            State::Standing(_) if standing => self.risen,
            // `wheels_carry` holds on the wheels whatever the stance.
            State::Standing(_) => matches!(self.state, State::Folding(_)) || self.wheels_carry(),
            State::Legs(LegMotion::Stand) => {
                self.risen
                    && matches!(
                        self.state,
                        State::Standing(_) | State::Legs(LegMotion::Stand)
                    )
            }
            _ => false,
        };
    }

    /// This tick's goal for every leg (`goal_rad`): the trot's targets while it trots, else
    /// the stance at `depth_m` ([`Controller::stance_goals`]). A goal the IK refuses keeps the
    /// leg's last one and is counted.
    pub(super) fn leg_goal(&mut self, now: Tick, depth_m: f32) {
        let config = &self.config;
        let goals: [Result<LegJoints, _>; 4] = match self.trot_motion() {
            Some((direction, command)) => self.trot.targets(
                direction,
                config.posture.trot_depth_for(self.teleop.body_height_m),
                &command,
                &self.sensors.attitude,
                &config.geometry,
                &config.limits,
                &config.posture,
            ),
            None => self.stance_goals(now, depth_m),
        };
        for (leg, goal) in Leg::ALL.into_iter().zip(goals) {
            match goal {
                Ok(joints) => *self.goal_rad.leg_mut(leg) = joints.to_array(),
                Err(_) => self.ik_failures = self.ik_failures.saturating_add(1),
            }
        }
    }
}
