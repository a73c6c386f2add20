//! Frictionless normal contact of a rough surface with an elastic half-space: projected conjugate
//! gradients, plain (Polonsky & Keer, Wear 231 (1999) 206–219) or preconditioned by the inverse
//! of the half-space compliance (after Vollebregt, J. Comput. Phys. 257 (2014) 333–351), and the
//! normal contact stiffness from the tangent problem ([`stiffness`]).
//!
//! Units: lengths and gaps in m, pressures and moduli in Pa, energy in J.
//!
//! # Problem
//! The two rough elastic bodies are reduced to a rigid rough surface of heights `h(x)` (the
//! equivalent surface: sum of both roughnesses, peaks positive) against a flat elastic half-space
//! of composite modulus `E*` (`1/E* = (1-ν1²)/E1 + (1-ν2²)/E2`). With the initial separation
//! `h0 = max(h) − h` (zero at the highest point), the rigid approach `δ` and the elastic surface
//! displacement `u = K ⊛ p` (Boussinesq; [`crate::halfspace::influence::boussinesq_spectrum`]),
//! the gap is
//!
//! `g = h0 − δ + u`,
//!
//! and the unilateral contact conditions are `g ≥ 0`, `p ≥ 0`, `p·g = 0`, with the mean pressure
//! imposed, `mean(p) = p̄` (load control). `δ` is the Lagrange multiplier of the load: it is the
//! rigid approach measured from first contact of the highest grid point.
//!
//! # Algorithm (load control)
//! Both methods minimise the elastic energy `½ p·K⊛p + p·h0` over `p ≥ 0`, `mean(p) = p̄` by
//! conjugate gradients on the contact set `Ic = {p > 0}`, with the gap centred by its mean over
//! `Ic` (the current δ), the direction kept at zero sum (the load is kept), points leaving the
//! set by projection (`p ← max(p − τ t, 0)`) and penetrating points entering it; see
//! `normal/projected_cg.rs` for the steps. They differ in the search direction:
//!
//! - [`NormalMethod::PolonskyKeer`]: the centred gap itself (Fletcher–Reeves). The condition
//!   number of `K` on the contact set grows with the grid (its eigenvalues are those of
//!   `2/(E*|q|)` from `q ~ 1/L` to `q ~ 1/dx`), and so does the iteration count: 77–2052 on
//!   512²–2048² self-affine surfaces (BENCHMARKS.md). Cheapest per iteration (one transform pair).
//! - [`NormalMethod::Preconditioned`]: the gap filtered by `E*|q|/2` (the exact inverse of the
//!   periodic compliance) and restricted to `Ic`, the FFT preconditioner of Vollebregt (2014);
//!   Polak–Ribière+ with a restart test; penetrating points join the line search. Two transform
//!   pairs per iteration (one `K⊛t`; one preconditioner, in single precision, about half the
//!   cost of a double-precision pair), but 10–50 iterations, nearly
//!   independent of the grid and of the contact fraction; cold solves start from the solution
//!   on the grid coarsened 2 × 2 (nested iteration down to [`COARSEST_GRID`]). For zero-padded
//!   windows the preconditioner is the periodic `E*|q|/2` of the window (the iteration counts on
//!   Hertz windows equal those of the padded `|q|` at a quarter of its cost).
//! - [`NormalMethod::Auto`] (default): the preconditioned method. Measured against
//!   Polonsky–Keer at every contact fraction from 0.01 % to 76 % (periodic Gaussian and
//!   self-affine surfaces, 512²–2048², and a measured zero-padded topography) it takes 3–43×
//!   fewer iterations and 1.7–28× less time (BENCHMARKS.md); Polonsky–Keer is kept as the
//!   reference path (`method = polonsky-keer`).
//!
//! Both give the same contact set and mean gap (to 1e-9 relative) with the same criterion
//! (`tests/normal_contact.rs`). The displacement is updated by linearity when no point left or
//! entered the contact set, recomputed from `p` otherwise, every [`REFRESH_INTERVAL`] iterations,
//! and always before convergence is accepted.
//!
//! # Convergence criterion
//! The residual is the pressure-weighted relative gap error
//!
//! `ε = (Σ_Ic p_i |g_i| + p̄ Σ_{i∉Ic} max(−g_i, 0)) / (Σ_i p_i · h_rms)`,
//!
//! i.e. a complementarity error `Σ p·g` made dimensionless by the total load and the rms height
//! `h_rms` of the surface (the kind of criterion tamaas' Polonsky–Keer–Rey solver uses; Rey,
//! Anciaux & Molinari, Comput. Mech. 60 (2017) 69–81), plus any remaining penetration outside
//! the contact set. At equal tolerance (1e-10) both codes give identical contact sets on the
//! reference surface (BENCHMARKS.md). The
//! solve stops when `ε ≤ tolerance` (default [`NormalOptions::DEFAULT_TOLERANCE`]), evaluated on
//! a freshly convolved displacement; reaching `max_iterations` first is an
//! [`Error::NonConvergence`], never a silent result.
//!
//! # Hardness-limited (elastic–perfectly plastic) contact
//! With a hardness `H` ([`NormalProblem::hardness_pa`]) the pressure is bounded, `0 ≤ p ≤ H`: the
//! pressure-saturation model of elastic–perfectly plastic contact (the mean pressure of a fully
//! plastic contact is the indentation hardness, ≈ 3Y; Johnson, *Contact Mechanics*, 1985, ch. 6;
//! used on rough surfaces by Almqvist, Sahlin, Larsson & Glavatskih, Tribol. Int. 40 (2007)
//! 574–579; tamaas' `KatoSaturated` solves the same problem). The conditions become
//!
//! - free (elastic) points `0 < p < H`: `g = 0`;
//! - plastic points `p = H`: `g ≤ 0` — they may penetrate, and leave the plastic set when their gap
//!   opens;
//! - points out of contact `p = 0`: `g ≥ 0`;
//!
//! with the load `mean(p) = p̄ < H` summed over all points. It is the minimum of the same energy over
//! the box `0 ≤ p ≤ H` (strictly convex, so the solution is unique), solved by the same
//! preconditioned projected CG: the CG set is the free set `F = {0 < p < H}`, which centres the gap
//! (δ is the mean of `K⊛p + h0` over `F`) and carries the conjugate direction; plastic points keep
//! `p = H` (`t = 0`) unless their gap opened (`g > 0`), in which case they join the direction with
//! `t = diag(M⁻¹)·g` like the penetrating points; the projection clamps at `H` as at 0. The
//! residual adds `H·max(g, 0)` of the plastic points. After a step that clipped or saturated points
//! the load is restored by scaling the free points, `p ← s·p` on `F` with
//! `s = (L − H·n_plastic)/Σ_F p`; when that would push a free point above `H` the load is restored
//! exactly within the box instead (`p ← min(s p, H)`, the `s` found by sorting). With `H = ∞` the
//! arithmetic is that of the elastic solve, bit for bit (`tests/plastic_contact.rs`). The
//! Polonsky–Keer path is elastic only.
//!
//! Outputs ([`NormalSolution`]): elastic (`0 < p < H`) and plastic (`p = H`) contact points and
//! area ratios, and the **plastically displaced volume**
//!
//! `V_p = Σ_{i: p_i = H} max(−g_i, 0)·dx·dy`  (m³),
//!
//! the interpenetration of the rigid equivalent surface and the elastically deformed half-space
//! at the plastic points: the material the model removes there (it conserves no volume — no
//! pile-up). Under monotonic loading the plastic work is `H·V_p`. The **residual surface** after
//! unloading is `h_res = h − max(−g, 0)·1_{p=H}` ([`NormalSolution::residual_surface`]): the
//! elastic solution of `h_res` at the same load is the elastic–plastic solution (its pressure
//! satisfies the elastic conditions of `h_res`, and that solution is unique), so unloading and
//! reloading up to the load are elastic on `h_res` (no reverse plasticity in this model).
//!
//! Stiffness: [`NormalSolver::contact_stiffness`] on the contact set `p > 0` is then the
//! **unloading/reloading** stiffness about the plastically deformed state (the elastic tangent of
//! `h_res`), the one a contact element carries; [`NormalSolver::loading_stiffness`] on the free set
//! is the tangent of continued loading (plastic points held at `H`), smaller ([`stiffness`]).
//!
//! # Displacement control
//! [`NormalSolver::solve_approach`] imposes the rigid approach `δ` instead of the load: the
//! approach is a continuous increasing function of the mean pressure, `δ(p̄)`, so the solver
//! finds `p̄` with `δ(p̄) = δ` by a bracketed secant (Illinois) search on `ln p̄`, each step a
//! warm-started load-controlled solve. This works identically for periodic patches (whose mean
//! pressure is not set by the zero-mean periodic kernel) and zero-padded (finite) contacts.

