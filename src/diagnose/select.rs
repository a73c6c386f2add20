//! Fitting and effect selection that does not reward flexibility.
//!
//! 1. The complete cycles are split alternately into a training set (cycles 0, 2, 4, …) and a
//!    held-out set (1, 3, 5, …). The model is always driven by the whole displacement history
//!    (the element has memory) but parameters are fitted on training samples only (least squares,
//!    Nelder–Mead in transformed variables, restarted once from its optimum).
//! 2. Each candidate effect not yet in the model is added and the model refitted; it is scored on
//!    the held-out samples with the Bayesian information criterion (Schwarz 1978)
//!    `ΔBIC = n_eff·ln(RSS_new/RSS_old) + Δp·ln(n_eff)`, where `n_eff = n·(1−ρ)/(1+ρ)` is the
//!    effective number of independent held-out samples for residuals with lag-1 autocorrelation
//!    `ρ` (AR(1) variance inflation), so that oversampled, correlated residuals do not count as
//!    independent evidence.
//! 3. The best candidate is accepted only when `ΔBIC < −10` ("very strong" evidence on the
//!    Kass–Raftery 1995 scale); otherwise the answer is "no effect needed". Accepted effects are
//!    kept and the search repeats for a further effect, up to `max_effects`.

use super::cycles::{classify_phases, segment, Cycles, Phase};
use super::effects::{Baseline, Drive, Effect, Model, ParamSpec};
use super::record::Record;
use crate::element::valanis::ValanisParams;
use crate::error::{Error, Result};
use argmin::core::{CostFunction, Executor, State};
use argmin::solver::neldermead::NelderMead;
use rayon::prelude::*;
use serde::Serialize;

/// Evidence threshold on ΔBIC for accepting an effect.
pub const BIC_THRESHOLD: f64 = -10.0;
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

/// A record prepared for analysis: decimated, segmented, with train / held-out masks.
#[derive(Debug, Clone)]
pub struct Prepared {
    /// The (block-averaged) record that is analysed.
    pub record: Record,
    /// Block-averaging factor applied to the input record.
    pub decimation: usize,
    pub cycles: Cycles,
    pub drive: Drive,
    /// Samples of training cycles.
    pub train: Vec<bool>,
    /// Samples of held-out cycles.
    pub held_out: Vec<bool>,
}

