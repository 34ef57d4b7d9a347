//! The `teleop` program: an operator drives the robot over CAN from a terminal (the report's
//! keys W/S/A/L/K/X, stand, fold, height, speed, E-stop), a gamepad or a script, on a SocketCAN bus
//! or, with the `sim` feature, on an in-process bus with the simulated robot beside it.
//!
//! The operator itself is sans-IO ([`teleop_core`]); this crate is its edge: [`app`] (the
//! interactive state), [`ui`] (the screen), [`terminal`] (keys and screen on a real terminal),
//! [`gamepad`] (a gamepad through evdev),
//! [`script`] (`send` and `script` on the wall clock), [`inproc`] (the simulated robot).
// Functions stay short enough to read whole (clippy.toml: 80 lines); tests may run longer.
#![cfg_attr(not(test), warn(clippy::too_many_lines))]
#![deny(missing_docs, clippy::unwrap_used, clippy::expect_used, clippy::panic)]

/// Most frames the program reads from the bus per pass of its loop (a pass takes a few ms):
/// far above any genuine bus, so that a flood cannot keep the loop from reading keys or
/// sending (the E-stop included).
pub const MAX_FRAMES_PER_PASS: usize = 1_000;

pub mod app;
pub mod gamepad;
#[cfg(feature = "sim")]
pub mod inproc;
pub mod script;
pub mod terminal;
pub mod ui;
