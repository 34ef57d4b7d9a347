//! The recorded inputs: `pil-format`'s raw format (`cargo xtask pil` writes it), read tick by
//! tick into CAN frames.

use embedded_can::{Frame, StandardId};
use heapless::Vec;
use pil_format::raw::Reader;

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
    reader: Reader<'static>,
}

impl Inputs {
    /// `None` unless `bytes` starts with a valid header.
    pub fn parse(bytes: &'static [u8]) -> Option<Self> {
        let reader = Reader::new(bytes).ok()?;
        let header = reader.header();
        Some(Self {
            control_hz: u32::from(header.control_hz),
            first_tick: header.first_tick,
            ticks: header.ticks,
            reader,
        })
    }

    /// The next tick's frames into `frames` (cleared first); `None` at the end, on a malformed
    /// record, or on a frame that is not a standard-id CAN (FD) frame or does not fit.
    pub fn next_tick<F: Frame>(&mut self, frames: &mut Vec<F, MAX_FRAMES>) -> Option<()> {
        frames.clear();
        for (id, data) in self.reader.next_tick().ok()?? {
            frames.push(F::new(StandardId::new(id)?, data)?).ok()?;
        }
        Some(())
    }
}
