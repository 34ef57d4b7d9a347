//! Frame-length maths against known figures, and the schedule's load.

use protocol::busload::*;
use protocol::dlc::{fd_padded_len, FD_LENGTHS};

#[test]
fn classic_worst_case_lengths_match_the_literature() {
    // Davis, Burns, Bril, Lukkien (2007): 11-bit id, 8 bytes → 135 bits worst case; 0 bytes → 55.
    assert_eq!(classic_frame_bits(8), 135);
    assert_eq!(classic_frame_bits(0), 55);
}

#[test]
fn fd_frame_lengths_grow_with_payload_and_switch_crc_above_16_bytes() {
    let mut previous = 0;
    for len in FD_LENGTHS {
        let bits = fd_frame_bits(len);
        assert_eq!(
            bits.nominal, 33,
            "arbitration + ack + eof + ifs + 4 stuff bits"
        );
        assert!(bits.data > previous, "{len} bytes");
        previous = bits.data;
    }
    // 16 → 20 bytes adds 32 data bits, 8 dynamic stuff bits, 4 CRC bits and one fixed stuff bit.
    assert_eq!(
        fd_frame_bits(20).data - fd_frame_bits(16).data,
        32 + 8 + 4 + 1
    );
    // 8 bytes at 1M/5M: 33 µs nominal + 114 bits at 200 ns.
    assert_eq!(fd_frame_bits(8).duration_ns(ROBOT_BUS), 33_000 + 114 * 200);
}

#[test]
fn fd_is_cheaper_than_classic_for_the_same_data() {
    // 64 bytes in one FD frame versus eight classic 8-byte frames at 1 Mbit/s.
    let fd = fd_frame_bits(64).duration_ns(ROBOT_BUS);
    let classic = 8 * u64::from(classic_frame_bits(8)) * 1000;
    assert!(fd * 5 < classic, "fd {fd} ns, classic {classic} ns");
}

#[test]
fn padding_rounds_up_to_the_next_fd_length() {
    assert_eq!(fd_padded_len(9), Some(12));
    assert_eq!(fd_padded_len(36), Some(48));
    assert_eq!(fd_padded_len(64), Some(64));
    assert_eq!(fd_padded_len(65), None);
}

#[test]
fn one_khz_control_fits_half_the_robots_bus() {
    let load = bus_load(1000, ROBOT_BUS, false);
    assert!(load.average_ppm <= 500_000, "{load:?}");
    assert!(load.worst_cycle_ppm <= 500_000, "{load:?}");
    // Lockstep adds SYNC every cycle; its average still fits.
    assert!(bus_load(1000, ROBOT_BUS, true).average_ppm <= 500_000);
}

#[test]
fn load_scales_with_the_control_rate() {
    let slow = bus_load(250, ROBOT_BUS, false);
    let fast = bus_load(1000, ROBOT_BUS, false);
    assert!(fast.average_ppm > slow.average_ppm);
    // Every-cycle traffic is 4× at 1 kHz; 250 Hz leg traffic is not, so the ratio is below 4.
    assert!(fast.average_ppm < 4 * slow.average_ppm);
}

#[test]
fn a_slower_bus_overloads() {
    let classic_speed = BitRates {
        nominal_bps: 500_000,
        data_bps: 500_000,
    };
    assert!(bus_load(1000, classic_speed, false).average_ppm > 1_000_000);
}
