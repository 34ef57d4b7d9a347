//! The receive path with its state: a sequence of frames (identifier, length, bytes) into one
//! `protocol::Receiver`, whose E2E windows and counters must survive anything.
#![no_main]

use libfuzzer_sys::fuzz_target;
use protocol::Receiver;

fuzz_target!(|input: &[u8]| {
    let mut receiver = Receiver::default();
    let mut rest = input;
    while let [id_low, id_high, len, tail @ ..] = rest {
        let id = u16::from_le_bytes([*id_low, *id_high]) & 0x7FF;
        let len = usize::from(*len).min(64).min(tail.len());
        let (data, next) = tail.split_at(len);
        let _ = receiver.receive(id, data);
        rest = next;
    }
});
