//! The `f32` functions the core uses, chosen per function for accuracy and speed.
//!
//! The IK budget is 0.5 mm and 0.1° after a round trip FK(IK(p)). Measured maximum errors of
//! `micromath` 2.1 against exact values (`cargo test -p firmware --test math_choice -- --nocapture`):
//!
//! | function | micromath error     | within budget? | used here                                  |
//! |----------|---------------------|----------------|--------------------------------------------|
//! | `sqrt`   | 6.1 % relative      | no             | FPU `vsqrt.f32` on the MCU, `libm` on host  |
//! | `acos`   | 2.9e-2 rad (1.7°)   | no             | `libm::acosf`                              |
//! | `atan2`  | 2.8e-3 rad (0.16°)  | no             | `libm::atan2f`                             |
//! | `sin/cos`| 1.1e-3              | no (0.4 mm)    | [`sin_cos`]: own, `f32` only               |
//!
//! `libm` is within 1–2 ulp for all of them. On the Cortex-M4F the hardware square root is
//! exact (IEEE correctly rounded, 14 cycles) and far faster than `libm`'s software `sqrtf`,
//! which this target would otherwise get. `libm::sinf`/`cosf` compute in double precision
//! (musl's kernels), which the M4F's single-precision FPU can only emulate in software: measured
//! in the processor-in-the-loop run (`cargo xtask pil`), they made up half of a trot step's
//! ~25,000 instructions (with [`sin_cos`]: ~11,000). [`sin_cos`] stays in `f32`: a Cody–Waite
//! reduction by π/2 and Taylor series on ±π/4, within 2 ulp of `libm` for the angles the core
//! uses (tested), and NaN beyond ±8192 rad rather than calling `libm` there, so that the image
//! links neither `libm`'s sine nor soft double-precision arithmetic.

/// `degrees` in radians (for readable constants).
pub const fn deg_to_rad(degrees: f32) -> f32 {
    degrees * (core::f32::consts::PI / 180.0)
}

/// Square root. Negative or NaN input gives NaN (IEEE), so callers clamp first.
#[inline]
pub fn sqrt(x: f32) -> f32 {
    #[cfg(all(target_arch = "arm", target_abi = "eabihf"))]
    {
        let bits: u32;
        // SAFETY: saves s0 on the stack, computes the square root there and restores it; no
        // other register or memory is touched. The `eabihf` ABI guarantees the FPU is present.
        // (Core registers carry the value because rustc's `sreg` operand class is gated on a
        // `vfp2` feature flag this target spells differently.)
        unsafe {
            core::arch::asm!(
                "vpush {{s0}}",
                "vmov s0, {x}",
                "vsqrt.f32 s0, s0",
                "vmov {bits}, s0",
                "vpop {{s0}}",
                x = in(reg) x.to_bits(),
                bits = lateout(reg) bits,
                options(pure, nomem, preserves_flags)
            );
        }
        f32::from_bits(bits)
    }
    #[cfg(not(all(target_arch = "arm", target_abi = "eabihf")))]
    {
        libm::sqrtf(x)
    }
}

/// Sine of `x` radians.
#[inline]
pub fn sin(x: f32) -> f32 {
    sin_cos(x).0
}

/// Cosine of `x` radians.
#[inline]
pub fn cos(x: f32) -> f32 {
    sin_cos(x).1
}

/// Beyond this the single-precision reduction loses accuracy, and no angle of the robot is
/// anywhere near it: the result is NaN, which the controller's checks of its outputs treat
/// as a fault. (`libm`'s fallback here took 6.4 KiB of the image: its large-argument
/// reduction and the soft double-precision arithmetic it needs.)
const SIN_COS_REDUCE_MAX: f32 = 8192.0;

