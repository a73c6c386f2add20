//! Uncertainty of an identified model and of its predictions: how far the levels not used may
//! lie from the prediction before the model must be called wrong.
//!
//! 1. **Gaussian approximation.** At the least-squares optimum `ẑ` (unit-box coordinates of the
//!    parameters not on a bound), the Gauss–Newton approximation of the estimator's covariance
//!    for the weighted objective `J = Σ_i w_i r_i²` (residual components `r_i`, real and
//!    imaginary parts of every row, `w_i = 1/(L·n_l)` as in [`super::fit::Objective`]) is the
//!    sandwich (Seber & Wild, *Nonlinear Regression*, 2003, §2.1 and §5.1)
//!
//!    `Σ_z = s² · (JᵀWJ)⁻¹ (JᵀW²J) (JᵀWJ)⁻¹ · (1+ρ)/(1−ρ)`,
//!
//!    with `J = ∂r/∂z` by central differences, `s² = Σ r_i² / (n − p)` the residual variance
//!    per component and `(1+ρ)/(1−ρ)` the variance inflation of residuals with lag-1
//!    autocorrelation `ρ` along the sweep (AR(1): `n_eff = n(1−ρ)/(1+ρ)`, the count the held-out
//!    ΔBIC uses). With equal weights it is the textbook `s²(JᵀJ)⁻¹`.
//! 2. **Ensemble of models that fit about as well.** A joint model is often sloppy: a Jenkins
//!    slider that slips at every measured amplitude fixes only combinations of its stiffness
//!    share, slip displacement and the mode's frequency, along curved valleys where a straight
//!    Gaussian step leaves the valley and predicts nonsense. The models are therefore drawn
//!    from the posterior `π(z) ∝ J(z)^(−n_eff/2)` (profiled Gaussian likelihood of the fit
//!    levels' residuals, flat prior on the box) by two adaptive Metropolis chains (Haario,
//!    Saksman & Tamminen 2001) from the optimum, the proposal started at a tenth of `Σ_z`
//!    (scaled by `2.38²/p`) and then following each chain's own covariance; the second halves
//!    are kept and thinned. The Gelman–Rubin `R̂` (Gelman & Rubin 1992) of `ln J` must be near 1
//!    (the chains agree on the fit); parameters with `R̂ > 1.1` are reported as not determined
//!    by the data, and each prediction carries its own `R̂`. (Importance sampling from the
//!    Gaussian collapsed on the Brake–Reuss beam: effective sample size 5 of 200.)
//! 3. **Prediction bands.** Every model of the ensemble is evaluated at every level's rows; the
//!    2.5 % and 97.5 % quantiles of the peak, resonance and phase resonance form the
//!    95 % band of each prediction (the parameters' intervals likewise). The residual a missing
//!    effect leaves counts as noise here: the band is the spread of models of this form that fit
//!    the fit levels about as well, not a bound on model-form error.
//!
//! Parameters on a bound are held at the bound: the data do not determine them, and their
//! one-sided uncertainty is not in the band (the report lists them). The ensemble is saved with
//! the model (`model.json`) so that `asperity predict` gives the same bands for any file.

use super::fit::{LevelData, Parametrised};
use super::model::{check_values, ParamSpec, NUMERICAL_COST_FLOOR};
use super::report::LevelErrors;
use super::select::{cost_all_rows, lag1_autocorrelation};
use crate::core::error::{Error, Result};
use crate::core::stats::quantile_hazen;
use nalgebra::{DMatrix, DVector, SymmetricEigen};
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use rayon::prelude::*;
use realfft::num_complex::Complex64;
use serde::{Deserialize, Serialize};

/// Central-difference step of the Jacobian in unit-box coordinates (0.1 % of the box; a
/// log-scaled parameter over three decades moves by 0.7 %).
pub const JACOBIAN_STEP: f64 = 1e-3;
/// Models kept in the ensemble (thinned from the chains).
pub const ENSEMBLE_DRAWS: usize = 200;
/// Seed of the draws (bands are reproducible).
pub const ENSEMBLE_SEED: u64 = 20261125;
/// Smallest eigenvalue of `JᵀWJ`, relative to its largest, for the parameters to count as
/// determined by the data (beyond it a direction of parameter space leaves the fit unchanged).
pub const IDENTIFIABLE_RATIO: f64 = 1e-12;

