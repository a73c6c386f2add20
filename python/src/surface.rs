//! Surfaces: generate, read, write, statistics and power spectrum, composite modulus.
//! Heights in m, spacings in m, moduli in Pa.

use crate::arrays::{borrow_f64, view};
use crate::errors::IntoPy;
use asperity::core::material::{self, Material};
use asperity::surface::combine;
use asperity::surface::generate::GaussianSurfaceSpec;
use asperity::surface::stats::{self, Detrend};
use asperity::surface::{Profile as RsProfile, Topography};
use asperity::Grid2;
use ndarray::{ArrayView1, Ix2};
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use std::path::PathBuf;

/// A rough surface: heights (m) on a regular grid, `heights[i, j]` at `(i·dx_m, j·dy_m)`.
///
/// `periodic` says whether the patch is one period of an infinite surface (generated surfaces
/// are): it selects the periodic or the zero-padded (finite window) contact kernels.
/// The object owns its heights and never changes them; `heights` is a read-only view of them
/// (no copy). Building a `Surface` from a numpy array copies it once, so that solvers can run
/// without the GIL on memory Python cannot change meanwhile.
#[pyclass(frozen, module = "asperity")]
pub struct Surface {
    /// Always `Topography::Area`.
    topo: Topography,
}

impl Surface {
    pub fn grid(&self) -> &Grid2 {
        match &self.topo {
            Topography::Area(g) => g,
            _ => unreachable!("a Surface holds a complete area"),
        }
    }

    pub fn from_grid(grid: Grid2) -> Self {
        Self {
            topo: Topography::Area(grid),
        }
    }
}

fn detrend(text: &str) -> PyResult<Detrend> {
    text.parse::<Detrend>().py()
}

/// Statistics of a topography (the keys of `asperity surface stats --json`; SI units, slopes
/// dimensionless; `None` where undefined).
#[pyclass(frozen, get_all, module = "asperity")]
pub struct SurfaceStats {
    /// `"profile"` or `"area"`.
    pub kind: String,
    /// Whether the samples are uniformly spaced.
    pub uniform: bool,
    /// Whether the topography is one period of a periodic surface.
    pub periodic: bool,
    /// What was removed first: `"mean"` or `"plane"`.
    pub detrend: String,
    /// Points along x.
    pub nx: usize,
    /// Points along y (1 for a profile).
    pub ny: usize,
    /// Missing points (excluded from every statistic).
    pub missing_points: usize,
    /// Spacing along x (m; the mean spacing of a nonuniform profile).
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
    /// Kurtosis Rku.
    pub rku: f64,
    /// RMS slope along x.
    pub rms_slope: f64,
    /// RMS slope along y (area only).
    pub rms_slope_y: Option<f64>,
    /// RMS gradient (area only).
    pub rms_gradient: Option<f64>,
    /// Correlation length where the (radially averaged) ACF drops below 1/e (m).
    pub correlation_length_1_over_e_m: Option<f64>,
    /// Correlation length where the ACF drops below 0.2 (m).
    pub correlation_length_0_2_m: Option<f64>,
    /// 1/e correlation length along x (area only, m).
    pub correlation_length_x_1_over_e_m: Option<f64>,
    /// 1/e correlation length along y (area only, m).
    pub correlation_length_y_1_over_e_m: Option<f64>,
}

#[pymethods]
impl SurfaceStats {
    fn __repr__(&self) -> String {
        format!(
            "SurfaceStats({}, {} x {}, Rq = {:.6e} m)",
            self.kind, self.nx, self.ny, self.rq_m
        )
    }
}

/// Statistics of any topography.
fn surface_stats(py: Python<'_>, topo: &Topography, detrend_: &str) -> PyResult<SurfaceStats> {
    let d = detrend(detrend_)?;
    let s = py.detach(|| stats::stats(topo, d)).py()?;
    Ok(SurfaceStats {
        kind: s.kind.to_string(),
        uniform: s.uniform,
        periodic: s.periodic,
        detrend: match s.detrend {
            Detrend::Mean => "mean",
            Detrend::Plane => "plane",
        }
        .to_string(),
        nx: s.nx,
        ny: s.ny,
        missing_points: s.missing_points,
        dx_m: s.dx_m,
        dy_m: s.dy_m,
        lx_m: s.lx_m,
        ly_m: s.ly_m,
        ra_m: s.ra_m,
        rq_m: s.rq_m,
        rsk: s.rsk,
        rku: s.rku,
        rms_slope: s.rms_slope,
        rms_slope_y: s.rms_slope_y,
        rms_gradient: s.rms_gradient,
        correlation_length_1_over_e_m: s.correlation_length_1_over_e_m,
        correlation_length_0_2_m: s.correlation_length_0_2_m,
        correlation_length_x_1_over_e_m: s.correlation_length_x_1_over_e_m,
        correlation_length_y_1_over_e_m: s.correlation_length_y_1_over_e_m,
    })
}

