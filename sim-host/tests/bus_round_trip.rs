//! The emulated drives and IMU on the in-process bus, driven by a hand-written controller that
//! speaks only CAN frames: it announces its session, targets go out, feedback comes back, and
//! the drives behave as real ones do on timeouts, corrupted frames and E-stops.

use std::cell::RefCell;
use std::path::Path;
use std::rc::Rc;
use std::time::Duration;

use host_can::bus::Bus;
use host_can::inproc_bus::{InprocBus, InprocEndpoint};
use protocol::SessionTime;
use protocol::{
    Angle, Announce, AnyMessage, Drive, DriveEnable, DriveFlags, DriveStatus, EStop, Epoch, Frame,
    Joints, Leg, LegFeedback, LegTargets, NodeId, PerDrive, Receiver, ReleaseToken, Sender,
    Session, Torque, WheelCommand, WheelFeedback, WireVersion, TEST_KEY,
};
use sim_host::clock::lockstep::{self, LockstepOptions};
use sim_host::output::recorder::Recorder;
use sim_host::robot::drive_core::{Authority, SS1_TIMER_US};
use sim_host::robot::imu::{ImuModel, ImuNoise};
use sim_host::robot::model::DEFAULT_MODEL;
use sim_host::robot::plant::Plant;
use sim_host::session::simulator::{Simulator, StartPose};

const HZ: u32 = 250;

/// What the test controller does each cycle.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Plan {
    /// Send leg targets and wheel torques.
    Command,
    /// Send nothing.
    Silent,
}

/// The test controller's session.
const SESSION: Session = Session::owned(TEST_KEY, Epoch::new(1));

/// A minimal controller: announces its session (at the first service, then every 25th),
/// sends fixed targets, keeps the latest feedback and status.
struct TestController {
    bus: InprocEndpoint,
    receiver: Receiver,
    sender: Sender,
    services: u32,
    targets_rad: Joints<f32>,
    wheel_torque_nm: [f32; 2],
    /// Whether the commands ask for torque.
    enabled: bool,
    plan: Plan,
    extra: Vec<Frame>,
    sent: Vec<Frame>,
    leg_feedback: [Option<LegFeedback>; 4],
    wheel_feedback: Option<WheelFeedback>,
    imu_gyro: Vec<[f32; 3]>,
    drive_status: PerDrive<Option<DriveStatus>>,
    feedback_frames: u64,
}

impl TestController {
    fn new(bus: InprocEndpoint) -> Self {
        let start = StartPose::standing();
        Self {
            bus,
            receiver: Receiver::owner(SESSION),
            sender: Sender::new(),
            services: 0,
            targets_rad: start.leg_joint_rad.map(|a| a as f32),
            wheel_torque_nm: [0.0; 2],
            enabled: true,
            plan: Plan::Command,
            extra: Vec::new(),
            sent: Vec::new(),
            leg_feedback: [None; 4],
            wheel_feedback: None,
            imu_gyro: Vec::new(),
            drive_status: PerDrive::splat(None),
            feedback_frames: 0,
        }
    }

    /// `message` sealed in the session with the next counter of its identifier.
    fn seal(&mut self, message: AnyMessage) -> Frame {
        self.sender.seal(&SESSION, &message).unwrap()
    }

