//! Encoding a message into a frame and decoding it back, with E2E protection.

use postcard::experimental::max_size::MaxSize;
use serde::de::DeserializeOwned;
use serde::Serialize;

use crate::dlc::{fd_padded_len, MAX_FD_LEN};
use crate::e2e::{self, HEADER_LEN};
use crate::error::DecodeError;
use crate::frame::Frame;
use crate::id::MessageId;
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

    /// The identifier this message goes out on.
    fn id(address: Self::Address) -> MessageId;
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

/// Why a message could not be encoded. Cannot happen for the messages of this crate (their
/// sizes are checked at compile time); reported rather than assumed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum EncodeError {
    /// The serializer ran out of room.
    TooLarge,
}

/// Encodes `message` for `address` with rolling counter `counter` into a padded CAN FD frame.
pub fn encode<M: Message>(
    message: &M,
    address: M::Address,
    counter: u16,
) -> Result<Frame, EncodeError> {
    let id = M::id(address);
    let mut buf = [0_u8; MAX_FD_LEN];
    let payload = buf
        .get_mut(HEADER_LEN..M::LEN)
        .ok_or(EncodeError::TooLarge)?;
    let written = postcard::to_slice(message, payload).map_err(|_| EncodeError::TooLarge)?;
    if written.len() != M::POSTCARD_MAX_SIZE {
        return Err(EncodeError::TooLarge);
    }
    e2e::protect(
        id.data_id(),
        counter,
        buf.get_mut(..M::LEN).ok_or(EncodeError::TooLarge)?,
    );
    Frame::new(
        id.raw(),
        buf.get(..M::WIRE_LEN).ok_or(EncodeError::TooLarge)?,
    )
    .ok_or(EncodeError::TooLarge)
}

/// Decodes the data of a frame on `id` as `M`: length, CRC and value ranges are checked; the
/// rolling counter is returned for the caller's sequence check.
pub fn decode<M: Message>(id: MessageId, data: &[u8]) -> Result<(M, u16), DecodeError> {
    let raw = id.raw();
    if data.len() != M::WIRE_LEN {
        return Err(DecodeError::WrongLength {
            id: raw,
            expected: M::WIRE_LEN,
            got: data.len(),
        });
    }
    let message = data.get(..M::LEN).ok_or(DecodeError::WrongLength {
        id: raw,
        expected: M::WIRE_LEN,
        got: data.len(),
    })?;
    let counter = e2e::verify(id.data_id(), message).ok_or(DecodeError::CrcMismatch { id: raw })?;
    let payload = message
        .get(HEADER_LEN..)
        .ok_or(DecodeError::CrcMismatch { id: raw })?;
    // The length is fixed and checked, so the only way postcard fails here is a field's own
    // range check (an out-of-range scalar, unknown enumeration value or flag bit).
    let value =
        postcard::from_bytes::<M>(payload).map_err(|_| DecodeError::OutOfRange { id: raw })?;
    Ok((value, counter))
}
