//! Updating a multi-DOF reduced model against measured sweeps: the linear structure and the
//! contact elements of an `asperity response` model file (lumped or reduced modal, element
//! tables from `asperity elements`) with four updating factors fitted on some levels and the
//! others predicted.
//!
//! # Model
//!
//! The equations of [`crate::dynamics::model`], `M·q̈ + C·q̇ + K·q + Σ_e P_eᵀ·f_e(P_e·q) = F(t)`,
//! with the structure as the file gives it except for four factors (all 1 = the model as
//! computed from the surfaces and the film, which is the prediction the measurement judges):
//!
//! | parameter | acts on | meaning |
//! |---|---|---|
//! | `frequency_factor` | `K → s_f²·K` | every natural frequency of the linear structure × `s_f` (the linear model's frequency error) |
//! | `damping_factor` | `C → s_ζ·s_f·C` | every modal damping ratio × `s_ζ` (the `s_f` keeps the ratios under the frequency factor) |
//! | `contact_stiffness_factor` | `E0, Et, kn → s_k·(E0, Et, kn)` | stiffness of every contact element (the calibration's stiffness error) |
//! | `friction_factor` | `μ → s_μ·μ` | slip limit `μ·N` of every contact element (friction coefficient, or the preload, in error) |
//!
//! The drive is the file's `[excitation]` (DOFs and weights, one newton per unit level, each
//! row's measured force applied), the measured response its first `[response]` DOF; harmonics,
//! time samples and formulation are those of its `[sweep]`. Each sweep is solved row by row in
//! sweep order, warm-started from the previous row; a row whose Newton iteration fails from the
//! warm start is solved again from rest and then by a ramp of the force.
//!
//! # Fit
//!
//! The same objective, bounds handling and search as the single-mode identification
//! ([`super::fit`]): complex response per unit force, each level divided by its peak and row
//! count, particle swarm then Nelder–Mead restarted until it converges, plus one Nelder–Mead
//! start from the model as given; the best is kept (with no swarm starts, the local start only). The effect search of
//! [`super::select`] is not run: its candidates are defined on the single nonlinear mode.
//!
//! # Report
//!
//! Every level's errors as given and updated (resonance, phase resonance, peak, RMS complex,
//! residual per region), the measurement scatter, the backbone as the equivalent linear mode
//! per level ([`backbone::equivalent_mode`]: the estimator the data's backbone uses, applied to
//! each model's response at the same rows) and the updated model's response-controlled FRF at
//! the measured peak responses.