/// Estimator covariance of a weighted least-squares fit (the sandwich of the module
/// documentation, without the autocorrelation factor): `jacobian` is `n × p` (`∂r_i/∂z_j`),
/// `weights` the `w_i`, `residual_variance` `s²`. `Err` names the worst-determined parameter
/// when `JᵀWJ` is singular to [`IDENTIFIABLE_RATIO`].
pub fn sandwich_covariance(
    jacobian: &DMatrix<f64>,
    weights: &[f64],
    residual_variance: f64,
    names: &[String],
) -> Result<DMatrix<f64>> {
    let w = DVector::from_column_slice(weights);
    let wj = DMatrix::from_fn(jacobian.nrows(), jacobian.ncols(), |i, j| {
        w[i] * jacobian[(i, j)]
    });
    let bread = jacobian.transpose() * &wj;
    let meat = wj.transpose() * &wj;
    let eig = SymmetricEigen::new(bread.clone());
    let max = eig.eigenvalues.amax();
    let (k, min) = eig
        .eigenvalues
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(b.1))
        .map(|(k, &v)| (k, v))
        .ok_or_else(|| Error::Data("no free parameter".into()))?;
    if min.is_nan() || min <= IDENTIFIABLE_RATIO * max {
        let v = eig.eigenvectors.column(k);
        let j = v.iamax();
        return Err(Error::Data(format!(
            "parameters not determined by the data: the fit does not change along a direction \
             dominated by {} (eigenvalue ratio {:.1e})",
            names.get(j).map_or("?", |s| s.as_str()),
            min / max
        )));
    }
    let inv = eig.eigenvectors.clone()
        * DMatrix::from_diagonal(&eig.eigenvalues.map(|l| 1.0 / l))
        * eig.eigenvectors.transpose();
    Ok(&inv * meat * &inv * residual_variance)
}

/// The Gaussian approximation at the optimum (unit-box coordinates of the free parameters).
#[derive(Debug, Clone, Serialize)]
pub struct ParameterCovariance {
    /// Indices (into the model's parameters) of the free parameters.
    pub free: Vec<usize>,
    /// `Σ_z` (`p × p`, unit-box coordinates of the free parameters): the sandwich of the module
    /// documentation with the autocorrelation factor.
    #[serde(skip)]
    pub covariance_z: DMatrix<f64>,
    /// Residual standard deviation per component, relative to the level peaks.
    pub residual_sd: f64,
    /// Lag-1 autocorrelation `ρ` of the residuals along each sweep, in `[0, 0.95]`.
    pub lag1_autocorrelation: f64,
    /// `(1+ρ)/(1−ρ)`.
    pub variance_inflation: f64,
    /// Residual components `n` (real and imaginary parts of every row of the fit levels).
    pub components: usize,
}

impl ParameterCovariance {
    /// `n_eff = n / inflation`.
    pub fn effective_components(&self) -> f64 {
        self.components as f64 / self.variance_inflation
    }
}

/// Residuals of a model at every row of some levels, per level.
fn all_residuals<S: Parametrised>(
    model: &S::Model,
    levels: &[LevelData],
) -> Result<Vec<Vec<Complex64>>> {
    levels
        .iter()
        .map(|l| Ok(l.residuals(&S::frf(model, l)?.0)))
        .collect()
}

/// Residual components (real and imaginary parts, level after level) and their weights in the
/// objective, `1/(L·n_l)`.
fn components(per_level: &[Vec<Complex64>]) -> (Vec<f64>, Vec<f64>) {
    let (mut r, mut w) = (Vec::new(), Vec::new());
    for rl in per_level {
        let wl = 1.0 / (per_level.len() * rl.len()) as f64;
        for v in rl {
            r.extend([v.re, v.im]);
            w.extend([wl, wl]);
        }
    }
    (r, w)
}

/// Covariance of a model of the family `spec` fitted on all rows of `levels` (the model at its
/// optimum).
pub fn parameter_covariance<S: Parametrised>(
    spec: &S,
    model: &S::Model,
    levels: &[LevelData],
) -> Result<ParameterCovariance> {
    let params = spec.params();
    let values = S::values_of(model);
    let free: Vec<usize> = (0..params.len())
        .filter(|&j| !super::model::at_bound(&params[j], values[j]))
        .collect();
    if free.is_empty() {
        return Err(Error::Data("every parameter is on a bound".into()));
    }
    let z: Vec<f64> = params
        .iter()
        .zip(values)
        .map(|(p, &v)| p.coordinate_of(v))
        .collect();
    let at = |zj: &[f64]| spec.model(params.iter().zip(zj).map(|(p, &v)| p.value(v)).collect());
    let per_level = all_residuals::<S>(model, levels)?;
    let (r0, w) = components(&per_level);
    let columns: Vec<Vec<f64>> = free
        .iter()
        .map(|&j| {
            let shifted = |s: f64| {
                let mut zz = z.clone();
                zz[j] += s;
                all_residuals::<S>(&at(&zz), levels).map(|r| components(&r).0)
            };
            let (rp, rm) = (shifted(JACOBIAN_STEP)?, shifted(-JACOBIAN_STEP)?);
            Ok(rp
                .iter()
                .zip(&rm)
                .map(|(a, b)| (a - b) / (2.0 * JACOBIAN_STEP))
                .collect())
        })
        .collect::<Result<_>>()?;
    let n = r0.len();
    let jac = DMatrix::from_fn(n, free.len(), |i, k| columns[k][i]);
    // Residual variance, not below the solver's numerical floor (noise-free data).
    let s2 = (r0.iter().map(|v| v * v).sum::<f64>() / (n - free.len()).max(1) as f64)
        .max(NUMERICAL_COST_FLOOR);
    let rho = lag1_autocorrelation(&per_level);
    let inflation = (1.0 + rho) / (1.0 - rho);
    let names: Vec<String> = free.iter().map(|&j| params[j].name.to_string()).collect();
    let cov = sandwich_covariance(&jac, &w, s2, &names)? * inflation;
    Ok(ParameterCovariance {
        free,
        covariance_z: cov,
        residual_sd: s2.sqrt(),
        lag1_autocorrelation: rho,
        variance_inflation: inflation,
        components: n,
    })
}

