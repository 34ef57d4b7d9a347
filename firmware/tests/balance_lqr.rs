//! The balance law's design: LQR on the linear wheeled-pendulum model of `firmware::wheels::balance`,
//! solved here on the host with `nalgebra`. Fails when the committed gains are stale (and
//! prints the new ones), and checks the firmware's own `Balance` on the model.

use firmware::config::Config;
use firmware::wheels::balance::{
    Balance, BalanceConfig, BalanceGains, BalanceInput, BalanceModel, DESIGN_DELAY_TICKS,
};
use nalgebra::{DMatrix, Matrix4, Matrix4x1, SMatrix};
use std::ops::AddAssign;

const GRAVITY: f64 = 9.81;
const DT_S: f64 = 0.004;

/// Continuous model `ẋ = A x + B τ`, states `[p, θ, v, θ̇]`.
fn continuous(model: &BalanceModel) -> (Matrix4<f64>, Matrix4x1<f64>) {
    let m = model.body_mass_kg as f64;
    let l = model.com_height_m as f64;
    let r = model.wheel_radius_m as f64;
    let mass = nalgebra::Matrix2::new(
        m + model.wheel_mass_kg as f64 + model.wheel_inertia_kg_m2 as f64 / (r * r),
        m * l,
        m * l,
        model.body_pitch_inertia_kg_m2 as f64 + m * l * l,
    );
    let inverse = mass
        .try_inverse()
        .expect("mass matrix is positive definite");
    let gravity = inverse * nalgebra::Vector2::new(0.0, m * GRAVITY * l);
    let input = inverse * nalgebra::Vector2::new(1.0 / r, -1.0);
    let mut a = Matrix4::zeros();
    a[(0, 2)] = 1.0;
    a[(1, 3)] = 1.0;
    a[(2, 1)] = gravity[0];
    a[(3, 1)] = gravity[1];
    let b = Matrix4x1::new(0.0, 0.0, input[0], input[1]);
    (a, b)
}

/// Zero-order-hold discretisation (Van Loan: exp of the augmented matrix).
fn discrete(a: &Matrix4<f64>, b: &Matrix4x1<f64>, dt: f64) -> (Matrix4<f64>, Matrix4x1<f64>) {
    let mut augmented = SMatrix::<f64, 5, 5>::zeros();
    augmented.fixed_view_mut::<4, 4>(0, 0).copy_from(&(a * dt));
    augmented.fixed_view_mut::<4, 1>(0, 4).copy_from(&(b * dt));
    let exp = augmented.exp();
    (
        exp.fixed_view::<4, 4>(0, 0).into_owned(),
        exp.fixed_view::<4, 1>(0, 4).into_owned(),
    )
}

/// The discrete model with an input delay of `delay` ticks: state `[x, τ_{k−1}, …, τ_{k−delay}]`,
/// the torque given now entering the register and the oldest one acting on the pendulum.
fn delayed(a: &Matrix4<f64>, b: &Matrix4x1<f64>, delay: usize) -> (DMatrix<f64>, DMatrix<f64>) {
    let n = 4 + delay;
    let mut ad = DMatrix::zeros(n, n);
    let mut bd = DMatrix::zeros(n, 1);
    ad.view_mut((0, 0), (4, 4)).copy_from(a);
    if delay == 0 {
        bd.view_mut((0, 0), (4, 1)).copy_from(b);
    } else {
        ad.view_mut((0, n - 1), (4, 1)).copy_from(b);
        bd[(4, 0)] = 1.0;
        for k in 1..delay {
            ad[(4 + k, 4 + k - 1)] = 1.0;
        }
    }
    (ad, bd)
}

