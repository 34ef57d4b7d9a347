//! A controller on an ideal plant (every drive reaches its target at once, the torso stays
//! level or turns as a gyro and an accelerometer report it, the operator's heartbeat arrives
//! every 5 ticks), for the step-by-step tests.

use firmware::control::controller::Output;
use firmware::control::fsm::{State, WheelMotion};
use firmware::{Config, Controller, Tick};
use protocol::{
    AngularRate, AnyMessage, EStop, EStopAction, Imu, Joints, NodeId, ReleaseToken,
    TeleopHeartbeat, TeleopMode,
};

use super::{command, imu, leg_feedback, Ticks};

pub const CONFIG: Config = Config::ROBOT;

/// A plant whose drives reach their targets at once and whose torso stays level, or turns to
/// `pitch_rad` at up to [`FALL_RAD_S`] as a gyro and an accelerometer would report it.
pub struct Bench {
    pub controller: Controller,
    pub now: u32,
    pub joints_rad: Joints<f32>,
    pub drives_alive: bool,
    pub imu_alive: bool,
    pub teleop_alive: bool,
    pub pitch_rad: f32,
    /// Where the torso is on its way to `pitch_rad`.
    pub torso_pitch_rad: f32,
}

/// How fast the bench's torso turns to a new pitch, rad/s (a fall).
pub const FALL_RAD_S: f32 = 10.0;

/// A latch, or a release (the controller takes any token: the node checks it).
pub fn estop(action: EStopAction) -> AnyMessage {
    AnyMessage::EStop(match action {
        EStopAction::Latch => EStop::latch(NodeId::Tool),
        EStopAction::Clear => EStop::release(NodeId::Tool, ReleaseToken::new(0)),
    })
}

impl Bench {
    pub fn new() -> Self {
        // Start on the legs, roughly standing.
        let joints = super::standing_joints_rad(&CONFIG);
        Self {
            controller: Controller::new(CONFIG).unwrap(),
            now: 0,
            joints_rad: joints,
            drives_alive: true,
            imu_alive: true,
            teleop_alive: true,
            pitch_rad: 0.0,
            torso_pitch_rad: 0.0,
        }
    }

    /// A bench run for 5 ticks whose operator has pressed X (STOP): the restart interlock is
    /// released and the next new key acts.
    pub fn ready() -> Self {
        let mut bench = Self::new();
        bench.run(5);
        bench.send(command(TeleopMode::Stop));
        bench
    }

    /// [`Bench::ready`], then folded onto the wheels and balancing in place.
    pub fn on_the_wheels() -> Self {
        let mut bench = Self::ready();
        bench.send(command(TeleopMode::Fold));
        bench.run(1_000);
        assert_eq!(bench.state(), State::Wheels(WheelMotion::Balance));
        bench
    }

    pub fn send(&mut self, message: AnyMessage) {
        self.controller.on_message(Tick(self.now), &message);
    }

    pub fn tick(&mut self) -> Output {
        let now = Tick(self.now);
        if self.drives_alive {
            for (leg, angles_rad) in self.joints_rad.iter_legs() {
                self.controller
                    .on_message(now, &AnyMessage::LegFeedback(leg, leg_feedback(angles_rad)));
            }
            let wheels_rad_s = super::following_wheels_rad_s(&self.controller);
            self.controller
                .on_message(now, &super::wheels_at(wheels_rad_s));
        }
        let dt_s = CONFIG.rate.period_s();
        let max_step = FALL_RAD_S * dt_s;
        let step = (self.pitch_rad - self.torso_pitch_rad).clamp(-max_step, max_step);
        self.torso_pitch_rad += step;
        if self.imu_alive {
            let sample = Imu {
                angular_rate: [0.0, step / dt_s, 0.0].map(AngularRate::saturating_from_si),
                ..imu(self.torso_pitch_rad)
            };
            self.controller.on_message(now, &AnyMessage::Imu(sample));
        }
        if self.teleop_alive && self.now % 5 == 0 {
            self.controller.on_message(
                now,
                &AnyMessage::TeleopHeartbeat(TeleopHeartbeat {
                    uptime: protocol::Millis::from_raw(self.now * 4).unwrap(),
                }),
            );
        }
        let output = self.controller.step(now);
        if output.legs_enabled {
            self.joints_rad = output.leg_targets_rad;
        }
        self.now += 1;
        output
    }

    pub fn state(&self) -> State {
        self.controller.state()
    }
}

impl Ticks for Bench {
    fn tick(&mut self) -> Output {
        Bench::tick(self)
    }
}

pub fn ms(ms: u32) -> u32 {
    CONFIG.rate.ticks_from_ms(ms)
}

pub fn torque_free(output: &Output) -> bool {
    !output.legs_enabled && output.wheel_torque_nm == [0.0, 0.0]
}
