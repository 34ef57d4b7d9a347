//! Shared by the firmware's closed-loop benches: the pose they start in, the messages an
//! ideal plant and operator send, and the bus session they send them in. Each test binary uses
//! part of it.
#![allow(dead_code)]

pub mod bench;

use firmware::config::Config;
use firmware::Node;
use protocol::{
    Acceleration, Angle, AngularRate, AnyMessage, BodyHeight, Epoch, Frame, Imu, JointVelocity,
    Joints, LegFeedback, Sender, Session, SpeedScale, TeleopCommand, TeleopMode, Torque,
    WheelFeedback, WheelVelocity, TEST_KEY,
};

/// The session the node under test opens (the simulation's key, epoch 1); the test's other
/// nodes (plant, operator) seal their frames in it, as if they had heard its announcement.
pub const SESSION: Session = Session::owned(TEST_KEY, Epoch::new(1));

/// A controller node running `config` in [`SESSION`].
pub fn node(config: Config) -> Node {
    Node::new(config, SESSION).expect("a valid configuration")
}

/// `message` sealed in [`SESSION`] with the next counter of its identifier in `sender`.
pub fn seal(sender: &mut Sender, message: &AnyMessage) -> Frame {
    sender
        .seal(&SESSION, message)
        .expect("the session is joined")
}

/// Every leg at the nominal stance of `config`, rad: the robot standing.
pub fn standing_joints_rad(config: &Config) -> Joints<f32> {
    let stance = config
        .posture
        .stance(
            &config.geometry,
            &config.limits,
            config.posture.depth_nominal_m,
        )
        .expect("the nominal stance is reachable")
        .to_array();
    Joints::from_leg_fn(|_| stance)
}

/// A bench stepped one control tick at a time.
pub trait Ticks {
    /// One tick; its output.
    fn tick(&mut self) -> firmware::control::controller::Output;

    /// `ticks` ticks (at least one); the last output.
    fn run(&mut self, ticks: u32) -> firmware::control::controller::Output {
        let mut last = self.tick();
        for _ in 1..ticks {
            last = self.tick();
        }
        last
    }
}

/// One leg's feedback: joints at `positions_rad` (wire order), at rest, no effort.
pub fn leg_feedback(positions_rad: &[f32]) -> LegFeedback {
    let mut position = [Angle::saturating_from_si(0.0); 4];
    for (slot, value) in position.iter_mut().zip(positions_rad) {
        *slot = Angle::saturating_from_si(*value);
    }
    LegFeedback {
        position,
        velocity: [JointVelocity::saturating_from_si(0.0); 4],
        effort: [Torque::saturating_from_si(0.0); 4],
    }
}

/// The wheel drive's feedback with both wheels at rest.
pub fn wheels_at_rest() -> AnyMessage {
    wheels_at(0.0)
}

/// The wheel drive's feedback with both wheels turning at `rate_rad_s`.
pub fn wheels_at(rate_rad_s: f32) -> AnyMessage {
    AnyMessage::WheelFeedback(WheelFeedback {
        velocity: [WheelVelocity::saturating_from_si(rate_rad_s); 2],
        effort: [Torque::saturating_from_si(0.0); 2],
    })
}

/// The wheel rate of an ideal plant that rolls at the balance law's speed reference, rad/s:
/// its wheels do what the law asks, so the stall and runaway detector stays quiet.
pub fn following_wheels_rad_s(controller: &firmware::Controller) -> f32 {
    let r = controller.config().balance.wheel_radius_m;
    controller.balance().velocity_ref_m_s() / r
}

/// An IMU sample of a torso pitched by `pitch_rad` (nose down), still, in 1 g: the specific
/// force points up, `g (−sin θ, 0, cos θ)` in the body frame.
pub fn imu(pitch_rad: f32) -> Imu {
    let g = 9.806_65;
    Imu {
        angular_rate: [AngularRate::saturating_from_si(0.0); 3],
        acceleration: [-g * pitch_rad.sin(), 0.0, g * pitch_rad.cos()]
            .map(Acceleration::saturating_from_si),
    }
}

/// One tick of an ideal plant's feedback: the four legs at `joints_rad`, the wheels at rest,
/// the torso level.
pub fn plant_feedback(joints_rad: &Joints<f32>) -> Vec<AnyMessage> {
    plant_feedback_rolling(joints_rad, 0.0)
}

/// [`plant_feedback`] with the wheels turning at `wheel_rate_rad_s`.
pub fn plant_feedback_rolling(joints_rad: &Joints<f32>, wheel_rate_rad_s: f32) -> Vec<AnyMessage> {
    let mut messages: Vec<AnyMessage> = joints_rad
        .iter_legs()
        .map(|(leg, angles_rad)| AnyMessage::LegFeedback(leg, leg_feedback(angles_rad)))
        .collect();
    messages.push(wheels_at(wheel_rate_rad_s));
    messages.push(AnyMessage::Imu(imu(0.0)));
    messages
}

/// The operator asking for `mode` at `speed_m_s` and `yaw_rate_rad_s` (drive, walk, steering).
pub fn velocity_command(mode: TeleopMode, speed_m_s: f32, yaw_rate_rad_s: f32) -> AnyMessage {
    AnyMessage::TeleopCommand(TeleopCommand {
        mode,
        body_height: BodyHeight::saturating_from_si(0.0),
        speed_scale: SpeedScale::from_raw(100).unwrap(),
        speed: protocol::GroundSpeed::saturating_from_si(speed_m_s),
        yaw_rate: protocol::YawRate::saturating_from_si(yaw_rate_rad_s),
    })
}

/// The operator asking for `mode` at nominal height and full speed.
pub fn command(mode: TeleopMode) -> AnyMessage {
    AnyMessage::TeleopCommand(TeleopCommand {
        mode,
        body_height: BodyHeight::saturating_from_si(0.0),
        speed_scale: SpeedScale::from_raw(100).unwrap(),
        speed: Default::default(),
        yaw_rate: Default::default(),
    })
}
