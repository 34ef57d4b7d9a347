//! Why a frame was rejected.

use crate::e2e::E2eStatus;

/// A frame that is not acted on, and why. Every variant maps to one [`RejectCause`] so a
/// receiver can count rejections by cause.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum DecodeError {
    /// No message of this bus uses the identifier.
    UnknownId(u16),
    /// The data length is not the message's CAN FD length.
    WrongLength {
        /// Identifier of the frame.
        id: u16,
        /// Length the message has on the wire.
        expected: usize,
        /// Length received.
        got: usize,
    },
    /// The E2E CRC does not match: the frame was corrupted or sent on the wrong identifier.
    CrcMismatch {
        /// Identifier of the frame.
        id: u16,
    },
    /// A field holds a value outside its documented range (or an unknown enumeration value or
    /// flag bit).
    OutOfRange {
        /// Identifier of the frame.
        id: u16,
    },
    /// The rolling counter repeats the previous frame's: a duplicate or a replay.
    Repeated {
        /// Identifier of the frame.
        id: u16,
    },
    /// The rolling counter jumped further than the receiver tolerates: stale, replayed or
    /// reordered.
    WrongSequence {
        /// Identifier of the frame.
        id: u16,
    },
    /// The frame passed every check, but its sender exceeded the rate the receiver serves for
    /// this identifier (a babbling node); the receiver drops it so that it keeps its period and
    /// serves the rest of the bus. The frame's counter still advanced the sequence, so the
    /// sender's next frame is in step.
    RateLimited {
        /// Identifier of the frame.
        id: u16,
    },
}

/// Cause of a rejection, for counters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum RejectCause {
    /// See [`DecodeError::UnknownId`].
    UnknownId = 0,
    /// See [`DecodeError::WrongLength`].
    WrongLength = 1,
    /// See [`DecodeError::CrcMismatch`].
    Crc = 2,
    /// See [`DecodeError::OutOfRange`].
    OutOfRange = 3,
    /// See [`DecodeError::Repeated`].
    Repeated = 4,
    /// See [`DecodeError::WrongSequence`].
    WrongSequence = 5,
    /// See [`DecodeError::RateLimited`].
    RateLimited = 6,
}

impl RejectCause {
    /// Every cause, in counter order.
    pub const ALL: [RejectCause; 7] = [
        RejectCause::UnknownId,
        RejectCause::WrongLength,
        RejectCause::Crc,
        RejectCause::OutOfRange,
        RejectCause::Repeated,
        RejectCause::WrongSequence,
        RejectCause::RateLimited,
    ];

    /// Short name for logs and tables.
    pub const fn name(self) -> &'static str {
        match self {
            RejectCause::UnknownId => "unknown_id",
            RejectCause::WrongLength => "wrong_length",
            RejectCause::Crc => "crc",
            RejectCause::OutOfRange => "out_of_range",
            RejectCause::Repeated => "repeated",
            RejectCause::WrongSequence => "wrong_sequence",
            RejectCause::RateLimited => "rate_limited",
        }
    }
}

impl DecodeError {
    /// The counter this rejection belongs to.
    pub const fn cause(&self) -> RejectCause {
        match self {
            DecodeError::UnknownId(_) => RejectCause::UnknownId,
            DecodeError::WrongLength { .. } => RejectCause::WrongLength,
            DecodeError::CrcMismatch { .. } => RejectCause::Crc,
            DecodeError::OutOfRange { .. } => RejectCause::OutOfRange,
            DecodeError::Repeated { .. } => RejectCause::Repeated,
            DecodeError::WrongSequence { .. } => RejectCause::WrongSequence,
            DecodeError::RateLimited { .. } => RejectCause::RateLimited,
        }
    }

    /// The rejection a rejecting E2E status stands for, or `None` if the status accepts.
    pub const fn from_e2e(id: u16, status: E2eStatus) -> Option<DecodeError> {
        match status {
            E2eStatus::Repeated => Some(DecodeError::Repeated { id }),
            E2eStatus::WrongSequence => Some(DecodeError::WrongSequence { id }),
            E2eStatus::CrcError => Some(DecodeError::CrcMismatch { id }),
            E2eStatus::Ok | E2eStatus::OkSomeLost { .. } | E2eStatus::Initial => None,
        }
    }
}

impl core::fmt::Display for DecodeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            DecodeError::UnknownId(id) => write!(f, "unknown CAN id 0x{id:03X}"),
            DecodeError::WrongLength { id, expected, got } => write!(
                f,
                "CAN id 0x{id:03X}: data length {got} bytes, this message has {expected}"
            ),
            DecodeError::CrcMismatch { id } => write!(f, "CAN id 0x{id:03X}: E2E CRC mismatch"),
            DecodeError::OutOfRange { id } => {
                write!(
                    f,
                    "CAN id 0x{id:03X}: a field is outside its documented range"
                )
            }
            DecodeError::Repeated { id } => {
                write!(
                    f,
                    "CAN id 0x{id:03X}: rolling counter repeated (duplicate or replay)"
                )
            }
            DecodeError::WrongSequence { id } => {
                write!(
                    f,
                    "CAN id 0x{id:03X}: rolling counter out of sequence (stale or replayed)"
                )
            }
            DecodeError::RateLimited { id } => {
                write!(f, "CAN id 0x{id:03X}: over the receiver's rate limit")
            }
        }
    }
}
