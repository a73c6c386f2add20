//! Normal contact (projected CG: preconditioned or Polonsky–Keer) and tangential partial slip
//! (Coulomb, with history).
//! Pressures and moduli in Pa, lengths and gaps in m, forces in N, energies in J.

use crate::arrays::{borrow_f64, view};
use crate::errors::IntoPy;
use crate::surface::Surface;
use asperity::calibrate::amplitudes;
use asperity::contact::normal::{self, NormalOptions, NormalProblem};
use asperity::contact::sweep::{self, SweepOptions};
use asperity::contact::tangential::{
    self, Control, Operator, Oscillation, TangentialOptions, TangentialProblem,
};
use asperity::core::fft::Boundary;
use asperity::core::material::Material;
use ndarray::{Array2, Ix2};
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// A converged normal-contact solution. Fields are SI; the arrays (`pressure`, `gap`,
/// `displacement`, shape (nx, ny)) are read-only views of the solution's memory (no copy).
#[pyclass(frozen, module = "asperity")]
pub struct NormalSolution {
    pub inner: normal::NormalSolution,
    /// Tolerance the solve met.
    tolerance: f64,
    /// Boundary of the surface it was solved on.
    pub periodic: bool,
}

/// How a normal solve converged.
#[pyclass(frozen, get_all, module = "asperity")]
pub struct Convergence {
    /// Iterations taken.
    pub iterations: usize,
    /// Final relative residual.
    pub residual: f64,
    /// Relative tolerance asked for.
    pub tolerance: f64,
    /// Whether the residual reached the tolerance.
    pub converged: bool,
    /// Wall-clock time of the solve (s).
    pub wall_time_s: f64,
}

#[pymethods]
impl Convergence {
    fn __repr__(&self) -> String {
        format!(
            "Convergence({} iterations, residual {:.3e} / tolerance {:.1e}, converged={})",
            self.iterations,
            self.residual,
            self.tolerance,
            if self.converged { "True" } else { "False" }
        )
    }
}

