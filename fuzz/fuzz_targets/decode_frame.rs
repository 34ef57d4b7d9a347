//! Every frame decoder: any identifier and any bytes into `protocol::decode_frame` either
//! decode to a message that encodes back to a frame that decodes to the same message, or give
//! a typed error. Never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use protocol::{decode_frame, Epoch, Session, TEST_KEY};

/// A session to encode in (the decoder checks no session; encoding a bound message needs one).
const SESSION: Session = Session::owned(TEST_KEY, Epoch::new(1));

fuzz_target!(|input: &[u8]| {
    let Some((id_bytes, data)) = input.split_first_chunk::<2>() else {
        return;
    };
    let id = u16::from_le_bytes(*id_bytes) & 0x7FF;
    if let Ok(decoded) = decode_frame(id, data) {
        let again = decoded
            .message
            .encode(&SESSION, u32::from(decoded.counter))
            .expect("a decoded message encodes");
        let back = decode_frame(again.id(), again.data()).expect("its encoding decodes");
        assert_eq!(back.message, decoded.message);
    }
});
