//! The hybrid wheel–leg robot in MuJoCo, presented on a CAN bus as its real hardware would be:
//! four leg drives, a wheel drive and an IMU, each a CAN node with the `protocol` crate's frames,
//! E2E checks and a command timeout. The buses come from `host_can` (one abstraction,
//! in-process and SocketCAN).
//!
//! The folders:
//!
//! - [`robot`]: the model and its state (ground truth), and the emulated hardware on the bus
//!   (leg drives, wheel drive, IMU);
//! - [`clock`]: the two clocks, lockstep (the simulator sends SYNC) and real time;
//! - [`session`]: one closed-loop run, with the firmware in-process or over SocketCAN;
//! - [`output`]: what a user looks at — telemetry CSV, the candump log, `summary.json`, plots,
//!   rendered frames, the viewer;
//! - [`faults`]: the fault matrix and the rig it runs on;
//! - [`campaign`]: the robustness campaign, the acceptance scenarios on many drawn robots.
// Functions stay short enough to read whole (clippy.toml: 80 lines); tests may run longer.
#![cfg_attr(not(test), warn(clippy::too_many_lines))]

pub mod campaign;
pub mod clock;
pub mod error_chain;
pub mod faults;
pub mod output;
pub mod robot;
pub mod scene;
pub mod session;
