//! Measured frequency responses → identified nonlinear mode (or updated reduced model) → errors
//! on the levels not used: `identify()` and `predict()` run the library's commands
//! (`asperity::identify::command`, the functions the CLI calls) and return typed reports.
//! Frequencies in Hz, forces in N, displacements in m; errors relative to each level's measured
//! peak.

use crate::errors::IntoPy;
use asperity::identify::command::{
    prepare_identify, prepare_predict, IdentifyConfig, PredictConfig,
};
use asperity::identify::report::LevelErrors;
use asperity::identify::uncertainty::ParameterInterval;
use pyo3::prelude::*;
use std::path::PathBuf;

/// A name given as a string (`param` in errors) read as one of `choices` of a library enum.
fn named<T: serde::de::DeserializeOwned>(param: &str, value: &str, choices: &str) -> PyResult<T> {
    serde_json::from_value(serde_json::Value::String(value.to_string()))
        .map_err(|_| asperity::Error::param(param, format!("{value:?}: one of {choices}")))
        .py()
}

/// A parameter of an identified model: its value and 95 % interval (unit `unit`; SI, "-" for a
/// ratio).
#[pyclass(frozen, get_all, skip_from_py_object, module = "asperity")]
#[derive(Clone)]
pub struct ParameterEstimate {
    /// Parameter name, as in the report's table.
    pub name: String,
    /// Unit of the value and the interval.
    pub unit: String,
    /// The identified value.
    pub value: f64,
    /// 2.5 % quantile over the posterior ensemble; `None` without prediction bands or for a
    /// parameter held on its bound.
    pub lo_95: Option<f64>,
    /// 97.5 % quantile; `None` as for `lo_95`.
    pub hi_95: Option<f64>,
    /// The parameter is held on a bound of its box.
    pub at_bound: bool,
}

impl From<&ParameterInterval> for ParameterEstimate {
    fn from(p: &ParameterInterval) -> Self {
        Self {
            name: p.name.clone(),
            unit: p.unit.clone(),
            value: p.value,
            lo_95: p.lo_95,
            hi_95: p.hi_95,
            at_bound: p.at_bound,
        }
    }
}

#[pymethods]
impl ParameterEstimate {
    fn __repr__(&self) -> String {
        let interval = match (self.lo_95, self.hi_95) {
            (Some(lo), Some(hi)) => format!(", 95 % [{lo:.6e}, {hi:.6e}]"),
            _ => String::new(),
        };
        format!(
            "ParameterEstimate({} = {:.6e} {}{interval})",
            self.name, self.value, self.unit
        )
    }
}

/// A model's errors on one measured level or file.
#[pyclass(frozen, get_all, skip_from_py_object, module = "asperity")]
#[derive(Clone)]
pub struct LevelError {
    /// File name of the sweep.
    pub file: String,
    /// `"fit"` (used in the fit) or `"predicted"` (held out).
    pub role: String,
    /// Mean measured drive force amplitude (N).
    pub mean_force_n: f64,
    /// Frequency of the measured amplitude peak (Hz).
    pub resonance_measured_hz: f64,
    /// Frequency of the modelled amplitude peak (Hz; NaN when every row failed).
    pub resonance_model_hz: f64,
    /// Model minus measured resonance frequency (Hz); `None` where the measured peak lies on
    /// the band's edge (no resonance in the band).
    pub resonance_error_hz: Option<f64>,
    /// Model minus measured phase resonance (Hz; NaN where either does not pass quadrature).
    pub phase_resonance_error_hz: f64,
    /// Peak measured response per unit force (the level's quantity per N).
    pub peak_measured: f64,
    /// Peak modelled response per unit force (same unit).
    pub peak_model: f64,
    /// Relative peak error `peak_model/peak_measured − 1`.
    pub peak_error: f64,
    /// RMS of the complex residual over all rows (fraction of the level's peak response).
    pub rms_complex: f64,
    /// Rows where the harmonic balance failed.
    pub failed_rows: usize,
}

impl From<&LevelErrors> for LevelError {
    fn from(e: &LevelErrors) -> Self {
        Self {
            file: e.file.clone(),
            role: e.role.clone(),
            mean_force_n: e.mean_force_n,
            resonance_measured_hz: e.resonance_measured_hz,
            resonance_model_hz: e.resonance_model_hz,
            resonance_error_hz: e.resonance_error.as_ref().ok().copied(),
            phase_resonance_error_hz: e.phase_resonance_error_hz,
            peak_measured: e.peak_measured,
            peak_model: e.peak_model,
            peak_error: e.peak_error,
            rms_complex: e.rms_complex,
            failed_rows: e.failed_rows,
        }
    }
}

