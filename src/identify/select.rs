//! Which effect does the model lack? Candidate effects accepted only on strong held-out
//! evidence, against the measurement scatter estimated from the data.
//!
//! The approach is that of `crate::diagnose::select` (held-out data, a "very strong"
//! threshold; the split, the effective sample size, the `ΔBIC` and the greedy rounds are
//! [`crate::core::fit::held_out`]'s), adapted to frequency responses:
//!
//! 1. **Split.** The rows of every fit level are split alternately into training rows (even
//!    positions in the sweep) and held-out rows (odd positions). Models are fitted on training
//!    rows only: evaluated along the whole sweep with the held-out rows masked (the thorough
//!    search), or along the training rows alone (the default, [`SelectOptions::training_rows_only`]:
//!    the same objective to the balance's tolerance at half the cost).
//! 2. **Candidates.** Each admissible effect ([`Extensible::admits`]: every candidate for the
//!    single mode, [`super::reduced::REDUCED_EFFECTS`] for a reduced model) is added and the
//!    model refitted, every candidate of a round in parallel, by Nelder–Mead from the current
//!    model's optimum with the effect's parameters at their neutral values, and (thorough) a
//!    particle swarm over the whole box followed by Nelder–Mead, or (default) Nelder–Mead from
//!    the current optimum with the joint back at the data's scales
//!    ([`SelectOptions::joint_restart`]); the best is kept. The default screens each candidate
//!    with a low iteration cap and refines those the held-out evidence leans to
//!    ([`SelectOptions::refine`]). An effect with a neutral value (zero stiffness change, zero
//!    delay, ...) therefore never fits worse than the current model; a joint family has none
//!    (its joint replaces the Jenkins slider).
//! 3. **Evidence.** On the held-out rows, `ΔBIC = n_eff·ln(J_new/J_old) + Δp·ln(n_eff)`
//!    (Schwarz 1978), `J` the objective of [`super::fit`] on held-out rows, `n = 2·rows`
//!    (real and imaginary parts), `n_eff = n·(1 − ρ)/(1 + ρ)` with `ρ` the lag-1
//!    autocorrelation of the current model's held-out residuals along each sweep (neighbouring
//!    rows of a smooth frequency response do not carry independent evidence). The best candidate
//!    is accepted when `ΔBIC < −10` ("very strong", Kass & Raftery 1995) **and** it lowers the
//!    held-out residual of every fit level (an effect that helps one level at another's expense
//!    is not structure-level). Up to `max_effects` effects are added, one per round.
//!    **Generalisation.** A candidate that nests an accepted effect (the power-law damper nests
//!    the quadratic one at `p = 1`, [`Effect::nests`]) is offered in the next rounds as a
//!    replacement of it: Nelder–Mead from the current optimum with the extra parameter at its
//!    nesting value, judged by the same ΔBIC with `Δp` the extra parameters only. It does not
//!    count as a new effect. Without it, an effect that wins round 1 by its lower parameter
//!    count would shut out its better-fitting generalisation for good.
//!    **Interacting effects.** When two new candidates of a round each reach the ΔBIC
//!    threshold on the pooled held-out rows while raising some level's residual (each suits
//!    some levels at the others' expense), they are also fitted together in pairs (the
//!    strongest [`MAX_PAIRED`]) and each pair judged as one candidate with `Δp` their
//!    parameters together, by the same two tests, competing with
//!    the single candidates by ΔBIC. A greedy search
//!    one effect at a time cannot otherwise find effects that only work together — a stiffness
//!    softening ∝ A and hardening ∝ A² that make a resonance fall and then rise.
//! 4. **Scatter.** The measurement scatter of each level is estimated from the smoothness of its
//!    sweep: for white noise of standard deviation `s` per component, the third difference of
//!    consecutive rows `Δ³Y_i = Y_{i+2} − 3Y_{i+1} + 3Y_i − Y_{i−1}` has variance `20·s²` per
//!    component, and `|Δ³Y|` of a complex Gaussian has median `1.1774·√20·s`; the median over
//!    the sweep is robust to the few rows at the resonance where the signal itself has large
//!    third differences. The scatter floor of the objective is `J_noise = mean over levels of
//!    2·(s_l/peak_l)²`. A residual is "at the scatter" when `J ≤ 4·J_noise` (RMS within twice
//!    the scatter).
//!
//! Verdicts: effects accepted; no effect needed (baseline at the scatter); or the residual stays
//! above the scatter and no candidate explains it — reported as such, nothing forced.

use super::effects::Effect;
use super::fit::{
    fit_global, fit_local, FitOptions, FitResult, LevelData, Objective, Parametrised,
};
use super::model::{Model, ModelSpec, NUMERICAL_COST_FLOOR};
use crate::core::error::Result;
use crate::core::fit::held_out;
use rayon::prelude::*;
use realfft::num_complex::Complex64;
use serde::Serialize;