use super::backbone::{self, BackbonePoint, LevelBackbone};
use super::fit::{fit_global, fit_local, FitOptions, FitResult, LevelData, Parametrised};
use super::measured::{sha256_hex, PhaseConvention, Sweep};
use super::model::check_values;
use super::model::{solve_sweep, Drive, ParamSpec, RowFailure};
use super::pipeline::{
    response_control_amplitudes, response_controlled_text, response_controlled_with,
    write_backbone_csv, write_response_controlled_csv, ResponseControlled,
};
use super::report::{
    errors_table, fine_curve_with, level_role, level_roles, plot_backbone, plot_level,
    regions_text, write_json, write_rows_csv, CurveRow, InputFile, LevelErrors,
};
use super::uncertainty::{self, Ensemble, Uncertainty};
use crate::dynamics::aft::Harmonics;
use crate::dynamics::contact::element_for;
use crate::dynamics::hbm::{Excitation, FormulationChoice, HbmSystem};
use crate::dynamics::model::Structure;
use crate::dynamics::model_file::{self, LoadedModel};
use crate::error::{Error, Result};
use crate::output::write_string_atomic;
use nalgebra::DVector;
use realfft::num_complex::Complex64;
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Bounds of the three multiplicative factors searched in `ln` (a factor of 50 either way: a
/// calibration error larger than that is not an update but a different model).
const FACTOR_RANGE: f64 = 50.0;

/// Bounds of the frequency factor: the linear structure's frequencies within −20 % / +25 %.
const FREQUENCY_FACTOR: (f64, f64) = (0.8, 1.25);

/// The reduced model of a response-model file and its updating parameters.
#[derive(Debug, Clone)]
pub struct ReducedSpec {
    pub loaded: Arc<LoadedModel>,
}

/// A reduced model with values of its updating factors.
#[derive(Debug, Clone, Serialize)]
pub struct ReducedModel {
    #[serde(skip)]
    pub spec: ReducedSpec,
    /// `frequency_factor, damping_factor, contact_stiffness_factor, friction_factor`.
    pub values: Vec<f64>,
}

impl ReducedSpec {
    /// Read a response-model file (`asperity response` format).
    pub fn load(path: &Path) -> Result<Self> {
        let loaded = model_file::load(path)?;
        if loaded.element_rows.is_empty() {
            return Err(Error::parse(
                path,
                0,
                "no `[[contact]]` elements: the contact stiffness and friction factors would \
                 have nothing to act on (a linear structure is updated by a linear fit)",
            ));
        }
        if loaded.structure.damping.iter().all(|&c| c == 0.0) {
            return Err(Error::parse(
                path,
                0,
                "the linear structure has no damping: the damping factor would have nothing to \
                 scale (give the modes' damping ratios or a damping matrix)",
            ));
        }
        Ok(Self {
            loaded: Arc::new(loaded),
        })
    }

    /// The model file's path.
    pub fn path(&self) -> &Path {
        &self.loaded.path
    }
}

impl Parametrised for ReducedSpec {
    type Model = ReducedModel;

    fn params(&self) -> Vec<ParamSpec> {
        let (lo, hi) = (1.0 / FACTOR_RANGE, FACTOR_RANGE);
        let (flo, fhi) = FREQUENCY_FACTOR;
        vec![
            ParamSpec::lin("frequency_factor", "-", flo, fhi, 1.0),
            ParamSpec::log("damping_factor", "-", lo, hi, 1.0),
            ParamSpec::log("contact_stiffness_factor", "-", lo, hi, 1.0),
            ParamSpec::log("friction_factor", "-", lo, hi, 1.0),
        ]
    }

    fn model(&self, values: Vec<f64>) -> ReducedModel {
        ReducedModel {
            spec: self.clone(),
            values,
        }
    }

    fn values_of(model: &ReducedModel) -> &[f64] {
        &model.values
    }

    fn frf(model: &ReducedModel, level: &LevelData) -> Result<(Vec<Complex64>, usize)> {
        let (x, failures) = model.receptance_tolerant(&level.drives, true)?;
        Ok((level.from_receptance(&x), failures.len()))
    }
}

impl ReducedModel {
    /// The model as the file gives it (every factor 1).
    pub fn as_given(spec: &ReducedSpec) -> Self {
        spec.model(vec![1.0; 4])
    }

    /// The updated structure: `K·s_f²`, `C·s_ζ·s_f`, contact elements rebuilt from their table
    /// rows with `E0, Et, kn` × `s_k` and `μ` × `s_μ`.
    pub fn structure(&self) -> Result<Structure> {
        let [sf, sz, sk, smu] = <[f64; 4]>::try_from(self.values.as_slice())
            .map_err(|_| Error::param("values", "four updating factors expected"))?;
        let l = &self.spec.loaded;
        let mut s = l.structure.clone();
        s.stiffness *= sf * sf;
        s.damping *= sz * sf;
        for (att, (law, row)) in s.elements.iter_mut().zip(&l.element_rows) {
            let mut r = row.clone();
            r.e0_n_per_m *= sk;
            r.et_n_per_m *= sk;
            r.kn_n_per_m *= sk;
            r.mu *= smu;
            att.element = element_for(*law, &r)?;
        }
        Ok(s)
    }

    /// Complex fundamental response per unit force (m/N, `e^{iωt}` convention) of the first
    /// response DOF at every drive, in order, warm-started along the list (the sweep order).
    /// With `tolerant`, a row that fails is recorded (NaN) instead of ending the evaluation.
    pub fn receptance_tolerant(
        &self,
        drives: &[Drive],
        tolerant: bool,
    ) -> Result<(Vec<Complex64>, Vec<RowFailure>)> {
        let s = self.structure()?;
        let sys = self.system(&s, self.spec.loaded.file.sweep.formulation)?;
        solve_sweep(drives, tolerant, |d, warm| {
            let p = solve_robust(&sys, d, warm)?;
            let x = self.observed(&sys.harmonics, &sys.coordinates(&p)) / d.force_n;
            Ok((x, p.z))
        })
    }

    /// The harmonic-balance system of the updated structure `s`: the file's excitation (one
    /// newton per unit level, fundamental), harmonics and time samples.
    fn system<'a>(
        &self,
        s: &'a Structure,
        formulation: FormulationChoice,
    ) -> Result<HbmSystem<'a>> {
        let l = &self.spec.loaded;
        let sw = &l.file.sweep;
        HbmSystem::new(
            s,
            Harmonics::new(sw.harmonics, sw.odd_only, sw.time_samples)?,
            Excitation {
                force: l.force.clone(),
                harmonic: 1,
            },
            formulation,
        )
    }

    /// Complex fundamental (`e^{iωt}`) of the first response DOF from the coordinates'
    /// harmonics `q` (coordinate-major).
    fn observed(&self, h: &Harmonics, q: &DVector<f64>) -> Complex64 {
        let (ci, si) = h.index_of(1).expect("fundamental retained");
        let len = h.len();
        let obs = &self.spec.loaded.responses[0].1;
        let (mut a, mut b) = (0.0, 0.0);
        for (c, &w) in obs.iter().enumerate() {
            a += w * q[c * len + ci];
            b += w * q[c * len + si];
        }
        Complex64::new(a, -b)
    }

    /// Response-controlled evaluation: at each frequency, the force that holds the amplitude of
    /// the fundamental response at `target_m[i]` (m, first response DOF), and the complex
    /// receptance there (coordinates formulation, warm-started along the sweep). Returns
    /// `(force amplitudes (N), receptances (m/N))`.
    pub fn response_controlled(
        &self,
        omegas: &[f64],
        target_m: &[f64],
    ) -> Result<(Vec<f64>, Vec<Complex64>)> {
        let s = self.structure()?;
        let sys = self.system(&s, FormulationChoice::Coordinates)?;
        let obs = &self.spec.loaded.responses[0].1;
        let (mut forces, mut recs) = (Vec::new(), Vec::new());
        let mut guess: Option<(DVector<f64>, f64)> = None;
        for (&w, &target) in omegas.iter().zip(target_m) {
            let p = sys.solve_response_controlled(
                w,
                target,
                obs,
                guess.as_ref().map(|(z, f)| (z, *f)),
            )?;
            forces.push(p.level);
            recs.push(self.observed(&sys.harmonics, &p.z) / p.level);
            guess = Some((p.z, p.level));
        }
        Ok((forces, recs))
    }
}

