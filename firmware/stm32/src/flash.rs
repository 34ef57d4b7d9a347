//! The controller's memory pages (`firmware::node::persist`) in the STM32G474's flash: the last
//! two 2 KiB pages of bank 2 (`0x0807_F000` and `0x0807_F800`, outside the image's region in
//! `memory.x`), programmed and erased through the FLASH registers.
//!
//! Why bank 2: the image runs from bank 1, and the G4 reads one bank while it writes the other,
//! so a page erase (up to ~40 ms) does not stall the control loop. That needs the dual-bank
//! layout (option bit `DBANK`, set by the factory); with a single bank [`BoardFlash::take`]
//! refuses and the board does not start.
//!
//! A double word whose programming a reset tore may fail its ECC: reading it raises an NMI with
//! `ECCD` set. [`NonMaskableInt`] clears it and marks the read, which then returns all zeros, a
//! slot the log reads as torn.

use core::sync::atomic::{AtomicBool, Ordering};

use cortex_m_rt::exception;
use firmware::node::persist::{Nor, Page, RECORD_BYTES};
use stm32g4xx_hal::pac;

/// Address of page A; page B follows it.
const PAGE_A: u32 = 0x0807_F000;
/// Bytes per page in the dual-bank layout.
const PAGE_BYTES: u32 = 2048;
/// Page numbers of A and B within bank 2.
const PAGE_NUMBERS: (u8, u8) = (126, 127);
/// The FLASH unlock sequence (RM0440, 3.3.5).
const KEYS: [u32; 2] = [0x4567_0123, 0xCDEF_89AB];
/// Most polls of `BSY` before an operation counts as failed: far beyond the ~40 ms of the
/// slowest page erase at 160 MHz.
const MAX_POLLS: u32 = 20_000_000;
/// The error bits of `FLASH_SR` (OPERR, PROGERR, WRPERR, PGAERR, SIZERR, PGSERR, MISERR,
/// FASTERR), cleared by writing them back.
const SR_ERRORS: u32 = 0x0000_C3FA;

/// Set by the NMI when a flash read failed its ECC.
static ECC_FAILED: AtomicBool = AtomicBool::new(false);

/// Why a flash operation failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FlashError {
    /// The FLASH control register stayed locked after the key sequence.
    Locked,
    /// The operation did not end within [`MAX_POLLS`].
    Timeout,
    /// `FLASH_SR` reported these error bits.
    Status(u32),
}

/// The two memory pages, owning the FLASH peripheral.
pub struct BoardFlash {
    flash: pac::FLASH,
}

impl BoardFlash {
    /// The pages, if the flash is in its dual-bank layout.
    pub fn take(flash: pac::FLASH) -> Option<Self> {
        flash
            .optr()
            .read()
            .dbank()
            .bit_is_set()
            .then_some(Self { flash })
    }

    fn address(page: Page, slot: u16) -> u32 {
        let base = match page {
            Page::A => PAGE_A,
            Page::B => PAGE_A + PAGE_BYTES,
        };
        base + u32::from(slot) * RECORD_BYTES as u32
    }

    fn wait(&self) -> Result<(), FlashError> {
        for _ in 0..MAX_POLLS {
            if self.flash.sr().read().bsy().bit_is_clear() {
                let errors = self.flash.sr().read().bits() & SR_ERRORS;
                // SAFETY: writing ones clears only those status bits.
                self.flash.sr().write(|w| unsafe { w.bits(errors) });
                return if errors == 0 {
                    Ok(())
                } else {
                    Err(FlashError::Status(errors))
                };
            }
        }
        Err(FlashError::Timeout)
    }

    /// Unlocks the control register, runs `operation`, and locks it again whatever happened.
    fn unlocked(
        &mut self,
        operation: impl FnOnce(&Self) -> Result<(), FlashError>,
    ) -> Result<(), FlashError> {
        self.wait()?;
        for key in KEYS {
            // SAFETY: the documented key sequence; a wrong key locks the register until reset.
            self.flash.keyr().write(|w| unsafe { w.keyr().bits(key) });
        }
        if self.flash.cr().read().lock().bit_is_set() {
            return Err(FlashError::Locked);
        }
        let result = operation(self);
        self.flash
            .cr()
            .modify(|_, w| w.pg().clear_bit().per().clear_bit().lock().set_bit());
        result
    }
}

impl Nor for BoardFlash {
    type Error = FlashError;

    fn slots(&self) -> u16 {
        (PAGE_BYTES / RECORD_BYTES as u32) as u16
    }

    fn read(&self, page: Page, slot: u16) -> Result<[u8; RECORD_BYTES], FlashError> {
        let address = Self::address(page, slot);
        ECC_FAILED.store(false, Ordering::SeqCst);
        // SAFETY: the address lies in the memory pages (slot < slots), aligned to 8 bytes; flash
        // reads have no side effect but the ECC check handled by the NMI.
        let (low, high) = unsafe {
            (
                core::ptr::read_volatile(address as *const u32),
                core::ptr::read_volatile((address + 4) as *const u32),
            )
        };
        if ECC_FAILED.swap(false, Ordering::SeqCst) {
            return Ok([0; RECORD_BYTES]);
        }
        let [a0, a1, a2, a3] = low.to_le_bytes();
        let [b0, b1, b2, b3] = high.to_le_bytes();
        Ok([a0, a1, a2, a3, b0, b1, b2, b3])
    }

    fn program(
        &mut self,
        page: Page,
        slot: u16,
        bytes: [u8; RECORD_BYTES],
    ) -> Result<(), FlashError> {
        let address = Self::address(page, slot);
        let [a0, a1, a2, a3, b0, b1, b2, b3] = bytes;
        let (low, high) = (
            u32::from_le_bytes([a0, a1, a2, a3]),
            u32::from_le_bytes([b0, b1, b2, b3]),
        );
        self.unlocked(|this| {
            this.flash.cr().modify(|_, w| w.pg().set_bit());
            // SAFETY: an erased, aligned double word of the memory pages, written as the two
            // words the programming sequence wants (RM0440, 3.3.7).
            unsafe {
                core::ptr::write_volatile(address as *mut u32, low);
                core::ptr::write_volatile((address + 4) as *mut u32, high);
            }
            this.wait()
        })
    }

    fn erase(&mut self, page: Page) -> Result<(), FlashError> {
        let number = match page {
            Page::A => PAGE_NUMBERS.0,
            Page::B => PAGE_NUMBERS.1,
        };
        self.unlocked(|this| {
            // SAFETY: a page number of bank 2 (7 bits).
            this.flash
                .cr()
                .modify(|_, w| unsafe { w.per().set_bit().bker().bank2().pnb().bits(number) });
            this.flash.cr().modify(|_, w| w.strt().set_bit());
            this.wait()
        })
    }
}

/// The NMI: a flash ECC double error (a torn double word of the memory pages) is cleared and
/// marked for [`BoardFlash::read`]; any other cause (a clock failure) halts the controller.
#[exception]
unsafe fn NonMaskableInt() {
    // SAFETY: ECCR is read and its ECCD flag cleared (write 1) here only.
    let flash = unsafe { &*pac::FLASH::ptr() };
    if flash.eccr().read().eccd().bit_is_set() {
        flash.eccr().modify(|_, w| w.eccd().set_bit());
        ECC_FAILED.store(true, Ordering::SeqCst);
    } else {
        crate::board::halt();
    }
}
