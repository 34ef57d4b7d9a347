//! From the key to the actuators, and from a lost operator to STOP, with the simulated robot
//! and the firmware on the in-process bus. Lockstep is exact (simulated cycles); real time is
//! wall clock and is printed as `MEASURED` lines (timing goals live in figures, not asserts,
//! beyond a bound that only a broken path would miss).
#![cfg(feature = "sim")]

use std::time::{Duration, Instant};

use host_can::bus::Bus;
use host_can::inproc_bus::{InprocBus, InprocEndpoint};
use protocol::{
    decode_frame, AnyMessage, ControllerMode, DriveEnable, Epoch, FaultFlags, Frame, Joints,
    Session, TEST_KEY,
};
use sim_host::clock::lockstep::{self, LockstepOptions};
use sim_host::output::recorder::Recorder;
use sim_host::robot::plant::Plant;
use sim_host::session::firmware_config;
use sim_host::session::inproc_controller::InprocController;
use sim_host::session::simulator::{Simulator, StartPose};
use teleop::app::App;
use teleop::inproc::{InprocOptions, InprocRobot};
use teleop_core::keys::Key;

const PERIOD_MS: u64 = 4;

/// The leg targets in `frame`, if it is a LegTargets frame.
fn leg_targets(frame: &Frame) -> Option<(DriveEnable, Joints<f32>)> {
    match decode_frame(frame.id(), frame.data()).ok()?.message {
        AnyMessage::LegTargets(t) => Some((t.enable, t.position.map(|a| a.si()))),
        _ => None,
    }
}

fn changed(a: &Joints<f32>, b: &Joints<f32>) -> bool {
    a.iter().zip(b).any(|(x, y)| (x - y).abs() > 1e-4)
}

/// Runs the lockstep loop; at `press_cycle` the operator presses `key`. Returns the cycles from
/// the press to the first LegTargets that `reflects` it.
fn lockstep_latency(
    key: Key,
    reflects: impl Fn(&(DriveEnable, Joints<f32>), &Joints<f32>) -> bool,
) -> u32 {
    let press_cycle = 250;
    let mut sim = Simulator::new(
        std::path::Path::new(sim_host::robot::model::DEFAULT_MODEL),
        250,
        StartPose::standing(),
        Plant::default(),
    )
    .unwrap();
    let bus = InprocBus::new();
    let mut sim_bus = bus.endpoint();
    let session = Session::owned(TEST_KEY, Epoch::new(1));
    let mut controller =
        InprocController::new(firmware_config(250).unwrap(), bus.endpoint(), session).unwrap();
    let mut teleop_bus = bus.endpoint();
    let mut probe = bus.endpoint();
    let mut app = App::new("inproc");
    let mut before = None::<Joints<f32>>;
    let seen = std::cell::Cell::new(None);
    lockstep::run(
        &mut sim,
        &mut sim_bus,
        &mut Recorder::discarding(),
        LockstepOptions {
            cycles: 400,
            reply_timeout: Duration::from_secs(1),
            max_speed: None,
        },
        |cycle| {
            let now_ms = u64::from(cycle) * PERIOD_MS;
            if cycle == press_cycle {
                app.key(now_ms, key);
            }
            for frame in app.poll(now_ms).unwrap() {
                teleop_bus.send(&frame)?;
            }
            controller.service()?;
            // What the firmware sent in this control tick; the operator hears it too (the
            // announcement joins it to the session, after which it sends its STOP, and the
            // motion key acts).
            while let Some(frame) = probe.recv(Duration::ZERO)? {
                app.observe(now_ms, &frame);
                let Some(targets) = leg_targets(&frame) else {
                    continue;
                };
                if cycle < press_cycle {
                    before = Some(targets.1);
                } else if seen.get().is_none() && reflects(&targets, &before.unwrap()) {
                    seen.set(Some(cycle - press_cycle));
                }
            }
            Ok(())
        },
        |_, _| seen.get().is_none(),
    )
    .unwrap();
    seen.get().expect("no actuator frame reflected the key")
}

