//! The controller as a CAN node: what goes out each tick, and what happens to bad frames.

mod common;

use common::seal;
use firmware::control::fsm::{Direction, LegMotion, State, WheelMotion};
use firmware::node::TELEOP_COMMANDS_PER_TICK;
use firmware::{Config, Node, Tick};
use protocol::{
    classic_latch, decode_frame, AnyMessage, DecodeError, DriveEnable, EStop, Joints, MessageId,
    NodeId, RejectCause, Sender, TeleopHeartbeat, TeleopMode,
};

fn node() -> Node {
    common::node(Config::ROBOT)
}

fn teleop_frame(teleop: &mut Sender, mode: TeleopMode) -> protocol::Frame {
    seal(teleop, &common::command(mode))
}

#[test]
fn sends_the_bus_schedule_at_250_hz() {
    let mut node = node();
    let mut counts = std::collections::HashMap::new();
    for tick in 0..250 {
        let (_, frames) = node.poll(Tick(tick));
        for frame in &frames {
            let decoded = decode_frame(frame.id(), frame.data()).expect("own frames decode");
            *counts.entry(decoded.id).or_insert(0) += 1;
        }
    }
    assert_eq!(counts[&MessageId::LegTargets], 250);
    assert_eq!(counts[&MessageId::WheelCommand], 250);
    assert_eq!(counts[&MessageId::ControllerStatus], 50);
    assert_eq!(counts[&MessageId::RejectCounters], 10);
    // The session announcement on the first poll, then at 50 Hz.
    assert_eq!(counts[&MessageId::Announce], 1 + 50);
    assert_eq!(node.encode_failures(), 0);
}

#[test]
fn a_corrupted_frame_is_rejected_counted_and_never_applied() {
    let mut node = node();
    let mut teleop = Sender::new();
    let stop = teleop_frame(&mut teleop, TeleopMode::Stop);
    node.on_frame(Tick(0), stop.id(), stop.data()).unwrap();
    let good = teleop_frame(&mut teleop, TeleopMode::WheelForward);
    let mut bad = good.data().to_vec();
    bad[6] ^= 0x01; // flip a payload bit
    assert!(matches!(
        node.on_frame(Tick(0), good.id(), &bad),
        Err(DecodeError::Unauthentic { .. })
    ));
    assert_eq!(node.controller().state(), State::Hold);
    assert_eq!(
        node.reject_counters().get(RejectCause::Unauthentic).raw(),
        1
    );
    // Feedback carries a CRC rather than a MAC: its corruption is counted as such.
    let imu = seal(&mut Sender::new(), &AnyMessage::Imu(common::imu(0.0)));
    let mut bad = imu.data().to_vec();
    bad[6] ^= 0x01;
    assert!(matches!(
        node.on_frame(Tick(0), imu.id(), &bad),
        Err(DecodeError::CrcMismatch { .. })
    ));
    assert_eq!(node.reject_counters().get(RejectCause::Crc).raw(), 1);
    // Wrong length and unknown id are counted under their own causes.
    assert!(node
        .on_frame(Tick(0), good.id(), &good.data()[..good.data().len() - 1])
        .is_err());
    assert!(node.on_frame(Tick(0), 0x7FF, &[0; 8]).is_err());
    assert_eq!(
        node.reject_counters().get(RejectCause::WrongLength).raw(),
        1
    );
    assert_eq!(node.reject_counters().get(RejectCause::UnknownId).raw(), 1);
    // The genuine frame acts; a replay of it is rejected.
    node.on_frame(Tick(0), good.id(), good.data()).unwrap();
    assert_eq!(
        node.controller().state(),
        State::Folding(WheelMotion::Drive(Direction::Forward))
    );
    assert!(node.on_frame(Tick(1), good.id(), good.data()).is_err());
    assert_eq!(node.reject_counters().get(RejectCause::Repeated).raw(), 1);
    // And the counters go out on the bus in the RejectCounters frame.
    let mut seen = None;
    for tick in 0..25 {
        let (_, frames) = node.poll(Tick(tick));
        for frame in &frames {
            if let Ok(decoded) = decode_frame(frame.id(), frame.data()) {
                if let AnyMessage::RejectCounters(counters) = decoded.message {
                    seen = Some(counters);
                }
            }
        }
    }
    let counters = seen.expect("a RejectCounters frame within 100 ms");
    assert_eq!(counters.total(), 5);
}

