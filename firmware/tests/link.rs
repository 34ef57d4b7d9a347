//! A lossy bus, through the node's frame handler: the link monitor lets the robot keep moving at
//! 1 % and 5 % frame loss and brings it to a controlled stop at 20 %, refusing new motion until
//! the link recovers.
//!
//! The plant is ideal (every drive reaches its target, the torso stays level); every frame to
//! the controller is sealed in the node's session, and the bus drops every n-th frame of each
//! identifier, so the receiver sees the gaps in each sequence.

mod common;

use common::{command, Ticks, SESSION};

use std::collections::HashMap;

use firmware::control::controller::Output;
use firmware::control::fsm::{Direction, LegMotion, State, WheelMotion};
use firmware::{Config, Node, Tick};
use protocol::{
    AnyMessage, ControllerMode, FaultFlags, Joints, RejectCause, TeleopHeartbeat, TeleopMode,
};

const CONFIG: Config = Config::ROBOT;
const TROT_F: State = State::Legs(LegMotion::Trot(Direction::Forward));

/// An ideal plant and a teleop on a bus that loses every `drop_every`-th frame of each id.
struct LossyBench {
    node: Node,
    now: u32,
    joints_rad: Joints<f32>,
    /// The teleop's mode, sent every 20 ms like the real one.
    mode: TeleopMode,
    /// Drop every n-th frame of each identifier (`None`: a clean bus).
    drop_every: Option<u32>,
    /// Next counter per identifier (a dropped frame still used its counter).
    counters: HashMap<u16, u32>,
    /// A babbling teleop: this many extra commands and heartbeats per tick, in sequence and
    /// never lost.
    flood_per_tick: u16,
}

impl LossyBench {
    fn new() -> Self {
        let joints = common::standing_joints_rad(&CONFIG);
        Self {
            node: common::node(CONFIG),
            now: 0,
            joints_rad: joints,
            mode: TeleopMode::Stop,
            drop_every: None,
            counters: HashMap::new(),
            flood_per_tick: 0,
        }
    }

    /// Puts `message` on the bus: sealed with its id's next counter, then delivered unless the
    /// bus drops it.
    fn send(&mut self, message: AnyMessage) {
        let id = message.id().raw();
        let counter = self.counters.entry(id).or_insert(0);
        let frame = message.encode(&SESSION, *counter).unwrap();
        *counter = counter.wrapping_add(1);
        let dropped = self.drop_every.is_some_and(|n| *counter % n == 0);
        if !dropped {
            self.node
                .on_frame(Tick(self.now), frame.id(), frame.data())
                .unwrap_or_else(|e| panic!("{id:03X} refused: {e:?}"));
        }
    }

    /// Puts a babbler's `message` on the bus, never lost; the node may rate-limit it.
    fn babble(&mut self, message: AnyMessage) {
        let counter = self.counters.entry(message.id().raw()).or_insert(0);
        let frame = message.encode(&SESSION, *counter).unwrap();
        *counter = counter.wrapping_add(1);
        match self.node.on_frame(Tick(self.now), frame.id(), frame.data()) {
            Ok(()) | Err(protocol::DecodeError::RateLimited { .. }) => {}
            Err(other) => panic!("babbled {:03X} refused: {other:?}", frame.id()),
        }
    }

    /// Asks for `mode` at once (a key press), then keeps sending it every 20 ms.
    fn press(&mut self, mode: TeleopMode) {
        self.mode = mode;
        self.send(command(mode));
    }

