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
//! start from the model as given; the best is kept (with no swarm starts, the local start only).
//!
//! # Closing the loop: effects the four factors cannot express
//!
//! When the four factors leave the objective above the measurement scatter
//! ([`super::select::SCATTER_FACTOR`] × the scatter floor), the effect search of
//! [`super::select`] runs on this family — the same split into training and held-out rows, the
//! same held-out ΔBIC with an effective sample size, the same "very strong" threshold and the
//! requirement that every fit level improves — with the candidates of [`REDUCED_EFFECTS`]:
//!
//! | effect | on the reduced model |
//! |---|---|
//! | `amplitude_stiffness` | cubic spring `k3·u³` from the response coordinate to ground, `k3 = 4ε·k_ref/(3·A_ref²)` |
//! | `quadratic_stiffness` | spring `k2·|u|·u` there, `k2 = 3π·ε1·k_ref/(8·A_ref)` |
//! | `preload_loss` | every contact element's stiffness and slip force × `(1 − λ·F̄/F_ref)` at a level of mean force `F̄` |
//! | `higher_harmonics` | harmonics up to 9 in the balance (default time sampling) |
//! | `out_of_band_modes` | residual receptance `ρ/k_ref` added to the response (modes outside the basis) |
//! | `shaker_interaction` | the measured force leads the force into the structure by `τ`, `Y·e^{−iωτ}` |
//!
//! with the parameters and bounds of the single mode ([`super::model::effect_params`]) and the
//! reference scales of the data ([`Scales`]: `A_ref` the largest peak response amplitude of the
//! fit levels, `F_ref` their largest mean force, `k_ref = m·(2π·f)²` from their equivalent
//! linear mode as seen at the response DOF). The baseline and every candidate are refitted by
//! Nelder–Mead only (each candidate from the current optimum with the effect at its neutral
//! value, so it never fits worse than the model without it): a swarm over a reduced model's box
//! costs thousands of harmonic-balance sweeps. The joint families are not candidates (the
//! contact laws come from the element tables), nor the amplitude-dependent damping laws (the
//! velocity-dependent element is defined on the single mode's coordinate). An accepted effect
//! is refitted with the factors on all rows of the fit levels, and the report gives the errors
//! of the factors-only update beside the final one: the error before and after the effect.
//!
//! # Report
//!
//! Every level's errors as given and updated (resonance, phase resonance, peak, RMS complex,
//! residual per region), the measurement scatter, the backbone as the equivalent linear mode
//! per level ([`backbone::equivalent_mode`]: the estimator the data's backbone uses, applied to
//! each model's response at the same rows) and the updated model's response-controlled FRF at
//! the measured peak responses.

use super::backbone::{self, BackbonePoint, LevelBackbone};
use super::effects::Effect;
use super::fit::{fit_global, fit_local, FitOptions, FitResult, LevelData, Parametrised};
use super::measured::{PhaseConvention, Sweep};
use super::model::check_values;
use super::model::{
    cubic_stiffness_law, effect_params, preload_factor_law, quadratic_stiffness_law, Scales,
};
use super::model::{solve_sweep, Drive, ParamSpec, RowFailure};
use super::model_free::{self, ModelFreeCheck};
use super::pipeline::{
    response_control_amplitudes, response_controlled_text, response_controlled_with,
    settled_first_rows, settled_rows_line, write_backbone_files, write_response_controlled_csv,
    FitRows, ResponseControlled,
};
use super::report::{
    errors_table, fine_curve_with, level_role, level_roles, plot_level, regions_text, write_json,
    write_rows_csv, CurveRow, InputFile, LevelErrors,
};
use super::select::{Extensible, SelectOptions, Selection};
use super::stationarity::{self, SideComparison};
use super::uncertainty::{self, Ensemble, Uncertainty};
use crate::core::error::{Error, Result};
use crate::core::hash::sha256_hex;
use crate::core::output::write_string_atomic;
use crate::dynamics::aft::Harmonics;
use crate::dynamics::contact::element_for;
use crate::dynamics::hbm::{Excitation, FormulationChoice, HbmSystem};
use crate::dynamics::model::Structure;
use crate::dynamics::model_file::{self, LoadedModel};
use crate::element::{CubicSpring, QuadraticSpring};
use nalgebra::{DMatrix, DVector};
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

/// Candidate effects the search offers a reduced model: the structure-level effects that act on
/// its response coordinate, the level or the measurement chain. The joint families are not
/// among them (the contact elements' laws come from the element tables), nor the
/// amplitude-dependent damping laws (velocity-dependent elements are defined on the single
/// mode's coordinate only).
pub const REDUCED_EFFECTS: [Effect; 6] = [
    Effect::AmplitudeStiffness,
    Effect::QuadraticStiffness,
    Effect::PreloadLoss,
    Effect::HigherHarmonics,
    Effect::OutOfBandModes,
    Effect::ShakerInteraction,
];

