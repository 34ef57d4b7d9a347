//! What a drive can deliver, and the limiter its current loop enforces whatever it is asked:
//! the peak torque, less as the motor's back-EMF eats the supply voltage at speed, and the
//! continuous torque once the winding has run hot.
//!
//! The model: in the motoring quadrant (torque and speed of one sign) the most torque falls
//! linearly from the peak at stall to nothing at the no-load speed; braking, the peak. The
//! winding's heat is the squared torque through a first-order filter of the thermal time
//! constant; above the continuous torque squared the drive folds back to the continuous torque
//! until it has cooled (an I²t limit, as servo drives implement it).

/// A drive's rating.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rating {
    /// Most torque at stall, N·m.
    pub peak_torque_nm: f64,
    /// Torque the drive sustains indefinitely, N·m.
    pub continuous_torque_nm: f64,
    /// Output speed at which the back-EMF leaves no torque to drive with, rad/s.
    pub no_load_speed_rad_s: f64,
    /// Time constant of the winding's heating, s.
    pub thermal_time_constant_s: f64,
}

impl Rating {
    /// A leg joint: a quasi-direct-drive actuator (outrunner BLDC, ~9:1 single-stage planetary,
    /// FOC drive) of the class of the Unitree A1 joint motor, which carries 12 kg quadrupeds:
    /// 33.5 N·m peak and 21 rad/s at the output as published; continuous a third of the peak and
    /// a 60 s winding time constant, typical of the class (these two are not published).
    pub const LEG_JOINT: Rating = Rating {
        peak_torque_nm: 33.5,
        continuous_torque_nm: 11.0,
        no_load_speed_rad_s: 21.0,
        thermal_time_constant_s: 60.0,
    };

    /// A wheel: a geared hub motor of the class that carries this 40 kg robot on 0.12 m
    /// wheels: 30 N·m peak (the controller plans with the same figure,
    /// `Config::wheel_torque_limit_nm`), 10 N·m continuous, 30 rad/s no-load (3.6 m/s).
    pub const WHEEL: Rating = Rating {
        peak_torque_nm: 30.0,
        continuous_torque_nm: 10.0,
        no_load_speed_rad_s: 30.0,
        thermal_time_constant_s: 120.0,
    };

    /// No limit at all: a joint servo as the report's model had it (for debugging).
    pub const UNLIMITED: Rating = Rating {
        peak_torque_nm: f64::INFINITY,
        continuous_torque_nm: f64::INFINITY,
        no_load_speed_rad_s: f64::INFINITY,
        thermal_time_constant_s: 60.0,
    };

    /// A flat 30 N·m at any speed and temperature: the wheels before the drives had ratings.
    pub const FLAT_WHEEL: Rating = Rating {
        peak_torque_nm: 30.0,
        continuous_torque_nm: f64::INFINITY,
        no_load_speed_rad_s: f64::INFINITY,
        thermal_time_constant_s: 120.0,
    };

    /// The most torque the motor gives at `speed_rad_s` toward the sign of `wanted_nm`, N·m
    /// (≥ 0), before any thermal foldback.
    pub fn envelope_nm(&self, speed_rad_s: f64, wanted_nm: f64) -> f64 {
        let motoring = wanted_nm * speed_rad_s > 0.0;
        if motoring {
            let left = 1.0 - speed_rad_s.abs() / self.no_load_speed_rad_s;
            self.peak_torque_nm * left.clamp(0.0, 1.0)
        } else {
            self.peak_torque_nm
        }
    }
}

/// The torque a drive applies after its limits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limited {
    /// Applied torque, N·m.
    pub torque_nm: f64,
    /// Whether the wanted torque was cut.
    pub saturated: bool,
}

/// One motor's limiter, with its winding's heat.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limiter {
    rating: Rating,
    /// Filtered squared torque, N²·m².
    heat: f64,
}

impl Limiter {
    /// A cold motor of `rating`.
    pub fn new(rating: Rating) -> Self {
        Self { rating, heat: 0.0 }
    }

    /// The rating.
    pub fn rating(&self) -> &Rating {
        &self.rating
    }

    /// Whether the winding is hot enough for the continuous limit to apply.
    pub fn folded_back(&self) -> bool {
        self.heat > self.rating.continuous_torque_nm.powi(2)
    }

    /// The torque applied for `wanted_nm` at `speed_rad_s` over the next `dt_s`; heats the
    /// winding by it. A non-finite wanted torque gives none.
    pub fn limit(&mut self, wanted_nm: f64, speed_rad_s: f64, dt_s: f64) -> Limited {
        let wanted = if wanted_nm.is_finite() {
            wanted_nm
        } else {
            0.0
        };
        let mut most = self.rating.envelope_nm(speed_rad_s, wanted);
        if self.folded_back() {
            most = most.min(self.rating.continuous_torque_nm);
        }
        let torque_nm = wanted.clamp(-most, most);
        self.heat_by(torque_nm, dt_s);
        Limited {
            torque_nm,
            saturated: torque_nm != wanted,
        }
    }

    /// The winding cools for `dt_s` with no torque (the drive is off).
    pub fn cool(&mut self, dt_s: f64) {
        self.heat_by(0.0, dt_s);
    }

    fn heat_by(&mut self, torque_nm: f64, dt_s: f64) {
        let alpha = (dt_s / self.rating.thermal_time_constant_s).clamp(0.0, 1.0);
        self.heat += alpha * (torque_nm * torque_nm - self.heat);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_peak_holds_at_stall_and_braking_and_fades_to_nothing_at_the_no_load_speed() {
        let mut limiter = Limiter::new(Rating::LEG_JOINT);
        let at = |l: &mut Limiter, wanted, speed| l.limit(wanted, speed, 0.004);
        assert_eq!(at(&mut limiter, 50.0, 0.0).torque_nm, 33.5);
        assert_eq!(at(&mut limiter, -50.0, 0.0).torque_nm, -33.5);
        assert!((at(&mut limiter, 50.0, 10.5).torque_nm - 16.75).abs() < 1e-9);
        assert_eq!(at(&mut limiter, 50.0, 25.0).torque_nm, 0.0);
        // Braking against the motion: the peak.
        assert_eq!(at(&mut limiter, -50.0, 10.5).torque_nm, -33.5);
        let within = at(&mut limiter, 5.0, 1.0);
        assert_eq!(
            within,
            Limited {
                torque_nm: 5.0,
                saturated: false
            }
        );
        assert!(at(&mut limiter, 40.0, 0.0).saturated);
        assert_eq!(at(&mut limiter, f64::NAN, 0.0).torque_nm, 0.0);
    }

    #[test]
    fn a_winding_run_at_the_peak_folds_back_to_the_continuous_torque_and_recovers_cold() {
        let mut limiter = Limiter::new(Rating::LEG_JOINT);
        let dt = 0.004;
        let mut t = 0.0;
        while !limiter.folded_back() {
            limiter.limit(33.5, 0.0, dt);
            t += dt;
            assert!(t < 60.0, "never folded back");
        }
        // (1 - e^(-t/60)) · 33.5² = 11²: t = 60 · ln(1 / (1 - 0.1078)) ≈ 6.8 s.
        assert!((6.0..8.0).contains(&t), "folded back after {t} s");
        assert_eq!(limiter.limit(33.5, 0.0, dt).torque_nm, 11.0);
        for _ in 0..(120.0 / dt) as u32 {
            limiter.cool(dt);
        }
        assert!(!limiter.folded_back());
        assert_eq!(limiter.limit(33.5, 0.0, dt).torque_nm, 33.5);
    }
}
