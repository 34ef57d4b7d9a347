//! What the controller remembers across restarts on a board without a file system: the last
//! session epoch it opened and whether its E-stop is latched, kept in two pages of NOR flash.
//!
//! # Why
//!
//! A frame's freshness is its epoch and counter: a controller that opened the same epoch twice
//! would take a recording of its earlier run as fresh. And a latched E-stop must survive a reset
//! (IEC 60204-1: no unexpected start-up). So a start reads the last epoch, opens the next one,
//! and **writes it before** the session opens: a reset at any moment after that can never reuse
//! it. A latch change is written when the node reports it.
//!
//! # On flash
//!
//! NOR flash erases a whole page to `0xFF` and programs each 8-byte slot once. The memory is an
//! append-only log of 8-byte records — epoch (`u32`, little-endian), latched (`0`/`1`), page
//! generation, CRC-16 of those six bytes — over two pages. The newest record of the page with
//! the newer generation is the state. When a page is full (or at a start, half full), the other
//! page is erased and the state is written there first with the next generation: a reset during
//! the erase or the write leaves the full page as it was, and a torn record fails its CRC and is
//! skipped (its slot is never programmed again). The erase happens at a start, then at most once
//! per half page of latch changes.
//!
//! The [`Nor`] trait is the board's flash: `firmware-stm32` implements it on two pages of the
//! STM32G474's second bank; the tests here on a model that tears writes and erases.

use crc::{Crc, NoTable, CRC_16_IBM_3740};
use protocol::Epoch;

/// Bytes of one record: the flash's programming unit (a double word on the STM32G4).
pub const RECORD_BYTES: usize = 8;

/// The check over a record's first six bytes (CRC-16/CCITT-FALSE, "IBM-3740"), bit by bit: six
/// bytes per record need no table in flash.
const CHECK: Crc<u16, NoTable> = Crc::<u16, NoTable>::new(&CRC_16_IBM_3740);

/// One of the two pages of the log.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Page {
    /// The first.
    A,
    /// The second.
    B,
}

impl Page {
    fn other(self) -> Page {
        match self {
            Page::A => Page::B,
            Page::B => Page::A,
        }
    }
}

/// NOR flash as the log uses it: two pages of [`Nor::slots`] records each, erased to `0xFF`, a
/// slot programmed at most once between erases. A slot that cannot be read (an ECC error after
/// a torn write) reads as zeros.
pub trait Nor {
    /// What the flash reports when an operation fails.
    type Error;
    /// Records per page.
    fn slots(&self) -> u16;
    /// Reads the record in `slot` of `page`.
    fn read(&self, page: Page, slot: u16) -> Result<[u8; RECORD_BYTES], Self::Error>;
    /// Programs `bytes` into `slot` of `page`, which must be erased.
    fn program(
        &mut self,
        page: Page,
        slot: u16,
        bytes: [u8; RECORD_BYTES],
    ) -> Result<(), Self::Error>;
    /// Erases `page`.
    fn erase(&mut self, page: Page) -> Result<(), Self::Error>;
}

/// What the controller remembers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Remembered {
    /// The session epoch of this start (the last one opened plus one).
    pub epoch: Epoch,
    /// Whether the E-stop was latched when the last run ended: the node starts latched.
    pub latched: bool,
}

/// Why the memory cannot be kept.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PersistError<E> {
    /// The flash failed (the board's error).
    Flash(E),
    /// Every epoch up to `u32::MAX` was opened: the controller cannot open a fresh session
    /// (erasing the pages with a new bus key restarts the count).
    EpochsExhausted,
    /// The board's pages hold fewer than two records each.
    PageTooSmall,
}

/// A decoded record.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Record {
    epoch: u32,
    latched: bool,
    generation: u8,
}

/// What a slot holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Slot {
    Erased,
    /// Programmed but not a record: a write torn by a reset.
    Torn,
    Valid(Record),
}

impl Record {
    fn encode(self) -> [u8; RECORD_BYTES] {
        let [e0, e1, e2, e3] = self.epoch.to_le_bytes();
        let head = [e0, e1, e2, e3, u8::from(self.latched), self.generation];
        let [c0, c1] = CHECK.checksum(&head).to_le_bytes();
        [e0, e1, e2, e3, head[4], head[5], c0, c1]
    }

