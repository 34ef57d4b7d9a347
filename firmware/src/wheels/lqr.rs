//! The balance law's model and gains: the wheeled inverted pendulum and the LQR design of the
//! full-state feedback [`crate::wheels::balance`] runs.
//!
//! # Model and derivation
//!
//! Planar, linearised about upright. States `x = [p, θ, v, θ̇]`: position error along the
//! ground `p` (m, the integral of the speed error), body pitch `θ` (rad, positive = leaning
//! forward, IMU about +y), ground speed error `v` (m/s) and pitch rate `θ̇` (rad/s). Input `τ`:
//! the sum of both wheel torques (N·m), which acts on the wheels and reacts on the body. With
//! body mass `M` at height `l` above the axle, body pitch inertia `I_b` about its centre of
//! mass, wheel mass `m_w`, wheel inertia `I_w` (both wheels) and radius `r`, Lagrange's
//! equations linearised at θ = 0 give
//!
//! ```text
//! (M + m_w + I_w/r²) ẍ + M l θ̈        = τ / r
//!  M l ẍ              + (I_b + M l²) θ̈ − M g l θ = −τ
//! ```
//!
//! The gains `K` of `τ = −K x` solve the discrete LQR problem for this model at the control
//! rate, with Bryson weights (p 0.15 m, θ 0.1 rad, v 0.3 m/s, θ̇ 1 rad/s, τ 30 N·m). These
//! leave the delay margin of a real CAN loop: with the stiffer p 0.1 m and v 0.2 m/s the
//! simulated robot at rest fell into a 15.5 Hz limit cycle at full torque with 12 ms of loop
//! latency (a mode of the body the pendulum model does not have; `sim-host/tests/latency.rs`);
//! the softer p 0.2 m and v 0.5 m/s brake too late for the E-stop's 1 s to rest.
//! The design lives in `firmware/tests/balance_lqr.rs` (host, `nalgebra`): it recomputes `K` from
//! [`BalanceModel::ROBOT`], fails if [`BalanceGains::ROBOT`] is stale and prints the new gains,
//! and checks the closed loop on the linear model.
//!
//! # Loop delay
//!
//! The state the law reads crossed the bus, and its torque crosses it back: on the default
//! plant a cycle each way, so a torque acts [`DESIGN_DELAY_TICKS`] ticks after the state it
//! answers. The LQR is solved for the model with that input delay, its state augmented with
//! the law's own last torques: `τ_k = −(K_x x_k + K_u [τ_{k−1}, τ_{k−2}])`. Designed without
//! it, the law leant on the wheels' viscous friction, which damps the wheel against the body at
//! once: with 0.1 N·m·s/rad instead of 2 and two cycles each way the robot limit-cycled (46 N·m
//! rms at 10 Hz, 37 % of the ticks at the limit; designed for the delay 1.1 N·m). The campaign's
//! stop after W: 71 → 94 % of 100 trials; designs for 1, 3, 4, 6 ticks measured 1.3, 0.7, 1.8,
//! 13 points below. In a steady state the past torques equal the present one, so the
//! feed-forward is scaled by `1 + Σ k_u` (unscaled, driven into the 6 cm step the robot
//! tracked its reference too loosely for the stall detector and ran back 0.85 m).

/// Physical parameters of the pendulum (SI units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BalanceModel {
    /// Everything but the wheels, kg.
    pub body_mass_kg: f32,
    /// Centre of mass of the body above the wheel axle, m.
    pub com_height_m: f32,
    /// Body pitch inertia about its centre of mass, kg·m².
    pub body_pitch_inertia_kg_m2: f32,
    /// Both wheels, kg.
    pub wheel_mass_kg: f32,
    /// Both wheels about the axle, kg·m².
    pub wheel_inertia_kg_m2: f32,
    /// Wheel radius, m.
    pub wheel_radius_m: f32,
}

impl BalanceModel {
    /// How much more the body leans than its balance point while the axle accelerates
    /// steadily, rad per m/s²: the body's moment balance about the axle with the wheels'
    /// ground force and inertia, `(1 + ((m + m_w) r + I_w / r) / (m l)) / g`.
    pub const fn lean_rad_per_m_s2(&self) -> f32 {
        let m = self.body_mass_kg;
        let pushed = (m + self.wheel_mass_kg) * self.wheel_radius_m
            + self.wheel_inertia_kg_m2 / self.wheel_radius_m;
        (1.0 + pushed / (m * self.com_height_m)) / crate::control::estimator::GRAVITY_M_S2
    }

    /// The robot at the report's density 600 kg/m³, legs folded: torso box 0.6 × 0.5 × 0.18 m
    /// (32.4 kg, centre 0.15 m above the axle) plus four legs of capsules and a sphere foot
    /// (≈ 0.85 kg each, near the hips); wheels r = 0.12 m, width 0.09 m (2.44 kg each).
    pub const ROBOT: Self = Self {
        body_mass_kg: 35.8,
        com_height_m: 0.147,
        body_pitch_inertia_kg_m2: 1.5,
        wheel_mass_kg: 4.886,
        wheel_inertia_kg_m2: 0.0352,
        wheel_radius_m: 0.12,
    };
}

/// The loop delay the gains are designed for, ticks: a cycle each way (see the module docs).
pub const DESIGN_DELAY_TICKS: usize = 2;

/// State-feedback gains, `τ = −(k·x + k_u·[τ_{k−1}, τ_{k−2}])` in N·m.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BalanceGains {
    /// N·m per m of position error.
    pub position_nm_per_m: f32,
    /// N·m per rad of pitch.
    pub pitch_nm_per_rad: f32,
    /// N·m per m/s of speed error.
    pub velocity_nm_per_m_s: f32,
    /// N·m per rad/s of pitch rate.
    pub pitch_rate_nm_per_rad_s: f32,
    /// N·m per N·m of the total torque the law gave one and two ticks ago.
    pub past_torque_nm_per_nm: [f32; DESIGN_DELAY_TICKS],
}

impl BalanceGains {
    /// LQR gains for [`BalanceModel::ROBOT`] at 250 Hz with [`DESIGN_DELAY_TICKS`] of loop
    /// delay (see the module docs).
    pub const ROBOT: Self = Self {
        position_nm_per_m: -176.7789,
        pitch_nm_per_rad: -524.7382,
        velocity_nm_per_m_s: -206.5036,
        pitch_rate_nm_per_rad_s: -106.3361,
        past_torque_nm_per_nm: [0.2277, 0.2369],
    };

    /// As an array `[p, θ, v, θ̇, τ_{k−1}, τ_{k−2}]`.
    pub const fn to_array(self) -> [f32; 4 + DESIGN_DELAY_TICKS] {
        let [u1, u2] = self.past_torque_nm_per_nm;
        [
            self.position_nm_per_m,
            self.pitch_nm_per_rad,
            self.velocity_nm_per_m_s,
            self.pitch_rate_nm_per_rad_s,
            u1,
            u2,
        ]
    }
}
