//! The wheel drive: two torque-controlled motors (the report's motor actuators, gear 1) that
//! take `WheelCommand` frames and report what they measure (each wheel's encoder count
//! velocity and the torque from the phase current: [`crate::robot::sensing`]) in
//! `WheelFeedback`.
//!
//! Like a real drive it enforces its rating whatever the wire says: a commanded torque above
//! the peak ([`WHEEL_PEAK_TORQUE_NM`]) is clamped to it and the command counted
//! ([`WheelDrive::clamped`]); at speed and when hot the motors give less
//! ([`Rating::WHEEL`]), and the next status says so ([`protocol::DriveFlags::SATURATED`]).

use protocol::{AnyMessage, DriveEnable, Frame, MessageId, Torque, WheelFeedback, WheelVelocity};

use crate::robot::drive_core::{Authority, DriveCore};
use crate::robot::physics::Physics;
use crate::robot::rating::{Limiter, Rating};
use crate::robot::sensing::{DriveSensing, Encoder};

/// The wheel motors' peak torque, N·m ([`Rating::WHEEL`]).
pub const WHEEL_PEAK_TORQUE_NM: f64 = Rating::WHEEL.peak_torque_nm;

/// The emulated wheel drive.
#[derive(Debug, Clone)]
pub struct WheelDrive {
    core: DriveCore,
    torque_nm: [f64; 2],
    clamped: u64,
    limiters: [Limiter; 2],
    /// The torques applied in the last step, N·m.
    applied_nm: [f64; 2],
    /// Physics steps in which a wheel's torque was cut to the rating.
    saturated_steps: u64,
    encoders: [Encoder; 2],
    effort_gains: [f64; 2],
}

impl WheelDrive {
    /// A wheel drive that joins the sessions it hears with `key`.
    pub fn new(key: protocol::Key) -> Self {
        Self {
            core: DriveCore::new(MessageId::WheelCommand, key),
            torque_nm: [0.0; 2],
            clamped: 0,
            limiters: [Limiter::new(Rating::WHEEL); 2],
            applied_nm: [0.0; 2],
            saturated_steps: 0,
            encoders: [Encoder::new(None); 2],
            effort_gains: [1.0; 2],
        }
    }

    /// The drive measuring its wheels as `sensing` says (default: exactly).
    pub fn sensing(mut self, sensing: &DriveSensing) -> Self {
        self.encoders = [Encoder::new(sensing.wheel_counts_per_turn); 2];
        // Stream 4: after the four legs' 0…3.
        self.effort_gains = sensing.effort_gains(4);
        self
    }

    /// The drive with motors of `rating` (default [`Rating::WHEEL`]); commands stay clamped to
    /// [`WHEEL_PEAK_TORQUE_NM`].
    pub fn rated(mut self, rating: Rating) -> Self {
        self.limiters = [Limiter::new(rating); 2];
        self
    }

    /// Physics steps in which a wheel's torque was cut to the rating.
    pub fn saturated_steps(&self) -> u64 {
        self.saturated_steps
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
            self.core
                .set_commanded_enable(command.enable == DriveEnable::Enabled);
        }
    }

    /// Commands with a torque above the rating, clamped to it.
    pub fn clamped(&self) -> u64 {
        self.clamped
    }

    /// The commanded torques the drive holds, clamped to the peak, N·m.
    pub fn commanded_torque_nm(&self) -> [f64; 2] {
        self.torque_nm
    }

    /// The torques the motors applied in the last step, N·m: the command within the rating, or
    /// zero when the drive is torque-off (timeout, E-stop, no command yet).
    pub fn applied_torque_nm(&self) -> [f64; 2] {
        self.applied_nm
    }

    /// Samples the encoders and drives the wheel motors in the simulation for the next step.
    pub fn apply(&mut self, now_us: u64, physics: &mut Physics) {
        let dt_s = physics.timestep_s();
        let speeds = physics.wheel_velocities_rad_s();
        self.sense(physics);
        let on = self.core.authority(now_us) == Authority::Drive;
        let mut saturated = false;
        for (i, limiter) in self.limiters.iter_mut().enumerate() {
            self.applied_nm[i] = if on {
                let limited = limiter.limit(self.torque_nm[i], speeds[i], dt_s);
                saturated |= limited.saturated;
                limited.torque_nm
            } else {
                limiter.cool(dt_s);
                0.0
            };
        }
        if saturated {
            self.saturated_steps += 1;
            self.core.note_saturated();
        }
        physics.set_wheel_torques(self.applied_nm);
    }

    /// Samples the encoders (once per simulated instant, see [`Encoder::sample`]).
    fn sense(&mut self, physics: &Physics) {
        let speeds = physics.wheel_velocities_rad_s();
        let angles = physics.wheel_positions_rad();
        let time_s = physics.time_s();
        for ((encoder, angle), speed) in self.encoders.iter_mut().zip(angles).zip(speeds) {
            encoder.sample(angle, speed, time_s);
        }
    }

    /// The feedback frame: the encoders' count velocities now, the applied torques as the
    /// drive measures them.
    pub fn feedback(&mut self, physics: &Physics) -> AnyMessage {
        self.sense(physics);
        let efforts_nm = physics.wheel_efforts_nm();
        AnyMessage::WheelFeedback(WheelFeedback {
            velocity: self
                .encoders
                .map(|e| WheelVelocity::saturating_from_si(e.velocity_rad_s() as f32)),
            effort: std::array::from_fn(|i| {
                Torque::saturating_from_si((efforts_nm[i] * self.effort_gains[i]) as f32)
            }),
        })
    }
}
