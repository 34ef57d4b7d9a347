//! The runaway and stall detector's unit tests.
#![allow(clippy::expect_used, clippy::default_numeric_fallback)]

use super::*;

const CONFIG: RunawayConfig = RunawayConfig::ROBOT;

fn detector() -> Runaway {
    // 250 Hz: 4 ms per tick.
    Runaway::new(&CONFIG, TickRate::SIM_250_HZ)
}

fn input(speed: f32, reference: f32, torque: f32) -> RunawayInput {
    RunawayInput {
        ground_speed_m_s: speed,
        lagging_wheel_m_s: speed,
        velocity_ref_m_s: reference,
        torque_nm: torque,
        torque_limit_nm: 60.0,
    }
}

fn ticks_to_trip(runaway: &mut Runaway, input: &RunawayInput) -> Option<(u32, FaultFlags)> {
    (1..=1000).find_map(|tick| runaway.update(&CONFIG, input).map(|cause| (tick, cause)))
}

/// Ticks at 250 Hz of `ms`, as the detector counts them.
fn ticks(ms: u32) -> u32 {
    TickRate::SIM_250_HZ.ticks_from_ms(ms)
}

#[test]
fn a_robot_stopped_hard_against_its_commanded_speed_trips_as_a_stall() {
    let mut runaway = detector();
    for _ in 0..50 {
        assert_eq!(runaway.update(&CONFIG, &input(0.48, 0.48, 10.0)), None);
    }
    // Against a step: 0.48 m/s to rest in 0.1 s (4.8 m/s²), while the reference stays.
    let mut speed = 0.48;
    let found = (1..=100).find_map(|tick| {
        speed = f32::max(speed - 4.8 * 0.004, 0.0);
        let cause = runaway.update(&CONFIG, &input(speed, 0.48, 10.0));
        cause.map(|cause| (tick, cause))
    });
    let (tick, cause) = found.expect("never tripped");
    assert_eq!(cause, FaultFlags::WHEEL_STALL);
    // The filter needs a few ticks to pass 2.5 m/s², then the collision time runs.
    assert!((ticks(24)..=ticks(24) + 4).contains(&tick), "{tick}");
}

/// Backing at 0.48 m/s into a riser met at an angle: one wheel stops in 0.1 s while the other
/// rolls on (the axle decelerates at 2.4 m/s², under the collision's 2.5); the tick the
/// detector trips and why, with the lagging wheel read (`lagging`) or the axle's mean alone.
fn met_at_an_angle(lagging: bool) -> Option<(u32, FaultFlags)> {
    let mut runaway = detector();
    for _ in 0..50 {
        assert_eq!(runaway.update(&CONFIG, &input(-0.48, -0.48, -10.0)), None);
    }
    let mut stopped = -0.48_f32;
    (1..=100).find_map(|tick| {
        stopped = f32::min(stopped + 4.8 * 0.004, 0.0);
        let mean = 0.5 * (stopped - 0.48);
        let sample = RunawayInput {
            lagging_wheel_m_s: if lagging { stopped } else { mean },
            ..input(mean, -0.48, -10.0)
        };
        runaway.update(&CONFIG, &sample).map(|cause| (tick, cause))
    })
}

/// Whether `lagging_wheel_m_s(wheels, reference, turn)` is `expected`, to rounding.
fn lags_at(wheels: [f32; 2], reference: f32, turn: f32, expected: f32) -> bool {
    (lagging_wheel_m_s(wheels, reference, turn) - expected).abs() < 1e-6
}

