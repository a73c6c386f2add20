//! Forced response of a structure with contact elements (multi-harmonic balance with AFT and
//! pseudo-arclength continuation, `asperity::dynamics`): a model read from the model file of
//! `asperity response` or built from numpy arrays, and a force-controlled frequency sweep
//! returning numpy columns. Units: SI (kg, N·s/m, N/m, N, m, Hz).

use crate::arrays::{borrow_f64, finite_slice, require_finite};
use crate::element::ValanisParams;
use crate::errors::{parameter, IntoPy};
use asperity::dynamics::aft::Harmonics;
use asperity::dynamics::continuation::ContinuationSettings;
use asperity::dynamics::hbm::{Excitation, FormulationChoice, HbmSystem};
use asperity::dynamics::model::{CoordinateKind, Structure};
use asperity::dynamics::model_file::{self, ModelFile};
use asperity::dynamics::{report, response};
use asperity::element::{
    CubicSpring, HystereticElement, Jenkins, JenkinsContact, MicroslipContact,
};
use nalgebra::{DMatrix, DVector};
use ndarray::{Array3, Ix1, Ix2};
use numpy::{PyArray1, PyArray2, PyArray3};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;
use std::sync::Arc;

/// A 2-D float64 array (finite) as a matrix.
fn matrix(obj: &Bound<'_, PyAny>, name: &str, what: &str) -> PyResult<DMatrix<f64>> {
    let a = borrow_f64::<Ix2>(obj, name, what)?;
    let (r, c) = a.as_array().dim();
    let s = a.as_slice().expect("checked C-contiguous");
    require_finite(obj.py(), name, s)?;
    Ok(DMatrix::from_row_slice(r, c, s))
}

/// A 1-D float64 array (finite) as a vector.
fn vector(obj: &Bound<'_, PyAny>, name: &str, what: &str) -> PyResult<DVector<f64>> {
    let a = borrow_f64::<Ix1>(obj, name, what)?;
    Ok(DVector::from_column_slice(finite_slice(
        obj.py(),
        &a,
        name,
    )?))
}

/// The linear structure with its elements, the excitation (force per unit level on the
/// coordinates) and the observed responses; from a model file (`ResponseModel.read`) or from
/// arrays (`ResponseModel.lumped`, `ResponseModel.modal`).
#[pyclass(module = "asperity")]
pub struct ResponseModel {
    structure: Structure,
    force: DVector<f64>,
    /// Quadrature part of the excitation (a model file's `phases_deg`).
    force_sin: Option<DVector<f64>>,
    /// Static force (a model file's `[static]`, N), the same at every level.
    static_force: Option<DVector<f64>>,
    harmonic: usize,
    responses: Vec<(String, DVector<f64>)>,
    /// The model file and its path, when read from one (sweep defaults and levels).
    file: Option<(PathBuf, ModelFile)>,
}

fn formulation(name: &str) -> PyResult<FormulationChoice> {
    match name {
        "auto" => Ok(FormulationChoice::Auto),
        "coordinates" => Ok(FormulationChoice::Coordinates),
        "receptance" => Ok(FormulationChoice::Receptance),
        other => Err(Python::attach(|py| {
            parameter(
                py,
                "formulation",
                format!("`{other}`: expected auto, coordinates or receptance"),
            )
        })),
    }
}

impl ResponseModel {
    /// A model from arrays: the excitation force (n,) and the response rows (label → (n,)).
    fn from_arrays(
        py: Python<'_>,
        structure: Structure,
        force: &Bound<'_, PyAny>,
        harmonic: usize,
        responses: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        let n = structure.n();
        let force = vector(
            force,
            "force",
            "N per unit level on each coordinate, shape (n,)",
        )?;
        if force.len() != n {
            return Err(parameter(
                py,
                "force",
                format!("{} entries for {n} coordinates", force.len()),
            ));
        }
        let responses = match responses {
            None => (0..n)
                .map(|r| {
                    let mut row = DVector::zeros(n);
                    row[r] = 1.0;
                    (structure.labels[r].clone(), row)
                })
                .collect(),
            Some(d) => {
                let mut out = Vec::new();
                for (k, v) in d.iter() {
                    let label: String = k.extract()?;
                    let row = vector(&v, "responses", "observation row, shape (n,)")?;
                    if row.len() != n {
                        return Err(parameter(
                            py,
                            "responses",
                            format!("`{label}`: {} entries for {n} coordinates", row.len()),
                        ));
                    }
                    out.push((label, row));
                }
                if out.is_empty() {
                    return Err(parameter(py, "responses", "no response given".into()));
                }
                out
            }
        };
        Ok(Self {
            structure,
            force,
            force_sin: None,
            static_force: None,
            harmonic,
            responses,
            file: None,
        })
    }

