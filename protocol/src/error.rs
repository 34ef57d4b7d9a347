//! Why a frame was rejected.

use crate::e2e::{Check, E2eStatus};

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
    /// The E2E CRC does not match at the counter and session the receiver expects: the frame
    /// was corrupted, sent on the wrong identifier, or replayed from another session or from
    /// 2^16 frames ago.
    CrcMismatch {
        /// Identifier of the frame.
        id: u16,
    },
    /// The authentication code (CMAC) does not match: forged without the key, corrupted, or
    /// replayed from another session or from 2^16 frames ago.
    Unauthentic {
        /// Identifier of the frame.
        id: u16,
    },
    /// The frame is bound to a session and this node has not joined one yet (it has not heard
    /// the controller's announcement).
    NoSession {
        /// Identifier of the frame.
        id: u16,
    },
    /// An announcement of an older session than the one this node is in: a replay.
    StaleSession {
        /// Identifier of the frame.
        id: u16,
    },
    /// An announcement of another wire version: this node and the announcing controller do
    /// not speak the same protocol; update one of them.
    WireVersion {
        /// The version announced.
        theirs: u8,
    },
    /// A release that does not echo the controller's present release token: made for another
    /// latch, withheld and sent late, or sent when nothing is latched.
    StaleRelease {
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
    /// See [`DecodeError::Unauthentic`].
    Unauthentic = 7,
    /// See [`DecodeError::NoSession`], [`DecodeError::StaleSession`] and
    /// [`DecodeError::WireVersion`].
    Session = 8,
    /// See [`DecodeError::StaleRelease`].
    StaleRelease = 9,
}

impl RejectCause {
    /// Every cause, in counter order.
    pub const ALL: [RejectCause; 10] = [
        RejectCause::UnknownId,
        RejectCause::WrongLength,
        RejectCause::Crc,
        RejectCause::OutOfRange,
        RejectCause::Repeated,
        RejectCause::WrongSequence,
        RejectCause::RateLimited,
        RejectCause::Unauthentic,
        RejectCause::Session,
        RejectCause::StaleRelease,
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
            RejectCause::Unauthentic => "unauthentic",
            RejectCause::Session => "session",
            RejectCause::StaleRelease => "stale_release",
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
            DecodeError::Unauthentic { .. } => RejectCause::Unauthentic,
            DecodeError::NoSession { .. }
            | DecodeError::StaleSession { .. }
            | DecodeError::WireVersion { .. } => RejectCause::Session,
            DecodeError::StaleRelease { .. } => RejectCause::StaleRelease,
        }
    }

    /// The rejection a rejecting E2E status stands for on a frame checked with `check`, or
    /// `None` if the status accepts.
    pub const fn from_e2e(id: u16, check: Check, status: E2eStatus) -> Option<DecodeError> {
        match status {
            E2eStatus::Repeated => Some(DecodeError::Repeated { id }),
            E2eStatus::WrongSequence => Some(DecodeError::WrongSequence { id }),
            E2eStatus::CheckFailed => Some(match check {
                Check::Crc => DecodeError::CrcMismatch { id },
                Check::Mac => DecodeError::Unauthentic { id },
            }),
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
            DecodeError::Unauthentic { id } => write!(
                f,
                "CAN id 0x{id:03X}: authentication code mismatch (forged, corrupted or replayed)"
            ),
            DecodeError::NoSession { id } => write!(
                f,
                "CAN id 0x{id:03X}: no session yet (the controller's announcement not heard)"
            ),
            DecodeError::StaleSession { id } => write!(
                f,
                "CAN id 0x{id:03X}: announcement of another session: an older one (a replay), or, \
                 heard by a controller, another controller on the bus"
            ),
            DecodeError::WireVersion { theirs } => write!(
                f,
                "the controller speaks wire version {theirs}, this build speaks {}: run the \
                 same release of firmware, simulator and teleop",
                crate::session::WIRE_VERSION
            ),
            DecodeError::StaleRelease { id } => write!(
                f,
                "CAN id 0x{id:03X}: E-stop release for another latch than the present one"
            ),
        }
    }
}
