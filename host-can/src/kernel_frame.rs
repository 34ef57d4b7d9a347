//! The Linux kernel's CAN frame structs as bytes: `struct canfd_frame` (72 bytes) and
//! `struct can_frame` (16 bytes), the records a raw CAN socket reads and writes. The batched
//! socket calls (`sendmmsg`, `recv` into a plain buffer) need them without going through a
//! frame type of the `socketcan` crate. Fields are in the host's byte order, as the kernel
//! keeps them.
//!
//! Layout (`linux/can.h`): `can_id` (u32: 11- or 29-bit id and the EFF/RTR/ERR flags),
//! `len` (u8, payload bytes), `flags` (u8, FD only), two reserved bytes, then the payload
//! (64 bytes for FD, 8 for classic).

use protocol::Frame;

/// Size of `struct canfd_frame`.
pub const FD_BYTES: usize = 72;
/// Size of `struct can_frame`.
pub const CLASSIC_BYTES: usize = 16;
/// Where the payload starts in both structs.
const DATA_AT: usize = 8;

/// `can_id` flag bits: extended (29-bit) id, remote request, error frame.
const EFF_FLAG: u32 = 0x8000_0000;
const RTR_FLAG: u32 = 0x4000_0000;
const ERR_FLAG: u32 = 0x2000_0000;
/// `flags` bit of a `canfd_frame` that is a CAN FD frame (set by recent kernels on receive).
const FDF_FLAG: u8 = 0x04;

/// `frame` as a `struct canfd_frame`, ready to write to a CAN FD socket.
pub fn encode_fd(frame: &Frame) -> [u8; FD_BYTES] {
    let mut bytes = [0_u8; FD_BYTES];
    let data = frame.data();
    bytes[..4].copy_from_slice(&u32::from(frame.id()).to_ne_bytes());
    // A protocol frame holds at most 64 bytes, so its length fits a byte.
    bytes[4] = u8::try_from(data.len()).unwrap_or(u8::MAX);
    bytes[5] = FDF_FLAG;
    bytes[DATA_AT..DATA_AT + data.len()].copy_from_slice(data);
    bytes
}

/// The frame in the first `len` bytes of `bytes` (what one read returned): a standard-id data
/// frame, classic or FD. `None` for anything this project's protocol cannot represent: an
/// error, remote or extended-id frame, or a record of neither struct's size.
pub fn decode(bytes: &[u8], len: usize) -> Option<Frame> {
    let capacity = match len {
        FD_BYTES => FD_BYTES - DATA_AT,
        CLASSIC_BYTES => CLASSIC_BYTES - DATA_AT,
        _ => return None,
    };
    let record = bytes.get(..len)?;
    let can_id = u32::from_ne_bytes(record.get(..4)?.try_into().ok()?);
    if can_id & (EFF_FLAG | RTR_FLAG | ERR_FLAG) != 0 {
        return None;
    }
    let payload = usize::from(*record.get(4)?).min(capacity);
    let id = u16::try_from(can_id).ok()?;
    Frame::new(id, record.get(DATA_AT..DATA_AT + payload)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_fd_frame_survives_the_round_trip() {
        let frame = Frame::new(0x123, &[7; 24]).unwrap();
        let bytes = encode_fd(&frame);
        assert_eq!(bytes[4], 24);
        assert_eq!(decode(&bytes, FD_BYTES), Some(frame));
    }

    #[test]
    fn a_classic_frame_from_cansend_is_read() {
        let mut bytes = [0_u8; CLASSIC_BYTES];
        bytes[..4].copy_from_slice(&0x7A_u32.to_ne_bytes());
        bytes[4] = 3;
        bytes[8..11].copy_from_slice(&[1, 2, 3]);
        assert_eq!(decode(&bytes, CLASSIC_BYTES), Frame::new(0x7A, &[1, 2, 3]));
    }

    #[test]
    fn foreign_records_are_refused() {
        let frame = Frame::new(0x123, &[1]).unwrap();
        for flag in [EFF_FLAG, RTR_FLAG, ERR_FLAG] {
            let mut bytes = encode_fd(&frame);
            let id = u32::from_ne_bytes(bytes[..4].try_into().unwrap()) | flag;
            bytes[..4].copy_from_slice(&id.to_ne_bytes());
            assert_eq!(decode(&bytes, FD_BYTES), None, "{flag:#x}");
        }
        let bytes = encode_fd(&frame);
        assert_eq!(decode(&bytes, 20), None);
        assert_eq!(decode(&bytes[..10], FD_BYTES), None);
        // A length byte beyond the struct's payload is cut to it, never read past.
        let mut classic = [0_u8; CLASSIC_BYTES];
        classic[4] = 200;
        assert_eq!(
            decode(&classic, CLASSIC_BYTES).map(|f| f.data().len()),
            Some(8)
        );
    }
}
