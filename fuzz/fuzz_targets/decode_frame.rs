//! Every frame decoder: any identifier and any bytes into `protocol::decode_frame` either
//! decode to a message that encodes back to a frame that decodes to the same message, or give
//! a typed error. Never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use protocol::decode_frame;

fuzz_target!(|input: &[u8]| {
    let Some((id_bytes, data)) = input.split_first_chunk::<2>() else {
        return;
    };
    let id = u16::from_le_bytes(*id_bytes) & 0x7FF;
    if let Ok(decoded) = decode_frame(id, data) {
        let again = decoded
            .message
            .encode(decoded.counter)
            .expect("a decoded message encodes");
        let back = decode_frame(again.id(), again.data()).expect("its encoding decodes");
        assert_eq!(back.message, decoded.message);
    }
});
