//! Control core of the hybrid wheel–leg robot.
//!
//! Sans-IO: the core takes decoded CAN messages and the tick, and returns actuator commands and
//! telemetry. It never touches a socket, a clock or a file, so the same code runs in host tests,
//! in the host firmware process next to the simulator, and on the Cortex-M4F. No heap, no
//! double-precision floats, integer time, bounded loops; clippy denies `unwrap`, `expect`,
//! `panic` and unchecked indexing.
//!
//! The folders are the layers, from the bus inwards:
//!
//! | layer | module | what it does |
//! |---|---|---|
//! | CAN node | [`node`] ([`node::service`], [`node::rate_limit`], [`node::link`], [`node::persist`]) | frames in (decode, E2E, counted rejects, a per-tick budget for operator commands, the link's loss ratio), frames out on the bus schedule; the one service loop every target runs; the epoch and latch a board keeps across restarts |
//! | control | [`control`] ([`control::controller`], [`control::fsm`], [`control::safety`], [`control::sensors`], [`control::estimator`], [`control::teleop`]) | the control step (attitude estimate → supervisor → FSM → leg goals + smoothing → wheel law → clamps), modes, watchdogs and clamps, the attitude from the IMU's rate and specific force, operator requests |
//! | legs | [`legs`] | IK/FK, stance and fold, the trot |
//! | wheels | [`wheels`] | LQR balance on the estimated pitch, turn speed loop, torque mixing |
//! | basics | [`config`], [`limits`], [`math`], [`time`], [`attitude`] | parameters, units, maths choices |
// Functions stay short enough to read whole (clippy.toml: 80 lines); tests may run longer.
#![cfg_attr(not(test), warn(clippy::too_many_lines))]
#![no_std]
#![deny(missing_docs)]
#![deny(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing,
    clippy::default_numeric_fallback
)]

pub use protocol;

pub mod attitude;
pub mod config;
pub mod control;
pub mod legs;
pub mod limits;
pub mod math;
pub mod node;
pub mod time;
pub mod wheels;

pub use config::Config;
pub use control::controller::{Controller, Output, Status};
pub use node::Node;
pub use time::{Tick, TickRate};
