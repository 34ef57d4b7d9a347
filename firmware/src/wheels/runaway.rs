//! The runaway and stall detector of the balance law.
//!
//! A balancing robot whose wheels cannot do what the law asks is not safe to leave running:
//! driven into a step its wheels cannot climb, the robot is thrown back and the law, saturated,
//! runs it away backward at 1.5 m/s; with its centre of mass a few centimetres off its trim the
//! law saturates at rest and the robot runs away. Neither tilts the torso past the tilt fault.
//! So the detector watches what the law can see: the ground speed against the speed reference,
//! and the total wheel torque against its limit. Either out of bounds for long enough trips it,
//! and so does a robot that stands still while it is asked to drive.
//!
//! The speed reference is rate-limited, so in normal driving the robot follows it closely; the
//! thresholds ([`RunawayConfig::ROBOT`]) sit well above the largest error of the acceptance
//! scenarios and below what a blocked wheel or a runaway shows within a tenth of a second.

use protocol::FaultFlags;

use crate::time::TickRate;

/// Thresholds of the detector.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunawayConfig {
    /// Ground speed this far from the speed reference counts as out of bounds, m/s.
    pub speed_error_m_s: f32,
    /// … for this long trips the detector, ms.
    pub speed_error_ms: u32,
    /// Total wheel torque at this fraction of its limit or above counts as saturated.
    pub saturation_fraction: f32,
    /// … for this long trips the detector, ms.
    pub saturation_ms: u32,
    /// The lagging wheel's acceleration ([`RunawayInput::lagging_wheel_m_s`]) this far from
    /// the reference's counts as a collision, m/s² (the reference changes at most at the brake
    /// limit; a step stops a wheel against it several times faster).
    pub collision_m_s2: f32,
    /// … for this long trips the detector, ms.
    pub collision_ms: u32,
    /// The collision criterion applies while the speed reference is at least this, m/s.
    pub collision_min_speed_m_s: f32,
    /// … on a wheel fallen behind its reference by at least this, m/s (a wheel against a step
    /// loses that within the collision time; a delayed loop's limit cycle swings about the
    /// reference, its decelerations as steep but its speed within a few cm/s of it), …
    pub collision_drop_m_s: f32,
    /// … and only to a robot that was following its reference within this, m/s, …
    pub following_m_s: f32,
    /// … for this long before the deceleration began, ms: a robot still settling after a fold,
    /// or swinging in the limit cycle of a delayed loop, is not hitting anything.
    pub following_ms: u32,
    /// A trip this soon after a deceleration against the commanded speed as hard as a
    /// collision's is a stall, ms, even if the robot had not followed its reference closely
    /// (it was still catching up with it) or now moves the other way (it was thrown back), …
    pub struck_ms: u32,
    /// … if it had been within this of its reference for [`RunawayConfig::following_ms`] before,
    /// m/s: a robot whose wheels slip in a limit cycle on low friction swings 0.5 m/s about its
    /// reference, decelerating as hard at every swing, and is running away, not blocked.
    pub struck_following_m_s: f32,
    /// A robot asked for at least [`RunawayConfig::blocked_ref_m_s`] that moves slower than
    /// this, m/s, …
    pub blocked_m_s: f32,
    /// … for this long is blocked, ms: one that backed softly into a riser (from 0.4 m away,
    /// under the collision's deceleration) pushed against it until the run ended.
    pub blocked_ms: u32,
    /// The speed reference from which a robot standing still counts as blocked, m/s.
    pub blocked_ref_m_s: f32,
}

impl RunawayConfig {
    /// The robot's thresholds.
    pub const ROBOT: Self = Self {
        speed_error_m_s: 0.7,
        speed_error_ms: 150,
        saturation_fraction: 0.98,
        saturation_ms: 300,
        collision_m_s2: 2.5,
        collision_ms: 24,
        collision_min_speed_m_s: 0.1,
        collision_drop_m_s: 0.05,
        following_m_s: 0.15,
        following_ms: 200,
        struck_ms: 600,
        struck_following_m_s: 0.3,
        blocked_m_s: 0.05,
        blocked_ms: 600,
        blocked_ref_m_s: 0.2,
    };
}

/// Backward speed, m/s, below which a robot blocked against a forward reference counts as
/// standing still (and the other way round).
const STALL_STILL_M_S: f32 = 0.02;

/// What the detector reads each tick the balance law runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunawayInput {
    /// Ground speed of the axle, m/s.
    pub ground_speed_m_s: f32,
    /// The wheel that lags, told as an axle's speed, m/s ([`lagging_wheel_m_s`]): the
    /// collision criterion reads it. A robot that meets a riser at an angle has one wheel
    /// stopped while the other rolls on, and the axle decelerates half as hard.
    pub lagging_wheel_m_s: f32,
    /// The balance law's speed reference, m/s.
    pub velocity_ref_m_s: f32,
    /// Total wheel torque the law asks for, N·m.
    pub torque_nm: f32,
    /// Total wheel torque limit, N·m.
    pub torque_limit_nm: f32,
}