#[test]
fn the_lagging_wheel_is_the_one_furthest_behind_its_own_reference() {
    // Forward, the slower wheel; backward, the one slower backward.
    assert!(lags_at([0.48, 0.2], 0.48, 0.0, 0.2));
    assert!(lags_at([0.1, 0.3], 0.48, 0.0, 0.1));
    assert!(lags_at([-0.48, -0.1], -0.48, 0.0, -0.1));
    assert!(lags_at([-0.2, -0.48], -0.48, 0.0, -0.2));
    // Turning at speed, each wheel on its own reference: none behind.
    assert!(lags_at([0.58, 0.38], 0.48, 0.1, 0.48));
    // The inner wheel of a turn stopped: behind by its own reference's speed.
    assert!(lags_at([0.58, 0.0], 0.48, 0.1, 0.1));
    // No reference: the axle's speed, whichever way the wheels turn.
    assert!(lags_at([0.2, -0.2], 0.0, 0.3, 0.0));
    assert!(lagging_wheel_m_s([f32::NAN, 0.2], 0.48, 0.0).is_nan());
    // A non-finite lagging wheel counts as out of bounds, the axle's speed fine.
    let sample = RunawayInput {
        lagging_wheel_m_s: f32::NAN,
        ..input(0.48, 0.48, 10.0)
    };
    let (tick, _) = ticks_to_trip(&mut detector(), &sample).expect("never tripped");
    assert_eq!(tick, ticks(CONFIG.speed_error_ms));
}

#[test]
fn a_wheel_stopped_by_a_riser_met_at_an_angle_trips_as_a_stall_while_the_other_rolls_on() {
    let (tick, cause) = met_at_an_angle(true).expect("never tripped");
    assert_eq!(cause, FaultFlags::WHEEL_STALL);
    assert!((ticks(24)..=ticks(24) + 4).contains(&tick), "{tick}");
    // Read by the axle's mean alone, the same meeting has not tripped in 0.4 s.
    assert_eq!(met_at_an_angle(false), None);
}

#[test]
fn a_robot_thrown_back_by_what_it_hit_trips_as_a_stall_not_a_runaway() {
    let mut runaway = detector();
    // Catching up with its reference, 0.18 m/s faster than it: not following, so the
    // collision rule is not armed.
    for _ in 0..100 {
        assert_eq!(runaway.update(&CONFIG, &input(0.66, 0.48, 10.0)), None);
    }
    // Stopped by a step within 0.1 s and thrown back at 0.6 m/s: the speed error trips.
    let mut speed = 0.66;
    let found = (1..=200).find_map(|tick| {
        speed = f32::max(speed - 6.0 * 0.004, -0.6);
        let cause = runaway.update(&CONFIG, &input(speed, 0.48, -30.0));
        cause.map(|cause| (tick, cause))
    });
    let (_, cause) = found.expect("never tripped");
    assert_eq!(cause, FaultFlags::WHEEL_STALL);
}

#[test]
fn wheels_slipping_in_a_limit_cycle_trip_as_a_runaway_not_a_stall() {
    let mut runaway = detector();
    // On low friction the law and the slipping wheels swing the robot ±0.5 m/s about its
    // 0.2 m/s reference at 4 Hz, decelerating at every swing as hard as in a collision…
    for tick in 0..250_u32 {
        let phase = tick as f32 * 0.004 * 4.0 * core::f32::consts::TAU;
        let speed = 0.2 + 0.5 * phase.sin();
        assert_eq!(runaway.update(&CONFIG, &input(speed, 0.2, 20.0)), None);
    }
    // … then runs away at 1.1 m/s.
    let found = ticks_to_trip(&mut runaway, &input(1.1, 0.2, 20.0));
    assert_eq!(found.map(|(_, cause)| cause), Some(FaultFlags::RUNAWAY));
}

#[test]
fn a_robot_far_from_its_reference_for_the_error_time_trips_as_a_runaway() {
    for (speed, reference) in [(-0.5, 0.48), (0.8, 0.0), (-0.8, 0.0), (1.2, 0.48)] {
        let mut runaway = detector();
        let found = ticks_to_trip(&mut runaway, &input(speed, reference, 0.0));
        let expected = Some((ticks(150), FaultFlags::RUNAWAY));
        assert_eq!(found, expected, "{speed} {reference}");
    }
}

#[test]
fn a_law_saturated_for_its_time_trips_even_at_the_reference_speed() {
    let mut runaway = detector();
    let found = ticks_to_trip(&mut runaway, &input(0.3, 0.3, -59.0));
    assert_eq!(found, Some((ticks(300), FaultFlags::RUNAWAY)));
}

