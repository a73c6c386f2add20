//! Multi-harmonic balance: residual, Jacobian and Newton's method at one frequency.
//!
//! Every coordinate is expanded in the retained harmonics ([`crate::dynamics::aft::Harmonics`]),
//! `q(t) = Q0 + Σ_k (Q_k^c·cos kωt + Q_k^s·sin kωt)`, and the equation of motion is balanced
//! harmonic by harmonic (Galerkin):
//!
//! ```text
//! R(Q, ω) = Z(ω)·Q + Σ_e (P_e ⊗ I)ᵀ·f̂_e((P_e ⊗ I)·Q) − level·F̂ = 0
//! Z(ω) on order k:  [K − (kω)²M,  kωC;  −kωC,  K − (kω)²M]   (order 0: K)
//! ```
//!
//! with `f̂_e` the element force harmonics by AFT. Two formulations of the same equations:
//!
//! * [`Formulation::Coordinates`]: unknowns `Q` (`n × len`), the physical DOFs of a lumped model
//!   or the modal coordinates of a reduced modal model. Jacobian
//!   `Z + Σ_e (P_e ⊗ I)ᵀ J_e (P_e ⊗ I)`, assembled by contracting the element-DOF index and the
//!   harmonic index separately (one matrix product over all elements, never the big sparse
//!   Kronecker products).
//! * [`Formulation::Receptance`]: unknowns the element displacements `U` (`n_c × len`, `n_c` the
//!   contact DOFs), condensed with the receptance `H(Ω) = (K − Ω²M + iΩC)⁻¹` per harmonic
//!   (see [`crate::dynamics::condensation`]): `U − G(ω)·(level·F̂ − f̂(U)) = 0`,
//!   `G_k = P·H(kω)·Pᵀ`. The problem size is set by the contact DOFs, not by the model.
//!
//! A cyclic sector ([`crate::dynamics::cyclic`]) is solved in the coordinates formulation on the
//! harmonics `z` of its coordinates off the right boundary: `Q = T·z`, the balance projected by
//! `Tᵀ`, and elements across the boundary evaluated on `A·z` (this sector's and the next sector's
//! harmonics), Jacobian `Tᵀ·Z·T + Aᵀ·J·A`. The products are dense: meant for lumped sectors of
//! tens to a few hundred DOFs.
//!
//! [`FormulationChoice::Auto`] takes the one with fewer unknowns and says which
//! ([`HbmSystem::formulation`]). Newton's method with a backtracking line search;
//! convergence when `‖R‖ ≤ tolerance·(‖level·F̂‖ + ‖f̂_nl‖)` (coordinates) or
//! `‖R‖ ≤ tolerance·(‖U_lin‖ + ‖G·f̂‖)` (receptance).

use crate::core::error::{Error, Result};
use crate::dynamics::aft::{self, AftSettings, ElementCycle, Harmonics};
use crate::dynamics::condensation::Receptance;
use crate::dynamics::cyclic;
use crate::dynamics::model::Structure;
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use std::time::Instant;

/// Elements per block of the Jacobian assembly ([`HbmSystem::element_jacobian`]).
const JACOBIAN_BLOCK_ELEMENTS: usize = 8;
/// Fewest elements a parallel task evaluates: one element's AFT costs microseconds (a single
/// joint of a modal model), less than waking a worker thread, so a structure with a handful of
/// elements is evaluated on the calling thread (which is usually a parallel task already, e.g.
/// one level of an identification).
const PARALLEL_MIN_ELEMENTS: usize = 4;

/// Harmonic force `F(t) = level·(force·cos(e·ω·t) + force_sin·sin(e·ω·t))` on the coordinates,
/// `e` the excitation's harmonic (N per unit level for physical DOFs; `Φᵀ·f` for modal
/// coordinates). A force with a phase per DOF, `f_i·cos(eωt − θ_i)`, has
/// `force_i = f_i·cos θ_i` and `force_sin_i = f_i·sin θ_i`.
#[derive(Debug, Clone, PartialEq)]
pub struct Excitation {
    /// In-phase (cosine) force on each coordinate per unit level (N for physical DOFs; `Φᵀ·f` for
    /// modal coordinates).
    pub force: DVector<f64>,
    /// Harmonic order `e` of the excitation (usually 1).
    pub harmonic: usize,
    /// Quadrature (sine) force per unit level, like `force`; `None`: none (a force in phase on
    /// every coordinate).
    pub force_sin: Option<DVector<f64>>,
}

/// Which unknowns to solve for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FormulationChoice {
    /// The formulation with fewer unknowns.
    Auto,
    /// Unknowns: harmonics of the structure's coordinates ([`Formulation::Coordinates`]).
    Coordinates,
    /// Unknowns: harmonics of the element displacements ([`Formulation::Receptance`]).
    Receptance,
}

/// The formulation in use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Formulation {
    /// Unknowns: harmonics of the structure's coordinates (physical or modal).
    Coordinates,
    /// Unknowns: harmonics of the element displacements (receptance condensation).
    Receptance,
}

/// Newton settings.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct NewtonSettings {
    /// Relative residual tolerance.
    pub tolerance: f64,
    /// Iteration cap.
    pub max_iterations: usize,
}

impl Default for NewtonSettings {
    fn default() -> Self {
        Self {
            tolerance: 1e-7,
            max_iterations: 40,
        }
    }
}

/// Residual and (optionally) its derivatives at one point.
#[derive(Debug, Clone)]
pub struct Evaluation {
    /// Harmonic-balance residual `R(z, ω, level)`: dynamic stiffness times the unknowns plus the
    /// elements' force harmonics minus the excitation (N).
    pub residual: DVector<f64>,
    /// `∂R/∂z` (empty `0 × 0` when not requested).
    pub jacobian: DMatrix<f64>,
    /// `∂R/∂ω`.
    pub d_omega: DVector<f64>,
    /// `∂R/∂level`.
    pub d_level: DVector<f64>,
    /// Scale of the residual (convergence is relative to it).
    pub scale: f64,
    /// Largest AFT periodicity error over the elements.
    pub periodicity_error: f64,
    /// Elements whose AFT state did not become periodic.
    pub non_periodic: usize,
    /// Start state of each element's periodic cycle with its sensitivity (warm start of a
    /// nearby evaluation, see [`HbmSystem::evaluate_from`]).
    pub element_states: Vec<aft::WarmStart>,
}

impl Evaluation {
    /// `‖R‖ / scale`.
    pub fn relative_residual(&self) -> f64 {
        self.residual.norm() / self.scale.max(f64::MIN_POSITIVE)
    }
}

