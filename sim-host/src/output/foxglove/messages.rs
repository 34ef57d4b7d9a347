//! The messages of the log's own topics, protobuf through the Foxglove SDK's derive (each
//! schema travels in the MCAP, so any reader decodes them): binary, because the log is written
//! every control cycle and text formatting was most of its cost.

use foxglove::bytes::Bytes;

/// The frames of one control cycle (`/can`): one message a cycle, not one a frame (a tenth of
/// the messages, and of the log's cost per message).
#[derive(foxglove::Encode)]
pub struct CanFrames {
    /// In the order they were seen.
    pub frames: Vec<CanFrame>,
}

/// One frame on the bus.
#[derive(foxglove::Encode)]
pub struct CanFrame {
    /// When it was seen, s (simulated in lockstep, wall clock in real time): the candump log's
    /// time, exported from here.
    pub time_s: f64,
    /// The 11-bit identifier.
    pub id: u32,
    /// The message's name in the DBC (`unknown` for an identifier the protocol lacks).
    pub name: &'static str,
    /// The data bytes.
    pub data: Bytes,
}

/// A vector, in the frame its message names.
#[derive(foxglove::Encode)]
pub struct Vector {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
}

/// What the IMU node sent (`/imu`), in its chip's frame.
#[derive(foxglove::Encode)]
pub struct Imu {
    /// Angular rate, rad/s.
    pub angular_velocity: Vector,
    /// Specific force, m/s².
    pub linear_acceleration: Vector,
}

/// What the wheel drive sent (`/wheels`): left, right.
#[derive(foxglove::Encode)]
pub struct WheelFeedback {
    /// Wheel rate relative to the body, rad/s, + rolling forward.
    pub velocity_rad_s: [f64; 2],
    /// Torque, N·m, + forward.
    pub effort_nm: [f64; 2],
}

/// What the controller reported (`/controller/status`).
#[derive(foxglove::Encode)]
pub struct ControllerStatus {
    /// Its mode, as the DBC names it.
    pub mode: &'static str,
    /// Its fault flags, as the DBC names them.
    pub faults: Vec<&'static str>,
    /// Estimated pitch, rad.
    pub pitch_rad: f64,
    /// Estimated roll, rad.
    pub roll_rad: f64,
    /// Body height offset, m.
    pub body_height_m: f64,
}

/// Every hinge of the model (`/joint_states`), in the order of `name`, as ROS's JointState.
#[derive(foxglove::Encode)]
pub struct JointState {
    /// The joints' names.
    pub name: Vec<String>,
    /// Angle, rad.
    pub position: Vec<f64>,
    /// Rate, rad/s.
    pub velocity: Vec<f64>,
    /// Actuator effort, N·m.
    pub effort: Vec<f64>,
}

/// The simulator's ground truth of one control cycle (`/telemetry`): the telemetry CSV's row,
/// exported from here.
#[derive(foxglove::Encode)]
pub struct Telemetry {
    /// Simulated time, s.
    pub time_s: f64,
    /// Torso centre in the world, m.
    pub torso_pos_m: [f64; 3],
    /// Torso roll, pitch (+ nose down), yaw (+ left), degrees.
    pub torso_rpy_deg: [f64; 3],
    /// Leg joint angles in the protocol's joint order, rad.
    pub leg_joint_rad: [f64; 16],
    /// Wheel torques, left and right, N·m.
    pub wheel_torque_nm: [f64; 2],
    /// Wheel speeds, left and right, rad/s.
    pub wheel_speed_rad_s: [f64; 2],
    /// Normal force on each foot (FL, FR, BL, BR), N.
    pub foot_force_n: [f64; 4],
    /// Whether a part other than the wheels and feet touches the ground.
    pub body_contact: bool,
    /// The controller's mode as the DBC names it, empty before its first status.
    pub mode: &'static str,
}
