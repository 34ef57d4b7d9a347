//! CAN FD data lengths.
//!
//! A CAN FD frame carries 0–8, 12, 16, 20, 24, 32, 48 or 64 bytes; a payload of another size is
//! padded up to the next of these. Classic CAN carries 0–8.

/// Largest CAN FD payload, bytes.
pub const MAX_FD_LEN: usize = 64;

/// The data lengths a CAN FD frame can have, ascending.
pub const FD_LENGTHS: [usize; 16] = [0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64];

/// The smallest CAN FD data length that holds `len` bytes, or `None` above 64.
pub const fn fd_padded_len(len: usize) -> Option<usize> {
    let mut rest: &[usize] = &FD_LENGTHS;
    while let [first, tail @ ..] = rest {
        if *first >= len {
            return Some(*first);
        }
        rest = tail;
    }
    None
}

/// Whether `len` is a length a CAN FD frame can have.
pub const fn is_fd_len(len: usize) -> bool {
    matches!(fd_padded_len(len), Some(padded) if padded == len)
}

/// The 4-bit DLC code of a CAN FD data length, or `None` if `len` is not one.
pub const fn fd_dlc_code(len: usize) -> Option<u8> {
    let mut rest: &[usize] = &FD_LENGTHS;
    let mut code = 0;
    while let [first, tail @ ..] = rest {
        if *first == len {
            return Some(code);
        }
        code += 1;
        rest = tail;
    }
    None
}
