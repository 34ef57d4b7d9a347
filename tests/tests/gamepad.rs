//! A gamepad session through the real input path: a virtual gamepad made with the kernel's
//! uinput, read by `teleop pad` through evdev, the firmware and the simulator as their own
//! processes on vcan, paced to real time. The pad drives (`drive` at the sticks' speed), curves,
//! E-stops, releases, drives again, and is unplugged.
//!
//! Needs `/dev/uinput` and evdev (the VM of `cargo xtask hil` loads both modules).

use std::path::Path;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use evdev::uinput::VirtualDevice;
use evdev::{
    AbsInfo, AbsoluteAxisCode, AttributeSet, EventType, InputEvent, KeyCode, UinputAbsSetup,
};
use hil_tests::{
    candump, find_in_log, firmware, one_at_a_time, out_dir, read_candump, start_sim, wait_for_log,
    Process, Vcan,
};
use protocol::{
    decode_frame, AnyMessage, ControllerMode, EStopAction, Frame, MessageId, TeleopMode,
};

/// A stick's travel on the virtual pad.
const STICK_MAX: i32 = 32_767;

/// A gamepad on uinput: the buttons and sticks the Linux gamepad API names.
struct VirtualPad {
    device: VirtualDevice,
}

impl VirtualPad {
    fn new() -> Self {
        assert!(
            Path::new("/dev/uinput").exists(),
            "no /dev/uinput: load the uinput module (the VM of `cargo xtask hil` does)"
        );
        let mut keys = AttributeSet::<KeyCode>::new();
        for key in [
            KeyCode::BTN_SOUTH,
            KeyCode::BTN_EAST,
            KeyCode::BTN_WEST,
            KeyCode::BTN_NORTH,
            KeyCode::BTN_TL,
            KeyCode::BTN_TR,
            KeyCode::BTN_START,
        ] {
            keys.insert(key);
        }
        let stick = AbsInfo::new(0, -STICK_MAX - 1, STICK_MAX, 16, 128, 0);
        let mut builder = VirtualDevice::builder()
            .unwrap()
            .name("hil virtual gamepad")
            .with_keys(&keys)
            .unwrap();
        for axis in [
            AbsoluteAxisCode::ABS_X,
            AbsoluteAxisCode::ABS_Y,
            AbsoluteAxisCode::ABS_RX,
            AbsoluteAxisCode::ABS_RY,
        ] {
            builder = builder
                .with_absolute_axis(&UinputAbsSetup::new(axis, stick))
                .unwrap();
        }
        Self {
            device: builder.build().unwrap(),
        }
    }

    /// The device node teleop reads.
    fn node(&mut self) -> String {
        let started = Instant::now();
        loop {
            if let Some(node) = self
                .device
                .enumerate_dev_nodes_blocking()
                .unwrap()
                .filter_map(Result::ok)
                .find(|p| p.to_string_lossy().contains("event"))
            {
                return node.display().to_string();
            }
            assert!(started.elapsed() < Duration::from_secs(5), "no event node");
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    /// Presses and releases `key`; returns when it went down (wall clock).
    fn press(&mut self, key: KeyCode) -> f64 {
        let at = wall_s();
        self.device
            .emit(&[InputEvent::new(EventType::KEY.0, key.0, 1)])
            .unwrap();
        std::thread::sleep(Duration::from_millis(50));
        self.device
            .emit(&[InputEvent::new(EventType::KEY.0, key.0, 0)])
            .unwrap();
        at
    }

    /// Moves a stick to `fraction` of its travel (+ right / down).
    fn stick(&mut self, axis: AbsoluteAxisCode, fraction: f64) {
        let value = (fraction * f64::from(STICK_MAX)).round() as i32;
        self.device
            .emit(&[InputEvent::new(EventType::ABSOLUTE.0, axis.0, value)])
            .unwrap();
    }
}

fn wall_s() -> f64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64())
}

fn message(frame: &Frame) -> Option<AnyMessage> {
    decode_frame(frame.id(), frame.data())
        .ok()
        .map(|d| d.message)
}

/// The controller's statuses in `frames`, with their times.
fn statuses(frames: &[(f64, Frame)]) -> Vec<(f64, ControllerMode)> {
    frames
        .iter()
        .filter_map(|(t, f)| match message(f) {
            Some(AnyMessage::ControllerStatus(s)) => Some((*t, s.mode)),
            _ => None,
        })
        .collect()
}

fn reports(log: &Path, mode: ControllerMode, after_s: f64, timeout: Duration) -> bool {
    reported_at(log, mode, after_s, timeout).is_some()
}

