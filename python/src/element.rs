//! The Valanis microslip element: integration of a displacement history and least-squares fit
//! to a hysteresis loop. Units: per unit area (q in m, F and Fz in Pa, E0, Et, kn in N/m³) or per
//! element (m, N, N/m) — the mathematics is the same.

use crate::arrays::{borrow_f64, finite_slice};
use crate::errors::IntoPy;
use asperity::calibrate::fit::{self, FitOptions, LoopData};
use asperity::element::{self, valanis, Integrator};
use ndarray::Ix1;
use numpy::PyArray1;
use pyo3::prelude::*;

/// Valanis element parameters, in the order of the Rust constructor: initial stiffness `e0`
/// (N/m³ or N/m), shape `k` (0 ≤ k < 1), residual stiffness `et` (0 ≤ et < e0, same unit as
/// e0), friction coefficient `mu` (> 0).
#[pyclass(frozen, module = "asperity", skip_from_py_object)]
#[derive(Clone, Copy)]
pub struct ValanisParams {
    pub inner: valanis::ValanisParams,
}

#[pymethods]
impl ValanisParams {
    #[new]
    #[pyo3(signature = (e0, k, et, mu))]
    fn new(e0: f64, k: f64, et: f64, mu: f64) -> PyResult<Self> {
        Ok(Self {
            inner: valanis::ValanisParams::new(e0, k, et, mu).py()?,
        })
    }

    #[getter]
    fn e0(&self) -> f64 {
        self.inner.e0
    }

    #[getter]
    fn k(&self) -> f64 {
        self.inner.k
    }

    #[getter]
    fn et(&self) -> f64 {
        self.inner.et
    }

    #[getter]
    fn mu(&self) -> f64 {
        self.inner.mu
    }

    /// Reload slope after a reversal from gross slip, 2·E0/(1+k) (Et = 0).
    #[getter]
    fn reload_slope(&self) -> f64 {
        self.inner.reload_slope()
    }

    /// Half-width of the sliding band μ·Fz·(1 − Et/E0) at normal load `fz`.
    fn slip_limit(&self, fz: f64) -> f64 {
        self.inner.slip_limit(fz)
    }

    fn __repr__(&self) -> String {
        let p = &self.inner;
        format!(
            "ValanisParams(e0={:e}, k={}, et={:e}, mu={})",
            p.e0, p.k, p.et, p.mu
        )
    }

    fn __eq__(&self, other: &Self) -> bool {
        self.inner == other.inner
    }
}

fn integrator(name: &str) -> PyResult<Integrator> {
    match name {
        "implicit-euler" => Ok(Integrator::ImplicitEuler),
        "reference" => Ok(Integrator::Reference),
        o => Err(asperity::Error::param(
            "method",
            format!("expected \"implicit-euler\" or \"reference\", got \"{o}\""),
        ))
        .py(),
    }
}

/// A normal-load argument: an array of the history's length, or one number (constant load).
fn normal_load(obj: &Bound<'_, PyAny>, n: usize) -> PyResult<Vec<f64>> {
    if let Ok(v) = obj.extract::<f64>() {
        return Ok(vec![v; n]);
    }
    let a = borrow_f64::<Ix1>(obj, "fz", "normal load history, same length as q")?;
    Ok(finite_slice(obj.py(), &a, "fz")?.to_vec())
}

/// Force history F[i] (Pa or N) of a virgin Valanis element driven by displacements `q` (m,
/// float64 array) under normal load `fz` (array of the same length, or a number; `fz ≤ 0` is
/// separation). `method`: "implicit-euler" (backward Euler, as dynamic codes use) or
/// "reference" (exact on constant-load branches, adaptive Dormand–Prince otherwise).
#[pyfunction]
#[pyo3(signature = (params, q, fz, method="implicit-euler"))]
pub fn valanis_integrate<'py>(
    py: Python<'py>,
    params: &ValanisParams,
    q: &Bound<'py, PyAny>,
    fz: &Bound<'py, PyAny>,
    method: &str,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let method = integrator(method)?;
    let q = borrow_f64::<Ix1>(q, "q", "displacement history (m)")?;
    let q = finite_slice(py, &q, "q")?;
    let fz = normal_load(fz, q.len())?;
    let f = valanis::integrate(&params.inner, q, &fz, method).py()?;
    Ok(PyArray1::from_vec(py, f))
}

