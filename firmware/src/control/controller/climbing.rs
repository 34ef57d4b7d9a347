//! The climb of a step behind ([`crate::legs::climb`]): started where the autonomous mode's
//! drive stalls against a riser (`Event::StepStall`), the feet placed by their drives' loads,
//! then a fold onto the wheels over the plateau and on in the autonomous mode (or balancing,
//! after a stop).

use protocol::{Joints, Leg};

use super::Controller;
use crate::control::fsm::{Event, State, WheelMotion};
use crate::legs::climb::{foot_of, solve, Climb, ClimbEnd, ClimbInput, Phase};
use crate::legs::crawl::foot_loads_n;
use crate::legs::crawl::frame::PerLeg;
use crate::legs::kinematics::{leg_fk, LegJoints};
use crate::time::Tick;

use super::riding::Riding;
use crate::control::terrain::rise::RiseWatch;

/// What the autonomous mode keeps of its climbs and of the ground it rides.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(super) struct Autonomy {
    /// The climb under way (`State::Climbing(_)`; `None` otherwise).
    pub(super) climb: Option<Climb>,
    /// Whether the running fold follows a climb that set the robot on its wheels.
    pub(super) climbed: bool,
    /// Whether a climb has set the robot on top of something and it has stayed on its wheels
    /// since: it then carries its front legs clear of the drop it will meet
    /// ([`crate::legs::levelling::FoldFamily::front_clear`]). Not before: started from that
    /// pose, the climb of a 9–11 cm step it cannot take put 26 of 50 robots down on their
    /// torsos instead of 6.
    pub(super) on_top: bool,
    /// Whether the autonomous mode gave up a climb: reported until the operator's next
    /// request.
    pub(super) step_refused: bool,
    /// Whether the autonomous mode stopped for a silent rangefinder: reported until the
    /// operator's next request.
    pub(super) range_lost: bool,
    /// The legs' pose for the ground behind (see [`Riding`]).
    pub(super) riding: Riding,
    /// What a backward trot sees behind (see [`RiseWatch`]).
    pub(super) behind: RiseWatch,
}

impl Controller {
    /// A stall on the wheels at `now`: in the autonomous mode with a climb configured and the
    /// legs in the fold the climb starts from, the climb starts (`true`); otherwise the caller
    /// faults (a manual drive into a step stops). From the riding pose
    /// ([`crate::legs::levelling::FoldFamily::ride_front`]) the climb's first move put the
    /// front feet down behind their hips, and no robot of 50 climbed a 6 cm step: a riser
    /// met riding is one the rangefinder missed, and the robot stops.
    #[inline(never)] // Its frame stays off the control step's deepest path (PIL stack budget).
    pub(super) fn climb_on_stall(&mut self, now: Tick) -> bool {
        if self.config.climb.is_none() || self.auto.riding.clear() {
            return false;
        }
        self.apply(Event::StepStall);
        if !matches!(self.state, State::Climbing(_)) {
            return false;
        }
        let measured =
            PerLeg::from_fn(|leg| LegJoints::from_array(*self.sensors.joint_position_rad.leg(leg)));
        self.auto.climb = Some(Climb::new(now, &self.config.geometry, &measured));
        true
    }

    /// What a transition into `next` keeps of a climb: on the plateau the front legs stay
    /// clear whatever the wheels are asked next (a STOP there does not swing them); off the
    /// wheels the climb is over.
    pub(super) fn climb_flags_into(&mut self, next: State) {
        self.auto.riding.enter(next);
        self.auto.on_top &= matches!(
            next,
            State::Wheels(_) | State::Folding(_) | State::Climbing(_)
        );
    }

    /// Whether the legs ride clear of a slope the rangefinder saw (else, on the wheels, in the
    /// fold or with the front legs clear after a climb).
    pub fn rides_clear(&self) -> bool {
        self.auto.riding.clear()
    }

    /// The climb under way, if any.
    pub fn climb(&self) -> Option<&Climb> {
        self.auto.climb.as_ref()
    }

    /// This tick of the climb: the legs' goal; at its end the fold.
    #[inline(never)] // As `climb_on_stall`.
    pub(super) fn climb_step(&mut self, now: Tick) {
        let (Some(mut climb), Some(config)) = (self.auto.climb, self.config.climb) else {
            self.apply(Event::PoseReached);
            return;
        };
        let geometry = &self.config.geometry;
        let depth_of = |joints: &Joints<f32>, leg: Leg| {
            foot_of(geometry, &LegJoints::from_array(*joints.leg(leg))).depth_m
        };
        let input = ClimbInput {
            loads_n: foot_loads_n(
                geometry,
                &self.sensors.joint_position_rad,
                &self.sensors.joint_effort_nm,
            ),
            lag_m: PerLeg::from_fn(|leg| {
                depth_of(&self.legs_rad, leg) - depth_of(&self.sensors.joint_position_rad, leg)
            }),
            pitch_rad: self.sensors.attitude.pitch_rad,
        };
        if self.state == State::Climbing(WheelMotion::Balance) {
            // Stopped: back to the fold if the legs have not lifted the robot yet.
            climb.stop(now);
        }
        climb.tick(&config, self.config.rate, now, &input);
        self.auto.climb = Some(climb);
        match climb.phase() {
            Phase::Ended(end) => {
                self.auto.climb = None;
                let refused = !matches!(end, ClimbEnd::Over | ClimbEnd::Stopped);
                if refused {
                    // Given up: fold and balance (driving on would meet the same riser).
                    self.apply(Event::StepRefused);
                }
                self.apply(Event::PoseReached);
                // After the transition, which clears both for a new fold.
                self.auto.climbed = end == ClimbEnd::Over;
                self.auto.on_top |= self.auto.climbed;
                self.auto.step_refused = refused;
            }
            _ => {
                self.climb_pose(&climb);
                self.smooth(self.config.leg_rate_per_s);
            }
        }
    }

    /// The goal from the climb's foot targets.
    fn climb_pose(&mut self, climb: &Climb) {
        let targets = climb.targets();
        for leg in Leg::ALL {
            let goal = LegJoints::from_array(*self.goal_rad.leg(leg));
            let pitch_rad = leg_fk(&self.config.geometry, &goal).pitch_rad;
            match solve(
                &self.config.geometry,
                &self.config.limits,
                targets.get(leg),
                pitch_rad,
            ) {
                Some(joints) => *self.goal_rad.leg_mut(leg) = joints.to_array(),
                None => self.ik_failures = self.ik_failures.saturating_add(1),
            }
        }
    }
}
