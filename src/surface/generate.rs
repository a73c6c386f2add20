//! Gaussian-correlated random rough patch from profilometer statistics.
//!
//! Method (Hu & Tonder, *Int. J. Mach. Tools Manufact.* 32 (1992) 83–90; Garcia & Stoll,
//! *Phys. Rev. Lett.* 52 (1984) 1798): white Gaussian noise `w` is circularly convolved with the
//! Gaussian filter
//!
//! `h(x, y) = exp(-2 (x²/clx² + y²/cly²))`,
//!
//! whose self-correlation is `(h ⋆ h)(x, y) ∝ exp(-(x²/clx² + y²/cly²))`. The filtered field
//! `z = h ⊛ w` therefore has the Gaussian autocorrelation function
//!
//! `ACF(x, y) = Rq² exp(-(x²/clx² + y²/cly²))`,
//!
//! so `clx`, `cly` are the **1/e correlation lengths**. The mean is removed and the heights are
//! rescaled so that the rms height equals `Rq` exactly. The convolution is circular, so the patch
//! is one period of an infinite surface (`Grid2::periodic == true`), as the periodic contact
//! solver expects.
//!
//! Reproducibility: the noise is drawn serially from a `ChaCha8Rng` seeded with `seed`, in
//! row-major order (`i` over x, then `j` over y); the FFT transforms every row independently. The
//! same seed therefore gives the same surface bit for bit, whatever the number of threads.

use crate::error::{require_positive, Error, Result};
use crate::grid::Grid2;
use crate::halfspace::convolution::{Boundary, FftPlan};
use ndarray::Array2;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

/// Statistics and discretisation of a Gaussian rough patch. Lengths in metres.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GaussianSurfaceSpec {
    /// Root-mean-square height Rq (m).
    pub rq_m: f64,
    /// 1/e correlation length along x (m).
    pub clx_m: f64,
    /// 1/e correlation length along y (m).
    pub cly_m: f64,
    /// Patch size (period) along x (m).
    pub lx_m: f64,
    /// Patch size (period) along y (m).
    pub ly_m: f64,
    /// Grid points along x.
    pub nx: usize,
    /// Grid points along y.
    pub ny: usize,
    /// Seed of the ChaCha8 random number generator.
    pub seed: u64,
}

impl GaussianSurfaceSpec {
    /// Seed of the reference case.
    pub const REFERENCE_SEED: u64 = 1;

    /// The project's reference case: ground steel, Rq = 0.177 µm, isotropic 1/e correlation
    /// length 6.6 µm, a 250 µm × 250 µm patch on a 1024 × 1024 grid (spacing 0.244 µm, 27 points
    /// per correlation length), seed [`Self::REFERENCE_SEED`] (= 1).
    pub fn reference() -> Self {
        Self {
            rq_m: 0.177e-6,
            clx_m: 6.6e-6,
            cly_m: 6.6e-6,
            lx_m: 250e-6,
            ly_m: 250e-6,
            nx: 1024,
            ny: 1024,
            seed: Self::REFERENCE_SEED,
        }
    }

    /// Grid spacing along x (m).
    pub fn dx(&self) -> f64 {
        self.lx_m / self.nx as f64
    }

    /// Grid spacing along y (m).
    pub fn dy(&self) -> f64 {
        self.ly_m / self.ny as f64
    }

