//! Stability of the harmonic-balance solutions: Hill's method, and the bifurcations named along
//! a branch.
//!
//! # Hill's eigenvalue problem
//!
//! A periodic solution `x(t)` of `M·ẍ + C·ẋ + K·x + f_nl(x) = F(t)` is perturbed by
//! `δx(t) = e^{st}·p(t)`, `p` periodic with the solution's period `T = 2π/ω` and expanded in the
//! same real harmonic basis as the solution (coordinate-major, `p = (P ⊗ basis)`; the basis of
//! [`crate::dynamics::aft::Harmonics`], orders `0..H` or odd only). Linearising the equation of
//! motion about `x` and balancing harmonic by harmonic gives the quadratic eigenvalue problem of
//! Hill's method (Lazarus & Thomas, "A harmonic-based method for computing the stability of
//! periodic solutions of dynamical systems", *C. R. Mécanique* 338 (2010) 510–517; Krack & Gross,
//! *Harmonic Balance for Nonlinear Vibration Problems*, Springer 2019, on stability analysis):
//!
//! ```text
//! (Δ2·s² + Δ1·s + Δ0)·P = 0,
//! Δ2 = M ⊗ I,   Δ1 = C ⊗ I + 2·M ⊗ ∇,   Δ0 = ∂R/∂Q = Z(ω) + Σ_e (P_e ⊗ I)ᵀ·J_e·(P_e ⊗ I)
//! ∇ on order k:  (a, b) ↦ (kω·b, −kω·a)   (d/dt of a·cos kωt + b·sin kωt)
//! ```
//!
//! `Δ0` is the harmonic-balance Jacobian at the solution ([`HbmSystem::evaluate`] with the
//! Jacobian), whose element part is the AFT Jacobian of the element forces. A rate-dependent
//! element (LuGre, Hunt–Crossley) also reacts to the perturbation's velocity `s·p`; that term
//! (its tangent damping in `Δ1`) is not included, so for them the exponents are those of the
//! element's response to `p` at the solution's own phase velocity only (an approximation). `M` is positive
//! definite, so the problem is linearised to the standard eigenproblem of the companion matrix
//! in the scaled eigenvalue `σ = s/ω`, with the state `(P, σ·P)`:
//!
//! ```text
//! A = [ 0                    I                 ]
//!     [ −(M⁻¹ ⊗ I)·Δ0/ω²    −(M⁻¹C ⊗ I)/ω − 2·(I ⊗ ∇)/ω ]      (2N × 2N, N = n·len)
//! ```
//!
//! (scaled by ω so that its entries are of the order of the harmonic orders squared), solved by
//! nalgebra's real Schur decomposition `A = Q·T·Qᵀ`; the eigen-solve's backward error
//! `‖A·Q − Q·T‖_F / ‖A‖_F` is reported ([`Stability::schur_residual`]).
//!
//! # Sorting: which eigenvalues are Floquet exponents
//!
//! Of the `2N` eigenvalues, every Floquet exponent `λ` of the `2n`-dimensional system appears as
//! the family `λ + ikω` over the retained orders `k` (for an odd-only basis, odd `k`); the
//! members with the smallest `|Im|` are the ones the truncated basis resolves, the others are
//! the truncation's copies. The `2n` eigenvalues of smallest `|Im s|` are kept (the imaginary-
//! part criterion; Lazarus & Thomas 2010; on its limits and the alternatives, Bayer & Leine,
//! "Sorting-free Hill-based stability analysis of periodic solutions through Koopman analysis",
//! *Nonlinear Dyn.* 111 (2023) 8439–8466), skipping a candidate that is a copy of one already
//! kept (`s − s' = ikω`, `k ≠ 0`, within [`DUPLICATE_TOLERANCE`]`·ω`): at the edge of the
//! fundamental strip (`|Im s| = ω/2`, or `ω` with odd harmonics only) a family's conjugate
//! members tie, and keeping both would drop another family. The Floquet multipliers are
//! `μ = e^{sT}`.
//!
//! With odd harmonics only the perturbations are anti-periodic (`p(t + T/2) = −p(t)`); for a
//! system symmetric under `x → −x` (a cubic spring, an unbiased friction contact) with a
//! symmetric solution these carry every Floquet multiplier of the full period (the half-period
//! map's multipliers `ν` give `μ = ν²`), shifted by `iω`.
//!
//! # Verdict and bifurcations
//!
//! A point is unstable when a kept exponent has `Re s > `[`UNSTABLE_TOLERANCE`]`·ω` (the
//! tolerance keeps the exponent of a neutral direction, zero to rounding, from deciding).
//! Between two consecutive points of a branch ([`bifurcations`]):
//!
//! * **fold**: a real multiplier (`μ > 0`) crosses the unit circle, or the continuation turns
//!   (`dω/ds` changes sign); the two coincide at a fold of a forced response, and a crossing
//!   without a turning point is named a **branch point**;
//! * **period doubling**: a real multiplier `μ < 0` crosses;
//! * **Neimark–Sacker**: a complex pair crosses.
//!
//! Its frequency is interpolated linearly where the largest real part changes sign (the turning
//! point's frequency for a fold seen by the continuation alone).
//!
//! # Formulations and elements
//!
//! Stability is always evaluated on the full model at the solution: with the receptance
//! formulation the coordinates' harmonics are recovered from the solved contact displacements
//! ([`HbmSystem::coordinates`]) and `Δ0` is the Jacobian of the coordinates formulation there.
//! (The condensed residual's Jacobian is not a Hill matrix: the receptance depends on `s`.) The
//! cost is therefore set by `n·len`, not by the unknowns of the solve: the eigen-solve is
//! `O((2·n·len)³)`.
//!
//! The element part of `Δ0` is exact for memoryless elements (a cubic spring: the perturbation's
//! force is `f'(x(t))·δx(t)` for any `s`). For hysteretic elements (Jenkins, Valanis) the AFT
//! Jacobian is the derivative of the periodic force harmonics with respect to periodic
//! displacement harmonics, including the periodic state's sensitivity; using it for the
//! perturbation `e^{st}·p(t)` treats the element as its periodic linearisation, as Hill's
//! method for friction-damped systems does in the harmonic-balance literature (Krack & Gross
//! 2019). A slip phase contributes a zero tangent, a stick phase the stick stiffness.