/// One converged (or reported) harmonic-balance solution.
#[derive(Debug, Clone)]
pub struct HbmPoint {
    /// Angular frequency of the fundamental (rad/s).
    pub omega: f64,
    /// Excitation level (multiplies [`Excitation::force`]).
    pub level: f64,
    /// Unknowns of the formulation in use.
    pub z: DVector<f64>,
    /// Newton (corrector) iterations spent.
    pub iterations: usize,
    /// Relative residual at the end.
    pub residual: f64,
    /// The relative residual met the tolerance.
    pub converged: bool,
    /// Largest AFT periodicity error over the elements (relative to the state scale).
    pub periodicity_error: f64,
    /// Wall-clock time of the solve (s).
    pub wall_time_s: f64,
}

/// A structure with its harmonic basis and excitation, ready to be solved.
pub struct HbmSystem<'a> {
    /// The structure with its elements attached.
    pub structure: &'a Structure,
    /// The harmonic basis (highest harmonic, odd only or all, time samples).
    pub harmonics: Harmonics,
    /// The harmonic force.
    pub excitation: Excitation,
    /// Settings of the alternating frequency–time evaluation of the elements.
    pub aft: AftSettings,
    /// Settings of the Newton solve.
    pub newton: NewtonSettings,
    formulation: Formulation,
    /// All element maps stacked (`n_c × w`): `[P_e]`, or `[P_e | P'_e]` (`w = 2n`) when an
    /// element joins a cyclic sector to the next one.
    stacked_map: DMatrix<f64>,
    /// First row of each element in the stack.
    offsets: Vec<usize>,
    /// Coordinates the element maps act on: `n`, or `2n` (this sector's and the next's).
    width: usize,
    /// The cyclic sector's operators (`None`: a structure on its own).
    cyclic: Option<CyclicOperators>,
    /// Harmonics (`n × len`, coordinate-major) of a static force that does not scale with the
    /// level (a preload: harmonic 0 only); `None`: none.
    static_force: Option<DVector<f64>>,
}

/// The operators of a cyclic sector (see [`crate::dynamics::cyclic`]).
struct CyclicOperators {
    /// `T` (`n·len × m·len`): the sector's harmonics from the unknowns.
    expansion: DMatrix<f64>,
    /// `A` (`w·len × m·len`): the harmonics the element maps act on from the unknowns, `T`
    /// stacked with `(I ⊗ S(φ))·T` (the next sector) when `w = 2n`.
    element_expansion: DMatrix<f64>,
}

/// Jacobian storage (bytes) below which [`HbmSystem::new`] does not consult the available
/// memory (64 MiB: about 1500 unknowns).
const JACOBIAN_BYTES_ALWAYS_AVAILABLE: u64 = 64 << 20;

/// The balance `R = lin + f̂_nl − level·F̂ − F̂0` on the unknowns (linear forces `lin` and their
/// frequency derivative `dlin`, element forces `fnl`, excitation `fex` per unit level, static
/// force `f0`), its scale for the convergence test, and the Jacobian `jac` with the elements'
/// periodicity.
#[allow(clippy::too_many_arguments)]
fn balance(
    lin: DVector<f64>,
    dlin: DVector<f64>,
    fnl: DVector<f64>,
    fex: DVector<f64>,
    f0: Option<DVector<f64>>,
    level: f64,
    jacobian: DMatrix<f64>,
    forces: &[aft::ElementHarmonics],
) -> Evaluation {
    let mut residual = &lin + &fnl - &fex * level;
    let mut scale = (&fex * level).norm() + fnl.norm();
    if let Some(f0) = f0 {
        residual -= &f0;
        scale += f0.norm();
    }
    let (perr, nonper) = periodicity(forces);
    Evaluation {
        residual,
        jacobian,
        d_omega: dlin,
        d_level: -fex,
        scale,
        periodicity_error: perr,
        non_periodic: nonper,
        element_states: element_states(forces),
    }
}

impl<'a> HbmSystem<'a> {
    /// Set up the harmonic-balance problem. The excitation harmonic must be retained; with the
    /// receptance formulation the structure needs a non-singular dynamic stiffness.
    pub fn new(
        structure: &'a Structure,
        harmonics: Harmonics,
        excitation: Excitation,
        choice: FormulationChoice,
    ) -> Result<Self> {
        if excitation.force.len() != structure.n() {
            return Err(Error::param(
                "excitation",
                format!(
                    "force vector has {} entries for {} coordinates",
                    excitation.force.len(),
                    structure.n()
                ),
            ));
        }
        if excitation
            .force_sin
            .as_ref()
            .is_some_and(|f| f.len() != structure.n())
        {
            return Err(Error::param(
                "excitation",
                format!(
                    "quadrature force vector has {} entries for {} coordinates",
                    excitation.force_sin.as_ref().map_or(0, |f| f.len()),
                    structure.n()
                ),
            ));
        }
        if harmonics.index_of(excitation.harmonic).is_none() {
            return Err(Error::param(
                "excitation.harmonic",
                format!(
                    "harmonic {} is not among the retained orders {:?}",
                    excitation.harmonic,
                    harmonics.orders()
                ),
            ));
        }
        let n = structure.n();
        let nc = structure.contact_dofs();
        let across = structure.has_elements_across();
        if across && structure.cyclic.is_none() {
            return Err(Error::param(
                "map",
                "an element joins a next sector, but the structure is not cyclic",
            ));
        }
        let width = if across { 2 * n } else { n };
        let mut stacked_map = DMatrix::zeros(nc, width);
        let mut offsets = Vec::with_capacity(structure.elements.len());
        let mut row = 0;
        for e in &structure.elements {
            offsets.push(row);
            let d = e.element.dofs();
            stacked_map.view_mut((row, 0), (d, n)).copy_from(&e.map);
            if let Some(p) = &e.neighbour_map {
                stacked_map.view_mut((row, n), (d, n)).copy_from(p);
            }
            row += d;
        }
        let cyclic = structure.cyclic.as_ref().map(|c| {
            let expansion = c.expansion(n, &harmonics);
            let element_expansion = if across {
                let next = cyclic::shift_all(n, &cyclic::shift_operator(&harmonics, c.phase()))
                    * &expansion;
                let mut a = DMatrix::zeros(2 * expansion.nrows(), expansion.ncols());
                a.rows_mut(0, expansion.nrows()).copy_from(&expansion);
                a.rows_mut(expansion.nrows(), expansion.nrows())
                    .copy_from(&next);
                a
            } else {
                expansion.clone()
            };
            CyclicOperators {
                expansion,
                element_expansion,
            }
        });
        if cyclic.is_some() && choice == FormulationChoice::Receptance {
            return Err(Error::param(
                "formulation",
                "a cyclic sector is solved in the coordinates formulation (the receptance \
                 condensation of the sector's boundary conditions is not implemented)",
            ));
        }
        let formulation = match choice {
            FormulationChoice::Coordinates => Formulation::Coordinates,
            FormulationChoice::Receptance => Formulation::Receptance,
            FormulationChoice::Auto => {
                if nc < n && cyclic.is_none() {
                    Formulation::Receptance
                } else {
                    Formulation::Coordinates
                }
            }
        };
        let system = Self {
            structure,
            harmonics,
            excitation,
            aft: AftSettings::default(),
            newton: NewtonSettings::default(),
            formulation,
            stacked_map,
            offsets,
            width,
            cyclic,
            static_force: None,
        };
        // The Newton iteration holds the dense Jacobian, its LU factors and a copy. Checked
        // against the available memory only when large: the identification builds a system per
        // row and evaluation, and reading the available memory would then dominate.
        let unknowns = system.unknowns();
        let jacobian_bytes = (unknowns as u64).pow(2).saturating_mul(8 * 3);
        if jacobian_bytes > JACOBIAN_BYTES_ALWAYS_AVAILABLE {
            crate::core::limits::check_memory(
                "sweep.harmonics",
                jacobian_bytes,
                &format!("a harmonic-balance Jacobian of {unknowns} unknowns"),
            )?;
        }
        Ok(system)
    }

