//! Closed-form contact solutions used to validate the boundary-element solvers.
//!
//! Hertz (sphere on flat), Johnson, *Contact Mechanics*, 1985, §4.2; see also
//! `../shared/data/contact/REFERENCES.md`. SI units.

/// Hertz contact of a sphere (radius `r`, m) pressed with force `p` (N), composite modulus
/// `e_star` (Pa).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hertz {
    /// Contact radius a = (3PR / (4E*))^(1/3) (m).
    pub radius: f64,
    /// Peak pressure p0 = 3P / (2πa²) (Pa).
    pub peak_pressure: f64,
    /// Approach δ = a² / R (m).
    pub approach: f64,
}

impl Hertz {
    /// Closed-form Hertz solution.
    pub fn new(sphere_radius: f64, force: f64, e_star: f64) -> Self {
        let a = (3.0 * force * sphere_radius / (4.0 * e_star)).cbrt();
        Self {
            radius: a,
            peak_pressure: 3.0 * force / (2.0 * std::f64::consts::PI * a * a),
            approach: a * a / sphere_radius,
        }
    }

    /// Pressure at distance `r` from the centre: p0·sqrt(1 - r²/a²) inside, 0 outside (Pa).
    pub fn pressure(&self, r: f64) -> f64 {
        let s = 1.0 - (r / self.radius).powi(2);
        if s > 0.0 {
            self.peak_pressure * s.sqrt()
        } else {
            0.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn contact_case_of_references_md() {
        // REFERENCES.md: G = 200 N/mm², ν = 0.42, R = 50 mm, Fn = 9.1954 N → a = 1 mm,
        // p0 = 4.390 N/mm², δ = 0.0200 mm. Work in mm and N/mm² (consistent units).
        let (g, nu) = (200.0, 0.42);
        let e = 2.0 * g * (1.0 + nu);
        let e_star = 1.0 / (2.0 * (1.0 - nu * nu) / e);
        let h = Hertz::new(50.0, 9.1954, e_star);
        assert!((h.radius - 1.0).abs() < 1e-3, "{}", h.radius);
        assert!(
            (h.peak_pressure - 4.390).abs() < 2e-3,
            "{}",
            h.peak_pressure
        );
        assert!((h.approach - 0.0200).abs() < 5e-5, "{}", h.approach);
    }
}
