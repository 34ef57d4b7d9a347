//! A gamepad read through the kernel's evdev interface (`/dev/input/event*`), turned into the
//! operator's actions by [`teleop_core::gamepad`]. Read without blocking from the same loop
//! that sends the heartbeat, so that a button reaches the bus within one pass of it.
//!
//! A device counts as a gamepad when it has the south button and a left stick (`BTN_SOUTH`,
//! `ABS_X`, `ABS_Y`): what the kernel's gamepad API promises. An unplugged pad reads as an
//! error (`ENODEV`): the operator is told it is lost, and the device is looked for again every
//! [`SEARCH_PERIOD`].

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use evdev::{AbsoluteAxisCode, Device, EventSummary, KeyCode};
use teleop_core::gamepad::{Gamepad, PadAxis, PadButton, PadInput};
use teleop_core::keys::Action;

/// How often a missing pad is looked for.
pub const SEARCH_PERIOD: Duration = Duration::from_millis(500);

/// Why no gamepad could be read.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PadError {
    /// The named device could not be opened.
    #[error("cannot open the gamepad {}: {source} (reading input devices needs the `input` group or root)", path.display())]
    Open {
        /// The device.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// The named device is not a gamepad.
    #[error("{} is not a gamepad: it has no south button or no left stick", path.display())]
    NotAGamepad {
        /// The device.
        path: PathBuf,
    },
    /// No device is a gamepad.
    #[error("no gamepad found in /dev/input: plug one in, or name its device with --gamepad /dev/input/eventN (reading input devices needs the `input` group or root)")]
    NoneFound,
}

/// A gamepad being read, and found again when it comes back.
pub struct PadReader {
    /// The device named on the command line (`None`: the first gamepad found).
    wanted: Option<PathBuf>,
    device: Option<OpenPad>,
    pad: Gamepad,
    next_search: Instant,
}

impl std::fmt::Debug for PadReader {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PadReader")
            .field("wanted", &self.wanted)
            .field("device", &self.device.as_ref().map(|(path, ..)| path))
            .finish_non_exhaustive()
    }
}

impl PadReader {
    /// Opens the gamepad at `path`, or the first one found.
    pub fn open(path: Option<&Path>) -> Result<Self, PadError> {
        let device = match path {
            Some(path) => open_pad(path)?,
            None => find_pad().ok_or(PadError::NoneFound)?,
        };
        Ok(Self {
            wanted: path.map(Path::to_owned),
            device: Some(device),
            pad: Gamepad::default(),
            next_search: Instant::now(),
        })
    }

    /// The device read now, if the pad is there.
    pub fn device(&self) -> Option<&Path> {
        self.device.as_ref().map(|(path, ..)| path.as_path())
    }

    /// The actions of everything the pad reported since the last call (without waiting); a pad
    /// that went away gives [`Action::InputLost`], and one found again [`Action::InputFound`].
    pub fn poll(&mut self, now: Instant) -> Vec<Action> {
        let mut inputs = Vec::new();
        match &mut self.device {
            Some((_, device, ranges)) => {
                let gone = match device.fetch_events() {
                    Ok(events) => {
                        inputs.extend(events.filter_map(|e| input_of(e.destructure(), ranges)));
                        false
                    }
                    Err(e) => e.kind() != std::io::ErrorKind::WouldBlock,
                };
                if gone {
                    self.device = None;
                    self.next_search = now + SEARCH_PERIOD;
                    inputs.push(PadInput::Disconnected);
                }
            }
            None if now >= self.next_search => {
                self.next_search = now + SEARCH_PERIOD;
                let found = match &self.wanted {
                    Some(path) => open_pad(path).ok(),
                    None => find_pad(),
                };
                if let Some(device) = found {
                    self.device = Some(device);
                    inputs.push(PadInput::Connected);
                }
            }
            None => {}
        }
        inputs
            .into_iter()
            .filter_map(|input| self.pad.action(input))
            .collect()
    }
}

type OpenPad = (PathBuf, Device, HashMap<AbsoluteAxisCode, (i32, i32)>);

/// The device at `path`, if it is a gamepad, opened for reading without blocking.
fn open_pad(path: &Path) -> Result<OpenPad, PadError> {
    let device = Device::open(path).map_err(|source| PadError::Open {
        path: path.to_owned(),
        source,
    })?;
    prepare(path.to_owned(), device).ok_or_else(|| PadError::NotAGamepad {
        path: path.to_owned(),
    })
}