#[test]
fn a_constant_classic_latch_latches_and_only_a_release_with_the_token_clears() {
    let mut node = node();
    // The latch an E-stop panel or `cansend vcan0 000#ED80D3C70000010A` (source = tool) sends:
    // eight bytes of classic CAN, a CRC over action and source, bound to no session.
    let latch = classic_latch(NodeId::Tool, 0).unwrap();
    assert_eq!(
        latch.data(),
        [0xED, 0x80, 0xD3, 0xC7, 0x00, 0x00, 0x01, 0x0A]
    );
    node.on_frame(Tick(0), latch.id(), latch.data()).unwrap();
    assert_eq!(node.controller().state(), State::EStop);
    let (output, frames) = node.poll(Tick(0));
    assert!(!output.legs_enabled && output.wheel_torque_nm == [0.0, 0.0]);
    let targets = frames
        .iter()
        .find_map(|f| match decode_frame(f.id(), f.data()).unwrap().message {
            AnyMessage::LegTargets(t) => Some(t),
            _ => None,
        })
        .unwrap();
    assert_eq!(targets.enable, DriveEnable::Disabled);
    // A release needs the key and the token the controller publishes for this latch: one
    // with another token is refused and counted, the right one releases.
    let mut tool = Sender::new();
    let token = node.release_token();
    let wrong = seal(
        &mut tool,
        &AnyMessage::EStop(EStop::release(NodeId::Tool, token.next())),
    );
    assert_eq!(
        node.on_frame(Tick(1), wrong.id(), wrong.data()),
        Err(DecodeError::StaleRelease { id: 0x000 })
    );
    assert_eq!(node.controller().state(), State::EStop);
    let release = seal(
        &mut tool,
        &AnyMessage::EStop(EStop::release(NodeId::Tool, token)),
    );
    node.on_frame(Tick(1), release.id(), release.data())
        .unwrap();
    assert_eq!(node.controller().state(), State::Hold);
    // The same latch again still acts (a stale latch can only stop the robot), and gets a
    // new token; neither the replayed release nor a fresh one with the old token releases it.
    node.on_frame(Tick(2), latch.id(), latch.data()).unwrap();
    assert_eq!(node.controller().state(), State::EStop);
    assert_ne!(node.release_token(), token);
    // A tick: the stop cuts every drive (a release waits for that, see `stops.rs`).
    let _ = node.poll(Tick(2));
    assert!(node
        .on_frame(Tick(3), release.id(), release.data())
        .is_err());
    let old = seal(
        &mut tool,
        &AnyMessage::EStop(EStop::release(NodeId::Tool, token)),
    );
    assert_eq!(
        node.on_frame(Tick(3), old.id(), old.data()),
        Err(DecodeError::StaleRelease { id: 0x000 })
    );
    assert_eq!(node.controller().state(), State::EStop);
    // A release when nothing is latched is refused as well.
    let fresh = seal(
        &mut tool,
        &AnyMessage::EStop(EStop::release(NodeId::Tool, node.release_token())),
    );
    node.on_frame(Tick(4), fresh.id(), fresh.data()).unwrap();
    assert_eq!(node.controller().state(), State::Hold);
    let again = seal(
        &mut tool,
        &AnyMessage::EStop(EStop::release(NodeId::Tool, node.release_token())),
    );
    assert_eq!(
        node.on_frame(Tick(5), again.id(), again.data()),
        Err(DecodeError::StaleRelease { id: 0x000 })
    );
    assert_eq!(
        node.reject_counters().get(RejectCause::StaleRelease).raw(),
        3
    );
}

