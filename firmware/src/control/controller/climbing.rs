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

impl Controller {
    /// A stall on the wheels at `now`: in the autonomous mode with a climb configured, the
    /// climb starts (`true`); otherwise the caller faults (a manual drive into a step stops).
    #[inline(never)] // Its frame stays off the control step's deepest path (PIL stack budget).
    pub(super) fn climb_on_stall(&mut self, now: Tick) -> bool {
        if self.config.climb.is_none() {
            return false;
        }
        self.apply(Event::StepStall);
        if !matches!(self.state, State::Climbing(_)) {
            return false;
        }
        let measured =
            PerLeg::from_fn(|leg| LegJoints::from_array(*self.sensors.joint_position_rad.leg(leg)));
        self.climb = Some(Climb::new(now, &self.config.geometry, &measured));
        true
    }

    /// What a transition into `next` keeps of a climb: on the plateau the front legs stay
    /// clear whatever the wheels are asked next (a STOP there does not swing them); off the
    /// wheels the climb is over.
    pub(super) fn climb_flags_into(&mut self, next: State) {
        self.on_top &= matches!(
            next,
            State::Wheels(_) | State::Folding(_) | State::Climbing(_)
        );
    }

    /// The climb under way, if any.
    pub fn climb(&self) -> Option<&Climb> {
        self.climb.as_ref()
    }

    /// This tick of the climb: the legs' goal; at its end the fold.
    #[inline(never)] // As `climb_on_stall`.
    pub(super) fn climb_step(&mut self, now: Tick) {
        let (Some(mut climb), Some(config)) = (self.climb, self.config.climb) else {
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
        self.climb = Some(climb);
        match climb.phase() {
            Phase::Ended(end) => {
                self.climb = None;
                let refused = !matches!(end, ClimbEnd::Over | ClimbEnd::Stopped);
                if refused {
                    // Given up: fold and balance (driving on would meet the same riser).
                    self.apply(Event::StepRefused);
                }
                self.apply(Event::PoseReached);
                // After the transition, which clears both for a new fold.
                self.climbed = end == ClimbEnd::Over;
                self.on_top |= self.climbed;
                self.step_refused = refused;
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
