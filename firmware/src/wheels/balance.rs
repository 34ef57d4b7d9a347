//! Balance on two coaxial wheels: the robot with its legs folded is a wheeled inverted
//! pendulum (as Ascento, Upkie and TITA are), kept upright by full-state feedback.
//!
//! The model, its derivation and the gains' design for the loop delay are in
//! [`crate::wheels::lqr`].
//!
//! The ground speed comes from the wheels: their joint rate is relative to the body, so the
//! wheel's rate over ground is the joint rate plus the body's pitch rate, `v = r (ω + θ̇)`.

pub use crate::wheels::lqr::{BalanceGains, BalanceModel, DESIGN_DELAY_TICKS};

/// Limits and trims of the balance law.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BalanceConfig {
    /// Gains.
    pub gains: BalanceGains,
    /// Wheel radius, m.
    pub wheel_radius_m: f32,
    /// Total torque of both wheels, N·m (symmetric).
    pub torque_limit_nm: f32,
    /// Bound on the position error the law remembers, m.
    pub position_error_limit_m: f32,
    /// Pitch at which the body's centre of mass is over the axle, rad (a fold pose that puts
    /// mass behind the hips needs a forward lean): the starting value of the learned trim.
    pub pitch_trim_rad: f32,
    /// Time constant of the trim learning from the position error at rest, s (see
    /// [`Balance::pitch_trim_rad`]).
    pub trim_time_constant_s: f32,
    /// The learned trim stays within this of `pitch_trim_rad`, rad.
    pub trim_range_rad: f32,
    /// Time constant of the trim's following the balance point the body's steady lean shows,
    /// s (see [`Balance::pitch_trim_rad`]): short, so that the few tenths of a second of
    /// steady rolling a fold or a drive gives are enough.
    pub trim_follow_time_constant_s: f32,
    /// How much more the body leans than its balance point per m/s² of steady acceleration,
    /// rad ([`BalanceModel::lean_rad_per_m_s2`]).
    pub lean_rad_per_m_s2: f32,
    /// The speed reference speeds up at most this fast, m/s²: a step in speed would throw the
    /// pendulum over by the lean it needs to accelerate ([`BalanceConfig::lean_rad_per_m_s2`]
    /// per m/s², plus the law's overshoot).
    pub accel_limit_m_s2: f32,
    /// The speed reference slows down at most this fast, m/s²: higher than the acceleration
    /// limit, so that a stop is quick; the lean it costs is brief.
    pub brake_limit_m_s2: f32,
    /// Viscous friction of one wheel's drive, N·m per rad/s (the report's joint damping 2):
    /// fed forward at the reference speed, so that driving does not need a standing position
    /// error (which the robot would make up by overshooting, and give back after a stop).
    pub wheel_viscous_nm_per_rad_s: f32,
}

/// Ground acceleration below which the trim follows the balance point the lean shows, m/s²
/// (the acceleration's share of the lean is taken out; beyond this the lean is no longer
/// steady enough to read).
const TRIM_FOLLOW_M_S2: f32 = 0.5;

/// Pitch rate below which the body counts as still for the trim learning, rad/s.
const TRIM_STILL_RAD_S: f32 = 0.05;

/// Ground acceleration below which the robot counts as quasi-static for the trim learning
/// (rolling at rest or at a steady speed: its lean is then its balance point), m/s².
const TRIM_STILL_M_S2: f32 = 0.05;

/// Ground speed below which a robot asked to stand counts as at rest for the trim learning,
/// m/s.
const TRIM_REST_M_S: f32 = 0.05;

/// How long a robot must have been at rest before its position error counts as a trim error,
/// s: right after a stop, or while a fold drives it back to where it stood, it is still on its
/// way back.
const TRIM_REST_S: f32 = 1.0;

/// Fraction of the position-error bound past which the law has run out of position authority
/// (it cannot hold the robot against a trim error: it drifts).
const TRIM_AUTHORITY: f32 = 0.95;

/// Weight of one tick's acceleration in its filtered value (about 40 ms at 250 Hz).
const TRIM_ACCEL_FILTER: f32 = 0.1;

/// Ground speed below which a braking robot counts as stopped, m/s.
const STOPPED_M_S: f32 = 0.02;

/// What the balance law reads each tick.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BalanceInput {
    /// Body pitch, rad, positive leaning forward.
    pub pitch_rad: f32,
    /// Body pitch rate, rad/s.
    pub pitch_rate_rad_s: f32,
    /// Mean wheel joint rate (relative to the body), rad/s, positive rolling forward.
    pub wheel_rate_rad_s: f32,
    /// Wanted ground speed, m/s (reached through the acceleration limit).
    pub velocity_ref_m_s: f32,
}

