//! The check values against their references (CRC-32C, AES-CMAC), a corrupted message, and the
//! wire layout of the header.

mod common;

use common::protected::protected;
use protocol::e2e::{check_value, header, protect, Freshness, Search, HEADER_LEN};
use protocol::{
    AnyMessage, Check, E2eChecker, E2eStatus, Epoch, Key, Session, Sync, Tick, TEST_KEY,
};

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
