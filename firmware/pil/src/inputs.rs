//! The recorded inputs (the "raw" format `cargo xtask pil` writes): `PIL1`, control rate u16,
//! first tick u32, tick count u32, then per tick a frame count u8 and per frame id u16,
//! length u8, data; little-endian.

use heapless::Vec;
use protocol::Frame;

/// Most frames one tick may carry.
pub const MAX_FRAMES: usize = 24;

/// The header and a cursor over the ticks.
pub struct Inputs {
    /// Control rate, Hz.
    pub control_hz: u32,
    /// The first tick's number.
    pub first_tick: u32,
    /// Ticks recorded.
    pub ticks: u32,
    cursor: Cursor,
}

impl Inputs {
    /// `None` unless `bytes` starts with a valid header.
    pub fn parse(bytes: &'static [u8]) -> Option<Self> {
        let mut cursor = Cursor { bytes, pos: 0 };
        if cursor.take(4)? != b"PIL1" {
            return None;
        }
        Some(Self {
            control_hz: u32::from(cursor.u16()?),
            first_tick: cursor.u32()?,
            ticks: cursor.u32()?,
            cursor,
        })
    }

    /// The next tick's frames into `frames` (cleared first); `None` at the end or on a
    /// malformed record.
    pub fn next_tick(&mut self, frames: &mut Vec<Frame, MAX_FRAMES>) -> Option<()> {
        frames.clear();
        let count = self.cursor.u8()?;
        for _ in 0..count {
            let id = self.cursor.u16()?;
            let len = usize::from(self.cursor.u8()?);
            let frame = Frame::new(id, self.cursor.take(len)?)?;
            frames.push(frame).ok()?;
        }
        Some(())
    }
}

struct Cursor {
    bytes: &'static [u8],
    pos: usize,
}

impl Cursor {
    fn take(&mut self, n: usize) -> Option<&'static [u8]> {
        let end = self.pos.checked_add(n)?;
        let out = self.bytes.get(self.pos..end)?;
        self.pos = end;
        Some(out)
    }

    fn u8(&mut self) -> Option<u8> {
        self.take(1)?.first().copied()
    }

    fn u16(&mut self) -> Option<u16> {
        Some(u16::from_le_bytes(self.take(2)?.try_into().ok()?))
    }

    fn u32(&mut self) -> Option<u32> {
        Some(u32::from_le_bytes(self.take(4)?.try_into().ok()?))
    }
}
