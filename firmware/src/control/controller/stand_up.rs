//! The stand-up's roll ahead. Unfolded from the wheels, the feet land behind their hips
//! (within the joint ranges no foot comes closer than 7 cm behind its hip at the depth of the
//! ground on the wheels) and sweep forward on the ground under the rising robot: they push it
//! back. So once the robot has settled on its wheels for a stand-up, and before its legs leave
//! the fold, the balance law rolls it ahead by about as much, and the stand-up ends where it
//! began. Once per stand-up: a change between stand-ups (`L` asked during `stand`) does not
//! roll it again; and not at all on top of a step the robot has climbed, whose edge lies ahead.

use super::folding::half_sine_m_s;
use super::Controller;
use crate::control::fsm::State;
use crate::legs::crawl::legs_load_n;
use crate::time::Tick;
use crate::wheels::lqr::BalanceModel;

/// How far a stand-up from the wheels rolls the robot ahead first, m: on the robot as drawn
/// the unfold pushed it 15 cm back.
const ROLL_AHEAD_M: f32 = 0.15;

/// Over how long, ms: a half-sine of speed (a lean of 3° at its steepest).
const ROLL_AHEAD_MS: u32 = 1_500;

/// A roll ahead whose wheels rolled less than this share of [`ROLL_AHEAD_M`] by the time it is
/// up was blocked (by something the robot touches ahead): the law forgets the distance it did
/// not make, so that the robot settles and stands up where it is instead of pressing on. Read
/// from the wheels, not from the law's position error, which also holds what the law held
/// before the roll (see [`crate::wheels::balance::Balance::set_counting`]), and kept.
const BLOCKED_SHARE: f32 = 0.5;

/// Below this share of the robot's weight on its wheels (what the feet's loads leave them) the
/// stand-up's hold lets them turn (see [`Controller::stand_hold_nm_per_rad_s`]); chosen over
/// the campaign's stand-ups (docs/firmware.md, "Folding in place").
const HOLD_MIN_SHARE: f32 = 0.2;

/// The robot's weight as modelled, N: what the feet do not carry of it the wheels do.
const WEIGHT_N: f32 = (BalanceModel::ROBOT.body_mass_kg + BalanceModel::ROBOT.wheel_mass_kg) * 9.81;

/// Where a stand-up's roll ahead is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum RollAhead {
    /// To come, once the balance law runs with the robot settled and its legs stowed.
    Due,
    /// Begun at tick `at`, and rolled `rolled_m` over ground since, m.
    Since { at: Tick, rolled_m: f32 },
    /// Made, or not to be made.
    Done,
}

impl Controller {
    /// What a transition into `next` keeps of the roll ahead: within a stand-up, all; into a
    /// stand-up on top of a climbed step, none to make; else one to make.
    pub(super) fn stand_roll_into(&mut self, next: State) {
        let within = matches!((self.state, next), (State::Standing(_), State::Standing(_)));
        if !within {
            self.feet_still_s = 0.0;
            let on_top = self.auto.on_top && matches!(next, State::Standing(_));
            self.stand_roll = if on_top {
                RollAhead::Done
            } else {
                RollAhead::Due
            };
        }
    }

    /// One tick of the balance law in a stand-up: the roll ahead begins once the robot has
    /// settled, counts the ground its wheels roll, and at its end a blocked roll's remaining
    /// distance is forgotten.
    pub(super) fn roll_ahead_tick(&mut self, now: Tick, dt_s: f32) {
        let due = self.stand_roll == RollAhead::Due;
        let settled = due && !self.rolling() && !self.leaning_or_stowing();
        match self.stand_roll {
            RollAhead::Due if settled => {
                self.stand_roll = RollAhead::Since {
                    at: now,
                    rolled_m: 0.0,
                }
            }
            RollAhead::Since { at, rolled_m } if !self.rolls_ahead_since(at, now) => {
                // A roll whose distance cannot be read counts as blocked, as having rolled none.
                let rolled_m = if rolled_m.is_finite() { rolled_m } else { 0.0 };
                if rolled_m < BLOCKED_SHARE * ROLL_AHEAD_M {
                    self.balance.forgive_m(ROLL_AHEAD_M - rolled_m);
                }
                self.stand_roll = RollAhead::Done;
            }
            RollAhead::Since { at, rolled_m } => {
                let rolled_m = rolled_m + self.ground_speed_m_s() * dt_s;
                self.stand_roll = RollAhead::Since { at, rolled_m };
            }
            _ => {}
        }
    }

