//! Where the core meets a CAN controller, generic over [`embedded_can::Frame`].
//!
//! A HAL's CAN driver (the STM32G474's FDCAN, a recorded bus in the processor-in-the-loop image)
//! only has to turn its received frames into some `embedded_can::Frame` and send the ones this
//! module hands back; [`receive`] feeds the [`Node`] and [`transmit`] converts what
//! [`Node::poll`] returns. [`FdFrame`] is a CAN FD data frame (up to 64 bytes) implementing the
//! trait, for drivers that have no frame type of their own.

use embedded_can::{Frame as CanFrame, Id, StandardId};
use protocol::{DecodeError, Frame};

use crate::node::Node;
use crate::time::Tick;

/// Longest CAN FD payload.
pub const MAX_FD_LEN: usize = 64;

/// A CAN FD data frame: an 11- or 29-bit id and 0–8, 12, 16, 20, 24, 32, 48 or 64 bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FdFrame {
    id: Id,
    len: u8,
    data: [u8; MAX_FD_LEN],
}

/// Whether `len` is a CAN FD payload length.
pub const fn is_fd_len(len: usize) -> bool {
    matches!(len, 0..=8 | 12 | 16 | 20 | 24 | 32 | 48 | 64)
}

impl CanFrame for FdFrame {
    fn new(id: impl Into<Id>, data: &[u8]) -> Option<Self> {
        if !is_fd_len(data.len()) {
            return None;
        }
        let mut buf = [0; MAX_FD_LEN];
        buf.get_mut(..data.len())?.copy_from_slice(data);
        Some(Self {
            id: id.into(),
            len: u8::try_from(data.len()).ok()?,
            data: buf,
        })
    }

    /// CAN FD has no remote frames.
    fn new_remote(_id: impl Into<Id>, _dlc: usize) -> Option<Self> {
        None
    }

    fn is_extended(&self) -> bool {
        matches!(self.id, Id::Extended(_))
    }

    fn is_remote_frame(&self) -> bool {
        false
    }

    fn id(&self) -> Id {
        self.id
    }

    /// The payload length in bytes (for CAN FD this is not the 4-bit DLC code).
    fn dlc(&self) -> usize {
        usize::from(self.len)
    }

    fn data(&self) -> &[u8] {
        self.data.get(..usize::from(self.len)).unwrap_or(&[])
    }
}

/// What became of a received frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Received {
    /// Decoded, checked and given to the controller.
    Accepted,
    /// Refused by the protocol's checks (and counted by the node).
    Rejected(DecodeError),
    /// Not a frame of this bus: an extended id or a remote frame. Not given to the node.
    Foreign,
}

/// Gives `frame` to `node` at `now`.
pub fn receive<F: CanFrame>(node: &mut Node, now: Tick, frame: &F) -> Received {
    let id = match frame.id() {
        Id::Standard(id) if !frame.is_remote_frame() => id.as_raw(),
        _ => return Received::Foreign,
    };
    match node.on_frame(now, id, frame.data()) {
        Ok(()) => Received::Accepted,
        Err(e) => Received::Rejected(e),
    }
}

/// The driver's frame for one of the node's frames (`None` only if the driver's frame type
/// cannot hold it).
pub fn transmit<F: CanFrame>(frame: &Frame) -> Option<F> {
    F::new(StandardId::new(frame.id())?, frame.data())
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::indexing_slicing)]

    use super::*;
    use crate::config::Config;
    use embedded_can::ExtendedId;
    use protocol::{AnyMessage, E2eCounter, Sync};

    #[test]
    fn fd_frame_lengths() {
        let id = StandardId::new(0x100).unwrap();
        assert!(FdFrame::new(id, &[0; 64]).is_some());
        assert!(FdFrame::new(id, &[0; 12]).is_some());
        assert!(FdFrame::new(id, &[0; 9]).is_none());
        assert!(FdFrame::new(id, &[0; 65]).is_none());
        assert!(FdFrame::new_remote(id, 0).is_none());
        let frame = FdFrame::new(id, &[1, 2, 3]).unwrap();
        assert_eq!(frame.data(), &[1, 2, 3]);
        assert_eq!(frame.dlc(), 3);
        assert!(!frame.is_extended());
    }

    #[test]
    fn frames_round_trip_through_the_trait() {
        let mut node = Node::new(Config::ROBOT).unwrap();
        let sync = AnyMessage::Sync(Sync {
            tick: protocol::Tick::from_raw(0).unwrap(),
        })
        .encode(E2eCounter::default().advance())
        .unwrap();
        let can: FdFrame = transmit(&sync).unwrap();
        assert_eq!(receive(&mut node, Tick(0), &can), Received::Accepted);
        let extended = FdFrame::new(ExtendedId::new(0x10).unwrap(), &[0; 8]).unwrap();
        assert_eq!(receive(&mut node, Tick(0), &extended), Received::Foreign);
        let (_, frames) = node.poll(Tick(0));
        for frame in &frames {
            let can: FdFrame = transmit(frame).unwrap();
            assert_eq!(can.data(), frame.data());
            assert_eq!(can.id(), Id::Standard(StandardId::new(frame.id()).unwrap()));
        }
    }
}