    fn decode(bytes: [u8; RECORD_BYTES]) -> Slot {
        if bytes == [0xFF; RECORD_BYTES] {
            return Slot::Erased;
        }
        let [e0, e1, e2, e3, latched, generation, c0, c1] = bytes;
        let head = [e0, e1, e2, e3, latched, generation];
        // Epochs start at 1: a slot of zeros (what a board reads from a double word that fails
        // its ECC) is torn too.
        let epoch = u32::from_le_bytes([e0, e1, e2, e3]);
        if CHECK.checksum(&head) != u16::from_le_bytes([c0, c1]) || latched > 1 || epoch == 0 {
            return Slot::Torn;
        }
        Slot::Valid(Record {
            epoch,
            latched: latched == 1,
            generation,
        })
    }
}

/// A page as read: its newest record and the first slot after its last programmed one.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct PageScan {
    newest: Option<Record>,
    next: u16,
}

fn scan<N: Nor>(nor: &N, page: Page) -> Result<PageScan, N::Error> {
    let mut found = PageScan {
        newest: None,
        next: 0,
    };
    for slot in 0..nor.slots() {
        match Record::decode(nor.read(page, slot)?) {
            Slot::Erased => {}
            Slot::Torn => found.next = slot.saturating_add(1),
            Slot::Valid(record) => {
                found.newest = Some(record);
                found.next = slot.saturating_add(1);
            }
        }
    }
    Ok(found)
}

/// The page whose records are newer: the one whose generation is the other's plus one (they
/// alternate), else the greater epoch.
fn newer(a: PageScan, b: PageScan) -> Page {
    match (a.newest, b.newest) {
        (Some(ra), Some(rb)) => {
            if rb.generation == ra.generation.wrapping_add(1) {
                Page::B
            } else if ra.generation == rb.generation.wrapping_add(1) || ra.epoch >= rb.epoch {
                Page::A
            } else {
                Page::B
            }
        }
        (None, Some(_)) => Page::B,
        _ => Page::A,
    }
}

/// The controller's memory on `N`: opened once per start, told every latch change.
#[derive(Debug)]
pub struct Memory<N: Nor> {
    nor: N,
    page: Page,
    next: u16,
    state: Record,
}

impl<N: Nor> Memory<N> {
    /// Reads what the last run left, opens the next epoch and writes it before returning (a
    /// blank flash starts at epoch 1, unlatched). What it returns is how the node starts.
    pub fn start(nor: N) -> Result<(Self, Remembered), PersistError<N::Error>> {
        if nor.slots() < 2 {
            return Err(PersistError::PageTooSmall);
        }
        let a = scan(&nor, Page::A).map_err(PersistError::Flash)?;
        let b = scan(&nor, Page::B).map_err(PersistError::Flash)?;
        let page = newer(a, b);
        let found = if page == Page::A { a } else { b };
        let last = found.newest.unwrap_or(Record {
            epoch: 0,
            latched: false,
            generation: 0,
        });
        let epoch = last
            .epoch
            .checked_add(1)
            .ok_or(PersistError::EpochsExhausted)?;
        let mut memory = Memory {
            nor,
            page,
            next: found.next,
            state: Record { epoch, ..last },
        };
        // At a start, half full is full: the erase goes here, before the control loop runs.
        let half = memory.nor.slots() / 2;
        if memory.next >= half {
            memory.move_to_other_page()?;
        } else {
            memory.append()?;
        }
        let remembered = Remembered {
            epoch: Epoch::new(epoch),
            latched: last.latched,
        };
        Ok((memory, remembered))
    }

    /// Records whether the E-stop is latched; a call that changes nothing writes nothing.
    pub fn record_latch(&mut self, latched: bool) -> Result<(), PersistError<N::Error>> {
        if latched == self.state.latched {
            return Ok(());
        }
        self.state.latched = latched;
        if self.next >= self.nor.slots() {
            self.move_to_other_page()
        } else {
            self.append()
        }
    }

    /// What is remembered now: this start's epoch and the latch as last recorded.
    pub fn remembered(&self) -> Remembered {
        Remembered {
            epoch: Epoch::new(self.state.epoch),
            latched: self.state.latched,
        }
    }

    /// The flash, back (for a test to restart on it).
    pub fn into_flash(self) -> N {
        self.nor
    }

    fn append(&mut self) -> Result<(), PersistError<N::Error>> {
        let slot = self.next;
        self.next = slot.saturating_add(1);
        self.nor
            .program(self.page, slot, self.state.encode())
            .map_err(PersistError::Flash)
    }

    fn move_to_other_page(&mut self) -> Result<(), PersistError<N::Error>> {
        let to = self.page.other();
        self.nor.erase(to).map_err(PersistError::Flash)?;
        self.page = to;
        self.next = 0;
        self.state.generation = self.state.generation.wrapping_add(1);
        self.append()
    }
}