/// When (wall clock) the controller first reported `mode` after `after_s`.
fn reported_at(log: &Path, mode: ControllerMode, after_s: f64, timeout: Duration) -> Option<f64> {
    find_in_log(log, timeout, Duration::from_millis(20), |frames| {
        statuses(frames)
            .iter()
            .find(|&&(t, m)| t > after_s && m == mode)
            .map(|&(t, _)| t)
    })
}

/// The simulator's control period, s: one SYNC frame per cycle.
const CYCLE_S: f64 = 0.004;

/// Waits until the simulator has run `seconds` of its own time after wall time `after_s`
/// (counted in its SYNC frames). The simulator is paced to real time but falls behind it when
/// the emulator is loaded; timing the motion between two presses in simulated time puts the
/// robot where the test means it to be: at its steady speed, not still in the overshoot that
/// follows a start (docs/hil.md).
fn run_for_sim_s(log: &Path, after_s: f64, seconds: f64) {
    let cycles = (seconds / CYCLE_S).round() as usize;
    let sync = MessageId::Sync.raw();
    let timeout = Duration::from_secs_f64(30.0 + 20.0 * seconds);
    // Polled slowly: the wait shares the emulated CPUs with what it times.
    let ran = find_in_log(log, timeout, Duration::from_millis(250), |frames| {
        let synced = frames
            .iter()
            .filter(|(t, f)| *t > after_s && f.id() == sync);
        (synced.count() >= cycles).then_some(())
    });
    assert!(
        ran.is_some(),
        "the simulator did not run {seconds} s in {} s of wall time (is its --duration-s long \
         enough?)",
        timeout.as_secs_f64()
    );
}

/// `(time s, ground speed m/s)` from the simulator's telemetry: the wheels' mean rate
/// (relative to the body) and the body's pitch rate are close enough at rest and when
/// braking; the torso's position gives the speed more plainly.
fn torso_speeds(csv: &Path) -> Vec<(f64, f64, String)> {
    let text = std::fs::read_to_string(csv).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (t, x, y, mode) = (
        col("time_s"),
        col("torso_x_m"),
        col("torso_y_m"),
        col("mode"),
    );
    let rows: Vec<(f64, f64, f64, String)> = lines
        .map(|line| {
            let cells: Vec<&str> = line.split(',').collect();
            let num = |i: usize| cells[i].parse::<f64>().unwrap_or(f64::NAN);
            (num(t), num(x), num(y), cells[mode].to_owned())
        })
        .collect();
    rows.windows(5)
        .map(|w| {
            let (a, b) = (&w[0], &w[4]);
            let v = ((b.1 - a.1).hypot(b.2 - a.2)) / (b.0 - a.0);
            (b.0, v, b.3.clone())
        })
        .collect()
}

