//! The wheel drive: two torque-controlled motors (the report's motor actuators, gear 1) that
//! take `WheelCommand` frames and report angle, speed and torque in `WheelFeedback`.
//!
//! Like a real drive it enforces its rating whatever the wire says: a torque above
//! [`WHEEL_PEAK_TORQUE_NM`] is clamped to it and the command counted ([`WheelDrive::clamped`]).

use protocol::{AnyMessage, Frame, MessageId, Torque, WheelFeedback, WheelVelocity};

use crate::robot::drive_core::{Authority, DriveCore};
use crate::robot::physics::Physics;

/// The wheel motors' peak torque, N·m: a hub motor of the class that carries this 40 kg robot
/// (the controller plans with the same figure, `Config::wheel_torque_limit_nm`; the drive does
/// not trust it to).
pub const WHEEL_PEAK_TORQUE_NM: f64 = 30.0;

/// The emulated wheel drive.
#[derive(Debug, Clone)]
pub struct WheelDrive {
    core: DriveCore,
    torque_nm: [f64; 2],
    clamped: u64,
}

impl WheelDrive {
    /// A wheel drive that joins the sessions it hears with `key`.
    pub fn new(key: protocol::Key) -> Self {
        Self {
            core: DriveCore::new(MessageId::WheelCommand, key),
            torque_nm: [0.0; 2],
            clamped: 0,
        }
    }
}

impl WheelDrive {
    /// Receive state, counters and flags.
    pub fn core(&self) -> &DriveCore {
        &self.core
    }

    /// Mutable access for the status frame.
    pub fn core_mut(&mut self) -> &mut DriveCore {
        &mut self.core
    }

    /// Takes a frame from the bus (see [`DriveCore::on_frame`]).
    pub fn on_frame(&mut self, now_us: u64, frame: &Frame) {
        if let Some(AnyMessage::WheelCommand(command)) = self.core.on_frame(now_us, frame) {
            let wanted = command.torque.map(|t| f64::from(t.si()));
            self.torque_nm = wanted.map(|t| t.clamp(-WHEEL_PEAK_TORQUE_NM, WHEEL_PEAK_TORQUE_NM));
            self.clamped += u64::from(self.torque_nm != wanted);
            self.core.set_commanded_enable(true);
        }
    }

    /// Commands with a torque above the rating, clamped to it.
    pub fn clamped(&self) -> u64 {
        self.clamped
    }

    /// The torques the motors apply for the next step: the command, or zero when the drive is
    /// torque-off (timeout, E-stop, no command yet).
    pub fn applied_torque_nm(&self, now_us: u64) -> [f64; 2] {
        match self.core.authority(now_us) {
            Authority::Drive => self.torque_nm,
            Authority::TorqueOff => [0.0; 2],
        }
    }

    /// Drives the wheel motors in the simulation for the next step.
    pub fn apply(&self, now_us: u64, physics: &mut Physics) {
        physics.set_wheel_torques(self.applied_torque_nm(now_us));
    }

    /// The feedback frame for the current state.
    pub fn feedback(&mut self, physics: &Physics) -> AnyMessage {
        AnyMessage::WheelFeedback(WheelFeedback {
            velocity: physics
                .wheel_velocities_rad_s()
                .map(|v| WheelVelocity::saturating_from_si(v as f32)),
            effort: physics
                .wheel_efforts_nm()
                .map(|t| Torque::saturating_from_si(t as f32)),
        })
    }
}
