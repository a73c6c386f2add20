//! Influence coefficients of the elastic half-space: surface displacement at a grid point due
//! to a uniform traction on one rectangular grid element.
//!
//! All functions take the composite (effective) modulus where relevant,
//! `1/E* = (1-ν1²)/E1 + (1-ν2²)/E2` (see [`crate::surface::combine`]), and element half-sizes
//! `a = dx/2`, `b = dy/2`. Lengths in m, moduli in Pa, displacement per unit traction in m/Pa.

use crate::core::fft::{Boundary, FftPlan, KernelSpectrum};
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

// ============================================================================================
// Cerruti: surface displacements due to uniform SHEAR traction on a rectangular element
// ============================================================================================
//
// Tangential (shear) traction `q = (q_x, q_y)` on the surface of an elastic half-space. The
// point-force solution of Cerruti (Johnson, *Contact Mechanics*, 1985, eq. 2.19 / 3.86a) for a
// force `Q_x` at the origin gives, at the surface point `(x, y)`, `ρ = sqrt(x² + y²)`:
//
// `u_x = Q_x/(2πG) · [(1-ν)/ρ + ν x²/ρ³]`,  `u_y = Q_x/(2πG) · ν x y/ρ³`,
// `u_z = -Q_x (1-2ν)/(4πG) · x/ρ²`  (normal–tangential coupling, see below),
//
// and the same with x and y exchanged for `Q_y`. For two bodies pressed together, the traction
// acts on body 1 and its opposite on body 2, so the *relative* tangential displacement is the sum
// of both bodies' compliances: the constants below add `(1-ν_k)/(2πG_k)` and `ν_k/(2πG_k)` over
// the two bodies.
//
// Quasi-identical materials: the coupling term `u_z ∝ (1-2ν)/G` enters the relative normal
// displacement as `(1-2ν1)/G1 - (1-2ν2)/G2` (Kalker's difference parameter), which vanishes for
// bodies of the same material. The tangential solver assumes this (normal and tangential
// problems decouple) and says so in its results.
//
// Integrated over the rectangle `|x'| ≤ a, |y'| ≤ b` with `ξ = x - x'`, `η = y - y'` (Love 1929's
// method for the Boussinesq element, applied to the Cerruti kernels):
//
// - `∫∫ dξ dη / ρ       = [ξ ln(η+ρ) + η ln(ξ+ρ)]`   (the Boussinesq corner function),
// - `∫∫ ξ²/ρ³ dξ dη     = [η ln(ξ+ρ)]`               (a term linear in η cancels in the corner sum),
// - `∫∫ η²/ρ³ dξ dη     = [ξ ln(η+ρ)]`,
// - `∫∫ ξη/ρ³ dξ dη     = [-ρ]`,
//
// where `[F] = F(x+a, y+b) − F(x+a, y−b) − F(x−a, y+b) + F(x−a, y−b)`. Each is checked against
// the point-force far field and against direct quadrature in the unit tests.

/// Compliance constants of the Cerruti solution for a pair of bodies (m²/N):
/// `c_iso = Σ_k (1-ν_k)/(2π G_k)`, `c_dir = Σ_k ν_k/(2π G_k)`, so that a point force `Q_x`
/// produces the relative surface displacement `u_x = Q_x·[c_iso/ρ + c_dir·x²/ρ³]`,
/// `u_y = Q_x·c_dir·x y/ρ³`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct CerrutiConstants {
    /// `Σ (1-ν_k)/(2π G_k)` (m²/N).
    pub c_iso: f64,
    /// `Σ ν_k/(2π G_k)` (m²/N).
    pub c_dir: f64,
}

impl CerrutiConstants {
    /// Constants for two bodies (body 1 and body 2 in contact). Shear moduli in Pa.
    pub fn two_bodies(g1: f64, nu1: f64, g2: f64, nu2: f64) -> Self {
        let two_pi = 2.0 * std::f64::consts::PI;
        Self {
            c_iso: (1.0 - nu1) / (two_pi * g1) + (1.0 - nu2) / (two_pi * g2),
            c_dir: nu1 / (two_pi * g1) + nu2 / (two_pi * g2),
        }
    }