use crate::contact::resolution::ContactResolution;
use crate::core::error::{require_positive, Error, Result};
use crate::core::fft::{Boundary, ConvolutionWorkspace, FftPlan, KernelSpectrum};
use crate::core::grid::Grid2;
use crate::halfspace::influence::boussinesq_spectrum;
use ndarray::Array2;
use std::time::Instant;

mod projected_cg;
pub mod stiffness;

pub use stiffness::ContactStiffness;

/// The displacement is recomputed by a full convolution at least this often (iterations).
pub const REFRESH_INTERVAL: usize = 25;

/// The preconditioned method uses a warm start at a load within this factor of the warm
/// start's, the nested coarse-to-fine start otherwise. Measured on the reference Gaussian
/// surface and the self-affine benchmark surface (1024², five loads at 0.01–39 % contact,
/// 1 thread; `cargo bench --bench normal -- --warm-start`): a warm start 2 % away takes
/// 0.70–0.92 of the nested start's time, 10 % away 0.96–1.19, a factor 2 away 1.16–1.35
/// (BENCHMARKS.md, normal contact, section D).
pub const WARM_START_LOAD_RATIO: f64 = 1.05;

/// Nested iteration stops coarsening below this many points a side.
pub const COARSEST_GRID: usize = 64;

/// Tolerance of the coarse solves of the nested iteration (they only provide a start).
const COARSE_TOLERANCE: f64 = 1e-6;

/// A normal contact problem: the equivalent rough surface against an elastic half-space.
#[derive(Debug, Clone, Copy)]
pub struct NormalProblem<'a> {
    /// Heights of the equivalent rough surface (m), peaks positive. `surface.periodic` selects
    /// the periodic (representative patch) or zero-padded (finite contact) convolution.
    pub surface: &'a Grid2,
    /// Composite modulus E* (Pa), see [`crate::core::material::composite_modulus`].
    pub e_star_pa: f64,
    /// Hardness H (Pa): the contact pressure is bounded by it (elastic–perfectly plastic
    /// contact, see the module documentation); `None` for purely elastic contact. Defaults per
    /// material: [`crate::core::material::MaterialGrade`].
    pub hardness_pa: Option<f64>,
}

/// Solver settings.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct NormalOptions {
    /// Tolerance on the relative gap error ε (see the module documentation).
    pub tolerance: f64,
    /// Iteration cap of one load-controlled solve; exceeding it is [`Error::NonConvergence`].
    pub max_iterations: usize,
    /// Relative tolerance on the approach in displacement control.
    pub approach_tolerance: f64,
    /// Iteration: preconditioned projected CG, Polonsky–Keer, or chosen automatically
    /// (see [`NormalMethod`]).
    #[serde(default)]
    pub method: NormalMethod,
    /// The preconditioned method starts from a given warm start only at a load within this
    /// factor of the warm start's load (≥ 1, `inf` for always; default
    /// [`WARM_START_LOAD_RATIO`]), from the nested coarse-to-fine start otherwise.
    #[serde(default = "default_warm_start_load_ratio")]
    pub warm_start_load_ratio: f64,
}

fn default_warm_start_load_ratio() -> f64 {
    WARM_START_LOAD_RATIO
}

/// The iteration of the load-controlled solve. Both methods solve the same problem with the
/// same convergence criterion and give the same contact set and mean gap (to the tolerance).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum NormalMethod {
    /// [`NormalMethod::Preconditioned`], the faster at every contact fraction measured
    /// (BENCHMARKS.md).
    #[default]
    Auto,
    /// Projected conjugate gradients of Polonsky & Keer (1999): the reference path.
    PolonskyKeer,
    /// Projected conjugate gradients preconditioned by the inverse of the half-space compliance,
    /// `E*|q|/2` in Fourier space, restricted to the contact set (Vollebregt, J. Comput. Phys.
    /// 257 (2014) 333–351): iteration counts nearly independent of the grid and of the contact
    /// fraction, at two transform pairs per iteration.
    Preconditioned,
}