impl RunawayInput {
    /// The fault a trip with this input reports: [`FaultFlags::WHEEL_STALL`] when the robot
    /// is slower than the reference in the reference's direction (something blocks it),
    /// [`FaultFlags::RUNAWAY`] when it is faster, goes the other way (by more than
    /// [`STALL_STILL_M_S`]: a blocked robot's measured speed is zero give or take the gyro's bias
    /// in the pitch rate the ground speed adds), or moves when asked to stay.
    fn cause(&self) -> FaultFlags {
        let wanted = self.velocity_ref_m_s;
        let blocked = wanted != 0.0 && self.ground_speed_m_s * wanted.signum() < wanted.abs();
        let forward_or_still = self.ground_speed_m_s * wanted.signum() > -STALL_STILL_M_S;
        if blocked && forward_or_still {
            FaultFlags::WHEEL_STALL
        } else {
            FaultFlags::RUNAWAY
        }
    }
}

/// How many times [`RunawayConfig::blocked_ms`] a patient watch waits (see
/// [`Runaway::set_patient`]).
pub const PATIENT_FACTOR: u32 = 4;

/// Counts how long the balance law has been out of bounds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Runaway {
    speed_error_ticks: u32,
    saturated_ticks: u32,
    collision_ticks: u32,
    following_ticks: u32,
    /// Whether the robot had followed its reference long enough when this deceleration began.
    collision_armed: bool,
    /// Ticks left in which a trip counts as a stall whatever the robot does: a hard
    /// deceleration against the commanded speed of a robot near its reference was seen that
    /// recently.
    struck_ticks: u32,
    /// Ticks the robot has been within [`RunawayConfig::struck_following_m_s`] of its
    /// reference, and whether it had been long enough when this deceleration began.
    near_ticks: u32,
    struck_armed: bool,
    limits_ticks: [u32; 6],
    /// Ticks the robot has stood still against a speed reference (see
    /// [`RunawayConfig::blocked_ms`]).
    blocked_ticks: u32,
    /// Whether standing still against the reference is given [`PATIENT_FACTOR`] times as long
    /// (see [`Runaway::set_patient`]).
    patient: bool,
    /// Last tick's speed error of the lagging wheel, m/s (NaN: none yet), and the filtered rate
    /// it changes, m/s².
    last_error_m_s: f32,
    error_rate_m_s2: f32,
    period_s: f32,
}

impl Runaway {
    /// A detector with thresholds `config` at the control rate `rate`.
    pub fn new(config: &RunawayConfig, rate: TickRate) -> Self {
        let ticks = |ms| rate.ticks_from_ms(ms).max(1);
        Self {
            speed_error_ticks: 0,
            saturated_ticks: 0,
            collision_ticks: 0,
            following_ticks: 0,
            collision_armed: false,
            struck_ticks: 0,
            near_ticks: 0,
            struck_armed: false,
            limits_ticks: [
                ticks(config.speed_error_ms),
                ticks(config.saturation_ms),
                ticks(config.collision_ms),
                ticks(config.following_ms),
                ticks(config.struck_ms),
                ticks(config.blocked_ms),
            ],
            blocked_ticks: 0,
            patient: false,
            last_error_m_s: f32::NAN,
            error_rate_m_s2: 0.0,
            period_s: rate.period_s(),
        }
    }

    /// Gives a robot standing still against its reference [`PATIENT_FACTOR`] times
    /// [`RunawayConfig::blocked_ms`] (`patient`) or that (not). A robot starting from rest up
    /// a slope leans into it for a second or more before it rolls (1.2 s on a 10° ramp), and
    /// one that rides clear of a slope has been told by its rangefinder that no riser is near.
    pub fn set_patient(&mut self, patient: bool) {
        self.patient = patient;
    }

    /// Forgets what it counted (when the balance law stops or starts).
    pub fn reset(&mut self) {
        self.speed_error_ticks = 0;
        self.saturated_ticks = 0;
        self.collision_ticks = 0;
        self.following_ticks = 0;
        self.collision_armed = false;
        self.struck_ticks = 0;
        self.near_ticks = 0;
        self.struck_armed = false;
        self.blocked_ticks = 0;
        self.last_error_m_s = f32::NAN;
        self.error_rate_m_s2 = 0.0;
    }

