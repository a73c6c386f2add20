//! Hysteresis loops from accelerations: the relative displacement across a joint by double
//! integration in the frequency domain, as bolted-joint rigs measure it (accelerometers on both
//! sides; the tangential force from the inertia of a mass, `F = m·a`).
//!
//! # Method
//!
//! A steady hysteresis record is periodic. The fundamental frequency `f1` is located at the
//! largest non-zero bin of the displacement's spectrum (the acceleration's divided by `ω²`) and
//! refined by minimising the residual of
//! a least-squares fit of a few harmonics of `f1` over the whole record (golden-section search
//! within one bin): a record need not hold a whole number of periods, nor a period a whole
//! number of samples. The acceleration is then fitted by the harmonics `k = 1…H` of `f1`
//! (`H` up to [`MAX_HARMONICS`], below the Nyquist frequency), and each is integrated twice
//! exactly,
//!
//! ```text
//! a(t) = Σ_k (c_k·cos kωt + s_k·sin kωt)   ⇒   x(t) = −Σ_k (c_k·cos kωt + s_k·sin kωt)/(kω)²
//! ```
//!
//! The mean displacement and any drift are not observable from an acceleration (the integration
//! constants): the displacement has no constant term (zero mean over a period), which leaves a hysteresis loop's shape, area and
//! force–displacement relation unchanged for elements that do not remember an absolute position.
//! The fit's relative RMS residual is reported: content that is not periodic at `f1` (noise,
//! transients, drift) is what the harmonics do not carry.

use crate::core::error::{Error, Result};
use nalgebra::{DMatrix, DVector};
use std::f64::consts::PI;

/// Most harmonics of the fundamental fitted to the acceleration.
pub const MAX_HARMONICS: usize = 40;

/// Harmonics used to refine the fundamental frequency.
const REFINE_HARMONICS: usize = 5;

/// The displacement from an acceleration and how it was obtained.
#[derive(Debug, Clone, PartialEq)]
pub struct Integrated {
    /// Displacement at every sample (m), without a constant term.
    pub displacement_m: Vec<f64>,
    /// Fundamental frequency (Hz).
    pub fundamental_hz: f64,
    /// Harmonics of the fundamental fitted.
    pub harmonics: usize,
    /// Relative RMS residual of the harmonic fit of the acceleration.
    pub fit_residual: f64,
}

impl Integrated {
    /// One line for reports.
    pub fn describe(&self, column: &str) -> String {
        format!(
            "displacement = double integral of `{column}` (m/s²) in the frequency domain: \
             {} harmonics of {:.6} Hz fitted over the record (relative RMS residual {:.2e}), \
             mean and drift not observable (no constant term)",
            self.harmonics, self.fundamental_hz, self.fit_residual
        )
    }
}

/// Least-squares fit of harmonics `1..=h` of `omega` (rad/s) to `a` at times `t`: the
/// coefficients `[c_1, s_1, c_2, s_2, …]` and the residual sum of squares. A constant is fitted
/// too (an accelerometer's offset) and left out of the coefficients.
fn harmonic_fit(t: &[f64], a: &[f64], omega: f64, h: usize) -> Option<(Vec<f64>, f64)> {
    let cols = 2 * h + 1;
    let t0 = t[0];
    let mut basis = DMatrix::zeros(t.len(), cols);
    for (i, &ti) in t.iter().enumerate() {
        let (s1, c1) = (omega * (ti - t0)).sin_cos();
        let (mut sk, mut ck) = (s1, c1);
        basis[(i, 0)] = 1.0;
        for k in 0..h {
            basis[(i, 1 + 2 * k)] = ck;
            basis[(i, 2 + 2 * k)] = sk;
            // Angle addition: (k+1)ωt from kωt and ωt.
            (sk, ck) = (sk * c1 + ck * s1, ck * c1 - sk * s1);
        }
    }
    let y = DVector::from_column_slice(a);
    let qr = basis.clone().qr();
    let coef = qr.r().solve_upper_triangular(&(qr.q().transpose() * &y))?;
    let residual = (&basis * &coef - &y).norm_squared();
    Some((coef.iter().skip(1).copied().collect(), residual))
}