#[test]
fn a_gamepad_drives_curves_e_stops_releases_and_unplugging_it_stops_the_robot() {
    let _alone = one_at_a_time();
    let mut pad = VirtualPad::new();
    let node = pad.node();
    let bus = Vcan::new();
    let fw = firmware(&bus);
    let log = out_dir("gamepad-dump").with_extension("log");
    let dump = candump(&bus, &log);
    let out = out_dir("gamepad");
    let sim = start_sim(bus.name(), &out, &["--duration-s", "36", "--pace", "1"]);
    assert!(
        wait_for_log(&log, Duration::from_secs(120), |f| f
            .iter()
            .any(|(_, f)| f.id() == 0x400)),
        "the controller never reported"
    );
    let teleop = Process::start(
        "teleop",
        &[
            "--bus",
            bus.name(),
            "--gamepad",
            &node,
            "pad",
            "--for",
            "300",
        ],
    );
    // Teleop's STOP releases the controller's start-up interlock; then A: drive.
    assert!(wait_for_log(&log, Duration::from_secs(30), |f| f
        .iter()
        .any(|(_, f)| f.id() == 0x201)));
    std::thread::sleep(Duration::from_millis(300));
    let start = pad.press(KeyCode::BTN_SOUTH);
    let driving = reported_at(
        &log,
        ControllerMode::Driving,
        start,
        Duration::from_secs(30),
    )
    .expect("A did not put the robot on its wheels in drive");
    // Left stick 62.5 % up: 0.27 m/s; then the right stick half left: a curve.
    pad.stick(AbsoluteAxisCode::ABS_Y, -0.625);
    run_for_sim_s(&log, driving, 3.0);
    pad.stick(AbsoluteAxisCode::ABS_RX, -0.5);
    run_for_sim_s(&log, driving, 6.0);

    // The red button: the latch on the bus within a pass of teleop's loop.
    let pressed = pad.press(KeyCode::BTN_EAST);
    assert!(reports(
        &log,
        ControllerMode::EStop,
        pressed,
        Duration::from_secs(10)
    ));
    let frames = read_candump(&log);
    let latch_s = frames
        .iter()
        .find(|(t, f)| {
            *t >= pressed
                && matches!(message(f), Some(AnyMessage::EStop(e)) if e.action == EStopAction::Latch)
        })
        .map(|(t, _)| *t)
        .expect("the latch is on the bus");
    // Release: Start twice, after the controlled stop (2 s).
    run_for_sim_s(&log, latch_s, 2.5);
    pad.press(KeyCode::BTN_START);
    std::thread::sleep(Duration::from_millis(200));
    let released = pad.press(KeyCode::BTN_START);
    assert!(
        wait_for_log(&log, Duration::from_secs(10), |f| statuses(f)
            .iter()
            .any(|&(t, m)| t > released && m != ControllerMode::EStop)),
        "Start twice did not release the E-stop"
    );
    // X, then A and the stick again; then unplug the pad while driving.
    let stop = pad.press(KeyCode::BTN_WEST);
    std::thread::sleep(Duration::from_millis(300));
    pad.press(KeyCode::BTN_SOUTH);
    pad.stick(AbsoluteAxisCode::ABS_RX, 0.0);
    pad.stick(AbsoluteAxisCode::ABS_Y, -0.625);
    let driving = reported_at(&log, ControllerMode::Driving, stop, Duration::from_secs(30))
        .expect("A did not drive again after the release");
    run_for_sim_s(&log, driving, 4.0);
    let unplugged = wall_s();
    drop(pad);
    run_for_sim_s(&log, unplugged, 3.0);
    let _ = teleop.terminate();
    assert!(sim.wait(Duration::from_secs(300)).success());
    let _ = fw.terminate();
    let _ = dump.terminate();

    let frames = read_candump(&log);
    // Teleop's STOP after the unplug, and the controller's first status out of `Driving`.
    let stop_s = frames
        .iter()
        .find(|(t, f)| {
            *t >= unplugged
                && matches!(message(f), Some(AnyMessage::TeleopCommand(c)) if c.mode == TeleopMode::Stop)
        })
        .map(|(t, _)| *t)
        .expect("teleop said STOP when the pad went");
    let left_s = statuses(&frames)
        .iter()
        .find(|&&(t, m)| t >= unplugged && m != ControllerMode::Driving)
        .map(|&(t, _)| t)
        .expect("the controller left drive");
    let commands_after = frames
        .iter()
        .filter(|(t, f)| *t > stop_s + 0.001 && (f.id() == 0x200 || f.id() == 0x201))
        .count();
    // At rest: from the simulator's own record (simulated time, paced to the wall): the speed
    // when the STOP arrived, and when the torso was first still after it.
    let sim_frames = read_candump(&out.join("bus.log"));
    let sim_stop_s = sim_frames
        .iter()
        .rev()
        .find(|(_, f)| {
            matches!(message(f), Some(AnyMessage::TeleopCommand(c)) if c.mode == TeleopMode::Stop)
        })
        .map(|(t, _)| *t)
        .expect("the simulator heard the STOP");
    let speeds = torso_speeds(&out.join("telemetry.csv"));
    let v_at_stop = speeds
        .iter()
        .find(|(t, ..)| *t >= sim_stop_s)
        .map_or(f64::NAN, |s| s.1);
    let rest_s = speeds
        .iter()
        .find(|(t, v, _)| *t >= sim_stop_s && *v < 0.03)
        .map_or(f64::INFINITY, |s| s.0);
    println!(
        "MEASURED gamepad: E-stop latch on the bus {:.1} ms after the press; unplugged → STOP \
         {:.1} ms, controller out of drive {:.0} ms; {:.2} m/s at the STOP, at rest {:.0} ms \
         later (allowed {:.0} ms); {commands_after} operator frames after the STOP",
        (latch_s - pressed) * 1e3,
        (stop_s - unplugged) * 1e3,
        (left_s - unplugged) * 1e3,
        v_at_stop,
        (rest_s - sim_stop_s) * 1e3,
        (0.5 + v_at_stop / 0.8) * 1e3,
    );
    assert!(v_at_stop > 0.15, "was it driving? {v_at_stop} m/s");
    // Teleop's loop is 2 ms; the bound leaves room for an emulated CPU that the host has
    // taken away for a while (16 ms seen with the host's two cores busy), and stays far inside
    // the 100 ms in which the drives must have stopped.
    assert!(latch_s - pressed <= 0.050, "{} s", latch_s - pressed);
    assert!(left_s - unplugged <= 0.5, "{} s", left_s - unplugged);
    assert!(
        rest_s - sim_stop_s <= 0.5 + v_at_stop / 0.8,
        "{} s",
        rest_s - sim_stop_s
    );
    assert_eq!(commands_after, 0, "teleop fell silent after the unplug");
}