/// Candidates of one round paired with one another at most (the strongest by ΔBIC of those
/// that reach the threshold but raise some level's residual): 4 give 6 pair fits.
pub const MAX_PAIRED: usize = 4;

/// Evidence threshold on the held-out ΔBIC.
pub const BIC_THRESHOLD: f64 = -10.0;
/// A residual is at the scatter when its objective is within this factor of the scatter floor
/// (RMS within twice the scatter).
pub const SCATTER_FACTOR: f64 = 4.0;

/// A model family the search can extend by candidate effects ([`super::effects`]): the single
/// nonlinear mode ([`ModelSpec`], every candidate) and the updated reduced model
/// ([`super::reduced::ReducedSpec`], the structure-level candidates that act on its response
/// coordinate).
pub trait Extensible: Parametrised + PartialEq {
    /// The effects added so far, in order.
    fn effects(&self) -> &[Effect];
    /// This family with one more effect (its parameters appended).
    fn with(&self, e: Effect) -> Self;
    /// Whether `e` may be added.
    fn admits(&self, e: Effect) -> bool;
    /// The family with the accepted effect that `e` nests replaced by `e`, and `values` mapped
    /// onto it (the same model); `None` when `e` nests no effect of this family.
    fn generalised(&self, e: Effect, values: &[f64]) -> Option<(Self, Vec<f64>)>;
    /// The family a member belongs to.
    fn spec_of(model: &Self::Model) -> &Self;
    /// `values` (a member of this family) with its joint back at the data's own scales, if the
    /// family has a joint: the second start of a candidate's fit in the default search
    /// ([`SelectOptions::joint_restart`]).
    fn joint_at_data_scales(&self, values: &[f64]) -> Option<Vec<f64>>;
}

impl Extensible for ModelSpec {
    fn effects(&self) -> &[Effect] {
        &self.effects
    }
    fn with(&self, e: Effect) -> Self {
        ModelSpec::with(self, e)
    }
    fn admits(&self, e: Effect) -> bool {
        ModelSpec::admits(self, e)
    }
    fn generalised(&self, e: Effect, values: &[f64]) -> Option<(Self, Vec<f64>)> {
        ModelSpec::generalised(self, e, values)
    }
    fn spec_of(model: &Model) -> &Self {
        &model.spec
    }
    /// The joint's stiffness share and slip displacement at their starts ([`Model::neutral`]:
    /// a 1 % share slipping at the lowest fit level's peak amplitude).
    fn joint_at_data_scales(&self, values: &[f64]) -> Option<Vec<f64>> {
        let p = self.params();
        let mut v = values.to_vec();
        v[3] = p[3].start;
        v[4] = p[4].start;
        Some(v)
    }
}

/// Measurement scatter of one level per component, relative to its peak (see the module
/// documentation).
pub fn relative_scatter(level: &LevelData) -> f64 {
    median_third_difference(&level.measured, |_| 1.0) / (1.1774 * 20f64.sqrt()) / level.peak
}

/// Measurement scatter of one level per component relative to each row's own response (noise
/// proportional to the response, as a sensor's or a force gauge's gain error gives): the
/// median third difference, each divided by the root-sum-square of its four rows' weighted
/// magnitudes, over the Rayleigh median 1.1774. Beside [`relative_scatter`] (constant noise,
/// a fraction of the peak), which underestimates proportional noise at the rows near the peak
/// by the ratio of the peak to the median row's response.
pub fn proportional_scatter(level: &LevelData) -> f64 {
    let y = &level.measured;
    let weight = |i: usize| {
        (y[i + 2].norm_sqr()
            + 9.0 * y[i + 1].norm_sqr()
            + 9.0 * y[i].norm_sqr()
            + y[i - 1].norm_sqr())
        .sqrt()
    };
    median_third_difference(y, weight) / 1.1774
}

/// The median over the rows of `|y[i+2] − 3y[i+1] + 3y[i] − y[i−1]| / scale(i)` (a Rayleigh
/// median, 1.1774 times the standard deviation per component of white noise whose third
/// difference at `i` has a standard deviation of `scale(i)` per component); NaN below four
/// rows.
fn median_third_difference(y: &[Complex64], scale: impl Fn(usize) -> f64) -> f64 {
    if y.len() < 4 {
        return f64::NAN;
    }
    let mut d3: Vec<f64> = (1..y.len() - 2)
        .map(|i| (y[i + 2] - 3.0 * y[i + 1] + 3.0 * y[i] - y[i - 1]).norm() / scale(i))
        .collect();
    d3.sort_by(|a, b| a.total_cmp(b));
    d3[d3.len() / 2]
}

/// Scatter floor of the objective over some levels: mean of `2·s_l²`.
pub fn scatter_floor(levels: &[LevelData]) -> f64 {
    levels
        .iter()
        .map(|l| 2.0 * relative_scatter(l).powi(2))
        .sum::<f64>()
        / levels.len() as f64
}

