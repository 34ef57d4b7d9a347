//! The joint-space ramp's time warp: a warped move starts and ends where and as the plain one
//! does (at rest), and takes its middle slower.

use firmware::legs::ramp::Ramp;
use firmware::time::Tick;
use protocol::Joints;

const TICKS: u32 = 200;

fn ramp() -> Ramp {
    Ramp::over(Joints::splat(0.0), Joints::splat(1.0), Tick(0), TICKS)
}

/// The first joint's value at tick `t` with warp `slow`.
fn at(slow: f32, t: u32) -> f32 {
    let (pose, _) = ramp().at_warped(Tick(t), slow);
    pose.iter().next().copied().unwrap_or(f32::NAN)
}

#[test]
fn no_warp_is_the_plain_smoothstep() {
    for t in [0, 1, 50, 100, 150, 199, 200, 250] {
        let u = (t.min(TICKS) as f32) / TICKS as f32;
        let smoothstep = u * u * (3.0 - 2.0 * u);
        assert!((at(0.0, t) - smoothstep).abs() < 1e-6, "tick {t}");
        assert_eq!(ramp().at(Tick(t)), ramp().at_warped(Tick(t), 0.0));
    }
}

#[test]
fn a_warped_ramp_ends_where_the_plain_one_does_and_at_rest() {
    for slow in [0.25, 0.5, 1.0] {
        assert_eq!(at(slow, 0), 0.0);
        assert_eq!(at(slow, TICKS), 1.0);
        assert!(
            ramp().at_warped(Tick(TICKS), slow).1,
            "over at its last tick"
        );
        assert!((at(slow, 100) - 0.5).abs() < 1e-6, "half way at half time");
        // At rest at both ends: the first and last ticks move far less than an even pace's
        // 1/200 (a fifth of it at most).
        assert!(
            at(slow, 1) < 0.2 / TICKS as f32,
            "slow {slow}: {}",
            at(slow, 1)
        );
        assert!(1.0 - at(slow, TICKS - 1) < 0.2 / TICKS as f32);
        // Monotonic.
        let mut last = 0.0;
        for t in 1..=TICKS {
            let x = at(slow, t);
            assert!(x >= last, "slow {slow}: tick {t} went back");
            last = x;
        }
    }
}

#[test]
fn the_middle_of_a_warped_ramp_goes_slower_by_the_warp() {
    let middle = |slow: f32| at(slow, 110) - at(slow, 90);
    let (plain, warped) = (middle(0.0), middle(0.5));
    // Over the middle tenth the smoothstep goes at 1.5 times an even pace; the warp halves it.
    assert!((warped / plain - 0.5).abs() < 0.02, "{warped} vs {plain}");
}

#[test]
fn a_warp_out_of_range_is_clamped() {
    for t in [0, 37, 100, 163, 200] {
        assert_eq!(at(-1.0, t), at(0.0, t));
        assert_eq!(at(2.0, t), at(1.0, t));
    }
}
