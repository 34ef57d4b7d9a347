//! The E-stop as a stop of category 1 (IEC 60204-1 "SS1"): the drives stay powered while the
//! controller brings the robot to rest and sets it down, then every drive goes torque-free.
//!
//! # Why not cut at once
//!
//! Cutting every drive on the latch (category 0) drops a balancing robot: at 0.48 m/s the
//! torso pitched 25° onto the folded legs and fell to 0.255 m, and a robot standing on limp legs
//! sags onto its wheels at 0.45–0.6 m/s and rolls back 25° onto its leg links (both measured in
//! the simulator). Category 0 stays for faults of the controller itself (`State::Fault`).
//!
//! # The sequence
//!
//! On the **wheels** (the measured leg pose puts them on the ground when the latch arrives):
//!
//! 1. **Brake** — the balance law keeps running with a zero speed reference, which the law
//!    ramps down at its brake limit
//!    ([`crate::wheels::balance::BalanceConfig::brake_limit_m_s2`], 1.2 m/s², the same as a
//!    Stop: from the top speed of 0.48 m/s the reference is at zero after 0.6 s, and the lean
//!    it costs stays near 6°); the legs ramp into the fold if the latch came mid-fold
//!    ([`StopConfig::fold_rate_rad_s`]).
//! 2. **Kickstand** — at rest (ground and turn speed below [`StopConfig::rest_speed_m_s`]),
//!    or when the deadline leaves no more time, the legs ramp in joint space (smoothstep: the
//!    joints start and end at rest) into the kickstand pose ([`StopConfig::kickstand_front`],
//!    [`StopConfig::kickstand_back`]), as slowly as the deadline allows, and its middle slower
//!    still ([`StopConfig::kickstand_slow_middle`]: half an even pace, the ends at twice). The
//!    middle is where the front feet pass under the hips, deeper than the wheels: they lift the
//!    robot onto its feet and set it back down, and at smoothstep's pace, fastest there, they
//!    threw it up and dropped it (in the campaign's E-stop, 60 of 100 runs descended faster than
//!    0.35 m/s under power; with the slow middle 17). The balance law runs
//!    while the leg pose leaves the wheels on the ground, and stops once the feet carry the robot
//!    ([`crate::legs::support`]). The front legs end stretched forward 2° short of their joint
//!    stops, the back legs behind and deeper than the wheels, so the robot comes to rest leaning
//!    about 12° forward on its front feet and wheels. Powered, the servos hold the 2° against the
//!    load (on the stops themselves, the load pressed a powered joint past its range by up to
//!    1.8° in the campaign); unpowered, a front leg pushed up by the ground presses its hip, knee
//!    and ankle into their stops: the legs are struts, and cutting the torque changes little.
//! 3. **Settle** — the kickstand pose is held for [`StopConfig::settle_ms`].
//! 4. **Off** — legs disabled, wheel torque 0.
//!
//! On the **legs** (standing, trotting, standing up) the legs ramp straight from where they are
//! into the kickstand pose, which sits the torso down onto its wheels and front feet; then
//! Settle and Off. The first share of that path ([`StopConfig::sit_rise_share`]) lifts the torso
//! a little rather than lowering it, so it goes at the fastest rate (**Rise**) and the rest of
//! the deadline goes to the part that lowers it (`sim-host/tests/estop_ss1.rs` measures the
//! descent).
//!
//! The front feet pass under the hips on the way to their stops. From the wheels they are
//! unloaded and swing out sideways on the way ([`StopConfig::kickstand_spread_rad`]), so they
//! barely touch the ground; from the legs they carry the robot and stay in their plane, and
//! the torso's last centimetres onto the wheels come as the front feet sweep forward and leave
//! the ground for a moment.
//!
//! Why a kickstand: unpowered on its wheels with the legs folded, the robot rolls back 26° onto
//! its leg links (its centre of mass sits just behind the axle), and limp legs cannot carry it
//! (a scan of poses dropped unpowered onto the wheels and nudged either way found no folded pose
//! below 23°, and the kickstand at 12° either way). The front legs cannot reach their stops
//! without touching the ground: their shank passes vertical on the way, which puts the foot
//! 0.30 m below the hip, deeper than the 0.235 m the wheels leave. So the sweep lifts the robot
//! onto its feet for a moment and sets it back down, under power.
//!
//! # Stall and runaway
//!
//! The same stop ends a stall or a runaway on the wheels ([`crate::wheels::runaway`]) in
//! `Fault`: the controller itself is sound, and cutting the torque would drop the robot. A
//! runaway brakes from the speed the robot has ([`Carrier::Wheels`]). A stall
//! ([`Carrier::Blocked`]) means something stands in front of the wheels: the back legs go
//! straight to their kickstand pose while the front legs stay folded (swung forward they would
//! push the robot off the obstacle), and the wheels hold still instead of balancing. Driving at
//! 0.53 m/s into the 6 cm step, the robot stays within 13 cm of where it met the step
//! (`sim-host/tests/stall.rs`).
//!
//! Whatever remains undone [`StopConfig::cut_margin_ms`] and a tick before [`SS1_DEADLINE_MS`]
//! after the latch is cut then (the margin lets the command cross the bus in time): the
//! drives start their own timer of the same length on the latch frame and cut torque when it
//! ends, so the controller's stop must be over by then. A robot doing nothing (`Hold`), already
//! in `Fault`, or not yet armed is cut at once; any fault cause during the sequence (a drive
//! fault, stale feedback or IMU, a fall, a non-finite output) cuts at once too: a fault can only
//! cut torque sooner.

