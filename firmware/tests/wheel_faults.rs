//! The stall and runaway faults on an ideal plant whose wheels can be made to misbehave: the
//! controller stops under control into `Fault`, reports why, ignores STOP until the robot is
//! set down, and an E-stop latched meanwhile keeps the controlled stop.

mod common;

use common::{command, plant_feedback_rolling, Ticks};

use firmware::control::controller::Output;
use firmware::control::fsm::{State, WheelMotion};
use firmware::control::safety::SS1_DEADLINE_MS;
use firmware::{Config, Controller, Tick};
use protocol::{
    AnyMessage, ControllerMode, EStop, FaultFlags, NodeId, Range, RangeDistance, RangeStatus,
    TeleopHeartbeat, TeleopMode,
};

const CONFIG: Config = Config::ROBOT;

/// What the plant's wheels do.
#[derive(Clone, Copy, PartialEq)]
enum Wheels {
    /// Roll at the balance law's speed reference.
    Follow,
    /// Stay still, whatever the law asks (blocked).
    Stuck,
    /// Roll at this ground speed, m/s, whatever the law asks.
    Roll(f32),
}

struct Bench {
    controller: Controller,
    now: u32,
    joints_rad: protocol::Joints<f32>,
    wheels: Wheels,
    /// What the rangefinder sends every 20 ms (`None`: nothing).
    ranging: Option<Range>,
}

impl Bench {
    /// A controller balancing on its wheels after a fold, wheels following, operator ready.
    fn on_the_wheels() -> Self {
        let mut bench = Self {
            controller: Controller::new(CONFIG).unwrap(),
            now: 0,
            joints_rad: common::standing_joints_rad(&CONFIG),
            wheels: Wheels::Follow,
            ranging: None,
        };
        bench.run(5);
        bench.send(command(TeleopMode::Stop));
        bench.send(command(TeleopMode::Fold));
        bench.run(ms(6_000));
        assert_eq!(bench.state(), State::Wheels(WheelMotion::Balance));
        bench
    }

    fn send(&mut self, message: AnyMessage) {
        self.controller.on_message(Tick(self.now), &message);
    }

    fn state(&self) -> State {
        self.controller.state()
    }
}

impl Ticks for Bench {
    fn tick(&mut self) -> Output {
        let r = CONFIG.balance.wheel_radius_m;
        let rate_rad_s = match self.wheels {
            Wheels::Follow => common::following_wheels_rad_s(&self.controller),
            Wheels::Stuck => 0.0,
            Wheels::Roll(speed_m_s) => speed_m_s / r,
        };
        for message in plant_feedback_rolling(&self.joints_rad, rate_rad_s) {
            self.send(message);
        }
        if let Some(range) = self.ranging.filter(|_| self.now % 5 == 0) {
            self.send(AnyMessage::Range(range));
        }
        if self.now % 5 == 0 {
            self.send(AnyMessage::TeleopHeartbeat(TeleopHeartbeat {
                uptime: protocol::Millis::from_raw(self.now * 4).unwrap(),
            }));
        }
        let output = self.controller.step(Tick(self.now));
        if output.legs_enabled {
            self.joints_rad = output.leg_targets_rad;
        }
        self.now += 1;
        output
    }
}

fn ms(ms: u32) -> u32 {
    CONFIG.rate.ticks_from_ms(ms)
}

/// A ranging of `distance_m` (`None`: no return within the part's range).
fn range(distance_m: Option<f32>) -> Range {
    Range {
        distance: RangeDistance::saturating_from_si(distance_m.unwrap_or(0.0)),
        status: if distance_m.is_some() {
            RangeStatus::Valid
        } else {
            RangeStatus::SignalFail
        },
    }
}

fn torque_free(output: &Output) -> bool {
    !output.legs_enabled && output.wheel_torque_nm == [0.0, 0.0]
}

/// Ticks until the controller reports `Fault` (at most `limit`), and that output.
fn until_fault(bench: &mut Bench, limit: u32) -> (u32, Output) {
    for n in 1..=limit {
        let output = bench.tick();
        if output.status.mode == ControllerMode::Fault {
            return (n, output);
        }
    }
    panic!("no fault within {limit} ticks");
}

/// Runs the controlled stop from its first tick; the tick from which every drive stayed
/// torque-free. Every tick reports `Fault` and `flag`.
fn stop_until_off(bench: &mut Bench, flag: FaultFlags) -> u32 {
    let mut off_from = None;
    for n in 1..=ms(SS1_DEADLINE_MS) + 10 {
        let output = bench.tick();
        assert_eq!(output.status.mode, ControllerMode::Fault, "tick {n}");
        assert!(output.status.faults.contains(flag), "tick {n}");
        match off_from {
            None if torque_free(&output) => off_from = Some(n),
            Some(_) => assert!(torque_free(&output), "tick {n}: a drive came back on"),
            None => {}
        }
    }
    off_from.expect("torque-free by the deadline")
}

#[test]
fn wheels_that_do_not_turn_raise_a_stall_and_a_controlled_stop_into_fault() {
    let mut bench = Bench::on_the_wheels();
    bench.wheels = Wheels::Stuck;
    bench.send(command(TeleopMode::WheelForward));
    // The law winds up against the blocked wheels: saturated, or standing still against its
    // reference, the stall watch trips.
    let (ticks, output) = until_fault(&mut bench, ms(3_000));
    assert!(output.status.faults.contains(FaultFlags::WHEEL_STALL));
    assert!(!output.status.faults.contains(FaultFlags::RUNAWAY));
    assert!(ticks >= ms(CONFIG.runaway.saturation_ms), "{ticks}");
    // Under control: the legs stay powered for the set-down.
    assert!(output.legs_enabled);
    // STOP does not reset a fault whose stop still runs.
    bench.send(command(TeleopMode::Stop));
    let off_from = stop_until_off(&mut bench, FaultFlags::WHEEL_STALL);
    assert!(off_from > 1 && off_from < ms(SS1_DEADLINE_MS), "{off_from}");
    // Set down and torque-free: a new STOP (a key, then X) resets, and the flag goes.
    bench.send(command(TeleopMode::Stop));
    bench.tick();
    assert_eq!(bench.state(), State::Fault, "a repeated STOP is no reset");
    bench.send(command(TeleopMode::Stand));
    bench.send(command(TeleopMode::Stop));
    let output = bench.tick();
    assert_eq!(bench.state(), State::Hold);
    assert!(!output.status.faults.contains(FaultFlags::WHEEL_STALL));
}