/// Models of the fitted form that fit the fit levels about as well: draws from the posterior
/// (physical values, equal weight), with the sampler's diagnostics.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Ensemble {
    /// Physical parameter values of each model (the model's parameter order).
    pub draws: Vec<Vec<f64>>,
    /// The chain each draw comes from (for `R̂` of anything computed from the draws).
    pub chain: Vec<usize>,
    /// Fraction of accepted Metropolis proposals (over both chains, after burn-in).
    pub acceptance_rate: f64,
    /// Gelman–Rubin `R̂` of `ln J` (1 for chains that agree on the fit quality).
    pub r_hat_ln_j: f64,
    /// Parameters whose `R̂` exceeds [`MAX_R_HAT`]: the chains wander along a valley of the
    /// objective in them — the data do not determine them (sloppy directions; what matters is
    /// whether the predictions' `R̂` stays near 1).
    pub undetermined: Vec<(String, f64)>,
    /// Chain steps (each chain).
    pub steps: usize,
}

/// Steps of each Metropolis chain (the first half is burn-in).
pub const CHAIN_STEPS: usize = 6000;
/// Independent chains (run in parallel).
pub const CHAINS: usize = 2;
/// Largest `R̂` for a band to be given (Gelman & Rubin 1992; 1.1 the customary limit).
pub const MAX_R_HAT: f64 = 1.1;

/// Gelman–Rubin potential scale reduction of one quantity over chains (Gelman et al.,
/// *Bayesian Data Analysis*, 3rd ed., §11.4: `R̂ = √(((n−1)/n·W + B/n)/W)`; chains of unequal
/// length — draws left out where a solve failed — with each chain's own mean and variance and
/// `n` their mean length).
pub fn gelman_rubin(chains: &[Vec<f64>]) -> f64 {
    let m = chains.len() as f64;
    let n = chains.iter().map(|c| c.len()).sum::<usize>() as f64 / m;
    let means: Vec<f64> = chains
        .iter()
        .map(|c| c.iter().sum::<f64>() / c.len() as f64)
        .collect();
    let grand = means.iter().sum::<f64>() / m;
    let b = n / (m - 1.0) * means.iter().map(|x| (x - grand).powi(2)).sum::<f64>();
    let w = chains
        .iter()
        .zip(&means)
        .map(|(c, mu)| c.iter().map(|x| (x - mu).powi(2)).sum::<f64>() / (c.len() as f64 - 1.0))
        .sum::<f64>()
        / m;
    if w <= 0.0 {
        return if b <= 0.0 { 1.0 } else { f64::INFINITY };
    }
    (((n - 1.0) / n * w + b / n) / w).sqrt()
}

/// The posterior ensemble of a model fitted on all rows of `fit_levels` (see the module
/// documentation): [`CHAINS`] adaptive Metropolis chains of `steps` steps from the optimum,
/// the second halves thinned to `draws` models in all. `Err` when the chains disagree on the
/// fit (`R̂` of `ln J` above [`MAX_R_HAT`]); parameters on which they disagree are listed.
pub fn posterior_ensemble<S: Parametrised>(
    spec: &S,
    model: &S::Model,
    cov: &ParameterCovariance,
    fit_levels: &[LevelData],
    draws: usize,
    steps: usize,
    seed: u64,
) -> Result<Ensemble> {
    sample_posterior(spec, model, cov, fit_levels, draws, steps, seed, None)
}