    /// The system with a static force `f0` (N per coordinate) on top of the harmonic
    /// excitation: a preload that does not scale with the level, balanced by the harmonic-0
    /// (mean) part of the response, `Z₀·Q₀ + f̂_nl,0 = f0` (the static equilibrium about which the
    /// structure vibrates, solved with the vibration). Needs harmonic 0 in the basis (`odd_only =
    /// false`) and the coordinates formulation. Errors name `static` or `formulation`.
    pub fn with_static_force(mut self, f0: &DVector<f64>) -> Result<Self> {
        let n = self.structure.n();
        if f0.len() != n {
            return Err(Error::param(
                "static",
                format!("force vector has {} entries for {n} coordinates", f0.len()),
            ));
        }
        if self.harmonics.orders().first() != Some(&0) {
            return Err(Error::param(
                "static",
                "a static force needs harmonic 0 (the mean) in the basis: set odd_only = false",
            ));
        }
        if self.formulation != Formulation::Coordinates {
            return Err(Error::param(
                "formulation",
                "a static force is solved in the coordinates formulation",
            ));
        }
        let len = self.harmonics.len();
        let mut f = DVector::zeros(n * len);
        for r in 0..n {
            f[r * len] = f0[r];
        }
        self.static_force = Some(f);
        Ok(self)
    }

    /// The formulation in use.
    pub fn formulation(&self) -> Formulation {
        self.formulation
    }

    /// Number of unknowns of the Newton problem.
    pub fn unknowns(&self) -> usize {
        let len = self.harmonics.len();
        match (self.formulation, &self.cyclic) {
            (Formulation::Coordinates, Some(c)) => c.expansion.ncols(),
            (Formulation::Coordinates, None) => self.structure.n() * len,
            (Formulation::Receptance, _) => self.structure.contact_dofs() * len,
        }
    }

    /// The cyclic symmetry the system is solved with (`None`: a structure on its own).
    pub fn cyclic(&self) -> Option<&crate::dynamics::cyclic::CyclicSymmetry> {
        self.cyclic.as_ref().and(self.structure.cyclic.as_ref())
    }

    /// Harmonics of the excitation per coordinate (`n × len`, coordinate-major), per unit level.
    pub fn excitation_harmonics(&self) -> DVector<f64> {
        let len = self.harmonics.len();
        let (ci, _) = self
            .harmonics
            .index_of(self.excitation.harmonic)
            .expect("checked in new");
        let mut f = DVector::zeros(self.structure.n() * len);
        for r in 0..self.structure.n() {
            f[r * len + ci] = self.excitation.force[r];
        }
        if let Some(fs) = &self.excitation.force_sin {
            let si = ci + 1;
            for r in 0..self.structure.n() {
                f[r * len + si] = fs[r];
            }
        }
        f
    }

    /// Element displacement harmonics `(P_e ⊗ I)·Q` of every element (`n_c × len`); for a
    /// cyclic sector `[P_e | P'_e]·A·z` (the unknowns `z` expanded to this sector's and the next
    /// sector's harmonics).
    fn element_displacements(&self, q: &DVector<f64>) -> DMatrix<f64> {
        let len = self.harmonics.len();
        let qm = match &self.cyclic {
            None => DMatrix::from_row_slice(self.structure.n(), len, q.as_slice()),
            Some(c) => {
                let x = &c.element_expansion * q;
                DMatrix::from_row_slice(self.width, len, x.as_slice())
            }
        };
        &self.stacked_map * qm
    }

    /// Force harmonics (and Jacobians) of every element for the element displacements `u`
    /// (`n_c × len`) at the fundamental frequency `omega` (rad/s).
    pub(crate) fn element_forces(
        &self,
        u: &DMatrix<f64>,
        omega: f64,
        warm: Option<&[aft::WarmStart]>,
        jacobian: bool,
    ) -> Vec<aft::ElementHarmonics> {
        let len = self.harmonics.len();
        self.structure
            .elements
            .par_iter()
            .zip(self.offsets.par_iter())
            .with_min_len(PARALLEL_MIN_ELEMENTS)
            .enumerate()
            .map(|(i, (e, &off))| {
                let d = e.element.dofs();
                let mut ue = vec![0.0; d * len];
                for c in 0..d {
                    for h in 0..len {
                        ue[c * len + h] = u[(off + c, h)];
                    }
                }
                aft::evaluate_from(
                    e.element.as_ref(),
                    &self.harmonics,
                    &ue,
                    omega,
                    warm.and_then(|w| w.get(i)),
                    jacobian,
                    &self.aft,
                )
            })
            .collect()
    }

    /// Element force harmonics stacked like the element displacements (`n_c × len`).
    pub(crate) fn stacked_forces(&self, forces: &[aft::ElementHarmonics]) -> DMatrix<f64> {
        self.stack(forces, |r| &r.forces)
    }

