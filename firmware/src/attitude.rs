//! Torso attitude: pitch and roll (x forward, y left, z up), as the
//! [`estimator`](crate::control::estimator) finds them.

/// Pitch and roll of the torso, rad.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Attitude {
    /// About +y, positive leaning forward (nose down), −π/2…π/2.
    pub pitch_rad: f32,
    /// About +x, positive with the left side up, −π…π.
    pub roll_rad: f32,
}

impl Attitude {
    /// The larger of |pitch| and |roll| (NaN if either is).
    pub fn tilt_rad(&self) -> f32 {
        if self.pitch_rad.is_nan() || self.roll_rad.is_nan() {
            f32::NAN
        } else {
            self.pitch_rad.abs().max(self.roll_rad.abs())
        }
    }
}
