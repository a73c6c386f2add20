//! The calibration chain: surfaces → normal sweep → tangential loops at several amplitudes →
//! Valanis fits → table of means with 95 % intervals, and the convergence checks.
//!
//! Units: SI; per unit nominal area throughout (pressures and shear stresses in Pa,
//! displacements in m, stiffnesses kn, E0, Et in N/m³, energies in J/m²).
//!
//! For each **realisation** (a Gaussian surface of the configured statistics with seed
//! `surface.seed + r`, or one given measured surface):
//!
//! 1. **Surface** ([`crate::surface::generate`](mod@crate::surface::generate)).
//! 2. **Normal sweep** ([`crate::contact::sweep`]): the normal contact solver at each nominal
//!    pressure, warm-started, with `kn = dp̄/dδ` from the tangent problem on the contact set.
//! 3. **Tangential loops** ([`crate::calibrate::amplitudes`]): on each pressure field, one
//!    history of increasing displacement amplitudes `factor × δ_gs(p̄)` along x (δ_gs the
//!    gross-slip displacement of monotonic loading at that pressure), from microslip to gross
//!    slip, giving the steady loop at each amplitude (Masing; checked by each loop's closure
//!    error and by the tests of [`crate::calibrate::amplitudes`]).
//! 4. **Fits** ([`crate::calibrate::fit`]): one Valanis element (E0, k, optionally Et; μ fixed,
//!    `Fz = p̄`) fitted to all amplitudes together (the table's values), and one per amplitude (to
//!    show how much the best element depends on the amplitude).
//!
//! Then, over the realisations, the mean and the 95 % interval of every tabulated value
//! ([`crate::calibrate::statistics`]), and the **convergence checks**
//! ([`crate::calibrate::convergence`]): the same surfaces on the grid with half the points per
//! side (resolution alone), and independent surfaces on the half-size patch at the same spacing
//! (patch size). The warnings name every pressure whose result rests on under-resolved spots,
//! few spots, an unconverged grid or patch, or a fitted `k` at a bound of its range.
//!
//! Realisations (and the checks' surfaces) are independent chains; they run concurrently, each
//! single-threaded (measured faster than one chain at a time on all threads, BENCHMARKS.md).
//! Every solver is bit-identical for any thread count, so the results do not depend on this.

use crate::calibrate::amplitudes::{self, AmplitudeSweep};
use crate::calibrate::config::CalibrationConfig;
use crate::calibrate::convergence::{Check, Verdict};
use crate::calibrate::fit::{fit_valanis, fit_valanis_loops, FitOptions, FitResult, LoopData};
use crate::calibrate::statistics::{paired_difference, summarise, welch_difference, Summary};
use crate::calibrate::table::{CalibrationRow, CalibrationTable, RowInterval};
use crate::contact::normal::{NormalOptions, NormalProblem, NormalSolver};
use crate::contact::resolution::RESOLVED_POINTS_ACROSS;
use crate::contact::sweep::{self, SweepOptions, SweepPoint};
use crate::contact::tangential::{TangentialOptions, TangentialProblem, TangentialSolver};
use crate::core::error::{Error, Result};
use crate::core::fft::Boundary;
use crate::core::grid::Grid2;
use crate::core::hash::sha256_hex;
use crate::core::material::{composite_modulus, Material};
use crate::element::ContactParamsPerArea;
use crate::surface::generate::{generate, GaussianSurfaceSpec};
use indicatif::ProgressBar;
use std::time::Instant;

/// A fitted `k` below this is reported as at the lower bound 0, above `1 − K_BOUND_FLAG` as at
/// the upper bound 1 (see [`k_bound_reading`]).
pub const K_BOUND_FLAG: f64 = 1e-3;

/// Fewer contact spots than this on the patch (mean over realisations) earn a warning: the row
/// describes a few asperities, not a rough surface.
pub const FEW_SPOTS: f64 = 10.0;

/// A loop whose closure error exceeds this earns a warning (Masing assumption weak).
pub const CLOSURE_WARNING: f64 = 0.05;

/// Where a fitted `k` sits in its range `[0, 1)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum KBound {
    /// `k < K_BOUND_FLAG`.
    Lower,
    /// Inside the range.
    Inside,
    /// `k > 1 − K_BOUND_FLAG`.
    Upper,
}

impl KBound {
    /// Classify a fitted `k`.
    pub fn of(k: f64) -> Self {
        if k < K_BOUND_FLAG {
            KBound::Lower
        } else if k > 1.0 - K_BOUND_FLAG {
            KBound::Upper
        } else {
            KBound::Inside
        }
    }
}

/// The physical reading of a fitted `k` at a bound of its range.
///
/// The Valanis force slope is `dF/dq = E0(1 + x)/(1 + kx)` with `x = −F/(μFz)` on loading: `k`
/// sets how the stiffness falls from E0 to 0 as the force approaches μFz.
pub fn k_bound_reading(bound: KBound) -> &'static str {
    match bound {
        KBound::Lower => {
            "k -> 0: the BEM loops soften more gradually than any Valanis element with k >= 0 \
             (exponential approach to muFz): many spots of different sizes enter slip one after \
             another; the fit is the best k = 0 element"
        }
        KBound::Upper => {
            "k -> 1: a Jenkins-like corner, full stiffness E0 until the force saturates at \
             muFz: the loops stick and then slip almost at once, as a few contact points do \
             when a spot's slip annulus is narrower than a grid spacing (one or few spots on \
             the patch, few points per spot); refine the grid and enlarge the patch"
        }
        KBound::Inside => "",
    }
}