#[pymethods]
impl NormalSolution {
    /// Contact pressure p (Pa); zero outside the contact.
    #[getter]
    fn pressure(slf: Bound<'_, Self>) -> Bound<'_, PyArray2<f64>> {
        let owner = slf.clone().into_any();
        view(&slf.get().inner.pressure, owner)
    }

    /// Gap g = h0 − δ + u (m), ≥ 0 up to the tolerance, zero in contact.
    #[getter]
    fn gap(slf: Bound<'_, Self>) -> Bound<'_, PyArray2<f64>> {
        let owner = slf.clone().into_any();
        view(&slf.get().inner.gap, owner)
    }

    /// Elastic surface displacement u = K ⊛ p (m), both bodies combined (zero-mean for
    /// periodic patches).
    #[getter]
    fn displacement(slf: Bound<'_, Self>) -> Bound<'_, PyArray2<f64>> {
        let owner = slf.clone().into_any();
        view(&slf.get().inner.displacement, owner)
    }

    /// Grid spacings (dx, dy) (m).
    #[getter]
    fn spacing_m(&self) -> (f64, f64) {
        (self.inner.dx, self.inner.dy)
    }

    /// Hardness H that bounded the pressure (Pa), or None for elastic contact.
    #[getter]
    fn hardness_pa(&self) -> Option<f64> {
        self.inner.hardness_pa
    }

    /// Grid points in elastic contact, 0 < p < H.
    #[getter]
    fn elastic_points(&self) -> usize {
        self.inner.elastic_points
    }

    /// Grid points in plastic contact, p = H.
    #[getter]
    fn plastic_points(&self) -> usize {
        self.inner.plastic_points
    }

    /// Elastic contact area over nominal area (-).
    #[getter]
    fn elastic_area_ratio(&self) -> f64 {
        self.inner.elastic_area_ratio
    }

    /// Plastic contact area over nominal area (-).
    #[getter]
    fn plastic_area_ratio(&self) -> f64 {
        self.inner.plastic_area_ratio
    }

    /// Plastically displaced volume V_p = Σ_{p=H} max(−g, 0)·dx·dy (m³).
    #[getter]
    fn plastic_volume_m3(&self) -> f64 {
        self.inner.plastic_volume_m3
    }

    /// Plastic penetration max(−g, 0) at the plastic points, zero elsewhere (m): the residual
    /// surface after unloading is the surface's heights minus it.
    fn plastic_penetration<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        PyArray2::from_owned_array(py, self.inner.plastic_penetration())
    }

    /// True when solved with the periodic kernel.
    #[getter]
    fn periodic(&self) -> bool {
        self.periodic
    }

    /// Imposed mean pressure p̄ over the patch (Pa).
    #[getter]
    fn mean_pressure_pa(&self) -> f64 {
        self.inner.mean_pressure_pa
    }

    /// Real over nominal contact area (-).
    #[getter]
    fn contact_area_ratio(&self) -> f64 {
        self.inner.contact_area_ratio
    }

    /// Grid points in contact.
    #[getter]
    fn contact_points(&self) -> usize {
        self.inner.contact_points
    }

    /// Contact spots (4-connected clusters; across periodic boundaries counted once).
    #[getter]
    fn contact_spots(&self) -> usize {
        self.inner.contact_spots
    }

    /// Grid points of the smallest contact spot.
    #[getter]
    fn smallest_spot_points(&self) -> usize {
        self.inner.smallest_spot_points
    }

    /// Grid points of the median contact spot.
    #[getter]
    fn median_spot_points(&self) -> usize {
        self.inner.median_spot_points
    }

    /// Mean gap (m): mean separation of the surfaces.
    #[getter]
    fn mean_gap_m(&self) -> f64 {
        self.inner.mean_gap_m
    }

    /// Rigid approach δ from first contact of the highest point (m).
    #[getter]
    fn approach_m(&self) -> f64 {
        self.inner.approach_m
    }

    /// Elastic energy ½ Σ p·u·dA (J).
    #[getter]
    fn elastic_energy_j(&self) -> f64 {
        self.inner.elastic_energy_j
    }

    /// Iterations of the solve (search directions).
    #[getter]
    fn iterations(&self) -> usize {
        self.inner.iterations
    }

    /// Final relative gap error ε.
    #[getter]
    fn residual(&self) -> f64 {
        self.inner.residual
    }

    /// Always True (non-convergence raises `asperity.ConvergenceError`).
    #[getter]
    fn converged(&self) -> bool {
        self.inner.converged
    }

    /// Wall time of the solve (s).
    #[getter]
    fn wall_time_s(&self) -> f64 {
        self.inner.wall_time_s
    }

    /// The convergence record: iterations, residual, tolerance, converged, wall time.
    #[getter]
    fn convergence(&self) -> Convergence {
        Convergence {
            iterations: self.inner.iterations,
            residual: self.inner.residual,
            tolerance: self.tolerance,
            converged: self.inner.converged,
            wall_time_s: self.inner.wall_time_s,
        }
    }

    fn __repr__(&self) -> String {
        format!(
            "NormalSolution(mean_pressure_pa={:e}, contact_area_ratio={:e}, mean_gap_m={:e}, iterations={}, residual={:e})",
            self.inner.mean_pressure_pa,
            self.inner.contact_area_ratio,
            self.inner.mean_gap_m,
            self.inner.iterations,
            self.inner.residual
        )
    }
}

/// Normal contact solver (projected CG) for one surface against an elastic half-space of
/// composite modulus `e_star_pa` (Pa; see `composite_modulus`): FFT plan and kernel are built
/// once and reused by every solve. Solves run without the GIL.
#[pyclass(module = "asperity")]
pub struct NormalSolver {
    inner: normal::NormalSolver,
    periodic: bool,
}

fn normal_options(tolerance: f64, max_iterations: usize, method: &str) -> PyResult<NormalOptions> {
    Ok(NormalOptions {
        tolerance,
        max_iterations,
        method: method.parse().py()?,
        ..NormalOptions::default()
    })
}

#[pymethods]
impl NormalSolver {
    /// `tolerance`: relative gap error ε to reach; `max_iterations`: cap per solve (reaching
    /// it raises `asperity.ConvergenceError`); `method`: "auto", "preconditioned" or
    /// "polonsky-keer".
    /// `hardness_pa`: the hardness H bounding the pressure (elastic–perfectly plastic contact),
    /// None for elastic contact.
    #[new]
    #[pyo3(signature = (surface, *, e_star_pa, hardness_pa=None, tolerance=NormalOptions::DEFAULT_TOLERANCE, max_iterations=5000, method="auto"))]
    fn new(
        py: Python<'_>,
        surface: &Surface,
        e_star_pa: f64,
        hardness_pa: Option<f64>,
        tolerance: f64,
        max_iterations: usize,
        method: &str,
    ) -> PyResult<Self> {
        let grid = surface.grid();
        let options = normal_options(tolerance, max_iterations, method)?;
        let inner = py
            .detach(|| {
                normal::NormalSolver::new(
                    &NormalProblem {
                        surface: grid,
                        e_star_pa,
                        hardness_pa,
                    },
                    options,
                )
            })
            .py()?;
        Ok(Self {
            inner,
            periodic: grid.periodic,
        })
    }

    /// Load control: the solution at mean pressure `mean_pressure_pa` (Pa, over the patch).
    /// `warm_start`: a previous solution on this grid (its pressure shape starts the iteration).
    #[pyo3(signature = (mean_pressure_pa, warm_start=None))]
    fn solve_load(
        &mut self,
        py: Python<'_>,
        mean_pressure_pa: f64,
        warm_start: Option<Bound<'_, NormalSolution>>,
    ) -> PyResult<NormalSolution> {
        let warm = warm_start.as_ref().map(|w| &w.get().inner);
        let inner = &mut self.inner;
        let sol = py
            .detach(|| inner.solve_load(mean_pressure_pa, warm))
            .py()?;
        Ok(self.wrap(sol))
    }

    /// Normal contact stiffness `kn = dp̄/dδ` (N/m³) of a converged solution of this solver,
    /// from the tangent problem on its contact set (one linear solve; what `normal_sweep` and the
    /// calibration use).
    fn contact_stiffness(
        &mut self,
        py: Python<'_>,
        solution: Bound<'_, NormalSolution>,
    ) -> PyResult<f64> {
        let sol = &solution.get().inner;
        let inner = &mut self.inner;
        let kn = py.detach(|| inner.contact_stiffness(sol)).py()?;
        Ok(kn.kn_n_per_m3)
    }

    /// Loading tangent dp̄/dδ (N/m³) of a hardness-limited solution: the tangent problem on its
    /// elastic points, the plastic ones held at H (equal to `contact_stiffness` without plastic
    /// points). `contact_stiffness` is then the unloading/reloading stiffness, the one an
    /// element carries.
    fn loading_stiffness(
        &mut self,
        py: Python<'_>,
        solution: Bound<'_, NormalSolution>,
    ) -> PyResult<f64> {
        let sol = &solution.get().inner;
        let inner = &mut self.inner;
        let kn = py.detach(|| inner.loading_stiffness(sol)).py()?;
        Ok(kn.kn_n_per_m3)
    }

    /// Displacement control: the solution at rigid approach `approach_m` (m, from first contact).
    #[pyo3(signature = (approach_m, warm_start=None))]
    fn solve_approach(
        &mut self,
        py: Python<'_>,
        approach_m: f64,
        warm_start: Option<Bound<'_, NormalSolution>>,
    ) -> PyResult<NormalSolution> {
        let warm = warm_start.as_ref().map(|w| &w.get().inner);
        let inner = &mut self.inner;
        let sol = py.detach(|| inner.solve_approach(approach_m, warm)).py()?;
        Ok(self.wrap(sol))
    }

    /// Elastic displacement u = K ⊛ p (m) of any pressure field p (Pa) on this grid.
    fn displacement_of<'py>(
        &mut self,
        py: Python<'py>,
        pressure: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let p = borrow_f64::<Ix2>(pressure, "pressure", "pressure (Pa), shape (nx, ny)")?;
        let p: Array2<f64> = p.as_array().to_owned();
        let inner = &mut self.inner;
        let u = py.detach(|| inner.displacement_of(&p)).py()?;
        Ok(PyArray2::from_owned_array(py, u))
    }

    /// Grid shape (nx, ny).
    #[getter]
    fn shape(&self) -> (usize, usize) {
        self.inner.grid_shape()
    }

    /// Composite modulus E* (Pa).
    #[getter]
    fn e_star_pa(&self) -> f64 {
        self.inner.e_star_pa()
    }

    /// Tolerance on the relative gap error.
    #[getter]
    fn tolerance(&self) -> f64 {
        self.inner.options().tolerance
    }

    /// Iteration cap per solve.
    #[getter]
    fn max_iterations(&self) -> usize {
        self.inner.options().max_iterations
    }
}

impl NormalSolver {
    fn wrap(&self, inner: normal::NormalSolution) -> NormalSolution {
        NormalSolution {
            inner,
            tolerance: self.inner.options().tolerance,
            periodic: self.periodic,
        }
    }
}

/// The columns of a sweep, named as in `normal_sweep.csv` (plus `wall_time_s`).
fn sweep_columns<'py>(
    py: Python<'py>,
    points: &[sweep::SweepPoint],
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let f = |g: fn(&sweep::SweepPoint) -> f64| {
        PyArray1::from_vec(py, points.iter().map(g).collect::<Vec<f64>>())
    };
    let u = |g: fn(&sweep::SweepPoint) -> usize| {
        PyArray1::from_vec(py, points.iter().map(|p| g(p) as u64).collect::<Vec<u64>>())
    };
    d.set_item("pressure_Pa", f(|p| p.pressure_pa))?;
    d.set_item("contact_area_ratio", f(|p| p.contact_area_ratio))?;
    d.set_item("mean_gap_m", f(|p| p.mean_gap_m))?;
    d.set_item("kn_N_per_m3", f(|p| p.kn_n_per_m3))?;
    d.set_item("approach_m", f(|p| p.approach_m))?;
    d.set_item("contact_spots", u(|p| p.contact_spots))?;
    d.set_item("smallest_spot_points", u(|p| p.smallest_spot_points))?;
    d.set_item("median_spot_points", u(|p| p.median_spot_points))?;
    d.set_item(
        "points_across_contact",
        f(|p| p.resolution.points_across_contact()),
    )?;
    d.set_item(
        "points_across_free",
        f(|p| p.resolution.points_across_free()),
    )?;
    d.set_item(
        "method",
        points.iter().map(|p| p.method.name()).collect::<Vec<_>>(),
    )?;
    d.set_item("iterations", u(|p| p.iterations))?;
    d.set_item("stiffness_iterations", u(|p| p.stiffness_iterations))?;
    d.set_item("residual", f(|p| p.residual))?;
    d.set_item("wall_time_s", f(|p| p.wall_time_s))?;
    if points.iter().all(|p| p.plastic.is_some()) && !points.is_empty() {
        let pl = |g: fn(&sweep::PlasticPoint) -> f64| {
            PyArray1::from_vec(
                py,
                points
                    .iter()
                    .map(|p| p.plastic.as_ref().map_or(f64::NAN, g))
                    .collect::<Vec<f64>>(),
            )
        };
        d.set_item("kn_unloading_N_per_m3", f(|p| p.kn_n_per_m3))?;
        d.set_item("kn_loading_N_per_m3", pl(|p| p.kn_loading_n_per_m3))?;
        d.set_item("elastic_area_ratio", pl(|p| p.elastic_area_ratio))?;
        d.set_item("plastic_area_ratio", pl(|p| p.plastic_area_ratio))?;
        d.set_item("plastic_points", pl(|p| p.plastic_points as f64))?;
        d.set_item("plastic_volume_m3", pl(|p| p.plastic_volume_m3))?;
    }
    Ok(d)
}

