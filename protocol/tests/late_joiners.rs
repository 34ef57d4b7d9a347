//! Members that join late in the session: they find each sender at its next frame, past wraps
//! of the low counter and period boundaries, and refuse a replay from beyond their search.

mod common;

use common::clock::slow_sender_counters;
use common::frames::{check_failed, heartbeat, receive, wheel_feedback, wheel_message, OLD};
use common::{member_at, owner_at};
use protocol::e2e::MAX_LAG_MS;
use protocol::*;

#[test]
fn a_late_joiner_finds_a_crc_sender_past_the_first_wrap() {
    // The status went out every millisecond since the session opened: its counter is about
    // the session time, which the member learns from the announcement it joins on.
    let status = |counter: u32| {
        AnyMessage::Sync(Sync {
            tick: Tick::from_raw(counter).unwrap(),
        })
        .encode(&Session::owned(TEST_KEY, OLD), counter)
        .unwrap()
    };
    let first = 200 << 16 | 0x1234;
    let mut member = member_at(OLD, first - 40);
    assert_eq!(
        receive(&mut member, &status(first)).unwrap().status,
        E2eStatus::Initial
    );
    assert_eq!(
        receive(&mut member, &status(first + 1)).unwrap().status,
        E2eStatus::Ok
    );
}

/// Wire version 2 first looked for a sender's first CMAC frame at high half zero only, so a
/// node that joined after the sender's counter passed 2^16 never accepted it. Now the senders
/// count from the session time and the late joiner looks around its own.
#[test]
fn a_member_that_joins_after_the_counter_wrapped_takes_the_next_frame() {
    // The controller's wheel command (CRC), the wheel drive's feedback (CRC) and the teleop's
    // heartbeat (CMAC), each every millisecond since the session opened: 70 000 of each
    // before the member joins. The drive and the teleop seal at the announced time.
    let at = |ms| Session::owned(TEST_KEY, OLD).at(SessionTime::from_ms(ms));
    let mut controller = Sender::new();
    let mut wheel_drive = Sender::new();
    let mut teleop = Sender::new();
    let mut sent: [Vec<Frame>; 3] = Default::default();
    for ms in 0..70_002 {
        let announced = at(ms / 20 * 20);
        sent[0].push(controller.seal(&at(ms), &wheel_message(ms)).unwrap());
        sent[1].push(wheel_drive.seal(&announced, &wheel_feedback(ms)).unwrap());
        sent[2].push(teleop.seal(&announced, &heartbeat(ms)).unwrap());
    }
    assert_eq!(
        decode_frame(0x101, sent[0][69_999].data()).unwrap().counter,
        (69_999_u32 - 0x1_0000) as u16,
        "the low counter wrapped"
    );
    let mut member = member_at(OLD, 70_000);
    for stream in &sent {
        let frame = |ms: u32| &stream[ms as usize];
        let id = frame(0).id();
        assert_eq!(
            receive(&mut member, frame(70_000)).unwrap().status,
            E2eStatus::Initial,
            "{id:#x}"
        );
        assert_eq!(
            receive(&mut member, frame(70_001)).unwrap().status,
            E2eStatus::Ok
        );
        // Replays of frames older than the last accepted are refused: within 2^15 as out of
        // sequence, further back as failing their check (the search looks only ahead).
        let check_failed = check_failed(frame(0));
        for (ms, refused) in [
            (70_001, DecodeError::Repeated { id }),
            (70_000, DecodeError::WrongSequence { id }),
            (69_999, DecodeError::WrongSequence { id }),
            (70_001 - 0x8000, DecodeError::WrongSequence { id }),
            (70_001 - 0x8001, check_failed),
            (70_001 - 0x1_0000, check_failed),
            (70_002 - 0x1_0000, check_failed),
            (0, check_failed),
        ] {
            assert_eq!(
                receive(&mut member, frame(ms)),
                Err(refused),
                "{id:#x} {ms}"
            );
        }
    }
    assert_eq!(member.counters().total(), 24);
    assert_eq!(member.counters().get(RejectCause::Unauthentic).raw(), 4);
    assert_eq!(member.counters().lost.raw(), 0);
}

