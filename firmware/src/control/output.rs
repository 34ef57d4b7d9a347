//! What the controller hands out each tick ([`Output`], with its telemetry [`Status`]), and why
//! it may refuse a configuration ([`ConfigError`]). Re-exported from
//! [`crate::control::controller`].

use protocol::{ControllerMode, FaultFlags, Joints};

use crate::time::Tick;

/// What the controller commands this tick.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Output {
    /// Whether the leg drives should servo (false: torque-free).
    pub legs_enabled: bool,
    /// Leg joint targets, rad; within the joint ranges and finite.
    pub leg_targets_rad: Joints<f32>,
    /// Wheel torques (left, right), N·m; within the torque limit and finite.
    pub wheel_torque_nm: [f32; 2],
    /// Telemetry.
    pub status: Status,
}

/// The controller's telemetry.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Status {
    /// Reported mode.
    pub mode: ControllerMode,
    /// Active fault causes.
    pub faults: FaultFlags,
    /// The tick of this output.
    pub tick: Tick,
    /// Body-height offset the legs realise, m.
    pub body_height_m: f32,
    /// Torso pitch, rad.
    pub pitch_rad: f32,
    /// Torso roll, rad.
    pub roll_rad: f32,
    /// IK solutions that failed and were replaced by the previous target (since power-on).
    pub ik_failures: u32,
}

/// Why [`Controller::new`](crate::control::controller::Controller::new) refused a configuration.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum ConfigError {
    /// The trot frequency is zero or not below the control rate.
    TrotFrequency,
    /// The link monitor's window is shorter than one tick, or its thresholds are not
    /// `recover ≤ degrade ≤ 1000 ‰` (checked by [`crate::node::Node::new`], which runs it).
    LinkMonitor,
}
