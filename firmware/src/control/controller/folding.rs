//! The fold from the legs onto the wheels ([`crate::legs::transfer`]), the wheels' torque
//! ramped in as they take the robot, and when a transition between legs and wheels is over.

use protocol::{Joints, Leg};

use super::Controller;
use crate::control::fsm::{State, WheelMotion};
use crate::control::safety::clamp_leg_targets;
use crate::legs::kinematics::LegJoints;
use crate::legs::transfer::Transfer;
use crate::time::Tick;

/// How long the balance law's torque takes to come in fully once the wheels take the robot in
/// a fold, ms: a full torque on the first tick of contact jolts it.
const WHEEL_RAMP_IN_MS: u32 = 300;

/// A fold is back in place when the robot is this close to where it stood, m, …
const FOLD_RETURNED_M: f32 = 0.03;

/// … and the robot rolls slower than this, m/s, …
const FOLD_REST_M_S: f32 = 0.05;

/// … or at the latest this long after the legs are tucked, ms.
const FOLD_SETTLE_MS: u32 = 1_500;

/// How long a fold's return to where it stood takes, ms (see
/// [`Controller::fold_return_m_s`]).
const FOLD_RETURN_MS: u32 = 1_000;

impl Controller {
    /// This tick of the fold: started on the first tick of the transition from where the legs
    /// are, through the stance at `depth_m`.
    pub(super) fn fold_step(&mut self, now: Tick, depth_m: f32) {
        let fold_goal_rad = self.fold_goal_rad();
        self.goal_rad = fold_goal_rad;
        let mut transfer = match self.transfer {
            Some(running) => running,
            None => {
                let on_wheels = self.wheels_may_drive();
                let origin_x_m = self.stance().mean_foot_x_m;
                self.fold_origin_x_m = (!on_wheels).then_some(origin_x_m);
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
                let (from, goal) = (self.legs_rad, fold_goal_rad);
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
        let wheels_down = {
            let stance = self.stance();
            self.config.support.lowered_onto_wheels(&stance)
        };
        let pitch_rad = self.sensors.attitude.pitch_rad;
        let (pose, done) = transfer.step(now, wheels_down, pitch_rad);
        if let (true, Some(origin_x_m)) = (transfer.on_feet(), self.fold_origin_x_m) {
            // Counted while the feet are down: the tuck lifts them, and where they are then
            // says nothing of where the torso went.
            let ahead_m = origin_x_m - self.stance().mean_foot_x_m;
            if ahead_m.is_finite() {
                self.fold_ahead_m = ahead_m;
            }
        }
        self.transfer = Some(transfer);
        if done && self.fold_done_at.is_none() {
            self.fold_done_at = Some(now);
        }
        if self.fold_done_at.is_some() {
            // Tucked: the legs follow the levelling from here.
            self.smooth(self.config.fold_rate_per_s);
        } else {
            self.legs_rad = pose;
        }
        self.transfer_done = done && self.back_in_place(now);
    }

    /// Whether a fold whose legs are tucked has also brought the robot back to where it stood
    /// and to rest (or has tried for [`FOLD_SETTLE_MS`]): a drive that starts before would
    /// start from wherever the fold's return left it.
    fn back_in_place(&self, now: Tick) -> bool {
        let Some(done_at) = self.fold_done_at else {
            return false;
        };
        let speed_m_s = self.ground_speed_m_s();
        let returned = self.carried_forward_m().abs() < FOLD_RETURNED_M;
        let timed_out = now.since(done_at) >= self.config.rate.ticks_from_ms(FOLD_SETTLE_MS);
        (returned && speed_m_s.abs() < FOLD_REST_M_S) || timed_out
    }

    /// How far the fold has put the robot ahead of where it stood, m: over the carry, the mean
    /// over the legs of how far each planted foot went back relative to its hip (the wheels
    /// were in the air, so the balance law's own odometry did not see it); after it, what the
    /// robot rolled on its held wheels while the feet left the ground, and then balancing.
    pub(super) fn carried_forward_m(&self) -> f32 {
        if self.fold_origin_x_m.is_some() && self.fold_ahead_m.is_finite() {
            self.fold_ahead_m
        } else {
            0.0
        }
    }

    /// The speed reference that takes a fold back to where it stood, m/s: a half-sine of
    /// speed over [`FOLD_RETURN_MS`] whose distance is what the carry put the robot ahead when
    /// the wheels took it; the balance law's position error tracks it. Handed to the law as a
    /// position error at once instead, its own position loop (about 0.85 /s) took over 2 s to
    /// bring back the 0.1–0.2 m, and the fold ended by its time-out 7–9 cm from where it began;
    /// a speed fed back from the remaining distance overshot by what the law lagged.
    #[inline(never)] // As `level`.
    pub(super) fn fold_return_m_s(&self, now: Tick) -> f32 {
        let Some((since, distance_m)) = self.fold_return else {
            return 0.0;
        };
        let t_s = now.since(since) as f32 * self.config.rate.period_s();
        half_sine_m_s(-distance_m, FOLD_RETURN_MS, t_s)
    }

    /// Which of the balance law's trim rules may learn now: from the position error only on
    /// the wheels, the following of the balance point also in a fold whose legs are tucked;
    /// riding clear of a slope, the trim's band ([`super::riding::Riding::trim_band_rad`]) and
    /// in the autonomous mode forgiving ([`super::riding::Riding::forgive_s`]).
    pub(super) fn set_trim_rules(&mut self, now: Tick) {
        let wheels = matches!(self.state, State::Wheels(_));
        let tucked = matches!(self.state, State::Folding(_)) && self.fold_done_at.is_some();
        self.balance.set_trim_learning(wheels);
        // A stand-up's roll ahead makes its distance from where the robot was held.
        self.balance
            .set_counting(matches!(self.state, State::Standing(_)));
        self.balance.set_trim_following(wheels || tucked);
        // Only riding clear: the comparison of 16 joints is no work for every tick.
        let settled = wheels && self.auto.riding.clear() && self.legs_at_goal();
        let rules = self.slope_rules();
        let rate = self.config.rate;
        let riding = &mut self.auto.riding;
        self.balance
            .set_trim_band(riding.trim_band_rad(rate, now, settled));
        self.balance.set_forgiving(riding.forgive_s(rules));
        let in_place = matches!(self.state, State::Wheels(WheelMotion::Balance));
        self.balance
            .set_place_holding(in_place && self.stopped_on_wheels);
    }

    /// The wheel torques that hold the wheels still (damped), in a controlled stop or while
    /// wheels and feet both carry the robot; what a fold rolls meanwhile counts toward how far
    /// it put the robot ahead.
    pub(super) fn hold_wheels(&mut self, dt_s: f32) -> [f32; 2] {
        let gain = if matches!(self.state, State::Standing(_)) {
            self.stand_hold_nm_per_rad_s()
        } else {
            self.config.stop.wheel_hold_nm_per_rad_s
        };
        let [left, right] = self.sensors.wheel_rate_rad_s;
        if matches!(self.state, State::Folding(_)) {
            self.fold_ahead_m += self.ground_speed_m_s() * dt_s;
        }
        self.wheels_since = None;
        self.balance.reset();
        self.lean.reset();
        self.runaway.reset();
        [-gain * left, -gain * right]
    }

    /// Scales the wheel torques by how long (`ticks`) the wheels have carried the robot.
    pub(super) fn ramp_in(&self, wheel_torque_nm: &mut [f32; 2], ticks: u32) {
        let ramp_ticks = self.config.rate.ticks_from_ms(WHEEL_RAMP_IN_MS).max(1);
        let authority = (ticks as f32 / ramp_ticks as f32).min(1.0);
        for torque in wheel_torque_nm {
            *torque *= authority;
        }
    }

    /// Whether a fold or a stand-up has the robot on its wheels while its feet carry part of
    /// it: the wheels then hold still (a stool on wheels and feet); the balance law takes over
    /// once a fold's tuck lifts the feet clear. Balancing on wheels and feet, the law read the
    /// lean the feet gave the torso as a fall and drove the robot off its feet into a runaway.
    /// A stand-up holds the wheels once the robot is settled on them and has rolled ahead
    /// ([`Controller::unsettled`]): balancing while the legs swing out under it, the law
    /// answered the shift of their mass with a jolt of the wheels, and the torso pitched 7–9°
    /// on the way up (6.5° now, holding, from the fold it stows to).
    pub(super) fn folding_on_feet(&mut self, now: Tick) -> bool {
        if !matches!(self.state, State::Folding(_) | State::Standing(_)) || !self.wheels_may_drive()
        {
            return false;
        }
        if matches!(self.state, State::Standing(_)) {
            // A stand-up asked from `Hold` with the robot on its wheels (after a start, an
            // E-stop's release or a reset) is one from the wheels too: `risen_into` could not
            // tell, as no tick in `Hold` finds the stance.
            self.risen = true;
            if !self.unsettled(now) {
                return true;
            }
        }
        let support = self.config.support;
        let on_feet = self.stance().height_m >= support.wheel_contact_height_m - support.margin_m;
        self.count_still_on_feet(on_feet);
        on_feet
    }

    /// Whether every commanded joint is within the pose tolerance of its goal.
    pub(super) fn legs_at_goal(&self) -> bool {
        let tolerance_rad = self.config.pose_tolerance_rad;
        self.legs_rad
            .iter()
            .zip(&self.goal_rad)
            .all(|(now, goal)| (goal - now).abs() <= tolerance_rad)
    }

    /// Whether a running transition is over (checked after this tick's goal and move, so the
    /// next tick runs the new state).
    pub(super) fn transition_arrived(&self) -> bool {
        let arrived = match self.state {
            State::Folding(_) => self.transfer_done,
            State::Standing(_) => self.legs_at_goal(),
            _ => false,
        };
        arrived && self.armed
    }

    /// A stand-up on the wheels not yet stowed: the legs follow the fold toward shift 0
    /// ([`crate::legs::levelling::Levelling::stow`]).
    #[inline(never)] // As `level`.
    pub(super) fn stow_legs(&mut self) {
        if self.wheels_carry() && !self.levelling.stowed() {
            let fold_rad = self.fold_rad();
            self.smooth_toward(self.config.fold_rate_per_s, fold_rad);
        }
    }

    /// The fold a controlled stop on the wheels brakes in: the family's pose at shift 0, the
    /// back legs behind the hips, from where the kickstand swings them straight back and down.
    /// From a levelled fold the back feet, under the torso, passed deeper than the wheels on
    /// the way and lifted the robot.
    #[inline(never)] // As `level`.
    pub(super) fn stop_fold_rad(&self) -> Joints<f32> {
        self.within_limits(self.config.levelling.family.pose(0.0))
    }

    /// One tick of the levelling ([`crate::legs::levelling`]): balancing in place and at rest
    /// with the legs folded (a fold's tuck done included), the shift follows the balance point
    /// while the trim is fresh; the fold pose follows the shift. Not while driving, turning or
    /// stopping: the legs' mass moving under a moving robot shifted where it stopped (an X
    /// after W rolled on past its 5 cm, an E-stop was not at rest within 1 s).
    #[inline(never)] // Its frame stays off the control step's deepest path (PIL stack budget).
    pub(super) fn level(&mut self, dt_s: f32) {
        let tucked = matches!(self.state, State::Folding(_)) && self.fold_done_at.is_some();
        let fresh = self.wheels_since.is_some() && self.balance.trim_followed();
        let config = &self.config.levelling;
        if matches!(self.state, State::Standing(_)) {
            self.levelling.stow(config, dt_s);
        } else if tucked && fresh {
            let balance_point_rad = self.balance.pitch_trim_rad();
            self.levelling.update(config, balance_point_rad, dt_s);
        } else {
            self.levelling.unstow(config, dt_s);
        }
    }

    /// The fold pose of all legs where the levelling has them, clamped into the joint ranges
    /// (computed, not kept: the MCU's stack is measured to the byte).
    #[inline(never)] // As `level`.
    pub(super) fn fold_rad(&self) -> Joints<f32> {
        self.within_limits(self.levelling.pose(&self.config.levelling))
    }

    /// Where a fold tucks the legs, and where they ride on the wheels: the fold pose; riding
    /// clear of a slope, both pairs clear of the ground
    /// ([`crate::legs::levelling::FoldFamily::ride_front`], `ride_back`); after a climb (or
    /// on top) the front legs clear ([`crate::legs::levelling::FoldFamily::front_clear`]):
    /// tucked under the torso, they dragged on the plateau as the balance law caught the
    /// robot tipping off its back feet, and the robot ran away.
    #[inline(never)] // As `level`.
    pub(super) fn fold_goal_rad(&self) -> Joints<f32> {
        let fold_rad = self.fold_rad();
        let family = &self.config.levelling.family;
        if self.auto.riding.clear() {
            let pose = self.with_pair(fold_rad, [Leg::Fl, Leg::Fr], family.ride_front);
            self.with_pair(pose, [Leg::Bl, Leg::Br], family.ride_back)
        } else if self.auto.climbed || self.auto.on_top {
            self.with_pair(fold_rad, [Leg::Fl, Leg::Fr], family.front_clear)
        } else {
            fold_rad
        }
    }

    /// `pose` with the legs of `pair` at `left` (the right leg mirrors its abduction),
    /// clamped into the joint ranges.
    #[inline(never)] // As `level`.
    fn with_pair(&self, pose: Joints<f32>, pair: [Leg; 2], left: LegJoints) -> Joints<f32> {
        let right = LegJoints {
            hip_abduction_rad: -left.hip_abduction_rad,
            ..left
        };
        let set = self.within_limits(Joints::from_leg_fn(|leg| match leg {
            Leg::Fr | Leg::Br => right.to_array(),
            Leg::Fl | Leg::Bl => left.to_array(),
        }));
        let mut pose = pose;
        for leg in pair {
            *pose.leg_mut(leg) = *set.leg(leg);
        }
        pose
    }

    /// `pose` clamped into the joint ranges.
    fn within_limits(&self, pose: Joints<f32>) -> Joints<f32> {
        let (mut clamped, fallback) = (pose, pose);
        clamp_leg_targets(&self.config.limits, &mut clamped, &fallback);
        clamped
    }
}

/// The speed at `t_s` of a half-sine of speed over `period_ms` that covers `distance_m`, m/s
/// (zero outside it, or for a distance that is not finite).
pub(super) fn half_sine_m_s(distance_m: f32, period_ms: u32, t_s: f32) -> f32 {
    let period_s = period_ms as f32 * 1e-3;
    if !(0.0..period_s).contains(&t_s) || !distance_m.is_finite() {
        return 0.0;
    }
    let omega = core::f32::consts::PI / period_s;
    distance_m * 0.5 * omega * crate::math::sin_cos(omega * t_s).0
}
