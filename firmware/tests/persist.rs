//! The controller's memory across restarts (`firmware::node::persist`) on a model of NOR flash
//! that a reset can interrupt at any operation: a program then leaves the slot partly written,
//! an erase leaves the page partly erased. Whatever the moment of the reset, the next start
//! opens an epoch greater than every epoch a start ever returned, and remembers the latch as
//! last recorded (or, if the reset hit the write of a change, either value).

use std::cell::RefCell;
use std::rc::Rc;

use firmware::node::persist::{Memory, Nor, Page, PersistError, RECORD_BYTES};

/// Two pages of records in RAM, shared by clones (the board's flash outlives each start), with
/// a reset after a budget of operations: the operation that exhausts it is torn, and nothing
/// more happens until power comes back.
#[derive(Debug, Clone)]
struct Flash(Rc<RefCell<Cells>>);

#[derive(Debug)]
struct Cells {
    pages: [Vec<[u8; RECORD_BYTES]>; 2],
    budget: Option<u32>,
    noise: u64,
    operations: u32,
    erases: u32,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct PoweredOff;

fn index(page: Page) -> usize {
    match page {
        Page::A => 0,
        Page::B => 1,
    }
}

impl Flash {
    fn blank(slots: usize) -> Self {
        Self(Rc::new(RefCell::new(Cells {
            pages: [
                vec![[0xFF; RECORD_BYTES]; slots],
                vec![[0xFF; RECORD_BYTES]; slots],
            ],
            budget: None,
            noise: 0x9E37_79B9_7F4A_7C15,
            operations: 0,
            erases: 0,
        })))
    }

    /// The power goes during the `n`-th operation from now (0: the next one).
    fn cut_after(&self, n: u32) {
        self.0.borrow_mut().budget = Some(n + 1);
    }

    fn power_on(&self) {
        self.0.borrow_mut().budget = None;
    }

    fn operations(&self) -> u32 {
        self.0.borrow().operations
    }
}

impl Cells {
    /// Spends one operation: `Ok(true)` to do it whole, `Ok(false)` to tear it.
    fn spend(&mut self) -> Result<bool, PoweredOff> {
        self.operations += 1;
        match self.budget {
            None => Ok(true),
            Some(0) => Err(PoweredOff),
            Some(n) => {
                self.budget = Some(n - 1);
                Ok(n > 1)
            }
        }
    }

    fn noise(&mut self) -> u8 {
        self.noise ^= self.noise << 13;
        self.noise ^= self.noise >> 7;
        self.noise ^= self.noise << 17;
        self.noise as u8
    }
}

impl Nor for Flash {
    type Error = PoweredOff;

    fn slots(&self) -> u16 {
        self.0.borrow().pages[0].len() as u16
    }

    fn read(&self, page: Page, slot: u16) -> Result<[u8; RECORD_BYTES], PoweredOff> {
        Ok(self.0.borrow().pages[index(page)][usize::from(slot)])
    }

    fn program(
        &mut self,
        page: Page,
        slot: u16,
        bytes: [u8; RECORD_BYTES],
    ) -> Result<(), PoweredOff> {
        let mut cells = self.0.borrow_mut();
        let whole = cells.spend()?;
        let cell = cells.pages[index(page)][usize::from(slot)];
        assert_eq!(
            cell, [0xFF; RECORD_BYTES],
            "slot {slot} of {page:?} programmed twice"
        );
        let mut written = bytes;
        if !whole {
            // Programming only clears bits: a torn write clears some of them.
            for byte in &mut written {
                *byte |= cells.noise();
            }
        }
        cells.pages[index(page)][usize::from(slot)] = written;
        if whole {
            Ok(())
        } else {
            Err(PoweredOff)
        }
    }