#[test]
fn lagging_braking_hard_stops_and_short_saturation_never_trip() {
    let mut runaway = detector();
    for round in 0..20 {
        // A robot lagging its reference by 0.6 m/s, as in a stop from top speed.
        for _ in 0..100 {
            assert_eq!(runaway.update(&CONFIG, &input(0.6, 0.0, 20.0)), None);
        }
        // Stopping hard (8 m/s²) with the reference at zero: a stop's last centimetres.
        let mut speed = 0.6;
        for _ in 0..20 {
            speed = f32::max(speed - 8.0 * 0.004, 0.0);
            assert_eq!(runaway.update(&CONFIG, &input(speed, 0.0, 20.0)), None);
        }
        // Following the reference, then decelerating at 2 m/s² against it.
        for _ in 0..50 {
            assert_eq!(runaway.update(&CONFIG, &input(0.48, 0.48, 20.0)), None);
        }
        let mut speed = 0.48;
        for _ in 0..50 {
            speed -= 2.0 * 0.004;
            assert_eq!(runaway.update(&CONFIG, &input(speed, 0.48, 20.0)), None);
        }
        // Saturated one tick short of the saturation time.
        for _ in 1..ticks(300) {
            assert_eq!(runaway.update(&CONFIG, &input(0.1, 0.1, 60.0)), None);
        }
        assert_eq!(
            runaway.update(&CONFIG, &input(0.1, 0.1, 0.0)),
            None,
            "{round}"
        );
    }
}

#[test]
fn a_robot_stopped_hard_driving_backward_trips_as_a_stall() {
    let mut runaway = detector();
    for _ in 0..50 {
        assert_eq!(runaway.update(&CONFIG, &input(-0.48, -0.48, -10.0)), None);
    }
    let mut speed = -0.48;
    let found = (1..=100).find_map(|tick| {
        speed = f32::min(speed + 4.8 * 0.004, 0.0);
        let cause = runaway.update(&CONFIG, &input(speed, -0.48, -10.0));
        cause.map(|cause| (tick, cause))
    });
    let (tick, cause) = found.expect("never tripped");
    assert_eq!(cause, FaultFlags::WHEEL_STALL);
    assert!((ticks(24)..=ticks(24) + 4).contains(&tick), "{tick}");
}

#[test]
fn a_sudden_stop_trips_as_a_stall_although_the_robot_no_longer_follows() {
    // Whether the robot had followed its reference is judged before the deceleration:
    // the collision itself takes it far from the reference at once.
    let mut runaway = detector();
    for _ in 0..ticks(CONFIG.following_ms) + 1 {
        assert_eq!(runaway.update(&CONFIG, &input(0.48, 0.48, 10.0)), None);
    }
    let mut speed = 0.24;
    let found = (1..=100).find_map(|tick| {
        let cause = runaway.update(&CONFIG, &input(speed, 0.48, 10.0));
        speed = f32::max(speed - 3.0 * 0.004, 0.0);
        cause.map(|cause| (tick, cause))
    });
    let (tick, cause) = found.expect("never tripped");
    assert_eq!(cause, FaultFlags::WHEEL_STALL);
    assert!(tick <= ticks(24) + 4, "{tick}");
}

#[test]
fn an_error_at_its_bound_is_within_it() {
    let mut runaway = detector();
    let at_bound = input(CONFIG.speed_error_m_s, 0.0, 0.0);
    assert_eq!(ticks_to_trip(&mut runaway, &at_bound), None);
}

#[test]
fn a_push_along_the_reference_is_no_collision() {
    let mut runaway = detector();
    for _ in 0..50 {
        assert_eq!(runaway.update(&CONFIG, &input(0.48, 0.48, 10.0)), None);
    }
    // Shoved forward at 5 m/s² for 60 ms: as sharp as a collision, but along the
    // reference.
    let mut speed = 0.48;
    for tick in 0..15 {
        speed += 5.0 * 0.004;
        let found = runaway.update(&CONFIG, &input(speed, 0.48, 10.0));
        assert_eq!(found, None, "{tick}");
    }
}