    fn service(&mut self) {
        if self.services % 25 == 0 {
            let announce = self.seal(AnyMessage::Announce(Announce {
                version: WireVersion::THIS,
                epoch: Epoch::new(1),
                time: SessionTime::from_ms(self.services * 1000 / HZ),
            }));
            self.bus.send(&announce).unwrap();
        }
        self.services += 1;
        while let Some(frame) = self.bus.recv(Duration::ZERO).unwrap() {
            let accepted = self
                .receiver
                .receive(frame.id(), frame.data())
                .unwrap_or_else(|e| panic!("the simulator sent a bad frame {frame:?}: {e:?}"));
            match accepted.message {
                AnyMessage::LegFeedback(leg, fb) => {
                    self.leg_feedback[leg as usize] = Some(fb);
                    self.feedback_frames += 1;
                }
                AnyMessage::WheelFeedback(fb) => {
                    self.wheel_feedback = Some(fb);
                    self.feedback_frames += 1;
                }
                AnyMessage::Imu(imu) => self.imu_gyro.push(imu.angular_rate.map(|r| r.si())),
                AnyMessage::DriveStatus(drive, status) => {
                    *self.drive_status.get_mut(drive) = Some(status)
                }
                _ => {}
            }
        }
        for frame in self.extra.drain(..) {
            self.bus.send(&frame).unwrap();
        }
        if self.plan == Plan::Command {
            let enable = if self.enabled {
                DriveEnable::Enabled
            } else {
                DriveEnable::Disabled
            };
            let legs = self.seal(AnyMessage::LegTargets(LegTargets {
                enable,
                position: self.targets_rad.map(Angle::saturating_from_si),
            }));
            let wheels = self.seal(AnyMessage::WheelCommand(WheelCommand {
                enable,
                torque: self.wheel_torque_nm.map(Torque::saturating_from_si),
            }));
            for frame in [legs, wheels] {
                self.bus.send(&frame).unwrap();
                self.sent.push(frame);
            }
        }
    }
}

fn setup() -> (Simulator, InprocEndpoint, Rc<RefCell<TestController>>) {
    let sim = Simulator::new(
        Path::new(DEFAULT_MODEL),
        HZ,
        StartPose::standing(),
        Plant::default(),
    )
    .unwrap();
    let bus = InprocBus::new();
    let sim_bus = bus.endpoint();
    let controller = Rc::new(RefCell::new(TestController::new(bus.endpoint())));
    (sim, sim_bus, controller)
}

/// Runs `cycles` lockstep cycles; returns how many cycles missed their command. The first
/// run's first cycle is the one in which the simulator hears the announcement: it sends
/// nothing and does not step.
fn run(
    sim: &mut Simulator,
    bus: &mut InprocEndpoint,
    controller: &Rc<RefCell<TestController>>,
    cycles: u64,
    mut each: impl FnMut(&Simulator),
) -> u64 {
    let mut recorder = Recorder::in_memory();
    let stats = lockstep::run(
        sim,
        bus,
        &mut recorder,
        LockstepOptions {
            cycles,
            reply_timeout: Duration::ZERO,
            max_speed: None,
        },
        |_| {
            controller.borrow_mut().service();
            Ok(())
        },
        |s, _| {
            each(s);
            true
        },
    )
    .unwrap();
    stats.missed_cycles
}

#[test]
fn leg_drives_servo_to_the_frames_targets_and_report_every_cycle() {
    let (mut sim, mut bus, ctl) = setup();
    // Abduct the front-left leg by 0.15 rad and bend its knee 0.1 rad more.
    {
        let mut c = ctl.borrow_mut();
        let fl = c.targets_rad.leg_mut(Leg::Fl);
        fl[0] += 0.15;
        fl[2] -= 0.10;
    }
    let wanted = {
        let c = ctl.borrow();
        let fl = c.targets_rad.leg(Leg::Fl);
        [fl[0], fl[2]]
    };
    let missed = run(&mut sim, &mut bus, &ctl, HZ as u64, |_| {});
    assert_eq!(missed, 0, "every cycle the command arrived");
    let c = ctl.borrow();
    // 250 cycles × (4 legs + wheels) of feedback, all accepted.
    assert!(
        c.feedback_frames >= 250 * 5 - 5,
        "{} feedback frames",
        c.feedback_frames
    );
    assert_eq!(c.receiver.counters().rejected.map(|n| n.raw()), [0; 10]);
    assert_eq!(c.receiver.counters().lost.raw(), 0);
    let fl = c.leg_feedback[0].expect("front-left feedback");
    let got = [fl.position[0].si(), fl.position[2].si()];
    for (g, w) in got.iter().zip(wanted) {
        assert!(
            (g - w).abs() < 0.03,
            "joint at {g:.4} rad, target {w:.4} rad"
        );
    }
    // The physics agrees with the feedback (to the wire's 1e-4 rad).
    let truth = sim.physics().leg_positions_rad();
    assert!((truth.leg(Leg::Fl)[0] as f32 - got[0]).abs() < 2e-4);
    // Every drive reports itself enabled and counts the commands it took.
    for (drive, status) in c.drive_status.iter_drives() {
        let status = status.unwrap_or_else(|| panic!("no status from drive {drive:?}"));
        assert!(
            status.flags.contains(DriveFlags::ENABLED),
            "drive {drive:?}: {status:?}"
        );
        assert!(status.commands.raw() > 200, "drive {drive:?}: {status:?}");
    }
    // The robot still stands.
    let z = sim.physics().torso().pos_m[2];
    assert!(z > 0.35, "torso at {z:.3} m");
}

