//! One fitting layer for every stage that fits parameters to data (calibration of the Valanis
//! element, the diagnosis of measured loops, the identification of measured frequency
//! responses), in `argmin`'s style: a problem is a cost over physical parameter values, the
//! solvers are `argmin`'s, and a search returns a result struct with its convergence
//! information.
//!
//! # Parameters and their transforms
//!
//! A [`ParamSpec`] names a physical parameter, its unit and its bounds, and how the optimiser's
//! unconstrained coordinate `z` maps onto it ([`Transform`]):
//!
//! | transform | coordinate | value |
//! |---|---|---|
//! | [`Transform::Linear`] | fraction `u` of the interval | `lo + (hi − lo)·u` |
//! | [`Transform::Log`] | fraction `u` of the interval (a scale spanning decades) | `lo·(hi/lo)^u` |
//! | [`Transform::Logit`] | `z ∈ ℝ` | `lo + (hi − lo)·σ(z)`, `σ` the logistic function (open interval) |
//! | [`Transform::Exp`] | `z ∈ ℝ` (clamped to ±50) | `reference·e^z` (a positive scale with no physical bound) |
//!
//! For the two interval transforms the fraction `u` is the coordinate itself, clamped to
//! `[0, 1]` ([`Coordinate::Box`]: the optimiser adds a quadratic penalty outside the box, so
//! that a simplex feels the wall), or `u = (sin z + 1)/2` ([`Coordinate::Sine`], the MINUIT
//! transform for doubly bounded parameters, James & Roos 1975: every trial is inside and the
//! sensitivity does not vanish at the bounds as with a logistic map).
//!
//! # Searches
//!
//! * [`minimise`]: Nelder–Mead (`argmin`) from a start, restarted from its optimum with a fresh
//!   simplex (the simplex can collapse away from a minimum; Lagarias et al. 1998, *SIAM J.
//!   Optim.* 9:112) as [`LocalSearch`] says; a run has converged when it stops on its tolerance
//!   (the standard deviation of the simplex's costs) rather than on its iteration cap.
//! * [`swarm`]: `argmin`'s particle swarm (SPSO-2011 coefficients, seeded xoshiro256++
//!   generator) over the coordinates' box, the global part of a restarted swarm + Nelder–Mead
//!   search ([`search`]).
//!
//! Every evaluation goes through one [`Bounded`] adapter (the `argmin` `CostFunction`), which
//! counts evaluations, advances a progress bar and adds the box penalty.
//!
//! # Held-out selection
//!
//! [`held_out`]: the scaffolding that the effect searches of `diagnose` and `identify` share —
//! alternate training / held-out units (cycles of a loop record, rows of a sweep), the effective
//! sample size of autocorrelated residuals, the held-out `ΔBIC`, and the greedy rounds that fit
//! every admissible candidate on the training units (in parallel) and accept the best one the
//! held-out evidence allows.

use crate::core::error::{Error, Result};
use argmin::core::{CostFunction, Executor, State, TerminationReason, TerminationStatus};
use argmin::solver::neldermead::NelderMead;
use argmin::solver::particleswarm::ParticleSwarm;
use rand_xoshiro::rand_core::SeedableRng;
use serde::Serialize;
use std::sync::atomic::{AtomicU64, Ordering};

/// How the optimiser's coordinate `z` maps onto a parameter's value (see the module table).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Transform {
    /// `lo + (hi − lo)·u`, `u` the fraction of the interval ([`Coordinate`]).
    Linear,
    /// `lo·(hi/lo)^u` (`0 < lo < hi`): a scale parameter spanning decades.
    Log,
    /// `lo + (hi − lo)·σ(z)` on the open interval (kept `1e-12` of the interval inside `hi`).
    Logit,
    /// `reference·e^z`, `z` clamped to ±50: a positive scale with no physical bound.
    Exp {
        /// Value at `z = 0`.
        reference: f64,
    },
}

/// How the fraction `u ∈ [0, 1]` of an interval transform follows from the coordinate `z`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Coordinate {
    /// `u = z` clamped to `[0, 1]`; outside the box the search adds `d²` (distance `d`).
    Box,
    /// `u = (sin z + 1)/2` (MINUIT; every `z` is inside the bounds).
    Sine,
}

/// Which bound a fitted parameter sits on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Bound {
    /// The lower bound `lo`.
    Lower,
    /// The upper bound `hi`.
    Upper,
}

impl Bound {
    /// `"lower"` or `"upper"`.
    pub fn name(self) -> &'static str {
        match self {
            Bound::Lower => "lower",
            Bound::Upper => "upper",
        }
    }
}

/// Clamp of the [`Transform::Exp`] coordinate (`e^50 ≈ 5·10²¹`).
const EXP_COORDINATE_LIMIT: f64 = 50.0;
/// Distance of a [`Transform::Logit`] value from its upper bound, relative to the interval.
const LOGIT_OPEN: f64 = 1e-12;

fn logistic(t: f64) -> f64 {
    1.0 / (1.0 + (-t).exp())
}

