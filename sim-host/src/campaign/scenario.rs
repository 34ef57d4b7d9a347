//! The acceptance scenarios a campaign runs on each drawn plant: what the operator commands
//! when, which stretches of the run are judged as segments, and how long a run lasts. The
//! plans and durations are those of the acceptance tests (`tests/closed_loop.rs`,
//! `tests/estop_ss1.rs`, `scenarios/acceptance/*.toml`), so that a nominal plant meets the
//! same figures here as there.

use std::fmt;
use std::str::FromStr;

use protocol::TeleopMode;
use serde::{Deserialize, Serialize};
use teleop_core::scripted::PlanStep;

/// One acceptance scenario.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub enum Scenario {
    /// Fold, settle 4 s, wheels forward 4 s: ≥ 1.4 m, tilt ≤ 10°, only the wheels down.
    W,
    /// The same backward.
    S,
    /// Fold, settle 4 s, turn on the spot 2 s: ≥ 180°, centre within 0.10 m.
    A,
    /// Stand 2 s, trot forward 8 s: ≥ 0.4 m, roll and pitch ≤ 15°, a diagonal gait.
    L,
    /// The same backward.
    K,
    /// From standing, fold onto the wheels and balance.
    Fold,
    /// Fold, W at 3 s, X at 6 s: stopped within 1 s, upright.
    XFromW,
    /// Stand, L at 3 s, X at 6 s: stopped within 1 s, upright.
    XFromL,
    /// Fold, W at full speed, an E-stop latched at 6 s: an SS1 stop on the wheels.
    EStop,
    /// Fold, settle, stand up from the wheels: in place (≤ 5 cm), tilt ≤ 8°, standing.
    StandUp,
}

impl Scenario {
    /// Every scenario, in the table's order.
    pub const ALL: [Scenario; 10] = [
        Scenario::W,
        Scenario::S,
        Scenario::A,
        Scenario::L,
        Scenario::K,
        Scenario::Fold,
        Scenario::XFromW,
        Scenario::XFromL,
        Scenario::EStop,
        Scenario::StandUp,
    ];

    /// The name on the command line and in the table.
    pub fn name(self) -> &'static str {
        match self {
            Scenario::W => "W",
            Scenario::S => "S",
            Scenario::A => "A",
            Scenario::L => "L",
            Scenario::K => "K",
            Scenario::Fold => "fold",
            Scenario::XFromW => "X-from-W",
            Scenario::XFromL => "X-from-L",
            Scenario::EStop => "estop-W",
            Scenario::StandUp => "stand-up",
        }
    }

    /// What the operator commands, times from the run's start.
    pub fn plan(self) -> Vec<PlanStep> {
        use TeleopMode::{
            Fold, Stand, Stop, TrotBackward, TrotForward, WheelBackward, WheelForward, WheelRotate,
        };
        let steps: &[(f64, TeleopMode)] = match self {
            Scenario::W => &[(0.0, Fold), (4.0, WheelForward)],
            Scenario::S => &[(0.0, Fold), (4.0, WheelBackward)],
            Scenario::A => &[(0.0, Fold), (4.0, WheelRotate)],
            Scenario::L => &[(0.0, Stand), (2.0, TrotForward)],
            Scenario::K => &[(0.0, Stand), (2.0, TrotBackward)],
            Scenario::Fold => &[(0.0, Fold)],
            Scenario::XFromW => &[(0.0, Fold), (3.0, WheelForward), (6.0, Stop)],
            Scenario::XFromL => &[(0.0, Stand), (3.0, TrotForward), (6.0, Stop)],
            Scenario::EStop => &[(0.0, Fold), (1.5, WheelForward)],
            Scenario::StandUp => &[(0.0, Fold), (STAND_UP_AT_S, Stand)],
        };
        steps
            .iter()
            .map(|&(at_s, mode)| PlanStep::at(at_s, mode))
            .collect()
    }

    /// The judged stretches: start, s, and label. The last runs to the end.
    pub fn segments(self) -> &'static [(f64, &'static str)] {
        match self {
            Scenario::W | Scenario::S => &[(0.0, "fold, settle"), (4.0, "drive")],
            Scenario::A => &[(0.0, "fold, settle"), (4.0, "turn")],
            Scenario::L | Scenario::K => &[(0.0, "stand"), (2.0, "trot")],
            // The fold is judged on its last second: balancing on the wheels alone.
            Scenario::Fold => &[(0.0, "fold"), (4.0, "balance")],
            Scenario::XFromW | Scenario::XFromL => &[(0.0, "start"), (3.0, "move"), (6.0, "X")],
            Scenario::EStop => &[(0.0, "fold"), (1.5, "drive"), (ESTOP_AT_S, "E-stop")],
            Scenario::StandUp => &[(0.0, "fold, settle"), (STAND_UP_AT_S, "stand-up")],
        }
    }

    /// How long a run lasts, s.
    pub fn duration_s(self) -> f64 {
        match self {
            Scenario::W | Scenario::S => 8.0,
            Scenario::A => 6.0,
            Scenario::L | Scenario::K => 10.0,
            Scenario::Fold => 5.0,
            Scenario::XFromW | Scenario::XFromL => 9.0,
            // The SS1 deadline (2 s) and 2.5 s of rest after it, as tests/estop_ss1.rs.
            Scenario::EStop => ESTOP_AT_S + 4.5,
            // The stand-up takes 3.2 s as drawn (settling, the roll ahead, the unfold); 8 s,
            // as the measurement over robots in `tests/transitions.rs` allows.
            Scenario::StandUp => STAND_UP_AT_S + 8.0,
        }
    }

    /// When a tool latches the E-stop, s (only the E-stop scenario).
    pub fn estop_at_s(self) -> Option<f64> {
        (self == Scenario::EStop).then_some(ESTOP_AT_S)
    }
}

/// When the E-stop scenario latches, s: at top speed, 4.5 s into W.
pub const ESTOP_AT_S: f64 = 6.0;

/// When the stand-up scenario asks to stand, s: the fold over and balancing (`fold`'s 4 s).
pub const STAND_UP_AT_S: f64 = 5.0;

impl fmt::Display for Scenario {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A name that is no scenario's.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("`{0}` is no scenario: use one of W S A L K fold X-from-W X-from-L estop-W stand-up")]
pub struct UnknownScenario(pub String);

impl FromStr for Scenario {
    type Err = UnknownScenario;

    /// A scenario by its name, ignoring case.
    fn from_str(text: &str) -> Result<Self, Self::Err> {
        Scenario::ALL
            .into_iter()
            .find(|s| s.name().eq_ignore_ascii_case(text.trim()))
            .ok_or_else(|| UnknownScenario(text.to_owned()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_parse_back_and_plans_fit_their_runs() {
        for s in Scenario::ALL {
            assert_eq!(s.name().to_lowercase().parse::<Scenario>(), Ok(s));
            let last = s.plan().last().map_or(0, |p| p.at_us);
            assert!((last as f64) * 1e-6 < s.duration_s(), "{s}");
            let segments = s.segments();
            assert!(segments.windows(2).all(|w| w[0].0 < w[1].0), "{s}");
            assert!(segments.last().is_some_and(|l| l.0 < s.duration_s()));
        }
        assert!("Q".parse::<Scenario>().is_err());
    }
}
