//! One leg's drive: four position servos (the report's position actuators, kp 180/200/260/160
//! in the model) that take their targets from the controller's `LegTargets` frame and report
//! joint position, velocity and torque in a `LegFeedback` frame.

use protocol::{
    Angle, AnyMessage, DriveEnable, E2eCounter, Frame, JointVelocity, Joints, Leg, LegFeedback,
    MessageId, Torque,
};

use crate::robot::drive_core::{Authority, DriveCore};
use crate::robot::physics::Physics;

/// The emulated drive of one leg.
#[derive(Debug, Clone)]
pub struct LegDrive {
    leg: Leg,
    core: DriveCore,
    targets_rad: [f64; 4],
    feedback_counter: E2eCounter,
}

impl LegDrive {
    /// The drive of `leg`.
    pub fn new(leg: Leg) -> Self {
        Self {
            leg,
            core: DriveCore::new(MessageId::LegTargets),
            targets_rad: [0.0; 4],
            feedback_counter: E2eCounter::default(),
        }
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
            self.targets_rad = targets.position.leg(self.leg).map(|a| f64::from(a.si()));
            self.core
                .set_commanded_enable(targets.enable == DriveEnable::Enabled);
        }
    }

    /// Drives the leg's servos in the simulation for the next step.
    pub fn apply(&self, now_us: u64, physics: &mut Physics) {
        let leg = self.leg as usize;
        match self.core.authority(now_us) {
            Authority::Drive => {
                physics.set_leg_targets(self.leg, &self.targets_rad);
                physics.set_leg_enabled(leg, true);
            }
            Authority::TorqueOff => physics.set_leg_enabled(leg, false),
        }
    }

    /// The feedback frame for the current state.
    pub fn feedback(&mut self, physics: &Physics) -> AnyMessage {
        let pick = |all: Joints<f64>| -> [f32; 4] { all.leg(self.leg).map(|v| v as f32) };
        let efforts = if physics.leg_enabled(self.leg as usize) {
            pick(physics.leg_efforts_nm())
        } else {
            [0.0; 4]
        };
        AnyMessage::LegFeedback(
            self.leg,
            LegFeedback {
                position: pick(physics.leg_positions_rad()).map(Angle::saturating_from_si),
                velocity: pick(physics.leg_velocities_rad_s())
                    .map(JointVelocity::saturating_from_si),
                effort: efforts.map(Torque::saturating_from_si),
            },
        )
    }

    /// The rolling counter for the next feedback frame.
    pub fn next_feedback_counter(&mut self) -> u16 {
        self.feedback_counter.advance()
    }
}