/// One fitted parameter: name and unit (for reports and error messages), physical bounds, the
/// transform of the optimiser's coordinate, and a starting value.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ParamSpec {
    /// Parameter name, as in reports and error messages.
    pub name: &'static str,
    /// Unit of `lo`, `hi` and `start` (SI, e.g. "N/m"; "-" for a ratio).
    pub unit: &'static str,
    /// Lower bound (physical units).
    pub lo: f64,
    /// Upper bound (physical units).
    pub hi: f64,
    /// How the optimiser's coordinate maps onto the value.
    pub transform: Transform,
    /// How an interval transform's fraction follows from the coordinate (box or sine).
    pub coordinate: Coordinate,
    /// Starting value (physical units, inside the bounds): for a model extension the value at
    /// which it is absent, otherwise a central start.
    pub start: f64,
}

impl ParamSpec {
    fn new(
        name: &'static str,
        unit: &'static str,
        lo: f64,
        hi: f64,
        transform: Transform,
        start: f64,
    ) -> Self {
        Self {
            name,
            unit,
            lo,
            hi,
            transform,
            coordinate: Coordinate::Box,
            start,
        }
    }

    /// A parameter bounded in `[lo, hi]`, spanned linearly (box coordinate).
    pub fn linear(name: &'static str, unit: &'static str, lo: f64, hi: f64, start: f64) -> Self {
        Self::new(name, unit, lo, hi, Transform::Linear, start)
    }

    /// A positive parameter bounded in `[lo, hi]`, spanned logarithmically (box coordinate).
    pub fn log(name: &'static str, unit: &'static str, lo: f64, hi: f64, start: f64) -> Self {
        Self::new(name, unit, lo, hi, Transform::Log, start)
    }

    /// A parameter in the open interval `(lo, hi)` through the logistic function.
    pub fn logit(name: &'static str, unit: &'static str, lo: f64, hi: f64, start: f64) -> Self {
        Self::new(name, unit, lo, hi, Transform::Logit, start)
    }

    /// A positive scale `reference·e^z` with no physical bound (bounds `reference·e^∓50`).
    pub fn exp(name: &'static str, unit: &'static str, reference: f64, start: f64) -> Self {
        let (lo, hi) = (
            reference * (-EXP_COORDINATE_LIMIT).exp(),
            reference * EXP_COORDINATE_LIMIT.exp(),
        );
        Self::new(name, unit, lo, hi, Transform::Exp { reference }, start)
    }

    /// The same parameter on the MINUIT sine coordinate ([`Coordinate::Sine`]).
    pub fn on_sine(self) -> Self {
        Self {
            coordinate: Coordinate::Sine,
            ..self
        }
    }

    /// The same parameter with another starting value.
    pub fn starting_at(self, start: f64) -> Self {
        Self { start, ..self }
    }

    /// Physical value at the fraction `u ∈ [0, 1]` of the interval (clamped; interval transforms).
    fn at_fraction(&self, u: f64) -> f64 {
        let u = u.clamp(0.0, 1.0);
        match self.transform {
            Transform::Log => self.lo * (self.hi / self.lo).powf(u),
            _ => self.lo + (self.hi - self.lo) * u,
        }
    }

    /// Fraction `u ∈ [0, 1]` of the interval at a physical value (clamped to the bounds; the
    /// logarithmic one for [`Transform::Log`] and [`Transform::Exp`]).
    pub fn fraction(&self, value: f64) -> f64 {
        let u = match self.transform {
            Transform::Log | Transform::Exp { .. } => {
                (value / self.lo).max(1e-300).ln() / (self.hi / self.lo).ln()
            }
            Transform::Linear | Transform::Logit => (value - self.lo) / (self.hi - self.lo),
        };
        if u.is_finite() {
            u.clamp(0.0, 1.0)
        } else {
            0.5
        }
    }

    /// Physical value of the optimiser coordinate `z`.
    pub fn value(&self, z: f64) -> f64 {
        match self.transform {
            Transform::Linear | Transform::Log => match self.coordinate {
                Coordinate::Box => self.at_fraction(z),
                Coordinate::Sine => self.at_fraction(0.5 * (z.sin() + 1.0)),
            },
            Transform::Logit => (self.lo + (self.hi - self.lo) * logistic(z))
                .min(self.hi - LOGIT_OPEN * (self.hi - self.lo)),
            Transform::Exp { reference } => {
                reference * z.clamp(-EXP_COORDINATE_LIMIT, EXP_COORDINATE_LIMIT).exp()
            }
        }
    }

    /// Optimiser coordinate of a physical value (the inverse of [`ParamSpec::value`]; values
    /// outside the bounds are taken to the bound, and for the logistic one just inside it).
    pub fn coordinate_of(&self, value: f64) -> f64 {
        match self.transform {
            Transform::Linear | Transform::Log => {
                let u = self.fraction(value);
                match self.coordinate {
                    Coordinate::Box => u,
                    Coordinate::Sine => (2.0 * u - 1.0).asin(),
                }
            }
            Transform::Logit => {
                let p = ((value - self.lo) / (self.hi - self.lo)).clamp(1e-12, 1.0 - 1e-12);
                (p / (1.0 - p)).ln()
            }
            Transform::Exp { reference } => (value / reference)
                .ln()
                .clamp(-EXP_COORDINATE_LIMIT, EXP_COORDINATE_LIMIT),
        }
    }