    fn attach(
        &mut self,
        label: String,
        element: Arc<dyn HystereticElement>,
        map: &Bound<'_, PyAny>,
    ) -> PyResult<()> {
        let map = matrix(
            map,
            "map",
            "element displacements per coordinate, shape (element dofs, n)",
        )?;
        self.structure.attach(label, element, map).py()
    }
}

/// A free decay of a `ResponseModel` (`asperity decay`): the first response at every time
/// step, and frequency and damping ratio per period (one estimate per half period).
#[pyclass(frozen, get_all, module = "asperity")]
pub struct DecayResult {
    /// Natural frequency of the linearised (stuck) mode it started in (Hz).
    pub linear_frequency_hz: f64,
    /// Time of every step (s).
    pub time_s: Py<PyArray1<f64>>,
    /// The first response at every step (m).
    pub response_m: Py<PyArray1<f64>>,
    /// Mid-time of each period (s).
    pub cycle_time_s: Py<PyArray1<f64>>,
    /// Amplitude of each period (m).
    pub cycle_amplitude_m: Py<PyArray1<f64>>,
    /// Frequency of each period (Hz).
    pub cycle_frequency_hz: Py<PyArray1<f64>>,
    /// Damping ratio of each period (logarithmic decrement).
    pub cycle_damping_ratio: Py<PyArray1<f64>>,
    /// Wall-clock time of the integration (s).
    pub wall_time_s: f64,
}

/// A nonlinear mode of a `ResponseModel` by the extended periodic motion concept (`asperity
/// modes`): the backbone per modal amplitude.
#[pyclass(frozen, get_all, module = "asperity")]
pub struct NonlinearModeResult {
    /// The linear mode continued (1-based, ascending frequency with the elements stuck).
    pub mode: usize,
    /// Its frequency with the elements stuck (Hz).
    pub linear_frequency_hz: f64,
    /// Its damping ratio with the elements stuck.
    pub linear_damping_ratio: f64,
    /// Modal amplitude of every converged point (m·kg^½).
    pub modal_amplitude_m_sqrt_kg: Py<PyArray1<f64>>,
    /// Frequency of every point (Hz).
    pub frequency_hz: Py<PyArray1<f64>>,
    /// Modal damping ratio `ξ/(2ω)` of every point.
    pub damping_ratio: Py<PyArray1<f64>>,
    /// Energy all elements dissipate per cycle at every point (J).
    pub element_energy_j: Py<PyArray1<f64>>,
    /// Energy per cycle of every element, shape (points, elements) (J).
    pub energy_per_element_j: Py<PyArray2<f64>>,
    /// Harmonic coefficients of every coordinate, shape (points, n, coefficients) (m).
    pub coordinate_harmonics: Py<PyArray3<f64>>,
    /// Harmonic orders of the coefficients.
    pub harmonic_orders: Vec<usize>,
    /// Why the continuation stopped before the last amplitude (`None`: complete).
    pub stopped: Option<String>,
    /// Wall-clock time of the continuation (s).
    pub wall_time_s: f64,
}

#[pymethods]
impl NonlinearModeResult {
    fn __repr__(&self) -> String {
        format!(
            "NonlinearModeResult(mode {}, linear {:.6} Hz{})",
            self.mode,
            self.linear_frequency_hz,
            self.stopped
                .as_ref()
                .map_or(String::new(), |w| format!(", stopped {w}"))
        )
    }
}

