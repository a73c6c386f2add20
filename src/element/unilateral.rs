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

/// A unilateral normal spring whose stiffness follows the load, `kn(N) = kn0·(N/N0)^b`: the
/// normal stiffness of a rough contact grows with the pressure (`kn″ ∝ p^b`, the calibration
/// table's power law between rows, `b` ≈ 0.6–0.9 on the reference surface; Persson's
/// exponential pressure–gap law is `b = 1`). Integrating `dN/dun = kn(N)` from `N(0) = N0`:
///
/// ```text
/// N(un) = N0·B^{1/(1−b)},  B = 1 + (1 − b)·kn0·un/N0     (b < 1; separated where B ≤ 0)
/// N(un) = N0·exp(kn0·un/N0)                              (b = 1; never separates)
/// ```
///
/// The trial load (the load before the unilateral cut, which the friction laws read and the
/// re-contact point interpolates) continues `N0·sign(B)·|B|^{1/(1−b)}` below `B = 0`, a
/// continuous and monotone continuation, as `N0 + kn·un` is for [`UnilateralNormal`]. `b = 0` is
/// [`UnilateralNormal`]. `b > 1` is refused: its load becomes infinite at a finite closure
/// `un = N0/((b − 1)·kn0)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PowerLawNormal {
    /// Normal stiffness `kn0` at the preload (N/m), > 0.
    pub kn0: f64,
    /// Normal preload `N0` (N), > 0.
    pub n0: f64,
    /// Exponent `b = d ln kn / d ln N`, `0 ≤ b ≤ 1`.
    pub exponent: f64,
}

impl PowerLawNormal {
    /// Build and validate (`kn0 > 0`, `N0 > 0`, `0 ≤ b ≤ 1`).
    pub fn new(kn0: f64, n0: f64, exponent: f64) -> Result<Self> {
        require_positive("kn", kn0)?;
        require_positive("N0", n0)?;
        if !(0.0..=1.0).contains(&exponent) {
            return Err(crate::core::error::Error::param(
                "kn_load_exponent",
                format!(
                    "{exponent} is outside [0, 1]: kn ∝ N^b with b > 1 makes the load infinite at a finite closure, b < 0 softens under load"
                ),
            ));
        }
        Ok(Self { kn0, n0, exponent })
    }

    /// The trial load at the approach `un` and its derivative `dN/dun` (type documentation).
    #[inline]
    pub fn trial_load_and_slope(&self, un: f64) -> (f64, f64) {
        let b = self.exponent;
        let z = self.kn0 * un / self.n0;
        if b == 1.0 {
            let n = self.n0 * z.exp();
            return (n, self.kn0 * n / self.n0);
        }
        let c = 1.0 - b;
        let base = 1.0 + c * z;
        let m = 1.0 / c;
        let mag = base.abs().powf(m);
        // dN/dun = N0·m·|B|^{m−1}·c·kn0/N0 = kn0·|B|^{b/(1−b)}.
        let slope = self.kn0 * base.abs().powf(b * m);
        (self.n0 * base.signum() * mag, slope)
    }

    /// The trial load at the approach `un` (type documentation).
    #[inline]
    pub fn trial_load(&self, un: f64) -> f64 {
        self.trial_load_and_slope(un).0
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
    fn power_law_normal_load_solves_dn_dun_equal_kn_of_n() {
        // dN/dun = kn0·(N/N0)^b along the closed form, by central differences, for b in [0, 1].
        for b in [0.0, 0.3, 0.62, 0.9, 1.0] {
            let n = PowerLawNormal::new(2.0e7, 3.0, b).unwrap();
            for un in [-5e-8, 0.0, 1e-7, 4e-7] {
                let (load, slope) = n.trial_load_and_slope(un);
                assert!(load > 0.0, "b={b}, un={un}");
                let h = 1e-12;
                let fd = (n.trial_load(un + h) - n.trial_load(un - h)) / (2.0 * h);
                let law = n.kn0 * (load / n.n0).powf(b);
                assert!((fd - law).abs() < 1e-6 * law, "b={b}: {fd} vs {law}");
                assert!((slope - law).abs() < 1e-12 * law, "b={b}: {slope} vs {law}");
            }
            assert_eq!(n.trial_load(0.0), 3.0);
        }
        // b = 0 is the linear spring; b < 1 separates at B = 0, where the trial load turns
        // negative continuously.
        let lin = UnilateralNormal::new(2.0e7, 3.0).unwrap();
        let p0 = PowerLawNormal::new(2.0e7, 3.0, 0.0).unwrap();
        for un in [-3e-7, -1e-7, 2e-7] {
            assert!((p0.trial_load(un) - lin.trial_load(un)).abs() < 1e-14);
        }
        let p = PowerLawNormal::new(2.0e7, 3.0, 0.5).unwrap();
        let open = -3.0 / (0.5 * 2.0e7);
        assert!(p.trial_load(open).abs() < 1e-12);
        assert!(p.trial_load(open - 1e-9) < 0.0 && p.trial_load(open + 1e-9) > 0.0);
        assert!(PowerLawNormal::new(2.0e7, 3.0, 1.2).is_err());
        assert!(PowerLawNormal::new(2.0e7, 3.0, -0.1).is_err());
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
