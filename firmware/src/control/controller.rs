//! The control step: decoded messages in, actuator commands and status out. Sans-IO — the
//! caller owns the clock and the bus and hands in the tick.
//!
//! Each tick ([`Controller::step`]):
//! 0. the IMU's sample of this tick goes through the attitude
//!    [`estimator`](crate::control::estimator), told what carries the robot;
//! 1. the supervisor checks the watchdogs and the tilt and raises faults;
//! 2. a running transition that has arrived fires `PoseReached`;
//! 3. the state picks the legs' goal pose (hold, stance, trot, fold, or the E-stop's controlled
//!    [`stop`](crate::control::stop)) and the wheels' law (balance + turn loop, or nothing);
//! 4. the legs' targets move toward the goal with the report's smoothing;
//! 5. every output is clamped to the joint and torque limits and made finite.

mod blocked;
mod carrier;
mod climbing;
mod folding;
mod riding;
mod stance;
mod stand_up;
mod status;
mod stopping;
mod supervise;
mod walking;
mod wheel_law;

use protocol::{AnyMessage, DriveFlags, EStopAction, FaultFlags, Joints, PerDrive};

use crate::config::Config;
use crate::control::estimator::AttitudeEstimator;
use crate::control::fsm::{Direction, Event, LegMotion, State, WheelMotion};
use crate::control::heading::HeadingHold;
pub use crate::control::output::{ConfigError, Output, Status};
use crate::control::safety::{clamp_leg_targets, clamp_wheel_torques};
use crate::control::sensors::Sensors;
use crate::control::stop::Stop;
use crate::control::teleop::Teleop;
use crate::legs::blocked::BlockedSwings;
use crate::legs::gait::Trot;
use crate::legs::levelling::Levelling;
use crate::legs::smoothing::Smoother;
use crate::legs::support::LegStance;
use crate::legs::transfer::Transfer;
use crate::time::Tick;
use crate::wheels::balance::Balance;
use crate::wheels::lean::LeanWatch;
use crate::wheels::runaway::Runaway;
use crate::wheels::traction::Traction;
use crate::wheels::wheel::SpeedLoop;
use climbing::Autonomy;
use stance::StandTilt;
use stand_up::RollAhead;

/// How fast the turn reference changes, rad/s² of wheel rate: a step to the turn's full
/// rate asked the turn loop for its whole torque at once, and on low friction the wheels slipped
/// (the campaign's `A`: spins stopped as runaways at friction 0.6–0.7).
const TURN_ACCEL_RAD_S2: f32 = 8.0;

