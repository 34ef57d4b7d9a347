//! The receive path with its state: a sequence of frames (identifier, length, bytes) into one
//! `protocol::Receiver` — the controller's (owner of the session) or another node's (member,
//! joining on announcements) — whose sequence checks, session and counters must survive
//! anything. A record whose identifier has the seal bit set is sealed in the session first.
#![no_main]

use libfuzzer_sys::fuzz_target;
use protocol::{Receiver, TEST_KEY};

#[path = "seal.rs"]
mod seal;

fuzz_target!(|input: &[u8]| {
    let Some((role, mut rest)) = input.split_first() else {
        return;
    };
    let mut receiver = if role % 2 == 0 {
        Receiver::owner(seal::SESSION)
    } else {
        Receiver::member(TEST_KEY)
    };
    let mut counters = [0; protocol::MessageId::ALL.len()];
    while let [id_low, id_high, len, tail @ ..] = rest {
        let id = u16::from_le_bytes([*id_low, *id_high]) & 0x7FF;
        let len = usize::from(*len).min(64).min(tail.len());
        let (data, next) = tail.split_at(len);
        let sealed = (id_high & seal::SEAL != 0)
            .then(|| seal::seal(id, data, &mut counters))
            .flatten();
        let _ = receiver.receive(id, sealed.as_deref().unwrap_or(data));
        rest = next;
    }
});