/// A member that has just joined has no sequence to hold a frame against: it takes the first
/// genuine frame its search finds, and so takes a frame replayed from earlier in the session if
/// its counter is one of the search's two candidates: the counter with the frame's low half
/// nearest the member's session time (within ±2^15 ms), and the one 2^16 below that. So a
/// replay is taken back to 2^15 + 2^16 ms (98.3 s) before the member's time and refused from
/// further back, CMAC and CRC alike; which end of the window is closed depends on the low half
/// of the member's time (the candidate 2^15 away on either side is the one in the same period of
/// 2^16). Every genuine sender is well inside: its counter is at most `MAX_LAG_MS` (16.4 s)
/// behind the session time.
///
/// Wire version 2 first looked through 2^8 periods of 2^16 ms for a CMAC (4.66 h) and 2^12 for
/// a CRC (74.6 h): a frame recorded two minutes or an hour before was taken.
#[test]
fn a_freshly_joined_member_refuses_a_replay_from_beyond_its_search() {
    let sync = |counter: u32| {
        AnyMessage::Sync(Sync {
            tick: Tick::from_raw(counter).unwrap(),
        })
        .encode(&Session::owned(TEST_KEY, OLD), counter)
        .unwrap()
    };
    let command = |counter: u32| {
        AnyMessage::TeleopCommand(TeleopCommand {
            mode: TeleopMode::WheelForward,
            body_height: BodyHeight::default(),
            speed_scale: SpeedScale::from_raw(40).unwrap(),
            speed: Default::default(),
            yaw_rate: Default::default(),
        })
        .encode(&Session::owned(TEST_KEY, OLD), counter)
        .unwrap()
    };
    type Seal = fn(u32) -> Frame;
    let cases: [(Seal, DecodeError); 2] = [
        (command, DecodeError::Unauthentic { id: 0x200 }),
        (sync, DecodeError::CrcMismatch { id: 0x010 }),
    ];
    const WINDOW: u32 = 0x8000 + 0x1_0000;
    assert_eq!(WINDOW, 98_304);
    for (seal, check_failed) in cases {
        // The member joins at `now`, 5.5 h into the session, low half below or above 2^15.
        for now in [300 << 16 | 0x1234, 300 << 16 | 0x9234] {
            // The oldest counter its search reaches.
            let oldest = if now & 0xFFFF < 0x8000 {
                now - WINDOW + 1
            } else {
                now - WINDOW
            };
            for (recorded, taken) in [
                (now, true),
                (now - 10, true),
                (now - MAX_LAG_MS, true),
                (now - 0x8000, true),
                (now - 60_000, true),
                (oldest, true),
                (oldest - 1, false),
                (now - 0x2_0000, false),
                (now - 120_000, false),
                (now - 3_600_000, false),
                (now - (1 << 24), false),
                (now - ((1 << 12) << 16).min(now), false),
            ] {
                let mut member = member_at(OLD, now);
                let got = receive(&mut member, &seal(recorded));
                if taken {
                    assert_eq!(got.unwrap().status, E2eStatus::Initial, "{now} {recorded}");
                } else {
                    assert_eq!(got, Err(check_failed), "{now} {recorded}");
                }
                // Either way the genuine sender's next frame is taken, and the replay is then
                // behind it.
                let genuine = now + 10;
                assert!(receive(&mut member, &seal(genuine))
                    .unwrap()
                    .status
                    .is_accepted());
                assert!(receive(&mut member, &seal(recorded)).is_err());
            }
        }
    }
}

/// Wire version 2 first looked for a first frame from the period of 2^16 ms after the
/// receiver's time's downward, the controller in two periods: a teleop that joined on an
/// announcement just below a boundary (65 500 ms) sealed its first frames there, while the
/// controller's time had passed the boundary (65 540 ms), so the controller refused it until
/// its counter passed 65 536. Now every receiver looks first at the counter nearest its time.
#[test]
fn a_teleop_joining_just_below_a_period_boundary_is_taken_from_its_first_frame() {
    let mut controller = owner_at(OLD, 65_540);
    let mut drive = member_at(OLD, 65_540);
    let teleop = member_at(OLD, 65_500);
    let mut tx = Sender::new();
    let command = AnyMessage::TeleopCommand(TeleopCommand {
        mode: TeleopMode::WheelForward,
        body_height: BodyHeight::default(),
        speed_scale: SpeedScale::from_raw(50).unwrap(),
        speed: Default::default(),
        yaw_rate: Default::default(),
    });
    for (message, status) in [
        (heartbeat(1), E2eStatus::Initial),
        (command, E2eStatus::Initial),
        (heartbeat(2), E2eStatus::Ok),
        (command, E2eStatus::Ok),
    ] {
        let frame = tx.seal(teleop.session(), &message).unwrap();
        let counter = decode_frame(frame.id(), frame.data()).unwrap().counter;
        assert!((65_500..65_502).contains(&u32::from(counter)), "{counter}");
        for rx in [&mut controller, &mut drive] {
            let accepted = receive(rx, &frame).unwrap();
            assert_eq!(accepted.message, message);
            assert_eq!(accepted.status, status, "{message:?}");
        }
    }
    assert_eq!(*controller.counters(), *drive.counters());
    assert_eq!(controller.counters().total(), 0);
    assert_eq!(controller.counters().lost.raw(), 0);
}

/// Wire version 2 first let a 50 Hz sender's counter fall behind the session time by 19 ms a
/// frame: a member that joined 6 h into the session looked for it within 2^8 periods of 2^16 ms
/// below its time (4.66 h) and never found it. Now its counter is within `MAX_LAG_MS`.
#[test]
fn a_member_joining_6_hours_in_takes_a_50_hz_sender_at_its_first_frame() {
    const JOIN: u32 = 6 * 3_600_000;
    // The teleop's heartbeat (CMAC), sealed at each announced time since the session opened.
    let mut tx = Sender::new();
    let times: Vec<u32> = (0..JOIN + 100).step_by(20).collect();
    let expected = slow_sender_counters(&times);
    let frames: Vec<Frame> = times
        .iter()
        .map(|&ms| {
            let session = Session::owned(TEST_KEY, OLD).at(SessionTime::from_ms(ms));
            tx.seal(&session, &heartbeat(ms)).unwrap()
        })
        .collect();
    let at_join = times.iter().position(|&ms| ms == JOIN).unwrap();
    assert!(JOIN - expected[at_join] <= MAX_LAG_MS);
    let mut member = member_at(OLD, JOIN);
    for (k, frame) in frames.iter().enumerate().skip(at_join) {
        let decoded = decode_frame(frame.id(), frame.data()).unwrap();
        assert_eq!(decoded.counter, expected[k] as u16);
        let status = receive(&mut member, frame).unwrap().status;
        let want = if k == at_join {
            E2eStatus::Initial
        } else {
            E2eStatus::Ok
        };
        assert_eq!(status, want, "{}", times[k]);
    }
    assert_eq!(member.counters().total(), 0);
    assert_eq!(member.counters().lost.raw(), 0);
}
