//! Every status of the E2E receiver, the check values against their references, and the wire
//! layout of the header.

use proptest::prelude::*;
use protocol::e2e::{check_value, header, protect, Freshness, Search, HEADER_LEN};
use protocol::{
    AnyMessage, Check, E2eChecker, E2eStatus, Epoch, Key, Receiver, Session, SessionTime, Sync,
    Tick, TEST_KEY,
};

/// The receiver's session time when `checker` is offered a genuine frame of counter `sent`: a
/// sender's counter never passes the session time, so the receiver's time is at or past both
/// `sent` and every counter it accepted before.
fn now_for(checker: &E2eChecker, sent: u32) -> u32 {
    checker.last().map_or(sent, |last| last.max(sent))
}

/// Offers `checker` a frame of a genuine sender whose full counter is `sent`: its check value
/// holds at that counter and at no other, as a check that covers the full counter does. The
/// receiver searches as every receiver does (two candidates).
fn offer(checker: &mut E2eChecker, sent: u32) -> E2eStatus {
    let search = Search::new(now_for(checker, sent));
    checker.check(sent as u16, search, |full| full == sent)
}

/// Offers `checker` a frame whose check holds at no counter: corrupted, forged, or from
/// another session. The receiver searches far wider than any does: every period of 2^16 from
/// the top of the counter range down.
fn offer_forged(checker: &mut E2eChecker, low: u16) -> E2eStatus {
    let search = Search {
        reference: 0xFFFF_0000,
        tries: 1 << 16,
    };
    checker.check(low, search, |_| false)
}

fn checker_after(counters: &[u32]) -> E2eChecker {
    let mut checker = E2eChecker::new();
    for &c in counters {
        assert!(offer(&mut checker, c).is_accepted(), "setup counter {c}");
    }
    checker
}

#[test]
fn first_frame_is_initial_then_ok() {
    let mut checker = E2eChecker::new();
    assert_eq!(checker.last(), None);
    assert_eq!(offer(&mut checker, 40), E2eStatus::Initial);
    assert_eq!(offer(&mut checker, 41), E2eStatus::Ok);
    assert_eq!(checker.last(), Some(41));
}

#[test]
fn a_gap_is_ok_some_lost() {
    let mut checker = checker_after(&[10]);
    assert_eq!(offer(&mut checker, 13), E2eStatus::OkSomeLost { lost: 2 });
    assert_eq!(offer(&mut checker, 14), E2eStatus::Ok);
    // No window short of half the counter range: a longer burst is accepted and counted too.
    assert_eq!(offer(&mut checker, 30), E2eStatus::OkSomeLost { lost: 15 });
    assert_eq!(checker.last(), Some(30));
}

/// A sender counts one frame a millisecond at most: a jump ahead by more frames than
/// milliseconds passed since the last accepted frame (with 100 ms of slack for a member's view
/// of the time) is a sender that restarted at the session time, not a loss.
#[test]
fn a_jump_past_the_elapsed_time_is_a_restart_not_a_loss() {
    let at = Search::new;
    let mut checker = E2eChecker::new();
    let mut offer_at = |sent: u32, now: u32| checker.check(sent as u16, at(now), |f| f == sent);
    assert_eq!(offer_at(1_000, 1_000), E2eStatus::Initial);
    // 300 ms later: up to 400 frames lost is a loss, 401 a restart.
    assert_eq!(offer_at(1_401, 1_300), E2eStatus::OkSomeLost { lost: 400 });
    assert_eq!(offer_at(1_803, 1_600), E2eStatus::Initial);
    assert_eq!(offer_at(1_804, 1_600), E2eStatus::Ok);
    // A slow sender's loss: 9 frames in 500 ms.
    assert_eq!(offer_at(1_814, 2_100), E2eStatus::OkSomeLost { lost: 9 });
}

#[test]
fn the_same_counter_twice_is_repeated() {
    let mut checker = checker_after(&[10]);
    assert_eq!(offer(&mut checker, 10), E2eStatus::Repeated);
    assert_eq!(
        offer(&mut checker, 11),
        E2eStatus::Ok,
        "a repeat does not disturb the sequence"
    );
}

#[test]
fn a_step_backwards_is_wrong_sequence() {
    let mut checker = checker_after(&[10]);
    assert_eq!(offer(&mut checker, 9), E2eStatus::WrongSequence);
    assert_eq!(offer(&mut checker, 0), E2eStatus::WrongSequence);
    assert_eq!(
        offer(&mut checker, 11),
        E2eStatus::Ok,
        "rejected frames do not move the sequence"
    );
}