    fn tick(&mut self) -> Output {
        let wheels_rad_s = common::following_wheels_rad_s(self.node.controller());
        for message in common::plant_feedback_rolling(&self.joints_rad, wheels_rad_s) {
            self.send(message);
        }
        if self.now % 5 == 0 {
            self.send(command(self.mode));
            self.send(AnyMessage::TeleopHeartbeat(TeleopHeartbeat {
                uptime: protocol::Millis::from_raw(self.now * 4).unwrap(),
            }));
        }
        for _ in 0..self.flood_per_tick {
            self.babble(command(self.mode));
            self.babble(AnyMessage::TeleopHeartbeat(TeleopHeartbeat {
                uptime: protocol::Millis::from_raw(self.now * 4).unwrap(),
            }));
        }
        let (output, _) = self.node.poll(Tick(self.now));
        if output.legs_enabled {
            self.joints_rad = output.leg_targets_rad;
        }
        self.now += 1;
        output
    }

    fn state(&self) -> State {
        self.node.controller().state()
    }

    /// A trotting robot on a clean bus.
    fn trotting() -> Self {
        let mut bench = Self::new();
        bench.run(5);
        bench.press(TeleopMode::TrotForward);
        bench.run(300);
        assert_eq!(bench.state(), TROT_F);
        bench
    }
}

impl Ticks for LossyBench {
    fn tick(&mut self) -> Output {
        LossyBench::tick(self)
    }
}

fn ticks_from_s(s: u32) -> u32 {
    CONFIG.rate.ticks_from_ms(s * 1000)
}

#[test]
fn one_and_five_percent_loss_keep_the_robot_trotting() {
    for every in [100, 20] {
        let mut bench = LossyBench::trotting();
        bench.drop_every = Some(every);
        for _ in 0..ticks_from_s(10) {
            let output = bench.tick();
            assert_eq!(
                bench.state(),
                TROT_F,
                "1 in {every} lost, tick {}",
                bench.now
            );
            assert!(!output.status.faults.contains(FaultFlags::LINK_DEGRADED));
        }
        let loss = bench.node.link().last_loss_permille().unwrap();
        let expected = 1000 / every;
        // Each identifier loses whole frames per window, so the measure is only near 1/every.
        assert!(
            (expected * 6 / 10..=expected * 14 / 10).contains(&loss),
            "1 in {every} lost: {loss} ‰"
        );
        assert!(bench.node.reject_counters().lost.raw() > 0);
        assert_eq!(bench.node.reject_counters().total(), 0);
    }
}

#[test]
fn twenty_percent_loss_stops_the_trot_and_refuses_motion_until_the_link_recovers() {
    let mut bench = LossyBench::trotting();
    // Every 5th frame of each identifier lost: feedback still arrives every few ms, so no
    // watchdog trips, but one frame in five is gone.
    bench.drop_every = Some(5);
    let mut ticks = 0;
    while bench.state() == TROT_F {
        bench.tick();
        ticks += 1;
        assert!(
            ticks <= ticks_from_s(3),
            "still trotting after 3 s at 20 % loss"
        );
    }
    let seconds = ticks as f32 / CONFIG.rate.hz() as f32;
    assert!(seconds <= 2.0, "stopped after {seconds} s");
    // A controlled stop: standing on four legs, drives enabled — not a fault, not torque-free.
    assert_eq!(bench.state(), State::Legs(LegMotion::Stand));
    let output = bench.tick();
    assert!(output.legs_enabled);
    assert_eq!(output.status.mode, ControllerMode::Stop);
    assert!(output.status.faults.contains(FaultFlags::LINK_DEGRADED));
    assert_eq!(
        output.status.faults.without(FaultFlags::LINK_DEGRADED),
        FaultFlags::EMPTY
    );
    // The teleop keeps resending L at 50 Hz, and a new key (W) comes through too: neither
    // starts a motion while the link is degraded.
    bench.run(ticks_from_s(2));
    assert_eq!(bench.state(), State::Legs(LegMotion::Stand));
    bench.press(TeleopMode::WheelForward);
    bench.run(ticks_from_s(2));
    assert_eq!(bench.state(), State::Legs(LegMotion::Stand));
    assert!(bench.node.controller().link_degraded());
    // The loss stops: within two windows the link recovers, and the robot stays put (the
    // operator's last key is not replayed) until a new key.
    bench.drop_every = None;
    let output = bench.run(ticks_from_s(2) + 1);
    assert!(!output.status.faults.contains(FaultFlags::LINK_DEGRADED));
    assert_eq!(bench.state(), State::Legs(LegMotion::Stand));
    bench.press(TeleopMode::TrotForward);
    bench.run(ticks_from_s(1));
    assert_eq!(bench.state(), TROT_F, "requests are obeyed again");
}

