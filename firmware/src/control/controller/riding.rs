//! How the autonomous mode carries its legs on the wheels, chosen by the ground the
//! rangefinder sees behind ([`crate::control::terrain`]): in the fold, which the climb of a
//! step starts from, or clear of a slope
//! ([`crate::legs::levelling::FoldFamily::ride_front`], `ride_back`).
//!
//! Backing up a 10° ramp the robot leans 12° beyond its balance point, and the fold's back
//! shanks, 0.45 m behind the axle, met the slope 0.6 s after the wheels; coming down, the
//! front shanks met it. Riding clear they do not, but the climb of a step does not start from
//! there (its first move put the front feet down behind their hips; no robot of 50 climbed).
//! So the pose follows what lies behind: a slope up seen there sets the legs clear, a riser
//! seen from level ground sets them back in the fold. Each change is made standing: the robot
//! brakes, the legs move once it rolls slower than [`REPOSE_SLOW_M_S`], and it drives on once
//! they are there and it has stood still. The rangefinder decides a 10° ramp 0.3–0.7 m before
//! the wheels reach its foot, and braking and moving the legs' mass roll the robot on
//! 0.1–0.2 m (0.5 m on the heaviest-legged robots).
//!
//! Riding clear in the autonomous mode ([`Controller::slope_rules`]), the stall watch waits
//! longer for a robot standing still against its reference
//! ([`crate::wheels::runaway::Runaway::set_patient`]: one starting up a slope leans into it
//! for a second or more first), a stall that leaves the robot rolling is the foot of a
//! slope, not a riser (`wheel_law`), and the balance law forgives a position error it is
//! making up ([`Riding::forgive_s`]); riding clear in any wheeled mode, it keeps its trim
//! within a band ([`Riding::trim_band_rad`]).

use super::Controller;
use crate::control::fsm::{Event, State, WheelMotion};
use crate::control::terrain::{Feature, Ranging, TerrainWatch};
use crate::time::{Tick, TickRate};

/// The robot is still for a change of pose below this ground speed, m/s, …
const REPOSE_STILL_M_S: f32 = 0.03;

/// … for this long, ms.
const REPOSE_STILL_MS: u32 = 300;

/// The longest a change of pose holds the robot, ms.
const REPOSE_MAX_MS: u32 = 3_000;

/// How far from the learned trim the balance point may move for the trim to follow it riding
/// clear, rad: a 10° slope leans the robot 12° beyond it, while legs that swing in at the
/// fold's rate move it less than this at a time (see
/// [`crate::wheels::balance::Balance::set_trim_band`]).
const TRIM_BAND_RAD: f32 = 4.0 * core::f32::consts::PI / 180.0;

/// How long the legs must have ridden still before the trim band applies, ms: the trim must
/// first find the balance point the riding legs give (a heavy-legged robot's moved 9°).
const TRIM_SETTLE_MS: u32 = 1_500;

/// How fast a position error the robot is making up is forgiven riding clear, s (see
/// [`crate::wheels::balance::Balance::set_forgiving`]).
const FORGIVE_S: f32 = 0.2;

/// The watch reads the ground only while the body pitches slower than this, rad/s, …
const STEADY_RAD_S: f32 = 0.3;

/// … and this long after a drop has ended, ms.
const LANDED_MS: u32 = 1_000;

/// A change of pose waits for the robot to roll slower than this before the legs move, m/s:
/// moving them while it brakes from its speed pitched a heavy-legged robot 19° and rolled it
/// 0.56 m.
const REPOSE_SLOW_M_S: f32 = 0.1;

/// The autonomous mode stops once no ranging has arrived for this long, ms: ten of the part's
/// 50 Hz rangings (a lossy bus drops one now and then; a silent part drops them all).
const RANGE_TIMEOUT_MS: u32 = 200;

