//! Fitting, effect selection and the verdict, with every residual measured against the noise
//! floor of the data ([`super::noise`]).
//!
//! 1. The complete cycles are split alternately into a training set (cycles 0, 2, 4, …) and a
//!    held-out set (1, 3, 5, …). The model is always driven by the whole displacement history
//!    (the element has memory) but parameters are fitted on training samples only (least squares,
//!    Nelder–Mead in bounded variables, restarted once from its optimum).
//! 2. Each candidate effect not yet in the model is added and the model refitted. On the
//!    held-out samples `H` it is scored against the current model (`f_old → f_new`) by the
//!    reduction of the residual sum of squares `ΔRSS = Σ_H (y − f_old)² − (y − f_new)²`:
//!    - **evidence** `z = ΔRSS / (2σ·√(κ·Σ_H (f_new − f_old)²))`. The held-out noise is
//!      independent of the fitted parameters, so under "the effect changes nothing real" the
//!      only random part of `ΔRSS` is `2Σ(f_new − f_old)·noise`, whose standard deviation is
//!      the denominator (σ the noise floor, κ = (1+ρ)/(1−ρ) the variance inflation of the
//!      noise's own lag-1 autocorrelation ρ). Required: `z ≥ 5`.
//!    - **relevance**: the effect must explain at least a quarter of the *excess* held-out
//!      residual, `ΔRSS ≥ 0.25·(RSS_old − n_H σ²)` (no condition when the current model is
//!      already at the floor).
//!    - **consistency**: the residual falls in every held-out cycle.
//!    - **physical parameters**: none of its parameters on a bound ([`super::effects`]).
//!    - **signature in the data**: a clearance (backlash) only where the measured force itself
//!      shows zero-force plateaus in at least half of the half-cycles
//!      ([`super::residual::clearance_regions`], model-free). Without this check a gap of
//!      2 µm in a 1 mm stroke was "found" in an Iwan loop, where it only bent the reversals.
//!
//!    Why not a `ΔBIC` with `n_eff` from the residual's lag-1 autocorrelation: a
//!    systematic misfit is smooth, so its residual has ρ → 1 and `n_eff = n(1−ρ)/(1+ρ)` falls
//!    to a few dozen: a model missing half of the physics made every candidate look
//!    insignificant and the answer read "no effect needed". That autocorrelation is the
//!    signature of the misfit, not of the noise; the noise's correlation is a property of the
//!    data and is estimated from the data alone.
//! 3. The eligible candidate with the largest `ΔRSS` is accepted and the search repeats for a
//!    further effect, up to `max_effects`, as long as the model is not yet adequate (below):
//!    once the residual is at the noise floor, what a further candidate could "explain" is as
//!    likely the baseline's own shape error as a physical effect (measured on the project's
//!    BEM loops of a rough patch: without this stop, a static friction peak and viscous
//!    damping were "found" in a quasi-static Coulomb contact).
//! 4. **Verdict** from the held-out residual of the final model: it is *adequate* when its
//!    RMS is at most 2σ overall **and** in every phase of the loop (stick, microslip,
//!    macroslip, clearance, closing; the reversal phase only overall, see [`Character`]) that
//!    holds at least 5 % of the held-out samples (a misfit concentrated in microslip is not
//!    diluted by a long macroslip); then *effects found* (if any were accepted) or *model
//!    adequate* (no effect larger than about 2σ RMS was looked for) — unless the noise floor
//!    is the two-cycle first-difference fallback ([`NoiseFloor::from_first_differences`]), in
//!    which a drift inflates σ: then *record too short* (noise and drift cannot be told
//!    apart). Otherwise *model inadequate, residual unexplained*, with where
//!    the residual sits, whether it rings, and the drift findings ([`super::residual`],
//!    [`super::stationarity`]). No verdict says that no effect is needed while the residual is
//!    above twice the noise floor.
//! 5. **Swapped split** ([`SwappedSplit`]): the held-out cycles chose the effects, so their
//!    "after" residual is the one the selection optimised; the baseline and the final structure
//!    are refitted on the held-out cycles and scored on the training cycles, which compared no
//!    candidates, and the report says so where less than a quarter of the gain carries over.

use super::cycles::{segment, Cycles, Phase};
use super::effects::{
    at_bound, linear_param, log_param, Baseline, Bound, Drive, Effect, Model, ParamSpec,
};
use super::noise::{self, NoiseFloor};
use super::record::Record;
use super::residual::{self, ClearanceRegion, PhaseStats, Ringing};
use super::stationarity::Stationarity;
use crate::core::error::{Error, Result};
use crate::core::fit::{self as core_fit, LocalSearch, Restarts, Tolerance};
use crate::core::stats::percentile_nearest;
use crate::element::valanis::ValanisParams;
use rayon::prelude::*;
use serde::Serialize;

/// Evidence threshold on the held-out improvement, in standard deviations of its noise.
pub const EVIDENCE_Z: f64 = 5.0;
/// Smallest share of the excess held-out residual an accepted effect must explain.
pub const MIN_EXPLAINED: f64 = 0.25;
/// A model is adequate when its held-out RMS residual is at most this multiple of the noise
/// floor.
pub const ADEQUATE_RATIO: f64 = 2.0;
/// A phase holding at least this share of the held-out samples counts in the adequacy rule.
pub const MIN_PHASE_SHARE: f64 = 0.05;
/// Records are block-averaged to at most this many samples per cycle before fitting.
pub const SAMPLES_PER_CYCLE: usize = 400;

/// Where the baseline element comes from.
#[derive(Debug, Clone)]
pub enum BaselineSource {
    /// Fit `E0`, `k` and the slip force `μN̄` to the training cycles (`Et = 0`).
    Fitted,
    /// Use a given element (e.g. from a calibration table) unchanged.
    Given(Baseline),
}

