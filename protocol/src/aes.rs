//! AES-128 encryption (FIPS 197), table-driven, for the CMAC of [`crate::cmac`].
//!
//! Why not the RustCrypto `aes` crate: its portable backend is fixsliced (constant time without
//! tables), which on the Cortex-M4F makes the control step several thousand instructions
//! dearer per CMAC: with it, `cargo xtask pil` measured a maximum of 42,520 instructions per
//! step against a budget of 20,000; with this one (rounds from one 1 KiB table and its byte
//! rotations), in otherwise the same code, 21,680. Only encryption is needed: CMAC never
//! decrypts.
//!
//! Timing: the lookups depend on key and data. On the MCU the tables must sit in SRAM without a
//! cache in front (not in flash behind the ART accelerator's cache) for the time to be
//! independent of them; on a host the simulation's key is public anyway. The tests check every
//! block against the RustCrypto implementation and the FIPS 197 example.

/// The S-box, computed from its definition (inverse in GF(2^8), then the affine map).
const SBOX: [u8; 256] = sbox_table();

/// `TE[x]`: the MixColumns column of S-box output `s = S[x]`, bytes (2s, s, s, 3s) from the
/// most significant. The other three positions of a column are this word rotated.
const TE: [u32; 256] = te_table();

/// The round constants of the key schedule, in the most significant byte.
const RCON: [u32; 10] = [
    0x0100_0000,
    0x0200_0000,
    0x0400_0000,
    0x0800_0000,
    0x1000_0000,
    0x2000_0000,
    0x4000_0000,
    0x8000_0000,
    0x1B00_0000,
    0x3600_0000,
];

const fn xtime(b: u8) -> u8 {
    (b << 1) ^ if b & 0x80 != 0 { 0x1B } else { 0 }
}

// Indexing in const evaluation: out of bounds is a build error, not a panic.
#[allow(clippy::indexing_slicing)]
const fn sbox_table() -> [u8; 256] {
    let mut table = [0_u8; 256];
    // p runs over the multiplicative group by powers of 3, q over the inverses (powers of 3⁻¹).
    let mut p: u8 = 1;
    let mut q: u8 = 1;
    loop {
        p ^= xtime(p);
        q ^= q << 1_u32;
        q ^= q << 2_u32;
        q ^= q << 4_u32;
        if q & 0x80 != 0 {
            q ^= 0x09;
        }
        let affine = q ^ q.rotate_left(1) ^ q.rotate_left(2) ^ q.rotate_left(3) ^ q.rotate_left(4);
        table[p as usize] = affine ^ 0x63;
        if p == 1 {
            break;
        }
    }
    table[0] = 0x63;
    table
}

#[allow(clippy::indexing_slicing)]
const fn te_table() -> [u32; 256] {
    let mut table = [0_u32; 256];
    let mut x = 0;
    while x < 256 {
        let s = SBOX[x];
        let s2 = xtime(s);
        let s3 = s2 ^ s;
        table[x] = (s2 as u32) << 24_u32 | (s as u32) << 16_u32 | (s as u32) << 8_u32 | s3 as u32;
        x += 1;
    }
    table
}

fn te(byte: u32) -> u32 {
    TE.get((byte & 0xFF) as usize).copied().unwrap_or(0)
}

fn sub(byte: u32) -> u32 {
    u32::from(SBOX.get((byte & 0xFF) as usize).copied().unwrap_or(0))
}

fn sub_word(w: u32) -> u32 {
    sub(w >> 24) << 24 | sub(w >> 16) << 16 | sub(w >> 8) << 8 | sub(w)
}

/// An AES-128 key, expanded: 44 round-key words.
#[derive(Clone, PartialEq, Eq)]
pub struct Aes128 {
    round_keys: [u32; 44],
}

impl core::fmt::Debug for Aes128 {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("Aes128(…)")
    }
}