    /// The elements' frequency derivatives `∂f̂_e/∂ω` stacked like the element displacements
    /// (`n_c × len`; zero rows for rate-independent elements), or `None` when no element has
    /// one (rate-independent elements only, or no Jacobian asked for).
    pub(crate) fn stacked_force_rates(
        &self,
        forces: &[aft::ElementHarmonics],
    ) -> Option<DMatrix<f64>> {
        forces
            .iter()
            .any(|r| !r.d_omega.is_empty())
            .then(|| self.stack(forces, |r| &r.d_omega))
    }

    fn stack<'f>(
        &self,
        forces: &'f [aft::ElementHarmonics],
        part: impl Fn(&'f aft::ElementHarmonics) -> &'f [f64],
    ) -> DMatrix<f64> {
        let len = self.harmonics.len();
        let mut fe = DMatrix::zeros(self.stacked_map.nrows(), len);
        for (e, r) in forces.iter().enumerate() {
            let v = part(r);
            if v.is_empty() {
                continue;
            }
            let d = self.structure.elements[e].element.dofs();
            for c in 0..d {
                for h in 0..len {
                    fe[(self.offsets[e] + c, h)] = v[c * len + h];
                }
            }
        }
        fe
    }

    /// `Z(ω)·Q` and `∂(Z·Q)/∂ω` for coordinate harmonics `q` (`n × len`, coordinate-major).
    fn linear_forces(&self, q: &DVector<f64>, omega: f64) -> (DVector<f64>, DVector<f64>) {
        let s = self.structure;
        let (n, len) = (s.n(), self.harmonics.len());
        let mut out = DVector::zeros(n * len);
        let mut dout = DVector::zeros(n * len);
        let column = |idx: usize| DVector::from_iterator(n, (0..n).map(|r| q[r * len + idx]));
        let mut c = 0;
        for &k in self.harmonics.orders() {
            if k == 0 {
                let f = &s.stiffness * column(c);
                for r in 0..n {
                    out[r * len + c] = f[r];
                }
                c += 1;
                continue;
            }
            let kw = k as f64 * omega;
            let (a, b) = (column(c), column(c + 1));
            let (ka, kb) = (&s.stiffness * &a, &s.stiffness * &b);
            let (ma, mb) = (&s.mass * &a, &s.mass * &b);
            let (ca, cb) = (&s.damping * &a, &s.damping * &b);
            for r in 0..n {
                out[r * len + c] = ka[r] - kw * kw * ma[r] + kw * cb[r];
                out[r * len + c + 1] = kb[r] - kw * kw * mb[r] - kw * ca[r];
                let kk = k as f64;
                dout[r * len + c] = -2.0 * kk * kw * ma[r] + kk * cb[r];
                dout[r * len + c + 1] = -2.0 * kk * kw * mb[r] - kk * ca[r];
            }
            c += 2;
        }
        (out, dout)
    }

    /// `Z(ω)` as a dense matrix in the coordinate-major ordering.
    fn dynamic_stiffness(&self, omega: f64) -> DMatrix<f64> {
        let s = self.structure;
        let (n, len) = (s.n(), self.harmonics.len());
        let mut z = DMatrix::zeros(n * len, n * len);
        let mut c = 0;
        for &k in self.harmonics.orders() {
            if k == 0 {
                for r in 0..n {
                    for q in 0..n {
                        z[(r * len + c, q * len + c)] = s.stiffness[(r, q)];
                    }
                }
                c += 1;
                continue;
            }
            let kw = k as f64 * omega;
            for r in 0..n {
                for q in 0..n {
                    let d = s.stiffness[(r, q)] - kw * kw * s.mass[(r, q)];
                    let v = kw * s.damping[(r, q)];
                    z[(r * len + c, q * len + c)] = d;
                    z[(r * len + c, q * len + c + 1)] = v;
                    z[(r * len + c + 1, q * len + c + 1)] = d;
                    z[(r * len + c + 1, q * len + c)] = -v;
                }
            }
            c += 2;
        }
        z
    }

    /// `Σ_e (P_e ⊗ I)ᵀ J_e (P_e ⊗ I)`: contract the harmonic index with each element's Jacobian,
    /// then the element-DOF index with the stacked map by matrix products.
    ///
    /// The elements are taken in blocks of [`JACOBIAN_BLOCK_ELEMENTS`]: a block's contracted
    /// Jacobian `W` (rows: the block's element DOFs `c`; columns `(h, s, h')`) stays in cache and
    /// its buffer is reused, and `Wᵀ·P_block` is accumulated into one `len·n·len × n` product
    /// per thread (contiguous groups of blocks; summed at the end). The `n·len × n·len` Jacobian is that product read
    /// row-major: `J[(r,h),(s,h')] = Σ_c P[c,r]·W[(c,h),(s,h')]`.
    fn element_jacobian(&self, forces: &[aft::ElementHarmonics]) -> DMatrix<f64> {
        // `n` here is the width of the element maps: the coordinates, or this sector's and the
        // next sector's for elements across a cyclic sector's boundary.
        let (n, len) = (self.width, self.harmonics.len());
        let nc = self.stacked_map.nrows();
        let wlen = len * n * len;
        let n_el = self.structure.elements.len();
        let blocks: Vec<usize> = (0..n_el).step_by(JACOBIAN_BLOCK_ELEMENTS).collect();
        // One accumulator per thread: contiguous groups of blocks.
        let groups = rayon::current_num_threads().clamp(1, blocks.len().max(1));
        let per_group = blocks.len().div_ceil(groups);
        let prod = blocks
            .par_chunks(per_group.max(1))
            .map(|group| {
                let mut acc = DMatrix::<f64>::zeros(wlen, n);
                let mut w = Vec::<f64>::new();
                for &e0 in group {
                    let e1 = (e0 + JACOBIAN_BLOCK_ELEMENTS).min(n_el);
                    let r0 = self.offsets[e0];
                    let r1 = self.offsets.get(e1).copied().unwrap_or(nc);
                    w.clear();
                    w.resize((r1 - r0) * wlen, 0.0);
                    // W[(c,h),(s,h')] = Σ_c' J_e[(c,h),(c',h')]·P_e[c',s], stored row c,
                    // columns (h,s,h').
                    for e in e0..e1 {
                        let el = &self.structure.elements[e];
                        let d = el.element.dofs();
                        let je = &forces[e].jacobian;
                        let dl = d * len;
                        for c in 0..d {
                            let wrow = &mut w[(self.offsets[e] - r0 + c) * wlen..][..wlen];
                            for h in 0..len {
                                let jrow = &je[(c * len + h) * dl..(c * len + h + 1) * dl];
                                for cp in 0..d {
                                    let jblock = &jrow[cp * len..(cp + 1) * len];
                                    for s in 0..n {
                                        let p = self.stacked_map[(self.offsets[e] + cp, s)];
                                        if p == 0.0 {
                                            continue;
                                        }
                                        let out = &mut wrow[h * n * len + s * len..][..len];
                                        for (o, j) in out.iter_mut().zip(jblock) {
                                            *o += p * j;
                                        }
                                    }
                                }
                            }
                        }
                    }
                    // Column-major (wlen × rows) view of the block's W is Wᵀ.
                    let wt = nalgebra::DMatrixView::from_slice(&w, wlen, r1 - r0);
                    acc.gemm(1.0, &wt, &self.stacked_map.rows(r0, r1 - r0), 1.0);
                }
                acc
            })
            .reduce(
                || DMatrix::zeros(wlen, n),
                |mut a, b| {
                    a += &b;
                    a
                },
            );
        // `prod`'s column-major data is J row-major, i.e. Jᵀ column-major.
        let nn = n * len;
        DMatrix::from_vec(nn, nn, prod.data.into()).transpose()
    }

