//! The controlled stop's sequence on its own (`firmware::control::stop::Stop`), tick by tick:
//! the poses it commands and when, for a robot that is at rest when the latch comes. The
//! closed-loop figures (descent, tilt, time to rest) are `sim-host/tests/estop_ss1.rs`'s.

use firmware::config::Config;
use firmware::control::safety::SS1_DEADLINE_MS;
use firmware::control::stop::{Carrier, Stop, StopCommand, StopInput};
use firmware::legs::kinematics::leg_fk;
use firmware::legs::ramp::ramp_ticks;
use firmware::time::Tick;
use protocol::{Joints, Leg};

const CONFIG: Config = Config::ROBOT;

/// A leg pose for all four legs.
fn all(pose: [f32; 4]) -> Joints<f32> {
    Joints::from_leg_fn(|_| pose)
}

/// A fold pose (abduction, hip pitch, knee, ankle), rad: the legs tucked.
const FOLD: [f32; 4] = [0.0, 1.2, -2.0, 0.3];

/// A standing pose, rad.
const STAND: [f32; 4] = [0.0, 0.5, -1.0, 0.5];

/// What the robot measures `k` ticks after the latch at `start`: at rest.
fn at_rest(start: Tick, k: u32) -> StopInput {
    StopInput {
        now: start.plus(k),
        speeds_m_s: [0.0; 2],
        braked: true,
        fault: false,
    }
}

/// Runs `stop`, latched at `start` on a robot at rest, until it commands every drive off; the
/// poses it servoed to, one per tick from the latch.
fn poses_until_off(stop: &mut Stop, start: Tick) -> Vec<Joints<f32>> {
    poses_until_off_with(stop, |k| at_rest(start, k))
}

/// The same with what the robot measures `k` ticks after the latch given by `input`.
fn poses_until_off_with(stop: &mut Stop, input: impl Fn(u32) -> StopInput) -> Vec<Joints<f32>> {
    let mut poses = Vec::new();
    for k in 0..CONFIG.rate.ticks_from_ms(2 * SS1_DEADLINE_MS) {
        match stop.step(&input(k)) {
            StopCommand::Servo(pose) => poses.push(pose),
            StopCommand::Off => return poses,
        }
    }
    panic!("the stop never cut the torque");
}

/// The cut comes before the SS1 deadline, by the configured margin.
fn assert_off_before_the_deadline(poses: &[Joints<f32>]) {
    let deadline = CONFIG
        .rate
        .ticks_from_ms(SS1_DEADLINE_MS - CONFIG.stop.cut_margin_ms);
    assert!(
        poses.len() as u32 <= deadline,
        "off after {} ticks",
        poses.len()
    );
}

/// The last pose is the kickstand (which it returns).
fn assert_settled_in_the_kickstand(poses: &[Joints<f32>]) -> Joints<f32> {
    let kickstand = CONFIG.stop.kickstand();
    let last = poses.last().expect("poses");
    assert_close(last, &kickstand, 1e-5, "the settled pose");
    kickstand
}

fn assert_close(a: &Joints<f32>, b: &Joints<f32>, tolerance: f32, what: &str) {
    for (x, y) in a.iter().zip(b.iter()) {
        assert!((x - y).abs() <= tolerance, "{what}: {a:?} against {b:?}");
    }
}

#[test]
fn from_the_wheels_the_front_legs_swing_out_midway_and_every_leg_ends_in_the_kickstand() {
    let start = Tick(u32::MAX - 100);
    let fold = all(FOLD);
    let mut stop = Stop::new(CONFIG.stop, CONFIG.rate, start, fold, fold, Carrier::Wheels);
    let poses = poses_until_off(&mut stop, start);
    assert_off_before_the_deadline(&poses);
    assert_settled_in_the_kickstand(&poses);
    // Fold and kickstand both have no abduction: what abduction there is, is the swing out.
    let abduction = |pose: &Joints<f32>, leg: Leg| pose.leg(leg)[0];
    let spread = CONFIG.stop.kickstand_spread_rad;
    let widest = poses
        .iter()
        .map(|pose| abduction(pose, Leg::Fl))
        .fold(f32::MIN, f32::max);
    assert!(
        (widest - spread).abs() < 0.01 * spread,
        "front left swung out {widest} rad, not {spread}"
    );
    for pose in &poses {
        // Outward is positive on the left, negative on the right; the back legs stay in plane.
        let left = abduction(pose, Leg::Fl);
        assert!(left >= 0.0 && left <= spread + 1e-6, "{pose:?}");
        assert!((abduction(pose, Leg::Fr) + left).abs() < 1e-6, "{pose:?}");
        assert_eq!(abduction(pose, Leg::Bl), 0.0);
        assert_eq!(abduction(pose, Leg::Br), 0.0);
    }
}

#[test]
fn the_kickstand_puts_the_front_feet_ahead_of_the_hips_and_the_back_feet_behind() {
    let geometry = &CONFIG.geometry;
    let front = leg_fk(geometry, &CONFIG.stop.kickstand_front);
    let back = leg_fk(geometry, &CONFIG.stop.kickstand_back);
    assert!(front.x_m > 0.1, "front foot {front:?}");
    assert!(back.x_m < -0.1, "back foot {back:?}");
    for foot in [front, back] {
        assert!(foot.z_m < 0.0, "below the hip: {foot:?}");
    }
}