/// Wire version 1 resynchronised on two consecutive frames, which let a replay of two
/// recorded frames take over the sequence. Now frames behind the sequence never move it, however
/// many there are in a row.
#[test]
fn frames_behind_the_sequence_never_take_it_over() {
    let mut checker = checker_after(&[5000, 5001]);
    for replayed in 0..100 {
        assert_eq!(
            offer(&mut checker, replayed),
            E2eStatus::WrongSequence,
            "replayed frame {replayed}"
        );
    }
    assert_eq!(checker.last(), Some(5001));
    // A new session: the receiver forgets the sequence and the sender starts at the session
    // time, here the start.
    checker.reset();
    assert_eq!(offer(&mut checker, 0), E2eStatus::Initial);
    assert_eq!(offer(&mut checker, 1), E2eStatus::Ok);
}

/// A sender restarted within the session starts its counters at the session time, which is
/// past every counter it sent before: it is in sequence (the frames between count as lost), or,
/// 2^15 or more ahead, found by the search.
#[test]
fn a_sender_restarted_within_the_session_is_taken_from_its_first_frame() {
    let mut checker = checker_after(&[5000, 5001]);
    // Restarted at session time 5100.
    assert_eq!(
        offer(&mut checker, 5100),
        E2eStatus::OkSomeLost { lost: 98 }
    );
    assert_eq!(offer(&mut checker, 5101), E2eStatus::Ok);
    // Restarted again, 100 s later: 2^15 and more ahead.
    let restart = 105_101;
    assert_eq!(offer(&mut checker, restart), E2eStatus::Initial);
    assert_eq!(offer(&mut checker, restart + 1), E2eStatus::Ok);
    // Its earlier lives' frames stay behind.
    for old in [5001, 5100, 5101, restart - 0x8000, restart] {
        assert!(!offer(&mut checker, old).is_accepted(), "{old}");
    }
    assert_eq!(checker.last(), Some(restart + 1));
}

#[test]
fn a_single_replayed_frame_does_not_disturb_the_sequence() {
    let mut checker = checker_after(&[5000]);
    assert_eq!(offer(&mut checker, 100), E2eStatus::WrongSequence);
    assert_eq!(offer(&mut checker, 5001), E2eStatus::Ok);
    assert_eq!(offer(&mut checker, 101), E2eStatus::WrongSequence);
    assert_eq!(offer(&mut checker, 5002), E2eStatus::Ok);
}

#[test]
fn the_counter_wraps_into_the_high_half() {
    let mut checker = checker_after(&[0xFFFE, 0xFFFF]);
    assert_eq!(offer(&mut checker, 0x1_0000), E2eStatus::Ok);
    assert_eq!(checker.last(), Some(0x1_0000));
    // The frame of full counter 0 has the same low half as the one just accepted, but its
    // check holds only at 0: a replay from 2^16 frames ago fails its check.
    assert_eq!(offer(&mut checker, 0), E2eStatus::CheckFailed);
    assert_eq!(offer(&mut checker, 0x1_0001), E2eStatus::Ok);
    assert_eq!(offer(&mut checker, 1), E2eStatus::CheckFailed);
    assert_eq!(offer(&mut checker, 0xFFFF), E2eStatus::WrongSequence);
    assert_eq!(checker.last(), Some(0x1_0001));
}

/// The full counter a receiver at session time `reference` tries first for low half `low`: the
/// one within 2^15 of `reference`, and at exactly 2^15 on either side the one in the same period
/// of 2^16 as `reference`. Negative when the nearest would be below zero (no such counter).
fn nearest(reference: u32, low: u16) -> i64 {
    let lowest = i64::from(reference)
        - if reference & 0xFFFF < 0x8000 {
            0x7FFF
        } else {
            0x8000
        };
    lowest + (i64::from(low) - lowest).rem_euclid(0x1_0000)
}

/// Whether a receiver at session time `reference` finds `counter` among the `tries` candidates
/// of its search: the nearest, then periods of 2^16 below it.
fn among_candidates(reference: u32, tries: u32, counter: u32) -> bool {
    let first = nearest(reference, counter as u16);
    let counter = i64::from(counter);
    counter <= first && (first - counter) >> 16 < i64::from(tries)
}