/// A force-controlled frequency sweep of a `ResponseModel` (the results of one level of
/// `asperity response`).
#[pyclass(frozen, get_all, module = "asperity")]
pub struct SweepResult {
    /// The columns of `response_level_<i>.csv`: frequency_Hz, <dof>_h<k>_amplitude_m (m),
    /// <dof>_h<k>_phase_rad, dissipated_energy_J (J per cycle), stick/slip/separation
    /// fractions, newton_iterations, relative_residual.
    pub columns: Py<PyDict>,
    /// Harmonic coefficients of every coordinate, shape (points, n, coefficients) (m).
    pub coordinate_harmonics: Py<PyArray3<f64>>,
    /// Harmonic orders of the coefficients.
    pub harmonic_orders: Vec<usize>,
    /// Index of the largest first-harmonic amplitude of the first response.
    pub peak: usize,
    /// Columns per element at the peak: element, law, dissipated_energy_J, stick_fraction,
    /// slip_fraction, separation_fraction.
    pub peak_elements: Py<PyDict>,
    /// Excitation level (N).
    pub level_n: f64,
    /// `"coordinates"` or `"receptance"`.
    pub formulation: String,
    /// Unknowns of the harmonic-balance system.
    pub unknowns: usize,
    /// Continuation steps rejected.
    pub rejected_steps: usize,
    /// Turning points passed.
    pub turning_points: usize,
    /// Jacobians evaluated.
    pub jacobians: usize,
    /// Wall-clock time of the sweep (s).
    pub wall_time_s: f64,
}

#[pymethods]
impl SweepResult {
    fn __repr__(&self) -> String {
        format!(
            "SweepResult(level {} N, {} formulation, peak at point {})",
            self.level_n, self.formulation, self.peak
        )
    }
}

impl ResponseModel {
    /// `method` does not solve a static preload: refused for a model file with `[static]`.
    fn refuse_static(&self, py: Python<'_>, method: &str) -> PyResult<()> {
        if self.static_force.is_some() {
            return Err(parameter(
                py,
                "static",
                format!(
                    "{method} does not solve the model file's [static] preload (sweep balances \
                     it)"
                ),
            ));
        }
        Ok(())
    }

    /// The harmonic basis: the arguments, else the model file's `[sweep]`, else harmonics 5,
    /// all orders, the default sampling.
    fn harmonics(
        &self,
        harmonics: Option<usize>,
        odd_only: Option<bool>,
        time_samples: Option<usize>,
    ) -> PyResult<Harmonics> {
        let s = self.file.as_ref().map(|(_, f)| &f.sweep);
        Harmonics::new(
            harmonics.or(s.map(|s| s.harmonics)).unwrap_or(5),
            odd_only.or(s.map(|s| s.odd_only)).unwrap_or(false),
            time_samples.or(s.and_then(|s| s.time_samples)),
        )
        .py()
    }
}

#[pymethods]
impl ResponseModel {
    /// Read a model file (TOML) exactly as `asperity response` does.
    #[staticmethod]
    fn read(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let m = py.detach(|| model_file::load(&path)).py()?;
        Ok(Self {
            structure: m.structure,
            force: m.force,
            force_sin: m.force_sin,
            static_force: m.static_force,
            harmonic: m.file.excitation.harmonic,
            responses: m.responses,
            file: Some((m.path, m.file)),
        })
    }

    /// Lumped model: labels of the n coordinates, symmetric positive definite `mass` (kg) and
    /// `stiffness` (N/m), symmetric positive semi-definite `damping` (N·s/m), each (n, n);
    /// `force` (n,) the excitation per unit level (N); `responses` maps a label to an
    /// observation row (n,) (default: every coordinate).
    #[staticmethod]
    #[pyo3(signature = (labels, mass, damping, stiffness, force, *, harmonic=1, responses=None))]
    #[allow(clippy::too_many_arguments)]
    fn lumped(
        py: Python<'_>,
        labels: Vec<String>,
        mass: &Bound<'_, PyAny>,
        damping: &Bound<'_, PyAny>,
        stiffness: &Bound<'_, PyAny>,
        force: &Bound<'_, PyAny>,
        harmonic: usize,
        responses: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        let structure = Structure::lumped(
            labels,
            matrix(mass, "mass", "kg, shape (n, n)")?,
            matrix(damping, "damping", "N·s/m, shape (n, n)")?,
            matrix(stiffness, "stiffness", "N/m, shape (n, n)")?,
        )
        .py()?;
        Self::from_arrays(py, structure, force, harmonic, responses)
    }

