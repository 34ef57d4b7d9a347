//! The wheels-first climb of a step behind the robot: it backs onto the step on its wheels,
//! and where the wheels stall against the riser the back hips already stand over the
//! plateau. The legs' knees bend so that a foot reaches high only behind its hip
//! ([`crate::legs::kinematics`]), so the back feet can be set on the plateau from there with
//! the robot still on its wheels — no foot has to step up a riser.
//!
//! The climb, one phase after another, every foot placed by its leg's own measured load:
//!
//! 1. **Prop**: the wheels hold still and the front feet are lowered from the fold onto the
//!    ground before the riser until each carries a load: the robot stands on wheels and front
//!    feet, a stool.
//! 2. **Reach**: the back feet swing from the fold to above the plateau, behind their hips.
//! 3. **Probe**: they are lowered until each carries a load.
//! 4. **Rise**: the legs lengthen, lifting the wheels clear of the plateau, each pair to its
//!    own depth below the hips; a step too high is stepped down from as soon as the height
//!    reads sound, partway up.
//! 5. **Shift, Step** (a crawl): the body shifts back over its four planted feet, each back foot steps back,
//!    and the body shifts back again; the stance is long (back feet well behind their hips on
//!    the plateau), so that the centre of mass stays inside the other three feet without a
//!    sway. The front feet do not step: each front step let the body slide forward as far as
//!    the shift had carried it back.
//! 6. **Lower**: all four legs shorten, the back pair more, until the wheels stand on the
//!    plateau; then the robot folds onto them there (the controller's fold).
//!
//! A step lower than the wheels climb, higher than the legs set a foot on, or no ground
//! within reach ends the climb with a [`ClimbEnd`] the controller reports.

use protocol::Leg;

mod config;
mod feet;

pub use config::ClimbConfig;
pub use feet::{foot_of, solve};

use feet::{blend, step_foot};

use crate::legs::crawl::frame::PerLeg;
use crate::legs::kinematics::{LegGeometry, LegJoints};
use crate::math::{clamp, smoothstep};
use crate::time::{Tick, TickRate};

/// Why a climb ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ClimbEnd {
    /// The crawl has set the wheels on the plateau: fold onto them.
    Over,
    /// Stopped before the legs lifted the robot: they are back in the fold, on the wheels.
    Stopped,
    /// No ground within the legs' reach.
    NoGround,
    /// The step is lower than the wheels climb (no climb needed) or higher than the legs set
    /// a foot on.
    StepOutOfRange,
    /// The legs have set the body down, but not on its wheels on the plateau.
    NotOver,
}

/// What the climb reads from the drives each tick.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClimbInput {
    /// Each foot's load from its hip and knee torques, N (`None`: not known).
    pub loads_n: PerLeg<Option<f32>>,
    /// How much higher each foot stands than it is sent (the commanded pose's depth less the
    /// measured pose's), m.
    pub lag_m: PerLeg<f32>,
    /// The body's estimated pitch, rad, positive nose down.
    pub pitch_rad: f32,
}

/// Where the climb is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Phase {
    /// Front feet swinging down and lowered until they carry.
    Prop,
    /// Back feet swinging from the fold to above the plateau.
    Reach,
    /// Back feet lowered until they carry.
    Probe,
    /// The legs lengthening.
    Rise,
    /// The legs going back to where they were before the rise (or the climb), the step too
    /// high or too low.
    Retreat,
    /// Crawl cycle `cycle`: the body shifting back over the planted feet.
    Shift {
        /// Cycles done before this one.
        cycle: u8,
    },
    /// Crawl cycle `cycle`: a back foot stepping back.
    Step {
        /// Cycles done before this one.
        cycle: u8,
        /// Which back foot: 0 the left, 1 the right.
        foot: u8,
    },
    /// The legs shortening until the wheels stand on the plateau.
    Lower,
    /// Over, or given up.
    Ended(ClimbEnd),
}

/// A foot's place in its leg frame: forward and below the hip, m.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Foot {
    /// Forward of the hip, m.
    pub x_m: f32,
    /// Below the hip, m.
    pub depth_m: f32,
}

/// The climb under way.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Climb {
    phase: Phase,
    since: Tick,
    /// Where each foot started this phase.
    from: PerLeg<Foot>,
    /// Each foot's target now.
    target: PerLeg<Foot>,
    /// Which feet are down.
    down: PerLeg<bool>,
    /// Each foot's target when the rise began, or when the climb began until then: where a
    /// retreat returns to.
    before_rise: PerLeg<Foot>,
    /// How a retreat ends.
    retreat_end: ClimbEnd,
    /// Whether the step's height was judged partway up the rise.
    rise_checked: bool,
}

impl Climb {
    /// A climb starting at `now` with the legs at `measured` (the fold).
    pub fn new(now: Tick, geometry: &LegGeometry, measured: &PerLeg<LegJoints>) -> Self {
        let feet = PerLeg::from_fn(|leg| foot_of(geometry, &measured.get(leg)));
        Self {
            phase: Phase::Prop,
            since: now,
            from: feet,
            target: feet,
            down: PerLeg::splat(false),
            before_rise: feet,
            retreat_end: ClimbEnd::StepOutOfRange,
            rise_checked: false,
        }
    }