/// Discrete LQR by iterating the Riccati equation to convergence: `K` of `u = −K z`.
fn lqr(a: &DMatrix<f64>, b: &DMatrix<f64>, q: &DMatrix<f64>, r: f64) -> Vec<f64> {
    let r = DMatrix::from_element(1, 1, r);
    let gain = |p: &DMatrix<f64>| {
        (&r + b.transpose() * p * b).try_inverse().expect("R > 0") * b.transpose() * p * a
    };
    let mut p = q.clone();
    for _ in 0..200_000 {
        let k = gain(&p);
        let next = q + a.transpose() * &p * (a - b * &k);
        let change = (&next - &p).abs().max();
        p = next;
        if change < 1e-12 * p.abs().max() {
            break;
        }
    }
    gain(&p).iter().copied().collect()
}

/// Bryson's rule: each state and the input weighted by 1 / (its largest acceptable value)²;
/// the past torques of the delayed model carry no weight of their own.
fn bryson(delay: usize) -> (DMatrix<f64>, f64) {
    let weight = |largest: f64| 1.0 / (largest * largest);
    let mut q = DMatrix::zeros(4 + delay, 4 + delay);
    for (i, largest) in [0.15, 0.1, 0.3, 1.0].into_iter().enumerate() {
        q[(i, i)] = weight(largest);
    }
    (q, weight(30.0))
}

fn discrete_model() -> (Matrix4<f64>, Matrix4x1<f64>) {
    let (a, b) = continuous(&BalanceModel::ROBOT);
    discrete(&a, &b, DT_S)
}

fn designed_gains() -> Vec<f64> {
    let (ad, bd) = discrete_model();
    let (a, b) = delayed(&ad, &bd, DESIGN_DELAY_TICKS);
    let (q, r) = bryson(DESIGN_DELAY_TICKS);
    lqr(&a, &b, &q, r)
}

/// The largest pole magnitude of the linear model under the committed gains with `delay`
/// ticks of loop delay (the law's past torques as it keeps them).
fn loop_radius(delay: usize) -> f64 {
    let (ad, bd) = discrete_model();
    let k = BalanceGains::ROBOT.to_array().map(f64::from);
    let kept = DESIGN_DELAY_TICKS;
    let n = 4 + delay.max(kept).max(1);
    // The register holds the last torques, newest first; the law reads the first `kept`, the
    // pendulum feels the one `delay` ticks old.
    let mut law = DMatrix::<f64>::zeros(1, n);
    for (j, gain) in k.iter().enumerate() {
        law[(0, j)] = -gain;
    }
    let mut a = DMatrix::<f64>::zeros(n, n);
    a.view_mut((0, 0), (4, 4)).copy_from(&ad);
    if delay == 0 {
        a.view_mut((0, 0), (4, n))
            .add_assign(&(DMatrix::from_column_slice(4, 1, bd.as_slice()) * &law));
    } else {
        a.view_mut((0, 4 + delay - 1), (4, 1)).add_assign(&bd);
    }
    a.row_mut(4).copy_from(&law);
    for j in 1..n - 4 {
        a[(4 + j, 4 + j - 1)] = 1.0;
    }
    a.complex_eigenvalues()
        .iter()
        .map(|l| l.norm())
        .fold(0.0, f64::max)
}

#[test]
fn committed_gains_match_the_lqr_design() {
    let designed = designed_gains();
    let committed = BalanceGains::ROBOT.to_array();
    let stale = designed
        .iter()
        .zip(committed)
        .any(|(d, c)| ((c as f64) - d).abs() > 1e-3 * d.abs().max(1.0));
    assert!(
        !stale,
        "BalanceGains::ROBOT is stale; the LQR design gives\n    position_nm_per_m: {:.4},\n    pitch_nm_per_rad: {:.4},\n    velocity_nm_per_m_s: {:.4},\n    pitch_rate_nm_per_rad_s: {:.4},\n    past_torque_nm_per_nm: [{:.4}, {:.4}],",
        designed[0], designed[1], designed[2], designed[3], designed[4], designed[5]
    );
}

#[test]
fn open_loop_is_unstable_and_closed_loop_is_stable() {
    let (ad, _) = discrete_model();
    assert!(
        ad.complex_eigenvalues().iter().any(|l| l.norm() > 1.0),
        "the pendulum must fall without control"
    );
    let radius = loop_radius(DESIGN_DELAY_TICKS);
    assert!(
        radius < 0.999,
        "closed-loop pole at {radius} with the design delay"
    );
}