#[test]
fn in_lockstep_the_estop_key_acts_in_the_same_control_tick_and_the_fold_within_eight() {
    let estop = lockstep_latency(Key::Char(' '), |(enable, _), _| {
        *enable == DriveEnable::Disabled
    });
    let fold = lockstep_latency(Key::Char('f'), |(_, position), before| {
        changed(position, before)
    });
    println!("MEASURED lockstep key-to-actuator: E-stop {estop} cycles, F (fold) {fold} cycles (period 4 ms)");
    assert_eq!(estop, 0, "E-stop: the tick after the key disables the legs");
    // The fold starts in the tick of the key, from rest: its joint-space ramps begin with zero
    // rate (a smoothstep), so the targets first move by a wire count (1e-4 rad) a few ticks in.
    assert!(
        fold <= 8,
        "fold: the leg targets move within 8 ticks of the key ({fold})"
    );
}

/// Drains `bus` into `app` until `found` says yes or `limit` passes; the operator keeps its
/// heartbeat going meanwhile. Returns when it was found.
fn wait_for(
    bus: &mut InprocEndpoint,
    app: &mut App,
    start: Instant,
    limit: Duration,
    mut found: impl FnMut(&Frame) -> bool,
) -> Option<Instant> {
    let until = Instant::now() + limit;
    while Instant::now() < until {
        let now_ms = start.elapsed().as_millis() as u64;
        for frame in app.poll(now_ms).unwrap() {
            bus.send(&frame).unwrap();
        }
        while let Some(frame) = bus.recv(Duration::from_micros(500)).unwrap() {
            let seen = Instant::now();
            app.observe(now_ms, &frame);
            if found(&frame) {
                return Some(seen);
            }
        }
    }
    None
}

fn percentile(sorted: &[f64], p: f64) -> f64 {
    sorted[((sorted.len() - 1) as f64 * p).round() as usize]
}

#[test]
fn in_real_time_the_key_reaches_the_actuators_within_about_a_period() {
    let (robot, mut bus) = InprocRobot::start(InprocOptions::wall_clock());
    let start = Instant::now();
    let mut app = App::new("inproc");
    let settled = wait_for(
        &mut bus,
        &mut app,
        start,
        Duration::from_secs(10),
        |f| matches!(decode_frame(f.id(), f.data()).map(|d| d.message), Ok(AnyMessage::ControllerStatus(s)) if s.mode == ControllerMode::Stop),
    );
    assert!(settled.is_some(), "the controller never reported STOP");
    let mut latencies_ms = Vec::new();
    for n in 0..10 {
        let pressed = Instant::now();
        app.key(start.elapsed().as_millis() as u64, Key::Char(' '));
        let seen = wait_for(&mut bus, &mut app, start, Duration::from_secs(1), |f| {
            leg_targets(f).is_some_and(|(enable, _)| enable == DriveEnable::Disabled)
        })
        .unwrap_or_else(|| panic!("E-stop {n}: the legs were never disabled"));
        latencies_ms.push((seen - pressed).as_secs_f64() * 1e3);
        // Once the controller reports its E-stop (a release answers the latch it reports),
        // release (R R) and wait until the legs are enabled again.
        let reported = wait_for(
            &mut bus,
            &mut app,
            start,
            Duration::from_secs(1),
            |f| matches!(decode_frame(f.id(), f.data()).map(|d| d.message), Ok(AnyMessage::ControllerStatus(s)) if s.mode == ControllerMode::EStop),
        );
        assert!(reported.is_some(), "E-stop {n}: never reported");
        for _ in 0..2 {
            app.key(start.elapsed().as_millis() as u64, Key::Char('r'));
        }
        let enabled = wait_for(&mut bus, &mut app, start, Duration::from_secs(2), |f| {
            leg_targets(f).is_some_and(|(enable, _)| enable == DriveEnable::Enabled)
        });
        assert!(
            enabled.is_some(),
            "E-stop {n}: released but the legs stayed off"
        );
        // A little while on, at a random phase of the control period.
        wait_for(
            &mut bus,
            &mut app,
            start,
            Duration::from_millis(37 + 7 * n),
            |_| false,
        );
    }
    robot.finish().unwrap();
    latencies_ms.sort_by(f64::total_cmp);
    let (p50, max) = (
        percentile(&latencies_ms, 0.5),
        latencies_ms[latencies_ms.len() - 1],
    );
    println!(
        "MEASURED real-time key-to-actuator (E-stop to the first disabled LegTargets, 10 presses): p50 {p50:.2} ms, max {max:.2} ms (period {PERIOD_MS} ms)"
    );
    assert!(max < 100.0, "a key took {max:.1} ms to reach the actuators");
}