/// The displacement whose second derivative is the acceleration `a` (m/s²) sampled at the
/// uniformly spaced times `t` (s); see the module documentation. `what` names the column in
/// errors.
pub fn displacement_from_acceleration(t: &[f64], a: &[f64], what: &str) -> Result<Integrated> {
    let n = t.len();
    if n < 16 || a.len() != n {
        return Err(Error::param(
            what,
            format!("{n} samples: too few to integrate an acceleration (at least 16)"),
        ));
    }
    let dt = (t[n - 1] - t[0]) / (n - 1) as f64;
    // Spectrum of the mean-removed acceleration, Hann-windowed (its side lobes fall fast, so
    // that the ω² division below does not lift the leakage of a non-whole number of periods
    // above the fundamental), divided by ω²: the displacement's spectrum, whose fundamental
    // dominates a loop record while the acceleration's largest line may be a harmonic.
    let mean = a.iter().sum::<f64>() / n as f64;
    let mut input: Vec<f64> = a
        .iter()
        .enumerate()
        .map(|(i, &v)| (v - mean) * (PI * i as f64 / (n - 1) as f64).sin().powi(2))
        .collect();
    let fft = realfft::RealFftPlanner::<f64>::new().plan_fft_forward(n);
    let mut buf = fft.make_output_vec();
    fft.process(&mut input, &mut buf)
        .map_err(|e| Error::Data(format!("FFT of `{what}`: {e}")))?;
    let (peak, _) = buf[2..buf.len() - 1]
        .iter()
        .enumerate()
        .map(|(i, c)| (i + 2, c.norm() / ((i + 2) * (i + 2)) as f64))
        .fold((0, 0.0), |best, b| if b.1 > best.1 { b } else { best });
    let span = n as f64 * dt;
    if peak < 2 {
        return Err(Error::param(
            what,
            "the acceleration holds less than two periods of its fundamental: a hysteresis \
             record needs whole cycles",
        ));
    }
    // Refine f1 within one bin by the residual of a few harmonics.
    let nyquist_harmonics = |f: f64| ((0.5 / dt) / f).floor() as usize;
    let residual_at = |f: f64| {
        let h = REFINE_HARMONICS
            .min(nyquist_harmonics(f).saturating_sub(1))
            .max(1);
        harmonic_fit(t, a, 2.0 * PI * f, h).map_or(f64::INFINITY, |(_, r)| r)
    };
    let (mut lo, mut hi) = ((peak as f64 - 1.0) / span, (peak as f64 + 1.0) / span);
    let g = 0.5 * (5f64.sqrt() - 1.0);
    let (mut x1, mut x2) = (hi - g * (hi - lo), lo + g * (hi - lo));
    let (mut r1, mut r2) = (residual_at(x1), residual_at(x2));
    for _ in 0..80 {
        if r1 < r2 {
            hi = x2;
            (x2, r2) = (x1, r1);
            x1 = hi - g * (hi - lo);
            r1 = residual_at(x1);
        } else {
            lo = x1;
            (x1, r1) = (x2, r2);
            x2 = lo + g * (hi - lo);
            r2 = residual_at(x2);
        }
        if hi - lo <= 1e-13 * hi {
            break;
        }
    }
    let f1 = 0.5 * (lo + hi);
    let h = MAX_HARMONICS
        .min(nyquist_harmonics(f1).saturating_sub(1))
        .max(1);
    let omega = 2.0 * PI * f1;
    let (coef, residual) = harmonic_fit(t, a, omega, h)
        .ok_or_else(|| Error::param(what, "the harmonic fit of the acceleration is singular"))?;
    let total = a.iter().map(|v| (v - mean).powi(2)).sum::<f64>();
    let t0 = t[0];
    let displacement_m = t
        .iter()
        .map(|&ti| {
            (0..h)
                .map(|k| {
                    let w = (k + 1) as f64 * omega;
                    let (s, c) = (w * (ti - t0)).sin_cos();
                    -(coef[2 * k] * c + coef[2 * k + 1] * s) / (w * w)
                })
                .sum::<f64>()
        })
        .collect();
    Ok(Integrated {
        displacement_m,
        fundamental_hz: f1,
        harmonics: h,
        fit_residual: (residual / total.max(f64::MIN_POSITIVE)).sqrt(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A periodic displacement with harmonics, sampled at a rate that is not a multiple of its
    /// frequency over a record that is not a whole number of periods: its exact second
    /// derivative integrates back to it (less its mean) to the rounding of the fit.
    #[test]
    fn double_integration_recovers_a_periodic_displacement() {
        let (f, fs) = (7.3, 2000.0);
        let w = 2.0 * PI * f;
        let t: Vec<f64> = (0..(12.4 * fs / f) as usize)
            .map(|i| i as f64 / fs)
            .collect();
        let x = |t: f64| {
            1e-4 * (w * t).sin() + 2e-5 * (3.0 * w * t + 0.4).sin() + 3e-6 * (5.0 * w * t).cos()
        };
        let acc = |t: f64| {
            -w * w
                * (1e-4 * (w * t).sin()
                    + 9.0 * 2e-5 * (3.0 * w * t + 0.4).sin()
                    + 25.0 * 3e-6 * (5.0 * w * t).cos())
        };
        let a: Vec<f64> = t.iter().map(|&t| acc(t) + 0.3).collect();
        let r = displacement_from_acceleration(&t, &a, "a").unwrap();
        assert!(
            (r.fundamental_hz / f - 1.0).abs() < 1e-9,
            "{}",
            r.fundamental_hz
        );
        // The displacement has no constant term: it comes back as it was, at every sample.
        let err = t
            .iter()
            .zip(&r.displacement_m)
            .map(|(&ti, g)| (x(ti) - g).abs())
            .fold(0.0, f64::max);
        assert!(err < 1e-9 * 1e-4, "{err:e}");
        assert!(r.fit_residual < 1e-9, "{}", r.fit_residual);
        // Too short a record is refused by name.
        let e = displacement_from_acceleration(&t[..10], &a[..10], "a_rel_m_per_s2")
            .unwrap_err()
            .to_string();
        assert!(e.contains("a_rel_m_per_s2"), "{e}");
    }
}
