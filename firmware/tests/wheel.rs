//! The turn loop's anti-windup and the torque mixer.

use firmware::wheels::wheel::{mix, SpeedLoop, SpeedLoopGains};

const GAINS: SpeedLoopGains = SpeedLoopGains::TURN;

#[test]
fn a_long_saturation_does_not_wind_up_the_integral() {
    let mut with = SpeedLoop::new(GAINS);
    // A wheel held still while asked for 4 rad/s for ten seconds: saturated throughout.
    for _ in 0..2500 {
        assert!(with.update(4.0, 0.004).abs() <= GAINS.limit_nm);
    }
    assert!(with.integral_nm().abs() <= GAINS.limit_nm);
    // Released: the error reverses, and the torque must reverse within a few ticks, not after
    // unwinding ten seconds of integral.
    let mut ticks = 0;
    while with.update(-1.0, 0.004) > 0.0 {
        ticks += 1;
        assert!(ticks < 250, "still pushing after {ticks} ticks");
    }
    // (A naive integrator would hold 10 s × 4 rad/s × ki = 240 N·m and push for seconds.)
}

#[test]
fn the_loop_reaches_its_speed_with_zero_steady_error() {
    // A wheel with inertia 0.05 kg·m² and viscous friction 0.5 N·m·s: the integral removes the
    // friction's steady error.
    let mut speed_loop = SpeedLoop::new(GAINS);
    let (inertia, friction, dt) = (0.05f32, 0.5f32, 0.004f32);
    let mut speed = 0.0f32;
    for _ in 0..2500 {
        let torque = speed_loop.update(4.0 - speed, dt);
        speed += (torque - friction * speed) / inertia * dt;
    }
    assert!((speed - 4.0).abs() < 0.01, "speed {speed} rad/s");
}

#[test]
fn mixing_saturates_each_wheel_and_rejects_non_finite_input() {
    assert_eq!(mix(10.0, 2.0, 30.0), (7.0, 3.0));
    assert_eq!(mix(100.0, 20.0, 30.0), (30.0, 30.0));
    assert_eq!(mix(0.0, 50.0, 30.0), (30.0, -30.0));
    assert_eq!(mix(f32::NAN, 1.0, 30.0), (1.0, -1.0));
    assert_eq!(mix(1.0, f32::INFINITY, f32::NAN), (0.0, 0.0));
    let mut speed_loop = SpeedLoop::new(GAINS);
    assert_eq!(speed_loop.update(f32::NAN, 0.004), 0.0);
    assert_eq!(speed_loop.integral_nm(), 0.0);
}
