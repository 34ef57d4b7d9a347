//! The sender's counters: per identifier from the session time, a sender restarted within the
//! session, and two operators releasing the E-stop in turn.

mod common;

use common::clock::Clock;
use common::frames::{heartbeat, receive, NEW, OLD};
use common::{member_at, owner_at};
use protocol::*;

#[test]
fn the_sender_counts_per_identifier_from_the_session_time() {
    let session = Session::owned(TEST_KEY, OLD).at(SessionTime::from_ms(5_000));
    let mut tx = Sender::new();
    let counter = |frame: Frame| decode_frame(frame.id(), frame.data()).unwrap().counter;
    let wheel = AnyMessage::WheelCommand(WheelCommand {
        enable: DriveEnable::Enabled,
        torque: [Torque::default(); 2],
    });
    let legs = AnyMessage::LegTargets(LegTargets {
        enable: DriveEnable::Disabled,
        position: [Angle::default(); 16].into(),
    });
    for expected in 5_000..5_003 {
        assert_eq!(counter(tx.seal(&session, &wheel).unwrap()), expected);
    }
    // Every identifier started at the session time of the sender's first frame in the
    // session; later frames count on from there, whatever the time.
    let later = session.at(SessionTime::from_ms(9_000));
    assert_eq!(counter(tx.seal(&later, &legs).unwrap()), 5_000);
    assert_eq!(counter(tx.seal(&later, &wheel).unwrap()), 5_003);
    // The E-stop counts with the session time: the greater of its next counter and the time.
    let release = AnyMessage::EStop(EStop::release(NodeId::Teleop, ReleaseToken::new(1)));
    let latch = AnyMessage::EStop(EStop::latch(NodeId::Teleop));
    assert_eq!(counter(tx.seal(&later, &release).unwrap()), 9_000);
    assert_eq!(counter(tx.seal(&later, &latch).unwrap()), 9_001);
    assert_eq!(counter(tx.seal(&later, &release).unwrap()), 9_002);
    let later = session.at(SessionTime::from_ms(20_000));
    assert_eq!(counter(tx.seal(&later, &release).unwrap()), 20_000);
    assert_eq!(counter(tx.seal(&later, &wheel).unwrap()), 5_004);
    // Another session starts every counter again, at that session's time.
    let next = Session::owned(TEST_KEY, NEW).at(SessionTime::from_ms(250));
    assert_eq!(counter(tx.seal(&next, &wheel).unwrap()), 250);
    assert_eq!(counter(tx.seal(&next, &legs).unwrap()), 250);
    assert_eq!(counter(tx.seal(&next, &release).unwrap()), 250);
}

