//! End-to-end protection: every frame carries a check value and the low half of a rolling
//! counter in front of its payload, in the manner of AUTOSAR E2E and SecOC.
//!
//! | byte      | field                                                                       |
//! |-----------|-----------------------------------------------------------------------------|
//! | 0–3       | check value, `u32` little-endian: CRC-32C or truncated CMAC-AES-128 ([`Check`]) |
//! | 4–5       | rolling counter, low 16 bits of the sender's 32-bit counter on this id      |
//! | 6…        | payload (postcard, fixed-width integers)                                     |
//! | after     | zero padding up to the CAN FD data length (not covered by the check)        |
//!
//! The check value covers, in this order: the identifier's data id
//! ([`MessageId::data_id`](crate::MessageId::data_id), `u16`), the session epoch (`u32`, zero
//! for a frame bound to no session), the sender's **full** counter (`u32`) and the payload, all
//! little-endian. Neither the data id, the epoch nor the counter's high half is sent: the
//! receiver supplies them, so a frame moved to another identifier, replayed from another
//! session, or replayed from 2^16 frames ago fails its check (see [`crate::session`]).
//!
//! A CMAC is the first four bytes of the 16-byte tag, read little-endian; CRC-32C is
//! Castagnoli's polynomial (0x1EDC6F41, reflected, init and xor-out 0xFFFFFFFF).

use crate::cmac::CmacKey;
use crc::{Crc, CRC_32_ISCSI};

use crate::session::{Epoch, Key};

/// Bytes of E2E header in front of every payload.
pub const HEADER_LEN: usize = 6;

const CRC32C: Crc<u32> = Crc::<u32>::new(&CRC_32_ISCSI);

/// Which check value a frame carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Check {
    /// CRC-32C: detects corruption; anyone can compute it.
    Crc,
    /// CMAC-AES-128 truncated to 32 bits: only a holder of the key can compute it.
    Mac,
}

/// How a frame is protected: its check value and whether it is bound to the session.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Protection {
    /// The check value.
    pub check: Check,
    /// Whether the check covers the session epoch (and so needs one to send or receive).
    pub bound: bool,
    /// Whether the frame takes part in its identifier's counter sequence. A frame outside it
    /// (the E-stop latch, the announcement) is checked at its low counter alone, with high
    /// half zero, so that a constant frame stays valid.
    pub sequenced: bool,
}

/// An authenticated command: CMAC bound to the session.
pub const AUTHENTICATED: Protection = Protection {
    check: Check::Mac,
    bound: true,
    sequenced: true,
};

/// The values a check covers besides the payload.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Freshness {
    /// The identifier's data id.
    pub data_id: u16,
    /// The session epoch, or `None` for a frame bound to no session.
    pub epoch: Option<Epoch>,
    /// The sender's full counter.
    pub counter: u32,
}

impl Freshness {
    fn bytes(&self) -> [u8; 10] {
        let [d0, d1] = self.data_id.to_le_bytes();
        let [e0, e1, e2, e3] = self.epoch.map_or(0, Epoch::raw).to_le_bytes();
        let [c0, c1, c2, c3] = self.counter.to_le_bytes();
        [d0, d1, e0, e1, e2, e3, c0, c1, c2, c3]
    }
}

/// A key ready to compute CMACs: the AES key schedule and the CMAC subkeys, computed once.
/// A node that checks or seals many frames keeps one ([`Sender`](crate::Sender) and
/// [`Receiver`](crate::Receiver) do), so that a MAC costs its blocks and nothing more.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PreparedKey(CmacKey);

impl PreparedKey {
    /// `key`, prepared.
    pub fn new(key: &Key) -> Self {
        PreparedKey(CmacKey::new(&key.0))
    }
}

/// What a CMAC is computed with: a [`Key`] (prepared anew for every MAC) or a
/// [`PreparedKey`].
pub trait MacKey {
    /// The CMAC tag of the concatenation of `parts`.
    fn tag(&self, parts: &[&[u8]]) -> [u8; 16];
}

impl MacKey for Key {
    fn tag(&self, parts: &[&[u8]]) -> [u8; 16] {
        CmacKey::new(&self.0).tag(parts)
    }
}