use crate::core::error::{Error, Result};
use crate::dynamics::aft::{Harmonics, WarmStart};
use crate::dynamics::continuation::{point_arclengths, point_between, Branch};
use crate::dynamics::hbm::{Formulation, FormulationChoice, HbmPoint, HbmSystem};
use nalgebra::{Complex, DMatrix};
use rayon::prelude::*;
use std::time::Instant;

/// A point is unstable when a Floquet exponent has `Re s > UNSTABLE_TOLERANCE·ω`.
pub const UNSTABLE_TOLERANCE: f64 = 1e-6;

/// Two eigenvalues are copies of one Floquet exponent when they differ by `ikω` (`k ≠ 0`)
/// within this fraction of `ω`.
pub const DUPLICATE_TOLERANCE: f64 = 1e-3;

/// A Floquet multiplier is taken as real when `|Im μ| ≤ REAL_MULTIPLIER_TOLERANCE·|μ|`.
pub const REAL_MULTIPLIER_TOLERANCE: f64 = 1e-3;

/// Whether `asperity response` assesses the stability of its points.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum StabilityChoice {
    /// When Hill's companion matrix has at most [`AUTO_MAX_COMPANION`] rows.
    Auto,
    /// Always.
    On,
    /// Never.
    Off,
}

/// Largest companion matrix (`2·n·len` rows) assessed by [`StabilityChoice::Auto`]. The
/// eigen-solve's cost grows as the cube of the size: about 10 ms per point at the blade–damper
/// example's 132 rows (where the assessment adds half the sweep's CPU time, most of it the
/// Jacobian at the point), some 50 ms at 256, 1.6 s at 900 (some twenty times the sweep's time
/// per point; BENCHMARKS.md).
pub const AUTO_MAX_COMPANION: usize = 256;

impl StabilityChoice {
    /// Whether the points of `system` are assessed.
    pub fn assesses(self, system: &HbmSystem<'_>) -> bool {
        if system.cyclic().is_some() {
            // Hill's method on a cyclic sector would assess perturbations of the solution's
            // harmonic index only: not implemented (HillAnalysis refuses it).
            return false;
        }
        match self {
            Self::On => true,
            Self::Off => false,
            Self::Auto => companion_size(system) <= AUTO_MAX_COMPANION,
        }
    }
}

/// Rows of Hill's companion matrix for `system`: `2·n·len` (the full model's coordinates, whatever
/// the formulation of the solve).
pub fn companion_size(system: &HbmSystem<'_>) -> usize {
    2 * system.structure.n() * system.harmonics.len()
}

