//! What the simulator records each step for the user: ground truth from MuJoCo and what the
//! bus said, one [`TelemetryRow`] per recorded step.

use protocol::{ControllerMode, Joints};

/// One recorded simulation step. Angles are ground truth from the simulator, not estimates.
#[derive(Debug, Clone, PartialEq)]
pub struct TelemetryRow {
    /// Simulation time, s.
    pub time_s: f64,
    /// Torso centre in the world frame (x forward at start, z up), m.
    pub torso_pos_m: [f64; 3],
    /// Torso roll, pitch (+ = nose down), yaw (+ = turning left), degrees.
    pub torso_rpy_deg: [f64; 3],
    /// Leg joint angles, rad.
    pub leg_joint_rad: Joints<f64>,
    /// Wheel torques applied by the wheel drive, left and right, N·m (+ = forward).
    pub wheel_torque_nm: [f64; 2],
    /// Wheel speeds, left and right, rad/s (+ = rolling forward).
    pub wheel_speed_rad_s: [f64; 2],
    /// Normal force on each foot (FL, FR, BL, BR) from its touch sensor, N (0 in the air).
    pub foot_force_n: [f64; 4],
    /// Whether a part of the robot other than its wheels and feet (torso, a leg link) touches
    /// the ground.
    pub body_contact: bool,
    /// The controller's mode from its last status frame, `None` before the first.
    pub mode: Option<ControllerMode>,
}