/// The law is designed for a cycle each way; the campaign draws none to two, and the linear
/// model keeps a margin beyond: stable from no delay to twice the design's and more.
#[test]
fn the_loop_stays_stable_from_no_delay_to_three_times_the_design() {
    for delay in 0..=3 * DESIGN_DELAY_TICKS {
        let radius = loop_radius(delay);
        println!("{delay} ticks of loop delay: largest pole {radius:.4}");
        assert!(radius < 0.999, "{delay} ticks: pole at {radius}");
    }
}

/// Runs the firmware's `Balance` (f32) on the discrete linear model; returns the state
/// history `[p_true, θ, v, θ̇]` and the torques. The model's θ is the lean from the balance
/// point, which the IMU reads at the configured trim plus `trim_error_rad` (a robot whose
/// centre of mass is not where the trim says).
fn simulate(pitch0_rad: f64, velocity_ref_m_s: f32, seconds: f64) -> (Vec<[f64; 4]>, Vec<f32>) {
    simulate_off_trim(pitch0_rad, velocity_ref_m_s, seconds, 0.0).0
}

/// [`simulate`] with a trim error; also returns the learned trim at the end, rad.
#[allow(clippy::type_complexity)]
fn simulate_off_trim(
    pitch0_rad: f64,
    velocity_ref_m_s: f32,
    seconds: f64,
    trim_error_rad: f32,
) -> ((Vec<[f64; 4]>, Vec<f32>), f32) {
    drive_off_trim(pitch0_rad, |_| velocity_ref_m_s, seconds, trim_error_rad)
}

/// [`simulate_off_trim`] with the speed reference a function of time, s.
#[allow(clippy::type_complexity)]
fn drive_off_trim(
    pitch0_rad: f64,
    velocity_ref_m_s: impl Fn(f64) -> f32,
    seconds: f64,
    trim_error_rad: f32,
) -> ((Vec<[f64; 4]>, Vec<f32>), f32) {
    let (a, b) = continuous(&BalanceModel::ROBOT);
    let (ad, bd) = discrete(&a, &b, DT_S);
    let config = Config::ROBOT.balance;
    let mut balance = Balance::new(config);
    balance.set_trim_learning(true);
    balance.set_trim_following(true);
    let mut x = Matrix4x1::new(0.0, pitch0_rad, 0.0, 0.0);
    let r = BalanceModel::ROBOT.wheel_radius_m as f64;
    let mut states = Vec::new();
    let mut torques = Vec::new();
    for step in 0..(seconds / DT_S) as usize {
        let input = BalanceInput {
            pitch_rad: x[1] as f32 + config.pitch_trim_rad + trim_error_rad,
            pitch_rate_rad_s: x[3] as f32,
            wheel_rate_rad_s: (x[2] / r - x[3]) as f32,
            velocity_ref_m_s: velocity_ref_m_s(step as f64 * DT_S),
        };
        let torque = balance.update(&input, DT_S as f32);
        torques.push(torque);
        x = ad * x + bd * torque as f64;
        states.push([x[0], x[1], x[2], x[3]]);
    }
    ((states, torques), balance.pitch_trim_rad())
}

/// How far apart the robot's positions lie from `from_s` on, m.
fn travel_from(states: &[[f64; 4]], from_s: f64) -> f64 {
    let tail = &states[(from_s / DT_S) as usize..];
    let (low, high) = tail.iter().fold((f64::MAX, f64::MIN), |(lo, hi), s| {
        (lo.min(s[0]), hi.max(s[0]))
    });
    high - low
}

