//! Integer time: durations in ticks, watchdogs across the counter wrap.

use firmware::control::safety::Watchdog;
use firmware::legs::smoothing::Smoother;
use firmware::{Tick, TickRate};

#[test]
fn milliseconds_round_up_to_whole_ticks() {
    let sim = TickRate::SIM_250_HZ;
    assert_eq!(sim.ticks_from_ms(50), 13); // 12.5 ticks: never early
    assert_eq!(sim.ticks_from_ms(500), 125);
    assert_eq!(TickRate::MCU_1_KHZ.ticks_from_ms(50), 50);
    assert_eq!(TickRate::new(0), None);
    assert_eq!(TickRate::new(20_000), None);
}

#[test]
fn a_watchdog_works_across_the_tick_counter_wrap() {
    let mut watchdog = Watchdog::new(13);
    assert!(watchdog.expired(Tick(0)), "never fed counts as expired");
    let fed = Tick(u32::MAX - 5);
    watchdog.feed(fed);
    assert!(!watchdog.expired(fed.plus(13)));
    assert!(watchdog.expired(fed.plus(14)));
    assert_eq!(watchdog.age_ticks(Tick(3)), Some(9));
}

#[test]
fn the_reports_smoothing_in_ticks() {
    // u += rate · (target − u) · dt with rate 8 /s at 250 Hz: α = 0.032.
    let smoother = Smoother::new(8.0, TickRate::SIM_250_HZ);
    assert!((smoother.alpha() - 0.032).abs() < 1e-6);
    assert!((smoother.step(0.0, 1.0) - 0.032).abs() < 1e-6);
    // One second at 1 kHz and at 250 Hz reach nearly the same point (1 − e^−8).
    let run = |rate: TickRate| {
        let smoother = Smoother::new(8.0, rate);
        (0..rate.hz()).fold(0.0f32, |u, _| smoother.step(u, 1.0))
    };
    let (fast, slow) = (run(TickRate::MCU_1_KHZ), run(TickRate::SIM_250_HZ));
    assert!((fast - (1.0 - (-8.0f32).exp())).abs() < 2e-3);
    assert!((fast - slow).abs() < 2e-3);
    // Rates that would overshoot in one tick are capped, and NaN holds.
    assert_eq!(Smoother::new(1e6, TickRate::SIM_250_HZ).alpha(), 1.0);
    assert_eq!(Smoother::new(f32::NAN, TickRate::SIM_250_HZ).alpha(), 0.0);
}