    /// Reduced modal model: natural frequencies (Hz) and modal damping ratios of mass-normalised
    /// modes; `force` (n_modes,) the modal force per unit level `Φᵀf`.
    #[staticmethod]
    #[pyo3(signature = (frequencies_hz, damping_ratios, force, *, harmonic=1, responses=None))]
    fn modal(
        py: Python<'_>,
        frequencies_hz: Vec<f64>,
        damping_ratios: Vec<f64>,
        force: &Bound<'_, PyAny>,
        harmonic: usize,
        responses: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        let structure = Structure::modal(&frequencies_hz, &damping_ratios).py()?;
        Self::from_arrays(py, structure, force, harmonic, responses)
    }

    /// Attach a 1-D Jenkins element (stiffness `kt_n_per_m`, slip force `slip_force_n`);
    /// `map` (1, n): its displacement per coordinate.
    fn attach_jenkins(
        &mut self,
        label: String,
        kt_n_per_m: f64,
        slip_force_n: f64,
        map: &Bound<'_, PyAny>,
    ) -> PyResult<()> {
        let e = Jenkins::new(kt_n_per_m, slip_force_n).py()?;
        self.attach(label, Arc::new(e), map)
    }

    /// Attach a cubic spring `f = k3·u³` (k3 in N/m³); `map` (1, n).
    fn attach_cubic_spring(
        &mut self,
        label: String,
        k3_n_per_m3: f64,
        map: &Bound<'_, PyAny>,
    ) -> PyResult<()> {
        if !k3_n_per_m3.is_finite() {
            return Err(parameter(
                map.py(),
                "k3_n_per_m3",
                format!("{k3_n_per_m3} is not finite"),
            ));
        }
        self.attach(label, Arc::new(CubicSpring { k3: k3_n_per_m3 }), map)
    }

    /// Attach the 3-D Valanis microslip contact of the element table (`law = "valanis"`):
    /// `params` per element (E0, Et in N/m), normal stiffness `kn_n_per_m`, preload `n0_n` (N);
    /// `map` (3, n): local displacements (t1, t2, n) per coordinate.
    fn attach_valanis_contact(
        &mut self,
        label: String,
        params: &ValanisParams,
        kn_n_per_m: f64,
        n0_n: f64,
        map: &Bound<'_, PyAny>,
    ) -> PyResult<()> {
        let e = MicroslipContact::new(params.inner, kn_n_per_m, n0_n).py()?;
        self.attach(label, Arc::new(e), map)
    }

    /// Attach the 3-D Jenkins contact (`law = "jenkins"`): tangential stiffness `kt_n_per_m`,
    /// friction coefficient `mu`, normal stiffness `kn_n_per_m`, preload `n0_n`; `map` (3, n).
    #[allow(clippy::too_many_arguments)]
    fn attach_jenkins_contact(
        &mut self,
        label: String,
        kt_n_per_m: f64,
        mu: f64,
        kn_n_per_m: f64,
        n0_n: f64,
        map: &Bound<'_, PyAny>,
    ) -> PyResult<()> {
        let e = JenkinsContact::new(kt_n_per_m, mu, kn_n_per_m, n0_n).py()?;
        self.attach(label, Arc::new(e), map)
    }

    /// Coordinate labels (`node.x` or `mode r`).
    #[getter]
    fn labels(&self) -> Vec<String> {
        self.structure.labels.clone()
    }