    /// One tick of the balance law: the fault to raise, if the law has been out of bounds for
    /// too long. A non-finite input counts as out of bounds.
    pub fn update(&mut self, config: &RunawayConfig, input: &RunawayInput) -> Option<FaultFlags> {
        let error = input.ground_speed_m_s - input.velocity_ref_m_s;
        let lag_error = input.lagging_wheel_m_s - input.velocity_ref_m_s;
        let rate = (lag_error - self.last_error_m_s) / self.period_s;
        self.last_error_m_s = lag_error;
        // About 16 ms of smoothing at 250 Hz: a step in the measured speed is not a collision.
        if rate.is_finite() {
            self.error_rate_m_s2 += 0.25 * (rate - self.error_rate_m_s2);
        }
        let speed_bad = beyond(error.abs(), config.speed_error_m_s) || lag_error.is_nan();
        let saturation_nm = config.saturation_fraction * input.torque_limit_nm;
        let saturated = input.torque_nm.is_nan() || input.torque_nm.abs() >= saturation_nm;
        // Only a deceleration against a commanded speed: a robot braking to rest stops hard in
        // its last centimetres, and a push is for the speed and saturation criteria.
        let direction = input.velocity_ref_m_s.signum();
        let against = input.velocity_ref_m_s.abs() >= config.collision_min_speed_m_s
            && self.error_rate_m_s2 * direction < 0.0
            && lag_error * direction <= -config.collision_drop_m_s;
        let collision = against && beyond(self.error_rate_m_s2.abs(), config.collision_m_s2);
        let [speed_limit, saturation_limit, collision_limit, following_limit, struck_limit, blocked_limit] =
            self.limits_ticks;
        self.struck_ticks = if collision && self.struck_armed {
            struck_limit
        } else {
            self.struck_ticks.saturating_sub(1)
        };
        if !collision {
            self.collision_armed = self.following_ticks >= following_limit;
            self.struck_armed = self.near_ticks >= following_limit;
        }
        let following = !beyond(error.abs(), config.following_m_s);
        let count = |ticks: u32, bad: bool| if bad { ticks.saturating_add(1) } else { 0 };
        self.following_ticks = count(self.following_ticks, following);
        let near = !beyond(error.abs(), config.struck_following_m_s);
        self.near_ticks = count(self.near_ticks, near);
        self.speed_error_ticks = count(self.speed_error_ticks, speed_bad);
        self.saturated_ticks = count(self.saturated_ticks, saturated);
        self.collision_ticks = count(self.collision_ticks, collision && self.collision_armed);
        let blocked = input.velocity_ref_m_s.abs() >= config.blocked_ref_m_s
            && input.ground_speed_m_s.abs() < config.blocked_m_s;
        self.blocked_ticks = count(self.blocked_ticks, blocked);
        let moving_wrong = self.speed_error_ticks >= speed_limit
            || self.saturated_ticks >= saturation_limit
            || self.collision_ticks >= collision_limit;
        let blocked_limit = if self.patient {
            blocked_limit.saturating_mul(PATIENT_FACTOR)
        } else {
            blocked_limit
        };
        let standing = self.blocked_ticks >= blocked_limit;
        // The robot's speed does not decide it: thrown back from a step at 0.62 m/s, the
        // measured ground speed swung to 1.03 m/s and more (it adds the body's pitch rate,
        // which swings as the robot is thrown).
        (moving_wrong || standing).then(|| {
            if self.struck_ticks > 0 || !moving_wrong {
                // Thrown back by what it hit, or standing still against its reference:
                // blocked, whichever way its speed reads within the blocked band.
                FaultFlags::WHEEL_STALL
            } else {
                input.cause()
            }
        })
    }
}

/// The wheel furthest behind its own reference, told as an axle's speed, m/s: `reference_m_s`
/// plus that wheel's speed error. Each wheel's reference is the axle's plus its share of the
/// turn (`turn_m_s`: the left wheel's ground speed over the axle's, the right's as much under),
/// so a turn alone puts neither wheel behind. With no reference, the axle's speed
/// (`wheels_m_s`' mean); NaN if either wheel's speed is not finite.
pub fn lagging_wheel_m_s(wheels_m_s: [f32; 2], reference_m_s: f32, turn_m_s: f32) -> f32 {
    let [left, right] = wheels_m_s;
    if !(left.is_finite() && right.is_finite()) {
        return f32::NAN;
    }
    if reference_m_s == 0.0 {
        return 0.5 * (left + right);
    }
    let left_error = left - (reference_m_s + turn_m_s);
    let right_error = right - (reference_m_s - turn_m_s);
    let behind = if (left_error - right_error) * reference_m_s < 0.0 {
        left_error
    } else {
        right_error
    };
    reference_m_s + behind
}

/// Whether `value` is past `bound`, or NaN (a non-finite input counts as out of bounds).
fn beyond(value: f32, bound: f32) -> bool {
    value.is_nan() || value > bound
}

#[cfg(test)]
mod tests;