/// Newton from the warm start; on failure from rest, then by a ramp of the force in four steps.
fn solve_robust(
    sys: &HbmSystem<'_>,
    d: &Drive,
    warm: Option<&DVector<f64>>,
) -> Result<crate::dynamics::hbm::HbmPoint> {
    let first = match sys.solve(d.omega, d.force_n, warm) {
        Ok(p) => return Ok(p),
        Err(e) => e,
    };
    if warm.is_some() {
        if let Ok(p) = sys.solve(d.omega, d.force_n, None) {
            return Ok(p);
        }
    }
    let mut z: Option<DVector<f64>> = None;
    for step in 1..=4 {
        match sys.solve(d.omega, d.force_n * step as f64 / 4.0, z.as_ref()) {
            Ok(p) => {
                if step == 4 {
                    return Ok(p);
                }
                z = Some(p.z);
            }
            Err(_) => break,
        }
    }
    Err(first)
}

/// The better of two fits of the same family, with the starts and evaluations of both.
fn merge_fits(a: FitResult<ReducedModel>, b: FitResult<ReducedModel>) -> FitResult<ReducedModel> {
    let (mut best, other) = if b.cost < a.cost { (b, a) } else { (a, b) };
    best.starts.extend(other.starts);
    best.evaluations += other.evaluations;
    best.wall_time_s += other.wall_time_s;
    best
}

