//! Control core of the hybrid wheel–leg robot.
//!
//! Sans-IO: the core takes decoded CAN messages and the tick, and returns actuator commands and
//! telemetry. It never touches a socket, a clock or a file, so the same code runs in host tests,
//! in the host firmware process next to the simulator, and on the Cortex-M4F. No heap, no
//! double-precision floats, integer time, bounded loops; clippy denies `unwrap`, `expect`,
//! `panic` and unchecked indexing.
//!
//! | layer | module | what it does |
//! |---|---|---|
//! | CAN node | [`node`], [`can`], [`rate_limit`], [`link`] | frames in (decode, E2E, counted rejects, a per-tick budget for operator commands, the link's loss ratio), frames out on the bus schedule |
//! | control step | [`controller`] | supervisor → FSM → leg goals + smoothing → wheel law → clamps |
//! | modes | [`fsm`] | states, events and the transition table |
//! | legs | [`kinematics`], [`posture`], [`gait`], [`foot_trajectory`], [`sine_gait`], [`phase`], [`smoothing`] | IK/FK, stance and fold, the trot |
//! | wheels | [`balance`], [`wheel`] | LQR balance on IMU pitch, turn speed loop, torque mixing |
//! | safety | [`safety`], [`sensors`], [`teleop`] | watchdogs, clamps, operator requests |
//! | basics | [`config`], [`limits`], [`math`], [`time`], [`attitude`] | parameters, units, maths choices |
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
pub mod balance;
pub mod can;
pub mod config;
pub mod controller;
pub mod foot_trajectory;
pub mod fsm;
pub mod gait;
pub mod kinematics;
pub mod limits;
pub mod link;
pub mod math;
pub mod node;
pub mod phase;
pub mod posture;
pub mod rate_limit;
pub mod safety;
pub mod sensors;
pub mod sine_gait;
pub mod smoothing;
pub mod support;
pub mod teleop;
pub mod time;
pub mod wheel;

pub use config::Config;
pub use controller::{Controller, Output, Status};
pub use node::Node;
pub use time::{Tick, TickRate};