    /// Constants of a pair of [`Material`](crate::core::material::Material)s.
    pub fn of_materials(
        body1: crate::core::material::Material,
        body2: crate::core::material::Material,
    ) -> Self {
        Self::two_bodies(
            body1.shear_modulus_pa(),
            body1.poisson_ratio,
            body2.shear_modulus_pa(),
            body2.poisson_ratio,
        )
    }
}

/// `ln(t + r)` with `r = sqrt(t² + s²)`, written without cancellation for `t < 0`:
/// `ln(t + r) = ln(s² / (r − t))`.
fn ln_t_plus_r(t: f64, s: f64, r: f64) -> f64 {
    if t >= 0.0 {
        (t + r).ln()
    } else {
        (s * s / (r - t)).ln()
    }
}

/// Corner function of `∫∫ ξ²/ρ³ dξ dη`: `η ln(ξ + ρ)` (→ 0 as η → 0).
fn cerruti_corner_xx(xi: f64, eta: f64) -> f64 {
    if eta == 0.0 {
        0.0
    } else {
        eta * ln_t_plus_r(xi, eta, xi.hypot(eta))
    }
}

/// Corner function of `∫∫ ξη/ρ³ dξ dη`: `−ρ`.
fn cerruti_corner_xy(xi: f64, eta: f64) -> f64 {
    -xi.hypot(eta)
}

/// Signed corner sum `[F]` over the element `|x'| ≤ a, |y'| ≤ b` seen from `(x, y)`.
fn corner_sum(f: impl Fn(f64, f64) -> f64, x: f64, y: f64, a: f64, b: f64) -> f64 {
    f(x + a, y + b) - f(x + a, y - b) - f(x - a, y + b) + f(x - a, y - b)
}

/// Relative tangential displacement `u_x` at `(x, y)` per unit uniform shear `q_x` on the element
/// `|x'| ≤ a, |y'| ≤ b` (m/Pa): `c_iso·[ξ ln(η+ρ) + η ln(ξ+ρ)] + c_dir·[η ln(ξ+ρ)]`.
/// By symmetry `u_y` per unit `q_y` is `cerruti_uxx(y, x, b, a, k)`.
pub fn cerruti_uxx(x: f64, y: f64, a: f64, b: f64, k: CerrutiConstants) -> f64 {
    k.c_iso * corner_sum(love_corner, x, y, a, b)
        + k.c_dir * corner_sum(cerruti_corner_xx, x, y, a, b)
}

/// Relative tangential displacement `u_y` at `(x, y)` per unit uniform shear `q_x` on the element
/// (m/Pa), equal to `u_x` per unit `q_y` (reciprocity): `c_dir·[−ρ]`.
pub fn cerruti_uxy(x: f64, y: f64, a: f64, b: f64, k: CerrutiConstants) -> f64 {
    k.c_dir * corner_sum(cerruti_corner_xy, x, y, a, b)
}

/// Relative tangential displacement `u_y` at `(x, y)` per unit uniform shear `q_y` (m/Pa).
pub fn cerruti_uyy(x: f64, y: f64, a: f64, b: f64, k: CerrutiConstants) -> f64 {
    cerruti_uxx(y, x, b, a, k)
}

/// The three kernel spectra of the tangential compliance for one plan:
/// `ũ_x = K_xx q̃_x + K_xy q̃_y`, `ũ_y = K_xy q̃_x + K_yy q̃_y`.
#[derive(Debug, Clone)]
pub struct CerrutiSpectra {
    /// `K_xx`: `u_x` per unit `q_x` (m/Pa).
    pub xx: KernelSpectrum,
    /// `K_xy`: `u_x` per unit `q_y`, equal to `u_y` per unit `q_x` (m/Pa).
    pub xy: KernelSpectrum,
    /// `K_yy`: `u_y` per unit `q_y` (m/Pa).
    pub yy: KernelSpectrum,
}

