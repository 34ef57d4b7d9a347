//! The hybrid wheel–leg robot in MuJoCo, presented on a CAN bus as its real hardware would be:
//! four leg drives, a wheel drive and an IMU, each a CAN node with the `protocol` crate's frames,
//! E2E checks and a command timeout.
//!
//! - [`physics`]: the model and its state (ground truth);
//! - the buses come from `host_can` (one abstraction, in-process and SocketCAN);
//! - [`leg_drive`], [`wheel_drive`], [`imu`], [`hardware`]: the emulated nodes;
//! - [`lockstep`], [`realtime`]: the two clocks;
//! - [`telemetry`], [`telemetry_csv`], [`candump`], [`plots`]: what a user looks at.

pub mod drive_core;
pub mod error_chain;
pub mod fault_matrix;
pub mod fault_rig;
pub mod hardware;
pub mod imu;
pub mod inproc_controller;
pub mod leg_drive;
pub mod lockstep;
pub mod metrics;
pub mod model;
pub mod output_error;
pub mod physics;
pub mod plots;
pub mod realtime;
pub mod recorder;
#[cfg(feature = "renderer")]
pub mod render;
pub mod run_stats;
pub mod session;
pub mod simulator;
pub mod summary;
pub mod telemetry;
pub mod telemetry_csv;
#[cfg(feature = "viewer")]
pub mod viewer;
pub mod wheel_drive;