/// The pressure sweep of `asperity contact normal` on one surface: warm-started solves at the
/// sorted `pressures_pa` (Pa) and `kn = dp̄/dδ` (N/m³) from the tangent problem on each contact
/// set. Returns a dict of columns named as in `normal_sweep.csv` (numpy arrays; `method` a list).
/// `hardness_pa`: elastic–perfectly plastic contact (pressure ≤ H); the dict then also holds the
/// unloading and loading stiffnesses, the elastic and plastic areas and the plastic volume.
#[pyfunction]
#[pyo3(signature = (surface, pressures_pa, *, e_star_pa, hardness_pa=None, tolerance=NormalOptions::DEFAULT_TOLERANCE, max_iterations=5000, method="auto"))]
#[allow(clippy::too_many_arguments)]
pub fn normal_sweep<'py>(
    py: Python<'py>,
    surface: &Surface,
    pressures_pa: Vec<f64>,
    e_star_pa: f64,
    hardness_pa: Option<f64>,
    tolerance: f64,
    max_iterations: usize,
    method: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let grid = surface.grid();
    let options = normal_options(tolerance, max_iterations, method)?;
    let result = py
        .detach(|| {
            let mut solver = normal::NormalSolver::new(
                &NormalProblem {
                    surface: grid,
                    e_star_pa,
                    hardness_pa,
                },
                options,
            )?;
            sweep::run(
                &mut solver,
                &pressures_pa,
                SweepOptions {
                    keep_solutions: false,
                },
                |_| {},
            )
        })
        .py()?;
    sweep_columns(py, &result.points)
}

