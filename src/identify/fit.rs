//! Fitting a model to measured sweeps: bounded physical parameters, a global search by particle
//! swarm followed by Nelder–Mead refinement, from several seeded starts (both optimisers from
//! `argmin`).
//!
//! # Objective
//!
//! The complex response of the measured quantity per unit force (amplitude and phase), compared
//! row by row at the measured frequency with the measured force of the row applied:
//!
//! ```text
//! r_i = (Y_model,i − Y_meas,i) / max_j |Y_meas,j|          (j over the rows of the level)
//! J   = (1/L)·Σ_levels (1/n_l)·Σ_{i in level l} |r_i|²
//! ```
//!
//! Dividing by each level's peak and by its row count makes every level weigh alike, whatever
//! its response amplitude (the peak accelerance of the Brake–Reuss beam falls threefold between
//! its lowest and highest level) and its number of rows. A row where the harmonic balance fails
//! counts as `|r| = 2` (worse than a zero response), so the search moves away from it.
//!
//! # Search
//!
//! Every parameter is mapped onto `[0, 1]` (logarithmically for positive parameters spanning
//! decades, see [`super::model::ParamSpec`]); the bounds are physical and stated with the
//! parameters. Each start runs `argmin`'s particle swarm (SPSO-2011 coefficients, seeded
//! xoshiro256++ generator, seed `seed + start`) over the box, then Nelder–Mead from the swarm's
//! best point (initial simplex 5 % of the box, outside the box the cost of the clamped point
//! plus a quadratic penalty), restarted once from its optimum with a fresh simplex. A fit has
//! converged when the restarted Nelder–Mead stops on its simplex tolerance (standard deviation of
//! the simplex costs below `1e-7` of the cost) rather than on its iteration cap. The best start
//! is kept; the spread of the starts' final costs is reported.

use super::measured::{PhaseConvention, Quantity, Sweep};
use super::model::{Drive, Model, ModelSpec, ParamSpec};
use crate::core::error::{Error, Result};
use argmin::core::{CostFunction, Executor, State, TerminationReason, TerminationStatus};
use argmin::solver::neldermead::NelderMead;
use argmin::solver::particleswarm::ParticleSwarm;
use rand_xoshiro::rand_core::SeedableRng;
use rayon::prelude::*;
use realfft::num_complex::Complex64;
use serde::Serialize;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

/// One measured level prepared for fitting.
#[derive(Debug, Clone)]
pub struct LevelData {
    /// File name.
    pub name: String,
    pub quantity: Quantity,
    /// Frequency and measured force of every row, in sweep order.
    pub drives: Vec<Drive>,
    /// Measured response per unit force (the file's quantity, the crate's phase convention).
    pub measured: Vec<Complex64>,
    /// 1-based lines of the rows in the file.
    pub lines: Vec<usize>,
    pub mean_force_n: f64,
    /// Largest `|Y_meas|` of the level.
    pub peak: f64,
}

impl LevelData {
    /// From a sweep in a given phase convention.
    pub fn new(s: &Sweep, conv: &PhaseConvention) -> Self {
        let measured = s.frf(conv);
        let peak = measured.iter().map(|v| v.norm()).fold(0.0, f64::max);
        Self {
            name: s.name(),
            quantity: s.quantity,
            drives: s
                .rows
                .iter()
                .map(|r| Drive {
                    omega: r.omega(),
                    force_n: r.force_n,
                })
                .collect(),
            measured,
            lines: s.rows.iter().map(|r| r.line).collect(),
            mean_force_n: s.mean_force_n(),
            peak,
        }
    }

    /// The level from row `first` (0-based, file order) on: the kept rows and their peak (the
    /// weight of the level's residual), but the whole level's mean force — the test level the
    /// preload-loss effect is a function of, so that a level is the same model whether it is
    /// fitted on these rows or scored on all of them.
    pub fn from_row(&self, first: usize) -> Self {
        let first = first.min(self.drives.len().saturating_sub(1));
        let drives = self.drives[first..].to_vec();
        let measured = self.measured[first..].to_vec();
        Self {
            name: self.name.clone(),
            quantity: self.quantity,
            mean_force_n: self.mean_force_n,
            peak: measured.iter().map(|v| v.norm()).fold(0.0, f64::max),
            lines: self.lines[first..].to_vec(),
            drives,
            measured,
        }
    }

    /// Model response per unit force in the level's quantity; failed rows are NaN.
    pub fn model_frf(&self, model: &Model) -> Result<(Vec<Complex64>, usize)> {
        let (x, failures) = model.receptance_tolerant(&self.drives, self.mean_force_n, true)?;
        Ok((self.from_receptance(&x), failures.len()))
    }