/// Training (even positions) and held-out (odd) masks of each level.
pub fn split(levels: &[LevelData]) -> (Vec<Vec<bool>>, Vec<Vec<bool>>) {
    levels
        .iter()
        .map(|l| held_out::alternate(l.drives.len()))
        .unzip()
}

/// Held-out score of a model: objective over the held-out rows, per level and pooled, and the
/// residuals of the held-out rows (per level, in sweep order).
#[derive(Debug, Clone, Serialize)]
pub struct HeldOut {
    /// Pooled objective: mean over levels of `per_level` (dimensionless, residuals relative to
    /// each level's peak response).
    pub cost: f64,
    /// Per level: mean of `|r_i|²` over its masked rows, `r_i` the residual relative to the level's
    /// peak response ([`LevelData::residuals`]).
    pub per_level: Vec<f64>,
    /// Per level: the relative residuals `r_i` of the masked rows, in sweep order.
    #[serde(skip)]
    pub residuals: Vec<Vec<Complex64>>,
}

/// Score a model on masked rows.
pub fn score<S: Parametrised>(
    model: &S::Model,
    levels: &[LevelData],
    masks: &[Vec<bool>],
) -> Result<HeldOut> {
    let mut per_level = Vec::new();
    let mut residuals = Vec::new();
    for (l, m) in levels.iter().zip(masks) {
        let (y, _) = S::frf(model, l)?;
        let r: Vec<Complex64> = l
            .residuals(&y)
            .into_iter()
            .zip(m)
            .filter(|(_, &k)| k)
            .map(|(r, _)| r)
            .collect();
        per_level.push(r.iter().map(|v| v.norm_sqr()).sum::<f64>() / r.len().max(1) as f64);
        residuals.push(r);
    }
    Ok(HeldOut {
        cost: per_level.iter().sum::<f64>() / per_level.len() as f64,
        per_level,
        residuals,
    })
}

/// Lag-1 autocorrelation of the residual components along each sweep (pooled), in `[0, 0.95]`.
pub fn lag1_autocorrelation(residuals: &[Vec<Complex64>]) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for r in residuals {
        for part in [|z: &Complex64| z.re, |z: &Complex64| z.im] {
            let v: Vec<f64> = r.iter().map(part).collect();
            let mean = v.iter().sum::<f64>() / v.len().max(1) as f64;
            for w in v.windows(2) {
                num += (w[0] - mean) * (w[1] - mean);
            }
            den += v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>();
        }
    }
    if den > 0.0 {
        (num / den).clamp(0.0, 0.95)
    } else {
        0.0
    }
}

/// One candidate of a round.
#[derive(Debug, Clone, Serialize)]
pub struct Candidate<M = Model> {
    /// The effect added to the round's current spec.
    pub effect: Effect,
    /// The accepted effect this candidate generalises (replaces by the nesting law, with
    /// the extra parameters only), if any.
    pub generalises: Option<Effect>,
    /// The second effect of a pair tested jointly ([`select`]'s step for interacting effects),
    /// if any: the candidate is `effect` and this one added together.
    pub jointly_with: Option<Effect>,
    /// One-line description of what the effect models.
    pub meaning: &'static str,
    /// Parameters the candidate adds (`Δp` of the `ΔBIC`).
    pub added_parameters: usize,
    /// Objective of its fit on the training rows (dimensionless).
    pub train_cost: f64,
    /// Its score on the held-out rows.
    pub held_out: HeldOut,
    /// Held-out `ΔBIC = n_eff·ln(J_new/J_old) + Δp·ln(n_eff)` against the round's current spec
    /// (Schwarz 1978); accepted below −10.
    pub delta_bic: f64,
    /// Every fit level's held-out residual fell.
    pub improves_every_level: bool,
    /// The candidate's Nelder–Mead fit met its tolerance (rather than its iteration cap).
    pub converged: bool,
    /// Model evaluations of the candidate's fit (screening and refinement).
    pub evaluations: u64,
    /// Wall time of the candidate's fit (s).
    pub wall_time_s: f64,
    /// Refitted from its screening optimum ([`SelectOptions::refine`]).
    pub refined: bool,
    /// The candidate's training fit.
    #[serde(skip)]
    pub fit: FitResult<M>,
}

/// One round of the search.
#[derive(Debug, Clone, Serialize)]
pub struct Round<M = Model> {
    /// Spec the candidates were added to.
    pub base_effects: Vec<Effect>,
    /// Held-out score of the spec the candidates were added to.
    pub base_held_out: HeldOut,
    /// Lag-1 autocorrelation `ρ` of the base spec's held-out residuals along each sweep, in
    /// `[0, 0.95]` ([`lag1_autocorrelation`]).
    pub lag1_autocorrelation: f64,
    /// Effective number of held-out samples `n_eff = n·(1 − ρ)/(1 + ρ)`, `n` twice the held-out
    /// rows (real and imaginary parts).
    pub effective_samples: f64,
    /// Every candidate fitted in this round.
    pub candidates: Vec<Candidate<M>>,
    /// The effect accepted in this round, if any (`None` ends the search).
    pub accepted: Option<Effect>,
    /// The second effect when the accepted candidate is a pair.
    pub accepted_with: Option<Effect>,
}