/// Options of the analysis.
#[derive(Debug, Clone)]
pub struct Options {
    /// Where the baseline element comes from: fitted to the training cycles, or given.
    pub baseline: BaselineSource,
    /// Candidate effects to test.
    pub candidates: Vec<Effect>,
    /// Maximum number of effects added (0: baseline only).
    pub max_effects: usize,
    /// Maximum Nelder–Mead iterations per fit.
    pub max_iterations: u64,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            baseline: BaselineSource::Fitted,
            candidates: Effect::ALL.to_vec(),
            max_effects: 2,
            max_iterations: 600,
        }
    }
}

/// A record prepared for analysis: decimated, segmented, with train / held-out masks and its
/// noise floor.
#[derive(Debug, Clone)]
pub struct Prepared {
    /// The (block-averaged) record that is analysed.
    pub record: Record,
    /// Block-averaging factor applied to the input record.
    pub decimation: usize,
    /// The record's complete cycles, their mean period and amplitude.
    pub cycles: Cycles,
    /// The simulation inputs derived from the record (drive displacement, velocity, phase, scales).
    pub drive: Drive,
    /// Samples of training cycles.
    pub train: Vec<bool>,
    /// Samples of held-out cycles.
    pub held_out: Vec<bool>,
    /// Noise floor of the analysed force.
    pub noise: NoiseFloor,
    /// Measured force smoothed like the drive (Savitzky–Golay over 1/64 of a cycle) (N).
    pub smooth_force_n: Vec<f64>,
}

fn block_average(x: &[f64], m: usize) -> Vec<f64> {
    x.chunks_exact(m)
        .map(|c| c.iter().sum::<f64>() / m as f64)
        .collect()
}

/// Savitzky–Golay (1964) local quadratic fit over `2h + 1` samples: smoothed value and first
/// derivative per unit sample index, `Σ c_j x_{i+j}` with
/// `c_j = 3(3h² + 3h − 1 − 5j²)/((2h − 1)(2h + 1)(2h + 3))` and `d_j = 3j/(h(h + 1)(2h + 1))`.
/// Within `h` samples of the ends the raw value and a one-sided or central difference are kept.
fn savitzky_golay(x: &[f64], h: usize) -> (Vec<f64>, Vec<f64>) {
    let n = x.len();
    let hf = h as f64;
    let norm_s = (2.0 * hf - 1.0) * (2.0 * hf + 1.0) * (2.0 * hf + 3.0);
    let norm_d = hf * (hf + 1.0) * (2.0 * hf + 1.0);
    let mut smooth = x.to_vec();
    let mut deriv: Vec<f64> = (0..n)
        .map(|i| {
            let (a, b) = (i.saturating_sub(1), (i + 1).min(n - 1));
            (x[b] - x[a]) / (b - a).max(1) as f64
        })
        .collect();
    if n > 2 * h {
        for i in h..n - h {
            let (mut sv, mut dv) = (0.0, 0.0);
            for j in -(h as i64)..=(h as i64) {
                let v = x[(i as i64 + j) as usize];
                let jf = j as f64;
                sv += 3.0 * (3.0 * hf * hf + 3.0 * hf - 1.0 - 5.0 * jf * jf) * v;
                dv += 3.0 * jf * v;
            }
            smooth[i] = sv / norm_s;
            deriv[i] = dv / norm_d;
        }
    }
    (smooth, deriv)
}

/// Segment, decimate and split a record; build the drive of the simulations.
pub fn prepare(record: &Record) -> Result<Prepared> {
    let full = segment(&record.time_s, &record.displacement_m)?;
    let in_cycles = full.cycles.last().map_or(0, |c| c.1) - full.cycles[0].0;
    let per_cycle = in_cycles / full.cycles.len();
    let m = per_cycle.div_ceil(SAMPLES_PER_CYCLE).max(1);
    let record = if m > 1 {
        Record::new(
            block_average(&record.time_s, m),
            block_average(&record.displacement_m, m),
            block_average(&record.force_n, m),
            record.normal_force_n.as_ref().map(|v| block_average(v, m)),
        )?
    } else {
        record.clone()
    };
    let cycles = segment(&record.time_s, &record.displacement_m)?;
    if cycles.cycles.len() < 2 {
        return Err(Error::Data(format!(
            "the record has {} complete cycle(s); at least 2 are needed to fit on one and score \
             on another",
            cycles.cycles.len()
        )));
    }
    let n = record.len();
    let (x, t) = (&record.displacement_m, &record.time_s);
    let (xmin, xmax) = (
        x.iter().cloned().fold(f64::MAX, f64::min),
        x.iter().cloned().fold(f64::MIN, f64::max),
    );
    let centre = 0.5 * (xmin + xmax);
    // The model is driven by the displacement smoothed over 1/64 of a cycle (measurement
    // noise on the drive would otherwise make the element trace spurious minor loops).
    let per_cycle = (cycles.cycles[0].1 - cycles.cycles[0].0).max(1);
    let (xs, dxs) = savitzky_golay(x, (per_cycle / 64).max(2));
    let mut velocity: Vec<f64> = (0..n)
        .map(|i| {
            let (a, b) = (i.saturating_sub(1), (i + 1).min(n - 1));
            dxs[i] * (b - a) as f64 / (t[b] - t[a])
        })
        .collect();
    // Within a half-cycle the drive moves one way: near the reversals the smoothed derivative
    // is noise-sized and can take the wrong sign, which would flip direction-dependent
    // friction for a few samples of microslip. There the speed is ~0: keep the stroke's sign.
    for h in &cycles.half_cycles {
        let dir = f64::from(h.direction);
        for v in &mut velocity[h.start + 1..=h.end.min(n - 1)] {
            if *v * dir <= 0.0 {
                *v = dir * f64::MIN_POSITIVE;
            }
        }
    }
    let t0 = t[cycles.reversals[0]];
    let tau = std::f64::consts::TAU;
    let normal_ratio = record.normal_force_n.as_ref().map(|nf| {
        let mean = nf.iter().sum::<f64>() / nf.len() as f64;
        nf.iter().map(|v| v / mean).collect()
    });
    let force_scale = 0.5
        * (percentile_nearest(&record.force_n, 0.995) - percentile_nearest(&record.force_n, 0.005));
    if force_scale <= 0.0 || force_scale.is_nan() {
        return Err(Error::Data(
            "the measured force is constant: nothing to fit".into(),
        ));
    }
    let abs_v: Vec<f64> = velocity.iter().map(|v| v.abs()).collect();
    let drive = Drive {
        time_s: t.clone(),
        q_m: xs.iter().map(|v| v - centre).collect(),
        velocity_scale: percentile_nearest(&abs_v, 0.99).max(1e-300),
        velocity_m_per_s: velocity,
        normal_ratio,
        phase_rad: t
            .iter()
            .map(|&ti| tau * (ti - t0) / cycles.period_s)
            .collect(),
        initial_force_n: record.force_n[0],
        force_scale_n: force_scale,
        amplitude_m: cycles.amplitude_m,
    };
    let (fsm, _) = savitzky_golay(&record.force_n, (per_cycle / 64).max(2));
    let noise = noise::estimate(&drive.q_m, &record.force_n, &cycles, force_scale);
    // Alternate complete cycles for training and held out, as sample masks.
    let (train_cycles, _) = core_fit::held_out::alternate(cycles.cycles.len());
    let mut train = vec![false; n];
    let mut held_out = vec![false; n];
    for (&(a, b), &training) in cycles.cycles.iter().zip(&train_cycles) {
        let mask = if training { &mut train } else { &mut held_out };
        mask[a..b].iter_mut().for_each(|m| *m = true);
    }
    Ok(Prepared {
        record,
        decimation: m,
        cycles,
        drive,
        train,
        held_out,
        noise,
        smooth_force_n: fsm,
    })
}