/// The robot's controller.
#[derive(Debug, Clone)]
pub struct Controller {
    config: Config,
    state: State,
    sensors: Sensors,
    teleop: Teleop,
    trot: Trot,
    balance: Balance,
    turn: SpeedLoop,
    /// The turn loop's reference, rad/s, slewed toward what the mode asks
    /// ([`TURN_ACCEL_RAD_S2`]).
    turn_ref_rad_s: f32,
    /// Smoothed leg targets, rad.
    legs_rad: Joints<f32>,
    /// Goal of the smoothing, rad (kept so a failed IK holds the previous goal).
    goal_rad: Joints<f32>,
    /// Where the folded legs put their mass (see [`crate::legs::levelling`]).
    levelling: Levelling,
    /// Whether the drives have reported positions so the targets start from them.
    armed: bool,
    /// Latest fault report of each drive.
    drive_faults: PerDrive<bool>,
    tilted: bool,
    non_finite: bool,
    /// Whether the node's link monitor finds the bus too lossy (see
    /// [`Controller::set_link_degraded`]).
    link_degraded: bool,
    /// Whether the last tick did not come after the one before (see
    /// [`Controller::set_clock_stalled`]).
    clock_stalled: bool,
    ik_failures: u32,
    /// The controlled stop of the present E-stop, or of a stall or runaway in `Fault` (`None`
    /// otherwise).
    stop: Option<Stop>,
    runaway: Runaway,
    /// Whether the wheels are on the ground ([`crate::wheels::traction`]).
    traction: Traction,
    /// Whether the robot leans on something other than its wheels ([`crate::wheels::lean`]).
    lean: LeanWatch,
    /// What the runaway detector found, reported until the fault is reset.
    wheel_fault: FaultFlags,
    /// An authentic release heard while the controlled stop still ran: it takes effect when
    /// the stop is over (see [`Controller::release`]).
    release_pending: bool,
    /// The fold under way (`Folding`; `None` otherwise).
    transfer: Option<Transfer>,
    /// Whether that fold has ended.
    transfer_done: bool,
    /// When the balance law took the wheels (`None` while it does not drive them).
    wheels_since: Option<Tick>,
    /// Where the measured legs put the feet, computed at most once a tick (see
    /// [`crate::legs::support`] and [`Controller::wheels_may_drive`]).
    leg_stance: Option<LegStance>,
    /// The feet's mean position forward of the hips when a fold from the legs began, m
    /// (`None` otherwise).
    fold_origin_x_m: Option<f32>,
    /// How far ahead of where it stood the fold has put the robot, m: what the planted feet
    /// carried it, what it rolled on its held wheels, then balancing (see
    /// [`Controller::carried_forward_m`]).
    fold_ahead_m: f32,
    /// When the wheels took the running fold and how far ahead it was then, m: its return
    /// (`None` before, or with no fold).
    fold_return: Option<(Tick, f32)>,
    /// Where the running stand-up's roll ahead is (see `stand_up`).
    stand_roll: RollAhead,
    /// Whether the legs stand after a stand-up from the wheels (see `stance`).
    risen: bool,
    /// How long a stand-up's unfold has sat still on wheels and feet, s (see `stand_up`).
    feet_still_s: f32,
    /// Whether a stand after a stand-up from the wheels has stayed tilted (see `stance`).
    stand_tilt: StandTilt,
    /// When the running fold's legs were tucked (`None` before, or with no fold).
    fold_done_at: Option<Tick>,
    /// Whether the robot came to balance in place by a stop from a drive or a turn: it then
    /// holds its place while its trim settles ([`Balance::set_place_holding`]).
    stopped_on_wheels: bool,
    /// Ground speed of the wheels last tick, m/s (`None` off the wheels): its change is the
    /// acceleration the attitude estimator takes out of the accelerometer's reading.
    last_ground_m_s: Option<f32>,
    /// The trot's blocked swings (see [`crate::legs::blocked`]).
    blocked_swings: BlockedSwings,
    /// Whether a blocked trot stopped the robot: reported until the operator's next request.
    leg_blocked: bool,
    /// Which way `Walk` trots (see [`Controller::follow_walk_direction`]).
    walk_direction: Direction,
    /// The trot's heading hold, and the yaw rate it gives the trot this tick, rad/s.
    heading: (HeadingHold, f32),
    /// The autonomous mode's climbs (see [`Autonomy`]).
    auto: Autonomy,
}