    /// Coordinate of the starting value.
    pub fn start_coordinate(&self) -> f64 {
        self.coordinate_of(self.start)
    }

    /// The natural size of a move of the coordinate, which the initial simplex's edges are
    /// fractions of: the box's width, 0.3 rad on the sine coordinate, one unit of the logistic
    /// coordinate, 0.3 (a factor 1.35) of the exponential one.
    pub fn step(&self) -> f64 {
        match (self.transform, self.coordinate) {
            (Transform::Linear | Transform::Log, Coordinate::Box) => 1.0,
            (Transform::Linear | Transform::Log, Coordinate::Sine) => 0.3,
            (Transform::Logit, _) => 1.0,
            (Transform::Exp { .. }, _) => 0.3,
        }
    }

    /// A vertex of an initial simplex: `z` moved by `step` (back into the box if it would leave
    /// it).
    fn moved(&self, z: f64, step: f64) -> f64 {
        match (self.transform, self.coordinate) {
            (Transform::Linear | Transform::Log, Coordinate::Box) if z + step > 1.0 => z - step,
            _ => z + step,
        }
    }

    /// Squared distance of `z` outside the box (0 for the other coordinates).
    fn penalty(&self, z: f64) -> f64 {
        match (self.transform, self.coordinate) {
            (Transform::Linear | Transform::Log, Coordinate::Box) => {
                let d = if z < 0.0 {
                    -z
                } else if z > 1.0 {
                    z - 1.0
                } else {
                    0.0
                };
                d * d
            }
            _ => 0.0,
        }
    }

    /// `z` taken into the box (the other coordinates as they are).
    fn inside(&self, z: f64) -> f64 {
        match (self.transform, self.coordinate) {
            (Transform::Linear | Transform::Log, Coordinate::Box) => z.clamp(0.0, 1.0),
            _ => z,
        }
    }

    /// The range of the coordinate a swarm searches: the box, `[−π/2, π/2]` on the sine
    /// coordinate; `None` for the unbounded ones.
    fn search_range(&self) -> Option<(f64, f64)> {
        match (self.transform, self.coordinate) {
            (Transform::Linear | Transform::Log, Coordinate::Box) => Some((0.0, 1.0)),
            (Transform::Linear | Transform::Log, Coordinate::Sine) => {
                Some((-std::f64::consts::FRAC_PI_2, std::f64::consts::FRAC_PI_2))
            }
            _ => None,
        }
    }

    /// The bound a value sits on: within `margin` (a fraction of the linear or logarithmic
    /// interval) of it.
    pub fn bound_at(&self, value: f64, margin: f64) -> Option<Bound> {
        let u = self.fraction(value);
        if u <= margin {
            Some(Bound::Lower)
        } else if u >= 1.0 - margin {
            Some(Bound::Upper)
        } else {
            None
        }
    }

    /// A value is one of this parameter's: finite and inside its bounds (to `1e-9` of the
    /// interval); the error names the parameter, its bounds and unit.
    pub fn check(&self, value: f64) -> Result<()> {
        let tol = 1e-9 * (self.hi - self.lo).abs().max(self.hi.abs());
        if value.is_finite() && value >= self.lo - tol && value <= self.hi + tol {
            Ok(())
        } else {
            Err(Error::param(
                self.name,
                format!(
                    "{value} is outside its bounds [{}, {}] {}",
                    self.lo, self.hi, self.unit
                ),
            ))
        }
    }
}

/// Physical values of a coordinate vector.
pub fn values(params: &[ParamSpec], z: &[f64]) -> Vec<f64> {
    params.iter().zip(z).map(|(p, &v)| p.value(v)).collect()
}

/// Coordinates of physical values.
pub fn coordinates(params: &[ParamSpec], v: &[f64]) -> Vec<f64> {
    params
        .iter()
        .zip(v)
        .map(|(p, &x)| p.coordinate_of(x))
        .collect()
}

/// Check a set of physical values against the parameters: one per parameter, each finite and
/// inside its bounds; the error names the parameter.
pub fn check_values(params: &[ParamSpec], values: &[f64]) -> Result<()> {
    if params.len() != values.len() {
        return Err(Error::param(
            "values",
            format!("{} parameters expected, got {}", params.len(), values.len()),
        ));
    }
    params.iter().zip(values).try_for_each(|(p, &v)| p.check(v))
}

/// A fitting problem: the cost of a set of physical parameter values (one per [`ParamSpec`]).
/// Values the model cannot follow are a large finite cost, not an error.
pub trait Objective: Sync {
    /// Cost of `values` (physical units, one per parameter); a large finite value where the model
    /// cannot follow them.
    fn cost(&self, values: &[f64]) -> f64;
}

