//! The crawl: a quasi-static free gait that moves one thing at a time, the body with all four
//! feet down or one foot with the other three down, for ground the trot cannot take. Blind:
//! a swinging foot finds the ground, or a riser, from the drives' encoders and torques, and a
//! sway frees a foot by the loads the torques give ([`foot_loads_n`]).
//!
//! [`Crawl`] runs one move at a time ([`Crawl::start`]) and says how it ended
//! ([`Outcome`]). The body and the feet live in a ground frame fixed where the crawl began
//! ([`frame`]); the legs' targets are the IK of each foot seen from the commanded body, so a
//! planted foot stays where it stands while the body moves over it.
//!
//! The controller does not run it yet: a planner that takes the robot up a step with these
//! moves has not crossed one on the honest plant (docs/obstacles.md, "Climbing").
//!
//! # A swing
//!
//! Up by `lift` above where the foot stood, forward at that height, then down at a slow,
//! steady speed until the foot stops above its target by [`CrawlConfig::touchdown_lag_m`] or
//! its knee takes [`CrawlConfig::touchdown_knee_nm`] (it stands on something), or reaches
//! [`CrawlConfig::search_below_m`] under where it stood ([`Outcome::NoGround`]). Carried forward, a foot that falls behind its target by
//! [`CrawlConfig::blocked_lag_m`] has met a riser taller than the lift ([`Outcome::Blocked`]);
//! a path out of the legs' reach ends in [`Outcome::OutOfReach`]. Either way the foot goes
//! back down where it stood, from where it had got to.

pub mod frame;
mod loads;
mod moves;
pub mod preload;
mod swing;

use protocol::{Joints, Leg};

use crate::legs::kinematics::{IkError, LegGeometry, LegJoints};
use crate::limits::JointLimits;
use crate::time::TickRate;
use frame::{BodyPose, CrawlGeometry, PerLeg, Point};
pub use loads::{foot_loads_n, legs_load_n};
pub use moves::{Move, Outcome};
use swing::{smooth, swing_point, RetreatCause, SwingStage};

/// Tunables of a crawl's moves.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CrawlConfig {
    /// The body's dimensions and the legs' foot-pitch schedule.
    pub geometry: CrawlGeometry,
    /// How long a foot takes to lift, ms.
    pub lift_ms: u32,
    /// How long a lifted foot takes to travel to above its target, ms.
    pub carry_ms: u32,
    /// How fast a foot goes down looking for the ground, m/s.
    pub lower_m_s: f32,
    /// A lowered foot this far above its target stands on something, m.
    pub touchdown_lag_m: f32,
    /// A lowered foot whose knee carries this torque stands on something, N·m: a stiff leg
    /// pushed down lifts the body rather than lagging its target, and its knee takes the load.
    pub touchdown_knee_nm: f32,
    /// How far under where it stood a foot looks for the ground, m.
    pub search_below_m: f32,
    /// A carried foot this far behind its target has met a riser, m.
    pub blocked_lag_m: f32,
    /// How far under where it touched a landed foot's target stays, so that it carries, m.
    pub preload_m: f32,
    /// A foot that carries no more than this share of the weight is free to lift.
    pub unloaded_share: f32,
    /// How fast the body sways to free a foot, m/s.
    pub unload_m_s: f32,
}

impl CrawlConfig {
    /// The robot.
    pub const ROBOT: Self = Self {
        geometry: CrawlGeometry::ROBOT,
        lift_ms: 400,
        carry_ms: 500,
        lower_m_s: 0.08,
        touchdown_lag_m: 0.01,
        touchdown_knee_nm: 4.0,
        search_below_m: 0.04,
        blocked_lag_m: 0.03,
        preload_m: 0.005,
        unloaded_share: 0.1,
        unload_m_s: 0.04,
    };
}

/// The move under way.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Running {
    Idle,
    Unload {
        leg: Leg,
        from: BodyPose,
        /// Unit direction of the sway (x, y).
        direction: (f32, f32),
        max_m: f32,
    },
    Body {
        from: BodyPose,
        to: BodyPose,
        ticks: u32,
    },
    Swing {
        leg: Leg,
        from: Point,
        to: Point,
        top_z_m: f32,
        stage: SwingStage,
        /// Ticks into the stage.
        stage_ticks: u32,
    },
}

/// A running crawl: the body's commanded pose, the feet, and the move under way.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Crawl {
    rate: TickRate,
    body: BodyPose,
    feet: PerLeg<Point>,
    running: Running,
    elapsed: u32,
}

impl Crawl {
    /// A crawl of a body at the origin, level, on feet at `feet` (ground frame).
    pub fn new(rate: TickRate, feet: PerLeg<Point>) -> Self {
        Self {
            rate,
            body: BodyPose::default(),
            feet,
            running: Running::Idle,
            elapsed: 0,
        }
    }

    /// The body's commanded pose.
    pub fn body(&self) -> BodyPose {
        self.body
    }

    /// Where each foot stands (a swinging foot: where it stood).
    pub fn feet(&self) -> PerLeg<Point> {
        self.feet
    }

    /// Whether no move is under way.
    pub fn idle(&self) -> bool {
        self.running == Running::Idle
    }

