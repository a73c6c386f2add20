//! Nonlinear modes by the extended periodic motion concept (EPMC): backbone (frequency and modal
//! damping ratio against modal amplitude), the mode shape's harmonics and the energy each element
//! dissipates per cycle, of a structure with hysteretic or nonlinear elastic elements.
//!
//! **The concept** (Krack, *Computers & Structures* 154 (2015) 59–71). A damped structure has no
//! periodic free motion; the EPMC makes one by adding an artificial negative mass-proportional
//! damping term that just compensates the dissipation,
//!
//! ```text
//! M·q̈ + C·q̇ + K·q + Σ_e P_eᵀ·f_e(P_e·q) − ξ·M·q̇ = 0,
//! ```
//!
//! and defines the nonlinear mode at modal amplitude `a` as the periodic solution of this
//! autonomous system with frequency `ω(a)` and self-excitation `ξ(a)`; the modal damping ratio is
//! `ζ(a) = ξ(a)/(2ω(a))`. For a linear structure with modal damping the EPMC returns its modes
//! exactly (`ξ = 2ζ_r ω_r`); for a conservative nonlinearity with mass-proportional `C = βM`,
//! `ξ = β` at every amplitude, so `ζ = β/(2ω(a))`.
//!
//! **Harmonic balance.** With the harmonic basis of [`crate::dynamics::hbm`]
//! (`q = Q0 + Σ_k Q_kᶜ cos kωt + Q_kˢ sin kωt`, coordinate-major), the residual is the
//! harmonic-balance residual at zero excitation plus the self-excitation term,
//!
//! ```text
//! R(Q, ω, ξ) = Z(ω)·Q + Σ_e (P_e ⊗ I)ᵀ f̂_e + ξ·E(ω)·Q,
//! E(ω) on order k:  [0, −kωM;  kωM, 0]   (the harmonics of −M·q̇; order 0: 0)
//! ```
//!
//! (i.e. `C → C − ξM` in `Z`). The unknowns `(Q, ω, ξ)` are two more than the balance equations;
//! the two closing equations are
//!
//! * the **amplitude**: `Q₁ᶜᵀ·M·Q₁ᶜ + Q₁ˢᵀ·M·Q₁ˢ = a²` — `a` is the mass-normalised amplitude
//!   of the fundamental harmonic (m·kg^½ for physical coordinates; for mass-normalised modal
//!   coordinates the amplitude of the modal coordinates), so that `Q₁ = a·φ` for a linear mode
//!   `φ` with `φᵀMφ = 1`;
//! * the **phase**: `Q₁ˢ` of the reference coordinate is zero (the autonomous system is
//!   invariant under a time shift). The reference is the coordinate with the largest
//!   mass-weighted amplitude `|φ_r|·√M_rr` in the underlying linear mode.
//!
//! Newton's method on the bordered system with the exact Jacobian: `∂R/∂Q = J_HBM + ξE(ω)`
//! (`J_HBM` of [`HbmSystem::evaluate`], with the elements' Jacobians from the AFT),
//! `∂R/∂ω = ∂(Z·Q)/∂ω + ξE(ω)·Q/ω` (E is linear in ω; the elements are rate-independent),
//! `∂R/∂ξ = E(ω)·Q`, and the two constraint rows analytic; a backtracking line search on the
//! scaled residual.
//!
//! **Start and continuation.** The underlying linear mode is the `mode`-th (ascending
//! frequency) eigenvector of `(K + K_el, M)`, `K_el` the elements' tangent stiffness at rest
//! (the stick stiffness of a friction element, the preloaded normal stiffness of a contact, zero
//! for a cubic spring), read from the first-harmonic block of the elements' Jacobian at zero
//! motion; its damping `ξ₀ = φᵀ(C + C_el)φ`. The amplitudes are taken in the order given
//! (typically log-spaced); each solve starts from the secant through the two previous solutions
//! in `ln a` (shape `Q/a`, `ω` and `ξ` extrapolated), the first from the linear mode. A failed
//! solve is retried from the previous solution scaled to the new amplitude, then the step in
//! `ln a` is halved (up to [`ModeSettings::max_subdivisions`] times; the intermediate solutions
//! serve as predictors and are not reported). A target that still fails stops the backbone there,
//! keeping the points before it ([`NonlinearMode::stopped`]).
//!
//! **Energy balance.** Over one period the self-excitation supplies
//! `W_ξ = ξ∮q̇ᵀMq̇ dt = πωξ Σ_k k²(Q_kᶜᵀMQ_kᶜ + Q_kˢᵀMQ_kˢ)`, the viscous damping takes
//! `W_C = πω Σ_k k²(Q_kᶜᵀCQ_kᶜ + Q_kˢᵀCQ_kˢ)` and the elements the rest, `Σ_e W_e = W_ξ − W_C`
//! (each `W_e = ∮f_e·du_e` from the AFT's time samples, [`HbmSystem::element_cycles`]); both
//! sides are reported per point as a check of the solution.