/// Every receiver makes the same search, whatever the check and whoever it is: two candidates,
/// the counter with the frame's low half nearest its session time, then the one 2^16 below:
/// 2^15 ahead of its time to 2^15 + 2^16 behind it.
#[test]
fn a_first_frame_is_looked_for_nearest_the_receivers_time_then_one_period_below() {
    let first = |sent: u32, search: Search| {
        let mut checker = E2eChecker::new();
        let status = checker.check(sent as u16, search, |full| full == sent);
        let accepted = status.is_accepted();
        assert_eq!(checker.last(), accepted.then_some(sent), "{sent:#x}");
        assert!(matches!(
            status,
            E2eStatus::Initial | E2eStatus::CheckFailed
        ));
        accepted
    };
    for now in [5 << 16 | 0x1234, 5 << 16 | 0x9234] {
        let search = |tries| Search {
            reference: now,
            tries,
        };
        assert_eq!(Search::new(now), search(2));
        // The tie at 2^15 goes to the counter in the period of `now`.
        let (behind, ahead) = if now & 0xFFFF < 0x8000 {
            (0x7FFF, 0x8000)
        } else {
            (0x8000, 0x7FFF)
        };
        // The nearest, found at the first try.
        for sent in [now, now - 1, now + 1, now - behind, now + ahead] {
            assert!(first(sent, search(1)), "{now:#x} {sent:#x}");
        }
        // One period below it: the second try.
        for sent in [now - behind - 1, now - 0x1_0000, now - behind - 0x1_0000] {
            assert!(!first(sent, search(1)), "{now:#x} {sent:#x}");
            assert!(first(sent, search(2)), "{now:#x} {sent:#x}");
            assert!(first(sent, Search::new(now)), "{now:#x} {sent:#x}");
        }
        // Further below: not with two tries, with more.
        for (sent, tries) in [
            (now - behind - 0x1_0001, 3),
            (now - 0x2_0000, 3),
            (now - 0x3_0000, 4),
            (now & 0xFFFF, 6),
        ] {
            assert!(!first(sent, Search::new(now)), "{now:#x} {sent:#x}");
            assert!(!first(sent, search(tries - 1)), "{now:#x} {sent:#x}");
            assert!(first(sent, search(tries)), "{now:#x} {sent:#x}");
        }
        // Past the nearest ahead: never, however many tries.
        for sent in [now + ahead + 1, now + 0x1_0000, now + 0x10_0000] {
            assert!(!first(sent, search(1 << 16)), "{now:#x} {sent:#x}");
        }
        assert!(!first(now, search(0)), "no tries, no search");
    }
    // Near zero there are no candidates below it: a low half whose nearest would be negative
    // is not looked for at all.
    assert!(!first(0x9000, Search::new(10)));
    assert!(first(0x8000, Search::new(0)));
    assert!(first(0x7000, Search::new(10)));
    // A teleop that joined on an announcement just below a boundary of 2^16 ms, its first frame
    // received by the controller just past it. (Wire version 2 first looked from the period
    // after the receiver's time's downward, the controller two periods: 2^17 + 65 500 and
    // 2^16 + 65 500, never 65 500 itself.)
    assert!(first(65_500, Search::new(65_540)));
    assert_eq!(nearest(65_540, 65_500_u32 as u16), 65_500);
}

#[test]
fn half_the_counter_range_ahead_is_found_by_the_search() {
    let mut checker = checker_after(&[10]);
    assert_eq!(
        offer(&mut checker, 10 + 0x7FFF),
        E2eStatus::OkSomeLost { lost: 0x7FFE }
    );
    // 2^15 ahead reads as 2^15 behind, where the check does not hold; the receiver, whose time
    // has reached the frame's counter, finds it in the search and restarts the sequence there.
    let mut checker = checker_after(&[10]);
    assert_eq!(offer(&mut checker, 10 + 0x8000), E2eStatus::Initial);
    assert_eq!(checker.last(), Some(10 + 0x8000));
    // A receiver whose time is more than a half behind the frame does not find it.
    let mut checker = checker_after(&[10]);
    let sent = 10 + 0x2_8000;
    let behind = Search::new(10);
    assert_eq!(
        checker.check(sent as u16, behind, |full| full == sent),
        E2eStatus::CheckFailed
    );
    assert_eq!(checker.last(), Some(10));
    // A genuine frame 2^15 behind is stale; one 2^15 + 1 behind reads as ahead and fails.
    let mut checker = checker_after(&[0x9000]);
    assert_eq!(offer(&mut checker, 0x1000), E2eStatus::WrongSequence);
    assert_eq!(offer(&mut checker, 0x0FFF), E2eStatus::CheckFailed);
}

/// The search never goes back to or behind the last accepted counter: a frame one or more
/// periods of 2^16 old with the low half of a counter ahead is not found, however many periods
/// are tried and wherever the receiver's time is.
#[test]
fn the_search_never_finds_a_counter_at_or_behind_the_last_accepted() {
    let last = 9 << 16 | 0x0100;
    for sent in [last, last - 1, 8 << 16 | 0x0200, 3 << 16 | 0x0100, 0x0100] {
        for reference in [sent, last, last + 0x8000, last + 0x1_0000, 0x7FFF_0000] {
            let mut checker = checker_after(&[last]);
            let search = Search {
                reference,
                tries: 1 << 16,
            };
            assert!(
                among_candidates(reference, 1 << 16, sent),
                "reached but for the last"
            );
            let status = checker.check(sent as u16, search, |full| full == sent);
            assert!(!status.is_accepted(), "{sent:#x}: {status:?}");
            assert_eq!(checker.last(), Some(last));
        }
    }
}

