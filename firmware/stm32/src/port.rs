//! The thin adapter between the HAL's FDCAN driver (`fdcan` crate, through `stm32g4xx-hal`) and
//! `embedded_can::Frame`: neither implements the embedded-can driver traits, so this is where
//! their frame headers become [`FdFrame`]s and back.
//!
//! Bus timing (from the 80 MHz PLL "Q" kernel clock): 1 Mbit/s arbitration (prescaler 2, 40 tq,
//! sample point 80 %) and 5 Mbit/s data (prescaler 1, 16 tq, sample point 81 %, transceiver
//! delay compensation on), CAN FD with bit-rate switching, every standard id into FIFO 0.

use core::num::{NonZeroU16, NonZeroU8};

use embedded_can::{Frame as _, Id, StandardId};
use fdcan::config::{DataBitTiming, FrameTransmissionConfig, NominalBitTiming};
use fdcan::filter::{StandardFilter, StandardFilterSlot};
use fdcan::frame::{FrameFormat, TxFrameHeader};
use fdcan::{FdCan, Instance, NormalOperationMode, ReceiveOverrun};
use firmware::can::{FdFrame, MAX_FD_LEN};

/// How often a frame waits for a free transmit buffer before it is dropped (each try is a
/// register read; a 64-byte FD frame takes ~140 µs on the bus).
const TX_TRIES: u32 = 20_000;

/// The FDCAN in normal operation, seen as frames.
pub struct FdcanPort<I: Instance> {
    can: FdCan<I, NormalOperationMode>,
    dropped: u32,
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
            dropped: 0,
        })
    }

    /// The next received frame, if any.
    pub fn receive(&mut self) -> Option<FdFrame> {
        let mut buffer = [0_u8; MAX_FD_LEN];
        let info = match self.can.receive0(&mut buffer) {
            // An overrun lost older frames (the node's sequence checks count them); this one
            // is good.
            Ok(ReceiveOverrun::NoOverrun(info) | ReceiveOverrun::Overrun(info)) => info,
            Err(_) => return None,
        };
        let id: Id = match info.id {
            fdcan::id::Id::Standard(id) => StandardId::new(id.as_raw())?.into(),
            fdcan::id::Id::Extended(id) => embedded_can::ExtendedId::new(id.as_raw())?.into(),
        };
        if info.rtr {
            return None;
        }
        FdFrame::new(id, buffer.get(..usize::from(info.len))?)
    }

    /// Queues `frame` for transmission, waiting (bounded) for a free buffer; a frame that
    /// finds none is dropped and counted.
    pub fn transmit(&mut self, frame: &FdFrame) {
        let id: fdcan::id::Id = match frame.id() {
            Id::Standard(id) => match fdcan::id::StandardId::new(id.as_raw()) {
                Some(id) => id.into(),
                None => return self.drop_one(),
            },
            Id::Extended(_) => return self.drop_one(),
        };
        let header = TxFrameHeader {
            len: u8::try_from(frame.dlc()).unwrap_or(0),
            frame_format: FrameFormat::Fdcan,
            id,
            bit_rate_switching: true,
            marker: None,
        };
        for _ in 0..TX_TRIES {
            // A full queue takes the frame only in place of a lower-priority one (which is then
            // lost); otherwise it asks to wait.
            match self
                .can
                .transmit_preserve(header, frame.data(), &mut |_, _, _| ())
            {
                Ok(None) => return,
                Ok(Some(())) => return self.drop_one(),
                Err(nb::Error::WouldBlock) => continue,
                Err(nb::Error::Other(never)) => match never {},
            }
        }
        self.drop_one();
    }

    fn drop_one(&mut self) {
        self.dropped = self.dropped.saturating_add(1);
    }

    /// Frames dropped on transmit.
    #[allow(dead_code)]
    pub fn dropped(&self) -> u32 {
        self.dropped
    }
}