/// Normal load history Fz = max(0, N0 + kn·uz) (Pa or N) for normal displacements `uz` (m).
#[pyfunction]
pub fn normal_load_history<'py>(
    py: Python<'py>,
    n0: f64,
    kn: f64,
    uz: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let uz = borrow_f64::<Ix1>(uz, "uz", "normal displacement history (m)")?;
    let uz = finite_slice(py, &uz, "uz")?;
    Ok(PyArray1::from_vec(
        py,
        element::unilateral::normal_load_history(n0, kn, uz),
    ))
}

/// Energy dissipated over a closed cycle, ∮ F dq (trapezoidal; J/m² per area or J per element).
#[pyfunction]
pub fn dissipated_energy(q: &Bound<'_, PyAny>, f: &Bound<'_, PyAny>) -> PyResult<f64> {
    let py = q.py();
    let qa = borrow_f64::<Ix1>(q, "q", "displacements (m)")?;
    let fa = borrow_f64::<Ix1>(f, "f", "forces")?;
    let (qs, fs) = (finite_slice(py, &qa, "q")?, finite_slice(py, &fa, "f")?);
    if qs.len() != fs.len() {
        return Err(asperity::Error::param(
            "f",
            format!("{} forces for {} displacements", fs.len(), qs.len()),
        ))
        .py();
    }
    Ok(element::dissipated_energy(qs, fs))
}

/// `amplitude·sin(2π i/points_per_cycle)`, i = 0 … cycles·points_per_cycle (m).
#[pyfunction]
pub fn sine_history(
    py: Python<'_>,
    amplitude: f64,
    cycles: usize,
    points_per_cycle: usize,
) -> Bound<'_, PyArray1<f64>> {
    PyArray1::from_vec(
        py,
        element::sine_history(amplitude, cycles, points_per_cycle),
    )
}

/// Result of `fit_valanis`.
#[pyclass(frozen, module = "asperity")]
pub struct ValanisFit {
    inner: fit::FitResult,
}

/// How well a fitted element reproduces one loop.
#[pyclass(frozen, get_all, module = "asperity")]
pub struct LoopFit {
    /// Coefficient of determination of the force.
    pub r2: f64,
    /// RMS force error over the force range.
    pub nrmse: f64,
    /// Energy per cycle of the data (J, or J/m² for stresses).
    pub energy_data: f64,
    /// Energy per cycle of the model (same unit).
    pub energy_model: f64,
    /// `energy_model / energy_data − 1`.
    pub energy_rel_error: f64,
}

#[pymethods]
impl ValanisFit {
    /// Best parameters (μ as given).
    #[getter]
    fn params(&self) -> ValanisParams {
        ValanisParams {
            inner: self.inner.params,
        }
    }

    /// Coefficient of determination on the steady cycle (several loops: their mean).
    #[getter]
    fn r2(&self) -> f64 {
        self.inner.r2
    }

    /// RMS residual over the peak-to-peak force of the steady cycle (first loop).
    #[getter]
    fn nrmse(&self) -> f64 {
        self.inner.loops[0].nrmse
    }

    /// ∮ F dq of the data over the steady cycle (first loop).
    #[getter]
    fn energy_data(&self) -> f64 {
        self.inner.loops[0].energy_data
    }

    /// ∮ F dq of the fitted element over the steady cycle (first loop).
    #[getter]
    fn energy_model(&self) -> f64 {
        self.inner.loops[0].energy_model
    }

    /// (energy_model − energy_data)/energy_data (first loop).
    #[getter]
    fn energy_rel_error(&self) -> f64 {
        self.inner.loops[0].energy_rel_error
    }

    /// Model force over the whole history (first loop; a new array).
    #[getter]
    fn model_force<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.inner.loops[0].model_force)
    }

    /// Per loop (several loops fitted together): its `LoopFit`.
    #[getter]
    fn loops(&self, py: Python<'_>) -> PyResult<Vec<Py<LoopFit>>> {
        self.inner
            .loops
            .iter()
            .map(|l| {
                Py::new(
                    py,
                    LoopFit {
                        r2: l.r2,
                        nrmse: l.nrmse,
                        energy_data: l.energy_data,
                        energy_model: l.energy_model,
                        energy_rel_error: l.energy_rel_error,
                    },
                )
            })
            .collect()
    }

    /// Nelder–Mead iterations summed over the starts.
    #[getter]
    fn iterations(&self) -> u64 {
        self.inner.iterations
    }

    /// Final cost 1 − R² of the best start.
    #[getter]
    fn final_cost(&self) -> f64 {
        self.inner.final_cost
    }

    /// True if the best start stopped on its simplex tolerance.
    #[getter]
    fn converged(&self) -> bool {
        self.inner.converged
    }

    /// Wall time of the fit (s).
    #[getter]
    fn wall_time_s(&self) -> f64 {
        self.inner.wall_time.as_secs_f64()
    }

    fn __repr__(&self) -> String {
        let p = &self.inner.params;
        format!(
            "ValanisFit(e0={:e}, k={}, et={:e}, r2={}, iterations={}, converged={})",
            p.e0,
            p.k,
            p.et,
            self.inner.r2,
            self.inner.iterations,
            if self.inner.converged {
                "True"
            } else {
                "False"
            }
        )
    }
}

