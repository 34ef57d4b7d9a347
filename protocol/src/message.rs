//! Any message of the bus, decoded from a raw identifier and data.

use crate::codec::{decode, encode_keyed, EncodeError, Message};
use crate::e2e::MacKey;
use crate::e2e::{Protection, HEADER_LEN};
use crate::error::DecodeError;
use crate::frame::Frame;
use crate::id::MessageId;
use crate::msg::{
    Announce, ControllerStatus, DriveStatus, EStop, Imu, LegFeedback, LegTargets, Range,
    RejectCounters, Sync, TeleopCommand, TeleopHeartbeat, WheelCommand, WheelFeedback,
};
use crate::msg::{CLASSIC_LATCH_LEN, LATCH_CHECKED_LEN};
use crate::node::{Drive, Leg};
use crate::session::Session;
use crate::signal::Field;
use crate::units::EStopAction;

/// A decoded message with the node it concerns, where the identifier names one.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[allow(missing_docs)]
pub enum AnyMessage {
    EStop(EStop),
    Sync(Sync),
    Announce(Announce),
    LegTargets(LegTargets),
    WheelCommand(WheelCommand),
    LegFeedback(Leg, LegFeedback),
    WheelFeedback(WheelFeedback),
    Imu(Imu),
    Range(Range),
    TeleopCommand(TeleopCommand),
    TeleopHeartbeat(TeleopHeartbeat),
    ControllerStatus(ControllerStatus),
    DriveStatus(Drive, DriveStatus),
    RejectCounters(RejectCounters),
}

/// A frame that passed the stateless checks (id, length, ranges); its check value is not
/// verified yet.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Decoded {
    /// Which identifier it came on.
    pub id: MessageId,
    /// The low half of its rolling counter, for the sequence check.
    pub counter: u16,
    /// The message.
    pub message: AnyMessage,
}

/// Parses a frame's identifier and data without session or sequence state: unknown id, wrong
/// length and out-of-range values are rejected here. The check value is not verified: use
/// [`Receiver`](crate::Receiver) for that and to reject repeated, stale and forged frames.
///
/// An E-stop latch sent as a classic CAN frame ([`CLASSIC_LATCH_LEN`] bytes) is read as the
/// latch it is; any other classic E-stop is refused as the wrong length.
pub fn decode_frame(raw_id: u16, data: &[u8]) -> Result<Decoded, DecodeError> {
    let id = MessageId::from_raw(raw_id).ok_or(DecodeError::UnknownId(raw_id))?;
    if id == MessageId::EStop && data.len() == CLASSIC_LATCH_LEN {
        return decode_classic_latch(data);
    }
    let (message, counter) = match id {
        MessageId::EStop => decode(id, data).map(|(m, c)| (AnyMessage::EStop(m), c))?,
        MessageId::Sync => decode(id, data).map(|(m, c)| (AnyMessage::Sync(m), c))?,
        MessageId::Announce => decode(id, data).map(|(m, c)| (AnyMessage::Announce(m), c))?,
        MessageId::LegTargets => decode(id, data).map(|(m, c)| (AnyMessage::LegTargets(m), c))?,
        MessageId::WheelCommand => {
            decode(id, data).map(|(m, c)| (AnyMessage::WheelCommand(m), c))?
        }
        MessageId::LegFeedback(leg) => {
            decode(id, data).map(|(m, c)| (AnyMessage::LegFeedback(leg, m), c))?
        }
        MessageId::WheelFeedback => {
            decode(id, data).map(|(m, c)| (AnyMessage::WheelFeedback(m), c))?
        }
        MessageId::Imu => decode(id, data).map(|(m, c)| (AnyMessage::Imu(m), c))?,
        MessageId::Range => decode(id, data).map(|(m, c)| (AnyMessage::Range(m), c))?,
        MessageId::TeleopCommand => {
            decode(id, data).map(|(m, c)| (AnyMessage::TeleopCommand(m), c))?
        }
        MessageId::TeleopHeartbeat => {
            decode(id, data).map(|(m, c)| (AnyMessage::TeleopHeartbeat(m), c))?
        }
        MessageId::ControllerStatus => {
            decode(id, data).map(|(m, c)| (AnyMessage::ControllerStatus(m), c))?
        }
        MessageId::DriveStatus(drive) => {
            decode(id, data).map(|(m, c)| (AnyMessage::DriveStatus(drive, m), c))?
        }
        MessageId::RejectCounters => {
            decode(id, data).map(|(m, c)| (AnyMessage::RejectCounters(m), c))?
        }
    };
    Ok(Decoded {
        id,
        counter,
        message,
    })
}