/// A power spectral density, radially averaged for areas.
#[pyclass(frozen, get_all, module = "asperity")]
pub struct PowerSpectrum {
    /// 1 for a profile, 2 for an area.
    pub dim: usize,
    /// Angular wavenumbers, bin centres (rad/m).
    pub q_rad_per_m: Py<PyArray1<f64>>,
    /// PSD values: m³ for a profile, m⁴ for an area.
    pub c: Py<PyArray1<f64>>,
    /// Fourier coefficients in each bin.
    pub count: Py<PyArray1<u64>>,
}

fn power_spectrum(py: Python<'_>, topo: &Topography, detrend_: &str) -> PyResult<PowerSpectrum> {
    let d = detrend(detrend_)?;
    let psd = py.detach(|| stats::power_spectrum(topo, d)).py()?;
    Ok(PowerSpectrum {
        dim: psd.dim,
        q_rad_per_m: PyArray1::from_vec(py, psd.q).unbind(),
        c: PyArray1::from_vec(py, psd.c).unbind(),
        count: PyArray1::from_vec(py, psd.count.into_iter().map(|c| c as u64).collect()).unbind(),
    })
}

#[pymethods]
impl Surface {
    /// Surface from a float64, C-contiguous array of heights (m), shape (nx, ny), with spacings
    /// `dx_m` and `dy_m` (m; default `dx_m`). Copies the heights once.
    #[new]
    #[pyo3(signature = (heights, dx_m, dy_m=None, periodic=false))]
    fn new(
        heights: &Bound<'_, PyAny>,
        dx_m: f64,
        dy_m: Option<f64>,
        periodic: bool,
    ) -> PyResult<Self> {
        let h = borrow_f64::<Ix2>(heights, "heights", "heights (m), shape (nx, ny)")?;
        let grid = Grid2::new(
            h.as_array().to_owned(),
            dx_m,
            dy_m.unwrap_or(dx_m),
            periodic,
        )
        .py()?;
        Ok(Self::from_grid(grid))
    }

    /// Surface from a SurfaceTopography `Topography` (or any object with its interface:
    /// `heights()`, `physical_sizes`, `nb_grid_pts`, `unit`, `is_periodic`): heights and sizes
    /// are converted from the topography's `unit` to metres, the spacing is the physical size
    /// over the grid points, and the periodicity is the topography's. A topography without a
    /// unit, of another dimension than 2, or with undefined (masked) points is refused.
    /// SurfaceTopography is not needed to call this.
    #[staticmethod]
    fn from_topography(t: &Bound<'_, PyAny>) -> PyResult<Self> {
        let py = t.py();
        let unit: Option<String> = t.getattr("unit")?.extract()?;
        let unit = unit.ok_or_else(|| {
            crate::errors::parameter(
                py,
                "unit",
                "the topography has no length unit: give it one (e.g. Topography(..., unit=\"m\"))"
                    .into(),
            )
        })?;
        let metres = asperity::surface::io::units::metres_per_unit(&unit).ok_or_else(|| {
            crate::errors::parameter(
                py,
                "unit",
                format!("{unit:?} is not a length unit (m, mm, µm, nm, Å, pm)"),
            )
        })?;
        let n: Vec<usize> = t.getattr("nb_grid_pts")?.extract()?;
        let sizes: Vec<f64> = t.getattr("physical_sizes")?.extract()?;
        if n.len() != 2 || sizes.len() != 2 {
            return Err(crate::errors::parameter(
                py,
                "topography",
                format!(
                    "a Surface needs an area (2 grid dimensions), got {} (a line scan: use Profile)",
                    n.len()
                ),
            ));
        }
        if t.getattr("has_undefined_data")
            .and_then(|v| v.extract::<bool>())
            .unwrap_or(false)
        {
            return Err(crate::errors::parameter(
                py,
                "topography",
                "it has undefined (masked) points: fill them first (e.g. t.interpolate_undefined_data())"
                    .into(),
            ));
        }
        let heights = t.call_method0("heights")?;
        let np = py.import("numpy")?;
        let kwargs = pyo3::types::PyDict::new(py);
        kwargs.set_item("dtype", np.getattr("float64")?)?;
        let heights = np.call_method("ascontiguousarray", (heights,), Some(&kwargs))?;
        let h = borrow_f64::<Ix2>(&heights, "heights", "heights, shape nb_grid_pts")?;
        if h.as_array().shape() != [n[0], n[1]] {
            return Err(crate::errors::parameter(
                py,
                "topography",
                format!(
                    "heights() has shape {:?}, nb_grid_pts is {n:?}",
                    h.as_array().shape()
                ),
            ));
        }
        let periodic: bool = t.getattr("is_periodic")?.extract()?;
        let grid = Grid2::new(
            h.as_array().mapv(|z| z * metres),
            sizes[0] * metres / n[0] as f64,
            sizes[1] * metres / n[1] as f64,
            periodic,
        )
        .py()?;
        Ok(Self::from_grid(grid))
    }

