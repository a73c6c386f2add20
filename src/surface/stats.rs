//! Statistics of a measured or generated topography: amplitude parameters (Ra, Rq, Rsk, Rku),
//! rms slope / gradient, correlation lengths from the autocorrelation function (ACF) and the
//! power spectral density (PSD).
//!
//! Definitions follow SurfaceTopography (Jacobs, Junge & Pastewka, *Surf. Topogr.: Metrol.
//! Prop.* 5 (2017) 013001; github.com/ContactEngineering/SurfaceTopography), so the numbers agree
//! with it to round-off:
//!
//! - **Uniform profile or area**: sample moments about the mean, `Rq = [⟨(h-h̄)²⟩]^½`,
//!   `Ra = ⟨|h-h̄|⟩`, `Rsk = ⟨(h-h̄)³⟩/Rq³`, `Rku = ⟨(h-h̄)⁴⟩/Rq⁴`.
//! - **Nonuniform profile** (measured positions): the profile is the piecewise-linear
//!   interpolant of the samples and every moment is its exact integral over the span `L`; the
//!   mean is `(1/L)∫h dx` (trapezoidal rule), `Rq² = (1/3L) Σ (h_i² + h_i h_{i+1} + h_{i+1}²) Δx_i`
//!   with heights about the mean, and the rms slope is `[(1/L) Σ Δh_i²/Δx_i]^½`.
//! - **Slopes** are first differences over the spacing, `(h_{i+1} - h_i)/dx`. Periodic data
//!   include the wrap-around difference (after removing the mean only: a removed plane leaves a
//!   seam, and plane-detrended data are treated as non-periodic, [`Detrend::periodic`]).
//!   Non-periodic areas use the differences at the points `i < nx-1, j < ny-1` for both
//!   directions (SurfaceTopography's trimming of its upwind stencil),
//!   and `rms_gradient = [⟨(∂h/∂x)² + (∂h/∂y)²⟩]^½`; a non-periodic profile has `n-1` differences.
//! - **ACF** `C(δ) = ⟨h(x) h(x+δ)⟩ / ⟨h²⟩`, computed by FFT: circular for periodic data, zero-padded
//!   with the unbiased overlap normalisation `1/((nx-|δi|)(ny-|δj|))` otherwise; radially averaged
//!   for areas (bins of width `min(dx, dy)`, up to half the shorter side). The correlation lengths
//!   are the first lags at which the ACF falls below `1/e` and below `0.2` (linear interpolation
//!   between bins); both are reported, named.
//! - **PSD** (Jacobs et al. 2017, eqs. 5–8): `C¹ᴰ(q) = |h̃(q)|²/L`, `C²ᴰ(q) = |h̃(q)|²/A` with
//!   `h̃(q) = Σ h e^{-iq·x} dx (dy)`, so that `Rq² = (1/L) Σ_q C¹ᴰ = (1/A) Σ_q C²ᴰ`; radially averaged
//!   for areas in bins of width `2π/max(Lx, Ly)` up to `min(π/dx, π/dy)`. Non-periodic data are
//!   multiplied by a Hann window (separable for areas) scaled to unit rms first.
//!
//! Nonuniform profiles are resampled to their mean spacing by linear interpolation for the ACF
//! and PSD only.
//!
//! ## Missing points
//!
//! A topography with missing points ([`crate::surface::missing`]) is analysed over its measured
//! points, as SurfaceTopography 1.27 does (and reproduced to 1e-9 on files with missing points,
//! tests/surface_missing.rs):
//!
//! - **Heights**: mean, Rq (its `Sq` for an area, `Rq` for a profile), Ra, Rsk, Rku over the
//!   measured points only; `--detrend plane` fits the plane to the measured points.
//! - **Slopes**: SurfaceTopography evaluates the difference `h(x+Δx) − h(x)` through its
//!   piecewise-linear interpolant (on each grid cell split into a lower-left and an upper-right
//!   triangle), whose zero weights still carry a NaN: a difference is missing when any point
//!   of the triangle it is read from is missing, not only its two end points. The statistics
//!   here evaluate the same interpolant at the same floating-point positions (`x_i = i·Lx/nx`
//!   for areas, `x_i = i·Δx` for profiles), so the same differences are dropped; the rms is
//!   taken over the remaining ones (for the gradient: the points where both components exist).
//! - **ACF**: averaged over the pairs of measured points at each lag,
//!   `C(δ) = Σ w(x)w(x+δ) h(x)h(x+δ) / Σ w(x)w(x+δ)` (w = 1 where measured), by FFT.
//! - **PSD**: SurfaceTopography refuses it with missing points, and so does this module: fill
//!   them first (`--fill harmonic|nearest`), and the PSD is that of the filled map.

use crate::core::error::{Error, Result};
use crate::core::fft::{Boundary, FftPlan};
use crate::core::grid::Grid2;
use crate::surface::missing::MaskedGrid;
use crate::surface::topography::{Profile, Topography};
use ndarray::{Array2, Axis};
use std::f64::consts::PI;

/// What is removed before the statistics are computed.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Detrend {
    /// Remove the mean height only (default).
    #[default]
    Mean,
    /// Remove the least-squares plane (area) or line (profile).
    Plane,
}

impl Detrend {
    /// Whether detrended data from a topography with periodicity `periodic` are still one
    /// period: removing the mean keeps a periodic topography periodic, removing a plane does
    /// not (its tilt leaves a jump of `b·L` at the seam), as in SurfaceTopography
    /// (`DetrendedUniformTopography.is_periodic`). Slopes, autocorrelation and spectrum of
    /// plane-detrended data are therefore those of a non-periodic topography (no wrap-around
    /// difference, zero-padded correlation, windowed spectrum).
    pub fn periodic(self, periodic: bool) -> bool {
        periodic && self == Detrend::Mean
    }
}

impl std::str::FromStr for Detrend {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "mean" => Ok(Detrend::Mean),
            "plane" => Ok(Detrend::Plane),
            _ => Err(Error::param(
                "detrend",
                format!("must be `mean` or `plane`, got `{s}`"),
            )),
        }
    }
}

/// Statistics of one topography (SI units; slopes dimensionless).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct SurfaceStats {
    /// `"profile"` (1-D) or `"area"` (2-D).
    pub kind: &'static str,
    /// Whether the samples are uniformly spaced.
    pub uniform: bool,
    /// Whether the topography is one period of a periodic surface.
    pub periodic: bool,
    /// What was removed before the statistics.
    pub detrend: Detrend,
    /// Points along x.
    pub nx: usize,
    /// Points along y (1 for a profile).
    pub ny: usize,
    /// Missing points (not measured; excluded from every statistic).
    pub missing_points: usize,
    /// Spacing along x (m); the mean spacing for a nonuniform profile.
    pub dx_m: f64,
    /// Spacing along y (m); `None` for a profile.
    pub dy_m: Option<f64>,
    /// Size along x (m).
    pub lx_m: f64,
    /// Size along y (m); `None` for a profile.
    pub ly_m: Option<f64>,
    /// Arithmetic mean deviation Ra (m).
    pub ra_m: f64,
    /// Root-mean-square height Rq (m).
    pub rq_m: f64,
    /// Skewness Rsk.
    pub rsk: f64,
    /// Kurtosis Rku (3 for a Gaussian height distribution).
    pub rku: f64,
    /// RMS slope along x (profile: dh/dx; area: SurfaceTopography's `rms_slope_from_profile`).
    pub rms_slope: f64,
    /// RMS slope along y (area only).
    pub rms_slope_y: Option<f64>,
    /// RMS gradient `[⟨|∇h|²⟩]^½` (area only).
    pub rms_gradient: Option<f64>,
    /// Correlation length where the (radially averaged) ACF first drops below 1/e (m).
    pub correlation_length_1_over_e_m: Option<f64>,
    /// Correlation length where the (radially averaged) ACF first drops below 0.2 (m).
    pub correlation_length_0_2_m: Option<f64>,
    /// 1/e correlation length along x from the ACF on the x axis (area only, m).
    pub correlation_length_x_1_over_e_m: Option<f64>,
    /// 1/e correlation length along y from the ACF on the y axis (area only, m).
    pub correlation_length_y_1_over_e_m: Option<f64>,
}

/// A power spectral density, radially averaged for areas.
#[derive(Debug, Clone, PartialEq)]
pub struct Psd {
    /// 1 for a profile (`C` in m³), 2 for an area (`C` in m⁴).
    pub dim: usize,
    /// Angular wavenumbers (rad/m), bin centres.
    pub q: Vec<f64>,
    /// PSD values.
    pub c: Vec<f64>,
    /// Number of Fourier coefficients in each bin.
    pub count: Vec<usize>,
}

