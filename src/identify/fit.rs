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
//! Every parameter is mapped onto the unit box (logarithmically for positive parameters spanning
//! decades, [`ParamSpec`]); the bounds are physical and stated with the parameters. The search
//! is the restarted swarm + Nelder–Mead of [`crate::core::fit`]: each global start runs `argmin`'s
//! particle swarm over the box (seed `seed + start`), then Nelder–Mead from the swarm's best
//! point (initial simplex 5 % of the box, outside the box the cost of the clamped point plus a
//! quadratic penalty), restarted from its optimum with a fresh simplex (2 % of the box) until a
//! restart stops on its tolerance (standard deviation of the simplex costs below
//! [`FitOptions::tolerance`] of the cost), at most [`FitOptions::restarts`] times; a fit has
//! converged when a restart stopped on its tolerance rather than on its iteration cap. The best
//! start is kept; the spread of the starts' final costs is reported.

use super::measured::{PhaseConvention, Quantity, Sweep};
use super::model::{Drive, Model, ModelSpec, ParamSpec};
use crate::core::error::{Error, Result};
use crate::core::fit::{self as core_fit, LocalSearch, Restarts, SwarmSettings, Tolerance};
use rayon::prelude::*;
use realfft::num_complex::Complex64;
use serde::Serialize;
use std::time::Instant;

pub use crate::core::fit::StartOutcome;

/// One measured level prepared for fitting.
#[derive(Debug, Clone)]
pub struct LevelData {
    /// File name.
    pub name: String,
    /// Response quantity of the level's file.
    pub quantity: Quantity,
    /// Frequency and measured force of every row, in sweep order.
    pub drives: Vec<Drive>,
    /// Measured response per unit force (the file's quantity, the crate's phase convention).
    pub measured: Vec<Complex64>,
    /// 1-based lines of the rows in the file.
    pub lines: Vec<usize>,
    /// Mean measured drive force amplitude of the level (N).
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
    /// Nelder–Mead restarts after the first run, at most: the fit has converged when a
    /// restart (a fresh simplex about the previous optimum) stops on its tolerance.
    pub restarts: usize,
    /// Stopping tolerance of each Nelder–Mead run: standard deviation of the simplex's costs
    /// relative to the cost.
    pub tolerance: f64,
}

impl FitOptions {
    /// Model evaluations of the particle swarms (every start: the initial particles and one
    /// evaluation per particle per iteration).
    pub fn swarm_evaluations(&self) -> u64 {
        self.starts as u64 * self.swarm_evaluations_per_start()
    }

    /// Model evaluations of one start's swarm.
    pub fn swarm_evaluations_per_start(&self) -> u64 {
        self.swarm(0).evaluations()
    }

    /// The swarm of start `k`.
    pub fn swarm(&self, k: usize) -> SwarmSettings {
        SwarmSettings {
            particles: self.particles,
            iterations: self.swarm_iterations,
            seed: self.seed + k as u64,
        }
    }