/// [`posterior_ensemble`], advancing `progress` by one per chain step.
#[allow(clippy::too_many_arguments)]
fn sample_posterior<S: Parametrised>(
    spec: &S,
    model: &S::Model,
    cov: &ParameterCovariance,
    fit_levels: &[LevelData],
    draws: usize,
    steps: usize,
    seed: u64,
    progress: Option<&indicatif::ProgressBar>,
) -> Result<Ensemble> {
    let params = spec.params();
    let z_hat: Vec<f64> = params
        .iter()
        .zip(S::values_of(model))
        .map(|(p, &v)| p.coordinate_of(v))
        .collect();
    let dim = cov.free.len();
    let n_eff = cov.effective_components();
    let values_of = |zf: &DVector<f64>| -> Vec<f64> {
        let mut z = z_hat.clone();
        for (k, &j) in cov.free.iter().enumerate() {
            z[j] = zf[k];
        }
        params.iter().zip(&z).map(|(p, &v)| p.value(v)).collect()
    };
    // ln π up to a constant: −(n_eff/2)·ln(J + J_num) on the box (J_num the numerical floor).
    let ln_post = |zf: &DVector<f64>| -> f64 {
        if zf.iter().any(|v| !(0.0..=1.0).contains(v)) {
            return f64::NEG_INFINITY;
        }
        if let Some(b) = progress {
            b.inc(1);
        }
        let j = cost_all_rows(spec, &spec.model(values_of(zf)), fit_levels);
        -0.5 * n_eff * (j + NUMERICAL_COST_FLOOR).ln()
    };
    let scale = 2.38 * 2.38 / dim as f64;
    let floor = cov.covariance_z.diagonal().map(|v| 1e-6 * v);
    let root_of = |c: &DMatrix<f64>| {
        let eig = SymmetricEigen::new(c.clone());
        &eig.eigenvectors * DMatrix::from_diagonal(&eig.eigenvalues.map(|l| l.max(0.0).sqrt()))
    };
    let start = DVector::from_fn(dim, |k, _| z_hat[cov.free[k]]);
    // Per chain: the kept states, their ln π, accepted moves after burn-in.
    let chains: Vec<(Vec<DVector<f64>>, Vec<f64>, usize)> = (0..CHAINS)
        .into_par_iter()
        .map(|c| {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed + c as u64);
            let (mut z, mut lp) = (start.clone(), ln_post(&start));
            // Adaptive Metropolis (Haario, Saksman & Tamminen 2001): the proposal starts at a
            // tenth of the Gauss–Newton covariance and follows the chain's own covariance
            // (second half of the history so far) every 100 steps after the first 500.
            let mut root = root_of(&(&cov.covariance_z * (0.1 * scale)));
            let (mut lps, mut accepted) = (Vec::new(), 0);
            let mut history: Vec<DVector<f64>> = Vec::with_capacity(steps);
            for t in 0..steps {
                if t >= 500 && t % 100 == 0 && t <= steps / 2 {
                    let h = &history[t / 2..];
                    let mean: DVector<f64> = h.iter().sum::<DVector<f64>>() / h.len() as f64;
                    let mut s = DMatrix::zeros(dim, dim);
                    for x in h {
                        let d = x - &mean;
                        s += &d * d.transpose();
                    }
                    s /= (h.len() - 1) as f64;
                    root = root_of(&((s + DMatrix::from_diagonal(&floor)) * scale));
                }
                let xi = DVector::from_fn(dim, |_, _| StandardNormal.sample(&mut rng));
                let cand = &z + &root * xi;
                let lc = ln_post(&cand);
                let u: f64 = rand::Rng::random(&mut rng);
                if u.ln() < lc - lp {
                    z = cand;
                    lp = lc;
                    if t >= steps / 2 {
                        accepted += 1;
                    }
                }
                history.push(z.clone());
                if t >= steps / 2 {
                    lps.push(lp);
                }
            }
            (history.split_off(steps / 2), lps, accepted)
        })
        .collect();
    let kept_len = chains[0].0.len();
    let r_hat_ln_j = gelman_rubin(&chains.iter().map(|c| c.1.clone()).collect::<Vec<_>>());
    let undetermined = (0..dim)
        .filter_map(|k| {
            let per: Vec<Vec<f64>> = chains
                .iter()
                .map(|c| c.0.iter().map(|z| z[k]).collect())
                .collect();
            let r = gelman_rubin(&per);
            (r.is_nan() || r > MAX_R_HAT).then(|| (params[cov.free[k]].name.to_string(), r))
        })
        .collect();
    let per_chain = draws.div_ceil(CHAINS);
    let stride = (kept_len / per_chain).max(1);
    let (mut out, mut chain) = (Vec::new(), Vec::new());
    for (c, ch) in chains.iter().enumerate() {
        for z in ch.0.iter().step_by(stride).take(per_chain) {
            out.push(values_of(z));
            chain.push(c);
        }
    }
    let acceptance_rate =
        chains.iter().map(|c| c.2).sum::<usize>() as f64 / (CHAINS * kept_len) as f64;
    if r_hat_ln_j.is_nan() || r_hat_ln_j > MAX_R_HAT {
        return Err(Error::Data(format!(
            "the models that fit about as well were not sampled reliably: the {CHAINS} \
             Metropolis chains of {steps} steps disagree on the fit (R̂ of ln J = \
             {r_hat_ln_j:.2} > {MAX_R_HAT}, acceptance {:.0} %)",
            100.0 * acceptance_rate
        )));
    }
    Ok(Ensemble {
        draws: out,
        chain,
        acceptance_rate,
        r_hat_ln_j,
        undetermined,
        steps,
    })
}