#[test]
fn twenty_percent_loss_brakes_a_wheel_drive_to_a_balanced_standstill() {
    let mut bench = LossyBench::new();
    bench.run(5);
    bench.press(TeleopMode::WheelForward);
    // The fold sets the robot down in place first (a few seconds).
    bench.run(ticks_from_s(5));
    let drive = State::Wheels(WheelMotion::Drive(Direction::Forward));
    assert_eq!(bench.state(), drive);
    bench.drop_every = Some(5);
    bench.run(ticks_from_s(3));
    assert_eq!(bench.state(), State::Wheels(WheelMotion::Balance));
    let output = bench.tick();
    assert!(output.status.faults.contains(FaultFlags::LINK_DEGRADED));
    assert_eq!(output.status.mode, ControllerMode::Stop);
    // A new motion request is refused while the link is degraded.
    bench.press(TeleopMode::WheelRotate);
    bench.run(10);
    assert_eq!(bench.state(), State::Wheels(WheelMotion::Balance));
}

#[test]
fn a_babbling_teleop_does_not_hide_a_lossy_bus() {
    let mut bench = LossyBench::trotting();
    // 10 000 commands and 10 000 heartbeats per second, in sequence and never lost, on a bus
    // that loses every 5th frame of everything else.
    bench.flood_per_tick = 40;
    bench.drop_every = Some(5);
    bench.run(ticks_from_s(3));
    assert_eq!(bench.state(), State::Legs(LegMotion::Stand));
    assert!(bench.node.controller().link_degraded());
    let loss = bench.node.link().last_loss_permille().unwrap();
    assert!(loss > 120, "{loss} ‰");
    assert!(
        bench
            .node
            .reject_counters()
            .get(RejectCause::RateLimited)
            .raw()
            > 0
    );
}

#[test]
fn loss_in_long_bursts_is_measured_too() {
    // Each identifier loses 12 frames in a row out of every 60 (20 %). The frame after a burst
    // is ahead of the sequence by 13 with a valid check: it is accepted and the 12 counted as
    // lost (any jump ahead of up to 2^15 is), so bursts weigh as much as scattered loss.
    let mut node = common::node(CONFIG);
    let joints = common::standing_joints_rad(&CONFIG);
    let mut counters: HashMap<u16, u32> = HashMap::new();
    for now in 0..ticks_from_s(2) {
        for message in common::plant_feedback(&joints) {
            let counter = counters.entry(message.id().raw()).or_insert(0);
            let frame = message.encode(&SESSION, *counter).unwrap();
            *counter += 1;
            if *counter % 60 >= 12 {
                node.on_frame(Tick(now), frame.id(), frame.data())
                    .unwrap_or_else(|e| panic!("{:03X} refused: {e:?}", frame.id()));
            }
        }
        node.poll(Tick(now));
    }
    let loss = node.link().last_loss_permille().unwrap();
    assert!((150..=250).contains(&loss), "measured {loss} ‰ of 200");
    assert!(node.link().degraded());
    // Nothing refused, and every burst counted whole: of each identifier's 500 frames, the
    // first burst comes before the first frame heard (which starts the sequence), and the
    // other 8 (from frame 60, 120, … 480 on) are each counted when the frame after them comes.
    assert_eq!(node.reject_counters().total(), 0);
    assert_eq!(node.reject_counters().lost.raw(), 6 * 12 * 8);
}
