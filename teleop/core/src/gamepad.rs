//! A gamepad as the operator's hands: its buttons and sticks as the operator's actions, sans-IO
//! (the device is read by the `teleop` program; its events come here already named after the
//! Linux gamepad API's buttons and axes).
//!
//! | control | action |
//! |---|---|
//! | left stick, up / down | ground speed, forward / backward (`drive` and `walk`) |
//! | right stick, left / right | yaw rate, turn left / right (`drive` and `walk`) |
//! | A (south) | `drive`: balance on the wheels at the sticks' speed and yaw rate |
//! | right shoulder | `walk`: trot at the sticks' speed and yaw rate |
//! | X or Y (west, north) | stop (the report's `X`) |
//! | B (east, the red one) | **E-stop**: latched at once, as the keyboard's space |
//! | Start twice within 2 s | release a latched E-stop, as the keyboard's `R R` |
//! | left shoulder | stand on the legs |
//! | Select (Back) | fold onto the wheels |
//! | D-pad up / down | body height +1 cm / −1 cm |
//!
//! X and Y both stop: the kernel's gamepad API names them by position (west, north), but the
//! common Xbox drivers (xpad, xone, xpadneo) report them swapped, so neither may start a
//! motion.
//!
//! The sticks are read as fractions of their travel; the operator turns them into a speed and
//! a yaw rate within the robot's limits for the mode ([`crate::operator`]). A pad that
//! disconnects is an operator lost: the operator sends STOP at once and falls silent, so that
//! the controller's heartbeat watchdog holds the robot too, and after the pad is back nothing
//! moves until a new motion is pressed (the operator comes back at STOP, which the controller's
//! restart interlock wants first).

use protocol::TeleopMode;

use crate::keys::Action;

/// A stick within this fraction of its centre reads as centred: worn sticks rest off centre.
pub const DEADBAND: f32 = 0.08;

/// A gamepad button, as the Linux gamepad API names them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PadButton {
    /// The bottom face button (A on an Xbox pad).
    South,
    /// The right face button (B, red).
    East,
    /// The left face button (X; Y on Xbox drivers that swap them).
    West,
    /// The top face button (Y; X on Xbox drivers that swap them).
    North,
    /// The left shoulder button.
    LeftShoulder,
    /// The right shoulder button.
    RightShoulder,
    /// Start.
    Start,
    /// Select (Back).
    Select,
    /// D-pad up.
    DPadUp,
    /// D-pad down.
    DPadDown,
}

/// A gamepad stick axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PadAxis {
    /// Left stick, + right.
    LeftX,
    /// Left stick, + down (the Linux convention).
    LeftY,
    /// Right stick, + right.
    RightX,
    /// Right stick, + down.
    RightY,
}

/// What a gamepad reports.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PadInput {
    /// A button went down.
    Pressed(PadButton),
    /// A stick moved: its position, −1…1 of its travel.
    Axis(PadAxis, f32),
    /// The pad is there (again).
    Connected,
    /// The pad went away (unplugged, out of range, its device gone).
    Disconnected,
}

/// The sticks' last positions.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Gamepad {
    left_y: f32,
    right_x: f32,
}

impl Gamepad {
    /// The operator's action for `input`, if it asks for one.
    pub fn action(&mut self, input: PadInput) -> Option<Action> {
        match input {
            PadInput::Pressed(button) => button_action(button),
            PadInput::Axis(axis, value) => {
                let value = if value.is_finite() {
                    value.clamp(-1.0, 1.0)
                } else {
                    0.0
                };
                match axis {
                    PadAxis::LeftY => self.left_y = value,
                    PadAxis::RightX => self.right_x = value,
                    PadAxis::LeftX | PadAxis::RightY => return None,
                }
                // Up is forward, left is a left turn (+ yaw).
                Some(Action::Sticks {
                    forward: -deadband(self.left_y),
                    turn: -deadband(self.right_x),
                })
            }
            PadInput::Connected => Some(Action::InputFound),
            PadInput::Disconnected => {
                *self = Self::default();
                Some(Action::InputLost)
            }
        }
    }
}

/// The action of a button.
pub const fn button_action(button: PadButton) -> Option<Action> {
    Some(match button {
        PadButton::South => Action::Mode(TeleopMode::Drive),
        PadButton::RightShoulder => Action::Mode(TeleopMode::Walk),
        PadButton::West | PadButton::North => Action::Mode(TeleopMode::Stop),
        PadButton::East => Action::EStop,
        PadButton::Start => Action::Release,
        PadButton::LeftShoulder => Action::Mode(TeleopMode::Stand),
        PadButton::Select => Action::Mode(TeleopMode::Fold),
        PadButton::DPadUp => Action::Height(0.01),
        PadButton::DPadDown => Action::Height(-0.01),
    })
}

/// `value` with the dead band taken out and the rest rescaled to reach ±1.
fn deadband(value: f32) -> f32 {
    let magnitude = value.abs();
    if magnitude <= DEADBAND {
        0.0
    } else {
        value.signum() * (magnitude - DEADBAND) / (1.0 - DEADBAND)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sticks_up_and_left_are_forward_and_a_left_turn_past_the_dead_band() {
        let mut pad = Gamepad::default();
        assert_eq!(
            pad.action(PadInput::Axis(PadAxis::LeftY, -1.0)),
            Some(Action::Sticks {
                forward: 1.0,
                turn: 0.0
            })
        );
        let Some(Action::Sticks { forward, turn }) =
            pad.action(PadInput::Axis(PadAxis::RightX, -0.54))
        else {
            panic!("a stick is a sticks action");
        };
        assert_eq!(forward, 1.0);
        assert!((turn - 0.5).abs() < 1e-6, "{turn}");
        assert_eq!(
            pad.action(PadInput::Axis(PadAxis::LeftY, 0.05)),
            Some(Action::Sticks { forward: 0.0, turn })
        );
        assert_eq!(pad.action(PadInput::Axis(PadAxis::LeftX, 1.0)), None);
    }

    #[test]
    fn neither_x_nor_y_starts_a_motion_whichever_way_a_driver_names_them() {
        for button in [PadButton::West, PadButton::North] {
            assert_eq!(button_action(button), Some(Action::Mode(TeleopMode::Stop)));
        }
    }

    #[test]
    fn the_red_button_latches_and_a_lost_pad_centres_its_sticks() {
        let mut pad = Gamepad::default();
        assert_eq!(
            pad.action(PadInput::Pressed(PadButton::East)),
            Some(Action::EStop)
        );
        pad.action(PadInput::Axis(PadAxis::LeftY, -1.0));
        assert_eq!(pad.action(PadInput::Disconnected), Some(Action::InputLost));
        assert_eq!(pad, Gamepad::default());
    }
}
