//! Amplitude-dependent natural frequency and damping ratio estimated directly from the measured
//! sweeps (no nonlinear model), and the resonance of a sampled curve.
//!
//! # Equivalent linear mode per level
//!
//! Each sweep is fitted by one linear mode, `X(ω) = R/(a − ω² + iωb)` (receptance per unit
//! force, `a = ω_n²`, `b = 2ζω_n`, `R = 1/m` the drive-point modal constant), by the
//! Sanathanan–Koerner iteration (1963, *IEEE Trans. Autom. Control* 8:56): the linearised
//! equations `a·X_i + b·iω_i·X_i − R = ω_i²·X_i` are solved by weighted least squares with the
//! weights `1/|a − ω_i² + iω_i·b|` of the previous iterate, which converges to the least-squares
//! fit of `X` itself. A force-controlled sweep of a nonlinear structure is an approximation of a
//! linear mode (the amplitude changes along the sweep), so these fits give one point per level.
//!
//! # Pointwise inversion
//!
//! With one modal constant `R` for every level (the modal mass does not depend on the
//! amplitude), every row near resonance gives its own equivalent mode:
//! `R/X_i = ω_n,i² − ω_i² + 2iζ_i·ω_n,i·ω_i`, at the row's drive-point displacement amplitude
//! `|X_i|·F_i`. Rows inside the half-power band are used (outside it the imaginary part is a
//! small difference of large numbers).
//!
//! # The modal constant
//!
//! The equivalent linear fit of the lowest level gives a first `R̂`, but a nonlinear sweep is
//! not a linear mode and its fit's constant is biased (on the Brake–Reuss files the four
//! levels' fits give modal masses of 2.54 down to 1.95 kg). A stepped sine passes every
//! amplitude twice, and for one nonlinear mode the two rows at the same amplitude share one
//! natural frequency; computed with `R̂ = ρR` they differ instead by
//! `f̂_n,l² − f̂_n,e² = (1 − ρ)(f_l² − f_e²)` (drive frequencies `f_e`, `f_l`). The median of
//! that shift over the pairs of the reference level — of three or more levels whose sides can
//! be compared the one of median shift, of two the lowest mean force,
//! [`super::stationarity::reference_shift`] — gives `ρ`, and the inversion is redone
//! with `R = R̂/ρ`, under which that level's sides agree (on the Brake–Reuss files 2.02 kg in
//! place of level 1's 2.54 kg). The damping ratios only scale with `ρ`, the natural frequencies'
//! side-to-side spread is what changes. Kept at `R̂` when the reference level has fewer than
//! [`MIN_REFERENCE_PAIRS`] pairs or a shift beyond [`MAX_REFERENCE_SHIFT`].

use super::measured::{Quantity, Sweep};
use crate::core::error::{Error, Result};
use nalgebra::{Matrix3, Vector3};
use realfft::num_complex::Complex64;
use serde::Serialize;
use std::f64::consts::TAU;

/// An equivalent linear mode.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LinearMode {
    /// Natural frequency `f_n` (Hz).
    pub frequency_hz: f64,
    /// Viscous damping ratio `ζ` (dimensionless).
    pub damping_ratio: f64,
    /// `1/R` (kg).
    pub modal_mass_kg: f64,
    /// RMS misfit of the fit relative to the peak `|X|`.
    pub relative_rms: f64,
}

impl LinearMode {
    /// Receptance at `ω` (m/N).
    pub fn receptance(&self, omega: f64) -> Complex64 {
        let wn = TAU * self.frequency_hz;
        1.0 / (self.modal_mass_kg
            * Complex64::new(
                wn * wn - omega * omega,
                2.0 * self.damping_ratio * wn * omega,
            ))
    }
}

/// Receptance per unit force of every row from the complex response per unit force of the
/// measured quantity.
pub fn receptance(quantity: Quantity, omegas: &[f64], frf: &[Complex64]) -> Vec<Complex64> {
    omegas
        .iter()
        .zip(frf)
        .map(|(&w, y)| y / quantity.from_displacement(w))
        .collect()
}