use protocol::{Joints, Leg};

use crate::control::safety::SS1_DEADLINE_MS;
use crate::legs::kinematics::LegJoints;
use crate::legs::ramp::ramp_ticks;
use crate::math::deg_to_rad;
use crate::time::{Tick, TickRate};

/// Tunables of the controlled stop.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StopConfig {
    /// Largest joint rate of the ramp into the fold when the latch came mid-fold, rad/s
    /// (reached mid-ramp; the mean is two thirds of it).
    pub fold_rate_rad_s: f32,
    /// Largest joint rate of the fastest ramp into the kickstand pose, rad/s: it decides when the
    /// kickstand must start at the latest to be settled before the deadline.
    pub kickstand_rate_rad_s: f32,
    /// Ground and turn speed below which the robot counts as at rest, m/s.
    pub rest_speed_m_s: f32,
    /// How long the kickstand pose is held, balancing, before the torque goes, ms.
    pub settle_ms: u32,
    /// How long before [`SS1_DEADLINE_MS`] the controller commands torque off, ms: the
    /// command has to reach the drives by the deadline through the bus's transport delay (up
    /// to two 4 ms cycles), whatever the drives' own timers do. Every millisecond of it is
    /// taken from the sit-down, whose torso descent grows as the ramp shortens.
    pub cut_margin_ms: u32,
    /// Outward hip abduction of the front legs midway through the kickstand from the wheels,
    /// rad (none at either end). Their feet pass under the hips on the way to the stops, 9 cm
    /// deeper than the wheels in the leg plane: swung out sideways they pass 1 to 2 cm deep
    /// instead, so the sweep no longer lifts the robot off its wheels and drops it (torso
    /// descent under power 1.17 m/s without, 0.31 m/s with 0.6 rad, in the simulator).
    pub kickstand_spread_rad: f32,
    /// Share of the kickstand's time over which the spread comes in, and again over which it
    /// goes out (held in between). A robot whose centre of mass sits behind balances nose down
    /// and its front feet meet the ground early in the sweep, where a spread that peaked only
    /// midway still had them in the leg plane: they pushed the robot back, lifted it and
    /// dropped it (the campaign's E-stop over 500 trials: 84.8 → 90.0 % with 0.3, and 85 % on
    /// the held-out 300 of them → 90 %; 0.2 and 0.5 measured worse than the bump, 0.28–0.35
    /// about as well).
    pub kickstand_spread_ramp: f32,
    /// Share of the joint path into the kickstand that a sit-down from the legs takes first, at
    /// [`StopConfig::kickstand_rate_rad_s`]: over it the torso does not come down (from a
    /// stand it rises 2 cm), so the rest of the deadline goes to the part that lowers it.
    pub sit_rise_share: f32,
    /// Damping the wheels hold still with in a stop against an obstacle, N·m per rad/s of
    /// wheel rate (the per-wheel torque limit clamps it).
    pub wheel_hold_nm_per_rad_s: f32,
    /// From the wheels, how much slower than an even pace the middle of the kickstand ramp
    /// goes, 0…1 (its ends go `1 + 2 ×` this faster; see the module docs, "Kickstand").
    pub kickstand_slow_middle: f32,
    /// Kickstand pose of the front legs (short of the joint stops: see the module docs).
    pub kickstand_front: LegJoints,
    /// Kickstand pose of the back legs.
    pub kickstand_back: LegJoints,
}