    /// The Nelder–Mead search of a fit of `dim` parameters.
    pub fn local(&self, dim: usize) -> LocalSearch {
        LocalSearch {
            max_iters: local_iteration_cap(self.local_iterations, dim),
            tolerance: Tolerance::Relative(self.tolerance),
            first_step: 0.05,
            restart_step: 0.02,
            restarts: Restarts::UntilConverged(self.restarts),
        }
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

impl Default for FitOptions {
    fn default() -> Self {
        Self {
            particles: 32,
            swarm_iterations: 40,
            starts: 3,
            seed: 1,
            local_iterations: 600,
            restarts: LOCAL_RESTARTS,
            tolerance: THOROUGH_TOLERANCE,
        }
    }
}

/// Relative tolerance of the thorough search's Nelder–Mead runs.
pub const THOROUGH_TOLERANCE: f64 = 1e-7;

/// Result of a fit.
#[derive(Debug, Clone, Serialize)]
pub struct FitResult<M = Model> {
    /// The model at the optimum (physical parameter values).
    pub model: M,
    /// Objective `J` at the optimum.
    pub cost: f64,
    /// The best run stopped on its tolerance rather than on its iteration cap.
    pub converged: bool,
    /// Outcome of every start (swarm and Nelder–Mead), in the order run.
    pub starts: Vec<StartOutcome>,
    /// Model evaluations (all levels at all rows) spent.
    pub evaluations: u64,
    /// Rows where the harmonic balance failed at the optimum.
    pub failed_rows: usize,
    /// Parameters within 0.5 % of the box width of a bound.
    pub at_bounds: Vec<String>,
    /// Wall-clock time of the fit (s).
    pub wall_time_s: f64,
}

/// The objective `J` of a family's models on masked rows of some levels.
pub struct Objective<'a, S: Parametrised = ModelSpec> {
    spec: S,
    params: Vec<ParamSpec>,
    levels: &'a [LevelData],
    /// Rows that count, per level.
    masks: &'a [Vec<bool>],
}

impl<'a, S: Parametrised> Objective<'a, S> {
    /// The objective of `spec`'s models on the rows of `levels` where `masks` is `true`.
    pub fn new(spec: S, levels: &'a [LevelData], masks: &'a [Vec<bool>]) -> Self {
        let params = spec.params();
        Self {
            spec,
            params,
            levels,
            masks,
        }
    }

    /// Physical values of a box point.
    pub fn values(&self, z: &[f64]) -> Vec<f64> {
        core_fit::values(&self.params, z)
    }

    /// Box point of physical values.
    pub fn coordinates(&self, v: &[f64]) -> Vec<f64> {
        core_fit::coordinates(&self.params, v)
    }

    /// `J` of a model and the number of failed rows.
    pub fn cost_of(&self, model: &S::Model) -> (f64, usize) {
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
}

impl<S: Parametrised> core_fit::Objective for Objective<'_, S> {
    fn cost(&self, values: &[f64]) -> f64 {
        self.cost_of(&self.spec.model(values.to_vec())).0
    }
}

/// Restarts of Nelder–Mead after its first run, at most, in the thorough search: a narrow
/// valley (the Brake–Reuss beam's final model: the linear, proportional and cubic stiffness
/// terms trade against one another) can need a second restart.
pub const LOCAL_RESTARTS: usize = 3;

/// The fit result of a search: the best model, its cost and failed rows evaluated once more
/// (counted), and the parameters on a bound.
fn finish<S: Parametrised>(
    obj: &Objective<'_, S>,
    search: core_fit::Search,
    t0: Instant,
    progress: Option<&indicatif::ProgressBar>,
) -> FitResult<S::Model> {
    let model = obj.spec.model(search.best.values.clone());
    let (cost, failed) = obj.cost_of(&model);
    if let Some(b) = progress {
        b.inc(1);
    }
    let at_bounds = obj
        .params
        .iter()
        .zip(S::values_of(&model))
        .filter(|(p, &v)| super::model::at_bound(p, v))
        .map(|(p, _)| p.name.to_string())
        .collect();
    FitResult {
        model,
        cost,
        converged: search.best.converged,
        starts: search.starts,
        evaluations: search.evaluations + 1,
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
    let obj = Objective::new(spec.clone(), levels, masks);
    let search = core_fit::search(
        &obj.params,
        &obj,
        &[],
        opts.starts.max(1),
        &opts.swarm(0),
        &opts.local(obj.params.len()),
        progress,
    )?;
    Ok(finish(&obj, search, t0, progress))
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
    let obj = Objective::new(spec.clone(), levels, masks);
    if starts_physical.is_empty() {
        return Err(Error::param("starts", "at least one start"));
    }
    let z0: Vec<Vec<f64>> = starts_physical.iter().map(|v| obj.coordinates(v)).collect();
    let search = core_fit::local_search(
        &obj.params,
        &obj,
        &z0,
        &opts.local(obj.params.len()),
        progress,
    )?;
    Ok(finish(&obj, search, t0, progress))
}

#[cfg(test)]
mod tests {
    use super::LevelData;
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
}
