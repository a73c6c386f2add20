//! Tangential contact with Coulomb friction and history: partial slip on a fixed pressure field.
//!
//! Units: lengths and displacements in m, tractions and pressures in Pa, forces in N, energies
//! in J (per unit nominal area: J/m²).
//!
//! # Assumption: quasi-identical materials
//! The shear traction also displaces the surfaces normally (Cerruti's `u_z ∝ (1−2ν)/G`), which
//! would change the pressure. For two bodies this coupling enters as
//! `(1−2ν1)/G1 − (1−2ν2)/G2` and vanishes when both bodies are of the same material
//! (Johnson, *Contact Mechanics*, 1985, §7.1; Kalker's "quasi-identical" bodies). The solver
//! assumes it: the pressure `p` from the normal solver is not changed by the shear and only the
//! tangential problem is solved, on a fixed pressure field or, under a varying normal load, on
//! the normal solution of each step ([`varying_load`]). Every result carries
//! [`QUASI_IDENTICAL_ASSUMPTION`].
//!
//! # The problem of one load step
//! On the contact set `{p > 0}` (fixed during the history), with `C` the tangential compliance
//! (Cerruti element coefficients of both bodies, [`crate::halfspace::influence`]), rigid shift
//! `δ` (a 2-vector: body 1 moves by `δ` relative to body 2 far from the contact) and `g` the
//! accumulated relative slip of the surface particles, the slip at point `i` is
//! `g_i = δ − (C q)_i`. Over a step from the previous state (`g_prev`) the slip increment is
//! `Δg_i = δ − (C q)_i − g_prev_i`, and Coulomb's law with history (Kalker 1990, *Three-
//! dimensional elastic bodies in rolling contact*, ch. 2) reads
//!
//! - stick: `|q_i| < μ p_i` and `Δg_i = 0`,
//! - slip: `|q_i| = μ p_i` and `Δg_i = λ_i q_i/|q_i|`, `λ_i ≥ 0` (traction along the slip
//!   increment, i.e. opposing the motion of body 2 relative to body 1).
//!
//! These are exactly the optimality conditions of the convex quadratic program
//! `min ½ qᵀCq − qᵀ(δ − g_prev)` subject to `|q_i| ≤ μ p_i` (Kalker's principle of minimum
//! complementary energy for the increment), since `−∇ = Δg`. In **load control** the force
//! `T = ΔA Σ q_i` is imposed instead and `δ` becomes the Lagrange multiplier of that constraint.
//!
//! # Solver
//! Projected gradient steps `T(q) = P(q + α Δg(q))` (`Δg = b − C q = −∇`, step `α = 1/L` with
//! `L` the largest eigenvalue of the restricted compliance, by power iteration once per pressure
//! field, with a 10 % margin), accelerated by Anderson mixing of the last 8 steps
//! (`TangentialSolver::solve_anderson`; Walker & Ni 2011), with FISTA (Beck & Teboulle 2009,
//! gradient-based adaptive restart after O'Donoghue & Candès 2015) from the best iterate as the
//! fallback should the mixing stall. Anderson needs 37 compliance products per step on the 1024²
//! reference cycle where FISTA needs 96 (BENCHMARKS.md). Each step is warm-started from the
//! previous step's traction, or within a monotone half-cycle of displacement control from the
//! secant predictor `P(q_n + s (q_n − q_{n−1}))` (see `TangentialSolver::warm_start`). The
//! projection is point-wise onto the disks `|q_i| ≤ μ p_i`; in load control it is onto the
//! disks intersected with `ΔA Σ q_i = T`, done exactly by a 2-D Newton iteration on the shift
//! `λ` with `q_i = P_i(z_i − λ)`; the rigid shift is then `δ = −λ/α`.
//!
//! Convergence: the natural residual of the variational inequality at the iterate `y`,
//! `max_i |y_i − P(y − α∇f(y))_i| / max_i μ p_i` (a relative traction error; zero exactly at the
//! solution), below [`TangentialOptions::tolerance`]. The iteration cap gives
//! [`Error::NonConvergence`].
//!
//! # Compliance operator: cost that follows the contact set
//! Shear lives only on the contact set, a small fraction of the grid at the reference loads.
//! Two exact implementations of `u = C q` on the contact points (module `compliance`):
//! - [`Operator::Dense`]: the restricted influence matrix by direct summation over the pairs of
//!   contact points, `O(n²)` per product with `n` contact points, its entries read from a table
//!   of the kernel by grid offset (memory `O(N)`, no `n × n` matrix is stored);
//! - [`Operator::Fft`]: scatter to the grid, FFT convolution with the three Cerruti spectra,
//!   gather, `O(N log N)` per product with `N` grid points (×4 when zero-padded).
//!
//! Both give the same product (to round-off; tested). [`Operator::Auto`] takes the one with the
//! lower estimated cost; see BENCHMARKS.md for the measured comparison.

mod compliance;
pub mod varying_load;

use crate::core::error::{require_positive, Error, Result};
use crate::core::fft::Boundary;
use crate::core::material::Material;
use crate::halfspace::influence::CerrutiConstants;
use compliance::{largest_eigenvalue, Compliance};
use nalgebra::{DMatrix, DVector};
use ndarray::Array2;
use std::collections::VecDeque;
use std::time::Instant;

/// The modelling assumption carried in every result's metadata.
pub const QUASI_IDENTICAL_ASSUMPTION: &str = "quasi-identical materials: normal-tangential \
coupling neglected (exact for two bodies of the same material); the pressure is the normal \
solution's, unaffected by the shear";

/// How the compliance product `u = C q` on the contact points is computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Operator {
    /// The one with the lower estimated cost (dense unless the contact set covers a large part
    /// of the grid).
    Auto,
    /// Influence matrix restricted to the contact points, by direct summation from a table of
    /// the kernel by grid offset.
    Dense,
    /// FFT convolution on the whole grid.
    Fft,
}

impl std::str::FromStr for Operator {
    type Err = Error;
    /// `auto`, `dense` or `fft`.
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "auto" => Ok(Operator::Auto),
            "dense" => Ok(Operator::Dense),
            "fft" => Ok(Operator::Fft),
            o => Err(Error::param(
                "operator",
                format!("expected auto, dense or fft, got `{o}`"),
            )),
        }
    }
}

/// A tangential contact problem on a fixed pressure field.
#[derive(Debug, Clone)]
pub struct TangentialProblem<'a> {
    /// Contact pressure p (Pa), shape `(nx, ny)`, `[[i, j]]` at `(i·dx, j·dy)`; the contact set
    /// is `{p > 0}`.
    pub pressure: &'a Array2<f64>,
    /// Grid spacing along x (m).
    pub dx: f64,
    /// Grid spacing along y (m).
    pub dy: f64,
    /// Periodic patch or finite contact (zero-padded convolution).
    pub boundary: Boundary,
    /// Coulomb friction coefficient μ (-), > 0.
    pub friction_coefficient: f64,
    /// Body 1 (the rough surface's material).
    pub body1: Material,
    /// Body 2 (the counter-face).
    pub body2: Material,
}

/// Solver settings.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TangentialOptions {
    /// Tolerance on the relative natural residual (see the module documentation). The default
    /// 1e-6 (a traction error of 1e-6 μ p_max) gives the energy per cycle of the 1024² reference
    /// cycle at 10 MPa within 7e-9 of the 1e-8 result (BENCHMARKS.md, "Tangential contact")
    /// for 32 % fewer iterations.
    pub tolerance: f64,
    /// Iteration cap of one step; exceeding it is [`Error::NonConvergence`].
    pub max_iterations: usize,
    /// Compliance operator.
    pub operator: Operator,
}

impl Default for TangentialOptions {
    fn default() -> Self {
        Self {
            tolerance: 1e-6,
            max_iterations: 20_000,
            operator: Operator::Auto,
        }
    }
}