/// Equivalent linear mode of one sweep (Sanathanan–Koerner, 30 iterations or until the
/// parameters change by less than 1e-12 relative).
pub fn fit_linear_mode(omegas: &[f64], x: &[Complex64]) -> Result<LinearMode> {
    let mut w: Vec<f64> = vec![1.0; x.len()];
    let mut theta = Vector3::zeros();
    for _ in 0..30 {
        let mut ata = Matrix3::zeros();
        let mut atb = Vector3::zeros();
        for ((&om, xi), wi) in omegas.iter().zip(x).zip(&w) {
            // Real and imaginary rows of [X, iωX, −1]·(a, b, R) = ω²X.
            let ix = Complex64::new(0.0, om) * xi;
            let rhs = xi * om * om;
            for (row, b) in [
                (Vector3::new(xi.re, ix.re, -1.0), rhs.re),
                (Vector3::new(xi.im, ix.im, 0.0), rhs.im),
            ] {
                ata += row * row.transpose() * (wi * wi);
                atb += row * (b * wi * wi);
            }
        }
        let new = ata
            .lu()
            .solve(&atb)
            .ok_or_else(|| Error::Data("equivalent linear fit: singular equations".into()))?;
        let change = (new - theta).norm() / new.norm().max(f64::MIN_POSITIVE);
        theta = new;
        for (wi, &om) in w.iter_mut().zip(omegas) {
            *wi = 1.0 / Complex64::new(theta[0] - om * om, om * theta[1]).norm();
        }
        if change < 1e-12 {
            break;
        }
    }
    let (a, b, r) = (theta[0], theta[1], theta[2]);
    if !(a > 0.0 && b > 0.0 && r > 0.0) {
        return Err(Error::Data(format!(
            "the sweep is not a single lightly damped mode: equivalent linear fit gives \
             ω_n² = {a:.4e}, 2ζω_n = {b:.4e}, 1/m = {r:.4e}"
        )));
    }
    let wn = a.sqrt();
    let mode = LinearMode {
        frequency_hz: wn / TAU,
        damping_ratio: b / (2.0 * wn),
        modal_mass_kg: 1.0 / r,
        relative_rms: 0.0,
    };
    let peak = x.iter().map(|v| v.norm()).fold(0.0, f64::max);
    let rms = (omegas
        .iter()
        .zip(x)
        .map(|(&om, xi)| (mode.receptance(om) - xi).norm_sqr())
        .sum::<f64>()
        / x.len() as f64)
        .sqrt();
    Ok(LinearMode {
        relative_rms: rms / peak,
        ..mode
    })
}

/// One point of a backbone.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct BackbonePoint {
    /// Drive-point displacement amplitude (m).
    pub amplitude_m: f64,
    /// Natural frequency `f_n` at this amplitude (Hz).
    pub frequency_hz: f64,
    /// Equivalent viscous damping ratio `ζ` at this amplitude (dimensionless).
    pub damping_ratio: f64,
}

/// A pointwise estimate with its row and the sensitivity of its damping ratio to measurement
/// noise.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SidePoint {
    /// Row (0-based, file order).
    pub row: usize,
    /// The row's excitation frequency (Hz).
    pub drive_hz: f64,
    /// The estimate: amplitude, natural frequency and damping ratio.
    pub point: BackbonePoint,
    /// `|R/X| / Im(R/X)`: a relative error `ε = δX/X` of the response gives the damping ratio a
    /// relative error of this times `|ε|` (the error of `R/X` is `−(R/X)·ε`, and `ζ ∝ Im(R/X)`).
    pub damping_sensitivity: f64,
    /// `peak |X| / |X|`: a complex error of standard deviation `s·peak` per component gives the
    /// point's amplitude a relative standard deviation of `s` times this (its radial
    /// component), which moves the point along the backbone.
    pub amplitude_noise_gain: f64,
}