impl Controller {
    /// A controller in [`State::Hold`] with drives torque-free until every drive has reported.
    pub fn new(config: Config) -> Result<Self, ConfigError> {
        let rate = config.rate;
        let trot = Trot::new(config.trot, rate).ok_or(ConfigError::TrotFrequency)?;
        Ok(Self {
            config,
            state: State::INITIAL,
            sensors: Sensors::new(
                rate.ticks_from_ms(config.feedback_timeout_ms),
                rate.ticks_from_ms(config.imu_timeout_ms),
                AttitudeEstimator::new(&config.attitude, rate),
            ),
            teleop: Teleop::new(rate.ticks_from_ms(config.teleop_timeout_ms)),
            trot,
            balance: Balance::new(config.balance),
            turn: SpeedLoop::new(config.turn),
            turn_ref_rad_s: 0.0,
            legs_rad: Joints::splat(0.0),
            goal_rad: Joints::splat(0.0),
            levelling: Levelling::new(&config.levelling),
            armed: false,
            drive_faults: PerDrive::splat(false),
            tilted: false,
            non_finite: false,
            link_degraded: false,
            clock_stalled: false,
            ik_failures: 0,
            stop: None,
            runaway: Runaway::new(&config.runaway, rate),
            traction: Traction::new(),
            lean: LeanWatch::new(&config.lean, rate),
            wheel_fault: FaultFlags::EMPTY,
            release_pending: false,
            transfer: None,
            transfer_done: false,
            wheels_since: None,
            leg_stance: None,
            fold_origin_x_m: None,
            fold_ahead_m: 0.0,
            fold_return: None,
            stand_roll: RollAhead::Due,
            risen: false,
            feet_still_s: 0.0,
            stand_tilt: StandTilt::default(),
            fold_done_at: None,
            stopped_on_wheels: false,
            last_ground_m_s: None,
            blocked_swings: BlockedSwings::new(),
            leg_blocked: false,
            walk_direction: Direction::Forward,
            heading: (HeadingHold::default(), 0.0),
            auto: Autonomy::default(),
        })
    }

    /// The configuration.
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// The present state.
    pub fn state(&self) -> State {
        self.state
    }

    /// The latest sensor values.
    pub fn sensors(&self) -> &Sensors {
        &self.sensors
    }

    /// The balance law (its speed reference and position error).
    pub fn balance(&self) -> &Balance {
        &self.balance
    }

    /// The levelling (the fold's shift).
    pub fn levelling(&self) -> &Levelling {
        &self.levelling
    }

    /// The trot generator (its phase).
    pub fn trot(&self) -> &Trot {
        &self.trot
    }

    /// Takes one accepted message received at `now`. Messages the controller does not consume
    /// (its own commands echoed, other nodes' status) are ignored.
    pub fn on_message(&mut self, now: Tick, message: &AnyMessage) {
        match message {
            AnyMessage::EStop(estop) => match estop.action {
                EStopAction::Latch => self.latch(now),
                EStopAction::Clear => self.release(),
            },
            AnyMessage::LegFeedback(leg, feedback) => self.sensors.record_leg(now, *leg, feedback),
            AnyMessage::WheelFeedback(feedback) => self.sensors.record_wheels(now, feedback),
            AnyMessage::Imu(imu) => self.sensors.record_imu(now, imu),
            AnyMessage::Range(range) => self.sensors.record_range(range),
            AnyMessage::TeleopHeartbeat(_) => self.teleop.heartbeat(now),
            AnyMessage::TeleopCommand(command) => {
                if let Some(mode) = self.teleop.command(now, command) {
                    if self.state == State::Fault && mode == protocol::TeleopMode::Stop {
                        let stopping = self.stop.is_some_and(|stop| !stop.off());
                        if self.fault_causes(now).is_empty() && !stopping {
                            self.apply(Event::Reset);
                        }
                    } else if self.link_degraded && mode != protocol::TeleopMode::Stop {
                        // A lossy link starts no motion (see `set_link_degraded`).
                    } else {
                        self.apply(Event::Request(mode));
                    }
                }
            }
            AnyMessage::DriveStatus(drive, status) => {
                let faulted = status.flags.contains(DriveFlags::FAULT);
                *self.drive_faults.get_mut(*drive) = faulted;
                if faulted {
                    self.apply(Event::Fault);
                }
            }
            AnyMessage::Sync(_)
            | AnyMessage::Announce(_)
            | AnyMessage::LegTargets(_)
            | AnyMessage::WheelCommand(_)
            | AnyMessage::ControllerStatus(_)
            | AnyMessage::RejectCounters(_) => {}
        }
    }