impl TangentialOptions {
    /// The options, checked: a relative tolerance in (0, 1) and at least one iteration.
    pub fn validated(self) -> Result<Self> {
        crate::core::sanity::tolerance("tolerance", self.tolerance)?;
        if self.max_iterations == 0 {
            return Err(Error::param("max_iterations", "must be at least 1"));
        }
        Ok(self)
    }
}

/// What is imposed in a step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Control {
    /// Rigid tangential shift δ of body 1 relative to body 2 (m).
    Displacement([f64; 2]),
    /// Total tangential force T on the contact (N).
    Force([f64; 2]),
}

impl Control {
    fn scaled(self, s: f64) -> Self {
        match self {
            Control::Displacement(d) => Control::Displacement([d[0] * s, d[1] * s]),
            Control::Force(t) => Control::Force([t[0] * s, t[1] * s]),
        }
    }

    fn vector(self) -> [f64; 2] {
        match self {
            Control::Displacement(v) | Control::Force(v) => v,
        }
    }

    /// The same kind of control with another vector.
    fn with_vector(self, v: [f64; 2]) -> Self {
        match self {
            Control::Displacement(_) => Control::Displacement(v),
            Control::Force(_) => Control::Force(v),
        }
    }
}

/// The state after one load step.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct TangentialStep {
    /// Rigid tangential shift δ (m).
    pub shift_m: [f64; 2],
    /// Tangential force T = ΔA Σ q (N).
    pub force_n: [f64; 2],
    /// Mean shear stress over the nominal (grid) area, T / (nx·dx·ny·dy) (Pa).
    pub mean_shear_pa: [f64; 2],
    /// Fraction of the contact points that stick (-).
    pub stick_fraction: f64,
    /// Slip path length ∫|dg| accumulated since the start, averaged over the contact area (m).
    pub accumulated_slip_m: f64,
    /// Frictional work of this step, ΔA Σ q·Δg (J).
    pub frictional_work_j: f64,
    /// Solver iterations of this step (compliance products).
    pub iterations: usize,
    /// Final relative natural residual.
    pub residual: f64,
    /// Residual below tolerance.
    pub converged: bool,
    /// Wall time of the step (s).
    pub wall_time_s: f64,
}

impl TangentialStep {
    /// The state a history starts from (step 0): no load, every point stuck.
    pub const INITIAL: TangentialStep = TangentialStep {
        shift_m: [0.0; 2],
        force_n: [0.0; 2],
        mean_shear_pa: [0.0; 2],
        stick_fraction: 1.0,
        accumulated_slip_m: 0.0,
        frictional_work_j: 0.0,
        iterations: 0,
        residual: 0.0,
        converged: true,
        wall_time_s: 0.0,
    };
}

/// Facts about a solver set up on one pressure field.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct TangentialMetadata {
    /// [`QUASI_IDENTICAL_ASSUMPTION`].
    pub assumption: &'static str,
    /// Friction coefficient μ.
    pub friction_coefficient: f64,
    /// Grid shape `(nx, ny)`.
    pub grid: (usize, usize),
    /// Boundary treatment.
    pub boundary: Boundary,
    /// Operator actually used (`Dense` or `Fft`).
    pub operator: Operator,
    /// Number of contact points.
    pub contact_points: usize,
    /// Normal force P = ΔA Σ p (N).
    pub normal_force_n: f64,
    /// Nominal (grid) area (m²).
    pub nominal_area_m2: f64,
    /// Largest eigenvalue estimate of the restricted compliance (m/Pa).
    pub compliance_norm_m_per_pa: f64,
    /// Time to build the operator (s).
    pub setup_time_s: f64,
}

/// Partial-slip solver on one fixed pressure field, holding the contact history.
pub struct TangentialSolver {
    nx: usize,
    ny: usize,
    element_area: f64,
    points: Vec<(usize, usize)>,
    /// Traction bound μ p_i (Pa).
    limit: Vec<f64>,
    compliance: Compliance,
    /// Step size α = 1/L (Pa/m).
    alpha: f64,
    /// Largest traction bound max μ p_i (Pa), the scale of the natural residual.
    max_limit: f64,
    options: TangentialOptions,
    metadata: TangentialMetadata,
    // History.
    q: Vec<[f64; 2]>,
    slip: Vec<[f64; 2]>,
    slip_path: Vec<f64>,
    shift: [f64; 2],
    /// Projection multiplier of the last load-controlled step (warm start of its Newton).
    lambda: [f64; 2],
    /// The step before the current state in displacement control: its imposed shift and
    /// traction (for the predictor of the next step's warm start).
    previous: Option<([f64; 2], Vec<[f64; 2]>)>,
}

impl std::fmt::Debug for TangentialSolver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TangentialSolver")
            .field("metadata", &self.metadata)
            .finish()
    }
}

impl TangentialSolver {
    /// Check the problem, find the contact set and build the compliance operator.
    ///
    /// Errors: μ ≤ 0 or not finite, non-positive spacing, negative or non-finite pressure,
    /// invalid materials ([`Error::InvalidParameter`]); no point with `p > 0`
    /// ([`Error::Data`]).
    pub fn new(problem: &TangentialProblem<'_>, options: TangentialOptions) -> Result<Self> {
        let start = Instant::now();
        let mu = crate::core::sanity::friction_coefficient(
            "friction_coefficient",
            problem.friction_coefficient,
        )?;
        let dx = require_positive("dx", problem.dx)?;
        let dy = require_positive("dy", problem.dy)?;
        let options = options.validated()?;
        let body1 = problem.body1.validated("body1")?;
        let body2 = problem.body2.validated("body2")?;
        let (nx, ny) = problem.pressure.dim();
        if nx == 0 || ny == 0 {
            return Err(Error::param("pressure", "empty pressure field"));
        }
        if let Some(((i, j), v)) = problem
            .pressure
            .indexed_iter()
            .find(|(_, v)| !(v.is_finite() && **v >= 0.0))
        {
            return Err(Error::param(
                "pressure",
                format!("must be finite and ≥ 0, got {v} Pa at grid point ({i}, {j})"),
            ));
        }
        let points: Vec<(usize, usize)> = problem
            .pressure
            .indexed_iter()
            .filter(|(_, p)| **p > 0.0)
            .map(|(ij, _)| ij)
            .collect();
        if points.is_empty() {
            return Err(Error::Data(
                "tangential contact: the pressure field has no contact (no point with p > 0); \
                 nothing can carry shear"
                    .into(),
            ));
        }
        let n = points.len();
        let limit: Vec<f64> = points
            .iter()
            .map(|&(i, j)| mu * problem.pressure[[i, j]])
            .collect();
        let k = CerrutiConstants::of_materials(body1, body2);
        let compliance = Compliance::new(
            options.operator,
            problem.boundary,
            (nx, ny),
            &points,
            (dx, dy),
            k,
        );
        let operator = compliance.operator();
        let l = largest_eigenvalue(&compliance, n);
        let max_limit = limit.iter().cloned().fold(0.0, f64::max);
        let element_area = dx * dy;
        let normal_force = element_area * problem.pressure.sum();
        let metadata = TangentialMetadata {
            assumption: QUASI_IDENTICAL_ASSUMPTION,
            friction_coefficient: mu,
            grid: (nx, ny),
            boundary: problem.boundary,
            operator,
            contact_points: n,
            normal_force_n: normal_force,
            nominal_area_m2: nx as f64 * dx * ny as f64 * dy,
            compliance_norm_m_per_pa: l,
            setup_time_s: start.elapsed().as_secs_f64(),
        };
        Ok(Self {
            nx,
            ny,
            element_area,
            points,
            limit,
            compliance,
            alpha: 1.0 / (1.1 * l),
            max_limit,
            options,
            metadata,
            q: vec![[0.0; 2]; n],
            slip: vec![[0.0; 2]; n],
            slip_path: vec![0.0; n],
            shift: [0.0; 2],
            lambda: [0.0; 2],
            previous: None,
        })
    }