/// The running balance law.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Balance {
    config: BalanceConfig,
    position_error_m: f32,
    velocity_ref_m_s: f32,
    /// Ground speed seen last tick, m/s.
    last_speed_m_s: f32,
    /// Whether the position is held where the robot came to rest (see [`Balance::update`]).
    anchored: bool,
    /// The learned pitch trim, rad.
    trim_rad: f32,
    /// Ground acceleration, filtered, m/s²: the trim is learned only while it is near zero.
    accel_m_s2: f32,
    /// Whether the trim may be learned now (see [`Balance::set_trim_learning`]).
    learning: bool,
    /// Whether the trim may follow the balance point now (see
    /// [`Balance::set_trim_following`]).
    following: bool,
    /// Time constant in which a position error the robot is making up is forgiven instead,
    /// s (`None`: it is made up; see [`Balance::set_forgiving`]).
    forgive_s: Option<f32>,
    /// How far from the trim a balance point may lie for the trim to follow it, rad (`None`:
    /// any; see [`Balance::set_trim_band`]).
    follow_band_rad: Option<f32>,
    /// Whether the trim followed the balance point on the last update.
    followed: bool,
    /// Whether a robot at rest holds its place while the trim changes (see
    /// [`Balance::set_place_holding`]).
    holding_place: bool,
    /// How long the robot has been at rest, s.
    rest_s: f32,
    /// The torques the law gave the last ticks, newest first, N·m.
    past_nm: [f32; DESIGN_DELAY_TICKS],
    /// Whether a motion's start and end keep the position error (see
    /// [`Balance::set_counting`]).
    counting: bool,
    /// Whether the running motion began while counting: its stop keeps the error too.
    counted: bool,
}

impl Balance {
    /// At rest, no remembered position error.
    pub const fn new(config: BalanceConfig) -> Self {
        Self {
            config,
            position_error_m: 0.0,
            velocity_ref_m_s: 0.0,
            last_speed_m_s: 0.0,
            anchored: true,
            trim_rad: config.pitch_trim_rad,
            accel_m_s2: 0.0,
            learning: false,
            following: false,
            follow_band_rad: None,
            forgive_s: None,
            followed: false,
            holding_place: false,
            rest_s: 0.0,
            past_nm: [0.0; DESIGN_DELAY_TICKS],
            counting: false,
            counted: false,
        }
    }

    /// Lets the trim be learned, or not: only while the robot balances with its legs folded
    /// (the pose the trim belongs to), not while a fold drives it back to where it stood or it
    /// stands up.
    pub fn set_trim_learning(&mut self, learning: bool) {
        self.learning = learning;
    }

    /// Whether a robot asked to stay where it is holds its place while the trim changes: once
    /// it has come to rest after a stop, what the trim takes no longer moves the place the law
    /// holds. A stop's brake leaves the trim off the balance point at rest (it followed the
    /// lean while driving, which the drive's torque shares), and as the trim found it the
    /// robot crept 5 cm after it had stopped.
    pub fn set_place_holding(&mut self, holding: bool) {
        self.holding_place = holding;
    }

    /// Whether a motion that starts now keeps the position error at its start and its stop
    /// instead of dropping it (see `Balance::anchor`): the law then makes the whole distance
    /// its speed reference integrates to, and keeps holding what it held before. A stand-up's
    /// roll ahead is such a move: dropped at its start and its end, the position error that
    /// held a robot whose trim was off its balance point (its legs moving to the stand-up's
    /// fold) let it run off by as much each time, backward as often as ahead. A motion that
    /// began before (a drive the stand-up stops) still drops its error where it stops: the
    /// brake's lag behind the reference is not a distance to make up.
    pub fn set_counting(&mut self, counting: bool) {
        self.counting = counting;
    }

    /// Lets the trim follow the balance point the lean shows, or not: while the legs are
    /// folded (the pose the trim belongs to), the fold's return to its start included (a
    /// deliberate position error does not mislead it).
    pub fn set_trim_following(&mut self, following: bool) {
        self.following = following;
    }

    /// Bounds how far from the trim a balance point the trim follows may lie (`None`: no
    /// bound). The lean shows the balance point only on level ground: on a slope the wheels
    /// hold the robot with a torque whose reaction leans the body (12° on 10°), the trim took
    /// that lean for the balance point, the law moved its position error with it and ran the
    /// robot down the slope. A robot whose trim was learned on the flat passes a bound that
    /// a slope's lean exceeds and its own legs' slow changes do not.
    pub fn set_trim_band(&mut self, band_rad: Option<f32>) {
        self.follow_band_rad = band_rad;
    }