fn percentile(x: &[f64], q: f64) -> f64 {
    let mut v = x.to_vec();
    v.sort_by(|a, b| a.total_cmp(b));
    v[((v.len() - 1) as f64 * q).round() as usize]
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
    let velocity: Vec<f64> = (0..n)
        .map(|i| {
            let (a, b) = (i.saturating_sub(1), (i + 1).min(n - 1));
            dxs[i] * (b - a) as f64 / (t[b] - t[a])
        })
        .collect();
    let t0 = t[cycles.reversals[0]];
    let tau = std::f64::consts::TAU;
    let normal_ratio = record.normal_force_n.as_ref().map(|nf| {
        let mean = nf.iter().sum::<f64>() / nf.len() as f64;
        nf.iter().map(|v| v / mean).collect()
    });
    let force_scale =
        0.5 * (percentile(&record.force_n, 0.995) - percentile(&record.force_n, 0.005));
    if force_scale <= 0.0 || force_scale.is_nan() {
        return Err(Error::Data(
            "the measured force is constant: nothing to fit".into(),
        ));
    }
    let abs_v: Vec<f64> = velocity.iter().map(|v| v.abs()).collect();
    let drive = Drive {
        time_s: t.clone(),
        q_m: xs.iter().map(|v| v - centre).collect(),
        velocity_scale: percentile(&abs_v, 0.99).max(1e-300),
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
    let mut train = vec![false; n];
    let mut held_out = vec![false; n];
    for (k, &(a, b)) in cycles.cycles.iter().enumerate() {
        let mask = if k % 2 == 0 {
            &mut train
        } else {
            &mut held_out
        };
        mask[a..b].iter_mut().for_each(|m| *m = true);
    }
    Ok(Prepared {
        record,
        decimation: m,
        cycles,
        drive,
        train,
        held_out,
    })
}

/// A model structure (baseline source + effects) with its parameter specifications.
#[derive(Debug, Clone)]
struct Structure {
    given: Option<Baseline>,
    normal_n: f64,
    baseline_specs: Vec<ParamSpec>,
    effects: Vec<(Effect, Vec<ParamSpec>)>,
}

impl Structure {
    fn decode(&self, z: &[f64]) -> Model {
        let mut i = 0;
        let baseline = match self.given {
            Some(b) => b,
            None => {
                let e0 = self.baseline_specs[0].value(z[0]);
                let k = self.baseline_specs[1].value(z[1]);
                let slip = self.baseline_specs[2].value(z[2]);
                i = 3;
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
                let v = specs
                    .iter()
                    .map(|s| {
                        let v = s.value(z[i]);
                        i += 1;
                        v
                    })
                    .collect();
                (*e, v)
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

/// Training cost: mean squared force residual over training samples, in units of the force
/// scale squared.
struct Problem<'a> {
    structure: &'a Structure,
    prep: &'a Prepared,
}

impl CostFunction for Problem<'_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, z: &Vec<f64>) -> std::result::Result<f64, argmin::core::Error> {
        let f = self.structure.decode(z).simulate(&self.prep.drive);
        Ok(masked_mse(&f, &self.prep.record.force_n, &self.prep.train)
            / self.prep.drive.force_scale_n.powi(2))
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
    pub iterations: u64,
    /// Final training cost (mean squared residual / force scale²).
    pub final_cost: f64,
    pub converged: bool,
    pub wall_time_s: f64,
}

fn fit(structure: &Structure, z0: Vec<f64>, prep: &Prepared, max_iter: u64) -> (Vec<f64>, FitInfo) {
    let start = std::time::Instant::now();
    if z0.is_empty() {
        let cost = Problem { structure, prep }
            .cost(&z0)
            .unwrap_or(f64::INFINITY);
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
    let steps: Vec<f64> = structure.specs().map(|s| s.step()).collect();
    let (mut z, mut iterations, mut converged, mut cost) = (z0, 0, false, f64::INFINITY);
    // Nelder–Mead, restarted from its optimum with a fresh simplex (Numerical Recipes §10.5).
    for round in 0..2 {
        let scale = if round == 0 { 1.0 } else { 0.3 };
        let mut simplex = vec![z.clone()];
        for (j, s) in steps.iter().enumerate() {
            let mut v = z.clone();
            v[j] += s * scale;
            simplex.push(v);
        }
        let solver = NelderMead::new(simplex)
            .with_sd_tolerance(1e-13)
            .expect("valid tolerance");
        match Executor::new(Problem { structure, prep }, solver)
            .configure(|s| s.max_iters(max_iter))
            .run()
        {
            Ok(res) => {
                let st = res.state();
                iterations += st.get_iter();
                if st.get_best_cost() <= cost {
                    cost = st.get_best_cost();
                    if let Some(p) = st.get_best_param() {
                        z = p.clone();
                    }
                }
                converged = st.get_iter() < max_iter;
            }
            Err(_) => break,
        }
    }
    (
        z,
        FitInfo {
            iterations,
            final_cost: cost,
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
    Errors {
        nrms: masked_mse(f, y, &all).sqrt() / fs,
        peak_force_error: peak / nc,
        energy_error: en / nc,
        held_out_nrms: masked_mse(f, y, &prep.held_out).sqrt() / fs,
    }
}

/// Residual statistics of one phase.
#[derive(Debug, Clone, Serialize)]
pub struct PhaseStats {
    pub phase: Phase,
    pub samples: usize,
    /// Mean residual (measured − model) signed in the direction of motion, / force amplitude.
    pub mean_residual: f64,
    /// RMS residual / force amplitude.
    pub rms_residual: f64,
}

/// Per-phase residual statistics, with phases classified from the model force `f`.
pub fn phase_stats(prep: &Prepared, f: &[f64]) -> Vec<PhaseStats> {
    let x = &prep.record.displacement_m;
    let y = &prep.record.force_n;
    let phases = classify_phases(x, f, &prep.cycles);
    let fs = prep.drive.force_scale_n;
    Phase::ALL
        .iter()
        .map(|&ph| {
            let idx: Vec<usize> = (0..y.len()).filter(|&i| phases[i] == Some(ph)).collect();
            let n = idx.len().max(1) as f64;
            let signed = |i: usize| (y[i] - f[i]) * prep.drive.velocity_m_per_s[i].signum();
            PhaseStats {
                phase: ph,
                samples: idx.len(),
                mean_residual: idx.iter().map(|&i| signed(i)).sum::<f64>() / n / fs,
                rms_residual: (idx.iter().map(|&i| (y[i] - f[i]).powi(2)).sum::<f64>() / n).sqrt()
                    / fs,
            }
        })
        .collect()
}

/// Evidence for one candidate effect in one round.
#[derive(Debug, Clone, Serialize)]
pub struct Candidate {
    pub effect: Effect,
    /// Parameter names with units and fitted values.
    pub parameters: Vec<(String, f64)>,
    pub extra_parameters: usize,
    pub train_nrms: f64,
    pub held_out_nrms: f64,
    /// Effective number of independent held-out samples.
    pub n_eff: f64,
    pub delta_bic: f64,
    pub fit: FitInfo,
    #[serde(skip)]
    model: Model,
    #[serde(skip)]
    z: Vec<f64>,
}

/// One round of the search: all candidates and the decision.
#[derive(Debug, Clone, Serialize)]
pub struct Round {
    pub candidates: Vec<Candidate>,
    /// The accepted effect, or `None` ("no further effect needed").
    pub accepted: Option<Effect>,
}

/// The result of the whole analysis.
#[derive(Debug, Clone)]
pub struct Diagnosis {
    pub prepared: Prepared,
    pub baseline: Model,
    pub baseline_fit: FitInfo,
    pub baseline_force: Vec<f64>,
    pub final_model: Model,
    pub final_force: Vec<f64>,
    pub rounds: Vec<Round>,
    pub errors_before: Errors,
    pub errors_after: Errors,
    pub phases_before: Vec<PhaseStats>,
    pub phases_after: Vec<PhaseStats>,
    pub n_parameters_before: usize,
    pub n_parameters_after: usize,
}

impl Diagnosis {
    /// Effects added, in order.
    pub fn effects_added(&self) -> Vec<Effect> {
        self.rounds.iter().filter_map(|r| r.accepted).collect()
    }
}

/// Lag-1 autocorrelation of the residual over the masked samples (contiguous pairs only).
fn lag1_autocorrelation(r: &[f64], mask: &[bool]) -> f64 {
    let idx: Vec<usize> = (0..r.len()).filter(|&i| mask[i]).collect();
    let mean = idx.iter().map(|&i| r[i]).sum::<f64>() / idx.len().max(1) as f64;
    let var: f64 = idx.iter().map(|&i| (r[i] - mean).powi(2)).sum();
    let cov: f64 = idx
        .windows(2)
        .filter(|w| w[1] == w[0] + 1)
        .map(|w| (r[w[0]] - mean) * (r[w[1]] - mean))
        .sum();
    if var > 0.0 {
        cov / var
    } else {
        0.0
    }
}

fn held_out_rss(prep: &Prepared, f: &[f64]) -> (f64, usize, f64) {
    let y = &prep.record.force_n;
    let r: Vec<f64> = f.iter().zip(y).map(|(a, b)| a - b).collect();
    let n = prep.held_out.iter().filter(|m| **m).count();
    let rss = masked_mse(f, y, &prep.held_out) * n as f64;
    (rss, n, lag1_autocorrelation(&r, &prep.held_out))
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

/// Run the whole diagnosis on a record.
pub fn diagnose(record: &Record, options: &Options) -> Result<Diagnosis> {
    let prep = prepare(record)?;
    let drive = &prep.drive;
    let normal_n = match (&options.baseline, &record.normal_force_n) {
        (BaselineSource::Given(b), _) => b.normal_n,
        (_, Some(nf)) => nf.iter().sum::<f64>() / nf.len() as f64,
        (_, None) => 1.0,
    };
    let stiff = drive.force_scale_n / drive.amplitude_m;
    let (given, baseline_specs, z_base) = match &options.baseline {
        BaselineSource::Given(b) => {
            b.valanis.validate()?;
            (Some(*b), vec![], vec![])
        }
        BaselineSource::Fitted => {
            let specs = vec![
                ParamSpec::log("e0", "N/m", stiff, initial_stiffness(&prep) / stiff),
                ParamSpec::unit_interval("k", "-", 0.98, 0.5),
                ParamSpec::log("slip_force", "N", drive.force_scale_n, 1.0),
            ];
            let z = specs.iter().map(|s| s.start_z()).collect();
            (None, specs, z)
        }
    };
    let base_structure = Structure {
        given,
        normal_n,
        baseline_specs,
        effects: vec![],
    };
    // The fitted baseline is started from two values of the shape parameter k and the better
    // optimum kept (the least-squares surface in (E0, k) has a long curved valley).
    let mut starts = vec![z_base.clone()];
    if given.is_none() {
        for k in [0.15, 0.8] {
            let mut z = z_base.clone();
            z[1] = base_structure.baseline_specs[1].z_of(k);
            starts.push(z);
        }
    }
    let (z_b, baseline_fit) = starts
        .into_par_iter()
        .map(|z| fit(&base_structure, z, &prep, options.max_iterations))
        .min_by(|a, b| a.1.final_cost.total_cmp(&b.1.final_cost))
        .expect("at least one start");
    let baseline = base_structure.decode(&z_b);
    let baseline_force = baseline.simulate(drive);

    let mut current = (base_structure.clone(), z_b.clone(), baseline_force.clone());
    let mut rounds = Vec::new();
    for _ in 0..options.max_effects {
        let remaining: Vec<Effect> = options
            .candidates
            .iter()
            .copied()
            .filter(|e| !current.0.effects.iter().any(|(k, _)| k == e))
            .collect();
        if remaining.is_empty() {
            break;
        }
        let (rss_old, _, _) = held_out_rss(&prep, &current.2);
        let current_model = current.0.decode(&current.1);
        let candidates: Vec<Candidate> = remaining
            .par_iter()
            .map(|&effect| {
                let mut specs = effect.params(drive);
                if effect == Effect::SeriesCompliance {
                    // Start stiff (nearly no effect) relative to the current element.
                    let e0 = current_model.baseline.valanis.e0;
                    specs[0].start = 20.0 * e0 / specs[0].scale;
                }
                let mut structure = current.0.clone();
                let mut z0 = current.1.clone();
                z0.extend(specs.iter().map(|s| s.start_z()));
                structure.effects.push((effect, specs.clone()));
                let (z, info) = fit(&structure, z0, &prep, options.max_iterations);
                let model = structure.decode(&z);
                let f = model.simulate(drive);
                let (rss, n, rho) = held_out_rss(&prep, &f);
                let rho = rho.clamp(0.0, 0.999);
                let n_eff = (n as f64 * (1.0 - rho) / (1.0 + rho)).max(2.0);
                let dp = specs.len() as f64;
                let delta_bic = n_eff * (rss / rss_old).ln() + dp * n_eff.ln();
                let params = model
                    .effects
                    .last()
                    .map(|(_, v)| v.clone())
                    .unwrap_or_default();
                Candidate {
                    effect,
                    parameters: specs
                        .iter()
                        .zip(params)
                        .map(|(s, v)| (format!("{} ({})", s.name, s.unit), v))
                        .collect(),
                    extra_parameters: specs.len(),
                    train_nrms: info.final_cost.sqrt(),
                    held_out_nrms: (rss / n as f64).sqrt() / drive.force_scale_n,
                    n_eff,
                    delta_bic: if delta_bic.is_finite() {
                        delta_bic
                    } else {
                        f64::INFINITY
                    },
                    fit: info,
                    model,
                    z,
                }
            })
            .collect();
        let best = candidates
            .iter()
            .filter(|c| c.delta_bic < BIC_THRESHOLD)
            .min_by(|a, b| a.delta_bic.total_cmp(&b.delta_bic))
            .cloned();
        let accepted = best.as_ref().map(|c| c.effect);
        rounds.push(Round {
            candidates,
            accepted,
        });
        match best {
            Some(c) => {
                let mut s = current.0.clone();
                s.effects.push((c.effect, c.effect.params(drive)));
                let f = c.model.simulate(drive);
                current = (s, c.z, f);
            }
            None => break,
        }
    }
    let final_model = current.0.decode(&current.1);
    let final_force = current.2;
    Ok(Diagnosis {
        errors_before: errors(&prep, &baseline_force),
        errors_after: errors(&prep, &final_force),
        phases_before: phase_stats(&prep, &baseline_force),
        phases_after: phase_stats(&prep, &final_force),
        n_parameters_before: base_structure.n_params(),
        n_parameters_after: current.0.n_params(),
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