/// Result of updating a reduced model.
#[derive(Debug, Clone, Serialize)]
pub struct ReducedIdentification {
    pub model_file: PathBuf,
    pub model_sha256: String,
    pub inputs: Vec<InputFile>,
    pub phase_convention: String,
    /// 0-based fit levels (by increasing mean force).
    pub fit_levels: Vec<usize>,
    pub parameters: Vec<ParamSpec>,
    pub fit: FitResult<ReducedModel>,
    /// Errors of the model as given (every factor 1) and of the updated model, per level.
    pub errors_before: Vec<LevelErrors>,
    pub errors_after: Vec<LevelErrors>,
    /// Measurement scatter per component of each fit level (third differences, fraction of
    /// its peak).
    pub scatter: Vec<f64>,
    /// The objective the scatter alone would leave ([`super::select::scatter_floor`]).
    pub scatter_floor: f64,
    /// Whether the updated model's objective is within [`super::select::SCATTER_FACTOR`] of it.
    pub at_scatter: bool,
    /// The data's backbone (equivalent linear mode per level, pointwise estimates), or why it
    /// could not be estimated (a sweep that is not one lightly damped mode).
    pub data_backbone: std::result::Result<Vec<LevelBackbone>, String>,
    /// Per level: the equivalent linear mode of the model's response at the level's rows, as
    /// given and updated (`None`: no resonance inside the measured band).
    pub backbone_before: Vec<Option<BackbonePoint>>,
    pub backbone_after: Vec<Option<BackbonePoint>>,
    /// The updated model under response control at the measured peak responses (or the given
    /// amplitudes), and the amplitudes where that solve failed, with the reason.
    pub response_controlled: Vec<ResponseControlled>,
    pub response_control_failures: Vec<(f64, String)>,
    /// Parameter intervals and 95 % bands of the updated model's predictions.
    pub uncertainty: Uncertainty,
    pub options: ReducedOptions,
    pub wall_time_s: f64,
    #[serde(skip)]
    pub levels: Vec<LevelData>,
    /// Responses per unit force of the model as given and updated at every level's rows (the
    /// level's quantity), kept for the files.
    #[serde(skip)]
    pub responses_before: Vec<Vec<Complex64>>,
    #[serde(skip)]
    pub responses_after: Vec<Vec<Complex64>>,
    #[serde(skip)]
    pub convention: PhaseConvention,
    #[serde(skip)]
    pub before: ReducedModel,
}

/// A model's response at every level's rows and its errors there (role `fit` or `predicted`).
fn responses_and_errors(
    model: &ReducedModel,
    levels: &[LevelData],
    fit: &[usize],
) -> Result<(Vec<Vec<Complex64>>, Vec<LevelErrors>)> {
    let mut responses = Vec::new();
    let mut errors = Vec::new();
    for (i, l) in levels.iter().enumerate() {
        let (y, failed) = ReducedSpec::frf(model, l)?;
        let role = level_role(i, fit);
        errors.push(LevelErrors::new(l, &y, role, failed));
        responses.push(y);
    }
    Ok((responses, errors))
}

/// Per level, the equivalent linear mode of a model's responses at the level's rows
/// ([`backbone::equivalent_mode`]).
fn model_modes(levels: &[LevelData], responses: &[Vec<Complex64>]) -> Vec<Option<BackbonePoint>> {
    levels
        .iter()
        .zip(responses)
        .map(|(l, y)| {
            let om: Vec<f64> = l.drives.iter().map(|d| d.omega).collect();
            let f: Vec<f64> = l.drives.iter().map(|d| d.force_n).collect();
            backbone::equivalent_mode(l.quantity, &om, &f, y)
        })
        .collect()
}

/// Settings of a reduced-model update.
#[derive(Debug, Clone, Serialize)]
pub struct ReducedOptions {
    pub fit: FitOptions,
    /// Response amplitudes (unit of the lowest level's quantity) of the response-controlled
    /// FRFs; `None`: the measured peak responses.
    pub response_amplitudes: Option<Vec<f64>>,
    /// Steps of each Metropolis chain of the prediction bands (0: no bands); `None`: the
    /// default [`uncertainty::CHAIN_STEPS`] when the bands are expected to take at most
    /// [`BAND_BUDGET_S`], none otherwise (the report says why).
    pub chain_steps: Option<usize>,
}

impl ReducedOptions {
    /// Default settings around a fit's.
    pub fn new(fit: FitOptions) -> Self {
        Self {
            fit,
            response_amplitudes: None,
            chain_steps: None,
        }
    }
}

/// Wall time (s) the prediction bands of a reduced model may be expected to take before the
/// default leaves them out: every evaluation of a large model costs seconds, and the chains
/// need thousands.
pub const BAND_BUDGET_S: f64 = 600.0;

/// The chain length to use for the bands of `model`, or why there are none: the explicit
/// `chain_steps`, or [`default_band_steps`] from one timed evaluation on the fit levels.
fn band_chain_steps(
    spec: &ReducedSpec,
    model: &ReducedModel,
    fit_data: &[LevelData],
    levels: usize,
    chain_steps: Option<usize>,
) -> std::result::Result<usize, String> {
    if let Some(n) = chain_steps {
        return Ok(n);
    }
    let t0 = std::time::Instant::now();
    super::select::cost_all_rows(spec, model, fit_data);
    default_band_steps(
        t0.elapsed().as_secs_f64(),
        levels,
        fit_data.len(),
        rayon::current_num_threads(),
    )
}