impl StopConfig {
    /// The robot's stop. The kickstand pose was chosen by a scan of poses dropped unpowered on
    /// the wheels and nudged either way (each ended at 12.4° forward, on the front feet).
    pub const ROBOT: Self = Self {
        fold_rate_rad_s: 2.0,
        kickstand_rate_rad_s: 3.0,
        rest_speed_m_s: 0.02,
        settle_ms: 100,
        cut_margin_ms: 12,
        kickstand_spread_rad: deg_to_rad(34.0),
        kickstand_spread_ramp: 0.3,
        sit_rise_share: 0.3,
        wheel_hold_nm_per_rad_s: 10.0,
        kickstand_slow_middle: 0.5,
        kickstand_front: LegJoints {
            hip_abduction_rad: 0.0,
            hip_pitch_rad: deg_to_rad(48.0),
            knee_rad: deg_to_rad(13.0),
            ankle_rad: deg_to_rad(38.0),
        },
        kickstand_back: LegJoints {
            hip_abduction_rad: 0.0,
            hip_pitch_rad: deg_to_rad(-48.0),
            knee_rad: deg_to_rad(13.0),
            ankle_rad: deg_to_rad(38.0),
        },
    };

    /// The kickstand pose of all four legs.
    pub fn kickstand(&self) -> Joints<f32> {
        let (front, back) = (
            self.kickstand_front.to_array(),
            self.kickstand_back.to_array(),
        );
        Joints::from_leg_fn(|leg| match leg {
            Leg::Fl | Leg::Fr => front,
            Leg::Bl | Leg::Br => back,
        })
    }
}

/// A [`legs::ramp::Ramp`](crate::legs::ramp::Ramp) with the front legs swung out by a spread
/// of abduction that is zero at both ends (clear of the wheels on the way into the kickstand).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Ramp {
    ramp: crate::legs::ramp::Ramp,
    spread_rad: f32,
    /// Share of the move over which the spread comes in and goes out.
    spread_ramp: f32,
    /// How much slower than an even pace the middle of the move goes (see
    /// [`crate::legs::ramp::Ramp::at_warped`]).
    slow_middle: f32,
}

impl Ramp {
    /// From `from` to `to` starting at `start`, no joint faster than `peak_rate_rad_s`.
    fn new(
        from: Joints<f32>,
        to: Joints<f32>,
        start: Tick,
        peak_rate_rad_s: f32,
        rate: TickRate,
    ) -> Self {
        Self {
            ramp: crate::legs::ramp::Ramp::new(from, to, start, peak_rate_rad_s, rate),
            spread_rad: 0.0,
            spread_ramp: 0.5,
            slow_middle: 0.0,
        }
    }

    /// The pose at `now`, and whether the ramp is over.
    fn at(&self, now: Tick) -> (Joints<f32>, bool) {
        let (mut pose, done) = self.ramp.at_warped(now, self.slow_middle);
        if done {
            return (pose, true);
        }
        let s = self.ramp.progress(now);
        // Abduction is about +x: outward is positive on the left, negative on the right.
        let ramp = self.spread_ramp.max(f32::EPSILON);
        let spread = self.spread_rad * (s.min(1.0 - s) / ramp).min(1.0);
        if let Some(fl) = pose.leg_mut(Leg::Fl).first_mut() {
            *fl += spread;
        }
        if let Some(fr) = pose.leg_mut(Leg::Fr).first_mut() {
            *fr -= spread;
        }
        (pose, false)
    }
}

/// What carries the robot when the E-stop latches, which decides how it stops.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Carrier {
    /// Nothing moves under power (`Hold`, `Fault`, not armed): torque off at once.
    Nothing,
    /// The wheels, balancing: brake to rest, then the kickstand.
    Wheels,
    /// The legs: straight into the kickstand, which lowers the torso onto the wheels.
    Legs,
    /// The wheels, stopped by something they cannot roll over: straight into the kickstand,
    /// at its fastest, while balancing.
    Blocked,
}

