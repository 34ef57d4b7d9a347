//! Worst-case frame lengths (with bit stuffing) and the bus load of the control schedule.
//!
//! CAN FD frame with an 11-bit id and bit-rate switch (ISO 11898-1:2015):
//!
//! | part                                             | bits              | rate    |
//! |--------------------------------------------------|-------------------|---------|
//! | SOF, id, RRS, IDE, FDF, res, BRS                  | 17 + 4 stuff      | nominal |
//! | ESI, DLC, data                                    | 5 + 8n + stuff    | data    |
//! | stuff count (4) and CRC (17 for n ≤ 16, else 21)  | + fixed stuff bits | data   |
//! | CRC delimiter                                     | 1                 | data    |
//! | ACK slot, ACK delimiter, EOF, intermission        | 1 + 1 + 7 + 3     | nominal |
//!
//! Dynamic stuffing, worst case, adds one bit per four from SOF to the end of the data:
//! ⌊(22 + 8n − 1)/4⌋, of which the 4 in the arbitration field go at the nominal rate. Fixed stuff
//! bits precede the stuff count and follow every fourth bit of stuff count and CRC:
//! ⌈(4 + CRC)/4⌉. Classic frames: 47 + 8n + ⌊(34 + 8n − 1)/4⌋ bits.

use crate::id::MessageId;
use crate::node::{Drive, Leg};

/// Bit rates of the bus.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BitRates {
    /// Arbitration (nominal) rate, bit/s.
    pub nominal_bps: u32,
    /// Data-phase rate, bit/s.
    pub data_bps: u32,
}

/// The robot's bus: 1 Mbit/s arbitration, 5 Mbit/s data (as moteus drives use).
pub const ROBOT_BUS: BitRates = BitRates {
    nominal_bps: 1_000_000,
    data_bps: 5_000_000,
};

/// Bits of one frame, by the rate they are sent at.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameBits {
    /// Bits at the nominal rate.
    pub nominal: u32,
    /// Bits at the data rate.
    pub data: u32,
}

impl FrameBits {
    /// Time on the bus, ns (rounded up).
    pub const fn duration_ns(self, rates: BitRates) -> u64 {
        div_ceil(
            self.nominal as u64 * 1_000_000_000,
            rates.nominal_bps as u64,
        ) + div_ceil(self.data as u64 * 1_000_000_000, rates.data_bps as u64)
    }
}

const fn div_ceil(a: u64, b: u64) -> u64 {
    if b == 0 {
        u64::MAX
    } else {
        a.div_ceil(b)
    }
}

/// Worst-case bits of a classic CAN data frame with an 11-bit id and `len` (0–8) data bytes,
/// including stuff bits and the 3-bit intermission. All at the nominal rate.
pub const fn classic_frame_bits(len: usize) -> u32 {
    let n = len as u32 * 8;
    47 + n + (34 + n - 1) / 4
}

/// Worst-case bits of a CAN FD frame (11-bit id, bit-rate switch) with `len` data bytes.
/// `len` is the frame's data length (a CAN FD length; pad first).
pub const fn fd_frame_bits(len: usize) -> FrameBits {
    let n = len as u32 * 8;
    let crc: u32 = if len <= 16 { 17 } else { 21 };
    let arbitration: u32 = 17;
    let dynamic_region = arbitration + 5 + n;
    let dynamic_stuff = (dynamic_region - 1) / 4;
    let arbitration_stuff = (arbitration - 1) / 4;
    let fixed_stuff = (4 + crc).div_ceil(4);
    FrameBits {
        nominal: arbitration + arbitration_stuff + 1 + 1 + 7 + 3,
        data: 5 + n + (dynamic_stuff - arbitration_stuff) + 4 + crc + fixed_stuff + 1,
    }
}

/// How often a message is sent.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Period {
    /// Once per control cycle.
    EveryCycle,
    /// At a fixed rate, Hz (at most once per cycle when the control rate is lower).
    Hz(u32),
    /// On an event, at most once per cycle (E-stop): counted in every worst-case cycle, not in
    /// the average.
    Sporadic,
}

/// One message of the control schedule.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Slot {
    /// The message.
    pub id: MessageId,
    /// How often.
    pub period: Period,
    /// Cycle offset within its period, so low-rate frames spread over cycles.
    pub phase: u32,
    /// Sent only in lockstep simulation (SYNC); a robot's bus does not carry it.
    pub lockstep_only: bool,
}

const fn slot(id: MessageId, period: Period, phase: u32) -> Slot {
    Slot {
        id,
        period,
        phase,
        lockstep_only: false,
    }
}