/// A model structure (baseline source + effects) with its parameter specifications.
#[derive(Debug, Clone)]
struct Structure {
    /// A given baseline (no baseline parameters).
    given: Option<Baseline>,
    /// Shape parameter held fixed (per-cycle fits): baseline parameters are `E0`, slip force.
    fixed_k: Option<f64>,
    normal_n: f64,
    baseline_specs: Vec<ParamSpec>,
    effects: Vec<(Effect, Vec<ParamSpec>)>,
}

impl Structure {
    /// The model at optimiser coordinates `z`.
    fn decode(&self, z: &[f64]) -> Model {
        let specs: Vec<ParamSpec> = self.specs().copied().collect();
        self.model(&core_fit::values(&specs, z))
    }

    /// The model at physical values (baseline parameters, then each effect's).
    fn model(&self, v: &[f64]) -> Model {
        let mut i = 0;
        let baseline = match self.given {
            Some(b) => b,
            None => {
                let e0 = v[0];
                let (k, slip) = match self.fixed_k {
                    Some(k) => (k, v[1]),
                    None => (v[1], v[2]),
                };
                i = self.baseline_specs.len();
                Baseline {
                    valanis: ValanisParams {
                        e0,
                        k,
                        et: 0.0,
                        mu: slip / self.normal_n,
                    },
                    normal_n: self.normal_n,
                }
            }
        };
        let effects = self
            .effects
            .iter()
            .map(|(e, specs)| {
                let values = v[i..i + specs.len()].to_vec();
                i += specs.len();
                (*e, values)
            })
            .collect();
        Model { baseline, effects }
    }

    fn n_params(&self) -> usize {
        self.baseline_specs.len() + self.effects.iter().map(|(_, s)| s.len()).sum::<usize>()
    }

    fn specs(&self) -> impl Iterator<Item = &ParamSpec> {
        self.baseline_specs
            .iter()
            .chain(self.effects.iter().flat_map(|(_, s)| s.iter()))
    }
}

/// Least-squares cost: mean squared force residual over the masked samples, in units of the
/// force scale squared.
struct Problem<'a> {
    structure: &'a Structure,
    prep: &'a Prepared,
    mask: &'a [bool],
}

impl core_fit::Objective for Problem<'_> {
    fn cost(&self, values: &[f64]) -> f64 {
        let f = self.structure.model(values).simulate(&self.prep.drive);
        masked_mse(&f, &self.prep.record.force_n, self.mask) / self.prep.drive.force_scale_n.powi(2)
    }
}

fn masked_mse(f: &[f64], y: &[f64], mask: &[bool]) -> f64 {
    let (mut s, mut n) = (0.0, 0usize);
    for i in 0..f.len() {
        if mask[i] {
            let r = f[i] - y[i];
            s += if r.is_finite() { r * r } else { 1e300 };
            n += 1;
        }
    }
    s / n.max(1) as f64
}

/// Result of one least-squares fit.
#[derive(Debug, Clone, Serialize)]
pub struct FitInfo {
    /// Nelder–Mead iterations run (all restarts).
    pub iterations: u64,
    /// Final cost (mean squared residual / force scale²).
    pub final_cost: f64,
    /// The simplex met its tolerance before the iteration cap.
    pub converged: bool,
    /// Wall-clock time of the fit (s).
    pub wall_time_s: f64,
}

/// Nelder–Mead (bounded variables on the MINUIT coordinate), restarted once from its optimum
/// with a fresh simplex of 0.3 of the first one's edge (Numerical Recipes §10.5).
fn fit(
    structure: &Structure,
    z0: Vec<f64>,
    prep: &Prepared,
    mask: &[bool],
    max_iter: u64,
) -> (Vec<f64>, FitInfo) {
    let start = std::time::Instant::now();
    let problem = Problem {
        structure,
        prep,
        mask,
    };
    if z0.is_empty() {
        let cost = core_fit::Objective::cost(&problem, &[]);
        return (
            z0,
            FitInfo {
                iterations: 0,
                final_cost: cost,
                converged: true,
                wall_time_s: start.elapsed().as_secs_f64(),
            },
        );
    }
    let specs: Vec<ParamSpec> = structure.specs().copied().collect();
    let local = LocalSearch {
        max_iters: max_iter,
        tolerance: Tolerance::Absolute(1e-13),
        first_step: 1.0,
        restart_step: 0.3,
        restarts: Restarts::Always(1),
    };
    let (z, iterations, final_cost, converged) =
        match core_fit::minimise(&specs, &problem, &z0, &local, None) {
            Ok(m) => (m.z, m.iterations, m.cost, m.converged),
            Err(_) => (z0, 0, f64::INFINITY, false),
        };
    (
        z,
        FitInfo {
            iterations,
            final_cost,
            converged,
            wall_time_s: start.elapsed().as_secs_f64(),
        },
    )
}