    /// `"physical"` or `"modal"`.
    #[getter]
    fn coordinates(&self) -> &'static str {
        match self.structure.kind {
            CoordinateKind::Physical => "physical",
            CoordinateKind::Modal => "modal",
        }
    }

    /// Mass (kg), damping (N·s/m) and stiffness (N/m) matrices, (n, n) copies.
    #[getter]
    fn matrices<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for (name, m) in [
            ("mass", &self.structure.mass),
            ("damping", &self.structure.damping),
            ("stiffness", &self.structure.stiffness),
        ] {
            let rows: Vec<Vec<f64>> = m.row_iter().map(|r| r.iter().copied().collect()).collect();
            d.set_item(name, PyArray2::from_vec2(py, &rows)?)?;
        }
        Ok(d)
    }

    /// Excitation force per unit level on the coordinates (N), (n,).
    #[getter]
    fn force<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.force.as_slice())
    }

    /// Labels of the observed responses (the CSV column prefixes).
    #[getter]
    fn response_labels(&self) -> Vec<String> {
        self.responses.iter().map(|r| r.0.clone()).collect()
    }

    /// `(label, law, dofs)` of every attached element.
    #[getter]
    fn elements(&self) -> Vec<(String, &'static str, usize)> {
        self.structure
            .elements
            .iter()
            .map(|e| (e.label.clone(), e.element.name(), e.element.dofs()))
            .collect()
    }

    /// Excitation levels (N) of the model file (None for a model built from arrays).
    #[getter]
    fn levels_n(&self) -> Option<Vec<f64>> {
        self.file
            .as_ref()
            .map(|(_, f)| f.excitation.levels_n.clone())
    }

    /// Force-controlled frequency sweep at excitation `level_n` (N) from `frequency_start_hz`
    /// to `frequency_end_hz` (Hz; downwards when end < start) by pseudo-arclength
    /// continuation, `harmonics` retained (odd only with `odd_only`), `time_samples` per period
    /// for AFT, at least `points` points over the span. Unset values come from the model
    /// file's `[sweep]` (required for a model built from arrays, except the defaults
    /// harmonics = 5, points = 200, formulation = "auto").
    ///
    /// Returns a dict: the columns of `response_level_<i>.csv` as float64 arrays
    /// (`frequency_Hz`, `<dof>_h<k>_amplitude_m`, `<dof>_h<k>_phase_rad`, `<dof>_h0_mean_m`,
    /// `dissipated_energy_J`, `stick_fraction`, `slip_fraction`, `separation_fraction`,
    /// `newton_iterations`, `relative_residual`, `aft_periodicity_error`) under `"columns"`;
    /// `"coordinate_harmonics"` (points, n, coefficients, m: `x_r(t) = Σ a·cos(kωt) +
    /// b·sin(kωt)` with, for each order `k` of `"harmonic_orders"` in turn, one coefficient for
    /// k = 0 (the mean) or a, b); the
    /// `"harmonic_orders"`; `"peak"` (index of the largest first-harmonic amplitude of the
    /// first response); `"peak_elements"` (label, law, dissipated_energy_J,
    /// stick/slip/separation fractions at the peak); `"level_N"`, `"formulation"`,
    /// `"unknowns"`, `"rejected_steps"`, `"turning_points"`, `"jacobians"`, `"wall_time_s"`.
    #[pyo3(signature = (level_n, frequency_start_hz=None, frequency_end_hz=None, *, harmonics=None, odd_only=None, time_samples=None, points=None, formulation=None))]
    #[allow(clippy::too_many_arguments)]
    fn sweep<'py>(
        &self,
        py: Python<'py>,
        level_n: f64,
        frequency_start_hz: Option<f64>,
        frequency_end_hz: Option<f64>,
        harmonics: Option<usize>,
        odd_only: Option<bool>,
        time_samples: Option<usize>,
        points: Option<usize>,
        formulation: Option<String>,
    ) -> PyResult<SweepResult> {
        let s = self.file.as_ref().map(|(_, f)| &f.sweep);
        let need = |v: Option<f64>, file: Option<f64>, name: &str| {
            v.or(file).ok_or_else(|| {
                parameter(
                    py,
                    name,
                    "required for a model built from arrays (no model file [sweep])".into(),
                )
            })
        };
        let start = need(
            frequency_start_hz,
            s.map(|s| s.frequency_start_hz),
            "frequency_start_hz",
        )?;
        let end = need(
            frequency_end_hz,
            s.map(|s| s.frequency_end_hz),
            "frequency_end_hz",
        )?;
        let h = self.harmonics(harmonics, odd_only, time_samples)?;
        let choice = match &formulation {
            Some(f) => self::formulation(f)?,
            None => s.map_or(FormulationChoice::Auto, |s| s.formulation),
        };
        // A static force is balanced in the coordinates formulation (as `asperity response`).
        let choice = match (&self.static_force, choice) {
            (Some(_), FormulationChoice::Auto) => FormulationChoice::Coordinates,
            (_, c) => c,
        };
        let mut settings = ContinuationSettings::new(start, end);
        settings.points = points.or(s.map(|s| s.points)).unwrap_or(200);
        let (system, result) = py
            .detach(|| {
                let mut system = HbmSystem::new(
                    &self.structure,
                    h,
                    Excitation {
                        force: self.force.clone(),
                        harmonic: self.harmonic,
                        force_sin: self.force_sin.clone(),
                    },
                    choice,
                )?;
                if let Some(f0) = &self.static_force {
                    system = system.with_static_force(f0)?;
                }
                let r = response::sweep_level(
                    &system,
                    level_n,
                    &settings,
                    &self.responses[0].1,
                    &mut |_| {},
                )?;
                r.branch.check_complete()?;
                Ok::<_, asperity::Error>((system, r))
            })
            .py()?;
        let cols = PyDict::new(py);
        for (name, values) in report::level_columns(&system, &self.responses, &result) {
            cols.set_item(name, PyArray1::from_vec(py, values))?;
        }
        let (n, len) = (self.structure.n(), system.harmonics.len());
        let mut x = Array3::<f64>::zeros((result.branch.points.len(), n, len));
        for (i, p) in result.branch.points.iter().enumerate() {
            let c = system.coordinates(p);
            for r in 0..n {
                for j in 0..len {
                    x[(i, r, j)] = c[r * len + j];
                }
            }
        }
        let pe = PyDict::new(py);
        let el = &self.structure.elements;
        let c = &result.peak_elements;
        pe.set_item(
            "element",
            el.iter().map(|e| e.label.clone()).collect::<Vec<_>>(),
        )?;
        pe.set_item(
            "law",
            el.iter().map(|e| e.element.name()).collect::<Vec<_>>(),
        )?;
        for (name, f) in [
            (
                "dissipated_energy_J",
                (|c: &asperity::dynamics::aft::ElementCycle| c.dissipated_energy_j)
                    as fn(&asperity::dynamics::aft::ElementCycle) -> f64,
            ),
            ("stick_fraction", |c| c.stick_fraction),
            ("slip_fraction", |c| c.slip_fraction),
            ("separation_fraction", |c| c.separation_fraction),
        ] {
            pe.set_item(name, PyArray1::from_vec(py, c.iter().map(f).collect()))?;
        }
        Ok(SweepResult {
            columns: cols.unbind(),
            coordinate_harmonics: PyArray3::from_owned_array(py, x).unbind(),
            harmonic_orders: system.harmonics.orders().to_vec(),
            peak: result.peak,
            peak_elements: pe.unbind(),
            level_n,
            formulation: match system.formulation() {
                asperity::dynamics::hbm::Formulation::Coordinates => "coordinates",
                asperity::dynamics::hbm::Formulation::Receptance => "receptance",
            }
            .to_string(),
            unknowns: system.unknowns(),
            rejected_steps: result.branch.rejected_steps,
            turning_points: result.branch.turning_points,
            jacobians: result.branch.jacobians,
            wall_time_s: result.branch.wall_time_s,
        })
    }

    /// Free decay (ring-down) by Newmark time integration with the elements, from rest in the
    /// linearised (stuck) mode `mode`, the first response starting at `amplitude_m` (m);
    /// frequency and damping ratio per period by peak picking (`asperity decay`).
    #[pyo3(signature = (amplitude_m, *, mode=1, periods=100, steps_per_period=256))]
    fn free_decay(
        &self,
        py: Python<'_>,
        amplitude_m: f64,
        mode: usize,
        periods: usize,
        steps_per_period: usize,
    ) -> PyResult<DecayResult> {
        self.refuse_static(py, "free_decay")?;
        let settings = asperity::dynamics::transient::DecaySettings {
            mode,
            amplitude_m,
            periods,
            steps_per_period,
        };
        let row = &self
            .responses
            .first()
            .ok_or_else(|| parameter(py, "responses", "the model observes no response".into()))?
            .1;
        let structure = &self.structure;
        let r = py
            .detach(|| {
                asperity::dynamics::transient::free_decay(structure, row, &settings, &mut |_| {})
            })
            .py()?;
        let col = |f: &dyn Fn(&asperity::dynamics::transient::DecayCycle) -> f64| {
            PyArray1::from_vec(py, r.cycles.iter().map(f).collect()).unbind()
        };
        Ok(DecayResult {
            linear_frequency_hz: r.linear_frequency_hz,
            time_s: PyArray1::from_slice(py, &r.time_s).unbind(),
            response_m: PyArray1::from_slice(py, &r.response_m).unbind(),
            cycle_time_s: col(&|c| c.time_s),
            cycle_amplitude_m: col(&|c| c.amplitude_m),
            cycle_frequency_hz: col(&|c| c.frequency_hz),
            cycle_damping_ratio: col(&|c| c.damping_ratio),
            wall_time_s: r.wall_time_s,
        })
    }

    /// The nonlinear mode `mode` by the extended periodic motion concept (`asperity modes`):
    /// `points` modal amplitudes log-spaced from `amplitude_min_m_sqrt_kg` to
    /// `amplitude_max_m_sqrt_kg` (m·kg^½), continued from the linear mode with the elements
    /// stuck. Harmonics as in `sweep`. A continuation that stops early returns the points before
    /// it and says why in `stopped`.
    #[pyo3(signature = (amplitude_min_m_sqrt_kg, amplitude_max_m_sqrt_kg, *, mode=1, points=60, harmonics=None, odd_only=None, time_samples=None))]
    #[allow(clippy::too_many_arguments)]
    fn nonlinear_mode(
        &self,
        py: Python<'_>,
        amplitude_min_m_sqrt_kg: f64,
        amplitude_max_m_sqrt_kg: f64,
        mode: usize,
        points: usize,
        harmonics: Option<usize>,
        odd_only: Option<bool>,
        time_samples: Option<usize>,
    ) -> PyResult<NonlinearModeResult> {
        use asperity::dynamics::nonlinear_modes::{self, ModeSettings};
        self.refuse_static(py, "nonlinear_mode")?;
        let h = self.harmonics(harmonics, odd_only, time_samples)?;
        let amplitudes =
            nonlinear_modes::log_spaced(amplitude_min_m_sqrt_kg, amplitude_max_m_sqrt_kg, points)
                .map_err(|e| match e {
                    asperity::Error::InvalidParameter { name, message } => asperity::Error::param(
                        match name.as_str() {
                            "amplitude_min" => "amplitude_min_m_sqrt_kg",
                            "amplitude_max" => "amplitude_max_m_sqrt_kg",
                            _ => "points",
                        },
                        message,
                    ),
                    other => other,
                })
                .py()?;
        let structure = &self.structure;
        let (system, result) = py
            .detach(|| {
                let system = HbmSystem::new(
                    structure,
                    h,
                    Excitation {
                        force: DVector::zeros(structure.n()),
                        harmonic: 1,
                        force_sin: None,
                    },
                    FormulationChoice::Coordinates,
                )?;
                let r = nonlinear_modes::nonlinear_mode(
                    &system,
                    ModeSettings::new(mode, amplitudes),
                    &mut |_| {},
                )?;
                Ok::<_, asperity::Error>((system, r))
            })
            .py()?;
        let pts = &result.points;
        let col = |f: &dyn Fn(&nonlinear_modes::ModePoint) -> f64| {
            PyArray1::from_vec(py, pts.iter().map(f).collect()).unbind()
        };
        let ne = structure.elements.len();
        let mut energy = ndarray::Array2::<f64>::zeros((pts.len(), ne));
        let (n, len) = (structure.n(), system.harmonics.len());
        let mut x = Array3::<f64>::zeros((pts.len(), n, len));
        for (i, p) in pts.iter().enumerate() {
            for (j, c) in p.elements.iter().enumerate() {
                energy[(i, j)] = c.dissipated_energy_j;
            }
            for r in 0..n {
                for j in 0..len {
                    x[(i, r, j)] = p.z[r * len + j];
                }
            }
        }
        Ok(NonlinearModeResult {
            mode,
            linear_frequency_hz: result.linear.frequency_hz(),
            linear_damping_ratio: result.linear.damping_ratio(),
            modal_amplitude_m_sqrt_kg: col(&|p| p.amplitude),
            frequency_hz: col(&|p| p.frequency_hz()),
            damping_ratio: col(&|p| p.damping_ratio()),
            element_energy_j: col(&|p| p.element_energy_j()),
            energy_per_element_j: PyArray2::from_owned_array(py, energy).unbind(),
            coordinate_harmonics: PyArray3::from_owned_array(py, x).unbind(),
            harmonic_orders: system.harmonics.orders().to_vec(),
            stopped: result.stopped,
            wall_time_s: result.wall_time_s,
        })
    }

    fn __repr__(&self) -> String {
        format!(
            "ResponseModel({} {} coordinates, {} elements, responses {:?}{})",
            self.structure.n(),
            self.coordinates(),
            self.structure.elements.len(),
            self.response_labels(),
            self.file
                .as_ref()
                .map_or(String::new(), |(p, _)| format!(", file {}", p.display()))
        )
    }
}
