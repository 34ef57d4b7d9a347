//! A controller on an ideal plant (every drive reaches its target at once, the torso stays
//! level, the operator's heartbeat arrives every 5 ticks), for the step-by-step tests.

use firmware::control::controller::Output;
use firmware::control::fsm::State;
use firmware::{Config, Controller, Tick};
use protocol::{
    AnyMessage, EStop, EStopAction, Joints, NodeId, ReleaseToken, TeleopHeartbeat, TeleopMode,
};

use super::{command, imu, leg_feedback, Ticks};

pub const CONFIG: Config = Config::ROBOT;

/// A plant whose drives reach their targets at once and whose torso stays level.
pub struct Bench {
    pub controller: Controller,
    pub now: u32,
    pub joints_rad: Joints<f32>,
    pub drives_alive: bool,
    pub imu_alive: bool,
    pub teleop_alive: bool,
    pub pitch_rad: f32,
}

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
        if self.imu_alive {
            self.controller
                .on_message(now, &AnyMessage::Imu(imu(self.pitch_rad)));
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