#[test]
fn the_wheel_drive_applies_the_commanded_torque_and_reports_it() {
    let (mut sim, mut bus, ctl) = setup();
    ctl.borrow_mut().wheel_torque_nm = [1.5, -1.5];
    run(&mut sim, &mut bus, &ctl, HZ as u64 / 2, |_| {});
    let c = ctl.borrow();
    let fb = c.wheel_feedback.expect("wheel feedback");
    let effort = fb.effort.map(|t| t.si());
    // As the drive measures it: within its gain error (5 %) and the field's 0.01 N·m.
    let within = |measured: f32, applied: f32| (measured - applied).abs() <= 0.05 * 1.5 + 0.011;
    assert!(
        within(effort[0], 1.5) && within(effort[1], -1.5),
        "{effort:?}"
    );
    // Standing on its legs, the wheels spin freely in opposite directions, up to the speed
    // where the report's joint damping (2 N·m·s/rad) eats the torque: 1.5 / 2 = 0.75 rad/s,
    // as the drive counts it (one count of its encoder in a 4 ms cycle is 0.096 rad/s).
    let speed = fb.velocity.map(|v| v.si());
    let tolerance = 0.03 + 0.096;
    assert!(
        (speed[0] - 0.75).abs() < tolerance && (speed[1] + 0.75).abs() < tolerance,
        "{speed:?}"
    );
}

#[test]
fn drives_go_torque_free_100_ms_after_the_last_command_and_say_so() {
    let (mut sim, mut bus, ctl) = setup();
    ctl.borrow_mut().wheel_torque_nm = [2.0, 2.0];
    run(&mut sim, &mut bus, &ctl, 50, |_| {});
    let last_command_us = sim.now_us() - 4_000;
    ctl.borrow_mut().plan = Plan::Silent;
    let mut off_at_us = None;
    run(&mut sim, &mut bus, &ctl, 100, |s| {
        let wheels_off = s.hardware().wheel_torque_nm() == [0.0; 2];
        let legs_off = (0..4).all(|leg| !s.physics().leg_enabled(leg));
        if off_at_us.is_none() && wheels_off && legs_off {
            off_at_us = Some(s.now_us());
        }
    });
    let off_after_ms =
        (off_at_us.expect("the drives never went torque-free") - last_command_us) as f64 / 1000.0;
    assert!(
        (100.0..=104.0).contains(&off_after_ms),
        "torque off {off_after_ms} ms after the last command"
    );
    let c = ctl.borrow();
    for (drive, status) in c.drive_status.iter_drives() {
        let status = status.unwrap();
        assert!(
            status.flags.contains(DriveFlags::TIMED_OUT),
            "drive {drive:?}: {status:?}"
        );
        assert!(
            !status.flags.contains(DriveFlags::ENABLED),
            "drive {drive:?}: {status:?}"
        );
    }
    // Torque-free legs cannot carry the torso: it sinks onto its wheels.
    assert!(sim.physics().torso().pos_m[2] < 0.33);
}

