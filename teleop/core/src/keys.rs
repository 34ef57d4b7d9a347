//! The operator's keys: the report's W/S/A/L/K/X, and what a real robot needs besides.
//!
//! | key            | action                                   |
//! |----------------|------------------------------------------|
//! | `W` `S` `A`    | wheels forward, backward, rotate          |
//! | `L` `K`        | trot forward, backward                   |
//! | `X`            | stop                                     |
//! | `T` / `F`      | stand on the legs / fold onto the wheels |
//! | `↑` `↓`        | body height +1 cm / −1 cm                |
//! | `←` `→`        | steer: yaw rate +0.1 / −0.1 rad/s (turn left / right) while driving or trotting; a mode key straightens |
//! | `]` `[`        | speed scale +10 % / −10 %                |
//! | space          | E-stop (latches)                         |
//! | `R` then `R`   | release a latched E-stop (within 2 s)    |
//! | `Q`, Esc       | quit (the controller stops within 500 ms) |

use protocol::TeleopMode;

/// A key press, as the terminal reports it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Key {
    /// A printable character.
    Char(char),
    /// Arrow up.
    Up,
    /// Arrow down.
    Down,
    /// Arrow left.
    Left,
    /// Arrow right.
    Right,
    /// Escape.
    Esc,
}

/// What a key asks for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Action {
    /// Command a mode.
    Mode(TeleopMode),
    /// Change the body height by this much, m.
    Height(f32),
    /// Change the speed scale by this much, %.
    Speed(f32),
    /// Change the yaw rate that steers the moving keys by this much, rad/s (+ left).
    Steer(f32),
    /// A gamepad's sticks: forward speed and left turn as fractions of the mode's limits
    /// (−1…1; see [`crate::gamepad`]).
    Sticks {
        /// Forward, + ahead.
        forward: f32,
        /// Turn, + left.
        turn: f32,
    },
    /// The input device went away: stop, then fall silent (an operator lost).
    InputLost,
    /// The input device is back.
    InputFound,
    /// Latch the E-stop.
    EStop,
    /// One press of the release sequence.
    Release,
    /// Leave.
    Quit,
}

/// One press of `←` or `→`, rad/s.
pub const STEER_STEP_RAD_S: f32 = 0.1;

/// The report's key for `mode`, if it has one (stand, fold and the autonomous mode have none:
/// `T`, `F` and `H` are this program's; drive and walk follow a gamepad's sticks).
pub const fn mode_key(mode: TeleopMode) -> Option<char> {
    match mode {
        TeleopMode::Stop => Some('X'),
        TeleopMode::WheelForward => Some('W'),
        TeleopMode::WheelBackward => Some('S'),
        TeleopMode::WheelRotate => Some('A'),
        TeleopMode::TrotForward => Some('L'),
        TeleopMode::TrotBackward => Some('K'),
        TeleopMode::Stand
        | TeleopMode::Fold
        | TeleopMode::Drive
        | TeleopMode::Walk
        | TeleopMode::Auto => None,
    }
}

/// The mode of one of the report's keys (either case), or `None` for any other key.
pub const fn mode_of_key(key: char) -> Option<TeleopMode> {
    Some(match key.to_ascii_uppercase() {
        'X' => TeleopMode::Stop,
        'W' => TeleopMode::WheelForward,
        'S' => TeleopMode::WheelBackward,
        'A' => TeleopMode::WheelRotate,
        'L' => TeleopMode::TrotForward,
        'K' => TeleopMode::TrotBackward,
        _ => return None,
    })
}

/// The action of `key`, `None` for a key with no meaning.
pub fn action(key: Key) -> Option<Action> {
    Some(match key {
        Key::Up => Action::Height(0.01),
        Key::Down => Action::Height(-0.01),
        Key::Left => Action::Steer(STEER_STEP_RAD_S),
        Key::Right => Action::Steer(-STEER_STEP_RAD_S),
        Key::Esc => Action::Quit,
        Key::Char(c) => match c.to_ascii_uppercase() {
            ' ' => Action::EStop,
            'T' => Action::Mode(TeleopMode::Stand),
            'F' => Action::Mode(TeleopMode::Fold),
            'H' => Action::Mode(TeleopMode::Auto),
            ']' => Action::Speed(10.0),
            '[' => Action::Speed(-10.0),
            'R' => Action::Release,
            'Q' => Action::Quit,
            other => Action::Mode(mode_of_key(other)?),
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_reports_keys_name_its_modes_both_ways() {
        for (key, mode) in [
            ('W', TeleopMode::WheelForward),
            ('S', TeleopMode::WheelBackward),
            ('A', TeleopMode::WheelRotate),
            ('L', TeleopMode::TrotForward),
            ('K', TeleopMode::TrotBackward),
            ('X', TeleopMode::Stop),
        ] {
            assert_eq!(mode_of_key(key), Some(mode));
            assert_eq!(mode_of_key(key.to_ascii_lowercase()), Some(mode));
            assert_eq!(mode_key(mode), Some(key));
        }
        assert_eq!(mode_of_key('Q'), None);
        assert_eq!(mode_key(TeleopMode::Stand), None);
    }

    #[test]
    fn the_reports_keys_and_the_others() {
        let mode = |c| action(Key::Char(c));
        for (c, m) in [
            ('w', TeleopMode::WheelForward),
            ('S', TeleopMode::WheelBackward),
            ('a', TeleopMode::WheelRotate),
            ('l', TeleopMode::TrotForward),
            ('k', TeleopMode::TrotBackward),
            ('x', TeleopMode::Stop),
            ('t', TeleopMode::Stand),
            ('f', TeleopMode::Fold),
        ] {
            assert_eq!(mode(c), Some(Action::Mode(m)), "{c}");
        }
        assert_eq!(mode(' '), Some(Action::EStop));
        assert_eq!(action(Key::Up), Some(Action::Height(0.01)));
        assert_eq!(mode('['), Some(Action::Speed(-10.0)));
        assert_eq!(mode('z'), None);
        assert_eq!(action(Key::Esc), Some(Action::Quit));
    }
}