    /// The level's quantity per unit force from drive-point receptances (m/N) at its rows.
    pub fn from_receptance(&self, x: &[Complex64]) -> Vec<Complex64> {
        self.drives
            .iter()
            .zip(x)
            .map(|(d, xi)| xi * self.quantity.from_displacement(d.omega))
            .collect()
    }

    /// Normalised residuals `r_i` of a model response (failed rows: `2`).
    pub fn residuals(&self, y: &[Complex64]) -> Vec<Complex64> {
        y.iter()
            .zip(&self.measured)
            .map(|(m, d)| {
                if m.re.is_finite() && m.im.is_finite() {
                    (m - d) / self.peak
                } else {
                    Complex64::new(2.0, 0.0)
                }
            })
            .collect()
    }
}

/// What a fit searches over: a family of models with bounded parameters, and the response of
/// one of them at a level's rows. The single nonlinear mode ([`ModelSpec`]) and the updated
/// reduced model of a response-model file ([`super::reduced::ReducedSpec`]) are both fitted
/// through it.
pub trait Parametrised: Clone + Send + Sync {
    /// A member of the family: the spec with values.
    type Model: Clone + Send + Sync + Serialize + std::fmt::Debug;
    /// The bounded parameters, in order.
    fn params(&self) -> Vec<ParamSpec>;
    /// The member with physical values (inside the bounds).
    fn model(&self, values: Vec<f64>) -> Self::Model;
    /// The physical values of a member.
    fn values_of(model: &Self::Model) -> &[f64];
    /// The member's response per unit force at every row of `level`, in the level's quantity
    /// (failed rows NaN), and the count of failed rows.
    fn frf(model: &Self::Model, level: &LevelData) -> Result<(Vec<Complex64>, usize)>;
}

impl Parametrised for ModelSpec {
    type Model = Model;
    fn params(&self) -> Vec<ParamSpec> {
        ModelSpec::params(self)
    }
    fn model(&self, values: Vec<f64>) -> Model {
        Model {
            spec: self.clone(),
            values,
        }
    }
    fn values_of(model: &Model) -> &[f64] {
        &model.values
    }
    fn frf(model: &Model, level: &LevelData) -> Result<(Vec<Complex64>, usize)> {
        level.model_frf(model)
    }
}

/// Settings of a fit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FitOptions {
    /// Particles of the swarm.
    pub particles: usize,
    /// Swarm iterations per start.
    pub swarm_iterations: u64,
    /// Independent starts (swarm + local refinement each).
    pub starts: usize,
    /// Seed of the first start.
    pub seed: u64,
    /// Nelder–Mead iteration cap per run (a run and up to [`LOCAL_RESTARTS`] restarts per start) for up to
    /// [`LOCAL_ITERATIONS_DIMENSION`] parameters; scaled in proportion to the parameter count
    /// beyond it ([`local_iteration_cap`]).
    pub local_iterations: u64,
}

impl FitOptions {
    /// Model evaluations of the particle swarms (every start: the initial particles and one
    /// evaluation per particle per iteration).
    pub fn swarm_evaluations(&self) -> u64 {
        self.starts as u64 * self.swarm_evaluations_per_start()
    }

    /// Model evaluations of one start's swarm.
    pub fn swarm_evaluations_per_start(&self) -> u64 {
        self.particles as u64 * (self.swarm_iterations + 1)
    }
}

/// Parameter count up to which [`FitOptions::local_iterations`] is the cap as given.
pub const LOCAL_ITERATIONS_DIMENSION: usize = 5;

/// Nelder–Mead iteration cap per run for `dim` parameters: `local_iterations` up to
/// [`LOCAL_ITERATIONS_DIMENSION`] parameters, in proportion to `dim` beyond. The iterations the
/// simplex needs grow with the dimension (each shrink or reflection moves one vertex of `dim + 1`);
/// measured on the Brake–Reuss beam: the eight-parameter final model (two stiffness laws and a
/// damper on the Jenkins baseline) hit a fixed cap of 600 per run.
pub fn local_iteration_cap(local_iterations: u64, dim: usize) -> u64 {
    local_iterations * dim.max(LOCAL_ITERATIONS_DIMENSION) as u64
        / LOCAL_ITERATIONS_DIMENSION as u64
}

/// Model evaluations one Nelder–Mead fit of `dim` parameters is budgeted on the progress bar:
/// two runs' iteration caps ([`local_iteration_cap`]; the run's estimate at its start,
/// `Options::estimated_evaluations`, counts two runs of `local_iterations` without the cap for
/// the dimension, which it does not know yet); a fit that needs all its restarts overruns it.
pub fn local_evaluations(local_iterations: u64, dim: usize) -> u64 {
    2 * local_iteration_cap(local_iterations, dim)
}

