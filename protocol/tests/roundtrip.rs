//! encode → decode is the identity for every message, and physical values survive within half
//! a quantization step.

mod common;

use proptest::prelude::*;
use protocol::*;

proptest! {
    #[test]
    fn every_message_round_trips(message in common::any_message(), counter in any::<u32>()) {
        let frame = message.encode(&common::controller_session(), counter).unwrap();
        prop_assert_eq!(frame.id(), message.id().raw());
        prop_assert_eq!(frame.data().len(), message.id().layout().wire_len);
        let decoded = decode_frame(frame.id(), frame.data()).unwrap();
        prop_assert_eq!(decoded.message, message);
        prop_assert_eq!(decoded.counter, counter as u16, "the low half travels");
        prop_assert_eq!(decoded.id, message.id());
    }

    /// What the sender seals, the receivers of its session accept: the check value the encoder
    /// writes is the one the receiver computes, for every message and both kinds of check. A
    /// sender's counter is at most `MAX_LAG_MS` behind the session time (and a member's view of
    /// the time may trail the controller's), so the receivers are at the counter or up to that
    /// much past it.
    #[test]
    fn every_sealed_message_is_accepted_by_the_session(
        message in common::any_message(),
        counter in prop_oneof![0_u32..0x2_0000, any::<u32>().prop_map(|c| c >> 1)],
        lag in prop_oneof![Just(0_u32), Just(e2e::MAX_LAG_MS), 0..=e2e::MAX_LAG_MS],
    ) {
        prop_assume!(!matches!(message, AnyMessage::Announce(_)));
        let frame = message.encode(&common::controller_session(), counter).unwrap();
        let now = counter + lag;
        for mut rx in [
            common::owner_at(common::EPOCH, now),
            common::member_at(common::EPOCH, now),
        ] {
            let accepted = rx.receive(frame.id(), frame.data()).unwrap();
            prop_assert_eq!(accepted.message, message);
            prop_assert_eq!(accepted.status, E2eStatus::Initial);
            prop_assert_eq!(rx.counters().total(), 0);
        }
    }

    #[test]
    fn angles_round_trip_within_half_a_step(rad in -3.2768_f32..3.2767) {
        let wire = Angle::from_si(rad).unwrap();
        prop_assert!((wire.si() - rad).abs() <= Angle::STEP / 2.0 + 1e-6);
    }

    #[test]
    fn body_height_is_checked_against_the_elevator_range(m in -0.2_f32..0.2) {
        match BodyHeight::from_si(m) {
            Some(h) => {
                prop_assert!((-0.10..=0.12).contains(&h.si()));
                prop_assert!((h.si() - m).abs() <= BodyHeight::STEP / 2.0 + 1e-6);
            }
            None => prop_assert!(!(-0.10001..=0.12001).contains(&m)),
        }
    }

    #[test]
    fn saturating_conversion_never_leaves_the_range(v in prop_oneof![any::<f32>(), Just(f32::NAN), Just(f32::INFINITY)]) {
        let w = WheelAngle::saturating_from_si(v);
        prop_assert!(w.raw() >= WheelAngle::RAW_MIN && w.raw() <= WheelAngle::RAW_MAX);
        prop_assert!(w.si().is_finite());
    }

    #[test]
    fn arbitrary_bytes_never_panic_the_decoder(id in 0_u16..0x800, data in proptest::collection::vec(any::<u8>(), 0..=64)) {
        for mut rx in [
            Receiver::owner(common::controller_session()),
            Receiver::member(TEST_KEY),
            common::joined_member(common::EPOCH),
        ] {
            let _ = rx.receive(id, &data);
        }
        let _ = decode_frame(id, &data);
    }
}

#[test]
fn every_id_maps_back_to_itself_and_has_a_unique_index() {
    for (i, id) in MessageId::ALL.into_iter().enumerate() {
        assert_eq!(MessageId::from_raw(id.raw()), Some(id));
        assert_eq!(id.index(), i);
    }
    let ids: Vec<u16> = MessageId::ALL.iter().map(|id| id.raw()).collect();
    assert!(
        ids.windows(2).all(|w| w[0] < w[1]),
        "ALL must be in priority order: {ids:x?}"
    );
}

#[test]
fn estop_has_the_highest_priority_then_sync_then_the_announcement_then_commands() {
    assert_eq!(MessageId::EStop.raw(), 0);
    assert!(MessageId::Sync.raw() < MessageId::Announce.raw());
    assert!(MessageId::Announce.raw() < MessageId::LegTargets.raw());
    assert!(MessageId::WheelCommand.raw() < MessageId::LegFeedback(Leg::Fl).raw());
    assert!(MessageId::Imu.raw() < MessageId::TeleopCommand.raw());
    assert!(MessageId::TeleopHeartbeat.raw() < MessageId::ControllerStatus.raw());
    assert!(MessageId::DriveStatus(Drive::Wheel).raw() < MessageId::RejectCounters.raw());
}
