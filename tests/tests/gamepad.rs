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
    candump, firmware, one_at_a_time, out_dir, read_candump, start_sim, wait_for_log, Process, Vcan,
};
use protocol::{decode_frame, AnyMessage, ControllerMode, EStopAction, Frame, TeleopMode};

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
    wait_for_log(log, timeout, |frames| {
        statuses(frames)
            .iter()
            .any(|&(t, m)| t > after_s && m == mode)
    })
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
    let sim = start_sim(bus.name(), &out, &["--duration-s", "40", "--pace", "1"]);
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
            "60",
        ],
    );
    // Teleop's STOP releases the controller's start-up interlock; then A: drive.
    assert!(wait_for_log(&log, Duration::from_secs(30), |f| f
        .iter()
        .any(|(_, f)| f.id() == 0x201)));
    std::thread::sleep(Duration::from_millis(300));
    let start = pad.press(KeyCode::BTN_SOUTH);
    assert!(
        reports(
            &log,
            ControllerMode::Driving,
            start,
            Duration::from_secs(30)
        ),
        "A did not put the robot on its wheels in drive"
    );
    // Left stick 62.5 % up: 0.27 m/s; then the right stick half left: a curve.
    pad.stick(AbsoluteAxisCode::ABS_Y, -0.625);
    std::thread::sleep(Duration::from_secs(3));
    pad.stick(AbsoluteAxisCode::ABS_RX, -0.5);
    std::thread::sleep(Duration::from_secs(3));

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
    std::thread::sleep(Duration::from_millis(2500));
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
    assert!(reports(
        &log,
        ControllerMode::Driving,
        stop,
        Duration::from_secs(30)
    ));
    std::thread::sleep(Duration::from_secs(3));
    let unplugged = wall_s();
    drop(pad);
    std::thread::sleep(Duration::from_secs(3));
    let _ = teleop.terminate();
    assert!(sim.wait(Duration::from_secs(120)).success());
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
    // One control period (4 ms) plus teleop's own loop (2 ms) and the bus.
    assert!(latch_s - pressed <= 0.010, "{} s", latch_s - pressed);
    assert!(left_s - unplugged <= 0.5, "{} s", left_s - unplugged);
    assert!(
        rest_s - sim_stop_s <= 0.5 + v_at_stop / 0.8,
        "{} s",
        rest_s - sim_stop_s
    );
    assert_eq!(commands_after, 0, "teleop fell silent after the unplug");
}