/// A CMAC costs a block cipher run per try: a frame forged without the key costs any receiver,
/// the controller or a member, one try where the sequence places it and at most two in the
/// search, within the budget of 1 + 1 + 2. The search skips candidates at or behind the last
/// accepted counter without a try, so with a recent sequence it costs at most one; both tries
/// are spent only with no sequence or one last heard more than 2^15 + 2^16 ms ago. (Wire
/// version 2 first let a member look through 2^8 periods for a CMAC frame: up to 1 + 256 runs
/// per forged frame.)
#[test]
fn a_forged_cmac_costs_at_most_one_verification_in_the_sequence_and_two_in_the_search() {
    let epoch = Some(Epoch::new(12));
    let data_id = 0xC200;
    let forger = Key([0x66; 16]);
    let payload = *b"drive!";
    let mut worst = 0;
    for now in [7 << 16 | 0x4000, 7 << 16 | 0xC000, 65_540, 100] {
        let recent: Vec<u32> = (now - 40..now - 20).collect();
        let stale: Vec<u32> = (now.saturating_sub(0x4_0000)..).take(20).collect();
        for (history, most) in [(&[][..], 2), (&recent[..], 1 + 1), (&stale[..], 1 + 2)] {
            for counter in [
                0,
                1,
                now - 21,
                now - 20,
                now - 19,
                now - 30,
                now,
                now - 0x8000.min(now),
                now - 0x1_0000.min(now),
                now + 0x8000,
                !0,
            ] {
                let mut checker = checker_after(history);
                let before = checker.last();
                let freshness = Freshness {
                    data_id,
                    epoch,
                    counter,
                };
                let message = protected(Check::Mac, &forger, &freshness, &payload);
                let (sent, low) = header(&message).unwrap();
                let mut runs = 0;
                let status = checker.check(low, Search::new(now), |counter| {
                    runs += 1;
                    let at = Freshness {
                        data_id,
                        epoch,
                        counter,
                    };
                    check_value(Check::Mac, &TEST_KEY, &at, &payload) == sent
                });
                assert_eq!(status, E2eStatus::CheckFailed, "{counter:#x}");
                assert_eq!(checker.last(), before);
                assert!(runs <= 1 + 1 + 2, "{counter:#x}: {runs} CMACs");
                assert!(
                    runs <= most,
                    "{now:#x} {counter:#x} {history:?}: {runs} CMACs"
                );
                worst = worst.max(runs);
            }
        }
    }
    assert_eq!(worst, 3, "one try in the sequence, two in the search");
}

#[test]
fn a_frame_whose_check_fails_is_check_failed_and_leaves_the_sequence_alone() {
    let mut checker = E2eChecker::new();
    assert_eq!(offer_forged(&mut checker, 0), E2eStatus::CheckFailed);
    assert_eq!(checker.last(), None);
    let mut checker = checker_after(&[10]);
    for low in [9, 10, 11, 5000, 0x8000 + 10] {
        assert_eq!(
            offer_forged(&mut checker, low),
            E2eStatus::CheckFailed,
            "{low}"
        );
    }
    assert_eq!(offer(&mut checker, 11), E2eStatus::Ok);
}

/// A message with `payload` protected under `freshness`.
fn protected(check: Check, key: &Key, freshness: &Freshness, payload: &[u8]) -> Vec<u8> {
    let mut message = vec![0; HEADER_LEN];
    message.extend_from_slice(payload);
    protect(check, key, freshness, &mut message).unwrap();
    message
}

/// The receiver's view of `message` on `data_id` in `epoch`: its check value verified at the
/// full counter the checker proposes.
fn receive_bytes(
    checker: &mut E2eChecker,
    check: Check,
    key: &Key,
    data_id: u16,
    epoch: Option<Epoch>,
    message: &[u8],
) -> E2eStatus {
    let (sent, low) = header(message).unwrap();
    checker.check(low, Search::new(0), |counter| {
        let freshness = Freshness {
            data_id,
            epoch,
            counter,
        };
        check_value(check, key, &freshness, &message[HEADER_LEN..]) == sent
    })
}

