//! The processor-in-the-loop recording: the frames the firmware received, tick by tick, in one
//! closed-loop run — and the one place its byte formats are coded. `sim-host`'s `pil_record`
//! example writes the raw format, `cargo xtask pil` keeps the compact one
//! (`firmware/pil/recording.pil`) and turns it into the raw one the PIL image embeds, and the
//! image reads that on the MCU.
//!
//! Both formats are little-endian and laid out alike: a header of [`Header::LEN`] bytes —
//! magic (4 bytes), control rate u16 (Hz), first tick u32, tick count u32 — then per tick a
//! frame count u8 and per frame an id u16, a length u8 and the data.
//!
//! - **raw** ([`raw`], magic `PIL1`): the data as received. The image reads it with
//!   [`raw::Reader`], which needs no heap.
//! - **compact** ([`compact`], magic `PILZ`): each frame's data is XORed with the previous
//!   frame of its id (zeros where that one is shorter or there is none, so most bytes of
//!   slowly changing feedback become zero), then run-length coded: a byte `n < 0x80` is
//!   followed by `n + 1` literal bytes, a byte `n ≥ 0x80` stands for `n − 0x7F` zero bytes.
//!
//! The core (header, errors, raw reader) is `no_std` without a heap; the `alloc` feature adds
//! `Recording`, which reads and writes both formats.

// Functions stay short enough to read whole (clippy.toml: 80 lines); tests may run longer.
#![cfg_attr(not(test), warn(clippy::too_many_lines))]
#![no_std]
#![deny(missing_docs)]
#![deny(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

/// The session epoch of the recorded run: the recorder, the image and the host replay all
/// open this session with the test key, so that the recorded frames are fresh to both cores.
pub const PIL_EPOCH: u32 = 1;

#[cfg(feature = "alloc")]
extern crate alloc;

pub mod compact;
mod cursor;
pub mod raw;
#[cfg(feature = "alloc")]
mod recording;

use core::fmt;

use cursor::Cursor;
#[cfg(feature = "alloc")]
pub use recording::{Frame, Recording};

/// Why bytes are not a recording, or a recording cannot be written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Error {
    /// The bytes do not start with the format's magic.
    BadMagic {
        /// The magic the format starts with.
        expected: &'static [u8; 4],
    },
    /// The bytes end inside the header, a tick or a frame.
    Truncated,
    /// Bytes are left after the last tick the header counts.
    TrailingBytes,
    /// A run of the compact format's run-length code goes past the end of its frame.
    RunOverrun,
    /// Writing: a tick with more frames than its count (u8) holds.
    TooManyFrames,
    /// Writing: a frame longer than its length (u8) holds.
    FrameTooLong,
    /// Writing: more ticks than the header's count (u32) holds.
    TooManyTicks,
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::BadMagic { expected } => write!(
                f,
                "not a recording of this format (it does not start with `{}`)",
                expected.escape_ascii()
            ),
            Self::Truncated => f.write_str("the recording ends inside a header, tick or frame"),
            Self::TrailingBytes => f.write_str("bytes after the recording's last tick"),
            Self::RunOverrun => f.write_str("a run of the compact code goes past its frame"),
            Self::TooManyFrames => f.write_str("a tick with more than 255 frames"),
            Self::FrameTooLong => f.write_str("a frame longer than 255 bytes"),
            Self::TooManyTicks => f.write_str("more ticks than a u32 counts"),
        }
    }
}

impl core::error::Error for Error {}

/// What both formats start with, after the magic.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Header {
    /// Control rate, Hz.
    pub control_hz: u16,
    /// The first tick's number.
    pub first_tick: u32,
    /// Ticks recorded.
    pub ticks: u32,
}

impl Header {
    /// Bytes of a header, magic included.
    pub const LEN: usize = 14;

    /// Reads `magic` and a header.
    fn read(cursor: &mut Cursor<'_>, magic: &'static [u8; 4]) -> Result<Self, Error> {
        if cursor.take(magic.len())? != magic.as_slice() {
            return Err(Error::BadMagic { expected: magic });
        }
        Ok(Self {
            control_hz: cursor.u16()?,
            first_tick: cursor.u32()?,
            ticks: cursor.u32()?,
        })
    }

    /// Appends `magic` and this header.
    #[cfg(feature = "alloc")]
    fn write(&self, magic: &[u8; 4], out: &mut alloc::vec::Vec<u8>) {
        out.extend_from_slice(magic);
        out.extend_from_slice(&self.control_hz.to_le_bytes());
        out.extend_from_slice(&self.first_tick.to_le_bytes());
        out.extend_from_slice(&self.ticks.to_le_bytes());
    }
}