impl MacKey for PreparedKey {
    fn tag(&self, parts: &[&[u8]]) -> [u8; 16] {
        self.0.tag(parts)
    }
}

/// The check value of `payload` under `freshness`.
pub fn check_value<K: MacKey + ?Sized>(
    check: Check,
    key: &K,
    freshness: &Freshness,
    payload: &[u8],
) -> u32 {
    let prefix = freshness.bytes();
    match check {
        Check::Crc => {
            let mut digest = CRC32C.digest();
            digest.update(&prefix);
            digest.update(payload);
            digest.finalize()
        }
        Check::Mac => {
            let tag = key.tag(&[&prefix, payload]);
            let mut first = [0; 4];
            for (slot, byte) in first.iter_mut().zip(tag.iter()) {
                *slot = *byte;
            }
            u32::from_le_bytes(first)
        }
    }
}

/// Writes check value and counter into the first [`HEADER_LEN`] bytes of `message`, whose
/// payload is already in place after them. Does nothing if `message` is shorter than the
/// header.
pub fn protect<K: MacKey + ?Sized>(
    check: Check,
    key: &K,
    freshness: &Freshness,
    message: &mut [u8],
) -> Option<()> {
    let low = (freshness.counter & 0xFFFF) as u16;
    message
        .get_mut(4..HEADER_LEN)?
        .copy_from_slice(&low.to_le_bytes());
    let value = check_value(check, key, freshness, message.get(HEADER_LEN..)?);
    message.get_mut(..4)?.copy_from_slice(&value.to_le_bytes());
    Some(())
}

/// The header of a received message: its check value and low counter, or `None` if the
/// message is shorter than the header.
pub fn header(message: &[u8]) -> Option<(u32, u16)> {
    let check = message.get(..4)?;
    let low = message.get(4..HEADER_LEN)?;
    Some((
        u32::from_le_bytes([
            *check.first()?,
            *check.get(1)?,
            *check.get(2)?,
            *check.get(3)?,
        ]),
        u16::from_le_bytes([*low.first()?, *low.get(1)?]),
    ))
}

/// What the receiver concludes about one frame of a sequence.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum E2eStatus {
    /// The next frame in sequence. Accept.
    Ok,
    /// In sequence after `lost` missing frames. Accept.
    OkSomeLost {
        /// Frames missing since the previous accepted one.
        lost: u32,
    },
    /// First frame of this sender in the session, or the first after it restarted or after a
    /// gap the sequence cannot span, found by the receiver's [`Search`]. Accept.
    Initial,
    /// Same counter as the previous frame, and a valid check: a duplicate or a replay. Reject.
    Repeated,
    /// Behind the sequence with a valid check: stale, replayed or reordered. Reject.
    WrongSequence,
    /// The check value does not match at the counter the sequence gives this frame: corrupted,
    /// forged, or replayed from another session or from 2^16 frames ago. Reject.
    CheckFailed,
}

impl E2eStatus {
    /// Whether a frame with this status may be acted on.
    pub const fn is_accepted(self) -> bool {
        matches!(
            self,
            E2eStatus::Ok | E2eStatus::OkSomeLost { .. } | E2eStatus::Initial
        )
    }
}

/// Where a receiver looks for a frame that does not follow the sequence it knows (or the
/// first frame of a sender it has not heard): first the counter with the frame's low half
/// nearest `reference` (within ±2^15), then one and more periods of 2^16 below it, `tries`
/// candidates in all, and only counters after the last accepted one.
///
/// A sender's counters stay within [`MAX_LAG_MS`] below the session time (see
/// [`crate::session`]), so a sender that restarted, a receiver that joined late, and a
/// sequence with a gap of 2^15 frames or more are found at the first candidate, while a replay
/// (at or behind the last accepted counter, or older than the candidates reach: 2^15 + 2^16 ms,
/// 98.3 s) is
/// not.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Search {
    /// The receiver's session time, ms.
    pub reference: u32,
    /// Most high halves to try.
    pub tries: u32,
}