use crate::core::error::{Error, Result};
use crate::dynamics::aft::{ElementCycle, WarmStart};
use crate::dynamics::hbm::{Evaluation, Formulation, HbmPoint, HbmSystem};
use crate::dynamics::model::undamped_modes;
use nalgebra::{DMatrix, DVector};
use std::time::Instant;

const TWO_PI: f64 = 2.0 * std::f64::consts::PI;

/// What to compute: which linear mode to continue, at which modal amplitudes, and Newton's
/// settings.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ModeSettings {
    /// The underlying linear mode, 1-based in ascending frequency of `(K + K_el, M)`.
    pub mode: usize,
    /// Modal amplitudes `a` (m·kg^½ for physical coordinates), positive and increasing.
    pub amplitudes: Vec<f64>,
    /// Relative tolerance on the balance residual (relative to `‖K·Q‖ + ω²‖M·Q‖ + ‖f̂_nl‖`) and
    /// on the two constraints (relative to `a²` and `a`).
    pub tolerance: f64,
    /// Newton iterations per solve.
    pub max_iterations: usize,
    /// Halvings of a step in `ln a` after a failed solve.
    pub max_subdivisions: usize,
}

impl ModeSettings {
    /// Mode `mode` at the given amplitudes; tolerance 1e-7 (that of the forced response's
    /// Newton solves, [`crate::dynamics::hbm::NewtonSettings`]), 20 iterations (a solve from a
    /// good predictor takes 2–6; a failing one is cut short and the step halved), 6
    /// subdivisions.
    pub fn new(mode: usize, amplitudes: Vec<f64>) -> Self {
        Self {
            mode,
            amplitudes,
            tolerance: 1e-7,
            max_iterations: 20,
            max_subdivisions: 6,
        }
    }
}

/// `count` amplitudes from `min` to `max`, equally spaced in `ln a` (both ends included).
/// Errors name `amplitude_min`, `amplitude_max` or `amplitudes`.
pub fn log_spaced(min: f64, max: f64, count: usize) -> Result<Vec<f64>> {
    crate::core::error::require_positive("amplitude_min", min)?;
    crate::core::error::require_positive("amplitude_max", max)?;
    if max <= min {
        return Err(Error::param(
            "amplitude_max",
            format!("must be larger than amplitude_min ({min:e}), got {max:e}"),
        ));
    }
    if count < 2 {
        return Err(Error::param("amplitudes", "at least 2 amplitudes"));
    }
    let (l0, l1) = (min.ln(), max.ln());
    Ok((0..count)
        .map(|i| {
            if i + 1 == count {
                max
            } else {
                (l0 + (l1 - l0) * i as f64 / (count - 1) as f64).exp()
            }
        })
        .collect())
}

