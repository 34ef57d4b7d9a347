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
//! | `sin/cos`| 1.1e-3              | no (0.4 mm)    | `libm::sinf` / `libm::cosf`                 |
//!
//! `libm` is within 1–2 ulp for all of them. On the Cortex-M4F the hardware square root is
//! exact (IEEE correctly rounded, 14 cycles) and far faster than `libm`'s software `sqrtf`,
//! which this target would otherwise get; the trigonometric functions have no FPU instruction
//! and come from `libm`.

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
    libm::sinf(x)
}

/// Cosine of `x` radians.
#[inline]
pub fn cos(x: f32) -> f32 {
    libm::cosf(x)
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