/// Stability of one periodic solution.
#[derive(Debug, Clone)]
pub struct Stability {
    /// The `2n` Floquet exponents kept (1/s), by decreasing real part.
    pub exponents: Vec<Complex<f64>>,
    /// Largest real part of the kept exponents (1/s).
    pub max_real_part: f64,
    /// No kept exponent has a real part above [`UNSTABLE_TOLERANCE`]`·ω`.
    pub stable: bool,
    /// Backward error of the eigen-solve, `‖A·Q − Q·T‖_F / ‖A‖_F` of the Schur decomposition of
    /// the companion matrix.
    pub schur_residual: f64,
    /// Angular frequency of the solution (rad/s).
    pub omega: f64,
    /// Wall-clock time of the assessment (s): the Jacobian on the full model and the
    /// eigen-solve.
    pub wall_time_s: f64,
}

impl Stability {
    /// Floquet multipliers `μ = e^{sT}` of the kept exponents, `T = 2π/ω`.
    pub fn multipliers(&self) -> Vec<Complex<f64>> {
        let t = 2.0 * std::f64::consts::PI / self.omega;
        self.exponents.iter().map(|s| (s * t).exp()).collect()
    }

    /// Exponents above the stability limit, counted by the kind of their multiplier:
    /// `(real positive, real negative, complex)`.
    pub fn unstable_counts(&self) -> (usize, usize, usize) {
        let t = 2.0 * std::f64::consts::PI / self.omega;
        let mut c = (0, 0, 0);
        for s in self
            .exponents
            .iter()
            .filter(|s| s.re > UNSTABLE_TOLERANCE * self.omega)
        {
            match multiplier_kind((s * t).exp()) {
                MultiplierKind::RealPositive => c.0 += 1,
                MultiplierKind::RealNegative => c.1 += 1,
                MultiplierKind::Complex => c.2 += 1,
            }
        }
        c
    }
}

/// Where a Floquet multiplier lies.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum MultiplierKind {
    RealPositive,
    RealNegative,
    Complex,
}

fn multiplier_kind(mu: Complex<f64>) -> MultiplierKind {
    if mu.im.abs() > REAL_MULTIPLIER_TOLERANCE * mu.norm() {
        MultiplierKind::Complex
    } else if mu.re > 0.0 {
        MultiplierKind::RealPositive
    } else {
        MultiplierKind::RealNegative
    }
}

/// The time derivative on the real harmonic basis (`len × len`): order `k` maps the
/// coefficients `(a, b)` of `a·cos kωt + b·sin kωt` to `(kω·b, −kω·a)`; the mean to zero.
pub fn derivative_operator(harmonics: &Harmonics, omega: f64) -> DMatrix<f64> {
    let len = harmonics.len();
    let mut d = DMatrix::zeros(len, len);
    let mut c = 0;
    for &k in harmonics.orders() {
        if k == 0 {
            c += 1;
            continue;
        }
        let kw = k as f64 * omega;
        d[(c, c + 1)] = kw;
        d[(c + 1, c)] = -kw;
        c += 2;
    }
    d
}

/// The companion matrix `A` of Hill's quadratic problem in the scaled eigenvalue `σ = s/ω`
/// (module documentation): `Δ0` the harmonic-balance Jacobian of the coordinates
/// (`n·len × n·len`, coordinate-major), `M` and `C` the structure's mass and damping, `∇` the
/// [`derivative_operator`]. Errors when `M` is not positive definite.
pub fn companion_matrix(
    delta0: &DMatrix<f64>,
    mass: &DMatrix<f64>,
    damping: &DMatrix<f64>,
    nabla: &DMatrix<f64>,
    omega: f64,
) -> Result<DMatrix<f64>> {
    let n = mass.nrows();
    let len = nabla.nrows();
    let nn = n * len;
    if delta0.nrows() != nn || delta0.ncols() != nn {
        return Err(Error::param(
            "delta0",
            format!(
                "{} × {} Jacobian for {n} coordinates × {len} coefficients",
                delta0.nrows(),
                delta0.ncols()
            ),
        ));
    }
    let m_inv = mass
        .clone()
        .cholesky()
        .ok_or_else(|| Error::param("mass", "not positive definite"))?
        .inverse();
    let minv_c = &m_inv * damping;
    let mut a = DMatrix::zeros(2 * nn, 2 * nn);
    for i in 0..nn {
        a[(i, nn + i)] = 1.0;
    }
    // Lower-left: −(M⁻¹ ⊗ I)·Δ0/ω², block row r = Σ_q M⁻¹[r,q]·(block row q of Δ0).
    let w2 = omega * omega;
    for r in 0..n {
        for q in 0..n {
            let f = -m_inv[(r, q)] / w2;
            if f == 0.0 {
                continue;
            }
            for h in 0..len {
                for col in 0..nn {
                    a[(nn + r * len + h, col)] += f * delta0[(q * len + h, col)];
                }
            }
        }
    }
    // Lower-right: −(M⁻¹C ⊗ I)/ω − 2·(I ⊗ ∇)/ω.
    for r in 0..n {
        for q in 0..n {
            let f = -minv_c[(r, q)] / omega;
            if f != 0.0 {
                for h in 0..len {
                    a[(nn + r * len + h, nn + q * len + h)] += f;
                }
            }
        }
        for h in 0..len {
            for g in 0..len {
                a[(nn + r * len + h, nn + r * len + g)] -= 2.0 * nabla[(h, g)] / omega;
            }
        }
    }
    Ok(a)
}

