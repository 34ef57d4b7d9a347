//! The lean watch: whether the robot still balances on its wheels, or rests on its legs.
//!
//! Measured: dropping off a step's near edge while folding on the plateau, and catching itself
//! from 18° nose down after a refused climb, robots swung 20° nose up onto their tucked back
//! shanks. On wheels and shanks, the balance law, which sees only a lean it cannot correct,
//! drove them forward at up to 3 m/s while its trim followed the lean; the runaway watch saw
//! it only once the fold had ended, 2 m later, and the brake on the balance law could not
//! stop a robot dragging its shanks.
//!
//! A robot balancing on its wheels carries nothing on its tucked legs, however far a hard catch
//! leans it (a centre of mass 3 cm off swung one 19° past the trim it had not learned yet, its
//! legs unloaded). So while the balance law drives the wheels, a lean more than
//! [`LeanConfig::lean_rad`] from the learned trim with the legs carrying
//! [`LeanConfig::load_n`] between them, for [`LeanConfig::lean_ms`] (a bounce off the ground
//! counts down, not back to zero), is a runaway to stop with the wheels held still: the robot
//! already rests on its wheels and legs.

use crate::time::TickRate;

/// When a lean counts as resting on the legs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LeanConfig {
    /// Lean from the learned trim beyond which the legs' load is weighed, rad.
    pub lean_rad: f32,
    /// The legs' load (all four together, from their hip and knee torques) that says they
    /// carry the robot, N: tucked and in the air it read 0 N on every leg through a 19°
    /// catch, and 22–150 N between the back legs of a robot on its shanks.
    pub load_n: f32,
    /// … for this long, ms.
    pub lean_ms: u32,
}

impl LeanConfig {
    /// The robot.
    pub const ROBOT: Self = Self {
        lean_rad: crate::math::deg_to_rad(10.0),
        load_n: 30.0,
        lean_ms: 200,
    };
}

/// How long the robot has leaned on its legs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LeanWatch {
    leaned_ticks: u32,
    limit_ticks: u32,
}

impl LeanWatch {
    /// A watch with `config`'s time at the control rate `rate`.
    pub fn new(config: &LeanConfig, rate: TickRate) -> Self {
        Self {
            leaned_ticks: 0,
            limit_ticks: rate.ticks_from_ms(config.lean_ms).max(1),
        }
    }

    /// Forgets the lean (when the balance law does not drive the wheels).
    pub fn reset(&mut self) {
        self.leaned_ticks = 0;
    }

    /// One tick of the balance law with the body's lean from the learned trim (`lean_rad`)
    /// and the legs' load (`load_n`, N, asked only of a lean beyond the limit: it costs four
    /// legs' statics): `true` once the robot has leaned on its legs long enough. A lean or a
    /// load that is not finite counts as leaning on them.
    pub fn update(
        &mut self,
        config: &LeanConfig,
        lean_rad: f32,
        load_n: impl FnOnce() -> f32,
    ) -> bool {
        self.leaned_ticks = if lean_rad.abs() <= config.lean_rad {
            0
        } else if lean_rad.is_finite() && load_n() < config.load_n {
            self.leaned_ticks.saturating_sub(1)
        } else {
            self.leaned_ticks.saturating_add(1)
        };
        self.leaned_ticks >= self.limit_ticks
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const RATE: TickRate = TickRate::SIM_250_HZ;

    /// `ticks` ticks leaned `lean_rad` with `load_n` on the legs; whether the last tripped.
    fn lean_for(watch: &mut LeanWatch, ticks: u32, lean_rad: f32, load_n: f32) -> bool {
        let mut tripped = false;
        for _ in 0..ticks {
            tripped = watch.update(&LeanConfig::ROBOT, lean_rad, || load_n);
        }
        tripped
    }

    #[test]
    fn leaning_on_the_legs_past_its_time_trips_and_a_bounce_only_delays_it() {
        let config = LeanConfig::ROBOT;
        let far = config.lean_rad + 0.05;
        let ticks = RATE.ticks_from_ms(config.lean_ms);
        let mut watch = LeanWatch::new(&config, RATE);
        assert!(!lean_for(&mut watch, ticks - 1, -far, 60.0));
        assert!(
            !lean_for(&mut watch, 2, -far, 0.0),
            "off the ground for a moment"
        );
        assert!(!lean_for(&mut watch, 2, -far, 60.0));
        assert!(lean_for(&mut watch, 1, -far, 60.0));
        watch.reset();
        assert!(!lean_for(&mut watch, ticks - 1, far, 60.0));
        assert!(
            !lean_for(&mut watch, 1, 0.0, 60.0),
            "upright again: the count restarts"
        );
        assert!(!lean_for(&mut watch, ticks - 1, far, 60.0));
    }

    #[test]
    fn a_hard_catch_on_unloaded_legs_or_a_loaded_robot_upright_never_trips_and_nan_does() {
        let config = LeanConfig::ROBOT;
        let mut watch = LeanWatch::new(&config, RATE);
        assert!(!lean_for(&mut watch, 10_000, config.lean_rad + 0.3, 10.0));
        assert!(!lean_for(&mut watch, 10_000, config.lean_rad, 500.0));
        assert!(lean_for(&mut watch, 10_000, f32::NAN, 0.0));
        watch.reset();
        assert!(lean_for(
            &mut watch,
            10_000,
            config.lean_rad + 0.1,
            f32::NAN
        ));
    }
}