#[test]
fn learns_a_trim_error_at_rest_and_stops_drifting() {
    // An IMU mounted 5° off in pitch (or a centre of mass ~1.3 cm off): the fixed trim would
    // need a standing position error of 0.2 m; the learned one needs none.
    for error_deg in [5.0_f32, -5.0] {
        let error_rad = error_deg.to_radians();
        let ((states, _), learned) = simulate_off_trim(0.0, 0.0, 40.0, error_rad);
        let expected = Config::ROBOT.balance.pitch_trim_rad + error_rad;
        assert!(
            (learned - expected).abs() < 0.2_f32.to_radians(),
            "{error_deg}°: learned {learned} rad, expected {expected}"
        );
        // Over the last 30 s the robot stays within 5 cm.
        let moved_m = travel_from(&states, 10.0);
        assert!(moved_m < 0.05, "{error_deg}°: drifted {moved_m} m");
    }
}

#[test]
fn learns_a_trim_error_while_driving_and_the_stop_holds_its_place() {
    // The campaign's X after W: the fold leaves no time at rest, so the trim is learned on the
    // way. Without it the stop would roll k_θ/k_p · 4° ≈ 0.2 m after the robot came to rest.
    for error_deg in [4.0_f32, -4.0] {
        let error_rad = error_deg.to_radians();
        let reference = |t: f64| if t < 3.0 { 0.48 } else { 0.0 };
        let ((states, _), learned) = drive_off_trim(0.0, reference, 8.0, error_rad);
        let expected = Config::ROBOT.balance.pitch_trim_rad + error_rad;
        assert!(
            (learned - expected).abs() < 0.2_f32.to_radians(),
            "{error_deg}°: learned {learned} rad, expected {expected}"
        );
        // From a second after the stop's command on, the robot moves less than 5 cm.
        let moved_m = travel_from(&states, 4.0);
        assert!(moved_m < 0.05, "{error_deg}°: moved {moved_m} m");
    }
}

#[test]
fn the_lean_per_acceleration_is_the_linear_models() {
    // Mid-way through the speed reference's ramp the pendulum accelerates steadily; its lean
    // from the balance point is what the trim following takes out.
    let config = Config::ROBOT.balance;
    let (states, _) = simulate(0.0, 0.48, 1.2);
    let [_, lean_rad, _, _] = states[(1.0 / DT_S) as usize];
    let expected = config.lean_rad_per_m_s2 as f64 * config.accel_limit_m_s2 as f64;
    assert!(
        (lean_rad - expected).abs() < 0.1 * expected,
        "lean {lean_rad} rad, expected {expected} rad"
    );
}

#[test]
fn recovers_from_a_ten_degree_lean_within_the_torque_limit() {
    let (states, torques) = simulate(10f64.to_radians(), 0.0, 4.0);
    let limit = Config::ROBOT.balance.torque_limit_nm;
    assert!(torques.iter().all(|t| t.is_finite() && t.abs() <= limit));
    let last = states.last().unwrap();
    assert!(
        last[1].abs() < 0.5f64.to_radians(),
        "pitch after 4 s: {} rad",
        last[1]
    );
    assert!(last[2].abs() < 0.02, "speed after 4 s: {} m/s", last[2]);
    let max_pitch = states.iter().map(|s| s[1].abs()).fold(0.0, f64::max);
    assert!(
        max_pitch < 15f64.to_radians(),
        "overshoot to {max_pitch} rad"
    );
}

#[test]
fn tracks_the_reports_wheel_speed_while_staying_upright() {
    // The report's 4 rad/s on 0.12 m wheels: 0.48 m/s.
    let (states, _) = simulate(0.0, 0.48, 5.0);
    let last = states.last().unwrap();
    assert!(
        (last[2] - 0.48).abs() < 0.02,
        "speed after 5 s: {} m/s",
        last[2]
    );
    let max_pitch = states.iter().map(|s| s[1].abs()).fold(0.0, f64::max);
    assert!(max_pitch < 10f64.to_radians(), "tilted to {max_pitch} rad");
}

