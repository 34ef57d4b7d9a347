//! End-to-end protection in the style of AUTOSAR E2E profile 5: every frame carries a CRC and a
//! rolling counter in front of its payload.
//!
//! | byte      | field                                                                     |
//! |-----------|---------------------------------------------------------------------------|
//! | 0–1       | CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF), little-endian              |
//! | 2–3       | rolling counter, `u16` little-endian, +1 per frame sent on this id, wraps |
//! | 4…        | payload (postcard, fixed-width integers)                                   |
//! | after     | zero padding up to the CAN FD data length (not covered by the CRC)         |
//!
//! The CRC covers bytes 2… of the message (counter and payload) followed by the identifier's
//! data id ([`MessageId::data_id`](crate::MessageId::data_id)), low byte first. The data id is
//! never sent: a frame that lands on another identifier fails its CRC.
//!
//! The counter is 16 bits (profile 5 has 8) so that at 1 kHz a replayed frame must be at least
//! 65 s old to fall inside the receiver's window by wrap-around.

use crc::{Crc, CRC_16_IBM_3740};

/// Bytes of E2E header in front of every payload.
pub const HEADER_LEN: usize = 4;

const CRC16: Crc<u16> = Crc::<u16>::new(&CRC_16_IBM_3740);

/// CRC of the protected bytes (counter and payload) and the data id.
pub fn crc(data_id: u16, protected: &[u8]) -> u16 {
    let mut digest = CRC16.digest();
    digest.update(protected);
    digest.update(&data_id.to_le_bytes());
    digest.finalize()
}

/// Writes counter and CRC into the first [`HEADER_LEN`] bytes of `message`, whose payload is
/// already in place after them. Does nothing if `message` is shorter than the header.
pub fn protect(data_id: u16, counter: u16, message: &mut [u8]) {
    if let Some(counter_bytes) = message.get_mut(2..HEADER_LEN) {
        counter_bytes.copy_from_slice(&counter.to_le_bytes());
    }
    let Some(protected) = message.get(2..) else {
        return;
    };
    let checksum = crc(data_id, protected);
    if let Some(crc_bytes) = message.get_mut(..2) {
        crc_bytes.copy_from_slice(&checksum.to_le_bytes());
    }
}

/// The counter of a message whose CRC matches, or `None` if it does not (or the message is
/// shorter than the header).
pub fn verify(data_id: u16, message: &[u8]) -> Option<u16> {
    let (crc_bytes, protected) = (message.get(..2)?, message.get(2..)?);
    let sent = u16::from_le_bytes([*crc_bytes.first()?, *crc_bytes.get(1)?]);
    if sent != crc(data_id, protected) {
        return None;
    }
    Some(u16::from_le_bytes([
        *protected.first()?,
        *protected.get(1)?,
    ]))
}

/// What the receiver concludes about one frame of a sequence.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum E2eStatus {
    /// The next frame in sequence. Accept.
    Ok,
    /// In sequence after `lost` missing frames (within the tolerated gap). Accept.
    OkSomeLost {
        /// Frames missing since the previous accepted one.
        lost: u16,
    },
    /// First frame seen, or the sender restarted and two consecutive frames confirmed its new
    /// sequence. Accept.
    Initial,
    /// Same counter as the previous frame: a duplicate or a replay. Reject.
    Repeated,
    /// Counter outside the tolerated window: stale, replayed, reordered or a restarted sender's
    /// first frame. Reject.
    WrongSequence,
    /// The CRC does not match. Reject.
    CrcError,
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

/// Rolling-counter state of one identifier at the receiver.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct E2eChecker {
    last: Option<u16>,
    candidate: Option<u16>,
    max_delta: u16,
}

/// Default tolerated counter step: up to 9 lost frames in a row still count as in sequence.
pub const DEFAULT_MAX_DELTA: u16 = 10;

impl Default for E2eChecker {
    fn default() -> Self {
        Self::new(DEFAULT_MAX_DELTA)
    }
}

impl E2eChecker {
    /// A checker that accepts a counter step of 1…`max_delta` (at least 1).
    pub const fn new(max_delta: u16) -> Self {
        Self {
            last: None,
            candidate: None,
            max_delta: if max_delta == 0 { 1 } else { max_delta },
        }
    }

    /// Checks a whole message: CRC first, then its counter against the sequence.
    pub fn check_message(&mut self, data_id: u16, message: &[u8]) -> E2eStatus {
        match verify(data_id, message) {
            Some(counter) => self.check_counter(counter),
            None => E2eStatus::CrcError,
        }
    }

    /// Checks the counter of a frame whose CRC already matched, and advances the sequence
    /// when the frame is accepted.
    ///
    /// A frame outside the window is rejected; if the next frame continues from it (its
    /// counter plus one), the sender is taken to have restarted and the sequence
    /// resynchronises there ([`E2eStatus::Initial`]).
    pub fn check_counter(&mut self, counter: u16) -> E2eStatus {
        let Some(last) = self.last else {
            self.accept(counter);
            return E2eStatus::Initial;
        };
        let delta = counter.wrapping_sub(last);
        let status = if delta == 0 {
            E2eStatus::Repeated
        } else if delta == 1 {
            E2eStatus::Ok
        } else if delta <= self.max_delta {
            E2eStatus::OkSomeLost { lost: delta - 1 }
        } else if self.candidate == Some(counter.wrapping_sub(1)) {
            E2eStatus::Initial
        } else {
            self.candidate = Some(counter);
            return E2eStatus::WrongSequence;
        };
        if status.is_accepted() {
            self.accept(counter);
        }
        status
    }

    /// How many frames a sender skipped if `counter` jumps ahead of the sequence beyond the
    /// tolerated window (a burst of loss longer than the window): counted from the last
    /// accepted counter, or from a pending out-of-window one it continues after. `None` for a
    /// counter in the window (see [`E2eStatus::OkSomeLost`]), a repeat, or one behind (half the
    /// counter range or more ahead counts as behind: stale, replayed or reordered, not lost).
    pub fn skipped_ahead(&self, counter: u16) -> Option<u16> {
        const HALF: u16 = 0x8000;
        let last = self.last?;
        let ahead_of_last = |delta: u16| delta > self.max_delta && delta < HALF;
        if let Some(candidate) = self
            .candidate
            .filter(|candidate| candidate.wrapping_sub(last) < HALF)
        {
            match counter.wrapping_sub(candidate) {
                // The pending counter again (a repeat), or the one after it (the sequence
                // resynchronises there): nothing skipped.
                0 | 1 => return None,
                delta if (2..HALF).contains(&delta) => return Some(delta - 1),
                _ => {}
            }
        }
        Some(counter.wrapping_sub(last))
            .filter(|delta| ahead_of_last(*delta))
            .map(|delta| delta - 1)
    }

    fn accept(&mut self, counter: u16) {
        self.last = Some(counter);
        self.candidate = None;
    }
}

/// The sending side of one identifier: hands out the rolling counter.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct E2eCounter(u16);

impl E2eCounter {
    /// A counter starting at `first`.
    pub const fn starting_at(first: u16) -> Self {
        Self(first)
    }

    /// The counter for the next frame.
    pub fn advance(&mut self) -> u16 {
        let current = self.0;
        self.0 = self.0.wrapping_add(1);
        current
    }
}
