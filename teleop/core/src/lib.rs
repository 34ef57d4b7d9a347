//! The operator of the robot as a CAN node, sans-IO: time comes in as milliseconds or
//! microseconds, frames go out as values; terminals, files' I/O and buses live at the edge.
//!
//! - [`keys`]: what an operator's keys mean (the report's W/S/A/L/K/X and the rest), and
//!   [`gamepad`]: what a gamepad's buttons and sticks mean;
//! - [`operator`]: what an interactive operator puts on the bus — the teleop command on every
//!   change and at 50 Hz, the heartbeat at 50 Hz, E-stop latch and clear;
//! - [`scenario`] and [`scripted`]: a script of commands over time (a TOML file) and the node
//!   that follows it, for automation and tests;
//! - [`link`]: the operator's end of the bus session (join, seal, resume);
//! - [`bus_status`]: what the operator sees of the robot, read off the bus.
// Functions stay short enough to read whole (clippy.toml: 80 lines); tests may run longer.
#![cfg_attr(not(test), warn(clippy::too_many_lines))]
#![deny(missing_docs, clippy::unwrap_used, clippy::expect_used, clippy::panic)]
#![cfg_attr(test, allow(clippy::unwrap_used, clippy::expect_used, clippy::panic))]

pub mod bus_status;
pub mod gamepad;
pub mod keys;
pub mod link;
pub mod operator;
pub mod release;
pub mod scenario;
pub mod scripted;