    /// A stop at `now`: before the rise the legs go back to the fold (and the climb ends
    /// [`ClimbEnd::Stopped`]); from the rise on the climb carries on over the step, since
    /// legs standing a step apart in height have no safe pose short of its end.
    pub fn stop(&mut self, now: Tick) {
        if matches!(self.phase, Phase::Prop | Phase::Reach | Phase::Probe) {
            self.retreat_end = ClimbEnd::Stopped;
            self.enter(Phase::Retreat, now);
        }
    }

    /// The phase.
    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// Each foot's target now.
    pub fn targets(&self) -> PerLeg<Foot> {
        self.target
    }

    /// The step's height from where the feet touched and the body's pitch then (positive nose
    /// down), m: the back feet's height over the front feet's.
    pub fn step_height_m(&self, config: &ClimbConfig, pitch_rad: f32) -> f32 {
        let mean = |a: Leg, b: Leg| 0.5 * (self.target.get(a).depth_m + self.target.get(b).depth_m);
        mean(Leg::Fl, Leg::Fr) - mean(Leg::Bl, Leg::Br)
            + 2.0 * config.hips.x_m * crate::math::sin(pitch_rad)
    }

    /// One tick at `now` with what the drives report (`input`).
    pub fn tick(&mut self, config: &ClimbConfig, rate: TickRate, now: Tick, input: &ClimbInput) {
        let pitch_rad = input.pitch_rad;
        let t_s = now.since(self.since) as f32 * rate.period_s();
        match self.phase {
            Phase::Prop => self.prop(config, rate, now, t_s, input),
            Phase::Reach => self.reach(config, now, t_s),
            Phase::Probe => self.probe(config, rate, now, input),
            Phase::Rise => self.rise(config, now, t_s, pitch_rad),
            Phase::Retreat => self.retreat(config, t_s),
            Phase::Shift { cycle } => self.shift(config, now, t_s, cycle),
            Phase::Step { cycle, foot } => self.step(config, now, t_s, cycle, foot),
            Phase::Lower => self.lower_onto_wheels(config, t_s, pitch_rad),
            Phase::Ended(_) => {}
        }
    }

    fn prop(
        &mut self,
        config: &ClimbConfig,
        rate: TickRate,
        now: Tick,
        t_s: f32,
        input: &ClimbInput,
    ) {
        let share = share_of(t_s, config.reach_ms);
        let goal = Foot {
            x_m: config.prop_x_m,
            depth_m: config.prop_depth_m,
        };
        if share < 1.0 {
            for leg in [Leg::Fl, Leg::Fr] {
                if !self.down.get(leg) {
                    *self.target.get_mut(leg) = blend(self.from.get(leg), goal, share);
                }
            }
        }
        if self.lower([Leg::Fl, Leg::Fr], config, rate, input) {
            self.enter(Phase::Reach, now);
        }
    }

    fn reach(&mut self, config: &ClimbConfig, now: Tick, t_s: f32) {
        let share = share_of(t_s, config.reach_ms);
        let goal = Foot {
            x_m: config.reach_x_m,
            depth_m: config.reach_depth_m,
        };
        for leg in [Leg::Bl, Leg::Br] {
            *self.target.get_mut(leg) = blend(self.from.get(leg), goal, share);
        }
        if share >= 1.0 {
            self.enter(Phase::Probe, now);
        }
    }

    fn probe(&mut self, config: &ClimbConfig, rate: TickRate, now: Tick, input: &ClimbInput) {
        if self.lower([Leg::Bl, Leg::Br], config, rate, input) {
            // A riser the wheels have started up tips the robot forward over its front feet
            // (19° at 10 cm, against 2–10° nose up at 6 and 8 cm): refused before the legs
            // lift it (the rise from there tipped it over). The back feet's touchdown reads
            // too early to tell the height here.
            if input.pitch_rad > config.pitch_max_rad {
                // Back to where the legs were when the wheels stalled.
                self.enter(Phase::Retreat, now);
            } else {
                self.enter(Phase::Rise, now);
                self.before_rise = self.target;
            }
        }
    }