/// Eigenvalues of `a` by the real Schur decomposition, with its backward error
/// `‖A·Q − Q·T‖_F / ‖A‖_F`. Errors when the QR iteration does not converge.
pub fn eigenvalues(a: &DMatrix<f64>) -> Result<(Vec<Complex<f64>>, f64)> {
    let dim = a.nrows();
    let schur = nalgebra::linalg::Schur::try_new(a.clone(), f64::EPSILON, 1000 * dim.max(1))
        .ok_or_else(|| {
            Error::Data(format!(
                "Hill's eigenvalue problem: the Schur decomposition of the {dim} × {dim} companion matrix did not converge"
            ))
        })?;
    let values: Vec<Complex<f64>> = schur.complex_eigenvalues().iter().copied().collect();
    let (q, t) = schur.unpack();
    let residual = (a * &q - &q * t).norm() / a.norm().max(f64::MIN_POSITIVE);
    Ok((values, residual))
}

/// The Floquet exponents among Hill's eigenvalues `s` (1/s) of a solution at `omega`: the
/// `count` of smallest `|Im s|`, copies (`s − s' = ikω`, `k ≠ 0`) of one already kept skipped
/// (module documentation); returned by decreasing real part.
pub fn floquet_exponents(
    eigenvalues: &[Complex<f64>],
    omega: f64,
    count: usize,
) -> Vec<Complex<f64>> {
    let mut order: Vec<&Complex<f64>> = eigenvalues.iter().collect();
    order.sort_by(|a, b| {
        a.im.abs()
            .total_cmp(&b.im.abs())
            .then(b.re.total_cmp(&a.re))
    });
    let mut kept: Vec<Complex<f64>> = Vec::with_capacity(count);
    for &s in order {
        if kept.len() == count {
            break;
        }
        let copy = kept.iter().any(|k| {
            let d = s - k;
            let shift = (d.im / omega).round();
            shift != 0.0 && d.re.hypot(d.im - shift * omega) <= DUPLICATE_TOLERANCE * omega
        });
        if !copy {
            kept.push(s);
        }
    }
    kept.sort_by(|a, b| b.re.total_cmp(&a.re).then(b.im.total_cmp(&a.im)));
    kept
}

/// Stability of the solution with Floquet exponents `exponents` (1/s) at `omega`.
pub fn verdict(exponents: &[Complex<f64>], omega: f64) -> (f64, bool) {
    // A NaN exponent (a failed assessment) makes the largest real part NaN: not called stable.
    let max_re = exponents
        .iter()
        .map(|s| s.re)
        .fold(f64::NEG_INFINITY, |m, r| {
            if m.is_nan() || r.is_nan() {
                f64::NAN
            } else {
                m.max(r)
            }
        });
    (max_re, max_re <= UNSTABLE_TOLERANCE * omega)
}

/// Hill's method for the points of a harmonic-balance system: holds the coordinates
/// formulation of the same system when the solve uses the receptance one.
pub struct HillAnalysis<'s, 'a> {
    system: &'s HbmSystem<'a>,
    full: Option<HbmSystem<'a>>,
}

impl<'s, 'a> HillAnalysis<'s, 'a> {
    /// Set up for `system`'s points (the full model's system is built when its formulation is
    /// the receptance's).
    pub fn new(system: &'s HbmSystem<'a>) -> Result<Self> {
        if system.cyclic().is_some() {
            return Err(Error::param(
                "cyclic",
                "Hill's method is not implemented for a cyclic sector (its perturbations of other \
                 harmonic indices are not in the sector's balance)",
            ));
        }
        let full = match system.formulation() {
            Formulation::Coordinates => None,
            Formulation::Receptance => {
                let mut full = HbmSystem::new(
                    system.structure,
                    system.harmonics.clone(),
                    system.excitation.clone(),
                    FormulationChoice::Coordinates,
                )?;
                full.aft = system.aft;
                full.newton = system.newton;
                Some(full)
            }
        };
        Ok(Self { system, full })
    }

