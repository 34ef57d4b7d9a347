//! The control-rate timer: SysTick on the core clock, one wrap per control tick. At 160 MHz its
//! 24-bit reload covers 10 Hz…10 kHz, so 250 Hz (the core's default) and 1 kHz both fit.

use cortex_m::peripheral::syst::SystClkSource;
use cortex_m::peripheral::SYST;
use firmware::TickRate;

/// SysTick counting control ticks.
pub struct ControlTimer {
    syst: SYST,
}

impl ControlTimer {
    /// Starts SysTick at `rate` from a core clock of `core_hz`; `None` if the period does not
    /// fit its 24-bit reload.
    pub fn start(mut syst: SYST, core_hz: u32, rate: TickRate) -> Option<Self> {
        let reload = (core_hz / rate.hz()).checked_sub(1)?;
        if reload == 0 || reload > 0x00FF_FFFF {
            return None;
        }
        syst.set_clock_source(SystClkSource::Core);
        syst.set_reload(reload);
        syst.clear_current();
        syst.enable_counter();
        Some(Self { syst })
    }

    /// Whether a tick is due (the counter wrapped since the last call). Polled: a loop that
    /// falls more than a period behind loses the ticks in between (the control core's
    /// durations are in ticks, so it then runs slow rather than bunching ticks up).
    pub fn due(&mut self) -> bool {
        self.syst.has_wrapped()
    }
}