impl SidePoint {
    /// `(peak |X| / |X|)·|R/X| / Im(R/X)`: a complex error of standard deviation `s·peak` per
    /// component gives the damping ratio a relative standard deviation of `s` times this.
    pub fn damping_noise_gain(&self) -> f64 {
        self.amplitude_noise_gain * self.damping_sensitivity
    }

    /// `|R/X|/(2π)²` (Hz²): a relative error `ε = δX/X` of standard deviation `σ` per component
    /// gives the squared natural frequency `f_n² = (Re(R/X) + ω²)/(2π)²` an error of standard
    /// deviation `σ` times this (each component of `δ(R/X) = −(R/X)·ε` has that deviation).
    /// From the stored quantities: `|R/X| = (|R/X|/Im(R/X))·|2ζ·ω_n·ω|`.
    pub fn frequency_squared_noise_gain_hz2(&self) -> f64 {
        self.damping_sensitivity
            * (2.0 * self.point.damping_ratio * self.point.frequency_hz * self.drive_hz).abs()
    }
}

/// The backbone estimated from one sweep.
#[derive(Debug, Clone, Serialize)]
pub struct LevelBackbone {
    /// File name of the sweep.
    pub file: String,
    /// Mean measured drive force amplitude of the sweep (N).
    pub mean_force_n: f64,
    /// Equivalent linear mode of the whole sweep.
    pub linear: LinearMode,
    /// Drive-point displacement amplitude at the largest response per force (m).
    pub peak_amplitude_m: f64,
    /// Pointwise inversion of the rows in the half-power band.
    pub points: Vec<BackbonePoint>,
    /// Row (file order) of each of `points`.
    #[serde(skip)]
    pub point_rows: Vec<usize>,
    /// Pointwise inversion of the rows down to half the peak: the band of the two sides'
    /// comparison ([`super::stationarity`]).
    #[serde(skip)]
    pub side_points: Vec<SidePoint>,
    /// Row of the largest receptance, the top of the half-power band.
    #[serde(skip)]
    pub resonance_row: usize,
    /// `1/R` (kg): the modal mass the pointwise inversion used, the same for every level of a
    /// [`from_data`] call (see there).
    pub pointwise_modal_mass_kg: f64,
}

/// Half-power band: indices of the rows whose `|Y|` is at least `peak/√2`, as the contiguous
/// run around the peak.
pub fn half_power_rows(y: &[f64]) -> (usize, usize) {
    band_rows(y, std::f64::consts::FRAC_1_SQRT_2)
}

/// Indices of the rows whose `|Y|` is at least `fraction·peak`, as the contiguous run around
/// the peak.
pub fn band_rows(y: &[f64], fraction: f64) -> (usize, usize) {
    let ip = (0..y.len())
        .max_by(|&a, &b| y[a].total_cmp(&y[b]))
        .expect("non-empty");
    let lim = y[ip] * fraction;
    let (mut lo, mut hi) = (ip, ip);
    while lo > 0 && y[lo - 1] >= lim {
        lo -= 1;
    }
    while hi + 1 < y.len() && y[hi + 1] >= lim {
        hi += 1;
    }
    (lo, hi)
}

/// Lower end of the band of the two sides' comparison, as a fraction of the peak `|X|` (half
/// the peak: the imaginary part of `R/X` is then half of its magnitude, so a relative error of
/// the response perturbs the damping ratio at most twice as much as at resonance).
pub const SIDE_BAND: f64 = 0.5;

