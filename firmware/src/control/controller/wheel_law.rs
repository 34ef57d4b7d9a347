//! The wheels' law: the balance law on their common mode, the turn loop on their difference,
//! and the runaway watch over both. What the state asks for becomes a speed reference (ground
//! speed, m/s) and a turn reference (half the wheels' rate difference, rad/s).

use super::{Controller, TURN_ACCEL_RAD_S2};
use crate::control::fsm::{Direction, State, WheelMotion};
use crate::control::steering::within;
use crate::time::Tick;
use crate::wheels::balance::BalanceInput;
use crate::wheels::runaway::RunawayInput;
use crate::wheels::wheel::mix;

/// How long after a drop's hold a stall is not taken for a riser, ms (a robot that landed
/// hard off a plateau tripped the stall watch 1.3 s later and began to climb at the edge).
const LANDING_NO_CLIMB_MS: u32 = 2_000;

/// Share of the speed reference a robot whose stall watch has tripped still rolls at, in the
/// reference's direction, for the mode riding clear of a slope to roll on instead of stopping:
/// a riser stops the wheels within the collision's few ticks; the foot of a slope the robot
/// runs down only slows it (the wheels meet the flat at the lean that held it on the slope,
/// and it kept 60 % of its speed).
const ROLLING_ON_SHARE: f32 = 0.5;

/// Whether a tripped stall watch's robot still rolls on (see [`ROLLING_ON_SHARE`]).
fn rolling_on(input: &RunawayInput) -> bool {
    let wanted = input.velocity_ref_m_s;
    wanted != 0.0 && input.ground_speed_m_s * wanted.signum() > ROLLING_ON_SHARE * wanted.abs()
}

impl Controller {
    /// This tick's wheel torques `[left, right]` from the balance law and the turn loop (none
    /// while the attitude is unknown).
    pub(super) fn wheel_law(&mut self, now: Tick, dt_s: f32) -> [f32; 2] {
        if !self.sensors.attitude_known(now) {
            return [0.0; 2];
        }
        self.set_trim_rules(now);
        if matches!(self.state, State::Standing(_)) {
            self.roll_ahead_tick(now, dt_s);
        }
        let (velocity_ref_m_s, turn_ref_rad_s) = self.wheel_references(now);
        let [_, pitch_rate_rad_s, _] = self.sensors.angular_rate_rad_s;
        let common = self.balance.update(
            &BalanceInput {
                pitch_rad: self.sensors.attitude.pitch_rad,
                pitch_rate_rad_s,
                wheel_rate_rad_s: self.sensors.mean_wheel_rate_rad_s(),
                velocity_ref_m_s,
            },
            dt_s,
        );
        let mut common = common;
        // A stand-up balances until the robot has settled (and rolled ahead): watched alike.
        if matches!(self.state, State::Wheels(_) | State::Standing(_)) {
            let input = RunawayInput {
                ground_speed_m_s: self.ground_speed_m_s(),
                lagging_wheel_m_s: self.lagging_wheel_m_s(),
                velocity_ref_m_s: self.balance.velocity_ref_m_s(),
                // What the law asks for, held for a fall or not: a fall's hold is short, and
                // a wheel that cannot do what the law asks for longer is what is watched.
                torque_nm: common,
                torque_limit_nm: self.config.balance.torque_limit_nm,
            };
            let slope_rules = self.slope_rules();
            self.runaway.set_patient(slope_rules);
            let tripped = self.runaway.update(&self.config.runaway, &input);
            let stall = tripped == Some(protocol::FaultFlags::WHEEL_STALL);
            // Riding clear of a slope, the slope's foot slows the robot without stopping it.
            let rolls_on = stall && slope_rules && rolling_on(&input);
            if let Some(cause) = tripped.filter(|_| !rolls_on) {
                // A stall just after a drop is the landing, not a riser: stop, do not climb.
                let landed = self
                    .traction
                    .fell_within(self.config.rate.ticks_from_ms(LANDING_NO_CLIMB_MS));
                let climbs = stall && !landed && self.climb_on_stall(now);
                if !climbs {
                    self.wheel_fault_stop(now, cause, input.ground_speed_m_s);
                }
            }
            // Only the autonomous mode drives off edges by itself. In a collision the robot
            // also bounces light for a moment, and holding the wheels at the reference then
            // hid the deceleration the stall watch looks for (W into a step stopped 0.15 s
            // later, past the half second the stall acceptance allows).
            let auto = self.state == State::Wheels(WheelMotion::Auto);
            let hold = self.traction.update(
                &self.config.traction,
                self.config.rate,
                self.sensors.mean_wheel_rate_rad_s(),
                // The wheels' rate against the torso that rolls them at the reference: the
                // ground speed is r (ω + θ̇).
                input.velocity_ref_m_s / self.config.balance.wheel_radius_m - pitch_rate_rad_s,
            );
            if let (true, Some(hold_nm)) = (auto, hold) {
                common = hold_nm;
            }
        }
        self.turn_ref_rad_s = crate::math::toward(
            self.turn_ref_rad_s,
            turn_ref_rad_s,
            TURN_ACCEL_RAD_S2 * dt_s,
        );
        let differential = self.turn.update(
            self.turn_ref_rad_s - self.sensors.differential_wheel_rate_rad_s(),
            dt_s,
        );
        let (left, right) = mix(common, differential, self.config.wheel_torque_limit_nm);
        [left, right]
    }

    /// The speed reference (m/s) and the turn reference (half the wheels' rate difference, left
    /// minus right, rad/s) of the present state: the report's keys at the speed scale, steered
    /// by the operator's yaw rate (not `A`, which turns on the spot at the scale); `Drive` at
    /// the operator's speed and yaw rate; a fold's return to where it stood.
    fn wheel_references(&self, now: Tick) -> (f32, f32) {
        let config = &self.config;
        let radius_m = config.balance.wheel_radius_m;
        let preset_m_s = config.wheel_speed_rad_s * self.teleop.speed_scale * radius_m;
        let steering = &config.steering;
        let turn = |yaw_rad_s: f32| {
            steering.differential_rate_rad_s(steering.wheel_yaw_rad_s(yaw_rad_s), radius_m)
        };
        let yaw_rad_s = self.teleop.yaw_rate_rad_s;
        match self.state {
            State::Wheels(WheelMotion::Drive(Direction::Forward)) => (preset_m_s, turn(yaw_rad_s)),
            // A change of the riding pose is made standing.
            State::Wheels(WheelMotion::Auto) if self.auto.riding.reposing() => (0.0, 0.0),
            State::Wheels(WheelMotion::Drive(Direction::Backward) | WheelMotion::Auto) => {
                (-preset_m_s, turn(yaw_rad_s))
            }
            State::Wheels(WheelMotion::Rotate) => {
                (0.0, config.wheel_speed_rad_s * self.teleop.speed_scale)
            }
            State::Wheels(WheelMotion::Velocity) => {
                let top_m_s = config.wheel_speed_rad_s * radius_m;
                (within(self.teleop.speed_m_s, top_m_s), turn(yaw_rad_s))
            }
            State::Folding(_) => (self.fold_return_m_s(now), 0.0),
            State::Standing(_) => (self.roll_ahead_m_s(now), 0.0),
            _ => (0.0, 0.0),
        }
    }
}