    /// Check every parameter; the error names the offending one.
    ///
    /// - `rq_m`, `clx_m`, `cly_m`, `lx_m`, `ly_m` finite and > 0, `nx`, `ny` ≥ 2;
    /// - each correlation length spans at least two grid spacings (otherwise the Gaussian
    ///   filter is not resolved and the surface is white noise with the wrong ACF);
    /// - each correlation length is at most half the patch (otherwise the periodic patch cannot
    ///   represent the correlation and the filter wraps onto itself).
    pub fn validate(&self) -> Result<()> {
        require_positive("rq_m", self.rq_m)?;
        require_positive("clx_m", self.clx_m)?;
        require_positive("cly_m", self.cly_m)?;
        require_positive("lx_m", self.lx_m)?;
        require_positive("ly_m", self.ly_m)?;
        for (name, n) in [("nx", self.nx), ("ny", self.ny)] {
            if n < 2 {
                return Err(Error::param(name, format!("must be at least 2, got {n}")));
            }
        }
        for (name, cl, d, l, axis) in [
            ("clx_m", self.clx_m, self.dx(), self.lx_m, "x"),
            ("cly_m", self.cly_m, self.dy(), self.ly_m, "y"),
        ] {
            if cl < 2.0 * d {
                return Err(Error::param(
                    name,
                    format!(
                        "correlation length {cl:e} m is under two grid spacings along {axis} \
                         (spacing {d:e} m): under-resolved; refine the grid or shrink the patch"
                    ),
                ));
            }
            if cl > 0.5 * l {
                return Err(Error::param(
                    name,
                    format!(
                        "correlation length {cl:e} m exceeds half the patch size along {axis} \
                         ({l:e} m): the periodic patch cannot represent it; enlarge the patch"
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// White Gaussian noise (zero mean, unit variance), drawn serially in row-major order.
pub fn white_noise(nx: usize, ny: usize, seed: u64) -> Array2<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut z = Array2::<f64>::zeros((nx, ny));
    for v in z.iter_mut() {
        *v = rng.sample(StandardNormal);
    }
    z
}

/// Gaussian filter `exp(-2 (x²/clx² + y²/cly²))` at offset `(x, y)` (m), whose
/// self-correlation is the Gaussian ACF `exp(-(x²/clx² + y²/cly²))`.
pub fn gaussian_filter(x: f64, y: f64, clx: f64, cly: f64) -> f64 {
    (-2.0 * ((x / clx).powi(2) + (y / cly).powi(2))).exp()
}

/// Remove the mean and rescale so that the rms height is exactly `rq`.
fn normalise_to_rq(z: &mut Array2<f64>, rq: f64) -> Result<()> {
    let n = z.len() as f64;
    let mean = z.sum() / n;
    z.mapv_inplace(|v| v - mean);
    let rms = (z.iter().map(|v| v * v).sum::<f64>() / n).sqrt();
    if !(rms.is_finite() && rms > 0.0) {
        return Err(Error::Data(format!(
            "generated surface has rms {rms} before scaling; cannot rescale to Rq"
        )));
    }
    let s = rq / rms;
    z.mapv_inplace(|v| v * s);
    Ok(())
}

/// Generate a periodic Gaussian-correlated rough patch (see the module documentation).
pub fn generate(spec: &GaussianSurfaceSpec) -> Result<Grid2> {
    spec.validate()?;
    let (nx, ny) = (spec.nx, spec.ny);
    let (dx, dy) = (spec.dx(), spec.dy());
    let noise = white_noise(nx, ny, spec.seed);
    let plan = FftPlan::new(nx, ny, Boundary::Periodic);
    let (clx, cly) = (spec.clx_m, spec.cly_m);
    let filter =
        plan.kernel_spectrum(|di, dj| gaussian_filter(di as f64 * dx, dj as f64 * dy, clx, cly));
    let mut z = plan.convolve(&filter, &noise);
    normalise_to_rq(&mut z, spec.rq_m)?;
    Grid2::new(z, dx, dy, true)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn small() -> GaussianSurfaceSpec {
        GaussianSurfaceSpec {
            rq_m: 1e-6,
            clx_m: 4e-6,
            cly_m: 4e-6,
            lx_m: 128e-6,
            ly_m: 128e-6,
            nx: 128,
            ny: 128,
            seed: 7,
        }
    }

    #[test]
    fn reference_is_valid_and_resolved() {
        let r = GaussianSurfaceSpec::reference();
        r.validate().unwrap();
        assert!((r.dx() - 250e-6 / 1024.0).abs() < 1e-20);
    }

    #[test]
    fn rq_exact_zero_mean_periodic() {
        let g = generate(&small()).unwrap();
        assert!(g.periodic);
        assert_eq!((g.nx(), g.ny()), (128, 128));
        let n = g.heights.len() as f64;
        let mean = g.heights.sum() / n;
        let rq = (g.heights.iter().map(|v| v * v).sum::<f64>() / n).sqrt();
        assert!(mean.abs() < 1e-12 * 1e-6, "mean {mean}");
        assert!((rq / 1e-6 - 1.0).abs() < 1e-12, "rq {rq}");
    }

    #[test]
    fn same_seed_same_surface_bit_for_bit_any_thread_count() {
        let a = generate(&small()).unwrap();
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let b = pool.install(|| generate(&small()).unwrap());
        assert!(a
            .heights
            .iter()
            .zip(b.heights.iter())
            .all(|(x, y)| x.to_bits() == y.to_bits()));
        let c = generate(&GaussianSurfaceSpec { seed: 8, ..small() }).unwrap();
        assert!(a.heights != c.heights);
    }

    #[test]
    fn autocorrelation_at_one_cl_is_one_over_e() {
        // Direct ACF estimate along x at lag cl (periodic): average over several seeds.
        let spec = GaussianSurfaceSpec {
            nx: 256,
            ny: 256,
            lx_m: 256e-6,
            ly_m: 256e-6,
            clx_m: 8e-6,
            cly_m: 4e-6,
            ..small()
        };
        let (mut ax, mut ay) = (0.0, 0.0);
        let seeds = 4;
        for s in 0..seeds {
            let g = generate(&GaussianSurfaceSpec { seed: s, ..spec }).unwrap();
            let h = &g.heights;
            let (nx, ny) = h.dim();
            let lag_x = 8; // 8 µm / 1 µm spacing
            let lag_y = 4;
            let mut sx = 0.0;
            let mut sy = 0.0;
            for i in 0..nx {
                for j in 0..ny {
                    sx += h[[i, j]] * h[[(i + lag_x) % nx, j]];
                    sy += h[[i, j]] * h[[i, (j + lag_y) % ny]];
                }
            }
            let var = h.iter().map(|v| v * v).sum::<f64>();
            ax += sx / var;
            ay += sy / var;
        }
        let e = (-1.0f64).exp();
        ax /= seeds as f64;
        ay /= seeds as f64;
        assert!((ax - e).abs() < 0.05, "ACF(clx) = {ax}, want {e}");
        assert!((ay - e).abs() < 0.05, "ACF(cly) = {ay}, want {e}");
    }

    #[test]
    fn bad_parameters_name_themselves() {
        let cases: Vec<(GaussianSurfaceSpec, &str)> = vec![
            (
                GaussianSurfaceSpec {
                    rq_m: 0.0,
                    ..small()
                },
                "rq_m",
            ),
            (
                GaussianSurfaceSpec {
                    rq_m: -1e-6,
                    ..small()
                },
                "rq_m",
            ),
            (
                GaussianSurfaceSpec {
                    rq_m: f64::NAN,
                    ..small()
                },
                "rq_m",
            ),
            (
                GaussianSurfaceSpec {
                    clx_m: 0.0,
                    ..small()
                },
                "clx_m",
            ),
            (
                GaussianSurfaceSpec {
                    cly_m: -1.0,
                    ..small()
                },
                "cly_m",
            ),
            (
                GaussianSurfaceSpec {
                    lx_m: 0.0,
                    ..small()
                },
                "lx_m",
            ),
            (
                GaussianSurfaceSpec {
                    ly_m: f64::INFINITY,
                    ..small()
                },
                "ly_m",
            ),
            (GaussianSurfaceSpec { nx: 0, ..small() }, "nx"),
            (GaussianSurfaceSpec { ny: 1, ..small() }, "ny"),
            (
                GaussianSurfaceSpec {
                    clx_m: 1.5e-6,
                    ..small()
                },
                "under-resolved",
            ),
            (
                GaussianSurfaceSpec {
                    cly_m: 100e-6,
                    ..small()
                },
                "half the patch",
            ),
        ];
        for (spec, want) in cases {
            let msg = generate(&spec).unwrap_err().to_string();
            assert!(msg.contains(want), "{msg} should mention {want}");
        }
    }
}