/// Ticks from the latch at which the controller cuts the torque whatever the sequence has done:
/// [`StopConfig::cut_margin_ms`] before [`SS1_DEADLINE_MS`], and a tick more, since the
/// controller may hear the latch frame a tick after the drives, which time their own cut from
/// it.
fn cut_ticks(config: &StopConfig, rate: TickRate) -> u32 {
    let margin_ms = config.cut_margin_ms.min(SS1_DEADLINE_MS);
    rate.ticks_from_ms(SS1_DEADLINE_MS - margin_ms)
        .saturating_sub(1)
}

/// Length of a kickstand ramp started `elapsed` ticks after the latch that ends, with the settle
/// time after it, at the cut: as slow as the deadline allows, since the torso's motion scales
/// with the joints'.
fn last_ramp_ticks(config: &StopConfig, rate: TickRate, elapsed: u32) -> u32 {
    cut_ticks(config, rate)
        .saturating_sub(elapsed)
        .saturating_sub(rate.ticks_from_ms(config.settle_ms))
        .saturating_sub(1)
}

/// The ramp from `from` into the kickstand pose, started at `now`, `elapsed` ticks after the
/// latch, ending (with the settle time after it) at the cut.
fn kickstand_ramp(
    config: &StopConfig,
    rate: TickRate,
    from: Joints<f32>,
    now: Tick,
    elapsed: u32,
    spread_rad: f32,
) -> Ramp {
    let ticks = last_ramp_ticks(config, rate, elapsed);
    Ramp {
        ramp: crate::legs::ramp::Ramp::over(from, config.kickstand(), now, ticks),
        spread_rad,
        spread_ramp: config.kickstand_spread_ramp,
        // From the wheels (the front legs swing out), the feet pass under the hips mid-move.
        slow_middle: if spread_rad > 0.0 {
            config.kickstand_slow_middle
        } else {
            0.0
        },
    }
}

/// Where the stop is.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Phase {
    /// On the wheels: braking to rest, balancing, legs ramping into the fold (they are there
    /// unless the latch came mid-fold).
    Brake(Ramp),
    /// From the legs: the first share of the way into the kickstand
    /// ([`StopConfig::sit_rise_share`]), which does not lower the torso, at the fastest rate.
    Rise(Ramp),
    /// Legs ramping into the kickstand pose, balancing while the wheels are on the ground.
    Kickstand(Ramp),
    /// The last pose reached at this tick and held until the settle time has passed.
    Settle(Tick, Joints<f32>),
    /// Every drive torque-free.
    Off,
}

/// What the controller measures for the stop each tick.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StopInput {
    /// This tick.
    pub now: Tick,
    /// Ground speed of the axle and half the speed difference of the wheels, m/s.
    pub speeds_m_s: [f32; 2],
    /// Whether the balance law's speed reference has come to zero.
    pub braked: bool,
    /// Whether a fault cause is active (a fault cuts torque at once).
    pub fault: bool,
}

/// What the stop asks of the drives this tick.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StopCommand {
    /// Servo the legs to these targets, and balance with a zero speed reference while the
    /// wheels are on the ground.
    Servo(Joints<f32>),
    /// Every drive torque-free.
    Off,
}

/// A running controlled stop, from the latch (or the stall or runaway) until it is cleared.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stop {
    config: StopConfig,
    rate: TickRate,
    latched: Tick,
    /// Ticks the kickstand needs from the fold, settle time and one spare tick included.
    kickstand_needed: u32,
    /// Whether the wheels hold still instead of balancing.
    holds_wheels: bool,
    phase: Phase,
    /// Whether a tick of the stop has commanded every drive torque-free.
    cut: bool,
}