impl Ensemble {
    /// Check an ensemble read from a file against its model's parameters: every draw a valid
    /// parameter set of the model's form.
    pub fn check(&self, params: &[ParamSpec]) -> std::result::Result<(), String> {
        if self.draws.is_empty() || self.chain.len() != self.draws.len() {
            return Err(format!(
                "ensemble: {} draws with {} chain labels",
                self.draws.len(),
                self.chain.len()
            ));
        }
        for (i, d) in self.draws.iter().enumerate() {
            check_values(params, d).map_err(|e| format!("ensemble draw {i}: {e}"))?;
        }
        Ok(())
    }

    /// 95 % intervals of the parameters `params` with the model's `values` (`None` for a
    /// parameter held on its bound, `free` the free ones).
    pub fn intervals(
        &self,
        params: &[ParamSpec],
        values: &[f64],
        free: &[usize],
    ) -> Vec<ParameterInterval> {
        params
            .iter()
            .enumerate()
            .map(|(j, p)| {
                let b = free
                    .contains(&j)
                    .then(|| band(values[j], self.draws.iter().map(|d| d[j]).collect()));
                ParameterInterval {
                    name: p.name.to_string(),
                    unit: p.unit.to_string(),
                    value: values[j],
                    lo_95: b.map(|b| b.lo_95),
                    hi_95: b.map(|b| b.hi_95),
                    at_bound: b.is_none(),
                }
            })
            .collect()
    }
}

/// 95 % interval of one parameter.
#[derive(Debug, Clone, Serialize)]
pub struct ParameterInterval {
    /// Parameter name, as in the model's parameter table.
    pub name: String,
    /// Unit of `value` and the interval (SI, e.g. "Hz", "N", "m"; "-" for a ratio).
    pub unit: String,
    /// The identified value (`unit`).
    pub value: f64,
    /// `None` for a parameter held on its bound.
    pub lo_95: Option<f64>,
    /// 97.5 % quantile over the ensemble (`unit`); `None` for a parameter held on its bound.
    pub hi_95: Option<f64>,
    /// The parameter is held on a bound of its box (not free in the fit).
    pub at_bound: bool,
}

/// A 95 % band `[lo, hi]` with the model's own value.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Band {
    /// The identified model's own value.
    pub value: f64,
    /// 2.5 % quantile over the ensemble (Hazen), same unit.
    pub lo_95: f64,
    /// 97.5 % quantile over the ensemble (Hazen), same unit.
    pub hi_95: f64,
}

impl Band {
    /// Whether `x` lies in the band.
    pub fn contains(&self, x: f64) -> bool {
        x >= self.lo_95 && x <= self.hi_95
    }
}

/// The 95 % bands of one level's predicted resonance quantities.
#[derive(Debug, Clone, Serialize)]
pub struct PredictionBand {
    /// File name of the level's sweep.
    pub file: String,
    /// "fit" or "predicted".
    pub role: String,
    /// Peak of the response per unit force (the level's quantity per N).
    pub peak: Band,
    /// Measured peak of the response per unit force (same unit as `peak`).
    pub peak_measured: f64,
    /// Amplitude resonance (Hz).
    pub resonance_hz: Band,
    /// Measured amplitude resonance (Hz).
    pub resonance_measured_hz: f64,
    /// Phase resonance (Hz).
    pub phase_resonance_hz: Band,
    /// Measured phase resonance (Hz; NaN where the phase does not pass quadrature in the band).
    #[serde(serialize_with = "super::report::phase_resonance_or_reason")]
    pub phase_resonance_measured_hz: f64,
    /// Ensemble models whose every row converged (the others are left out).
    pub models: usize,
    /// Largest Gelman–Rubin `R̂` of the three quantities over the ensemble's chains (near 1:
    /// the chains agree on this prediction; above [`MAX_R_HAT`] the band is not reliable).
    pub r_hat: f64,
}