/// A radially averaged (area) or one-sided (profile) autocorrelation function, normalised to 1 at
/// zero lag.
#[derive(Debug, Clone, PartialEq)]
pub struct Acf {
    /// Lag distance (m): mean radius of each bin.
    pub r: Vec<f64>,
    /// Normalised ACF.
    pub c: Vec<f64>,
}

impl Acf {
    /// First lag at which the ACF drops below `level` (linear interpolation), if it does.
    pub fn crossing(&self, level: f64) -> Option<f64> {
        (1..self.c.len()).find_map(|k| {
            let (c0, c1) = (self.c[k - 1], self.c[k]);
            if c0 >= level && c1 < level {
                let t = (c0 - level) / (c0 - c1);
                Some(self.r[k - 1] + t * (self.r[k] - self.r[k - 1]))
            } else {
                None
            }
        })
    }
}

// ---------------------------------------------------------------------------------------------
// Detrending
// ---------------------------------------------------------------------------------------------

/// Heights of a uniform profile with the sample mean or least-squares line removed.
fn detrend_uniform_line(h: &[f64], detrend: Detrend) -> Vec<f64> {
    let n = h.len() as f64;
    let mean = h.iter().sum::<f64>() / n;
    match detrend {
        Detrend::Mean => h.iter().map(|v| v - mean).collect(),
        Detrend::Plane => {
            let xm = (n - 1.0) / 2.0;
            let sxx: f64 = (0..h.len()).map(|i| (i as f64 - xm).powi(2)).sum();
            let sxh: f64 = h.iter().enumerate().map(|(i, v)| (i as f64 - xm) * v).sum();
            let b = sxh / sxx;
            h.iter()
                .enumerate()
                .map(|(i, v)| v - mean - b * (i as f64 - xm))
                .collect()
        }
    }
}

/// Heights of an area with the mean or least-squares plane removed (uniform grid: the centred
/// coordinates are orthogonal, so the plane coefficients decouple).
pub(crate) fn detrend_area(h: &Array2<f64>, detrend: Detrend) -> Array2<f64> {
    let (nx, ny) = h.dim();
    let n = (nx * ny) as f64;
    let mean = h.sum() / n;
    match detrend {
        Detrend::Mean => h.mapv(|v| v - mean),
        Detrend::Plane => {
            let (xm, ym) = ((nx as f64 - 1.0) / 2.0, (ny as f64 - 1.0) / 2.0);
            let sxx = ny as f64 * (0..nx).map(|i| (i as f64 - xm).powi(2)).sum::<f64>();
            let syy = nx as f64 * (0..ny).map(|j| (j as f64 - ym).powi(2)).sum::<f64>();
            let (mut sxh, mut syh) = (0.0, 0.0);
            for ((i, j), v) in h.indexed_iter() {
                sxh += (i as f64 - xm) * v;
                syh += (j as f64 - ym) * v;
            }
            let (bx, by) = (
                if sxx > 0.0 { sxh / sxx } else { 0.0 },
                if syy > 0.0 { syh / syy } else { 0.0 },
            );
            Array2::from_shape_fn((nx, ny), |(i, j)| {
                h[[i, j]] - mean - bx * (i as f64 - xm) - by * (j as f64 - ym)
            })
        }
    }
}

/// Mean `(1/L)∫h dx` of the piecewise-linear interpolant (trapezoidal rule).
fn trapezoid_mean(x: &[f64], h: &[f64]) -> f64 {
    let l = x[x.len() - 1] - x[0];
    x.windows(2)
        .zip(h.windows(2))
        .map(|(xs, hs)| 0.5 * (hs[0] + hs[1]) * (xs[1] - xs[0]))
        .sum::<f64>()
        / l
}