#[test]
fn corrupted_and_replayed_commands_are_rejected_counted_and_never_applied() {
    let (mut sim, mut bus, ctl) = setup();
    // Settle first, so that the only thing that could move the hips is the bad frame.
    run(&mut sim, &mut bus, &ctl, 250, |_| {});
    let before = sim.physics().leg_positions_rad().leg(Leg::Fl)[1];
    // A corrupted frame that would swing every hip forward by 0.5 rad.
    let mut evil_targets = ctl.borrow().targets_rad;
    for leg in Leg::ALL {
        evil_targets.leg_mut(leg)[1] += 0.5;
    }
    let evil = ctl.borrow_mut().seal(AnyMessage::LegTargets(LegTargets {
        enable: DriveEnable::Enabled,
        position: evil_targets.map(Angle::saturating_from_si),
    }));
    let mut flipped = evil.data().to_vec();
    flipped[7] ^= 0x10;
    let corrupted = Frame::new(evil.id(), &flipped).unwrap();
    let replayed = ctl.borrow().sent[10];
    {
        let mut c = ctl.borrow_mut();
        c.plan = Plan::Silent;
        c.extra = vec![corrupted, replayed];
    }
    run(&mut sim, &mut bus, &ctl, 1, |_| {});
    ctl.borrow_mut().plan = Plan::Command;
    run(&mut sim, &mut bus, &ctl, 50, |_| {});
    let after = sim.physics().leg_positions_rad().leg(Leg::Fl)[1];
    assert!(
        (after - before).abs() < 0.02,
        "hip moved {before:.3} → {after:.3}"
    );
    // Each leg drive rejected both frames; the wheel drive ignores leg frames.
    assert_eq!(sim.hardware().rejected(), 4 * 2);
    for leg in sim.hardware().legs() {
        assert_eq!(leg.core().rejected(), 2, "{:?}", leg.leg());
    }
    let status = ctl.borrow().drive_status.get(Drive::LegFl).unwrap();
    assert_eq!(status.rejected.raw(), 2);
}

#[test]
fn an_e_stop_frame_lets_the_drives_obey_for_the_ss1_timer_then_stops_them_until_the_clear() {
    let (mut sim, mut bus, ctl) = setup();
    ctl.borrow_mut().wheel_torque_nm = [3.0, 3.0];
    run(&mut sim, &mut bus, &ctl, 25, |_| {});
    // The drives act on any authentic release (the controller checks its token).
    let estop = |estop| ctl.borrow_mut().seal(AnyMessage::EStop(estop));
    let latch = estop(EStop::latch(NodeId::Tool));
    ctl.borrow_mut().extra = vec![latch];
    let timer_cycles = (SS1_TIMER_US / (1_000_000 / u64::from(HZ))) as usize;
    let mut off_from = None;
    let mut n = 0;
    // The controller keeps commanding torque all along; a second latch half-way does not
    // restart the timer.
    run(&mut sim, &mut bus, &ctl, timer_cycles as u64 + 50, |s| {
        n += 1;
        let now = s.now_us();
        let hardware = s.hardware();
        let authorities: Vec<_> = (hardware.legs().iter().map(|leg| leg.core()))
            .chain([hardware.wheel().core()])
            .map(|core| core.authority(now))
            .collect();
        // The torque a drive applied in the cycle's step follows its authority one cycle on.
        let off = authorities.iter().all(|a| *a == Authority::TorqueOff);
        let on = authorities.iter().all(|a| *a == Authority::Drive)
            && hardware.wheel_torque_nm() == [3.0; 2];
        let applied_off = hardware.wheel_torque_nm() == [0.0; 2];
        if n == timer_cycles / 2 {
            ctl.borrow_mut().extra = vec![estop(EStop::latch(NodeId::Tool))];
        }
        match off_from {
            None if off => off_from = Some(n),
            None => assert!(on, "cycle {n} of the timer: the drives must obey"),
            Some(from) => {
                assert!(off, "a drive restarted while the E-stop is latched");
                assert!(
                    n == from || applied_off,
                    "wheel torque applied after the timer"
                );
            }
        }
    });
    assert_eq!(
        off_from,
        Some(timer_cycles),
        "the drives obey for the SS1 timer ({timer_cycles} cycles), then stop"
    );
    for status in ctl.borrow().drive_status {
        assert!(status.unwrap().flags.contains(DriveFlags::ESTOP));
    }
    // An authentic release alone does not clear the drives: they wait for the controller's
    // status to show it left its E-stop (it checks the token).
    let release = estop(EStop::release(NodeId::Tool, ReleaseToken::new(1)));
    ctl.borrow_mut().extra = vec![release];
    run(&mut sim, &mut bus, &ctl, 30, |_| {});
    assert_eq!(sim.hardware().wheel_torque_nm(), [0.0, 0.0]);
    let still_latched = status_frame(&ctl, protocol::ControllerMode::EStop);
    ctl.borrow_mut().extra = vec![still_latched];
    run(&mut sim, &mut bus, &ctl, 5, |_| {});
    assert_eq!(sim.hardware().wheel_torque_nm(), [0.0, 0.0]);
    let released = status_frame(&ctl, protocol::ControllerMode::Stop);
    ctl.borrow_mut().extra = vec![released];
    run(&mut sim, &mut bus, &ctl, 30, |_| {});
    assert_eq!(sim.hardware().wheel_torque_nm(), [3.0, 3.0]);
    assert!((0..4).all(|leg| sim.physics().leg_enabled(leg)));
    for status in ctl.borrow().drive_status {
        assert!(!status.unwrap().flags.contains(DriveFlags::ESTOP));
    }
}

