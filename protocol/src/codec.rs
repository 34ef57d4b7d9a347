//! Encoding a message into a frame and decoding it back, with E2E protection.

use postcard::experimental::max_size::MaxSize;
use serde::de::DeserializeOwned;
use serde::Serialize;

use crate::dlc::{fd_padded_len, MAX_FD_LEN};
#[cfg(doc)]
use crate::e2e::PreparedKey;
use crate::e2e::{self, Check, Freshness, MacKey, Protection, HEADER_LEN};
use crate::error::DecodeError;
use crate::frame::Frame;
use crate::id::MessageId;
use crate::session::Session;
use crate::signal::Field;

/// A message of the bus: its layout, name and where it may be sent.
///
/// Implementations come with compile-time checks (see `message!`) that the payload fits its
/// CAN FD frame and that [`Message::FIELDS`] describes exactly the bytes postcard writes.
pub trait Message: Serialize + DeserializeOwned + MaxSize + Sized {
    /// What selects the identifier among those carrying this layout: `()` for a message with
    /// one identifier, a [`Leg`](crate::Leg) or [`Drive`](crate::Drive) for per-node messages.
    type Address: Copy;
    /// Name of the layout (the DBC name adds the node suffix for per-node messages).
    const NAME: &'static str;
    /// One-line description, copied into the DBC.
    const DOC: &'static str;
    /// The fields in wire order.
    const FIELDS: &'static [Field];
    /// Bytes of E2E header and payload.
    const LEN: usize = HEADER_LEN + Self::POSTCARD_MAX_SIZE;
    /// Data length of the frame: [`Message::LEN`] padded to a CAN FD length.
    const WIRE_LEN: usize = match fd_padded_len(Self::LEN) {
        Some(len) => len,
        None => MAX_FD_LEN,
    };

    /// How this message is protected (see [`crate::session`]): a CRC bound to the session
    /// unless the message says otherwise.
    const PROTECTION: Protection = Protection {
        check: Check::Crc,
        bound: true,
        sequenced: true,
    };

    /// The identifier this message goes out on.
    fn id(address: Self::Address) -> MessageId;

    /// The protection of this value and how many payload bytes its check covers (all of them
    /// unless the message says otherwise: an E-stop latch covers two).
    fn protection(&self) -> (Protection, usize) {
        (Self::PROTECTION, Self::POSTCARD_MAX_SIZE)
    }
}

/// Declares the compile-time checks of a message layout: the payload fits a CAN FD frame, and
/// the field table covers exactly the bytes postcard writes.
macro_rules! check_layout {
    ($msg:ty) => {
        const _: () = {
            assert!(
                <$msg as $crate::codec::Message>::LEN <= $crate::dlc::MAX_FD_LEN,
                "message does not fit a CAN FD frame"
            );
            assert!(
                $crate::signal::payload_bytes(<$msg as $crate::codec::Message>::FIELDS)
                    == <$msg as postcard::experimental::max_size::MaxSize>::POSTCARD_MAX_SIZE,
                "field table does not match the serialized size"
            );
        };
    };
}
pub(crate) use check_layout;

/// Why a message could not be encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum EncodeError {
    /// The serializer ran out of room. Cannot happen for the messages of this crate (their
    /// sizes are checked at compile time); reported rather than assumed.
    TooLarge,
    /// The message is bound to a session and the sender has not joined one: it has not heard
    /// the controller's announcement yet.
    NoSession,
}

/// Encodes `message` for `address` with the sender's full counter `counter` into a padded CAN
/// FD frame, protected as the message requires under `session`.
pub fn encode<M: Message>(
    message: &M,
    address: M::Address,
    session: &Session,
    counter: u32,
) -> Result<Frame, EncodeError> {
    encode_keyed(message, address, session, session.key(), counter)
}

/// As [`encode`], computing a MAC with `key` (the session's key, [prepared](PreparedKey)).
pub fn encode_keyed<M: Message, K: MacKey + ?Sized>(
    message: &M,
    address: M::Address,
    session: &Session,
    key: &K,
    counter: u32,
) -> Result<Frame, EncodeError> {
    let id = M::id(address);
    let (protection, covered) = message.protection();
    let epoch = if protection.bound {
        Some(session.epoch().ok_or(EncodeError::NoSession)?)
    } else {
        None
    };
    let mut buf = [0_u8; MAX_FD_LEN];
    let payload = buf
        .get_mut(HEADER_LEN..M::LEN)
        .ok_or(EncodeError::TooLarge)?;
    let written = postcard::to_slice(message, payload).map_err(|_| EncodeError::TooLarge)?;
    if written.len() != M::POSTCARD_MAX_SIZE {
        return Err(EncodeError::TooLarge);
    }
    let freshness = Freshness {
        data_id: id.data_id(),
        epoch,
        counter: if protection.sequenced {
            counter
        } else {
            counter & 0xFFFF
        },
    };
    e2e::protect(
        protection.check,
        key,
        &freshness,
        buf.get_mut(..HEADER_LEN + covered)
            .ok_or(EncodeError::TooLarge)?,
    )
    .ok_or(EncodeError::TooLarge)?;
    Frame::new(
        id.raw(),
        buf.get(..M::WIRE_LEN).ok_or(EncodeError::TooLarge)?,
    )
    .ok_or(EncodeError::TooLarge)
}

/// Parses the data of a frame on `id` as `M`: length and value ranges are checked and the
/// header's low counter returned. The check value is **not** verified here — that needs the
/// session and the sequence, which [`Receiver`](crate::Receiver) holds.
pub fn decode<M: Message>(id: MessageId, data: &[u8]) -> Result<(M, u16), DecodeError> {
    let raw = id.raw();
    let wrong_length = DecodeError::WrongLength {
        id: raw,
        expected: M::WIRE_LEN,
        got: data.len(),
    };
    if data.len() != M::WIRE_LEN {
        return Err(wrong_length);
    }
    let (_, counter) = e2e::header(data).ok_or(wrong_length)?;
    let payload = data.get(HEADER_LEN..M::LEN).ok_or(wrong_length)?;
    // The length is fixed and checked, so the only way postcard fails here is a field's own
    // range check (an out-of-range scalar, unknown enumeration value or flag bit).
    let value =
        postcard::from_bytes::<M>(payload).map_err(|_| DecodeError::OutOfRange { id: raw })?;
    Ok((value, counter))
}