impl NormalMethod {
    /// The name used on the command line and in CSV files.
    pub fn name(self) -> &'static str {
        match self {
            NormalMethod::Auto => "auto",
            NormalMethod::PolonskyKeer => "polonsky-keer",
            NormalMethod::Preconditioned => "preconditioned",
        }
    }
}

impl std::str::FromStr for NormalMethod {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "auto" => Ok(NormalMethod::Auto),
            "polonsky-keer" => Ok(NormalMethod::PolonskyKeer),
            "preconditioned" => Ok(NormalMethod::Preconditioned),
            _ => Err(Error::param(
                "method",
                format!("must be `auto`, `polonsky-keer` or `preconditioned`, got `{s}`"),
            )),
        }
    }
}

impl NormalOptions {
    /// Default tolerance on ε: well below the discretisation error of any practical grid.
    pub const DEFAULT_TOLERANCE: f64 = 1e-10;

    /// Check the settings: tolerances finite and > 0, at least one iteration.
    pub fn validate(&self) -> Result<()> {
        crate::core::sanity::tolerance("tolerance", self.tolerance)?;
        require_positive("approach_tolerance", self.approach_tolerance)?;
        if self.max_iterations == 0 {
            return Err(Error::param("max_iterations", "must be at least 1"));
        }
        if self.warm_start_load_ratio.is_nan() || self.warm_start_load_ratio < 1.0 {
            return Err(Error::param(
                "warm_start_load_ratio",
                format!("must be at least 1, got {}", self.warm_start_load_ratio),
            ));
        }
        Ok(())
    }
}

impl Default for NormalOptions {
    fn default() -> Self {
        Self {
            tolerance: Self::DEFAULT_TOLERANCE,
            max_iterations: 5000,
            approach_tolerance: 1e-7,
            method: NormalMethod::Auto,
            warm_start_load_ratio: WARM_START_LOAD_RATIO,
        }
    }
}

/// Solution of one normal contact problem. Every field is in SI units.
#[derive(Debug, Clone)]
pub struct NormalSolution {
    /// Contact pressure p (Pa), grid shape; zero outside the contact.
    pub pressure: Array2<f64>,
    /// Gap g = h0 − δ + u (m), ≥ 0 up to the tolerance; zero (to round-off) in contact.
    pub gap: Array2<f64>,
    /// Elastic surface displacement u = K ⊛ p (m), combined for both bodies. Periodic patches:
    /// zero-mean (the mean displacement is carried by the approach).
    pub displacement: Array2<f64>,
    /// Grid spacing along x (m), as the surface.
    pub dx: f64,
    /// Grid spacing along y (m).
    pub dy: f64,
    /// Nominal (imposed) mean pressure p̄ = mean(p) over the patch (Pa).
    pub mean_pressure_pa: f64,
    /// Real contact area over nominal area (-).
    pub contact_area_ratio: f64,
    /// Grid points in contact.
    pub contact_points: usize,
    /// Number of contact spots (4-connected clusters of contact points; clusters touching across
    /// a periodic boundary count once).
    pub contact_spots: usize,
    /// Grid points of the smallest contact spot (0 without contact).
    pub smallest_spot_points: usize,
    /// Median spot size in grid points.
    pub median_spot_points: usize,
    /// Grid points across the contact spots and the free regions: whether the grid resolves
    /// this contact (see [`crate::contact::resolution`]).
    pub resolution: ContactResolution,
    /// Mean gap (mean separation of the mean planes for a periodic patch) (m).
    pub mean_gap_m: f64,
    /// Rigid approach δ from first contact of the highest grid point (m).
    pub approach_m: f64,
    /// Elastic energy ½ Σ p·u·dA (J); periodic patches: the energy of the zero-mean part.
    pub elastic_energy_j: f64,
    /// Hardness H that bounded the pressure (Pa); `None` for elastic contact.
    pub hardness_pa: Option<f64>,
    /// Grid points in elastic contact, `0 < p < H` (every contact point without hardness).
    pub elastic_points: usize,
    /// Grid points in plastic contact, `p = H` (0 without hardness).
    pub plastic_points: usize,
    /// Elastic contact area over nominal area (-).
    pub elastic_area_ratio: f64,
    /// Plastic contact area over nominal area (-).
    pub plastic_area_ratio: f64,
    /// Plastically displaced volume `V_p = Σ_{p=H} max(−g, 0)·dx·dy` (m³): the interpenetration
    /// of the rigid equivalent surface and the elastically deformed half-space at the plastic
    /// points, i.e. the material the saturation model removes there (see the module
    /// documentation). 0 without hardness.
    pub plastic_volume_m3: f64,
    /// The iteration used ([`NormalMethod::Auto`] resolved).
    pub method: NormalMethod,
    /// Iterations (search directions) of the last (or, in displacement control, all) solves.
    pub iterations: usize,
    /// Convolutions with the compliance `K⊛` (transform pairs of the kernel's grid) of the
    /// last solve: one per iteration, plus one per recomputation of the displacement.
    pub convolutions: usize,
    /// Applications of the preconditioner (transform pairs of the periodic grid of the patch
    /// or window) of the last solve.
    pub preconditioner_applications: usize,
    /// Iterations on the coarser grids of the nested iteration that gave the initial pressure
    /// (each costs about 4⁻ˡ of an iteration on this grid at level l); 0 without.
    pub coarse_iterations: usize,
    /// Final relative gap error ε.
    pub residual: f64,
    /// Always true for a returned solution (non-convergence is an error).
    pub converged: bool,
    /// Wall time of the solve (s).
    pub wall_time_s: f64,
}

impl NormalSolution {
    /// Plastic penetration `max(−g, 0)` at the plastic points (`p ≥ H`), zero elsewhere (m);
    /// all zero without hardness. Its sum times `dx·dy` is [`NormalSolution::plastic_volume_m3`].
    pub fn plastic_penetration(&self) -> Array2<f64> {
        let h = self.hardness_pa.unwrap_or(f64::INFINITY);
        let mut pen = Array2::zeros(self.pressure.dim());
        ndarray::Zip::from(&mut pen)
            .and(&self.pressure)
            .and(&self.gap)
            .for_each(|d, &p, &g| {
                if p >= h {
                    *d = (-g).max(0.0);
                }
            });
        pen
    }

    /// Plastic work `W_p = H·V_p` (J): the work of the pressure H on the plastic penetration
    /// under monotonic loading. 0 without hardness.
    pub fn plastic_work_j(&self) -> f64 {
        self.hardness_pa.map_or(0.0, |h| {
            if self.plastic_points > 0 {
                h * self.plastic_volume_m3
            } else {
                0.0
            }
        })
    }