fn operator(name: &str) -> PyResult<Operator> {
    match name {
        "auto" => Ok(Operator::Auto),
        "dense" => Ok(Operator::Dense),
        "fft" => Ok(Operator::Fft),
        o => Err(asperity::Error::param(
            "operator",
            format!("expected \"auto\", \"dense\" or \"fft\", got \"{o}\""),
        ))
        .py(),
    }
}

/// Exactly one of a displacement (m) or a force (N) as a control, along `direction`.
fn control(displacement_m: Option<[f64; 2]>, force_n: Option<[f64; 2]>) -> PyResult<Control> {
    match (displacement_m, force_n) {
        (Some(d), None) => Ok(Control::Displacement(d)),
        (None, Some(f)) => Ok(Control::Force(f)),
        _ => Err(asperity::Error::param(
            "displacement_m / force_n",
            "give exactly one",
        ))
        .py(),
    }
}

/// Partial-slip solver on one fixed pressure field (quasi-identical materials: normal–tangential
/// coupling neglected, exact for two bodies of the same material). Holds the contact history.
/// One tangential load step (SI).
#[pyclass(frozen, get_all, module = "asperity")]
pub struct TangentialStep {
    /// Rigid shift (dx, dy) of the bodies (m).
    pub shift_m: (f64, f64),
    /// Total tangential force (Tx, Ty) (N).
    pub force_n: (f64, f64),
    /// Mean shear stress (Pa) over the nominal area.
    pub mean_shear_pa: (f64, f64),
    /// Fraction of the contact points in stick.
    pub stick_fraction: f64,
    /// Slip accumulated since the virgin state, summed over the points (m).
    pub accumulated_slip_m: f64,
    /// Frictional work since the virgin state (J).
    pub frictional_work_j: f64,
    /// Solver iterations of the step.
    pub iterations: usize,
    /// Final relative residual.
    pub residual: f64,
    /// Whether the residual reached the tolerance.
    pub converged: bool,
    /// Wall-clock time of the step (s).
    pub wall_time_s: f64,
}

