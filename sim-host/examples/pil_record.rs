//! Records what the firmware receives in a closed-loop run, for the processor-in-the-loop test
//! (`cargo xtask pil --record` runs this and compresses the result into
//! `firmware/pil/recording.pil`).
//!
//! The closed loop is the simulator's in-process one (MuJoCo, the emulated drives and IMU, a
//! scripted operator), with the firmware's `Node` stepped here so that every frame it is given
//! is written down with the tick it belongs to. The plan: stand, trot forward (L), then W —
//! which folds the legs, catches the robot on its wheels and drives off balancing — both
//! steered left at 0.3 rad/s.
//!
//! Output: `pil-format`'s raw format (the one the PIL image reads).
//!
//! ```sh
//! cargo run --release -p sim-host --example pil_record -- OUT.raw [SECONDS]
//! ```

use std::time::Duration;

use firmware::node::service::{self, Drain};
use firmware::node::Node;
use firmware::time::Tick;
use host_can::bus::{Bus, BusError};
use host_can::inproc_bus::InprocBus;
use host_can::port::{BusPort, Wait};
use pil_format::Recording;
use protocol::{Epoch, Session, TeleopMode, TEST_KEY};
use sim_host::clock::lockstep::{self, LockstepOptions};
use sim_host::output::recorder::Recorder;
use sim_host::robot::model::DEFAULT_MODEL;
use sim_host::robot::plant::Plant;
use sim_host::session::firmware_config;
use sim_host::session::run_stats::RunError;
use sim_host::session::simulator::{Simulator, StartPose};
use teleop_core::scripted::{PlanStep, ScriptedTeleop};

const CONTROL_HZ: u32 = 250;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let out = args.next().ok_or("usage: pil_record OUT.raw [SECONDS]")?;
    let seconds: f64 = args.next().map_or(Ok(6.0), |s| s.parse())?;
    let step = |at_s: f64, mode| PlanStep {
        at_us: (at_s * 1e6) as u64,
        mode,
        body_height_m: 0.0,
        speed_scale_pct: 100.0,
        speed_m_s: 0.0,
        yaw_rate_rad_s: 0.0,
    };
    let plan = vec![
        step(0.0, TeleopMode::Stand),
        // Steered: the turning trot's strides and the wheels' curve are the dearer paths.
        step(0.2, TeleopMode::TrotForward).with_velocity(0.0, 0.3),
        step(2.6, TeleopMode::WheelForward).with_velocity(0.0, 0.3),
    ];
    let mut sim = Simulator::new(
        DEFAULT_MODEL.as_ref(),
        CONTROL_HZ,
        StartPose::standing(),
        Plant::default(),
    )?;
    let config = firmware_config(CONTROL_HZ).ok_or("control rate")?;
    let session = Session::owned(TEST_KEY, Epoch::new(pil_format::PIL_EPOCH));
    let mut node = Node::new(config, session).map_err(|e| format!("{e:?}"))?;
    let bus = InprocBus::new();
    let mut sim_bus = bus.endpoint();
    let mut controller_bus = bus.endpoint();
    let mut teleop_bus = bus.endpoint();
    let mut teleop = ScriptedTeleop::new(plan);
    let period_us = 1_000_000 / u64::from(CONTROL_HZ);
    let cycles = (seconds * f64::from(CONTROL_HZ)).round() as u64;

    let mut ticks: Vec<Vec<(u16, Vec<u8>)>> = Vec::new();
    let mut modes = Vec::new();
    let peers = |cycle: u32| -> Result<(), RunError> {
        while let Some(frame) = teleop_bus.recv(std::time::Duration::ZERO)? {
            teleop.observe(&frame);
        }
        for frame in teleop.frames(u64::from(cycle) * period_us)? {
            teleop_bus.send(&frame)?;
        }
        let now = Tick(cycle);
        // The firmware's own service loop, on a port that writes down what it hands over.
        let mut recording = Recorded {
            bus: &mut controller_bus,
            received: Vec::new(),
        };
        let mut port = BusPort::new(&mut recording, Wait::Never);
        service::receive(&mut node, now, &mut port, Drain::All, u32::MAX)?;
        let sent = service::transmit(&mut node, now, &mut port)?;
        modes.push(sent.output.status.mode);
        let received = recording.received;
        ticks.push(received);
        Ok(())
    };
    let stats = lockstep::run(
        &mut sim,
        &mut sim_bus,
        &mut Recorder::discarding(),
        LockstepOptions {
            cycles,
            reply_timeout: Duration::from_secs(1),
            max_speed: None,
        },
        peers,
        |_, _| true,
    )?;
    let recording = Recording {
        control_hz: u16::try_from(CONTROL_HZ)?,
        first_tick: 0,
        ticks,
    };
    let bytes = recording.to_raw()?;
    std::fs::write(&out, &bytes)?;
    // Where the controller's mode changed, to show what the recording covers.
    let mut changes = String::new();
    let mut last = None;
    for (tick, mode) in modes.iter().enumerate() {
        if last != Some(mode) {
            changes.push_str(&format!(
                " {:.2}s:{mode:?}",
                tick as f64 / f64::from(CONTROL_HZ)
            ));
            last = Some(mode);
        }
    }
    eprintln!(
        "pil_record: {} ticks, {} frames, {} bytes raw, missed cycles {}; modes:{changes}",
        recording.ticks.len(),
        recording.ticks.iter().map(Vec::len).sum::<usize>(),
        bytes.len(),
        stats.missed_cycles
    );
    Ok(())
}

/// The controller's bus connection, writing down every frame it receives.
struct Recorded<'a, B: Bus> {
    bus: &'a mut B,
    received: Vec<(u16, Vec<u8>)>,
}

impl<B: Bus> Bus for Recorded<'_, B> {
    fn send(&mut self, frame: &protocol::Frame) -> Result<(), BusError> {
        self.bus.send(frame)
    }

    fn recv(&mut self, timeout: Duration) -> Result<Option<protocol::Frame>, BusError> {
        let frame = self.bus.recv(timeout)?;
        if let Some(frame) = &frame {
            self.received.push((frame.id(), frame.data().to_vec()));
        }
        Ok(frame)
    }

    fn name(&self) -> &str {
        self.bus.name()
    }
}