/// Error measures of a simulated force against the measurement, over all complete cycles.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Errors {
    /// RMS force residual / force amplitude (half the 0.5–99.5 % range of the measured force).
    pub nrms: f64,
    /// Mean over cycles of the absolute error of the maximum and minimum force, / force amplitude.
    pub peak_force_error: f64,
    /// Mean over cycles of |E_model − E_measured| / E_measured, `E = ∮F dx` (J).
    pub energy_error: f64,
    /// Normalised RMS force error on the held-out cycles only.
    pub held_out_nrms: f64,
    /// RMS force residual on the held-out cycles / noise floor.
    pub held_out_rms_over_noise: f64,
}

/// Dissipated energy `∮F dx` (J) over the samples `a..=b` (trapezoid rule).
pub fn energy(x: &[f64], f: &[f64], a: usize, b: usize) -> f64 {
    (a..b)
        .map(|i| 0.5 * (f[i] + f[i + 1]) * (x[i + 1] - x[i]))
        .sum()
}

/// Compute [`Errors`] of `f` against the prepared record.
pub fn errors(prep: &Prepared, f: &[f64]) -> Errors {
    let y = &prep.record.force_n;
    let x = &prep.record.displacement_m;
    let fs = prep.drive.force_scale_n;
    let mut all = vec![false; y.len()];
    let (mut peak, mut en) = (0.0, 0.0);
    let nc = prep.cycles.cycles.len() as f64;
    for &(a, b) in &prep.cycles.cycles {
        all[a..b].iter_mut().for_each(|m| *m = true);
        let mx = |v: &[f64]| v[a..=b].iter().cloned().fold(f64::MIN, f64::max);
        let mn = |v: &[f64]| v[a..=b].iter().cloned().fold(f64::MAX, f64::min);
        peak += 0.5 * ((mx(f) - mx(y)).abs() + (mn(f) - mn(y)).abs()) / fs;
        let em = energy(x, y, a, b);
        en += (energy(x, f, a, b) - em).abs() / em.abs().max(1e-300);
    }
    let held = masked_mse(f, y, &prep.held_out).sqrt();
    Errors {
        nrms: masked_mse(f, y, &all).sqrt() / fs,
        peak_force_error: peak / nc,
        energy_error: en / nc,
        held_out_nrms: held / fs,
        held_out_rms_over_noise: held / prep.noise.sigma_n,
    }
}

/// The final model scored on cycles that did not choose it. The held-out cycles both score the
/// candidates and report the "after" error, so that error is the one the selection optimised;
/// here the split is swapped: the baseline and the final structure (its effects as chosen) are
/// refitted on the held-out cycles and scored on the training cycles, which took no part in
/// any comparison of candidates (two-fold cross-validation of the chosen structure; Hastie,
/// Tibshirani & Friedman, *The Elements of Statistical Learning*, 2009, §7.10). An effect that
/// was chosen for the held-out cycles' noise shows no gain here.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct SwappedSplit {
    /// RMS residual of the baseline refitted on the held-out cycles, on the training cycles,
    /// over the noise floor.
    pub before_rms_over_noise: f64,
    /// The same for the final model (effects as chosen, every parameter refitted).
    pub after_rms_over_noise: f64,
}

/// Refit `structure` (from `z0`) on the held-out cycles and return its RMS residual on the
/// training cycles over the noise floor ([`SwappedSplit`]).
fn swapped_score(structure: &Structure, z0: &[f64], prep: &Prepared, max_iter: u64) -> f64 {
    let (z, _) = fit(structure, z0.to_vec(), prep, &prep.held_out, max_iter);
    let f = structure.decode(&z).simulate(&prep.drive);
    masked_mse(&f, &prep.record.force_n, &prep.train).sqrt() / prep.noise.sigma_n
}

/// Evidence for one candidate effect in one round.
#[derive(Debug, Clone, Serialize)]
pub struct Candidate {
    /// The effect added to the round's current model.
    pub effect: Effect,
    /// Parameter names with units and fitted values.
    pub parameters: Vec<(String, f64)>,
    /// Parameters on a bound: `(name (unit), bound)`.
    pub at_bound: Vec<(String, Bound)>,
    /// Parameters the effect adds.
    pub extra_parameters: usize,
    /// RMS force residual on the training cycles / force scale (dimensionless).
    pub train_nrms: f64,
    /// RMS force residual on the held-out cycles / force scale (dimensionless).
    pub held_out_nrms: f64,
    /// Held-out RMS residual / noise floor.
    pub held_out_rms_over_noise: f64,
    /// Held-out `ΔRSS` (N²), positive when the residual falls.
    pub delta_rss: f64,
    /// Evidence `z` (module documentation).
    pub evidence_z: f64,
    /// Share of the excess held-out residual explained (`None`: the current model is at the
    /// noise floor, so there is no excess to explain).
    pub explained_fraction: Option<f64>,
    /// Held-out cycles in which the residual falls, of all held-out cycles.
    pub improved_cycles: (usize, usize),
    /// Whether it passes every acceptance rule.
    pub eligible: bool,
    /// The first rule it fails, or "eligible".
    pub decision: String,
    /// Convergence of the candidate's fit.
    pub fit: FitInfo,
    #[serde(skip)]
    model: Model,
    #[serde(skip)]
    z: Vec<f64>,
}

/// One round of the search: all candidates and the decision.
#[derive(Debug, Clone, Serialize)]
pub struct Round {
    /// Every candidate fitted in the round.
    pub candidates: Vec<Candidate>,
    /// The accepted effect, or `None` (no candidate passes).
    pub accepted: Option<Effect>,
}