impl<F: Fn(&[f64]) -> f64 + Sync> Objective for F {
    fn cost(&self, values: &[f64]) -> f64 {
        self(values)
    }
}

/// The `argmin` cost function of an [`Objective`] over the optimiser's coordinates: maps them to
/// physical values, adds the box penalty, counts the evaluations and advances the progress bar.
pub struct Bounded<'a, O: ?Sized> {
    /// The parameters the coordinates map onto.
    pub params: &'a [ParamSpec],
    /// The cost of physical values.
    pub objective: &'a O,
    evaluations: &'a AtomicU64,
    progress: Option<&'a indicatif::ProgressBar>,
}

impl<'a, O: Objective + ?Sized> Bounded<'a, O> {
    /// The adapter of `objective`, counting into `evaluations`.
    pub fn new(
        params: &'a [ParamSpec],
        objective: &'a O,
        evaluations: &'a AtomicU64,
        progress: Option<&'a indicatif::ProgressBar>,
    ) -> Self {
        Self {
            params,
            objective,
            evaluations,
            progress,
        }
    }

    /// The cost at coordinates `z` (penalty included), counted.
    pub fn at(&self, z: &[f64]) -> f64 {
        self.evaluations.fetch_add(1, Ordering::Relaxed);
        if let Some(b) = self.progress {
            b.inc(1);
        }
        let penalty: f64 = self.params.iter().zip(z).map(|(p, &v)| p.penalty(v)).sum();
        self.objective.cost(&values(self.params, z)) + penalty
    }
}

impl<O: Objective + ?Sized> CostFunction for Bounded<'_, O> {
    type Param = Vec<f64>;
    type Output = f64;

    fn cost(&self, z: &Vec<f64>) -> std::result::Result<f64, argmin::core::Error> {
        Ok(self.at(z))
    }
}

fn optimiser_error(e: argmin::core::Error) -> Error {
    Error::Data(format!("optimiser: {e}"))
}

/// Stopping tolerance of a Nelder–Mead run: the standard deviation of the simplex's costs.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Tolerance {
    /// An absolute cost.
    Absolute(f64),
    /// A fraction of the best cost before the run (at least `1e-12` of it is asked).
    Relative(f64),
}

/// When a restarted Nelder–Mead search ends.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Restarts {
    /// Up to `n` restarts, ending at the first restart that stops on its tolerance.
    UntilConverged(usize),
    /// Exactly `n` restarts.
    Always(usize),
}

impl Restarts {
    /// The most restarts.
    pub fn max(self) -> usize {
        match self {
            Restarts::UntilConverged(n) | Restarts::Always(n) => n,
        }
    }
}

/// Settings of a (restarted) Nelder–Mead search.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LocalSearch {
    /// Iteration cap of each run.
    pub max_iters: u64,
    /// When a run has converged: the standard deviation of the simplex's costs below it.
    pub tolerance: Tolerance,
    /// Edge of the first run's initial simplex along each coordinate, as a fraction of the
    /// parameter's [`ParamSpec::step`].
    pub first_step: f64,
    /// Edge of each restart's initial simplex, likewise.
    pub restart_step: f64,
    /// How many restarts, and whether to stop at the first converged one.
    pub restarts: Restarts,
}

/// Why a run stopped.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Termination {
    /// On its tolerance: converged.
    Tolerance,
    /// On its iteration cap.
    IterationCap,
    /// Anything else the optimiser reported.
    Other(String),
}

impl Termination {
    fn of(status: &TerminationStatus) -> Self {
        match status {
            TerminationStatus::Terminated(TerminationReason::SolverConverged) => Self::Tolerance,
            TerminationStatus::Terminated(TerminationReason::MaxItersReached) => Self::IterationCap,
            s => Self::Other(format!("{s:?}")),
        }
    }
}

/// One Nelder–Mead run of a search.
#[derive(Debug, Clone, Serialize)]
pub struct Run {
    /// Nelder–Mead iterations of the run.
    pub iterations: u64,
    /// Best cost of the run.
    pub cost: f64,
    /// Why the run stopped.
    pub termination: Termination,
}

/// Result of [`minimise`].
#[derive(Debug, Clone, Serialize)]
pub struct Minimum {
    /// Optimiser coordinates of the best point.
    pub z: Vec<f64>,
    /// Its physical values.
    pub values: Vec<f64>,
    /// Cost at the best point.
    pub cost: f64,
    /// Iterations of all runs.
    pub iterations: u64,
    /// Cost evaluations of this search.
    pub evaluations: u64,
    /// Every Nelder–Mead run, the first then the restarts.
    pub runs: Vec<Run>,
    /// The last run stopped on its tolerance (with restarts: a restart did).
    pub converged: bool,
}