/// The controller's status in `mode`, sealed by `ctl`.
fn status_frame(ctl: &Rc<RefCell<TestController>>, mode: protocol::ControllerMode) -> Frame {
    ctl.borrow_mut()
        .seal(AnyMessage::ControllerStatus(protocol::ControllerStatus {
            mode,
            faults: protocol::FaultFlags::EMPTY,
            tick: protocol::Tick::from_raw(0).unwrap(),
            body_height: protocol::BodyHeight::saturating_from_si(0.0),
            pitch: Angle::saturating_from_si(0.0),
            roll: Angle::saturating_from_si(0.0),
            release_token: ReleaseToken::new(1),
        }))
}

/// Whether every drive has torque this instant.
fn all_drive(sim: &Simulator) -> bool {
    let now = sim.now_us();
    let hardware = sim.hardware();
    (hardware.legs().iter().map(|leg| leg.core()))
        .chain([hardware.wheel().core()])
        .all(|core| core.authority(now) == Authority::Drive)
}

/// Whether every drive is torque-free this instant, cut by the E-stop's own rules.
fn all_refused(sim: &Simulator) -> bool {
    let now = sim.now_us();
    let hardware = sim.hardware();
    (hardware.legs().iter().map(|leg| leg.core()))
        .chain([hardware.wheel().core()])
        .all(|core| core.authority(now) == Authority::TorqueOff && core.stop_refused())
}

/// The drives obeying a controller that asks for 3 N·m on each wheel, 25 cycles in; the
/// simulator, its bus and the controller.
fn driving() -> (Simulator, InprocEndpoint, Rc<RefCell<TestController>>) {
    let (mut sim, mut bus, ctl) = setup();
    ctl.borrow_mut().wheel_torque_nm = [3.0, 3.0];
    run(&mut sim, &mut bus, &ctl, 25, |_| {});
    (sim, bus, ctl)
}

/// An E-stop latch from a tool, sealed by `ctl`.
fn latch_frame(ctl: &Rc<RefCell<TestController>>) -> Frame {
    ctl.borrow_mut()
        .seal(AnyMessage::EStop(EStop::latch(NodeId::Tool)))
}

#[test]
fn within_the_ss1_timer_a_controller_that_reports_another_mode_is_not_obeyed() {
    // A controller that reports another mode after the latch is not stopping the robot: the
    // drives cut the torque at once, long before the timer.
    let (mut sim, mut bus, ctl) = driving();
    let stopping = status_frame(&ctl, protocol::ControllerMode::EStop);
    ctl.borrow_mut().extra = vec![latch_frame(&ctl), stopping];
    run(&mut sim, &mut bus, &ctl, 20, |_| {});
    assert!(all_drive(&sim), "a controller in its E-stop is obeyed");
    let driving = status_frame(&ctl, protocol::ControllerMode::WheelForward);
    ctl.borrow_mut().extra = vec![driving];
    run(&mut sim, &mut bus, &ctl, 2, |_| {});
    assert!(
        all_refused(&sim),
        "a controller that drives on is not obeyed"
    );
    run(&mut sim, &mut bus, &ctl, 20, |_| {});
    assert_eq!(sim.hardware().wheel_torque_nm(), [0.0, 0.0]);
    assert!((0..4).all(|leg| !sim.physics().leg_enabled(leg)));
}