#[test]
fn saturates_and_stays_finite_when_it_cannot_win() {
    let config = BalanceConfig {
        gains: BalanceGains::ROBOT,
        ..Config::ROBOT.balance
    };
    let mut balance = Balance::new(config);
    for pitch in [1.5_f32, -1.5, 0.8, f32::NAN, f32::INFINITY, 0.0] {
        let torque = balance.update(
            &BalanceInput {
                pitch_rad: pitch,
                pitch_rate_rad_s: 3.0,
                wheel_rate_rad_s: 50.0,
                velocity_ref_m_s: 0.0,
            },
            0.004,
        );
        assert!(torque.is_finite() && torque.abs() <= config.torque_limit_nm);
        assert!(balance.position_error_m().abs() <= config.position_error_limit_m);
    }
}

/// Where a robot whose trim is `trim_error_rad` off its balance point (neither learned nor
/// followed, as in a stand-up) ends after resting 4 s, moving 15 cm ahead on a half-sine of
/// speed over 1.5 s and resting 4 s more, relative to where the move began, m.
fn moved_off_trim(trim_error_rad: f32, counting: bool) -> f64 {
    let (a, b) = continuous(&BalanceModel::ROBOT);
    let (ad, bd) = discrete(&a, &b, DT_S);
    let config = Config::ROBOT.balance;
    let mut balance = Balance::new(config);
    balance.set_counting(counting);
    let mut x = Matrix4x1::new(0.0, 0.0, 0.0, 0.0);
    let r = BalanceModel::ROBOT.wheel_radius_m as f64;
    let (rest_s, move_s, distance_m) = (4.0, 1.5, 0.15);
    let mut start_m = 0.0;
    for step in 0..((2.0 * rest_s + move_s) / DT_S) as usize {
        let t_s = step as f64 * DT_S - rest_s;
        if t_s.abs() < 0.5 * DT_S {
            start_m = x[0];
        }
        let reference = if (0.0..move_s).contains(&t_s) {
            distance_m / move_s * (1.0 - (std::f64::consts::TAU * t_s / move_s).cos())
        } else {
            0.0
        };
        let input = BalanceInput {
            pitch_rad: x[1] as f32 + config.pitch_trim_rad + trim_error_rad,
            pitch_rate_rad_s: x[3] as f32,
            wheel_rate_rad_s: (x[2] / r - x[3]) as f32,
            velocity_ref_m_s: reference as f32,
        };
        let torque = balance.update(&input, DT_S as f32);
        x = ad * x + bd * torque as f64;
    }
    x[0] - start_m
}

#[test]
fn a_counted_move_makes_its_distance_whatever_the_trim_error() {
    // A stand-up's roll ahead: its legs' stow moved the balance point 3° away from the trim.
    // Dropped at the move's start and end, the position error that held the robot was made
    // up again each time: k_θ/k_p · 3° ≈ 0.15 m off, twice over. Counted, the move is 15 cm.
    for error_deg in [3.0_f32, -3.0] {
        let counted_m = moved_off_trim(error_deg.to_radians(), true);
        assert!(
            (counted_m - 0.15).abs() < 0.02,
            "{error_deg}°: counted move {counted_m} m"
        );
        let dropped_m = moved_off_trim(error_deg.to_radians(), false);
        assert!(
            (dropped_m - 0.15).abs() > 0.1,
            "{error_deg}°: a move that drops its error made {dropped_m} m"
        );
    }
}

#[test]
fn a_blocked_move_forgives_what_it_did_not_make_and_keeps_the_rest() {
    let config = Config::ROBOT.balance;
    let mut balance = Balance::new(config);
    let bound_m = config.position_error_limit_m;
    balance.forgive_m(-0.1);
    assert!((balance.position_error_m() + 0.1).abs() < 1e-6);
    balance.forgive_m(0.04);
    assert!((balance.position_error_m() + 0.06).abs() < 1e-6);
    balance.forgive_m(10.0);
    assert_eq!(balance.position_error_m(), bound_m);
    balance.forgive_m(f32::NAN);
    assert_eq!(balance.position_error_m(), bound_m);
}