/// Everything computed at one pressure of one realisation.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct PressureCalibration {
    /// Normal contact.
    pub sweep: SweepPoint,
    /// Loops at the amplitudes.
    pub amplitudes: AmplitudeSweep,
    /// One element fitted to all amplitudes together.
    pub fit: FitResult,
    /// One element per amplitude (same order as the amplitudes).
    pub per_amplitude: Vec<FitResult>,
    /// Set-up time of the tangential solver (s).
    pub tangential_setup_s: f64,
}

/// Time of each stage (s): wall time and CPU time of the chain's thread. For a realisation, its
/// chain (single-threaded when chains run concurrently, so that the CPU time is the stage's
/// whole cost, unaffected by other processes on the machine); for a run, summed over all chains,
/// with the run's wall time in `total_s`.
#[derive(Debug, Clone, Copy, Default, serde::Serialize, serde::Deserialize)]
pub struct StageTimes {
    /// Wall time generating (or hashing) the surface (s).
    pub surface_s: f64,
    /// Wall time of the normal-contact sweep (s).
    pub normal_s: f64,
    /// Wall time of the tangential loops (s).
    pub tangential_s: f64,
    /// Wall time of the Valanis fits (s).
    pub fit_s: f64,
    /// CPU time of the surface stage (s).
    pub surface_cpu_s: f64,
    /// CPU time of the normal sweep (s).
    pub normal_cpu_s: f64,
    /// CPU time of the tangential loops (s).
    pub tangential_cpu_s: f64,
    /// CPU time of the fits (s).
    pub fit_cpu_s: f64,
    /// Wall time of the whole chain (realisation) or of the whole run (s).
    pub total_s: f64,
}

impl StageTimes {
    fn add(&mut self, o: &StageTimes) {
        self.surface_s += o.surface_s;
        self.normal_s += o.normal_s;
        self.tangential_s += o.tangential_s;
        self.fit_s += o.fit_s;
        self.surface_cpu_s += o.surface_cpu_s;
        self.normal_cpu_s += o.normal_cpu_s;
        self.tangential_cpu_s += o.tangential_cpu_s;
        self.fit_cpu_s += o.fit_cpu_s;
    }
}

/// CPU time of the calling thread (s; `CLOCK_THREAD_CPUTIME_ID`, exact to the nanosecond where
/// /proc/thread-self/schedstat moves in scheduler ticks of several ms), NaN where the platform
/// has no such clock.
fn thread_cpu_s() -> f64 {
    cpu_time::ThreadTime::try_now().map_or(f64::NAN, |t| t.as_duration().as_secs_f64())
}

/// Wall and thread-CPU stopwatch of a stage.
struct Lap {
    wall: Instant,
    cpu: f64,
}

impl Lap {
    fn start() -> Self {
        Self {
            wall: Instant::now(),
            cpu: thread_cpu_s(),
        }
    }

    /// `(wall, cpu)` seconds since the start.
    fn stop(&self) -> (f64, f64) {
        (self.wall.elapsed().as_secs_f64(), thread_cpu_s() - self.cpu)
    }
}

/// One surface through the chain.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct Realisation {
    /// Seed of a generated surface (`None` for a given surface).
    pub seed: Option<u64>,
    /// Grid points `(nx, ny)`.
    pub grid: (usize, usize),
    /// Patch size `(lx, ly)` (m).
    pub patch_m: (f64, f64),
    /// SHA-256 of the surface heights (f64 little-endian, row-major).
    pub surface_sha256: String,
    /// One entry per pressure.
    pub pressures: Vec<PressureCalibration>,
    /// Stage times of this chain.
    pub times: StageTimes,
}

/// The surfaces to calibrate on.
#[derive(Debug, Clone)]
pub enum SurfaceSource {
    /// `realisations.count` Gaussian surfaces of the configuration's `[surface]` statistics.
    Generated,
    /// One given (e.g. measured) equivalent surface; its periodicity selects the kernel.
    Given {
        /// Heights (m) on the grid.
        surface: Grid2,
        /// Where it came from (file names), for the reports.
        description: String,
    },
}

/// Convergence facts and verdicts at one pressure.
#[derive(Debug, Clone, serde::Serialize)]
pub struct PressureConvergence {
    /// Nominal pressure (Pa).
    pub pressure_pa: f64,
    /// Contact spots on the patch over the realisations.
    pub contact_spots: Summary,
    /// Median over the realisations of the median spot size (grid points).
    pub median_spot_points: f64,
    /// Smallest median spot size of a realisation (grid points).
    pub min_median_spot_points: usize,
    /// Realisations whose grid does not resolve the narrower of contact spots and free regions
    /// (fewer than [`RESOLVED_POINTS_ACROSS`] points across, [`SweepPoint::under_resolved`]).
    pub under_resolved_realisations: usize,
    /// Smallest number of grid points across the narrower phase over the realisations.
    pub min_points_across: f64,
    /// Whether that narrowest phase is the contact spots (else the free regions).
    pub narrowest_is_contact: bool,
    /// Grid checks of kn, E0, k (`n` against `n/2` points per side, same surfaces).
    pub grid: [Check; 3],
    /// Patch checks of kn, E0, k (`L` against `L/2`, independent surfaces).
    pub patch: [Check; 3],
    /// Worst grid verdict.
    pub grid_verdict: Verdict,
    /// Worst patch verdict.
    pub patch_verdict: Verdict,
}