/// The 95 % band of values (non-finite ones left out) about `value`.
fn band(value: f64, xs: Vec<f64>) -> Band {
    let mut xs: Vec<f64> = xs.into_iter().filter(|x| x.is_finite()).collect();
    xs.sort_by(f64::total_cmp);
    if xs.is_empty() {
        return Band {
            value,
            lo_95: f64::NAN,
            hi_95: f64::NAN,
        };
    }
    Band {
        value,
        lo_95: quantile_hazen(&xs, 0.025),
        hi_95: quantile_hazen(&xs, 0.975),
    }
}

/// 95 % bands of every level's peak, resonance and phase resonance over the ensemble's models;
/// `roles[i]` is level `i`'s role ("fit", "predicted").
pub fn prediction_bands<S: Parametrised>(
    spec: &S,
    model: &S::Model,
    ensemble: &Ensemble,
    levels: &[LevelData],
    roles: &[&str],
) -> Result<Vec<PredictionBand>> {
    // Per model, per level: (peak, resonance, phase resonance), NaN where a row failed.
    let outcomes: Vec<Vec<[f64; 3]>> = ensemble
        .draws
        .par_iter()
        .map(|v| {
            let m = spec.model(v.clone());
            levels
                .iter()
                .map(|l| match S::frf(&m, l) {
                    Ok((y, 0)) => {
                        let e = LevelErrors::new(l, &y, "", 0);
                        [
                            e.peak_model,
                            e.resonance_model_hz,
                            e.phase_resonance_model_hz,
                        ]
                    }
                    _ => [f64::NAN; 3],
                })
                .collect()
        })
        .collect();
    levels
        .iter()
        .enumerate()
        .map(|(i, l)| {
            let (y, failed) = S::frf(model, l)?;
            let own = LevelErrors::new(l, &y, roles[i], failed);
            let col = |k: usize| outcomes.iter().map(|o| o[i][k]).collect::<Vec<f64>>();
            Ok(PredictionBand {
                file: l.name.clone(),
                role: roles[i].to_string(),
                peak: band(own.peak_model, col(0)),
                peak_measured: own.peak_measured,
                resonance_hz: band(own.resonance_model_hz, col(1)),
                resonance_measured_hz: own.resonance_measured_hz,
                phase_resonance_hz: band(own.phase_resonance_model_hz, col(2)),
                phase_resonance_measured_hz: own.phase_resonance_measured_hz,
                models: outcomes.iter().filter(|o| o[i][0].is_finite()).count(),
                r_hat: (0..3)
                    .map(|k| {
                        let per: Vec<Vec<f64>> = (0..CHAINS)
                            .map(|c| {
                                outcomes
                                    .iter()
                                    .zip(&ensemble.chain)
                                    .filter(|(o, &ch)| ch == c && o[i][k].is_finite())
                                    .map(|(o, _)| o[i][k])
                                    .collect()
                            })
                            .collect();
                        gelman_rubin(&per)
                    })
                    .fold(1.0, f64::max),
            })
        })
        .collect()
}

/// The estimated uncertainty: the Gaussian approximation, the ensemble (its draws go to
/// `model.json`; its diagnostics are repeated here for the report) and the bands.
#[derive(Debug, Clone, Serialize)]
pub struct Estimate {
    /// The Gaussian approximation at the optimum.
    pub covariance: ParameterCovariance,
    /// The models drawn from the posterior (saved with the model, not in the report's JSON).
    #[serde(skip)]
    pub ensemble: Ensemble,
    /// Fraction of accepted Metropolis proposals (both chains, after burn-in).
    pub acceptance_rate: f64,
    /// Gelman–Rubin `R̂` of `ln J` over the chains (near 1: they agree on the fit quality).
    pub r_hat_ln_j: f64,
    /// Parameters (name, `R̂`) whose `R̂` exceeds [`MAX_R_HAT`]: not determined by the data.
    pub undetermined: Vec<(String, f64)>,
    /// 95 % interval of every parameter.
    pub intervals: Vec<ParameterInterval>,
    /// 95 % bands of every level's peak, resonance and phase resonance.
    pub bands: Vec<PredictionBand>,
}

/// The uncertainty section of an identification.
#[derive(Debug, Clone, Serialize)]
#[serde(tag = "status", rename_all = "snake_case")]
pub enum Uncertainty {
    /// Covariance, ensemble and bands were estimated.
    Estimated(Box<Estimate>),
    /// Why no band could be given (a parameter the data do not determine, a failed solve, an
    /// ensemble that could not be sampled).
    NotEstimated {
        /// What stopped the estimate.
        reason: String,
    },
}