    /// A periodic Gaussian-correlated patch (autocorrelation `rq_m² exp(-(x²/clx_m² + y²/cly_m²))`,
    /// Rq exact), the same surface as `asperity surface generate` for the same arguments. The
    /// defaults are the reference case: Rq 0.177 µm, 1/e correlation length 6.6 µm, 250 µm
    /// square, 1024², seed 1. `cly_m`, `ly_m`, `ny` default to their x counterparts.
    #[staticmethod]
    #[pyo3(signature = (*, rq_m=0.177e-6, clx_m=6.6e-6, cly_m=None, lx_m=250e-6, ly_m=None, nx=1024, ny=None, seed=1))]
    #[allow(clippy::too_many_arguments)]
    fn generate(
        py: Python<'_>,
        rq_m: f64,
        clx_m: f64,
        cly_m: Option<f64>,
        lx_m: f64,
        ly_m: Option<f64>,
        nx: usize,
        ny: Option<usize>,
        seed: u64,
    ) -> PyResult<Self> {
        let spec = GaussianSurfaceSpec {
            rq_m,
            clx_m,
            cly_m: cly_m.unwrap_or(clx_m),
            lx_m,
            ly_m: ly_m.unwrap_or(lx_m),
            nx,
            ny: ny.unwrap_or(nx),
            seed,
        };
        let grid = py
            .detach(|| {
                spec.validate()
                    .and_then(|_| asperity::surface::generate(&spec))
            })
            .py()?;
        Ok(Self::from_grid(grid))
    }

    /// Read a height map: `.npy` (+ `.npy.json` sidecar), `.x3p`, or a height-matrix text file.
    /// A 1-D profile file raises `asperity.DataError` (use `read_topography`).
    #[staticmethod]
    fn read(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let grid = py
            .detach(|| {
                asperity::surface::io::read(&path)
                    .and_then(|t| t.into_area(&path.display().to_string()))
            })
            .py()?;
        Ok(Self::from_grid(grid))
    }

    /// Write the heights; the format follows the extension (`.npy` + sidecar, `.x3p`,
    /// `.csv`/`.txt`/`.asc` matrix, `.png` image). Atomic: complete or absent.
    fn write(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        py.detach(|| asperity::surface::io::write(&path, self.grid()))
            .py()
    }