/// Make room on the progress bar for a fit of `n` more evaluations. The bar's length is the
/// run's estimate at its start; a search can fit more than estimated (pairs of effects, a
/// round that accepts nothing, larger final models), and a bar past its length shows no time
/// left for the rest of the run. The length grows only where the fit would overrun it.
pub fn reserve_progress(progress: Option<&indicatif::ProgressBar>, n: u64) {
    if let Some(b) = progress {
        let need = b.position() + n;
        if b.length().is_some_and(|len| len < need) {
            b.set_length(need);
        }
    }
}

impl Default for FitOptions {
    fn default() -> Self {
        Self {
            particles: 32,
            swarm_iterations: 40,
            starts: 3,
            seed: 1,
            local_iterations: 600,
        }
    }
}

/// Outcome of one start.
#[derive(Debug, Clone, Serialize)]
pub struct StartOutcome {
    pub seed: Option<u64>,
    /// Cost after the global search (None for a local-only start).
    pub swarm_cost: Option<f64>,
    pub final_cost: f64,
    pub local_iterations: u64,
    pub converged: bool,
}

/// Result of a fit.
#[derive(Debug, Clone, Serialize)]
pub struct FitResult<M = Model> {
    pub model: M,
    /// Objective `J` at the optimum.
    pub cost: f64,
    pub converged: bool,
    pub starts: Vec<StartOutcome>,
    /// Model evaluations (all levels at all rows) spent.
    pub evaluations: u64,
    /// Rows where the harmonic balance failed at the optimum.
    pub failed_rows: usize,
    /// Parameters within 0.5 % of the box width of a bound.
    pub at_bounds: Vec<String>,
    pub wall_time_s: f64,
}

/// The objective over the unit box.
pub struct Objective<'a, S: Parametrised = ModelSpec> {
    spec: S,
    params: Vec<ParamSpec>,
    levels: &'a [LevelData],
    /// Rows that count, per level.
    masks: &'a [Vec<bool>],
    evaluations: AtomicU64,
    progress: Option<&'a indicatif::ProgressBar>,
}

impl<'a, S: Parametrised> Objective<'a, S> {
    pub fn new(
        spec: S,
        levels: &'a [LevelData],
        masks: &'a [Vec<bool>],
        progress: Option<&'a indicatif::ProgressBar>,
    ) -> Self {
        let params = spec.params();
        Self {
            spec,
            params,
            levels,
            masks,
            evaluations: AtomicU64::new(0),
            progress,
        }
    }

    /// Physical values of a box point.
    pub fn values(&self, z: &[f64]) -> Vec<f64> {
        self.params
            .iter()
            .zip(z)
            .map(|(p, &v)| p.value(v))
            .collect()
    }

    /// Box point of physical values.
    pub fn coordinates(&self, v: &[f64]) -> Vec<f64> {
        self.params
            .iter()
            .zip(v)
            .map(|(p, &x)| p.coordinate(x))
            .collect()
    }

    /// Add the evaluations made by an optimiser's own copy of the objective.
    fn add_evaluations_of(&self, run: Option<&Objective<'_, S>>) {
        let n = run.map_or(0, |p| p.evaluations.load(Ordering::Relaxed));
        self.evaluations.fetch_add(n, Ordering::Relaxed);
    }

    /// `J` of a model and the number of failed rows.
    pub fn cost_of(&self, model: &S::Model) -> (f64, usize) {
        self.evaluations.fetch_add(1, Ordering::Relaxed);
        if let Some(b) = self.progress {
            b.inc(1);
        }
        let per: Vec<(f64, usize)> = self
            .levels
            .par_iter()
            .zip(self.masks.par_iter())
            .map(|(l, mask)| match S::frf(model, l) {
                Ok((y, failed)) => {
                    let r = l.residuals(&y);
                    let (mut s, mut n) = (0.0, 0usize);
                    for (ri, &m) in r.iter().zip(mask) {
                        if m {
                            s += ri.norm_sqr();
                            n += 1;
                        }
                    }
                    (s / n.max(1) as f64, failed)
                }
                Err(_) => (4.0, l.drives.len()),
            })
            .collect();
        let cost = per.iter().map(|p| p.0).sum::<f64>() / per.len() as f64;
        (cost, per.iter().map(|p| p.1).sum())
    }

    fn model(&self, z: &[f64]) -> S::Model {
        self.spec.model(self.values(z))
    }
}