/// The underlying linear mode: the low-amplitude limit of the nonlinear mode.
#[derive(Debug, Clone)]
pub struct LinearMode {
    /// 1-based index in ascending frequency.
    pub index: usize,
    /// Natural angular frequency (rad/s) of `(K + K_el, M)`.
    pub omega: f64,
    /// `φᵀ(C + C_el)φ` (1/s): the EPMC's `ξ` of the linear mode.
    pub xi: f64,
    /// Mass-normalised shape `φ` (`φᵀMφ = 1`; kg^-½ for physical coordinates), positive at the
    /// reference coordinate.
    pub shape: DVector<f64>,
    /// Coordinate whose first-harmonic sine coefficient is held at zero (0-based).
    pub reference: usize,
    /// Natural frequencies (Hz) of all modes of `(K + K_el, M)`, ascending.
    pub frequencies_hz: Vec<f64>,
}

impl LinearMode {
    /// Natural frequency (Hz).
    pub fn frequency_hz(&self) -> f64 {
        self.omega / TWO_PI
    }

    /// Modal damping ratio `ξ/(2ω)`.
    pub fn damping_ratio(&self) -> f64 {
        self.xi / (2.0 * self.omega)
    }
}

/// One point of the backbone: the periodic motion at one modal amplitude.
#[derive(Debug, Clone)]
pub struct ModePoint {
    /// Modal amplitude `a` (m·kg^½ for physical coordinates).
    pub amplitude: f64,
    /// Angular frequency (rad/s).
    pub omega: f64,
    /// Self-excitation `ξ` (1/s).
    pub xi: f64,
    /// Harmonics of the coordinates (`n × len`, coordinate-major, the layout of
    /// [`Formulation::Coordinates`]).
    pub z: DVector<f64>,
    /// Newton iterations of the final solve.
    pub iterations: usize,
    /// Relative residual at the end (the largest of the balance and the two constraints).
    pub residual: f64,
    /// Largest AFT periodicity error over the elements.
    pub periodicity_error: f64,
    /// Energy dissipated per cycle and contact states of every element.
    pub elements: Vec<ElementCycle>,
    /// Energy the viscous damping `C` dissipates per cycle (J).
    pub viscous_energy_j: f64,
    /// Energy the self-excitation `ξ·M·q̇` supplies per cycle (J).
    pub self_excitation_energy_j: f64,
    /// Wall-clock time to reach the point, with any intermediate solves (s).
    pub wall_time_s: f64,
}

impl ModePoint {
    /// Frequency (Hz).
    pub fn frequency_hz(&self) -> f64 {
        self.omega / TWO_PI
    }

    /// Modal damping ratio `ζ = ξ/(2ω)`.
    pub fn damping_ratio(&self) -> f64 {
        self.xi / (2.0 * self.omega)
    }

    /// Energy the elements dissipate per cycle, summed (J).
    pub fn element_energy_j(&self) -> f64 {
        self.elements.iter().map(|c| c.dissipated_energy_j).sum()
    }

    /// `|Σ_e W_e − (W_ξ − W_C)| / W_ξ`: how well the energy balance closes (0 for an exact
    /// periodic solution; the AFT's trapezoidal energies err by O(samples⁻²)).
    pub fn energy_balance_error(&self) -> f64 {
        let supplied = self.self_excitation_energy_j;
        if supplied == 0.0 {
            return 0.0;
        }
        (self.element_energy_j() - (supplied - self.viscous_energy_j)).abs() / supplied.abs()
    }
}

/// The computed nonlinear mode.
#[derive(Debug, Clone)]
pub struct NonlinearMode {
    /// The underlying linear mode.
    pub linear: LinearMode,
    /// The backbone points, in the order of the amplitudes.
    pub points: Vec<ModePoint>,
    /// Why the continuation stopped before the last amplitude (`None`: complete).
    pub stopped: Option<String>,
    /// Solves that failed and were retried (other predictor or a smaller step).
    pub retries: usize,
    /// Intermediate amplitudes inserted by step halving.
    pub subdivisions: usize,
    /// Wall-clock time (s).
    pub wall_time_s: f64,
}