#[test]
fn when_the_operator_goes_silent_the_controller_stops_within_500_ms() {
    let (robot, mut bus) = InprocRobot::start(InprocOptions::wall_clock());
    let start = Instant::now();
    let mut app = App::new("inproc");
    // The controller starts interlocked: the operator's STOP (sent from the start) releases
    // it, then L.
    let armed = wait_for(
        &mut bus,
        &mut app,
        start,
        Duration::from_secs(10),
        |f| matches!(decode_frame(f.id(), f.data()).map(|d| d.message), Ok(AnyMessage::ControllerStatus(s)) if !s.faults.contains(FaultFlags::AWAITING_STOP)),
    );
    assert!(armed.is_some(), "the controller never left its interlock");
    app.key(start.elapsed().as_millis() as u64, Key::Char('l'));
    let trotting = wait_for(
        &mut bus,
        &mut app,
        start,
        Duration::from_secs(10),
        |f| matches!(decode_frame(f.id(), f.data()).map(|d| d.message), Ok(AnyMessage::ControllerStatus(s)) if s.mode == ControllerMode::TrotForward),
    );
    assert!(trotting.is_some(), "the robot never trotted");
    wait_for(
        &mut bus,
        &mut app,
        start,
        Duration::from_millis(500),
        |_| false,
    );
    // Teleop dies: its last heartbeat went out at most 20 ms ago; nothing more is sent.
    let now_ms = start.elapsed().as_millis() as u64;
    for frame in app.poll(now_ms).unwrap() {
        bus.send(&frame).unwrap();
    }
    let last_heartbeat =
        Instant::now() - Duration::from_millis(app.heartbeat_age_ms(now_ms).unwrap());
    let mut stopped = None;
    while last_heartbeat.elapsed() < Duration::from_secs(2) && stopped.is_none() {
        if let Some(frame) = bus.recv(Duration::from_millis(1)).unwrap() {
            if let Ok(AnyMessage::ControllerStatus(s)) =
                decode_frame(frame.id(), frame.data()).map(|d| d.message)
            {
                if s.faults.contains(FaultFlags::TELEOP_TIMEOUT) {
                    stopped = Some((Instant::now() - last_heartbeat, s.mode));
                }
            }
        }
    }
    robot.finish().unwrap();
    let (after, mode) = stopped.expect("the controller never reported the lost operator");
    println!(
        "MEASURED operator lost: the controller reported it {:.0} ms after the last heartbeat, mode {}",
        after.as_secs_f64() * 1e3,
        mode.label()
    );
    // The watchdog's 460 ms, then the next 50 Hz status frame says so.
    assert!(after <= Duration::from_millis(500), "{after:?}");
    assert!(
        after >= Duration::from_millis(455),
        "reported {after:?} after the last heartbeat: the operator was not lost yet"
    );
    assert!(
        !matches!(mode, ControllerMode::TrotForward),
        "still trotting: {mode:?}"
    );
}