impl From<&tangential::TangentialStep> for TangentialStep {
    fn from(s: &tangential::TangentialStep) -> Self {
        Self {
            shift_m: (s.shift_m[0], s.shift_m[1]),
            force_n: (s.force_n[0], s.force_n[1]),
            mean_shear_pa: (s.mean_shear_pa[0], s.mean_shear_pa[1]),
            stick_fraction: s.stick_fraction,
            accumulated_slip_m: s.accumulated_slip_m,
            frictional_work_j: s.frictional_work_j,
            iterations: s.iterations,
            residual: s.residual,
            converged: s.converged,
            wall_time_s: s.wall_time_s,
        }
    }
}

/// Energy of one load cycle.
#[pyclass(frozen, get_all, module = "asperity")]
pub struct CycleEnergy {
    /// Cycle number (1-based; cycle 1 includes the initial loading branch).
    pub cycle: usize,
    /// Loop area ∮T·dδ (J).
    pub dissipated_j: f64,
    /// The same per nominal area (J/m²).
    pub dissipated_j_per_m2: f64,
    /// Frictional work of the cycle (J).
    pub frictional_work_j: f64,
}

/// Set-up facts of a tangential solver.
#[pyclass(frozen, get_all, skip_from_py_object, module = "asperity")]
#[derive(Clone)]
pub struct TangentialMetadata {
    /// The coupling assumption.
    pub assumption: String,
    /// Friction coefficient μ.
    pub friction_coefficient: f64,
    /// Grid points (nx, ny).
    pub grid: (usize, usize),
    /// `"periodic"` or the finite window's boundary.
    pub boundary: String,
    /// The shear compliance operator.
    pub operator: String,
    /// Points in contact.
    pub contact_points: usize,
    /// Normal force (N).
    pub normal_force_n: f64,
    /// Nominal area (m²).
    pub nominal_area_m2: f64,
    /// Norm of the compliance operator (m/Pa).
    pub compliance_norm_m_per_pa: f64,
    /// Set-up time (s).
    pub setup_time_s: f64,
}

/// A serde-named enum's name (the JSON string).
fn serde_name<T: serde::Serialize>(v: &T) -> String {
    match serde_json::to_value(v) {
        Ok(serde_json::Value::String(s)) => s,
        Ok(other) => other.to_string(),
        Err(e) => e.to_string(),
    }
}

impl From<&tangential::TangentialMetadata> for TangentialMetadata {
    fn from(m: &tangential::TangentialMetadata) -> Self {
        Self {
            assumption: m.assumption.to_string(),
            friction_coefficient: m.friction_coefficient,
            grid: m.grid,
            boundary: serde_name(&m.boundary),
            operator: serde_name(&m.operator),
            contact_points: m.contact_points,
            normal_force_n: m.normal_force_n,
            nominal_area_m2: m.nominal_area_m2,
            compliance_norm_m_per_pa: m.compliance_norm_m_per_pa,
            setup_time_s: m.setup_time_s,
        }
    }
}