#[test]
fn a_corrupted_message_fails_its_check_and_leaves_the_sequence_alone() {
    let epoch = Some(Epoch::new(9));
    let data_id = 0xC123;
    for check in [Check::Crc, Check::Mac] {
        let freshness = Freshness {
            data_id,
            epoch,
            counter: 7,
        };
        let message = protected(check, &TEST_KEY, &freshness, b"robot!");
        assert_eq!(header(&message).map(|(_, low)| low), Some(7));

        let mut checker = E2eChecker::default();
        let mut corrupted = message.clone();
        corrupted[HEADER_LEN + 2] ^= 0x10;
        let mut rx = |message: &[u8], data_id: u16, epoch: Option<Epoch>| {
            receive_bytes(&mut checker, check, &TEST_KEY, data_id, epoch, message)
        };
        assert_eq!(rx(&corrupted, data_id, epoch), E2eStatus::CheckFailed);
        assert_eq!(
            rx(&message, data_id ^ 1, epoch),
            E2eStatus::CheckFailed,
            "{check:?}: wrong data id"
        );
        assert_eq!(
            rx(&message, data_id, Some(Epoch::new(10))),
            E2eStatus::CheckFailed,
            "{check:?}: another session"
        );
        assert_eq!(
            rx(&message, data_id, None),
            E2eStatus::CheckFailed,
            "{check:?}: no session"
        );
        assert_eq!(rx(&message, data_id, epoch), E2eStatus::Initial);
        assert_eq!(rx(&message, data_id, epoch), E2eStatus::Repeated);
    }
}

#[test]
fn the_crc_is_crc32c_over_data_id_epoch_counter_then_payload() {
    // CRC-32C (Castagnoli) check value: "123456789" → 0xE3069283.
    let reference = crc::Crc::<u32>::new(&crc::CRC_32_ISCSI);
    assert_eq!(reference.checksum(b"123456789"), 0xE306_9283);
    let freshness = Freshness {
        data_id: 0x3412,
        epoch: Some(Epoch::new(0x0A0B_0C0D)),
        counter: 0x0102_0304,
    };
    let mut covered = vec![0x12, 0x34, 0x0D, 0x0C, 0x0B, 0x0A, 0x04, 0x03, 0x02, 0x01];
    covered.extend_from_slice(b"123456789");
    assert_eq!(
        check_value(Check::Crc, &TEST_KEY, &freshness, b"123456789"),
        reference.checksum(&covered)
    );
    // No session: the epoch is four zero bytes. The key plays no part in a CRC.
    let unbound = Freshness {
        epoch: None,
        ..freshness
    };
    covered[2..6].fill(0);
    assert_eq!(
        check_value(Check::Crc, &Key([0xA5; 16]), &unbound, b"123456789"),
        reference.checksum(&covered)
    );
}

#[test]
fn the_mac_is_the_first_four_bytes_of_the_aes_cmac_tag() {
    // RFC 4493, example 2: K = 2b7e1516 28aed2a6 abf71588 09cf4f3c,
    // M = 6bc1bee2 2e409f96 e93d7e11 7393172a, T = 070a16b4 6b4d4144 f79bdd9d d04a287c.
    // The ten freshness bytes are the first ten of M, the payload the other six.
    let key = Key::from_hex("2b7e151628aed2a6abf7158809cf4f3c").unwrap();
    let freshness = Freshness {
        data_id: u16::from_le_bytes([0x6b, 0xc1]),
        epoch: Some(Epoch::new(u32::from_le_bytes([0xbe, 0xe2, 0x2e, 0x40]))),
        counter: u32::from_le_bytes([0x9f, 0x96, 0xe9, 0x3d]),
    };
    let payload = [0x7e, 0x11, 0x73, 0x93, 0x17, 0x2a];
    assert_eq!(
        check_value(Check::Mac, &key, &freshness, &payload),
        u32::from_le_bytes([0x07, 0x0a, 0x16, 0xb4])
    );
    assert_ne!(
        check_value(Check::Mac, &TEST_KEY, &freshness, &payload),
        check_value(Check::Mac, &key, &freshness, &payload),
        "the key matters"
    );
}