/// Least-squares Valanis fit (E0, k; Et too with `fit_et`; μ fixed) of a hysteresis record from
/// the virgin state: displacements `q` (m), forces `force` and normal load `normal_load` (array
/// or number; Pa per area or N), measured on the samples `steady = (start, stop)` (one closed
/// cycle). Nelder–Mead from each of `k_starts`, the best kept. Runs without the GIL.
#[pyfunction]
#[pyo3(signature = (q, force, normal_load, steady, *, mu, fit_et=false, max_iterations=600, k_starts=vec![0.1, 0.5, 0.9]))]
#[allow(clippy::too_many_arguments)]
pub fn fit_valanis(
    py: Python<'_>,
    q: &Bound<'_, PyAny>,
    force: &Bound<'_, PyAny>,
    normal_load: &Bound<'_, PyAny>,
    steady: (usize, usize),
    mu: f64,
    fit_et: bool,
    max_iterations: u64,
    k_starts: Vec<f64>,
) -> PyResult<ValanisFit> {
    let qa = borrow_f64::<Ix1>(q, "q", "displacement history (m)")?;
    let fa = borrow_f64::<Ix1>(force, "force", "force history")?;
    let q = finite_slice(py, &qa, "q")?.to_vec();
    let force = finite_slice(py, &fa, "force")?.to_vec();
    let nl = self::normal_load(normal_load, q.len())?;
    let data = LoopData {
        q,
        force,
        normal_load: nl,
        steady: steady.0..steady.1,
    };
    let opts = FitOptions {
        mu,
        fit_et,
        max_iters: max_iterations,
        k_starts,
    };
    let inner = py.detach(|| fit::fit_valanis(&data, &opts)).py()?;
    Ok(ValanisFit { inner })
}

/// `(q, force, normal_load, steady)` of one loop, as Python passes it.
type LoopArgs<'py> = (
    Bound<'py, PyAny>,
    Bound<'py, PyAny>,
    Bound<'py, PyAny>,
    (usize, usize),
);

/// One Valanis element (E0, k, and Et if `fit_et`; μ fixed) fitted to several loops together:
/// `loops` is a list of `(q, force, normal_load, steady)` as for `fit_valanis`, each driving the
/// element from its own virgin state; the mean of their 1 − R² is minimised (each loop counts
/// the same whatever its force level). Runs without the GIL.
#[pyfunction]
#[pyo3(signature = (loops, *, mu, fit_et=false, max_iterations=600, k_starts=vec![0.1, 0.5, 0.9]))]
pub fn fit_valanis_loops(
    py: Python<'_>,
    loops: Vec<LoopArgs<'_>>,
    mu: f64,
    fit_et: bool,
    max_iterations: u64,
    k_starts: Vec<f64>,
) -> PyResult<ValanisFit> {
    let mut data = Vec::with_capacity(loops.len());
    for (q, force, normal_load, steady) in &loops {
        let qa = borrow_f64::<Ix1>(q, "q", "displacement history (m)")?;
        let fa = borrow_f64::<Ix1>(force, "force", "force history")?;
        let q = finite_slice(py, &qa, "q")?.to_vec();
        let force = finite_slice(py, &fa, "force")?.to_vec();
        let nl = self::normal_load(normal_load, q.len())?;
        data.push(LoopData {
            q,
            force,
            normal_load: nl,
            steady: steady.0..steady.1,
        });
    }
    let opts = FitOptions {
        mu,
        fit_et,
        max_iters: max_iterations,
        k_starts,
    };
    let inner = py.detach(|| fit::fit_valanis_loops(&data, &opts)).py()?;
    Ok(ValanisFit { inner })
}

/// Two-sided 95 % quantile of Student's t with `dof` degrees of freedom (the factor of the
/// calibration table's confidence intervals, `t·s/√N` with `dof = N − 1`).
#[pyfunction]
pub fn student_t_975(dof: f64) -> f64 {
    asperity::core::stats::student_t_975(dof)
}