/// The coarser configurations of the convergence checks.
#[derive(Debug, Clone, serde::Serialize)]
pub struct ConvergenceStudy {
    /// Grid check: the main surfaces with half the points per side (None if that grid does
    /// not resolve the correlation length, or for a given surface).
    pub grid_spec: Option<GaussianSurfaceSpec>,
    /// Patch check: half the patch side at the same spacing, seeds after the main ones.
    pub patch_spec: Option<GaussianSurfaceSpec>,
    /// Why a check was not run.
    pub notes: Vec<String>,
    /// Verdicts per pressure.
    pub pressures: Vec<PressureConvergence>,
}

/// Result of [`run`].
#[derive(Debug, Clone)]
pub struct CalibrationRun {
    /// The configuration the run used.
    pub config: CalibrationConfig,
    /// What the surfaces were.
    pub surface_description: String,
    /// Means (and intervals over ≥ 2 realisations) per pressure.
    pub table: CalibrationTable,
    /// The main realisations.
    pub realisations: Vec<Realisation>,
    /// The realisations of the grid check (same seeds, half the points per side).
    pub grid_check: Vec<Realisation>,
    /// The realisations of the patch check (half the patch, same spacing).
    pub patch_check: Vec<Realisation>,
    /// Convergence verdicts.
    pub convergence: ConvergenceStudy,
    /// Everything the user should know about the table's reliability, one sentence each.
    pub warnings: Vec<String>,
    /// Stage times summed over all chains (main and checks), and the run's wall time.
    pub times: StageTimes,
}

fn surface_sha256(surface: &Grid2) -> String {
    let mut bytes = Vec::with_capacity(surface.heights.len() * 8);
    for h in surface.heights.iter() {
        bytes.extend_from_slice(&h.to_le_bytes());
    }
    sha256_hex(&bytes)
}

/// Progress units of one chain (surface, normal solves, tangential steps, fits).
fn chain_units(config: &CalibrationConfig) -> u64 {
    let p = config.loading.pressures_pa.len();
    let steps = amplitudes::step_count(
        &config.loading.amplitude_factors,
        config.loading.steps_per_cycle,
    );
    (1 + p + p * steps + p) as u64
}

/// The checks' surface statistics: half the points per side on the same patch (grid), and half
/// the patch side at the same spacing (patch); `None` where that spec is invalid.
fn check_specs(
    config: &CalibrationConfig,
) -> (
    Option<GaussianSurfaceSpec>,
    Option<GaussianSurfaceSpec>,
    Vec<String>,
) {
    let s = config.surface;
    let mut notes = Vec::new();
    let mut admissible = |spec: GaussianSurfaceSpec, what: &str| match spec.validate() {
        Ok(()) => Some(spec),
        Err(e) => {
            notes.push(format!(
                "{what} check not run: {}x{} points over {:e} m x {:e} m is not admissible ({e})",
                spec.nx, spec.ny, spec.lx_m, spec.ly_m
            ));
            None
        }
    };
    let grid = admissible(
        GaussianSurfaceSpec {
            nx: s.nx / 2,
            ny: s.ny / 2,
            ..s
        },
        "grid",
    );
    let patch = admissible(
        GaussianSurfaceSpec {
            nx: s.nx / 2,
            ny: s.ny / 2,
            lx_m: s.lx_m * (s.nx / 2) as f64 / s.nx as f64,
            ly_m: s.ly_m * (s.ny / 2) as f64 / s.ny as f64,
            seed: s.seed.wrapping_add(config.realisations.count as u64),
            ..s
        },
        "patch",
    );
    (grid, patch, notes)
}

/// The chains of a realisation ([`RealisationChains`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Chain {
    /// The main surface.
    Main,
    /// The same seed on the grid with half the points per side.
    GridCheck,
    /// The independent surface of the half-size patch.
    PatchCheck,
}

impl Chain {
    /// The three chains, in the order of [`RealisationChains`].
    pub const ALL: [Chain; 3] = [Chain::Main, Chain::GridCheck, Chain::PatchCheck];

    /// Name in messages (`main`, `grid check`, `patch check`).
    pub fn name(self) -> &'static str {
        match self {
            Chain::Main => "main",
            Chain::GridCheck => "grid check",
            Chain::PatchCheck => "patch check",
        }
    }
}

/// The generated surface of `chain` of realisation `r` (0-based) of a calibration over generated
/// surfaces: the main surface has seed `surface.seed + r`, the grid check the same seed at half
/// the points per side, the patch check seed `surface.seed + realisations.count + r` on the
/// half-size patch; `None` for a check that does not run (its spec is not admissible). What
/// [`run_realisations`] generates, and what a sharded calibration's merge checks each chain's
/// seed, grid and patch against.
pub fn chain_spec(
    config: &CalibrationConfig,
    chain: Chain,
    r: usize,
) -> Option<GaussianSurfaceSpec> {
    let (grid, patch, _) = check_specs(config);
    chain_spec_of(config, grid, patch, chain, r)
}

/// [`chain_spec`] with the check specs computed once.
fn chain_spec_of(
    config: &CalibrationConfig,
    grid: Option<GaussianSurfaceSpec>,
    patch: Option<GaussianSurfaceSpec>,
    chain: Chain,
    r: usize,
) -> Option<GaussianSurfaceSpec> {
    let base = match chain {
        Chain::Main => Some(config.surface),
        Chain::GridCheck => grid,
        Chain::PatchCheck => patch,
    }?;
    Some(GaussianSurfaceSpec {
        seed: base.seed.wrapping_add(r as u64),
        ..base
    })
}

/// Number of realisations: `realisations.count` generated surfaces, or one given surface.
pub fn realisation_count(config: &CalibrationConfig, source: &SurfaceSource) -> usize {
    match source {
        SurfaceSource::Given { .. } => 1,
        SurfaceSource::Generated => config.realisations.count,
    }
}