fn decode_classic_latch(data: &[u8]) -> Result<Decoded, DecodeError> {
    let id = MessageId::EStop;
    let mut padded = [0_u8; EStop::WIRE_LEN];
    padded
        .get_mut(..data.len())
        .ok_or(DecodeError::WrongLength {
            id: id.raw(),
            expected: EStop::WIRE_LEN,
            got: data.len(),
        })?
        .copy_from_slice(data);
    let (message, counter) = decode::<EStop>(id, &padded)?;
    if message.action != EStopAction::Latch {
        return Err(DecodeError::WrongLength {
            id: id.raw(),
            expected: EStop::WIRE_LEN,
            got: data.len(),
        });
    }
    Ok(Decoded {
        id,
        counter,
        message: AnyMessage::EStop(message),
    })
}

/// How a frame on `id` with data `data` is protected, and how many payload bytes its check
/// covers. Read from the raw bytes, before the payload is parsed, so that the check is
/// verified first: an E-stop whose action byte says latch is checked as a latch.
pub fn protection_of(id: MessageId, data: &[u8]) -> (Protection, usize) {
    let layout = id.layout();
    if id == MessageId::EStop && data.get(HEADER_LEN) == Some(&EStopAction::Latch.raw()) {
        return (crate::msg::LATCH_PROTECTION, LATCH_CHECKED_LEN);
    }
    (layout.protection, layout.len - HEADER_LEN)
}

impl AnyMessage {
    /// The identifier this message goes out on.
    pub fn id(&self) -> MessageId {
        match self {
            AnyMessage::EStop(_) => MessageId::EStop,
            AnyMessage::Sync(_) => MessageId::Sync,
            AnyMessage::Announce(_) => MessageId::Announce,
            AnyMessage::LegTargets(_) => MessageId::LegTargets,
            AnyMessage::WheelCommand(_) => MessageId::WheelCommand,
            AnyMessage::LegFeedback(leg, _) => MessageId::LegFeedback(*leg),
            AnyMessage::WheelFeedback(_) => MessageId::WheelFeedback,
            AnyMessage::Imu(_) => MessageId::Imu,
            AnyMessage::Range(_) => MessageId::Range,
            AnyMessage::TeleopCommand(_) => MessageId::TeleopCommand,
            AnyMessage::TeleopHeartbeat(_) => MessageId::TeleopHeartbeat,
            AnyMessage::ControllerStatus(_) => MessageId::ControllerStatus,
            AnyMessage::DriveStatus(drive, _) => MessageId::DriveStatus(*drive),
            AnyMessage::RejectCounters(_) => MessageId::RejectCounters,
        }
    }

    /// Encodes this message with the sender's full counter `counter` under `session`.
    pub fn encode(&self, session: &Session, counter: u32) -> Result<Frame, EncodeError> {
        self.encode_keyed(session, session.key(), counter)
    }

    /// As [`AnyMessage::encode`], computing a MAC with `key` (the session's key, prepared).
    pub fn encode_keyed<K: MacKey + ?Sized>(
        &self,
        session: &Session,
        key: &K,
        counter: u32,
    ) -> Result<Frame, EncodeError> {
        match self {
            AnyMessage::EStop(m) => encode_keyed(m, (), session, key, counter),
            AnyMessage::Sync(m) => encode_keyed(m, (), session, key, counter),
            AnyMessage::Announce(m) => encode_keyed(m, (), session, key, counter),
            AnyMessage::LegTargets(m) => encode_keyed(m, (), session, key, counter),
            AnyMessage::WheelCommand(m) => encode_keyed(m, (), session, key, counter),
            AnyMessage::LegFeedback(leg, m) => encode_keyed(m, *leg, session, key, counter),
            AnyMessage::WheelFeedback(m) => encode_keyed(m, (), session, key, counter),
            AnyMessage::Imu(m) => encode_keyed(m, (), session, key, counter),
            AnyMessage::Range(m) => encode_keyed(m, (), session, key, counter),
            AnyMessage::TeleopCommand(m) => encode_keyed(m, (), session, key, counter),
            AnyMessage::TeleopHeartbeat(m) => encode_keyed(m, (), session, key, counter),
            AnyMessage::ControllerStatus(m) => encode_keyed(m, (), session, key, counter),
            AnyMessage::DriveStatus(drive, m) => encode_keyed(m, *drive, session, key, counter),
            AnyMessage::RejectCounters(m) => encode_keyed(m, (), session, key, counter),
        }
    }
}