/// Nelder–Mead from `z0` (optimiser coordinates), restarted from its optimum as `settings`
/// say. With a relative tolerance the start is evaluated first (the tolerance's scale).
pub fn minimise<O: Objective + ?Sized>(
    params: &[ParamSpec],
    objective: &O,
    z0: &[f64],
    settings: &LocalSearch,
    progress: Option<&indicatif::ProgressBar>,
) -> Result<Minimum> {
    let evaluations = AtomicU64::new(0);
    let problem = Bounded::new(params, objective, &evaluations, progress);
    let mut z = z0.to_vec();
    let mut cost = match settings.tolerance {
        Tolerance::Relative(_) => problem.at(&z),
        Tolerance::Absolute(_) => f64::INFINITY,
    };
    let (mut iterations, mut converged, mut runs) = (0, false, Vec::new());
    for run in 0..=settings.restarts.max() {
        let scale = if run == 0 {
            settings.first_step
        } else {
            settings.restart_step
        };
        let mut simplex = vec![z.clone()];
        for (j, p) in params.iter().enumerate() {
            let mut v = z.clone();
            v[j] = p.moved(v[j], p.step() * scale);
            simplex.push(v);
        }
        let tolerance = match settings.tolerance {
            Tolerance::Absolute(t) => t,
            Tolerance::Relative(r) => r * cost.max(1e-12),
        };
        let solver = NelderMead::new(simplex)
            .with_sd_tolerance(tolerance)
            .map_err(optimiser_error)?;
        let res = Executor::new(
            Bounded::new(params, objective, &evaluations, progress),
            solver,
        )
        .configure(|s| s.max_iters(settings.max_iters))
        .run()
        .map_err(optimiser_error)?;
        let st = res.state();
        iterations += st.get_iter();
        let termination = Termination::of(st.get_termination_status());
        runs.push(Run {
            iterations: st.get_iter(),
            cost: st.get_best_cost(),
            termination: termination.clone(),
        });
        if st.get_best_cost() <= cost {
            cost = st.get_best_cost();
            if let Some(p) = st.get_best_param() {
                z = params.iter().zip(p).map(|(s, &v)| s.inside(v)).collect();
            }
        }
        converged = termination == Termination::Tolerance;
        if run > 0 && converged && matches!(settings.restarts, Restarts::UntilConverged(_)) {
            break;
        }
    }
    Ok(Minimum {
        values: values(params, &z),
        z,
        cost,
        iterations,
        evaluations: evaluations.load(Ordering::Relaxed),
        runs,
        converged,
    })
}

/// Settings of the particle swarm of a global search.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct SwarmSettings {
    /// Particles of the swarm.
    pub particles: usize,
    /// Swarm iterations (each moves every particle once).
    pub iterations: u64,
    /// Seed of the swarm's xoshiro256++ generator (the search is reproducible).
    pub seed: u64,
}

impl SwarmSettings {
    /// Cost evaluations of the swarm: the initial particles and one per particle per iteration.
    pub fn evaluations(&self) -> u64 {
        self.particles as u64 * (self.iterations + 1)
    }
}

/// Best point of a swarm: coordinates and cost.
#[derive(Debug, Clone, Serialize)]
pub struct SwarmBest {
    /// Optimiser coordinates of the best particle.
    pub z: Vec<f64>,
    /// Its cost.
    pub cost: f64,
    /// Cost evaluations the swarm spent.
    pub evaluations: u64,
}

/// `argmin`'s particle swarm over the coordinates' search box (every parameter needs one:
/// interval transforms).
pub fn swarm<O: Objective + ?Sized>(
    params: &[ParamSpec],
    objective: &O,
    settings: &SwarmSettings,
    progress: Option<&indicatif::ProgressBar>,
) -> Result<SwarmBest> {
    let (lo, hi): (Vec<f64>, Vec<f64>) = params
        .iter()
        .map(|p| {
            p.search_range().ok_or_else(|| {
                Error::param(
                    p.name,
                    "an unbounded coordinate: a swarm needs bounds on every parameter",
                )
            })
        })
        .collect::<Result<Vec<_>>>()?
        .into_iter()
        .unzip();
    let evaluations = AtomicU64::new(0);
    let pso = ParticleSwarm::new((lo, hi), settings.particles).with_rng_generator(
        rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(settings.seed),
    );
    let res = Executor::new(Bounded::new(params, objective, &evaluations, progress), pso)
        .configure(|s| s.max_iters(settings.iterations))
        .run()
        .map_err(optimiser_error)?;
    let st = res.state();
    let z = st
        .get_best_param()
        .map(|p| p.position.clone())
        .ok_or_else(|| Error::Data("particle swarm returned no point".into()))?;
    Ok(SwarmBest {
        z,
        cost: st.get_best_cost(),
        evaluations: evaluations.load(Ordering::Relaxed),
    })
}

/// Outcome of one start of a [`search`].
#[derive(Debug, Clone, Serialize)]
pub struct StartOutcome {
    /// Seed of the swarm (`None` for a local start from a given point).
    pub seed: Option<u64>,
    /// Cost after the swarm (`None` for a local start).
    pub swarm_cost: Option<f64>,
    /// Best cost after the Nelder–Mead polish.
    pub final_cost: f64,
    /// Nelder–Mead iterations of the start.
    pub local_iterations: u64,
    /// The Nelder–Mead polish stopped on its tolerance.
    pub converged: bool,
}