/// The feedback of one tick (four legs at zero, wheels, IMU), sealed with the plant's next
/// counters.
fn feedback_frames(plant: &mut Sender) -> Vec<protocol::Frame> {
    common::plant_feedback(&Joints::splat(0.0))
        .iter()
        .map(|m| seal(plant, m))
        .collect()
}

/// Sends one teleop command per mode, sealed in sequence by `teleop`; returns how many the
/// node applied and how many it refused as rate limited (any other refusal fails the test).
fn flood(node: &mut Node, now: u32, modes: &[TeleopMode], teleop: &mut Sender) -> (u32, u32) {
    let (mut applied, mut limited) = (0, 0);
    for (k, mode) in modes.iter().enumerate() {
        let frame = teleop_frame(teleop, *mode);
        match node.on_frame(Tick(now), frame.id(), frame.data()) {
            Ok(()) => applied += 1,
            Err(DecodeError::RateLimited { id: 0x200 }) => limited += 1,
            Err(other) => panic!("teleop frame {k} refused: {other:?}"),
        }
    }
    (applied, limited)
}

/// A node whose restart interlock the operator has released at tick 0 (STOP, as X does),
/// polled once, and the operator's sender.
fn node_after_stop() -> (Node, Sender) {
    let mut node = node();
    let mut teleop = Sender::new();
    assert_eq!(
        flood(&mut node, 0, &[TeleopMode::Stop], &mut teleop),
        (1, 0)
    );
    node.poll(Tick(0));
    (node, teleop)
}

#[test]
fn a_teleop_flood_is_rate_limited_per_tick_and_counted_and_other_traffic_still_flows() {
    assert_eq!(TELEOP_COMMANDS_PER_TICK, 2);
    let (mut node, mut teleop) = node_after_stop();
    let mut plant = Sender::new();
    // 10 000 frames/s from a babbling teleop: 40 valid frames, in sequence, in one 4 ms tick.
    // The first two act (Stand, then trot); any of the 38 Folds after them would fold the legs.
    let mut modes = vec![TeleopMode::Stand, TeleopMode::TrotForward];
    modes.extend([TeleopMode::Fold; 38]);
    assert_eq!(flood(&mut node, 1, &modes, &mut teleop), (2, 38));
    assert_eq!(
        node.controller().state(),
        State::Standing(LegMotion::Trot(Direction::Forward))
    );
    assert_eq!(
        node.reject_counters().get(RejectCause::RateLimited).raw(),
        38
    );
    assert_eq!(node.reject_counters().total(), 38);
    // The rest of the bus is served in the same tick: feedback, heartbeats (not limited).
    for frame in feedback_frames(&mut plant) {
        node.on_frame(Tick(1), frame.id(), frame.data())
            .unwrap_or_else(|e| panic!("feedback {:03X} refused: {e:?}", frame.id()));
    }
    for n in 0..40 {
        let heartbeat = AnyMessage::TeleopHeartbeat(TeleopHeartbeat {
            uptime: protocol::Millis::from_raw(n).unwrap(),
        });
        let heartbeat = seal(&mut teleop, &heartbeat);
        node.on_frame(Tick(1), heartbeat.id(), heartbeat.data())
            .unwrap();
    }
    let (output, _) = node.poll(Tick(1));
    assert!(output.legs_enabled, "the feedback armed the drives");
    // The next tick has a new budget, and the limited frames kept the sequence in step: the
    // next two act (stop, then fold), the rest is limited again, none is out of sequence.
    let mut modes = vec![TeleopMode::Stop, TeleopMode::Fold];
    modes.extend([TeleopMode::Stand; 38]);
    assert_eq!(flood(&mut node, 2, &modes, &mut teleop), (2, 38));
    assert_eq!(
        node.controller().state(),
        State::Folding(WheelMotion::Balance)
    );
    for frame in feedback_frames(&mut plant) {
        node.on_frame(Tick(2), frame.id(), frame.data()).unwrap();
    }
    let counters = node.reject_counters();
    assert_eq!(counters.get(RejectCause::RateLimited).raw(), 76);
    assert_eq!(counters.total(), 76);
    assert_eq!(counters.lost.raw(), 0);
    // The limit holds per tick, whatever the gap between ticks: one command per poll is served.
    for tick in 3..50 {
        node.poll(Tick(tick));
        assert_eq!(
            flood(&mut node, tick, &[TeleopMode::Fold], &mut teleop),
            (1, 0)
        );
    }
}

