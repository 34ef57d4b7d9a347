//! The runaway and stall detector of the balance law.
//!
//! A balancing robot whose wheels cannot do what the law asks is not safe to leave running:
//! driven into a step its wheels cannot climb, the robot is thrown back and the law, saturated,
//! runs it away backward at 1.5 m/s; with its centre of mass a few centimetres off its trim the
//! law saturates at rest and the robot runs away. Neither tilts the torso past the tilt fault.
//! So the detector watches what the law can see: the ground speed against the speed reference,
//! and the total wheel torque against its limit. Either out of bounds for long enough trips it.
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
    /// The robot's acceleration this far from the reference's counts as a collision, m/s²
    /// (the reference changes at most at the brake limit; a wheel against a step stops the
    /// robot several times faster).
    pub collision_m_s2: f32,
    /// … for this long trips the detector, ms.
    pub collision_ms: u32,
    /// The collision criterion applies while the speed reference is at least this, m/s.
    pub collision_min_speed_m_s: f32,
    /// … that has fallen behind its reference by at least this, m/s (a wheel against a step
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
    limits_ticks: [u32; 5],
    /// Last tick's speed error, m/s (NaN: none yet), and the filtered rate it changes, m/s².
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
            ],
            last_error_m_s: f32::NAN,
            error_rate_m_s2: 0.0,
            period_s: rate.period_s(),
        }
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
        self.last_error_m_s = f32::NAN;
        self.error_rate_m_s2 = 0.0;
    }

    /// One tick of the balance law: the fault to raise, if the law has been out of bounds for
    /// too long. A non-finite input counts as out of bounds.
    pub fn update(&mut self, config: &RunawayConfig, input: &RunawayInput) -> Option<FaultFlags> {
        let error = input.ground_speed_m_s - input.velocity_ref_m_s;
        let rate = (error - self.last_error_m_s) / self.period_s;
        self.last_error_m_s = error;
        // About 16 ms of smoothing at 250 Hz: a step in the measured speed is not a collision.
        if rate.is_finite() {
            self.error_rate_m_s2 += 0.25 * (rate - self.error_rate_m_s2);
        }
        let speed_bad = beyond(error.abs(), config.speed_error_m_s);
        let saturation_nm = config.saturation_fraction * input.torque_limit_nm;
        let saturated = input.torque_nm.is_nan() || input.torque_nm.abs() >= saturation_nm;
        // Only a deceleration against a commanded speed: a robot braking to rest stops hard in
        // its last centimetres, and a push is for the speed and saturation criteria.
        let direction = input.velocity_ref_m_s.signum();
        let against = input.velocity_ref_m_s.abs() >= config.collision_min_speed_m_s
            && self.error_rate_m_s2 * direction < 0.0
            && error * direction <= -config.collision_drop_m_s;
        let collision = against && beyond(self.error_rate_m_s2.abs(), config.collision_m_s2);
        let [speed_limit, saturation_limit, collision_limit, following_limit, struck_limit] =
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
        let tripped = self.speed_error_ticks >= speed_limit
            || self.saturated_ticks >= saturation_limit
            || self.collision_ticks >= collision_limit;
        // The robot's speed does not decide it: thrown back from a step at 0.62 m/s, the
        // measured ground speed swung to 1.03 m/s and more (it adds the body's pitch rate,
        // which swings as the robot is thrown).
        tripped.then(|| {
            if self.struck_ticks > 0 {
                // Thrown back by what it hit: blocked, whatever its speed says now.
                FaultFlags::WHEEL_STALL
            } else {
                input.cause()
            }
        })
    }
}

/// Whether `value` is past `bound`, or NaN (a non-finite input counts as out of bounds).
fn beyond(value: f32, bound: f32) -> bool {
    value.is_nan() || value > bound
}

#[cfg(test)]
mod tests {
    #![allow(clippy::expect_used, clippy::default_numeric_fallback)]

    use super::*;

    const CONFIG: RunawayConfig = RunawayConfig::ROBOT;

    fn detector() -> Runaway {
        // 250 Hz: 4 ms per tick.
        Runaway::new(&CONFIG, TickRate::SIM_250_HZ)
    }

    fn input(speed: f32, reference: f32, torque: f32) -> RunawayInput {
        RunawayInput {
            ground_speed_m_s: speed,
            velocity_ref_m_s: reference,
            torque_nm: torque,
            torque_limit_nm: 60.0,
        }
    }

    fn ticks_to_trip(runaway: &mut Runaway, input: &RunawayInput) -> Option<(u32, FaultFlags)> {
        (1..=1000).find_map(|tick| runaway.update(&CONFIG, input).map(|cause| (tick, cause)))
    }

    /// Ticks at 250 Hz of `ms`, as the detector counts them.
    fn ticks(ms: u32) -> u32 {
        TickRate::SIM_250_HZ.ticks_from_ms(ms)
    }