#[pymethods]
impl LevelError {
    fn __repr__(&self) -> String {
        format!(
            "LevelError({}, {}: peak error {:+.4}, RMS {:.4})",
            self.file, self.role, self.peak_error, self.rms_complex
        )
    }
}

fn level_errors(e: &[LevelErrors]) -> Vec<LevelError> {
    e.iter().map(LevelError::from).collect()
}

fn paths(written: &[PathBuf]) -> Vec<String> {
    written.iter().map(|p| p.display().to_string()).collect()
}

/// What `identify()` found (the report of `asperity identify`).
#[pyclass(frozen, get_all, module = "asperity")]
pub struct IdentifyReport {
    /// `"mode"` (single nonlinear mode) or `"reduced"` (a reduced model updated).
    pub kind: String,
    /// Ids of the effects the held-out evidence added, in the order accepted.
    pub selected_effects: Vec<String>,
    /// The search's conclusion in words.
    pub verdict: String,
    /// Levels fitted on (1-based, by increasing mean force).
    pub fit_levels: Vec<usize>,
    /// The final model's parameters with their 95 % intervals.
    pub parameters: Vec<ParameterEstimate>,
    /// Why the parameters have no intervals (`None` where they have).
    pub uncertainty_reason: Option<String>,
    /// Per level (by increasing mean force): errors of the baseline (reduced: the model as
    /// given).
    pub errors_before: Vec<LevelError>,
    /// Per level: errors of the final model.
    pub errors_after: Vec<LevelError>,
    /// The report as `identify.txt` holds it.
    pub text: String,
    /// Files written into `out_dir` (empty without one).
    pub written: Vec<String>,
    /// Wall-clock time of the identification (s).
    pub wall_time_s: f64,
}

#[pymethods]
impl IdentifyReport {
    /// Errors of the final model on the levels the fit did not use (role `"predicted"`).
    #[getter]
    fn held_out_errors(&self) -> Vec<LevelError> {
        self.errors_after
            .iter()
            .filter(|e| e.role == "predicted")
            .cloned()
            .collect()
    }

    fn __repr__(&self) -> String {
        format!(
            "IdentifyReport({}, fit levels {:?}, effects {:?}, {} parameters)",
            self.kind,
            self.fit_levels,
            self.selected_effects,
            self.parameters.len()
        )
    }
}

/// Identify a jointed structure's nonlinear mode from stepped-sine sweeps at several excitation
/// levels (one CSV per level), or update the reduced model of a response-model file
/// (`structure`): the command `asperity identify`, whose flags the keywords follow (errors name
/// the flag). `family`: jenkins, valanis or iwan; `candidates`: effect ids (`["none"]`: no
/// search; default all); `rows`: all or settled. With `out_dir` the command's files are written
/// there (all or none; an input is never overwritten). Runs without the GIL.
#[pyfunction]
#[pyo3(signature = (files, *, fit_levels=None, family="jenkins", candidates=None, max_effects=3, thorough=false, starts=None, particles=None, swarm_iterations=None, local_iterations=None, seed=1, response_amplitude=None, chain_steps=None, rows="all", structure=None, out_dir=None))]
#[allow(clippy::too_many_arguments)]
pub fn identify(
    py: Python<'_>,
    files: Vec<PathBuf>,
    fit_levels: Option<Vec<usize>>,
    family: &str,
    candidates: Option<Vec<String>>,
    max_effects: usize,
    thorough: bool,
    starts: Option<usize>,
    particles: Option<usize>,
    swarm_iterations: Option<u64>,
    local_iterations: Option<u64>,
    seed: u64,
    response_amplitude: Option<Vec<f64>>,
    chain_steps: Option<usize>,
    rows: &str,
    structure: Option<PathBuf>,
    out_dir: Option<PathBuf>,
) -> PyResult<IdentifyReport> {
    let config = IdentifyConfig {
        files,
        fit_levels,
        family: named("family", family, "jenkins, valanis, iwan")?,
        candidates,
        max_effects,
        thorough,
        starts,
        particles,
        swarm_iterations,
        local_iterations,
        seed,
        response_amplitude,
        chain_steps,
        rows: named("rows", rows, "all, settled")?,
        structure,
    };
    let (r, written) = py
        .detach(|| {
            prepare_identify(&config, out_dir.as_deref().map(|d| (d, "out_dir")))?
                .run(None)?
                .write()
        })
        .py()?;
    Ok(IdentifyReport {
        kind: match r {
            asperity::identify::command::IdentifyReport::Mode(_) => "mode",
            asperity::identify::command::IdentifyReport::Reduced(_) => "reduced",
        }
        .to_string(),
        selected_effects: r
            .selected_effects()
            .iter()
            .map(|e| e.id().to_string())
            .collect(),
        verdict: r.verdict(),
        fit_levels: r.fit_levels().iter().map(|i| i + 1).collect(),
        parameters: r.parameters().iter().map(ParameterEstimate::from).collect(),
        uncertainty_reason: r.uncertainty_reason().map(str::to_string),
        errors_before: level_errors(r.errors_before()),
        errors_after: level_errors(r.errors_after()),
        text: r.text(),
        written: paths(&written),
        wall_time_s: r.wall_time_s(),
    })
}