    /// Starts `next` (replacing a move under way).
    pub fn start(&mut self, next: Move) {
        self.elapsed = 0;
        self.running = match next {
            Move::Unload { leg, max_m } => Running::Unload {
                leg,
                from: self.body,
                direction: self.away_from(leg),
                // A length that is not a length sways nowhere.
                max_m: if max_m.is_finite() {
                    max_m.max(0.0)
                } else {
                    0.0
                },
            },
            Move::Body { to, ms } => Running::Body {
                from: self.body,
                to,
                ticks: self.rate.ticks_from_ms(ms).max(1),
            },
            Move::Swing { leg, to, lift_m } => {
                let from = self.feet.get(leg);
                Running::Swing {
                    leg,
                    from,
                    to,
                    top_z_m: from.z_m.max(to.z_m) + lift_m,
                    stage: SwingStage::Lift,
                    stage_ticks: 0,
                }
            }
        };
    }

    /// The unit direction (x, y) of the sway that leaves `leg`'s load to the other three
    /// feet: sideways, away from the foot's side. (A sway toward the middle of the feet also
    /// moved the body along them, and it loaded the hips of the legs it moved over until they
    /// saturated at their rating.)
    fn away_from(&self, leg: Leg) -> (f32, f32) {
        let f = self.feet;
        let mid_y = 0.25 * (f.fl.y_m + f.fr.y_m + f.bl.y_m + f.br.y_m);
        let side = if f.get(leg).y_m > mid_y { -1.0 } else { 1.0 };
        match leg {
            // Back too, toward the back feet: by half as much as sideways.
            Leg::Fl | Leg::Fr => (-0.447, 0.894 * side),
            Leg::Bl | Leg::Br => (0.0, side),
        }
    }

    /// Where `leg`'s foot is commanded now.
    pub fn foot_target(&self, config: &CrawlConfig, leg: Leg) -> Point {
        match self.running {
            Running::Swing {
                leg: swinging,
                from,
                to,
                top_z_m,
                stage,
                stage_ticks,
            } if swinging == leg => {
                swing_point(config, self.rate, &from, &to, top_z_m, stage, stage_ticks)
            }
            _ => self.feet.get(leg),
        }
    }

    /// Joint targets of all four legs (in [`Leg::ALL`] order).
    pub fn targets(
        &self,
        config: &CrawlConfig,
        geometry: &LegGeometry,
        limits: &JointLimits,
    ) -> [Result<LegJoints, IkError>; 4] {
        Leg::ALL.map(|leg| {
            let foot = self.foot_target(config, leg);
            config
                .geometry
                .solve(geometry, limits, &self.body, leg, &foot)
        })
    }

    /// One tick of the move under way, with the drives' measured joint angles; `Some` when it
    /// ends.
    pub fn tick(
        &mut self,
        config: &CrawlConfig,
        geometry: &LegGeometry,
        limits: &JointLimits,
        measured_rad: &Joints<f32>,
        effort_nm: &Joints<f32>,
    ) -> Option<Outcome> {
        let outcome = self.advance(config, geometry, limits, measured_rad, effort_nm);
        if outcome.is_some() {
            self.reanchor(config, geometry, measured_rad);
        }
        outcome
    }

    /// How far the sway under way has gone, m: at the sway's speed, at most `max_m`.
    fn swayed_m(&self, config: &CrawlConfig, max_m: f32) -> f32 {
        (config.unload_m_s * self.elapsed as f32 * self.rate.period_s()).min(max_m)
    }

    /// Takes every foot's position along the ground from where the encoders put it, its
    /// height from its target. A foot that slipped, or a leg pushed off its target along the
    /// ground by the others, would otherwise leave the legs pushing against each other with
    /// the error times the servos' stiffness (5 cm of it saturated a hip at its 30 N·m
    /// rating); a leg sagging under its load keeps its target height, and with it its load.
    fn reanchor(
        &mut self,
        config: &CrawlConfig,
        geometry: &LegGeometry,
        measured_rad: &Joints<f32>,
    ) {
        for leg in Leg::ALL {
            let joints = LegJoints::from_array(*measured_rad.leg(leg));
            let measured = config.geometry.foot_of(geometry, &self.body, leg, &joints);
            let foot = self.feet.get_mut(leg);
            if measured.x_m.is_finite() && measured.y_m.is_finite() {
                foot.x_m = measured.x_m;
                foot.y_m = measured.y_m;
            }
        }
    }