/// Wire version 2 first refused a teleop restarted within the session until it resumed its
/// counters from a state file. Now a node restarted within the session starts its counters at
/// the session time it joins at, past everything it sent before: the controller and every
/// member take it from its first frame, and the frames of its previous life stay refused.
#[test]
fn a_sender_restarted_within_the_session_is_taken_from_its_first_frame() {
    for down_for in [30, 150_000] {
        let mut clock = Clock::new(1_000);
        let mut controller = owner_at(OLD, 1_000);
        let mut drive = member_at(OLD, 1_000);
        // First life: the teleop joins at 1 s and sends a heartbeat every 20 ms for 10 s.
        let mut teleop = member_at(OLD, 1_000);
        let mut tx = Sender::new();
        let mut first_life = Vec::new();
        for k in 0..500 {
            let ms = 1_000 + 20 * k;
            clock.to(ms, &mut controller, &mut [&mut drive, &mut teleop]);
            let frame = tx.seal(teleop.session(), &heartbeat(ms)).unwrap();
            for rx in [&mut controller, &mut drive] {
                assert!(receive(rx, &frame).is_ok());
            }
            first_life.push(frame);
        }
        // The teleop restarts: a new receiver joins on the next announcement, a new sender.
        let back = clock.ms + down_for;
        clock.to(back, &mut controller, &mut [&mut drive]);
        let mut teleop = Receiver::member(TEST_KEY);
        clock.announce(back / 20 * 20 + 20, &mut [&mut drive, &mut teleop]);
        let rejoined = teleop.session().time().ms();
        clock.to(rejoined + 5, &mut controller, &mut []);
        let mut tx = Sender::new();
        let frame = tx.seal(teleop.session(), &heartbeat(rejoined)).unwrap();
        assert_eq!(
            decode_frame(frame.id(), frame.data()).unwrap().counter,
            rejoined as u16,
            "it starts at the session time it joined at"
        );
        // Its counter jumped further than the session time moved since its last frame (it
        // sent one frame every 20 ms): a restart, not a loss.
        for rx in [&mut controller, &mut drive] {
            let lost_before = rx.counters().lost;
            assert_eq!(receive(rx, &frame).unwrap().status, E2eStatus::Initial);
            assert_eq!(rx.counters().lost, lost_before);
        }
        // Its previous life, replayed now, is refused by both, in any order.
        for frame in first_life.iter().rev().chain(&first_life) {
            for rx in [&mut controller, &mut drive] {
                let refused = receive(rx, frame).unwrap_err();
                assert!(
                    matches!(
                        refused,
                        DecodeError::WrongSequence { .. } | DecodeError::Unauthentic { .. }
                    ),
                    "{refused:?}"
                );
            }
        }
        // And its new life goes on in sequence.
        let frame = tx.seal(teleop.session(), &heartbeat(rejoined)).unwrap();
        for rx in [&mut controller, &mut drive] {
            assert_eq!(receive(rx, &frame).unwrap().status, E2eStatus::Ok);
        }
    }
}

/// Wire version 2 first counted E-stop releases like any identifier, from zero per sender, so
/// that two operators releasing on the one E-stop identifier (the teleop and a tool) collided
/// and the second was refused as a repeat. Now a release counts with the session time.
#[test]
fn two_operators_releasing_in_turn_are_both_taken() {
    let mut clock = Clock::new(1_000);
    let mut controller = owner_at(OLD, 1_000);
    let mut teleop = member_at(OLD, 1_000);
    let mut tool = member_at(OLD, 1_000);
    let mut teleop_tx = Sender::new();
    let mut tool_tx = Sender::new();
    let release = |source| AnyMessage::EStop(EStop::release(source, ReleaseToken::new(3)));
    let latch = |source| AnyMessage::EStop(EStop::latch(source));
    let mut statuses = Vec::new();
    // Among them times just past a 2^16 ms boundary of the controller's time (65 536,
    // 131 072), where the operator seals at the last announced time, just before it.
    for (ms, source) in [
        (10_020, NodeId::Teleop),
        (12_040, NodeId::Tool),
        (12_150, NodeId::Teleop),
        (30_010, NodeId::Teleop),
        (31_000, NodeId::Tool),
        (65_538, NodeId::Teleop),
        (65_600, NodeId::Tool),
        (100_000, NodeId::Tool),
        (100_130, NodeId::Teleop),
        (131_075, NodeId::Tool),
        (131_190, NodeId::Teleop),
        (190_500, NodeId::Teleop),
        (190_610, NodeId::Tool),
    ] {
        clock.to(ms, &mut controller, &mut [&mut teleop, &mut tool]);
        let (tx, rx) = match source {
            NodeId::Teleop => (&mut teleop_tx, &teleop),
            _ => (&mut tool_tx, &tool),
        };
        // Each operator latches first, then releases.
        let frame = tx.seal(rx.session(), &latch(source)).unwrap();
        assert!(receive(&mut controller, &frame).is_ok());
        let frame = tx.seal(rx.session(), &release(source)).unwrap();
        let accepted = receive(&mut controller, &frame)
            .unwrap_or_else(|e| panic!("{source:?} at {ms} ms: {e:?}"));
        assert_eq!(accepted.message, release(source));
        statuses.push(accepted.status);
    }
    assert_eq!(statuses[0], E2eStatus::Initial);
    assert!(statuses.iter().all(|s| s.is_accepted()));
    assert_eq!(controller.counters().total(), 0);
}