/// The outcome of the search.
#[derive(Debug, Clone, Serialize)]
pub enum Verdict {
    /// Effects accepted on held-out evidence; `at_scatter`: the final residual is within the
    /// scatter.
    EffectsFound {
        /// Accepted effects in the order they were accepted.
        effects: Vec<Effect>,
        /// The final model's held-out objective is within the scatter (`J ≤ 4·J_noise`).
        at_scatter: bool,
    },
    /// The baseline's residual is already at the scatter.
    NoEffectNeeded,
    /// The residual stays above the scatter and no candidate explains it.
    Unexplained {
        /// Held-out objective of the final model (dimensionless).
        held_out_cost: f64,
        /// The scatter floor `J_noise` it is compared with (dimensionless).
        scatter_floor: f64,
    },
}

/// Result of the effect search.
#[derive(Debug, Clone, Serialize)]
#[serde(bound(serialize = "S: Serialize"))]
pub struct Selection<S: Extensible = ModelSpec> {
    /// Training fit of the baseline spec.
    pub baseline_train_fit: FitResult<S::Model>,
    /// The search's rounds in order, one effect accepted per round.
    pub rounds: Vec<Round<S::Model>>,
    /// The baseline with every accepted effect.
    pub final_spec: S,
    /// Training fit of the final spec.
    #[serde(skip)]
    pub final_train_fit: FitResult<S::Model>,
    /// Scatter floor of the objective, `J_noise` = mean over levels of `2·(s_l/peak_l)²`
    /// (dimensionless, [`scatter_floor`]).
    pub scatter_floor: f64,
    /// Per level: measurement scatter per component relative to the peak response, `s_l/peak_l`
    /// ([`relative_scatter`]).
    pub relative_scatter_per_level: Vec<f64>,
    /// What the search concluded.
    pub verdict: Verdict,
}

/// Options of the search.
#[derive(Debug, Clone, Serialize)]
pub struct SelectOptions {
    /// Effects offered as candidates (those the spec admits are tried).
    pub candidates: Vec<Effect>,
    /// Most effects added (one per round).
    pub max_effects: usize,
    /// Fit of the baseline (several starts).
    pub baseline_fit: FitOptions,
    /// Global part of each candidate's fit (usually one start).
    pub candidate_fit: FitOptions,
    /// Training fits evaluate the model at the training rows only (warm-started along them)
    /// instead of along every row with the held-out rows masked: the same objective to the
    /// harmonic balance's tolerance at half the rows.
    pub training_rows_only: bool,
    /// Each new candidate is fitted also from the current optimum with the joint back at the
    /// data's own scales ([`Extensible::joint_at_data_scales`]): an effect can take over what
    /// the joint did (a damper the joint's dissipation, on the Brake–Reuss beam: the Jenkins
    /// baseline's joint carries half the stiffness and slips at the highest level's amplitude,
    /// the model with quadratic damping a 1 % share slipping at every amplitude), an optimum
    /// in another basin that a local start from the current optimum does not reach and a
    /// swarm per candidate finds at a dozen times the cost.
    pub joint_restart: bool,
    /// Screening: with `Some`, [`SelectOptions::candidate_fit`] is a screening fit (a low
    /// iteration cap), and the candidates whose held-out evidence leans to them (`ΔBIC` below
    /// [`REFINE_BELOW`]) are refitted from their screening optimum with these settings before
    /// the round decides; the others are refused on their screening fit.
    pub refine: Option<FitOptions>,
}

/// Fit a candidate spec: Nelder–Mead from each of `starts` (physical values) and one swarm
/// over the box (the global part of [`SelectOptions::candidate_fit`]); the best.
fn fit_candidate<S: Extensible>(
    spec: &S,
    starts: &[Vec<f64>],
    levels: &[LevelData],
    train: &[Vec<bool>],
    opts: &SelectOptions,
    progress: Option<&indicatif::ProgressBar>,
) -> Result<FitResult<S::Model>> {
    let local = fit_local(spec, levels, train, starts, &opts.candidate_fit, progress)?;
    if opts.candidate_fit.starts == 0 {
        return Ok(local);
    }
    let global = fit_global(spec, levels, train, &opts.candidate_fit, progress)?;
    Ok(if global.cost < local.cost {
        global
    } else {
        local
    })
}