#[test]
fn an_estop_in_a_teleop_flood_acts() {
    let (mut node, mut teleop) = node_after_stop();
    assert_eq!(
        flood(&mut node, 1, &[TeleopMode::Fold; 20], &mut teleop),
        (2, 18)
    );
    assert_eq!(
        node.controller().state(),
        State::Folding(WheelMotion::Balance)
    );
    // The budget is spent, and an E-stop still acts at once.
    let latch = seal(
        &mut teleop,
        &AnyMessage::EStop(EStop::latch(NodeId::Teleop)),
    );
    node.on_frame(Tick(1), latch.id(), latch.data())
        .expect("an E-stop is never rate limited");
    assert_eq!(node.controller().state(), State::EStop);
    assert_eq!(
        flood(&mut node, 1, &[TeleopMode::Fold; 20], &mut teleop),
        (0, 20)
    );
    node.poll(Tick(1));
    assert_eq!(
        flood(&mut node, 2, &[TeleopMode::Stand; 40], &mut teleop),
        (2, 38)
    );
    assert_eq!(node.controller().state(), State::EStop);
    assert_eq!(node.reject_counters().total(), 18 + 20 + 38);
}

#[test]
fn a_tick_that_freezes_or_goes_back_faults_with_sync_lost_until_stop() {
    let mut node = node();
    let joints = common::standing_joints_rad(&Config::ROBOT);
    let mut plant = Sender::new();
    let mut teleop = Sender::new();
    let mut tick = |node: &mut Node, now: u32| {
        for message in common::plant_feedback(&joints) {
            let frame = seal(&mut plant, &message);
            node.on_frame(Tick(now), frame.id(), frame.data()).unwrap();
        }
        node.poll(Tick(now)).0
    };
    for now in 0..20 {
        tick(&mut node, now);
    }
    assert_eq!(node.controller().state(), State::Hold);
    // The lockstep SYNC freezes at tick 19: the next poll is at the same tick.
    let output = tick(&mut node, 19);
    assert_eq!(node.controller().state(), State::Fault);
    assert!(output
        .status
        .faults
        .contains(protocol::FaultFlags::SYNC_LOST));
    // Going back is the same; advancing clears the cause, and STOP then leaves the fault.
    tick(&mut node, 3);
    assert_eq!(node.controller().state(), State::Fault);
    let output = tick(&mut node, 4);
    assert!(!output
        .status
        .faults
        .contains(protocol::FaultFlags::SYNC_LOST));
    assert_eq!(node.controller().state(), State::Fault);
    let stop = teleop_frame(&mut teleop, TeleopMode::Stop);
    node.on_frame(Tick(5), stop.id(), stop.data()).unwrap();
    tick(&mut node, 5);
    assert_eq!(node.controller().state(), State::Hold);
}

#[test]
fn a_release_sent_before_a_second_latch_does_not_undo_it() {
    let mut node = node();
    node.poll(Tick(0));
    let latch = classic_latch(NodeId::Tool, 0).unwrap();
    node.on_frame(Tick(1), latch.id(), latch.data()).unwrap();
    let first = node.release_token();
    // The same source repeating its latch (a teleop does until confirmed) keeps the token.
    node.on_frame(Tick(2), latch.id(), latch.data()).unwrap();
    assert_eq!(node.release_token(), first);
    // An operator released (the frame still on its way) and another source latched meanwhile.
    let mut tool = Sender::new();
    let release = seal(
        &mut tool,
        &AnyMessage::EStop(EStop::release(NodeId::Tool, first)),
    );
    let panel = classic_latch(NodeId::Teleop, 0).unwrap();
    node.on_frame(Tick(2), panel.id(), panel.data()).unwrap();
    assert_ne!(
        node.release_token(),
        first,
        "another source's latch takes a new token"
    );
    assert_eq!(
        node.on_frame(Tick(3), release.id(), release.data()),
        Err(DecodeError::StaleRelease { id: 0x000 })
    );
    assert_eq!(node.controller().state(), State::EStop);
}

