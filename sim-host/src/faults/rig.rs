//! The closed loop on the in-process bus in lockstep, with faults and the means to break its
//! peers: the simulator's bus connection goes through a [`FaultyBus`], the teleop's too (for a
//! flood), the firmware can be killed and the simulator restarted mid-run, and a tool can put
//! raw frames on the bus as `cansend` would. Each cycle leaves a [`CycleRecord`] of ground truth,
//! what the firmware decided and what the drives did, for the fault matrix to judge.

use std::path::{Path, PathBuf};
use std::time::Duration;

use firmware::control::fsm::State;
use host_can::bus::Bus;
use host_can::fault_plan::Faults;
use host_can::faulty_bus::{FaultStats, FaultyBus};
use host_can::inproc_bus::{InprocBus, InprocEndpoint};
use protocol::{
    Epoch, FaultFlags, Frame, Joints, PerDrive, RejectCause, RejectCounters, Session, TEST_KEY,
};
use teleop_core::scripted::{PlanStep, ScriptedTeleop};

use crate::clock::lockstep;
use crate::output::metrics::FALLEN_TILT_DEG;
use crate::output::recorder::Recorder;
use crate::robot::drive_core::{Authority, DriveCore};
use crate::robot::plant::Plant;
use crate::session::inproc_controller::InprocController;
use crate::session::run_stats::{RunError, RunStats};
use crate::session::simulator::{Simulator, StartPose};
use crate::session::{firmware_config, SessionError};

/// Control rate of the rig, Hz.
pub const RIG_HZ: u32 = 250;
/// One control period, µs.
pub const PERIOD_US: u64 = 1_000_000 / RIG_HZ as u64;
/// The rig's controller session (a rig is its own bus: no earlier session shares it).
pub const RIG_EPOCH: Epoch = Epoch::new(1);

/// One cycle of a rig run.
#[derive(Debug, Clone, PartialEq)]
pub struct CycleRecord {
    /// Rig time at the end of the cycle (does not restart with the simulator), µs.
    pub time_us: u64,
    /// Torso position, world frame, m.
    pub torso_pos_m: [f64; 3],
    /// Torso tilt from upright, degrees.
    pub tilt_deg: f64,
    /// Whether the torso touches the ground.
    pub torso_contact: bool,
    /// The firmware's state after its tick (`None`: firmware not running).
    pub state: Option<State>,
    /// The firmware's active faults.
    pub faults: FaultFlags,
    /// The firmware's leg targets, rad, and whether the legs are enabled.
    pub leg_targets_rad: Option<(Joints<f32>, bool)>,
    /// The firmware's wheel torques, N·m.
    pub wheel_torque_nm: Option<[f32; 2]>,
    /// Per drive: torque-free now.
    pub torque_off: PerDrive<bool>,
    /// Per drive: reporting a command timeout.
    pub timed_out: PerDrive<bool>,
    /// Per drive: E-stop latched.
    pub estop: PerDrive<bool>,
    /// Whether the controller's wheel command arrived this cycle (false in a cycle that did
    /// not step).
    pub commanded: bool,
    /// Whether the physics stepped this cycle: false until the simulator has joined the
    /// controller's session (heard its announcement), when nothing is sent and time stands
    /// still.
    pub stepped: bool,
}

impl CycleRecord {
    /// Fallen, as the run summaries judge it: tilted past [`FALLEN_TILT_DEG`] or the torso on
    /// the ground.
    pub fn fallen(&self) -> bool {
        self.tilt_deg > FALLEN_TILT_DEG || self.torso_contact
    }
}

/// A closed loop to break.
#[derive(Debug)]
pub struct Rig {
    model: PathBuf,
    /// How the robot starts, and starts again after a simulator restart.
    start: StartPose,
    sim: Simulator,
    sim_bus: FaultyBus<InprocEndpoint>,
    controller: Option<InprocController>,
    teleop: ScriptedTeleop,
    teleop_bus: FaultyBus<InprocEndpoint>,
    tool: InprocEndpoint,
    bus: InprocBus,
    recorder: Recorder,
    stats: RunStats,
    time_us: u64,
    records: Vec<CycleRecord>,
    /// The firmware's reject counters as last seen, and their totals without the wire's
    /// 16-bit wrap.
    seen: RejectCounters,
    rejected_total: [u64; RejectCause::ALL.len()],
}

impl Rig {
    /// The robot standing on `model`, the firmware on the bus, a teleop playing `plan` (times
    /// from the rig's start), the simulator's connection broken per `faults` and the teleop's
    /// per `teleop_faults`.
    pub fn new(
        model: &Path,
        plan: Vec<PlanStep>,
        faults: &Faults,
        teleop_faults: &Faults,
    ) -> Result<Self, SessionError> {
        Self::with_plant(model, plan, faults, teleop_faults, Plant::default())
    }

