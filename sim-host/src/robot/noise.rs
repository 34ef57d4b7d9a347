//! White noise for the emulated parts: one normal draw from a part's own generator.

use rand::rngs::SmallRng;
use rand_distr::{Distribution, Normal};

/// A draw from the normal distribution of mean 0 and standard deviation `std` (0 for a
/// standard deviation that is not positive or not finite: no noise).
pub fn gaussian(rng: &mut SmallRng, std: f64) -> f64 {
    if std > 0.0 {
        Normal::new(0.0, std).map_or(0.0, |n| n.sample(rng))
    } else {
        0.0
    }
}
