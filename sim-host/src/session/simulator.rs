//! The simulated robot: MuJoCo physics plus the emulated CAN nodes, advanced one control cycle
//! at a time. Bus- and clock-agnostic: [`crate::clock::lockstep`] and [`crate::clock::wall`]
//! move frames between it and a [`host_can::bus::Bus`].

use std::path::Path;

use protocol::{AnyMessage, EncodeError, Frame, Joints, Key, MessageId, Sync, Tick, TEST_KEY};

use crate::robot::link::NodeLink;

use crate::output::telemetry::TelemetryRow;
use crate::robot::hardware::{FramesDue, Hardware};
use crate::robot::model::ModelError;
use crate::robot::physics::Physics;
use crate::robot::plant::Plant;

/// How the simulation starts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StartPose {
    /// Torso centre height, m.
    pub height_m: f64,
    /// Leg joint angles, rad.
    pub leg_joint_rad: Joints<f64>,
    /// The torso's heading, rad about the vertical (0: facing +x, along the scenes' path,
    /// square to their obstacles; + turned left).
    pub heading_rad: f64,
}

impl StartPose {
    /// Standing on the firmware's nominal stance (feet 0.35 m below the hips), feet just on the
    /// ground.
    pub fn standing() -> Self {
        let config = firmware::config::Config::ROBOT;
        let posture = config.posture;
        let depth_m = posture.depth_nominal_m;
        let leg = posture
            .stance(&config.geometry, &config.limits, depth_m)
            .map(|j| j.to_array())
            .unwrap_or([0.0; 4]);
        Self {
            height_m: f64::from(depth_m) + FOOT_RADIUS_M,
            leg_joint_rad: Joints::from_leg_fn(|_| leg.map(f64::from)),
            heading_rad: 0.0,
        }
    }

    /// This pose turned to `heading_rad`: the scene's obstacles met at that angle.
    pub fn turned(self, heading_rad: f64) -> Self {
        Self {
            heading_rad,
            ..self
        }
    }
}

/// Foot sphere radius in the model, m.
pub const FOOT_RADIUS_M: f64 = 0.035;

/// The simulated robot.
#[derive(Debug)]
pub struct Simulator {
    physics: Physics,
    hardware: Hardware,
    steps_per_cycle: u32,
    cycle_us: u64,
    cycle: u32,
    now_us: u64,
    /// The simulator's clock as a bus node: it sends SYNC in the controller's session.
    clock: NodeLink,
    plant: Plant,
}

impl Simulator {
    /// Loads `model`, places the robot at `start` and sets the nodes up for a controller at
    /// `control_hz`, with the simulation's test key. The model's timestep must divide the
    /// control period.
    pub fn new(
        model: &Path,
        control_hz: u32,
        start: StartPose,
        plant: Plant,
    ) -> Result<Self, ModelError> {
        Self::with_key(model, control_hz, start, plant, TEST_KEY)
    }

    /// As [`Simulator::new`], every node joining the sessions it hears with `key`.
    pub fn with_key(
        model: &Path,
        control_hz: u32,
        start: StartPose,
        plant: Plant,
        key: Key,
    ) -> Result<Self, ModelError> {
        let mut physics = Physics::load_varied(model, &plant.variation)?;
        let timestep_s = physics.timestep_s();
        let period_s = 1.0 / f64::from(control_hz.max(1));
        let ratio = period_s / timestep_s;
        let steps = ratio.round();
        if !(1.0..=1000.0).contains(&steps) || (ratio - steps).abs() > 1e-6 {
            return Err(ModelError::Timestep {
                path: model.to_owned(),
                timestep_s,
                period_s,
            });
        }
        physics.place(start.height_m, &start.leg_joint_rad, start.heading_rad);
        let hardware = Hardware::new(control_hz, plant, &physics.layout().leg_range_rad, key);
        Ok(Self {
            physics,
            hardware,
            steps_per_cycle: steps as u32,
            cycle_us: (period_s * 1e6).round() as u64,
            cycle: 0,
            now_us: 0,
            clock: NodeLink::new(key),
            plant,
        })
    }

    /// The parts it emulates.
    pub fn plant(&self) -> &Plant {
        &self.plant
    }

    /// The physics (ground truth).
    pub fn physics(&self) -> &Physics {
        &self.physics
    }

    /// The emulated nodes.
    pub fn hardware(&self) -> &Hardware {
        &self.hardware
    }

    /// The control cycle about to run.
    pub fn cycle(&self) -> u32 {
        self.cycle
    }

    /// Simulation time, µs (integer, so that long runs do not drift).
    pub fn now_us(&self) -> u64 {
        self.now_us
    }

    /// Simulation time, s.
    pub fn time_s(&self) -> f64 {
        self.now_us as f64 * 1e-6
    }

    /// Hands a received frame to the nodes.
    pub fn receive(&mut self, frame: &Frame) {
        self.hardware.on_frame(self.now_us, frame);
        if frame.id() == MessageId::Announce.raw() {
            // A refused announcement is counted by the clock's link; nothing else to do.
            let _ = self.clock.receive(frame.id(), frame.data());
        }
    }

    /// Whether the simulator's clock has joined the controller's session: in lockstep, no
    /// SYNC goes out before (the controller announces its session at start).
    pub fn joined(&self) -> bool {
        self.clock.joined()
    }

    /// The lockstep SYNC frame of this cycle: the tick the controller should compute; `None`
    /// before the controller's session is joined.
    pub fn sync_frame(&mut self) -> Result<Option<Frame>, EncodeError> {
        let sync = AnyMessage::Sync(Sync {
            tick: Tick::from_raw(self.cycle).unwrap_or(Tick::saturating_from_si(0.0)),
        });
        self.clock.seal(&sync)
    }

    /// The frames the nodes send at the start of this cycle (feedback, IMU, status).
    pub fn frames_due(&mut self) -> Result<FramesDue, EncodeError> {
        self.hardware
            .frames_due(self.now_us, self.cycle, &self.physics)
    }

    /// Applies the drives' commands and steps the physics through one control period.
    pub fn advance(&mut self) {
        self.hardware.apply(self.now_us, &mut self.physics);
        for _ in 0..self.steps_per_cycle {
            self.physics.step();
        }
        self.cycle = self.cycle.wrapping_add(1);
        self.now_us += self.cycle_us;
    }

    /// Telemetry of the current state.
    pub fn telemetry(&self) -> TelemetryRow {
        let torso = self.physics.torso();
        TelemetryRow {
            time_s: self.time_s(),
            torso_pos_m: torso.pos_m,
            torso_rpy_deg: torso.rpy_rad().map(f64::to_degrees),
            leg_joint_rad: self.physics.leg_positions_rad(),
            wheel_torque_nm: self.hardware.wheel_torque_nm(),
            wheel_speed_rad_s: self.physics.wheel_velocities_rad_s(),
            foot_force_n: self.physics.foot_forces_n(),
            body_contact: self.physics.ground_contacts().other,
            mode: self.hardware.controller_mode(),
        }
    }
}