/// The reduced model of a response-model file, its updating parameters and the effects the
/// search added.
#[derive(Debug, Clone, Serialize)]
pub struct ReducedSpec {
    /// The response-model file as read: structure, excitation, observation and its input files.
    #[serde(skip)]
    pub loaded: Arc<LoadedModel>,
    /// Effects added to the file's model (in [`REDUCED_EFFECTS`]), in order; their parameters
    /// follow the four factors.
    pub effects: Vec<Effect>,
    /// Reference scales of the effects' dimensionless parameters, from the data as for the
    /// single mode: `A_ref` the largest peak response amplitude of the fit levels, `F_ref`
    /// their largest mean force, and the reference stiffness `k_ref = m·(2π·f)²` of the
    /// response coordinate from the fit levels' equivalent linear mode (modal mass and
    /// resonance frequency as seen at the response DOF). `None` before a search.
    pub scales: Option<Scales>,
}

impl PartialEq for ReducedSpec {
    fn eq(&self, other: &Self) -> bool {
        self.loaded.path == other.loaded.path
            && self.effects == other.effects
            && self.scales == other.scales
    }
}

impl Extensible for ReducedSpec {
    fn effects(&self) -> &[Effect] {
        &self.effects
    }
    fn with(&self, e: Effect) -> Self {
        let mut s = self.clone();
        s.effects.push(e);
        s
    }
    /// An effect of [`REDUCED_EFFECTS`] not yet added, when the scales are known.
    fn admits(&self, e: Effect) -> bool {
        self.scales.is_some() && REDUCED_EFFECTS.contains(&e) && !self.effects.contains(&e)
    }
    /// None of [`REDUCED_EFFECTS`] nests another.
    fn generalised(&self, _e: Effect, _values: &[f64]) -> Option<(Self, Vec<f64>)> {
        None
    }
    fn spec_of(model: &ReducedModel) -> &Self {
        &model.spec
    }
    fn joint_at_data_scales(&self, _values: &[f64]) -> Option<Vec<f64>> {
        None
    }
}

/// A reduced model with values of its updating factors.
#[derive(Debug, Clone, Serialize)]
pub struct ReducedModel {
    /// The model the values belong to.
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
            effects: Vec::new(),
            scales: None,
        })
    }

    /// This spec with the reference scales of the effects' parameters.
    pub fn with_scales(&self, scales: Scales) -> Self {
        Self {
            scales: Some(scales),
            ..self.clone()
        }
    }

    /// Reference stiffness `k_ref = m·(2π·f)²` of the response coordinate (N/m).
    fn reference_stiffness(&self) -> Option<f64> {
        self.scales
            .map(|s| s.modal_mass_kg * (TAU * s.frequency_hz).powi(2))
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
        let mut p = vec![
            ParamSpec::linear("frequency_factor", "-", flo, fhi, 1.0),
            ParamSpec::log("damping_factor", "-", lo, hi, 1.0),
            ParamSpec::log("contact_stiffness_factor", "-", lo, hi, 1.0),
            ParamSpec::log("friction_factor", "-", lo, hi, 1.0),
        ];
        if let Some(scales) = &self.scales {
            for &e in &self.effects {
                p.extend(effect_params(e, scales));
            }
        }
        p
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
        let (x, failures) = model.receptance_tolerant(&level.drives, level.mean_force_n, true)?;
        Ok((level.from_receptance(&x), failures.len()))
    }
}

impl ReducedModel {
    /// The model as the file gives it (every factor 1, no effect).
    pub fn as_given(spec: &ReducedSpec) -> Self {
        spec.model(vec![1.0; 4])
    }

    /// The value of a named parameter, if the model has it.
    fn get(&self, name: &str) -> Option<f64> {
        self.spec
            .params()
            .iter()
            .position(|p| p.name == name)
            .map(|i| self.values[i])
    }

    /// Factor on the contact elements' stiffness and slip force at a level of mean force
    /// `mean_force_n` (preload loss: `1 − λ·F̄/F_ref`, at least 0.05; 1 without it), the law
    /// of the single mode ([`super::model::Model::preload_factor`]).
    pub fn preload_factor(&self, mean_force_n: f64) -> f64 {
        match (self.get("preload_loss_per_ref_force"), self.spec.scales) {
            (Some(l), Some(s)) => preload_factor_law(l, mean_force_n, s.force_n),
            _ => 1.0,
        }
    }

    /// Cubic stiffness `k3 = 4·ε·k_ref/(3·A_ref²)` (N/m³) on the response coordinate: its
    /// describing-function stiffness `(3/4)·k3·A²` is `ε·k_ref` at the reference amplitude.
    pub fn cubic_stiffness(&self) -> Option<f64> {
        let eps = self.get("stiffness_change_at_ref_amplitude")?;
        let (k, s) = (self.spec.reference_stiffness()?, self.spec.scales?);
        Some(cubic_stiffness_law(eps, k, s.amplitude_max_m))
    }

    /// Quadratic stiffness `k2 = 3π·ε1·k_ref/(8·A_ref)` (N/m²) on the response coordinate:
    /// its describing-function stiffness `(8/3π)·k2·A` is `ε1·k_ref` at the reference amplitude.
    pub fn quadratic_stiffness(&self) -> Option<f64> {
        let eps = self.get("proportional_stiffness_change_at_ref_amplitude")?;
        let (k, s) = (self.spec.reference_stiffness()?, self.spec.scales?);
        Some(quadratic_stiffness_law(eps, k, s.amplitude_max_m))
    }