    /// Stability of one point of the system (module documentation).
    pub fn point(&self, point: &HbmPoint) -> Result<Stability> {
        Ok(self.point_from(point, None)?.0)
    }

    /// [`HillAnalysis::point`] with the elements' periodic states searched from `warm` (the
    /// states of a nearby point, as [`HbmSystem::evaluate_from`]: the same Jacobian within the
    /// AFT's periodicity tolerance, in fewer periods); returns the point's states too.
    pub fn point_from(
        &self,
        point: &HbmPoint,
        warm: Option<&[WarmStart]>,
    ) -> Result<(Stability, Vec<WarmStart>)> {
        let t0 = Instant::now();
        let (full, q) = match &self.full {
            None => (self.system, point.z.clone()),
            Some(full) => (full, self.system.coordinates(point)),
        };
        let s = full.structure;
        let omega = point.omega;
        let ev = full.evaluate_from(&q, omega, point.level, true, warm);
        let (delta0, states) = (ev.jacobian, ev.element_states);
        let nabla = derivative_operator(&full.harmonics, omega);
        let a = companion_matrix(&delta0, &s.mass, &s.damping, &nabla, omega)?;
        let (sigma, schur_residual) = eigenvalues(&a)?;
        let values: Vec<Complex<f64>> = sigma.iter().map(|v| v * omega).collect();
        let exponents = floquet_exponents(&values, omega, 2 * s.n());
        let (max_real_part, stable) = verdict(&exponents, omega);
        Ok((
            Stability {
                exponents,
                max_real_part,
                stable,
                schur_residual,
                omega,
                wall_time_s: t0.elapsed().as_secs_f64(),
            },
            states,
        ))
    }
}

/// What kind of bifurcation lies between two points.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum BifurcationKind {
    /// A real multiplier `μ > 0` crosses the unit circle where the branch turns (saddle-node).
    Fold,
    /// A real multiplier `μ > 0` crosses the unit circle without a turning point.
    BranchPoint,
    /// A real multiplier `μ < 0` crosses the unit circle (flip).
    PeriodDoubling,
    /// A complex pair of multipliers crosses the unit circle (secondary Hopf, quasi-periodic
    /// motion nearby).
    NeimarkSacker,
}

impl BifurcationKind {
    /// The name used in reports.
    pub fn name(self) -> &'static str {
        match self {
            Self::Fold => "fold",
            Self::BranchPoint => "branch point",
            Self::PeriodDoubling => "period doubling",
            Self::NeimarkSacker => "Neimark–Sacker",
        }
    }
}

/// A bifurcation located between two consecutive points of a branch.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Bifurcation {
    /// Its kind.
    pub kind: BifurcationKind,
    /// Index of the point before it (the bifurcation lies between this point and the next).
    pub after_point: usize,
    /// Frequency (Hz): located on the branch where the largest real part crosses the stability
    /// limit; otherwise a fold's turning point or the midpoint (module documentation).
    pub frequency_hz: f64,
    /// Whether a Floquet exponent's crossing was seen (a fold found only from the turning of
    /// the continuation has `false`).
    pub exponent_crossing: bool,
}

/// Stability of every point of a branch, and the bifurcations between them.
#[derive(Debug, Clone)]
pub struct BranchStability {
    /// One assessment per point of the branch, in path order.
    pub points: Vec<Stability>,
    /// The bifurcations, in path order.
    pub bifurcations: Vec<Bifurcation>,
    /// Wall-clock time of the assessments (s).
    pub wall_time_s: f64,
}

impl BranchStability {
    /// Number of unstable points.
    pub fn unstable_points(&self) -> usize {
        self.points.iter().filter(|s| !s.stable).count()
    }

    /// Largest backward error of the eigen-solves.
    pub fn max_schur_residual(&self) -> f64 {
        self.points
            .iter()
            .map(|s| s.schur_residual)
            .fold(0.0, f64::max)
    }
}