/// The default chain length when the bands' expected wall time fits [`BAND_BUDGET_S`], or why
/// they are left out. The work is [`uncertainty::CHAINS`] chains of
/// [`uncertainty::CHAIN_STEPS`] evaluations of the fit levels and the ensemble's
/// [`uncertainty::ENSEMBLE_DRAWS`] models at every level, all sharing the `threads` cores; one
/// evaluation took `per_evaluation_s` with its `fit_levels` levels solved in parallel, i.e.
/// `min(fit_levels, threads)` cores' worth of work.
pub fn default_band_steps(
    per_evaluation_s: f64,
    levels: usize,
    fit_levels: usize,
    threads: usize,
) -> std::result::Result<usize, String> {
    let steps = uncertainty::CHAIN_STEPS;
    let chains = uncertainty::CHAINS;
    let (fit_levels, threads) = (fit_levels.max(1), threads.max(1));
    let evaluations =
        (chains * steps) as f64 + (uncertainty::ENSEMBLE_DRAWS * levels) as f64 / fit_levels as f64;
    let cores_per_evaluation = fit_levels.min(threads) as f64 / threads as f64;
    let expected = evaluations * per_evaluation_s * cores_per_evaluation;
    if expected <= BAND_BUDGET_S {
        Ok(steps)
    } else {
        Err(format!(
            "left out by default: about {:.1} h expected ({chains} chains of {steps} steps and \
             {} models at every level, {:.2} s per evaluation of the fit levels); --chain-steps N \
             runs them with chains of N steps",
            expected / 3600.0,
            uncertainty::ENSEMBLE_DRAWS,
            per_evaluation_s
        ))
    }
}

/// Update the reduced model of `spec` on the fit levels (0-based, already checked) and score
/// every level, before (as given) and after; the 95 % bands of the updated model's predictions
/// and its response-controlled FRFs.
pub fn identify_reduced(
    spec: &ReducedSpec,
    sweeps: Vec<Sweep>,
    fit_levels: Vec<usize>,
    options: &ReducedOptions,
    progress: Option<&indicatif::ProgressBar>,
) -> Result<ReducedIdentification> {
    let opts = &options.fit;
    let response_amplitudes = options.response_amplitudes.as_deref();
    let t0 = std::time::Instant::now();
    let convention = PhaseConvention::detect(&sweeps)?;
    let levels: Vec<LevelData> = sweeps
        .iter()
        .map(|s| LevelData::new(s, &convention))
        .collect();
    let fit_data: Vec<LevelData> = fit_levels.iter().map(|&i| levels[i].clone()).collect();
    let masks: Vec<Vec<bool>> = fit_data
        .iter()
        .map(|l| vec![true; l.drives.len()])
        .collect();
    // One Nelder–Mead start from the model as given (the prediction being updated is the
    // natural first guess) and the swarm's starts, if any; the best is kept. Without swarm
    // starts the update is local: the choice for large models, whose every evaluation costs
    // seconds (README).
    let local = fit_local(spec, &fit_data, &masks, &[vec![1.0; 4]], opts, progress)?;
    let fit = if opts.starts == 0 {
        local
    } else {
        merge_fits(fit_global(spec, &fit_data, &masks, opts, progress)?, local)
    };
    if !fit.converged {
        return Err(Error::NonConvergence {
            solver: format!(
                "reduced-model update ({}, Nelder–Mead restarted from its optimum up to {} times)",
                spec.path().display(),
                super::fit::LOCAL_RESTARTS
            ),
            iterations: fit.starts.iter().map(|s| s.local_iterations as usize).sum(),
            residual: fit.cost,
            tolerance: 1e-7 * fit.cost,
        });
    }
    let (responses_after, errors_after) = responses_and_errors(&fit.model, &levels, &fit_levels)?;
    for (l, y) in levels.iter().zip(&responses_after) {
        if let Some(k) = y.iter().position(|v| !v.re.is_finite()) {
            return Err(Error::Data(format!(
                "{}:{}: the updated model has no harmonic-balance solution at this row",
                l.name, l.lines[k]
            )));
        }
    }
    let before = ReducedModel::as_given(spec);
    let (responses_before, errors_before) = responses_and_errors(&before, &levels, &fit_levels)?;
    let scatter = fit_data
        .iter()
        .map(super::select::relative_scatter)
        .collect();
    let scatter_floor = super::select::scatter_floor(&fit_data);
    let at_scatter = fit.cost <= super::select::SCATTER_FACTOR * scatter_floor;
    let roles = level_roles(levels.len(), &fit_levels);
    let uncertainty = match band_chain_steps(
        spec,
        &fit.model,
        &fit_data,
        levels.len(),
        options.chain_steps,
    ) {
        Ok(steps) => uncertainty::estimate(spec, &fit.model, &fit_data, &levels, &roles, steps),
        Err(reason) => Uncertainty::NotEstimated { reason },
    };
    let frfs: Vec<Vec<Complex64>> = sweeps.iter().map(|s| s.frf(&convention)).collect();
    let data_backbone = backbone::from_data(&sweeps, &frfs).map_err(|e| e.to_string());
    let backbone_before = model_modes(&levels, &responses_before);
    let backbone_after = model_modes(&levels, &responses_after);
    let quantity = sweeps[0].quantity;
    let (amplitudes, band) = response_control_amplitudes(&sweeps, response_amplitudes);
    let (mut response_controlled, mut response_control_failures) = (Vec::new(), Vec::new());
    for a in amplitudes {
        crate::error::require_positive("--response-amplitude", a)?;
        match response_controlled_with(quantity, a, band, |om, targets| {
            fit.model.response_controlled(om, targets)
        }) {
            Ok(r) => response_controlled.push(r),
            Err(e) => response_control_failures.push((a, e.to_string())),
        }
    }
    let bytes = std::fs::read(spec.path()).map_err(|e| Error::io(spec.path(), e))?;
    Ok(ReducedIdentification {
        model_file: spec.path().to_path_buf(),
        model_sha256: sha256_hex(&bytes),
        inputs: sweeps.iter().map(InputFile::of).collect(),
        phase_convention: convention.describe(),
        fit_levels,
        parameters: spec.params(),
        fit,
        errors_before,
        errors_after,
        scatter,
        scatter_floor,
        at_scatter,
        uncertainty,
        data_backbone,
        backbone_before,
        backbone_after,
        response_controlled,
        response_control_failures,
        options: options.clone(),
        wall_time_s: t0.elapsed().as_secs_f64(),
        levels,
        responses_before,
        responses_after,
        convention,
        before,
    })
}