/// The first gamepad among the input devices.
fn find_pad() -> Option<OpenPad> {
    evdev::enumerate().find_map(|(path, device)| prepare(path, device))
}

fn prepare(path: PathBuf, device: Device) -> Option<OpenPad> {
    let has_button = device
        .supported_keys()
        .is_some_and(|keys| keys.contains(KeyCode::BTN_SOUTH));
    let has_stick = device.supported_absolute_axes().is_some_and(|axes| {
        axes.contains(AbsoluteAxisCode::ABS_X) && axes.contains(AbsoluteAxisCode::ABS_Y)
    });
    if !(has_button && has_stick) {
        return None;
    }
    let ranges = device
        .get_absinfo()
        .ok()?
        .map(|(axis, info)| (axis, (info.minimum(), info.maximum())))
        .collect();
    device.set_nonblocking(true).ok()?;
    Some((path, device, ranges))
}

/// What an evdev event says, in the gamepad API's terms.
fn input_of(
    event: EventSummary,
    ranges: &HashMap<AbsoluteAxisCode, (i32, i32)>,
) -> Option<PadInput> {
    match event {
        EventSummary::Key(_, code, 1) => button_of(code).map(PadInput::Pressed),
        EventSummary::AbsoluteAxis(_, AbsoluteAxisCode::ABS_HAT0Y, value) => match value {
            v if v < 0 => Some(PadInput::Pressed(PadButton::DPadUp)),
            v if v > 0 => Some(PadInput::Pressed(PadButton::DPadDown)),
            _ => None,
        },
        EventSummary::AbsoluteAxis(_, code, value) => {
            let axis = match code {
                AbsoluteAxisCode::ABS_X => PadAxis::LeftX,
                AbsoluteAxisCode::ABS_Y => PadAxis::LeftY,
                AbsoluteAxisCode::ABS_RX => PadAxis::RightX,
                AbsoluteAxisCode::ABS_RY => PadAxis::RightY,
                _ => return None,
            };
            let (min, max) = ranges.get(&code).copied()?;
            Some(PadInput::Axis(axis, normalised(value, min, max)))
        }
        _ => None,
    }
}

fn button_of(code: KeyCode) -> Option<PadButton> {
    Some(match code {
        KeyCode::BTN_SOUTH => PadButton::South,
        KeyCode::BTN_EAST => PadButton::East,
        KeyCode::BTN_WEST => PadButton::West,
        KeyCode::BTN_NORTH => PadButton::North,
        KeyCode::BTN_TL => PadButton::LeftShoulder,
        KeyCode::BTN_TR => PadButton::RightShoulder,
        KeyCode::BTN_START => PadButton::Start,
        KeyCode::BTN_SELECT => PadButton::Select,
        KeyCode::BTN_DPAD_UP => PadButton::DPadUp,
        KeyCode::BTN_DPAD_DOWN => PadButton::DPadDown,
        _ => return None,
    })
}

/// `value` within `min…max` as −1…1 (0 for an empty range).
fn normalised(value: i32, min: i32, max: i32) -> f32 {
    let span = f64::from(max) - f64::from(min);
    if span <= 0.0 {
        return 0.0;
    }
    ((2.0 * (f64::from(value) - f64::from(min)) / span - 1.0).clamp(-1.0, 1.0)) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axes_span_minus_one_to_one_and_the_hat_is_the_d_pad() {
        assert_eq!(normalised(-32768, -32768, 32767), -1.0);
        assert_eq!(normalised(32767, -32768, 32767), 1.0);
        assert!(normalised(0, -32768, 32767).abs() < 1e-4);
        assert!((normalised(128, 0, 255) - 1.0 / 255.0).abs() < 1e-6);
        assert_eq!(normalised(5, 3, 3), 0.0);
        let ranges = HashMap::new();
        let up = EventSummary::AbsoluteAxis(
            evdev::AbsoluteAxisEvent::new(AbsoluteAxisCode::ABS_HAT0Y, -1),
            AbsoluteAxisCode::ABS_HAT0Y,
            -1,
        );
        assert_eq!(
            input_of(up, &ranges),
            Some(PadInput::Pressed(PadButton::DPadUp))
        );
    }
}
