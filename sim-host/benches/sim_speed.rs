//! Simulation speed: raw MuJoCo steps of the robot model, and full closed-loop cycles (SYNC and
//! feedback encoded, the firmware's control core decoding them and computing its commands, the
//! drives decoding those, one MuJoCo step) on the in-process bus. `cargo xtask bench` prints
//! both as steps per second.

use std::path::Path;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion};
use host_can::bus::Bus;
use host_can::inproc_bus::InprocBus;
use protocol::{Epoch, Session, TeleopMode, TEST_KEY};
use sim_host::clock::lockstep::{self, LockstepOptions};
use sim_host::output::recorder::Recorder;
use sim_host::robot::model::DEFAULT_MODEL;
use sim_host::robot::physics::Physics;
use sim_host::robot::plant::Plant;
use sim_host::session::firmware_config;
use sim_host::session::inproc_controller::InprocController;
use sim_host::session::simulator::{Simulator, StartPose};
use teleop_core::scripted::{PlanStep, ScriptedTeleop};

fn raw_step(c: &mut Criterion) {
    let mut physics = Physics::load(Path::new(DEFAULT_MODEL)).expect("model");
    let start = StartPose::standing();
    physics.place(start.height_m, &start.leg_joint_rad, start.heading_rad);
    let mut steps = 0u32;
    c.bench_function("mujoco_step", |b| {
        b.iter(|| {
            // Restart now and then so that every sample measures a standing robot.
            steps += 1;
            if steps % 5_000 == 0 {
                physics.place(start.height_m, &start.leg_joint_rad, start.heading_rad);
            }
            physics.step();
        })
    });
}

fn closed_loop(c: &mut Criterion) {
    let start = StartPose::standing();
    let mut sim =
        Simulator::new(Path::new(DEFAULT_MODEL), 250, start, Plant::default()).expect("model");
    let bus = InprocBus::new();
    let mut sim_bus = bus.endpoint();
    let mut teleop_bus = bus.endpoint();
    let session = Session::owned(TEST_KEY, Epoch::new(1));
    let mut controller = InprocController::new(
        firmware_config(250).expect("250 Hz"),
        bus.endpoint(),
        session,
    )
    .expect("firmware");
    // Drive forward on the wheels: the balance loop, the IMU and the wheel drive all work. The
    // operator hears the controller's announcement and status, and arms it (STOP, then W).
    let mut teleop = ScriptedTeleop::new(vec![PlanStep {
        at_us: 0,
        mode: TeleopMode::WheelForward,
        body_height_m: 0.0,
        speed_scale_pct: 100.0,
        speed_m_s: 0.0,
        yaw_rate_rad_s: 0.0,
    }]);
    let mut recorder = Recorder::discarding();
    let options = LockstepOptions {
        cycles: 1,
        reply_timeout: Duration::ZERO,
        max_speed: None,
    };
    c.bench_function("closed_loop_cycle", |b| {
        b.iter(|| {
            lockstep::run(
                &mut sim,
                &mut sim_bus,
                &mut recorder,
                options,
                |cycle| {
                    while let Some(frame) = teleop_bus.recv(Duration::ZERO)? {
                        teleop.observe(&frame);
                    }
                    for frame in teleop.frames(u64::from(cycle) * 4_000)? {
                        teleop_bus.send(&frame)?;
                    }
                    controller.service()?;
                    Ok(())
                },
                |_, _| true,
            )
            .expect("cycle")
        })
    });
    assert!(teleop.armed(), "the operator never armed the controller");
    let state = controller.node().controller().state();
    assert!(
        matches!(state, firmware::control::fsm::State::Wheels(_)),
        "measured in {state:?}, not on the wheels"
    );
}

criterion_group!(benches, raw_step, closed_loop);
criterion_main!(benches);