/// Fit the baseline on the training rows: the swarm starts of [`fit_global`] (none when
/// `opts.starts` is 0) and Nelder–Mead from each of `starts` (physical values), the best. For
/// the single mode the start is the data's own scales ([`Model::neutral`]: the resonance
/// frequency and modal mass of the fit levels' equivalent linear modes, ζ0 = 0.1 %, a 1 % joint
/// stiffness share slipping at the lowest fit level's peak amplitude): a small swarm can settle
/// in the basin of a heavily damped linear mode between the levels' resonances; the data start
/// does not, and costs one local fit. For the reduced model it is the update on all rows.
fn fit_baseline<S: Extensible>(
    baseline: &S,
    starts: &[Vec<f64>],
    levels: &[LevelData],
    train: &[Vec<bool>],
    opts: &FitOptions,
    progress: Option<&indicatif::ProgressBar>,
) -> Result<FitResult<S::Model>> {
    let local = fit_local(baseline, levels, train, starts, opts, progress)?;
    if opts.starts == 0 {
        return Ok(local);
    }
    let global = fit_global(baseline, levels, train, opts, progress)?;
    let (mut best, other) = if local.cost < global.cost {
        (local, global)
    } else {
        (global, local)
    };
    best.starts.extend(other.starts);
    best.evaluations += other.evaluations;
    Ok(best)
}

/// The data start of the single mode's baseline fit ([`Model::neutral`]).
pub fn neutral_start(baseline: &ModelSpec) -> Vec<Vec<f64>> {
    vec![Model::neutral(baseline.clone()).values]
}

/// What a round of the search starts from.
struct RoundStart {
    base_effects: Vec<Effect>,
    base_held_out: HeldOut,
    rho: f64,
    n_eff: f64,
}

/// The fit levels restricted to their training rows (each level's peak and mean force kept,
/// so that the objective is the one on all rows with the held-out rows masked), for searches
/// that evaluate the training rows only ([`SelectOptions::training_rows_only`]).
fn training_levels(levels: &[LevelData], train: &[Vec<bool>]) -> Vec<LevelData> {
    levels
        .iter()
        .zip(train)
        .map(|(l, m)| {
            fn keep<T: Copy>(v: &[T], m: &[bool]) -> Vec<T> {
                v.iter()
                    .zip(m)
                    .filter(|(_, &k)| k)
                    .map(|(x, _)| *x)
                    .collect()
            }
            LevelData {
                name: l.name.clone(),
                quantity: l.quantity,
                drives: keep(&l.drives, m),
                measured: keep(&l.measured, m),
                lines: keep(&l.lines, m),
                mean_force_n: l.mean_force_n,
                peak: l.peak,
            }
        })
        .collect()
}