/// A saved model's prediction of one measured file.
#[pyclass(frozen, get_all, module = "asperity")]
pub struct FilePrediction {
    /// The measured file.
    pub file: String,
    /// The model's errors against it.
    pub errors: LevelError,
    /// Response control: RMS of `F_model/F_meas − 1` over the rows (`None` under force control).
    pub force_rms_error: Option<f64>,
    /// Largest drive-point displacement amplitude of the file's rows (m).
    pub peak_amplitude_m: f64,
    /// Why the file lies outside the amplitudes the model was identified on, or `None`.
    pub extrapolation: Option<String>,
    /// Why the file is not one lightly damped mode, or `None`.
    pub not_one_mode: Option<String>,
}

/// What `predict()` found (the report of `asperity predict`).
#[pyclass(frozen, get_all, module = "asperity")]
pub struct PredictReport {
    /// The model file that predicted.
    pub model_file: String,
    /// `"force"` or `"response"`: how the measured tests were controlled.
    pub control: String,
    /// Where the control comes from (a file's header, the argument, or the default).
    pub control_source: String,
    /// Where the phase convention comes from.
    pub convention_source: String,
    /// One prediction per measured file, in the order given.
    pub files: Vec<Py<FilePrediction>>,
    /// The report as `predict.txt` holds it.
    pub text: String,
    /// Files written into `out_dir` (empty without one).
    pub written: Vec<String>,
}

#[pymethods]
impl PredictReport {
    fn __repr__(&self) -> String {
        format!(
            "PredictReport({}, {} control, {} file(s))",
            self.model_file,
            self.control,
            self.files.len()
        )
    }
}

/// Score an identified model (`model.json` of `identify`) on measured files: the command
/// `asperity predict`. `control`: "force" or "response"; default what the files' headers state
/// (force where they state nothing). With `out_dir` the command's files are written there.
/// Runs without the GIL.
#[pyfunction]
#[pyo3(signature = (model, files, *, control=None, out_dir=None))]
pub fn predict(
    py: Python<'_>,
    model: PathBuf,
    files: Vec<PathBuf>,
    control: Option<&str>,
    out_dir: Option<PathBuf>,
) -> PyResult<PredictReport> {
    let config = PredictConfig {
        model,
        files,
        control: control
            .map(|c| named("control", c, "force, response"))
            .transpose()?,
    };
    let (p, written) = py
        .detach(|| {
            prepare_predict(&config, out_dir.as_deref().map(|d| (d, "out_dir")))?
                .run()?
                .write()
        })
        .py()?;
    let files = p
        .files
        .iter()
        .map(|f| {
            Py::new(
                py,
                FilePrediction {
                    file: f.input.path.display().to_string(),
                    errors: LevelError::from(&f.errors),
                    force_rms_error: f.force_rms_error,
                    peak_amplitude_m: f.peak_amplitude_m,
                    extrapolation: f.extrapolation.clone(),
                    not_one_mode: f.not_one_mode.clone(),
                },
            )
        })
        .collect::<PyResult<Vec<_>>>()?;
    Ok(PredictReport {
        model_file: p.model_file.display().to_string(),
        control: match p.control {
            asperity::identify::Control::Force => "force",
            asperity::identify::Control::Response => "response",
        }
        .to_string(),
        control_source: p.control_source.clone(),
        convention_source: p.convention_source.clone(),
        files,
        text: p.text(),
        written: paths(&written),
    })
}