/// Unknowns `x = (Q, ω, ξ)` with the amplitude they belong to.
#[derive(Debug, Clone)]
struct State {
    amplitude: f64,
    x: DVector<f64>,
}

/// Outcome of one Newton solve.
struct Solved {
    x: DVector<f64>,
    iterations: usize,
    residual: f64,
    periodicity_error: f64,
}

/// The EPMC problem of a harmonic-balance system (coordinates formulation).
pub struct Epmc<'s, 'a> {
    system: &'s HbmSystem<'a>,
    linear: LinearMode,
    settings: ModeSettings,
    n: usize,
    len: usize,
    ci: usize,
    si: usize,
}

/// `(A ⊗ I)·z` in the coordinate-major layout (`z` is `n × len` row-major).
fn per_harmonic(a: &DMatrix<f64>, z: &DVector<f64>, len: usize) -> DVector<f64> {
    let n = a.nrows();
    let zm = DMatrix::from_row_slice(n, len, z.as_slice());
    let p = a * zm;
    DVector::from_row_slice(p.transpose().as_slice())
}

/// The underlying linear mode `mode` (1-based) of `system`'s structure with its elements
/// linearised at rest (see the [module documentation](self)). Errors name `mode`.
pub fn linear_mode(system: &HbmSystem<'_>, mode: usize) -> Result<LinearMode> {
    let s = system.structure;
    let (n, len) = (s.n(), system.harmonics.len());
    if system.cyclic().is_some() {
        return Err(Error::param(
            "cyclic",
            "nonlinear modes of a cyclic sector are not implemented",
        ));
    }
    if mode == 0 || mode > n {
        return Err(Error::param(
            "mode",
            format!("must be between 1 and the {n} coordinates of the model, got {mode}"),
        ));
    }
    let (ci, si) = system
        .harmonics
        .index_of(1)
        .ok_or_else(|| Error::param("harmonics", "the first harmonic must be retained"))?;
    // Elements' tangent at rest: the Jacobian at zero motion minus the linear part, first
    // harmonic block (at ω = 1 rad/s the cos→sin entry is the tangent damping).
    let (k_el, c_el) = if s.elements.is_empty() {
        (DMatrix::zeros(n, n), DMatrix::zeros(n, n))
    } else {
        let ev = system.evaluate(&DVector::zeros(n * len), 1.0, 0.0, true);
        let j = ev.jacobian - system.linear_dynamic_stiffness(1.0);
        (
            DMatrix::from_fn(n, n, |r, c| j[(r * len + ci, c * len + ci)]),
            DMatrix::from_fn(n, n, |r, c| j[(r * len + ci, c * len + si)]),
        )
    };
    if k_el.iter().chain(c_el.iter()).any(|v| !v.is_finite()) {
        return Err(Error::Data(
            "the elements' tangent stiffness at rest is not finite".into(),
        ));
    }
    let sym = |a: DMatrix<f64>| (&a + a.transpose()) * 0.5;
    let k = &s.stiffness + sym(k_el);
    let c = &s.damping + sym(c_el);
    let (eigenvalues, mut shapes) = undamped_modes(&s.mass, &k)?;
    let lambda = eigenvalues[mode - 1];
    if lambda.is_nan() || lambda <= 0.0 {
        return Err(Error::param(
            "mode",
            format!(
                "linear mode {mode} has no positive stiffness (eigenvalue {lambda:e} rad²/s²): \
                 a rigid-body mode has no nonlinear mode"
            ),
        ));
    }
    let mut phi = shapes.swap_remove(mode - 1);
    let reference = (0..n)
        .max_by(|&x, &y| {
            let w = |r: usize| phi[r].abs() * s.mass[(r, r)].sqrt();
            w(x).total_cmp(&w(y))
        })
        .unwrap_or(0);
    if phi[reference] < 0.0 {
        phi = -phi;
    }
    let xi = (phi.transpose() * &c * &phi)[(0, 0)];
    let frequencies_hz = eigenvalues
        .iter()
        .map(|&l| l.max(0.0).sqrt() / TWO_PI)
        .collect();
    Ok(LinearMode {
        index: mode,
        omega: lambda.sqrt(),
        xi,
        shape: phi,
        reference,
        frequencies_hz,
    })
}

