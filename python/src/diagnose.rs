//! Measured hysteresis record → Valanis baseline → missing effect (selected on held-out cycles)
//! → errors before and after: `asperity diagnose` from numpy arrays. Time in s, displacement in
//! m, forces in N, stiffnesses in N/m.

use crate::arrays::{borrow_f64, finite_slice};
use crate::element::ValanisParams;
use crate::errors::IntoPy;
use asperity::diagnose::report::{InputInfo, Report};
use asperity::diagnose::Record as RecordData;
use asperity::diagnose::{Baseline, BaselineSource, Columns, Options};
use ndarray::Ix1;
use numpy::PyArray1;
use pyo3::prelude::*;
use std::path::PathBuf;

/// A measured hysteresis record: sample times (s), tangential displacement (m) and force (N),
/// and the normal force (N) where the file has a column for it.
#[pyclass(frozen, get_all, module = "asperity")]
pub struct Record {
    /// Sample times (s).
    pub time_s: Py<PyArray1<f64>>,
    /// Tangential displacement (m).
    pub displacement_m: Py<PyArray1<f64>>,
    /// Tangential force (N).
    pub force_n: Py<PyArray1<f64>>,
    /// Normal force (N), or `None` without a normal-force column.
    pub normal_force_n: Option<Py<PyArray1<f64>>>,
    /// How columns were derived from what was measured (a displacement integrated from an
    /// acceleration, a force from a mass's inertia), one line each; empty when read as they are.
    pub derived: Vec<String>,
}

#[pymethods]
impl Record {
    fn __repr__(&self, py: Python<'_>) -> String {
        format!(
            "Record({} samples{})",
            numpy::PyUntypedArrayMethods::len(self.time_s.bind(py)),
            if self.normal_force_n.is_some() {
                ", with normal force"
            } else {
                ""
            }
        )
    }
}

/// Read the chosen columns of a record CSV into a `Record` (float64 arrays).
#[pyfunction]
#[pyo3(signature = (path, *, time_column="time_s", displacement_column="displacement_m", force_column="friction_force_N", normal_force_column=None, relative_acceleration_column=None, inertia_acceleration_column=None, mass_kg=None))]
#[allow(clippy::too_many_arguments)]
pub fn read_record(
    py: Python<'_>,
    path: PathBuf,
    time_column: &str,
    displacement_column: &str,
    force_column: &str,
    normal_force_column: Option<String>,
    relative_acceleration_column: Option<String>,
    inertia_acceleration_column: Option<String>,
    mass_kg: Option<f64>,
) -> PyResult<Record> {
    let columns = Columns {
        time: time_column.into(),
        displacement: displacement_column.into(),
        force: force_column.into(),
        normal_force: normal_force_column,
        ..Columns::default()
    }
    .with_accelerations(
        relative_acceleration_column,
        inertia_acceleration_column,
        mass_kg,
    )
    .py()?;
    let r = RecordData::read_csv(&path, &columns).py()?;
    Ok(Record {
        time_s: PyArray1::from_vec(py, r.time_s).unbind(),
        displacement_m: PyArray1::from_vec(py, r.displacement_m).unbind(),
        force_n: PyArray1::from_vec(py, r.force_n).unbind(),
        normal_force_n: r
            .normal_force_n
            .map(|nf| PyArray1::from_vec(py, nf).unbind()),
        derived: r.derived,
    })
}

fn column(obj: &Bound<'_, PyAny>, name: &str, what: &str) -> PyResult<Vec<f64>> {
    let a = borrow_f64::<Ix1>(obj, name, what)?;
    Ok(finite_slice(obj.py(), &a, name)?.to_vec())
}

/// Error measures of a model's force against the measured record, over all complete cycles.
#[pyclass(frozen, get_all, skip_from_py_object, module = "asperity")]
#[derive(Clone)]
pub struct DiagnoseErrors {
    /// RMS force residual / force amplitude.
    pub nrms: f64,
    /// Mean over cycles of the absolute error of the maximum and minimum force / force
    /// amplitude.
    pub peak_force_error: f64,
    /// Mean over cycles of |E_model − E_measured| / E_measured (dissipated energy per cycle).
    pub energy_error: f64,
    /// Normalised RMS force error on the held-out cycles only.
    pub held_out_nrms: f64,
    /// RMS force residual on the held-out cycles / noise floor.
    pub held_out_rms_over_noise: f64,
}

/// What `diagnose()` found (the report of `asperity diagnose`).
#[pyclass(frozen, get_all, module = "asperity")]
pub struct DiagnoseReport {
    /// The verdict in words: effect(s) found, model adequate, model inadequate, or undecided.
    pub verdict: String,
    /// The conclusion as the report states it.
    pub conclusion: String,
    /// Ids of the effects added to the baseline, in the order accepted.
    pub effects_added: Vec<String>,
    /// Errors of the baseline.
    pub errors_before: DiagnoseErrors,
    /// Errors of the final model (baseline plus the effects added).
    pub errors_after: DiagnoseErrors,
    /// Noise floor of the force, standard deviation per sample (N).
    pub noise_sigma_n: f64,
    /// Samples analysed (after block averaging).
    pub samples_analysed: usize,
    /// Complete cycles of the record.
    pub complete_cycles: usize,
    /// Cycles the models were fitted on (0-based).
    pub training_cycles: Vec<usize>,
    /// Cycles held out for the effect search (0-based).
    pub held_out_cycles: Vec<usize>,
    /// The report as `diagnose.txt` holds it.
    pub text: String,
    /// Sample times analysed (s).
    pub time_s: Py<PyArray1<f64>>,
    /// Displacement analysed (m).
    pub displacement_m: Py<PyArray1<f64>>,
    /// Measured force analysed (N).
    pub force_n: Py<PyArray1<f64>>,
    /// Force of the baseline model (N).
    pub baseline_force_n: Py<PyArray1<f64>>,
    /// Force of the final model (N).
    pub final_force_n: Py<PyArray1<f64>>,
    /// The whole report as the CLI's `diagnose.json` holds it (JSON text).
    pub json: String,
}