/// The three verdicts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// Effects were added and the residual is at the noise floor.
    EffectsFound,
    /// No effect was needed: the baseline's residual is at the noise floor.
    ModelAdequate,
    /// The residual stays above twice the noise floor (effects may have explained part of it).
    ModelInadequate,
    /// The baseline is within twice a noise floor that comes from first differences across
    /// two cycles, in which a drift does not cancel: noise and drift cannot be told apart, so
    /// neither "adequate" nor "no effect needed" can be said.
    RecordTooShort,
}

impl Verdict {
    /// The verdict in words, as in the report.
    pub fn name(self) -> &'static str {
        match self {
            Verdict::EffectsFound => "effect(s) found",
            Verdict::ModelAdequate => "model adequate",
            Verdict::ModelInadequate => "model inadequate, residual unexplained",
            Verdict::RecordTooShort => "undecided, record too short to tell noise from drift",
        }
    }
}

/// What characterises the residual of one model.
#[derive(Debug, Clone, Serialize)]
pub struct Character {
    /// Held-out RMS residual / noise floor.
    pub held_out_rms_over_noise: f64,
    /// Per-phase statistics over the held-out cycles.
    pub phases: Vec<PhaseStats>,
    /// The phase (other than the reversal, with at least [`MIN_PHASE_SHARE`] of the samples)
    /// with the largest RMS residual, and that RMS / noise floor.
    pub worst_phase: Option<(Phase, f64)>,
    /// At the noise floor: held-out RMS ≤ 2σ overall and in every phase (but the reversal)
    /// that holds at least [`MIN_PHASE_SHARE`] of the held-out samples.
    pub adequate: bool,
    /// Phases carrying the excess residual, largest share first.
    pub concentrated_at: Vec<Phase>,
    /// A ringing in the residual, if any.
    pub ringing: Option<Ringing>,
}

/// The result of the whole analysis.
#[derive(Debug, Clone)]
pub struct Diagnosis {
    /// The record as analysed: block-averaged, segmented into cycles, split and its noise floor.
    pub prepared: Prepared,
    /// The baseline model (Valanis element, no effect).
    pub baseline: Model,
    /// Whether the normal load is known (measured, or from a calibration table): only then is
    /// a friction coefficient meaningful.
    pub normal_load_known: bool,
    /// Convergence of the baseline's fit (iterations 0 for a given baseline).
    pub baseline_fit: FitInfo,
    /// Baseline parameters on a bound: `(name (unit), bound)`.
    pub baseline_at_bound: Vec<(String, Bound)>,
    /// The baseline's simulated force at every analysed sample (N).
    pub baseline_force: Vec<f64>,
    /// The baseline with every accepted effect, refitted.
    pub final_model: Model,
    /// The final model's simulated force at every analysed sample (N).
    pub final_force: Vec<f64>,
    /// The search's rounds, in order.
    pub rounds: Vec<Round>,
    /// Error measures of the baseline.
    pub errors_before: Errors,
    /// Error measures of the final model.
    pub errors_after: Errors,
    /// The final model against the baseline on the cycles that did not choose it; `None` when
    /// no effect was added.
    pub swapped_split: Option<SwappedSplit>,
    /// What characterises the baseline's residual.
    pub before: Character,
    /// What characterises the final model's residual.
    pub after: Character,
    /// Zero-force plateaus of the measured force (clearances), per half-cycle.
    pub clearances: Vec<ClearanceRegion>,
    /// Trends of slip force, stiffness and loop area over the cycles.
    pub stationarity: Stationarity,
    /// What the search concluded.
    pub verdict: Verdict,
    /// Fitted parameters of the baseline (0 for a given baseline).
    pub n_parameters_before: usize,
    /// Fitted parameters of the final model.
    pub n_parameters_after: usize,
}

impl Diagnosis {
    /// Effects added, in order.
    pub fn effects_added(&self) -> Vec<Effect> {
        self.rounds.iter().filter_map(|r| r.accepted).collect()
    }

    /// Phase of every sample for the final model (with the measured clearances).
    pub fn phases(&self) -> Vec<Option<Phase>> {
        residual::phases(
            &self.prepared.drive.q_m,
            &self.final_force,
            &self.prepared.cycles,
            &self.clearances,
        )
    }
}

/// Held-out comparison of `f_new` against `f_old` (module documentation):
/// `(ΔRSS, z, explained fraction, (improved cycles, held-out cycles))`.
fn held_out_evidence(
    prep: &Prepared,
    f_old: &[f64],
    f_new: &[f64],
) -> (f64, f64, Option<f64>, (usize, usize)) {
    let y = &prep.record.force_n;
    let sigma = prep.noise.sigma_n;
    let (mut d_rss, mut sdf2, mut rss_old, mut n) = (0.0, 0.0, 0.0, 0usize);
    let (mut improved, mut held) = (0, 0);
    for (k, &(a, b)) in prep.cycles.cycles.iter().enumerate() {
        if k % 2 == 0 {
            continue;
        }
        held += 1;
        let mut dc = 0.0;
        for i in a..b {
            let (ro, rn) = (y[i] - f_old[i], y[i] - f_new[i]);
            let d = ro * ro - rn * rn;
            dc += if d.is_finite() { d } else { f64::NEG_INFINITY };
            sdf2 += (f_new[i] - f_old[i]).powi(2);
            rss_old += ro * ro;
            n += 1;
        }
        d_rss += dc;
        if dc > 0.0 {
            improved += 1;
        }
    }
    let denom = 2.0 * sigma * (prep.noise.correlation_inflation * sdf2).sqrt();
    let z = if denom > 0.0 && d_rss.is_finite() {
        d_rss / denom
    } else {
        0.0
    };
    let excess = rss_old - n as f64 * sigma * sigma;
    let explained = (excess > 0.0).then(|| d_rss / excess);
    (d_rss, z, explained, (improved, held))
}