    /// Replace the pressure field, keeping the history (varying normal load): the traction
    /// bounds become `μ p_i` of the new field on the solver's points, which must hold every
    /// point of the new contact set (build the solver on a field whose contact set contains all
    /// those of the history, e.g. their point-wise maximum). A point of the set with `p = 0` is
    /// out of contact: its traction is zero and its relative displacement `g_i = δ − (C q)_i` is
    /// carried along, so that when it comes back into contact it starts to stick from where it
    /// is (Kalker 1990, §2.3: the slip is the change of the relative displacement since the
    /// previous instant, at points in contact at both). The secant predictor is dropped (the
    /// next step starts from the current traction).
    ///
    /// Errors: a different shape, a negative or non-finite pressure, contact outside the
    /// solver's points, or no contact at all.
    pub fn set_pressure(&mut self, pressure: &Array2<f64>) -> Result<()> {
        if pressure.dim() != (self.nx, self.ny) {
            return Err(Error::param(
                "pressure",
                format!(
                    "shape {:?} differs from the solver's {:?}",
                    pressure.dim(),
                    (self.nx, self.ny)
                ),
            ));
        }
        if let Some(((i, j), v)) = pressure
            .indexed_iter()
            .find(|(_, v)| !(v.is_finite() && **v >= 0.0))
        {
            return Err(Error::param(
                "pressure",
                format!("must be finite and ≥ 0, got {v} Pa at grid point ({i}, {j})"),
            ));
        }
        let mu = self.metadata.friction_coefficient;
        let limit: Vec<f64> = self
            .points
            .iter()
            .map(|&(i, j)| mu * pressure[[i, j]])
            .collect();
        let covered = limit.iter().filter(|&&r| r > 0.0).count();
        let total = pressure.iter().filter(|&&p| p > 0.0).count();
        if covered < total {
            return Err(Error::param(
                "pressure",
                format!(
                    "{} contact points lie outside the solver's {} points: build the solver on \
                     a field whose contact set holds every one of the history",
                    total - covered,
                    self.points.len()
                ),
            ));
        }
        if covered == 0 {
            return Err(Error::Data(
                "tangential contact: the pressure field has no contact (no point with p > 0); \
                 nothing can carry shear"
                    .into(),
            ));
        }
        self.max_limit = limit.iter().cloned().fold(0.0, f64::max);
        self.limit = limit;
        self.metadata.normal_force_n = self.element_area * pressure.sum();
        self.previous = None;
        Ok(())
    }

    /// Number of the solver's points in contact (`p > 0`) under the current pressure.
    pub fn points_in_contact(&self) -> usize {
        self.limit.iter().filter(|&&r| r > 0.0).count()
    }

    /// Facts about the set-up (assumption, operator, contact points, normal force, ...).
    pub fn metadata(&self) -> &TangentialMetadata {
        &self.metadata
    }

    /// Friction limit of the total tangential force, μP (N).
    pub fn friction_limit_n(&self) -> f64 {
        self.element_area * self.limit.iter().sum::<f64>()
    }

    /// Largest traction bound `max_i μ p_i` (Pa), the scale of the natural residual.
    pub fn traction_bound_pa(&self) -> f64 {
        self.max_limit
    }

    /// Tolerance on the relative natural residual each step is solved to (the traction error
    /// of a converged step is at most this times [`Self::traction_bound_pa`] per point).
    pub fn tolerance(&self) -> f64 {
        self.options.tolerance
    }

    /// Forget the history: back to the virgin state (q = 0, no slip, no shift).
    pub fn reset(&mut self) {
        self.q.iter_mut().for_each(|v| *v = [0.0; 2]);
        self.slip.iter_mut().for_each(|v| *v = [0.0; 2]);
        self.slip_path.iter_mut().for_each(|v| *v = 0.0);
        self.shift = [0.0; 2];
        self.lambda = [0.0; 2];
        self.previous = None;
    }

    /// Shear traction field (Pa) on the grid, components `(q_x, q_y)`.
    pub fn traction(&self) -> (Array2<f64>, Array2<f64>) {
        let mut qx = Array2::zeros((self.nx, self.ny));
        let mut qy = Array2::zeros((self.nx, self.ny));
        for (k, &(i, j)) in self.points.iter().enumerate() {
            qx[[i, j]] = self.q[k][0];
            qy[[i, j]] = self.q[k][1];
        }
        (qx, qy)
    }

    /// Stick mask on the grid (true where the contact sticks).
    pub fn stick_mask(&self) -> Array2<bool> {
        let mut m = Array2::from_elem((self.nx, self.ny), false);
        for (k, &(i, j)) in self.points.iter().enumerate() {
            m[[i, j]] = self.sticks(k);
        }
        m
    }

    /// Stick: strictly inside the friction disk (a projection puts slipping points exactly on it).
    fn sticks(&self, k: usize) -> bool {
        let [x, y] = self.q[k];
        x.hypot(y) < self.limit[k] * (1.0 - 1e-9)
    }

    /// Solve one load step from the current state and make it the new state.
    ///
    /// Errors: non-finite control; in load control `|T| ≥ μP` (gross slip, no static solution);
    /// the iteration cap ([`Error::NonConvergence`], the state is left unchanged).
    pub fn step(&mut self, control: Control) -> Result<TangentialStep> {
        let start = Instant::now();
        let v = control.vector();
        if !(v[0].is_finite() && v[1].is_finite()) {
            return Err(Error::param(
                "control",
                format!("tangential load must be finite, got {v:?}"),
            ));
        }
        let n = self.points.len();
        let alpha = self.alpha;
        // b = δ − g_prev (displacement control) or −g_prev (load control, δ unknown).
        let (b, force_sum) = match control {
            Control::Displacement(d) => (
                self.slip
                    .iter()
                    .map(|g| [d[0] - g[0], d[1] - g[1]])
                    .collect::<Vec<_>>(),
                None,
            ),
            Control::Force(t) => {
                let limit = self.friction_limit_n();
                let tm = t[0].hypot(t[1]);
                if tm >= limit {
                    return Err(Error::param(
                        "tangential force",
                        format!(
                            "|T| = {tm:.6e} N reaches the friction limit μP = {limit:.6e} N: \
                             gross slip has no static solution in load control"
                        ),
                    ));
                }
                (
                    self.slip.iter().map(|g| [-g[0], -g[1]]).collect(),
                    Some([t[0] / self.element_area, t[1] / self.element_area]),
                )
            }
        };
        let q0 = self.warm_start(control);
        let solved = self.solve(&b, force_sum, q0)?;
        let (q_new, lambda, iterations, residual) =
            (solved.q, solved.lambda, solved.iterations, solved.residual);
        let converged = true;
        let mut u = vec![[0.0; 2]; n];
        // Accept q_new; rigid shift, slip and work of the step.
        let shift = match control {
            Control::Displacement(d) => d,
            Control::Force(_) => [-lambda[0] / alpha, -lambda[1] / alpha],
        };
        self.compliance.apply(&q_new, &mut u);
        let mut work = 0.0;
        for k in 0..n {
            let g = [shift[0] - u[k][0], shift[1] - u[k][1]];
            let dg = [g[0] - self.slip[k][0], g[1] - self.slip[k][1]];
            work += q_new[k][0] * dg[0] + q_new[k][1] * dg[1];
            // Slip is counted where the point is in contact (a point out of contact, possible
            // after `set_pressure`, only moves with the body).
            if self.limit[k] > 0.0 {
                self.slip_path[k] += dg[0].hypot(dg[1]);
            }
            self.slip[k] = g;
        }
        let old_q = std::mem::replace(&mut self.q, q_new);
        self.previous = match control {
            Control::Displacement(_) => Some((self.shift, old_q)),
            Control::Force(_) => None,
        };
        self.shift = shift;
        self.lambda = lambda;
        let fsum = self
            .q
            .iter()
            .fold([0.0, 0.0], |a, v| [a[0] + v[0], a[1] + v[1]]);
        let force = [fsum[0] * self.element_area, fsum[1] * self.element_area];
        let area = self.metadata.nominal_area_m2;
        let stick = (0..n).filter(|&k| self.sticks(k)).count();
        let in_contact = self.limit.iter().filter(|&&r| r > 0.0).count().max(1);
        Ok(TangentialStep {
            shift_m: shift,
            force_n: force,
            mean_shear_pa: [force[0] / area, force[1] / area],
            stick_fraction: stick as f64 / in_contact as f64,
            accumulated_slip_m: self.slip_path.iter().sum::<f64>() / in_contact as f64,
            frictional_work_j: work * self.element_area,
            iterations,
            residual,
            converged,
            wall_time_s: start.elapsed().as_secs_f64(),
        })
    }