    /// As [`Rig::new`], on `plant` (drives, IMU, a varied body).
    pub fn with_plant(
        model: &Path,
        plan: Vec<PlanStep>,
        faults: &Faults,
        teleop_faults: &Faults,
        plant: Plant,
    ) -> Result<Self, SessionError> {
        let start = StartPose::standing();
        Self::with_start(model, plan, (faults, teleop_faults), plant, start)
    }

    /// As [`Rig::with_plant`], the robot starting at `start` (standing, turned to a heading).
    pub fn with_start(
        model: &Path,
        plan: Vec<PlanStep>,
        (faults, teleop_faults): (&Faults, &Faults),
        plant: Plant,
        start: StartPose,
    ) -> Result<Self, SessionError> {
        let sim = Simulator::new(model, RIG_HZ, start, plant)?;
        let bus = InprocBus::new();
        let sim_bus = FaultyBus::new(bus.endpoint(), &plant.link_faults(faults));
        let firmware = firmware_config(RIG_HZ).ok_or(SessionError::ControlRate(RIG_HZ))?;
        let session = Session::owned(TEST_KEY, RIG_EPOCH);
        let controller = InprocController::new(firmware, bus.endpoint(), session)
            .map_err(SessionError::Firmware)?;
        let teleop_bus = FaultyBus::new(bus.endpoint(), teleop_faults);
        let tool = bus.transmitter();
        Ok(Self {
            bus,
            model: model.to_owned(),
            start,
            sim,
            sim_bus,
            controller: Some(controller),
            teleop: ScriptedTeleop::new(plan),
            teleop_bus,
            tool,
            recorder: Recorder::discarding(),
            stats: RunStats::default(),
            time_us: 0,
            records: Vec::new(),
            seen: RejectCounters::default(),
            rejected_total: [0; RejectCause::ALL.len()],
        })
    }

    /// A release of the controller's present latch from `from`, sealed with the key as a
    /// keyholder's tool (`cargo xtask frame`) would, its counter the session time; `None` once
    /// the controller is gone.
    pub fn release_frame(&self, from: protocol::NodeId) -> Option<Frame> {
        let node = self.controller.as_ref()?.node();
        let release =
            protocol::AnyMessage::EStop(protocol::EStop::release(from, node.release_token()));
        let session = node.session();
        release.encode(session, session.time().ms()).ok()
    }

    /// Restarts the firmware as a new process would: a new node opening session `epoch` on the
    /// same bus (its latch, if the old one had one, is not carried over: a board that persists
    /// it restores it itself).
    pub fn restart_firmware(&mut self, epoch: Epoch) -> Result<(), SessionError> {
        let firmware = firmware_config(RIG_HZ).ok_or(SessionError::ControlRate(RIG_HZ))?;
        let session = Session::owned(TEST_KEY, epoch);
        self.controller = Some(
            InprocController::new(firmware, self.bus.endpoint(), session)
                .map_err(SessionError::Firmware)?,
        );
        Ok(())
    }

    /// Runs one control cycle.
    pub fn step(&mut self) -> Result<(), RunError> {
        let missed_before = self.stats.missed_cycles;
        let now_us = self.time_us;
        let teleop = &mut self.teleop;
        let teleop_bus = &mut self.teleop_bus;
        let controller = &mut self.controller;
        let mut peers = |_cycle: u32| -> Result<(), RunError> {
            while let Some(frame) = teleop_bus.recv(Duration::ZERO)? {
                teleop.observe(&frame);
            }
            for frame in teleop.frames(now_us)? {
                teleop_bus.send(&frame)?;
            }
            teleop_bus.end_cycle()?;
            if let Some(controller) = controller.as_mut() {
                controller.service()?;
            }
            Ok(())
        };
        let stepped = lockstep::cycle(
            &mut self.sim,
            &mut self.sim_bus,
            &mut self.recorder,
            &mut self.stats,
            Duration::ZERO,
            &mut peers,
        )?;
        self.time_us += PERIOD_US;
        self.count_rejections();
        let record = self.record(
            stepped,
            stepped && self.stats.missed_cycles == missed_before,
        );
        self.records.push(record);
        Ok(())
    }

    /// Runs until rig time `until_s`.
    pub fn run_until(&mut self, until_s: f64) -> Result<(), RunError> {
        let until_us = (until_s * 1e6).round() as u64;
        while self.time_us < until_us {
            self.step()?;
        }
        Ok(())
    }