/// Number of progress units [`run`] reports for `config` and `source`.
pub fn progress_units(config: &CalibrationConfig, source: &SurfaceSource) -> u64 {
    progress_units_of(config, source, realisation_count(config, source))
}

/// The fit data of one amplitude: the element's own virgin quarter cycle to `+a` (the BEM's
/// virgin curve at those displacements, which the cost does not use) and the steady BEM loop.
pub fn loop_data(
    sweep: &AmplitudeSweep,
    j: usize,
    steps_per_cycle: usize,
    pressure_pa: f64,
) -> LoopData {
    let n = steps_per_cycle;
    let l = &sweep.loops[j];
    let a = l.amplitude_m;
    let mut q: Vec<f64> = (0..=n / 4)
        .map(|k| {
            if k == n / 4 {
                a
            } else {
                a * (2.0 * std::f64::consts::PI * k as f64 / n as f64).sin()
            }
        })
        .collect();
    let mut force: Vec<f64> = q.iter().map(|&d| sweep.virgin_shear_at(d)).collect();
    q.extend(&l.displacement_m[1..]);
    force.extend(&l.shear_stress_pa[1..]);
    LoopData::constant_load(q, force, pressure_pa, n / 4..n / 4 + n + 1)
}

/// Run one surface through the chain (single pass, on the current rayon pool). `bar` receives
/// `chain_units` increments.
pub fn calibrate_surface(
    config: &CalibrationConfig,
    surface: &Grid2,
    bar: &ProgressBar,
) -> Result<(Vec<PressureCalibration>, StageTimes)> {
    let mut times = StageTimes::default();
    let material = Material {
        youngs_modulus_pa: config.material.youngs_modulus_pa,
        poisson_ratio: config.material.poisson_ratio,
    }
    .validated("material")?;
    let e_star = composite_modulus(material, material)?;

    // Normal sweep.
    let t = Lap::start();
    let mut normal = NormalSolver::new(
        &NormalProblem {
            surface,
            e_star_pa: e_star,
            hardness_pa: config.material.hardness()?,
        },
        NormalOptions {
            tolerance: config.contact.normal_tolerance,
            ..NormalOptions::default()
        },
    )?;
    let sweep = sweep::run(
        &mut normal,
        &config.loading.pressures_pa,
        SweepOptions {
            keep_solutions: true,
        },
        |_| bar.inc(1),
    )?;
    drop(normal);
    (times.normal_s, times.normal_cpu_s) = t.stop();

    // Tangential loops.
    let boundary = if surface.periodic {
        Boundary::Periodic
    } else {
        Boundary::ZeroPadded
    };
    let t = Lap::start();
    let mut loops = Vec::with_capacity(sweep.points.len());
    for sol in &sweep.solutions {
        let started = Instant::now();
        let mut solver = TangentialSolver::new(
            &TangentialProblem {
                pressure: &sol.pressure,
                dx: sol.dx,
                dy: sol.dy,
                boundary,
                friction_coefficient: config.contact.mu,
                body1: material,
                body2: material,
            },
            TangentialOptions {
                tolerance: config.contact.tangential_tolerance,
                ..TangentialOptions::default()
            },
        )?;
        let setup = started.elapsed().as_secs_f64();
        let sweep = amplitudes::run(
            &mut solver,
            &config.loading.amplitude_factors,
            config.loading.steps_per_cycle,
            || bar.inc(1),
        )?;
        loops.push((sweep, setup));
    }
    drop(sweep.solutions);
    (times.tangential_s, times.tangential_cpu_s) = t.stop();

    // Fits.
    let t = Lap::start();
    let opts = FitOptions {
        mu: config.contact.mu,
        fit_et: config.fit.fit_et,
        max_iters: config.fit.max_iterations,
        k_starts: config.fit.k_starts.clone(),
    };
    let n = config.loading.steps_per_cycle;
    let mut out = Vec::with_capacity(loops.len());
    for (point, (amps, setup)) in sweep.points.into_iter().zip(loops) {
        let p = point.pressure_pa;
        let data: Vec<LoopData> = (0..amps.loops.len())
            .map(|j| loop_data(&amps, j, n, p))
            .collect();
        let failed = |e: Error| Error::Data(format!("Valanis fit at {p} Pa failed: {e}"));
        let fit = fit_valanis_loops(&data, &opts).map_err(failed)?;
        let per_amplitude = data
            .iter()
            .map(|d| fit_valanis(d, &opts).map_err(failed))
            .collect::<Result<Vec<_>>>()?;
        out.push(PressureCalibration {
            sweep: point,
            amplitudes: amps,
            fit,
            per_amplitude,
            tangential_setup_s: setup,
        });
        bar.inc(1);
    }
    (times.fit_s, times.fit_cpu_s) = t.stop();
    Ok((out, times))
}

/// How the chains share the cores.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Parallelism {
    /// Chains run concurrently, each single-threaded (the default of [`run`]).
    ChainsConcurrently,
    /// One chain at a time, each on all threads of the current pool.
    OneChainAtATime,
}