/// `kind` of a saved reduced model.
pub const REDUCED_KIND: &str = "reduced";

/// The saved updated model (`model.json` of a reduced-model identification): the response-model
/// file (absolute path and SHA-256: a file changed since is refused) and the factors.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SavedReducedModel {
    pub kind: String,
    pub model_file: PathBuf,
    pub model_sha256: String,
    /// `(name, value)` of every updating factor.
    pub factors: Vec<(String, f64)>,
    /// Phase convention of the identification's files (used where a file to predict does not
    /// pass through a resonance).
    pub phase_convention: PhaseConvention,
    /// Models of the updated form that fit about as well (the prediction bands), if sampled.
    #[serde(default)]
    pub ensemble: Option<Ensemble>,
}

impl SavedReducedModel {
    /// Whether a saved model file is a reduced model (by its `kind`).
    pub fn is_reduced(path: &Path) -> Result<bool> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        let v: serde_json::Value = serde_json::from_str(&text).map_err(|e| {
            Error::parse(
                path,
                e.line(),
                format!("not an identified model file (JSON of `asperity identify`): {e}"),
            )
        })?;
        Ok(v.get("kind").and_then(|k| k.as_str()) == Some(REDUCED_KIND))
    }

    /// Read a saved reduced model and rebuild it: the response-model file must be unchanged and
    /// the factors named and inside their bounds.
    pub fn read(path: &Path) -> Result<(ReducedModel, PhaseConvention, Option<Ensemble>)> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        let s: SavedReducedModel = serde_json::from_str(&text)
            .map_err(|e| Error::parse(path, e.line(), format!("not a reduced model file: {e}")))?;
        let bytes = std::fs::read(&s.model_file).map_err(|e| Error::io(&s.model_file, e))?;
        if sha256_hex(&bytes) != s.model_sha256 {
            return Err(Error::parse(
                path,
                0,
                format!(
                    "{} has changed since the identification (SHA-256 differs): the factors \
                     update the model as it was",
                    s.model_file.display()
                ),
            ));
        }
        let spec = ReducedSpec::load(&s.model_file)?;
        let params = spec.params();
        if s.factors.len() != params.len() {
            return Err(Error::parse(
                path,
                0,
                format!("{} factors, expected {}", s.factors.len(), params.len()),
            ));
        }
        for (p, (name, _)) in params.iter().zip(&s.factors) {
            if name != p.name {
                return Err(Error::parse(
                    path,
                    0,
                    format!("factor {name}: expected {}", p.name),
                ));
            }
        }
        let values: Vec<f64> = s.factors.iter().map(|f| f.1).collect();
        check_values(&params, &values).map_err(|e| Error::parse(path, 0, e.to_string()))?;
        if let Some(e) = &s.ensemble {
            e.check(&params).map_err(|e| Error::parse(path, 0, e))?;
        }
        Ok((spec.model(values), s.phase_convention, s.ensemble))
    }
}