/// Kernel spectra of the tangential (Cerruti) compliance for a plan.
///
/// - Zero-padded plans: the element coefficients [`cerruti_uxx`], [`cerruti_uxy`],
///   [`cerruti_uyy`] at every signed offset (DC-FFT).
/// - Periodic plans: the exact periodic compliance, the Fourier transform of the point-force
///   solution (`FT[1/ρ] = 2π/q`, `FT[x²/ρ³] = 2π q_y²/q³`, `FT[xy/ρ³] = −2π q_x q_y/q³`):
///   `K_xx = 2π(c_iso/q + c_dir q_y²/q³)`, `K_yy = 2π(c_iso/q + c_dir q_x²/q³)`,
///   `K_xy = −2π c_dir q_x q_y/q³` (zero at the Nyquist wavenumbers, where an odd kernel has no
///   coefficient); for one body these reduce to the familiar
///   `(1 − ν q_x²/q²)/(G q)` (e.g. the Kelvin/Cerruti kernels of tamaas). The `q = 0` term is
///   zero: the mean displacement is carried by the rigid tangential shift.
pub fn cerruti_spectra(plan: &FftPlan, dx: f64, dy: f64, k: CerrutiConstants) -> CerrutiSpectra {
    let (a, b) = (0.5 * dx, 0.5 * dy);
    match plan.boundary() {
        Boundary::ZeroPadded => CerrutiSpectra {
            xx: plan.kernel_spectrum(|di, dj| cerruti_uxx(di as f64 * dx, dj as f64 * dy, a, b, k)),
            xy: plan.kernel_spectrum(|di, dj| cerruti_uxy(di as f64 * dx, dj as f64 * dy, a, b, k)),
            yy: plan.kernel_spectrum(|di, dj| cerruti_uyy(di as f64 * dx, dj as f64 * dy, a, b, k)),
        },
        Boundary::Periodic => {
            let two_pi = 2.0 * std::f64::consts::PI;
            let spec = |f: &(dyn Fn(f64, f64, f64) -> f64 + Sync)| {
                plan.spectrum_from_wavenumbers(dx, dy, |qx, qy| {
                    let q = qx.hypot(qy);
                    if q == 0.0 {
                        Complex64::new(0.0, 0.0)
                    } else {
                        Complex64::new(two_pi * f(qx, qy, q), 0.0)
                    }
                })
            };
            // `K_xy` is real and odd in x and in y, and a real odd sequence has no Nyquist
            // coefficient: on an even grid the terms at q_x = π/dx or q_y = π/dy are zero.
            let nyquist = |q: f64, d: f64| q.abs() >= (1.0 - 1e-12) * std::f64::consts::PI / d;
            CerrutiSpectra {
                xx: spec(&|_qx, qy, q| k.c_iso / q + k.c_dir * qy * qy / (q * q * q)),
                xy: spec(&|qx, qy, q| {
                    if nyquist(qx, dx) || nyquist(qy, dy) {
                        0.0
                    } else {
                        -k.c_dir * qx * qy / (q * q * q)
                    }
                }),
                yy: spec(&|qx, _qy, q| k.c_iso / q + k.c_dir * qx * qx / (q * q * q)),
            }
        }
    }
}

#[cfg(test)]
mod cerruti_tests {
    use super::*;

    const K: CerrutiConstants = CerrutiConstants {
        c_iso: 0.7,
        c_dir: 0.3,
    };

    /// Point-force Cerruti solution times the element area.
    fn point(x: f64, y: f64, area: f64) -> (f64, f64, f64) {
        let r = x.hypot(y);
        let r3 = r * r * r;
        (
            area * (K.c_iso / r + K.c_dir * x * x / r3),
            area * K.c_dir * x * y / r3,
            area * (K.c_iso / r + K.c_dir * y * y / r3),
        )
    }

    /// Midpoint quadrature of the point-force solution over the element (field point outside).
    fn quadrature(x: f64, y: f64, a: f64, b: f64) -> (f64, f64, f64) {
        let n = 400;
        let (hx, hy) = (2.0 * a / n as f64, 2.0 * b / n as f64);
        let mut s = (0.0, 0.0, 0.0);
        for i in 0..n {
            for j in 0..n {
                let xs = -a + (i as f64 + 0.5) * hx;
                let ys = -b + (j as f64 + 0.5) * hy;
                let p = point(x - xs, y - ys, hx * hy);
                s.0 += p.0;
                s.1 += p.1;
                s.2 += p.2;
            }
        }
        s
    }