/// The frames of the control loop. The balance loop (wheels, IMU) runs every cycle; the leg
/// drives servo locally, so their targets and feedback run at 250 Hz, spread over cycles;
/// status and operator traffic run at 50 Hz and 10 Hz in the remaining cycles.
pub const SCHEDULE: [Slot; 21] = [
    slot(MessageId::EStop, Period::Sporadic, 0),
    Slot {
        id: MessageId::Sync,
        period: Period::EveryCycle,
        phase: 0,
        lockstep_only: true,
    },
    slot(MessageId::WheelCommand, Period::EveryCycle, 0),
    slot(MessageId::WheelFeedback, Period::EveryCycle, 0),
    slot(MessageId::Imu, Period::EveryCycle, 0),
    slot(MessageId::LegTargets, Period::Hz(250), 0),
    slot(MessageId::LegFeedback(Leg::Fl), Period::Hz(250), 1),
    slot(MessageId::LegFeedback(Leg::Fr), Period::Hz(250), 1),
    slot(MessageId::LegFeedback(Leg::Bl), Period::Hz(250), 2),
    slot(MessageId::LegFeedback(Leg::Br), Period::Hz(250), 2),
    slot(MessageId::Range, Period::Hz(50), 4),
    slot(MessageId::TeleopCommand, Period::Hz(50), 3),
    slot(MessageId::TeleopHeartbeat, Period::Hz(50), 7),
    slot(MessageId::ControllerStatus, Period::Hz(50), 11),
    slot(MessageId::RejectCounters, Period::Hz(10), 15),
    slot(MessageId::Announce, Period::Hz(50), 19),
    slot(MessageId::DriveStatus(Drive::LegFl), Period::Hz(10), 19),
    slot(MessageId::DriveStatus(Drive::LegFr), Period::Hz(10), 23),
    slot(MessageId::DriveStatus(Drive::LegBl), Period::Hz(10), 27),
    slot(MessageId::DriveStatus(Drive::LegBr), Period::Hz(10), 31),
    slot(MessageId::DriveStatus(Drive::Wheel), Period::Hz(10), 35),
];

/// `SLOT_OF[id.index()]`: the position of `id`'s slot in [`SCHEDULE`] (`u8::MAX`: none).
const SLOT_OF: [u8; MessageId::ALL.len()] = slot_of_table();

// Indexing in const evaluation: out of bounds is a build error, not a panic.
#[allow(clippy::indexing_slicing)]
const fn slot_of_table() -> [u8; MessageId::ALL.len()] {
    let mut table = [u8::MAX; MessageId::ALL.len()];
    let mut n = 0;
    while n < SCHEDULE.len() {
        table[SCHEDULE[n].id.index()] = n as u8;
        n += 1;
    }
    table
}

/// The schedule's slot for `id`, found without a search (the controller asks every tick).
pub fn slot_of(id: MessageId) -> Option<&'static Slot> {
    let at = *SLOT_OF.get(id.index())?;
    SCHEDULE.get(usize::from(at))
}

impl Slot {
    /// Cycles between two frames at `control_hz` (0 for sporadic).
    pub const fn period_cycles(&self, control_hz: u32) -> u32 {
        match self.period {
            Period::EveryCycle => 1,
            Period::Hz(hz) => {
                if hz == 0 || hz >= control_hz {
                    1
                } else {
                    control_hz / hz
                }
            }
            Period::Sporadic => 0,
        }
    }

    /// Worst-case time of one frame on the bus, ns.
    pub const fn frame_ns(&self, rates: BitRates) -> u64 {
        fd_frame_bits(self.id.layout().wire_len).duration_ns(rates)
    }

    /// Whether this slot sends in `cycle` at `control_hz` (sporadic slots: always, as the worst
    /// case).
    pub const fn sends_in(&self, cycle: u32, control_hz: u32) -> bool {
        let period = self.period_cycles(control_hz);
        period == 0 || cycle % period == self.phase % period
    }
}

/// Bus load of the schedule at one control rate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Load {
    /// Control rate, Hz.
    pub control_hz: u32,
    /// Whether SYNC (lockstep simulation) is counted.
    pub with_sync: bool,
    /// Average load over the schedule's hyperperiod, parts per million of bus time.
    pub average_ppm: u32,
    /// Load of the busiest cycle, including one sporadic E-stop, ppm of the cycle.
    pub worst_cycle_ppm: u32,
    /// Bus time of the busiest cycle, ns.
    pub worst_cycle_ns: u64,
}

const MAX_HYPERPERIOD: u32 = 10_000;

const fn gcd(mut a: u32, mut b: u32) -> u32 {
    while b != 0 {
        let t = a % b;
        a = b;
        b = t;
    }
    a
}

/// Load of [`SCHEDULE`] at `control_hz` on a bus with `rates`.
pub fn bus_load(control_hz: u32, rates: BitRates, with_sync: bool) -> Load {
    let control_hz = control_hz.max(1);
    let cycle_ns = 1_000_000_000 / u64::from(control_hz);
    let slots = || SCHEDULE.iter().filter(|s| with_sync || !s.lockstep_only);
    let hyperperiod = slots()
        .map(|s| s.period_cycles(control_hz))
        .filter(|&p| p > 0)
        .fold(1_u32, |acc, p| (acc / gcd(acc, p) * p).min(MAX_HYPERPERIOD));
    let mut total_ns = 0_u64;
    let mut worst_ns = 0_u64;
    for cycle in 0..hyperperiod {
        let sending = || slots().filter(|s| s.sends_in(cycle, control_hz));
        let cycle_ns_total: u64 = sending().map(|s| s.frame_ns(rates)).sum();
        total_ns += sending()
            .filter(|s| !matches!(s.period, Period::Sporadic))
            .map(|s| s.frame_ns(rates))
            .sum::<u64>();
        worst_ns = worst_ns.max(cycle_ns_total);
    }
    let span_ns = cycle_ns * u64::from(hyperperiod);
    Load {
        control_hz,
        with_sync,
        average_ppm: u32::try_from(total_ns * 1_000_000 / span_ns).unwrap_or(u32::MAX),
        worst_cycle_ppm: u32::try_from(worst_ns * 1_000_000 / cycle_ns).unwrap_or(u32::MAX),
        worst_cycle_ns: worst_ns,
    }
}