    /// Forgives, with time constant `tau_s`, a position error the robot is making up (`None`:
    /// it is made up, the law's way of holding a place or a distance). Up a slope the law
    /// falls behind its reference and needs the position error's torque to climb at all; past
    /// the crest it then ran the robot down the far side 50 % over its reference speed to
    /// make up the distance, tilted 24°. A robot that only has to drive on (the autonomous
    /// mode) keeps the error while it is behind and forgets it once it has caught up.
    pub fn set_forgiving(&mut self, tau_s: Option<f32>) {
        self.forgive_s = tau_s;
    }

    /// One step of the trim learning: while the robot is asked to stand, and either has been
    /// at rest for [`TRIM_REST_S`] with its body turning slower than [`TRIM_STILL_RAD_S`] and
    /// accelerating less than [`TRIM_STILL_M_S2`] (`at_rest`), or drifts away because the law
    /// has used up its position authority (`drifting`), the trim moves by the trim error that
    /// the remembered position error stands for (at equilibrium the law's position and pitch
    /// terms cancel: `k_p p = −k_θ (θ − trim)`).
    fn learn_trim(&mut self, input: &BalanceInput, at_rest: bool, drifting: bool, dt_s: f32) {
        let still = input.pitch_rate_rad_s.abs() < TRIM_STILL_RAD_S
            && self.accel_m_s2.abs() < TRIM_STILL_M_S2;
        let settled = (at_rest && still) || drifting;
        let tau_s = self.config.trim_time_constant_s;
        let k = self.config.gains;
        let error_rad = -self.position_error_m * k.position_nm_per_m / k.pitch_nm_per_rad;
        if !(self.learning && settled && error_rad.is_finite() && tau_s > 0.0) {
            return;
        }
        // A drift is corrected four times faster: the robot is rolling away meanwhile.
        let tau_s = if drifting { 0.25 * tau_s } else { tau_s };
        self.take_trim(error_rad, dt_s / tau_s, !drifting);
    }

    /// One step of the trim following the balance point: whenever the body's lean is steady
    /// (it turns slower than [`TRIM_STILL_RAD_S`] and the robot accelerates less than
    /// [`TRIM_FOLLOW_M_S2`]), the lean is the balance point plus what the acceleration needs
    /// ([`BalanceConfig::lean_rad_per_m_s2`]), and the trim follows that balance point
    /// (time constant [`BalanceConfig::trim_follow_time_constant_s`]). It holds at rest, rolling
    /// and drifting, whatever the wheels' friction (the drive's torque and the friction both act
    /// between wheel and body and cancel on it). The position error is no measure while rolling:
    /// it also stands for the friction the feed-forward does not match, which a stop drops. So
    /// a trim learned before the stop is what lets the stop hold its place.
    fn follow_balance_point(&mut self, input: &BalanceInput, dt_s: f32) {
        let steady = input.pitch_rate_rad_s.abs() < TRIM_STILL_RAD_S
            && self.accel_m_s2.abs() < TRIM_FOLLOW_M_S2;
        let balance_point_rad = input.pitch_rad - self.config.lean_rad_per_m_s2 * self.accel_m_s2;
        let error_rad = balance_point_rad - self.trim_rad;
        let tau_s = self.config.trim_follow_time_constant_s;
        let within = self
            .follow_band_rad
            .is_none_or(|band_rad| error_rad.abs() <= band_rad);
        self.followed = self.following && steady && within && error_rad.is_finite() && tau_s > 0.0;
        if self.followed {
            self.take_trim(error_rad, dt_s / tau_s, false);
        }
    }

    /// Moves the trim by `gain` of `error_rad` (within its range), and the position error by
    /// as much as keeps the law at the same equilibrium: the robot stays where it is instead
    /// of rolling back to where its position error was counted from. (Letting the robot roll
    /// back instead, as a trim that corrects its own error would, measured worse in every
    /// wheeled scenario of the campaign.)
    fn take_trim(&mut self, error_rad: f32, gain: f32, hold_place: bool) {
        let k = self.config.gains;
        let gain = crate::math::clamp(gain, 0.0, 1.0);
        let nominal = self.config.pitch_trim_rad;
        let range = self.config.trim_range_rad;
        let learned = self.trim_rad + gain * error_rad;
        let learned = crate::math::clamp(learned, nominal - range, nominal + range);
        let taken_rad = learned - self.trim_rad;
        self.trim_rad = learned;
        let resting = self.holding_place && self.anchored && self.velocity_ref_m_s == 0.0;
        if !(hold_place || resting) {
            self.position_error_m += taken_rad * k.pitch_nm_per_rad / k.position_nm_per_m;
        }
    }