/// Static description of the message on one identifier.
#[derive(Debug, Clone, Copy)]
pub struct Layout {
    /// Name, unique on the bus (per-node messages carry the node suffix, `LegFeedback_FL`).
    pub name: &'static str,
    /// One-line description.
    pub doc: &'static str,
    /// Fields in wire order, after the E2E header.
    pub fields: &'static [Field],
    /// Bytes of E2E header and payload.
    pub len: usize,
    /// CAN FD data length on the wire.
    pub wire_len: usize,
    /// How frames on this identifier are protected (an E-stop latch differs: see
    /// [`protection_of`]).
    pub protection: Protection,
}

const fn layout<M: Message>(name: &'static str) -> Layout {
    Layout {
        name,
        doc: M::DOC,
        fields: M::FIELDS,
        len: M::LEN,
        wire_len: M::WIRE_LEN,
        protection: M::PROTECTION,
    }
}

impl MessageId {
    /// Name, layout and sizes of the message on this identifier.
    pub const fn layout(self) -> Layout {
        match self {
            MessageId::EStop => layout::<EStop>(EStop::NAME),
            MessageId::Sync => layout::<Sync>(Sync::NAME),
            MessageId::Announce => layout::<Announce>(Announce::NAME),
            MessageId::LegTargets => layout::<LegTargets>(LegTargets::NAME),
            MessageId::WheelCommand => layout::<WheelCommand>(WheelCommand::NAME),
            MessageId::LegFeedback(leg) => layout::<LegFeedback>(match leg {
                Leg::Fl => "LegFeedback_FL",
                Leg::Fr => "LegFeedback_FR",
                Leg::Bl => "LegFeedback_BL",
                Leg::Br => "LegFeedback_BR",
            }),
            MessageId::WheelFeedback => layout::<WheelFeedback>(WheelFeedback::NAME),
            MessageId::Imu => layout::<Imu>(Imu::NAME),
            MessageId::Range => layout::<Range>(Range::NAME),
            MessageId::TeleopCommand => layout::<TeleopCommand>(TeleopCommand::NAME),
            MessageId::TeleopHeartbeat => layout::<TeleopHeartbeat>(TeleopHeartbeat::NAME),
            MessageId::ControllerStatus => layout::<ControllerStatus>(ControllerStatus::NAME),
            MessageId::DriveStatus(drive) => layout::<DriveStatus>(match drive {
                Drive::LegFl => "DriveStatus_LegFL",
                Drive::LegFr => "DriveStatus_LegFR",
                Drive::LegBl => "DriveStatus_LegBL",
                Drive::LegBr => "DriveStatus_LegBR",
                Drive::Wheel => "DriveStatus_Wheel",
            }),
            MessageId::RejectCounters => layout::<RejectCounters>(RejectCounters::NAME),
        }
    }

    /// The node that sends this message.
    pub const fn sender(self) -> crate::NodeId {
        use crate::NodeId;
        match self {
            MessageId::EStop | MessageId::TeleopCommand | MessageId::TeleopHeartbeat => {
                NodeId::Teleop
            }
            MessageId::Sync => NodeId::Simulator,
            MessageId::Announce => NodeId::Controller,
            MessageId::LegTargets
            | MessageId::WheelCommand
            | MessageId::ControllerStatus
            | MessageId::RejectCounters => NodeId::Controller,
            MessageId::LegFeedback(leg) => leg.drive().node(),
            MessageId::WheelFeedback => NodeId::WheelDrive,
            MessageId::Imu => NodeId::Imu,
            MessageId::Range => NodeId::Rangefinder,
            MessageId::DriveStatus(drive) => drive.node(),
        }
    }
}