#[test]
fn a_robot_swinging_about_its_reference_is_no_collision() {
    // A delayed loop's limit cycle: ±0.3 m/s at 3 Hz about 0.2 m/s, peaks of 5.7 m/s².
    let mut runaway = detector();
    for tick in 0..ticks(5_000) {
        let phase = core::f32::consts::TAU * 3.0 * tick as f32 * 0.004;
        let speed = 0.2 + 0.3 * phase.sin();
        assert_eq!(
            runaway.update(&CONFIG, &input(speed, 0.2, 20.0)),
            None,
            "{tick}"
        );
    }
}

#[test]
fn a_fast_limit_cycle_read_through_an_encoder_is_no_collision() {
    // Driving at 0.48 m/s with two cycles of transport delay each way the loop swings at
    // 10 Hz (±0.035 m/s measured in the closed loop, where it tripped the collision
    // criterion after 3.5 s of driving), and the ground speed comes from 14-bit encoder
    // counts, 0.0115 m/s a count at 250 Hz. A swing of ±0.08 m/s decelerates past 2.5 m/s²
    // for longer than the collision time every cycle; its speed is then never 5 cm/s
    // behind the reference (it is near the top of its swing).
    let count_m_s = 0.12 * core::f32::consts::TAU / 16_384.0 / 0.004;
    let mut runaway = detector();
    for tick in 0..ticks(10_000) {
        let phase = core::f32::consts::TAU * 10.0 * tick as f32 * 0.004;
        let speed = 0.48 + 0.08 * phase.sin();
        let read = (speed / count_m_s).round() * count_m_s;
        assert_eq!(
            runaway.update(&CONFIG, &input(read, 0.48, 10.0)),
            None,
            "{tick}"
        );
    }
}

#[test]
fn a_reset_starts_the_count_again_and_non_finite_input_counts_as_bad() {
    let mut runaway = detector();
    for _ in 1..ticks(150) {
        assert_eq!(runaway.update(&CONFIG, &input(0.9, 0.0, 0.0)), None);
    }
    runaway.reset();
    for _ in 1..ticks(150) {
        assert_eq!(runaway.update(&CONFIG, &input(f32::NAN, 0.0, 0.0)), None);
    }
    assert_eq!(
        runaway.update(&CONFIG, &input(f32::NAN, 0.0, 0.0)),
        Some(FaultFlags::RUNAWAY)
    );
}

#[test]
fn a_robot_standing_still_against_its_reference_trips_as_a_stall_after_the_blocked_time() {
    // Pushed softly against a riser: no collision, no saturation, the speed error under its
    // bound; only standing still does not end.
    for speed in [0.01, 0.03, -0.03] {
        let mut runaway = detector();
        let found = ticks_to_trip(&mut runaway, &input(speed, -0.48, -9.0));
        let expected = Some((ticks(CONFIG.blocked_ms), FaultFlags::WHEEL_STALL));
        assert_eq!(found, expected, "at {speed} m/s");
    }
    // A reference under the blocked one (a creep) is left to the other rules.
    let mut runaway = detector();
    assert_eq!(ticks_to_trip(&mut runaway, &input(0.0, 0.15, 5.0)), None);
}

#[test]
fn a_robot_starting_from_rest_behind_its_ramped_reference_trips_only_if_it_never_moves() {
    // The reference ramps at 0.35 m/s² (past the blocked rule's 0.2 m/s at 0.57 s); the robot
    // follows `lag_s` behind it, under 0.05 m/s until 0.14 s after that.
    let start = |lag_s: f32| {
        let mut runaway = detector();
        (0..750_u32).find_map(|tick| {
            let t_s = tick as f32 * 0.004;
            let reference = f32::min(0.35 * t_s, 0.48);
            let speed = f32::min(0.35 * f32::max(t_s - lag_s, 0.0), 0.48);
            runaway.update(&CONFIG, &input(speed, reference, 5.0))
        })
    };
    assert_eq!(start(0.3), None);
    assert_eq!(start(0.9), None);
    assert_eq!(start(1.2), Some(FaultFlags::WHEEL_STALL));
}