    /// Residual at `(z, ω, level)`, with the Jacobian `∂R/∂z` when `jacobian` is set.
    pub fn evaluate(&self, z: &DVector<f64>, omega: f64, level: f64, jacobian: bool) -> Evaluation {
        self.evaluate_from(z, omega, level, jacobian, None)
    }

    /// [`HbmSystem::evaluate`] with each element's search for its periodic state started from
    /// `warm` (the [`Evaluation::element_states`] of a nearby point): the same result within
    /// the AFT's periodicity tolerance, in fewer periods.
    pub fn evaluate_from(
        &self,
        z: &DVector<f64>,
        omega: f64,
        level: f64,
        jacobian: bool,
        warm: Option<&[aft::WarmStart]>,
    ) -> Evaluation {
        match self.formulation {
            Formulation::Coordinates if self.cyclic.is_some() => {
                self.evaluate_cyclic(z, omega, level, jacobian, warm)
            }
            Formulation::Coordinates => self.evaluate_coordinates(z, omega, level, jacobian, warm),
            Formulation::Receptance => {
                Receptance::new(self, omega).evaluate(self, z, level, jacobian, warm)
            }
        }
    }

    fn evaluate_coordinates(
        &self,
        q: &DVector<f64>,
        omega: f64,
        level: f64,
        jacobian: bool,
        warm: Option<&[aft::WarmStart]>,
    ) -> Evaluation {
        let u = self.element_displacements(q);
        let forces = self.element_forces(&u, omega, warm, jacobian);
        let fex = self.excitation_harmonics();
        let (lin, mut dlin) = self.linear_forces(q, omega);
        // Σ_e P_eᵀ f̂_e, and Σ_e P_eᵀ ∂f̂_e/∂ω for rate-dependent elements.
        let fnl = self.stacked_map.transpose() * self.stacked_forces(&forces);
        let fnl = DVector::from_row_slice(fnl.transpose().as_slice());
        if let Some(rates) = self.stacked_force_rates(&forces) {
            let d = self.stacked_map.transpose() * rates;
            dlin += DVector::from_row_slice(d.transpose().as_slice());
        }
        let jac = if jacobian {
            let mut j = self.dynamic_stiffness(omega);
            if !self.structure.elements.is_empty() {
                j += self.element_jacobian(&forces);
            }
            j
        } else {
            DMatrix::zeros(0, 0)
        };
        let f0 = self.static_force.clone();
        balance(lin, dlin, fnl, fex, f0, level, jac, &forces)
    }

    /// The balance of a cyclic sector on the unknowns `z` (the harmonics of the coordinates off
    /// the right boundary): `Tᵀ·(Z(ω)·T·z − level·F̂) + Aᵀ·[P | P']ᵀ·f̂([P | P']·A·z)`, Jacobian
    /// `Tᵀ·Z·T + Aᵀ·J·A` with `J` the elements' Jacobian on the width of their maps
    /// ([`crate::dynamics::cyclic`]).
    fn evaluate_cyclic(
        &self,
        z: &DVector<f64>,
        omega: f64,
        level: f64,
        jacobian: bool,
        warm: Option<&[aft::WarmStart]>,
    ) -> Evaluation {
        let c = self.cyclic.as_ref().expect("cyclic system");
        let len = self.harmonics.len();
        let u = self.element_displacements(z);
        let forces = self.element_forces(&u, omega, warm, jacobian);
        let fex = c.expansion.tr_mul(&self.excitation_harmonics());
        let q = &c.expansion * z;
        let (lin, dlin) = self.linear_forces(&q, omega);
        let (lin, mut dlin) = (c.expansion.tr_mul(&lin), c.expansion.tr_mul(&dlin));
        // Σ_e [P_e | P'_e]ᵀ f̂_e on this sector's and the next sector's coordinates, then Aᵀ.
        let fw = self.stacked_map.transpose() * self.stacked_forces(&forces);
        debug_assert_eq!(fw.shape(), (self.width, len));
        let fnl = c
            .element_expansion
            .tr_mul(&DVector::from_row_slice(fw.transpose().as_slice()));
        if let Some(rates) = self.stacked_force_rates(&forces) {
            let dw = self.stacked_map.transpose() * rates;
            dlin += c
                .element_expansion
                .tr_mul(&DVector::from_row_slice(dw.transpose().as_slice()));
        }
        let jac = if jacobian {
            let t = &c.expansion;
            let mut j = t.tr_mul(&(self.dynamic_stiffness(omega) * t));
            if !self.structure.elements.is_empty() {
                let a = &c.element_expansion;
                j += a.tr_mul(&(self.element_jacobian(&forces) * a));
            }
            j
        } else {
            DMatrix::zeros(0, 0)
        };
        let f0 = self.static_force.as_ref().map(|f| c.expansion.tr_mul(f));
        balance(lin, dlin, fnl, fex, f0, level, jac, &forces)
    }

    /// Harmonics of the coordinates (`n × len`, coordinate-major) of a solution; for a cyclic
    /// sector, of every coordinate of the sector (the right boundary's from the left's).
    pub fn coordinates(&self, point: &HbmPoint) -> DVector<f64> {
        match self.formulation {
            Formulation::Coordinates => match &self.cyclic {
                Some(c) => &c.expansion * &point.z,
                None => point.z.clone(),
            },
            Formulation::Receptance => {
                Receptance::new(self, point.omega).coordinates(self, &point.z, point.level)
            }
        }
    }

