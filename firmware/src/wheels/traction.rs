//! Traction: whether the wheels carry the robot, or it is falling.
//!
//! Backing off a plateau's edge, the wheels pivot over it and the robot drops for a tenth of a
//! second. The balance law, seeing the torso pitch as the robot tips over the edge, drives the
//! wheels at its limit, and with nothing to push against they spin up (from 5 to 24 rad/s
//! within 80 ms, measured at 6 cm): the robot lands on wheels turning four times faster than
//! it moves and is thrown into a runaway. A falling robot feels no weight: the accelerometer's
//! specific force drops toward zero (on the wheels it reads about g, whatever the law does).
//! So while the specific force stays well under g the wheels turn at the rate the speed
//! reference asks for, and the robot lands rolling as fast as it moves; the balance law takes
//! over again a moment after the weight is back.
//!
//! A hold is bounded: one longer than a step's drop takes ([`TractionConfig::max_hold_ms`],
//! and the landing's) gives the wheels back to the law, and a new one starts only after the law
//! has had them for [`TractionConfig::rearm_ms`], so an accelerometer reading low cannot
//! switch the balance off for more than a share of the time.

use crate::time::TickRate;

/// When the robot counts as falling and how the wheels hold meanwhile.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TractionConfig {
    /// Specific force below this, m/s², …
    pub falling_m_s2: f32,
    /// … on this many IMU samples in a row is a fall.
    pub falling_samples: u8,
    /// The wheels hold until the specific force has been back over
    /// [`TractionConfig::falling_m_s2`] for this long, ms (the landing).
    pub landing_ms: u32,
    /// … and no longer than this and the landing, ms (a 10 cm drop takes 140 ms).
    pub max_hold_ms: u32,
    /// A new hold starts only this long after the last one ended, ms.
    pub rearm_ms: u32,
    /// The hold's torque per rad/s off the rate asked for, N·m·s/rad (both wheels together).
    pub hold_nm_per_rad_s: f32,
    /// A hold that fell for at least this long was a drop off an edge, ms (a 6 cm drop takes
    /// 110 ms); a shorter one was a bounce ([`Traction::fell_within`]).
    pub drop_min_ms: u32,
}

impl TractionConfig {
    /// The robot.
    pub const ROBOT: Self = Self {
        falling_m_s2: 4.0,
        falling_samples: 2,
        landing_ms: 40,
        max_hold_ms: 300,
        rearm_ms: 700,
        hold_nm_per_rad_s: 1.0,
        drop_min_ms: 60,
    };
}

/// The fall watch's state.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Traction {
    /// IMU samples in a row under the falling threshold.
    light_samples: u8,
    /// Ticks held so far in this fall.
    held_ticks: u32,
    /// Ticks left of the landing's hold.
    landing_left: u32,
    /// Ticks since the last hold ended (saturating; `u32::MAX` before the first).
    since_hold: u32,
    /// Ticks the running (or last) hold fell, not counting its landing.
    fell_ticks: u32,
    /// Ticks since the last hold that was a drop ([`TractionConfig::drop_min_ms`]) ended
    /// (saturating; `u32::MAX` before the first).
    since_drop: u32,
}

impl Traction {
    /// Carried, nothing seen.
    pub const fn new() -> Self {
        Self {
            light_samples: 0,
            held_ticks: 0,
            landing_left: 0,
            since_hold: u32::MAX,
            fell_ticks: 0,
            since_drop: u32::MAX,
        }
    }

    /// Forgets what it saw (the wheels stopped driving).
    pub fn reset(&mut self) {
        *self = Self::new();
    }

    /// Takes this tick's IMU sample's specific force, m/s² (its magnitude).
    pub fn record(&mut self, config: &TractionConfig, specific_force_m_s2: f32) {
        self.light_samples = if specific_force_m_s2 < config.falling_m_s2 {
            self.light_samples.saturating_add(1)
        } else {
            0
        };
    }

    /// One tick: the common torque that turns the wheels at `hold_rate_rad_s` (the rate the
    /// speed reference asks for) from `rate_rad_s` (their mean rate) while the robot falls and
    /// lands, N·m; `None` while the wheels carry it.
    pub fn update(
        &mut self,
        config: &TractionConfig,
        rate: TickRate,
        rate_rad_s: f32,
        hold_rate_rad_s: f32,
    ) -> Option<f32> {
        let falling = self.light_samples >= config.falling_samples;
        if !falling && self.landing_left == 0 {
            self.held_ticks = 0;
        }
        let rearmed = self.since_hold >= rate.ticks_from_ms(config.rearm_ms);
        if falling && (self.landing_left > 0 || rearmed) {
            let within_bound = self.held_ticks < rate.ticks_from_ms(config.max_hold_ms);
            self.landing_left = if within_bound {
                rate.ticks_from_ms(config.landing_ms).max(1)
            } else {
                0
            };
        }
        self.since_drop = self.since_drop.saturating_add(1);
        if self.landing_left == 0 {
            self.since_hold = self.since_hold.saturating_add(1);
            return None;
        }
        if self.since_hold > 0 {
            // A new hold.
            self.fell_ticks = 0;
        }
        self.since_hold = 0;
        if falling {
            self.fell_ticks = self.fell_ticks.saturating_add(1);
        } else {
            self.landing_left = self.landing_left.saturating_sub(1);
        }
        if self.fell_ticks >= rate.ticks_from_ms(config.drop_min_ms) {
            self.since_drop = 0;
        }
        self.held_ticks = self.held_ticks.saturating_add(1);
        Some(config.hold_nm_per_rad_s * (hold_rate_rad_s - rate_rad_s))
    }

