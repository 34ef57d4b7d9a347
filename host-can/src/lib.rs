//! The host side of the robot's CAN bus: what every host program (the simulator, the firmware
//! runner, teleop, the vcan suite) needs to be a node, and nothing of the control core.
//!
//! - [`bus`]: one [`bus::Bus`] trait for a node's connection, with two implementations:
//!   [`inproc_bus`] (deterministic, in one process) and [`socketcan_bus`] (Linux SocketCAN:
//!   `vcan0`, `can0`);
//! - [`faulty_bus`] and [`fault_plan`]: a layer that breaks frames on purpose between a node
//!   and its bus, for fault-injection tests, and the plans that say how;
//! - [`candump`]: the one reader and writer of the can-utils log format (`candump -L`,
//!   `canplayer`, `cansend`);
//! - [`port`]: a bus as an `embedded-can` port, for the firmware's service loop;
//! - [`logging`]: `tracing` set up the same way in every host program.
// Functions stay short enough to read whole (clippy.toml: 80 lines); tests may run longer.
#![cfg_attr(not(test), warn(clippy::too_many_lines))]
#![deny(missing_docs, clippy::unwrap_used, clippy::expect_used, clippy::panic)]
#![cfg_attr(test, allow(clippy::unwrap_used, clippy::expect_used, clippy::panic))]

pub mod bus;
pub mod candump;
pub mod fault_plan;
pub mod faulty_bus;
pub mod inproc_bus;
pub mod kernel_frame;
pub mod key_file;
pub mod logging;
pub mod port;
pub mod socketcan_bus;

pub use bus::{Bus, BusError};
pub use candump::LoggedFrame;