impl Aes128 {
    /// Expands `key`.
    pub fn new(key: &[u8; 16]) -> Self {
        let mut w = [0_u32; 44];
        for (word, chunk) in w.iter_mut().zip(key.chunks_exact(4)) {
            let mut bytes = [0_u8; 4];
            bytes.copy_from_slice(chunk);
            *word = u32::from_be_bytes(bytes);
        }
        for i in 4..44 {
            let previous = w.get(i - 1).copied().unwrap_or(0);
            let back = w.get(i - 4).copied().unwrap_or(0);
            let mixed = if i % 4 == 0 {
                sub_word(previous.rotate_left(8)) ^ RCON.get(i / 4 - 1).copied().unwrap_or(0)
            } else {
                previous
            };
            if let Some(word) = w.get_mut(i) {
                *word = back ^ mixed;
            }
        }
        Self { round_keys: w }
    }

    /// Encrypts one block.
    pub fn encrypt(&self, block: &[u8; 16]) -> [u8; 16] {
        let mut keys = self.round_keys.chunks_exact(4).map(|k| {
            let mut round = [0_u32; 4];
            round.copy_from_slice(k);
            round
        });
        let first = keys.next().unwrap_or_default();
        let mut s = [0_u32; 4];
        for ((word, chunk), k) in s.iter_mut().zip(block.chunks_exact(4)).zip(first) {
            let mut bytes = [0_u8; 4];
            bytes.copy_from_slice(chunk);
            *word = u32::from_be_bytes(bytes) ^ k;
        }
        let column = |a: u32, b: u32, c: u32, d: u32| {
            te(a >> 24)
                ^ te(b >> 16).rotate_right(8)
                ^ te(c >> 8).rotate_right(16)
                ^ te(d).rotate_right(24)
        };
        for [k0, k1, k2, k3] in keys.by_ref().take(9) {
            let [s0, s1, s2, s3] = s;
            s = [
                column(s0, s1, s2, s3) ^ k0,
                column(s1, s2, s3, s0) ^ k1,
                column(s2, s3, s0, s1) ^ k2,
                column(s3, s0, s1, s2) ^ k3,
            ];
        }
        let [k0, k1, k2, k3] = keys.next().unwrap_or_default();
        let [s0, s1, s2, s3] = s;
        let last = |a: u32, b: u32, c: u32, d: u32| {
            sub(a >> 24_u32) << 24_u32
                | sub(b >> 16_u32) << 16_u32
                | sub(c >> 8_u32) << 8_u32
                | sub(d)
        };
        let out = [
            last(s0, s1, s2, s3) ^ k0,
            last(s1, s2, s3, s0) ^ k1,
            last(s2, s3, s0, s1) ^ k2,
            last(s3, s0, s1, s2) ^ k3,
        ];
        let mut bytes = [0_u8; 16];
        for (chunk, word) in bytes.chunks_exact_mut(4).zip(out) {
            chunk.copy_from_slice(&word.to_be_bytes());
        }
        bytes
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fips_197_example_encrypts() {
        // FIPS 197, appendix C.1.
        let key: [u8; 16] = core::array::from_fn(|i| i as u8);
        let plain: [u8; 16] = core::array::from_fn(|i| (i as u8) * 0x11);
        let expected = [
            0x69, 0xc4, 0xe0, 0xd8, 0x6a, 0x7b, 0x04, 0x30, 0xd8, 0xcd, 0xb7, 0x80, 0x70, 0xb4,
            0xc5, 0x5a,
        ];
        assert_eq!(Aes128::new(&key).encrypt(&plain), expected);
    }

    #[test]
    fn the_s_box_is_a_permutation_with_the_known_corners() {
        assert_eq!((SBOX[0x00], SBOX[0x01], SBOX[0x53]), (0x63, 0x7c, 0xed));
        let mut seen = [false; 256];
        for s in SBOX {
            seen[usize::from(s)] = true;
        }
        assert!(seen.iter().all(|&s| s));
    }
}
