//! Zero heap allocations per lockstep cycle on the simulation's thread in steady state, with
//! every output on (the candump log, the CSV, the Foxglove MCAP): a run twice as long makes not
//! one allocation more on the thread that runs it. A counting allocator counts per thread; the
//! log writer's own thread is free to allocate (it formats and writes). What the runs allocate
//! (the model, the files, the channels) is the same for both.

mod common;

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::path::Path;

use common::config;
use protocol::TeleopMode;
use sim_host::robot::plant::Plant;
use sim_host::session;
use teleop_core::scripted::PlanStep;

/// The system allocator, counting allocations and reallocations on each thread.
struct Counting;

thread_local! {
    static ALLOCATIONS: Cell<u64> = const { Cell::new(0) };
}

fn count() {
    let _ = ALLOCATIONS.try_with(|n| n.set(n.get() + 1));
}

// SAFETY: every call is forwarded unchanged to the system allocator; counting touches only a
// thread-local cell with no destructor, which never allocates.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        // SAFETY: the caller's contract, passed on.
        unsafe { System.alloc(layout) }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        count();
        // SAFETY: the caller's contract, passed on.
        unsafe { System.alloc_zeroed(layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        // SAFETY: the caller's contract, passed on.
        unsafe { System.realloc(ptr, layout, new_size) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: the caller's contract, passed on.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// Allocations on this thread by one run of `seconds` with every output, plots aside (they are
/// drawn after the run).
fn allocations_of_run(seconds: f64) -> u64 {
    let plan = vec![
        PlanStep::at(0.0, TeleopMode::Stand),
        PlanStep::at(1.0, TeleopMode::TrotForward).with_velocity(0.1, 0.2),
    ];
    let mut cfg = config(Plant::default(), plan, Vec::new(), seconds);
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("allocations")
        .join(format!("{seconds}"));
    let _ = std::fs::remove_dir_all(&dir);
    cfg.out_dir = Some(dir);
    cfg.plots = false;
    let before = ALLOCATIONS.with(Cell::get);
    let report = session::run(&cfg).unwrap();
    let after = ALLOCATIONS.with(Cell::get);
    assert!(report.stats.cycles > 0);
    drop(report);
    after - before
}

#[test]
fn a_longer_run_allocates_nothing_more_on_the_simulation_thread() {
    // What is made once per process (lazy statics) is paid for by a first run.
    allocations_of_run(2.0);
    let short = allocations_of_run(6.0);
    let long = allocations_of_run(12.0);
    println!("allocations on the simulation thread: {short} in 6 s, {long} in 12 s");
    assert_eq!(
        long,
        short,
        "1,500 more lockstep cycles made {} more allocations",
        long as i128 - short as i128
    );
}