/// Starting value of `E0` from the measured loops: the median over reversals of the secant
/// slope from the reversal to the point where the force has moved by half the force amplitude
/// (the Valanis reload slope is `2E0/(1+k)`; the secant underestimates it, the fit corrects).
fn initial_stiffness(prep: &Prepared) -> f64 {
    let (x, y) = (&prep.record.displacement_m, &prep.record.force_n);
    let fs = prep.drive.force_scale_n;
    let mut slopes: Vec<f64> = prep
        .cycles
        .half_cycles
        .iter()
        .filter_map(|h| {
            (h.start..=h.end)
                .find(|&i| (y[i] - y[h.start]).abs() > 0.5 * fs)
                .map(|i| (y[i] - y[h.start]).abs() / (x[i] - x[h.start]).abs().max(1e-300))
        })
        .collect();
    if slopes.is_empty() {
        return fs / prep.drive.amplitude_m * 10.0;
    }
    slopes.sort_by(|a, b| a.total_cmp(b));
    slopes[slopes.len() / 2]
}

/// Bounds of the fitted baseline (module documentation of [`super::effects`]).
fn baseline_specs(prep: &Prepared, e0_start: f64, k: Option<f64>) -> Vec<ParamSpec> {
    let (f, a) = (prep.drive.force_scale_n, prep.drive.amplitude_m);
    let stiff = f / a;
    let e0 = log_param(
        "e0",
        "N/m",
        0.5 * stiff,
        1e4 * stiff,
        e0_start.clamp(0.6 * stiff, 0.9e4 * stiff),
    );
    let slip = log_param("slip_force", "N", 0.2 * f, 5.0 * f, f);
    match k {
        Some(_) => vec![e0, slip],
        None => vec![e0, linear_param("k", "-", 0.0, 0.98, 0.5), slip],
    }
}

/// Parameters of `model` that sit on a bound of `specs` (baseline specs then effects).
fn bound_hits(specs: &[&ParamSpec], values: &[f64]) -> Vec<(String, Bound)> {
    specs
        .iter()
        .zip(values)
        .filter_map(|(s, &v)| at_bound(s, v).map(|b| (format!("{} ({})", s.name, s.unit), b)))
        .collect()
}

/// Characterise the residual of `f` against the prepared record.
fn characterise(prep: &Prepared, f: &[f64], clearances: &[ClearanceRegion]) -> Character {
    let y = &prep.record.force_n;
    let sigma = prep.noise.sigma_n;
    let phases = residual::phases(&prep.drive.q_m, f, &prep.cycles, clearances);
    let (a, b) = (
        prep.cycles.cycles[0].0,
        prep.cycles.cycles.last().map_or(y.len(), |c| c.1),
    );
    let stats = residual::phase_stats(
        y,
        f,
        &prep.drive.velocity_m_per_s,
        &phases,
        &prep.held_out,
        sigma,
    );
    let total: usize = stats.iter().map(|p| p.samples).sum();
    // The reversal phase (the first 2 % of the stroke) is reported but not judged per phase:
    // there the force is most sensitive to the displacement (stick stiffness × the drive's
    // measurement noise and smoothing), a scatter that the force repeatability, measured at
    // 3–97 % of the stroke, does not contain (1 µm of displacement noise at 1 mm gave 2–2.8σ
    // there with an exact model). It still counts in the overall RMS.
    let worst_phase = stats
        .iter()
        .filter(|p| p.phase != Phase::Reversal)
        .filter(|p| p.samples as f64 >= MIN_PHASE_SHARE * total as f64)
        .filter_map(|p| p.rms_over_noise.map(|r| (p.phase, r)))
        .max_by(|p, q| p.1.total_cmp(&q.1));
    let held = masked_mse(f, y, &prep.held_out).sqrt() / sigma;
    let r: Vec<f64> = (a..b).map(|i| y[i] - f[i]).collect();
    let t = &prep.record.time_s;
    let dt = (t[b - 1] - t[a]) / (b - 1 - a) as f64;
    Character {
        held_out_rms_over_noise: held,
        concentrated_at: residual::concentrated_at(&stats),
        adequate: held <= ADEQUATE_RATIO && worst_phase.is_none_or(|w| w.1 <= ADEQUATE_RATIO),
        worst_phase,
        phases: stats,
        ringing: residual::ringing(
            &r,
            dt,
            prep.cycles.cycles.len() as f64,
            prep.noise
                .high_pass_n
                .max(noise::RESOLUTION_FRACTION * prep.drive.force_scale_n),
        ),
    }
}

/// Stationarity: the baseline fitted to each complete cycle at the steady amplitude alone
/// (`E0` and slip force, `k` of the whole-record baseline), and the measured loop area per
/// cycle.
fn stationarity(prep: &Prepared, baseline: &Baseline, max_iter: u64) -> Stationarity {
    let v = baseline.valanis;
    let specs = baseline_specs(prep, v.e0, Some(v.k));
    let structure = Structure {
        given: None,
        fixed_k: Some(v.k),
        normal_n: baseline.normal_n,
        effects: vec![],
        baseline_specs: vec![
            ParamSpec {
                start: v.e0.clamp(specs[0].lo, specs[0].hi),
                ..specs[0]
            },
            ParamSpec {
                start: baseline.slip_force_n().clamp(specs[1].lo, specs[1].hi),
                ..specs[1]
            },
        ],
    };
    let z0: Vec<f64> = structure
        .baseline_specs
        .iter()
        .map(|s| s.start_coordinate())
        .collect();
    let n = prep.record.len();
    let (x, y) = (&prep.record.displacement_m, &prep.record.force_n);
    // Cycles at the steady amplitude: peak-to-peak stroke within 3 % of the largest (a drive
    // amplitude that ramps up or down changes the loop for a reason that is not drift).
    let stroke = |&(a, b): &(usize, usize)| {
        let (lo, hi) = x[a..=b]
            .iter()
            .fold((f64::MAX, f64::MIN), |(l, h), &v| (l.min(v), h.max(v)));
        hi - lo
    };
    let largest = prep.cycles.cycles.iter().map(stroke).fold(0.0, f64::max);
    let steady: Vec<usize> = (0..prep.cycles.cycles.len())
        .filter(|&c| stroke(&prep.cycles.cycles[c]) >= 0.97 * largest)
        .collect();
    let per_cycle: Vec<(f64, f64)> = steady
        .par_iter()
        .map(|&c| {
            let (a, b) = prep.cycles.cycles[c];
            let mut mask = vec![false; n];
            mask[a..b].iter_mut().for_each(|m| *m = true);
            let (z, _) = fit(&structure, z0.clone(), prep, &mask, max_iter);
            let m = structure.decode(&z);
            (m.baseline.slip_force_n(), m.baseline.valanis.reload_slope())
        })
        .collect();
    let area: Vec<f64> = steady
        .iter()
        .map(|&c| {
            let (a, b) = prep.cycles.cycles[c];
            energy(x, y, a, b)
        })
        .collect();
    let slip: Vec<f64> = per_cycle.iter().map(|p| p.0).collect();
    let stiff: Vec<f64> = per_cycle.iter().map(|p| p.1).collect();
    Stationarity::new(&steady, &slip, &stiff, &area)
}