    /// One step's quadratic program: Anderson-accelerated projected gradient, and FISTA from
    /// its best iterate should it stall (never seen on the validation and reference cases, a
    /// safeguard: FISTA converges from any start).
    fn solve(
        &self,
        b: &[[f64; 2]],
        force_sum: Option<[f64; 2]>,
        q0: Vec<[f64; 2]>,
    ) -> Result<Solved> {
        match self.solve_anderson(b, force_sum, q0)? {
            Anderson::Converged(s) => Ok(s),
            Anderson::Stalled { best, used } => self.solve_fista(b, force_sum, best, used),
        }
    }

    /// The projection `P` of the step: onto the disks `|q_i| ≤ μ p_i`, and in load control onto
    /// their intersection with `Σ q_i = sum` (Newton on the multiplier from `lambda`, updated).
    fn project(
        &self,
        z: &[[f64; 2]],
        force_sum: Option<[f64; 2]>,
        lambda: &mut [f64; 2],
        out: &mut [[f64; 2]],
    ) {
        match force_sum {
            None => {
                for ((o, zi), &r) in out.iter_mut().zip(z).zip(&self.limit) {
                    *o = project_disk(*zi, r);
                }
            }
            Some(s) => *lambda = project_disks_with_sum(z, &self.limit, s, *lambda, out),
        }
    }

    /// Anderson-accelerated projected gradient (type II; Walker & Ni 2011, *SIAM J. Numer.
    /// Anal.* 49; for projected fixed-point maps e.g. Mai & Johansson 2020, *ICML*).
    ///
    /// The map is the projected gradient step `T(q) = P(q + α Δg(q))` (`Δg = b − C q`, step
    /// `α = 1/L`), whose fixed point is the solution. With `f_k = T(q_k) − q_k` and the
    /// differences `ΔF`, `ΔG` of the last [`ANDERSON_MEMORY`] residuals and map values, the next
    /// iterate is `q_{k+1} = P(T(q_k) − ΔG γ)`, `γ = argmin |f_k − ΔF γ|` (a least-squares
    /// problem of at most 8 unknowns, by its regularised normal equations). Safeguard: the
    /// memory is cleared, i.e. a plain projected-gradient step is taken, when the residual
    /// exceeds twice the smallest so far. One compliance product per iteration, like FISTA,
    /// but 2.6× fewer iterations on the 1024² reference cycle (BENCHMARKS.md).
    ///
    /// Acceptance is FISTA's: the natural residual `max_i |T(q)_i − q_i| / max μp ≤ tol`, and
    /// the accepted traction is `T(q)` (feasible). Returns [`Anderson::Stalled`] with the best
    /// iterate after [`ANDERSON_STALL`] iterations without a new smallest residual.
    fn solve_anderson(
        &self,
        b: &[[f64; 2]],
        force_sum: Option<[f64; 2]>,
        q0: Vec<[f64; 2]>,
    ) -> Result<Anderson> {
        let n = self.points.len();
        let (alpha, rmax) = (self.alpha, self.max_limit);
        let mut x = q0;
        let mut u = vec![[0.0; 2]; n];
        let mut z = vec![[0.0; 2]; n];
        let mut g = vec![[0.0; 2]; n];
        let mut lambda = self.lambda;
        let mut memory: VecDeque<FieldPair> = VecDeque::with_capacity(ANDERSON_MEMORY + 1);
        // The residual and map value of the previous iterate.
        let mut previous: Option<FieldPair> = None;
        let (mut best, mut best_x, mut since_best) = (f64::INFINITY, x.clone(), 0);
        let mut residual = f64::INFINITY;
        let mut iterations = 0;
        while iterations < self.options.max_iterations {
            iterations += 1;
            self.compliance.apply(&x, &mut u);
            for k in 0..n {
                z[k] = [
                    x[k][0] + alpha * (b[k][0] - u[k][0]),
                    x[k][1] + alpha * (b[k][1] - u[k][1]),
                ];
            }
            self.project(&z, force_sum, &mut lambda, &mut g);
            let f: Vec<[f64; 2]> = g
                .iter()
                .zip(&x)
                .map(|(a, c)| [a[0] - c[0], a[1] - c[1]])
                .collect();
            residual = f.iter().map(|v| v[0].hypot(v[1])).fold(0.0, f64::max) / rmax;
            if residual <= self.options.tolerance {
                return Ok(Anderson::Converged(Solved {
                    q: g,
                    lambda,
                    iterations,
                    residual,
                }));
            }
            if residual < best {
                (best, since_best) = (residual, 0);
                best_x.clone_from(&x);
            } else {
                since_best += 1;
                if since_best >= ANDERSON_STALL {
                    return Ok(Anderson::Stalled {
                        best: best_x,
                        used: iterations,
                    });
                }
            }
            if residual > 2.0 * best {
                memory.clear();
                previous = None;
            }
            if let Some((fp, gp)) = previous.take() {
                memory.push_back((difference(&f, &fp), difference(&g, &gp)));
                if memory.len() > ANDERSON_MEMORY {
                    memory.pop_front();
                }
            }
            let mut next = g.clone();
            if let Some(gamma) = least_squares_combination(&memory, &f) {
                for (gi, (_, dg)) in gamma.iter().zip(&memory) {
                    for (v, d) in next.iter_mut().zip(dg) {
                        v[0] -= gi * d[0];
                        v[1] -= gi * d[1];
                    }
                }
            }
            previous = Some((f, g.clone()));
            self.project(&next, force_sum, &mut lambda, &mut x);
        }
        Err(Error::NonConvergence {
            solver: "tangential partial-slip (Anderson-accelerated projected gradient)".into(),
            iterations,
            residual,
            tolerance: self.options.tolerance,
        })
    }

    /// FISTA with gradient restart from `q0` on `min ½ qᵀCq − qᵀb` over the disks (and, in load
    /// control, `Σ q = sum`), `used` products already spent on this step.
    fn solve_fista(
        &self,
        b: &[[f64; 2]],
        force_sum: Option<[f64; 2]>,
        q0: Vec<[f64; 2]>,
        used: usize,
    ) -> Result<Solved> {
        let n = self.points.len();
        let alpha = self.alpha;
        let rmax = self.max_limit;
        let mut q = q0;
        let mut y = q.clone();
        let mut q_new = vec![[0.0; 2]; n];
        let mut u = vec![[0.0; 2]; n];
        let mut z = vec![[0.0; 2]; n];
        let mut lambda = self.lambda;
        let mut t = 1.0f64;
        let mut residual = f64::INFINITY;
        let mut iterations = used;
        while iterations < self.options.max_iterations {
            iterations += 1;
            self.compliance.apply(&y, &mut u);
            for k in 0..n {
                // z = y − α ∇f(y) = y + α Δg.
                z[k] = [
                    y[k][0] - alpha * (u[k][0] - b[k][0]),
                    y[k][1] - alpha * (u[k][1] - b[k][1]),
                ];
            }
            match force_sum {
                None => {
                    for k in 0..n {
                        q_new[k] = project_disk(z[k], self.limit[k]);
                    }
                }
                Some(s) => {
                    lambda = project_disks_with_sum(&z, &self.limit, s, lambda, &mut q_new);
                }
            }
            residual = y
                .iter()
                .zip(&q_new)
                .map(|(a, c)| (a[0] - c[0]).hypot(a[1] - c[1]))
                .fold(0.0, f64::max)
                / rmax;
            if residual <= self.options.tolerance {
                return Ok(Solved {
                    q: q_new,
                    lambda,
                    iterations,
                    residual,
                });
            }
            // Gradient restart: momentum pointing against the descent direction.
            let restart: f64 = (0..n)
                .map(|k| {
                    (y[k][0] - q_new[k][0]) * (q_new[k][0] - q[k][0])
                        + (y[k][1] - q_new[k][1]) * (q_new[k][1] - q[k][1])
                })
                .sum();
            let t_next = if restart > 0.0 {
                1.0
            } else {
                0.5 * (1.0 + (1.0 + 4.0 * t * t).sqrt())
            };
            let beta = if restart > 0.0 {
                0.0
            } else {
                (t - 1.0) / t_next
            };
            for k in 0..n {
                y[k] = [
                    q_new[k][0] + beta * (q_new[k][0] - q[k][0]),
                    q_new[k][1] + beta * (q_new[k][1] - q[k][1]),
                ];
            }
            std::mem::swap(&mut q, &mut q_new);
            t = t_next;
        }
        Err(Error::NonConvergence {
            solver: "tangential partial-slip (FISTA)".into(),
            iterations,
            residual,
            tolerance: self.options.tolerance,
        })
    }