impl ReducedIdentification {
    /// The report text.
    pub fn text(&self) -> String {
        let mut s = format!(
            "reduced-model update of {} (sha256 {})\n{}\n\n",
            self.model_file.display(),
            &self.model_sha256[..16.min(self.model_sha256.len())],
            self.phase_convention
        );
        s += "levels (by increasing mean force):\n";
        for (i, inp) in self.inputs.iter().enumerate() {
            s += &format!(
                "  {} {:<40} {:>3} rows, mean force {:.4} N  [{}]\n",
                i + 1,
                inp.path.display(),
                inp.rows,
                inp.mean_force_n,
                level_role(i, &self.fit_levels)
            );
        }
        s += "\nupdating factors (1 = the model as given):\n";
        for (p, v) in self.parameters.iter().zip(&self.fit.model.values) {
            s += &format!(
                "  {:<26} {:>10.5}   bounds [{}, {}]{}\n",
                p.name,
                v,
                p.lo,
                p.hi,
                if p.at_bound(*v) { "  AT BOUND" } else { "" }
            );
        }
        s += &format!(
            "objective J = {:.4e} ({} model evaluations, {} starts, converged: {})\n",
            self.fit.cost,
            self.fit.evaluations,
            self.fit.starts.len(),
            self.fit.converged
        );
        s += "effect search: not run (its candidates are defined on the single nonlinear mode)\n\n";
        let rows: Vec<(&LevelErrors, Option<&LevelErrors>)> = self
            .errors_before
            .iter()
            .zip(&self.errors_after)
            .map(|(b, a)| (b, Some(a)))
            .collect();
        s += &errors_table("errors, model as given → updated", &rows);
        s += &format!(
            "\nmeasurement scatter per component (third differences) of the fit levels: {} of \
             their peaks; objective J = {:.3e} against the {:.3e} the scatter alone leaves: {}\n",
            self.scatter
                .iter()
                .map(|v| format!("{v:.4}"))
                .collect::<Vec<_>>()
                .join(", "),
            self.fit.cost,
            self.scatter_floor,
            if self.at_scatter {
                "the updated model fits to the measurement scatter"
            } else {
                "the residual stays above the scatter — part of the misfit is not explained by \
                 the updated model (its four factors cannot express what the measurement shows)"
            }
        );
        s += &regions_text("residual per region, model as given → updated", &rows);
        s += &self.uncertainty.text("updated model");
        s += "\nbackbone: equivalent linear mode per level (the same estimator on the measured \
              sweep and on each model's response at its rows; amplitude = peak drive-point \
              displacement):\n";
        let cell = |b: Option<&BackbonePoint>| match b {
            Some(b) => format!(
                "{:>9.3e} m {:>9.3} Hz ζ {:.5}",
                b.amplitude_m, b.frequency_hz, b.damping_ratio
            ),
            None => format!("{:>36}", "no resonance in the band"),
        };
        match &self.data_backbone {
            Ok(data) => {
                s += &format!(
                    "  {:<34} | {:<36} | {:<36} | {:<36}\n",
                    "level", "data", "as given", "updated"
                );
                for (i, d) in data.iter().enumerate() {
                    let p = BackbonePoint {
                        amplitude_m: d.peak_amplitude_m,
                        frequency_hz: d.linear.frequency_hz,
                        damping_ratio: d.linear.damping_ratio,
                    };
                    s += &format!(
                        "  {:<34} | {} | {} | {}\n",
                        d.file,
                        cell(Some(&p)),
                        cell(self.backbone_before[i].as_ref()),
                        cell(self.backbone_after[i].as_ref())
                    );
                }
            }
            Err(reason) => s += &format!("  not estimated from the data: {reason}\n"),
        }
        s += &response_controlled_text(&self.response_controlled);
        for (a, e) in &self.response_control_failures {
            s += &format!("  response amplitude {a}: no solution under response control: {e}\n");
        }
        s
    }

    /// The model backbones as plotted and written: the levels' equivalent modes in order of
    /// amplitude (levels without a resonance in the band left out).
    fn model_backbone_points(modes: &[Option<BackbonePoint>]) -> Vec<BackbonePoint> {
        let mut pts: Vec<BackbonePoint> = modes.iter().flatten().copied().collect();
        pts.sort_by(|a, b| a.amplitude_m.total_cmp(&b.amplitude_m));
        pts
    }

