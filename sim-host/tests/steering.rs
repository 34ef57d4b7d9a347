//! Steering (`firmware::control::steering`): a curve on the wheels and a turning trot, on the
//! campaign's robots as built (`campaign::draw`: varied body, drives rated, the IMU chip's
//! offsets, transport delay).
//!
//! `cargo test --release -p sim-host --test steering -- --nocapture` prints the figures.

use firmware::control::fsm::State;
use host_can::fault_plan::Faults;
use protocol::TeleopMode;
use sim_host::campaign::draw::Draws;
use sim_host::campaign::Drives;
use sim_host::faults::rig::Rig;
use sim_host::robot::model::DEFAULT_MODEL;
use sim_host::robot::rotation::rpy_rad;
use teleop_core::scripted::PlanStep;

/// The least-squares circle through `points` (Kåsa's fit): centre, radius, and the RMS of the
/// points' distances from it, m.
fn fit_circle(points: &[[f64; 2]]) -> ([f64; 2], f64, f64) {
    // x² + y² + D x + E y + F = 0, linear in D, E, F: the normal equations.
    let mut a = [[0.0_f64; 3]; 3];
    let mut b = [0.0_f64; 3];
    for &[x, y] in points {
        let row = [x, y, 1.0];
        let rhs = -(x * x + y * y);
        for i in 0..3 {
            for j in 0..3 {
                a[i][j] += row[i] * row[j];
            }
            b[i] += row[i] * rhs;
        }
    }
    let [d, e, f] = solve3(a, b);
    let centre = [-d / 2.0, -e / 2.0];
    let radius = (centre[0] * centre[0] + centre[1] * centre[1] - f).sqrt();
    let mean_square = points
        .iter()
        .map(|p| {
            let r = ((p[0] - centre[0]).powi(2) + (p[1] - centre[1]).powi(2)).sqrt();
            (r - radius).powi(2)
        })
        .sum::<f64>()
        / points.len() as f64;
    (centre, radius, mean_square.sqrt())
}