    #[test]
    fn a_robot_stopped_hard_against_its_commanded_speed_trips_as_a_stall() {
        let mut runaway = detector();
        for _ in 0..50 {
            assert_eq!(runaway.update(&CONFIG, &input(0.48, 0.48, 10.0)), None);
        }
        // Against a step: 0.48 m/s to rest in 0.1 s (4.8 m/s²), while the reference stays.
        let mut speed = 0.48;
        let found = (1..=100).find_map(|tick| {
            speed = f32::max(speed - 4.8 * 0.004, 0.0);
            let cause = runaway.update(&CONFIG, &input(speed, 0.48, 10.0));
            cause.map(|cause| (tick, cause))
        });
        let (tick, cause) = found.expect("never tripped");
        assert_eq!(cause, FaultFlags::WHEEL_STALL);
        // The filter needs a few ticks to pass 2.5 m/s², then the collision time runs.
        assert!((ticks(24)..=ticks(24) + 4).contains(&tick), "{tick}");
    }

    #[test]
    fn a_robot_thrown_back_by_what_it_hit_trips_as_a_stall_not_a_runaway() {
        let mut runaway = detector();
        // Catching up with its reference, 0.18 m/s faster than it: not following, so the
        // collision rule is not armed.
        for _ in 0..100 {
            assert_eq!(runaway.update(&CONFIG, &input(0.66, 0.48, 10.0)), None);
        }
        // Stopped by a step within 0.1 s and thrown back at 0.6 m/s: the speed error trips.
        let mut speed = 0.66;
        let found = (1..=200).find_map(|tick| {
            speed = f32::max(speed - 6.0 * 0.004, -0.6);
            let cause = runaway.update(&CONFIG, &input(speed, 0.48, -30.0));
            cause.map(|cause| (tick, cause))
        });
        let (_, cause) = found.expect("never tripped");
        assert_eq!(cause, FaultFlags::WHEEL_STALL);
    }

    #[test]
    fn wheels_slipping_in_a_limit_cycle_trip_as_a_runaway_not_a_stall() {
        let mut runaway = detector();
        // On low friction the law and the slipping wheels swing the robot ±0.5 m/s about its
        // 0.2 m/s reference at 4 Hz, decelerating at every swing as hard as in a collision…
        for tick in 0..250_u32 {
            let phase = tick as f32 * 0.004 * 4.0 * core::f32::consts::TAU;
            let speed = 0.2 + 0.5 * phase.sin();
            assert_eq!(runaway.update(&CONFIG, &input(speed, 0.2, 20.0)), None);
        }
        // … then runs away at 1.1 m/s.
        let found = ticks_to_trip(&mut runaway, &input(1.1, 0.2, 20.0));
        assert_eq!(found.map(|(_, cause)| cause), Some(FaultFlags::RUNAWAY));
    }

    #[test]
    fn a_robot_far_from_its_reference_for_the_error_time_trips_as_a_runaway() {
        for (speed, reference) in [(-0.5, 0.48), (0.8, 0.0), (-0.8, 0.0), (1.2, 0.48)] {
            let mut runaway = detector();
            let found = ticks_to_trip(&mut runaway, &input(speed, reference, 0.0));
            let expected = Some((ticks(150), FaultFlags::RUNAWAY));
            assert_eq!(found, expected, "{speed} {reference}");
        }
    }

    #[test]
    fn a_law_saturated_for_its_time_trips_even_at_the_reference_speed() {
        let mut runaway = detector();
        let found = ticks_to_trip(&mut runaway, &input(0.3, 0.3, -59.0));
        assert_eq!(found, Some((ticks(300), FaultFlags::RUNAWAY)));
    }

    #[test]
    fn lagging_braking_hard_stops_and_short_saturation_never_trip() {
        let mut runaway = detector();
        for round in 0..20 {
            // A robot lagging its reference by 0.6 m/s, as in a stop from top speed.
            for _ in 0..100 {
                assert_eq!(runaway.update(&CONFIG, &input(0.6, 0.0, 20.0)), None);
            }
            // Stopping hard (8 m/s²) with the reference at zero: a stop's last centimetres.
            let mut speed = 0.6;
            for _ in 0..20 {
                speed = f32::max(speed - 8.0 * 0.004, 0.0);
                assert_eq!(runaway.update(&CONFIG, &input(speed, 0.0, 20.0)), None);
            }
            // Following the reference, then decelerating at 2 m/s² against it.
            for _ in 0..50 {
                assert_eq!(runaway.update(&CONFIG, &input(0.48, 0.48, 20.0)), None);
            }
            let mut speed = 0.48;
            for _ in 0..50 {
                speed -= 2.0 * 0.004;
                assert_eq!(runaway.update(&CONFIG, &input(speed, 0.48, 20.0)), None);
            }
            // Saturated one tick short of the saturation time.
            for _ in 1..ticks(300) {
                assert_eq!(runaway.update(&CONFIG, &input(0.1, 0.1, 60.0)), None);
            }
            assert_eq!(
                runaway.update(&CONFIG, &input(0.1, 0.1, 0.0)),
                None,
                "{round}"
            );
        }
    }