/// The ensemble of `model` fitted on all rows of `fit_levels` (chains of `steps` steps; 0: none),
/// and the bands of every level of `levels` (`roles[i]` level `i`'s role).
pub fn estimate<S: Parametrised>(
    spec: &S,
    model: &S::Model,
    fit_levels: &[LevelData],
    levels: &[LevelData],
    roles: &[&str],
    steps: usize,
    progress: Option<&indicatif::ProgressBar>,
) -> Uncertainty {
    if steps == 0 {
        return Uncertainty::NotEstimated {
            reason: "not requested (--chain-steps 0)".into(),
        };
    }
    let run = || -> Result<Uncertainty> {
        let covariance = parameter_covariance(spec, model, fit_levels)?;
        let sample = |steps: usize| {
            sample_posterior(
                spec,
                model,
                &covariance,
                fit_levels,
                ENSEMBLE_DRAWS,
                steps,
                ENSEMBLE_SEED,
                progress,
            )
        };
        // Short chains (the fast default) that disagree are run again at the thorough length
        // before the bands are given up: a slow-mixing posterior needs the longer chains, an
        // unidentifiable one still fails at that length and says so.
        let ensemble = match sample(steps) {
            Err(_) if steps < CHAIN_STEPS => {
                if let Some(p) = progress {
                    p.inc_length((CHAINS * CHAIN_STEPS) as u64);
                }
                sample(CHAIN_STEPS)?
            }
            r => r?,
        };
        let bands = prediction_bands(spec, model, &ensemble, levels, roles)?;
        Ok(Uncertainty::Estimated(Box::new(Estimate {
            intervals: ensemble.intervals(&spec.params(), S::values_of(model), &covariance.free),
            acceptance_rate: ensemble.acceptance_rate,
            r_hat_ln_j: ensemble.r_hat_ln_j,
            undetermined: ensemble.undetermined.clone(),
            covariance,
            ensemble,
            bands,
        })))
    };
    run().unwrap_or_else(|e| Uncertainty::NotEstimated {
        reason: e.to_string(),
    })
}