impl<'s, 'a> Epmc<'s, 'a> {
    /// The EPMC problem of `system` (which must use the coordinates formulation) for the
    /// settings' mode. Errors name `formulation`, `mode` or `amplitudes`.
    pub fn new(system: &'s HbmSystem<'a>, settings: ModeSettings) -> Result<Self> {
        if system.formulation() != Formulation::Coordinates {
            return Err(Error::param(
                "formulation",
                "nonlinear modes are computed in the coordinates formulation (the amplitude \
                 condition needs every coordinate's harmonics)",
            ));
        }
        if system.cyclic().is_some() {
            return Err(Error::param(
                "cyclic",
                "nonlinear modes of a cyclic sector are not implemented",
            ));
        }
        if settings.amplitudes.is_empty() {
            return Err(Error::param("amplitudes", "give at least one amplitude"));
        }
        if let Some(a) = settings
            .amplitudes
            .iter()
            .find(|a| !(a.is_finite() && **a > 0.0))
        {
            return Err(Error::param(
                "amplitudes",
                format!("must be finite and > 0, got {a}"),
            ));
        }
        if settings.amplitudes.windows(2).any(|w| w[1] <= w[0]) {
            return Err(Error::param("amplitudes", "must be strictly increasing"));
        }
        crate::core::error::require_positive("tolerance", settings.tolerance)?;
        let linear = linear_mode(system, settings.mode)?;
        let (ci, si) = system
            .harmonics
            .index_of(1)
            .expect("checked in linear_mode");
        Ok(Self {
            n: system.structure.n(),
            len: system.harmonics.len(),
            system,
            linear,
            settings,
            ci,
            si,
        })
    }

    /// The underlying linear mode.
    pub fn linear(&self) -> &LinearMode {
        &self.linear
    }

    /// `E(ω)·Q` from `M·Q` (`mq`, coordinate-major): cosine rows `−kω·(M·Q_kˢ)`, sine rows
    /// `+kω·(M·Q_kᶜ)`.
    fn self_excitation(&self, mq: &DVector<f64>, omega: f64) -> DVector<f64> {
        let mut out = DVector::zeros(self.n * self.len);
        let mut c = 0;
        for &k in self.system.harmonics.orders() {
            if k == 0 {
                c += 1;
                continue;
            }
            let kw = k as f64 * omega;
            for r in 0..self.n {
                out[r * self.len + c] = -kw * mq[r * self.len + c + 1];
                out[r * self.len + c + 1] = kw * mq[r * self.len + c];
            }
            c += 2;
        }
        out
    }

    /// Add `ξ·E(ω)` to the balance block of `j`.
    fn add_self_excitation_jacobian(&self, j: &mut DMatrix<f64>, omega: f64, xi: f64) {
        let (n, len, m) = (self.n, self.len, &self.system.structure.mass);
        let mut c = 0;
        for &k in self.system.harmonics.orders() {
            if k == 0 {
                c += 1;
                continue;
            }
            let v = xi * k as f64 * omega;
            for r in 0..n {
                for s in 0..n {
                    let mrs = m[(r, s)];
                    if mrs == 0.0 {
                        continue;
                    }
                    j[(r * len + c, s * len + c + 1)] -= v * mrs;
                    j[(r * len + c + 1, s * len + c)] += v * mrs;
                }
            }
            c += 2;
        }
    }

