//! The E-stop latch: the classic-CAN frame of a panel is accepted by anyone, again and again, a
//! classic frame that is not a latch is refused, and any latch with a valid CRC acts.

mod common;

use common::frames::{receive, NEW, OLD, PANEL_COUNTER};
use common::joined_member;
use proptest::prelude::*;
use protocol::*;

#[test]
fn a_classic_latch_is_accepted_by_anyone_again_and_again() {
    for source in NodeId::ALL {
        let frame = classic_latch(source, PANEL_COUNTER).unwrap();
        assert_eq!(frame.id(), 0);
        assert_eq!(frame.data().len(), CLASSIC_LATCH_LEN);
        assert_eq!(CLASSIC_LATCH_LEN, 8);
        for mut rx in [
            Receiver::member(TEST_KEY),
            joined_member(OLD),
            Receiver::owner(Session::owned(TEST_KEY, OLD)),
            Receiver::member(Key([9; 16])),
        ] {
            for _ in 0..5 {
                let accepted = receive(&mut rx, &frame).unwrap();
                assert_eq!(accepted.message, AnyMessage::EStop(EStop::latch(source)));
                assert_eq!(accepted.status, E2eStatus::Initial);
            }
            assert_eq!(rx.counters().total(), 0);
        }
        let decoded = decode_frame(frame.id(), frame.data()).unwrap();
        assert_eq!(decoded.counter, PANEL_COUNTER);
    }
}

#[test]
fn a_classic_frame_that_is_not_a_latch_is_refused() {
    let release = AnyMessage::EStop(EStop::release(NodeId::Teleop, ReleaseToken::new(0)))
        .encode(&Session::owned(TEST_KEY, OLD), 0)
        .unwrap();
    let classic = &release.data()[..CLASSIC_LATCH_LEN];
    let wrong_length = Err(DecodeError::WrongLength {
        id: 0,
        expected: 12,
        got: 8,
    });
    for mut rx in [
        joined_member(OLD),
        Receiver::owner(Session::owned(TEST_KEY, OLD)),
    ] {
        assert_eq!(rx.receive(0, classic), wrong_length);
        assert_eq!(rx.counters().get(RejectCause::WrongLength).raw(), 1);
        // The full frame is a release like any other.
        assert!(receive(&mut rx, &release).is_ok());
    }
    assert!(Receiver::member(TEST_KEY).receive(0, classic).is_err());
    assert!(matches!(
        decode_frame(0, classic),
        Err(DecodeError::WrongLength { got: 8, .. })
    ));
    // A latch's eight bytes on any other identifier, and a corrupted classic latch.
    let latch = classic_latch(NodeId::Tool, 0).unwrap();
    let mut rx = joined_member(OLD);
    assert!(matches!(
        rx.receive(0x200, latch.data()),
        Err(DecodeError::WrongLength { got: 8, .. })
    ));
    let mut corrupted = latch.data().to_vec();
    corrupted[7] ^= 0x01;
    assert_eq!(
        rx.receive(0, &corrupted),
        Err(DecodeError::CrcMismatch { id: 0 })
    );
}

proptest! {
    /// Whatever its counter, session or sender, a latch with a valid CRC acts.
    #[test]
    fn a_latch_acts_whatever_its_counter_and_session(
        source in proptest::sample::select(&NodeId::ALL[..]),
        counter in any::<u32>(),
        epoch in proptest::option::of(any::<u32>()),
        classic in any::<bool>(),
    ) {
        let session = match epoch {
            Some(epoch) => Session::owned(Key([3; 16]), Epoch::new(epoch)),
            None => Session::unjoined(Key([3; 16])),
        };
        let frame = if classic {
            classic_latch(source, counter as u16).unwrap()
        } else {
            AnyMessage::EStop(EStop::latch(source)).encode(&session, counter).unwrap()
        };
        for mut rx in [
            Receiver::member(TEST_KEY),
            joined_member(OLD),
            Receiver::owner(Session::owned(TEST_KEY, NEW)),
        ] {
            let accepted = rx.receive(frame.id(), frame.data()).unwrap();
            prop_assert_eq!(accepted.message, AnyMessage::EStop(EStop::latch(source)));
        }
    }
}
