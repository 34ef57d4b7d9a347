//! The controller tells the attitude estimator when the legs stride
//! (`firmware::control::estimator::Motion::striding`), on an ideal plant whose IMU reports a
//! trot's bounce and rocking: knocked 10° off by a gyro glitch mid-trot, the estimate comes
//! back while the robot trots (the accelerometer read over a stride), and stays off while it
//! stands and the torso bounces and rocks alike (read sample by sample, they leave it
//! untrusted).

mod common;

use common::bench::{ms, Bench};
use common::{command, velocity_command, Ticks};

use firmware::control::fsm::{Direction, LegMotion, State};
use protocol::{Acceleration, AngularRate, AnyMessage, Imu, TeleopMode};

/// The bounce: ±0.3 g along the torso's up at the trot's 2 Hz step rate.
const BOUNCE_G: f32 = 0.3;

/// The rocking: ±3° of pitch at the same rate.
const ROCK_RAD: f32 = 0.052;

/// Runs `bench` for `ticks`, its IMU reporting a torso rocking [`ROCK_RAD`] and bouncing
/// [`BOUNCE_G`], and for the first `glitch_ticks` a pitch rate 1.745 rad/s more than the torso
/// makes; how far the estimated pitch is off the torso's at the end, degrees.
fn bouncing(bench: &mut Bench, ticks: u32, glitch_ticks: u32) -> f32 {
    bench.imu_alive = false;
    let (g, step_rad_s) = (9.806_65, 4.0 * core::f32::consts::PI);
    let mut pitch_rad = 0.0;
    for n in 0..ticks {
        let t_s = bench.now as f32 * bench.controller.config().rate.period_s();
        let (sin, cos) = (step_rad_s * t_s).sin_cos();
        pitch_rad = ROCK_RAD * sin;
        let up_m_s2 = g * (1.0 + BOUNCE_G * sin);
        let glitch = if n < glitch_ticks { 1.745 } else { 0.0 };
        let sample = Imu {
            angular_rate: [0.0, ROCK_RAD * step_rad_s * cos + glitch, 0.0]
                .map(AngularRate::saturating_from_si),
            acceleration: [-up_m_s2 * pitch_rad.sin(), 0.0, up_m_s2 * pitch_rad.cos()]
                .map(Acceleration::saturating_from_si),
        };
        bench.send(AnyMessage::Imu(sample));
        bench.tick();
    }
    (bench.controller.sensors().attitude.pitch_rad - pitch_rad).to_degrees()
}

/// A ready bench standing for 2 s, then `mode`.
fn stood_then(mode: TeleopMode) -> Bench {
    let mut bench = Bench::ready();
    bench.send(command(TeleopMode::Stand));
    bench.run(ms(2_000));
    bench.send(command(mode));
    bench.run(1);
    bench
}

#[test]
fn a_trotting_robot_knocked_off_comes_back_a_standing_one_bouncing_does_not() {
    let mut trotting = stood_then(TeleopMode::TrotBackward);
    assert_eq!(
        trotting.state(),
        State::Legs(LegMotion::Trot(Direction::Backward))
    );
    bouncing(&mut trotting, ms(1_000), 0);
    let knocked = bouncing(&mut trotting, ms(100), ms(100));
    assert!(knocked.abs() > 8.0, "the glitch: {knocked:.1}°");
    let trotted = bouncing(&mut trotting, ms(10_000), 0);
    let mut standing = stood_then(TeleopMode::Stand);
    bouncing(&mut standing, ms(1_000), 0);
    bouncing(&mut standing, ms(100), ms(100));
    let stood = bouncing(&mut standing, ms(10_000), 0);
    println!("10 s after a 10° glitch, bouncing: trotting {trotted:.2}°, standing {stood:.2}°");
    assert!(trotted.abs() < 1.5, "trotting: {trotted:.2}°");
    assert!(stood.abs() > 5.0, "standing: {stood:.2}°");
    assert_eq!(
        trotting.state(),
        State::Legs(LegMotion::Trot(Direction::Backward))
    );
}

/// How far off the estimate is 10 s after a 10° glitch, degrees, in a walk at no speed turning
/// at `yaw_rate_rad_s`.
fn walking_at_no_speed(yaw_rate_rad_s: f32) -> f32 {
    let mut bench = stood_then(TeleopMode::Stand);
    bench.send(velocity_command(TeleopMode::Walk, 0.0, yaw_rate_rad_s));
    bench.run(1);
    assert_eq!(bench.state(), State::Legs(LegMotion::Walk));
    bouncing(&mut bench, ms(1_000), 0);
    bouncing(&mut bench, ms(100), ms(100));
    bouncing(&mut bench, ms(10_000), 0)
}

/// A walk at no speed that turns on the spot lifts its feet: it strides as far as the estimator
/// is concerned; one that neither travels nor turns marks time with its feet down, and does not.
#[test]
fn a_walk_turning_on_the_spot_strides_one_marking_time_does_not() {
    let (turned, marked) = (walking_at_no_speed(0.5), walking_at_no_speed(0.0));
    println!("10 s after a 10° glitch: walk turning {turned:.2}°, marking time {marked:.2}°");
    assert!(turned.abs() < 1.5, "turning: {turned:.2}°");
    assert!(marked.abs() > 5.0, "marking time: {marked:.2}°");
}
