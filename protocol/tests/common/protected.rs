//! A message protected with its E2E header.

use protocol::e2e::{protect, Freshness, HEADER_LEN};
use protocol::{Check, Key};

/// A message with `payload` protected under `freshness`.
pub fn protected(check: Check, key: &Key, freshness: &Freshness, payload: &[u8]) -> Vec<u8> {
    let mut message = vec![0; HEADER_LEN];
    message.extend_from_slice(payload);
    protect(check, key, freshness, &mut message).unwrap();
    message
}