/// The header as `e2e`'s module documentation gives it, computed here with `crc` and `cmac`
/// directly: what a node written without this crate (or a `cantools` script) must produce.
#[test]
fn frames_on_the_wire_follow_the_documented_layout() {
    use cmac::Mac;
    let epoch = Epoch::new(0x0102_0304);
    let session = Session::owned(TEST_KEY, epoch);
    let counter: u32 = 0x0005_A1B2;
    let freshness_bytes = |data_id: u16, epoch: u32, counter: u32| {
        let mut bytes = data_id.to_le_bytes().to_vec();
        bytes.extend_from_slice(&epoch.to_le_bytes());
        bytes.extend_from_slice(&counter.to_le_bytes());
        bytes
    };

    // A CRC-32C frame bound to the session.
    let sync = AnyMessage::Sync(Sync {
        tick: Tick::from_raw(0xDEAD_BEEF).unwrap(),
    });
    let frame = sync.encode(&session, counter).unwrap();
    let data = frame.data();
    assert_eq!(data[4..6], [0xB2, 0xA1], "low half of the counter");
    assert_eq!(data[6..10], 0xDEAD_BEEF_u32.to_le_bytes(), "payload");
    let mut covered = freshness_bytes(0xC010, epoch.raw(), counter);
    covered.extend_from_slice(&data[6..10]);
    let crc = crc::Crc::<u32>::new(&crc::CRC_32_ISCSI).checksum(&covered);
    assert_eq!(data[..4], crc.to_le_bytes());
    assert!(data[10..].iter().all(|&b| b == 0), "zero padding");

    // A CMAC frame bound to the session.
    let heartbeat = AnyMessage::TeleopHeartbeat(protocol::TeleopHeartbeat {
        uptime: protocol::Millis::from_raw(1234).unwrap(),
    });
    let frame = heartbeat.encode(&session, counter).unwrap();
    let data = frame.data();
    let mut covered = freshness_bytes(0xC201, epoch.raw(), counter);
    covered.extend_from_slice(&data[6..10]);
    let mut mac = <cmac::Cmac<aes::Aes128> as Mac>::new_from_slice(&TEST_KEY.0).unwrap();
    mac.update(&covered);
    let tag = mac.finalize().into_bytes();
    assert_eq!(data[..4], tag[..4]);

    // An E-stop latch: CRC over data id 0xC000, zero epoch, low counter, action and source.
    let latch = protocol::EStop::latch(protocol::NodeId::Tool);
    let frame = AnyMessage::EStop(latch).encode(&session, counter).unwrap();
    let data = frame.data();
    let mut covered = freshness_bytes(0xC000, 0, counter & 0xFFFF);
    covered.extend_from_slice(&data[6..8]);
    let crc = crc::Crc::<u32>::new(&crc::CRC_32_ISCSI).checksum(&covered);
    assert_eq!(data[..4], crc.to_le_bytes());
    assert_eq!(data[6], protocol::EStopAction::Latch.raw());
    assert_eq!(data[7], protocol::NodeId::Tool as u8);
    // The classic frame of a panel is the first eight bytes of the same frame.
    let classic = protocol::classic_latch(protocol::NodeId::Tool, counter as u16).unwrap();
    assert_eq!(classic.data(), &data[..8]);
}

#[test]
fn too_short_messages_have_no_header() {
    assert_eq!(header(&[]), None);
    assert_eq!(header(&[1, 2, 3, 4, 5]), None);
    assert_eq!(header(&[1, 0, 0, 0, 0x34, 0x12]), Some((1, 0x1234)));
    let freshness = Freshness {
        data_id: 0,
        epoch: None,
        counter: 0,
    };
    let mut short = [0_u8; HEADER_LEN - 1];
    assert_eq!(protect(Check::Crc, &TEST_KEY, &freshness, &mut short), None);
    assert_eq!(short, [0; HEADER_LEN - 1], "nothing written");
}

#[test]
fn the_receiver_counts_frames_lost_in_a_burst() {
    let session = Session::owned(TEST_KEY, Epoch::new(3)).at(SessionTime::from_ms(40));
    let mut receiver = Receiver::owner(session);
    let sync = |counter: u32| {
        AnyMessage::Sync(Sync {
            tick: Tick::from_raw(counter).unwrap(),
        })
        .encode(&session, counter)
        .unwrap()
    };
    for counter in [0, 1, 2] {
        let frame = sync(counter);
        receiver.receive(frame.id(), frame.data()).unwrap();
    }
    // 30 frames lost in one burst, then the sender goes on.
    let frame = sync(33);
    assert_eq!(
        receiver.receive(frame.id(), frame.data()).unwrap().status,
        E2eStatus::OkSomeLost { lost: 30 }
    );
    let frame = sync(34);
    assert_eq!(
        receiver.receive(frame.id(), frame.data()).unwrap().status,
        E2eStatus::Ok
    );
    assert_eq!(receiver.counters().lost.raw(), 30);
    // A replay of an old frame is refused and counts no loss.
    let frame = sync(1);
    assert!(receiver.receive(frame.id(), frame.data()).is_err());
    assert_eq!(receiver.counters().lost.raw(), 30);
    assert_eq!(receiver.counters().total(), 1);
}

#[test]
fn only_in_sequence_frames_are_accepted() {
    for status in [
        E2eStatus::Ok,
        E2eStatus::OkSomeLost { lost: 3 },
        E2eStatus::Initial,
    ] {
        assert!(status.is_accepted(), "{status:?}");
    }
    for status in [
        E2eStatus::Repeated,
        E2eStatus::WrongSequence,
        E2eStatus::CheckFailed,
    ] {
        assert!(!status.is_accepted(), "{status:?}");
    }
}