impl<S: Parametrised> CostFunction for Objective<'_, S> {
    type Param = Vec<f64>;
    type Output = f64;

    fn cost(&self, z: &Self::Param) -> std::result::Result<f64, argmin::core::Error> {
        let penalty: f64 = z
            .iter()
            .map(|&v| {
                let d = if v < 0.0 {
                    -v
                } else if v > 1.0 {
                    v - 1.0
                } else {
                    0.0
                };
                d * d
            })
            .sum();
        Ok(self.cost_of(&self.model(z)).0 + penalty)
    }
}

fn argmin_err(e: argmin::core::Error) -> Error {
    Error::Data(format!("optimiser: {e}"))
}

/// Restarts of Nelder–Mead after its first run, at most: the fit has converged when a restart
/// (a fresh simplex about the previous optimum) stops on its tolerance.
pub const LOCAL_RESTARTS: usize = 3;

/// Nelder–Mead from `z0`, then restarted from its optimum (a new simplex guards against the
/// collapsed simplex that Nelder–Mead can stop on away from a minimum; Lagarias et al. 1998)
/// until a restart stops on its tolerance, at most [`LOCAL_RESTARTS`] times. Returns the best
/// point, its cost, the iterations of all runs and whether a restart converged. A narrow valley
/// (the Brake–Reuss beam's final model: the linear, proportional and cubic stiffness terms trade
/// against one another) can need a second restart.
fn nelder_mead<S: Parametrised>(
    obj: &Objective<'_, S>,
    z0: &[f64],
    max_iter: u64,
) -> Result<(Vec<f64>, f64, u64, bool)> {
    let mut z = z0.to_vec();
    let mut cost = obj.cost(&z).map_err(argmin_err)?;
    let mut iterations = 0;
    let mut converged = false;
    let max_iter = local_iteration_cap(max_iter, z.len());
    for run in 0..=LOCAL_RESTARTS {
        let step = if run == 0 { 0.05 } else { 0.02 };
        let mut simplex = vec![z.clone()];
        for i in 0..z.len() {
            let mut v = z.clone();
            v[i] = if v[i] + step <= 1.0 {
                v[i] + step
            } else {
                v[i] - step
            };
            simplex.push(v);
        }
        let solver = NelderMead::new(simplex)
            .with_sd_tolerance(1e-7 * cost.max(1e-12))
            .map_err(argmin_err)?;
        let res = Executor::new(
            Objective::new(obj.spec.clone(), obj.levels, obj.masks, obj.progress),
            solver,
        )
        .configure(|s| s.max_iters(max_iter))
        .run()
        .map_err(argmin_err)?;
        let st = res.state();
        iterations += st.get_iter();
        obj.add_evaluations_of(res.problem.problem.as_ref());
        if st.get_best_cost() <= cost {
            cost = st.get_best_cost();
            if let Some(p) = st.get_best_param() {
                z = p.iter().map(|v| v.clamp(0.0, 1.0)).collect();
            }
        }
        converged = run > 0
            && matches!(
                st.get_termination_status(),
                TerminationStatus::Terminated(TerminationReason::SolverConverged)
            );
        if converged {
            break;
        }
    }
    Ok((z, cost, iterations, converged))
}

fn finish<S: Parametrised>(
    obj: &Objective<'_, S>,
    best: (Vec<f64>, f64, bool),
    starts: Vec<StartOutcome>,
    t0: Instant,
) -> FitResult<S::Model> {
    let model = obj.model(&best.0);
    let (cost, failed) = obj.cost_of(&model);
    let at_bounds = obj
        .params
        .iter()
        .zip(S::values_of(&model))
        .filter(|(p, &v)| p.at_bound(v))
        .map(|(p, _)| p.name.to_string())
        .collect();
    FitResult {
        model,
        cost,
        converged: best.2,
        starts,
        evaluations: obj.evaluations.load(Ordering::Relaxed),
        failed_rows: failed,
        at_bounds,
        wall_time_s: t0.elapsed().as_secs_f64(),
    }
}