    #[test]
    fn far_field_is_cerruti_point_force() {
        let (a, b) = (0.5, 0.25);
        for &(x, y) in &[(300.0, 0.0), (0.0, 300.0), (200.0, 150.0), (-170.0, 220.0)] {
            let want = point(x, y, 4.0 * a * b);
            let got = (
                cerruti_uxx(x, y, a, b, K),
                cerruti_uxy(x, y, a, b, K),
                cerruti_uyy(x, y, a, b, K),
            );
            assert!((got.0 / want.0 - 1.0).abs() < 1e-5, "{got:?} {want:?}");
            assert!((got.1 - want.1).abs() < 1e-4 * want.0, "{got:?} {want:?}");
            assert!((got.2 / want.2 - 1.0).abs() < 1e-5, "{got:?} {want:?}");
        }
    }

    #[test]
    fn near_field_matches_quadrature() {
        // Field points one to two element sizes away, where the far field is poor.
        let (a, b) = (0.5, 0.35);
        for &(x, y) in &[(1.2, 0.3), (0.4, 1.0), (-1.5, -0.9), (1.1, -1.3)] {
            let want = quadrature(x, y, a, b);
            let got = (
                cerruti_uxx(x, y, a, b, K),
                cerruti_uxy(x, y, a, b, K),
                cerruti_uyy(x, y, a, b, K),
            );
            assert!(
                (got.0 - want.0).abs() < 1e-5 * want.0.abs(),
                "{got:?} {want:?}"
            );
            assert!(
                (got.1 - want.1).abs() < 1e-4 * want.1.abs(),
                "{got:?} {want:?}"
            );
            assert!(
                (got.2 - want.2).abs() < 1e-5 * want.2.abs(),
                "{got:?} {want:?}"
            );
        }
    }

    #[test]
    fn centre_of_square_and_symmetries() {
        // At the centre of a square, ∫∫ξ²/ρ³ = ∫∫η²/ρ³ = ½∫∫1/ρ = 4a·ln(1+√2), ∫∫ξη/ρ³ = 0.
        let a = 1.0;
        let half = 4.0 * a * (1.0 + 2f64.sqrt()).ln();
        let want = K.c_iso * 2.0 * half + K.c_dir * half;
        assert!((cerruti_uxx(0.0, 0.0, a, a, K) - want).abs() < 1e-12);
        assert!(cerruti_uxy(0.0, 0.0, a, a, K).abs() < 1e-12);
        // u_xx even in x and y; u_xy odd in each; finite on element edges.
        let (a, b) = (0.5, 0.25);
        for &(x, y) in &[
            (0.5, 0.0),
            (0.0, 0.25),
            (0.5, 0.25),
            (1.0, 0.5),
            (0.7, -0.1),
        ] {
            let u = cerruti_uxx(x, y, a, b, K);
            assert!(u.is_finite() && u > 0.0);
            assert!((u - cerruti_uxx(-x, y, a, b, K)).abs() < 1e-14);
            assert!((u - cerruti_uxx(x, -y, a, b, K)).abs() < 1e-14);
            let c = cerruti_uxy(x, y, a, b, K);
            assert!((c + cerruti_uxy(-x, y, a, b, K)).abs() < 1e-14);
            assert!((c + cerruti_uxy(x, -y, a, b, K)).abs() < 1e-14);
        }
    }