/// Run `f` on every job with as many worker threads as the current rayon pool has, each
/// taking the next job from a shared counter and running it inside its own single-threaded
/// rayon pool (so the solvers' parallel loops run serially within a chain). Results in job
/// order.
fn run_concurrently<J: Copy + Sync, T: Send>(
    jobs: &[J],
    f: impl Fn(J) -> Result<T> + Sync,
) -> Result<Vec<Result<T>>> {
    let workers = rayon::current_num_threads().clamp(1, jobs.len().max(1));
    let next = std::sync::atomic::AtomicUsize::new(0);
    let slots: Vec<std::sync::Mutex<Option<Result<T>>>> =
        jobs.iter().map(|_| std::sync::Mutex::new(None)).collect();
    let pools = (0..workers)
        .map(|_| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(1)
                .build()
                .map_err(|e| Error::Data(format!("cannot start a worker thread: {e}")))
        })
        .collect::<Result<Vec<_>>>()?;
    std::thread::scope(|scope| {
        for pool in &pools {
            scope.spawn(|| loop {
                let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                let Some(&job) = jobs.get(i) else { break };
                let r = pool.install(|| f(job));
                *slots[i].lock().expect("result slot") = Some(r);
            });
        }
    });
    Ok(slots
        .into_iter()
        .map(|m| {
            m.into_inner()
                .expect("result slot")
                .expect("every job was run")
        })
        .collect())
}

/// Run the calibration (see the module documentation). `bar` receives [`progress_units`]
/// increments (pass `ProgressBar::hidden()` for none).
pub fn run(
    config: &CalibrationConfig,
    source: &SurfaceSource,
    bar: &ProgressBar,
) -> Result<CalibrationRun> {
    run_with(config, source, bar, Parallelism::ChainsConcurrently)
}

/// [`run`] with the given [`Parallelism`] (the benchmark compares both; the results are the
/// same bit for bit).
pub fn run_with(
    config: &CalibrationConfig,
    source: &SurfaceSource,
    bar: &ProgressBar,
    parallelism: Parallelism,
) -> Result<CalibrationRun> {
    config.validate()?;
    let started = Instant::now();
    let count = realisation_count(config, source);
    let units = run_realisations(config, source, 0..count, bar, parallelism)?;
    assemble(config, source, units, started.elapsed().as_secs_f64())
}

/// The chains of realisation `r`: the main surface (seed `surface.seed + r`, or the given
/// surface) and, where the checks run, the same seed on the grid with half the points per side
/// and the independent surface `r` of the half-size patch. The unit of a sharded calibration
/// ([`crate::calibrate::sweep::CalibrationSweep`]): nothing in it depends on another
/// realisation.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct RealisationChains {
    /// The main realisation.
    pub main: Realisation,
    /// Its grid check (None when that check does not run).
    pub grid_check: Option<Realisation>,
    /// Its patch check (None when that check does not run).
    pub patch_check: Option<Realisation>,
}

/// The grid and patch check specs of `source` and the notes on checks that do not run.
fn checks_of(
    config: &CalibrationConfig,
    source: &SurfaceSource,
) -> (
    Option<GaussianSurfaceSpec>,
    Option<GaussianSurfaceSpec>,
    Vec<String>,
) {
    match source {
        SurfaceSource::Generated => check_specs(config),
        SurfaceSource::Given { .. } => (
            None,
            None,
            vec!["grid and patch checks not run: a given surface has no other resolution or size of the same realisation".to_string()],
        ),
    }
}

/// Progress units of [`run_realisations`] over `realisations` realisations.
pub fn progress_units_of(
    config: &CalibrationConfig,
    source: &SurfaceSource,
    realisations: usize,
) -> u64 {
    let (g, p, _) = checks_of(config, source);
    (realisations * (1 + usize::from(g.is_some()) + usize::from(p.is_some()))) as u64
        * chain_units(config)
}

/// Run the chains of the realisations `realisations` (0-based; `0..1` for a given surface),
/// concurrently or one at a time (see [`Parallelism`]). `bar` receives
/// [`progress_units_of`] increments. The result of a realisation does not depend on which
/// others run with it.
pub fn run_realisations(
    config: &CalibrationConfig,
    source: &SurfaceSource,
    realisations: std::ops::Range<usize>,
    bar: &ProgressBar,
    parallelism: Parallelism,
) -> Result<Vec<RealisationChains>> {
    config.validate()?;
    let count = realisation_count(config, source);
    if realisations.end > count {
        return Err(Error::param(
            "realisations",
            format!("realisations {realisations:?} requested, the configuration has {count}"),
        ));
    }
    let (grid_spec, patch_spec, _) = checks_of(config, source);
    // One job per chain to run: (chain, realisation), the main chains first.
    let mut jobs: Vec<(Chain, usize)> = realisations.clone().map(|r| (Chain::Main, r)).collect();
    if grid_spec.is_some() {
        jobs.extend(realisations.clone().map(|r| (Chain::GridCheck, r)));
    }
    if patch_spec.is_some() {
        jobs.extend(realisations.clone().map(|r| (Chain::PatchCheck, r)));
    }
    let spec_of = |(chain, r): (Chain, usize)| -> GaussianSurfaceSpec {
        chain_spec_of(config, grid_spec, patch_spec, chain, r)
            .expect("a job for every chain that runs")
    };
    let run_job = |job: (Chain, usize)| -> Result<Realisation> {
        let t = Lap::start();
        let (surface, seed) = match source {
            SurfaceSource::Given { surface, .. } => (surface.clone(), None),
            SurfaceSource::Generated => {
                let spec = spec_of(job);
                (generate(&spec)?, Some(spec.seed))
            }
        };
        let sha = surface_sha256(&surface);
        let (surface_s, surface_cpu_s) = t.stop();
        bar.inc(1);
        let (pressures, mut times) = calibrate_surface(config, &surface, bar)?;
        (times.surface_s, times.surface_cpu_s) = (surface_s, surface_cpu_s);
        times.total_s = t.stop().0;
        Ok(Realisation {
            seed,
            grid: (surface.nx(), surface.ny()),
            patch_m: (surface.lx(), surface.ly()),
            surface_sha256: sha,
            pressures,
            times,
        })
    };
    let results: Vec<Result<Realisation>> = match parallelism {
        Parallelism::OneChainAtATime => jobs.iter().map(|&j| run_job(j)).collect(),
        Parallelism::ChainsConcurrently => run_concurrently(&jobs, run_job)?,
    };
    let mut units: Vec<RealisationChains> = Vec::with_capacity(realisations.len());
    for (job, r) in jobs.iter().zip(results) {
        let r = r?;
        match *job {
            (Chain::Main, _) => units.push(RealisationChains {
                main: r,
                grid_check: None,
                patch_check: None,
            }),
            (Chain::GridCheck, i) => units[i - realisations.start].grid_check = Some(r),
            (Chain::PatchCheck, i) => units[i - realisations.start].patch_check = Some(r),
        }
    }
    Ok(units)
}

