//! The `estop` bench's plant: the four leg drives, the wheel drive and the IMU, reduced to the
//! feedback the controller hears from them every 20 ms (an ideal servo, or fixed joints), and
//! what the operator sends on the same period (its heartbeat, its last command again).

use firmware::control::controller::Output;
use firmware::Config;
use protocol::{
    Acceleration, Angle, AngularRate, AnyMessage, Imu, JointVelocity, Joints, LegFeedback, Torque,
    WheelFeedback, WheelVelocity,
};

/// What the plant reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Feedback {
    /// Nothing (the drives and the IMU are silent).
    None,
    /// The joints where the enabled drives were last commanded (an ideal servo).
    Follow,
    /// Fixed joints.
    Fixed,
}

/// The drives and the IMU as the controller hears them, and the operator's habits.
#[derive(Debug, Clone, Copy)]
pub struct Plant {
    feedback: Feedback,
    joints_rad: Joints<f32>,
    wheel_rad_s: f32,
    pitch_rad: f32,
    /// Whether the operator sends its heartbeat every 20 ms.
    pub heartbeats: bool,
    /// Whether the operator sends its last command again every 20 ms.
    pub repeats: bool,
}

impl Plant {
    /// Silent drives and IMU, a silent operator.
    pub const SILENT: Plant = Plant {
        feedback: Feedback::None,
        joints_rad: Joints::splat(0.0),
        wheel_rad_s: 0.0,
        pitch_rad: 0.0,
        heartbeats: false,
        repeats: false,
    };

    /// Sets what the plant reports and the operator repeats (see the script's `Plant`).
    pub fn set(&mut self, config: &Config, mode: u8, wheel: u8, pitch: u8) {
        self.heartbeats = mode & 4 != 0;
        self.repeats = mode & 8 != 0;
        self.feedback = match mode % 4 {
            0 => Feedback::None,
            1 => Feedback::Follow,
            _ => Feedback::Fixed,
        };
        if mode % 4 == 2 {
            let posture = &config.posture;
            let stance = posture
                .stance(&config.geometry, &config.limits, posture.depth_nominal_m)
                .map_or([0.0; 4], |joints| joints.to_array());
            self.joints_rad = Joints::from_leg_fn(|_| stance);
        } else if mode % 4 == 3 {
            let levelling = &config.levelling;
            self.joints_rad = levelling.family.pose(levelling.start_shift);
        }
        self.wheel_rad_s = f32::from(wheel as i8) * 0.05;
        self.pitch_rad = f32::from(pitch as i8) * 0.5_f32.to_radians();
    }

    /// Takes a tick's commands: an ideal servo's joints go where the enabled drives were sent.
    pub fn observe(&mut self, output: &Output) {
        if self.feedback == Feedback::Follow && output.legs_enabled {
            self.joints_rad = output.leg_targets_rad;
        }
    }

    /// One round of feedback: four legs, the wheels, the IMU (none when silent).
    pub fn messages(&self) -> Vec<AnyMessage> {
        if self.feedback == Feedback::None {
            return Vec::new();
        }
        let mut messages: Vec<AnyMessage> = self
            .joints_rad
            .iter_legs()
            .map(|(leg, angles)| {
                let feedback = LegFeedback {
                    position: angles.map(Angle::saturating_from_si),
                    velocity: [JointVelocity::saturating_from_si(0.0); 4],
                    effort: [Torque::saturating_from_si(0.0); 4],
                };
                AnyMessage::LegFeedback(leg, feedback)
            })
            .collect();
        messages.push(AnyMessage::WheelFeedback(WheelFeedback {
            velocity: [WheelVelocity::saturating_from_si(self.wheel_rad_s); 2],
            effort: [Torque::saturating_from_si(0.0); 2],
        }));
        // Still, pitched by `pitch_rad`: the chip feels the specific force g (−sin θ, 0, cos θ).
        let g = 9.806_65;
        let (sin, cos) = (self.pitch_rad.sin(), self.pitch_rad.cos());
        messages.push(AnyMessage::Imu(Imu {
            angular_rate: [AngularRate::saturating_from_si(0.0); 3],
            acceleration: [-g * sin, 0.0, g * cos].map(Acceleration::saturating_from_si),
        }));
        messages
    }
}