/// … and once it has backed this far on level ground with no return from the part, m: the
/// part sends its frames but sees nothing (a covered window, a dead emitter). Level ground is
/// 0.8 m along the beam; only a slope going down, where the robot leans off its trim, or the
/// crest before one, where the beam runs past its far foot for up to 0.8 m, gives none.
const BLIND_M: f32 = 1.5;

/// A change of pose under way.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Repose {
    /// When it began.
    since: Tick,
    /// The pose it changes to (clear or not), set once the robot has slowed.
    to_clear: bool,
    /// Since when the robot has stood still with its legs there (`None`: not yet).
    still_since: Option<Tick>,
}

/// The autonomous mode's riding pose and what decides it.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(super) struct Riding {
    /// Whether the legs ride clear of a slope (else in the fold).
    clear: bool,
    repose: Option<Repose>,
    watch: TerrainWatch,
    /// How far the robot has backed in the mode, m (the watch's path).
    backed_m: f32,
    /// Since when the legs have ridden still and clear (`None`: they move, or ride folded).
    settled_since: Option<Tick>,
    /// Ticks in the mode since the last ranging.
    silent_ticks: u32,
    /// Whether the last ranging had no return.
    no_return: bool,
    /// How far the robot has backed on level ground since a ranging last had a return, m.
    blind_m: f32,
}

impl Riding {
    /// Whether the legs ride clear of a slope.
    pub(super) fn clear(&self) -> bool {
        self.clear
    }

    /// Whether a change of pose holds the robot.
    pub(super) fn reposing(&self) -> bool {
        self.repose.is_some()
    }

    /// What a transition into `next` keeps: the pose while the robot stays on its wheels (a
    /// STOP on a ramp does not swing the legs into it), the watch and a change of pose only
    /// in the autonomous mode.
    pub(super) fn enter(&mut self, next: State) {
        self.silent_ticks = 0;
        if !matches!(next, State::Wheels(_)) {
            self.clear = false;
        }
        if next != State::Wheels(WheelMotion::Auto) {
            self.repose = None;
            self.watch.reset();
            self.backed_m = 0.0;
            self.blind_m = 0.0;
        }
    }

    /// The band the trim follows the balance point within (`None`: any): riding clear, in any
    /// wheeled mode (a robot stopped on a slope leans as it did rolling up it, and a trim that
    /// took that lean would run it down), once the legs have settled for [`TRIM_SETTLE_MS`]
    /// (`settled`: at their goal now).
    pub(super) fn trim_band_rad(
        &mut self,
        rate: TickRate,
        now: Tick,
        settled: bool,
    ) -> Option<f32> {
        self.settled_since = if self.clear && settled {
            self.settled_since.or(Some(now))
        } else {
            None
        };
        let since = self.settled_since?;
        (now.since(since) >= rate.ticks_from_ms(TRIM_SETTLE_MS)).then_some(TRIM_BAND_RAD)
    }

    /// How fast a position error being made up is forgiven, s (`None`: it is made up): riding
    /// clear in the autonomous mode (`rules`), but not while the legs move there (the robot
    /// holds its place meanwhile: the riding legs' mass moves back, and a heavy-legged robot
    /// rolled 0.7 m to the foot of the slope without it).
    pub(super) fn forgive_s(&self, rules: bool) -> Option<f32> {
        (rules && self.repose.is_none()).then_some(FORGIVE_S)
    }
}

impl Controller {
    /// Whether the slope's driving rules apply (the patient stall watch, rolling on at a
    /// slope's foot, forgiving a position error): riding clear in the autonomous mode. Legs
    /// left clear under a manual drive or a stop keep their pose and the trim's band, but the
    /// robot is driven as anywhere else.
    pub(super) fn slope_rules(&self) -> bool {
        self.auto.riding.clear() && self.state == State::Wheels(WheelMotion::Auto)
    }