    /// One tick of the move under way; `Some` when it ends.
    fn advance(
        &mut self,
        config: &CrawlConfig,
        geometry: &LegGeometry,
        limits: &JointLimits,
        measured_rad: &Joints<f32>,
        effort_nm: &Joints<f32>,
    ) -> Option<Outcome> {
        self.elapsed = self.elapsed.saturating_add(1);
        match self.running {
            Running::Idle => None,
            Running::Unload {
                leg,
                from,
                direction: (dx, dy),
                max_m,
            } => {
                // A leg whose load cannot be told adds nothing to the total: the share of the
                // foot to free only comes out larger, and the sway goes on.
                let loads = foot_loads_n(geometry, measured_rad, effort_nm);
                let total: f32 = Leg::ALL.into_iter().filter_map(|l| loads.get(l)).sum();
                let unloaded = loads
                    .get(leg)
                    .is_some_and(|load| total > 0.0 && load <= config.unloaded_share * total);
                let moved_m = self.swayed_m(config, max_m);
                self.body.centre.x_m = from.centre.x_m + dx * moved_m;
                self.body.centre.y_m = from.centre.y_m + dy * moved_m;
                let outcome = if unloaded {
                    Outcome::Freed { leg }
                } else if moved_m >= max_m {
                    Outcome::StillLoaded { leg }
                } else {
                    return None;
                };
                self.running = Running::Idle;
                Some(outcome)
            }
            Running::Body { from, to, ticks } => {
                let share = self.elapsed as f32 / ticks as f32;
                self.body = from.toward(&to, smooth(share));
                (self.elapsed >= ticks).then(|| {
                    self.running = Running::Idle;
                    Outcome::Moved
                })
            }
            Running::Swing { leg, .. } => {
                let measured = config.geometry.foot_of(
                    geometry,
                    &self.body,
                    leg,
                    &LegJoints::from_array(*measured_rad.leg(leg)),
                );
                let target = self.foot_target(config, leg);
                let reachable = config
                    .geometry
                    .solve(geometry, limits, &self.body, leg, &target)
                    .is_ok();
                let [_, _, knee_nm, _] = *effort_nm.leg(leg);
                self.swing_tick(config, measured, knee_nm, reachable)
            }
        }
    }

    /// One tick of a swing: the foot where the encoders put it, its knee's torque, and
    /// whether the legs reach its present target.
    fn swing_tick(
        &mut self,
        config: &CrawlConfig,
        measured: Point,
        knee_nm: f32,
        reachable: bool,
    ) -> Option<Outcome> {
        let Running::Swing {
            leg,
            from,
            to,
            top_z_m,
            stage,
            stage_ticks,
        } = self.running
        else {
            return None;
        };
        let target = swing_point(config, self.rate, &from, &to, top_z_m, stage, stage_ticks);
        let ticks = stage_ticks.saturating_add(1);
        let lift_ticks = self.rate.ticks_from_ms(config.lift_ms).max(1);
        let carry_ticks = self.rate.ticks_from_ms(config.carry_ms).max(1);
        let sign = if to.x_m >= from.x_m { 1.0 } else { -1.0 };
        let (stage, ticks, outcome) = match stage {
            // Out of the legs' reach: the ground is not there, or the way over is not.
            SwingStage::Lower if !reachable => {
                let last = swing_point(
                    config,
                    self.rate,
                    &from,
                    &to,
                    top_z_m,
                    stage,
                    stage_ticks.saturating_sub(1),
                );
                return self.end_swing(leg, last, Outcome::NoGround { leg });
            }
            SwingStage::Lift | SwingStage::Carry if !reachable => {
                (retreat(target, RetreatCause::OutOfReach), 0, None)
            }
            SwingStage::Lift if ticks >= lift_ticks => (SwingStage::Carry, 0, None),
            SwingStage::Carry if sign * (target.x_m - measured.x_m) > config.blocked_lag_m => {
                (retreat(target, RetreatCause::Riser), 0, None)
            }
            SwingStage::Carry if ticks >= carry_ticks => (SwingStage::Lower, 0, None),
            SwingStage::Lower
                if measured.z_m - target.z_m > config.touchdown_lag_m
                    || knee_nm > config.touchdown_knee_nm =>
            {
                let landed = Point {
                    z_m: measured.z_m - config.preload_m,
                    ..target
                };
                *self.feet.get_mut(leg) = landed;
                self.running = Running::Idle;
                return Some(Outcome::Landed {
                    leg,
                    z_m: measured.z_m,
                });
            }
            SwingStage::Lower if target.z_m <= from.z_m.min(to.z_m) - config.search_below_m => {
                return self.end_swing(leg, target, Outcome::NoGround { leg });
            }
            SwingStage::Retreat { cause, .. } if ticks >= lift_ticks => {
                let outcome = match cause {
                    RetreatCause::Riser => Outcome::Blocked { leg },
                    RetreatCause::OutOfReach => Outcome::OutOfReach { leg },
                };
                return self.end_swing(leg, from, outcome);
            }
            other => (other, ticks, None),
        };
        if let Running::Swing {
            stage: s,
            stage_ticks: t,
            ..
        } = &mut self.running
        {
            *s = stage;
            *t = ticks;
        }
        outcome
    }

    /// Ends a swing that found no foothold, the foot commanded at `at` from now on.
    fn end_swing(&mut self, leg: Leg, at: Point, outcome: Outcome) -> Option<Outcome> {
        *self.feet.get_mut(leg) = at;
        self.running = Running::Idle;
        Some(outcome)
    }
}

/// The retreat of a swing that gave up with the foot sent to `at`.
fn retreat(at: Point, cause: RetreatCause) -> SwingStage {
    SwingStage::Retreat { at, cause }
}

#[cfg(test)]
mod tests;
