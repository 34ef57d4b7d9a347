//! Shared by the stateful targets: a record may ask for its bytes to be sealed, so that the
//! fuzzer reaches past the check value (a CRC-32C it could learn, a CMAC it never would) into
//! the sequence checks, the session logic, the decoders and the controller.

use protocol::e2e::{protect, Freshness, HEADER_LEN};
use protocol::{protection_of, Epoch, MessageId, Session, TEST_KEY};

/// The session the controller under test owns, in which sealed records are bound.
pub const SESSION: Session = Session::owned(TEST_KEY, Epoch::new(1));

/// Bit of a record's identifier high byte (above the 11-bit identifier) that asks for sealing.
pub const SEAL: u8 = 0x80;

/// Per identifier, the next full counter of sealed records.
pub type Counters = [u32; MessageId::ALL.len()];

/// `bytes` as the payload of a frame on `raw_id`, at its wire length, with a valid check value
/// for the identifier's protection at its next counter (the low half only for a frame outside
/// the sequence), bound to [`SESSION`] where the protection is; `None` for an unknown id.
pub fn seal(raw_id: u16, bytes: &[u8], counters: &mut Counters) -> Option<Vec<u8>> {
    let id = MessageId::from_raw(raw_id)?;
    let layout = id.layout();
    let mut data = vec![0_u8; layout.wire_len];
    for (slot, byte) in data.iter_mut().skip(HEADER_LEN).zip(bytes) {
        *slot = *byte;
    }
    let (protection, covered) = protection_of(id, &data);
    let counter = counters.get_mut(id.index())?;
    let freshness = Freshness {
        data_id: id.data_id(),
        epoch: if protection.bound {
            SESSION.epoch()
        } else {
            None
        },
        counter: if protection.sequenced {
            *counter
        } else {
            *counter & 0xFFFF
        },
    };
    *counter = counter.wrapping_add(1);
    protect(
        protection.check,
        SESSION.key(),
        &freshness,
        data.get_mut(..HEADER_LEN + covered)?,
    )?;
    Some(data)
}
