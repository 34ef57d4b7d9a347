//! The candidates of the E2E receiver's search for a frame's full counter.

/// The full counter a receiver at session time `reference` tries first for low half `low`: the
/// one within 2^15 of `reference`, and at exactly 2^15 on either side the one in the same period
/// of 2^16 as `reference`. Negative when the nearest would be below zero (no such counter).
pub fn nearest(reference: u32, low: u16) -> i64 {
    let lowest = i64::from(reference)
        - if reference & 0xFFFF < 0x8000 {
            0x7FFF
        } else {
            0x8000
        };
    lowest + (i64::from(low) - lowest).rem_euclid(0x1_0000)
}

/// Whether a receiver at session time `reference` finds `counter` among the `tries` candidates
/// of its search: the nearest, then periods of 2^16 below it.
pub fn among_candidates(reference: u32, tries: u32, counter: u32) -> bool {
    let first = nearest(reference, counter as u16);
    let counter = i64::from(counter);
    counter <= first && (first - counter) >> 16 < i64::from(tries)
}
