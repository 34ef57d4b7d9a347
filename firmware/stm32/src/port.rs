//! The thin adapter between the HAL's FDCAN driver (`fdcan` crate, through `stm32g4xx-hal`) and
//! the control core: neither implements the embedded-can driver traits, so this port does —
//! [`embedded_can::nb::Can`] with the protocol's [`Frame`] — and the core's one service loop
//! ([`firmware::node::service`]) drives it.
//!
//! Bus timing (from the 80 MHz PLL "Q" kernel clock): 1 Mbit/s arbitration (prescaler 2, 40 tq,
//! sample point 80 %) and 5 Mbit/s data (prescaler 1, 16 tq, sample point 81 %, transceiver
//! delay compensation on), CAN FD with bit-rate switching, every standard id into FIFO 0.

use core::convert::Infallible;
use core::num::{NonZeroU16, NonZeroU8};

use embedded_can::nb::Can;
use fdcan::config::{DataBitTiming, FrameTransmissionConfig, NominalBitTiming};
use fdcan::filter::{StandardFilter, StandardFilterSlot};
use fdcan::frame::{FrameFormat, TxFrameHeader};
use fdcan::{FdCan, Instance, NormalOperationMode, ReceiveOverrun};
use protocol::dlc::MAX_FD_LEN;
use protocol::Frame;

/// Frames the receive FIFO can hold: the most one `receive` skips before it answers.
const RX_FIFO_DEPTH: usize = 3;

/// The FDCAN in normal operation, seen as frames.
pub struct FdcanPort<I: Instance> {
    can: FdCan<I, NormalOperationMode>,
    foreign: u32,
}

impl<I: Instance> FdcanPort<I> {
    /// Configures `can` (timing, FD with bit-rate switching, filters) and starts it.
    pub fn start(mut can: FdCan<I, fdcan::ConfigMode>) -> Option<Self> {
        can.set_protocol_exception_handling(false);
        can.set_nominal_bit_timing(NominalBitTiming {
            prescaler: NonZeroU16::new(2)?,
            seg1: NonZeroU8::new(31)?,
            seg2: NonZeroU8::new(8)?,
            sync_jump_width: NonZeroU8::new(8)?,
        });
        can.set_data_bit_timing(DataBitTiming {
            transceiver_delay_compensation: true,
            prescaler: NonZeroU8::new(1)?,
            seg1: NonZeroU8::new(12)?,
            seg2: NonZeroU8::new(3)?,
            sync_jump_width: NonZeroU8::new(3)?,
        });
        can.set_frame_transmit(FrameTransmissionConfig::AllowFdCanAndBRS);
        can.set_standard_filter(
            StandardFilterSlot::_0,
            StandardFilter::accept_all_into_fifo0(),
        );
        Some(Self {
            can: can.into_normal(),
            foreign: 0,
        })
    }

    /// The next frame of this bus in the receive FIFO, skipping (and counting) what the bus
    /// does not carry: extended ids and remote frames.
    fn next_frame(&mut self) -> Option<Frame> {
        for _ in 0..RX_FIFO_DEPTH {
            let mut buffer = [0_u8; MAX_FD_LEN];
            let info = match self.can.receive0(&mut buffer) {
                // An overrun lost older frames (the node's sequence checks count them); this
                // one is good.
                Ok(ReceiveOverrun::NoOverrun(info) | ReceiveOverrun::Overrun(info)) => info,
                Err(_) => return None,
            };
            let frame = match info.id {
                fdcan::id::Id::Standard(id) if !info.rtr => buffer
                    .get(..usize::from(info.len))
                    .and_then(|data| Frame::new(id.as_raw(), data)),
                _ => None,
            };
            match frame {
                Some(frame) => return Some(frame),
                None => self.foreign = self.foreign.saturating_add(1),
            }
        }
        None
    }

    /// Frames received that this bus does not carry (extended ids, remote frames).
    #[allow(dead_code)]
    pub fn foreign(&self) -> u32 {
        self.foreign
    }
}

impl<I: Instance> Can for FdcanPort<I> {
    type Frame = Frame;
    type Error = Infallible;

    /// Queues `frame` with bit-rate switching. A full queue takes it only in place of a
    /// lower-priority frame, which is returned (lost); otherwise it asks to wait.
    fn transmit(&mut self, frame: &Frame) -> nb::Result<Option<Frame>, Infallible> {
        let Some(id) = fdcan::id::StandardId::new(frame.id()) else {
            // `Frame` holds 11-bit ids only, so this cannot happen; refusing is the safe answer.
            return Ok(Some(*frame));
        };
        let header = TxFrameHeader {
            len: u8::try_from(frame.data().len()).unwrap_or(0),
            frame_format: FrameFormat::Fdcan,
            id: id.into(),
            bit_rate_switching: true,
            marker: None,
        };
        let replaced =
            self.can
                .transmit_preserve(header, frame.data(), &mut |_, header, words| {
                    replaced_frame(&header, words)
                })?;
        // A replaced frame that cannot be rebuilt is still reported as lost.
        Ok(replaced.map(|lost| lost.unwrap_or(*frame)))
    }

    fn receive(&mut self) -> nb::Result<Frame, Infallible> {
        self.next_frame().ok_or(nb::Error::WouldBlock)
    }
}

/// The frame in a transmit mailbox that a higher-priority one replaced.
fn replaced_frame(header: &TxFrameHeader, words: &[u32]) -> Option<Frame> {
    let fdcan::id::Id::Standard(id) = header.id else {
        return None;
    };
    let mut bytes = [0_u8; MAX_FD_LEN];
    for (chunk, word) in bytes.chunks_exact_mut(4).zip(words) {
        chunk.copy_from_slice(&word.to_le_bytes());
    }
    Frame::new(id.as_raw(), bytes.get(..usize::from(header.len))?)
}