/// Run the search on the fit levels; the baseline's training fit starts from `baseline_starts`
/// (physical values; [`neutral_start`] for the single mode) and, with swarm starts in
/// [`SelectOptions::baseline_fit`], from the swarm. The candidates of a round are fitted in
/// parallel (a candidate that starts from a nested candidate's optimum after it; the report
/// keeps the order of [`SelectOptions::candidates`]).
pub fn select<S: Extensible>(
    baseline: &S,
    baseline_starts: &[Vec<f64>],
    levels: &[LevelData],
    opts: &SelectOptions,
    progress: Option<&indicatif::ProgressBar>,
) -> Result<Selection<S>> {
    let (train, held) = split(levels);
    // The levels and masks the training fits evaluate.
    let (fit_levels, fit_masks) = if opts.training_rows_only {
        let t = training_levels(levels, &train);
        let all = t.iter().map(|l| vec![true; l.drives.len()]).collect();
        (t, all)
    } else {
        (levels.to_vec(), train.clone())
    };
    let (fit_levels, train) = (&fit_levels[..], &fit_masks[..]);
    let base_fit = fit_baseline(
        baseline,
        baseline_starts,
        fit_levels,
        train,
        &opts.baseline_fit,
        progress,
    )?;
    let floor = scatter_floor(levels);
    // State: the current model's training fit and the effects accepted so far.
    let state = (base_fit.clone(), Vec::<Effect>::new());
    let (state, core_rounds) = held_out::rounds(
        state,
        usize::MAX,
        |_| true,
        |(current, accepted_effects): &(FitResult<S::Model>, Vec<Effect>)| {
            let spec = S::spec_of(&current.model).clone();
            let base_held = score::<S>(&current.model, levels, &held)?;
            let rho = lag1_autocorrelation(&base_held.residuals);
            let n: usize = base_held.residuals.iter().map(|r| 2 * r.len()).sum();
            let n_eff = held_out::effective_samples(n, rho);
            let evidence = Evidence::<S> {
                levels,
                held: &held,
                base_held: &base_held,
                n_eff,
                base_params: spec.params().len(),
                family: std::marker::PhantomData,
            };
            // New effects while fewer than `max_effects` are in, and generalisations of
            // accepted ones (one extra parameter each, not counted as a new effect) in every
            // round.
            let room = accepted_effects.len() < opts.max_effects;
            let tried: Vec<Effect> = opts
                .candidates
                .iter()
                .copied()
                .filter(|&e| {
                    spec.generalised(e, S::values_of(&current.model)).is_some()
                        || (room && spec.admits(e))
                })
                .collect();
            // A new candidate that nests another one tried before it in this round starts
            // also from that one's optimum, so it is fitted after it.
            let waits = |e: Effect| {
                let before = &tried[..tried.iter().position(|&x| x == e).unwrap_or(0)];
                spec.generalised(e, S::values_of(&current.model)).is_none()
                    && e.nests().is_some_and(|n| before.contains(&n))
            };
            let fit_one =
                |e: Effect, earlier: &[Candidate<S::Model>]| -> Result<Candidate<S::Model>> {
                    let generalisation = spec.generalised(e, S::values_of(&current.model));
                    let generalises = e.nests().filter(|_| generalisation.is_some());
                    let (cspec, fit) = match generalisation {
                        Some((cspec, start)) => {
                            let fit = fit_local(
                                &cspec,
                                fit_levels,
                                train,
                                &[start],
                                &opts.candidate_fit,
                                progress,
                            )?;
                            (cspec, fit)
                        }
                        None => {
                            // From the current optimum with the effect at its neutral values, and
                            // from the optimum of a nested candidate of the same round (extended
                            // to this effect by [`Effect::nested_values`]).
                            let cspec = spec.with(e);
                            let mut start = S::values_of(&current.model).to_vec();
                            start.extend(cspec.params()[start.len()..].iter().map(|p| p.start));
                            let nested = e.nests().and_then(|n| {
                                let c = earlier.iter().find(|c| c.effect == n)?;
                                let mut v = S::values_of(&c.fit.model).to_vec();
                                v.extend(e.nested_values());
                                Some(v)
                            });
                            let extra = cspec.params()[S::values_of(&current.model).len()..]
                                .iter()
                                .map(|p| p.start)
                                .collect::<Vec<_>>();
                            let joint = opts
                                .joint_restart
                                .then(|| spec.joint_at_data_scales(S::values_of(&current.model)))
                                .flatten()
                                .map(|mut v| {
                                    v.extend(&extra);
                                    v
                                });
                            let starts: Vec<Vec<f64>> =
                                std::iter::once(start).chain(joint).chain(nested).collect();
                            let fit =
                                fit_candidate(&cspec, &starts, fit_levels, train, opts, progress)?;
                            (cspec, fit)
                        }
                    };
                    evidence.judge(&cspec, e, None, generalises, fit)
                };
            let first: Vec<Candidate<S::Model>> = tried
                .par_iter()
                .filter(|&&e| !waits(e))
                .map(|&e| fit_one(e, &[]))
                .collect::<Result<_>>()?;
            let second: Vec<Candidate<S::Model>> = tried
                .par_iter()
                .filter(|&&e| waits(e))
                .map(|&e| fit_one(e, &first))
                .collect::<Result<_>>()?;
            let mut candidates: Vec<Candidate<S::Model>> = first
                .into_iter()
                .chain(second)
                .collect::<Vec<_>>()
                .into_par_iter()
                .map(|c| evidence.refined(c, fit_levels, train, opts, progress))
                .collect::<Result<_>>()?;
            candidates.sort_by_key(|c| tried.iter().position(|&e| e == c.effect));
            // Interacting effects: when two new effects each have strong evidence on the
            // pooled held-out rows but raise some level's residual (on the Brake–Reuss beam
            // fitted on all four levels: a stiffness softening ∝ A suits level 2, hardening ∝
            // A² levels 1 and 4, and the resonance needs both), every two of them (the
            // strongest [`MAX_PAIRED`]) are also tested together, `Δp` their parameters
            // together, and compete with the single candidates by ΔBIC.
            if accepted_effects.len() + 2 <= opts.max_effects {
                let mut strong: Vec<&Candidate<S::Model>> = candidates
                    .iter()
                    .filter(|c| {
                        c.generalises.is_none()
                            && c.delta_bic < BIC_THRESHOLD
                            && !c.improves_every_level
                    })
                    .collect();
                strong.sort_by(|a, b| a.delta_bic.total_cmp(&b.delta_bic));
                strong.truncate(MAX_PAIRED);
                let mut pairs = Vec::new();
                for (k, a) in strong.iter().enumerate() {
                    for b in &strong[k + 1..] {
                        let pair = spec.with(a.effect);
                        if pair.admits(b.effect) {
                            pairs.push((a, b, pair.with(b.effect)));
                        }
                    }
                }
                let pairs: Vec<Candidate<S::Model>> = pairs
                    .into_par_iter()
                    .map(|(a, b, cspec)| {
                        // From the two single candidates' optima combined.
                        let mut start = S::values_of(&a.fit.model).to_vec();
                        start.extend(
                            &S::values_of(&b.fit.model)[S::values_of(&current.model).len()..],
                        );
                        let fit =
                            fit_candidate(&cspec, &[start], fit_levels, train, opts, progress)?;
                        let c = evidence.judge(&cspec, a.effect, Some(b.effect), None, fit)?;
                        evidence.refined(c, fit_levels, train, opts, progress)
                    })
                    .collect::<Result<_>>()?;
                candidates.extend(pairs);
            }
            let start = RoundStart {
                base_effects: spec.effects().to_vec(),
                base_held_out: base_held,
                rho,
                n_eff,
            };
            Ok((start, candidates))
        },
        |_, candidates| {
            candidates
                .iter()
                .enumerate()
                .filter(|(_, c)| c.delta_bic < BIC_THRESHOLD && c.improves_every_level)
                .min_by(|a, b| a.1.delta_bic.total_cmp(&b.1.delta_bic))
                .map(|(i, _)| i)
        },
        |(_, mut accepted_effects), c| {
            match c
                .generalises
                .and_then(|r| accepted_effects.iter().position(|&x| x == r))
            {
                Some(i) => accepted_effects[i] = c.effect,
                None => accepted_effects.push(c.effect),
            }
            accepted_effects.extend(c.jointly_with);
            Ok((c.fit.clone(), accepted_effects))
        },
    )?;
    let (current, accepted_effects) = state;
    let rounds: Vec<Round<S::Model>> = core_rounds
        .into_iter()
        .map(|r| Round {
            base_effects: r.meta.base_effects,
            base_held_out: r.meta.base_held_out,
            lag1_autocorrelation: r.meta.rho,
            effective_samples: r.meta.n_eff,
            accepted: r.accepted.map(|i| r.candidates[i].effect),
            accepted_with: r.accepted.and_then(|i| r.candidates[i].jointly_with),
            candidates: r.candidates,
        })
        .collect();
    let final_held = score::<S>(&current.model, levels, &held)?;
    let base_held = score::<S>(&base_fit.model, levels, &held)?;
    let verdict = if !accepted_effects.is_empty() {
        Verdict::EffectsFound {
            effects: accepted_effects,
            at_scatter: final_held.cost <= SCATTER_FACTOR * floor,
        }
    } else if base_held.cost <= SCATTER_FACTOR * floor {
        Verdict::NoEffectNeeded
    } else {
        Verdict::Unexplained {
            held_out_cost: base_held.cost,
            scatter_floor: floor,
        }
    };
    Ok(Selection {
        baseline_train_fit: base_fit,
        final_spec: S::spec_of(&current.model).clone(),
        final_train_fit: current,
        rounds,
        scatter_floor: floor,
        relative_scatter_per_level: levels.iter().map(relative_scatter).collect(),
        verdict,
    })
}