fn any_check() -> impl Strategy<Value = Check> {
    prop_oneof![Just(Check::Crc), Just(Check::Mac)]
}

fn any_epoch() -> impl Strategy<Value = Option<Epoch>> {
    proptest::option::of(any::<u32>().prop_map(Epoch::new))
}

/// A genuine sender's history as a checker saw it: a first counter anywhere in the first
/// `2^16 · 8` and gaps of up to half the counter range.
fn history() -> impl Strategy<Value = (u32, Vec<u32>)> {
    (
        0_u32..(8 << 16),
        proptest::collection::vec(
            prop_oneof![4 => Just(1_u32), 2 => 2_u32..100, 1 => 100_u32..0x8000],
            0..40,
        ),
    )
}

/// A checker that accepted the frames of `history`, and the last counter.
fn replay_history(start: u32, gaps: &[u32]) -> (E2eChecker, u32) {
    let mut checker = E2eChecker::new();
    assert_eq!(offer(&mut checker, start), E2eStatus::Initial);
    let mut last = start;
    for &gap in gaps {
        last += gap;
        let expected = if gap == 1 {
            E2eStatus::Ok
        } else {
            E2eStatus::OkSomeLost { lost: gap - 1 }
        };
        assert_eq!(offer(&mut checker, last), expected);
    }
    (checker, last)
}