    #[test]
    fn a_robot_stopped_hard_driving_backward_trips_as_a_stall() {
        let mut runaway = detector();
        for _ in 0..50 {
            assert_eq!(runaway.update(&CONFIG, &input(-0.48, -0.48, -10.0)), None);
        }
        let mut speed = -0.48;
        let found = (1..=100).find_map(|tick| {
            speed = f32::min(speed + 4.8 * 0.004, 0.0);
            let cause = runaway.update(&CONFIG, &input(speed, -0.48, -10.0));
            cause.map(|cause| (tick, cause))
        });
        let (tick, cause) = found.expect("never tripped");
        assert_eq!(cause, FaultFlags::WHEEL_STALL);
        assert!((ticks(24)..=ticks(24) + 4).contains(&tick), "{tick}");
    }

    #[test]
    fn a_sudden_stop_trips_as_a_stall_although_the_robot_no_longer_follows() {
        // Whether the robot had followed its reference is judged before the deceleration:
        // the collision itself takes it far from the reference at once.
        let mut runaway = detector();
        for _ in 0..ticks(CONFIG.following_ms) + 1 {
            assert_eq!(runaway.update(&CONFIG, &input(0.48, 0.48, 10.0)), None);
        }
        let mut speed = 0.24;
        let found = (1..=100).find_map(|tick| {
            let cause = runaway.update(&CONFIG, &input(speed, 0.48, 10.0));
            speed = f32::max(speed - 3.0 * 0.004, 0.0);
            cause.map(|cause| (tick, cause))
        });
        let (tick, cause) = found.expect("never tripped");
        assert_eq!(cause, FaultFlags::WHEEL_STALL);
        assert!(tick <= ticks(24) + 4, "{tick}");
    }

    #[test]
    fn an_error_at_its_bound_is_within_it() {
        let mut runaway = detector();
        let at_bound = input(CONFIG.speed_error_m_s, 0.0, 0.0);
        assert_eq!(ticks_to_trip(&mut runaway, &at_bound), None);
    }

    #[test]
    fn a_push_along_the_reference_is_no_collision() {
        let mut runaway = detector();
        for _ in 0..50 {
            assert_eq!(runaway.update(&CONFIG, &input(0.48, 0.48, 10.0)), None);
        }
        // Shoved forward at 5 m/s² for 60 ms: as sharp as a collision, but along the
        // reference.
        let mut speed = 0.48;
        for tick in 0..15 {
            speed += 5.0 * 0.004;
            let found = runaway.update(&CONFIG, &input(speed, 0.48, 10.0));
            assert_eq!(found, None, "{tick}");
        }
    }

    #[test]
    fn a_robot_swinging_about_its_reference_is_no_collision() {
        // A delayed loop's limit cycle: ±0.3 m/s at 3 Hz about 0.2 m/s, peaks of 5.7 m/s².
        let mut runaway = detector();
        for tick in 0..ticks(5_000) {
            let phase = core::f32::consts::TAU * 3.0 * tick as f32 * 0.004;
            let speed = 0.2 + 0.3 * phase.sin();
            assert_eq!(
                runaway.update(&CONFIG, &input(speed, 0.2, 20.0)),
                None,
                "{tick}"
            );
        }
    }

    #[test]
    fn a_fast_limit_cycle_read_through_an_encoder_is_no_collision() {
        // Driving at 0.48 m/s with two cycles of transport delay each way the loop swings at
        // 10 Hz (±0.035 m/s measured in the closed loop, where it tripped the collision
        // criterion after 3.5 s of driving), and the ground speed comes from 14-bit encoder
        // counts, 0.0115 m/s a count at 250 Hz. A swing of ±0.08 m/s decelerates past 2.5 m/s²
        // for longer than the collision time every cycle; its speed is then never 5 cm/s
        // behind the reference (it is near the top of its swing).
        let count_m_s = 0.12 * core::f32::consts::TAU / 16_384.0 / 0.004;
        let mut runaway = detector();
        for tick in 0..ticks(10_000) {
            let phase = core::f32::consts::TAU * 10.0 * tick as f32 * 0.004;
            let speed = 0.48 + 0.08 * phase.sin();
            let read = (speed / count_m_s).round() * count_m_s;
            assert_eq!(
                runaway.update(&CONFIG, &input(read, 0.48, 10.0)),
                None,
                "{tick}"
            );
        }
    }

    #[test]
    fn a_reset_starts_the_count_again_and_non_finite_input_counts_as_bad() {
        let mut runaway = detector();
        for _ in 1..ticks(150) {
            assert_eq!(runaway.update(&CONFIG, &input(0.9, 0.0, 0.0)), None);
        }
        runaway.reset();
        for _ in 1..ticks(150) {
            assert_eq!(runaway.update(&CONFIG, &input(f32::NAN, 0.0, 0.0)), None);
        }
        assert_eq!(
            runaway.update(&CONFIG, &input(f32::NAN, 0.0, 0.0)),
            Some(FaultFlags::RUNAWAY)
        );
    }
}