    #[test]
    fn periodic_spectrum_matches_element_sum_for_a_long_wave() {
        // A cosine shear traction q_x = cos(2πx/L) on a periodic grid: the exact response is
        // u_x = 2π·c_iso/k · cos (q_y = 0), u_y = 0. The zero-padded element kernel on a large
        // window approaches it in the middle, the periodic spectrum reproduces it exactly.
        let (nx, ny, dx) = (32, 8, 1.0);
        let plan = FftPlan::new(nx, ny, Boundary::Periodic);
        let s = cerruti_spectra(&plan, dx, dx, K);
        let kx = 2.0 * std::f64::consts::PI / (nx as f64 * dx);
        let q = ndarray::Array2::from_shape_fn((nx, ny), |(i, _)| (kx * i as f64 * dx).cos());
        let ux = plan.convolve(&s.xx, &q);
        let uy = plan.convolve(&s.xy, &q);
        let amp = 2.0 * std::f64::consts::PI * K.c_iso / kx;
        for ((i, _), v) in ux.indexed_iter() {
            assert!((v - amp * (kx * i as f64 * dx).cos()).abs() < 1e-10 * amp);
        }
        assert!(uy.iter().all(|v| v.abs() < 1e-10 * amp));
        // A cosine along y loaded in x: u_x = 2π(c_iso + c_dir)/k (q_x = 0 in the kernel).
        let q = ndarray::Array2::from_shape_fn((ny, nx), |(_, j)| (kx * j as f64 * dx).cos());
        let plan = FftPlan::new(ny, nx, Boundary::Periodic);
        let s = cerruti_spectra(&plan, dx, dx, K);
        let ux = plan.convolve(&s.xx, &q);
        let amp = 2.0 * std::f64::consts::PI * (K.c_iso + K.c_dir) / kx;
        for ((_, j), v) in ux.indexed_iter() {
            assert!((v - amp * (kx * j as f64 * dx).cos()).abs() < 1e-10 * amp);
        }
    }

    /// The periodic cross-compliance is odd in x and in y: a point shear in x displaces the
    /// grid lines through it (x = 0 or y = 0) not at all in y, its own point included. On even
    /// grids this needs the Nyquist coefficients of `K_xy` at zero (a real odd sequence has
    /// none); evaluated there, the self term came out at −0.072 (8², c_dir = 1, dx = 1) and
    /// −0.0091 (64²) where the symmetry demands 0.
    #[test]
    fn periodic_cross_compliance_is_odd() {
        for (nx, ny) in [(8, 8), (8, 6), (7, 8), (64, 64)] {
            let plan = FftPlan::new(nx, ny, Boundary::Periodic);
            let s = cerruti_spectra(&plan, 1.0, 1.0, K);
            let mut q = ndarray::Array2::zeros((nx, ny));
            q[[0, 0]] = 1.0;
            let uy = plan.convolve(&s.xy, &q);
            let ux = plan.convolve(&s.xx, &q);
            let scale = ux[[0, 0]];
            for i in 0..nx {
                assert!(
                    uy[[i, 0]].abs() < 1e-12 * scale,
                    "{nx}×{ny}: u_y({i}, 0) = {}",
                    uy[[i, 0]]
                );
            }
            for j in 0..ny {
                assert!(
                    uy[[0, j]].abs() < 1e-12 * scale,
                    "{nx}×{ny}: u_y(0, {j}) = {}",
                    uy[[0, j]]
                );
            }
        }
    }

    #[test]
    fn zero_padded_spectrum_is_the_element_convolution() {
        let (nx, ny, dx, dy) = (5, 4, 1.0, 0.5);
        let plan = FftPlan::new(nx, ny, Boundary::ZeroPadded);
        let s = cerruti_spectra(&plan, dx, dy, K);
        let mut qy = ndarray::Array2::zeros((nx, ny));
        qy[[1, 2]] = 1.0;
        let ux = plan.convolve(&s.xy, &qy);
        let uy = plan.convolve(&s.yy, &qy);
        for i in 0..nx {
            for j in 0..ny {
                let (x, y) = ((i as f64 - 1.0) * dx, (j as f64 - 2.0) * dy);
                assert!((ux[[i, j]] - cerruti_uxy(x, y, 0.5 * dx, 0.5 * dy, K)).abs() < 1e-12);
                assert!((uy[[i, j]] - cerruti_uyy(x, y, 0.5 * dx, 0.5 * dy, K)).abs() < 1e-12);
            }
        }
    }
}