proptest! {
    /// Every gap short of half the counter range is in sequence, counted as lost, and the
    /// checker follows the sender's full counter across any number of wraps of the low half.
    #[test]
    fn gaps_below_half_the_range_are_accepted_and_counted((start, gaps) in history()) {
        let (checker, last) = replay_history(start, &gaps);
        prop_assert_eq!(checker.last(), Some(last));
    }

    /// A genuine frame sent `age` frames before the last accepted one, replayed: a repeat, stale
    /// while the low half can tell, and a failed check from half the counter range on — never
    /// accepted, and the sequence goes on undisturbed.
    #[test]
    fn a_replayed_earlier_frame_is_refused_according_to_its_age(
        (start, gaps) in history(),
        age in prop_oneof![
            0_u32..0x100,
            0x7F00_u32..0x8100,
            0_u32..(6 << 16),
            proptest::sample::select(&[0x7FFF_u32, 0x8000, 0x8001, 0xFFFF, 0x1_0000, 0x1_0001][..]),
        ],
    ) {
        let start = start + (6 << 16);
        let (mut checker, last) = replay_history(start, &gaps);
        // 2^15 behind is still behind; ahead by 2^15 is not ahead (see below).
        let expected = match age {
            0 => E2eStatus::Repeated,
            1..=0x8000 => E2eStatus::WrongSequence,
            _ => E2eStatus::CheckFailed,
        };
        prop_assert_eq!(offer(&mut checker, last - age), expected);
        prop_assert_eq!(checker.last(), Some(last));
        prop_assert_eq!(offer(&mut checker, last + 1), E2eStatus::Ok);
    }

    /// A genuine frame half the counter range or more ahead (a gap of 2^15 frames or more) is
    /// found when the receiver's time has reached it, as a sender's counter never passes the
    /// session time: the sequence restarts there.
    #[test]
    fn a_frame_half_the_range_or_more_ahead_is_found_at_its_time(
        (start, gaps) in history(),
        ahead in prop_oneof![0x8000_u32..0x8100, 0xFF00_u32..0x1_0100, 0x8000_u32..0x1000_0000],
    ) {
        let (mut checker, last) = replay_history(start, &gaps);
        prop_assert_eq!(offer(&mut checker, last + ahead), E2eStatus::Initial);
        prop_assert_eq!(checker.last(), Some(last + ahead));
        prop_assert_eq!(offer(&mut checker, last + ahead + 1), E2eStatus::Ok);
    }

    /// The same frame, at a receiver whose time is `now`: found exactly when it is one of the
    /// two candidates of the search (2^15 ahead of `now` to 2^15 + 2^16 behind it); refused
    /// otherwise, and the sequence unchanged.
    #[test]
    fn a_frame_half_the_range_or_more_ahead_is_found_only_near_the_receivers_time(
        (start, gaps) in history(),
        ahead in prop_oneof![0x8000_u32..0x8100, 0xFF00_u32..0x1_0100, 0x8000_u32..0x1000_0000],
        lead in 0_u32..0x4_0000,
    ) {
        let (mut checker, last) = replay_history(start, &gaps);
        let sent = last + ahead;
        let now = (last + lead).min(sent + 0x2_0000);
        let status = checker.check(sent as u16, Search::new(now), |full| full == sent);
        let distance = i64::from(sent) - i64::from(now);
        prop_assert_eq!(
            among_candidates(now, 2, sent),
            (-0x1_8000..=0x8000).contains(&distance)
                && !(distance == 0x8000 && now & 0xFFFF >= 0x8000)
                && !(distance == -0x1_8000 && now & 0xFFFF < 0x8000)
        );
        if among_candidates(now, 2, sent) {
            prop_assert_eq!(status, E2eStatus::Initial);
            prop_assert_eq!(checker.last(), Some(sent));
        } else {
            prop_assert_eq!(status, E2eStatus::CheckFailed);
            prop_assert_eq!(checker.last(), Some(last));
        }
    }

    /// A frame whose check holds at no counter never enters or moves a sequence.
    #[test]
    fn a_forged_frame_never_moves_the_sequence(
        (start, gaps) in history(),
        low in any::<u16>(),
        reference in any::<u32>(),
        tries in 0_u32..300,
    ) {
        let mut fresh = E2eChecker::new();
        prop_assert_eq!(
            fresh.check(low, Search { reference, tries }, |_| false),
            E2eStatus::CheckFailed
        );
        prop_assert_eq!(fresh.last(), None);
        let (mut checker, last) = replay_history(start, &gaps);
        prop_assert_eq!(offer_forged(&mut checker, low), E2eStatus::CheckFailed);
        prop_assert_eq!(checker.last(), Some(last));
    }

    /// A first frame is found exactly when it is among the `tries` candidates: the counter with
    /// its low half nearest the receiver's time, and the `tries − 1` periods of 2^16 below it.
    #[test]
    fn a_first_frame_is_found_within_its_tries(
        sent in 0_u32..(600 << 16),
        reference in 0_u32..(600 << 16),
        tries in 0_u32..600,
    ) {
        let mut checker = E2eChecker::new();
        let search = Search { reference, tries };
        let status = checker.check(sent as u16, search, |full| full == sent);
        if among_candidates(reference, tries, sent) {
            prop_assert_eq!(status, E2eStatus::Initial);
            prop_assert_eq!(checker.last(), Some(sent));
        } else {
            prop_assert_eq!(status, E2eStatus::CheckFailed);
            prop_assert_eq!(checker.last(), None);
        }
    }

    /// Protect, then verify at the same freshness: the check holds; with any one bit of check
    /// value, counter or payload flipped, it does not (certain for CRC-32C, which detects every
    /// burst of up to 32 bits; 2^-32 for the MAC).
    #[test]
    fn a_flipped_bit_in_a_protected_message_fails_its_check(
        check in any_check(),
        data_id in any::<u16>(),
        epoch in any_epoch(),
        counter in any::<u32>(),
        payload in proptest::collection::vec(any::<u8>(), 1..58),
        bit in any::<prop::sample::Index>(),
    ) {
        let freshness = Freshness { data_id, epoch, counter };
        let message = protected(check, &TEST_KEY, &freshness, &payload);
        let holds = |message: &[u8]| {
            let (sent, low) = header(message).unwrap();
            let at = Freshness { counter: counter & !0xFFFF | u32::from(low), ..freshness };
            check_value(check, &TEST_KEY, &at, &message[HEADER_LEN..]) == sent
        };
        prop_assert!(holds(&message));
        let bit = bit.index(message.len() * 8);
        let mut flipped = message.clone();
        flipped[bit / 8] ^= 1 << (bit % 8);
        prop_assert!(!holds(&flipped), "bit {} flipped", bit);
    }

    /// The check covers the data id, the epoch and the full counter: a change of any one of
    /// them changes it, as it must for a frame moved to another id, replayed from another
    /// session or replayed from 2^16 frames ago to fail.
    #[test]
    fn the_check_binds_data_id_epoch_and_counter(
        check in any_check(),
        data_id in any::<u16>(),
        epoch in any::<u32>(),
        counter in any::<u32>(),
        field in 0_usize..3,
        other in any::<u32>(),
        payload in proptest::collection::vec(any::<u8>(), 0..58),
    ) {
        let freshness = Freshness { data_id, epoch: Some(Epoch::new(epoch)), counter };
        let changed = match field {
            0 => Freshness { data_id: other as u16, ..freshness },
            1 => Freshness { epoch: Some(Epoch::new(other)), ..freshness },
            _ => Freshness { counter: other, ..freshness },
        };
        prop_assume!(changed != freshness);
        prop_assert_ne!(
            check_value(check, &TEST_KEY, &freshness, &payload),
            check_value(check, &TEST_KEY, &changed, &payload)
        );
    }
}