    /// Adds this cycle's rejections to the totals (a cycle never brings 65,536 of one cause).
    fn count_rejections(&mut self) {
        let now = self.firmware_counters();
        for (cause, total) in RejectCause::ALL.iter().zip(self.rejected_total.iter_mut()) {
            let delta = now
                .get(*cause)
                .raw()
                .wrapping_sub(self.seen.get(*cause).raw());
            *total += u64::from(delta);
        }
        self.seen = now;
    }

    /// Frames the firmware refused for `cause` since the start (not wrapped at 16 bits like
    /// the counters on the wire).
    pub fn firmware_rejected(&self, cause: RejectCause) -> u64 {
        RejectCause::ALL
            .iter()
            .position(|c| *c == cause)
            .and_then(|i| self.rejected_total.get(i))
            .copied()
            .unwrap_or(0)
    }

    fn record(&self, stepped: bool, commanded: bool) -> CycleRecord {
        let physics = self.sim.physics();
        let torso = physics.torso();
        let now_us = self.sim.now_us();
        let hardware = self.sim.hardware();
        let cores = PerDrive::new([
            hardware.legs()[0].core(),
            hardware.legs()[1].core(),
            hardware.legs()[2].core(),
            hardware.legs()[3].core(),
            hardware.wheel().core(),
        ]);
        let output = self.controller.as_ref().and_then(|c| c.last_output());
        CycleRecord {
            time_us: self.time_us,
            torso_pos_m: torso.pos_m,
            tilt_deg: torso.tilt_rad().to_degrees(),
            torso_contact: physics.ground_contacts().torso,
            state: self
                .controller
                .as_ref()
                .map(|c| c.node().controller().state()),
            faults: output.map_or(FaultFlags::EMPTY, |o| o.status.faults),
            leg_targets_rad: output.map(|o| (o.leg_targets_rad, o.legs_enabled)),
            wheel_torque_nm: output.map(|o| o.wheel_torque_nm),
            torque_off: cores.map(|c| c.authority(now_us) == Authority::TorqueOff),
            timed_out: cores.map(|c| c.timed_out(now_us)),
            estop: cores.map(DriveCore::estop),
            commanded,
            stepped,
        }
    }

    /// Stops the firmware as if its process died: no more frames from it, no goodbye.
    pub fn kill_firmware(&mut self) {
        self.controller = None;
    }

    /// Replaces the simulator with a fresh one (robot standing at the origin, new counters, SYNC
    /// from tick 0) on the same bus, as when the simulator process is restarted.
    pub fn restart_simulator(&mut self) -> Result<(), SessionError> {
        // (The firmware keeps running: its counters go on.)
        let plant = *self.sim.plant();
        self.sim = Simulator::new(&self.model, RIG_HZ, self.start, plant)?;
        Ok(())
    }

    /// A listener on the bus from now on, as `candump` is: it hears every frame of every node.
    pub fn tap(&self) -> InprocEndpoint {
        self.bus.endpoint()
    }

    /// Puts `frame` on the bus from outside, as `cansend` does.
    pub fn tool_send(&mut self, frame: &Frame) -> Result<(), RunError> {
        Ok(self.tool.send(frame)?)
    }

    /// Changes the faults on the simulator's connection from now on (the plant's transport
    /// delay stays).
    pub fn set_faults(&mut self, faults: &Faults) {
        self.sim_bus
            .set_faults(&self.sim.plant().link_faults(faults));
    }

    /// Every cycle so far.
    pub fn records(&self) -> &[CycleRecord] {
        &self.records
    }

    /// The firmware (`None` once killed).
    pub fn controller(&self) -> Option<&InprocController> {
        self.controller.as_ref()
    }

    /// The firmware's reject counters (zero once killed).
    pub fn firmware_counters(&self) -> RejectCounters {
        self.controller
            .as_ref()
            .map(|c| *c.node().reject_counters())
            .unwrap_or_default()
    }

    /// The simulator.
    pub fn sim(&self) -> &Simulator {
        &self.sim
    }

    /// What the faults did to the simulator's feedback (`tx`) and to the commands (`rx`).
    pub fn fault_stats(&self) -> [FaultStats; 2] {
        [self.sim_bus.tx_stats(), self.sim_bus.rx_stats()]
    }

    /// The simulator's faulty connection (per-id counts of bad frames).
    pub fn sim_bus(&self) -> &FaultyBus<InprocEndpoint> {
        &self.sim_bus
    }

    /// What the teleop's faults did (the flood).
    pub fn teleop_fault_stats(&self) -> FaultStats {
        self.teleop_bus.tx_stats()
    }

    /// Lockstep counters (cycles, missed cycles).
    pub fn stats(&self) -> &RunStats {
        &self.stats
    }

    /// Rig time, s.
    pub fn time_s(&self) -> f64 {
        self.time_us as f64 * 1e-6
    }
}