    /// Write `identify.{txt,json}`, `model.json`, `identify-rows.csv`, `identify-level<N>.png`,
    /// `identify-backbone.{csv,png}` and `identify-response-controlled.csv`.
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>> {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        let mut written = Vec::new();
        let p = dir.join("identify.txt");
        write_string_atomic(&p, &self.text())?;
        written.push(p);
        let p = dir.join("identify.json");
        write_json(&p, self)?;
        written.push(p);
        let saved = SavedReducedModel {
            kind: REDUCED_KIND.into(),
            model_file: std::fs::canonicalize(&self.model_file)
                .map_err(|e| Error::io(&self.model_file, e))?,
            model_sha256: self.model_sha256.clone(),
            factors: self
                .parameters
                .iter()
                .zip(&self.fit.model.values)
                .map(|(p, &v)| (p.name.to_string(), v))
                .collect(),
            phase_convention: self.convention,
            ensemble: match &self.uncertainty {
                Uncertainty::Estimated(e) => Some(e.ensemble.clone()),
                Uncertainty::NotEstimated { .. } => None,
            },
        };
        let p = dir.join("model.json");
        write_json(&p, &saved)?;
        written.push(p);
        let mut rows = Vec::new();
        for (i, l) in self.levels.iter().enumerate() {
            let (yb, ya) = (&self.responses_before[i], &self.responses_after[i]);
            let role = self.errors_after[i].role.clone();
            for (k, d) in l.drives.iter().enumerate() {
                rows.push(CurveRow {
                    file: l.name.clone(),
                    role: role.clone(),
                    line: l.lines[k],
                    frequency_hz: d.omega / TAU,
                    force_n: d.force_n,
                    measured: l.measured[k],
                    models: vec![yb[k], ya[k]],
                });
            }
            let curve = |m: &ReducedModel| {
                fine_curve_with(l, 4, &|drives: &[Drive]| {
                    m.receptance_tolerant(drives, true).map(|(x, _)| x)
                })
            };
            let png = dir.join(format!("identify-level{}.png", i + 1));
            plot_level(
                &png,
                l,
                &self.convention,
                &[
                    ("as given".to_string(), curve(&self.before)),
                    (format!("updated ({role})"), curve(&self.fit.model)),
                ],
                &format!("level {} ({}), {role}", i + 1, l.name),
            )?;
            written.push(png);
        }
        let p = dir.join("identify-rows.csv");
        let conv = self.convention;
        write_rows_csv(
            &p,
            &format!(
                "units: frequency Hz, force N, response per force in the file's unit per N, \
                 phase rad; models: the reduced model {} as given and updated",
                self.model_file.display()
            ),
            &["as_given", "updated"],
            &rows,
            &|_| conv,
        )?;
        written.push(p);
        let before = Self::model_backbone_points(&self.backbone_before);
        let after = Self::model_backbone_points(&self.backbone_after);
        let data: &[LevelBackbone] = self.data_backbone.as_deref().unwrap_or(&[]);
        let p = dir.join("identify-backbone.csv");
        write_backbone_csv(
            &p,
            data,
            &[("as-given-model", &before), ("updated-model", &after)],
        )?;
        written.push(p);
        if !data.is_empty() {
            let p = dir.join("identify-backbone.png");
            plot_backbone(
                &p,
                data,
                &[
                    ("as given (equivalent mode per level)".into(), before),
                    ("updated (equivalent mode per level)".into(), after),
                ],
            )?;
            written.push(p);
        }
        if !self.response_controlled.is_empty() {
            let p = dir.join("identify-response-controlled.csv");
            write_response_controlled_csv(&p, &self.response_controlled)?;
            written.push(p);
        }
        Ok(written)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The default bands run where the chains take a few minutes (the two-mode test model,
    /// 14 ms per evaluation of two levels on two cores: 12 300 evaluations, 172 s) and are left
    /// out at the blade–damper example's 6.3 s (about 21.5 h), with the time in the reason.
    #[test]
    fn default_bands_follow_the_cost_of_an_evaluation() {
        assert_eq!(
            default_band_steps(0.014, 3, 2, 2),
            Ok(uncertainty::CHAIN_STEPS)
        );
        let why = default_band_steps(6.3, 3, 2, 2).unwrap_err();
        assert!(
            why.contains("21.5 h") && why.contains("--chain-steps"),
            "{why}"
        );
    }
}