/// The run from the chains of every realisation, in order (as [`run_realisations`] returns them
/// for `0..count`, or merged from the shards of a sharded calibration): the table, the
/// convergence verdicts and the warnings. `total_s` is the run's wall time.
pub fn assemble(
    config: &CalibrationConfig,
    source: &SurfaceSource,
    units: Vec<RealisationChains>,
    total_s: f64,
) -> Result<CalibrationRun> {
    config.validate()?;
    let count = realisation_count(config, source);
    let (grid_spec, patch_spec, notes) = checks_of(config, source);
    if units.len() != count
        || units.iter().any(|u| {
            u.grid_check.is_some() != grid_spec.is_some()
                || u.patch_check.is_some() != patch_spec.is_some()
        })
    {
        return Err(Error::Data(format!(
            "a calibration of {count} realisation(s) needs the chains of each, got {} realisation(s) (or chains of checks the configuration does not run)",
            units.len()
        )));
    }
    let mut main = Vec::with_capacity(count);
    let mut grid_check = Vec::new();
    let mut patch_check = Vec::new();
    let mut times = StageTimes::default();
    for u in units {
        times.add(&u.main.times);
        main.push(u.main);
        if let Some(g) = u.grid_check {
            times.add(&g.times);
            grid_check.push(g);
        }
        if let Some(p) = u.patch_check {
            times.add(&p.times);
            patch_check.push(p);
        }
    }
    let pressures: Vec<PressureConvergence> = (0..config.loading.pressures_pa.len())
        .map(|i| convergence_at(config, i, &main, &grid_check, &patch_check))
        .collect();
    let table = table_of(config, &main)?.with_convergence(
        pressures
            .iter()
            .map(|pc| Verdict::worst([pc.grid_verdict, pc.patch_verdict]))
            .collect(),
    )?;
    let table = table.with_comments(vec![crate::calibrate::table::kn_comment(
        config.material.hardness()?,
    )])?;
    let surface_description = match source {
        SurfaceSource::Given { description, .. } => description.clone(),
        SurfaceSource::Generated => {
            let s = config.surface;
            format!(
                "{count} Gaussian surface(s), Rq {} m, correlation lengths {} x {} m, patch {} x {} m, {}x{} points, seeds {}..={}",
                s.rq_m, s.clx_m, s.cly_m, s.lx_m, s.ly_m, s.nx, s.ny, s.seed, s.seed.wrapping_add(count as u64 - 1)
            )
        }
    };
    let convergence = ConvergenceStudy {
        grid_spec,
        patch_spec,
        notes,
        pressures,
    };
    let warnings = warnings_of(config, &main, &convergence);
    times.total_s = total_s;
    Ok(CalibrationRun {
        config: config.clone(),
        surface_description,
        table,
        realisations: main,
        grid_check,
        patch_check,
        convergence,
        warnings,
        times,
    })
}

/// Values of one quantity at pressure `i` over realisations.
fn values(rs: &[Realisation], i: usize, f: impl Fn(&PressureCalibration) -> f64) -> Vec<f64> {
    rs.iter().map(|r| f(&r.pressures[i])).collect()
}

fn kn(pc: &PressureCalibration) -> f64 {
    pc.sweep.kn_n_per_m3
}
fn e0(pc: &PressureCalibration) -> f64 {
    pc.fit.params.e0
}
fn k(pc: &PressureCalibration) -> f64 {
    pc.fit.params.k
}
/// Energy per cycle of the BEM loop at the largest amplitude (J/m²).
fn energy(pc: &PressureCalibration) -> f64 {
    pc.amplitudes
        .loops
        .last()
        .map_or(f64::NAN, |l| l.loop_area_j_per_m2)
}

/// The table: means over the realisations, with intervals when there are at least two.
fn table_of(config: &CalibrationConfig, rs: &[Realisation]) -> Result<CalibrationTable> {
    let mut rows = Vec::new();
    let mut intervals = Vec::new();
    for (i, &p) in config.loading.pressures_pa.iter().enumerate() {
        let s = |f: &dyn Fn(&PressureCalibration) -> f64| summarise(&values(rs, i, f));
        let area = s(&|pc| pc.sweep.contact_area_ratio);
        let (skn, se0, sk) = (s(&kn), s(&e0), s(&k));
        let set = s(&|pc| pc.fit.params.et);
        let sen = s(&energy);
        rows.push(CalibrationRow {
            pressure_pa: p,
            contact_area_ratio: area.mean,
            element: ContactParamsPerArea {
                kn_n_per_m3: skn.mean,
                e0_n_per_m3: se0.mean,
                k: sk.mean,
                mu: config.contact.mu,
                et_n_per_m3: set.mean,
            },
            fit_r2: s(&|pc| pc.fit.r2).mean,
            energy_per_cycle_j_per_m2: sen.mean,
        });
        intervals.push(RowInterval {
            realisations: rs.len(),
            contact_area_ratio: area.ci95,
            kn_n_per_m3: skn.ci95,
            e0_n_per_m3: se0.ci95,
            k: sk.ci95,
            et_n_per_m3: set.ci95,
            energy_per_cycle_j_per_m2: sen.ci95,
        });
    }
    if rs.len() >= 2 {
        CalibrationTable::with_intervals(rows, intervals)
    } else {
        CalibrationTable::new(rows)
    }
}