    /// Element displacement harmonics of a solution, one `d × len` vector per element.
    pub fn element_displacement_harmonics(&self, point: &HbmPoint) -> Vec<Vec<f64>> {
        let len = self.harmonics.len();
        let u = match self.formulation {
            Formulation::Coordinates => self.element_displacements(&point.z),
            Formulation::Receptance => {
                DMatrix::from_row_slice(self.stacked_map.nrows(), len, point.z.as_slice())
            }
        };
        self.structure
            .elements
            .iter()
            .zip(&self.offsets)
            .map(|(e, &off)| {
                let d = e.element.dofs();
                let mut v = vec![0.0; d * len];
                for c in 0..d {
                    for h in 0..len {
                        v[c * len + h] = u[(off + c, h)];
                    }
                }
                v
            })
            .collect()
    }

    /// The periodic cycle's displacement and force samples of every element at a solution.
    pub fn element_samples(&self, point: &HbmPoint) -> Vec<aft::ElementSamples> {
        let us = self.element_displacement_harmonics(point);
        self.structure
            .elements
            .par_iter()
            .zip(us.par_iter())
            .with_min_len(PARALLEL_MIN_ELEMENTS)
            .map(|(e, u)| {
                aft::cycle_samples(
                    e.element.as_ref(),
                    &self.harmonics,
                    u,
                    point.omega,
                    &self.aft,
                )
            })
            .collect()
    }

    /// Dissipated energy per cycle and contact-state fractions of every element at a solution.
    pub fn element_cycles(&self, point: &HbmPoint) -> Vec<ElementCycle> {
        let us = self.element_displacement_harmonics(point);
        self.structure
            .elements
            .par_iter()
            .zip(us.par_iter())
            .with_min_len(PARALLEL_MIN_ELEMENTS)
            .map(|(e, u)| {
                aft::cycle_summary(
                    e.element.as_ref(),
                    &self.harmonics,
                    u,
                    point.omega,
                    &self.aft,
                )
            })
            .collect()
    }

    /// Newton's method at fixed frequency `omega` (rad/s) and excitation `level`, from `guess`
    /// (warm start; `None`: from rest). Non-convergence is an error naming the frequency, the
    /// residual and the iterations.
    pub fn solve(&self, omega: f64, level: f64, guess: Option<&DVector<f64>>) -> Result<HbmPoint> {
        let t0 = Instant::now();
        let n = self.unknowns();
        let mut z = guess.cloned().unwrap_or_else(|| DVector::zeros(n));
        if z.len() != n {
            return Err(Error::param(
                "guess",
                format!("{} unknowns expected, got {}", n, z.len()),
            ));
        }
        let mut ev = self.evaluate(&z, omega, level, true);
        for it in 0..=self.newton.max_iterations {
            let rel = ev.relative_residual();
            if rel <= self.newton.tolerance || ev.residual.norm() == 0.0 {
                return Ok(HbmPoint {
                    omega,
                    level,
                    z,
                    iterations: it,
                    residual: rel,
                    converged: true,
                    periodicity_error: ev.periodicity_error,
                    wall_time_s: t0.elapsed().as_secs_f64(),
                });
            }
            if it == self.newton.max_iterations {
                break;
            }
            let step = solve_linear(&ev.jacobian, &(-&ev.residual), omega)?;
            // Warm start the elements' periodic states from the last iterate, except on the
            // first step from rest: a state at rest is no start for a cycle of finite amplitude,
            // and where a slider's cycle sticks throughout, a start that slips in its first
            // period can end on the cycle that just touches the slip limit instead of the
            // virgin start's (another, spurious, static offset).
            let warm = std::mem::take(&mut ev.element_states);
            let warm = (it > 0 || guess.is_some()).then_some(warm.as_slice());
            let (znew, evnew) = self.line_search(&z, &step, &ev, |zz, jac| {
                self.evaluate_from(zz, omega, level, jac, warm)
            });
            z = znew;
            ev = evnew;
        }
        Err(Error::NonConvergence {
            solver: format!(
                "harmonic balance at {:.6} Hz (level {level:.4e})",
                omega / (2.0 * std::f64::consts::PI)
            ),
            iterations: self.newton.max_iterations,
            residual: ev.relative_residual(),
            tolerance: self.newton.tolerance,
        })
    }

    /// Backtracking line search along `step`: the full step is taken when it lowers `‖R‖`
    /// (its Jacobian is then already computed), otherwise the step is halved up to 8 times.
    fn line_search(
        &self,
        z: &DVector<f64>,
        step: &DVector<f64>,
        ev: &Evaluation,
        eval: impl Fn(&DVector<f64>, bool) -> Evaluation,
    ) -> (DVector<f64>, Evaluation) {
        backtrack(ev.residual.norm(), |lambda, jacobian| {
            let trial = z + step * lambda;
            let e = eval(&trial, jacobian);
            let merit = e.residual.norm();
            ((trial, e), merit)
        })
    }