/// Backbones of several sweeps: an equivalent linear mode per sweep and the pointwise
/// inversion with one modal constant for all, the one under which the two sides of the
/// reference level agree in natural frequency (module documentation; without a level whose
/// sides can be compared, that of the linear fit of the sweep of lowest mean force).
pub fn from_data(sweeps: &[Sweep], frfs: &[Vec<Complex64>]) -> Result<Vec<LevelBackbone>> {
    let mut fits = Vec::with_capacity(sweeps.len());
    for (s, y) in sweeps.iter().zip(frfs) {
        let om: Vec<f64> = s.rows.iter().map(|r| r.omega()).collect();
        let x = receptance(s.quantity, &om, y);
        let lin = fit_linear_mode(&om, &x)
            .map_err(|e| Error::Data(format!("{}: {e}", s.path.display())))?;
        fits.push((om, x, lin));
    }
    let lowest = (0..sweeps.len())
        .min_by(|&a, &b| {
            sweeps[a]
                .mean_force_n()
                .total_cmp(&sweeps[b].mean_force_n())
        })
        .ok_or_else(|| Error::Data("no sweep".into()))?;
    let linear_r = 1.0 / fits[lowest].2.modal_mass_kg;
    let first = invert_levels(sweeps, &fits, linear_r);
    Ok(
        match super::stationarity::reference_shift(&first)
            .filter(|s| s.pairs >= MIN_REFERENCE_PAIRS && s.shift.abs() <= MAX_REFERENCE_SHIFT)
        {
            Some(s) => invert_levels(sweeps, &fits, linear_r / (1.0 - s.shift)),
            None => first,
        },
    )
}

/// Fewest compared pairs of the reference level for its median shift to set the modal constant.
pub const MIN_REFERENCE_PAIRS: usize = 3;
/// Largest reference shift `1 − R̂/R` taken as the linear fit's error of the modal constant
/// (beyond it the linear fit would be off by more than a factor 1.5 to 2, far beyond its bias
/// on the measured data, 20 %: the sides are then taken as not one mode's and the linear fit's
/// constant is kept).
pub const MAX_REFERENCE_SHIFT: f64 = 0.5;

type LevelFit = (Vec<f64>, Vec<Complex64>, LinearMode);

/// The pointwise inversion of every level with the modal constant `r` (1/kg).
fn invert_levels(sweeps: &[Sweep], fits: &[LevelFit], r: f64) -> Vec<LevelBackbone> {
    sweeps
        .iter()
        .zip(fits)
        .map(|(s, (om, x, lin))| {
            let mag: Vec<f64> = x.iter().map(|v| v.norm()).collect();
            let ip = s.peak_row();
            let (lo, hi) = half_power_rows(&mag);
            let peak = mag.iter().copied().fold(0.0, f64::max);
            let invert = |(lo, hi): (usize, usize)| -> Vec<SidePoint> {
                (lo..=hi)
                    .filter_map(|i| {
                        let point = pointwise_mode(r, om[i], x[i], s.rows[i].force_n)?;
                        let d = r / x[i];
                        Some(SidePoint {
                            row: i,
                            drive_hz: s.rows[i].frequency_hz,
                            point,
                            damping_sensitivity: d.norm() / d.im.abs(),
                            amplitude_noise_gain: peak / mag[i],
                        })
                    })
                    .collect()
            };
            let (point_rows, points) = invert((lo, hi))
                .into_iter()
                .map(|p| (p.row, p.point))
                .unzip();
            let side_points = invert(band_rows(&mag, SIDE_BAND));
            // The top of the band (`band_rows` grows it around the largest |X|).
            let resonance_row = (lo..=hi)
                .max_by(|&a, &b| mag[a].total_cmp(&mag[b]))
                .expect("the band holds its peak row");
            LevelBackbone {
                file: s.name(),
                mean_force_n: s.mean_force_n(),
                linear: *lin,
                peak_amplitude_m: mag[ip] * s.rows[ip].force_n,
                points,
                point_rows,
                side_points,
                resonance_row,
                pointwise_modal_mass_kg: 1.0 / r,
            }
        })
        .collect()
}

/// Pointwise inversion of one row (see the module documentation): the equivalent mode
/// `R/X = ω_n² − ω² + 2iζ·ω_n·ω` of receptance `x` (m/N) at `ω` (rad/s) with modal constant
/// `r = 1/m` (1/kg), at the drive-point amplitude `|x|·F`; `None` where `ω_n² ≤ 0`.
pub fn pointwise_mode(r: f64, omega: f64, x: Complex64, force_n: f64) -> Option<BackbonePoint> {
    let z = r / x;
    let wn2 = z.re + omega * omega;
    (wn2 > 0.0).then(|| {
        let wn = wn2.sqrt();
        BackbonePoint {
            amplitude_m: x.norm() * force_n,
            frequency_hz: wn / TAU,
            damping_ratio: z.im / (2.0 * wn * omega),
        }
    })
}

