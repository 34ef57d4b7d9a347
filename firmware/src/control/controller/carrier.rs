//! What carries the robot — its legs or its wheels — and what follows for the wheel law and
//! the attitude estimator: whether the balance law may drive, whether the robot still rolls,
//! whether an attitude is needed, and the torso's own acceleration on the wheels.
//!
//! The legs' kinematics that decide it cost ~700 instructions a leg on the MCU, so they run at
//! most once a tick, and only where the answer is not given by the state: between the legs and
//! the wheels (folding, standing up, a controlled stop).

use super::Controller;
use crate::control::estimator::Motion;
use crate::control::fsm::State;
use crate::legs::support::LegStance;
use crate::time::Tick;
use crate::wheels::runaway::lagging_wheel_m_s;

/// A stand-up waits while the body leans more than this from its balance point, rad.
const STAND_LEAN_RAD: f32 = 0.08;

/// … or pitches faster than this, rad/s.
const STAND_STILL_RAD_S: f32 = 0.3;

/// A robot at rest on its wheels, or once its legs unfold still on wheels and feet, this long,
/// s, …
const STAND_REST_S: f32 = 1.0;

/// … and pitching slower than this, rad/s, leans at its balance point, whatever its trim says.
pub(super) const STAND_STEADY_RAD_S: f32 = 0.05;

impl Controller {
    /// Whether the balance law runs (where the wheels are on the ground): in the states that
    /// carry the robot on its wheels, and in `EStop` until the controlled stop cuts the torque.
    pub(super) fn balancing(&self) -> bool {
        match self.state {
            State::EStop | State::Fault => self.stop.is_some_and(|stop| !stop.off()),
            state => state.balancing(),
        }
    }

    /// Ground speed of the axle, m/s: the wheels' joint rate is relative to the body, so the
    /// body's pitch rate is added back.
    pub(super) fn ground_speed_m_s(&self) -> f32 {
        let r = self.config.balance.wheel_radius_m;
        let [_, pitch_rate_rad_s, _] = self.sensors.angular_rate_rad_s;
        r * (self.sensors.mean_wheel_rate_rad_s() + pitch_rate_rad_s)
    }

    /// The wheel furthest behind its reference, told as an axle's speed, m/s (see
    /// [`lagging_wheel_m_s`]): each wheel's ground speed is r (ω + θ̇) with its own rate, its
    /// reference the balance law's plus its share of the turn reference.
    pub(super) fn lagging_wheel_m_s(&self) -> f32 {
        let r = self.config.balance.wheel_radius_m;
        let [_, pitch_rate_rad_s, _] = self.sensors.angular_rate_rad_s;
        let wheels_m_s = self
            .sensors
            .wheel_rate_rad_s
            .map(|rate_rad_s| r * (rate_rad_s + pitch_rate_rad_s));
        lagging_wheel_m_s(
            wheels_m_s,
            self.balance.velocity_ref_m_s(),
            r * self.turn_ref_rad_s,
        )
    }

    /// What the attitude estimator should know of the torso's own acceleration this tick: on
    /// the wheels while the balance law drives them, the change of the ground speed
    /// `r (ω + θ̇)` over the tick; on the legs, whether their feet stride (the torso bounces
    /// at the step rate). Run first in the tick; on the legs it costs no kinematics.
    pub(super) fn motion(&mut self) -> Motion {
        if !(self.balancing() && self.wheels_may_drive()) {
            self.last_ground_m_s = None;
            let striding = self
                .trot_motion()
                .is_some_and(|(_, command)| command.lifts_feet());
            return Motion {
                striding,
                ..Motion::default()
            };
        }
        let ground_m_s = self.ground_speed_m_s();
        let hz = self.config.rate.hz() as f32;
        let accel = self
            .last_ground_m_s
            .map_or(0.0, |last| (ground_m_s - last) * hz);
        self.last_ground_m_s = Some(ground_m_s).filter(|v| v.is_finite());
        Motion {
            on_wheels: true,
            ground_accel_m_s2: if accel.is_finite() { accel } else { 0.0 },
            striding: false,
        }
    }

    /// Whether the balance law needs an attitude now: the state balances and the wheels carry
    /// the robot (as found this tick). Without one (the IMU silent, or its estimator not
    /// started yet: a robot is not calm in the first tenth of a second after power-up) that is
    /// a fault; while the legs still carry the robot it is not.
    pub(super) fn needs_attitude(&self) -> bool {
        self.state.balancing() && self.wheels_carry()
    }