/// A sinusoidal tangential history (the results of `asperity contact tangential`).
#[pyclass(frozen, get_all, module = "asperity")]
pub struct OscillationResult {
    /// Columns per step (step 0: unloaded): displacement_m, displacement_y_m, force_N,
    /// force_y_N, mean_shear_stress_Pa, mean_shear_stress_y_Pa, stick_fraction,
    /// accumulated_slip_m, frictional_work_J, iterations, residual, wall_time_s.
    pub steps: Py<PyDict>,
    /// Energy per cycle.
    pub cycles: Vec<Py<CycleEnergy>>,
    /// The solver's set-up facts.
    pub metadata: TangentialMetadata,
    /// Wall-clock time of the history (s).
    pub wall_time_s: f64,
}

/// One amplitude's loop of the calibration's loading history.
#[pyclass(frozen, get_all, module = "asperity")]
pub struct AmplitudeLoop {
    /// Amplitude over the gross-slip displacement.
    pub amplitude_factor: f64,
    /// Amplitude (m).
    pub amplitude_m: f64,
    /// Steady cycle +a → −a → +a: displacement (m).
    pub displacement_m: Py<PyArray1<f64>>,
    /// Mean shear stress at those samples (Pa).
    pub shear_stress_pa: Py<PyArray1<f64>>,
    /// Loop area ∮τ dδ (J/m²).
    pub loop_area_j_per_m2: f64,
    /// Frictional dissipation of the computed half cycle, doubled (J/m²).
    pub dissipation_j_per_m2: f64,
    /// Closure error of the computed half cycle (0 for an exactly closed Masing loop).
    pub closure_error: f64,
    /// Displacement of the loop as the calibration fits it (m).
    pub fit_q: Py<PyArray1<f64>>,
    /// Shear stress of the loop as the calibration fits it (Pa).
    pub fit_force: Py<PyArray1<f64>>,
    /// Index range [start, end) of the steady cycle in `fit_q`.
    pub steady: (usize, usize),
}

/// The calibration's loading history: loops at increasing amplitudes.
#[pyclass(frozen, get_all, module = "asperity")]
pub struct AmplitudeHistory {
    /// Gross-slip displacement δ_gs (m) the amplitudes are scaled by.
    pub gross_slip_displacement_m: f64,
    /// Load steps taken.
    pub steps: usize,
    /// One loop per amplitude, in order.
    pub loops: Vec<Py<AmplitudeLoop>>,
}

#[pyclass(module = "asperity")]
pub struct TangentialSolver {
    inner: tangential::TangentialSolver,
}