    /// Scaled residual (balance rows / their scale, then the two constraints), with the bordered
    /// Jacobian when asked, the convergence measure and the element states.
    fn evaluate(
        &self,
        x: &DVector<f64>,
        a: f64,
        jacobian: bool,
        warm: Option<&[WarmStart]>,
    ) -> (DVector<f64>, DMatrix<f64>, f64, Evaluation) {
        let (n, len) = (self.n, self.len);
        let nn = n * len;
        let s = self.system.structure;
        let z = x.rows(0, nn).into_owned();
        let (omega, xi) = (x[nn], x[nn + 1]);
        let ev = self.system.evaluate_from(&z, omega, 0.0, jacobian, warm);
        let mq = per_harmonic(&s.mass, &z, len);
        let eq = self.self_excitation(&mq, omega);
        let scale =
            (per_harmonic(&s.stiffness, &z, len).norm() + omega * omega * mq.norm() + ev.scale)
                .max(f64::MIN_POSITIVE);
        let r = &ev.residual + &eq * xi;
        let (ci, si, rf) = (self.ci, self.si, self.linear.reference);
        let modal: f64 = (0..n)
            .map(|i| z[i * len + ci] * mq[i * len + ci] + z[i * len + si] * mq[i * len + si])
            .sum();
        let g_amp = modal / (a * a) - 1.0;
        let w_ref = s.mass[(rf, rf)].sqrt();
        let g_phase = z[rf * len + si] * w_ref / a;
        let mut res = DVector::zeros(nn + 2);
        res.rows_mut(0, nn).copy_from(&(&r / scale));
        res[nn] = g_amp;
        res[nn + 1] = g_phase;
        let measure = (r.norm() / scale).max(g_amp.abs()).max(g_phase.abs());
        let mut j = DMatrix::zeros(0, 0);
        if jacobian {
            j = DMatrix::zeros(nn + 2, nn + 2);
            let mut top = ev.jacobian.clone();
            self.add_self_excitation_jacobian(&mut top, omega, xi);
            j.view_mut((0, 0), (nn, nn)).copy_from(&(top / scale));
            let d_omega = (&ev.d_omega + &eq * (xi / omega)) / scale;
            j.view_mut((0, nn), (nn, 1)).copy_from(&d_omega);
            j.view_mut((0, nn + 1), (nn, 1)).copy_from(&(&eq / scale));
            for i in 0..n {
                j[(nn, i * len + ci)] = 2.0 * mq[i * len + ci] / (a * a);
                j[(nn, i * len + si)] = 2.0 * mq[i * len + si] / (a * a);
            }
            j[(nn + 1, rf * len + si)] = w_ref / a;
        }
        (res, j, measure, ev)
    }

    /// Newton's method at amplitude `a` from the unknowns `x0`.
    fn solve(&self, a: f64, x0: DVector<f64>) -> Result<Solved> {
        let nn = self.n * self.len;
        let mut x = x0;
        let (mut res, mut j, mut measure, mut ev) = self.evaluate(&x, a, true, None);
        let start = measure;
        for it in 0..=self.settings.max_iterations {
            // Not finite, or diverging far from the predictor: no point in going on.
            if !measure.is_finite() || measure > 1e3 * start.max(1.0) {
                break;
            }
            if measure <= self.settings.tolerance {
                if x[nn].is_nan() || x[nn] <= 0.0 {
                    return Err(Error::Data(format!(
                        "the solve at modal amplitude {a:.4e} converged to a non-positive frequency"
                    )));
                }
                return Ok(Solved {
                    x,
                    iterations: it,
                    residual: measure,
                    periodicity_error: ev.periodicity_error,
                });
            }
            if it == self.settings.max_iterations {
                break;
            }
            let step = j.clone().lu().solve(&(-&res)).ok_or_else(|| {
                Error::Data(format!(
                    "singular EPMC Jacobian at modal amplitude {a:.4e} ({:.6} Hz)",
                    x[nn] / TWO_PI
                ))
            })?;
            let warm = std::mem::take(&mut ev.element_states);
            let merit0 = res.norm();
            // Backtracking: the full step when it lowers the scaled residual, otherwise the
            // first of 1/2, 1/4, …, 1/256 that does (a stick–slip residual is not smooth).
            let trial = |lambda: f64, jac: bool| {
                let xt = &x + &step * lambda;
                let e = self.evaluate(&xt, a, jac, Some(&warm));
                (xt, e)
            };
            let (mut xn, mut en) = trial(1.0, true);
            if en.0.norm().is_nan() || en.0.norm() >= merit0 {
                let mut lambda = 0.5;
                for _ in 0..8 {
                    let (_, e) = trial(lambda, false);
                    if e.0.norm() < merit0 {
                        (xn, en) = trial(lambda, true);
                        break;
                    }
                    lambda *= 0.5;
                }
            }
            x = xn;
            (res, j, measure, ev) = en;
        }
        Err(Error::NonConvergence {
            solver: format!(
                "EPMC harmonic balance at modal amplitude {a:.4e} ({:.6} Hz, ξ {:.4e} 1/s)",
                x[nn] / TWO_PI,
                x[nn + 1]
            ),
            iterations: self.settings.max_iterations,
            residual: measure,
            tolerance: self.settings.tolerance,
        })
    }

