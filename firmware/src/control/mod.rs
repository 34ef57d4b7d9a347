//! The control step and what keeps it safe: the [`controller`] runs the [`fsm`]'s mode, with
//! the [`safety`] watchdogs and clamps around it, the [`sensors`] it last heard (attitude from the IMU by the [`estimator`]), the operator's
//! [`teleop`] requests (their speed and yaw rate within the [`steering`] limits) and the E-stop's controlled [`stop`]; its [`output`] is the commands and
//! the telemetry.

pub mod controller;
pub mod estimator;
pub mod fsm;
pub mod heading;
pub mod output;
pub mod safety;
pub mod sensors;
pub mod steering;
pub mod stop;
pub mod teleop;
pub mod terrain;
