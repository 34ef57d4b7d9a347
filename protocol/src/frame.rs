//! A CAN FD frame as this crate produces and consumes it, independent of any driver.
//!
//! Adapters (SocketCAN, the in-process bus, the MCU's FDCAN) convert to and from their own frame
//! type; this one only guarantees a standard 11-bit id and a valid CAN FD data length.

use crate::dlc::{is_fd_len, MAX_FD_LEN};
use crate::id::MAX_STANDARD_ID;

/// A CAN FD frame with an 11-bit identifier and a valid FD data length.
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct Frame {
    id: u16,
    len: u8,
    data: [u8; MAX_FD_LEN],
}

impl Frame {
    /// A frame, or `None` if `id` is not an 11-bit identifier or `data.len()` is not a CAN FD
    /// length (0–8, 12, 16, 20, 24, 32, 48, 64).
    pub fn new(id: u16, data: &[u8]) -> Option<Frame> {
        if id > MAX_STANDARD_ID || !is_fd_len(data.len()) {
            return None;
        }
        let mut buf = [0; MAX_FD_LEN];
        buf.get_mut(..data.len())?.copy_from_slice(data);
        Some(Frame {
            id,
            len: u8::try_from(data.len()).ok()?,
            data: buf,
        })
    }

    /// The 11-bit identifier.
    pub const fn id(&self) -> u16 {
        self.id
    }

    /// The payload.
    pub fn data(&self) -> &[u8] {
        self.data.get(..usize::from(self.len)).unwrap_or(&[])
    }
}

impl core::fmt::Debug for Frame {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "Frame({:03X}##", self.id)?;
        for byte in self.data() {
            write!(f, "{byte:02X}")?;
        }
        f.write_str(")")
    }
}

/// The frame every driver can take: any `embedded-can` port whose frame type is this one
/// carries the robot's bus. Only what the bus uses can be built: an 11-bit id and a CAN FD
/// data length; extended ids and remote frames give `None`.
impl embedded_can::Frame for Frame {
    fn new(id: impl Into<embedded_can::Id>, data: &[u8]) -> Option<Self> {
        match id.into() {
            embedded_can::Id::Standard(id) => Frame::new(id.as_raw(), data),
            embedded_can::Id::Extended(_) => None,
        }
    }

    /// CAN FD has no remote frames.
    fn new_remote(_id: impl Into<embedded_can::Id>, _dlc: usize) -> Option<Self> {
        None
    }

    fn is_extended(&self) -> bool {
        false
    }

    fn is_remote_frame(&self) -> bool {
        false
    }

    fn id(&self) -> embedded_can::Id {
        // Every `Frame` holds an 11-bit id (checked in `Frame::new`).
        embedded_can::StandardId::new(self.id)
            .unwrap_or(embedded_can::StandardId::ZERO)
            .into()
    }

    /// The payload length in bytes (for CAN FD this is not the 4-bit DLC code).
    fn dlc(&self) -> usize {
        usize::from(self.len)
    }

    fn data(&self) -> &[u8] {
        Frame::data(self)
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;
    use embedded_can::{ExtendedId, Frame as _, Id, StandardId};

    #[test]
    fn the_embedded_can_view_is_the_same_frame() {
        let id = StandardId::new(0x123).unwrap();
        let frame = <Frame as embedded_can::Frame>::new(id, &[1, 2, 3]).unwrap();
        assert_eq!(frame, Frame::new(0x123, &[1, 2, 3]).unwrap());
        assert_eq!(embedded_can::Frame::id(&frame), Id::Standard(id));
        assert_eq!(frame.dlc(), 3);
        assert!(!frame.is_extended() && !frame.is_remote_frame());
        assert!(<Frame as embedded_can::Frame>::new(id, &[0; 12]).is_some());
        assert!(<Frame as embedded_can::Frame>::new(id, &[0; 9]).is_none());
        let extended = ExtendedId::new(0x10).unwrap();
        assert!(<Frame as embedded_can::Frame>::new(extended, &[]).is_none());
        assert!(Frame::new_remote(id, 0).is_none());
    }
}
