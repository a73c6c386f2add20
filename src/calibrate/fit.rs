//! Least-squares fit of Valanis parameters (E0, k, optionally Et; μ fixed) to a hysteresis loop.
//!
//! # Problem
//!
//! Given a displacement history `q_i` driving a contact from its virgin state, the measured (or
//! BEM-computed) tangential force `F_i`, the normal load `Fz_i` and the index range of the steady
//! cycle, minimise
//!
//! ```text
//! J(E0, k, Et) = Σ_{i ∈ steady} (F_i − F_model,i)² / Σ_{i ∈ steady} (F_i − mean F)²   = 1 − R²
//! ```
//!
//! Several loops (one element at several amplitudes, [`fit_valanis_loops`]) are fitted together
//! by minimising the **mean of their `1 − R²`**: each loop counts the same whatever its force
//! level, so that the microslip loops, whose forces are a fraction of the gross-slip ones, are
//! not drowned by them. Each loop drives the element from its own virgin state.
//!
//! where `F_model` is the Valanis element ([`crate::element::valanis`]) driven through the whole
//! history with the accurate reference integrator (so that the fit identifies the element's
//! parameters, not the discretisation error of a time stepper). Units as in the element module:
//! per unit nominal area (m, Pa, N/m³) in the calibration pipeline.
//!
//! # Method
//!
//! Nelder–Mead simplex of [`crate::core::fit`] on transformed parameters that keep the
//! constraints by construction: `E0 = E0_ref·exp(θ₀)` (> 0, [`ParamSpec::exp`]),
//! `k = σ(θ₁)` (in (0, 1)), `Et = E0·σ(θ₂)` (in [0, E0)), with `σ` the logistic function
//! ([`ParamSpec::logit`]). Several starts (default k₀ = 0.1, 0.5, 0.9) with `E0` from the
//! steepest slope of the data (the reload slope `2E0/(1+k)`), best result kept.
//!
//! # Reported quality
//!
//! R² on the steady cycle, normalised RMS error (RMS residual over the peak-to-peak force of the
//! cycle) and the relative error of the energy dissipated per cycle `∮F dq`.

use crate::core::error::{Error, Result};
use crate::core::fit::{self as core_fit, LocalSearch, ParamSpec, Restarts, Tolerance};
use crate::element::dissipated_energy;
use crate::element::valanis::{integrate_reference, ValanisParams};
use std::ops::Range;
use std::time::{Duration, Instant};

/// A hysteresis record to fit: the whole history from the virgin state.
#[derive(Debug, Clone)]
pub struct LoopData {
    /// Tangential displacement history (m), starting from the virgin (unloaded) state.
    pub q: Vec<f64>,
    /// Tangential force history (Pa per area, or N).
    pub force: Vec<f64>,
    /// Normal load history (Pa per area, or N), same length.
    pub normal_load: Vec<f64>,
    /// Indices of the steady cycle (one closed period) on which the fit is measured.
    pub steady: Range<usize>,
}

impl LoopData {
    /// A loop under constant normal load.
    pub fn constant_load(
        q: Vec<f64>,
        force: Vec<f64>,
        normal_load: f64,
        steady: Range<usize>,
    ) -> Self {
        let n = q.len();
        Self {
            q,
            force,
            normal_load: vec![normal_load; n],
            steady,
        }
    }

    fn validate(&self) -> Result<()> {
        let n = self.q.len();
        if self.force.len() != n || self.normal_load.len() != n {
            return Err(Error::param(
                "loop",
                format!(
                    "q, force and normal_load lengths differ ({n}, {}, {})",
                    self.force.len(),
                    self.normal_load.len()
                ),
            ));
        }
        if self.steady.start >= self.steady.end || self.steady.end > n || self.steady.len() < 8 {
            return Err(Error::param(
                "steady",
                format!(
                    "range {:?} is not a cycle of at least 8 samples within 0..{n}",
                    self.steady
                ),
            ));
        }
        if self
            .q
            .iter()
            .chain(&self.force)
            .chain(&self.normal_load)
            .any(|v| !v.is_finite())
        {
            return Err(Error::Data("loop contains non-finite samples".into()));
        }
        Ok(())
    }
}

/// Fit settings.
#[derive(Debug, Clone, PartialEq)]
pub struct FitOptions {
    /// Friction coefficient, held fixed.
    pub mu: f64,
    /// Fit the residual stiffness Et too (otherwise Et = 0).
    pub fit_et: bool,
    /// Nelder–Mead iteration cap per start.
    pub max_iters: u64,
    /// Starting values of k, one Nelder–Mead run each (each in [0, 1)); the best is kept.
    pub k_starts: Vec<f64>,
}