    /// Whether the wheels hold for a fall now.
    pub fn holding(&self) -> bool {
        self.landing_left > 0
    }

    /// Whether the wheels held for a drop within the last `ticks`: a stall then is the landing
    /// or the edge just rolled off, not a riser to climb. A bounce is no drop: set down on its
    /// wheels by a climb, a robot read light for two samples, and the riser of the next step
    /// of a flight, met a second later, was taken for a landing and stopped it.
    pub fn fell_within(&self, ticks: u32) -> bool {
        self.since_drop <= ticks
    }
}

impl Default for Traction {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const RATE: TickRate = TickRate::SIM_250_HZ;

    fn tick(traction: &mut Traction, force_m_s2: f32) -> Option<f32> {
        let config = TractionConfig::ROBOT;
        traction.record(&config, force_m_s2);
        traction.update(&config, RATE, -8.0, -4.0)
    }

    #[test]
    fn carried_the_law_drives_falling_the_wheels_turn_at_the_reference_until_landed() {
        let mut traction = Traction::new();
        assert_eq!(tick(&mut traction, 9.8), None);
        assert_eq!(tick(&mut traction, 1.0), None, "one light sample is noise");
        let hold = tick(&mut traction, 1.0);
        assert!(
            hold.is_some_and(|nm| nm > 0.0),
            "slows the spun-up wheels: {hold:?}"
        );
        for _ in 0..20_u32 {
            assert!(tick(&mut traction, 0.5).is_some());
        }
        // Landed: held for the landing, then the law again.
        let landing = RATE.ticks_from_ms(TractionConfig::ROBOT.landing_ms);
        for _ in 0..landing {
            assert!(tick(&mut traction, 30.0).is_some());
        }
        assert_eq!(tick(&mut traction, 9.8), None);
        assert!(!traction.holding());
    }

    #[test]
    fn a_fall_longer_than_a_drop_gives_the_wheels_back_to_the_law() {
        let mut traction = Traction::new();
        let bound = RATE.ticks_from_ms(TractionConfig::ROBOT.max_hold_ms);
        let held = (0..2 * bound)
            .filter(|_| tick(&mut traction, 0.0).is_some())
            .count() as u32;
        assert_eq!(held, bound, "held for the bound, then the law");
        assert_eq!(tick(&mut traction, 0.0), None);
    }

    #[test]
    fn a_sensor_reading_low_most_of_the_time_leaves_the_law_most_of_it() {
        let mut traction = Traction::new();
        let ticks = 10 * RATE.ticks_from_ms(1_000);
        // Light, with one normal sample in ten.
        let held = (0..ticks)
            .filter(|i| tick(&mut traction, if i % 10 == 0 { 9.8 } else { 0.0 }).is_some())
            .count() as u32;
        let config = TractionConfig::ROBOT;
        let cycle = config.max_hold_ms + config.landing_ms + config.rearm_ms;
        let most = (config.max_hold_ms + config.landing_ms) as f32 / cycle as f32;
        assert!(
            held as f32 <= most * ticks as f32 + 1.0,
            "held {held} of {ticks}"
        );
        assert!(held > 0);
    }

    #[test]
    fn a_stall_soon_after_a_drop_is_known_as_one_and_a_bounce_neither_counts_nor_erases_it() {
        let mut traction = Traction::new();
        let landing = RATE.ticks_from_ms(TractionConfig::ROBOT.landing_ms);
        // A bounce: light for three samples.
        for _ in 0..3_u32 {
            tick(&mut traction, 0.0);
        }
        for _ in 0..landing + 10 {
            tick(&mut traction, 9.8);
        }
        assert!(!traction.fell_within(1_000));
        // Rearmed, then a drop off a 6 cm edge: 110 ms light.
        for _ in 0..RATE.ticks_from_ms(TractionConfig::ROBOT.rearm_ms) {
            tick(&mut traction, 9.8);
        }
        for _ in 0..RATE.ticks_from_ms(110) {
            tick(&mut traction, 0.0);
        }
        let landing = RATE.ticks_from_ms(TractionConfig::ROBOT.landing_ms);
        for _ in 0..landing + 10 {
            tick(&mut traction, 9.8);
        }
        assert!(!traction.holding());
        assert!(traction.fell_within(20));
        assert!(!traction.fell_within(5));
        // A bounce after the drop does not make it forgotten.
        for _ in 0..RATE.ticks_from_ms(TractionConfig::ROBOT.rearm_ms) {
            tick(&mut traction, 9.8);
        }
        for _ in 0..3_u32 {
            tick(&mut traction, 0.0);
        }
        for _ in 0..landing + 10 {
            tick(&mut traction, 9.8);
        }
        let since_drop_ticks = RATE.ticks_from_ms(TractionConfig::ROBOT.rearm_ms) + 2 * landing;
        assert!(traction.fell_within(since_drop_ticks + 40));
    }
}
