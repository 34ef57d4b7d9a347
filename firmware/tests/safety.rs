//! The safety layer's small parts, each held to what it reports: the clamps say when they had
//! to replace a value that was not a number, a watchdog says whether it was ever fed, the link
//! monitor says degraded only on a lossy link. (These pin down answers that mutation testing
//! found no test looking at: see docs/faults.md, `cargo xtask mutants`.)

use firmware::control::safety::{clamp_leg_targets, clamp_wheel_torques, Watchdog};
use firmware::node::link::LinkMonitor;
use firmware::{Config, Tick};
use protocol::{E2eStatus, Joints};

#[test]
fn clamping_reports_a_replaced_non_finite_value_and_nothing_else() {
    let limits = Config::ROBOT.limits;
    let fallback = Joints::splat(0.1_f32);
    // In range, and out of range: clamped silently, nothing replaced.
    for value in [0.0_f32, 0.2, 9.0, -9.0] {
        let mut targets = Joints::splat(value);
        assert!(
            !clamp_leg_targets(&limits, &mut targets, &fallback),
            "{value}"
        );
        assert!(targets.iter().all(|t| t.is_finite()));
    }
    let mut targets = Joints::splat(0.0_f32);
    *targets.get_mut(5).unwrap() = f32::NAN;
    assert!(clamp_leg_targets(&limits, &mut targets, &fallback));
    assert_eq!(targets.get(5), Some(&0.1));

    let mut torques = [12.0_f32, -80.0];
    assert!(!clamp_wheel_torques(30.0, &mut torques));
    assert_eq!(torques, [12.0, -30.0]);
    let mut torques = [f32::INFINITY, 1.0];
    assert!(clamp_wheel_torques(30.0, &mut torques));
    assert_eq!(torques, [0.0, 1.0]);
}

#[test]
fn a_watchdog_knows_whether_it_was_ever_fed() {
    let mut watchdog = Watchdog::new(10);
    assert!(!watchdog.ever_fed());
    watchdog.feed(Tick(3));
    assert!(watchdog.ever_fed());
}

#[test]
fn a_clean_link_is_not_degraded() {
    let mut link = LinkMonitor::new(10, 100, 30).unwrap();
    assert!(!link.degraded());
    for tick in 0..50 {
        link.record(E2eStatus::Ok);
        assert!(!link.update(Tick(tick)));
    }
    assert!(!link.degraded());
    assert_eq!(link.last_loss_permille(), Some(0));
}
