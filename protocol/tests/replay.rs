//! A recorded bus replayed: single frames, pairs, slices and the whole log, later in their
//! session and in a new one, are refused but for the E-stop latches.

mod common;

use common::bus::Logged;
use common::recorded::{expected_later, expected_next_session, recorded, replay, traffic_goes_on};
use proptest::prelude::*;
use protocol::*;

#[test]
fn the_recorded_run_wraps_the_counter_and_carries_every_kind_of_frame() {
    let log = &recorded().log;
    let on = |id: MessageId| log.iter().filter(|l| l.id() == id).count();
    assert!(on(MessageId::WheelCommand) > 1 << 16);
    assert!(on(MessageId::WheelFeedback) > 1 << 16);
    for id in [
        MessageId::Announce,
        MessageId::LegTargets,
        MessageId::TeleopCommand,
        MessageId::TeleopHeartbeat,
        MessageId::ControllerStatus,
    ] {
        assert!(on(id) > 0, "{id:?}");
    }
    let latches = log.iter().filter(|l| l.is_latch()).count();
    assert_eq!(latches, 14, "7 sealed and 7 classic");
    assert_eq!(on(MessageId::EStop), 21, "and 7 releases");
    // The identifiers slower than one frame a millisecond fell `MAX_LAG_MS` behind the session
    // time and jumped to it, again and again; the 1 kHz ones never did.
    let jumps = |id: MessageId| {
        let counters: Vec<u32> = log
            .iter()
            .filter(|l| l.id() == id)
            .map(|l| l.counter)
            .collect();
        counters.windows(2).filter(|w| w[1] != w[0] + 1).count()
    };
    for id in [
        MessageId::LegTargets,
        MessageId::TeleopHeartbeat,
        MessageId::ControllerStatus,
        MessageId::TeleopCommand,
    ] {
        assert!(jumps(id) >= 2, "{id:?}: {}", jumps(id));
    }
    assert_eq!(jumps(MessageId::WheelCommand), 0);
    assert_eq!(jumps(MessageId::WheelFeedback), 0);
}

#[test]
fn the_whole_log_replayed_later_in_its_session_is_refused_but_for_the_latches() {
    // (And the latest announcement, which the members take again without effect.)
    let recorded = recorded();
    let mut bus = recorded.later.clone();
    let tally = replay(&mut bus, &recorded.log, expected_later);
    // Every way a replay in the same session fails occurred.
    for cause in [
        RejectCause::Repeated,
        RejectCause::WrongSequence,
        RejectCause::Crc,
        RejectCause::Unauthentic,
    ] {
        assert!(tally[cause as usize] > 0, "{cause:?}: {tally:?}");
    }
    assert_eq!(tally[RejectCause::Session as usize], 0);
    traffic_goes_on(&mut bus, 200);
}

#[test]
fn the_whole_log_replayed_in_a_new_session_is_refused_but_for_the_latches() {
    let recorded = recorded();
    let mut bus = recorded.next_session.clone();
    // Every node hears every frame of the old session: the one that joined last (no sequence
    // on any identifier) and each node its own identifiers too, which it has no sequence on.
    // A receiver with no sequence looks only near its session time (300 ms into the new
    // session): the old session's frames fail their check there, and everywhere else.
    let tally = replay(&mut bus, &recorded.log, expected_next_session);
    for cause in [
        RejectCause::Crc,
        RejectCause::Unauthentic,
        RejectCause::Session,
    ] {
        assert!(tally[cause as usize] > 0, "{cause:?}: {tally:?}");
    }
    assert_eq!(tally[RejectCause::Repeated as usize], 0);
    assert_eq!(tally[RejectCause::WrongSequence as usize], 0);
    traffic_goes_on(&mut bus, 200);
}

/// A pick of frames from the log: `at` places it, `len` frames long.
fn slice(at: prop::sample::Index, len: usize) -> &'static [Logged] {
    let log = &recorded().log;
    let start = at.index(log.len() - len + 1);
    &log[start..start + len]
}

/// Two consecutive frames of one identifier, as the old resynchronisation rule wanted.
fn consecutive_on_one_id(id: prop::sample::Index, at: prop::sample::Index) -> [Logged; 2] {
    let log = &recorded().log;
    let ids = [
        MessageId::Announce,
        MessageId::WheelCommand,
        MessageId::WheelFeedback,
        MessageId::LegTargets,
        MessageId::TeleopCommand,
        MessageId::TeleopHeartbeat,
        MessageId::ControllerStatus,
        MessageId::EStop,
    ];
    let id = ids[id.index(ids.len())];
    let on_id: Vec<&Logged> = log
        .iter()
        .filter(|l| l.id() == id && !l.is_latch())
        .collect();
    let i = at.index(on_id.len() - 1);
    [*on_id[i], *on_id[i + 1]]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    #[test]
    fn any_frame_replayed_later_in_its_session_is_refused(at in any::<prop::sample::Index>()) {
        let mut bus = recorded().later.clone();
        replay(&mut bus, slice(at, 1), expected_later);
        traffic_goes_on(&mut bus, 5);
    }

    #[test]
    fn any_frame_replayed_in_a_new_session_is_refused(at in any::<prop::sample::Index>()) {
        let mut bus = recorded().next_session.clone();
        replay(&mut bus, slice(at, 1), expected_next_session);
        traffic_goes_on(&mut bus, 5);
    }

    #[test]
    fn any_two_consecutive_frames_replayed_are_refused(
        at in any::<prop::sample::Index>(),
        id in any::<prop::sample::Index>(),
        on_id in any::<prop::sample::Index>(),
        twice in any::<bool>(),
    ) {
        let mut pairs = vec![slice(at, 2).to_vec(), consecutive_on_one_id(id, on_id).to_vec()];
        if twice {
            for pair in &mut pairs {
                pair.extend(pair.clone());
            }
        }
        for pair in &pairs {
            let mut bus = recorded().later.clone();
            replay(&mut bus, pair, expected_later);
            traffic_goes_on(&mut bus, 5);
            let mut bus = recorded().next_session.clone();
            replay(&mut bus, pair, expected_next_session);
            traffic_goes_on(&mut bus, 5);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    #[test]
    fn any_slice_of_the_log_replayed_is_refused(
        at in any::<prop::sample::Index>(),
        len in prop_oneof![3_usize..50, 50_usize..3_000],
    ) {
        let frames = slice(at, len);
        let mut bus = recorded().later.clone();
        replay(&mut bus, frames, expected_later);
        traffic_goes_on(&mut bus, 5);
        let mut bus = recorded().next_session.clone();
        replay(&mut bus, frames, expected_next_session);
        traffic_goes_on(&mut bus, 5);
    }
}