impl Uncertainty {
    /// Report section on the model called `name` ("final model", "updated model").
    pub fn text(&self, name: &str) -> String {
        let e = match self {
            Uncertainty::Estimated(e) => e,
            Uncertainty::NotEstimated { reason } => {
                return format!("\nprediction uncertainty: not estimated: {reason}\n");
            }
        };
        let Estimate {
            covariance: cov,
            acceptance_rate,
            r_hat_ln_j,
            undetermined,
            intervals,
            bands,
            ..
        } = e.as_ref();
        let mut s = format!(
            "\nprediction uncertainty of the {name}: models of its form that fit the fit \
             levels about as well (posterior ∝ (J + {NUMERICAL_COST_FLOOR:.0e})^(−n_eff/2), the second term \
             the solver's numerical floor; n_eff = {:.1} of {} residual \
             components: residual sd {:.4} of the peak per component, lag-1 autocorrelation \
             {:.2}; {CHAINS} adaptive Metropolis chains of {} steps from the optimum, \
             acceptance {:.0} %, R̂ of ln J {:.3}; {ENSEMBLE_DRAWS} models kept); 95 % intervals and bands; \
             the misfit of a missing effect counts as noise, model-form error is not in the band:\n",
            cov.effective_components(),
            cov.components,
            cov.residual_sd,
            cov.lag1_autocorrelation,
            e.ensemble.steps,
            100.0 * acceptance_rate,
            r_hat_ln_j
        );
        for p in intervals {
            s += &match (p.lo_95, p.hi_95) {
                (Some(lo), Some(hi)) => format!(
                    "    {:<47} {:>12.5e} {:<3} 95 % [{:.4e}, {:.4e}]\n",
                    p.name, p.value, p.unit, lo, hi
                ),
                _ => format!(
                    "    {:<47} {:>12.5e} {:<3} on its bound: held there, not in the band\n",
                    p.name, p.value, p.unit
                ),
            };
        }
        if !undetermined.is_empty() {
            s += &format!(
                "  not determined by the data (the chains wander along a valley of the objective, \
                 R̂ > {MAX_R_HAT}): {}\n",
                undetermined
                    .iter()
                    .map(|(n, r)| format!("{n} (R̂ {r:.2})"))
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        }
        s += &bands_table(bands);
        s
    }
}

/// Table of 95 % bands beside the measured values (`*` where a measured value lies outside).
pub fn bands_table(bands: &[PredictionBand]) -> String {
    let mut s = format!(
        "  {:<34} {:>9}  {:>26} {:>8}  {:>26} {:>8}  {:>26} {:>8}  {:>5}\n",
        "level",
        "role",
        "peak: model [95 % band]",
        "measured",
        "f_res (Hz) [95 % band]",
        "measured",
        "f_90 (Hz) [95 % band]",
        "measured",
        "R̂"
    );
    let cell = |b: &Band, m: f64, d: usize| {
        if !(m.is_finite() && b.value.is_finite()) {
            return format!("{:>36}", "n/a");
        }
        let inside = if b.contains(m) { " " } else { "*" };
        format!(
            "{:>8.d$} [{:>7.d$}, {:>7.d$}] {:>8.d$}{inside}",
            b.value, b.lo_95, b.hi_95, m
        )
    };
    for b in bands {
        s += &format!(
            "  {:<34} {:>9}  {}  {}  {}  {:>5.3}\n",
            b.file,
            b.role,
            cell(&b.peak, b.peak_measured, 2),
            cell(&b.resonance_hz, b.resonance_measured_hz, 3),
            cell(&b.phase_resonance_hz, b.phase_resonance_measured_hz, 3),
            b.r_hat
        );
    }
    s += &format!(
        "  (* measured value outside the model's 95 % band: the difference is not explained by \
         the parameters' uncertainty; R̂ of the level's three predictions over the chains, above \
         {MAX_R_HAT} the band is not reliable)\n"
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// For a straight line `y = a + b·x` fitted by least squares, the covariance is the
    /// textbook one: `Var b = s²/Sxx`, `Var a = s²(1/n + x̄²/Sxx)`, `Cov(a, b) = −s²x̄/Sxx`; a
    /// constant factor on every weight changes nothing (the sandwich is scale-free).
    #[test]
    fn straight_line_covariance_is_the_textbook_one() {
        let x: Vec<f64> = (0..11).map(|i| 0.3 * i as f64 - 0.7).collect();
        let n = x.len() as f64;
        // r = y − a − b·x → ∂r/∂a = −1, ∂r/∂b = −x.
        let jac = DMatrix::from_fn(x.len(), 2, |i, j| if j == 0 { -1.0 } else { -x[i] });
        let xm = x.iter().sum::<f64>() / n;
        let sxx: f64 = x.iter().map(|v| (v - xm).powi(2)).sum();
        let s2 = 0.37;
        let names = vec!["a".to_string(), "b".to_string()];
        for w in [1.0, 1.0 / 22.0] {
            let c = sandwich_covariance(&jac, &vec![w; x.len()], s2, &names).unwrap();
            assert!((c[(1, 1)] / (s2 / sxx) - 1.0).abs() < 1e-12);
            assert!((c[(0, 0)] / (s2 * (1.0 / n + xm * xm / sxx)) - 1.0).abs() < 1e-12);
            assert!((c[(0, 1)] / (-s2 * xm / sxx) - 1.0).abs() < 1e-12);
        }
        // A parameter the residuals do not depend on is reported, not inverted.
        let flat = DMatrix::from_fn(x.len(), 2, |i, j| if j == 0 { -1.0 } else { 0.0 * x[i] });
        let e = sandwich_covariance(&flat, &vec![1.0; x.len()], s2, &names).unwrap_err();
        assert!(e.to_string().contains("dominated by b"), "{e}");
    }

    /// The weighted mean `m̂ = Σw_i·y_i / Σw_i` of observations of equal variance `s²` has
    /// `Var m̂ = s²·Σw_i² / (Σw_i)²` for any weights: the sandwich, not `s²(JᵀWJ)⁻¹`.
    #[test]
    fn weighted_mean_variance_is_the_sandwich() {
        let w = [1.0, 2.0, 0.5, 4.0, 1.5];
        let jac = DMatrix::from_element(w.len(), 1, -1.0);
        let s2 = 2.5;
        let c = sandwich_covariance(&jac, &w, s2, &["m".to_string()]).unwrap();
        let sw: f64 = w.iter().sum();
        let want = w.iter().map(|v| v * v * s2).sum::<f64>() / (sw * sw);
        assert!((c[(0, 0)] / want - 1.0).abs() < 1e-12);
    }

    /// The Hazen quantile puts the k-th of n sorted values at `(k + ½)/n`.
    #[test]
    fn hazen_quantiles() {
        let xs: Vec<f64> = (0..=100).map(f64::from).collect();
        assert!((quantile_hazen(&xs, 0.025) - 2.025).abs() < 1e-12);
        assert!((quantile_hazen(&xs, 0.975) - 97.975).abs() < 1e-12);
        assert!((quantile_hazen(&[0.0, 1.0], 0.5) - 0.5).abs() < 1e-12);
        assert_eq!(quantile_hazen(&[0.0, 1.0], 0.1), 0.0);
        assert_eq!(quantile_hazen(&[0.0, 1.0], 0.9), 1.0);
        assert_eq!(quantile_hazen(&[3.0], 0.5), 3.0);
    }
}
