//! Integer time: durations in ticks, watchdogs across the counter wrap, and a whole node
//! trotting across it.

mod common;

use firmware::control::fsm::{Direction, LegMotion, State};
use firmware::control::safety::Watchdog;
use firmware::legs::smoothing::Smoother;
use firmware::{Config, Node, Tick, TickRate};
use protocol::{AnyMessage, FaultFlags, Sender, TeleopHeartbeat, TeleopMode};

#[test]
fn milliseconds_round_up_to_whole_ticks() {
    let sim = TickRate::SIM_250_HZ;
    assert_eq!(sim.ticks_from_ms(50), 13); // 12.5 ticks: never early
    assert_eq!(sim.ticks_from_ms(500), 125);
    assert_eq!(TickRate::MCU_1_KHZ.ticks_from_ms(50), 50);
    assert_eq!(TickRate::new(0), None);
    assert_eq!(TickRate::new(20_000), None);
}

#[test]
fn a_watchdog_works_across_the_tick_counter_wrap() {
    let mut watchdog = Watchdog::new(13);
    assert!(watchdog.expired(Tick(0)), "never fed counts as expired");
    let fed = Tick(u32::MAX - 5);
    watchdog.feed(fed);
    assert!(!watchdog.expired(fed.plus(13)));
    assert!(watchdog.expired(fed.plus(14)));
    assert_eq!(watchdog.age_ticks(Tick(3)), Some(9));
}

#[test]
fn the_reports_smoothing_in_ticks() {
    // u += rate · (target − u) · dt with rate 8 /s at 250 Hz: α = 0.032.
    let smoother = Smoother::new(8.0, TickRate::SIM_250_HZ);
    assert!((smoother.alpha() - 0.032).abs() < 1e-6);
    assert!((smoother.step(0.0, 1.0) - 0.032).abs() < 1e-6);
    // One second at 1 kHz and at 250 Hz reach nearly the same point (1 − e^−8).
    let run = |rate: TickRate| {
        let smoother = Smoother::new(8.0, rate);
        (0..rate.hz()).fold(0.0f32, |u, _| smoother.step(u, 1.0))
    };
    let (fast, slow) = (run(TickRate::MCU_1_KHZ), run(TickRate::SIM_250_HZ));
    assert!((fast - (1.0 - (-8.0f32).exp())).abs() < 2e-3);
    assert!((fast - slow).abs() < 2e-3);
    // Rates that would overshoot in one tick are capped, and NaN holds.
    assert_eq!(Smoother::new(1e6, TickRate::SIM_250_HZ).alpha(), 1.0);
    assert_eq!(Smoother::new(f32::NAN, TickRate::SIM_250_HZ).alpha(), 0.0);
}

#[test]
fn a_node_trots_on_across_the_tick_counter_wrap() {
    // Started 4 s before its tick counter wraps (about 199 days of uptime at 250 Hz), on an
    // ideal plant with the operator holding L (after the X that releases the restart
    // interlock): it must trot through the wrap without a watchdog, the link monitor or the
    // schedule noticing anything.
    let config = Config::ROBOT;
    let mut node = common::node(config);
    let mut joints = common::standing_joints_rad(&config);
    let mut bus = Sender::new();
    let mut send = |node: &mut Node, now: Tick, message: AnyMessage| {
        let frame = common::seal(&mut bus, &message);
        node.on_frame(now, frame.id(), frame.data()).unwrap();
    };
    let start = Tick(u32::MAX - 1000);
    let trot = State::Legs(LegMotion::Trot(Direction::Forward));
    for k in 0..2500_u32 {
        let now = start.plus(k);
        for message in common::plant_feedback(&joints) {
            send(&mut node, now, message);
        }
        if k == 0 {
            send(&mut node, now, common::command(TeleopMode::Stop));
        }
        if k % 5 == 0 {
            send(&mut node, now, common::command(TeleopMode::TrotForward));
            let uptime = protocol::Millis::from_raw(k * 4).unwrap();
            send(
                &mut node,
                now,
                AnyMessage::TeleopHeartbeat(TeleopHeartbeat { uptime }),
            );
        }
        let (output, frames) = node.poll(now);
        assert_eq!(output.status.faults, FaultFlags::EMPTY, "tick {}", now.0);
        assert!(!frames.is_empty(), "tick {}: nothing sent", now.0);
        if output.legs_enabled {
            joints = output.leg_targets_rad;
        }
        if k >= 500 {
            assert_eq!(node.controller().state(), trot, "tick {}", now.0);
        }
    }
}