/// Stability of every point of `branch`, a branch of `system` (the points in parallel).
pub fn branch_stability(system: &HbmSystem<'_>, branch: &Branch) -> Result<BranchStability> {
    let t0 = Instant::now();
    let hill = HillAnalysis::new(system)?;
    // One contiguous run of points per thread, each point's element states warm-starting the
    // next one's.
    let per_thread = branch
        .points
        .len()
        .div_ceil(rayon::current_num_threads().max(1))
        .max(1);
    let points = branch
        .points
        .par_chunks(per_thread)
        .map(|run| {
            let mut warm: Option<Vec<WarmStart>> = None;
            run.iter()
                .map(|p| {
                    let (st, states) = hill.point_from(p, warm.as_deref())?;
                    warm = Some(states);
                    Ok(st)
                })
                .collect::<Result<Vec<_>>>()
        })
        .collect::<Result<Vec<_>>>()?
        .concat();
    let mut bifurcations = bifurcations(&branch.points, &points);
    for b in bifurcations.iter_mut().filter(|b| b.exponent_crossing) {
        if let Some(w) = locate_crossing(&hill, branch, &points, b.after_point) {
            b.frequency_hz = w / (2.0 * std::f64::consts::PI);
        }
    }
    Ok(BranchStability {
        points,
        bifurcations,
        wall_time_s: t0.elapsed().as_secs_f64(),
    })
}

/// Most solves spent locating one bifurcation ([`locate_crossing`]).
const LOCATE_SOLVES: usize = 10;

/// A located crossing is accepted when the largest real part there is within this fraction of
/// `ω` of the stability limit ([`locate_crossing`]).
const LOCATED_MARGIN: f64 = 1e-4;

/// `Re s − tolerance` of the largest real part: zero where the point's verdict changes.
fn margin(st: &Stability) -> f64 {
    st.max_real_part - UNSTABLE_TOLERANCE * st.omega
}

/// Frequency (rad/s) on the branch where the largest real part of the Floquet exponents crosses
/// the stability limit between points `i` and `i + 1`: regula falsi (Illinois) along the
/// arclength, each abscissa solved on the branch ([`point_between`], the parabola through three
/// consecutive points and the bordered corrector) and assessed, until the margin is below
/// `1e-9·ω` or after `LOCATE_SOLVES` solves. `None` when the margin does not change sign
/// between the two points (another exponent crossed on an unstable branch), the branch has
/// fewer than three points, a solve fails, or no solved point came within
/// `LOCATED_MARGIN·ω` of the limit (the caller keeps its estimate).
pub fn locate_crossing(
    hill: &HillAnalysis<'_, '_>,
    branch: &Branch,
    stability: &[Stability],
    i: usize,
) -> Option<f64> {
    let pts = &branch.points;
    if pts.len() < 3 || i + 1 >= pts.len() {
        return None;
    }
    let (fa0, fb0) = (margin(&stability[i]), margin(&stability[i + 1]));
    if fa0 * fb0 >= 0.0 {
        return None;
    }
    // Frame of three points containing i and i + 1, arclength measured from the middle one.
    let mid = if i >= 1 { i } else { i + 1 };
    let frame = [&pts[mid - 1], &pts[mid], &pts[mid + 1]];
    let (_, _, s) = point_arclengths(frame);
    let (mut a, mut b) = if mid == i { (0.0, s[2]) } else { (s[0], 0.0) };
    let (mut fa, mut fb) = (fa0, fb0);
    let mut best = (f64::INFINITY, None);
    for _ in 0..LOCATE_SOLVES {
        let x = b - fb * (b - a) / (fb - fa);
        let p = point_between(hill.system, branch.level, frame, x)?;
        let st = hill.point(&p).ok()?;
        let fx = margin(&st);
        if fx.abs() < best.0 {
            best = (fx.abs(), Some(p.omega));
        }
        if fx.abs() <= 1e-9 * p.omega {
            break;
        }
        if fx * fb < 0.0 {
            (a, fa) = (b, fb);
        } else {
            fa *= 0.5;
        }
        (b, fb) = (x, fx);
    }
    // A corrector that lands away from its abscissa (a sharp turn between widely spaced
    // points) makes the margin erratic: only a point close to the limit is taken.
    (best.0 <= LOCATED_MARGIN * pts[i].omega)
        .then_some(best.1)
        .flatten()
}

/// Indices `i` of the points where the path turns: `(ω_i − ω_{i−1})·(ω_{i+1} − ω_i) < 0`.
pub fn turning_points(omegas: &[f64]) -> Vec<usize> {
    (1..omegas.len().saturating_sub(1))
        .filter(|&i| (omegas[i] - omegas[i - 1]) * (omegas[i + 1] - omegas[i]) < 0.0)
        .collect()
}