/// How far a sender's counter may fall behind the session time before it jumps to it, ms: a
/// sender slower than one frame per millisecond falls behind, and the receivers' search
/// ([`Search`]) only looks so far back.
pub const MAX_LAG_MS: u32 = 1 << 14;

impl Search {
    /// The search a receiver makes at session time `reference`: two candidates, the nearest
    /// and one period below (a CMAC costs a block cipher run per try).
    pub const fn new(reference: u32) -> Self {
        Self {
            reference,
            tries: 2,
        }
    }

    /// The candidate full counters for low half `low`, nearest `reference` first.
    fn candidates(self, low: u16) -> impl Iterator<Item = u32> {
        let low = u32::from(low);
        let same = self.reference & !0xFFFF | low;
        let nearest = if same > self.reference.saturating_add(0x8000) {
            same.checked_sub(0x1_0000)
        } else if same.saturating_add(0x8000) < self.reference {
            same.checked_add(0x1_0000)
        } else {
            Some(same)
        };
        (0..self.tries).map_while(move |n| nearest?.checked_sub(n.checked_mul(0x1_0000)?))
    }
}

/// Slack on the session time a member knows, ms: it hears the time at 50 Hz, and a frame may
/// wait in a queue.
const TIME_SLACK_MS: u32 = 100;

/// Counter state of one identifier at the receiver: the last accepted counter and the session
/// time it was accepted at.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct E2eChecker {
    last: Option<u32>,
    last_at_ms: u32,
}

impl E2eChecker {
    /// A checker that has heard nothing.
    pub const fn new() -> Self {
        Self {
            last: None,
            last_at_ms: 0,
        }
    }

    /// Forgets the sequence (a new session restarts every sender).
    pub fn reset(&mut self) {
        *self = Self::new();
    }

    /// The last accepted full counter.
    pub const fn last(&self) -> Option<u32> {
        self.last
    }

    /// Places a received low counter in the sequence, verifies the frame at that full counter
    /// with `verify`, and advances the sequence when the frame is accepted.
    ///
    /// Ahead by 1…2^15 − 1 is in sequence (the frames between are lost), unless more frames
    /// would be lost than milliseconds have passed since the last accepted one: then the
    /// sender restarted at the session time, and the sequence restarts (`Initial`). The same
    /// counter with
    /// a valid check is a repeat; behind by 1…2^15 with a valid check is out of sequence. A
    /// frame that fits none of these is looked for as `search` says ([`Search`]): found, it
    /// restarts the sequence (`Initial`); not found, its check failed.
    pub fn check(
        &mut self,
        low: u16,
        search: Search,
        mut verify: impl FnMut(u32) -> bool,
    ) -> E2eStatus {
        if let Some(last) = self.last {
            let delta = low.wrapping_sub((last & 0xFFFF) as u16);
            if delta == 0 {
                if verify(last) {
                    return E2eStatus::Repeated;
                }
            } else if delta < 0x8000 {
                let full = last.saturating_add(u32::from(delta));
                if verify(full) {
                    let elapsed_ms = search.reference.saturating_sub(self.last_at_ms);
                    let lost = u32::from(delta) - 1;
                    self.accept(full, search.reference);
                    return match lost {
                        0 => E2eStatus::Ok,
                        _ if lost > elapsed_ms.saturating_add(TIME_SLACK_MS) => E2eStatus::Initial,
                        _ => E2eStatus::OkSomeLost { lost },
                    };
                }
            } else {
                let behind = 0x1_0000 - u32::from(delta);
                if last.checked_sub(behind).is_some_and(&mut verify) {
                    return E2eStatus::WrongSequence;
                }
            }
        }
        let last = self.last;
        let found = search
            .candidates(low)
            .filter(|full| last.is_none_or(|last| *full > last))
            .find(|full| verify(*full));
        match found {
            Some(full) => {
                self.accept(full, search.reference);
                E2eStatus::Initial
            }
            None => E2eStatus::CheckFailed,
        }
    }

    fn accept(&mut self, counter: u32, at_ms: u32) {
        self.last = Some(counter);
        self.last_at_ms = at_ms;
    }
}
