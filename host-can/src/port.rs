//! A [`Bus`] seen as an `embedded-can` port, so that the firmware's one service loop
//! (`firmware::node::service`) drives a host bus exactly as it drives the MCU's FDCAN.
//!
//! `embedded-can`'s non-blocking `receive` answers "nothing now" with `WouldBlock`; a host
//! port may first wait for a frame, as the runner's clocks need: not at all (take what is
//! there) or until a deadline (the next tick of a wall-clock runner, or the end of one
//! lockstep wait for the simulator, after which the runner looks at its stop flag).

use std::time::{Duration, Instant};

use embedded_can::nb::Can;
use protocol::Frame;

use crate::bus::{Bus, BusError};

/// How long [`BusPort`]'s `receive` waits for a frame before it answers `WouldBlock`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Wait {
    /// Not at all: only frames already there.
    Never,
    /// Until this instant; after it, not at all and no frame is taken.
    Until(Instant),
}

/// A bus as a port: `transmit` sends (or, batching, queues until [`BusPort::flush`]),
/// `receive` waits as told.
#[derive(Debug)]
pub struct BusPort<'a, B: Bus + ?Sized> {
    bus: &'a mut B,
    wait: Wait,
    outbox: Option<Vec<Frame>>,
}

impl<'a, B: Bus + ?Sized> BusPort<'a, B> {
    /// `bus` as a port whose `receive` waits as `wait` says and whose `transmit` sends at once.
    pub fn new(bus: &'a mut B, wait: Wait) -> Self {
        Self {
            bus,
            wait,
            outbox: None,
        }
    }

    /// As [`BusPort::new`], but `transmit` queues the frames and [`BusPort::flush`] puts them
    /// on the bus in one call ([`Bus::send_all`]): a tick's commands then wake the other
    /// nodes once. Frames not flushed are never sent.
    pub fn batching(bus: &'a mut B, wait: Wait) -> Self {
        Self {
            bus,
            wait,
            outbox: Some(Vec::new()),
        }
    }

    /// Sends the queued frames, in the order they were transmitted.
    pub fn flush(&mut self) -> Result<(), BusError> {
        match self.outbox.as_mut() {
            Some(outbox) if !outbox.is_empty() => {
                let result = self.bus.send_all(outbox);
                outbox.clear();
                result
            }
            _ => Ok(()),
        }
    }
}

impl<B: Bus + ?Sized> Can for BusPort<'_, B> {
    type Frame = Frame;
    type Error = BusError;

    /// Sends `frame`; a host bus never replaces a queued frame.
    fn transmit(&mut self, frame: &Frame) -> nb::Result<Option<Frame>, BusError> {
        match self.outbox.as_mut() {
            Some(outbox) => outbox.push(*frame),
            None => self.bus.send(frame).map_err(nb::Error::Other)?,
        }
        Ok(None)
    }

    fn receive(&mut self) -> nb::Result<Frame, BusError> {
        let timeout = match self.wait {
            Wait::Never => Duration::ZERO,
            Wait::Until(deadline) => match deadline.checked_duration_since(Instant::now()) {
                Some(left) if !left.is_zero() => left,
                _ => return Err(nb::Error::WouldBlock),
            },
        };
        match self.bus.recv(timeout) {
            Ok(Some(frame)) => Ok(frame),
            Ok(None) => Err(nb::Error::WouldBlock),
            Err(error) => Err(nb::Error::Other(error)),
        }
    }
}

impl embedded_can::Error for BusError {
    fn kind(&self) -> embedded_can::ErrorKind {
        embedded_can::ErrorKind::Other
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::inproc_bus::InprocBus;

    #[test]
    fn a_port_passes_frames_and_answers_would_block_when_dry() {
        let bus = InprocBus::new();
        let mut a = bus.endpoint();
        let mut b = bus.endpoint();
        let frame = Frame::new(0x123, &[1, 2]).unwrap();
        let mut port_a = BusPort::new(&mut a, Wait::Never);
        assert!(matches!(port_a.transmit(&frame), Ok(None)));
        let soon = Instant::now() + Duration::from_millis(1);
        let mut port_b = BusPort::new(&mut b, Wait::Until(soon));
        assert!(matches!(port_b.receive(), Ok(f) if f == frame));
        assert!(matches!(port_b.receive(), Err(nb::Error::WouldBlock)));
        let past = Instant::now();
        let mut port_b = BusPort::new(&mut b, Wait::Until(past));
        assert!(matches!(port_b.receive(), Err(nb::Error::WouldBlock)));
    }

    #[test]
    fn a_batching_port_sends_on_flush_in_order() {
        let bus = InprocBus::new();
        let mut a = bus.endpoint();
        let mut b = bus.endpoint();
        let frames = [
            Frame::new(0x10, &[1]).unwrap(),
            Frame::new(0x20, &[2]).unwrap(),
        ];
        let mut port_a = BusPort::batching(&mut a, Wait::Never);
        for frame in &frames {
            assert!(matches!(port_a.transmit(frame), Ok(None)));
        }
        assert_eq!(b.recv(Duration::ZERO).unwrap(), None);
        port_a.flush().unwrap();
        port_a.flush().unwrap();
        assert_eq!(b.recv(Duration::ZERO).unwrap(), Some(frames[0]));
        assert_eq!(b.recv(Duration::ZERO).unwrap(), Some(frames[1]));
        assert_eq!(b.recv(Duration::ZERO).unwrap(), None);
    }
}