/// The held-out evidence a round judges its candidates by: the current model's held-out
/// residual, the effective sample size and the current parameter count.
struct Evidence<'a, S> {
    levels: &'a [LevelData],
    held: &'a [Vec<bool>],
    base_held: &'a HeldOut,
    n_eff: f64,
    base_params: usize,
    family: std::marker::PhantomData<S>,
}

impl<S: Extensible> Evidence<'_, S> {
    /// Score a fitted candidate (`effect`, with `jointly_with` for a pair) on the held-out rows:
    /// `ΔBIC = n_eff·ln(J_new/J_old) + Δp·ln(n_eff)` and whether every level's residual fell.
    fn judge(
        &self,
        cspec: &S,
        effect: Effect,
        jointly_with: Option<Effect>,
        generalises: Option<Effect>,
        fit: FitResult<S::Model>,
    ) -> Result<Candidate<S::Model>> {
        let h = score::<S>(&fit.model, self.levels, self.held)?;
        let dp = (cspec.params().len() - self.base_params) as f64;
        Ok(Candidate {
            effect,
            generalises,
            jointly_with,
            meaning: effect.meaning(),
            added_parameters: dp as usize,
            train_cost: fit.cost,
            delta_bic: held_out::delta_bic(
                self.n_eff,
                h.cost + NUMERICAL_COST_FLOOR,
                self.base_held.cost + NUMERICAL_COST_FLOOR,
                dp as usize,
            ),
            improves_every_level: h
                .per_level
                .iter()
                .zip(&self.base_held.per_level)
                .all(|(a, b)| a < b),
            held_out: h,
            converged: fit.converged,
            evaluations: fit.evaluations,
            wall_time_s: fit.wall_time_s,
            refined: false,
            fit,
        })
    }

    /// With [`SelectOptions::refine`], a screened candidate whose held-out `ΔBIC` is below
    /// [`REFINE_BELOW`] refitted from its optimum by Nelder–Mead with those settings and judged
    /// again; any other candidate as it is.
    fn refined(
        &self,
        c: Candidate<S::Model>,
        fit_levels: &[LevelData],
        train: &[Vec<bool>],
        opts: &SelectOptions,
        progress: Option<&indicatif::ProgressBar>,
    ) -> Result<Candidate<S::Model>> {
        let Some(refine) = &opts.refine else {
            return Ok(c);
        };
        if c.delta_bic.is_nan() || c.delta_bic >= REFINE_BELOW {
            return Ok(c);
        }
        let cspec = S::spec_of(&c.fit.model).clone();
        let start = S::values_of(&c.fit.model).to_vec();
        let fit = fit_local(&cspec, fit_levels, train, &[start], refine, progress)?;
        let evaluations = c.evaluations + fit.evaluations;
        let wall_time_s = c.wall_time_s + fit.wall_time_s;
        let mut r = self.judge(&cspec, c.effect, c.jointly_with, c.generalises, fit)?;
        r.evaluations = evaluations;
        r.wall_time_s = wall_time_s;
        r.refined = true;
        Ok(r)
    }
}

