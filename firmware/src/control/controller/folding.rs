//! The fold from the legs onto the wheels ([`crate::legs::transfer`]), the wheels' torque
//! ramped in as they take the robot, and when a transition between legs and wheels is over.

use protocol::Joints;

use super::Controller;
use crate::control::fsm::State;
use crate::legs::kinematics::{leg_fk, LegJoints};
use crate::legs::transfer::Transfer;
use crate::time::Tick;

/// How long the balance law's torque takes to come in fully once the wheels take the robot in
/// a fold, ms: a full torque on the first tick of contact jolts it.
const WHEEL_RAMP_IN_MS: u32 = 300;

impl Controller {
    /// This tick of the fold: started on the first tick of the transition from where the legs
    /// are, through the stance at `depth_m`.
    pub(super) fn fold_step(&mut self, now: Tick, depth_m: f32) {
        self.goal_rad = self.fold_rad;
        let mut transfer = match self.transfer {
            Some(running) => running,
            None => {
                let on_wheels = self.wheels_may_drive();
                let config = &self.config;
                let stance = match config
                    .posture
                    .stance(&config.geometry, &config.limits, depth_m)
                {
                    Ok(joints) => {
                        let pose = joints.to_array();
                        Joints::from_leg_fn(|_| pose)
                    }
                    Err(_) => self.legs_rad,
                };
                let (from, goal) = (self.legs_rad, self.fold_rad);
                self.fold_origin = (!on_wheels).then_some(self.sensors.joint_position_rad);
                Transfer::new(
                    config.transfer,
                    config.rate,
                    now,
                    from,
                    stance,
                    goal,
                    on_wheels,
                )
            }
        };
        let (pose, done) = transfer.step(now);
        self.legs_rad = pose;
        self.transfer = Some(transfer);
        self.transfer_done = done;
    }

    /// How far the torso has moved forward over its planted feet since the fold began, m: the
    /// mean over the legs of how far each foot went back relative to its hip. The wheels were
    /// in the air, so the balance law's own odometry did not see it.
    pub(super) fn carried_forward_m(&self) -> f32 {
        let Some(origin) = self.fold_origin else {
            return 0.0;
        };
        let geometry = &self.config.geometry;
        let now = &self.sensors.joint_position_rad;
        let moved: f32 = origin
            .iter_legs()
            .zip(now.iter_legs())
            .map(|((_, before), (_, after))| {
                let before = leg_fk(geometry, &LegJoints::from_array(*before)).x_m;
                let after = leg_fk(geometry, &LegJoints::from_array(*after)).x_m;
                before - after
            })
            .sum();
        let mean = 0.25 * moved;
        if mean.is_finite() {
            mean
        } else {
            0.0
        }
    }

    /// Scales the wheel torques by how long (`ticks`) the wheels have carried the robot.
    pub(super) fn ramp_in(&self, wheel_torque_nm: &mut [f32; 2], ticks: u32) {
        let ramp_ticks = self.config.rate.ticks_from_ms(WHEEL_RAMP_IN_MS).max(1);
        let authority = (ticks as f32 / ramp_ticks as f32).min(1.0);
        for torque in wheel_torque_nm {
            *torque *= authority;
        }
    }

    /// On the wheels the balance law always runs; while folding or standing up only once the
    /// measured leg pose puts the wheels on the ground (see [`crate::legs::support`]).
    pub(super) fn wheels_may_drive(&mut self) -> bool {
        if matches!(self.state, State::Wheels(_)) {
            return true;
        }
        // The legs' kinematics cost ~700 instructions a leg on the MCU: once a tick.
        let (config, joints) = (&self.config, &self.sensors.joint_position_rad);
        *self
            .grounded
            .get_or_insert_with(|| config.support.wheels_grounded(&config.geometry, joints))
    }

    /// Whether a fold has set the robot on its wheels while its feet still carry part of it:
    /// the wheels then hold still (a stool on wheels and feet), and the balance law takes over
    /// once the tuck lifts the feet clear. Balancing on wheels and feet, the law read the lean
    /// the feet gave the torso as a fall and drove the robot off its feet into a runaway.
    pub(super) fn folding_on_feet(&mut self) -> bool {
        if !matches!(self.state, State::Folding(_)) || !self.wheels_may_drive() {
            return false;
        }
        let (config, joints) = (&self.config, &self.sensors.joint_position_rad);
        !config.support.feet_clear(&config.geometry, joints)
    }

    /// Whether a running transition is over (checked after this tick's goal and move, so the
    /// next tick runs the new state).
    pub(super) fn transition_arrived(&self) -> bool {
        let arrived = match self.state {
            State::Folding(_) => self.transfer_done,
            State::Standing(_) => self
                .legs_rad
                .iter()
                .zip(&self.goal_rad)
                .all(|(now, goal)| (goal - now).abs() <= self.config.pose_tolerance_rad),
            _ => false,
        };
        arrived && self.armed
    }
}