impl Stop {
    /// A stop latched at `now` with the legs at `legs_rad` and the robot on `carrier`
    /// (`fold_rad`: the fold pose the wheels brake in).
    pub fn new(
        config: StopConfig,
        rate: TickRate,
        now: Tick,
        legs_rad: Joints<f32>,
        fold_rad: Joints<f32>,
        carrier: Carrier,
    ) -> Self {
        let phase = match carrier {
            Carrier::Nothing => Phase::Off,
            Carrier::Wheels => Phase::Brake(Ramp::new(
                legs_rad,
                fold_rad,
                now,
                config.fold_rate_rad_s,
                rate,
            )),
            Carrier::Blocked => {
                let mut to = config.kickstand();
                for leg in [Leg::Fl, Leg::Fr] {
                    *to.leg_mut(leg) = *fold_rad.leg(leg);
                }
                Phase::Kickstand(Ramp::new(
                    legs_rad,
                    to,
                    now,
                    config.kickstand_rate_rad_s,
                    rate,
                ))
            }
            Carrier::Legs => {
                let share = config.sit_rise_share.clamp(0.0, 1.0);
                let mut to = legs_rad;
                for (joint, goal) in to.iter_mut().zip(config.kickstand().iter()) {
                    *joint += share * (goal - *joint);
                }
                let peak_rate = config.kickstand_rate_rad_s;
                Phase::Rise(Ramp::new(legs_rad, to, now, peak_rate, rate))
            }
        };
        // The fastest kickstand from the fold, settled, with one tick to spare: what the
        // braking must leave before the cut.
        let kickstand_needed = ramp_ticks(
            &fold_rad,
            &config.kickstand(),
            config.kickstand_rate_rad_s,
            rate,
        )
        .saturating_add(rate.ticks_from_ms(config.settle_ms))
        .saturating_add(1);
        Self {
            config,
            rate,
            latched: now,
            kickstand_needed,
            holds_wheels: carrier == Carrier::Blocked,
            phase,
            cut: false,
        }
    }

    /// Whether the wheels hold still rather than balance: a robot stopped by an obstacle
    /// rests on its wheels and legs, and balancing would roll it away from the obstacle.
    pub fn holds_wheels(&self) -> bool {
        self.holds_wheels && self.phase != Phase::Off
    }

    /// Whether every drive is torque-free from now until the clear.
    pub fn off(&self) -> bool {
        self.phase == Phase::Off
    }

    /// One tick of the stop.
    pub fn step(&mut self, input: &StopInput) -> StopCommand {
        let now = input.now;
        if input.fault || now.since(self.latched) >= cut_ticks(&self.config, self.rate) {
            self.phase = Phase::Off;
        }
        let (command, next) = match self.phase {
            Phase::Brake(ramp) => {
                let (pose, done) = ramp.at(now);
                let [ground, turn] = input.speeds_m_s;
                let rest = self.config.rest_speed_m_s;
                let at_rest = input.braked && ground.abs() < rest && turn.abs() < rest;
                let next = ((done && at_rest) || self.kickstand_due(now))
                    .then(|| self.kickstand_from(pose, now, self.config.kickstand_spread_rad));
                (StopCommand::Servo(pose), next)
            }
            Phase::Rise(ramp) => {
                let (pose, done) = ramp.at(now);
                // No spread: the front feet carry the robot until the wheels take it.
                let next = done.then(|| self.kickstand_from(pose, now, 0.0));
                (StopCommand::Servo(pose), next)
            }
            Phase::Kickstand(ramp) => {
                let (pose, done) = ramp.at(now);
                (
                    StopCommand::Servo(pose),
                    // Done, the pose is the ramp's goal.
                    done.then_some(Phase::Settle(now, pose)),
                )
            }
            Phase::Settle(since, pose) => {
                // Off from the tick the settle ends: the phase is `Off` only once the torque is.
                if now.since(since) >= self.rate.ticks_from_ms(self.config.settle_ms) {
                    (StopCommand::Off, Some(Phase::Off))
                } else {
                    (StopCommand::Servo(pose), None)
                }
            }
            Phase::Off => (StopCommand::Off, None),
        };
        if let Some(next) = next {
            self.phase = next;
        }
        self.cut |= command == StopCommand::Off;
        command
    }

    /// Whether a tick of the stop has commanded every drive torque-free (it is then over: a
    /// stop of category 1 ends torque-free).
    pub fn cut(&self) -> bool {
        self.cut
    }

    /// The ramp from `pose` into the kickstand started at `now`, as slowly as the deadline
    /// allows (the torso's descent scales with it), the front legs swung out by `spread_rad`.
    fn kickstand_from(&self, pose: Joints<f32>, now: Tick, spread_rad: f32) -> Phase {
        let elapsed = now.since(self.latched);
        let ramp = kickstand_ramp(&self.config, self.rate, pose, now, elapsed, spread_rad);
        Phase::Kickstand(ramp)
    }

    /// Whether the kickstand must start now to be reached and settled before the deadline
    /// (planned from the fold, with one tick to spare).
    fn kickstand_due(&self, now: Tick) -> bool {
        now.since(self.latched)
            .saturating_add(self.kickstand_needed)
            >= cut_ticks(&self.config, self.rate)
    }
}