/// Sine and cosine of `x` radians, in `f32` only. NaN, infinite or beyond ±8192 rad input
/// gives NaN.
pub fn sin_cos(x: f32) -> (f32, f32) {
    // π/2 in three parts: the first two have few significant bits, so `k × part` is exact for
    // the quotients that occur here (|k| < 2^13).
    const PIO2_1: f32 = 1.570_312_5;
    const PIO2_2: f32 = 4.837_513e-4;
    const PIO2_3: f32 = 7.549_79e-8;
    // NaN fails the range test too.
    if !(-SIN_COS_REDUCE_MAX..=SIN_COS_REDUCE_MAX).contains(&x) {
        return (f32::NAN, f32::NAN);
    }
    // Nearest multiple of π/2.
    let q = x * core::f32::consts::FRAC_2_PI;
    let k = if q >= 0.0 {
        (q + 0.5) as i32
    } else {
        (q - 0.5) as i32
    };
    let kf = k as f32;
    let r = ((x - kf * PIO2_1) - kf * PIO2_2) - kf * PIO2_3;
    let z = r * r;
    // Taylor series; on |r| ≤ π/4 the first omitted terms are below 2e-9.
    let s =
        r + r * z * (-1.0 / 6.0 + z * (1.0 / 120.0 + z * (-1.0 / 5040.0 + z * (1.0 / 362_880.0))));
    let c = 1.0
        + z * (-0.5
            + z * (1.0 / 24.0 + z * (-1.0 / 720.0 + z * (1.0 / 40_320.0 - z / 3_628_800.0))));
    match k & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

/// Arc cosine, in 0…π. Input outside −1…1 gives NaN, so callers clamp first.
#[inline]
pub fn acos(x: f32) -> f32 {
    libm::acosf(x)
}

/// Arc sine, in −π/2…π/2. Input outside −1…1 gives NaN, so callers clamp first.
#[inline]
pub fn asin(x: f32) -> f32 {
    libm::asinf(x)
}

/// Four-quadrant arc tangent of `y / x`, in −π…π; `atan2(0, 0) = 0`.
#[inline]
pub fn atan2(y: f32, x: f32) -> f32 {
    libm::atan2f(y, x)
}

/// The smooth step `3s² − 2s³` of `s` in 0…1: from 0 to 1 with no speed at either end, the
/// blend of a move that starts and ends at rest.
#[inline]
pub fn smoothstep(s: f32) -> f32 {
    s * s * (3.0 - 2.0 * s)
}

/// `x` clamped to `lo…hi`; NaN stays NaN so callers can detect it.
#[inline]
pub fn clamp(x: f32, lo: f32, hi: f32) -> f32 {
    if x < lo {
        lo
    } else if x > hi {
        hi
    } else {
        x
    }
}

/// `from` moved toward `to` by at most `step` (a rate limit; a non-finite result holds
/// `from`).
#[inline]
pub fn toward(from: f32, to: f32, step: f32) -> f32 {
    let moved = from + clamp(to - from, -step, step);
    if moved.is_finite() {
        moved
    } else {
        from
    }
}

/// `angle_rad` wrapped into −π…π.
#[inline]
pub fn wrap_pi(angle_rad: f32) -> f32 {
    use core::f32::consts::{PI, TAU};
    let mut wrapped = libm::remainderf(angle_rad, TAU);
    if wrapped <= -PI {
        wrapped += TAU;
    } else if wrapped > PI {
        wrapped -= TAU;
    }
    wrapped
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Within 2 ulp of 1 (absolute) of `libm` on ±50 rad, and exact at zero.
    #[test]
    fn sin_cos_match_libm() {
        let mut worst = 0.0_f32;
        for i in -500_000_i32..=500_000_i32 {
            let x = i as f32 * 1e-4;
            let (s, c) = sin_cos(x);
            worst = worst
                .max((s - libm::sinf(x)).abs())
                .max((c - libm::cosf(x)).abs());
        }
        assert!(worst <= 2.0 * f32::EPSILON, "worst {worst:e}");
        assert_eq!(sin_cos(0.0), (0.0, 1.0));
        assert!(sin_cos(f32::NAN).0.is_nan() && sin_cos(f32::INFINITY).1.is_nan());
        assert!(sin_cos(1.0e6).0.is_nan() && sin_cos(-8193.0).1.is_nan());
        let edge = SIN_COS_REDUCE_MAX;
        assert!((sin_cos(edge).0 - libm::sinf(edge)).abs() < 1e-3);
    }
}
