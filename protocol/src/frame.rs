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