    /// The residual (plastically deformed) surface after unloading: the heights of `surface`
    /// (the equivalent surface this solution was solved on) minus the plastic penetration,
    /// `h_res = h − max(−g, 0)·1_{p=H}` (m). Its elastic solution at this solution's load is this
    /// solution's pressure (see the module documentation): unloading and reloading up to this
    /// load are elastic on `h_res`.
    pub fn residual_surface(&self, surface: &Grid2) -> Result<Grid2> {
        if surface.heights.dim() != self.pressure.dim() {
            let (a, b) = surface.heights.dim();
            let (c, d) = self.pressure.dim();
            return Err(Error::param(
                "surface",
                format!("grid {a} × {b} does not match the solution's grid {c} × {d}"),
            ));
        }
        let mut residual = surface.clone();
        residual.heights -= &self.plastic_penetration();
        Ok(residual)
    }
}

/// Polonsky–Keer solver for one surface: FFT plan, kernel spectrum and work arrays are built
/// once by [`NormalSolver::new`] and reused by every solve (load steps, warm starts).
pub struct NormalSolver {
    nx: usize,
    ny: usize,
    dx: f64,
    dy: f64,
    boundary: Boundary,
    e_star: f64,
    /// Hardness H (Pa), the upper bound of the pressure; infinite for elastic contact.
    hardness: f64,
    /// Initial separation h0 = max(h) − h (m).
    separation: Array2<f64>,
    /// Normalisation length of the residual: rms height about the mean (m).
    height_scale: f64,
    plan: FftPlan,
    kernel: KernelSpectrum,
    /// Displacement of a grid point under unit pressure on itself (m/Pa), relative to the
    /// patch mean for periodic kernels: the step length used to let penetrating points enter
    /// when the conjugate direction vanishes (a contact set of a single point).
    self_compliance: f64,
    ws: ConvolutionWorkspace,
    options: NormalOptions,
    /// Preconditioner of the preconditioned method, built on first use.
    precond: Option<Preconditioner>,
    /// Solver of the 2 × 2-coarsened surface for nested iteration, built on first use.
    coarse: Option<Box<NormalSolver>>,
    /// Diagonal of the preconditioner `M⁻¹` (Pa/m); 1 before it is built.
    precond_diagonal: f64,
    /// Convolutions `K⊛` and preconditioner applications of the last solve.
    counts: (usize, usize),
    // Work arrays, reused: pressure, centred gap, direction, its displacement, preconditioned
    // residual (allocated with the preconditioner).
    p: Array2<f64>,
    g: Array2<f64>,
    t: Array2<f64>,
    r: Array2<f64>,
    z: Array2<f64>,
}

/// The preconditioner `M⁻¹ = F⁻¹ (E*|q|/2) F`: the inverse of the periodic Boussinesq compliance.
/// Its plan is periodic on the grid: for periodic patches the grid of the solver's own plan;
/// for zero-padded windows the window itself (its |q| is the inverse of the free-space
/// compliance up to the wrap-around coupling, which the projected iteration tolerates; half the
/// cost of a padded transform pair).
///
/// It runs in single precision: it only shapes the search directions, while the residual, the
/// steps and the convergence test are computed in double precision on the operator `K⊛`. Its
/// rounding (relative 1e-7, as if `M` were perturbed by that much) cost no iteration on any
/// benchmark case (self-affine and Gaussian, 512²–2048²), and it halves the preconditioner's
/// memory traffic (BENCHMARKS.md, normal contact).
struct Preconditioner {
    plan: FftPlan<f32>,
    spectrum: KernelSpectrum<f32>,
    ws: ConvolutionWorkspace<f32>,
    /// Diagonal of the circulant `M⁻¹`, `mean_q(E*|q|/2)` (Pa/m).
    diagonal: f64,
}

impl Preconditioner {
    fn new(nx: usize, ny: usize, dx: f64, dy: f64, e_star: f64) -> Self {
        let plan = FftPlan::new(nx, ny, Boundary::Periodic);
        let (spectrum, diagonal) = projected_cg::precond_spectrum(&plan, dx, dy, e_star);
        let ws = plan.workspace();
        Self {
            plan,
            spectrum,
            ws,
            diagonal,
        }
    }
}

impl std::fmt::Debug for NormalSolver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("NormalSolver")
            .field("grid", &(self.nx, self.ny))
            .field("spacing_m", &(self.dx, self.dy))
            .field("boundary", &self.boundary)
            .field("e_star_pa", &self.e_star)
            .field("options", &self.options)
            .finish()
    }
}

impl NormalSolver {
    /// Check the problem, plan the FFTs and transform the Boussinesq kernel.
    pub fn new(problem: &NormalProblem<'_>, options: NormalOptions) -> Result<Self> {
        let s = problem.surface;
        let e_star = require_positive("e_star_pa", problem.e_star_pa)?;
        let hardness = match problem.hardness_pa {
            Some(h) => require_positive("hardness_pa", h)?,
            None => f64::INFINITY,
        };
        if hardness.is_finite() && options.method == NormalMethod::PolonskyKeer {
            return Err(Error::param(
                "method",
                "the hardness-limited solve uses the preconditioned projected CG; choose `auto` \
                 or `preconditioned`",
            ));
        }
        require_positive("dx", s.dx)?;
        require_positive("dy", s.dy)?;
        options.validate()?;
        let (nx, ny) = s.heights.dim();
        if nx < 2 || ny < 1 || nx * ny < 4 {
            return Err(Error::param(
                "surface",
                format!("grid {nx} × {ny} is too small for a contact solution"),
            ));
        }
        if let Some(((i, j), v)) = s.heights.indexed_iter().find(|(_, v)| !v.is_finite()) {
            return Err(Error::param(
                "surface",
                format!("non-finite height {v} at grid point ({i}, {j})"),
            ));
        }
        let h_max = s.heights.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let separation = s.heights.mapv(|h| h_max - h);
        let n = (nx * ny) as f64;
        let mean = s.heights.sum() / n;
        let rms = (s.heights.iter().map(|h| (h - mean).powi(2)).sum::<f64>() / n).sqrt();
        // A perfectly flat surface has no length scale of its own; its gap error is exactly zero
        // after the first iteration, so any positive scale works.
        let height_scale = if rms > 0.0 { rms } else { s.dx.max(s.dy) };
        let boundary = if s.periodic {
            Boundary::Periodic
        } else {
            Boundary::ZeroPadded
        };
        let plan = FftPlan::new(nx, ny, boundary);
        let kernel = boussinesq_spectrum(&plan, s.dx, s.dy, e_star);
        let ws = plan.workspace();
        let z = Array2::<f64>::zeros((nx, ny));
        let mut delta = z.clone();
        delta[[0, 0]] = 1.0;
        let self_compliance = plan.convolve(&kernel, &delta)[[0, 0]];
        Ok(Self {
            nx,
            ny,
            dx: s.dx,
            dy: s.dy,
            boundary,
            e_star,
            hardness,
            separation,
            height_scale,
            plan,
            kernel,
            self_compliance,
            ws,
            options,
            precond: None,
            coarse: None,
            precond_diagonal: 1.0,
            counts: (0, 0),
            p: z.clone(),
            g: z.clone(),
            t: z.clone(),
            r: z,
            z: Array2::zeros((0, 0)),
        })
    }