    /// Unknowns of the linear mode at amplitude `a`.
    fn linear_guess(&self, a: f64) -> DVector<f64> {
        let nn = self.n * self.len;
        let mut x = DVector::zeros(nn + 2);
        for r in 0..self.n {
            x[r * self.len + self.ci] = a * self.linear.shape[r];
        }
        x[nn] = self.linear.omega;
        x[nn + 1] = self.linear.xi;
        x
    }

    /// Predictors at amplitude `a` from the solutions so far: the secant in `ln a` of the
    /// normalised unknowns `(Q/a, ω, ξ)` through the last two, then the last one scaled; the
    /// linear mode when there is none.
    fn predictors(&self, history: &[State], a: f64) -> Vec<DVector<f64>> {
        let nn = self.n * self.len;
        let normalised = |s: &State| {
            let mut v = s.x.clone();
            v.rows_mut(0, nn).unscale_mut(s.amplitude);
            v
        };
        let scaled = |mut v: DVector<f64>| {
            v.rows_mut(0, nn).scale_mut(a);
            v
        };
        match history {
            [] => vec![self.linear_guess(a)],
            [last] => vec![scaled(normalised(last))],
            [.., p0, p1] => {
                let (v0, v1) = (normalised(p0), normalised(p1));
                let t = (a / p1.amplitude).ln() / (p1.amplitude / p0.amplitude).ln();
                let mut secant = &v1 + (&v1 - &v0) * t;
                // A predictor with a non-positive frequency is no start.
                if secant[nn].is_nan() || secant[nn] <= 0.0 {
                    secant[nn] = v1[nn];
                }
                vec![scaled(secant), scaled(v1)]
            }
        }
    }

    /// The coordinates' harmonics of unknowns `x` as a harmonic-balance point (zero excitation).
    fn point(&self, x: &DVector<f64>) -> HbmPoint {
        let nn = self.n * self.len;
        HbmPoint {
            omega: x[nn],
            level: 0.0,
            z: x.rows(0, nn).into_owned(),
            iterations: 0,
            residual: 0.0,
            converged: true,
            periodicity_error: 0.0,
            wall_time_s: 0.0,
        }
    }

    /// `πω Σ_k k²(Q_kᶜᵀAQ_kᶜ + Q_kˢᵀAQ_kˢ)`: `∮q̇ᵀAq̇ dt` over one period.
    fn velocity_energy(&self, a: &DMatrix<f64>, z: &DVector<f64>, omega: f64) -> f64 {
        let aq = per_harmonic(a, z, self.len);
        let mut sum = 0.0;
        let mut c = 0;
        for &k in self.system.harmonics.orders() {
            if k == 0 {
                c += 1;
                continue;
            }
            let kk = (k * k) as f64;
            for r in 0..self.n {
                let (i, j) = (r * self.len + c, r * self.len + c + 1);
                sum += kk * (z[i] * aq[i] + z[j] * aq[j]);
            }
            c += 2;
        }
        std::f64::consts::PI * omega * sum
    }