#[pymethods]
impl TangentialSolver {
    /// `pressure`: a `NormalSolution`, or a float64 array of pressures (Pa, shape (nx, ny)) with
    /// `spacing_m=(dx, dy)` and `periodic`. Body 1 has `youngs_modulus_pa`, `poisson_ratio`;
    /// body 2 the `_2` values (default: the same material). `friction_coefficient` μ (-).
    /// `tolerance`: relative natural residual; `operator`: "auto", "dense" or "fft".
    #[new]
    #[pyo3(signature = (pressure, *, friction_coefficient, spacing_m=None, periodic=None, youngs_modulus_pa=210e9, poisson_ratio=0.3, youngs_modulus_2_pa=None, poisson_ratio_2=None, tolerance=TangentialOptions::default().tolerance, max_iterations=TangentialOptions::default().max_iterations, operator="auto"))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        pressure: &Bound<'_, PyAny>,
        friction_coefficient: f64,
        spacing_m: Option<(f64, f64)>,
        periodic: Option<bool>,
        youngs_modulus_pa: f64,
        poisson_ratio: f64,
        youngs_modulus_2_pa: Option<f64>,
        poisson_ratio_2: Option<f64>,
        tolerance: f64,
        max_iterations: usize,
        operator: &str,
    ) -> PyResult<Self> {
        let options = TangentialOptions {
            tolerance,
            max_iterations,
            operator: self::operator(operator)?,
        };
        let body1 = Material {
            youngs_modulus_pa,
            poisson_ratio,
        };
        let body2 = Material {
            youngs_modulus_pa: youngs_modulus_2_pa.unwrap_or(youngs_modulus_pa),
            poisson_ratio: poisson_ratio_2.unwrap_or(poisson_ratio),
        };
        let build = |p: &Array2<f64>, (dx, dy): (f64, f64), periodic: bool| {
            tangential::TangentialSolver::new(
                &TangentialProblem {
                    pressure: p,
                    dx,
                    dy,
                    boundary: if periodic {
                        Boundary::Periodic
                    } else {
                        Boundary::ZeroPadded
                    },
                    friction_coefficient,
                    body1,
                    body2,
                },
                options,
            )
        };
        let inner = if let Ok(sol) = pressure.cast::<NormalSolution>() {
            let s = sol.get();
            let spacing = spacing_m.unwrap_or((s.inner.dx, s.inner.dy));
            let periodic = periodic.unwrap_or(s.periodic);
            py.detach(|| build(&s.inner.pressure, spacing, periodic))
        } else {
            let p = borrow_f64::<Ix2>(pressure, "pressure", "pressure (Pa), shape (nx, ny)")?;
            let (Some(spacing), Some(periodic)) = (spacing_m, periodic) else {
                return Err(asperity::Error::param(
                    "spacing_m / periodic",
                    "give both with a pressure array (they come from a NormalSolution otherwise)",
                ))
                .py();
            };
            let p = p.as_array().to_owned();
            py.detach(|| build(&p, spacing, periodic))
        }
        .py()?;
        Ok(Self { inner })
    }

    /// One load step from the current state: impose a rigid shift `displacement_m=(dx, dy)` (m)
    /// or a total force `force_n=(Tx, Ty)` (N). Returns the step's `TangentialStep`.
    #[pyo3(signature = (*, displacement_m=None, force_n=None))]
    fn step(
        &mut self,
        py: Python<'_>,
        displacement_m: Option<[f64; 2]>,
        force_n: Option<[f64; 2]>,
    ) -> PyResult<TangentialStep> {
        let c = control(displacement_m, force_n)?;
        let inner = &mut self.inner;
        let s = py.detach(|| inner.step(c)).py()?;
        Ok(TangentialStep::from(&s))
    }

    /// A sinusoidal history from the virgin state (the solver is reset first):
    /// `amplitude · sin(2π k / steps_per_cycle)`, `k = 1 … cycles·steps_per_cycle`, with the
    /// amplitude a displacement `amplitude_m=(ax, ay)` (m) or a force `amplitude_n` (N).
    /// Returns an `OscillationResult`; step 0 is the unloaded initial state.
    #[pyo3(signature = (*, amplitude_m=None, amplitude_n=None, cycles=3, steps_per_cycle=40))]
    fn oscillate<'py>(
        &mut self,
        py: Python<'py>,
        amplitude_m: Option<[f64; 2]>,
        amplitude_n: Option<[f64; 2]>,
        cycles: usize,
        steps_per_cycle: usize,
    ) -> PyResult<OscillationResult> {
        let amplitude = control(amplitude_m, amplitude_n)?;
        let inner = &mut self.inner;
        let r = py
            .detach(|| {
                tangential::oscillate(
                    inner,
                    &Oscillation {
                        amplitude,
                        cycles,
                        steps_per_cycle,
                    },
                    |_, _| {},
                )
            })
            .py()?;
        oscillation_result(py, &r)
    }

    /// The calibration's loading history (`asperity::calibrate::amplitudes`): one history of
    /// increasing displacement amplitudes `factors × δ_gs` along x from the virgin state (the
    /// solver is reset first), one half cycle per amplitude completed by its point reflection
    /// (Masing). Returns an `AmplitudeHistory`; each loop's `fit_q`, `fit_force` and `steady`
    /// are the loop as the calibration fits it (the element's virgin quarter cycle to +a, then
    /// the steady cycle), for `fit_valanis_loops` with the pressure as the normal load.
    #[pyo3(signature = (factors, steps_per_cycle=40))]
    fn amplitude_loops<'py>(
        &mut self,
        py: Python<'py>,
        factors: Vec<f64>,
        steps_per_cycle: usize,
    ) -> PyResult<AmplitudeHistory> {
        let inner = &mut self.inner;
        let sweep = py
            .detach(|| amplitudes::run(inner, &factors, steps_per_cycle, || {}))
            .py()?;
        let loops = sweep
            .loops
            .iter()
            .enumerate()
            .map(|(j, l)| {
                // The normal load is set by the caller; 1.0 here only fills the field.
                let data =
                    asperity::calibrate::pipeline::loop_data(&sweep, j, steps_per_cycle, 1.0);
                Py::new(
                    py,
                    AmplitudeLoop {
                        amplitude_factor: l.amplitude_factor,
                        amplitude_m: l.amplitude_m,
                        displacement_m: PyArray1::from_slice(py, &l.displacement_m).unbind(),
                        shear_stress_pa: PyArray1::from_slice(py, &l.shear_stress_pa).unbind(),
                        loop_area_j_per_m2: l.loop_area_j_per_m2,
                        dissipation_j_per_m2: l.dissipation_j_per_m2,
                        closure_error: l.closure_error,
                        fit_q: PyArray1::from_vec(py, data.q).unbind(),
                        fit_force: PyArray1::from_vec(py, data.force).unbind(),
                        steady: (data.steady.start, data.steady.end),
                    },
                )
            })
            .collect::<PyResult<Vec<_>>>()?;
        Ok(AmplitudeHistory {
            gross_slip_displacement_m: sweep.gross_slip_displacement_m,
            steps: sweep.steps,
            loops,
        })
    }

    /// Shift (m) along `direction` at which every contact point slips (gross slip).
    #[pyo3(signature = (direction=(1.0, 0.0)))]
    fn gross_slip_displacement(&self, py: Python<'_>, direction: (f64, f64)) -> PyResult<f64> {
        let inner = &self.inner;
        py.detach(|| inner.gross_slip_displacement([direction.0, direction.1]))
            .py()
    }

    /// Current shear tractions (qx, qy) (Pa), shape (nx, ny).
    fn traction<'py>(
        &self,
        py: Python<'py>,
    ) -> (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<f64>>) {
        let (qx, qy) = self.inner.traction();
        (
            PyArray2::from_owned_array(py, qx),
            PyArray2::from_owned_array(py, qy),
        )
    }

    /// Current stick mask (bool, shape (nx, ny)); False outside the contact.
    fn stick_mask<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<bool>> {
        PyArray2::from_owned_array(py, self.inner.stick_mask())
    }

    /// Back to the virgin state (no shear, no slip history).
    fn reset(&mut self) {
        self.inner.reset()
    }

    /// Total Coulomb limit μP (N).
    #[getter]
    fn friction_limit_n(&self) -> f64 {
        self.inner.friction_limit_n()
    }

    /// Set-up facts: assumption, μ, grid, boundary, operator, contact points, normal force (N),
    /// nominal area (m²), compliance norm (m/Pa), setup time (s).
    #[getter]
    fn metadata(&self) -> TangentialMetadata {
        TangentialMetadata::from(self.inner.metadata())
    }
}

