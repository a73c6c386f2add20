//! Unilateral normal contact, shared by the contact laws: a normal spring of stiffness `kn` about
//! a preload `N0`,
//!
//! ```text
//! N = max(0, N0 + kn·un)          (un > 0 closes the contact; N0 + kn·un ≤ 0 is separation)
//! ```
//!
//! and, for an increment that starts separated and ends in contact, the re-contact point where
//! the linearly interpolated load `N0 + kn·un` crosses zero. The friction laws take `N` as their
//! normal load; the 3-D contact elements ([`crate::element::contact3d`]) return `N − N0` in their
//! normal component. Units: per unit area (Pa, Pa/m, m) or per element (N, N/m, m).

use crate::core::error::{require_positive, Result};

/// Normal load `Fz = max(0, N0 + kn·uz)` (zero on separation; `uz > 0` closes the contact).
pub fn normal_load(n0: f64, kn: f64, uz: f64) -> f64 {
    (n0 + kn * uz).max(0.0)
}

/// [`normal_load`] for a whole history of normal displacements.
pub fn normal_load_history(n0: f64, kn: f64, uz: &[f64]) -> Vec<f64> {
    uz.iter().map(|&u| normal_load(n0, kn, u)).collect()
}

/// A unilateral normal spring about a preload (module documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UnilateralNormal {
    /// Normal contact stiffness `kn` (N/m), > 0.
    pub kn: f64,
    /// Normal preload `N0` (N), > 0.
    pub n0: f64,
}

impl UnilateralNormal {
    /// Build and validate (`kn > 0`, `N0 > 0`).
    pub fn new(kn: f64, n0: f64) -> Result<Self> {
        require_positive("kn", kn)?;
        require_positive("N0", n0)?;
        Ok(Self { kn, n0 })
    }

    /// The load before the unilateral cut, `N0 + kn·un` (`≤ 0`: separated). The friction laws
    /// take it as their normal load (they treat `≤ 0` as separation).
    #[inline]
    pub fn trial_load(&self, un: f64) -> f64 {
        self.n0 + self.kn * un
    }

    /// The normal force change `max(0, N) − N0` at the trial load `n` ([`Self::trial_load`])
    /// and its derivative with respect to the approach `un`: `kn` in contact, 0 separated.
    #[inline]
    pub fn force_change(&self, n: f64) -> (f64, f64) {
        (n.max(0.0) - self.n0, if n > 0.0 { self.kn } else { 0.0 })
    }
}

/// Fraction `θ = Fz0/(Fz0 − Fz1)` of an increment at which the linearly interpolated normal load
/// crosses zero (a contact separated at its start, `Fz0 ≤ 0`, closing by its end, `Fz1 > 0`),
/// with `∂θ/∂Fz0 = −Fz1/(Fz0 − Fz1)²` and `∂θ/∂Fz1 = Fz0/(Fz0 − Fz1)²`.
pub fn recontact_fraction(fz0: f64, fz1: f64) -> (f64, f64, f64) {
    let den = (fz0 - fz1) * (fz0 - fz1);
    (fz0 / (fz0 - fz1), -fz1 / den, fz0 / den)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recontact_fraction_and_its_derivatives() {
        let (fz0, fz1, h) = (-3.0, 7.0, 1e-6);
        let (th, d0, d1) = recontact_fraction(fz0, fz1);
        // The interpolated load vanishes at θ.
        assert!((fz0 + th * (fz1 - fz0)).abs() < 1e-15);
        let fd0 =
            (recontact_fraction(fz0 + h, fz1).0 - recontact_fraction(fz0 - h, fz1).0) / (2.0 * h);
        let fd1 =
            (recontact_fraction(fz0, fz1 + h).0 - recontact_fraction(fz0, fz1 - h).0) / (2.0 * h);
        assert!((fd0 - d0).abs() < 1e-9 && (fd1 - d1).abs() < 1e-9);
    }

    #[test]
    fn separation_cuts_the_load() {
        let n = UnilateralNormal::new(2.0, 1.0).unwrap();
        assert_eq!(n.force_change(n.trial_load(0.25)), (0.5, 2.0));
        assert_eq!(n.force_change(n.trial_load(-1.0)), (-1.0, 0.0));
        assert_eq!(normal_load(1.0, 2.0, -1.0), 0.0);
        assert!(UnilateralNormal::new(0.0, 1.0).is_err());
        assert!(UnilateralNormal::new(1.0, -1.0).is_err());
    }
}