/// A screened candidate is refined when its held-out `ΔBIC` is below this (the evidence leans
/// to it; the acceptance threshold [`BIC_THRESHOLD`] is ten below).
pub const REFINE_BELOW: f64 = 0.0;

/// Refit a model on all rows of the fit levels (local, from its training optimum).
pub fn refit_all_rows<S: Extensible>(
    from: &FitResult<S::Model>,
    levels: &[LevelData],
    opts: &FitOptions,
    progress: Option<&indicatif::ProgressBar>,
) -> Result<FitResult<S::Model>> {
    let all: Vec<Vec<bool>> = levels.iter().map(|l| vec![true; l.drives.len()]).collect();
    fit_local(
        S::spec_of(&from.model),
        levels,
        &all,
        &[S::values_of(&from.model).to_vec()],
        opts,
        progress,
    )
}

/// The objective of a model of the family `spec` over all rows of some levels.
pub fn cost_all_rows<S: Parametrised>(spec: &S, model: &S::Model, levels: &[LevelData]) -> f64 {
    let all: Vec<Vec<bool>> = levels.iter().map(|l| vec![true; l.drives.len()]).collect();
    Objective::new(spec.clone(), levels, &all).cost_of(model).0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::identify::measured::Quantity;
    use crate::identify::model::Drive;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    /// 41 rows of a lightly damped resonance (80.2 Hz, ζ = 0.3 %, peak about 2.6) at
    /// 79.2–81.2 Hz, each row's exact response passed through `measured_of`; peak 1.
    fn resonance_level(mut measured_of: impl FnMut(Complex64) -> Complex64) -> LevelData {
        let drives: Vec<Drive> = (0..41)
            .map(|i| Drive {
                omega: std::f64::consts::TAU * (79.2 + 0.05 * i as f64),
                force_n: 1.0,
            })
            .collect();
        let w0 = std::f64::consts::TAU * 80.2;
        let measured: Vec<Complex64> = drives
            .iter()
            .map(|d| {
                let h = 1.0 / Complex64::new(w0 * w0 - d.omega * d.omega, 0.006 * w0 * d.omega);
                measured_of(h * 3.9e3)
            })
            .collect();
        LevelData {
            name: "x".into(),
            quantity: Quantity::Displacement,
            drives,
            lines: vec![0; 41],
            mean_force_n: 1.0,
            peak: 1.0,
            measured,
        }
    }

    /// The third-difference estimate recovers the scatter of white noise on a smooth
    /// resonance within 15 % (41 rows, 20 realisations averaged).
    #[test]
    fn scatter_of_white_noise_on_a_resonance() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let s = 0.01;
        let noise = Normal::new(0.0, s).unwrap();
        let mut est = 0.0;
        for _ in 0..20 {
            let l = resonance_level(|y| {
                y + Complex64::new(noise.sample(&mut rng), noise.sample(&mut rng))
            });
            est += relative_scatter(&l) / 20.0;
        }
        assert!((est / s - 1.0).abs() < 0.15, "{est} vs {s}");
    }

    /// Noise proportional to the response (1 % of each row's own value per component, as a
    /// gain error gives): [`proportional_scatter`] recovers it within 15 % (same resonance, 20
    /// realisations averaged), while [`relative_scatter`], which reads noise as a constant
    /// fraction of the peak, puts it at less than half of 1 % of the peak — the noise of the
    /// rows near the peak it would therefore understate by more than 2×.
    #[test]
    fn scatter_of_noise_proportional_to_the_response() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let s = 0.01;
        let noise = Normal::new(0.0, s).unwrap();
        let (mut proportional, mut constant) = (0.0, 0.0);
        for _ in 0..20 {
            let mut l = resonance_level(|y| {
                y * (1.0 + Complex64::new(noise.sample(&mut rng), noise.sample(&mut rng)))
            });
            l.peak = l.measured.iter().map(|v| v.norm()).fold(0.0, f64::max);
            proportional += proportional_scatter(&l) / 20.0;
            constant += relative_scatter(&l) / 20.0;
        }
        assert!(
            (proportional / s - 1.0).abs() < 0.15,
            "{proportional} vs {s}"
        );
        assert!(constant < 0.5 * s, "{constant} vs {s}");
    }
}
