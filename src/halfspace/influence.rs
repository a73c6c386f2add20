//! Influence coefficients of the elastic half-space: surface displacement at a grid point due
//! to a uniform traction on one rectangular grid element.
//!
//! All functions take the composite (effective) modulus where relevant,
//! `1/E* = (1-ν1²)/E1 + (1-ν2²)/E2` (see [`crate::surface::combine`]), and element half-sizes
//! `a = dx/2`, `b = dy/2`. Lengths in m, moduli in Pa, displacement per unit traction in m/Pa.

use super::convolution::{Boundary, FftPlan, KernelSpectrum};
use rustfft::num_complex::Complex64;

/// Antiderivative of `1/r` over a rectangle corner:
/// `F(ξ, η) = ξ·ln(η + r) + η·ln(ξ + r)`, `r = sqrt(ξ² + η²)`, so that
/// `∫∫ dξ dη / r = F` (Johnson, *Contact Mechanics*, 1985, eq. 3.25, Love 1929).
/// Written to stay finite and accurate when `η + r` or `ξ + r` cancels.
fn love_corner(xi: f64, eta: f64) -> f64 {
    let r = xi.hypot(eta);
    // ln(η + r) for η < 0 equals ln(ξ² / (r − η)), free of cancellation.
    let ln_sum = |t: f64, other: f64| -> f64 {
        if t >= 0.0 {
            (t + r).ln()
        } else {
            (other * other / (r - t)).ln()
        }
    };
    let a = if xi == 0.0 { 0.0 } else { xi * ln_sum(eta, xi) };
    let b = if eta == 0.0 {
        0.0
    } else {
        eta * ln_sum(xi, eta)
    };
    a + b
}

/// Normal surface displacement `u_z` at `(x, y)` per unit uniform pressure on the rectangle
/// `|x'| ≤ a, |y'| ≤ b` (Boussinesq problem integrated by Love, 1929; Johnson 1985 §3.2):
///
/// `u_z = 1/(π E*) · [F(x+a, y+b) − F(x+a, y−b) − F(x−a, y+b) + F(x−a, y−b)]`.
pub fn boussinesq_uz(x: f64, y: f64, a: f64, b: f64, e_star: f64) -> f64 {
    let s = love_corner(x + a, y + b) - love_corner(x + a, y - b) - love_corner(x - a, y + b)
        + love_corner(x - a, y - b);
    s / (std::f64::consts::PI * e_star)
}

/// Kernel spectrum of the normal (Boussinesq) compliance for a plan.
///
/// - Zero-padded plans: Love's element coefficients at every signed offset (DC-FFT).
/// - Periodic plans: the exact periodic half-space compliance `ũ(q) = 2 p̃(q) / (E* |q|)`
///   (Johnson 1985 §2.8; the spectral form used by Stanley & Kato 1997 and tamaas), with the
///   `q = 0` term set to zero: the mean displacement is carried by the rigid approach.
pub fn boussinesq_spectrum(plan: &FftPlan, dx: f64, dy: f64, e_star: f64) -> KernelSpectrum {
    match plan.boundary() {
        Boundary::ZeroPadded => plan.kernel_spectrum(|di, dj| {
            boussinesq_uz(di as f64 * dx, dj as f64 * dy, 0.5 * dx, 0.5 * dy, e_star)
        }),
        Boundary::Periodic => plan.spectrum_from_wavenumbers(dx, dy, |qx, qy| {
            let q = qx.hypot(qy);
            if q == 0.0 {
                Complex64::new(0.0, 0.0)
            } else {
                Complex64::new(2.0 / (e_star * q), 0.0)
            }
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn far_field_is_point_load() {
        // Far from the element, u_z → P/(π E* r) with P = 4ab·p.
        let (a, b, e) = (0.5, 0.5, 1.0);
        let r: f64 = 200.0;
        let u = boussinesq_uz(r, 0.0, a, b, e);
        let point = 4.0 * a * b / (std::f64::consts::PI * e * r);
        assert!((u / point - 1.0).abs() < 1e-5, "{u} vs {point}");
    }

    #[test]
    fn centre_of_square_matches_closed_form() {
        // Centre of a uniformly loaded square of side 2a: ∫∫ dA/r = 8a·ln(1+√2), so
        // u = 8a·ln(1+√2)·p/(π E*) (Johnson 1985, §3.2).
        let (a, e) = (1.0, 1.0);
        let u = boussinesq_uz(0.0, 0.0, a, a, e);
        let want = 8.0 * a * (1.0 + 2f64.sqrt()).ln() / (std::f64::consts::PI * e);
        assert!((u - want).abs() < 1e-12, "{u} vs {want}");
    }

    #[test]
    fn symmetric_and_finite_on_element_edges() {
        let (a, b, e) = (0.5, 0.25, 2.0);
        for &(x, y) in &[
            (0.5, 0.0),
            (0.0, 0.25),
            (0.5, 0.25),
            (1.0, 0.5),
            (-0.5, -0.25),
        ] {
            let u = boussinesq_uz(x, y, a, b, e);
            assert!(u.is_finite() && u > 0.0);
            assert!((u - boussinesq_uz(-x, y, a, b, e)).abs() < 1e-14);
            assert!((u - boussinesq_uz(x, -y, a, b, e)).abs() < 1e-14);
        }
    }
}
