//! Start-up, the control loop and the panic handler of the board.

use core::panic::PanicInfo;

use cortex_m_rt::entry;
use firmware::node::persist::Memory;
use firmware::node::service::{self, Drain};
use firmware::{Config, Node, Tick};
use stm32g4xx_hal::can::CanExt;
use stm32g4xx_hal::gpio::GpioExt;
use stm32g4xx_hal::pac;
use stm32g4xx_hal::pwr::{PwrExt, VoltageScale};
use stm32g4xx_hal::rcc::{
    self, FdCanClockSource, PllConfig, PllMDiv, PllNMul, PllQDiv, PllRDiv, PllSrc, RccExt,
};
use stm32g4xx_hal::time::RateExtU32;

use crate::flash::BoardFlash;
use crate::port::FdcanPort;
use crate::timer::ControlTimer;

/// The core's configuration: the robot at its default control rate (250 Hz; the timer and the
/// bus also carry 1 kHz, `Config::ROBOT.at_rate(TickRate::MCU_1_KHZ)`).
const CONFIG: Config = Config::ROBOT;

/// The bus key, from `ROBOT_KEY_HEX` (32 hexadecimal digits) at build time; the public test
/// key when it is unset. A value that is not a key fails the build (an image must never fall
/// back to the public key unnoticed). Not yet provisioned on the part itself: see
/// `docs/mcu.md`, "Keys and epochs".
const KEY: protocol::Key = match option_env!("ROBOT_KEY_HEX") {
    None => protocol::TEST_KEY,
    Some(hex) => match key_from_hex(hex.as_bytes()) {
        Some(key) => key,
        // Evaluated at compile time: this stops the build, it cannot happen on the board.
        #[allow(clippy::panic)]
        None => panic!("ROBOT_KEY_HEX must be exactly 32 hexadecimal digits"),
    },
};

fn key() -> protocol::Key {
    KEY
}

/// 32 hexadecimal digits as a key, at compile time.
// Indexing in const evaluation: out of bounds is a build error, not a panic.
#[allow(clippy::indexing_slicing)]
const fn key_from_hex(hex: &[u8]) -> Option<protocol::Key> {
    if hex.len() != 32 {
        return None;
    }
    let mut key = [0_u8; 16];
    let mut i = 0;
    while i < 16 {
        let (Some(high), Some(low)) = (hex_digit(hex[2 * i]), hex_digit(hex[2 * i + 1])) else {
            return None;
        };
        key[i] = high << 4_u32 | low;
        i += 1;
    }
    Some(protocol::Key(key))
}

const fn hex_digit(c: u8) -> Option<u8> {
    match c {
        b'0'..=b'9' => Some(c - b'0'),
        b'a'..=b'f' => Some(c - b'a' + 10),
        b'A'..=b'F' => Some(c - b'A' + 10),
        _ => None,
    }
}

/// Frames taken from the receive FIFO per pass of the loop (the FIFO holds 3).
const RX_PER_PASS: u32 = 8;

#[entry]
fn main() -> ! {
    let (Some(dp), Some(cp)) = (pac::Peripherals::take(), cortex_m::Peripherals::take()) else {
        halt()
    };
    // 24 MHz crystal (NUCLEO-G474RE) → PLL: /6 ×80 = 320 MHz; R /2 = 160 MHz core (boost
    // mode, above 150 MHz), Q /4 = 80 MHz FDCAN kernel clock.
    let pwr = dp
        .PWR
        .constrain()
        .vos(VoltageScale::Range1 { enable_boost: true })
        .freeze();
    let clocks = rcc::Config::pll()
        .pll_cfg(PllConfig {
            mux: PllSrc::HSE(24.MHz()),
            m: PllMDiv::DIV_6,
            n: PllNMul::MUL_80,
            r: Some(PllRDiv::DIV_2),
            q: Some(PllQDiv::DIV_4),
            p: None,
        })
        .boost(true)
        .fdcan_src(FdCanClockSource::PLLQ);
    let mut rcc = dp.RCC.constrain().freeze(clocks, pwr);
    let gpioa = dp.GPIOA.split(&mut rcc);
    let rx = gpioa.pa11.into_alternate::<9>();
    let tx = gpioa.pa12.into_alternate::<9>();
    let Some(mut port) = FdcanPort::start(dp.FDCAN1.fdcan(tx, rx, &mut rcc)) else {
        halt()
    };
    let Some(mut timer) = ControlTimer::start(cp.SYST, rcc.clocks.core_clk.raw(), CONFIG.rate)
    else {
        halt()
    };
    // The next epoch is written to flash before the session opens, and a latched E-stop comes
    // back latched (`firmware::node::persist`).
    let Some(flash) = BoardFlash::take(dp.FLASH) else {
        halt()
    };
    let Ok((mut memory, remembered)) = Memory::start(flash) else {
        halt()
    };
    let session = protocol::Session::owned(key(), remembered.epoch);
    let Ok(mut node) = Node::new(CONFIG, session) else {
        halt()
    };
    let mut now = Tick(0);
    if remembered.latched {
        node.restore_latch(now);
    }
    loop {
        // Frames that arrive before tick `now` runs belong to it. Rejections are counted by
        // the node and reported on the bus; the port cannot fail.
        let _ = service::receive(&mut node, now, &mut port, Drain::All, RX_PER_PASS);
        if timer.due() {
            let _ = service::transmit(&mut node, now, &mut port);
            now = now.plus(1);
            // A latch change is written at once (a program takes ~0.1 ms; a page erase runs in
            // bank 2 beside the loop). A flash that fails leaves the change unrecorded: the
            // E-stop still acts, and the next start reads what was recorded.
            let _ = memory.record_latch(node.estop_latched());
        }
    }
}

/// Stops here for good: the safe state of this controller is silence.
pub(crate) fn halt() -> ! {
    silence_fdcan();
    loop {
        cortex_m::asm::wfi();
    }
}

/// A panic (a bug: overflow checks are on in release too) halts the controller instead of
/// resetting it: the FDCAN is put into its init state, which cancels the queued frames and sends
/// nothing more, and every drive goes torque-free by its own 100 ms command timeout — the
/// designed safe state (legs limp, wheels unpowered). A reset would restart the core in its
/// start-up mode under a robot that may be balancing on its wheels, and a bug that panics once
/// would likely panic again; halted, the state stays for a debugger (`probe-rs attach`).
#[panic_handler]
fn panic(_info: &PanicInfo) -> ! {
    cortex_m::interrupt::disable();
    halt()
}

/// FDCAN1 into its init state and its pending transmissions cancelled.
fn silence_fdcan() {
    // SAFETY: runs only once the control loop has stopped for good (panic or failed start-up);
    // nothing else touches the FDCAN from then on.
    let fdcan = unsafe { &*pac::FDCAN1::ptr() };
    fdcan.cccr().modify(|_, w| w.init().set_bit());
    // SAFETY: any bit pattern is a valid cancellation request (one bit per TX buffer).
    fdcan.txbcr().write(|w| unsafe { w.bits(0b111) });
}