    fn erase(&mut self, page: Page) -> Result<(), PoweredOff> {
        let mut cells = self.0.borrow_mut();
        let whole = cells.spend()?;
        cells.erases += 1;
        for slot in 0..cells.pages[0].len() {
            // A torn erase leaves a random part of the page as it was.
            if whole || cells.noise() % 2 == 0 {
                cells.pages[index(page)][slot] = [0xFF; RECORD_BYTES];
            }
        }
        if whole {
            Ok(())
        } else {
            Err(PoweredOff)
        }
    }
}

/// What a run left: the epoch its start opened (if it did), the latch as last recorded, and
/// whether the power went while a change was being written (the latch may then be either).
#[derive(Debug, Clone, Copy)]
struct Run {
    epoch: Option<u32>,
    latched: bool,
    torn_change: bool,
}

/// A start on `flash`, then `changes` latch changes (each the opposite of the last), until done
/// or the power goes. `latched` is the latch before the run, kept if the start fails.
fn run(flash: &Flash, changes: u32, latched: bool) -> Run {
    let Ok((mut memory, remembered)) = Memory::start(flash.clone()) else {
        return Run {
            epoch: None,
            latched,
            torn_change: false,
        };
    };
    let mut run = Run {
        epoch: Some(remembered.epoch.raw()),
        latched: remembered.latched,
        torn_change: false,
    };
    assert_eq!(remembered.latched, latched, "the start forgot the latch");
    for _ in 0..changes {
        match memory.record_latch(!run.latched) {
            Ok(()) => run.latched = !run.latched,
            Err(PersistError::Flash(PoweredOff)) => {
                run.torn_change = true;
                break;
            }
            Err(other) => panic!("{other:?}"),
        }
    }
    run
}

#[test]
fn a_blank_flash_starts_at_epoch_1_unlatched_and_each_start_opens_the_next_epoch() {
    let flash = Flash::blank(16);
    for expected in 1..=100 {
        let (mut memory, remembered) = Memory::start(flash.clone()).unwrap();
        assert_eq!(remembered.epoch.raw(), expected);
        assert_eq!(remembered.latched, expected % 3 == 0, "start {expected}");
        // Latched at the end of every third-minus-one run: the next start is latched.
        memory.record_latch(expected % 3 == 2).unwrap();
    }
}

#[test]
fn a_thousand_latch_changes_over_two_small_pages_are_remembered() {
    let flash = Flash::blank(8);
    let (mut memory, _) = Memory::start(flash.clone()).unwrap();
    for n in 0..1_000 {
        memory.record_latch(n % 2 == 0).unwrap();
        // Repeating the state writes nothing.
        let before = flash.operations();
        memory.record_latch(n % 2 == 0).unwrap();
        assert_eq!(flash.operations(), before);
    }
    let (_, remembered) = Memory::start(flash).unwrap();
    assert_eq!(remembered.epoch.raw(), 2);
    assert!(!remembered.latched, "the last change released");
}

#[test]
fn a_reset_at_any_flash_operation_never_reopens_an_epoch_nor_loses_a_recorded_latch() {
    // Pages of 6 records: page moves (and their erases) come often.
    for cut in 0..200_u32 {
        let flash = Flash::blank(6);
        let mut opened = 0_u32;
        let mut latched = false;
        for round in 0..12_u32 {
            if round == 5 {
                flash.cut_after(cut % 17);
            }
            let before = latched;
            let run = run(&flash, 3 + round % 3, latched);
            flash.power_on();
            if let Some(epoch) = run.epoch {
                assert!(
                    epoch > opened,
                    "cut {cut}, round {round}: epoch {epoch} after {opened}"
                );
                opened = epoch;
            }
            // The next start must find `run.latched`, or either value after a torn change.
            let (memory, remembered) = Memory::start(flash.clone()).unwrap();
            assert!(remembered.epoch.raw() > opened, "cut {cut}, round {round}");
            opened = remembered.epoch.raw();
            if run.torn_change {
                latched = remembered.latched;
            } else {
                assert_eq!(
                    remembered.latched, run.latched,
                    "cut {cut}, round {round}: latch lost (was {before})"
                );
                latched = run.latched;
            }
            drop(memory);
        }
    }
}

#[test]
fn every_epoch_opened_is_refused_once_u32_is_spent() {
    // A flash whose record says the last epoch was u32::MAX.
    let flash = Flash::blank(4);
    let (mut memory, _) = Memory::start(flash.clone()).unwrap();
    memory.record_latch(true).unwrap();
    drop(memory);
    {
        let mut cells = flash.0.borrow_mut();
        let crc = crc::Crc::<u16>::new(&crc::CRC_16_IBM_3740);
        let head = [0xFF, 0xFF, 0xFF, 0xFF, 1, 0];
        let [c0, c1] = crc.checksum(&head).to_le_bytes();
        cells.pages[0][2] = [0xFF, 0xFF, 0xFF, 0xFF, 1, 0, c0, c1];
    }
    assert_eq!(
        Memory::start(flash).map(|(_, r)| r).unwrap_err(),
        PersistError::EpochsExhausted
    );
}

/// A record as the log writes it (epoch, latched byte, generation), with its CRC.
fn record(epoch: u32, latched: u8, generation: u8) -> [u8; RECORD_BYTES] {
    let [e0, e1, e2, e3] = epoch.to_le_bytes();
    let head = [e0, e1, e2, e3, latched, generation];
    let [c0, c1] = crc::Crc::<u16>::new(&crc::CRC_16_IBM_3740)
        .checksum(&head)
        .to_le_bytes();
    [e0, e1, e2, e3, latched, generation, c0, c1]
}

/// A flash of 8-record pages holding `a` and `b` from their first slots.
fn flash_with(a: &[[u8; RECORD_BYTES]], b: &[[u8; RECORD_BYTES]]) -> Flash {
    let flash = Flash::blank(8);
    {
        let mut cells = flash.0.borrow_mut();
        for (slot, bytes) in a.iter().enumerate() {
            cells.pages[0][slot] = *bytes;
        }
        for (slot, bytes) in b.iter().enumerate() {
            cells.pages[1][slot] = *bytes;
        }
    }
    flash
}

fn started(flash: Flash) -> (u32, bool) {
    let (_, remembered) = Memory::start(flash).unwrap();
    (remembered.epoch.raw(), remembered.latched)
}

#[test]
fn a_record_with_a_good_check_but_epoch_0_or_a_latch_byte_past_1_is_torn() {
    // Epoch 0 (a double word read as zeros after an ECC error) and a latch byte of 2 do not
    // count, whatever their check: the newest good record (epoch 7, latched) does.
    let flash = flash_with(&[record(7, 1, 0), record(0, 0, 0), record(9, 2, 0)], &[]);
    assert_eq!(started(flash), (8, true));
}

#[test]
fn the_page_of_the_next_generation_is_the_newer_one_else_the_greater_epoch() {
    // B's generation follows A's: B, though its epoch is smaller (a wrapped test value).
    assert_eq!(
        started(flash_with(&[record(50, 0, 3)], &[record(40, 1, 4)])),
        (41, true)
    );
    // A's follows B's.
    assert_eq!(
        started(flash_with(&[record(40, 1, 5)], &[record(50, 0, 4)])),
        (41, true)
    );
    // Generations that do not follow each other (a page from long ago): the greater epoch.
    assert_eq!(
        started(flash_with(&[record(20, 0, 9)], &[record(30, 1, 2)])),
        (31, true)
    );
    assert_eq!(
        started(flash_with(&[record(30, 1, 9)], &[record(20, 0, 2)])),
        (31, true)
    );
}

#[test]
fn pages_of_fewer_than_two_records_are_refused_and_starts_erase_rarely() {
    assert_eq!(
        Memory::start(Flash::blank(1)).map(|_| ()).unwrap_err(),
        PersistError::PageTooSmall
    );
    assert!(Memory::start(Flash::blank(2)).is_ok());
    // Starts write one record each; a page of 16 is erased when half full: 40 starts erase
    // 40 / 8 = 5 times, not at every start.
    let flash = Flash::blank(16);
    for _ in 0..40 {
        Memory::start(flash.clone()).unwrap();
    }
    let erases = flash.0.borrow().erases;
    assert!((4..=6).contains(&erases), "{erases} erases in 40 starts");
}
