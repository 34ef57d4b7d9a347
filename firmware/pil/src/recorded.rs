//! The recorded bus as a CAN port: the frames recorded for a tick come out of `receive`, and
//! what the node transmits is kept for the report, so that the image runs the firmware's own
//! service loop ([`firmware::node::service`]) exactly as the board does.

use core::convert::Infallible;

use embedded_can::nb::Can;
use firmware::node::TickFrames;
use heapless::Vec;
use protocol::Frame;

use crate::inputs::MAX_FRAMES;

/// One tick's recorded frames in, the node's frames out.
pub struct Recorded {
    inbox: Vec<Frame, MAX_FRAMES>,
    next: usize,
    sent: TickFrames,
}

impl Recorded {
    pub const fn new() -> Self {
        Self {
            inbox: Vec::new(),
            next: 0,
            sent: TickFrames::new(),
        }
    }

    /// The buffer for the next tick's frames; taking it starts a new tick.
    pub fn inbox(&mut self) -> &mut Vec<Frame, MAX_FRAMES> {
        self.next = 0;
        self.sent.clear();
        &mut self.inbox
    }

    /// What the node sent this tick.
    pub fn sent(&self) -> &[Frame] {
        &self.sent
    }
}

impl Can for Recorded {
    type Frame = Frame;
    type Error = Infallible;

    /// Keeps the frame; a tick never sends more than `TickFrames` holds.
    fn transmit(&mut self, frame: &Frame) -> nb::Result<Option<Frame>, Infallible> {
        Ok(self.sent.push(*frame).err())
    }

    fn receive(&mut self) -> nb::Result<Frame, Infallible> {
        let frame = self
            .inbox
            .get(self.next)
            .copied()
            .ok_or(nb::Error::WouldBlock)?;
        self.next += 1;
        Ok(frame)
    }
}