impl Default for FitOptions {
    fn default() -> Self {
        Self {
            mu: 0.6,
            fit_et: false,
            max_iters: 600,
            k_starts: vec![0.1, 0.5, 0.9],
        }
    }
}

/// Quality of the fitted element on one loop.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct LoopFit {
    /// Coefficient of determination on the steady cycle.
    pub r2: f64,
    /// RMS residual over the peak-to-peak force of the steady cycle.
    pub nrmse: f64,
    /// Energy dissipated per cycle by the data, `∮F dq` over the steady cycle.
    pub energy_data: f64,
    /// Energy dissipated per cycle by the fitted element (same samples, same quadrature).
    pub energy_model: f64,
    /// `(energy_model − energy_data)/energy_data`.
    pub energy_rel_error: f64,
    /// Model force over the whole history (same samples as the data).
    pub model_force: Vec<f64>,
}

/// Result of [`fit_valanis`] / [`fit_valanis_loops`].
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct FitResult {
    /// Best parameters (μ as given).
    pub params: ValanisParams,
    /// Mean coefficient of determination over the loops (`1 −` the final cost).
    pub r2: f64,
    /// The fitted element on each loop, in the order given.
    pub loops: Vec<LoopFit>,
    /// Nelder–Mead iterations summed over the starts.
    pub iterations: u64,
    /// Final cost, the mean of `1 − R²` over the loops, of the best start.
    pub final_cost: f64,
    /// True if the best start stopped on its simplex tolerance (not on the iteration cap).
    pub converged: bool,
    /// Wall time of the whole fit.
    pub wall_time: Duration,
}

/// R² and normalised RMS error of `model` against `data`.
pub fn goodness_of_fit(data: &[f64], model: &[f64]) -> (f64, f64) {
    let n = data.len().max(1) as f64;
    let mean = data.iter().sum::<f64>() / n;
    let ss_tot: f64 = data.iter().map(|d| (d - mean).powi(2)).sum();
    let ss_res: f64 = data.iter().zip(model).map(|(d, m)| (d - m).powi(2)).sum();
    let (lo, hi) = data
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        });
    let r2 = if ss_tot > 0.0 {
        1.0 - ss_res / ss_tot
    } else {
        f64::NAN
    };
    (r2, (ss_res / n).sqrt() / (hi - lo))
}

/// The loops and what the fit holds fixed: the cost of a parameter set.
struct Problem<'a> {
    loops: &'a [LoopData],
    mu: f64,
    fit_et: bool,
    /// Total sum of squares of each loop's steady cycle.
    ss_tot: Vec<f64>,
}

impl Problem<'_> {
    /// The element of the fitted values `[E0, k]` or `[E0, k, Et/E0]`.
    fn params(&self, v: &[f64]) -> ValanisParams {
        ValanisParams {
            e0: v[0],
            k: v[1],
            et: if self.fit_et { v[0] * v[2] } else { 0.0 },
            mu: self.mu,
        }
    }

    fn model(&self, p: &ValanisParams, data: &LoopData) -> Result<Vec<f64>> {
        let end = data.steady.end;
        integrate_reference(p, &data.q[..end], &data.normal_load[..end])
    }

    /// Mean over the loops of `1 − R²`.
    fn cost(&self, p: &ValanisParams) -> Result<f64> {
        let mut total = 0.0;
        for (data, ss_tot) in self.loops.iter().zip(&self.ss_tot) {
            let model = self.model(p, data)?;
            let r = data.steady.clone();
            let ss: f64 = data.force[r.clone()]
                .iter()
                .zip(&model[r])
                .map(|(d, m)| (d - m).powi(2))
                .sum();
            total += ss / ss_tot;
        }
        Ok(total / self.loops.len() as f64)
    }
}

impl core_fit::Objective for Problem<'_> {
    fn cost(&self, values: &[f64]) -> f64 {
        // Parameters the integrator cannot follow are simply bad parameters.
        self.cost(&self.params(values)).unwrap_or(f64::MAX)
    }
}