/// Result of a [`search`]: the best start's minimum and every start's outcome.
#[derive(Debug, Clone, Serialize)]
pub struct Search {
    /// The best start's minimum.
    pub best: Minimum,
    /// Local starts first (in the order given), then the swarm starts.
    pub starts: Vec<StartOutcome>,
    /// Cost evaluations of every start.
    pub evaluations: u64,
}

/// A restarted search: Nelder–Mead from each of `local_starts` (coordinates), and for each
/// swarm seed `swarm.seed + k`, `k < swarm_starts`, a particle swarm followed by Nelder–Mead
/// from its best point; the best start (the first of equal costs) is kept.
pub fn search<O: Objective + ?Sized>(
    params: &[ParamSpec],
    objective: &O,
    local_starts: &[Vec<f64>],
    swarm_starts: usize,
    swarm_settings: &SwarmSettings,
    local: &LocalSearch,
    progress: Option<&indicatif::ProgressBar>,
) -> Result<Search> {
    let mut best: Option<Minimum> = None;
    let (mut starts, mut evaluations) = (Vec::new(), 0);
    let mut keep = |m: Minimum, outcome: StartOutcome, evaluations: &mut u64| {
        *evaluations += m.evaluations;
        starts.push(outcome);
        if best.as_ref().is_none_or(|b| m.cost < b.cost) {
            best = Some(m);
        }
    };
    for z0 in local_starts {
        let m = minimise(params, objective, z0, local, progress)?;
        let outcome = StartOutcome {
            seed: None,
            swarm_cost: None,
            final_cost: m.cost,
            local_iterations: m.iterations,
            converged: m.converged,
        };
        keep(m, outcome, &mut evaluations);
    }
    for k in 0..swarm_starts {
        let settings = SwarmSettings {
            seed: swarm_settings.seed + k as u64,
            ..*swarm_settings
        };
        let s = swarm(params, objective, &settings, progress)?;
        evaluations += s.evaluations;
        let m = minimise(params, objective, &s.z, local, progress)?;
        let outcome = StartOutcome {
            seed: Some(settings.seed),
            swarm_cost: Some(s.cost),
            final_cost: m.cost,
            local_iterations: m.iterations,
            converged: m.converged,
        };
        keep(m, outcome, &mut evaluations);
    }
    let best = best.ok_or_else(|| Error::param("starts", "give at least one start"))?;
    Ok(Search {
        best,
        starts,
        evaluations,
    })
}

/// Nelder–Mead from each of `local_starts` (coordinates); the best (the first of equal costs).
pub fn local_search<O: Objective + ?Sized>(
    params: &[ParamSpec],
    objective: &O,
    local_starts: &[Vec<f64>],
    local: &LocalSearch,
    progress: Option<&indicatif::ProgressBar>,
) -> Result<Search> {
    let none = SwarmSettings {
        particles: 0,
        iterations: 0,
        seed: 0,
    };
    search(params, objective, local_starts, 0, &none, local, progress)
}

/// Held-out selection: what the effect searches of `diagnose` (cycles of a loop record) and
/// `identify` (rows of frequency sweeps) share.
///
/// 1. The data's units (cycles, rows) are split alternately into training (even positions)
///    and held-out (odd) units ([`held_out::alternate`]); every candidate is fitted on the
///    training units and judged on the held-out ones, whose noise is independent of its fit.
/// 2. Residuals of neighbouring units are correlated: `n` residual components with lag-1
///    autocorrelation `ρ` carry the evidence of `n_eff = n·(1 − ρ)/(1 + ρ)` independent ones
///    (AR(1); [`held_out::effective_samples`], [`held_out::variance_inflation`]).
/// 3. A candidate's held-out evidence against the current model as the Schwarz (1978)
///    criterion `ΔBIC = n_eff·ln(J_new/J_old) + Δp·ln(n_eff)` ([`held_out::delta_bic`]);
///    "very strong" below −10 (Kass & Raftery 1995).
/// 4. [`held_out::rounds`]: greedy forward selection — every admissible candidate fitted and
///    judged, the best eligible one accepted, again from the extended model, up to a number of
///    effects.
pub mod held_out {
    /// Training (even positions) and held-out (odd) flags of `n` units.
    pub fn alternate(n: usize) -> (Vec<bool>, Vec<bool>) {
        (
            (0..n).map(|i| i % 2 == 0).collect(),
            (0..n).map(|i| i % 2 == 1).collect(),
        )
    }

    /// Variance inflation `(1 + ρ)/(1 − ρ)` of the mean of AR(1) samples with lag-1
    /// autocorrelation `ρ`.
    pub fn variance_inflation(rho: f64) -> f64 {
        (1.0 + rho) / (1.0 - rho)
    }

    /// Effective count `n·(1 − ρ)/(1 + ρ)` of `n` AR(1) samples, at least 2.
    pub fn effective_samples(n: usize, rho: f64) -> f64 {
        (n as f64 * (1.0 - rho) / (1.0 + rho)).max(2.0)
    }