/// `a x = b` by Cramer's rule (the fit's 3 × 3 normal equations are well conditioned for a
/// turn's worth of points).
fn solve3(a: [[f64; 3]; 3], b: [f64; 3]) -> [f64; 3] {
    let det = |m: [[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let whole = det(a);
    let mut x = [0.0; 3];
    for (k, xk) in x.iter_mut().enumerate() {
        let mut m = a;
        for (row, bi) in m.iter_mut().zip(b) {
            row[k] = bi;
        }
        *xk = det(m) / whole;
    }
    x
}

/// What a steered run did.
#[derive(Debug)]
struct Turn {
    seed: u64,
    /// Radius of the best-fit circle, m, and the points' RMS distance from it.
    radius_m: f64,
    residual_m: f64,
    /// Heading change over the measured window, rad (unwrapped).
    heading_rad: f64,
    max_tilt_deg: f64,
    max_roll_deg: f64,
    max_pitch_deg: f64,
    fell: bool,
    /// The controller's state at the end.
    state: Option<State>,
}

/// Runs `plan` on campaign robot `seed` and measures from `from_s` to `until_s`.
fn run(seed: u64, plan: Vec<PlanStep>, from_s: f64, until_s: f64) -> Turn {
    let plant = Draws::of(seed).plant(Drives::Rated.ratings());
    let faults = Faults::default();
    let model = std::path::Path::new(DEFAULT_MODEL);
    let mut rig = Rig::with_plant(model, plan, &faults, &faults, plant).unwrap();
    rig.run_until(from_s).unwrap();
    let mut points = Vec::new();
    let (mut heading_rad, mut last_yaw) = (0.0, None::<f64>);
    let (mut max_tilt_deg, mut max_roll_deg, mut max_pitch_deg) = (0.0_f64, 0.0_f64, 0.0_f64);
    let mut fell = false;
    while rig.time_s() < until_s {
        rig.step().unwrap();
        let torso = rig.sim().physics().torso();
        let [roll, pitch, yaw] = rpy_rad(torso.quat_wxyz);
        if let Some(last) = last_yaw {
            let mut change = yaw - last;
            change -= (change / std::f64::consts::TAU).round() * std::f64::consts::TAU;
            heading_rad += change;
        }
        last_yaw = Some(yaw);
        points.push([torso.pos_m[0], torso.pos_m[1]]);
        let record = rig.records().last().unwrap();
        max_tilt_deg = max_tilt_deg.max(record.tilt_deg);
        max_roll_deg = max_roll_deg.max(roll.to_degrees().abs());
        max_pitch_deg = max_pitch_deg.max(pitch.to_degrees().abs());
        fell |= record.fallen();
    }
    let (_, radius_m, residual_m) = fit_circle(&points);
    Turn {
        seed,
        radius_m,
        residual_m,
        heading_rad,
        max_tilt_deg,
        max_roll_deg,
        max_pitch_deg,
        fell,
        state: rig.records().last().and_then(|r| r.state),
    }
}

#[test]
fn the_circle_fit_finds_a_known_circle() {
    let points: Vec<[f64; 2]> = (0..100)
        .map(|i| {
            let a = i as f64 * 0.07;
            [2.0 + 1.5 * a.cos(), -1.0 + 1.5 * a.sin()]
        })
        .collect();
    let (centre, radius, residual) = fit_circle(&points);
    assert!((centre[0] - 2.0).abs() < 1e-9 && (centre[1] + 1.0).abs() < 1e-9);
    assert!((radius - 1.5).abs() < 1e-9 && residual < 1e-9);
}

/// From a steady W at 0.3 m/s (62.5 % of its 0.48 m/s), a yaw rate of 0.3 rad/s: one full
/// turn on a circle of v / ω = 1 m. Half the trials steer W (the keys' `←`), half `drive` at
/// 0.3 m/s (a gamepad's sticks).
#[test]
fn a_curve_on_the_wheels_follows_its_circle() {
    const YAW_RAD_S: f32 = 0.3;
    const TURN_AT_S: f64 = 10.0;
    // The turn rate is slewed in and the speed steady by then; one full turn from there.
    let from_s = TURN_AT_S + 2.0;
    let until_s = from_s + std::f64::consts::TAU / f64::from(YAW_RAD_S);
    let mut failures = Vec::new();
    for seed in 0..8 {
        let steady = PlanStep::at(4.0, TeleopMode::WheelForward).with_speed_scale(62.5);
        let turn = if seed % 2 == 0 {
            PlanStep {
                yaw_rate_rad_s: YAW_RAD_S,
                ..PlanStep::at(TURN_AT_S, TeleopMode::WheelForward)
            }
            .with_speed_scale(62.5)
        } else {
            PlanStep::at(TURN_AT_S, TeleopMode::Drive).with_velocity(0.3, YAW_RAD_S)
        };
        let plan = vec![PlanStep::at(0.0, TeleopMode::Fold), steady, turn];
        let t = run(seed, plan, from_s, until_s);
        println!("MEASURED curve 0.3 m/s, 0.3 rad/s, robot {}: {t:?}", t.seed);
        let turned_once = (t.heading_rad - std::f64::consts::TAU).abs() < 0.6;
        if !((t.radius_m - 1.0).abs() <= 0.1
            && t.residual_m <= 0.05
            && t.max_tilt_deg <= 10.0
            && turned_once
            && matches!(t.state, Some(State::Wheels(motion)) if motion.moving())
            && !t.fell)
        {
            failures.push(t);
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// A trot steered at 0.3 rad/s, walking (`L` with the keys' steering) and turning on the spot
/// (`walk` at no speed): the heading changes by at least 45° in 8 s, roll and pitch within
/// 15°.
#[test]
fn a_turning_trot_turns() {
    const YAW_RAD_S: f32 = 0.3;
    const TURN_AT_S: f64 = 2.0;
    let mut failures = Vec::new();
    for seed in 0..8 {
        let turn = if seed % 2 == 0 {
            PlanStep {
                yaw_rate_rad_s: YAW_RAD_S,
                ..PlanStep::at(TURN_AT_S, TeleopMode::TrotForward)
            }
        } else {
            PlanStep::at(TURN_AT_S, TeleopMode::Walk).with_velocity(0.0, -YAW_RAD_S)
        };
        let plan = vec![PlanStep::at(0.0, TeleopMode::Stand), turn];
        let t = run(seed, plan, TURN_AT_S, TURN_AT_S + 8.0);
        println!(
            "MEASURED turning trot 0.3 rad/s for 8 s, robot {}: {t:?}",
            t.seed
        );
        if !(t.heading_rad.abs() >= 45_f64.to_radians()
            && t.heading_rad.signum() == f64::from(turn.yaw_rate_rad_s).signum()
            && t.max_roll_deg <= 15.0
            && t.max_pitch_deg <= 15.0
            && matches!(t.state, Some(State::Legs(motion)) if motion.trotting())
            && !t.fell)
        {
            failures.push(t);
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}