    /// Grid shape `(nx, ny)`.
    pub fn grid_shape(&self) -> (usize, usize) {
        (self.nx, self.ny)
    }

    /// Grid spacings `(dx, dy)` (m).
    pub fn spacing(&self) -> (f64, f64) {
        (self.dx, self.dy)
    }

    /// Boundary mode (from the surface's periodic flag).
    pub fn boundary(&self) -> Boundary {
        self.boundary
    }

    /// Composite modulus E* (Pa).
    pub fn e_star_pa(&self) -> f64 {
        self.e_star
    }

    /// Hardness H (Pa) bounding the pressure; `None` for elastic contact.
    pub fn hardness_pa(&self) -> Option<f64> {
        self.hardness.is_finite().then_some(self.hardness)
    }

    /// Solver settings.
    pub fn options(&self) -> &NormalOptions {
        &self.options
    }

    /// Change the settings (e.g. the tolerance) without re-planning.
    pub fn set_options(&mut self, options: NormalOptions) -> Result<()> {
        options.validate()?;
        if self.hardness.is_finite() && options.method == NormalMethod::PolonskyKeer {
            return Err(Error::param(
                "method",
                "the hardness-limited solve uses the preconditioned projected CG",
            ));
        }
        self.options = options;
        Ok(())
    }

    /// The FFT plan (for callers convolving other kernels on the same grid).
    pub fn plan(&self) -> &FftPlan {
        &self.plan
    }

    /// Initial separation h0 = max(h) − h (m).
    pub fn separation(&self) -> &Array2<f64> {
        &self.separation
    }

    /// Elastic displacement `u = K ⊛ p` (m) for any pressure field on this grid (Pa).
    pub fn displacement_of(&mut self, pressure: &Array2<f64>) -> Result<Array2<f64>> {
        self.check_shape("pressure", pressure.dim())?;
        let mut out = Array2::zeros((self.nx, self.ny));
        self.plan
            .convolve_into(&self.kernel, pressure, &mut out, &mut self.ws);
        Ok(out)
    }

    fn check_shape(&self, name: &str, dim: (usize, usize)) -> Result<()> {
        if dim != (self.nx, self.ny) {
            return Err(Error::param(
                name,
                format!(
                    "grid {} × {} does not match the surface grid {} × {}",
                    dim.0, dim.1, self.nx, self.ny
                ),
            ));
        }
        Ok(())
    }

    /// Load control: solve for the imposed mean pressure `mean_pressure_pa` (Pa, over the whole
    /// patch). `warm_start` (a previous solution on the same grid) gives the initial pressure
    /// shape, scaled to the new load (the preconditioned method uses it only within a factor
    /// [`NormalOptions::warm_start_load_ratio`] of its load); otherwise the iteration starts
    /// from uniform pressure, or (preconditioned method) from the solution on the grid
    /// coarsened 2 × 2 (nested iteration, recursively down to [`COARSEST_GRID`] points a side).
    pub fn solve_load(
        &mut self,
        mean_pressure_pa: f64,
        warm_start: Option<&NormalSolution>,
    ) -> Result<NormalSolution> {
        let start = Instant::now();
        let p_mean = require_positive("mean_pressure_pa", mean_pressure_pa)?;
        // The same small-strain limit as every command and configuration (crate::core::sanity).
        crate::core::sanity::nominal_strain(p_mean, self.e_star)
            .map_err(|m| Error::param("mean_pressure_pa", m))?;
        if p_mean >= self.hardness {
            return Err(Error::param(
                "mean_pressure_pa",
                format!(
                    "{p_mean:e} Pa is not below the hardness {:e} Pa: the whole patch at the \
                     hardness carries no more",
                    self.hardness
                ),
            ));
        }
        let n = (self.nx * self.ny) as f64;
        let mut coarse_iterations = 0;
        let warm = match warm_start {
            Some(w) => {
                self.check_shape("warm_start", w.pressure.dim())?;
                let s = w.pressure.sum();
                if !(s.is_finite() && s > 0.0) || w.pressure.iter().any(|v| v.is_nan() || *v < 0.0)
                {
                    return Err(Error::param(
                        "warm_start",
                        "pressure must be finite, non-negative and not all zero",
                    ));
                }
                Some((w, s))
            }
            None => None,
        };
        let method = match self.options.method {
            NormalMethod::Auto => NormalMethod::Preconditioned,
            m => m,
        };
        // The preconditioned method converges faster from a solution at a load within a few
        // per cent than from the nested coarse-to-fine start, and no faster from farther away
        // (BENCHMARKS.md): a warm start is used within that range, the nested start beyond it.
        let near = |w: &NormalSolution| {
            let ratio = p_mean / w.mean_pressure_pa;
            let limit = self.options.warm_start_load_ratio;
            (1.0 / limit..=limit).contains(&ratio)
        };
        match warm {
            Some((w, s)) if method != NormalMethod::Preconditioned || near(w) => {
                let scale = p_mean * n / s;
                self.p.zip_mut_with(&w.pressure, |p, w| *p = w * scale);
            }
            _ => match (method, self.coarse_start(p_mean)) {
                (NormalMethod::Preconditioned, Some((p, its))) => {
                    self.p.assign(&p);
                    coarse_iterations = its;
                }
                _ => self.p.fill(p_mean),
            },
        }
        if self.hardness.is_finite() {
            // A scaled warm start may exceed the hardness: start from its projection.
            let h = self.hardness;
            self.p.mapv_inplace(|p| p.min(h));
        }
        let (iterations, residual, approach) = self.iterate(p_mean, method)?;
        let mut sol = self.solution(p_mean, approach, method, iterations, residual, start);
        sol.coarse_iterations = coarse_iterations;
        Ok(sol)
    }