    fn rise(&mut self, config: &ClimbConfig, now: Tick, t_s: f32, pitch_rad: f32) {
        let share = share_of(t_s, config.rise_ms);
        let s = smoothstep(share);
        for leg in Leg::ALL {
            let from = self.from.get(leg);
            let depth_m = match leg {
                Leg::Fl | Leg::Fr => config.front_depth_m,
                Leg::Bl | Leg::Br => config.back_depth_m,
            };
            *self.target.get_mut(leg) = Foot {
                depth_m: from.depth_m + (depth_m - from.depth_m) * s,
                ..from
            };
        }
        // The body's pitch and the two pairs' depths say how much higher the back feet stand
        // than the front ones. A step higher than the crawl carries the robot over safely is
        // stepped down from again, as early as the estimate is sound; a step too low only at
        // the end, where the estimate is best.
        let step_m = self.step_height_m(config, pitch_rad);
        if pitch_rad > config.rise_pitch_max_rad {
            self.enter(Phase::Retreat, now);
            return;
        }
        if !self.rise_checked && share >= config.rise_check_share {
            self.rise_checked = true;
            if step_m > config.step_max_m {
                self.enter(Phase::Retreat, now);
                return;
            }
        }
        if share >= 1.0 {
            if (config.step_min_m..=config.step_max_m).contains(&step_m) {
                self.enter(Phase::Shift { cycle: 0 }, now);
            } else {
                self.enter(Phase::Retreat, now);
            }
        }
    }

    fn retreat(&mut self, config: &ClimbConfig, t_s: f32) {
        let share = share_of(t_s, config.rise_ms);
        for leg in Leg::ALL {
            *self.target.get_mut(leg) = blend(self.from.get(leg), self.before_rise.get(leg), share);
        }
        if share >= 1.0 {
            self.phase = Phase::Ended(self.retreat_end);
        }
    }

    fn shift(&mut self, config: &ClimbConfig, now: Tick, t_s: f32, cycle: u8) {
        let share = share_of(t_s, config.shift_ms);
        for leg in Leg::ALL {
            let from = self.from.get(leg);
            *self.target.get_mut(leg) = Foot {
                x_m: from.x_m + config.crawl_m * smoothstep(share),
                ..from
            };
        }
        if share >= 1.0 {
            if cycle.saturating_add(1) >= config.crawl_cycles {
                self.enter(Phase::Lower, now);
            } else {
                self.enter(Phase::Step { cycle, foot: 0 }, now);
            }
        }
    }

    fn step(&mut self, config: &ClimbConfig, now: Tick, t_s: f32, cycle: u8, foot: u8) {
        let share = share_of(t_s, config.step_ms);
        if let Some(&leg) = STEP_ORDER.get(usize::from(foot)) {
            *self.target.get_mut(leg) = step_foot(self.from.get(leg), config, share);
        }
        if share >= 1.0 {
            let next_foot = foot.saturating_add(1);
            let next = if usize::from(next_foot) < STEP_ORDER.len() {
                Phase::Step {
                    cycle,
                    foot: next_foot,
                }
            } else {
                Phase::Shift {
                    cycle: cycle.saturating_add(1),
                }
            };
            self.enter(next, now);
        }
    }

    fn lower_onto_wheels(&mut self, config: &ClimbConfig, t_s: f32, pitch_rad: f32) {
        let share = share_of(t_s, config.rise_ms);
        for leg in Leg::ALL {
            let from = self.from.get(leg);
            let lower_m = match leg {
                Leg::Fl | Leg::Fr => config.lower_front_m,
                Leg::Bl | Leg::Br => config.lower_back_m,
            };
            *self.target.get_mut(leg) = Foot {
                depth_m: from.depth_m - lower_m * smoothstep(share),
                ..from
            };
        }
        if share >= 1.0 {
            let over = pitch_rad.abs() <= config.over_pitch_max_rad;
            self.phase = Phase::Ended(if over {
                ClimbEnd::Over
            } else {
                ClimbEnd::NotOver
            });
        }
    }

    /// Lowers `legs`' feet not yet down by this tick's share of the probe speed, and marks
    /// those that carry; `true` once all are down. A foot past the deepest probe ends the
    /// climb ([`ClimbEnd::NoGround`]).
    fn lower(
        &mut self,
        legs: [Leg; 2],
        config: &ClimbConfig,
        rate: TickRate,
        input: &ClimbInput,
    ) -> bool {
        let step_m = config.probe_m_s * rate.period_s();
        for leg in legs {
            if self.down.get(leg) {
                continue;
            }
            let loaded = input
                .loads_n
                .get(leg)
                .is_some_and(|n| n >= config.touchdown_n);
            let carries = loaded && input.lag_m.get(leg) >= config.touchdown_lag_m;
            let foot = self.target.get_mut(leg);
            if carries {
                foot.depth_m += config.preload_m;
                *self.down.get_mut(leg) = true;
            } else if foot.depth_m + step_m > config.probe_depth_max_m {
                self.phase = Phase::Ended(ClimbEnd::NoGround);
                return false;
            } else {
                foot.depth_m += step_m;
            }
        }
        legs.iter().all(|&leg| self.down.get(leg))
    }

    fn enter(&mut self, phase: Phase, now: Tick) {
        self.phase = phase;
        self.since = now;
        self.from = self.target;
    }
}

/// How far through a span of `ms` milliseconds `t_s` seconds are, 0…1.
fn share_of(t_s: f32, ms: u32) -> f32 {
    clamp(t_s / (ms as f32 * 1e-3), 0.0, 1.0)
}

/// The feet that step in a crawl cycle, in order: the back feet, on the plateau.
const STEP_ORDER: [Leg; 2] = [Leg::Bl, Leg::Br];