    /// This tick of the autonomous mode's watch on the ground behind, with the ranging
    /// received this tick (`None`: none; the caller consumes it in every state): a slope or a
    /// step decided starts a change of pose if the legs ride the other way; a change under way
    /// ends once the legs are there and the robot has stood still for [`REPOSE_STILL_MS`], or
    /// after [`REPOSE_MAX_MS`]. A rangefinder that has gone quiet ([`Self::range_lost_now`])
    /// stops the mode (`RANGE_TIMEOUT`).
    #[inline(never)] // Its frame stays off the control step's deepest path (PIL stack budget).
    pub(super) fn ride_step(&mut self, now: Tick, dt_s: f32, ranging: Option<Option<f32>>) {
        let speed_m_s = self.ground_speed_m_s();
        self.auto.riding.backed_m -= speed_m_s * dt_s;
        if let Some(distance_m) = ranging {
            let riding = &mut self.auto.riding;
            riding.silent_ticks = 0;
            riding.no_return = distance_m.is_none();
            if distance_m.is_some() {
                riding.blind_m = 0.0;
            }
            self.watch_ranging(now, distance_m);
        } else {
            self.auto.riding.silent_ticks = self.auto.riding.silent_ticks.saturating_add(1);
        }
        if self.auto.riding.no_return && self.leans_at_trim() {
            self.auto.riding.blind_m += speed_m_s.abs() * dt_s;
        }
        if self.range_lost_now() {
            self.apply(Event::RangeLost);
            self.auto.range_lost = true;
            return;
        }
        self.repose_step(now, speed_m_s);
    }

    /// Whether the rangefinder has gone quiet: no ranging for [`RANGE_TIMEOUT_MS`], or none
    /// with a return over [`BLIND_M`] of level ground.
    fn range_lost_now(&self) -> bool {
        let riding = &self.auto.riding;
        riding.silent_ticks >= self.config.rate.ticks_from_ms(RANGE_TIMEOUT_MS)
            || riding.blind_m >= BLIND_M
    }

    /// Whether the body leans within [`TRIM_BAND_RAD`] of its trim: on level ground.
    fn leans_at_trim(&self) -> bool {
        let lean_rad = self.sensors.attitude.pitch_rad - self.balance.pitch_trim_rad();
        lean_rad.abs() < TRIM_BAND_RAD
    }

    /// Reads one ranging into the terrain watch, and starts a change of pose for what it
    /// decides. Pitching fast (a drop's landing, a start), the estimated pitch lags the body's
    /// by more than the watch's heights allow: it learns anew once the body is steady.
    #[inline(never)] // Once in five ticks: its frame stays off the others.
    fn watch_ranging(&mut self, now: Tick, distance_m: Option<f32>) {
        let [_, pitch_rate_rad_s, _] = self.sensors.angular_rate_rad_s;
        let steady = pitch_rate_rad_s.abs() < STEADY_RAD_S
            && !self
                .traction
                .fell_within(self.config.rate.ticks_from_ms(LANDED_MS));
        // Back into the fold only on level ground: on a slope the robot leans off its trim,
        // and stopping there to fold meets the slope with the fold's shanks.
        let level = self.leans_at_trim();
        let riding = &mut self.auto.riding;
        // The legs that move in a change of pose pitch the body as they go: what the beam
        // sees meanwhile is no ground's.
        if !steady || riding.repose.is_some() {
            riding.watch.unsteady();
            return;
        }
        let ranging = Ranging {
            distance_m,
            pitch_rad: self.sensors.attitude.pitch_rad,
            backed_m: riding.backed_m,
        };
        // Up only: down a slope the legs already ride clear (the robot came up one), and off
        // an edge the spot jumps along the beam by a run that the body's pitch can make look
        // like a slope's; an edge needs no fold (the legs ride clear of it).
        let clear = match riding.watch.update(&self.config.terrain, &ranging) {
            Some(Feature::Slope { rise_m }) if rise_m > 0.0 => Some(true),
            Some(Feature::Step { rise_m }) if rise_m > 0.0 && level => Some(false),
            _ => None,
        };
        let changing = riding.repose.map_or(riding.clear, |r| r.to_clear);
        if let Some(to_clear) = clear.filter(|&clear| clear != changing) {
            riding.repose = Some(Repose {
                since: now,
                to_clear,
                still_since: None,
            });
            self.runaway.reset();
        }
    }

