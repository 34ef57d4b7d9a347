//! The backward trot's rangefinder watch (`firmware::control::terrain::rise`) wired into the
//! controller, on an ideal plant whose rangefinder reports a chosen distance every 20 ms: a
//! shorter ranging behind a backward trot (the spot on a riser) stops it with `leg_blocked`,
//! `X` and `K` again stop it again at once; a forward trot, a walk back come to a halt and
//! flat ground are never stopped.

mod common;

use common::bench::{ms, Bench};
use common::{command, velocity_command, Ticks};

use firmware::control::fsm::{Direction, LegMotion, State};
use protocol::{AnyMessage, FaultFlags, Range, RangeDistance, RangeStatus, TeleopMode};

/// Flat ground along the beam from the standing robot, m (any steady distance: the watch
/// compares heights with each other).
const FLAT_M: f32 = 1.0;

/// The spot on a plateau 6 cm higher: the beam, 25° down, is shortened by 0.06 / sin 25°.
const RISER_M: f32 = FLAT_M - 0.14;

/// Runs `bench` for `ticks` with the rangefinder at `distance_m`; the tick the state first
/// left `from`, if it did.
fn run_ranging(bench: &mut Bench, ticks: u32, distance_m: f32, from: State) -> Option<u32> {
    let range = Range {
        distance: RangeDistance::saturating_from_si(distance_m),
        status: RangeStatus::Valid,
    };
    for n in 0..ticks {
        if bench.now % 5 == 0 {
            bench.send(AnyMessage::Range(range));
        }
        bench.tick();
        if bench.state() != from {
            return Some(n);
        }
    }
    None
}

const BACK: State = State::Legs(LegMotion::Trot(Direction::Backward));

/// A ready bench standing, then trotting backward (`K`) over flat ground for `flat_ms`.
fn trotting_back(flat_ms: u32) -> Bench {
    let mut bench = Bench::ready();
    bench.send(command(TeleopMode::Stand));
    bench.run(ms(2_000));
    bench.send(command(TeleopMode::TrotBackward));
    bench.run(1);
    assert_eq!(bench.state(), BACK);
    let left = run_ranging(&mut bench, ms(flat_ms), FLAT_M, BACK);
    assert_eq!(left, None, "stopped on flat ground");
    bench
}

#[test]
fn a_riser_seen_behind_a_backward_trot_stops_it_and_k_again_stops_at_once() {
    let mut bench = trotting_back(10_000);
    let stopped = run_ranging(&mut bench, ms(3_000), RISER_M, BACK);
    // A stride's average rising, then a second of it.
    let stopped_ms = stopped.map(|n| n * 4);
    assert!(
        stopped_ms.is_some_and(|t| (1_000..=2_200).contains(&t)),
        "{stopped_ms:?}"
    );
    assert_eq!(bench.state(), State::Legs(LegMotion::Stand));
    let status = bench.tick().status;
    assert!(status.faults.contains(FaultFlags::LEG_BLOCKED));
    // The operator's X clears the report; K again walks toward the same riser.
    bench.send(command(TeleopMode::Stop));
    run_ranging(
        &mut bench,
        ms(1_000),
        RISER_M,
        State::Legs(LegMotion::Stand),
    );
    bench.send(command(TeleopMode::TrotBackward));
    bench.run(1);
    let again = run_ranging(&mut bench, ms(1_000), RISER_M, BACK);
    assert!(again.is_some_and(|n| n <= 5 * 2), "{again:?}");
    // Walked forward, the watch starts afresh: K then needs its settling again.
    bench.send(command(TeleopMode::TrotForward));
    run_ranging(
        &mut bench,
        ms(1_000),
        RISER_M,
        State::Legs(LegMotion::Trot(Direction::Forward)),
    );
    bench.send(command(TeleopMode::TrotBackward));
    bench.run(1);
    assert_eq!(run_ranging(&mut bench, ms(3_000), RISER_M, BACK), None);
}

#[test]
fn flat_ground_a_forward_trot_and_a_halted_walk_are_never_stopped() {
    // Thirty seconds backward over flat ground.
    trotting_back(30_000);
    // Forward, the spot behind climbing a riser means nothing.
    let mut bench = Bench::ready();
    bench.send(command(TeleopMode::TrotForward));
    let forward = State::Legs(LegMotion::Trot(Direction::Forward));
    run_ranging(&mut bench, ms(6_000), FLAT_M, forward);
    assert_eq!(run_ranging(&mut bench, ms(4_000), RISER_M, forward), None);
    // A walk back that has come to a halt: someone stepping into the beam behind the
    // standing robot stops nothing.
    let mut bench = Bench::ready();
    bench.send(velocity_command(TeleopMode::Walk, -0.1, 0.0));
    let walk = State::Legs(LegMotion::Walk);
    assert_eq!(run_ranging(&mut bench, ms(6_000), FLAT_M, walk), None);
    bench.send(velocity_command(TeleopMode::Walk, 0.0, 0.0));
    assert_eq!(run_ranging(&mut bench, ms(4_000), RISER_M, walk), None);
}