    /// Nested iteration (coarse-to-fine): the solution on the grid coarsened by 2 × 2 block
    /// averages (itself started the same way), prolonged by copying each coarse value to its
    /// 2 × 2 block, as the initial pressure. `None` when the grid cannot be halved (odd sizes,
    /// or below [`COARSEST_GRID`] points a side) or the coarse solve fails. Returns the pressure
    /// and the iterations of all coarser levels.
    fn coarse_start(&mut self, p_mean: f64) -> Option<(Array2<f64>, usize)> {
        let (nx, ny) = (self.nx, self.ny);
        if nx % 2 != 0 || ny % 2 != 0 || nx / 2 < COARSEST_GRID || ny / 2 < COARSEST_GRID {
            return None;
        }
        if self.coarse.is_none() {
            let h0 = &self.separation;
            let heights = Array2::from_shape_fn((nx / 2, ny / 2), |(i, j)| {
                -0.25
                    * (h0[[2 * i, 2 * j]]
                        + h0[[2 * i + 1, 2 * j]]
                        + h0[[2 * i, 2 * j + 1]]
                        + h0[[2 * i + 1, 2 * j + 1]])
            });
            let surface = Grid2::new(
                heights,
                2.0 * self.dx,
                2.0 * self.dy,
                self.boundary == Boundary::Periodic,
            )
            .ok()?;
            let options = NormalOptions {
                tolerance: self.options.tolerance.max(COARSE_TOLERANCE),
                method: NormalMethod::Preconditioned,
                ..self.options
            };
            let solver = NormalSolver::new(
                &NormalProblem {
                    surface: &surface,
                    e_star_pa: self.e_star,
                    hardness_pa: self.hardness_pa(),
                },
                options,
            )
            .ok()?;
            self.coarse = Some(Box::new(solver));
        }
        let coarse = self.coarse.as_mut()?;
        let sol = coarse.solve_load(p_mean, None).ok()?;
        let p = Array2::from_shape_fn((nx, ny), |(i, j)| sol.pressure[[i / 2, j / 2]]);
        Some((p, sol.iterations + sol.coarse_iterations))
    }

    /// Displacement control: solve for the imposed rigid approach `approach_m` (m, measured from
    /// first contact of the highest grid point; must be > 0). The mean pressure is found by a
    /// bracketed secant search on `δ(p̄)` (see the module documentation); `warm_start` provides
    /// the first guess of the pressure. `iterations` of the result counts all inner iterations.
    pub fn solve_approach(
        &mut self,
        approach_m: f64,
        warm_start: Option<&NormalSolution>,
    ) -> Result<NormalSolution> {
        let start = Instant::now();
        let target = require_positive("approach_m", approach_m)?;
        let tol = self.options.approach_tolerance;
        // First guess of p̄: from the warm start, else the stiffness of a full flat contact
        // scaled down (any positive value works; the bracket expands geometrically).
        let mut guess = match warm_start {
            Some(w) => w.mean_pressure_pa * (target / w.approach_m.max(f64::MIN_POSITIVE)),
            None => self.e_star * target / self.nx.max(self.ny) as f64 / self.dx.max(self.dy),
        };
        if !(guess.is_finite() && guess > 0.0) {
            guess = self.e_star * 1e-6;
        }
        // With hardness the load stays below H (p̄ → H as δ → ∞, every point plastic): a trial
        // load at or above H is replaced by the point halfway from the current one to H.
        let hardness = self.hardness;
        if guess >= hardness {
            guess = 0.5 * hardness;
        }
        let mut total_iterations = 0;
        let solve =
            |this: &mut Self, p: f64, warm: Option<&NormalSolution>| this.solve_load(p, warm);
        let mut cur = solve(self, guess, warm_start)?;
        total_iterations += cur.iterations;
        let f = |s: &NormalSolution| s.approach_m / target - 1.0;
        // Bracket the root in ln p̄.
        let (mut lo, mut hi);
        let mut fc = f(&cur);
        if fc.abs() <= tol {
            cur.iterations = total_iterations;
            cur.wall_time_s = start.elapsed().as_secs_f64();
            return Ok(cur);
        }
        let factor: f64 = if fc < 0.0 { 4.0 } else { 0.25 };
        let mut expansions = 0;
        loop {
            let mut trial = cur.mean_pressure_pa * factor;
            if trial >= hardness {
                trial = 0.5 * (cur.mean_pressure_pa + hardness);
                // The approach of a fully plastic patch is finite (the lowest point touches at
                // p̄ = H); a target beyond it is not reached by any load below H.
                if trial >= hardness * (1.0 - 1e-9) {
                    return Err(Error::param(
                        "approach_m",
                        format!(
                            "{target:e} m is beyond the approach of the fully plastic patch \
                             ({:e} m at p̄ = {:e} Pa, hardness {hardness:e} Pa): every point \
                             is at the hardness before it",
                            cur.approach_m, cur.mean_pressure_pa
                        ),
                    ));
                }
            }
            let next = solve(self, trial, Some(&cur))?;
            total_iterations += next.iterations;
            let fnext = f(&next);
            if fnext.abs() <= tol {
                let mut s = next;
                s.iterations = total_iterations;
                s.wall_time_s = start.elapsed().as_secs_f64();
                return Ok(s);
            }
            if (fnext < 0.0) != (fc < 0.0) {
                if fc < 0.0 {
                    lo = (cur, fc);
                    hi = (next, fnext);
                } else {
                    lo = (next, fnext);
                    hi = (cur, fc);
                }
                break;
            }
            cur = next;
            fc = fnext;
            expansions += 1;
            if expansions > 60 {
                return Err(Error::NonConvergence {
                    solver: "normal contact, displacement control (bracketing)".into(),
                    iterations: total_iterations,
                    residual: fc.abs(),
                    tolerance: tol,
                });
            }
        }
        // Illinois (modified regula falsi) on x = ln p̄.
        let mut side = 0i32;
        for _ in 0..100 {
            let (xl, fl) = (lo.0.mean_pressure_pa.ln(), lo.1);
            let (xh, fh) = (hi.0.mean_pressure_pa.ln(), hi.1);
            let (mut wl, mut wh) = (fl, fh);
            if side == -1 {
                wh *= 0.5;
            } else if side == 1 {
                wl *= 0.5;
            }
            let x = (xl * wh - xh * wl) / (wh - wl);
            let warm = if fl.abs() < fh.abs() { &lo.0 } else { &hi.0 };
            let s = solve(self, x.exp(), Some(warm))?;
            total_iterations += s.iterations;
            let fs = f(&s);
            if fs.abs() <= tol || (xh - xl).abs() < 1e-15 {
                let mut s = s;
                s.iterations = total_iterations;
                s.wall_time_s = start.elapsed().as_secs_f64();
                return Ok(s);
            }
            if fs < 0.0 {
                lo = (s, fs);
                side = -1;
            } else {
                hi = (s, fs);
                side = 1;
            }
        }
        Err(Error::NonConvergence {
            solver: "normal contact, displacement control (secant)".into(),
            iterations: total_iterations,
            residual: lo.1.abs().min(hi.1.abs()),
            tolerance: tol,
        })
    }