    /// Warm start of a step: the current traction, or in displacement control, when the
    /// increment continues in the direction of the previous one (within a monotone half-cycle),
    /// the secant predictor `P(q_n + s (q_n − q_{n−1}))` with `s = |δ − δ_n| / |δ_n − δ_{n−1}|`
    /// (the linear extrapolation that is exact while the stick and slip sets do not change;
    /// capped at `s ≤ 2`). At a reversal, the current traction: every point sticks at first.
    /// Only the starting point changes; the converged solution is the same (the problem is
    /// strictly convex — except on a periodic patch in contact at every point, where a uniform
    /// traction costs no compliance energy and only the friction disks bound it).
    fn warm_start(&self, control: Control) -> Vec<[f64; 2]> {
        let (Control::Displacement(d), Some((d_prev, q_prev))) = (control, &self.previous) else {
            return self.q.clone();
        };
        let inc = [d[0] - self.shift[0], d[1] - self.shift[1]];
        let inc_prev = [self.shift[0] - d_prev[0], self.shift[1] - d_prev[1]];
        let dot = inc[0] * inc_prev[0] + inc[1] * inc_prev[1];
        let norm_prev = inc_prev[0].hypot(inc_prev[1]);
        if !(dot > 0.0 && norm_prev > 0.0) {
            return self.q.clone();
        }
        let s = (inc[0].hypot(inc[1]) / norm_prev).min(2.0);
        self.q
            .iter()
            .zip(q_prev)
            .zip(&self.limit)
            .map(|((a, b), &r)| {
                project_disk([a[0] + s * (a[0] - b[0]), a[1] + s * (a[1] - b[1])], r)
            })
            .collect()
    }

    /// Rigid shift at which monotonic loading from the virgin state along the unit direction
    /// `e` reaches gross slip (m): with every point saturated, `q_i = μ p_i e`, the slip
    /// `g_i = δ − (C q)_i` must point along `e` everywhere, which first happens at
    /// `δ_gs = max_i (C q)_i·e`. For a Hertz contact this is Mindlin's `3μP·s/(16a)`. Exact
    /// where `(C q)_i` is parallel to `e` at every point (a pressure field mirror-symmetric about
    /// the `e` axis, as Hertz's); on a rough patch the x–y coupling of the Cerruti kernel
    /// (`c_dir`) gives `(C q)_i` a small sideways component, the saturated field is then not
    /// exactly along `e`, and `δ_gs` is an approximation (second order in the sideways angle),
    /// used as an amplitude scale.
    pub fn gross_slip_displacement(&self, direction: [f64; 2]) -> Result<f64> {
        let m = direction[0].hypot(direction[1]);
        if !(m.is_finite() && m > 0.0) {
            return Err(Error::param(
                "direction",
                format!("must be a finite non-zero vector, got {direction:?}"),
            ));
        }
        let e = [direction[0] / m, direction[1] / m];
        let q: Vec<[f64; 2]> = self.limit.iter().map(|&r| [r * e[0], r * e[1]]).collect();
        let u = self.apply_compliance(&q);
        Ok(u.iter()
            .map(|v| v[0] * e[0] + v[1] * e[1])
            .fold(f64::NEG_INFINITY, f64::max))
    }

    /// Apply `u = C q` on the contact points (for tests and diagnostics).
    pub fn apply_compliance(&self, q: &[[f64; 2]]) -> Vec<[f64; 2]> {
        let mut u = vec![[0.0; 2]; self.points.len()];
        self.compliance.apply(q, &mut u);
        u
    }

    /// Contact points `(i, j)` in the order used by [`Self::apply_compliance`].
    pub fn contact_points(&self) -> &[(usize, usize)] {
        &self.points
    }
}

/// The solution of one step's quadratic program.
struct Solved {
    q: Vec<[f64; 2]>,
    /// Load control: the multiplier of `Σ q = T/ΔA` (zero in displacement control).
    lambda: [f64; 2],
    /// Compliance products spent.
    iterations: usize,
    residual: f64,
}

/// Previous steps combined by the Anderson acceleration.
const ANDERSON_MEMORY: usize = 8;

/// Iterations without a new smallest residual after which the Anderson acceleration hands over
/// to FISTA.
const ANDERSON_STALL: usize = 100;

/// Two traction fields of the Anderson acceleration: a residual `T(q) − q` and the map value
/// `T(q)`, or (in the memory) the differences `ΔF`, `ΔG` of two consecutive ones.
type FieldPair = (Vec<[f64; 2]>, Vec<[f64; 2]>);

/// Outcome of [`TangentialSolver::solve_anderson`].
enum Anderson {
    Converged(Solved),
    /// No progress: the best iterate and the products spent.
    Stalled {
        best: Vec<[f64; 2]>,
        used: usize,
    },
}

/// `a − b` point by point.
fn difference(a: &[[f64; 2]], b: &[[f64; 2]]) -> Vec<[f64; 2]> {
    a.iter()
        .zip(b)
        .map(|(x, y)| [x[0] - y[0], x[1] - y[1]])
        .collect()
}

/// `γ = argmin |f − Σ_i γ_i ΔF_i|` over the stored residual differences `ΔF_i` (the first of
/// each pair in `memory`), by Cholesky on the normal equations with a relative Tikhonov term of
/// 1e-10 (the differences become nearly dependent close to convergence). `None` without memory
/// or if the system is numerically singular.
fn least_squares_combination(memory: &VecDeque<FieldPair>, f: &[[f64; 2]]) -> Option<Vec<f64>> {
    let m = memory.len();
    if m == 0 {
        return None;
    }
    let dot = |a: &[[f64; 2]], b: &[[f64; 2]]| -> f64 {
        a.iter()
            .zip(b)
            .map(|(x, y)| x[0] * y[0] + x[1] * y[1])
            .sum()
    };
    let mut gram = DMatrix::from_fn(m, m, |i, j| dot(&memory[i].0, &memory[j].0));
    let regularisation = 1e-10 * gram.trace() / m as f64;
    for i in 0..m {
        gram[(i, i)] += regularisation;
    }
    let rhs = DVector::from_fn(m, |i, _| dot(&memory[i].0, f));
    let gamma = gram.cholesky()?.solve(&rhs);
    gamma
        .iter()
        .all(|g| g.is_finite())
        .then(|| gamma.iter().copied().collect())
}

/// Projection of `z` onto the disk of radius `r`.
fn project_disk(z: [f64; 2], r: f64) -> [f64; 2] {
    let m = z[0].hypot(z[1]);
    if m <= r {
        z
    } else {
        let s = r / m;
        [z[0] * s, z[1] * s]
    }
}