    /// Force level that holds the amplitude of the excitation harmonic of `observation·q` at
    /// `target` (response-controlled test, e.g. a constant modal amplitude), at frequency
    /// `omega`. Unknowns: the harmonics and the level, with the extra equation
    /// `√(a² + b²) = target`. Warm start from `guess = (z, level)`; without one, a first solve at
    /// unit level is scaled to the target. Coordinates formulation only.
    pub fn solve_response_controlled(
        &self,
        omega: f64,
        target: f64,
        observation: &DVector<f64>,
        guess: Option<(&DVector<f64>, f64)>,
    ) -> Result<HbmPoint> {
        let t0 = Instant::now();
        if self.formulation != Formulation::Coordinates {
            return Err(Error::param(
                "formulation",
                "response control is implemented for the coordinates formulation",
            ));
        }
        if self.cyclic.is_some() {
            return Err(Error::param(
                "cyclic",
                "response control is not implemented for a cyclic sector",
            ));
        }
        crate::core::error::require_positive("target amplitude", target)?;
        if observation.len() != self.structure.n() {
            return Err(Error::param(
                "observation",
                format!(
                    "{} entries for {} coordinates",
                    observation.len(),
                    self.structure.n()
                ),
            ));
        }
        let len = self.harmonics.len();
        let n = self.structure.n();
        let (ci, si) = self
            .harmonics
            .index_of(self.excitation.harmonic)
            .expect("checked in new");
        let (mut z, mut level) = match guess {
            Some((z, l)) => (z.clone(), l),
            None => {
                let p = self.solve(omega, 1.0, None)?;
                let a = amplitude(&p.z, observation, len, ci, si);
                if a == 0.0 {
                    return Err(Error::Data(
                        "the observed response does not respond to the excitation".into(),
                    ));
                }
                let f = target / a;
                (&p.z * f, f)
            }
        };
        let nn = n * len;
        let mut iterations = 0;
        let mut rel = f64::INFINITY;
        let mut perr = 0.0;
        // Merit of the bordered system: the balance residual and the amplitude condition, each
        // relative (the convergence measure).
        let merit = |ev: &Evaluation, z: &DVector<f64>| {
            let g = amplitude(z, observation, len, ci, si) - target;
            ev.relative_residual().max(g.abs() / target)
        };
        let mut ev = self.evaluate(&z, omega, level, true);
        while iterations <= self.newton.max_iterations {
            perr = ev.periodicity_error;
            let a = amplitude(&z, observation, len, ci, si);
            let g = a - target;
            rel = ev.relative_residual().max(g.abs() / target);
            if rel <= self.newton.tolerance {
                // The amplitude condition does not fix the sign of the level: (z, −L) holds the
                // same amplitude. Report the positive level, shifting the response in time by
                // half an excitation period (which negates the excitation).
                if level < 0.0 {
                    z = self.shifted_by_half_excitation_period(&z);
                    level = -level;
                }
                return Ok(HbmPoint {
                    omega,
                    level,
                    z,
                    iterations,
                    residual: rel,
                    converged: true,
                    periodicity_error: perr,
                    wall_time_s: t0.elapsed().as_secs_f64(),
                });
            }
            iterations += 1;
            let mut j = DMatrix::zeros(nn + 1, nn + 1);
            j.view_mut((0, 0), (nn, nn)).copy_from(&ev.jacobian);
            j.view_mut((0, nn), (nn, 1)).copy_from(&ev.d_level);
            let (ac, as_) = (
                (0..n)
                    .map(|r| observation[r] * z[r * len + ci])
                    .sum::<f64>(),
                (0..n)
                    .map(|r| observation[r] * z[r * len + si])
                    .sum::<f64>(),
            );
            let am = a.max(f64::MIN_POSITIVE);
            for r in 0..n {
                j[(nn, r * len + ci)] = observation[r] * ac / am;
                j[(nn, r * len + si)] = observation[r] * as_ / am;
            }
            let mut rhs = DVector::zeros(nn + 1);
            rhs.rows_mut(0, nn).copy_from(&(-&ev.residual));
            rhs[nn] = -g;
            let step = solve_linear(&j, &rhs, omega)?;
            // Backtracking as in `line_search`: a non-smooth (stick–slip) residual can make the
            // full Newton step of the bordered system cycle.
            let warm = std::mem::take(&mut ev.element_states);
            let trial = |lambda: f64, jac: bool| {
                let zt = &z + step.rows(0, nn) * lambda;
                let lt = level + step[nn] * lambda;
                let et = self.evaluate_from(&zt, omega, lt, jac, Some(&warm));
                let m = merit(&et, &zt);
                ((zt, lt, et), m)
            };
            let next = backtrack(rel, trial);
            (z, level, ev) = (next.0, next.1, next.2);
        }
        Err(Error::NonConvergence {
            solver: format!(
                "response-controlled harmonic balance at {:.6} Hz (target amplitude {target:.4e}, periodicity error {perr:.1e})",
                omega / (2.0 * std::f64::consts::PI)
            ),
            iterations: self.newton.max_iterations,
            residual: rel,
            tolerance: self.newton.tolerance,
        })
    }
}

impl HbmSystem<'_> {
    /// The periodic solution advanced by `τ = T/(2e)`, `e` the excitation's harmonic: harmonic
    /// `h` turns by `θ = hπ/e` (`(a, b) → (a cos θ + b sin θ, b cos θ − a sin θ)` for
    /// `a cos hωt + b sin hωt`), the mean stays. It answers the excitation negated, since the
    /// steady state of a time-invariant system commutes with a time shift.
    fn shifted_by_half_excitation_period(&self, z: &DVector<f64>) -> DVector<f64> {
        let len = self.harmonics.len();
        let e = self.excitation.harmonic as f64;
        let mut out = z.clone();
        for &h in self.harmonics.orders().iter().filter(|&&h| h > 0) {
            let (ci, si) = self.harmonics.index_of(h).expect("retained order");
            let (sn, cs) = (h as f64 * std::f64::consts::PI / e).sin_cos();
            for r in 0..self.structure.n() {
                let (a, b) = (z[r * len + ci], z[r * len + si]);
                out[r * len + ci] = a * cs + b * sn;
                out[r * len + si] = b * cs - a * sn;
            }
        }
        out
    }

    /// `Z(ω)`, the linear structure's dynamic stiffness in the harmonic basis (coordinate-major,
    /// the layout of [`Formulation::Coordinates`]); see the [module documentation](self).
    pub fn linear_dynamic_stiffness(&self, omega: f64) -> DMatrix<f64> {
        self.dynamic_stiffness(omega)
    }
}

/// Backtracking on a merit: `trial(λ, jacobian)` evaluates the point at step fraction `λ`
/// (with its Jacobian when asked) and returns it with its merit. The full step is taken when
/// its merit is below `merit0`, otherwise the first of `λ = 1/2, 1/4, …, 1/256` that is
/// (re-evaluated with its Jacobian), and the full step when none is.
fn backtrack<T>(merit0: f64, trial: impl Fn(f64, bool) -> (T, f64)) -> T {
    let (full, m) = trial(1.0, true);
    if m < merit0 {
        return full;
    }
    let mut lambda = 0.5;
    for _ in 0..8 {
        if trial(lambda, false).1 < merit0 {
            return trial(lambda, true).0;
        }
        lambda *= 0.5;
    }
    full
}

/// Amplitude `√(a² + b²)` of harmonic `(ci, si)` of `observation·q`.
pub fn amplitude(
    q: &DVector<f64>,
    observation: &DVector<f64>,
    len: usize,
    ci: usize,
    si: usize,
) -> f64 {
    let n = observation.len();
    let a: f64 = (0..n).map(|r| observation[r] * q[r * len + ci]).sum();
    let b: f64 = (0..n).map(|r| observation[r] * q[r * len + si]).sum();
    a.hypot(b)
}

/// Start states of the elements' periodic cycles.
pub(crate) fn element_states(forces: &[aft::ElementHarmonics]) -> Vec<aft::WarmStart> {
    forces.iter().map(|f| f.warm_start.clone()).collect()
}