    /// The stand-up's speed reference, m/s: the roll ahead while it runs, else none.
    pub(super) fn roll_ahead_m_s(&self, now: Tick) -> f32 {
        let RollAhead::Since { at, .. } = self.stand_roll else {
            return 0.0;
        };
        let t_s = now.since(at) as f32 * self.config.rate.period_s();
        half_sine_m_s(ROLL_AHEAD_M, ROLL_AHEAD_MS, t_s)
    }

    /// Whether the stand-up still has its roll ahead to make or is making it at `now`.
    pub(super) fn rolling_ahead(&self, now: Tick) -> bool {
        match self.stand_roll {
            RollAhead::Due => true,
            RollAhead::Since { at, .. } => self.rolls_ahead_since(at, now),
            RollAhead::Done => false,
        }
    }

    fn rolls_ahead_since(&self, since: Tick, now: Tick) -> bool {
        now.since(since) < self.config.rate.ticks_from_ms(ROLL_AHEAD_MS)
    }

    /// Counts how long a stand-up whose legs have begun to unfold (its roll ahead made) has sat
    /// still on its wheels and feet (`on_feet`, pitching slower than
    /// [`super::carrier::STAND_STEADY_RAD_S`]): see [`Controller::leaning_or_stowing`]. Called
    /// on the ticks the wheels are on the ground in a fold or a stand-up: a tick of those not
    /// still on wheels and feet starts the count afresh, and so does every new stand-up
    /// (`stand_roll_into`). Once the legs carry the robot alone the count stays as it was; it
    /// then no longer matters (the lean rule is for the wheels).
    pub(super) fn count_still_on_feet(&mut self, on_feet: bool) {
        let [_, pitch_rate_rad_s, _] = self.sensors.angular_rate_rad_s;
        let still = on_feet
            && matches!(self.state, State::Standing(_))
            && self.stand_roll == RollAhead::Done
            && pitch_rate_rad_s.abs() < super::carrier::STAND_STEADY_RAD_S;
        self.feet_still_s = if still {
            self.feet_still_s + self.config.rate.period_s()
        } else {
            0.0
        };
    }

    /// The damping the wheels hold still with while a stand-up's legs unfold, N·m per rad/s:
    /// the stop's ([`crate::control::stop::StopConfig::wheel_hold_nm_per_rad_s`]) while the
    /// wheels carry at least [`HOLD_MIN_SHARE`] of the weight, none once the feet's loads (from
    /// the legs' drive torques) leave them less. A wheel the feet have unloaded turns with
    /// little more than its own inertia (0.018 kg·m²), and damping it through the loop's delay
    /// is a tick `ω ← ω − g ω₋ₙ`, `g = K·dt/J`, stable only for `g < 2 sin(π / (2(2n + 1)))`
    /// (`K` ≤ 1.3 at the campaign's five ticks): the stop's 10 swung the wheels between their
    /// torque limits, shook the torso and read as rolling, and the legs waited on it for good.
    /// Unloaded, the wheels hold nothing anyway: their grip is the load they carry. Loads that
    /// cannot be read keep the hold.
    pub(super) fn stand_hold_nm_per_rad_s(&self) -> f32 {
        let full = self.config.stop.wheel_hold_nm_per_rad_s;
        let sensors = &self.sensors;
        let legs_n = legs_load_n(
            &self.config.geometry,
            &sensors.joint_position_rad,
            &sensors.joint_effort_nm,
        );
        let share = 1.0 - legs_n / WEIGHT_N;
        if share.is_finite() && share < HOLD_MIN_SHARE {
            0.0
        } else {
            full
        }
    }
}