    /// Forgets `behind_m` of the position error the robot is behind its reference by, and
    /// keeps the rest (within the error's bound): a move that something blocked gives up the
    /// distance it did not make, not what the law held before it.
    pub fn forgive_m(&mut self, behind_m: f32) {
        let bound = self.config.position_error_limit_m;
        let error_m = self.position_error_m + behind_m;
        if error_m.is_finite() {
            self.position_error_m = crate::math::clamp(error_m, -bound, bound);
        }
    }

    /// Forgets the position error: the robot holds where it is now, not where the error was
    /// counted from (a turn on the spot starts from where the robot is, as a drive does; see
    /// [`Balance::update`]).
    pub fn hold_here(&mut self) {
        self.position_error_m = 0.0;
    }

    /// Forgets the position error and its past torques (when the wheels take over).
    pub fn reset(&mut self) {
        self.past_nm = [0.0; DESIGN_DELAY_TICKS];
        self.position_error_m = 0.0;
        self.velocity_ref_m_s = 0.0;
        self.last_speed_m_s = 0.0;
        self.anchored = true;
        self.followed = false;
    }

    /// Takes the robot's present ground speed as the speed reference and forgets the position
    /// error: a stop that starts from a stall or a runaway brakes from where the robot is, not
    /// from what it was asked for.
    pub fn rebase(&mut self, ground_speed_m_s: f32) {
        if ground_speed_m_s.is_finite() {
            self.velocity_ref_m_s = ground_speed_m_s;
            self.last_speed_m_s = ground_speed_m_s;
        }
        self.position_error_m = 0.0;
        self.anchored = false;
    }

    /// The learned pitch trim, rad: where this robot's centre of mass is over the axle.
    ///
    /// A robot is not its drawing: with the torso's centre of mass 3 cm behind where the model
    /// has it, the fixed trim left the law needing more standing position error than it may
    /// remember, and the robot rolled away at 0.15 m/s, leaning 14°. Two rules learn it, and
    /// what the trim takes over the position error gives up (the robot stays where it is):
    ///
    /// - whenever the lean is steady, rolling or at rest, the trim follows the balance point
    ///   the lean shows, the acceleration's share taken out (time constant
    ///   [`BalanceConfig::trim_follow_time_constant_s`]): a drive that follows a fold with no
    ///   rest between learns it on the way, and its stop holds its place;
    /// - at rest, or drifting at its position-error bound, the trim integrates the trim error
    ///   that the position error the law holds stands for
    ///   ([`BalanceConfig::trim_time_constant_s`]), so the law ends needing none.
    ///
    /// [`Balance::reset`] keeps what was learned.
    pub fn pitch_trim_rad(&self) -> f32 {
        self.trim_rad
    }

    /// Whether the trim followed the balance point on the last update: it is then fresh.
    pub fn trim_followed(&self) -> bool {
        self.followed
    }

    /// The speed reference after the acceleration limit, m/s.
    pub fn velocity_ref_m_s(&self) -> f32 {
        self.velocity_ref_m_s
    }

    /// How long the robot has rolled slower than the trim learning's rest speed, s.
    pub fn rested_s(&self) -> f32 {
        self.rest_s
    }

    /// The remembered position error, m.
    pub fn position_error_m(&self) -> f32 {
        self.position_error_m
    }

    /// The ground speed the wheels report, m/s.
    pub fn ground_speed_m_s(&self, input: &BalanceInput) -> f32 {
        self.config.wheel_radius_m * (input.wheel_rate_rad_s + input.pitch_rate_rad_s)
    }

    /// Takes `velocity_ref` as the reference and re-anchors the position error where a motion
    /// starts or ends.
    ///
    /// A drive starts from where the robot is: a position error still remembered from before
    /// (a fold's return to its start) would be distance the drive owes. A stop holds the robot
    /// where it came to rest, not where the speed reference did: the robot lags the reference
    /// while braking, and rolling back to the reference's stop point would be a second motion
    /// nobody asked for. So once the reference is at rest and the robot's own speed has come to
    /// zero (or changed sign), the remembered position error is dropped, once per stop. A
    /// motion begun while counting keeps it at both ends ([`Balance::set_counting`]).
    fn anchor(&mut self, input: &BalanceInput, velocity_ref: f32) {
        if self.velocity_ref_m_s == 0.0 && velocity_ref != 0.0 {
            self.counted = self.counting;
            if !self.counting {
                self.position_error_m = 0.0;
            }
        }
        self.velocity_ref_m_s = velocity_ref;
        let speed = self.ground_speed_m_s(input);
        if input.velocity_ref_m_s == 0.0 && velocity_ref == 0.0 {
            let stopped = speed * self.last_speed_m_s <= 0.0 || speed.abs() < STOPPED_M_S;
            if !self.anchored && stopped {
                if !(self.counting && self.counted) {
                    self.position_error_m = 0.0;
                }
                self.anchored = true;
            }
        } else {
            self.anchored = false;
        }
        self.last_speed_m_s = speed;
    }