#[test]
fn a_robot_rolling_away_while_it_should_stand_still_raises_a_runaway() {
    let mut bench = Bench::on_the_wheels();
    bench.wheels = Wheels::Roll(0.9);
    let (ticks, output) = until_fault(&mut bench, ms(1_000));
    assert!(output.status.faults.contains(FaultFlags::RUNAWAY));
    assert!(ticks <= ms(CONFIG.runaway.speed_error_ms) + 1, "{ticks}");
    let off_from = stop_until_off(&mut bench, FaultFlags::RUNAWAY);
    assert!(off_from < ms(SS1_DEADLINE_MS), "{off_from}");
}

#[test]
fn an_estop_during_a_stall_stop_keeps_the_controlled_stop() {
    let mut bench = Bench::on_the_wheels();
    bench.wheels = Wheels::Stuck;
    bench.send(command(TeleopMode::WheelForward));
    until_fault(&mut bench, ms(3_000));
    bench.run(5);
    bench.send(AnyMessage::EStop(EStop::latch(NodeId::Tool)));
    let output = bench.tick();
    assert_eq!(output.status.mode, ControllerMode::EStop);
    // Not cut at once (category 0 would drop a robot on its wheels): the stop goes on.
    assert!(output.legs_enabled);
    let mut off = false;
    for _ in 0..ms(SS1_DEADLINE_MS) {
        let output = bench.tick();
        assert_eq!(output.status.mode, ControllerMode::EStop);
        off |= torque_free(&output);
    }
    assert!(off, "never torque-free");
}

#[test]
fn following_wheels_never_trip_in_drive_stop_turn_and_reverse() {
    let mut bench = Bench::on_the_wheels();
    for mode in [
        TeleopMode::WheelForward,
        TeleopMode::Stop,
        TeleopMode::WheelBackward,
        TeleopMode::WheelForward,
        TeleopMode::WheelRotate,
        TeleopMode::Stop,
    ] {
        bench.send(command(mode));
        for _ in 0..ms(3_000) {
            let output = bench.tick();
            assert_ne!(output.status.mode, ControllerMode::Fault, "{mode:?}");
        }
    }
}

/// Runs `bench` in the autonomous mode for at most `limit` ticks; the tick at which the mode
/// stopped for its rangefinder (balancing, `range_timeout` reported), `None` if it drove on.
fn until_range_stop(bench: &mut Bench, limit: u32) -> Option<u32> {
    for n in 1..=limit {
        let output = bench.tick();
        if bench.state() != State::Wheels(WheelMotion::Auto) {
            assert_eq!(bench.state(), State::Wheels(WheelMotion::Balance));
            assert!(output.status.faults.contains(FaultFlags::RANGE_TIMEOUT));
            return Some(n);
        }
    }
    None
}

#[test]
fn the_autonomous_mode_stops_and_says_so_when_the_rangefinder_falls_silent() {
    let mut bench = Bench::on_the_wheels();
    bench.ranging = Some(range(Some(0.8)));
    bench.send(command(TeleopMode::Auto));
    for _ in 0..ms(2_000) {
        let output = bench.tick();
        assert!(!output.status.faults.contains(FaultFlags::RANGE_TIMEOUT));
    }
    assert_eq!(bench.state(), State::Wheels(WheelMotion::Auto));
    // Silent: stopped within ten of the part's 20 ms rangings, balancing, the flag up.
    bench.ranging = None;
    let stopped_after =
        until_range_stop(&mut bench, ms(300)).expect("still driving blind after 0.3 s");
    assert!(
        stopped_after >= ms(180),
        "stopped after {stopped_after} ticks"
    );
    for _ in 0..ms(500) {
        let output = bench.tick();
        assert!(output.status.faults.contains(FaultFlags::RANGE_TIMEOUT));
        assert_eq!(bench.state(), State::Wheels(WheelMotion::Balance));
    }
    // The operator's next request (a key other than the one held) clears the report, and
    // with the part ranging again the mode drives on.
    bench.ranging = Some(range(Some(0.8)));
    bench.send(command(TeleopMode::Stop));
    let output = bench.tick();
    assert!(!output.status.faults.contains(FaultFlags::RANGE_TIMEOUT));
    bench.send(command(TeleopMode::Auto));
    bench.run(ms(500));
    assert_eq!(bench.state(), State::Wheels(WheelMotion::Auto));
}

#[test]
fn the_autonomous_mode_stops_when_the_rangefinder_sees_nothing_on_level_ground() {
    let mut bench = Bench::on_the_wheels();
    // The part sends its frames, but never with a return (a covered window).
    bench.ranging = Some(range(None));
    bench.send(command(TeleopMode::Auto));
    // 1.5 m at the mode's 0.48 m/s, after the start.
    let stopped_after =
        until_range_stop(&mut bench, ms(8_000)).expect("still driving blind after 8 s");
    assert!(
        (ms(3_000)..=ms(5_000)).contains(&stopped_after),
        "stopped after {stopped_after} ticks"
    );
}
