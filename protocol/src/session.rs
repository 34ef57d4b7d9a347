//! The bus session: the shared key and the controller's per-boot epoch that every check binds
//! a frame to, in the manner of AUTOSAR SecOC's freshness value.
//!
//! The controller owns the session. At every start it takes an **epoch** strictly greater than
//! any it used before (persisted: firmware-host's state file; the MCU image does not persist it
//! yet, see `docs/mcu.md`, "Keys and epochs") and
//! announces it with the wire version and its **session time** (ms since the session opened)
//! ([`Announce`](crate::Announce), authenticated, at 50 Hz). Every other node joins by hearing
//! the announcement and from then on binds each frame to the session: the frame's check value
//! covers the epoch and the frame's full 32-bit counter, of which only the low 16 bits travel.
//!
//! A sender starts its counters at the session time it (re)joins at and counts one per frame;
//! a sender slower than one frame per millisecond falls behind the session time, and jumps to
//! it when it is [`MAX_LAG_MS`](crate::e2e::MAX_LAG_MS) behind. At up to one frame per
//! millisecond on an identifier its counter never passes the session time, so a node that
//! restarts in the same session starts above everything it sent before, and a receiver that
//! joins late, or misses 2^15 frames, finds the counter near the session time
//! ([`Search`](crate::e2e::Search)); a jump further than the time elapsed restarts the
//! sequence rather than counting as loss. A frame recorded in an earlier session fails its
//! check in this one; a frame recorded earlier in this session is at or behind the receiver's
//! counter, or too old for its search, and a receiver only ever accepts a counter after the
//! last it accepted. Replays are refused, not merely rare. The E-stop **release** counts with
//! the session time itself (the greater of its next counter and the time), so that two
//! operators releasing on one identifier both stay ahead.
//!
//! Operator commands, E-stop releases and the announcement carry a truncated CMAC-AES-128 as
//! their check value, so that a node without the key cannot command the controller or release
//! an E-stop; drive commands, feedback and status carry a CRC-32C, which guards against
//! corruption and replay but not against a forger on the bus (see `docs/protocol.md`, "Threat
//! model": a CMAC of both drive commands every tick would take the Cortex-M4F's control step
//! past its instruction budget).
//!
//! One frame is bound to nothing: the E-stop **latch**, which anyone may send at any time with
//! a fixed content (an E-stop panel's constant frame, an operator's `cansend`).

pub use crate::units::{Epoch, SessionTime};

/// The wire version this build speaks. Nodes refuse an announcement of another version: the
/// layouts differ, and a node that guessed would misread every frame.
pub const WIRE_VERSION: u8 = 12;

/// An AES-128 key shared by the robot's nodes and its operators.
///
/// Real keys live outside the repository (see `docs/protocol.md`, "Keys"); [`TEST_KEY`] is for
/// simulation and CI, and a robot built with it is open to anyone who reads this file.
#[derive(Clone, Copy, Eq)]
pub struct Key(pub [u8; 16]);

impl PartialEq for Key {
    /// As one 128-bit word: no call and no early exit per byte.
    fn eq(&self, other: &Key) -> bool {
        u128::from_ne_bytes(self.0) == u128::from_ne_bytes(other.0)
    }
}

impl core::fmt::Debug for Key {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        if *self == TEST_KEY {
            f.write_str("Key(test key)")
        } else {
            f.write_str("Key(…)")
        }
    }
}

/// The public key of simulation and CI: every simulated node and the test suite use it.
pub const TEST_KEY: Key = Key(*b"hybrid-robot-sim");

/// Why a key could not be read from text.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum KeyError {
    /// Not 32 hexadecimal digits (surrounding whitespace is ignored).
    Length {
        /// Hex digits found.
        digits: usize,
    },
    /// A character that is not a hexadecimal digit, at this position.
    NotHex {
        /// Position of the character (0-based, after trimming).
        at: usize,
    },
}

impl core::fmt::Display for KeyError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            KeyError::Length { digits } => write!(
                f,
                "a key is 32 hexadecimal digits (16 bytes); this one has {digits}"
            ),
            KeyError::NotHex { at } => write!(f, "character {at} is not a hexadecimal digit"),
        }
    }
}

impl Key {
    /// Reads a key written as 32 hexadecimal digits.
    pub fn from_hex(text: &str) -> Result<Key, KeyError> {
        let text = text.trim();
        if text.len() != 32 {
            return Err(KeyError::Length {
                digits: text.chars().count(),
            });
        }
        let mut key = [0_u8; 16];
        for (at, (byte, pair)) in key.iter_mut().zip(text.as_bytes().chunks(2)).enumerate() {
            let digit = |offset: usize| {
                pair.get(offset)
                    .and_then(|c| char::from(*c).to_digit(16))
                    .and_then(|d| u8::try_from(d).ok())
                    .ok_or(KeyError::NotHex {
                        at: at * 2 + offset,
                    })
            };
            *byte = digit(0)? << 4_u32 | digit(1)?;
        }
        Ok(Key(key))
    }
}

/// What a node knows of the bus session: the key, the epoch once it has joined, and the
/// session time (the controller's own, or the latest it announced).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Session {
    key: Key,
    epoch: Option<Epoch>,
    time: SessionTime,
}

impl Session {
    /// The controller's session: it owns `epoch`.
    pub const fn owned(key: Key, epoch: Epoch) -> Session {
        Session {
            key,
            epoch: Some(epoch),
            time: SessionTime::from_ms(0),
        }
    }

    /// A node that has not heard the controller yet: it can send the E-stop latch and nothing
    /// bound to a session until it joins.
    pub const fn unjoined(key: Key) -> Session {
        Session {
            key,
            epoch: None,
            time: SessionTime::from_ms(0),
        }
    }

    /// The key.
    pub const fn key(&self) -> &Key {
        &self.key
    }

    /// The epoch, once joined.
    pub const fn epoch(&self) -> Option<Epoch> {
        self.epoch
    }

    /// The session time: the controller's own, or the latest it announced.
    pub const fn time(&self) -> SessionTime {
        self.time
    }

    /// The same session `time` into it.
    pub const fn at(self, time: SessionTime) -> Session {
        Session { time, ..self }
    }

    pub(crate) fn join(&mut self, epoch: Epoch, time: SessionTime) {
        self.epoch = Some(epoch);
        self.time = time;
    }

    pub(crate) fn set_time(&mut self, time: SessionTime) {
        self.time = time;
    }
}