/// Nonuniform heights with the least-squares line (unweighted, on the samples) removed when
/// asked; the mean is removed later by the moments.
fn detrend_nonuniform(x: &[f64], h: &[f64], detrend: Detrend) -> Vec<f64> {
    match detrend {
        Detrend::Mean => h.to_vec(),
        Detrend::Plane => {
            let n = h.len() as f64;
            let xm = x.iter().sum::<f64>() / n;
            let hm = h.iter().sum::<f64>() / n;
            let sxx: f64 = x.iter().map(|v| (v - xm).powi(2)).sum();
            let sxh: f64 = x.iter().zip(h).map(|(a, b)| (a - xm) * (b - hm)).sum();
            let b = sxh / sxx;
            x.iter()
                .zip(h)
                .map(|(a, v)| v - hm - b * (a - xm))
                .collect()
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Amplitude parameters
// ---------------------------------------------------------------------------------------------

/// (Ra, Rq, Rsk, Rku) of zero-mean samples.
fn sample_moments<'a>(h: impl Iterator<Item = &'a f64> + Clone) -> (f64, f64, f64, f64) {
    let (mut n, mut s1, mut s2, mut s3, mut s4) = (0usize, 0.0, 0.0, 0.0, 0.0);
    for v in h {
        let v2 = v * v;
        n += 1;
        s1 += v.abs();
        s2 += v2;
        s3 += v2 * v;
        s4 += v2 * v2;
    }
    let n = n as f64;
    let rq = (s2 / n).sqrt();
    (s1 / n, rq, s3 / n / rq.powi(3), s4 / n / rq.powi(4))
}

/// (Ra, Rq, Rsk, Rku) of the piecewise-linear profile through `(x, h)` with `h` about its mean:
/// exact segment integrals `∫₀¹ (a + (b-a)t)^k dt = (Σ_{m=0..k} a^m b^(k-m))/(k+1)` and, for Ra,
/// `(|a|+|b|)/2` or `(a²+b²)/(2(|a|+|b|))` when the segment crosses zero.
fn piecewise_linear_moments(x: &[f64], h: &[f64]) -> (f64, f64, f64, f64) {
    let l = x[x.len() - 1] - x[0];
    let (mut s1, mut s2, mut s3, mut s4) = (0.0, 0.0, 0.0, 0.0);
    for (xs, hs) in x.windows(2).zip(h.windows(2)) {
        let d = xs[1] - xs[0];
        let (a, b) = (hs[0], hs[1]);
        s1 += d * if a * b >= 0.0 {
            0.5 * (a.abs() + b.abs())
        } else {
            0.5 * (a * a + b * b) / (a.abs() + b.abs())
        };
        s2 += d * (a * a + a * b + b * b) / 3.0;
        s3 += d * (a * a * a + a * a * b + a * b * b + b * b * b) / 4.0;
        s4 += d * (a.powi(4) + a.powi(3) * b + a * a * b * b + a * b.powi(3) + b.powi(4)) / 5.0;
    }
    let rq = (s2 / l).sqrt();
    (s1 / l, rq, s3 / l / rq.powi(3), s4 / l / rq.powi(4))
}

// ---------------------------------------------------------------------------------------------
// Slopes
// ---------------------------------------------------------------------------------------------

/// RMS of first differences over the spacing of a uniform profile.
fn rms_slope_uniform(h: &[f64], dx: f64, periodic: bool) -> f64 {
    let n = h.len();
    let mut s: f64 = h.windows(2).map(|w| (w[1] - w[0]).powi(2)).sum();
    let mut m = n - 1;
    if periodic {
        s += (h[0] - h[n - 1]).powi(2);
        m = n;
    }
    (s / m as f64).sqrt() / dx
}

/// RMS slopes along x and y and the rms gradient of an area (see the module documentation for
/// the points used).
pub fn rms_slopes_area(h: &Array2<f64>, dx: f64, dy: f64, periodic: bool) -> (f64, f64, f64) {
    let (nx, ny) = h.dim();
    let (mx, my) = if periodic { (nx, ny) } else { (nx - 1, ny - 1) };
    let (mut sx, mut sy) = (0.0, 0.0);
    for i in 0..mx {
        let ip = (i + 1) % nx;
        for j in 0..my {
            let jp = (j + 1) % ny;
            let v = h[[i, j]];
            sx += ((h[[ip, j]] - v) / dx).powi(2);
            sy += ((h[[i, jp]] - v) / dy).powi(2);
        }
    }
    let m = (mx * my) as f64;
    ((sx / m).sqrt(), (sy / m).sqrt(), ((sx + sy) / m).sqrt())
}

// ---------------------------------------------------------------------------------------------
// Autocorrelation
// ---------------------------------------------------------------------------------------------

/// Raw autocorrelation sums `S(δi, δj) = Σ h(i,j) h(i+δi, j+δj)` for `δi, δj ≥ 0` (zero-padded)
/// or all circular lags (periodic), by FFT: `S = F⁻¹|F h|²`.
fn autocorrelation_sums(h: &Array2<f64>, boundary: Boundary) -> Array2<f64> {
    let (nx, ny) = h.dim();
    let plan = FftPlan::new(nx, ny, boundary);
    let mut spec = plan.forward(h);
    spec.mapv_inplace(|s| s * s.conj());
    plan.inverse(spec)
}

/// Radially binned average of `value(di, dj)` over signed lags, with radius
/// `√((di·dx)² + (dj·dy)²)` in bins of width `min(dx, dy)` up to `r_max`.
struct RadialBins {
    dr: f64,
    sum: Vec<f64>,
    rsum: Vec<f64>,
    count: Vec<usize>,
}

impl RadialBins {
    fn new(dr: f64, r_max: f64) -> Self {
        let nb = (r_max / dr).floor() as usize + 1;
        Self {
            dr,
            sum: vec![0.0; nb],
            rsum: vec![0.0; nb],
            count: vec![0; nb],
        }
    }

    fn add(&mut self, r: f64, v: f64, weight: usize) {
        let k = (r / self.dr).round() as usize;
        if k < self.sum.len() {
            self.sum[k] += v * weight as f64;
            self.rsum[k] += r * weight as f64;
            self.count[k] += weight;
        }
    }

    /// (mean radius, mean value, count) of non-empty bins.
    fn finish(self) -> Vec<(f64, f64, usize)> {
        (0..self.sum.len())
            .filter(|&k| self.count[k] > 0)
            .map(|k| {
                let c = self.count[k] as f64;
                (self.rsum[k] / c, self.sum[k] / c, self.count[k])
            })
            .collect()
    }
}

/// Normalised ACF of a uniform profile (zero-mean heights), one-sided, lags up to `n/2`.
fn acf_profile(h: &[f64], dx: f64, periodic: bool) -> Acf {
    let n = h.len();
    let a = Array2::from_shape_vec((1, n), h.to_vec()).expect("shape matches");
    let boundary = if periodic {
        Boundary::Periodic
    } else {
        Boundary::ZeroPadded
    };
    let s = autocorrelation_sums(&a, boundary);
    let norm = |k: usize| {
        if periodic {
            n as f64
        } else {
            (n - k) as f64
        }
    };
    let c0 = s[[0, 0]] / norm(0);
    let kmax = n / 2;
    Acf {
        r: (0..=kmax).map(|k| k as f64 * dx).collect(),
        c: (0..=kmax).map(|k| s[[0, k]] / norm(k) / c0).collect(),
    }
}

/// Normalised ACF of an area (zero-mean heights): radially averaged, and along the x and y axes.
fn acf_area(h: &Array2<f64>, dx: f64, dy: f64, periodic: bool) -> (Acf, Acf, Acf) {
    let (nx, ny) = h.dim();
    let r_max = 0.5 * (nx as f64 * dx).min(ny as f64 * dy);
    let mut bins = RadialBins::new(dx.min(dy), r_max);
    let (hx, hy) = (nx / 2, ny / 2);
    let (ax, ay);
    if periodic {
        let s = autocorrelation_sums(h, Boundary::Periodic);
        let c0 = s[[0, 0]];
        for ((i, j), v) in s.indexed_iter() {
            let di = if i <= hx {
                i as f64
            } else {
                i as f64 - nx as f64
            };
            let dj = if j <= hy {
                j as f64
            } else {
                j as f64 - ny as f64
            };
            bins.add((di * dx).hypot(dj * dy), v / c0, 1);
        }
        ax = (0..=hx).map(|i| s[[i, 0]] / c0).collect::<Vec<_>>();
        ay = (0..=hy).map(|j| s[[0, j]] / c0).collect::<Vec<_>>();
    } else {
        // Quadrant δj ≥ 0 from h, quadrant δj ≤ 0 from h flipped along y (C(δi,-δj) = ACF of
        // the flipped field at (δi, δj)); δi < 0 mirrors δi > 0.
        let s = autocorrelation_sums(h, Boundary::ZeroPadded);
        let mut flipped = h.clone();
        flipped.invert_axis(Axis(1));
        let sf = autocorrelation_sums(
            &flipped.as_standard_layout().into_owned(),
            Boundary::ZeroPadded,
        );
        let overlap = |i: usize, j: usize| ((nx - i) * (ny - j)) as f64;
        let c0 = s[[0, 0]] / overlap(0, 0);
        for i in 0..nx {
            for j in 0..ny {
                let r = (i as f64 * dx).hypot(j as f64 * dy);
                if r > r_max + dx.min(dy) {
                    continue;
                }
                // Each stored lag stands for itself and its point mirror (−δi, −δj).
                let w = if i == 0 && j == 0 { 1 } else { 2 };
                bins.add(r, s[[i, j]] / overlap(i, j) / c0, w);
                if i > 0 && j > 0 {
                    bins.add(r, sf[[i, j]] / overlap(i, j) / c0, 2);
                }
            }
        }
        ax = (0..=hx)
            .map(|i| s[[i, 0]] / overlap(i, 0) / c0)
            .collect::<Vec<_>>();
        ay = (0..=hy)
            .map(|j| s[[0, j]] / overlap(0, j) / c0)
            .collect::<Vec<_>>();
    }
    let radial = bins.finish();
    (
        Acf {
            r: radial.iter().map(|b| b.0).collect(),
            c: radial.iter().map(|b| b.1).collect(),
        },
        Acf {
            r: (0..ax.len()).map(|i| i as f64 * dx).collect(),
            c: ax,
        },
        Acf {
            r: (0..ay.len()).map(|j| j as f64 * dy).collect(),
            c: ay,
        },
    )
}

// ---------------------------------------------------------------------------------------------
// Power spectral density
// ---------------------------------------------------------------------------------------------

/// Hann window of length `n`, `w_i = sin²(π i/(n-1))`, scaled to unit rms.
fn hann_unit_rms(n: usize) -> Vec<f64> {
    if n < 3 {
        return vec![1.0; n];
    }
    let w: Vec<f64> = (0..n)
        .map(|i| (PI * i as f64 / (n - 1) as f64).sin().powi(2))
        .collect();
    let rms = (w.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
    w.into_iter().map(|v| v / rms).collect()
}

fn psd_profile(h: &[f64], dx: f64, periodic: bool) -> Psd {
    let n = h.len();
    let mut a = Array2::from_shape_vec((1, n), h.to_vec()).expect("shape matches");
    if !periodic {
        let w = hann_unit_rms(n);
        for (v, wi) in a.iter_mut().zip(&w) {
            *v *= wi;
        }
    }
    let plan = FftPlan::new(1, n, Boundary::Periodic);
    let spec = plan.forward(&a);
    let l = n as f64 * dx;
    let (q, c): (Vec<f64>, Vec<f64>) = (1..spec.nrows())
        .map(|m| {
            let q = 2.0 * PI * m as f64 / l;
            (q, dx * dx * spec[[m, 0]].norm_sqr() / l)
        })
        .unzip();
    Psd {
        dim: 1,
        count: vec![1; q.len()],
        q,
        c,
    }
}

fn psd_area(h: &Array2<f64>, dx: f64, dy: f64, periodic: bool) -> Psd {
    let (nx, ny) = h.dim();
    let mut a = h.clone();
    if !periodic {
        let (wx, wy) = (hann_unit_rms(nx), hann_unit_rms(ny));
        for ((i, j), v) in a.indexed_iter_mut() {
            *v *= wx[i] * wy[j];
        }
    }
    let plan = FftPlan::new(nx, ny, Boundary::Periodic);
    let spec = plan.forward(&a);
    let (qx, qy) = plan.wavenumbers(dx, dy);
    let (lx, ly) = (nx as f64 * dx, ny as f64 * dy);
    let area = lx * ly;
    let dq = 2.0 * PI / lx.max(ly);
    let q_max = (PI / dx).min(PI / dy);
    let nb = (q_max / dq).floor() as usize + 1;
    let (mut sum, mut count) = (vec![0.0; nb], vec![0usize; nb]);
    let scale = (dx * dy).powi(2) / area;
    for (m, row) in spec.axis_iter(Axis(0)).enumerate() {
        // Rows 0 < m < ny/2 stand for ±qy (conjugate symmetry of a real field).
        let w = if m == 0 || 2 * m == ny { 1 } else { 2 };
        for (k, s) in row.iter().enumerate() {
            let q = qx[k].hypot(qy[m]);
            let b = (q / dq).round() as usize;
            if b == 0 || b >= nb {
                continue;
            }
            sum[b] += w as f64 * scale * s.norm_sqr();
            count[b] += w;
        }
    }
    let mut psd = Psd {
        dim: 2,
        q: vec![],
        c: vec![],
        count: vec![],
    };
    for b in 1..nb {
        if count[b] > 0 {
            psd.q.push(b as f64 * dq);
            psd.c.push(sum[b] / count[b] as f64);
            psd.count.push(count[b]);
        }
    }
    psd
}

/// Linear interpolation of a nonuniform profile onto `n` points at its mean spacing.
fn resample_uniform(x: &[f64], h: &[f64]) -> Vec<f64> {
    let n = x.len();
    let dx = (x[n - 1] - x[0]) / (n - 1) as f64;
    let mut k = 0;
    (0..n)
        .map(|i| {
            let xi = x[0] + i as f64 * dx;
            while k + 2 < n && x[k + 1] < xi {
                k += 1;
            }
            let t = ((xi - x[k]) / (x[k + 1] - x[k])).clamp(0.0, 1.0);
            h[k] + t * (h[k + 1] - h[k])
        })
        .collect()
}

// ---------------------------------------------------------------------------------------------
// Entry points
// ---------------------------------------------------------------------------------------------

/// Refuse heights whose moments overflow, and a topography that is flat after detrending (its
/// rms height is round-off of the largest height `max_abs`: Rsk, Rku would be noise).
fn check_not_flat(rq: f64, rku: f64, max_abs: f64) -> Result<()> {
    let overflow = !rq.is_finite() || !max_abs.is_finite() || rku.is_infinite();
    if overflow {
        return Err(Error::Data(format!(
            "heights up to {} m overflow double precision in the statistics (the 4th power of \
             a height must stay below 1.8e308): wrong unit?",
            crate::core::error::num(max_abs)
        )));
    }
    if rq <= 64.0 * f64::EPSILON * max_abs || rq == 0.0 || rku.is_nan() {
        return Err(Error::Data(format!(
            "the topography is flat after detrending (Rq = {} m is round-off of heights up to \
             {} m): no statistics to compute",
            crate::core::error::num(rq),
            crate::core::error::num(max_abs)
        )));
    }
    Ok(())
}

/// Largest |height| of the measured (non-NaN) values.
fn max_abs<'a>(h: impl Iterator<Item = &'a f64>) -> f64 {
    h.filter(|v| !v.is_nan())
        .fold(0.0f64, |m, v| m.max(v.abs()))
}

/// Zero-mean, detrended uniform heights of a profile (resampled when nonuniform) for ACF / PSD.
fn uniform_profile_heights(p: &Profile, detrend: Detrend) -> Vec<f64> {
    match &p.positions {
        None => detrend_uniform_line(&p.heights, detrend),
        Some(x) => {
            let h = detrend_nonuniform(x, &p.heights, detrend);
            detrend_uniform_line(&resample_uniform(x, &h), Detrend::Mean)
        }
    }
}

/// Statistics of a profile from its moments `(Ra, Rq, Rsk, Rku)`, rms slope and ACF.
fn profile_result(
    p: &Profile,
    detrend: Detrend,
    (ra, rq, rsk, rku): (f64, f64, f64, f64),
    slope: f64,
    acf: &Acf,
) -> SurfaceStats {
    SurfaceStats {
        kind: "profile",
        uniform: p.is_uniform(),
        periodic: detrend.periodic(p.periodic),
        detrend,
        nx: p.len(),
        ny: 1,
        missing_points: p.missing(),
        dx_m: p.dx,
        dy_m: None,
        lx_m: p.length(),
        ly_m: None,
        ra_m: ra,
        rq_m: rq,
        rsk,
        rku,
        rms_slope: slope,
        rms_slope_y: None,
        rms_gradient: None,
        correlation_length_1_over_e_m: acf.crossing((-1.0f64).exp()),
        correlation_length_0_2_m: acf.crossing(0.2),
        correlation_length_x_1_over_e_m: None,
        correlation_length_y_1_over_e_m: None,
    }
}

/// Statistics of an area (`nx × ny` points of spacing `dx × dy`, `missing` of them missing) from
/// its moments, slopes `(x, y, gradient)` and ACFs `(radial, x, y)`.
fn area_result(
    (nx, ny, dx, dy, periodic, missing): (usize, usize, f64, f64, bool, usize),
    detrend: Detrend,
    (ra, rq, rsk, rku): (f64, f64, f64, f64),
    (sx, sy, grad): (f64, f64, f64),
    (radial, ax, ay): (&Acf, &Acf, &Acf),
) -> SurfaceStats {
    let e = (-1.0f64).exp();
    SurfaceStats {
        kind: "area",
        uniform: true,
        periodic,
        detrend,
        nx,
        ny,
        missing_points: missing,
        dx_m: dx,
        dy_m: Some(dy),
        lx_m: nx as f64 * dx,
        ly_m: Some(ny as f64 * dy),
        ra_m: ra,
        rq_m: rq,
        rsk,
        rku,
        rms_slope: sx,
        rms_slope_y: Some(sy),
        rms_gradient: Some(grad),
        correlation_length_1_over_e_m: radial.crossing(e),
        correlation_length_0_2_m: radial.crossing(0.2),
        correlation_length_x_1_over_e_m: ax.crossing(e),
        correlation_length_y_1_over_e_m: ay.crossing(e),
    }
}

fn profile_stats(p: &Profile, detrend: Detrend) -> Result<SurfaceStats> {
    if p.missing() > 0 {
        return masked_profile_stats(p, detrend);
    }
    let (ra, rq, rsk, rku, slope) = match &p.positions {
        None => {
            let h = detrend_uniform_line(&p.heights, detrend);
            let (ra, rq, rsk, rku) = sample_moments(h.iter());
            (
                ra,
                rq,
                rsk,
                rku,
                rms_slope_uniform(&h, p.dx, detrend.periodic(p.periodic)),
            )
        }
        Some(x) => {
            let h = detrend_nonuniform(x, &p.heights, detrend);
            let mean = trapezoid_mean(x, &h);
            let h0: Vec<f64> = h.iter().map(|v| v - mean).collect();
            let (ra, rq, rsk, rku) = piecewise_linear_moments(x, &h0);
            let l = x[x.len() - 1] - x[0];
            let s: f64 = x
                .windows(2)
                .zip(h.windows(2))
                .map(|(xs, hs)| (hs[1] - hs[0]).powi(2) / (xs[1] - xs[0]))
                .sum();
            (ra, rq, rsk, rku, (s / l).sqrt())
        }
    };
    check_not_flat(rq, rku, max_abs(p.heights.iter()))?;
    let acf = acf_profile(
        &uniform_profile_heights(p, detrend),
        p.dx,
        detrend.periodic(p.periodic),
    );
    Ok(profile_result(p, detrend, (ra, rq, rsk, rku), slope, &acf))
}

fn area_stats(g: &Grid2, detrend: Detrend) -> Result<SurfaceStats> {
    let (nx, ny) = (g.nx(), g.ny());
    if nx < 2 || ny < 2 {
        return Err(Error::Data(format!(
            "an area needs at least 2 × 2 points, got {nx} × {ny}"
        )));
    }
    let h = detrend_area(&g.heights, detrend);
    let (ra, rq, rsk, rku) = sample_moments(h.iter());
    check_not_flat(rq, rku, max_abs(g.heights.iter()))?;
    let (sx, sy, grad) = rms_slopes_area(&h, g.dx, g.dy, detrend.periodic(g.periodic));
    let (radial, ax, ay) = acf_area(&h, g.dx, g.dy, detrend.periodic(g.periodic));
    Ok(area_result(
        (nx, ny, g.dx, g.dy, detrend.periodic(g.periodic), 0),
        detrend,
        (ra, rq, rsk, rku),
        (sx, sy, grad),
        (&radial, &ax, &ay),
    ))
}

/// Statistics of a topography after removing the mean (or the plane).
pub fn stats(topo: &Topography, detrend: Detrend) -> Result<SurfaceStats> {
    let s = match topo {
        Topography::Profile(p) => profile_stats(p, detrend),
        Topography::Area(g) => area_stats(g, detrend),
        Topography::MaskedArea(m) => masked_area_stats(m, detrend),
    }?;
    s.check_finite()?;
    Ok(s)
}

impl SurfaceStats {
    /// Every statistic finite: one that overflowed (heights or spacings far outside any
    /// roughness) is an error naming the statistic and the input it came from, never printed
    /// as `inf` or `NaN`.
    pub fn check_finite(&self) -> Result<()> {
        let spacing = format!(
            "spacing {}{} m",
            crate::core::error::num(self.dx_m),
            self.dy_m.map_or(String::new(), |d| format!(
                " × {}",
                crate::core::error::num(d)
            ))
        );
        let heights = "the heights".to_string();
        let rq = format!("the heights (Rq {} m)", crate::core::error::num(self.rq_m));
        let slope_cause = format!("the heights over the {spacing}");
        let length_cause = format!("the {spacing}");
        let values = [
            ("Ra", Some(self.ra_m), &heights),
            ("Rq", Some(self.rq_m), &heights),
            ("Rsk", Some(self.rsk), &rq),
            ("Rku", Some(self.rku), &rq),
            ("rms slope", Some(self.rms_slope), &slope_cause),
            ("rms slope (y)", self.rms_slope_y, &slope_cause),
            ("rms gradient", self.rms_gradient, &slope_cause),
            ("patch length", Some(self.lx_m), &length_cause),
            ("patch width", self.ly_m, &length_cause),
            (
                "correlation length",
                self.correlation_length_1_over_e_m,
                &length_cause,
            ),
            (
                "correlation length (0.2)",
                self.correlation_length_0_2_m,
                &length_cause,
            ),
            (
                "correlation length along x",
                self.correlation_length_x_1_over_e_m,
                &length_cause,
            ),
            (
                "correlation length along y",
                self.correlation_length_y_1_over_e_m,
                &length_cause,
            ),
        ];
        for (name, v, cause) in values {
            if let Some(v) = v.filter(|v| !v.is_finite()) {
                return Err(Error::Data(format!(
                    "the {name} is {} (not a finite number): it overflowed from {cause}; \
                     check their units",
                    crate::core::error::num(v)
                )));
            }
        }
        Ok(())
    }
}

/// Power spectral density (radially averaged for areas) after detrending. Refused when points
/// are missing (fill them first, as SurfaceTopography requires).
pub fn power_spectrum(topo: &Topography, detrend: Detrend) -> Result<Psd> {
    let missing = topo.missing();
    if missing > 0 {
        return Err(Error::Data(format!(
            "the power spectrum needs every point and {missing} are missing: fill them first \
             (--fill harmonic or --fill nearest)"
        )));
    }
    match topo {
        Topography::MaskedArea(_) => unreachable!("no missing points"),
        Topography::Profile(p) => Ok(psd_profile(
            &uniform_profile_heights(p, detrend),
            p.dx,
            detrend.periodic(p.periodic),
        )),
        Topography::Area(g) => Ok(psd_area(
            &detrend_area(&g.heights, detrend),
            g.dx,
            g.dy,
            detrend.periodic(g.periodic),
        )),
    }
}

/// Radially averaged (area) or one-sided (profile) normalised autocorrelation function.
pub fn autocorrelation(topo: &Topography, detrend: Detrend) -> Acf {
    match topo {
        Topography::MaskedArea(m) => {
            let h = masked_detrend(&m.heights, detrend);
            acf_area_masked(&h, m.dx, m.dy, detrend.periodic(m.periodic)).0
        }
        Topography::Profile(p) if p.missing() > 0 => {
            let h = masked_detrend(&profile_column(&p.heights), detrend);
            acf_profile_masked(&h, p.dx, detrend.periodic(p.periodic))
        }
        Topography::Profile(p) => acf_profile(
            &uniform_profile_heights(p, detrend),
            p.dx,
            detrend.periodic(p.periodic),
        ),
        Topography::Area(g) => {
            acf_area(
                &detrend_area(&g.heights, detrend),
                g.dx,
                g.dy,
                detrend.periodic(g.periodic),
            )
            .0
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Missing points (SurfaceTopography's definitions; see the module documentation)
// ---------------------------------------------------------------------------------------------

/// A profile's heights as an `n × 1` array.
fn profile_column(h: &[f64]) -> Array2<f64> {
    Array2::from_shape_vec((h.len(), 1), h.to_vec()).expect("shape matches")
}

/// An area topography with the mean (or the least-squares plane) of its measured points removed
/// (`asperity surface convert --detrend`), and a sentence saying what was removed. A plane
/// removed from one period of a periodic surface leaves a seam, so the result is then
/// non-periodic ([`Detrend::periodic`]). Profiles are returned unchanged (the writers write
/// areas only).
pub fn detrend_topography(topo: &Topography, detrend: Detrend) -> (Topography, String) {
    let (heights, dx, dy, periodic) = match topo {
        Topography::Area(g) => (&g.heights, g.dx, g.dy, g.periodic),
        Topography::MaskedArea(m) => (&m.heights, m.dx, m.dy, m.periodic),
        Topography::Profile(_) => return (topo.clone(), "a profile is not detrended".into()),
    };
    let levelled = masked_detrend(heights, detrend);
    let periodic_out = detrend.periodic(periodic);
    // What was removed: the mean, and the plane's rise between the outermost measured points.
    let removed: Vec<f64> = heights
        .iter()
        .zip(&levelled)
        .filter(|(h, _)| !h.is_nan())
        .map(|(h, l)| h - l)
        .collect();
    let mean = removed.iter().sum::<f64>() / removed.len() as f64;
    let (lo, hi) = removed
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let what = match detrend {
        Detrend::Mean => format!("removed the mean height {mean:.4e} m of the measured points"),
        Detrend::Plane => format!(
            "removed the least-squares plane of the measured points (mean {mean:.4e} m, rise \
             {:.4e} m across the window){}",
            hi - lo,
            if periodic && !periodic_out {
                "; the input was periodic, the levelled output is not (the plane leaves a seam)"
            } else {
                ""
            }
        ),
    };
    let out = match topo {
        Topography::Area(_) => Topography::Area(Grid2 {
            heights: levelled,
            dx,
            dy,
            periodic: periodic_out,
        }),
        _ => Topography::MaskedArea(MaskedGrid {
            heights: levelled,
            dx,
            dy,
            periodic: periodic_out,
        }),
    };
    (out, what)
}

/// Heights with the mean (or the least-squares plane) of the measured points removed; missing
/// points stay NaN. Works for profiles (`ny == 1`) too.
fn masked_detrend(h: &Array2<f64>, detrend: Detrend) -> Array2<f64> {
    let pts: Vec<(f64, f64, f64)> = h
        .indexed_iter()
        .filter(|(_, v)| !v.is_nan())
        .map(|((i, j), &v)| (i as f64, j as f64, v))
        .collect();
    let n = pts.len() as f64;
    let mean = pts.iter().map(|p| p.2).sum::<f64>() / n;
    match detrend {
        Detrend::Mean => h.mapv(|v| v - mean),
        Detrend::Plane => {
            let (xm, ym) = (
                pts.iter().map(|p| p.0).sum::<f64>() / n,
                pts.iter().map(|p| p.1).sum::<f64>() / n,
            );
            let (mut sxx, mut sxy, mut syy, mut sxh, mut syh) = (0.0, 0.0, 0.0, 0.0, 0.0);
            for &(x, y, v) in &pts {
                let (a, b, c) = (x - xm, y - ym, v - mean);
                sxx += a * a;
                sxy += a * b;
                syy += b * b;
                sxh += a * c;
                syh += b * c;
            }
            let det = sxx * syy - sxy * sxy;
            let (bx, by) = if det > 1e-12 * (sxx * syy).max(f64::MIN_POSITIVE) {
                ((sxh * syy - syh * sxy) / det, (syh * sxx - sxh * sxy) / det)
            } else if sxx > 0.0 {
                (sxh / sxx, 0.0)
            } else if syy > 0.0 {
                (0.0, syh / syy)
            } else {
                (0.0, 0.0)
            };
            Array2::from_shape_fn(h.dim(), |(i, j)| {
                h[[i, j]] - mean - bx * (i as f64 - xm) - by * (j as f64 - ym)
            })
        }
    }
}

/// SurfaceTopography's piecewise-linear interpolant of an area at `(x, y)` (its
/// `interpolate_linear`, periodic wrap): each cell split into a lower-left and an upper-right
/// triangle; NaN wherever a point of the triangle is NaN, whatever its weight.
fn st_linear_2d(h: &Array2<f64>, px: f64, py: f64, x: f64, y: f64) -> f64 {
    let (nx, ny) = h.dim();
    let (sx, sy) = (x / px, y / py);
    let (fx0, fy0) = (sx.floor(), sy.floor());
    let (fx, fy) = (sx - fx0, sy - fy0);
    let ix = (fx0 as i64).rem_euclid(nx as i64) as usize;
    let iy = (fy0 as i64).rem_euclid(ny as i64) as usize;
    let (ix1, iy1) = ((ix + 1) % nx, (iy + 1) % ny);
    if fx + fy > 1.0 {
        (fx + fy - 1.0) * h[[ix1, iy1]] + (1.0 - fx) * h[[ix, iy1]] + (1.0 - fy) * h[[ix1, iy]]
    } else {
        (1.0 - fx - fy) * h[[ix, iy]] + fx * h[[ix1, iy]] + fy * h[[ix, iy1]]
    }
}

/// SurfaceTopography's linear interpolant of a profile at `x` (periodic wrap).
fn st_linear_1d(h: &[f64], px: f64, x: f64) -> f64 {
    let n = h.len();
    let s = x / px;
    let f0 = s.floor();
    let f = s - f0;
    let i = (f0 as i64).rem_euclid(n as i64) as usize;
    (1.0 - f) * h[i] + f * h[(i + 1) % n]
}

/// RMS of the finite values (NaN = missing difference).
fn rms_finite(v: impl Iterator<Item = f64>) -> f64 {
    let (s, n) = v
        .filter(|x| x.is_finite())
        .fold((0.0, 0usize), |(s, n), x| (s + x * x, n + 1));
    (s / n as f64).sqrt()
}

/// Upwind differences of an area with missing points, as SurfaceTopography computes them
/// (`derivative(1)` with linear interpolation): `(∂h/∂x, ∂h/∂y)` at the points `i < nx−1,
/// j < ny−1` (all points when periodic), NaN where missing.
fn masked_slopes_area(h: &Array2<f64>, dx: f64, dy: f64, periodic: bool) -> (Vec<f64>, Vec<f64>) {
    let (nx, ny) = h.dim();
    let (sx, sy) = (nx as f64 * dx, ny as f64 * dy);
    let (px, py) = (sx / nx as f64, sy / ny as f64);
    let (mx, my) = if periodic { (nx, ny) } else { (nx - 1, ny - 1) };
    let (mut gx, mut gy) = (Vec::with_capacity(mx * my), Vec::with_capacity(mx * my));
    for i in 0..mx {
        let x = i as f64 * sx / nx as f64;
        for j in 0..my {
            let y = j as f64 * sy / ny as f64;
            let l0 = st_linear_2d(h, px, py, x + 0.0, y + 0.0);
            let lx = st_linear_2d(h, px, py, x + px, y + 0.0);
            let ly = st_linear_2d(h, px, py, x + 0.0, y + py);
            gx.push((-l0 + lx) / px);
            gy.push((-l0 + ly) / py);
        }
    }
    (gx, gy)
}

/// Upwind differences of a profile with missing points (SurfaceTopography's `derivative(1)`):
/// `n − 1` values (n when periodic), NaN where missing.
fn masked_slopes_profile(h: &[f64], dx: f64, periodic: bool) -> Vec<f64> {
    let n = h.len();
    let px = n as f64 * dx / n as f64;
    let m = if periodic { n } else { n - 1 };
    (0..m)
        .map(|i| {
            let x = i as f64 * px;
            (-st_linear_1d(h, px, x + 0.0) + st_linear_1d(h, px, x + px)) / px
        })
        .collect()
}

/// Raw correlation sums of `a` (see [`autocorrelation_sums`]), rounded when `count` (pair
/// counts are integers).
fn sums(a: &Array2<f64>, boundary: Boundary, count: bool) -> Array2<f64> {
    let s = autocorrelation_sums(a, boundary);
    if count {
        s.mapv(f64::round)
    } else {
        s
    }
}

/// Normalised ACF of a profile with missing points: pair-averaged products, lags up to `n/2`.
fn acf_profile_masked(h: &Array2<f64>, dx: f64, periodic: bool) -> Acf {
    let n = h.len();
    let g = Array2::from_shape_fn((1, n), |(_, i)| {
        let v = h[[i, 0]];
        if v.is_nan() {
            0.0
        } else {
            v
        }
    });
    let w = Array2::from_shape_fn((1, n), |(_, i)| f64::from(u8::from(!h[[i, 0]].is_nan())));
    let boundary = if periodic {
        Boundary::Periodic
    } else {
        Boundary::ZeroPadded
    };
    let (sg, sw) = (sums(&g, boundary, false), sums(&w, boundary, true));
    let c0 = sg[[0, 0]] / sw[[0, 0]];
    let (mut r, mut c) = (Vec::new(), Vec::new());
    for k in 0..=n / 2 {
        if sw[[0, k]] >= 0.5 {
            r.push(k as f64 * dx);
            c.push(sg[[0, k]] / sw[[0, k]] / c0);
        }
    }
    Acf { r, c }
}

/// Normalised ACF of an area with missing points (zero-mean heights, NaN missing): radially
/// averaged, and along the x and y axes; each lag averages the products of the pairs of measured
/// points at that lag.
fn acf_area_masked(h: &Array2<f64>, dx: f64, dy: f64, periodic: bool) -> (Acf, Acf, Acf) {
    let (nx, ny) = h.dim();
    let g = h.mapv(|v| if v.is_nan() { 0.0 } else { v });
    let w = h.mapv(|v| f64::from(u8::from(!v.is_nan())));
    let r_max = 0.5 * (nx as f64 * dx).min(ny as f64 * dy);
    let mut bins = RadialBins::new(dx.min(dy), r_max);
    let (hx, hy) = (nx / 2, ny / 2);
    let axis = |s: &Array2<f64>, c: &Array2<f64>, c0: f64, along_x: bool| -> Acf {
        let (mut r, mut v) = (Vec::new(), Vec::new());
        let m = if along_x { hx } else { hy };
        for k in 0..=m {
            let (a, b) = if along_x { (k, 0) } else { (0, k) };
            if c[[a, b]] >= 0.5 {
                r.push(k as f64 * if along_x { dx } else { dy });
                v.push(s[[a, b]] / c[[a, b]] / c0);
            }
        }
        Acf { r, c: v }
    };
    let boundary = if periodic {
        Boundary::Periodic
    } else {
        Boundary::ZeroPadded
    };
    let (s, c) = (sums(&g, boundary, false), sums(&w, boundary, true));
    let c0 = s[[0, 0]] / c[[0, 0]];
    if periodic {
        for ((i, j), v) in s.indexed_iter() {
            if c[[i, j]] < 0.5 {
                continue;
            }
            let di = if i <= hx {
                i as f64
            } else {
                i as f64 - nx as f64
            };
            let dj = if j <= hy {
                j as f64
            } else {
                j as f64 - ny as f64
            };
            bins.add((di * dx).hypot(dj * dy), v / c[[i, j]] / c0, 1);
        }
    } else {
        let mut gf = g.clone();
        gf.invert_axis(Axis(1));
        let mut wf = w.clone();
        wf.invert_axis(Axis(1));
        let sf = sums(&gf.as_standard_layout().into_owned(), boundary, false);
        let cf = sums(&wf.as_standard_layout().into_owned(), boundary, true);
        for i in 0..nx {
            for j in 0..ny {
                let r = (i as f64 * dx).hypot(j as f64 * dy);
                if r > r_max + dx.min(dy) {
                    continue;
                }
                let wgt = if i == 0 && j == 0 { 1 } else { 2 };
                if c[[i, j]] >= 0.5 {
                    bins.add(r, s[[i, j]] / c[[i, j]] / c0, wgt);
                }
                if i > 0 && j > 0 && cf[[i, j]] >= 0.5 {
                    bins.add(r, sf[[i, j]] / cf[[i, j]] / c0, 2);
                }
            }
        }
    }
    let ax = axis(&s, &c, c0, true);
    let ay = axis(&s, &c, c0, false);
    let radial = bins.finish();
    (
        Acf {
            r: radial.iter().map(|b| b.0).collect(),
            c: radial.iter().map(|b| b.1).collect(),
        },
        ax,
        ay,
    )
}

fn masked_profile_stats(p: &Profile, detrend: Detrend) -> Result<SurfaceStats> {
    let h = masked_detrend(&profile_column(&p.heights), detrend);
    let (ra, rq, rsk, rku) = sample_moments(h.iter().filter(|v| !v.is_nan()));
    check_not_flat(rq, rku, max_abs(p.heights.iter()))?;
    let hv: Vec<f64> = h.iter().copied().collect();
    let slope =
        rms_finite(masked_slopes_profile(&hv, p.dx, detrend.periodic(p.periodic)).into_iter());
    let acf = acf_profile_masked(&h, p.dx, detrend.periodic(p.periodic));
    Ok(profile_result(p, detrend, (ra, rq, rsk, rku), slope, &acf))
}

fn masked_area_stats(m: &MaskedGrid, detrend: Detrend) -> Result<SurfaceStats> {
    let (nx, ny) = (m.nx(), m.ny());
    if nx < 2 || ny < 2 {
        return Err(Error::Data(format!(
            "an area needs at least 2 × 2 points, got {nx} × {ny}"
        )));
    }
    let h = masked_detrend(&m.heights, detrend);
    let (ra, rq, rsk, rku) = sample_moments(h.iter().filter(|v| !v.is_nan()));
    check_not_flat(rq, rku, max_abs(m.heights.iter()))?;
    let (gx, gy) = masked_slopes_area(&h, m.dx, m.dy, detrend.periodic(m.periodic));
    let sx = rms_finite(gx.iter().copied());
    let sy = rms_finite(gy.iter().copied());
    let grad = rms_finite(gx.iter().zip(&gy).map(|(a, b)| (a * a + b * b).sqrt()));
    if !(sx.is_finite() && sy.is_finite() && grad.is_finite()) {
        return Err(Error::Data(
            "no two neighbouring points are both measured: slopes cannot be computed".into(),
        ));
    }
    let (radial, ax, ay) = acf_area_masked(&h, m.dx, m.dy, detrend.periodic(m.periodic));
    Ok(area_result(
        (
            nx,
            ny,
            m.dx,
            m.dy,
            detrend.periodic(m.periodic),
            m.missing(),
        ),
        detrend,
        (ra, rq, rsk, rku),
        (sx, sy, grad),
        (&radial, &ax, &ay),
    ))
}

/// A non-periodic contact surface tilted by more than its roughness: the least-squares plane's
/// height change across the window, `|b|·Lx + |c|·Ly`, above the rms height left once the plane
/// is removed. The solvers take the heights as given, so a tilt loads one side of the window:
/// a slope of 1e-3 added to the measured `x3p-2.x3p` (0.2 µm across 205 µm, Rq 0.077 µm) moved
/// kn at 10 MPa by −11 % and the mean gap by +22 %. Returns the warning
/// naming `source`, or `None` (periodic patches carry no tilt).
pub fn contact_surface_tilt(source: &str, grid: &Grid2) -> Option<String> {
    let (tilt, rq) = plane_tilt(grid);
    (!grid.periodic && tilt > rq).then(|| {
        format!(
            "{source}: the least-squares plane of the heights rises {tilt:.3e} m across the window, more than the roughness left without it (Rq {rq:.3e} m); the contact solvers use the heights as given, so the tilt loads one side: if the tilt is not part of the contact, level the surface first (`asperity surface convert <file> --detrend plane -o <levelled file>`, for two bodies each of them)"
        )
    })
}

/// `(rise of the least-squares plane between the window's outermost samples, Rq of h − plane)`,
/// the plane from the surface statistics' detrending ([`Detrend::Plane`]).
pub fn plane_tilt(grid: &Grid2) -> (f64, f64) {
    let level = detrend_area(&grid.heights, Detrend::Plane);
    // The plane alone: mean-removed heights minus plane-removed ones; its range is its rise
    // between the window's corners.
    let plane = detrend_area(&grid.heights, Detrend::Mean) - &level;
    let (lo, hi) = plane
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let rq = (level.iter().map(|v| v * v).sum::<f64>() / level.len() as f64).sqrt();
    (hi - lo, rq)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::surface::generate::{generate, GaussianSurfaceSpec};

    /// `surface convert --detrend plane`: a plane `a + b·i + c·j` added to a zero-mean,
    /// plane-free pattern (a checkerboard on an even grid: orthogonal to 1, i and j) is removed
    /// exactly; a pure plane with missing points is removed exactly from the measured points and
    /// the missing ones stay missing; the description gives the plane's rise
    /// `|b|(nx−1) + |c|(ny−1)`.
    #[test]
    fn detrending_a_topography_removes_the_plane_of_its_measured_points() {
        let (nx, ny) = (16, 12);
        let (a, b, c) = (3e-6, 2e-8, -5e-9);
        let plane = |i: usize, j: usize| a + b * i as f64 + c * j as f64;
        let pattern = |i: usize, j: usize| {
            if (i + j).is_multiple_of(2) {
                1e-9
            } else {
                -1e-9
            }
        };
        let rough = Array2::from_shape_fn((nx, ny), |(i, j)| plane(i, j) + pattern(i, j));
        let topo = Topography::Area(Grid2::new(rough, 1e-7, 1e-7, false).unwrap());
        let (Topography::Area(g), what) = detrend_topography(&topo, Detrend::Plane) else {
            panic!("an area")
        };
        for ((i, j), v) in g.heights.indexed_iter() {
            assert!((v - pattern(i, j)).abs() < 1e-15, "({i}, {j}): {v}");
        }
        let mut h = Array2::from_shape_fn((nx, ny), |(i, j)| plane(i, j));
        h[[3, 4]] = f64::NAN;
        h[[0, 11]] = f64::NAN;
        let topo = Topography::MaskedArea(MaskedGrid::new(h, 1e-7, 1e-7, false).unwrap());
        let (Topography::MaskedArea(m), masked_what) = detrend_topography(&topo, Detrend::Plane)
        else {
            panic!("still masked")
        };
        assert!(!m.periodic);
        for ((i, j), v) in m.heights.indexed_iter() {
            if (i, j) == (3, 4) || (i, j) == (0, 11) {
                assert!(v.is_nan());
            } else {
                assert!(v.abs() < 1e-18, "({i}, {j}): {v}");
            }
        }
        // Its rise is taken over the measured points.
        assert!(masked_what.contains("rise"), "{masked_what}");
        let rise = b.abs() * (nx - 1) as f64 + c.abs() * (ny - 1) as f64;
        assert!(what.contains(&format!("rise {rise:.4e} m")), "{what}");
        // `mean` keeps the tilt and the periodicity.
        let periodic = Topography::Area(
            Grid2::new(
                Array2::from_shape_fn((4, 4), |(i, _)| i as f64),
                1.0,
                1.0,
                true,
            )
            .unwrap(),
        );
        let (Topography::Area(g), _) = detrend_topography(&periodic, Detrend::Mean) else {
            panic!("an area")
        };
        assert!(g.periodic);
        assert_eq!(g.heights[[0, 0]], -1.5);
        let (Topography::Area(g), what) = detrend_topography(&periodic, Detrend::Plane) else {
            panic!("an area")
        };
        assert!(
            !g.periodic && what.contains("the levelled output is not"),
            "{what}"
        );
        assert!(g.heights.iter().all(|v| v.abs() < 1e-15));
    }

    /// Removing a plane from one period of a periodic surface leaves a seam: the statistics are
    /// then those of the same heights taken as non-periodic (SurfaceTopography's rule). On
    /// `h = sin(2πi/64)` (64 × 64, dx = 1) the fitted tilt is −0.030 and the wrap-around
    /// difference made the rms slope 0.2345 where the non-periodic one is 0.0744.
    #[test]
    fn plane_detrending_makes_a_periodic_area_non_periodic() {
        let n = 64;
        let h = Array2::from_shape_fn((n, n), |(i, _)| (2.0 * PI * i as f64 / n as f64).sin());
        let topo = |periodic| {
            Topography::Area(crate::core::grid::Grid2::new(h.clone(), 1.0, 1.0, periodic).unwrap())
        };
        let plane = stats(&topo(true), Detrend::Plane).unwrap();
        let open = stats(&topo(false), Detrend::Plane).unwrap();
        assert!(!plane.periodic);
        assert_eq!(plane.rms_slope, open.rms_slope);
        assert!(
            (plane.rms_slope - 0.0744).abs() < 5e-4,
            "{}",
            plane.rms_slope
        );
        let psd = |periodic| power_spectrum(&topo(periodic), Detrend::Plane).unwrap();
        assert_eq!(psd(true), psd(false));
        // Removing the mean keeps it periodic: the sine's exact slope 2π/64/√2 (x) over the
        // area, the gradient's rms.
        let mean = stats(&topo(true), Detrend::Mean).unwrap();
        assert!(mean.periodic);
        let exact = 2.0 * (PI / n as f64).sin() / 2f64.sqrt();
        assert!(
            (mean.rms_slope - exact).abs() < 1e-12,
            "{} {exact}",
            mean.rms_slope
        );
    }

    fn rel(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs()
    }

    #[test]
    fn sine_profile_closed_forms() {
        // h = A sin(2πx/λ) over whole periods: Rq = A/√2, Ra = 2A/π, Rsk = 0, Rku = 1.5,
        // rms slope of the first differences = (2A/dx)·sin(π dx/λ)/√2.
        let (a, n, per) = (2e-6, 400, 8);
        let dx = 1e-6;
        let lambda = n as f64 * dx / per as f64;
        let h: Vec<f64> = (0..n)
            .map(|i| a * (2.0 * PI * i as f64 * dx / lambda).sin())
            .collect();
        let t = Topography::Profile(Profile::new(h, dx, true).unwrap());
        let s = stats(&t, Detrend::Mean).unwrap();
        assert!(rel(s.rq_m, a / 2f64.sqrt()) < 1e-12);
        // Ra of N = 50 samples per period: (A/N)·Σ|sin(2πi/N)| = 2A·cot(π/N)/N (→ 2A/π).
        let np = (n / per) as f64;
        assert!(rel(s.ra_m, 2.0 * a / (PI / np).tan() / np) < 1e-12);
        assert!(s.rsk.abs() < 1e-10);
        assert!(rel(s.rku, 1.5) < 1e-10);
        let slope = 2.0 * a / dx * (PI * dx / lambda).sin() / 2f64.sqrt();
        assert!(rel(s.rms_slope, slope) < 1e-12);
        // PSD: all power in the bin q = 2π/λ, and Parseval (1/L) Σ C = Rq².
        let p = power_spectrum(&t, Detrend::Mean).unwrap();
        let l = n as f64 * dx;
        let total: f64 = p.c.iter().sum::<f64>() / l;
        // One-sided sum holds half the power (the ±q pair), apart from the Nyquist term.
        assert!(rel(2.0 * total, s.rq_m.powi(2)) < 1e-10);
        let kmax =
            p.c.iter()
                .enumerate()
                .max_by(|x, y| x.1.total_cmp(y.1))
                .unwrap()
                .0;
        assert!(rel(p.q[kmax], 2.0 * PI / lambda) < 1e-12);
    }

    #[test]
    fn nonuniform_equals_uniform_integrals_on_a_line() {
        // For a linear profile h = x the piecewise-linear integrals are exact:
        // Rq = L/√12, rms slope = 1, Rsk = 0, Rku = 9/5, Ra = L/4, whatever the spacing.
        let x = vec![0.0, 0.1, 0.35, 0.4, 0.7, 1.0];
        let p = Profile::nonuniform(x.clone(), x.clone()).unwrap();
        let s = stats(&Topography::Profile(p), Detrend::Mean).unwrap();
        assert!(rel(s.rq_m, 1.0 / 12f64.sqrt()) < 1e-14);
        assert!(rel(s.rms_slope, 1.0) < 1e-14);
        assert!(s.rsk.abs() < 1e-12);
        assert!(rel(s.rku, 1.8) < 1e-12);
        assert!(rel(s.ra_m, 0.25) < 1e-14);
        // The plane detrend removes the line entirely.
        let p = Profile::nonuniform(
            x.clone(),
            x.iter().map(|v| v + 0.01 * (v * 9.0).sin()).collect(),
        )
        .unwrap();
        let s = stats(&Topography::Profile(p), Detrend::Plane).unwrap();
        assert!(s.rq_m < 0.01);
    }

    #[test]
    fn plane_detrend_removes_tilt() {
        let g = generate(&GaussianSurfaceSpec {
            rq_m: 1e-6,
            clx_m: 4e-6,
            cly_m: 4e-6,
            lx_m: 64e-6,
            ly_m: 64e-6,
            nx: 64,
            ny: 64,
            seed: 3,
        })
        .unwrap();
        let mut tilted = g.clone();
        for ((i, j), v) in tilted.heights.indexed_iter_mut() {
            *v += 1e-3 * i as f64 * g.dx - 2e-3 * j as f64 * g.dy + 5e-6;
        }
        tilted.periodic = false;
        let mut flat = g.clone();
        flat.periodic = false;
        let a = stats(&Topography::Area(flat.clone()), Detrend::Plane).unwrap();
        let b = stats(&Topography::Area(tilted), Detrend::Plane).unwrap();
        assert!(rel(b.rq_m, a.rq_m) < 1e-9);
        assert!(rel(b.rms_gradient.unwrap(), a.rms_gradient.unwrap()) < 1e-9);
    }

    #[test]
    fn generated_surface_matches_its_model() {
        // Gaussian ACF exp(-r²/cl²) ⇒ PSD C(q) = π Rq² cl² exp(-q² cl²/4) and
        // rms gradient √2·Rq·(√2/cl) = 2 Rq / cl (continuum), cl from the ACF.
        let spec = GaussianSurfaceSpec {
            rq_m: 1e-6,
            clx_m: 8e-6,
            cly_m: 8e-6,
            lx_m: 256e-6,
            ly_m: 256e-6,
            nx: 256,
            ny: 256,
            seed: 11,
        };
        let t = Topography::Area(generate(&spec).unwrap());
        let s = stats(&t, Detrend::Mean).unwrap();
        assert!(rel(s.rq_m, 1e-6) < 1e-12);
        assert!(
            rel(s.correlation_length_1_over_e_m.unwrap(), 8e-6) < 0.1,
            "{s:?}"
        );
        // 0.2-crossing of exp(-r²/cl²): r = cl √(ln 5).
        assert!(rel(s.correlation_length_0_2_m.unwrap(), 8e-6 * 5f64.ln().sqrt()) < 0.1);
        assert!(
            rel(s.rms_gradient.unwrap(), 2.0 * 1e-6 / 8e-6) < 0.1,
            "{s:?}"
        );
        let p = power_spectrum(&t, Detrend::Mean).unwrap();
        // Average the PSD ratio over the well-resolved band q·cl in [0.5, 3].
        let (mut acc, mut n) = (0.0, 0);
        for (q, c) in p.q.iter().zip(&p.c) {
            let qc = q * 8e-6;
            if (0.5..3.0).contains(&qc) {
                acc += c / (PI * 1e-12 * 64e-12 * (-qc * qc / 4.0).exp());
                n += 1;
            }
        }
        assert!(n > 10);
        assert!(
            (acc / n as f64 - 1.0).abs() < 0.1,
            "PSD/model = {}",
            acc / n as f64
        );
    }

    #[test]
    fn nonperiodic_acf_and_slopes() {
        // The same surface read as non-periodic keeps its correlation length (within noise).
        let spec = GaussianSurfaceSpec {
            rq_m: 1e-6,
            clx_m: 6e-6,
            cly_m: 6e-6,
            lx_m: 128e-6,
            ly_m: 128e-6,
            nx: 128,
            ny: 128,
            seed: 5,
        };
        let mut g = generate(&spec).unwrap();
        let per = stats(&Topography::Area(g.clone()), Detrend::Mean).unwrap();
        g.periodic = false;
        let non = stats(&Topography::Area(g), Detrend::Mean).unwrap();
        let (a, b) = (
            per.correlation_length_1_over_e_m.unwrap(),
            non.correlation_length_1_over_e_m.unwrap(),
        );
        assert!(rel(b, a) < 0.05, "{a} vs {b}");
        assert!(rel(non.rms_gradient.unwrap(), per.rms_gradient.unwrap()) < 0.05);
        assert!(
            (non.rms_gradient.unwrap().powi(2)
                - non.rms_slope.powi(2)
                - non.rms_slope_y.unwrap().powi(2))
            .abs()
                < 1e-12
        );
    }

    #[test]
    fn flat_surface_is_an_error() {
        let g = Grid2::new(Array2::from_elem((8, 8), 3e-6), 1e-6, 1e-6, false).unwrap();
        let e = stats(&Topography::Area(g), Detrend::Mean)
            .unwrap_err()
            .to_string();
        assert!(e.contains("flat"), "{e}");
    }

    /// A plane added to a rough (here: sinusoidal) window is measured exactly and flagged once
    /// it exceeds the roughness; the same window level, or periodic, is not flagged.
    #[test]
    fn a_tilted_window_is_flagged_with_its_tilt() {
        let (n, d) = (64, 1e-6);
        let rough = |i: usize, j: usize| 0.1e-6 * (0.7 * i as f64).sin() * (1.3 * j as f64).cos();
        let grid = |slope: f64, periodic: bool| Grid2 {
            heights: ndarray::Array2::from_shape_fn((n, n), |(i, j)| {
                rough(i, j) + slope * i as f64 * d
            }),
            dx: d,
            dy: d,
            periodic,
        };
        let (tilt, rq) = plane_tilt(&grid(1e-2, false));
        let (level_tilt, level_rq) = plane_tilt(&grid(0.0, false));
        // The plane's rise across the window is the slope times the window (within what the
        // rough part projects onto a plane), and removing it leaves the rough part's Rq.
        assert!(
            (tilt - 1e-2 * n as f64 * d).abs() < 0.02 * 1e-2 * n as f64 * d,
            "{tilt}"
        );
        assert!((rq / level_rq - 1.0).abs() < 1e-9, "{rq} vs {level_rq}");
        assert!(level_tilt < 0.1 * level_rq);
        let w = contact_surface_tilt("x.csv", &grid(1e-2, false)).unwrap();
        assert!(
            w.starts_with("x.csv:")
                && w.contains("level the surface")
                && w.contains("--detrend plane"),
            "{w}"
        );
        assert!(contact_surface_tilt("x.csv", &grid(0.0, false)).is_none());
        assert!(contact_surface_tilt("x.csv", &grid(1e-2, true)).is_none());
    }
}