/// Global fit: for each start, particle swarm over the box then Nelder–Mead; the best start.
pub fn fit_global<S: Parametrised>(
    spec: &S,
    levels: &[LevelData],
    masks: &[Vec<bool>],
    opts: &FitOptions,
    progress: Option<&indicatif::ProgressBar>,
) -> Result<FitResult<S::Model>> {
    let t0 = Instant::now();
    let obj = Objective::new(spec.clone(), levels, masks, progress);
    let dim = obj.params.len();
    let mut starts = Vec::new();
    let mut best: Option<(Vec<f64>, f64, bool)> = None;
    for k in 0..opts.starts.max(1) {
        let seed = opts.seed + k as u64;
        reserve_progress(
            progress,
            opts.swarm_evaluations_per_start() + local_evaluations(opts.local_iterations, dim),
        );
        let pso = ParticleSwarm::new((vec![0.0; dim], vec![1.0; dim]), opts.particles)
            .with_rng_generator(rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(seed));
        let res = Executor::new(Objective::new(spec.clone(), levels, masks, progress), pso)
            .configure(|s| s.max_iters(opts.swarm_iterations))
            .run()
            .map_err(argmin_err)?;
        obj.add_evaluations_of(res.problem.problem.as_ref());
        let st = res.state();
        let swarm_cost = st.get_best_cost();
        let z0 = st
            .get_best_param()
            .map(|p| p.position.clone())
            .ok_or_else(|| Error::Data("particle swarm returned no point".into()))?;
        let (z, cost, it, conv) = nelder_mead(&obj, &z0, opts.local_iterations)?;
        starts.push(StartOutcome {
            seed: Some(seed),
            swarm_cost: Some(swarm_cost),
            final_cost: cost,
            local_iterations: it,
            converged: conv,
        });
        if best.as_ref().is_none_or(|b| cost < b.1) {
            best = Some((z, cost, conv));
        }
    }
    Ok(finish(&obj, best.expect("one start"), starts, t0))
}

/// Local fit: Nelder–Mead from each given start (physical values); the best.
pub fn fit_local<S: Parametrised>(
    spec: &S,
    levels: &[LevelData],
    masks: &[Vec<bool>],
    starts_physical: &[Vec<f64>],
    opts: &FitOptions,
    progress: Option<&indicatif::ProgressBar>,
) -> Result<FitResult<S::Model>> {
    let t0 = Instant::now();
    let obj = Objective::new(spec.clone(), levels, masks, progress);
    let mut starts = Vec::new();
    let mut best: Option<(Vec<f64>, f64, bool)> = None;
    for v in starts_physical {
        let z0 = obj.coordinates(v);
        reserve_progress(progress, local_evaluations(opts.local_iterations, z0.len()));
        let (z, cost, it, conv) = nelder_mead(&obj, &z0, opts.local_iterations)?;
        starts.push(StartOutcome {
            seed: None,
            swarm_cost: None,
            final_cost: cost,
            local_iterations: it,
            converged: conv,
        });
        if best.as_ref().is_none_or(|b| cost < b.1) {
            best = Some((z, cost, conv));
        }
    }
    let best = best.ok_or_else(|| Error::param("starts", "at least one start"))?;
    Ok(finish(&obj, best, starts, t0))
}

#[cfg(test)]
mod tests {
    use super::{reserve_progress, LevelData};
    use crate::identify::measured::Quantity;
    use crate::identify::model::Drive;
    use realfft::num_complex::Complex64;

    /// A level cut at a row keeps the rows from it on and their peak, and the whole level's
    /// mean force; a cut past the end keeps the last row.
    #[test]
    fn a_level_from_a_row_on_keeps_those_rows_and_the_level_force() {
        let level = LevelData {
            name: "l.csv".into(),
            quantity: Quantity::Displacement,
            drives: (0..5)
                .map(|i| Drive {
                    omega: 500.0 + i as f64,
                    force_n: 1.0 + i as f64,
                })
                .collect(),
            measured: [4.0, 9.0, 3.0, 2.0, 1.0]
                .iter()
                .map(|&v| Complex64::new(0.0, v))
                .collect(),
            lines: (2..7).collect(),
            mean_force_n: 3.0,
            peak: 9.0,
        };
        let cut = level.from_row(2);
        assert_eq!(cut.lines, vec![4, 5, 6]);
        assert_eq!(cut.drives.len(), 3);
        assert_eq!(cut.drives[0].omega, 502.0);
        assert_eq!(cut.measured[0], Complex64::new(0.0, 3.0));
        assert_eq!(cut.mean_force_n, 3.0, "the whole level's");
        assert_eq!(cut.peak, 3.0);
        assert_eq!(level.from_row(9).lines, vec![6]);
    }

    #[test]
    fn progress_grows_only_where_a_fit_would_overrun_the_estimate() {
        let bar = indicatif::ProgressBar::hidden();
        bar.set_length(100);
        bar.set_position(90);
        reserve_progress(Some(&bar), 5);
        assert_eq!(bar.length(), Some(100));
        reserve_progress(Some(&bar), 50);
        assert_eq!(bar.length(), Some(140));
        reserve_progress(None, 1000);
    }
}