/// Projection onto `{|q_i| ≤ r_i} ∩ {Σ q_i = s}`: `q_i = P_i(z_i − λ)` with the 2-vector `λ`
/// solving `h(λ) = Σ P_i(z_i − λ) − s = 0` (monotone; damped Newton from `λ0`). Returns `λ`.
fn project_disks_with_sum(
    z: &[[f64; 2]],
    r: &[f64],
    s: [f64; 2],
    lambda0: [f64; 2],
    out: &mut [[f64; 2]],
) -> [f64; 2] {
    let scale = r.iter().sum::<f64>().max(f64::MIN_POSITIVE);
    let eval = |lam: [f64; 2], out: &mut [[f64; 2]]| -> ([f64; 2], [f64; 3]) {
        let mut h = [-s[0], -s[1]];
        let mut jac = [0.0; 3]; // Σ D_i (symmetric 2×2: [xx, xy, yy])
        for ((o, zi), &ri) in out.iter_mut().zip(z).zip(r) {
            let v = [zi[0] - lam[0], zi[1] - lam[1]];
            let m = v[0].hypot(v[1]);
            if m <= ri {
                *o = v;
                jac[0] += 1.0;
                jac[2] += 1.0;
            } else {
                let c = ri / m;
                let e = [v[0] / m, v[1] / m];
                *o = [v[0] * c, v[1] * c];
                jac[0] += c * (1.0 - e[0] * e[0]);
                jac[1] -= c * e[0] * e[1];
                jac[2] += c * (1.0 - e[1] * e[1]);
            }
            h[0] += o[0];
            h[1] += o[1];
        }
        (h, jac)
    };
    let mut lam = lambda0;
    let (mut h, mut jac) = eval(lam, out);
    for _ in 0..100 {
        let hn = h[0].hypot(h[1]);
        if hn <= 1e-14 * scale {
            break;
        }
        // Newton: Σ D_i · Δλ = h (since ∂h/∂λ = −Σ D_i). Regularised against singular Σ D.
        let reg = 1e-12 * z.len() as f64;
        let (a, b, d) = (jac[0] + reg, jac[1], jac[2] + reg);
        let det = a * d - b * b;
        let step = [(d * h[0] - b * h[1]) / det, (a * h[1] - b * h[0]) / det];
        let mut f = 1.0;
        let mut accepted = false;
        for _ in 0..40 {
            let trial = [lam[0] + f * step[0], lam[1] + f * step[1]];
            let (ht, jt) = eval(trial, out);
            if ht[0].hypot(ht[1]) < hn {
                lam = trial;
                h = ht;
                jac = jt;
                accepted = true;
                break;
            }
            f *= 0.5;
        }
        if !accepted {
            break;
        }
    }
    // Leave `out` consistent with the returned λ.
    eval(lam, out);
    lam
}

/// A sinusoidal history: `control(t) = amplitude · sin(2π k / steps_per_cycle)`, `k = 1 ..=
/// cycles·steps_per_cycle`, starting from the virgin state: a to-and-fro along the amplitude's
/// in-plane direction (any angle; [`EllipticalPath`] for a path that encloses an area).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Oscillation {
    /// Amplitude: displacement δa (m) or force T* (N), with its direction.
    pub amplitude: Control,
    /// Number of cycles (≥ 1).
    pub cycles: usize,
    /// Steps per cycle (≥ 4).
    pub steps_per_cycle: usize,
}

/// Energy balance of one cycle.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct CycleEnergy {
    /// Cycle number (1-based; cycle 1 starts from the virgin state and includes the initial
    /// loading branch, so it is not a closed loop).
    pub cycle: usize,
    /// Loop area ∮ T·dδ (trapezoidal rule over the steps) (J).
    pub dissipated_j: f64,
    /// The same per unit nominal area (J/m²).
    pub dissipated_j_per_m2: f64,
    /// Frictional work ΔA Σ q·Δg summed over the cycle's steps (J): equals the loop area for a
    /// closed loop, up to the time discretisation.
    pub frictional_work_j: f64,
}

/// Result of an oscillating history.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct OscillationResult {
    /// Every step, starting with the initial state (step 0: zero load).
    pub steps: Vec<TangentialStep>,
    /// One entry per cycle.
    pub cycles: Vec<CycleEnergy>,
    /// Set-up facts, including the quasi-identical assumption.
    pub metadata: TangentialMetadata,
    /// Total wall time (s).
    pub wall_time_s: f64,
}

/// Run an oscillating history from the virgin state (the solver is reset first).
/// `progress(k, total)` is called after each step.
///
/// Errors: zero or non-finite amplitude, fewer than 1 cycle or 4 steps per cycle
/// ([`Error::InvalidParameter`]); any step's errors.
pub fn oscillate(
    solver: &mut TangentialSolver,
    oscillation: &Oscillation,
    progress: impl FnMut(usize, usize),
) -> Result<OscillationResult> {
    let start = Instant::now();
    let a = oscillation.amplitude.vector();
    let am = a[0].hypot(a[1]);
    if !(am.is_finite() && am > 0.0) {
        return Err(Error::param(
            "amplitude",
            format!("oscillation amplitude must be finite and non-zero, got {a:?}"),
        ));
    }
    if oscillation.cycles == 0 {
        return Err(Error::param("cycles", "must be at least 1"));
    }
    if oscillation.steps_per_cycle < 4 {
        return Err(Error::param(
            "steps_per_cycle",
            format!("must be at least 4, got {}", oscillation.steps_per_cycle),
        ));
    }
    let n = oscillation.steps_per_cycle;
    run_history(
        solver,
        oscillation.cycles,
        n,
        |k| {
            let phase = 2.0 * std::f64::consts::PI * k as f64 / n as f64;
            // sin of exact multiples of π are set to zero so that cycles close exactly.
            let s = if (2 * k) % n == 0 { 0.0 } else { phase.sin() };
            oscillation.amplitude.scaled(s)
        },
        start,
        progress,
    )
}

/// A closed elliptical path of the tangential load in the plane, from the virgin state:
/// `control(θ) = major · sin θ + minor · (1 − cos θ)`, `θ = 2π k / steps_per_cycle`: the ellipse
/// with semi-axes `major` and `minor` centred on `minor`, through the origin, travelled once per
/// cycle; a circle of radius `|major|` when `minor ⟂ major` and `|minor| = |major|`; the
/// to-and-fro of [`Oscillation`] when `minor = 0`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EllipticalPath {
    /// First semi-axis: displacement (m) or force (N), with its direction.
    pub major: Control,
    /// Second semi-axis, same unit and control (m or N).
    pub minor: [f64; 2],
    /// Number of cycles (≥ 1).
    pub cycles: usize,
    /// Steps per cycle (≥ 4, a multiple of 4 keeps the extremes on steps).
    pub steps_per_cycle: usize,
}

/// Run an elliptical path from the virgin state (the solver is reset first). The energy of a
/// cycle is `∮ T·dδ` over both components. Errors as [`oscillate`], and a non-finite minor axis.
pub fn oscillate_elliptical(
    solver: &mut TangentialSolver,
    path: &EllipticalPath,
    progress: impl FnMut(usize, usize),
) -> Result<OscillationResult> {
    let start = Instant::now();
    let (a, b) = (path.major.vector(), path.minor);
    if !(a[0].is_finite() && a[1].is_finite() && a[0].hypot(a[1]) > 0.0) {
        return Err(Error::param(
            "major",
            format!("the path's first semi-axis must be finite and non-zero, got {a:?}"),
        ));
    }
    if !(b[0].is_finite() && b[1].is_finite()) {
        return Err(Error::param(
            "minor",
            format!("the path's second semi-axis must be finite, got {b:?}"),
        ));
    }
    if path.cycles == 0 {
        return Err(Error::param("cycles", "must be at least 1"));
    }
    if path.steps_per_cycle < 4 {
        return Err(Error::param(
            "steps_per_cycle",
            format!("must be at least 4, got {}", path.steps_per_cycle),
        ));
    }
    let n = path.steps_per_cycle;
    run_history(
        solver,
        path.cycles,
        n,
        |k| {
            let phase = 2.0 * std::f64::consts::PI * k as f64 / n as f64;
            // Exact at multiples of π/2 so that cycles close exactly.
            let (s, c) = if (4 * k) % n != 0 {
                (phase.sin(), 1.0 - phase.cos())
            } else {
                match (4 * k / n) % 4 {
                    0 => (0.0, 0.0),
                    1 => (1.0, 1.0),
                    2 => (0.0, 2.0),
                    _ => (-1.0, 1.0),
                }
            };
            path.major
                .with_vector([a[0] * s + b[0] * c, a[1] * s + b[1] * c])
        },
        start,
        progress,
    )
}