/// Frequency (rad/s) of the turning point near point `i`: the vertex of the parabola through
/// the frequencies of points `i − 1, i, i + 1` over their arclength
/// ([`point_arclengths`]; exact for a quadratic path, where `dω/ds = 0`).
pub fn turning_frequency(points: &[HbmPoint], i: usize) -> f64 {
    let (_, _, s) = point_arclengths([&points[i - 1], &points[i], &points[i + 1]]);
    let w = [points[i - 1].omega, points[i].omega, points[i + 1].omega];
    let d01 = (w[1] - w[0]) / (s[1] - s[0]);
    let d12 = (w[2] - w[1]) / (s[2] - s[1]);
    let c = (d12 - d01) / (s[2] - s[0]);
    if !(c.is_finite() && c != 0.0) {
        return w[1];
    }
    let x = (0.5 * (s[0] + s[1]) - d01 / (2.0 * c)).clamp(s[0], s[2]);
    w[0] + d01 * (x - s[0]) + c * (x - s[0]) * (x - s[1])
}

/// The bifurcations between consecutive points of a branch (`points`) with their assessments
/// `stability` (module documentation).
pub fn bifurcations(points: &[HbmPoint], stability: &[Stability]) -> Vec<Bifurcation> {
    const TWO_PI: f64 = 2.0 * std::f64::consts::PI;
    let omegas: Vec<f64> = points.iter().map(|p| p.omega).collect();
    let turns = turning_points(&omegas);
    let mut used_turns = vec![false; turns.len()];
    let mut out = Vec::new();
    for i in 0..stability.len().saturating_sub(1) {
        let (a, b) = (&stability[i], &stability[i + 1]);
        let (ca, cb) = (a.unstable_counts(), b.unstable_counts());
        // Where the largest real part changes sign, interpolate; otherwise the midpoint.
        let (ra, rb) = (
            a.max_real_part - UNSTABLE_TOLERANCE * a.omega,
            b.max_real_part - UNSTABLE_TOLERANCE * b.omega,
        );
        let crossing = if ra * rb < 0.0 {
            omegas[i] + (omegas[i + 1] - omegas[i]) * ra / (ra - rb)
        } else {
            0.5 * (omegas[i] + omegas[i + 1])
        };
        let mut push = |kind, omega: f64| {
            out.push(Bifurcation {
                kind,
                after_point: i,
                frequency_hz: omega / TWO_PI,
                exponent_crossing: true,
            })
        };
        if ca.0 != cb.0 {
            let turn = turns
                .iter()
                .position(|&t| t == i || t == i + 1)
                .filter(|&k| !used_turns[k]);
            match turn {
                Some(k) => {
                    used_turns[k] = true;
                    push(BifurcationKind::Fold, turning_frequency(points, turns[k]));
                }
                None => push(BifurcationKind::BranchPoint, crossing),
            }
        }
        if ca.1 != cb.1 {
            push(BifurcationKind::PeriodDoubling, crossing);
        }
        if ca.2 != cb.2 {
            push(BifurcationKind::NeimarkSacker, crossing);
        }
    }
    for (k, &t) in turns.iter().enumerate() {
        if !used_turns[k] {
            out.push(Bifurcation {
                kind: BifurcationKind::Fold,
                after_point: t.saturating_sub(1),
                frequency_hz: turning_frequency(points, t) / TWO_PI,
                exponent_crossing: false,
            });
        }
    }
    out.sort_by_key(|b| b.after_point);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dynamics::hbm::Excitation;
    use crate::dynamics::model::Structure;
    use nalgebra::DVector;

    /// A linear system's Floquet exponents are its eigenvalues `−ζω_r ± iω_r√(1−ζ²)` shifted by
    /// multiples of `iω` into the fundamental strip: Hill's method on a 2-DOF chain with
    /// non-proportional damping returns them to rounding, with all orders and with odd orders
    /// only, in both formulations.
    #[test]
    fn linear_exponents_are_the_eigenvalues_of_the_state_matrix() {
        let m = DMatrix::from_diagonal(&DVector::from_vec(vec![1.0, 0.5]));
        let k = DMatrix::from_row_slice(2, 2, &[3.0e4, -1.0e4, -1.0e4, 1.0e4]);
        let c = DMatrix::from_row_slice(2, 2, &[4.0, -1.0, -1.0, 2.0]);
        let s = Structure::lumped(
            vec!["a.x".into(), "b.x".into()],
            m.clone(),
            c.clone(),
            k.clone(),
        )
        .unwrap();
        // State matrix [0 I; −M⁻¹K −M⁻¹C].
        let mi = m.clone().try_inverse().unwrap();
        let mut state = DMatrix::zeros(4, 4);
        state.view_mut((0, 2), (2, 2)).fill_with_identity();
        state.view_mut((2, 0), (2, 2)).copy_from(&(-&mi * &k));
        state.view_mut((2, 2), (2, 2)).copy_from(&(-&mi * &c));
        let exact: Vec<Complex<f64>> = state.complex_eigenvalues().iter().copied().collect();
        for (odd, choice) in [
            (false, FormulationChoice::Coordinates),
            (true, FormulationChoice::Coordinates),
        ] {
            let h = Harmonics::new(3, odd, Some(16)).unwrap();
            let sys = HbmSystem::new(
                &s,
                h,
                Excitation {
                    force: DVector::from_vec(vec![1.0, 0.0]),
                    harmonic: 1,
                    force_sin: None,
                },
                choice,
            )
            .unwrap();
            let omega = 2.0 * std::f64::consts::PI * 21.0;
            let p = sys.solve(omega, 1.0, None).unwrap();
            let st = HillAnalysis::new(&sys).unwrap().point(&p).unwrap();
            assert_eq!(st.exponents.len(), 4);
            assert!(st.stable);
            assert!(st.schur_residual < 1e-13, "{}", st.schur_residual);
            for e in &exact {
                // Some kept exponent equals e up to a multiple of iω.
                let best = st
                    .exponents
                    .iter()
                    .map(|s| {
                        let d = s - e;
                        let k = (d.im / omega).round();
                        d.re.hypot(d.im - k * omega)
                    })
                    .fold(f64::INFINITY, f64::min);
                assert!(
                    best < 1e-9 * e.norm(),
                    "odd {odd}: {e} not found: {:?}",
                    st.exponents
                );
            }
        }
    }

    /// Copies of one exponent at the edge of the strip are skipped: of `λ1 ± iω` and
    /// `λ2 ± iω` (odd harmonics, two real-multiplier families) one of each is kept.
    #[test]
    fn conjugate_copies_at_the_strip_edge_are_one_exponent() {
        let w = 10.0;
        let eig = [
            Complex::new(-1.0, w),
            Complex::new(-1.0, -w),
            Complex::new(0.5, w),
            Complex::new(0.5, -w),
            Complex::new(-1.0, 3.0 * w),
            Complex::new(-1.0, -3.0 * w),
        ];
        let kept = floquet_exponents(&eig, w, 2);
        assert_eq!(kept.len(), 2);
        assert_eq!(kept[0].re, 0.5);
        assert_eq!(kept[1].re, -1.0);
        assert!(!verdict(&kept, w).1);
    }

    /// A stability change with a turning point is a fold; with a complex pair, Neimark–Sacker;
    /// a turning point without an assessment change is still named.
    #[test]
    fn bifurcations_are_named_by_the_crossing_multiplier() {
        let w = 100.0;
        let st = |exps: &[Complex<f64>], omega: f64| {
            let (max_real_part, stable) = verdict(exps, omega);
            Stability {
                exponents: exps.to_vec(),
                max_real_part,
                stable,
                schur_residual: 0.0,
                omega,
                wall_time_s: 0.0,
            }
        };
        let stable = [Complex::new(-1.0, 2.0), Complex::new(-1.0, -2.0)];
        let real_unstable = [Complex::new(3.0, 0.0), Complex::new(-5.0, 0.0)];
        let complex_unstable = [Complex::new(2.0, 7.0), Complex::new(2.0, -7.0)];
        // Path: ω rises, turns back at point 2 (unstable after), turns again at 4.
        let omegas = [w, w + 1.0, w + 2.0, w + 1.5, w + 1.0, w + 1.8, w + 2.5];
        let pts = vec![
            st(&stable, omegas[0]),
            st(&stable, omegas[1]),
            st(&stable, omegas[2]),
            st(&real_unstable, omegas[3]),
            st(&real_unstable, omegas[4]),
            st(&stable, omegas[5]),
            st(&complex_unstable, omegas[6]),
        ];
        let points: Vec<HbmPoint> = omegas
            .iter()
            .enumerate()
            .map(|(i, &omega)| HbmPoint {
                omega,
                level: 1.0,
                z: DVector::from_element(1, i as f64),
                iterations: 0,
                residual: 0.0,
                converged: true,
                periodicity_error: 0.0,
                wall_time_s: 0.0,
            })
            .collect();
        let b = bifurcations(&points, &pts);
        let kinds: Vec<BifurcationKind> = b.iter().map(|b| b.kind).collect();
        assert_eq!(
            kinds,
            [
                BifurcationKind::Fold,
                BifurcationKind::Fold,
                BifurcationKind::NeimarkSacker
            ],
            "{b:?}"
        );
        assert_eq!(b[0].after_point, 2);
        assert_eq!(b[1].after_point, 4);
        assert_eq!(b[2].after_point, 5);
    }
}
