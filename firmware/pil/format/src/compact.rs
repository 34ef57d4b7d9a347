//! The compact format (magic `PILZ`) the repository keeps: the raw layout with each frame's
//! data XORed with the previous frame of its id and run-length coded (see the crate docs).
//! Reading and writing it is `Recording`'s (feature `alloc`): undoing the XOR needs
//! each id's previous frame, kept on the heap.

#[cfg(feature = "alloc")]
use crate::{cursor::Cursor, Error};

/// The compact format's magic.
pub const MAGIC: &[u8; 4] = b"PILZ";

/// A token below this is followed by `token + 1` literal bytes; from it on it stands for
/// `token − 0x7F` zero bytes.
#[cfg(feature = "alloc")]
const ZEROS: u8 = 0x80;

/// Longest run one token codes, literal or zero.
#[cfg(feature = "alloc")]
const MAX_RUN: usize = 128;

/// Decodes run-length tokens from `cursor` until `out` is exactly full.
#[cfg(feature = "alloc")]
pub(crate) fn decode_runs(cursor: &mut Cursor<'_>, out: &mut [u8]) -> Result<(), Error> {
    let mut filled = 0;
    while filled < out.len() {
        let token = cursor.u8()?;
        let (n, literal) = if token < ZEROS {
            (usize::from(token) + 1, true)
        } else {
            (usize::from(token - (ZEROS - 1)), false)
        };
        let end = filled + n;
        let slot = out.get_mut(filled..end).ok_or(Error::RunOverrun)?;
        if literal {
            slot.copy_from_slice(cursor.take(n)?);
        } else {
            slot.fill(0);
        }
        filled = end;
    }
    Ok(())
}

/// Appends the run-length code of `bytes`: zero runs of two or more (or a last lone zero) as
/// one token, everything else as literals up to the next pair of zeros.
#[cfg(feature = "alloc")]
pub(crate) fn encode_runs(bytes: &[u8], out: &mut alloc::vec::Vec<u8>) {
    let mut rest = bytes;
    while !rest.is_empty() {
        let zeros = rest.iter().take(MAX_RUN).take_while(|&&b| b == 0).count();
        let (n, token) = if zeros >= 2 || (zeros == 1 && rest.len() == 1) {
            // 1..=128 zeros: tokens 0x80..=0xFF.
            (zeros, (ZEROS - 1).wrapping_add(zeros as u8))
        } else {
            // At least one byte: `rest` does not start with two zeros.
            let literals = (0..rest.len().min(MAX_RUN))
                .take_while(|&i| !(rest.get(i) == Some(&0) && rest.get(i + 1) == Some(&0)))
                .count()
                .max(1);
            // 1..=128 literals: tokens 0x00..=0x7F.
            (literals, (literals - 1) as u8)
        };
        let (run, tail) = rest.split_at_checked(n).unwrap_or((rest, &[]));
        out.push(token);
        if token < ZEROS {
            out.extend_from_slice(run);
        }
        rest = tail;
    }
}
