//! The balance law's design: LQR on the linear wheeled-pendulum model of `firmware::wheels::balance`,
//! solved here on the host with `nalgebra`. Fails when the committed gains are stale (and
//! prints the new ones), and checks the firmware's own `Balance` on the model.

use firmware::config::Config;
use firmware::wheels::balance::{Balance, BalanceConfig, BalanceGains, BalanceInput, BalanceModel};
use nalgebra::{Matrix1, Matrix4, Matrix4x1, SMatrix};

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

/// Discrete LQR by iterating the Riccati equation to convergence.
fn lqr(a: &Matrix4<f64>, b: &Matrix4x1<f64>, q: &Matrix4<f64>, r: f64) -> [f64; 4] {
    let mut p = *q;
    for _ in 0..200_000 {
        let gain_denominator = Matrix1::new(r) + b.transpose() * p * b;
        let k = gain_denominator.try_inverse().expect("R > 0") * b.transpose() * p * a;
        let next = q + a.transpose() * p * (a - b * k);
        let change = (next - p).abs().max();
        p = next;
        if change < 1e-12 * p.abs().max() {
            break;
        }
    }
    let k = (Matrix1::new(r) + b.transpose() * p * b)
        .try_inverse()
        .expect("R > 0")
        * b.transpose()
        * p
        * a;
    [k[0], k[1], k[2], k[3]]
}

/// Bryson's rule: each state and the input weighted by 1 / (its largest acceptable value)².
fn bryson() -> (Matrix4<f64>, f64) {
    let weight = |largest: f64| 1.0 / (largest * largest);
    let q = Matrix4::from_diagonal(&nalgebra::Vector4::new(
        weight(0.15),
        weight(0.1),
        weight(0.3),
        weight(1.0),
    ));
    (q, weight(30.0))
}

fn designed_gains() -> [f64; 4] {
    let (a, b) = continuous(&BalanceModel::ROBOT);
    let (ad, bd) = discrete(&a, &b, DT_S);
    let (q, r) = bryson();
    lqr(&ad, &bd, &q, r)
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
        "BalanceGains::ROBOT is stale; the LQR design gives\n    position_nm_per_m: {:.4},\n    pitch_nm_per_rad: {:.4},\n    velocity_nm_per_m_s: {:.4},\n    pitch_rate_nm_per_rad_s: {:.4},",
        designed[0], designed[1], designed[2], designed[3]
    );
}

#[test]
fn open_loop_is_unstable_and_closed_loop_is_stable() {
    let (a, b) = continuous(&BalanceModel::ROBOT);
    let (ad, bd) = discrete(&a, &b, DT_S);
    let open = ad.complex_eigenvalues();
    assert!(
        open.iter().any(|l| l.norm() > 1.0),
        "the pendulum must fall without control"
    );
    let k = designed_gains();
    let k = nalgebra::RowVector4::new(k[0], k[1], k[2], k[3]);
    let closed = (ad - bd * k).complex_eigenvalues();
    for l in closed.iter() {
        assert!(
            l.norm() < 0.999,
            "closed-loop pole {l} not inside the unit circle"
        );
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