    /// Runs one control tick at `now`.
    pub fn step(&mut self, now: Tick) -> Output {
        self.leg_stance = None;
        let motion = self.motion();
        if let Some(force_m_s2) = self.sensors.estimate(&self.config.attitude, motion) {
            self.traction.record(&self.config.traction, force_m_s2);
        }
        self.supervise(now);
        if !self.armed {
            self.follow_measured();
        }
        let dt_s = self.config.rate.period_s();
        let ranging = self.sensors.take_range();
        self.watch_behind(ranging);
        if self.state == State::Wheels(WheelMotion::Auto) {
            self.ride_step(now, dt_s, ranging);
        }
        let depth_m = self.config.posture.depth_for(self.teleop.body_height_m);
        let previous = self.legs_rad;
        let mut legs_enabled = self.armed;
        let state = self.state;
        match state {
            State::EStop => {
                legs_enabled &= self.run_stop(now);
                self.release_when_stopped();
            }
            State::Fault if self.stop.is_some() => legs_enabled &= self.run_stop(now),
            State::Hold | State::Fault => {}
            State::Standing(_) if self.unsettled(now) => {
                // Settle on the wheels first (`unsettled`): legs that unfold under a rolling
                // robot lift it off its wheels with its momentum in it (driving at 0.48 m/s,
                // standing up flipped it over). The goal is set, so the transition is not
                // taken as done, but the legs wait, or go to the fold a stand-up starts
                // from (`Levelling::stow`).
                self.leg_goal(now, depth_m);
                self.stow_legs();
            }
            State::Legs(_) | State::Standing(_) => {
                self.follow_walk_direction();
                self.hold_heading(dt_s);
                self.leg_goal(now, depth_m);
                let rate = match self.state {
                    State::Legs(motion) if motion.trotting() => self.config.gait_rate_per_s,
                    _ => self.config.leg_rate_per_s,
                };
                self.smooth(rate);
            }
            State::Folding(_) => self.fold_step(now, depth_m),
            State::Climbing(_) => self.climb_step(now),
            State::Wheels(_) => {
                self.goal_rad = self.fold_goal_rad();
                self.smooth(self.config.fold_rate_per_s);
            }
        }
        let mut wheel_torque_nm = self.wheel_torques(now, dt_s);
        self.level(dt_s);
        self.watch_stand_tilt(now);
        self.watch_swings();
        if matches!(self.state, State::Legs(motion) if motion.trotting()) {
            self.trot.advance();
        }
        let mut leg_targets_rad = self.legs_rad;
        let legs_bad = clamp_leg_targets(&self.config.limits, &mut leg_targets_rad, &previous);
        let wheels_bad =
            clamp_wheel_torques(self.config.wheel_torque_limit_nm, &mut wheel_torque_nm);
        self.non_finite = legs_bad || wheels_bad;
        self.legs_rad = leg_targets_rad;
        if self.transition_arrived() {
            self.apply(Event::PoseReached);
        }
        Output {
            legs_enabled,
            leg_targets_rad,
            wheel_torque_nm,
            status: self.status(now, depth_m),
        }
    }

    /// This tick's wheel torques: held still (a stop against an obstacle, or wheels and feet
    /// both down in a fold or stand-up), the balance law's where the wheels carry the robot, or
    /// none.
    fn wheel_torques(&mut self, now: Tick, dt_s: f32) -> [f32; 2] {
        // A climb holds the wheels from its first tick: balancing, the robot rolled off the
        // riser as the legs moved.
        let climbing = matches!(self.state, State::Climbing(_));
        if self.stop.is_some_and(|stop| stop.holds_wheels())
            || self.folding_on_feet(now)
            || climbing
        {
            return self.hold_wheels(dt_s);
        }
        if !(self.balancing() && self.armed && self.wheels_may_drive()) {
            self.wheels_since = None;
            self.balance.reset();
            self.lean.reset();
            self.turn.reset();
            self.turn_ref_rad_s = 0.0;
            return [0.0; 2];
        }
        let since = *self.wheels_since.get_or_insert(now);
        if since == now && matches!(self.state, State::Folding(_)) {
            // The wheels take the robot (again): back to where it stood from where it is.
            self.fold_return = Some((now, self.carried_forward_m()));
        }
        let mut wheel_torque_nm = self.wheel_law(now, dt_s);
        if matches!(self.state, State::Climbing(_)) || self.leans_on_its_legs(now) {
            // The wheels stalled this tick and a climb began, or the robot leans on its legs:
            // they hold from now.
            return self.hold_wheels(dt_s);
        }
        if matches!(self.state, State::Folding(_)) {
            self.ramp_in(&mut wheel_torque_nm, now.since(since));
            self.fold_ahead_m += self.ground_speed_m_s() * dt_s;
        }
        wheel_torque_nm
    }