    /// Whether the robot still rolls on its wheels (ground speed above 5 cm/s, or turning) while
    /// they carry it.
    pub(super) fn rolling(&mut self) -> bool {
        let r = self.config.balance.wheel_radius_m;
        let speed_m_s = r * self.sensors.mean_wheel_rate_rad_s();
        let turn_m_s = r * self.sensors.differential_wheel_rate_rad_s();
        self.wheels_may_drive() && (speed_m_s.abs() > 0.05 || turn_m_s.abs() > 0.05)
    }

    /// Whether a robot on its wheels is not yet settled for a stand-up: it still rolls, or its
    /// body still leans more than [`STAND_LEAN_RAD`] from its trim or pitches faster than
    /// [`STAND_STILL_RAD_S`] (a stop's brake leans it forward by up to 13°; legs unfolded
    /// under that lean land their front feet first and stand the robot up nose-down) — unless
    /// it has stood still on its wheels for [`STAND_REST_S`] and pitches slower than
    /// [`STAND_STEADY_RAD_S`]: its lean is then its balance point (the stow moves that point
    /// away from the trim, which does not follow it there, and robots whose lean stayed past
    /// the bound waited on their wheels for good), or, once its legs unfold, has sat as long
    /// still on wheels and feet: its feet then set its pitch (robots whose front feet landed
    /// first rocked back onto their back feet, 15° from the trim, and their legs waited for
    /// good: 60 of the campaign's 500) — or its legs are not yet at the fold a stand-up starts
    /// from
    /// ([`crate::legs::levelling::Levelling::stowed`]), or it has its roll ahead to make or
    /// makes it (`stand_up`).
    pub(super) fn unsettled(&mut self, now: Tick) -> bool {
        self.rolling()
            || (self.wheels_may_drive() && (self.leaning_or_stowing() || self.rolling_ahead(now)))
    }

    /// Whether the body leans or pitches too much for a stand-up, or the legs are not yet
    /// stowed (see [`Controller::unsettled`]).
    pub(super) fn leaning_or_stowing(&self) -> bool {
        let lean_rad = self.sensors.attitude.pitch_rad - self.balance.pitch_trim_rad();
        let [_, pitch_rate_rad_s, _] = self.sensors.angular_rate_rad_s;
        let rested = self.balance.rested_s().max(self.feet_still_s);
        let steady = rested >= STAND_REST_S && pitch_rate_rad_s.abs() < STAND_STEADY_RAD_S;
        let leaning = (lean_rad.abs() > STAND_LEAN_RAD && !steady)
            || pitch_rate_rad_s.abs() > STAND_STILL_RAD_S;
        leaning || !self.levelling.stowed()
    }

    /// On the wheels the balance law always runs; while folding or standing up only once the
    /// measured leg pose puts the wheels on the ground (see [`crate::legs::support`]).
    pub(super) fn wheels_may_drive(&mut self) -> bool {
        if !matches!(self.state, State::Wheels(_)) {
            self.stance();
        }
        self.wheels_carry()
    }

    /// [`Controller::wheels_may_drive`] as far as this tick has found: off the wheels, false
    /// until the legs' stance has been computed. The fold that ends a climb counts as on the
    /// wheels throughout: the climb has set them on the plateau, and the stance, which takes
    /// the ground to be one level, would read the robot as standing on its feet.
    pub(super) fn wheels_carry(&self) -> bool {
        matches!(self.state, State::Wheels(_))
            || (self.auto.climbed && matches!(self.state, State::Folding(_)))
            || self
                .leg_stance
                .is_some_and(|stance| self.config.support.grounds_wheels(&stance))
    }

    /// Where the measured legs put the feet, computed once a tick.
    pub(super) fn stance(&mut self) -> LegStance {
        let (config, joints) = (&self.config, &self.sensors.joint_position_rad);
        *self
            .leg_stance
            .get_or_insert_with(|| config.support.stance_of(&config.geometry, joints))
    }

    /// Targets and goal at the measured joint positions: nothing moves, and nothing jumps
    /// when the drives are (re-)enabled.
    pub(super) fn follow_measured(&mut self) {
        self.legs_rad = self.sensors.joint_position_rad;
        self.goal_rad = self.legs_rad;
    }
}