    /// Residual receptance `r = ρ/k_ref` (m/N) of the modes outside the model's basis.
    pub fn residual_receptance(&self) -> f64 {
        match (
            self.get("residual_flexibility_ratio"),
            self.spec.reference_stiffness(),
        ) {
            (Some(rho), Some(k)) => rho / k,
            _ => 0.0,
        }
    }

    /// Delay `τ` (s) between the measured force and the force into the structure.
    pub fn force_delay(&self) -> f64 {
        self.get("force_delay_s").unwrap_or(0.0)
    }

    /// The updated structure at a preload factor: `K·s_f²`, `C·s_ζ·s_f`, contact elements
    /// rebuilt from their table rows with `E0, Et, kn` × `s_k·φ` and `μ` × `s_μ·φ` (`φ` the
    /// preload factor, 1 without preload loss), and the springs of the stiffness effects on
    /// the response coordinate (to ground).
    pub fn structure(&self, preload: f64) -> Result<Structure> {
        let [sf, sz, sk, smu] = <[f64; 4]>::try_from(self.values.get(..4).unwrap_or(&[]))
            .map_err(|_| Error::param("values", "four updating factors expected"))?;
        let l = &self.spec.loaded;
        let mut s = l.structure.clone();
        s.stiffness *= sf * sf;
        s.damping *= sz * sf;
        for (att, (law, row)) in s.elements.iter_mut().zip(&l.element_rows) {
            let mut r = row.clone();
            r.element = r.element.scaled(sk * preload, smu * preload);
            att.element = element_for(*law, &r)?;
        }
        let map = DMatrix::from_row_slice(1, s.n(), l.responses[0].1.as_slice());
        if let Some(k3) = self.cubic_stiffness().filter(|&k| k != 0.0) {
            s.attach("cubic spring", Arc::new(CubicSpring { k3 }), map.clone())?;
        }
        if let Some(k2) = self.quadratic_stiffness().filter(|&k| k != 0.0) {
            s.attach("quadratic spring", Arc::new(QuadraticSpring { k2 }), map)?;
        }
        Ok(s)
    }

    /// Complex fundamental response per unit measured force (m/N, `e^{iωt}` convention) of the
    /// first response DOF at every drive, in order, warm-started along the list (the sweep
    /// order), at a level of mean force `mean_force_n` (preload loss); the residual receptance
    /// and the force delay applied to the result. With `tolerant`, a row that fails is
    /// recorded (NaN) instead of ending the evaluation.
    pub fn receptance_tolerant(
        &self,
        drives: &[Drive],
        mean_force_n: f64,
        tolerant: bool,
    ) -> Result<(Vec<Complex64>, Vec<RowFailure>)> {
        let s = self.structure(self.preload_factor(mean_force_n))?;
        let sys = self.system(&s, self.spec.loaded.file.sweep.formulation)?;
        let (r, tau) = (self.residual_receptance(), self.force_delay());
        solve_sweep(drives, tolerant, |d, warm| {
            let p = solve_robust(&sys, d, warm)?;
            let x = self.observed(&sys.harmonics, &sys.coordinates(&p)) / d.force_n;
            Ok((measured_chain(x, d.omega, r, tau), p.z))
        })
    }