/// Run `control(k)`, `k = 1 ..= cycles·n`, from the virgin state; energies per cycle.
fn run_history(
    solver: &mut TangentialSolver,
    cycles: usize,
    n: usize,
    control: impl Fn(usize) -> Control,
    start: Instant,
    mut progress: impl FnMut(usize, usize),
) -> Result<OscillationResult> {
    solver.reset();
    let total = cycles * n;
    let mut steps = Vec::with_capacity(total + 1);
    steps.push(TangentialStep::INITIAL);
    for k in 1..=total {
        steps.push(solver.step(control(k))?);
        progress(k, total);
    }
    let cycles = cycle_energies(&steps, cycles, n, solver.metadata().nominal_area_m2);
    Ok(OscillationResult {
        steps,
        cycles,
        metadata: solver.metadata().clone(),
        wall_time_s: start.elapsed().as_secs_f64(),
    })
}

/// The energy balance of each of the `cycles` cycles of `n` steps of a history `steps` (step 0
/// the initial state, cycle `c` from step `(c−1)·n` to `c·n`) on a patch of nominal area
/// `area_m2` (m²): the loop area ([`loop_area`]) and the frictional work of the cycle's steps.
pub fn cycle_energies(
    steps: &[TangentialStep],
    cycles: usize,
    n: usize,
    area_m2: f64,
) -> Vec<CycleEnergy> {
    (0..cycles)
        .map(|c| {
            let w = loop_area(&steps[c * n..=(c + 1) * n]);
            let fw = steps[c * n + 1..=(c + 1) * n]
                .iter()
                .map(|s| s.frictional_work_j)
                .sum();
            CycleEnergy {
                cycle: c + 1,
                dissipated_j: w,
                dissipated_j_per_m2: w / area_m2,
                frictional_work_j: fw,
            }
        })
        .collect()
}