fn convergence_at(
    config: &CalibrationConfig,
    i: usize,
    main: &[Realisation],
    grid: &[Realisation],
    patch: &[Realisation],
) -> PressureConvergence {
    let c = config.convergence;
    let quantities: [fn(&PressureCalibration) -> f64; 3] = [kn, e0, k];
    let tolerance = |j: usize, mean: f64| {
        if j == 2 {
            c.k_tolerance
        } else {
            c.relative_tolerance * mean.abs()
        }
    };
    let checks = |other: &[Realisation], paired: bool| -> [Check; 3] {
        std::array::from_fn(|j| {
            if other.is_empty() {
                return Check::not_checked();
            }
            let x = values(main, i, quantities[j]);
            let y = values(other, i, quantities[j]);
            let d = if paired {
                paired_difference(&x, &y)
            } else {
                welch_difference(&x, &y)
            };
            Check::new(d, tolerance(j, summarise(&x).mean))
        })
    };
    let grid = checks(grid, true);
    let patch = checks(patch, false);
    let mut medians: Vec<usize> = main
        .iter()
        .map(|r| r.pressures[i].sweep.median_spot_points)
        .collect();
    medians.sort_unstable();
    let median = if medians.len() % 2 == 1 {
        medians[medians.len() / 2] as f64
    } else {
        0.5 * (medians[medians.len() / 2 - 1] + medians[medians.len() / 2]) as f64
    };
    let narrowest = main
        .iter()
        .map(|r| r.pressures[i].sweep.resolution)
        .min_by(|a, b| a.points_across().total_cmp(&b.points_across()))
        .expect("at least one realisation");
    PressureConvergence {
        under_resolved_realisations: main
            .iter()
            .filter(|r| r.pressures[i].sweep.under_resolved())
            .count(),
        min_points_across: narrowest.points_across(),
        narrowest_is_contact: narrowest.contact_is_narrower(),
        pressure_pa: config.loading.pressures_pa[i],
        contact_spots: summarise(&values(main, i, |pc| pc.sweep.contact_spots as f64)),
        median_spot_points: median,
        min_median_spot_points: medians[0],
        grid_verdict: Verdict::worst(grid.iter().map(|c| c.verdict)),
        patch_verdict: Verdict::worst(patch.iter().map(|c| c.verdict)),
        grid,
        patch,
    }
}

/// Relative difference between the fitted element's and the BEM loops' energy per cycle (means
/// over the realisations) beyond which a pressure gets a warning: the dissipation, which sets a
/// friction damper's damping, is then off by more than a fifth at that amplitude.
pub const ENERGY_WARNING_REL: f64 = 0.2;

/// Energy per cycle at one amplitude over the realisations (J/m²; a row of
/// `energy_vs_amplitude.csv`).
pub(crate) struct EnergyAtAmplitude {
    /// Amplitude over the gross-slip displacement (-).
    pub factor: f64,
    /// The BEM loops' areas.
    pub bem: Summary,
    /// The fitted element's loops' areas.
    pub element: Summary,
    /// Largest numerical floor of the BEM loop areas over the realisations
    /// ([`crate::calibrate::amplitudes::energy_floor`]).
    pub floor: f64,
    /// Realisations whose BEM loop area is negative beyond its floor (numerical artefacts).
    pub negative_beyond_floor: usize,
}

impl EnergyAtAmplitude {
    /// `mean element energy / mean BEM energy − 1`, `None` where the mean BEM energy is within
    /// the numerical floor (a relative error of an unresolved energy is not a result).
    pub fn relative_error(&self) -> Option<f64> {
        (self.bem.mean > self.floor).then(|| self.element.mean / self.bem.mean - 1.0)
    }
}

/// Per amplitude at pressure `i`: the BEM's and the element's energy per cycle over the
/// realisations and the BEM loops' numerical floor (`energy_vs_amplitude.csv`).
pub(crate) fn energy_summaries(
    config: &CalibrationConfig,
    realisations: &[Realisation],
    i: usize,
) -> Vec<EnergyAtAmplitude> {
    let factors = &config.loading.amplitude_factors;
    (0..factors.len())
        .map(|j| {
            let bem = values(realisations, i, |pc| {
                pc.amplitudes.loops[j].loop_area_j_per_m2
            });
            let el = values(realisations, i, |pc| pc.fit.loops[j].energy_model);
            let loops = realisations
                .iter()
                .map(|r| &r.pressures[i].amplitudes.loops[j]);
            EnergyAtAmplitude {
                factor: factors[j],
                bem: summarise(&bem),
                element: summarise(&el),
                floor: loops
                    .clone()
                    .map(|l| l.energy_floor_j_per_m2)
                    .fold(0.0, f64::max),
                negative_beyond_floor: loops
                    .filter(|l| l.loop_area_j_per_m2 < -l.energy_floor_j_per_m2)
                    .count(),
            }
        })
        .collect()
}