    /// The harmonic-balance system of the updated structure `s`: the file's excitation (one
    /// newton per unit level, fundamental), harmonics and time samples (harmonics up to 9 and
    /// the default sampling with the higher-harmonics effect).
    fn system<'a>(
        &self,
        s: &'a Structure,
        formulation: FormulationChoice,
    ) -> Result<HbmSystem<'a>> {
        let l = &self.spec.loaded;
        let sw = &l.file.sweep;
        let harmonics = if self.spec.effects.contains(&Effect::HigherHarmonics) {
            Harmonics::new(sw.harmonics.max(9), sw.odd_only, None)?
        } else {
            Harmonics::new(sw.harmonics, sw.odd_only, sw.time_samples)?
        };
        HbmSystem::new(
            s,
            harmonics,
            Excitation {
                force: l.force.clone(),
                harmonic: 1,
                force_sin: None,
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

    /// Response-controlled evaluation at a level of mean force `mean_force_n` (preload loss):
    /// at each frequency, the force that holds the amplitude of the fundamental response at
    /// `target_m[i]` (m, first response DOF), and the complex response per unit measured force
    /// there (coordinates formulation, warm-started along the sweep). With a residual receptance
    /// `r` the held amplitude is the measured one, `|x + r·F|`: the structure's target is
    /// corrected by fixed-point iteration (as for the single mode). Returns
    /// `(force amplitudes (N), receptances (m/N))`.
    pub fn response_controlled(
        &self,
        omegas: &[f64],
        target_m: &[f64],
        mean_force_n: f64,
    ) -> Result<(Vec<f64>, Vec<Complex64>)> {
        let s = self.structure(self.preload_factor(mean_force_n))?;
        let sys = self.system(&s, FormulationChoice::Coordinates)?;
        let obs = &self.spec.loaded.responses[0].1;
        let (r, tau) = (self.residual_receptance(), self.force_delay());
        let (mut forces, mut recs) = (Vec::new(), Vec::new());
        let mut guess: Option<(DVector<f64>, f64)> = None;
        for (&w, &target) in omegas.iter().zip(target_m) {
            let mut structural = target;
            let (mut point, mut error) = (None, f64::NAN);
            for _ in 0..RESIDUAL_TARGET_ITERATIONS {
                let p = sys.solve_response_controlled(
                    w,
                    structural,
                    obs,
                    guess.as_ref().map(|(z, f)| (z, *f)),
                )?;
                let x = self.observed(&sys.harmonics, &p.z) / p.level;
                let held = (x + r).norm() * p.level;
                error = (held / target - 1.0).abs();
                guess = Some((p.z.clone(), p.level));
                if r == 0.0 || error < RESIDUAL_TARGET_TOLERANCE {
                    point = Some((p.level, x));
                    break;
                }
                structural *= target / held;
            }
            let Some((f, x)) = point else {
                return Err(Error::NonConvergence {
                    solver: format!(
                        "response control of {} at {:.4} Hz with the residual receptance \
                         (fixed point on the structure's amplitude)",
                        self.spec.path().display(),
                        w / TAU
                    ),
                    iterations: RESIDUAL_TARGET_ITERATIONS,
                    residual: error,
                    tolerance: RESIDUAL_TARGET_TOLERANCE,
                });
            };
            forces.push(f);
            recs.push(measured_chain(x, w, r, tau));
        }
        Ok((forces, recs))
    }
}

/// Fixed-point iterations of the response-controlled target under a residual receptance (it
/// converges geometrically at the ratio `|r|·F/|x|`, small away from antiresonances).
const RESIDUAL_TARGET_ITERATIONS: usize = 30;

/// Relative tolerance on the held (measured) amplitude under a residual receptance.
const RESIDUAL_TARGET_TOLERANCE: f64 = 1e-10;

/// The response per unit measured force from the structure's `x` (m/N): the residual
/// receptance `r` added and the force delayed by `τ`, `(x + r)·e^{−iωτ}`.
fn measured_chain(x: Complex64, omega: f64, r: f64, tau: f64) -> Complex64 {
    (x + r) * Complex64::from_polar(1.0, -omega * tau)
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

/// A fit that stopped on its iteration cap is an error naming the model file.
fn require_converged(spec: &ReducedSpec, fit: &FitResult<ReducedModel>, what: &str) -> Result<()> {
    if fit.converged {
        return Ok(());
    }
    Err(Error::NonConvergence {
        solver: format!(
            "{what} ({}, Nelder–Mead restarted from its optimum up to {} times)",
            spec.path().display(),
            super::fit::LOCAL_RESTARTS
        ),
        iterations: fit.starts.iter().map(|s| s.local_iterations as usize).sum(),
        residual: fit.cost,
        tolerance: 1e-7 * fit.cost,
    })
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
    /// The response-model file that was updated.
    pub model_file: PathBuf,
    /// SHA-256 of the response-model file (hex).
    pub model_sha256: String,
    /// The measured sweeps, by increasing mean force.
    pub inputs: Vec<InputFile>,
    /// The measurements' phase convention, as described in the report.
    pub phase_convention: String,
    /// 0-based fit levels (by increasing mean force).
    pub fit_levels: Vec<usize>,
    /// Name, unit and bounds of every parameter (the four factors, then the effects').
    #[serde(serialize_with = "super::model::serialize_params")]
    pub parameters: Vec<ParamSpec>,
    /// The final update on all rows of the fit levels: the four factors and the effects the
    /// search accepted.
    pub fit: FitResult<ReducedModel>,
    /// The effect search, run when the update by the four factors alone stays above the
    /// measurement scatter.
    pub effect_search: EffectSearch,
    /// The update by the four factors alone on all rows, and its errors per level, when the
    /// search accepted effects (the error before and after the effects).
    pub factors_only: Option<(FitResult<ReducedModel>, Vec<LevelErrors>)>,
    /// Errors of the model as given (every factor 1) and of the final updated model, per level.
    pub errors_before: Vec<LevelErrors>,
    /// Per level: errors of the final updated model.
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
    #[serde(serialize_with = "super::report::available_or_reason")]
    pub data_backbone: std::result::Result<Vec<LevelBackbone>, String>,
    /// The fit levels' own backbone interpolated in a single-nonlinear-mode response, no model
    /// ([`super::model_free`]): what the data alone predict for every level, or why not.
    #[serde(serialize_with = "super::report::available_or_reason")]
    pub model_free: std::result::Result<ModelFreeCheck, String>,
    /// Per level: its two sides at equal amplitude ([`super::stationarity`]; `None` where they
    /// have too few points at common amplitudes), or why the data's backbone is not available.
    #[serde(serialize_with = "super::report::available_or_reason")]
    pub stationarity: std::result::Result<Vec<Option<SideComparison>>, String>,
    /// Per fit level: the first row fitted when only its settled rows were
    /// ([`FitRows::Settled`] on a level that is not stationary), `None` where every row was.
    pub settled_from: Vec<Option<usize>>,
    /// When a fit level's sides differ: the model-free check on the settled rows (the earlier
    /// side of such levels left out), or why it could not be made.
    #[serde(serialize_with = "super::report::optional_available_or_reason")]
    pub model_free_settled: Option<std::result::Result<ModelFreeCheck, String>>,
    /// Per level: the equivalent linear mode of the model's response at the level's rows, as
    /// given and updated (`None`: no resonance inside the measured band).
    pub backbone_before: Vec<Option<BackbonePoint>>,
    /// Per level: the same for the updated model.
    pub backbone_after: Vec<Option<BackbonePoint>>,
    /// The updated model under response control at the measured peak responses (or the given
    /// amplitudes), and the amplitudes where that solve failed, with the reason.
    pub response_controlled: Vec<ResponseControlled>,
    /// Response amplitudes (unit of the lowest level's quantity) whose response-controlled solve
    /// failed, with the reason.
    pub response_control_failures: Vec<(f64, String)>,
    /// Parameter intervals and 95 % bands of the updated model's predictions.
    pub uncertainty: Uncertainty,
    /// The settings the update ran with.
    pub options: ReducedOptions,
    /// Wall-clock time of the whole update (s).
    pub wall_time_s: f64,
    /// The measured levels (by increasing mean force), kept for the files.
    #[serde(skip)]
    pub levels: Vec<LevelData>,
    /// Responses per unit force of the model as given and updated at every level's rows (the
    /// level's quantity), kept for the files.
    #[serde(skip)]
    pub responses_before: Vec<Vec<Complex64>>,
    /// Responses per unit force of the updated model at every level's rows.
    #[serde(skip)]
    pub responses_after: Vec<Vec<Complex64>>,
    /// Phase convention of the measurements, for writing the files in it.
    #[serde(skip)]
    pub convention: PhaseConvention,
    /// The model as given (every factor 1).
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
    /// Settings of the updates' fits (swarm starts, Nelder–Mead tolerance and iterations).
    pub fit: FitOptions,
    /// Response amplitudes (unit of the lowest level's quantity) of the response-controlled
    /// FRFs; `None`: the measured peak responses.
    pub response_amplitudes: Option<Vec<f64>>,
    /// Steps of each Metropolis chain of the prediction bands (0: no bands); `None`: the
    /// default [`uncertainty::CHAIN_STEPS`] when the bands are expected to take at most
    /// [`BAND_BUDGET_S`], none otherwise (the report says why).
    pub chain_steps: Option<usize>,
    /// Candidate effects of the search (of [`REDUCED_EFFECTS`]; empty: no search); `None`:
    /// all of them when the search is expected to take at most [`BAND_BUDGET_S`], none
    /// otherwise (the report says why).
    pub candidates: Option<Vec<Effect>>,
    /// Most effects the search adds.
    pub max_effects: usize,
    /// Rows of the fit levels to fit (every row, or the settled rows of a level that is not
    /// stationary).
    pub rows: FitRows,
}

impl ReducedOptions {
    /// Default settings around a fit's: the default candidates, up to three effects (as for
    /// the single mode).
    pub fn new(fit: FitOptions) -> Self {
        Self {
            fit,
            response_amplitudes: None,
            chain_steps: None,
            candidates: None,
            max_effects: 3,
            rows: FitRows::All,
        }
    }

    /// The search's settings: the baseline refitted on the training rows by Nelder–Mead from
    /// the update on all rows, each candidate by Nelder–Mead from there with the effect
    /// neutral (every candidate of [`REDUCED_EFFECTS`] has a neutral value, so no swarm is
    /// needed for a candidate never to fit worse than the model without it; a swarm over a
    /// reduced model's box costs thousands of harmonic-balance sweeps).
    fn select_options(&self, candidates: Vec<Effect>) -> SelectOptions {
        let local = FitOptions {
            starts: 0,
            ..self.fit
        };
        SelectOptions {
            candidates,
            max_effects: self.max_effects,
            baseline_fit: local,
            candidate_fit: local,
            training_rows_only: false,
            joint_restart: false,
            refine: None,
        }
    }
}

/// The effect search of a reduced-model update.
#[derive(Debug, Clone, Serialize)]
#[serde(rename_all = "snake_case", tag = "status")]
pub enum EffectSearch {
    /// The update alone fits to the measurement scatter (on all rows of the fit levels):
    /// nothing is left for an effect to explain.
    NotNeeded,
    /// Not run, and why (no candidates, or no reference scales from the data).
    NotRun {
        /// Why the search was not run.
        reason: String,
    },
    /// Run on the fit levels' training and held-out rows ([`super::select`]).
    Run(Box<Selection<ReducedSpec>>),
}

/// Wall time (s) the prediction bands of a reduced model may be expected to take before the
/// default leaves them out: every evaluation of a large model costs seconds, and the chains
/// need thousands.
pub const BAND_BUDGET_S: f64 = 600.0;

/// Model evaluations one Nelder–Mead refit of the search is expected to take (300–420 per fit
/// on the two-mode test model, five parameters).
pub const SEARCH_EVALUATIONS_PER_FIT: f64 = 400.0;

/// Nelder–Mead refits of a search over `candidates` effects adding up to `max_effects`: the
/// baseline on the training rows, every candidate in each round, the final refit on all rows.
fn search_fits(candidates: usize, max_effects: usize) -> usize {
    2 + max_effects.max(1) * candidates
}

/// Model evaluations a search is expected to take (the progress bar's extension).
fn search_evaluations(candidates: usize, max_effects: usize) -> u64 {
    (search_fits(candidates, max_effects) as f64 * SEARCH_EVALUATIONS_PER_FIT) as u64
}

/// The search's candidates: the explicit ones, or by default all of [`REDUCED_EFFECTS`] when the
/// search's refits (`search_fits`: the baseline, every candidate in each of up to
/// `max_effects` rounds and the final refit, at
/// [`SEARCH_EVALUATIONS_PER_FIT`] evaluations each) are expected to take at most
/// [`BAND_BUDGET_S`] at `per_evaluation_s()` per evaluation of the fit levels (timed only for
/// the default); otherwise why not.
pub fn search_candidates(
    explicit: Option<&[Effect]>,
    max_effects: usize,
    per_evaluation_s: impl FnOnce() -> f64,
) -> std::result::Result<Vec<Effect>, String> {
    if let Some(c) = explicit {
        return if c.is_empty() {
            Err("no candidate effects given (--candidates none)".into())
        } else {
            Ok(c.to_vec())
        };
    }
    let per_evaluation_s = per_evaluation_s();
    let fits = search_fits(REDUCED_EFFECTS.len(), max_effects);
    let expected = fits as f64 * SEARCH_EVALUATIONS_PER_FIT * per_evaluation_s;
    if expected <= BAND_BUDGET_S {
        Ok(REDUCED_EFFECTS.to_vec())
    } else {
        Err(format!(
            "left out by default: about {:.1} h expected ({fits} Nelder–Mead refits of about {:.0} \
             evaluations, {:.2} s per evaluation of the fit levels); --candidates <ids> runs it",
            expected / 3600.0,
            SEARCH_EVALUATIONS_PER_FIT,
            per_evaluation_s
        ))
    }
}

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
    let convention = PhaseConvention::detect_common(&sweeps)?;
    let levels: Vec<LevelData> = sweeps
        .iter()
        .map(|s| LevelData::new(s, &convention))
        .collect();
    let frfs: Vec<Vec<Complex64>> = sweeps.iter().map(|s| s.frf(&convention)).collect();
    let data_backbone = backbone::from_data(&sweeps, &frfs).map_err(|e| e.to_string());
    let stationarity = data_backbone
        .as_ref()
        .map(|b| stationarity::compare_levels(b, &levels))
        .map_err(Clone::clone);
    // A level whose sides could not be compared keeps its rows.
    let settled_from = match (&data_backbone, &stationarity) {
        (Ok(b), Ok(sides)) => settled_first_rows(&fit_levels, sides, b, options.rows),
        _ => vec![None; fit_levels.len()],
    };
    let fit_data: Vec<LevelData> = fit_levels
        .iter()
        .zip(&settled_from)
        .map(|(&i, first)| first.map_or_else(|| levels[i].clone(), |r| levels[i].from_row(r)))
        .collect();
    let masks: Vec<Vec<bool>> = fit_data
        .iter()
        .map(|l| vec![true; l.drives.len()])
        .collect();
    // One Nelder–Mead start from the model as given (the prediction being updated is the
    // natural first guess) and the swarm's starts, if any; the best is kept. Without swarm
    // starts the update is local: the choice for large models, whose every evaluation costs
    // seconds (docs/identify.md).
    let local = fit_local(spec, &fit_data, &masks, &[vec![1.0; 4]], opts, progress)?;
    let factors_fit = if opts.starts == 0 {
        local
    } else {
        merge_fits(fit_global(spec, &fit_data, &masks, opts, progress)?, local)
    };
    require_converged(spec, &factors_fit, "reduced-model update")?;
    let scatter_floor = super::select::scatter_floor(&fit_data);
    // The effect search, when the four factors leave a residual above the scatter: the
    // single mode's search ([`super::select`]) on the family of this file's model with the
    // reference scales of the data.
    let effect_search = if factors_fit.cost <= super::select::SCATTER_FACTOR * scatter_floor {
        EffectSearch::NotNeeded
    } else {
        let candidates =
            search_candidates(options.candidates.as_deref(), options.max_effects, || {
                let t0 = std::time::Instant::now();
                super::select::cost_all_rows(spec, &factors_fit.model, &fit_data);
                t0.elapsed().as_secs_f64()
            });
        match (candidates, &data_backbone) {
            (Err(reason), _) => EffectSearch::NotRun { reason },
            (Ok(_), Err(reason)) => EffectSearch::NotRun {
                reason: format!(
                    "the effects' reference scales come from the data's equivalent linear mode, \
                     which could not be estimated: {reason}"
                ),
            },
            (Ok(candidates), Ok(bb)) => {
                if let Some(bar) = progress {
                    bar.inc_length(search_evaluations(candidates.len(), options.max_effects));
                }
                let scales = super::pipeline::scales_from(&sweeps, &fit_levels, bb);
                EffectSearch::Run(Box::new(super::select::select(
                    &spec.with_scales(scales),
                    std::slice::from_ref(&factors_fit.model.values),
                    &fit_data,
                    &options.select_options(candidates),
                    progress,
                )?))
            }
        }
    };
    let (fit, factors_only) = match &effect_search {
        EffectSearch::Run(sel) if !sel.final_spec.effects.is_empty() => {
            let fit = super::select::refit_all_rows::<ReducedSpec>(
                &sel.final_train_fit,
                &fit_data,
                opts,
                progress,
            )?;
            let ids: Vec<&str> = sel.final_spec.effects.iter().map(|e| e.id()).collect();
            require_converged(
                spec,
                &fit,
                &format!("reduced-model update with {}", ids.join(" + ")),
            )?;
            let (_, errors) = responses_and_errors(&factors_fit.model, &levels, &fit_levels)?;
            (fit, Some((factors_fit, errors)))
        }
        _ => (factors_fit, None),
    };
    let (responses_after, errors_after) = responses_and_errors(&fit.model, &levels, &fit_levels)?;
    for (l, y) in levels.iter().zip(&responses_after) {
        if let Some(k) = y.iter().position(|v| !v.re.is_finite()) {
            return Err(Error::Data(format!(
                "{}:{}: the updated model has no harmonic-balance solution at this row",
                l.name, l.lines[k]
            )));
        }
    }
    let model_free = model_free::check(&sweeps, &frfs, &levels, &fit_levels, &errors_after)
        .map_err(|e| e.to_string());
    let model_free_settled = stationarity.as_ref().ok().and_then(|sides| {
        model_free::check_settled(&sweeps, &frfs, &levels, &fit_levels, &errors_after, sides)
    });
    let before = ReducedModel::as_given(spec);
    let (responses_before, errors_before) = responses_and_errors(&before, &levels, &fit_levels)?;
    let scatter = fit_data
        .iter()
        .map(super::select::relative_scatter)
        .collect();
    let at_scatter = fit.cost <= super::select::SCATTER_FACTOR * scatter_floor;
    let roles = level_roles(levels.len(), &fit_levels);
    let uncertainty = match band_chain_steps(
        &fit.model.spec,
        &fit.model,
        &fit_data,
        levels.len(),
        options.chain_steps,
    ) {
        Ok(steps) => uncertainty::estimate(
            &fit.model.spec,
            &fit.model,
            &fit_data,
            &levels,
            &roles,
            steps,
            None,
        ),
        Err(reason) => Uncertainty::NotEstimated { reason },
    };
    let backbone_before = model_modes(&levels, &responses_before);
    let backbone_after = model_modes(&levels, &responses_after);
    let quantity = sweeps[0].quantity;
    let (amplitudes, band) = response_control_amplitudes(&sweeps, response_amplitudes);
    let reference_force = fit_data.iter().map(|l| l.mean_force_n).fold(0.0, f64::max);
    let (mut response_controlled, mut response_control_failures) = (Vec::new(), Vec::new());
    for a in amplitudes {
        crate::core::error::require_positive("--response-amplitude", a)?;
        match response_controlled_with(quantity, a, band, |om, targets| {
            fit.model.response_controlled(om, targets, reference_force)
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
        parameters: fit.model.spec.params(),
        fit,
        effect_search,
        factors_only,
        errors_before,
        errors_after,
        scatter,
        scatter_floor,
        at_scatter,
        uncertainty,
        stationarity,
        settled_from,
        model_free_settled,
        data_backbone,
        model_free,
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
#[serde(deny_unknown_fields)]
pub struct SavedReducedModel {
    /// Kind tag, always [`REDUCED_KIND`].
    pub kind: String,
    /// Absolute path of the response-model file.
    pub model_file: PathBuf,
    /// SHA-256 of the response-model file (hex); a file changed since is refused.
    pub model_sha256: String,
    /// `(name, value)` of every parameter: the four updating factors, then the effects'.
    pub factors: Vec<(String, f64)>,
    /// Effects the search added (absent in files written before the search existed).
    #[serde(default)]
    pub effects: Vec<Effect>,
    /// Reference scales of the effects' parameters.
    #[serde(default)]
    pub scales: Option<Scales>,
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
        s.phase_convention
            .check()
            .map_err(|e| Error::parse(path, 0, format!("phase_convention.{e}")))?;
        if let Some(scales) = &s.scales {
            scales
                .check()
                .map_err(|e| Error::parse(path, 0, format!("scales.{e}")))?;
        }
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
        let mut spec = ReducedSpec::load(&s.model_file)?;
        if let Some(e) = s.effects.iter().find(|e| !REDUCED_EFFECTS.contains(e)) {
            return Err(Error::parse(
                path,
                0,
                format!("effect {} is not one a reduced model takes", e.id()),
            ));
        }
        if !s.effects.is_empty() && s.scales.is_none() {
            return Err(Error::parse(
                path,
                0,
                "effects without the reference scales of their parameters",
            ));
        }
        spec.effects = s.effects.clone();
        spec.scales = s.scales;
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
        for (&i, first) in self.fit_levels.iter().zip(&self.settled_from) {
            if let Some(r) = *first {
                let l = &self.levels[i];
                s += &settled_rows_line(
                    i,
                    l.lines[r],
                    l.drives[r].omega / TAU,
                    l.drives.len() - r,
                    l.drives.len(),
                );
            }
        }
        if self.options.rows == FitRows::Settled {
            if let Err(why) = &self.stationarity {
                s += &format!(
                    "fit rows (--rows settled): every row fitted: the levels' sides could not be \
                     compared: {why}\n"
                );
            }
        }
        s += "\nupdating factors (1 = the model as given) and effects' parameters:\n";
        for (p, v) in self.parameters.iter().zip(&self.fit.model.values) {
            s += &format!(
                "  {:<46} {:>11.5e} {:<3}  bounds [{:.4e}, {:.4e}]{}\n",
                p.name,
                v,
                p.unit,
                p.lo,
                p.hi,
                if super::model::at_bound(p, *v) {
                    "  AT BOUND"
                } else {
                    ""
                }
            );
        }
        s += &format!(
            "objective J = {:.4e} ({} model evaluations, {} starts, converged: {})\n",
            self.fit.cost,
            self.fit.evaluations,
            self.fit.starts.len(),
            self.fit.converged
        );
        s += &self.effect_search_text();
        let rows: Vec<(&LevelErrors, Option<&LevelErrors>)> = self
            .errors_before
            .iter()
            .zip(&self.errors_after)
            .map(|(b, a)| (b, Some(a)))
            .collect();
        s += &errors_table("errors, model as given → updated", &rows);
        if let Some((f, errors)) = &self.factors_only {
            let rows: Vec<(&LevelErrors, Option<&LevelErrors>)> = errors
                .iter()
                .zip(&self.errors_after)
                .map(|(b, a)| (b, Some(a)))
                .collect();
            s += &errors_table(
                &format!(
                    "errors, updated by the four factors alone (J = {:.4e}) → with the effects \
                     (J = {:.4e}): the error before and after the effects",
                    f.cost, self.fit.cost
                ),
                &rows,
            );
        }
        s += &model_free::section(&self.model_free, &self.errors_after);
        match &self.stationarity {
            Ok(c) => s += &stationarity::levels_section(c, &self.fit_levels),
            Err(why) => s += &format!("\nstationarity not checked: {why}\n"),
        }
        if let Some(settled) = &self.model_free_settled {
            s += &model_free::section(settled, &self.errors_after);
        }
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

    /// The effect search's part of the report: its rounds and verdict, or why it did not run.
    fn effect_search_text(&self) -> String {
        match &self.effect_search {
            EffectSearch::NotNeeded => "effect search: not needed (the four factors fit the fit \
                                        levels to the measurement scatter)\n\n"
                .into(),
            EffectSearch::NotRun { reason } => format!("effect search: not run: {reason}\n\n"),
            EffectSearch::Run(sel) => {
                let mut s = format!(
                    "effect search (the four factors leave a residual above the scatter; \
                     candidates on held-out rows, ΔBIC < {:.0} and every fit level better):\n\
                     baseline refitted on the training rows: J = {:.4e}\n",
                    super::select::BIC_THRESHOLD,
                    sel.baseline_train_fit.cost
                );
                s += &super::pipeline::rounds_text(&sel.rounds);
                s += &format!(
                    "\nverdict: {}\n\n",
                    super::pipeline::verdict_text(&sel.verdict)
                );
                s
            }
        }
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
            effects: self.fit.model.spec.effects.clone(),
            scales: self.fit.model.spec.scales,
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
                    m.receptance_tolerant(drives, l.mean_force_n, true)
                        .map(|(x, _)| x)
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
        written.extend(write_backbone_files(
            dir,
            data,
            [
                (
                    "as-given-model",
                    "as given (equivalent mode per level)",
                    before,
                ),
                (
                    "updated-model",
                    "updated (equivalent mode per level)",
                    after,
                ),
            ],
            &self.model_free,
        )?);
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

    /// The default search runs on the two-mode test model (14 ms per evaluation of two levels:
    /// 20 refits × 400 evaluations, about 112 s) and is left out at the blade–damper example's
    /// 6.3 s (about 14.0 h), with the time in the reason; explicit candidates run regardless,
    /// `--candidates none` not at all.
    #[test]
    fn default_search_follows_the_cost_of_an_evaluation() {
        assert_eq!(
            search_candidates(None, 3, || 0.014),
            Ok(REDUCED_EFFECTS.to_vec())
        );
        let why = search_candidates(None, 3, || 6.3).unwrap_err();
        assert!(
            why.contains("14.0 h") && why.contains("--candidates"),
            "{why}"
        );
        assert_eq!(
            search_candidates(Some(&[Effect::PreloadLoss]), 3, || unreachable!()),
            Ok(vec![Effect::PreloadLoss])
        );
        assert!(search_candidates(Some(&[]), 3, || unreachable!()).is_err());
    }

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