    /// Heights (m), shape (nx, ny): a read-only view (no copy).
    #[getter]
    fn heights(slf: Bound<'_, Self>) -> Bound<'_, PyArray2<f64>> {
        let owner = slf.clone().into_any();
        view(&slf.get().grid().heights, owner)
    }

    /// Grid spacing along x (m).
    #[getter]
    fn dx_m(&self) -> f64 {
        self.grid().dx
    }

    /// Grid spacing along y (m).
    #[getter]
    fn dy_m(&self) -> f64 {
        self.grid().dy
    }

    /// True when the patch is one period of a periodic surface.
    #[getter]
    fn periodic(&self) -> bool {
        self.grid().periodic
    }

    /// Grid shape (nx, ny).
    #[getter]
    fn shape(&self) -> (usize, usize) {
        (self.grid().nx(), self.grid().ny())
    }

    /// Patch size (lx, ly) = (nx·dx, ny·dy) (m).
    #[getter]
    fn size_m(&self) -> (f64, f64) {
        (self.grid().lx(), self.grid().ly())
    }

    /// Statistics (those of `asperity surface stats --json`). `detrend`: "mean" or "plane".
    #[pyo3(signature = (detrend="mean"))]
    fn stats(&self, py: Python<'_>, detrend: &str) -> PyResult<SurfaceStats> {
        surface_stats(py, &self.topo, detrend)
    }

    /// Radially averaged power spectral density (`c` in m⁴).
    #[pyo3(signature = (detrend="mean"))]
    fn power_spectrum(&self, py: Python<'_>, detrend: &str) -> PyResult<PowerSpectrum> {
        power_spectrum(py, &self.topo, detrend)
    }

    fn __repr__(&self) -> String {
        let g = self.grid();
        format!(
            "Surface({} x {} points, dx_m={:e}, dy_m={:e}, periodic={})",
            g.nx(),
            g.ny(),
            g.dx,
            g.dy,
            if g.periodic { "True" } else { "False" }
        )
    }
}

/// A 1-D line scan: heights (m) at `x = i·dx_m`, or at measured `positions_m`.
#[pyclass(frozen, module = "asperity")]
pub struct Profile {
    /// Always `Topography::Profile`.
    topo: Topography,
}

impl Profile {
    fn profile(&self) -> &RsProfile {
        match &self.topo {
            Topography::Profile(p) => p,
            _ => unreachable!("a Profile holds a profile"),
        }
    }
}

#[pymethods]
impl Profile {
    /// Heights (m): a read-only view (no copy).
    #[getter]
    fn heights(slf: Bound<'_, Self>) -> Bound<'_, PyArray1<f64>> {
        let owner = slf.clone().into_any();
        view(&ArrayView1::from(&slf.get().profile().heights[..]), owner)
    }

    /// Measured positions (m) of a nonuniform profile, or None.
    #[getter]
    fn positions_m<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f64>>> {
        self.profile()
            .positions
            .as_ref()
            .map(|x| PyArray1::from_slice(py, x))
    }

    /// Sample spacing (m); the mean spacing of a nonuniform profile.
    #[getter]
    fn dx_m(&self) -> f64 {
        self.profile().dx
    }

    #[getter]
    fn periodic(&self) -> bool {
        self.profile().periodic
    }

    /// Statistics, as for `Surface.stats`.
    #[pyo3(signature = (detrend="mean"))]
    fn stats(&self, py: Python<'_>, detrend: &str) -> PyResult<SurfaceStats> {
        surface_stats(py, &self.topo, detrend)
    }

    /// Power spectral density (`c` in m³).
    #[pyo3(signature = (detrend="mean"))]
    fn power_spectrum(&self, py: Python<'_>, detrend: &str) -> PyResult<PowerSpectrum> {
        power_spectrum(py, &self.topo, detrend)
    }

    fn __len__(&self) -> usize {
        self.profile().len()
    }

    fn __repr__(&self) -> String {
        let p = self.profile();
        format!(
            "Profile({} points, dx_m={:e}, {})",
            p.len(),
            p.dx,
            if p.is_uniform() {
                "uniform"
            } else {
                "nonuniform"
            }
        )
    }
}

/// Read any topography file: a `Surface` (areas) or a `Profile` (Dektak CSV, profile text).
#[pyfunction]
pub fn read_topography(py: Python<'_>, path: PathBuf) -> PyResult<Py<PyAny>> {
    let topo = py.detach(|| asperity::surface::io::read(&path)).py()?;
    // A map with missing points is refused, naming the file and `--fill` (fill it with
    // `asperity surface convert --fill harmonic|nearest` first).
    let topo = match topo {
        t @ Topography::MaskedArea(_) => {
            Topography::Area(t.into_area(&path.display().to_string()).py()?)
        }
        t => t,
    };
    Ok(match topo {
        Topography::Profile(_) => Py::new(py, Profile { topo })?.into_any(),
        _ => Py::new(py, Surface { topo })?.into_any(),
    })
}

/// Composite modulus E* (Pa) of two bodies: `1/E* = (1-ν1²)/E1 + (1-ν2²)/E2`
/// (body 2 defaults to body 1).
#[pyfunction]
#[pyo3(signature = (youngs_modulus_pa, poisson_ratio, youngs_modulus_2_pa=None, poisson_ratio_2=None))]
pub fn composite_modulus(
    youngs_modulus_pa: f64,
    poisson_ratio: f64,
    youngs_modulus_2_pa: Option<f64>,
    poisson_ratio_2: Option<f64>,
) -> PyResult<f64> {
    let b1 = Material {
        youngs_modulus_pa,
        poisson_ratio,
    };
    let b2 = Material {
        youngs_modulus_pa: youngs_modulus_2_pa.unwrap_or(youngs_modulus_pa),
        poisson_ratio: poisson_ratio_2.unwrap_or(poisson_ratio),
    };
    material::composite_modulus(b1, b2).py()
}

/// Equivalent rough surface `h1 − h2` of two bodies on a common grid (for a rigid-elastic
/// contact with the composite modulus).
#[pyfunction]
pub fn equivalent_surface(body1: &Surface, body2: &Surface) -> PyResult<Surface> {
    Ok(Surface::from_grid(
        combine::equivalent_surface(body1.grid(), body2.grid()).py()?,
    ))
}