/// Largest `|mean element energy / mean BEM energy − 1|` over the amplitudes at pressure `i`
/// whose BEM energy is above its numerical floor, with its amplitude factor (the
/// `mean_rel_error` of `energy_vs_amplitude.csv`); `(0, NaN)` when none is.
fn worst_energy_error(config: &CalibrationConfig, main: &[Realisation], i: usize) -> (f64, f64) {
    energy_summaries(config, main, i)
        .into_iter()
        .filter_map(|e| e.relative_error().map(|r| (r, e.factor)))
        .fold((0.0, f64::NAN), |worst, e| {
            if e.0.abs() > worst.0.abs() || e.0.is_nan() {
                e
            } else {
                worst
            }
        })
}

fn warnings_of(
    config: &CalibrationConfig,
    main: &[Realisation],
    conv: &ConvergenceStudy,
) -> Vec<String> {
    let mut w = Vec::new();
    let n = main.len();
    if n == 1 {
        w.push(
            "one realisation: the values come from one surface and carry no confidence interval"
                .to_string(),
        );
    }
    w.extend(conv.notes.iter().cloned());
    let mpa = |p: f64| format!("{} MPa", p / 1e6);
    for (i, pc) in conv.pressures.iter().enumerate() {
        let p = mpa(pc.pressure_pa);
        if pc.under_resolved_realisations > 0 {
            w.push(format!(
                "{p}: under-resolved {} in {} of {n} realisation(s): {:.1} grid points across (fewer than {}; median spot {} grid points): refine the grid",
                if pc.narrowest_is_contact {
                    "contact spots"
                } else {
                    "free regions"
                },
                pc.under_resolved_realisations,
                pc.min_points_across,
                RESOLVED_POINTS_ACROSS,
                pc.median_spot_points
            ));
        }
        if pc.contact_spots.mean < FEW_SPOTS {
            w.push(format!(
                "{p}: {:.1} contact spots on the patch on average: the row describes a few asperities, not a rough surface; enlarge the patch",
                pc.contact_spots.mean
            ));
        }
        let energies = energy_summaries(config, main, i);
        let unresolved: Vec<String> = energies
            .iter()
            .filter(|e| e.relative_error().is_none())
            .map(|e| e.factor.to_string())
            .collect();
        if !unresolved.is_empty() {
            w.push(format!(
                "{p}: the BEM energy per cycle at {} × the gross-slip displacement is within its numerical floor (solver tolerance × traction bound × contact fraction × 4a; energy_floor_J_per_m2 of energy_vs_amplitude.csv): no energy error is given there; a finer grid or a tighter tangential_tolerance resolves it",
                unresolved.join(", ")
            ));
        }
        for e in energies.iter().filter(|e| e.negative_beyond_floor > 0) {
            w.push(format!(
                "{p}: negative BEM loop area beyond its numerical floor in {} of {n} realisation(s) at {} × the gross-slip displacement: a numerical artefact (the loop is not resolved), not a dissipation",
                e.negative_beyond_floor, e.factor
            ));
        }
        let (energy_error, factor) = worst_energy_error(config, main, i);
        if energy_error.abs() > ENERGY_WARNING_REL || energy_error.is_nan() {
            w.push(format!(
                "{p}: the fitted element's energy per cycle differs from the BEM loops' by {:+.0} % at {factor} × the gross-slip displacement (ratio of the means over the realisations: mean_rel_error of energy_vs_amplitude.csv): one element does not carry the dissipation at every amplitude",
                100.0 * energy_error
            ));
        }
        let why_undetermined = if main.len() < 2 {
            "one realisation gives no interval of the change"
        } else {
            "the 95 % interval of the change straddles the tolerance"
        };
        for (what, v) in [("grid", pc.grid_verdict), ("patch size", pc.patch_verdict)] {
            match v {
                Verdict::NotConverged => w.push(format!("{p}: NOT converged in {what}")),
                Verdict::Undetermined => w.push(format!(
                    "{p}: convergence in {what} undetermined ({why_undetermined}; more realisations would tell)"
                )),
                Verdict::NotChecked | Verdict::Converged => {}
            }
        }
        for bound in [KBound::Lower, KBound::Upper] {
            let hits = main
                .iter()
                .filter(|r| KBound::of(r.pressures[i].fit.params.k) == bound)
                .count();
            if hits > 0 {
                w.push(format!(
                    "{p}: k at its {} bound in {hits} of {n} realisation(s) ({})",
                    if bound == KBound::Lower {
                        "lower"
                    } else {
                        "upper"
                    },
                    k_bound_reading(bound)
                ));
            }
        }
        let unconverged = main
            .iter()
            .filter(|r| !r.pressures[i].fit.converged)
            .count();
        if unconverged > 0 {
            w.push(format!(
                "{p}: the Valanis fit stopped on its iteration cap ({} per start) in {unconverged} of {n} realisation(s)",
                config.fit.max_iterations
            ));
        }
        let worst_closure = main
            .iter()
            .flat_map(|r| {
                r.pressures[i]
                    .amplitudes
                    .loops
                    .iter()
                    .map(|l| l.closure_error)
            })
            .fold(0.0, f64::max);
        if worst_closure > CLOSURE_WARNING {
            w.push(format!(
                "{p}: a loop's closure error is {worst_closure:.3} of max mu p: the Masing assumption of the amplitude history is weak here"
            ));
        }
    }
    w
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn k_bounds_are_flagged_with_their_reading() {
        assert_eq!(KBound::of(7.8e-11), KBound::Lower);
        assert_eq!(KBound::of(0.9999996), KBound::Upper);
        assert_eq!(KBound::of(0.5), KBound::Inside);
        assert!(k_bound_reading(KBound::Lower).contains("gradually"));
        assert!(k_bound_reading(KBound::Upper).contains("Jenkins"));
        assert!(k_bound_reading(KBound::Inside).is_empty());
    }
}