    fn apply(&mut self, event: Event) {
        let request = matches!(event, Event::Request(_))
            && !matches!(self.state, State::EStop | State::Fault);
        if request || event == Event::Reset {
            // The operator has seen the stop and asks for something (or resets a fault): the
            // report has served.
            self.leg_blocked = false;
            self.auto.step_refused = false;
            self.auto.range_lost = false;
            self.stand_tilt = StandTilt::default();
        }
        let next = self.state.next(event);
        if next == self.state {
            return;
        }
        let trotting = |state: State| matches!(state, State::Legs(motion) if motion.trotting());
        let entering_trot = trotting(next) && !trotting(self.state);
        if next == State::Legs(LegMotion::Walk) && self.state != next {
            self.walk_direction = Direction::Forward;
        }
        if trotting(next) {
            // Counted afresh for every trot and every change of its direction.
            self.blocked_swings.reset();
        }
        if entering_trot {
            self.trot.restart();
        }
        if next == State::Wheels(WheelMotion::Rotate) && self.state != next {
            // A turn on the spot turns where the robot is: a position error still remembered
            // from the fold's return was worked off during the spin and moved its centre.
            self.balance.hold_here();
        }
        if next == State::Hold {
            // Unarmed, the targets already follow the measured positions every tick.
            self.follow_measured();
        }
        if self.state == State::EStop {
            // A release moves nothing by itself: the operator sends STOP, then a motion.
            self.teleop.interlock();
        }
        if !matches!(next, State::Climbing(_)) {
            self.auto.climb = None;
        }
        if next != State::EStop {
            self.stop = None;
            self.release_pending = false;
        }
        if self.state == State::Fault {
            self.wheel_fault = FaultFlags::EMPTY;
        }
        if !matches!(next, State::Wheels(_)) {
            self.runaway.reset();
        }
        // A bounce in a manual mode is no drop the autonomous mode rolled off.
        let entering_auto = next == State::Wheels(WheelMotion::Auto) && self.state != next;
        if !matches!(next, State::Wheels(_)) || entering_auto {
            self.traction.reset();
        }
        // A new request while folding (W after F) changes what follows the fold, not the fold.
        let still_folding = matches!((self.state, next), (State::Folding(_), State::Folding(_)));
        if !still_folding {
            self.transfer = None;
            self.transfer_done = false;
            self.fold_origin_x_m = None;
            self.fold_ahead_m = 0.0;
            self.fold_return = None;
            self.fold_done_at = None;
            self.auto.climbed = false;
        }
        self.stand_roll_into(next);
        self.risen_into(next);
        self.climb_flags_into(next);
        let moving_on_wheels = matches!(self.state, State::Wheels(motion) if motion.moving());
        self.stopped_on_wheels = moving_on_wheels && next == State::Wheels(WheelMotion::Balance);
        self.state = next;
    }

    fn smooth(&mut self, rate_per_s: f32) {
        self.smooth_toward(rate_per_s, self.goal_rad);
    }

    /// One tick of the leg targets toward `goal_rad` with the report's smoothing at
    /// `rate_per_s`.
    pub(super) fn smooth_toward(&mut self, rate_per_s: f32, goal_rad: Joints<f32>) {
        let smoother = Smoother::new(rate_per_s, self.config.rate);
        for (target, goal) in self.legs_rad.iter_mut().zip(&goal_rad) {
            *target = smoother.step(*target, *goal);
        }
    }
}