    /// Held-out `ΔBIC = n_eff·ln(J_new/J_old) + Δp·ln(n_eff)` of a model with `added_params`
    /// more parameters whose held-out cost is `cost_new` against `cost_old` (both including
    /// any numerical floor the caller adds).
    pub fn delta_bic(n_eff: f64, cost_new: f64, cost_old: f64, added_params: usize) -> f64 {
        n_eff * (cost_new / cost_old).ln() + added_params as f64 * n_eff.ln()
    }

    /// One round of a greedy search: what the round started from (`meta`), the candidates
    /// judged, and the one accepted (index).
    #[derive(Debug, Clone)]
    pub struct Round<C, M = ()> {
        /// What the round started from (the caller's record, e.g. the current model's held-out score).
        pub meta: M,
        /// Every candidate judged in the round.
        pub candidates: Vec<C>,
        /// Index into `candidates` of the accepted one; `None` ends the search.
        pub accepted: Option<usize>,
    }

    /// Greedy forward selection. From `state`, round after round while fewer than
    /// `max_rounds` rounds have run and `more(&state)` holds: `round(&state)` fits and judges
    /// every candidate that may extend the state, with what the round needs to say about its
    /// start (an empty list ends the search), `pick` names the one to accept (none: the search
    /// ends) and `accept` extends the state by it. Returns the final state and the rounds.
    pub fn rounds<S, C, M>(
        mut state: S,
        max_rounds: usize,
        more: impl Fn(&S) -> bool,
        mut round: impl FnMut(&S) -> crate::core::error::Result<(M, Vec<C>)>,
        pick: impl Fn(&S, &[C]) -> Option<usize>,
        accept: impl Fn(S, &C) -> crate::core::error::Result<S>,
    ) -> crate::core::error::Result<(S, Vec<Round<C, M>>)> {
        let mut out = Vec::new();
        while out.len() < max_rounds && more(&state) {
            let (meta, candidates) = round(&state)?;
            if candidates.is_empty() {
                break;
            }
            let accepted = pick(&state, &candidates);
            if let Some(i) = accepted {
                state = accept(state, &candidates[i])?;
            }
            out.push(Round {
                meta,
                candidates,
                accepted,
            });
            if accepted.is_none() {
                break;
            }
        }
        Ok((state, out))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rosenbrock(v: &[f64]) -> f64 {
        (1.0 - v[0]).powi(2) + 100.0 * (v[1] - v[0] * v[0]).powi(2)
    }

    /// Every transform maps its coordinate of a value back onto the value.
    #[test]
    fn coordinates_and_values_are_inverse() {
        let specs = [
            ParamSpec::linear("a", "m", -2.0, 3.0, 0.5),
            ParamSpec::log("b", "Pa", 1e-3, 1e4, 2.0),
            ParamSpec::linear("c", "-", 0.0, 1.0, 0.3).on_sine(),
            ParamSpec::log("d", "N/m", 1e2, 1e8, 1e5).on_sine(),
            ParamSpec::logit("e", "-", 0.0, 1.0, 0.25),
            ParamSpec::exp("f", "Pa/m", 5e12, 7e11),
        ];
        for p in &specs {
            let z = p.start_coordinate();
            assert!(
                (p.value(z) / p.start - 1.0).abs() < 1e-12,
                "{}: {} vs {}",
                p.name,
                p.value(z),
                p.start
            );
            p.check(p.value(z)).unwrap();
        }
    }

    /// Values stay inside the bounds whatever the coordinate; a value outside is refused with
    /// the parameter's name and unit.
    #[test]
    fn values_stay_inside_and_outside_values_are_named() {
        let p = ParamSpec::log("gap", "m", 1e-6, 1e-3, 1e-5);
        for z in [-5.0, -0.1, 0.0, 0.5, 1.0, 7.0] {
            let v = p.value(z);
            assert!((1e-6..=1e-3).contains(&v), "{z} -> {v}");
            let s = p.on_sine().value(z);
            assert!((1e-6..=1e-3 * (1.0 + 1e-15)).contains(&s), "{z} -> {s}");
        }
        let l = ParamSpec::logit("k", "-", 0.0, 1.0, 0.5);
        assert!(l.value(1e3) < 1.0 && l.value(-1e3) >= 0.0);
        let e = p.check(2e-3).unwrap_err().to_string();
        assert!(e.contains("gap") && e.contains(" m"), "{e}");
        assert_eq!(p.bound_at(1.0000001e-6, 2e-3), Some(Bound::Lower));
        assert_eq!(p.bound_at(9.99e-4, 2e-3), Some(Bound::Upper));
        assert_eq!(p.bound_at(3e-5, 2e-3), None);
    }

    /// Nelder–Mead with restarts finds the Rosenbrock minimum (1, 1) on every coordinate kind;
    /// it reports convergence and counts its evaluations.
    #[test]
    fn minimise_finds_the_rosenbrock_minimum() {
        let settings = LocalSearch {
            max_iters: 2000,
            tolerance: Tolerance::Absolute(1e-16),
            first_step: 1.0,
            restart_step: 0.3,
            restarts: Restarts::UntilConverged(3),
        };
        let cases = [
            [
                ParamSpec::linear("x", "-", -2.0, 2.0, -1.0),
                ParamSpec::linear("y", "-", -2.0, 2.0, 1.5),
            ],
            [
                ParamSpec::linear("x", "-", -2.0, 2.0, -1.0).on_sine(),
                ParamSpec::log("y", "-", 1e-2, 1e2, 3.0).on_sine(),
            ],
            [
                ParamSpec::logit("x", "-", -2.0, 2.0, -1.0),
                ParamSpec::exp("y", "-", 1.0, 3.0),
            ],
        ];
        for params in &cases {
            let z0: Vec<f64> = params.iter().map(|p| p.start_coordinate()).collect();
            let m = minimise(params, &rosenbrock, &z0, &settings, None).unwrap();
            assert!(m.converged, "{m:?}");
            assert!((m.values[0] - 1.0).abs() < 1e-5, "{m:?}");
            assert!((m.values[1] - 1.0).abs() < 1e-5, "{m:?}");
            assert!(m.evaluations > m.iterations, "{m:?}");
            assert_eq!(m.runs.len() as u64, m.runs.len() as u64);
        }
    }

    /// A run stopped by its iteration cap has not converged.
    #[test]
    fn a_capped_search_has_not_converged() {
        let params = [
            ParamSpec::linear("x", "-", -2.0, 2.0, -1.0),
            ParamSpec::linear("y", "-", -2.0, 2.0, 1.5),
        ];
        let z0: Vec<f64> = params.iter().map(|p| p.start_coordinate()).collect();
        let settings = LocalSearch {
            max_iters: 5,
            tolerance: Tolerance::Relative(1e-12),
            first_step: 0.05,
            restart_step: 0.02,
            restarts: Restarts::UntilConverged(1),
        };
        let m = minimise(&params, &rosenbrock, &z0, &settings, None).unwrap();
        assert!(!m.converged);
        assert_eq!(m.runs.len(), 2);
        assert!(m
            .runs
            .iter()
            .all(|r| r.termination == Termination::IterationCap));
    }

    /// The box penalty keeps a search whose minimum lies outside the box on the wall.
    #[test]
    fn the_box_holds_a_minimum_outside_it() {
        let params = [ParamSpec::linear("x", "-", 0.0, 1.0, 0.5)];
        let f = |v: &[f64]| (v[0] - 3.0).powi(2);
        let s = search(
            &params,
            &f,
            &[vec![0.5]],
            1,
            &SwarmSettings {
                particles: 8,
                iterations: 10,
                seed: 3,
            },
            &LocalSearch {
                max_iters: 500,
                tolerance: Tolerance::Absolute(1e-14),
                first_step: 0.05,
                restart_step: 0.02,
                restarts: Restarts::UntilConverged(3),
            },
            None,
        )
        .unwrap();
        assert!((s.best.values[0] - 1.0).abs() < 1e-6, "{:?}", s.best);
        assert_eq!(s.starts.len(), 2);
        assert!(s.starts[1].swarm_cost.is_some());
    }

    #[test]
    fn held_out_statistics() {
        let (t, h) = held_out::alternate(5);
        assert_eq!(t, vec![true, false, true, false, true]);
        assert_eq!(h, vec![false, true, false, true, false]);
        assert_eq!(held_out::effective_samples(100, 0.0), 100.0);
        assert!((held_out::effective_samples(90, 0.5) - 30.0).abs() < 1e-12);
        assert!((held_out::variance_inflation(0.5) - 3.0).abs() < 1e-12);
        // Halving the cost at n_eff = e² with one parameter more.
        let e2 = std::f64::consts::E.powi(2);
        assert!((held_out::delta_bic(e2, 1.0, 2.0, 1) - (2.0 - e2 * 2f64.ln())).abs() < 1e-12);
    }

    /// The greedy rounds accept the best candidate each round until none is eligible.
    #[test]
    fn greedy_rounds_accept_until_nothing_helps() {
        // State: the effects accepted; a candidate's gain is its value unless taken.
        let gains = [3.0, 0.5, 2.0];
        let (state, rounds) = held_out::rounds(
            Vec::<usize>::new(),
            5,
            |s: &Vec<usize>| s.len() < 3,
            |s: &Vec<usize>| {
                Ok((
                    (),
                    (0..3)
                        .filter(|k| !s.contains(k))
                        .map(|k| (k, gains[k]))
                        .collect(),
                ))
            },
            |_, c: &[(usize, f64)]| {
                c.iter()
                    .enumerate()
                    .filter(|(_, c)| c.1 > 1.0)
                    .max_by(|a, b| a.1 .1.total_cmp(&b.1 .1))
                    .map(|(i, _)| i)
            },
            |mut s, c| {
                s.push(c.0);
                Ok(s)
            },
        )
        .unwrap();
        assert_eq!(state, vec![0, 2]);
        assert_eq!(rounds.len(), 3);
        assert_eq!(rounds[1].accepted, Some(1));
        assert_eq!(rounds[2].accepted, None);
    }
}