#[pymethods]
impl DiagnoseReport {
    fn __repr__(&self) -> String {
        format!(
            "DiagnoseReport({}, effects {:?})",
            self.verdict, self.effects_added
        )
    }
}

/// Diagnose a record: fit (or take) a Valanis baseline, estimate the noise floor from the
/// record's cycle-to-cycle repeatability, search the candidate effects by their held-out
/// evidence against that floor, give one of three verdicts (effect(s) found, model adequate,
/// model inadequate with where the residual sits) and the errors before and after. The baseline is fitted to
/// the training cycles, or given as `baseline` (a `ValanisParams` in N/m) with the mean normal
/// load `normal_n` (N). Returns a `DiagnoseReport` (its `json` is the CLI's
/// `diagnose.json`), with the analysed samples and both models' forces as arrays. Runs without
/// the GIL.
#[pyfunction]
#[pyo3(signature = (time_s, displacement_m, force_n, normal_force_n=None, *, baseline=None, normal_n=None, max_effects=2, source="numpy arrays"))]
#[allow(clippy::too_many_arguments)]
pub fn diagnose<'py>(
    py: Python<'py>,
    time_s: &Bound<'py, PyAny>,
    displacement_m: &Bound<'py, PyAny>,
    force_n: &Bound<'py, PyAny>,
    normal_force_n: Option<&Bound<'py, PyAny>>,
    baseline: Option<&ValanisParams>,
    normal_n: Option<f64>,
    max_effects: usize,
    source: &str,
) -> PyResult<DiagnoseReport> {
    let record = RecordData::new(
        column(time_s, "time_s", "sample times (s)")?,
        column(
            displacement_m,
            "displacement_m",
            "tangential displacement (m)",
        )?,
        column(force_n, "force_n", "tangential force (N)")?,
        normal_force_n
            .map(|n| column(n, "normal_force_n", "normal force (N)"))
            .transpose()?,
    )
    .py()?;
    let (baseline, baseline_source) = match (baseline, normal_n) {
        (Some(p), Some(n)) => (
            BaselineSource::Given(Baseline {
                valanis: p.inner,
                normal_n: asperity::core::error::require_positive("normal_n", n).py()?,
            }),
            "given".to_string(),
        ),
        (None, None) => (
            BaselineSource::Fitted,
            "fitted to the training cycles".to_string(),
        ),
        _ => {
            return Err(asperity::Error::param(
                "baseline / normal_n",
                "give both (a given baseline) or neither (a fitted one)",
            ))
            .py()
        }
    };
    let options = Options {
        baseline,
        max_effects,
        ..Options::default()
    };
    let d = py
        .detach(|| asperity::diagnose::diagnose(&record, &options))
        .py()?;
    let mut columns = vec!["time_s".into(), "displacement_m".into(), "force_N".into()];
    if record.normal_force_n.is_some() {
        columns.push("normal_force_N".into());
    }
    let report = Report::new(
        &d,
        InputInfo {
            file: source.to_string(),
            columns,
            derived: record.derived.clone(),
            baseline_source,
        },
    );
    let json = serde_json::to_string_pretty(&report)
        .map_err(|e| asperity::Error::Data(format!("diagnose report: cannot serialise: {e}")));
    let p = &d.prepared.record;
    let errors = |e: &asperity::diagnose::select::Errors| DiagnoseErrors {
        nrms: e.nrms,
        peak_force_error: e.peak_force_error,
        energy_error: e.energy_error,
        held_out_nrms: e.held_out_nrms,
        held_out_rms_over_noise: e.held_out_rms_over_noise,
    };
    Ok(DiagnoseReport {
        verdict: report.verdict.name().to_string(),
        conclusion: report.conclusion.clone(),
        effects_added: report
            .effects_added
            .iter()
            .map(|e| e.id().to_string())
            .collect(),
        errors_before: errors(&report.errors_before),
        errors_after: errors(&report.errors_after),
        noise_sigma_n: report.noise.sigma_n,
        samples_analysed: report.samples_analysed,
        complete_cycles: report.complete_cycles,
        training_cycles: report.training_cycles.clone(),
        held_out_cycles: report.held_out_cycles.clone(),
        text: report.text(),
        json: json.py()?,
        time_s: PyArray1::from_slice(py, &p.time_s).unbind(),
        displacement_m: PyArray1::from_slice(py, &p.displacement_m).unbind(),
        force_n: PyArray1::from_slice(py, &p.force_n).unbind(),
        baseline_force_n: PyArray1::from_vec(py, d.baseline_force).unbind(),
        final_force_n: PyArray1::from_vec(py, d.final_force).unbind(),
    })
}
