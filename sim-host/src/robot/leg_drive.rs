//! One leg's drive: four position servos that take their targets from the controller's
//! `LegTargets` frame, close the position loop themselves (the report's stiffness, kp
//! 180/200/260/160 N·m/rad) on torque motors of a real rating ([`Rating::LEG_JOINT`]), and
//! report what they measure of each joint (its encoder's angle and count velocity, the torque
//! from the phase current: [`crate::robot::sensing`]) in a `LegFeedback` frame.
//!
//! Like a real servo drive it enforces its own limits whatever the wire says: a target outside
//! a joint's range (the model's `range`, the leg's mechanical stops) is clamped to it and the
//! command counted ([`LegDrive::clamped`]); a torque beyond the motor's peak, its torque-speed
//! limit or its thermal foldback is cut and the next status says so
//! ([`protocol::DriveFlags::SATURATED`]).

use protocol::{
    Angle, AnyMessage, DriveEnable, Frame, JointVelocity, Leg, LegFeedback, MessageId, Torque,
};

use crate::robot::drive_core::{Authority, DriveCore};
use crate::robot::physics::Physics;
use crate::robot::rating::{Limiter, Rating};
use crate::robot::sensing::{DriveSensing, Encoder};

/// The servos' stiffness, N·m/rad, per joint (hip abduction, hip pitch, knee, ankle): the
/// report's position actuators.
pub const SERVO_KP_NM_RAD: [f64; 4] = [180.0, 200.0, 260.0, 160.0];

/// The emulated drive of one leg.
#[derive(Debug, Clone)]
pub struct LegDrive {
    leg: Leg,
    core: DriveCore,
    range_rad: [[f64; 2]; 4],
    targets_rad: [f64; 4],
    clamped: u64,
    limiters: [Limiter; 4],
    /// Physics steps in which a joint's torque was cut to the rating.
    saturated_steps: u64,
    encoders: [Encoder; 4],
    effort_gains: [f64; 4],
}

impl LegDrive {
    /// The drive of `leg`, whose joints (hip abduction, hip pitch, knee, ankle) move within
    /// `range_rad` ([low, high] each). The drive keeps its limits as the wire does, in counts of
    /// the `Angle` field (1e-4 rad), so that a target the controller put exactly on a limit is
    /// not clamped by the field's rounding.
    pub fn new(leg: Leg, range_rad: [[f64; 2]; 4], key: protocol::Key) -> Self {
        let in_counts = |rad: f64| f64::from(Angle::saturating_from_si(rad as f32).si());
        Self {
            leg,
            core: DriveCore::new(MessageId::LegTargets, key),
            range_rad: range_rad.map(|[low, high]| [in_counts(low), in_counts(high)]),
            targets_rad: [0.0; 4],
            clamped: 0,
            limiters: [Limiter::new(Rating::LEG_JOINT); 4],
            saturated_steps: 0,
            encoders: [Encoder::new(None); 4],
            effort_gains: [1.0; 4],
        }
    }

    /// The drive measuring its joints as `sensing` says (default: exactly).
    pub fn sensing(mut self, sensing: &DriveSensing) -> Self {
        self.encoders = [Encoder::new(sensing.leg_counts_per_turn); 4];
        self.effort_gains = sensing.effort_gains(self.leg as u64);
        self
    }

    /// The drive with its joints' motors of `rating` (default [`Rating::LEG_JOINT`]).
    pub fn rated(mut self, rating: Rating) -> Self {
        self.limiters = [Limiter::new(rating); 4];
        self
    }

    /// Physics steps in which a joint's torque was cut to the rating.
    pub fn saturated_steps(&self) -> u64 {
        self.saturated_steps
    }

    /// The joint targets the servos hold (after clamping), rad.
    pub fn targets_rad(&self) -> [f64; 4] {
        self.targets_rad
    }

    /// Commands with a target outside a joint's range, clamped to it.
    pub fn clamped(&self) -> u64 {
        self.clamped
    }

    /// Which leg.
    pub fn leg(&self) -> Leg {
        self.leg
    }

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
        if let Some(AnyMessage::LegTargets(targets)) = self.core.on_frame(now_us, frame) {
            let wanted = targets.position.leg(self.leg).map(|a| f64::from(a.si()));
            let mut clamped = false;
            for ((target, wanted), [low, high]) in
                self.targets_rad.iter_mut().zip(wanted).zip(self.range_rad)
            {
                *target = wanted.clamp(low, high);
                clamped |= *target != wanted;
            }
            self.clamped += u64::from(clamped);
            self.core
                .set_commanded_enable(targets.enable == DriveEnable::Enabled);
        }
    }

    /// Samples the encoders and runs the leg's servos for the next physics step: the position
    /// loop's torque on the measured angle, limited to the rating, or none when the drive is
    /// torque-off.
    pub fn apply(&mut self, now_us: u64, physics: &mut Physics) {
        let leg = self.leg as usize;
        let dt_s = physics.timestep_s();
        self.sense(physics);
        match self.core.authority(now_us) {
            Authority::Drive => {
                // The motor's back-EMF follows the true speed.
                let speeds = *physics.leg_velocities_rad_s().leg(self.leg);
                let mut torques = [0.0; 4];
                let mut saturated = false;
                for (i, limiter) in self.limiters.iter_mut().enumerate() {
                    let measured_rad = self.encoders[i].angle_rad();
                    let wanted = SERVO_KP_NM_RAD[i] * (self.targets_rad[i] - measured_rad);
                    let limited = limiter.limit(wanted, speeds[i], dt_s);
                    torques[i] = limited.torque_nm;
                    saturated |= limited.saturated;
                }
                if saturated {
                    self.saturated_steps += 1;
                    self.core.note_saturated();
                }
                physics.set_leg_torques(self.leg, &torques);
                physics.set_leg_enabled(leg, true);
            }
            Authority::TorqueOff => {
                for limiter in &mut self.limiters {
                    limiter.cool(dt_s);
                }
                physics.set_leg_enabled(leg, false);
            }
        }
    }

    /// Samples the encoders (once per simulated instant, see [`Encoder::sample`]).
    fn sense(&mut self, physics: &Physics) {
        let speeds = *physics.leg_velocities_rad_s().leg(self.leg);
        let angles = *physics.leg_positions_rad().leg(self.leg);
        let time_s = physics.time_s();
        for ((encoder, angle), speed) in self.encoders.iter_mut().zip(angles).zip(speeds) {
            encoder.sample(angle, speed, time_s);
        }
    }

    /// The feedback frame: the encoders' sample now, the applied torques as the drive
    /// measures them.
    pub fn feedback(&mut self, physics: &Physics) -> AnyMessage {
        self.sense(physics);
        let efforts_nm = *physics.leg_efforts_nm().leg(self.leg);
        let enabled = physics.leg_enabled(self.leg as usize);
        let effort = std::array::from_fn(|i| {
            let nm = if enabled {
                efforts_nm[i] * self.effort_gains[i]
            } else {
                0.0
            };
            Torque::saturating_from_si(nm as f32)
        });
        AnyMessage::LegFeedback(
            self.leg,
            LegFeedback {
                position: self
                    .encoders
                    .map(|e| Angle::saturating_from_si(e.angle_rad() as f32)),
                velocity: self
                    .encoders
                    .map(|e| JointVelocity::saturating_from_si(e.velocity_rad_s() as f32)),
                effort,
            },
        )
    }
}