/// Equivalent linear mode of a response per unit force `y` (the level's quantity, `e^{iωt}`) at
/// one level's rows — the estimator [`from_data`] applies to each measured sweep, applied to a
/// model's response at the same rows, so that a model's backbone is compared with the data's
/// like for like — as a backbone point at the response's peak displacement amplitude. `None`
/// where the response has failed rows or no resonance the fit can place (a model whose mode
/// lies outside the measured band).
pub fn equivalent_mode(
    quantity: Quantity,
    omegas: &[f64],
    forces_n: &[f64],
    y: &[Complex64],
) -> Option<BackbonePoint> {
    if y.iter().any(|v| !(v.re.is_finite() && v.im.is_finite())) {
        return None;
    }
    let x = receptance(quantity, omegas, y);
    let lin = fit_linear_mode(omegas, &x).ok()?;
    let (w_lo, w_hi) = omegas
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), &w| (a.min(w), b.max(w)));
    let wn = TAU * lin.frequency_hz;
    let inside = wn >= w_lo && wn <= w_hi && lin.damping_ratio > 0.0 && lin.modal_mass_kg > 0.0;
    let ip = (0..x.len()).max_by(|&a, &b| x[a].norm().total_cmp(&x[b].norm()))?;
    inside.then(|| BackbonePoint {
        amplitude_m: x[ip].norm() * forces_n[ip],
        frequency_hz: lin.frequency_hz,
        damping_ratio: lin.damping_ratio,
    })
}

/// Phase resonance of a sampled drive-point receptance `x` (m/N, `e^{iωt}` convention): the
/// frequency where the displacement is in quadrature with the force (`Re x = 0`, `Im x < 0`),
/// by linear interpolation of the dynamic stiffness `Re(1/x)` between the two rows of the sign
/// change nearest to `near_hz`; `None` without such a change. For a linear mode
/// `Re(1/x) = k − mω²` at any damping, so that it is the undamped natural frequency to the
/// interpolation's `Δf²/8f` (`Re x` itself bends sharply within the half-power band and would
/// be off by a tenth of the step); for a nonlinear mode it is the backbone at the response's
/// amplitude — the phase-resonance criterion of nonlinear modal testing (Peeters, Kerschen &
/// Golinval 2011, *MSSP* 25:1227). Unlike the amplitude peak, it does not move when the
/// shaker's force dips at resonance.
pub fn phase_resonance(freqs: &[f64], x: &[Complex64], near_hz: f64) -> Option<f64> {
    (0..x.len().saturating_sub(1))
        .filter_map(|i| {
            let (a, b) = (x[i].inv(), x[i + 1].inv());
            let crosses = a.re.is_finite()
                && b.re.is_finite()
                && (a.re > 0.0) != (b.re > 0.0)
                && a.im + b.im > 0.0;
            crosses.then(|| freqs[i] + a.re / (a.re - b.re) * (freqs[i + 1] - freqs[i]))
        })
        .min_by(|f1, f2| (f1 - near_hz).abs().total_cmp(&(f2 - near_hz).abs()))
}

