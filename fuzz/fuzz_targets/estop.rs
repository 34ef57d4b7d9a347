//! The E-stop contract under any sequence of operations: ticks (from near `u32::MAX`, so that
//! the tick wraps), fresh sealed frames of every message the controller hears, SYNC advancing,
//! frozen or going back, replays of any earlier frame or run of frames, latches, fresh and
//! forged releases, releases held back, and controller restarts with the latch persisted as
//! firmware-host persists it — into `firmware::Node`, whose every frame and tick the oracle
//! ([`oracle`]) checks against the contract: once latched, no motion command obeyed, every
//! drive torque-free by the SS1 deadline and after it, no release but a fresh authenticated
//! one echoing the published token, the latch kept across restarts, and after a start, a
//! restart or a release nothing moving before an operator STOP.
//!
//! The input is a script ([`script`]): every byte string is one.
#![no_main]

use libfuzzer_sys::fuzz_target;

#[path = "estop/bench.rs"]
mod bench;
#[path = "estop/oracle.rs"]
mod oracle;
#[path = "estop/plant.rs"]
mod plant;
#[path = "estop/script.rs"]
mod script;

use script::{Op, HEADER_LEN, MAX_PAYLOAD};

/// `n` bytes from the front of `bytes` (zeros past its end), and the rest.
fn take(bytes: &[u8], n: usize) -> ([u8; 3], &[u8]) {
    let mut args = [0_u8; 3];
    for (slot, byte) in args.iter_mut().zip(bytes.iter().take(n)) {
        *slot = *byte;
    }
    (args, bytes.get(n..).unwrap_or(&[]))
}

fuzz_target!(|input: &[u8]| {
    let Some((header, mut rest)) = input.split_first_chunk::<HEADER_LEN>() else {
        return;
    };
    let Some(mut bench) = bench::Bench::new(header) else {
        return;
    };
    while let Some((code, tail)) = rest.split_first() {
        let op = Op::of(*code);
        let ([a, b, c], tail) = take(tail, op.args());
        rest = tail;
        match op {
            Op::Tick => bench.ticks(1 + u32::from(a % 32)),
            Op::Run => bench.ticks(32 * (1 + u32::from(a % 32))),
            Op::Sync => bench.sync(a, b),
            Op::Plant => bench.set_plant(a, b, c),
            Op::Command => bench.command(a, b, c),
            Op::Heartbeat => bench.heartbeat(),
            Op::Message => {
                let len = (usize::from(b) % (MAX_PAYLOAD + 1)).min(rest.len());
                let (payload, tail) = rest.split_at(len);
                rest = tail;
                bench.message(a, payload);
            }
            Op::Latch => bench.latch(a),
            Op::Release => bench.release(a),
            Op::Forge => bench.forge(a, b),
            Op::Withhold => bench.withhold(a),
            Op::Deliver => bench.deliver(),
            Op::Replay => bench.replay(a, 1),
            Op::ReplayRun => bench.replay(a, 1 + b % 16),
            Op::Restart => bench.restart(a),
        }
        if bench.exhausted() {
            break;
        }
    }
});