/// Run the whole diagnosis on a record.
pub fn diagnose(record: &Record, options: &Options) -> Result<Diagnosis> {
    let prep = prepare(record)?;
    let drive = &prep.drive;
    let normal_n = match (&options.baseline, &record.normal_force_n) {
        (BaselineSource::Given(b), _) => b.normal_n,
        (_, Some(nf)) => nf.iter().sum::<f64>() / nf.len() as f64,
        (_, None) => 1.0,
    };
    let normal_load_known =
        matches!(options.baseline, BaselineSource::Given(_)) || record.normal_force_n.is_some();
    let (given, specs, z_base) = match &options.baseline {
        BaselineSource::Given(b) => {
            b.valanis.validate()?;
            (Some(*b), vec![], vec![])
        }
        BaselineSource::Fitted => {
            let specs = baseline_specs(&prep, initial_stiffness(&prep), None);
            let z = specs.iter().map(|s| s.start_coordinate()).collect();
            (None, specs, z)
        }
    };
    let base_structure = Structure {
        given,
        fixed_k: None,
        normal_n,
        baseline_specs: specs,
        effects: vec![],
    };
    // The fitted baseline is started from three values of the shape parameter k and the best
    // optimum kept (the least-squares surface in (E0, k) has a long curved valley).
    let mut starts = vec![z_base.clone()];
    if given.is_none() {
        for k in [0.15, 0.8] {
            let mut z = z_base.clone();
            z[1] = base_structure.baseline_specs[1].coordinate_of(k);
            starts.push(z);
        }
    }
    let (z_b, baseline_fit) = starts
        .into_par_iter()
        .map(|z| {
            fit(
                &base_structure,
                z,
                &prep,
                &prep.train,
                options.max_iterations,
            )
        })
        .min_by(|a, b| a.1.final_cost.total_cmp(&b.1.final_cost))
        .expect("at least one start");
    let baseline = base_structure.decode(&z_b);
    let baseline_force = baseline.simulate(drive);
    let baseline_at_bound = {
        let b = baseline.baseline;
        let values = [b.valanis.e0, b.valanis.k, b.slip_force_n()];
        let specs: Vec<&ParamSpec> = base_structure.baseline_specs.iter().collect();
        bound_hits(&specs, &values[..specs.len()])
    };

    let clearances = residual::clearance_regions(
        &prep.drive.q_m,
        &prep.smooth_force_n,
        &prep.cycles,
        prep.drive.force_scale_n,
    );
    // The structure of the current model with `effect` added, its parameters' specs (a series
    // spring starts stiff: nearly no effect relative to the current element).
    let extended = |current: &(Structure, Vec<f64>, Vec<f64>), effect: Effect| {
        let mut specs = effect.params(drive);
        if effect == Effect::SeriesCompliance {
            let e0 = current.0.decode(&current.1).baseline.valanis.e0;
            specs[0].start = (20.0 * e0).clamp(specs[0].lo, specs[0].hi);
        }
        let mut structure = current.0.clone();
        structure.effects.push((effect, specs.clone()));
        (structure, specs)
    };
    let half_cycles = prep.cycles.half_cycles.len();
    let (current, core_rounds) = core_fit::held_out::rounds(
        (base_structure.clone(), z_b.clone(), baseline_force.clone()),
        options.max_effects,
        // A model at the noise floor needs no further effect: what a candidate could still
        // "explain" is then as likely the baseline's own shape error as a physical effect.
        |current| !characterise(&prep, &current.2, &clearances).adequate,
        |current| {
            let remaining: Vec<Effect> = options
                .candidates
                .iter()
                .copied()
                .filter(|e| !current.0.effects.iter().any(|(k, _)| k == e))
                .collect();
            let candidates: Vec<Candidate> = remaining
                .par_iter()
                .map(|&effect| {
                    let (structure, specs) = extended(current, effect);
                    let mut z0 = current.1.clone();
                    z0.extend(specs.iter().map(|s| s.start_coordinate()));
                    let (z, info) = fit(&structure, z0, &prep, &prep.train, options.max_iterations);
                    let model = structure.decode(&z);
                    let f = model.simulate(drive);
                    let (d_rss, ev, explained, improved) = held_out_evidence(&prep, &current.2, &f);
                    let params = model
                        .effects
                        .last()
                        .map(|(_, v)| v.clone())
                        .unwrap_or_default();
                    let spec_refs: Vec<&ParamSpec> = specs.iter().collect();
                    let at_bound = bound_hits(&spec_refs, &params);
                    let decision = if ev.is_nan() || ev < EVIDENCE_Z {
                        format!("evidence z = {ev:.1} < {EVIDENCE_Z}")
                    } else if explained.is_some_and(|e| e < MIN_EXPLAINED) {
                        format!(
                            "explains {:.0} % of the excess residual (< {:.0} %)",
                            100.0 * explained.unwrap_or(0.0),
                            100.0 * MIN_EXPLAINED
                        )
                    } else if improved.0 < improved.1 {
                        format!(
                            "improves only {} of {} held-out cycles",
                            improved.0, improved.1
                        )
                    } else if let Some((name, b)) = at_bound.first() {
                        format!("{name} on its {} bound", b.name())
                    } else if effect == Effect::Backlash && 2 * clearances.len() < half_cycles {
                        "no zero-force plateau in the measured force".to_string()
                    } else {
                        "eligible".to_string()
                    };
                    let n_held = prep.held_out.iter().filter(|m| **m).count().max(1) as f64;
                    let rss_new = masked_mse(&f, &prep.record.force_n, &prep.held_out) * n_held;
                    Candidate {
                        effect,
                        parameters: specs
                            .iter()
                            .zip(params)
                            .map(|(s, v)| (format!("{} ({})", s.name, s.unit), v))
                            .collect(),
                        at_bound,
                        extra_parameters: specs.len(),
                        train_nrms: info.final_cost.sqrt(),
                        held_out_nrms: (rss_new / n_held).sqrt() / drive.force_scale_n,
                        held_out_rms_over_noise: (rss_new / n_held).sqrt() / prep.noise.sigma_n,
                        delta_rss: d_rss,
                        evidence_z: ev,
                        explained_fraction: explained,
                        improved_cycles: improved,
                        eligible: decision == "eligible",
                        decision,
                        fit: info,
                        model,
                        z,
                    }
                })
                .collect();
            Ok(((), candidates))
        },
        |_, candidates| {
            candidates
                .iter()
                .enumerate()
                .filter(|(_, c)| c.eligible)
                .max_by(|a, b| a.1.delta_rss.total_cmp(&b.1.delta_rss))
                .map(|(i, _)| i)
        },
        |current, c| {
            let (structure, _) = extended(&current, c.effect);
            let f = c.model.simulate(drive);
            Ok((structure, c.z.clone(), f))
        },
    )?;
    let rounds: Vec<Round> = core_rounds
        .into_iter()
        .map(|r| Round {
            accepted: r.accepted.map(|i| r.candidates[i].effect),
            candidates: r.candidates,
        })
        .collect();
    let final_model = current.0.decode(&current.1);
    let final_force = current.2;
    let swapped_split = (!current.0.effects.is_empty()).then(|| {
        let (before, after) = rayon::join(
            || swapped_score(&base_structure, &z_b, &prep, options.max_iterations),
            || swapped_score(&current.0, &current.1, &prep, options.max_iterations),
        );
        SwappedSplit {
            before_rms_over_noise: before,
            after_rms_over_noise: after,
        }
    });
    let before = characterise(&prep, &baseline_force, &clearances);
    let after = characterise(&prep, &final_force, &clearances);
    let stationarity = stationarity(&prep, &baseline.baseline, options.max_iterations);
    let added = rounds.iter().any(|r| r.accepted.is_some());
    let verdict = if !after.adequate {
        Verdict::ModelInadequate
    } else if added {
        Verdict::EffectsFound
    } else if prep.noise.from_first_differences() {
        Verdict::RecordTooShort
    } else {
        Verdict::ModelAdequate
    };
    Ok(Diagnosis {
        errors_before: errors(&prep, &baseline_force),
        errors_after: errors(&prep, &final_force),
        swapped_split,
        n_parameters_before: base_structure.n_params(),
        n_parameters_after: current.0.n_params(),
        normal_load_known,
        baseline_at_bound,
        before,
        after,
        clearances,
        stationarity,
        verdict,
        prepared: prep,
        baseline,
        baseline_fit,
        baseline_force,
        final_model,
        final_force,
        rounds,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn savitzky_golay_is_exact_for_quadratics() {
        let x: Vec<f64> = (0..30)
            .map(|i| 2.0 + 0.5 * i as f64 - 0.03 * (i * i) as f64)
            .collect();
        let (s, d) = savitzky_golay(&x, 4);
        for i in 4..26 {
            assert!((s[i] - x[i]).abs() < 1e-12);
            assert!((d[i] - (0.5 - 0.06 * i as f64)).abs() < 1e-12);
        }
    }

    /// A force scaled by 1.1 has exactly 10 % energy and peak errors, and an RMS error of
    /// 0.1·RMS(F)/force amplitude; the measured force itself has none.
    #[test]
    fn error_measures_of_a_scaled_force() {
        let per = 200;
        let n = 3 * per + per / 2;
        let tau = std::f64::consts::TAU;
        let t: Vec<f64> = (0..n).map(|i| i as f64 / per as f64).collect();
        let x: Vec<f64> = t.iter().map(|&t| 1e-3 * (tau * t).sin()).collect();
        let y: Vec<f64> = t.iter().map(|&t| 50.0 * (tau * t + 0.5).cos()).collect();
        let rec = Record::new(t, x, y.clone(), None).unwrap();
        let prep = prepare(&rec).unwrap();
        let e0 = errors(&prep, &y);
        assert_eq!(
            (e0.nrms, e0.peak_force_error, e0.energy_error),
            (0.0, 0.0, 0.0)
        );
        let f: Vec<f64> = y.iter().map(|v| 1.1 * v).collect();
        let e = errors(&prep, &f);
        assert!((e.energy_error - 0.1).abs() < 1e-12, "{}", e.energy_error);
        let fs = prep.drive.force_scale_n;
        assert!(
            (e.peak_force_error - 0.1 * 50.0 / fs).abs() < 2e-3,
            "{}",
            e.peak_force_error
        );
        // RMS of a sinusoid of amplitude 50 N is 50/√2 (whole cycles).
        let expected = 0.1 * 50.0 / 2f64.sqrt() / fs;
        assert!(
            (e.nrms / expected - 1.0).abs() < 0.01,
            "{} vs {expected}",
            e.nrms
        );
    }

    #[test]
    fn energy_of_a_rectangle_loop() {
        let x = [-1.0, -1.0, 1.0, 1.0, -1.0];
        let f = [-2.0, 2.0, 2.0, -2.0, -2.0];
        assert!((energy(&x, &f, 0, 4) - 8.0).abs() < 1e-12);
    }
}