#[test]
fn from_the_legs_the_sit_down_rises_first_at_the_fastest_rate_then_lowers_slowly() {
    let start = Tick(7);
    let (stand, fold) = (all(STAND), all(FOLD));
    let mut stop = Stop::new(CONFIG.stop, CONFIG.rate, start, stand, fold, Carrier::Legs);
    let poses = poses_until_off(&mut stop, start);
    assert_off_before_the_deadline(&poses);
    let kickstand = assert_settled_in_the_kickstand(&poses);
    // The rise: the first share of the straight way, over a ramp at the kickstand's rate.
    let share = CONFIG.stop.sit_rise_share;
    let risen = Joints::from_leg_fn(|leg| {
        let (from, to) = (stand.leg(leg), kickstand.leg(leg));
        core::array::from_fn(|j| from[j] + share * (to[j] - from[j]))
    });
    let rise_ticks = ramp_ticks(
        &stand,
        &risen,
        CONFIG.stop.kickstand_rate_rad_s,
        CONFIG.rate,
    );
    let at_rise_end = poses
        .get(rise_ticks as usize)
        .expect("the rise ends before the cut");
    assert_close(at_rise_end, &risen, 1e-4, "the end of the rise");
    // The rest of the way takes what the deadline leaves, less the settle time: much slower.
    let period_s = CONFIG.rate.period_s();
    let fastest = |poses: &[Joints<f32>]| {
        poses
            .windows(2)
            .flat_map(|w| {
                w[0].iter()
                    .zip(w[1].iter())
                    .map(|(a, b)| (b - a).abs() / period_s)
                    .collect::<Vec<_>>()
            })
            .fold(0.0_f32, f32::max)
    };
    let (rise, lower) = poses.split_at(rise_ticks as usize);
    let rate = CONFIG.stop.kickstand_rate_rad_s;
    assert!(fastest(rise) <= rate * 1.01 && fastest(rise) > 0.9 * rate);
    assert!(
        fastest(lower) < 0.5 * rate,
        "lowered at {} rad/s",
        fastest(lower)
    );
    let settle = CONFIG.rate.ticks_from_ms(CONFIG.stop.settle_ms) as usize;
    let settled = &poses[poses.len() - settle..];
    assert!(settled.iter().all(|pose| pose == &kickstand));
}

#[test]
fn on_the_wheels_the_kickstand_waits_until_the_robot_is_braked_and_neither_rolls_nor_turns() {
    let start = Tick(0);
    let fold = all(FOLD);
    let waiting = CONFIG.rate.ticks_from_ms(300);
    let slow = 0.5 * CONFIG.stop.rest_speed_m_s;
    let fast = 2.0 * CONFIG.stop.rest_speed_m_s;
    for (what, speeds_m_s, braked) in [
        ("rolling", [fast, 0.0], true),
        ("turning", [0.0, fast], true),
        ("still braking", [slow, slow], false),
        // At rest is below the rest speed.
        (
            "rolling at the rest speed",
            [CONFIG.stop.rest_speed_m_s, 0.0],
            true,
        ),
        (
            "turning at the rest speed",
            [0.0, -CONFIG.stop.rest_speed_m_s],
            true,
        ),
    ] {
        let mut stop = Stop::new(CONFIG.stop, CONFIG.rate, start, fold, fold, Carrier::Wheels);
        assert!(
            !stop.holds_wheels(),
            "{what}: a robot on its wheels balances"
        );
        let poses = poses_until_off_with(&mut stop, |k| StopInput {
            speeds_m_s: if k < waiting { speeds_m_s } else { [slow; 2] },
            braked: braked || k >= waiting,
            ..at_rest(start, k)
        });
        let first_move = poses.iter().position(|pose| pose != &fold);
        assert_eq!(first_move, Some(waiting as usize + 1), "{what}");
        assert!(
            !stop.holds_wheels(),
            "{what}: a robot on its wheels balances"
        );
    }
}

#[test]
fn against_an_obstacle_the_wheels_hold_still_until_the_torque_goes() {
    let start = Tick(0);
    let fold = all(FOLD);
    let mut stop = Stop::new(
        CONFIG.stop,
        CONFIG.rate,
        start,
        fold,
        fold,
        Carrier::Blocked,
    );
    assert!(stop.holds_wheels());
    let poses = poses_until_off(&mut stop, start);
    assert!(!stop.holds_wheels(), "torque-free: nothing holds");
    // The back legs go into the kickstand; the front legs stay folded (swung forward they
    // would push the robot off the obstacle).
    let last = poses.last().expect("poses");
    let kickstand = CONFIG.stop.kickstand();
    for leg in [Leg::Bl, Leg::Br] {
        assert_eq!(last.leg(leg), kickstand.leg(leg));
    }
    for leg in [Leg::Fl, Leg::Fr] {
        assert_eq!(last.leg(leg), fold.leg(leg));
    }
}

#[test]
fn a_robot_that_never_comes_to_rest_still_ends_in_the_kickstand_before_the_cut() {
    let start = Tick(3);
    let fold = all(FOLD);
    let mut stop = Stop::new(CONFIG.stop, CONFIG.rate, start, fold, fold, Carrier::Wheels);
    let rolling = 2.0 * CONFIG.stop.rest_speed_m_s;
    let poses = poses_until_off_with(&mut stop, |k| StopInput {
        speeds_m_s: [rolling, 0.0],
        ..at_rest(start, k)
    });
    assert_off_before_the_deadline(&poses);
    // It brakes as long as the kickstand leaves time for, then sits down at the fastest rate.
    let kickstand = assert_settled_in_the_kickstand(&poses);
    let first_move = poses.iter().position(|pose| pose != &fold).expect("moved");
    let needed = ramp_ticks(
        &fold,
        &kickstand,
        CONFIG.stop.kickstand_rate_rad_s,
        CONFIG.rate,
    ) + CONFIG.rate.ticks_from_ms(CONFIG.stop.settle_ms);
    let latest = poses.len() as u32 - needed;
    assert!(
        (first_move as u32).abs_diff(latest) <= 2,
        "the kickstand began at tick {first_move} of {}, not at the latest ({latest})",
        poses.len()
    );
}