fn periodicity(forces: &[aft::ElementHarmonics]) -> (f64, usize) {
    (
        aft::worst_periodicity_error(forces.iter().map(|f| f.periodicity_error)),
        forces.iter().filter(|f| !f.periodic).count(),
    )
}

/// Dense LU solve; a singular matrix is an error naming the frequency and the likely cause.
pub fn solve_linear(a: &DMatrix<f64>, b: &DVector<f64>, omega: f64) -> Result<DVector<f64>> {
    a.clone().lu().solve(b).ok_or_else(|| {
        Error::Data(format!(
            "singular harmonic-balance Jacobian at {:.6} Hz (a coordinate without stiffness in some \
             harmonic, e.g. the mean position of a DOF held only by friction: add its support \
             stiffness or use odd harmonics only)",
            omega / (2.0 * std::f64::consts::PI)
        ))
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::MicroslipContact;
    use crate::element::ValanisParams;
    use std::f64::consts::{PI, TAU};
    use std::sync::Arc;

    /// Response control of a mode with a Jenkins joint, first harmonic only, from a cold start
    /// at every frequency: the force that holds the amplitude `a` is Caughey's describing
    /// function `F = a·|k − ω² + K_eq(a) + i(cω + h(a))|`, `K_eq = (k_t/π)(β − sin 2β/2)`,
    /// `h = (4F_s/(πa))(1 − F_s/(k_t a))`, `cos β = 1 − 2F_s/(k_t a)` (Caughey 1960, *J. Appl.
    /// Mech.* 27:640), within the AFT's sampling of the slip onset (0.5 % at 256 samples), at
    /// amplitudes from stick to gross slip across the resonance.
    #[test]
    fn response_control_of_a_jenkins_mode_matches_caughey() {
        let (f0, zeta) = (80.0, 2e-3);
        let k = (TAU * f0).powi(2);
        let c = 2.0 * zeta * TAU * f0;
        let (kt, fs) = (0.3 * k, 0.3 * k * 1e-4);
        let mut s = Structure::modal(&[f0], &[zeta]).unwrap();
        let jenkins = crate::element::Jenkins::new(kt, fs).unwrap();
        s.attach("joint", Arc::new(jenkins), DMatrix::from_element(1, 1, 1.0))
            .unwrap();
        let sys = HbmSystem::new(
            &s,
            Harmonics::new(1, true, Some(256)).unwrap(),
            Excitation {
                force: DVector::from_element(1, 1.0),
                harmonic: 1,
                force_sin: None,
            },
            FormulationChoice::Coordinates,
        )
        .unwrap();
        let obs = DVector::from_element(1, 1.0);
        for a in [5e-5, 2e-4, 1e-3, 1e-2] {
            for fr in [78.0, 80.0, 84.0, 88.0, 90.0] {
                let w = TAU * fr;
                let p = sys.solve_response_controlled(w, a, &obs, None).unwrap();
                let (k_eq, h) = if kt * a <= fs {
                    (kt, 0.0)
                } else {
                    let beta = (1.0 - 2.0 * fs / (kt * a)).acos();
                    (
                        kt / PI * (beta - (2.0 * beta).sin() / 2.0),
                        4.0 * fs / (PI * a) * (1.0 - fs / (kt * a)),
                    )
                };
                let r = sys.evaluate(&p.z, w, p.level, false).relative_residual();
                assert!(
                    r < 1e-6,
                    "a = {a:e} m, {fr} Hz: residual {r:e} at the level returned"
                );
                let exact = a * (k - w * w + k_eq).hypot(c * w + h);
                assert!(
                    (p.level / exact - 1.0).abs() < 5e-3,
                    "a = {a:e} m, {fr} Hz: force {} vs {exact}",
                    p.level
                );
            }
        }
    }

    /// The blocked assembly of [`HbmSystem::element_jacobian`] equals the direct sum
    /// `Σ_e (P_e ⊗ I)ᵀ J_e (P_e ⊗ I)` formed entry by entry, for 19 microslip elements (two full
    /// blocks and a partial one) with some zero map entries, in partial slip.
    #[test]
    fn blocked_jacobian_assembly_equals_the_direct_sum() {
        let modes = 5;
        let mut s = Structure::modal(&[100.0, 180.0, 250.0, 400.0, 700.0], &[0.01; 5]).unwrap();
        let v = ValanisParams::new(1e6, 0.3, 0.0, 0.6).unwrap();
        for e in 0..19usize {
            let map = DMatrix::from_fn(3, modes, |c, m| {
                if (e + c + m) % 5 == 0 {
                    0.0
                } else {
                    ((e * 7 + c * 3 + m * 5) % 11) as f64 / 11.0 - 0.45
                }
            });
            let el = MicroslipContact::new(v, 1e6, 1.0).unwrap();
            s.attach(format!("e{e}"), Arc::new(el), map).unwrap();
        }
        let h = Harmonics::new(3, false, Some(32)).unwrap();
        let len = h.len();
        let force = DVector::from_element(modes, 1.0);
        let sys = HbmSystem::new(
            &s,
            h,
            Excitation {
                force,
                harmonic: 1,
                force_sin: None,
            },
            FormulationChoice::Coordinates,
        )
        .unwrap();
        // Coordinates of a few µm (slip starts near μN0/E0 = 0.6 µm): partial slip.
        let q = DVector::from_fn(modes * len, |i, _| {
            1e-6 * (((i * 37) % 17) as f64 / 8.0 - 1.0)
        });
        let u = sys.element_displacements(&q);
        let forces = sys.element_forces(&u, 1.0, None, true);
        let j = sys.element_jacobian(&forces);
        let nn = modes * len;
        let mut reference = DMatrix::<f64>::zeros(nn, nn);
        for (e, el) in s.elements.iter().enumerate() {
            let je = &forces[e].jacobian;
            let dl = 3 * len;
            for (r, hh, ss, hp) in (0..modes).flat_map(|r| {
                (0..len).flat_map(move |hh| {
                    (0..modes).flat_map(move |ss| (0..len).map(move |hp| (r, hh, ss, hp)))
                })
            }) {
                let mut sum = 0.0;
                for c in 0..3 {
                    for cp in 0..3 {
                        sum += el.map[(c, r)]
                            * je[(c * len + hh) * dl + cp * len + hp]
                            * el.map[(cp, ss)];
                    }
                }
                reference[(r * len + hh, ss * len + hp)] += sum;
            }
        }
        let scale = reference.amax();
        assert!(scale > 0.0);
        let err = (&j - &reference).amax();
        assert!(err <= 1e-12 * scale, "assembly error {err:e} of {scale:e}");
    }
}
