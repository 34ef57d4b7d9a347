//! Teleop over CAN: what an operator's keys mean ([`keys`]) and what the operator node puts on
//! the bus ([`operator`]) — the teleop command on every change and at 50 Hz, the heartbeat at
//! 50 Hz, E-stop latch and clear. Sans-IO: time comes in as milliseconds, frames go out as
//! values; the terminal UI and the bus live at the edge. [`bus_status`] is what the operator
//! sees of the robot, read off the bus.

#![deny(missing_docs, clippy::unwrap_used, clippy::expect_used, clippy::panic)]
#![cfg_attr(test, allow(clippy::unwrap_used, clippy::expect_used, clippy::panic))]

pub mod bus_status;
pub mod keys;
pub mod operator;