/// Resonance of a sampled amplitude curve: the vertex of the parabola through the largest
/// sample and its two neighbours (the sample itself at an end of the sweep). Returns
/// `(frequency (Hz), peak value)`.
pub fn resonance(freqs: &[f64], amps: &[f64]) -> (f64, f64) {
    let i = (0..amps.len())
        .filter(|&i| amps[i].is_finite())
        .max_by(|&a, &b| amps[a].total_cmp(&amps[b]))
        .expect("a finite sample");
    if i == 0 || i + 1 == amps.len() || !amps[i - 1].is_finite() || !amps[i + 1].is_finite() {
        return (freqs[i], amps[i]);
    }
    let (x0, x1, x2) = (freqs[i - 1], freqs[i], freqs[i + 1]);
    let (y0, y1, y2) = (amps[i - 1], amps[i], amps[i + 1]);
    // Lagrange parabola; its vertex.
    let d01 = (y1 - y0) / (x1 - x0);
    let d12 = (y2 - y1) / (x2 - x1);
    let c2 = (d12 - d01) / (x2 - x0);
    if c2 >= 0.0 {
        return (x1, y1);
    }
    let c1 = d01 - c2 * (x0 + x1);
    let xv = (-c1 / (2.0 * c2)).clamp(x0.min(x2), x0.max(x2));
    let yv = y0 + d01 * (xv - x0) + c2 * (xv - x0) * (xv - x1);
    (xv, yv)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The phase resonance of a linear mode sampled at the Brake–Reuss beam's 0.05 Hz steps is
    /// its undamped natural frequency (to the interpolation's 1e-5 Hz), at any damping.
    #[test]
    fn phase_resonance_of_a_linear_mode_is_its_natural_frequency() {
        let (m, fn_hz) = (2.0, 80.013);
        let k = m * (TAU * fn_hz).powi(2);
        for zeta in [1e-3, 1e-2] {
            let c = 2.0 * zeta * (k * m).sqrt();
            let f: Vec<f64> = (0..41).map(|i| 79.0 + 0.05 * i as f64).collect();
            let x: Vec<Complex64> = f
                .iter()
                .map(|&fr| {
                    let w = TAU * fr;
                    1.0 / Complex64::new(k - m * w * w, c * w)
                })
                .collect();
            let f90 = phase_resonance(&f, &x, 80.0).unwrap();
            assert!((f90 - fn_hz).abs() < 1e-5, "ζ = {zeta}: {f90} vs {fn_hz}");
        }
        let x = vec![Complex64::new(1.0, -1.0); 3];
        assert!(phase_resonance(&[1.0, 2.0, 3.0], &x, 2.0).is_none());
    }

    /// An exact linear mode (with a force that varies along the sweep) is recovered to round-off.
    #[test]
    fn linear_mode_is_recovered_exactly() {
        let truth = LinearMode {
            frequency_hz: 80.3,
            damping_ratio: 2.5e-3,
            modal_mass_kg: 1.7,
            relative_rms: 0.0,
        };
        let om: Vec<f64> = (0..41).map(|i| TAU * (79.2 + 0.05 * i as f64)).collect();
        let x: Vec<Complex64> = om.iter().map(|&w| truth.receptance(w)).collect();
        let fit = fit_linear_mode(&om, &x).unwrap();
        assert!((fit.frequency_hz - truth.frequency_hz).abs() < 1e-10 * truth.frequency_hz);
        assert!((fit.damping_ratio - truth.damping_ratio).abs() < 1e-8 * truth.damping_ratio);
        assert!((fit.modal_mass_kg - truth.modal_mass_kg).abs() < 1e-8 * truth.modal_mass_kg);
        assert!(fit.relative_rms < 1e-10);
    }

    /// The parabola vertex of samples of `1 − (f − f0)²` is exact.
    #[test]
    fn resonance_of_a_parabola_is_exact() {
        let f: Vec<f64> = (0..9).map(|i| i as f64 * 0.5).collect();
        let y: Vec<f64> = f.iter().map(|x| 3.0 - (x - 2.13) * (x - 2.13)).collect();
        let (fr, yr) = resonance(&f, &y);
        assert!((fr - 2.13).abs() < 1e-12 && (yr - 3.0).abs() < 1e-12);
        // Limit 3/√2 = 2.12: row 1 (2.2) in, row 3 (2.0) out, and row 4 (2.5) out because the
        // band is the contiguous run around the peak.
        assert_eq!(half_power_rows(&[1.0, 2.2, 3.0, 2.0, 2.5]), (1, 2));
    }
}