    /// Assemble the result from the converged work arrays.
    fn solution(
        &self,
        p_mean: f64,
        approach: f64,
        method: NormalMethod,
        iterations: usize,
        residual: f64,
        start: Instant,
    ) -> NormalSolution {
        let n = (self.nx * self.ny) as f64;
        let pressure = self.p.clone();
        let gap = self.g.clone();
        // u = g − h0 + δ (the gap was computed from a fresh convolution at convergence).
        let mut displacement = gap.clone();
        displacement.zip_mut_with(&self.separation, |u, h0| *u += approach - h0);
        let contact = pressure.mapv(|v| v > 0.0);
        let contact_points = contact.iter().filter(|c| **c).count();
        let h = self.hardness;
        let (plastic_points, plastic_depth) = pressure
            .iter()
            .zip(gap.iter())
            .filter(|(p, _)| **p >= h)
            .fold((0usize, 0.0), |(k, v), (_, g)| (k + 1, v + (-g).max(0.0)));
        let spots = spot_sizes(&contact, self.boundary == Boundary::Periodic);
        let mut sorted = spots.clone();
        sorted.sort_unstable();
        let energy = 0.5
            * pressure
                .iter()
                .zip(displacement.iter())
                .map(|(p, u)| p * u)
                .sum::<f64>()
            * self.dx
            * self.dy;
        NormalSolution {
            mean_gap_m: gap.sum() / n,
            pressure,
            gap,
            displacement,
            dx: self.dx,
            dy: self.dy,
            mean_pressure_pa: p_mean,
            contact_area_ratio: contact_points as f64 / n,
            contact_points,
            contact_spots: spots.len(),
            smallest_spot_points: sorted.first().copied().unwrap_or(0),
            median_spot_points: sorted.get(sorted.len() / 2).copied().unwrap_or(0),
            resolution: ContactResolution::of(&contact, self.boundary == Boundary::Periodic),
            approach_m: approach,
            elastic_energy_j: energy,
            hardness_pa: self.hardness_pa(),
            elastic_points: contact_points - plastic_points,
            plastic_points,
            elastic_area_ratio: (contact_points - plastic_points) as f64 / n,
            plastic_area_ratio: plastic_points as f64 / n,
            plastic_volume_m3: plastic_depth * self.dx * self.dy,
            method,
            iterations,
            convolutions: self.counts.0,
            preconditioner_applications: self.counts.1,
            coarse_iterations: 0,
            residual,
            converged: true,
            wall_time_s: start.elapsed().as_secs_f64(),
        }
    }
}