/// The Python view of a library oscillation result: the step columns as numpy arrays, the
/// energy per cycle and the solver's set-up facts.
pub(crate) fn oscillation_result(
    py: Python<'_>,
    r: &tangential::OscillationResult,
) -> PyResult<OscillationResult> {
    let steps = PyDict::new(py);
    let col = |f: &dyn Fn(&tangential::TangentialStep) -> f64| {
        PyArray1::from_vec(py, r.steps.iter().map(f).collect::<Vec<f64>>())
    };
    steps.set_item("displacement_m", col(&|s| s.shift_m[0]))?;
    steps.set_item("displacement_y_m", col(&|s| s.shift_m[1]))?;
    steps.set_item("force_N", col(&|s| s.force_n[0]))?;
    steps.set_item("force_y_N", col(&|s| s.force_n[1]))?;
    steps.set_item("mean_shear_stress_Pa", col(&|s| s.mean_shear_pa[0]))?;
    steps.set_item("mean_shear_stress_y_Pa", col(&|s| s.mean_shear_pa[1]))?;
    steps.set_item("stick_fraction", col(&|s| s.stick_fraction))?;
    steps.set_item("accumulated_slip_m", col(&|s| s.accumulated_slip_m))?;
    steps.set_item("frictional_work_J", col(&|s| s.frictional_work_j))?;
    steps.set_item(
        "iterations",
        PyArray1::from_vec(
            py,
            r.steps
                .iter()
                .map(|s| s.iterations as u64)
                .collect::<Vec<u64>>(),
        ),
    )?;
    steps.set_item("residual", col(&|s| s.residual))?;
    steps.set_item("wall_time_s", col(&|s| s.wall_time_s))?;
    Ok(OscillationResult {
        steps: steps.unbind(),
        cycles: r
            .cycles
            .iter()
            .map(|c| {
                Py::new(
                    py,
                    CycleEnergy {
                        cycle: c.cycle,
                        dissipated_j: c.dissipated_j,
                        dissipated_j_per_m2: c.dissipated_j_per_m2,
                        frictional_work_j: c.frictional_work_j,
                    },
                )
            })
            .collect::<PyResult<Vec<_>>>()?,
        metadata: TangentialMetadata::from(&r.metadata),
        wall_time_s: r.wall_time_s,
    })
}