#[test]
fn within_the_ss1_timer_torque_asked_back_after_the_controller_let_go_is_refused_until_the_clear() {
    let (mut sim, mut bus, ctl) = driving();
    ctl.borrow_mut().extra = vec![latch_frame(&ctl)];
    run(&mut sim, &mut bus, &ctl, 20, |_| {});
    assert!(all_drive(&sim));
    ctl.borrow_mut().enabled = false;
    run(&mut sim, &mut bus, &ctl, 5, |_| {});
    assert!(!all_drive(&sim), "the controller let go");
    ctl.borrow_mut().enabled = true;
    run(&mut sim, &mut bus, &ctl, 20, |_| {});
    assert!(
        all_refused(&sim),
        "torque asked back during the stop is refused"
    );
    assert_eq!(sim.hardware().wheel_torque_nm(), [0.0, 0.0]);
    // Until the clear: a release and the controller's status out of its E-stop.
    let release = ctl.borrow_mut().seal(AnyMessage::EStop(EStop::release(
        NodeId::Tool,
        ReleaseToken::new(1),
    )));
    let released = status_frame(&ctl, protocol::ControllerMode::Stop);
    ctl.borrow_mut().extra = vec![release, released];
    run(&mut sim, &mut bus, &ctl, 20, |_| {});
    assert!(all_drive(&sim), "the clear restores the drives");
    assert_eq!(sim.hardware().wheel_torque_nm(), [3.0, 3.0]);
}

/// Gyro x over the second half of `cycles` cycles of a robot standing still on `plant`: mean
/// and standard deviation.
fn still_gyro_x(plant: Plant, cycles: u64) -> ((f32, f32), Simulator) {
    let mut sim =
        Simulator::new(Path::new(DEFAULT_MODEL), HZ, StartPose::standing(), plant).unwrap();
    let bus_all = InprocBus::new();
    let mut sim_bus = bus_all.endpoint();
    let ctl = Rc::new(RefCell::new(TestController::new(bus_all.endpoint())));
    run(&mut sim, &mut sim_bus, &ctl, cycles, |_| {});
    let samples: Vec<f32> = ctl.borrow().imu_gyro[cycles as usize / 2..]
        .iter()
        .map(|s| s[0])
        .collect();
    let n = samples.len() as f32;
    let mean = samples.iter().sum::<f32>() / n;
    let var = samples.iter().map(|s| (s - mean).powi(2)).sum::<f32>() / n;
    ((mean, var.sqrt()), sim)
}

#[test]
fn the_imu_is_a_bmi088_by_default_ideal_or_noisier_when_asked() {
    // The chip: its turn-on bias and its noise over the filter's bandwidth (0.014 °/s/√Hz
    // over ~255 Hz: 3.9e-3 rad/s RMS).
    let ((mean, std), sim) = still_gyro_x(Plant::default(), 500);
    let (bias, _) = sim.hardware().imu().chip().unwrap().bias();
    println!(
        "chip: gyro x mean {mean:.4} (bias {:.4}), std {std:.4}",
        bias[0]
    );
    assert!(
        (f64::from(mean) - bias[0]).abs() < 0.002,
        "mean {mean} vs bias {bias:?}"
    );
    assert!((0.003..0.006).contains(&std), "std {std}");

    let ideal = Plant {
        imu: ImuModel::Ideal,
        ..Plant::default()
    };
    let ((mean, quiet), _) = still_gyro_x(ideal, 250);
    assert!(
        mean.abs() < 0.002 && quiet < 0.002,
        "a still robot's ideal gyro: {mean} ± {quiet}"
    );

    let noise = ImuNoise {
        gyro_std_rad_s: 0.05,
        gyro_bias_rad_s: [0.2, 0.0, 0.0],
        seed: 7,
        ..ImuNoise::default()
    };
    let noisy = Plant {
        imu: ImuModel::Ideal,
        imu_noise: noise,
        ..Plant::default()
    };
    let ((mean, std), _) = still_gyro_x(noisy, 250);
    assert!((mean - 0.2).abs() < 0.02, "bias: mean {mean}");
    assert!((std - 0.05).abs() < 0.015, "noise: std {std}");
}