/// Sizes (grid points) of the 4-connected clusters of `true` cells. With `periodic`, clusters
/// connect across the opposite edges of the grid.
pub fn spot_sizes(mask: &Array2<bool>, periodic: bool) -> Vec<usize> {
    let (nx, ny) = mask.dim();
    let mut seen = Array2::from_elem((nx, ny), false);
    let mut sizes = Vec::new();
    let mut stack = Vec::new();
    for i0 in 0..nx {
        for j0 in 0..ny {
            if !mask[[i0, j0]] || seen[[i0, j0]] {
                continue;
            }
            seen[[i0, j0]] = true;
            stack.push((i0, j0));
            let mut size = 0;
            while let Some((i, j)) = stack.pop() {
                size += 1;
                let mut visit = |a: usize, b: usize| {
                    if mask[[a, b]] && !seen[[a, b]] {
                        seen[[a, b]] = true;
                        stack.push((a, b));
                    }
                };
                if i > 0 {
                    visit(i - 1, j);
                } else if periodic {
                    visit(nx - 1, j);
                }
                if i + 1 < nx {
                    visit(i + 1, j);
                } else if periodic {
                    visit(0, j);
                }
                if j > 0 {
                    visit(i, j - 1);
                } else if periodic {
                    visit(i, ny - 1);
                }
                if j + 1 < ny {
                    visit(i, j + 1);
                } else if periodic {
                    visit(i, 0);
                }
            }
            sizes.push(size);
        }
    }
    sizes
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::analytic::Hertz;

    /// Sphere of radius `r` as a height map (peak at the grid centre), zero-padded window.
    fn sphere(n: usize, dx: f64, radius: f64) -> Grid2 {
        let c = (n / 2) as f64;
        let h = Array2::from_shape_fn((n, n), |(i, j)| {
            let x = (i as f64 - c) * dx;
            let y = (j as f64 - c) * dx;
            -(x * x + y * y) / (2.0 * radius)
        });
        Grid2::new(h, dx, dx, false).unwrap()
    }

    #[test]
    fn spots_count_periodic_wrap() {
        let mut m = Array2::from_elem((6, 5), false);
        m[[0, 2]] = true;
        m[[5, 2]] = true; // joins (0,2) across the x boundary when periodic
        m[[2, 0]] = true;
        m[[2, 1]] = true;
        m[[3, 3]] = true;
        let mut open = spot_sizes(&m, false);
        open.sort();
        assert_eq!(open, vec![1, 1, 1, 2]);
        let mut per = spot_sizes(&m, true);
        per.sort();
        assert_eq!(per, vec![1, 2, 2]);
    }

    #[test]
    fn hertz_small_grid_and_warm_start() {
        // Coarse Hertz check (the 1 % validation lives in tests/normal_contact.rs).
        let (radius, e_star) = (0.01, 1e11);
        let hz = Hertz::new(radius, 1.0, e_star);
        let n = 49;
        let dx = 2.4 * hz.radius / n as f64;
        let s = sphere(n, dx, radius);
        let mut solver = NormalSolver::new(
            &NormalProblem {
                surface: &s,
                e_star_pa: e_star,
                hardness_pa: None,
            },
            NormalOptions::default(),
        )
        .unwrap();
        let p_mean = 1.0 / s.area();
        let cold = solver.solve_load(p_mean, None).unwrap();
        let force = cold.pressure.sum() * dx * dx;
        assert!((force - 1.0).abs() < 1e-9);
        assert!((cold.approach_m / hz.approach - 1.0).abs() < 0.03);
        assert_eq!(cold.contact_spots, 1);
        let warm = solver.solve_load(p_mean, Some(&cold)).unwrap();
        assert!(warm.iterations < cold.iterations / 2 + 2);
        // Displacement control recovers the load.
        let dc = solver.solve_approach(cold.approach_m, Some(&cold)).unwrap();
        assert!((dc.mean_pressure_pa / p_mean - 1.0).abs() < 1e-5);
        let dc2 = solver.solve_approach(cold.approach_m * 1.3, None).unwrap();
        assert!((dc2.approach_m / (cold.approach_m * 1.3) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn warm_start_only_near_its_load() {
        // 128²: the nested start has one coarser level (64²), so it is visible in
        // `coarse_iterations`.
        let (radius, e_star) = (0.01, 1e11);
        let hz = Hertz::new(radius, 1.0, e_star);
        let n = 128;
        let s = sphere(n, 2.4 * hz.radius / n as f64, radius);
        let make = |ratio: f64| {
            NormalSolver::new(
                &NormalProblem {
                    surface: &s,
                    e_star_pa: e_star,
                    hardness_pa: None,
                },
                NormalOptions {
                    warm_start_load_ratio: ratio,
                    ..NormalOptions::default()
                },
            )
            .unwrap()
        };
        let mut solver = make(WARM_START_LOAD_RATIO);
        let p_mean = 1.0 / s.area();
        let base = solver.solve_load(p_mean, None).unwrap();
        assert!(base.coarse_iterations > 0);
        let near = solver.solve_load(1.02 * p_mean, Some(&base)).unwrap();
        assert_eq!(near.coarse_iterations, 0, "2 % away: warm start");
        let far = solver.solve_load(1.5 * p_mean, Some(&base)).unwrap();
        assert!(far.coarse_iterations > 0, "50 % away: nested start");
        let forced = make(f64::INFINITY)
            .solve_load(1.5 * p_mean, Some(&base))
            .unwrap();
        assert_eq!(forced.coarse_iterations, 0, "infinite ratio: always warm");
        // Same solution either way (same criterion).
        assert!((forced.mean_gap_m / far.mean_gap_m - 1.0).abs() < 1e-8);
        for bad in [0.5, f64::NAN] {
            let options = NormalOptions {
                warm_start_load_ratio: bad,
                ..NormalOptions::default()
            };
            assert!(options.validate().is_err(), "ratio {bad} accepted");
        }
    }

    #[test]
    fn rejects_bad_input() {
        let s = sphere(16, 1e-6, 1e-3);
        let mk = |e: f64| {
            NormalSolver::new(
                &NormalProblem {
                    surface: &s,
                    e_star_pa: e,
                    hardness_pa: None,
                },
                NormalOptions::default(),
            )
        };
        assert!(mk(0.0).is_err());
        assert!(mk(f64::NAN).is_err());
        let mut solver = mk(1e11).unwrap();
        for p in [0.0, -1.0, f64::NAN, f64::INFINITY, 0.11e11] {
            let e = solver.solve_load(p, None).unwrap_err().to_string();
            assert!(e.contains("mean_pressure_pa"), "{e}");
        }
        // The small-strain limit is the one every command applies (crate::core::sanity).
        let e = solver.solve_load(0.11e11, None).unwrap_err().to_string();
        assert!(e.contains("0.1 × E*"), "{e}");
        let mut bad = s.clone();
        bad.heights[[3, 4]] = f64::NAN;
        let e = NormalSolver::new(
            &NormalProblem {
                surface: &bad,
                e_star_pa: 1e11,
                hardness_pa: None,
            },
            NormalOptions::default(),
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("(3, 4)"), "{e}");
        // Warm start from another grid.
        let other = sphere(8, 1e-6, 1e-3);
        let mut o = NormalSolver::new(
            &NormalProblem {
                surface: &other,
                e_star_pa: 1e11,
                hardness_pa: None,
            },
            NormalOptions::default(),
        )
        .unwrap();
        let sol = o.solve_load(1e6, None).unwrap();
        let e = solver.solve_load(1e6, Some(&sol)).unwrap_err().to_string();
        assert!(e.contains("warm_start") && e.contains("8 × 8"), "{e}");
    }

    /// A single asperity carrying the load is a valid state, and warm-starting a higher load
    /// from it must let neighbours enter (the conjugate direction vanishes on one point).
    #[test]
    fn single_point_contact_set_grows_under_more_load() {
        let n = 32;
        let dx = 1e-6;
        let mut h = Array2::from_shape_fn((n, n), |(i, j)| {
            1e-8 * ((i as f64 * 0.7).sin() + (j as f64 * 1.3).cos())
        });
        h[[10, 12]] = 1e-6;
        let s = Grid2::new(h, dx, dx, true).unwrap();
        let mut solver = NormalSolver::new(
            &NormalProblem {
                surface: &s,
                e_star_pa: 1e11,
                hardness_pa: None,
            },
            NormalOptions::default(),
        )
        .unwrap();
        let light = solver.solve_load(1e3, None).unwrap();
        assert_eq!(
            light.contact_points, 1,
            "the spike alone carries a light load"
        );
        let heavy = solver.solve_load(2e9, Some(&light)).unwrap();
        assert!(heavy.converged && heavy.contact_points > 1);
        // Same answer as from a cold start.
        let cold = solver.solve_load(2e9, None).unwrap();
        assert!((heavy.mean_gap_m / cold.mean_gap_m - 1.0).abs() < 1e-6);
    }

    #[test]
    fn iteration_cap_is_an_error() {
        let s = sphere(32, 1e-6, 1e-3);
        let mut solver = NormalSolver::new(
            &NormalProblem {
                surface: &s,
                e_star_pa: 1e11,
                hardness_pa: None,
            },
            NormalOptions {
                max_iterations: 3,
                ..NormalOptions::default()
            },
        )
        .unwrap();
        match solver.solve_load(1e6, None) {
            Err(Error::NonConvergence { iterations, .. }) => assert_eq!(iterations, 3),
            other => panic!("expected NonConvergence, got {other:?}"),
        }
    }
}