    /// This tick of a change of pose, the robot rolling at `speed_m_s`: the legs move once it
    /// has slowed; a robot that has not slowed within [`REPOSE_MAX_MS`] (held on a slope, say)
    /// keeps its pose and drives on, its stall watch still over it; legs that moved but did
    /// not settle are let go after [`REPOSE_MAX_MS`] from their move.
    fn repose_step(&mut self, now: Tick, speed_m_s: f32) {
        let Some(mut repose) = self.auto.riding.repose else {
            return;
        };
        let rate = self.config.rate;
        let max_ticks = rate.ticks_from_ms(REPOSE_MAX_MS);
        if self.auto.riding.clear != repose.to_clear {
            if speed_m_s.abs() < REPOSE_SLOW_M_S {
                self.auto.riding.clear = repose.to_clear;
                repose.since = now;
            } else if now.since(repose.since) >= max_ticks {
                self.auto.riding.repose = None;
                self.runaway.reset();
                return;
            }
        }
        let moved = self.auto.riding.clear == repose.to_clear;
        let there = self.legs_at_goal();
        repose.still_since = if moved && there && speed_m_s.abs() < REPOSE_STILL_M_S {
            repose.still_since.or(Some(now))
        } else {
            None
        };
        let stood = repose
            .still_since
            .is_some_and(|at| now.since(at) >= rate.ticks_from_ms(REPOSE_STILL_MS));
        if stood || (moved && now.since(repose.since) >= max_ticks) {
            self.auto.riding.repose = None;
            self.runaway.reset();
        } else {
            self.auto.riding.repose = Some(repose);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const RATE: TickRate = TickRate::SIM_250_HZ;

    fn riding_clear() -> Riding {
        Riding {
            clear: true,
            ..Riding::default()
        }
    }

    #[test]
    fn the_trim_band_holds_only_once_clear_legs_have_settled_long_enough() {
        let mut folded = Riding::default();
        assert_eq!(folded.trim_band_rad(RATE, Tick(0), true), None);
        let mut riding = riding_clear();
        let settle = RATE.ticks_from_ms(TRIM_SETTLE_MS);
        assert_eq!(riding.trim_band_rad(RATE, Tick(10), true), None);
        assert_eq!(riding.trim_band_rad(RATE, Tick(9 + settle), true), None);
        let band = riding.trim_band_rad(RATE, Tick(10 + settle), true);
        assert_eq!(band, Some(TRIM_BAND_RAD));
        // Legs that move again start the wait afresh.
        let later = 20 + settle;
        assert_eq!(riding.trim_band_rad(RATE, Tick(later), false), None);
        assert_eq!(riding.trim_band_rad(RATE, Tick(later + 1), true), None);
    }

    #[test]
    fn a_position_error_is_forgiven_only_under_the_slope_rules_and_not_while_reposing() {
        let mut riding = riding_clear();
        assert_eq!(riding.forgive_s(false), None);
        assert_eq!(riding.forgive_s(true), Some(FORGIVE_S));
        riding.repose = Some(Repose {
            since: Tick(0),
            to_clear: false,
            still_since: None,
        });
        assert_eq!(riding.forgive_s(true), None);
    }

    #[test]
    fn leaving_the_wheels_folds_the_pose_and_leaving_the_mode_drops_its_watch() {
        let mut riding = riding_clear();
        riding.backed_m = 2.0;
        riding.enter(State::Wheels(WheelMotion::Balance));
        assert!(riding.clear(), "a stop on the wheels keeps the legs clear");
        assert_eq!(riding.backed_m, 0.0);
        riding.enter(State::Legs(crate::control::fsm::LegMotion::Stand));
        assert!(!riding.clear());
    }
}
