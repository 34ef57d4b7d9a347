//! The run: calibrate the timer, step the node through the inputs, report.

use core::panic::PanicInfo;
use core::ptr::{addr_of, read_volatile};

use cortex_m::peripheral::syst::SystClkSource;
use cortex_m::peripheral::SYST;
use cortex_m_rt::{entry, exception, ExceptionFrame};
use cortex_m_semihosting::{debug, hio};
use firmware::node::service::{self, Drain};
use firmware::{Config, Node, Tick, TickRate};
use protocol::{Epoch, Session, TEST_KEY};

use crate::inputs::{Inputs, MAX_FRAMES};
use crate::line::Line;
use crate::recorded::Recorded;

/// The recorded inputs, prepared by `cargo xtask pil`.
static INPUTS: &[u8] = include_bytes!(env!("PIL_INPUTS"));

/// What an untouched stack word holds (cortex-m-rt paints the stack region at reset).
const PAINT: u32 = cortex_m_rt::STACK_PAINT_VALUE;

/// SysTick's full 24-bit period.
const SYST_MASK: u32 = 0x00FF_FFFF;

/// Iterations of the calibration loop (two instructions each).
const CAL_LOOPS: u32 = 100_000;

extern "C" {
    /// Lowest address of the stack region (end of `.bss`/`.uninit`), from cortex-m-rt.
    static _stack_end: u32;
    /// Top of the stack, from cortex-m-rt.
    static _stack_start: u32;
}

#[entry]
fn main() -> ! {
    let Some(mut cp) = cortex_m::Peripherals::take() else {
        fail("no core peripherals")
    };
    let Ok(mut out) = hio::hstdout() else {
        fail("no semihosting stdout")
    };
    let mut line = Line::new();
    // SysTick from the processor clock (25 MHz on the AN386), free-running over 2^24.
    cp.SYST.set_clock_source(SystClkSource::Core);
    cp.SYST.set_reload(SYST_MASK);
    cp.SYST.clear_current();
    cp.SYST.enable_counter();

    let start = SYST::get_current();
    calibration_loop(CAL_LOOPS);
    let cal = elapsed(start);
    line.str("PIL-CAL ")
        .dec(2 * CAL_LOOPS)
        .str(" ")
        .dec(cal)
        .send(&mut out);
    let start = SYST::get_current();
    let base = elapsed(start);
    line.str("PIL-BASE ").dec(base).send(&mut out);

    let Some(mut inputs) = Inputs::parse(INPUTS) else {
        fail("bad input file")
    };
    let Some(rate) = TickRate::new(inputs.control_hz) else {
        fail("bad control rate")
    };
    let session = Session::owned(TEST_KEY, Epoch::new(pil_format::PIL_EPOCH));
    let Ok(mut node) = Node::new(Config::ROBOT.at_rate(rate), session) else {
        fail("config rejected")
    };
    let mut port = Recorded::new();
    let mut done = 0_u32;
    for k in 0..inputs.ticks {
        if inputs.next_tick(port.inbox()).is_none() {
            fail("truncated input file");
        }
        let now = Tick(inputs.first_tick.wrapping_add(k));
        let start = SYST::get_current();
        // The same calls as the board's loop: every recorded frame of the tick, then the tick.
        let _ = service::receive(&mut node, now, &mut port, Drain::All, MAX_FRAMES as u32);
        let _ = service::transmit(&mut node, now, &mut port);
        let cost = elapsed(start);
        line.str("T ").dec(now.0).str(" ").dec(cost).send(&mut out);
        for f in port.sent() {
            line.str("F ")
                .hex(&f.id().to_be_bytes())
                .str(" ")
                .hex(f.data())
                .send(&mut out);
        }
        done += 1;
    }
    line.str("PIL-STACK ").dec(stack_peak()).send(&mut out);
    line.str("PIL-END ").dec(done).send(&mut out);
    debug::exit(debug::EXIT_SUCCESS);
    loop {
        cortex_m::asm::nop();
    }
}

/// SysTick ticks since `start` (it counts down, modulo 2^24).
fn elapsed(start: u32) -> u32 {
    start.wrapping_sub(SYST::get_current()) & SYST_MASK
}

/// Exactly `2 × n` instructions (plus the few around it).
#[inline(never)]
fn calibration_loop(n: u32) {
    // SAFETY: register-only loop.
    unsafe {
        core::arch::asm!(
            "2:",
            "subs {0}, {0}, #1",
            "bne 2b",
            inout(reg) n => _,
            options(nomem, nostack),
        );
    }
}

/// Bytes of stack used at the deepest: from the top down to the lowest word that is no longer
/// [`PAINT`].
fn stack_peak() -> u32 {
    let bottom = addr_of!(_stack_end) as usize;
    let top = addr_of!(_stack_start) as usize;
    let mut p = bottom;
    while p < top {
        // SAFETY: reading RAM inside the stack region.
        if unsafe { read_volatile(p as *const u32) } != PAINT {
            break;
        }
        p += 4;
    }
    u32::try_from(top - p).unwrap_or(u32::MAX)
}

fn fail(why: &str) -> ! {
    if let Ok(mut out) = hio::hstdout() {
        let mut line = Line::new();
        line.str("PIL-FAIL ").str(why).send(&mut out);
    }
    debug::exit(debug::EXIT_FAILURE);
    loop {
        cortex_m::asm::nop();
    }
}

#[panic_handler]
fn panic(_info: &PanicInfo) -> ! {
    fail("panic")
}

#[exception]
unsafe fn HardFault(_frame: &ExceptionFrame) -> ! {
    fail("hard fault")
}
