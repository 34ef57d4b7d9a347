//! Records what the firmware receives in a closed-loop run, for the processor-in-the-loop test
//! (`cargo xtask pil --record` runs this and compresses the result into
//! `firmware/pil/recording.pil`).
//!
//! The closed loop is the simulator's in-process one (MuJoCo, the emulated drives and IMU, a
//! scripted operator), with the firmware's `Node` stepped here so that every frame it is given
//! is written down with the tick it belongs to. The plan: stand, trot forward (L), then W —
//! which folds the legs, catches the robot on its wheels and drives off balancing.
//!
//! Output (the "raw" format the PIL image reads): `PIL1`, control rate u16, first tick u32,
//! tick count u32, then per tick: frame count u8 and per frame id u16, length u8, data. All
//! little-endian.
//!
//! ```sh
//! cargo run --release -p sim-host --example pil_record -- OUT.raw [SECONDS]
//! ```

use std::time::Duration;

use firmware::node::Node;
use firmware::time::Tick;
use host_can::bus::Bus;
use host_can::inproc_bus::InprocBus;
use protocol::TeleopMode;
use sim_host::clock::lockstep::{self, LockstepOptions};
use sim_host::output::recorder::Recorder;
use sim_host::robot::imu::ImuNoise;
use sim_host::robot::model::DEFAULT_MODEL;
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
    };
    let plan = vec![
        step(0.0, TeleopMode::Stand),
        step(0.2, TeleopMode::TrotForward),
        step(2.6, TeleopMode::WheelForward),
    ];
    let mut sim = Simulator::new(
        DEFAULT_MODEL.as_ref(),
        CONTROL_HZ,
        StartPose::standing(),
        ImuNoise::default(),
    )?;
    let config = firmware_config(CONTROL_HZ).ok_or("control rate")?;
    let mut node = Node::new(config).map_err(|e| format!("{e:?}"))?;
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
        for frame in teleop.frames(u64::from(cycle) * period_us)? {
            teleop_bus.send(&frame)?;
        }
        let now = Tick(cycle);
        let mut received = Vec::new();
        while let Some(frame) = controller_bus.recv(Duration::ZERO)? {
            received.push((frame.id(), frame.data().to_vec()));
            let _ = node.on_frame(now, frame.id(), frame.data());
        }
        let (output, frames) = node.poll(now);
        modes.push(output.status.mode);
        for frame in &frames {
            controller_bus.send(frame)?;
        }
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
    let mut bytes = Vec::new();
    bytes.extend_from_slice(b"PIL1");
    bytes.extend_from_slice(&u16::try_from(CONTROL_HZ)?.to_le_bytes());
    bytes.extend_from_slice(&0_u32.to_le_bytes());
    bytes.extend_from_slice(&u32::try_from(ticks.len())?.to_le_bytes());
    for frames in &ticks {
        bytes.push(u8::try_from(frames.len())?);
        for (id, data) in frames {
            bytes.extend_from_slice(&id.to_le_bytes());
            bytes.push(u8::try_from(data.len())?);
            bytes.extend_from_slice(data);
        }
    }
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
        ticks.len(),
        ticks.iter().map(Vec::len).sum::<usize>(),
        bytes.len(),
        stats.missed_cycles
    );
    Ok(())
}