/// `∫ T·dδ` along consecutive steps, trapezoidal rule (J).
pub fn loop_area(steps: &[TangentialStep]) -> f64 {
    steps
        .windows(2)
        .map(|w| {
            let (a, b) = (&w[0], &w[1]);
            (0..2)
                .map(|c| 0.5 * (a.force_n[c] + b.force_n[c]) * (b.shift_m[c] - a.shift_m[c]))
                .sum::<f64>()
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn steel() -> Material {
        Material::STEEL
    }

    fn blob(nx: usize, ny: usize) -> Array2<f64> {
        // Two separate contact spots and a few isolated points.
        Array2::from_shape_fn((nx, ny), |(i, j)| {
            let r1 = ((i as f64 - 4.0).powi(2) + (j as f64 - 5.0).powi(2)).sqrt();
            let r2 = ((i as f64 - 12.0).powi(2) + (j as f64 - 3.0).powi(2)).sqrt();
            let mut p = 0.0;
            if r1 < 3.0 {
                p += 1e6 * (1.0 - r1 / 3.0);
            }
            if r2 < 2.0 {
                p += 2e6 * (1.0 - r2 / 2.0);
            }
            if (i * 7 + j * 3) % 23 == 0 {
                p += 5e5;
            }
            p
        })
    }

    fn solver(
        p: &Array2<f64>,
        boundary: Boundary,
        op: Operator,
        mu: f64,
    ) -> Result<TangentialSolver> {
        TangentialSolver::new(
            &TangentialProblem {
                pressure: p,
                dx: 1e-6,
                dy: 1.5e-6,
                boundary,
                friction_coefficient: mu,
                body1: steel(),
                body2: steel(),
            },
            TangentialOptions {
                operator: op,
                ..TangentialOptions::default()
            },
        )
    }

    #[test]
    fn dense_and_fft_operators_agree() {
        let p = blob(16, 11);
        for boundary in [Boundary::ZeroPadded, Boundary::Periodic] {
            let d = solver(&p, boundary, Operator::Dense, 0.5).unwrap();
            let f = solver(&p, boundary, Operator::Fft, 0.5).unwrap();
            assert_eq!(d.metadata().operator, Operator::Dense);
            assert_eq!(f.metadata().operator, Operator::Fft);
            let q: Vec<[f64; 2]> = (0..d.contact_points().len())
                .map(|k| [(k as f64 * 0.37).sin() * 1e5, (k as f64 * 0.91).cos() * 1e5])
                .collect();
            let ud = d.apply_compliance(&q);
            let uf = f.apply_compliance(&q);
            let scale = ud
                .iter()
                .map(|u| u[0].abs().max(u[1].abs()))
                .fold(0.0, f64::max);
            for (a, b) in ud.iter().zip(&uf) {
                // The dense path's kernel table is stored in single precision.
                assert!(
                    (a[0] - b[0]).abs() < 1e-6 * scale,
                    "{boundary:?} {a:?} {b:?}"
                );
                assert!(
                    (a[1] - b[1]).abs() < 1e-6 * scale,
                    "{boundary:?} {a:?} {b:?}"
                );
            }
            // And the solutions of a step agree.
            let (mut d, mut f) = (d, f);
            let c = Control::Displacement([5e-12, -2e-12]);
            let sd = d.step(c).unwrap();
            let sf = f.step(c).unwrap();
            assert!(
                sd.stick_fraction > 0.05 && sd.stick_fraction < 0.95,
                "{sd:?}"
            );
            assert!((sd.force_n[0] / sf.force_n[0] - 1.0).abs() < 1e-5);
            assert!((sd.force_n[1] / sf.force_n[1] - 1.0).abs() < 1e-5);
        }
    }

    /// The Anderson-accelerated solver and FISTA (its fallback) solve the same quadratic
    /// program: the same traction to the tolerance, in both controls, with Anderson in fewer
    /// products.
    #[test]
    fn anderson_and_fista_reach_the_same_solution() {
        let p = blob(16, 11);
        for boundary in [Boundary::ZeroPadded, Boundary::Periodic] {
            let s = TangentialSolver::new(
                &TangentialProblem {
                    pressure: &p,
                    dx: 1e-6,
                    dy: 1.5e-6,
                    boundary,
                    friction_coefficient: 0.5,
                    body1: steel(),
                    body2: steel(),
                },
                TangentialOptions {
                    tolerance: 1e-10,
                    ..TangentialOptions::default()
                },
            )
            .unwrap();
            let n = s.contact_points().len();
            let zero = vec![[0.0; 2]; n];
            // Displacement control from the virgin state: b = δ.
            let b = vec![[4e-12, -1.5e-12]; n];
            // Load control: b = 0 and Σ q fixed at 40 % of the friction limit.
            let sum = {
                let r: f64 = s.limit.iter().sum();
                [0.3 * r, 0.25 * r]
            };
            for (b, force_sum) in [(b, None), (zero.clone(), Some(sum))] {
                let Ok(Anderson::Converged(a)) = s.solve_anderson(&b, force_sum, zero.clone())
                else {
                    panic!("Anderson did not converge");
                };
                let f = s.solve_fista(&b, force_sum, zero.clone(), 0).unwrap();
                let stick = (0..n)
                    .filter(|&k| a.q[k][0].hypot(a.q[k][1]) < s.limit[k] * (1.0 - 1e-6))
                    .count();
                assert!(
                    stick > 0 && stick < n,
                    "{boundary:?}: partial slip, {stick}/{n}"
                );
                for k in 0..n {
                    for c in 0..2 {
                        assert!(
                            (a.q[k][c] - f.q[k][c]).abs() < 1e-7 * s.max_limit,
                            "{boundary:?} {force_sum:?} point {k}: {:?} vs {:?}",
                            a.q[k],
                            f.q[k]
                        );
                    }
                }
                if force_sum.is_some() {
                    for c in 0..2 {
                        assert!((a.lambda[c] - f.lambda[c]).abs() < 1e-6 * f.lambda[c].abs());
                    }
                }
                assert!(
                    a.iterations < f.iterations,
                    "{boundary:?} {force_sum:?}: Anderson {} vs FISTA {} products",
                    a.iterations,
                    f.iterations
                );
            }
        }
    }

    /// The compliance product sums every target in a fixed order and the step solver is
    /// sequential apart from it: a history is bit-identical in pools of 1 and 2 threads.
    #[test]
    fn results_do_not_depend_on_the_thread_count() {
        let p = blob(16, 11);
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let mut s = solver(&p, Boundary::Periodic, Operator::Dense, 0.5).unwrap();
                let d = s.gross_slip_displacement([1.0, 0.3]).unwrap();
                let r = oscillate(
                    &mut s,
                    &Oscillation {
                        amplitude: Control::Displacement([0.8 * d, 0.24 * d]),
                        cycles: 1,
                        steps_per_cycle: 8,
                    },
                    |_, _| {},
                )
                .unwrap();
                r.steps
                    .iter()
                    .flat_map(|s| [s.force_n[0].to_bits(), s.force_n[1].to_bits()])
                    .collect::<Vec<u64>>()
            })
        };
        assert_eq!(run(1), run(2));
    }

    #[test]
    fn load_control_returns_the_imposed_force_and_inverts_displacement_control() {
        let p = blob(16, 11);
        let mut s = solver(&p, Boundary::ZeroPadded, Operator::Dense, 0.5).unwrap();
        let d = s.step(Control::Displacement([3e-12, 1e-12])).unwrap();
        assert!(d.stick_fraction > 0.0 && d.stick_fraction < 1.0, "{d:?}");
        let mut s2 = solver(&p, Boundary::ZeroPadded, Operator::Dense, 0.5).unwrap();
        let f = s2.step(Control::Force(d.force_n)).unwrap();
        for c in 0..2 {
            assert!((f.force_n[c] - d.force_n[c]).abs() < 1e-9 * s.friction_limit_n());
            assert!(
                (f.shift_m[c] - d.shift_m[c]).abs() < 1e-5 * 3e-12,
                "{f:?} {d:?}"
            );
        }
    }

    #[test]
    fn gross_slip_saturates_every_point_and_load_control_refuses_it() {
        let p = blob(16, 11);
        let mut s = solver(&p, Boundary::Periodic, Operator::Auto, 0.3).unwrap();
        let st = s.step(Control::Displacement([1e-5, 0.0])).unwrap();
        assert_eq!(st.stick_fraction, 0.0);
        assert!((st.force_n[0] / s.friction_limit_n() - 1.0).abs() < 1e-9);
        assert!(st.force_n[1].abs() < 1e-9 * s.friction_limit_n());
        let lim = s.friction_limit_n();
        let e = s.step(Control::Force([lim, 0.0])).unwrap_err();
        assert!(e.to_string().contains("friction limit"), "{e}");
    }

    #[test]
    fn gross_slip_displacement_separates_partial_from_gross_slip() {
        let p = blob(16, 11);
        let mut s = solver(&p, Boundary::ZeroPadded, Operator::Dense, 0.4).unwrap();
        let d = s.gross_slip_displacement([1.0, 0.0]).unwrap();
        let below = s.step(Control::Displacement([0.97 * d, 0.0])).unwrap();
        assert!(below.stick_fraction > 0.0, "{below:?}");
        s.reset();
        let above = s.step(Control::Displacement([1.001 * d, 0.0])).unwrap();
        assert_eq!(above.stick_fraction, 0.0, "{above:?}");
    }

    #[test]
    fn bad_inputs_are_named() {
        let p = blob(8, 8);
        for mu in [0.0, -0.2, f64::NAN] {
            let e = solver(&p, Boundary::Periodic, Operator::Auto, mu).unwrap_err();
            assert!(e.to_string().contains("friction_coefficient"), "{e}");
        }
        let zero = Array2::<f64>::zeros((8, 8));
        let e = solver(&zero, Boundary::Periodic, Operator::Auto, 0.5).unwrap_err();
        assert!(e.to_string().contains("no contact"), "{e}");
        let mut neg = p.clone();
        neg[[2, 3]] = -1.0;
        let e = solver(&neg, Boundary::Periodic, Operator::Auto, 0.5).unwrap_err();
        assert!(e.to_string().contains("(2, 3)"), "{e}");
        let mut s = solver(&p, Boundary::Periodic, Operator::Auto, 0.5).unwrap();
        let e = oscillate(
            &mut s,
            &Oscillation {
                amplitude: Control::Displacement([0.0, 0.0]),
                cycles: 1,
                steps_per_cycle: 8,
            },
            |_, _| {},
        )
        .unwrap_err();
        assert!(e.to_string().contains("amplitude"), "{e}");
    }

    /// `set_pressure` keeps the history on the solver's points: a field with contact outside
    /// them, of another shape or without contact is refused; a point that leaves contact drops
    /// its traction, and the stick fraction counts the points in contact only.
    #[test]
    fn set_pressure_follows_the_contact_within_the_solver_points() {
        let p = blob(16, 11);
        let mut s = solver(&p, Boundary::ZeroPadded, Operator::Dense, 0.5).unwrap();
        s.step(Control::Displacement([2e-12, 0.0])).unwrap();
        let mut wider = p.clone();
        wider[[15, 10]] += 1e5;
        assert!(p[[15, 10]] == 0.0);
        let e = s.set_pressure(&wider).unwrap_err().to_string();
        assert!(e.contains("outside the solver"), "{e}");
        let e = s
            .set_pressure(&Array2::zeros((16, 10)))
            .unwrap_err()
            .to_string();
        assert!(e.contains("shape"), "{e}");
        let e = s
            .set_pressure(&Array2::zeros((16, 11)))
            .unwrap_err()
            .to_string();
        assert!(e.contains("no contact"), "{e}");
        // Half the pressure, the second spot released.
        let mut less = p.mapv(|v| 0.5 * v);
        for ((i, j), v) in less.indexed_iter_mut() {
            if ((i as f64 - 12.0).powi(2) + (j as f64 - 3.0).powi(2)).sqrt() < 2.0 {
                *v = 0.0;
            }
        }
        s.set_pressure(&less).unwrap();
        let in_contact = less.iter().filter(|&&v| v > 0.0).count();
        assert_eq!(s.points_in_contact(), in_contact);
        let st = s.step(Control::Displacement([2e-12, 0.0])).unwrap();
        let (qx, qy) = s.traction();
        for ((i, j), &v) in less.indexed_iter() {
            if v == 0.0 {
                assert_eq!((qx[[i, j]], qy[[i, j]]), (0.0, 0.0));
            } else {
                assert!(qx[[i, j]].hypot(qy[[i, j]]) <= 0.5 * v * (1.0 + 1e-12));
            }
        }
        let sticking = s.stick_mask().iter().filter(|b| **b).count();
        assert_eq!(st.stick_fraction, sticking as f64 / in_contact as f64);
        assert!(
            (s.friction_limit_n() - 0.5 * less.sum() * 1.5e-12).abs() < 1e-9 * s.friction_limit_n()
        );
    }

    #[test]
    fn iteration_cap_is_non_convergence() {
        let p = blob(16, 11);
        let mut s = TangentialSolver::new(
            &TangentialProblem {
                pressure: &p,
                dx: 1e-6,
                dy: 1e-6,
                boundary: Boundary::ZeroPadded,
                friction_coefficient: 0.5,
                body1: steel(),
                body2: steel(),
            },
            TangentialOptions {
                max_iterations: 2,
                tolerance: 1e-14,
                operator: Operator::Auto,
            },
        )
        .unwrap();
        match s.step(Control::Displacement([1e-8, 0.0])) {
            Err(Error::NonConvergence { iterations, .. }) => assert_eq!(iterations, 2),
            other => panic!("expected NonConvergence, got {other:?}"),
        }
    }
}