    /// One tick of `dt_s`: the total wheel torque, N·m, within ±`torque_limit_nm`. Any
    /// non-finite input gives zero torque and leaves the state untouched.
    pub fn update(&mut self, input: &BalanceInput, dt_s: f32) -> f32 {
        let current = self.velocity_ref_m_s;
        let change = input.velocity_ref_m_s - current;
        // Slowing down: the change points back toward zero speed.
        let braking = change * current < 0.0;
        let limit_m_s2 = if braking {
            self.config.brake_limit_m_s2
        } else {
            self.config.accel_limit_m_s2
        };
        let step = limit_m_s2 * dt_s;
        let velocity_ref = current + crate::math::clamp(change, -step, step);
        let speed_error = self.ground_speed_m_s(input) - velocity_ref;
        let accel = (self.ground_speed_m_s(input) - self.last_speed_m_s) / dt_s;
        if accel.is_finite() {
            self.accel_m_s2 += TRIM_ACCEL_FILTER * (accel - self.accel_m_s2);
        }
        let at_rest = input.velocity_ref_m_s == 0.0 && velocity_ref == 0.0;
        let speed = self.ground_speed_m_s(input);
        let bound = self.config.position_error_limit_m;
        let out_of_authority = self.position_error_m.abs() >= TRIM_AUTHORITY * bound;
        self.rest_s = if speed.abs() < TRIM_REST_M_S {
            self.rest_s + dt_s
        } else {
            0.0
        };
        let rested = self.rest_s >= TRIM_REST_S;
        self.learn_trim(input, at_rest && rested, at_rest && out_of_authority, dt_s);
        self.followed = false;
        if input.velocity_ref_m_s == velocity_ref {
            self.follow_balance_point(input, dt_s);
        }
        let pitch = input.pitch_rad - self.trim_rad;
        if !(speed_error.is_finite()
            && velocity_ref.is_finite()
            && pitch.is_finite()
            && input.pitch_rate_rad_s.is_finite())
        {
            return 0.0;
        }
        self.anchor(input, velocity_ref);
        let k = self.config.gains;
        let limit = self.config.torque_limit_nm;
        let [u1, u2] = self.past_nm;
        let [k1, k2] = k.past_torque_nm_per_nm;
        let past = k1 * u1 + k2 * u2;
        let torque_at = |position_error_m: f32| {
            -(k.position_nm_per_m * position_error_m
                + k.pitch_nm_per_rad * pitch
                + k.velocity_nm_per_m_s * speed_error
                + k.pitch_rate_nm_per_rad_s * input.pitch_rate_rad_s
                + past)
        };
        let bound = self.config.position_error_limit_m;
        let candidate =
            crate::math::clamp(self.position_error_m + speed_error * dt_s, -bound, bound);
        let unclamped = torque_at(candidate);
        // Anti-windup: while the torque saturates, keep the position error only if it does
        // not push the torque further past the limit.
        let saturated = unclamped.abs() > limit;
        let grows = torque_at(candidate).abs() > torque_at(self.position_error_m).abs();
        if !(saturated && grows) {
            self.position_error_m = candidate;
        }
        if let Some(tau_s) = self.forgive_s.filter(|tau_s| *tau_s > 0.0) {
            // Made up when the robot runs ahead of its reference against the error's sign.
            if self.position_error_m * speed_error < 0.0 {
                self.position_error_m *= 1.0 - crate::math::clamp(dt_s / tau_s, 0.0, 1.0);
            }
        }
        // In a steady state the past torques equal the present one, so the law gives
        // `(−K_x x + ff) / (1 + Σ k_u)`: the feed-forward is scaled up by as much.
        let feedforward = 2.0 * self.config.wheel_viscous_nm_per_rad_s * velocity_ref
            / self.config.wheel_radius_m
            * (1.0 + k1 + k2);
        let torque = crate::math::clamp(
            torque_at(self.position_error_m) + feedforward,
            -limit,
            limit,
        );
        self.past_nm = [torque, u1];
        torque
    }
}