/// The fitted parameters: `E0` about the data's steepest slope, `k`, and `Et/E0` if fitted.
fn param_specs(slope: f64, k0: f64, fit_et: bool) -> Vec<ParamSpec> {
    let mut p = vec![
        ParamSpec::exp("E0", "Pa/m", slope, slope * (1.0 + k0) / 2.0),
        ParamSpec::logit("k", "-", 0.0, 1.0, k0),
    ];
    if fit_et {
        p.push(ParamSpec::logit("Et/E0", "-", 0.0, 1.0, 0.01));
    }
    p
}

/// Fit E0, k (and Et if `opts.fit_et`) of a Valanis element to `data` with μ fixed.
pub fn fit_valanis(data: &LoopData, opts: &FitOptions) -> Result<FitResult> {
    fit_valanis_loops(std::slice::from_ref(data), opts)
}

/// Fit one Valanis element (E0, k, and Et if `opts.fit_et`; μ fixed) to several loops together:
/// the mean of their `1 − R²` is minimised (see the module documentation).
pub fn fit_valanis_loops(loops: &[LoopData], opts: &FitOptions) -> Result<FitResult> {
    let started = Instant::now();
    if loops.is_empty() {
        return Err(Error::param("loops", "give at least one loop to fit"));
    }
    crate::core::error::require_positive("mu", opts.mu)?;
    let mut ss_tot = Vec::with_capacity(loops.len());
    let mut slope: f64 = 0.0;
    for data in loops {
        data.validate()?;
        let f_steady = &data.force[data.steady.clone()];
        let mean = f_steady.iter().sum::<f64>() / f_steady.len() as f64;
        let ss: f64 = f_steady.iter().map(|f| (f - mean).powi(2)).sum();
        if ss <= 0.0 {
            return Err(Error::Data(
                "loop force is constant on the steady cycle: nothing to fit".into(),
            ));
        }
        ss_tot.push(ss);
        // Steepest secant slope of the data: close to the reload slope 2E0/(1+k).
        slope = data
            .q
            .windows(2)
            .zip(data.force.windows(2))
            .filter(|(q, _)| q[1] != q[0])
            .map(|(q, f)| ((f[1] - f[0]) / (q[1] - q[0])).abs())
            .fold(slope, f64::max);
    }
    if !(slope > 0.0 && slope.is_finite()) {
        return Err(Error::Data(
            "loop has no finite positive slope to start the fit from".into(),
        ));
    }
    let problem = Problem {
        loops,
        mu: opts.mu,
        fit_et: opts.fit_et,
        ss_tot,
    };
    if opts.k_starts.is_empty() {
        return Err(Error::param("k_starts", "give at least one start"));
    }
    if let Some(k) = opts
        .k_starts
        .iter()
        .find(|k| !(k.is_finite() && (0.0..1.0).contains(*k)))
    {
        return Err(Error::param(
            "k_starts",
            format!("each k must satisfy 0 <= k < 1, got {k}"),
        ));
    }
    // One Nelder–Mead run per start of k, E0 from the slope; the transforms do not depend on
    // the start, only the start points do.
    let params = param_specs(slope, 0.5, opts.fit_et);
    let starts: Vec<Vec<f64>> = opts
        .k_starts
        .iter()
        .map(|&k_start| {
            let k0 = k_start.clamp(1e-6, 1.0 - 1e-6);
            param_specs(slope, k0, opts.fit_et)
                .iter()
                .map(|p| p.start_coordinate())
                .collect()
        })
        .collect();
    let local = LocalSearch {
        max_iters: opts.max_iters,
        tolerance: Tolerance::Absolute(1e-12),
        first_step: 1.0,
        restart_step: 1.0,
        restarts: Restarts::UntilConverged(0),
    };
    let search = core_fit::local_search(&params, &problem, &starts, &local, None)
        .map_err(|e| Error::Data(format!("Valanis fit failed: {e}")))?;
    let iterations = search.starts.iter().map(|s| s.local_iterations).sum();
    let (cost, converged) = (search.best.cost, search.best.converged);
    let params = problem.params(&search.best.values);
    let mut fits = Vec::with_capacity(loops.len());
    for data in loops {
        let model_force = problem.model(&params, data)?;
        let steady = data.steady.clone();
        let f_steady = &data.force[steady.clone()];
        let (r2, nrmse) = goodness_of_fit(f_steady, &model_force[steady.clone()]);
        let q_steady = &data.q[steady.clone()];
        let energy_data = dissipated_energy(q_steady, f_steady);
        let energy_model = dissipated_energy(q_steady, &model_force[steady]);
        fits.push(LoopFit {
            r2,
            nrmse,
            energy_data,
            energy_model,
            energy_rel_error: (energy_model - energy_data) / energy_data,
            model_force,
        });
    }
    Ok(FitResult {
        params,
        r2: 1.0 - cost,
        loops: fits,
        iterations,
        final_cost: cost,
        converged,
        wall_time: started.elapsed(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::sine_history;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    /// Three cycles of a sine history reaching 2.5× the elastic limit displacement μFz/E0
    /// (microslip onset, transition and gross slip all present), 500 samples per cycle, Gaussian
    /// noise of standard deviation `noise`·μFz on the force.
    fn synthetic(truth: &ValanisParams, fz: f64, noise: f64, seed: u64) -> LoopData {
        let per = 500;
        let amp = 2.5 * truth.mu * fz / truth.e0;
        let q = sine_history(amp, 3, per);
        let fzs = vec![fz; q.len()];
        let mut f = integrate_reference(truth, &q, &fzs).unwrap();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let n = Normal::new(0.0, noise * truth.mu * fz).unwrap();
        for v in &mut f {
            *v += n.sample(&mut rng);
        }
        let len = q.len();
        LoopData::constant_load(q, f, fz, len - per - 1..len)
    }

    #[test]
    fn recovers_e0_and_k_without_noise() {
        let truth = ValanisParams::new(5.0e12, 0.35, 0.0, 0.6).unwrap();
        let data = synthetic(&truth, 1e6, 0.0, 1);
        let fit = fit_valanis(&data, &FitOptions::default()).unwrap();
        assert!(
            (fit.params.e0 / truth.e0 - 1.0).abs() < 1e-4,
            "{:?}",
            fit.params
        );
        assert!((fit.params.k - truth.k).abs() < 1e-4, "{:?}", fit.params);
        assert!(fit.r2 > 0.999_999);
        assert!(fit.loops[0].energy_rel_error.abs() < 1e-4);
    }

    /// Done-when 1: loops from known parameters with 1% noise are fitted back within 2%.
    #[test]
    fn recovers_e0_k_et_from_noisy_loops_within_two_percent() {
        let truths = [
            ValanisParams::new(5.0e12, 0.35, 2.0e11, 0.6).unwrap(),
            ValanisParams::new(2.0e13, 0.7, 1.0e12, 0.6).unwrap(),
            ValanisParams::new(8.0e11, 0.15, 4.0e10, 0.6).unwrap(),
        ];
        let opts = FitOptions {
            fit_et: true,
            ..FitOptions::default()
        };
        for (seed, truth) in truths.iter().enumerate() {
            let data = synthetic(truth, 2e6, 0.01, seed as u64 + 7);
            let exact = fit_valanis(&synthetic(truth, 2e6, 0.0, 0), &opts).unwrap();
            eprintln!("noise-free: {:?}", exact.params);
            let fit = fit_valanis(&data, &opts).unwrap();
            let p = fit.params;
            eprintln!(
                "1% noise: {p:?} (iterations {}, converged {})",
                fit.iterations, fit.converged
            );
            let rel = |a: f64, b: f64| (a / b - 1.0).abs();
            assert!(rel(p.e0, truth.e0) < 0.02, "E0 {:?} vs {truth:?}", p);
            assert!(rel(p.k, truth.k) < 0.02, "k {:?} vs {truth:?}", p);
            assert!(rel(p.et, truth.et) < 0.02, "Et {:?} vs {truth:?}", p);
            assert!(fit.r2 > 0.99);
        }
    }

    #[test]
    fn goodness_of_perfect_and_mean_models() {
        let d = [1.0, 2.0, 3.0, 4.0];
        assert_eq!(goodness_of_fit(&d, &d), (1.0, 0.0));
        assert!(goodness_of_fit(&d, &[2.5; 4]).0.abs() < 1e-12);
    }

    #[test]
    fn bad_loops_are_refused() {
        let q = vec![0.0; 20];
        let data = LoopData::constant_load(q.clone(), vec![0.0; 20], 1.0, 0..20);
        assert!(fit_valanis(&data, &FitOptions::default()).is_err());
        let short = LoopData::constant_load(q.clone(), vec![0.0; 20], 1.0, 0..3);
        assert!(fit_valanis(&short, &FitOptions::default()).is_err());
        let mismatched = LoopData::constant_load(q, vec![0.0; 19], 1.0, 0..10);
        assert!(fit_valanis(&mismatched, &FitOptions::default()).is_err());
    }
}
