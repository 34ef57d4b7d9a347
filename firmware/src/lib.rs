//! Control core of the hybrid wheel–leg robot.
//!
//! Sans-IO: the core takes decoded CAN messages and the tick, and returns actuator commands and
//! telemetry. It never touches a socket, a clock or a file, so the same code runs in host tests,
//! in the host firmware process next to the simulator, and on the Cortex-M4F.
//!
//! The kinematics, gait, FSM, balance and safety modules arrive with the control-core issue;
//! this crate already builds for the host and for `thumbv7em-none-eabihf`.
#![no_std]
#![deny(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing,
    clippy::default_numeric_fallback
)]

pub use protocol;
