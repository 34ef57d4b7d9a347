//! Frames forged without the key: a forger computes the CRC right, but a CMAC it cannot, and an
//! announcement it forges opens no session.

mod common;

use common::frames::{check_failed, receive, OLD};
use common::joined_member;
use protocol::e2e::HEADER_LEN;
use protocol::*;

/// `message` as an attacker without the key makes it for `epoch` and full counter `counter`:
/// the documented layout, the right counter, and a CRC-32C it computes itself over exactly
/// what the receiver's check covers (data id, epoch, full counter, payload).
fn forged(message: &AnyMessage, epoch: Epoch, counter: u32) -> Frame {
    // The layout is public: any key gives the right bytes after the check value.
    let template = message
        .encode(&Session::owned(Key([0; 16]), epoch), counter)
        .unwrap();
    let mut data = template.data().to_vec();
    let (protection, covered) = protection_of(message.id(), &data);
    let counter = if protection.sequenced {
        counter
    } else {
        counter & 0xFFFF
    };
    let mut fields = message.id().data_id().to_le_bytes().to_vec();
    let epoch = if protection.bound { epoch.raw() } else { 0 };
    fields.extend_from_slice(&epoch.to_le_bytes());
    fields.extend_from_slice(&counter.to_le_bytes());
    fields.extend_from_slice(&data[HEADER_LEN..HEADER_LEN + covered]);
    let crc = crc::Crc::<u32>::new(&crc::CRC_32_ISCSI).checksum(&fields);
    data[..4].copy_from_slice(&crc.to_le_bytes());
    Frame::new(template.id(), &data).unwrap()
}

/// The messages that carry a CMAC and take part in a sequence (the operator's), each with the
/// controller's receiver and a member's.
fn authenticated_messages() -> Vec<(AnyMessage, fn() -> Receiver)> {
    let owner: fn() -> Receiver = || Receiver::owner(common::controller_session());
    let member: fn() -> Receiver = || joined_member(common::EPOCH);
    let messages = [
        AnyMessage::TeleopCommand(TeleopCommand {
            mode: TeleopMode::TrotForward,
            body_height: BodyHeight::default(),
            speed_scale: SpeedScale::from_raw(100).unwrap(),
            speed: Default::default(),
            yaw_rate: Default::default(),
        }),
        AnyMessage::TeleopHeartbeat(TeleopHeartbeat {
            uptime: Millis::from_raw(99).unwrap(),
        }),
        AnyMessage::EStop(EStop::release(NodeId::Teleop, ReleaseToken::new(2))),
    ];
    let all: Vec<_> = messages
        .into_iter()
        .flat_map(|message| [(message, owner), (message, member)])
        .collect();
    for (message, _) in &all {
        let frame = message.encode(&common::controller_session(), 0).unwrap();
        assert_eq!(
            check_failed(&frame),
            DecodeError::Unauthentic { id: frame.id() }
        );
    }
    all
}

#[test]
fn a_command_forged_without_the_key_is_unauthentic_and_the_same_with_the_key_passes() {
    for (message, receiver) in authenticated_messages() {
        for counter in [0, 1, 1234] {
            let mut rx = receiver();
            let fake = forged(&message, common::EPOCH, counter);
            assert_eq!(
                rx.receive(fake.id(), fake.data()),
                Err(DecodeError::Unauthentic { id: fake.id() }),
                "{message:?}"
            );
            assert_eq!(rx.counters().get(RejectCause::Unauthentic).raw(), 1);
            assert_eq!(rx.counters().total(), 1);
            // With the key, the same message at the same counter: the forgery took nothing.
            let genuine = message
                .encode(&common::controller_session(), counter)
                .unwrap();
            assert_eq!(
                fake.data()[4..],
                genuine.data()[4..],
                "only the check differs"
            );
            let accepted = rx.receive(genuine.id(), genuine.data()).unwrap();
            assert_eq!(accepted.message, message);
            assert_eq!(accepted.status, E2eStatus::Initial);
        }
    }
}

#[test]
fn the_forger_computes_the_crc_right_a_crc_frame_it_forges_passes() {
    // The threat model: feedback and status carry a CRC, which anyone can compute. This pins
    // the forger above to the receiver's own computation, so that the refusals above come from
    // the missing key and not from a wrong CRC.
    let status = AnyMessage::DriveStatus(
        Drive::Wheel,
        DriveStatus {
            flags: DriveFlags::ENABLED,
            rejected: Count::ZERO,
            commands: Count::ZERO,
        },
    );
    let fake = forged(&status, common::EPOCH, 77);
    let genuine = status.encode(&common::controller_session(), 77).unwrap();
    assert_eq!(fake, genuine);
    // So do the drive commands, which carry a CRC (a CMAC is too dear for the drives at 1 kHz):
    // a forger on the bus can command the drives, though not replay the controller's frames.
    let command = AnyMessage::WheelCommand(WheelCommand {
        enable: DriveEnable::Enabled,
        torque: [Torque::from_raw(-2500).unwrap(); 2],
    });
    let fake = forged(&command, common::EPOCH, 5);
    assert_eq!(
        fake,
        command.encode(&common::controller_session(), 5).unwrap()
    );
    let mut drive = joined_member(common::EPOCH);
    assert_eq!(receive(&mut drive, &fake).unwrap().message, command);
    let latch = AnyMessage::EStop(EStop::latch(NodeId::Tool));
    let mut rx = Receiver::member(TEST_KEY);
    let fake = forged(&latch, common::EPOCH, 5);
    assert!(
        rx.receive(fake.id(), fake.data()).is_ok(),
        "anyone may latch"
    );
}

#[test]
fn a_command_sealed_with_another_key_is_unauthentic() {
    let other = Session::owned(
        Key::from_hex("00112233445566778899aabbccddeeff").unwrap(),
        common::EPOCH,
    );
    for (message, receiver) in authenticated_messages() {
        let mut rx = receiver();
        let frame = message.encode(&other, 0).unwrap();
        assert_eq!(
            rx.receive(frame.id(), frame.data()),
            Err(DecodeError::Unauthentic { id: frame.id() }),
            "{message:?}"
        );
    }
}

#[test]
fn an_announcement_forged_without_the_key_opens_no_session() {
    let announce = AnyMessage::Announce(Announce {
        version: WireVersion::THIS,
        epoch: Epoch::new(u32::MAX),
        time: SessionTime::from_ms(u32::MAX),
    });
    for mut rx in [Receiver::member(TEST_KEY), joined_member(OLD)] {
        let epoch = rx.session().epoch();
        for frame in [
            forged(&announce, Epoch::new(0), 0),
            announce
                .encode(&Session::unjoined(Key([7; 16])), 0)
                .unwrap(),
        ] {
            assert_eq!(
                rx.receive(frame.id(), frame.data()),
                Err(DecodeError::Unauthentic { id: 0x020 })
            );
            assert_eq!(rx.session().epoch(), epoch, "not moved");
        }
    }
}
