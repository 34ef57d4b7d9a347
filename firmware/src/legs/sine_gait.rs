//! The report's joint-space trot (section 6.3), kept to reproduce its figures:
//! `hip2 = A_hip sin(ωt + φ)`, `knee = q_base + A_knee sin(ωt + φ)`, `ankle = A_ank sin(ωt + φ)`,
//! hip abduction at zero.

use crate::legs::kinematics::LegJoints;
use crate::legs::phase::Phase;
use crate::math::sin;

/// Amplitudes and offset of the report's sinusoids.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SineGait {
    /// Hip pitch amplitude, rad.
    pub hip_amplitude_rad: f32,
    /// Knee offset, rad.
    pub knee_base_rad: f32,
    /// Knee amplitude, rad.
    pub knee_amplitude_rad: f32,
    /// Ankle amplitude, rad.
    pub ankle_amplitude_rad: f32,
}

impl SineGait {
    /// The report's values: hip 0.35 rad, knee −0.7 ± 0.25 rad, ankle 0.15 rad.
    pub const REPORT: Self = Self {
        hip_amplitude_rad: 0.35,
        knee_base_rad: -0.7,
        knee_amplitude_rad: 0.25,
        ankle_amplitude_rad: 0.15,
    };

    /// Joint targets at `phase` (the leg's own phase, pair offset already applied), with the
    /// amplitudes scaled by `scale` (0…1, clamped; the knee offset stays).
    pub fn joints(&self, phase: Phase, scale: f32) -> LegJoints {
        let s = sin(phase.radians()) * crate::math::clamp(scale, 0.0, 1.0);
        LegJoints {
            hip_abduction_rad: 0.0,
            hip_pitch_rad: self.hip_amplitude_rad * s,
            knee_rad: self.knee_base_rad + self.knee_amplitude_rad * s,
            ankle_rad: self.ankle_amplitude_rad * s,
        }
    }
}