/// The session time of the node's latest announcement among `frames`, ms.
fn announced_ms(frames: &[protocol::Frame]) -> Option<u32> {
    frames.iter().find_map(|frame| {
        match decode_frame(frame.id(), frame.data()).map(|d| d.message) {
            Ok(AnyMessage::Announce(announce)) => Some(announce.time.ms()),
            _ => None,
        }
    })
}

/// Polls `node` from tick `from` for `n` ticks; the last announced session time, ms.
fn run_ticks(node: &mut Node, from: u32, n: u32) -> u32 {
    let mut last = None;
    for k in 0..n {
        let (_, frames) = node.poll(Tick(from.wrapping_add(k)));
        last = announced_ms(&frames).or(last);
    }
    last.expect("announced")
}

#[test]
fn the_session_time_follows_the_ticks_forward_only_and_across_the_u32_wrap() {
    // 250 ticks at 250 Hz: the announcements' time reaches about one second (50 Hz: the last
    // one a few ticks before the end).
    let mut node = node();
    let after_1_s = run_ticks(&mut node, 0, 250);
    assert!((960..=1_000).contains(&after_1_s), "{after_1_s} ms");
    // A tick that goes back (a restarted simulator's SYNC) adds nothing: the time never goes
    // back, and counting resumes from the new tick.
    let back = run_ticks(&mut node, 10, 250);
    assert!(back > after_1_s, "{back} ms after {after_1_s} ms");
    assert!(
        (back - after_1_s) <= 1_000 + 8,
        "{back} ms after {after_1_s} ms"
    );
    // A tick half the counter (2^31) ahead of the last one (tick 259) is taken as one that
    // went back: nothing added.
    let ahead = run_ticks(&mut node, 10 + 249 + (1 << 31), 5);
    assert!(ahead <= back + 5 * 4, "{ahead} ms after {back} ms");
    // Ticks that wrap past u32::MAX count as the ticks they are.
    let mut wrapping = common::node(Config::ROBOT);
    let start = u32::MAX - 100;
    let across = run_ticks(&mut wrapping, start, 250);
    assert!(
        (960..=1_000).contains(&across),
        "{across} ms across the wrap"
    );
}

#[test]
fn a_restored_latch_starts_the_node_latched_until_a_fresh_release() {
    let mut node = node();
    assert!(!node.estop_latched());
    node.restore_latch(Tick(0));
    assert!(node.estop_latched());
    let (output, _) = node.poll(Tick(1));
    assert_eq!(output.status.mode, protocol::ControllerMode::EStop);
    let (output, _) = node.poll(Tick(2));
    assert!(output
        .status
        .faults
        .contains(protocol::FaultFlags::ESTOP_LATCHED));
    assert_eq!(node.controller().state(), State::EStop);
}

#[test]
fn the_announcement_before_the_first_tick_and_the_status_tick_say_what_the_node_is() {
    let mut node = node();
    // What a lockstep runner sends while it waits for its first SYNC.
    let frame = node.announce_frame().expect("an announcement");
    match decode_frame(frame.id(), frame.data()).map(|d| d.message) {
        Ok(AnyMessage::Announce(announce)) => {
            assert_eq!(announce.version, protocol::WireVersion::THIS);
            assert_eq!(Some(announce.epoch), node.session().epoch());
        }
        other => panic!("{other:?}"),
    }
    // The status carries the tick it was sent in.
    let status_tick = (0..20).find_map(|tick| {
        let (_, frames) = node.poll(Tick(1_000 + tick));
        frames.iter().find_map(
            |f| match decode_frame(f.id(), f.data()).map(|d| d.message) {
                Ok(AnyMessage::ControllerStatus(status)) => Some((tick, status.tick.raw())),
                _ => None,
            },
        )
    });
    let (tick, raw) = status_tick.expect("a status within 20 ticks");
    assert_eq!(raw, 1_000 + tick);
}
