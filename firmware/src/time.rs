//! Integer time. The core never reads a clock: every call is handed the current [`Tick`], and
//! every duration is a whole number of ticks, so behaviour does not drift with uptime.

/// A point in time, counted in control ticks since the controller started. Wraps after
/// 2^32 ticks (about 199 days at 250 Hz, 50 days at 1 kHz); all comparisons use wrapping
/// differences, so the wrap is harmless for durations shorter than half that span.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Tick(pub u32);

impl Tick {
    /// Ticks elapsed from `earlier` to `self`, modulo 2^32.
    pub const fn since(self, earlier: Tick) -> u32 {
        self.0.wrapping_sub(earlier.0)
    }

    /// The tick `ticks` after `self`, modulo 2^32.
    pub const fn plus(self, ticks: u32) -> Tick {
        Tick(self.0.wrapping_add(ticks))
    }
}

/// The control rate, in ticks per second. Valid range 1…10 000 Hz; [`TickRate::new`] rejects
/// anything else so that every derived duration and gain is finite and non-zero.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TickRate {
    hz: u32,
}

impl TickRate {
    /// 250 Hz: one control tick per simulator step of the report's 0.004 s timestep.
    pub const SIM_250_HZ: Self = Self { hz: 250 };
    /// 1 kHz: the MCU's control rate.
    pub const MCU_1_KHZ: Self = Self { hz: 1000 };
    /// Highest supported rate.
    pub const MAX_HZ: u32 = 10_000;

    /// `None` unless `1 ≤ hz ≤ 10 000`.
    pub const fn new(hz: u32) -> Option<Self> {
        if hz >= 1 && hz <= Self::MAX_HZ {
            Some(Self { hz })
        } else {
            None
        }
    }

    /// Ticks per second.
    pub const fn hz(self) -> u32 {
        self.hz
    }

    /// The tick period in seconds.
    pub fn period_s(self) -> f32 {
        1.0 / self.hz as f32
    }

    /// Milliseconds in `ticks` ticks (rounded down, saturating at `u32::MAX`).
    pub const fn ms_from_ticks(self, ticks: u32) -> u32 {
        // The usual rates divide 1000: a multiplication, not a 64-bit division, every tick.
        if 1000 % self.hz == 0 {
            return ticks.saturating_mul(1000 / self.hz);
        }
        let ms = ticks as u64 * 1000 / self.hz as u64;
        if ms > u32::MAX as u64 {
            u32::MAX
        } else {
            ms as u32
        }
    }

    /// The number of whole ticks that covers at least `ms` milliseconds (rounded up, so a
    /// watchdog never fires early).
    pub const fn ticks_from_ms(self, ms: u32) -> u32 {
        let product = ms as u64 * self.hz as u64;
        let ticks = product.div_ceil(1000);
        if ticks > u32::MAX as u64 {
            u32::MAX
        } else {
            ticks as u32
        }
    }
}