    /// The backbone over the settings' amplitudes (continuation in the module documentation).
    /// `progress(done)` is called after each amplitude. A first amplitude that cannot be solved
    /// is an error; a later one stops the backbone ([`NonlinearMode::stopped`]).
    pub fn backbone(&self, progress: &mut dyn FnMut(usize)) -> Result<NonlinearMode> {
        let t0 = Instant::now();
        let nn = self.n * self.len;
        let s = self.system.structure;
        let mut history: Vec<State> = Vec::new();
        let mut points = Vec::new();
        let (mut retries, mut subdivisions) = (0usize, 0usize);
        let mut stopped = None;
        for (i, &a) in self.settings.amplitudes.iter().enumerate() {
            let tp = Instant::now();
            let mut target = a;
            let mut halvings = 0;
            let outcome = loop {
                let mut last_err = None;
                let mut solved = None;
                for (k, guess) in self.predictors(&history, target).into_iter().enumerate() {
                    if k > 0 {
                        retries += 1;
                    }
                    match self.solve(target, guess) {
                        Ok(v) => {
                            solved = Some(v);
                            break;
                        }
                        Err(e) => last_err = Some(e),
                    }
                }
                match solved {
                    Some(v) if target == a => break Ok(v),
                    Some(v) => {
                        // An intermediate amplitude: a predictor for the target.
                        history.push(State {
                            amplitude: target,
                            x: v.x,
                        });
                        target = a;
                    }
                    None => {
                        let e = last_err.expect("at least one predictor");
                        let Some(prev) = history.last() else {
                            break Err(e);
                        };
                        if halvings >= self.settings.max_subdivisions {
                            break Err(e);
                        }
                        halvings += 1;
                        subdivisions += 1;
                        retries += 1;
                        target = (prev.amplitude * target).sqrt();
                    }
                }
            };
            match outcome {
                Ok(v) => {
                    let hp = self.point(&v.x);
                    let (omega, xi) = (v.x[nn], v.x[nn + 1]);
                    let elements = self.system.element_cycles(&hp);
                    points.push(ModePoint {
                        amplitude: a,
                        omega,
                        xi,
                        viscous_energy_j: self.velocity_energy(&s.damping, &hp.z, omega),
                        self_excitation_energy_j: xi * self.velocity_energy(&s.mass, &hp.z, omega),
                        z: hp.z,
                        iterations: v.iterations,
                        residual: v.residual,
                        periodicity_error: v.periodicity_error,
                        elements,
                        wall_time_s: tp.elapsed().as_secs_f64(),
                    });
                    history.push(State {
                        amplitude: a,
                        x: v.x,
                    });
                }
                Err(e) if points.is_empty() => {
                    return Err(match e {
                        Error::NonConvergence { .. } | Error::Data(_) => Error::Data(format!(
                            "no nonlinear mode at the first modal amplitude {a:.4e} from the linear mode {} ({:.6} Hz): {e}",
                            self.linear.index,
                            self.linear.frequency_hz()
                        )),
                        other => other,
                    });
                }
                Err(e) => {
                    stopped = Some(format!("at modal amplitude {a:.4e}: {e}"));
                    break;
                }
            }
            progress(i + 1);
        }
        Ok(NonlinearMode {
            linear: self.linear.clone(),
            points,
            stopped,
            retries,
            subdivisions,
            wall_time_s: t0.elapsed().as_secs_f64(),
        })
    }
}

/// The nonlinear mode of `system` over `settings` ([`Epmc::new`] and [`Epmc::backbone`]).
pub fn nonlinear_mode(
    system: &HbmSystem<'_>,
    settings: ModeSettings,
    progress: &mut dyn FnMut(usize),
) -> Result<NonlinearMode> {
    Epmc::new(system, settings)?.backbone(progress)
}
