//! Valanis microslip element with a time-varying normal load.
//!
//! # Constitutive equation
//!
//! The endochronic (Valanis) friction element in the form used for 3-D microslip contact elements
//! in harmonic-balance codes (Valanis 1971; Gaul & Lenz 1997, *Acta Mechanica* 125; with the
//! normal-load dependent λ of the 3-D contact-element literature):
//!
//! ```text
//! dF/dt = E0·q̇ · [1 + (λ/E0)·s·(Et·q − F)] / [1 + k·(λ/E0)·s·(Et·q − F)],   s = sign(q̇)
//! λ     = E0 / (μ·Fz(t)·(1 − k·Et/E0)),                                    0 ≤ k < 1, 0 ≤ Et < E0
//! Fz(t) = max(0, N0 + kn·uz(t))                                            (zero on separation)
//! ```
//!
//! With the abbreviation `x = (λ/E0)·s·(Et·q − F)` the force rate along the path is
//! `dF/dq = E0·(1 + x)/(1 + k·x)` ([`force_slope`]).
//!
//! * `E0` is the **initial-loading slope** (`x = 0` on a virgin element).
//! * After a reversal from gross slip (`x = +1` for `Et = 0`) the **reload slope is 2E0/(1+k)**.
//! * Under sustained sliding the force approaches the asymptote `F = Et·q ± μ·Fz·(1 − Et/E0)`
//!   (`x → x∞ = −(1 − Et/E0)/(1 − k·Et/E0)`), i.e. the Coulomb limit `±μFz` for `Et = 0`.
//!
//! # Units
//!
//! The mathematics is the same in two systems of units; pick one and keep it:
//!
//! | quantity | per unit nominal area (calibration tables) | per element (dynamic codes) |
//! |---|---|---|
//! | `q`, `uz` | m | m |
//! | `F`, `Fz`, `N0` | Pa (traction, pressure) | N |
//! | `E0`, `Et`, `kn` | N/m³ (Pa/m) | N/m |
//! | `k`, `μ` | – | – |
//!
//! Sign convention: `uz > 0` closes the contact (increases the normal load); `Fz ≤ 0` is
//! separation.
//!
//! # Policies (documented, shared by both integrators)
//!
//! * **Falling normal load.** When `Fz` decreases the admissible force shrinks. The force is
//!   projected onto the current limit `|F − Et·(q − q_ref)| ≤ μ·Fz·(1 − Et/E0)` (a return map, as
//!   for a Coulomb slider). With constant `Fz` the projection never acts.
//! * **Separation** (`Fz ≤ 0`): `F = 0`, and the element forgets its history. At re-contact (the
//!   point where the linearly interpolated `Fz` crosses zero) it starts as a virgin element with
//!   `q_ref` = the displacement at re-contact, so that the `Et` spring is unstretched there.
//!   Initially `q_ref = q[0]`.
//!
//! # Integrators
//!
//! * [`implicit_euler_step`]: backward Euler on each input increment, as dynamic codes use. The
//!   scalar implicit equation is a quadratic in `x` and is solved in closed form (no iteration).
//! * [`reference_step`]: the accurate reference. On increments at constant `Fz` (each increment
//!   is a monotonic branch) the exact solution [`closed_form_branch`] (the separable ODE integrated
//!   analytically, solved by a monotone Newton iteration); where `Fz` changes, adaptive
//!   Dormand–Prince 5(4) along the increment ([`adaptive_step`]; displacement and normal load
//!   interpolated linearly, tolerance 1e-10 of the slip force).
//!
//! Two in-plane directions are two uncoupled elements ([`integrate_in_plane`]).

use crate::core::error::{Error, Result};
use crate::element::hysteretic::StepPartials as ElementPartials;
use crate::element::unilateral::recontact_fraction;

/// Parameters of a Valanis element (see the module documentation for units).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ValanisParams {
    /// Initial-loading tangential stiffness `E0` (N/m³ per area, or N/m per element).
    pub e0: f64,
    /// Shape parameter `k`, `0 ≤ k < 1`: the reload slope after reversal is `2E0/(1+k)`.
    pub k: f64,
    /// Residual (post-slip) stiffness `Et`, `0 ≤ Et < E0`, same unit as `E0`.
    pub et: f64,
    /// Friction coefficient `μ > 0`.
    pub mu: f64,
}

impl ValanisParams {
    /// Build and validate.
    pub fn new(e0: f64, k: f64, et: f64, mu: f64) -> Result<Self> {
        let p = Self { e0, k, et, mu };
        p.validate()?;
        Ok(p)
    }

    /// Check `E0 > 0`, `0 ≤ k < 1`, `0 ≤ Et < E0`, `μ > 0`, all finite.
    pub fn validate(&self) -> Result<()> {
        crate::core::error::require_positive("e0", self.e0)?;
        crate::core::error::require_positive("mu", self.mu)?;
        if !(self.k.is_finite() && (0.0..1.0).contains(&self.k)) {
            return Err(Error::param(
                "k",
                format!("must satisfy 0 <= k < 1, got {}", self.k),
            ));
        }
        if !(self.et.is_finite() && self.et >= 0.0 && self.et < self.e0) {
            return Err(Error::param(
                "et",
                format!("must satisfy 0 <= Et < E0 = {}, got {}", self.e0, self.et),
            ));
        }
        Ok(())
    }

    /// `λ = E0 / (μ·Fz·(1 − k·Et/E0))` (infinite at separation).
    pub fn lambda(&self, fz: f64) -> f64 {
        self.e0 / (self.mu * fz.max(0.0) * (1.0 - self.k * self.et / self.e0))
    }

    /// Half-width of the sliding asymptote band: `|F − Et·q| → μ·Fz·(1 − Et/E0)`.
    pub fn slip_limit(&self, fz: f64) -> f64 {
        self.mu * fz.max(0.0) * (1.0 - self.et / self.e0)
    }

    /// `x∞ = −(1 − Et/E0)/(1 − k·Et/E0)`: the value of `x` on the sliding asymptote.
    pub fn x_asymptote(&self) -> f64 {
        let a = self.et / self.e0;
        -(1.0 - a) / (1.0 - self.k * a)
    }

    /// Slope of the force right after a reversal from gross slip, `Et = 0`: `2E0/(1+k)`.
    /// (For `Et > 0` the general value is [`force_slope`] at `x = −x∞`.)
    pub fn reload_slope(&self) -> f64 {
        2.0 * self.e0 / (1.0 + self.k)
    }
}

/// `dF/dq = E0·(1 + x)/(1 + k·x)`, the Valanis force slope as a function of
/// `x = (λ/E0)·s·(Et·q − F)`. Valid for `1 + k·x > 0`.
pub fn force_slope(p: &ValanisParams, x: f64) -> f64 {
    p.e0 * (1.0 + x) / (1.0 + p.k * x)
}

/// State of one element after a step: everything the next step needs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ValanisState {
    /// Tangential force `F` (Pa or N).
    pub force: f64,
    /// Tangential displacement `q` at which `force` holds (m).
    pub q: f64,
    /// Normal load `Fz` at this point as given (Pa or N; `≤ 0` means separated).
    pub fz: f64,
    /// Displacement at the last (re-)contact: the `Et` term uses `q − q_ref` (m).
    pub q_ref: f64,
}

impl ValanisState {
    /// A virgin element at displacement `q` under normal load `fz`.
    pub fn virgin(q: f64, fz: f64) -> Self {
        Self {
            force: 0.0,
            q,
            fz,
            q_ref: q,
        }
    }
}

/// Project `force` onto the admissible band `|F − Et·(q − q_ref)| ≤ μ·Fz·(1 − Et/E0)`.
fn project(p: &ValanisParams, force: f64, q: f64, q_ref: f64, fz: f64) -> f64 {
    let centre = p.et * (q - q_ref);
    let half = p.slip_limit(fz);
    force.clamp(centre - half, centre + half)
}

/// Handle separation and re-contact inside the increment `state → (q1, fz1)`. Returns `Ok` with
/// the state from which the smooth update must start (moved to the re-contact point if contact
/// begins inside the increment), or `Err` with the final state when the increment ends separated.
fn contact_transition(
    state: &ValanisState,
    q1: f64,
    fz1: f64,
) -> std::result::Result<ValanisState, ValanisState> {
    if fz1 <= 0.0 {
        // Ends separated: no force, history forgotten.
        return Err(ValanisState {
            force: 0.0,
            q: q1,
            fz: fz1,
            q_ref: q1,
        });
    }
    if state.fz <= 0.0 {
        // Re-contact where the linearly interpolated load crosses zero.
        let (theta, _, _) = recontact_fraction(state.fz, fz1);
        let q_contact = state.q + theta * (q1 - state.q);
        return Ok(ValanisState::virgin(q_contact, 0.0));
    }
    Ok(*state)
}

/// The root `x1` of the backward-Euler quadratic `k·x² + (1 − A·k + B)·x + (B − A) = 0` of
/// [`implicit_euler_step`] (`A = g·(Et·(q1 − q_ref) − F0)`, `B = λ1·|Δq| ≥ 0`): the larger root,
/// the unique one with `1 + k·x > 0` (the discriminant exceeds `(1 − B + A·k)²` by `4B(1 − k)`),
/// in the cancellation-free form; for `k = 0` the linear equation's root `(A − B)/(1 + B)`.
fn implicit_euler_root(p: &ValanisParams, a: f64, b: f64) -> f64 {
    if p.k == 0.0 {
        return (a - b) / (1.0 + b);
    }
    let bb = 1.0 - a * p.k + b;
    let c = b - a;
    let disc = (bb * bb - 4.0 * p.k * c).max(0.0).sqrt();
    if bb > 0.0 {
        // x₊ = (−b + √Δ)/(2k) = 2c/(−b − √Δ)
        2.0 * c / (-bb - disc)
    } else {
        (-bb + disc) / (2.0 * p.k)
    }
}

/// One backward-Euler increment of the Valanis element from `state` to displacement `q1` under
/// normal load `fz1`.
///
/// Backward Euler: `F1 = F0 + Δq·E0·(1 + x1)/(1 + k·x1)`, `x1 = g·(Et·(q1 − q_ref) − F1)`,
/// `g = s·λ(Fz1)/E0`. Substituting `F1 = Et·(q1 − q_ref) − x1/g` gives the quadratic
/// `k·x² + (1 − A·k + B)·x + (B − A) = 0` with `A = g·(Et·(q1 − q_ref) − F0)` and
/// `B = λ1·|Δq| ≥ 0`; its larger root is the unique one with `1 + k·x > 0` (the discriminant
/// exceeds `(1 − B + A·k)²` by `4B(1 − k)`), evaluated in the cancellation-free form.
pub fn implicit_euler_step(
    p: &ValanisParams,
    state: &ValanisState,
    q1: f64,
    fz1: f64,
) -> ValanisState {
    let start = match contact_transition(state, q1, fz1) {
        Ok(s) => s,
        Err(separated) => return separated,
    };
    let fz1 = fz1.max(0.0);
    let dq = q1 - start.q;
    let q_ref = start.q_ref;
    let mut force = start.force;
    if dq != 0.0 {
        let lam = p.lambda(fz1);
        let g = dq.signum() * lam / p.e0;
        let x = implicit_euler_root(p, g * (p.et * (q1 - q_ref) - start.force), lam * dq.abs());
        force = p.et * (q1 - q_ref) - x / g;
    }
    ValanisState {
        force: project(p, force, q1, q_ref, fz1),
        q: q1,
        fz: fz1,
        q_ref,
    }
}

/// Index of the start force `F0` in the arrays of [`ValanisPartials`] (inputs
/// `(F0, q_ref0, q0, Fz0, q1, Fz1)`).
pub const F0: usize = 0;
/// Index of the start reference displacement `q_ref0`.
pub const QR0: usize = 1;
/// Index of the start displacement `q0`.
pub const Q0: usize = 2;
/// Index of the start normal load `Fz0`.
pub const FZ0: usize = 3;
/// Index of the end displacement `q1`.
pub const Q1: usize = 4;
/// Index of the end normal load `Fz1`.
pub const FZ1: usize = 5;

/// The start `(F, q, q_ref)` of the smooth update of an increment that ends in contact
/// (`fz1 > 0`) — the state itself, or the virgin state at the re-contact point
/// `q_c = q0 + θ·(q1 − q0)`, `θ = Fz0/(Fz0 − Fz1)` — and its derivatives with respect to the six
/// inputs.
struct SmoothStart {
    force: f64,
    q: f64,
    q_ref: f64,
    /// Derivatives of `force`, `q` and `q_ref` with respect to the six inputs.
    dforce: [f64; 6],
    dq: [f64; 6],
    dq_ref: [f64; 6],
}

fn smooth_start(state: &ValanisState, q1: f64, fz1: f64) -> SmoothStart {
    if state.fz <= 0.0 {
        let (theta, dth_dfz0, dth_dfz1) = recontact_fraction(state.fz, fz1);
        let qc = state.q + theta * (q1 - state.q);
        let mut dqc = [0.0; 6];
        dqc[Q0] = 1.0 - theta;
        dqc[Q1] = theta;
        dqc[FZ0] = (q1 - state.q) * dth_dfz0;
        dqc[FZ1] = (q1 - state.q) * dth_dfz1;
        SmoothStart {
            force: 0.0,
            q: qc,
            q_ref: qc,
            dforce: [0.0; 6],
            dq: dqc,
            dq_ref: dqc,
        }
    } else {
        SmoothStart {
            force: state.force,
            q: state.q,
            q_ref: state.q_ref,
            dforce: unit(F0),
            dq: unit(Q0),
            dq_ref: unit(QR0),
        }
    }
}

/// The frame shared by the differentiated steps ([`implicit_euler_step_partials`],
/// [`frozen_load_step_partials`]): an increment that ends separated; otherwise the smooth start,
/// the centre `Et·(q1 − q_ref)` of the band and its derivative, the integrator's unprojected end
/// force with its derivative (`unprojected(start, centre, dcentre)`), and their projection onto
/// the band of `Fz1`. The state is built from the same values (the step is not taken twice).
#[inline(always)]
fn differentiated_step(
    p: &ValanisParams,
    state: &ValanisState,
    q1: f64,
    fz1: f64,
    step: fn(&ValanisParams, &ValanisState, f64, f64) -> ValanisState,
    unprojected: impl FnOnce(&SmoothStart, f64, &[f64; 6]) -> (f64, [f64; 6]),
) -> (ValanisState, ValanisPartials) {
    if fz1 <= 0.0 {
        return (step(p, state, q1, fz1), separated_partials());
    }
    let st = smooth_start(state, q1, fz1);
    let dq1 = unit(Q1);
    let centre = p.et * (q1 - st.q_ref);
    let dcentre: [f64; 6] = std::array::from_fn(|i| p.et * (dq1[i] - st.dq_ref[i]));
    let (force, dforce) = unprojected(&st, centre, &dcentre);
    let d = ValanisPartials {
        force: projected_partials(p, force, centre, &dcentre, fz1, dforce),
        q_ref: st.dq_ref,
    };
    let out = ValanisState {
        force: project(p, force, q1, st.q_ref, fz1),
        q: q1,
        fz: fz1,
        q_ref: st.q_ref,
    };
    (out, d)
}

/// The partials of an increment that ends separated: `F1 = 0`, `q_ref1 = q1`.
fn separated_partials() -> ValanisPartials {
    let mut d = ValanisPartials::default();
    d.q_ref[Q1] = 1.0;
    d
}

/// The unit derivative of input `k`.
fn unit(k: usize) -> [f64; 6] {
    let mut v = [0.0; 6];
    v[k] = 1.0;
    v
}

/// Derivative of a force after its projection onto the band `|F − centre| ≤ μ·Fz1·(1 − Et/E0)`
/// ([`project`]): `dforce` where `force` lies inside, the band edge's `dcentre ± dhalf·dFz1`
/// outside.
fn projected_partials(
    p: &ValanisParams,
    force: f64,
    centre: f64,
    dcentre: &[f64; 6],
    fz1: f64,
    dforce: [f64; 6],
) -> [f64; 6] {
    let half = p.slip_limit(fz1);
    let dhalf = p.mu * (1.0 - p.et / p.e0);
    let dfz1 = unit(FZ1);
    if force > centre + half {
        std::array::from_fn(|i| dcentre[i] + dhalf * dfz1[i])
    } else if force < centre - half {
        std::array::from_fn(|i| dcentre[i] - dhalf * dfz1[i])
    } else {
        dforce
    }
}

/// Partial derivatives of one [`implicit_euler_step`] with respect to its inputs, in the order
/// `(F0, q_ref0, q0, Fz0, q1, Fz1)` (start force, start reference displacement, start
/// displacement, start normal load, end displacement, end normal load).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ValanisPartials {
    /// `∂F1/∂(F0, q_ref0, q0, Fz0, q1, Fz1)`.
    pub force: [f64; 6],
    /// `∂q_ref1/∂(F0, q_ref0, q0, Fz0, q1, Fz1)`.
    pub q_ref: [f64; 6],
}

/// [`implicit_euler_step`] together with the exact derivatives of the discrete update
/// ([`ValanisPartials`]), for Newton solvers that differentiate a time-discrete element (e.g. the
/// alternating frequency–time method of `crate::dynamics::aft`).
///
/// Derivation: the quadratic `P(x) = k·x² + (1 − A·k + B)·x + (B − A) = 0` of
/// [`implicit_euler_step`] is differentiated implicitly, `dx = −(P_A·dA + P_B·dB)/P_x`, with
/// `A = g·(Et·(q1 − q_ref) − F0)`, `B = λ(Fz1)·|q1 − q0|`, `g = s·λ/E0`, `dλ/dFz1 = −λ/Fz1`;
/// then `F1 = Et·(q1 − q_ref) − x/g`. On the projection (the force on the slip limit)
/// `F1 = Et·(q1 − q_ref) ± μ·Fz1·(1 − Et/E0)`. At re-contact inside the increment the start
/// point `q_c = q0 + θ·(q1 − q0)`, `θ = Fz0/(Fz0 − Fz1)` is differentiated too. On the kink
/// `q1 = q0` the one-sided derivative for `q1 > q0` is returned.
pub fn implicit_euler_step_partials(
    p: &ValanisParams,
    state: &ValanisState,
    q1: f64,
    fz1: f64,
) -> (ValanisState, ValanisPartials) {
    differentiated_step(
        p,
        state,
        q1,
        fz1,
        implicit_euler_step,
        |st, centre, dcentre| {
            let (fs, qs, qrs) = (st.force, st.q, st.q_ref);
            let (dfs, dqs, dqrs) = (&st.dforce, &st.dq, &st.dq_ref);
            let (dq1, dfz1) = (unit(Q1), unit(FZ1));
            let dq = q1 - qs;
            if dq == 0.0 {
                // F1 = F0 + Δq·E0·(1 + x)/(1 + k·x) + O(Δq²): the one-sided slope for Δq → 0+.
                let lam = p.lambda(fz1);
                let x = lam / p.e0 * (p.et * (q1 - qrs) - fs);
                let slope = force_slope(p, x);
                let mut df = *dfs;
                for i in 0..6 {
                    df[i] += slope * (dq1[i] - dqs[i]);
                }
                return (fs, df);
            }
            let lam = p.lambda(fz1);
            let s = dq.signum();
            let g = s * lam / p.e0;
            let dvar = p.et * (q1 - qrs) - fs;
            let a = g * dvar;
            let b = lam * dq.abs();
            let x = implicit_euler_root(p, a, b);
            let px = 2.0 * p.k * x + 1.0 - a * p.k + b;
            let pa = -p.k * x - 1.0;
            let pb = x + 1.0;
            let mut df = [0.0; 6];
            for i in 0..6 {
                let dlam = -lam / fz1 * dfz1[i];
                let dg = s * dlam / p.e0;
                let dd = p.et * (dq1[i] - dqrs[i]) - dfs[i];
                let da = g * dd + dvar * dg;
                let db = dq.abs() * dlam + lam * s * (dq1[i] - dqs[i]);
                let dx = -(pa * da + pb * db) / px;
                df[i] = dcentre[i] - dx / g + x / (g * g) * dg;
            }
            (centre - x / g, df)
        },
    )
}

/// Relative tolerance of [`reference_step`], as a fraction of the slip force scale.
pub const REFERENCE_TOLERANCE: f64 = 1e-10;

/// One increment of the accurate reference integrator. At constant normal load over the increment
/// (the path is then a monotonic branch) it is the exact solution [`closed_form_branch`];
/// otherwise adaptive Dormand–Prince 5(4) ([`adaptive_step`]) in the path
/// parameter `θ ∈ [0, 1]` with `q(θ) = q0 + θ·Δq`, `Fz(θ) = Fz0 + θ·ΔFz` (linear interpolation of
/// the input samples), error per step below [`REFERENCE_TOLERANCE`] × `max(μ·Fz, |F|)`.
///
/// Inside a step `x` is clamped to `≥ x∞` so that the right-hand side stays finite when the
/// normal load falls; after each accepted step the force is projected onto the admissible band
/// (the same policy as [`implicit_euler_step`]). Fails with [`Error::NonConvergence`] only if the
/// step size collapses.
pub fn reference_step(
    p: &ValanisParams,
    state: &ValanisState,
    q1: f64,
    fz1: f64,
) -> Result<ValanisState> {
    let start = match contact_transition(state, q1, fz1) {
        Ok(s) => s,
        Err(separated) => return Ok(separated),
    };
    if start.fz == fz1 {
        // Constant normal load over the increment: exact solution of the monotonic branch.
        let force = closed_form_branch(p, fz1, start.q_ref, start.q, start.force, q1);
        return Ok(ValanisState {
            force: project(p, force, q1, start.q_ref, fz1),
            q: q1,
            fz: fz1,
            q_ref: start.q_ref,
        });
    }
    adaptive_step(p, &start, q1, fz1)
}

/// One increment that is exact for a piecewise-linear displacement path when the normal load
/// steps to `fz1` at the start of the increment and is held over it: the start force is
/// projected onto the band of `fz1` (the falling-load policy) and the monotonic branch is then
/// integrated in closed form ([`closed_form_branch`]).
///
/// Where the load changes continuously this differs from [`reference_step`] only by the
/// load change within one increment (`O(ΔFz·Δq)`), at the cost of a few Newton iterations
/// instead of an adaptive integration. It carries none of the first-order lag of
/// [`implicit_euler_step`], whose error at coarse sampling (a drive increment comparable to
/// the stick range `μFz/E0`) is a systematic phase lag of the whole loop — the error that an
/// identification must not mistake for a physical effect (see `crate::diagnose::effects`).
pub fn frozen_load_step(
    p: &ValanisParams,
    state: &ValanisState,
    q1: f64,
    fz1: f64,
) -> ValanisState {
    let start = match contact_transition(state, q1, fz1) {
        Ok(s) => s,
        Err(separated) => return separated,
    };
    let f0 = project(p, start.force, start.q, start.q_ref, fz1);
    let force = closed_form_branch(p, fz1, start.q_ref, start.q, f0, q1);
    ValanisState {
        force: project(p, force, q1, start.q_ref, fz1),
        q: q1,
        fz: fz1,
        q_ref: start.q_ref,
    }
}

/// [`frozen_load_step`] together with the exact derivatives of the update ([`ValanisPartials`]),
/// for the alternating frequency–time method, whose Newton iteration differentiates the
/// element through the period.
///
/// Derivation, per input: the start (the state, or the re-contact point) as in
/// [`implicit_euler_step_partials`]; its force projected onto the band of `Fz1` (on the band's
/// edge `F0' = Et·(q0 − q_ref) ± μ·Fz1·(1 − Et/E0)`); then [`closed_form_branch`],
/// differentiated implicitly through `ψ(w) = k·r0·(eʷ − 1) + (k − 1)·w − D²·λ·|Δq| = 0`:
/// `dw = (d(D²λ|Δq|) − k·(eʷ − 1)·dr0)/ψ'(w)`, `dr0 = D·dx0`,
/// `dx0 = dg·(Et·(q0 − q_ref) − F0') + g·(Et·(dq0 − dq_ref) − dF0')` (zero where `x0` is
/// clamped to `x∞`), `dx1 = eʷ·(dr0 + r0·dw)/D` (`dx1 = dx0` on the asymptote), `g = s·λ/E0`,
/// `dλ/dFz1 = −λ/Fz1`; `F1 = Et·(q1 − q_ref) − x1/g`; finally the projection of `F1`. On the
/// kink `q1 = q0` the one-sided derivative for `q1 > q0` is returned.
pub fn frozen_load_step_partials(
    p: &ValanisParams,
    state: &ValanisState,
    q1: f64,
    fz1: f64,
) -> (ValanisState, ValanisPartials) {
    differentiated_step(
        p,
        state,
        q1,
        fz1,
        frozen_load_step,
        |st, centre, dcentre| {
            let (fs, qs, qrs) = (st.force, st.q, st.q_ref);
            let (dfs, dqs, dqrs) = (&st.dforce, &st.dq, &st.dq_ref);
            let (dq1, dfz1) = (unit(Q1), unit(FZ1));
            // The start force on the band of Fz1.
            let centre0 = p.et * (qs - qrs);
            let dcentre0: [f64; 6] = std::array::from_fn(|i| p.et * (dqs[i] - dqrs[i]));
            let f0 = project(p, fs, qs, qrs, fz1);
            let df0 = projected_partials(p, fs, centre0, &dcentre0, fz1, *dfs);
            let dq = q1 - qs;
            if dq == 0.0 {
                // F1 = F0' and, for Δq → 0+, dF1/dq1 = the branch's slope at the start.
                let x = p.lambda(fz1) / p.e0 * (centre - f0);
                let slope = force_slope(p, x);
                (
                    f0,
                    std::array::from_fn(|i| df0[i] + slope * (dq1[i] - dqs[i])),
                )
            } else {
                let b = branch_solution(p, fz1, qrs, qs, f0, q1);
                let dd = p.et / p.e0 * p.k - 1.0;
                // λ and g depend on Fz1 only.
                let dlam_dfz1 = -b.lam / fz1;
                let dg_dfz1 = b.s * dlam_dfz1 / p.e0;
                // dx1 = c_x0·dx0 + c_t·d(λ·|Δq|), from dx1 = eʷ·(dr0 + r0·dw)/D with dr0 = D·dx0.
                let (c_x0, c_t) = if b.r0 >= 0.0 {
                    (1.0, 0.0)
                } else {
                    let psi_w = p.k * b.r0 * b.ew + (p.k - 1.0);
                    (
                        b.ew * (1.0 - b.r0 * p.k * (b.ew - 1.0) / psi_w),
                        b.ew * b.r0 * dd / psi_w,
                    )
                };
                let inv_g = 1.0 / b.g;
                let gap0 = if b.clamped { 0.0 } else { centre0 - f0 };
                let g0 = if b.clamped { 0.0 } else { b.g };
                let df: [f64; 6] = std::array::from_fn(|i| {
                    let dg = dg_dfz1 * dfz1[i];
                    let dx0 = dg * gap0 + g0 * (dcentre0[i] - df0[i]);
                    let dtarget = dlam_dfz1 * dfz1[i] * dq.abs() + b.lam * b.s * (dq1[i] - dqs[i]);
                    let dx1 = c_x0 * dx0 + c_t * dtarget;
                    dcentre[i] - dx1 * inv_g + b.x1 * inv_g * inv_g * dg
                });
                (centre - b.x1 / b.g, df)
            }
        },
    )
}

/// One increment by adaptive Dormand–Prince 5(4) (see [`reference_step`]); `state` must be in
/// contact (`fz > 0`, or `0` at the re-contact point) and `fz1 > 0`.
pub fn adaptive_step(
    p: &ValanisParams,
    start: &ValanisState,
    q1: f64,
    fz1: f64,
) -> Result<ValanisState> {
    adaptive_step_with(|_| *p, |_| 0.0, start, q1, fz1)
}

/// [`adaptive_step`] with parameters that follow the instantaneous normal load:
/// `params_at(Fz)` is evaluated at every stage of the Dormand–Prince step (and for the
/// projection onto the band after it), and the elastic part of the force `F − Et·(q − q_ref)`
/// follows `E0` (`log_slope(Fz) = d ln E0/d ln Fz`; see [`LoadDependentValanis`]). With `params_at` constant and `log_slope` zero it is
/// [`adaptive_step`].
fn adaptive_step_with(
    params_at: impl Fn(f64) -> ValanisParams,
    log_slope: impl Fn(f64) -> f64,
    start: &ValanisState,
    q1: f64,
    fz1: f64,
) -> Result<ValanisState> {
    let fz1 = fz1.max(0.0);
    let p = &params_at(fz1);
    let (q0, fz0, q_ref) = (start.q, start.fz.max(0.0), start.q_ref);
    let dq = q1 - q0;
    if dq == 0.0 {
        // Only the load moves: the elastic force follows E0 exactly.
        let centre = p.et * (q1 - q_ref);
        let moving = fz1 != fz0 && fz0 > 0.0 && log_slope(fz1) != 0.0;
        let force = if moving {
            centre + (start.force - centre) * p.e0 / params_at(fz0).e0
        } else {
            start.force
        };
        return Ok(ValanisState {
            force: project(p, force, q1, q_ref, fz1),
            q: q1,
            fz: fz1,
            q_ref,
        });
    }
    let s = dq.signum();
    let dfz = fz1 - fz0;
    // dF/dθ along the increment: the Valanis slope, and the elastic force following E0(Fz).
    let rhs = |theta: f64, f: f64| -> f64 {
        let q = q0 + theta * dq;
        let fz = (fz0 + theta * dfz).max(f64::MIN_POSITIVE);
        let p = &params_at(fz);
        let elastic = f - p.et * (q - q_ref);
        let x = (p.lambda(fz) / p.e0 * s * (-elastic)).max(p.x_asymptote());
        dq * force_slope(p, x) + log_slope(fz) * dfz / fz * elastic
    };
    let scale = (p.mu * fz0.max(fz1))
        .max(start.force.abs())
        .max(f64::MIN_POSITIVE);
    let tol = REFERENCE_TOLERANCE * scale;

    // Dormand–Prince 5(4) tableau.
    const C: [f64; 7] = [0.0, 0.2, 0.3, 0.8, 8.0 / 9.0, 1.0, 1.0];
    const A: [[f64; 6]; 7] = [
        [0.0; 6],
        [0.2, 0.0, 0.0, 0.0, 0.0, 0.0],
        [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0],
        [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0],
        [
            19372.0 / 6561.0,
            -25360.0 / 2187.0,
            64448.0 / 6561.0,
            -212.0 / 729.0,
            0.0,
            0.0,
        ],
        [
            9017.0 / 3168.0,
            -355.0 / 33.0,
            46732.0 / 5247.0,
            49.0 / 176.0,
            -5103.0 / 18656.0,
            0.0,
        ],
        [
            35.0 / 384.0,
            0.0,
            500.0 / 1113.0,
            125.0 / 192.0,
            -2187.0 / 6784.0,
            11.0 / 84.0,
        ],
    ];
    const B5: [f64; 7] = [
        35.0 / 384.0,
        0.0,
        500.0 / 1113.0,
        125.0 / 192.0,
        -2187.0 / 6784.0,
        11.0 / 84.0,
        0.0,
    ];
    const B4: [f64; 7] = [
        5179.0 / 57600.0,
        0.0,
        7571.0 / 16695.0,
        393.0 / 640.0,
        -92097.0 / 339200.0,
        187.0 / 2100.0,
        1.0 / 40.0,
    ];

    let mut theta = 0.0;
    let mut f = start.force;
    let mut h: f64 = 0.25;
    let mut steps = 0usize;
    const MAX_STEPS: usize = 100_000;
    while theta < 1.0 {
        if steps >= MAX_STEPS || h < 1e-14 {
            return Err(Error::NonConvergence {
                solver: "Valanis reference integrator (Dormand–Prince 5(4))".into(),
                iterations: steps,
                residual: h,
                tolerance: 1e-14,
            });
        }
        steps += 1;
        h = h.min(1.0 - theta);
        let mut kk = [0.0; 7];
        for i in 0..7 {
            let mut fi = f;
            for (j, kj) in kk.iter().enumerate().take(i) {
                fi += h * A[i][j] * kj;
            }
            kk[i] = rhs(theta + C[i] * h, fi);
        }
        let f5: f64 = f + h * B5.iter().zip(&kk).map(|(b, k)| b * k).sum::<f64>();
        let f4: f64 = f + h * B4.iter().zip(&kk).map(|(b, k)| b * k).sum::<f64>();
        let err = (f5 - f4).abs();
        if err <= tol || h < 1e-12 {
            theta += h;
            let q = q0 + theta * dq;
            let fz = fz0 + theta * (fz1 - fz0);
            f = project(&params_at(fz), f5, q, q_ref, fz);
        }
        let factor = if err == 0.0 {
            5.0
        } else {
            (0.9 * (tol / err).powf(0.2)).clamp(0.2, 5.0)
        };
        h *= factor;
    }
    Ok(ValanisState {
        force: f,
        q: q1,
        fz: fz1,
        q_ref,
    })
}

/// Which integrator [`integrate`] uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Integrator {
    /// Backward Euler on each input increment ([`implicit_euler_step`]).
    ImplicitEuler,
    /// Adaptive Dormand–Prince 5(4) reference ([`reference_step`]).
    Reference,
}

fn check_history(q: &[f64], fz: &[f64]) -> Result<()> {
    if q.len() != fz.len() {
        return Err(Error::param(
            "fz",
            format!(
                "normal-load history has {} samples, displacement history {}",
                fz.len(),
                q.len()
            ),
        ));
    }
    if let Some(i) = q.iter().position(|v| !v.is_finite()) {
        return Err(Error::param("q", format!("sample {i} is not finite")));
    }
    if let Some(i) = fz.iter().position(|v| !v.is_finite()) {
        return Err(Error::param("fz", format!("sample {i} is not finite")));
    }
    Ok(())
}

/// Force history `F[i]` of a virgin element driven by displacements `q[i]` under normal loads
/// `fz[i]` (same length; `fz ≤ 0` is separation). `F[0] = 0`.
pub fn integrate(p: &ValanisParams, q: &[f64], fz: &[f64], method: Integrator) -> Result<Vec<f64>> {
    p.validate()?;
    drive(q, fz, |state, qi, fzi| match method {
        Integrator::ImplicitEuler => Ok(implicit_euler_step(p, state, qi, fzi)),
        Integrator::Reference => reference_step(p, state, qi, fzi),
    })
}

/// [`integrate`] with [`Integrator::ImplicitEuler`].
pub fn integrate_implicit_euler(p: &ValanisParams, q: &[f64], fz: &[f64]) -> Result<Vec<f64>> {
    integrate(p, q, fz, Integrator::ImplicitEuler)
}

/// [`integrate`] with [`Integrator::Reference`].
pub fn integrate_reference(p: &ValanisParams, q: &[f64], fz: &[f64]) -> Result<Vec<f64>> {
    integrate(p, q, fz, Integrator::Reference)
}

/// Two in-plane directions as two uncoupled elements sharing the normal load:
/// returns `(Fx, Fy)` for displacement histories `qx`, `qy`.
pub fn integrate_in_plane(
    p: &ValanisParams,
    qx: &[f64],
    qy: &[f64],
    fz: &[f64],
    method: Integrator,
) -> Result<(Vec<f64>, Vec<f64>)> {
    Ok((integrate(p, qx, fz, method)?, integrate(p, qy, fz, method)?))
}

/// A Valanis element whose parameters follow the instantaneous normal load: `E0(Fz)`, `k(Fz)`,
/// `Et(Fz)` tabulated at constant loads (the calibration table's rows, or constant-load fits
/// spanning a cycle's load range) and interpolated between them, the slip limit staying
/// `μ·Fz` through `λ = E0(Fz)/(μ·Fz·(1 − k·Et/E0))`.
///
/// This is the element the reference underplatform-damper study proposes where `λ ∝ 1/Fz` alone
/// does not follow the contact: stiffness and shape that depend on the instantaneous load as the
/// rough contact's do. The interpolation is piecewise linear in `ln Fz` for `ln E0`, `k` and
/// `Et/E0` (power laws between the tabulated loads; a rough contact's `E0 ∝ p^m` with `m`
/// slowly varying), constant outside the tabulated range.
///
/// **What the force does when the load moves.** A stiffness that follows the load cannot enter
/// the rate equation alone: `dF = E0(Fz)·dq` around a cycle in which `q` and `Fz` are out of
/// phase gives `∮E0 dq ≠ 0`, a force that drifts cycle after cycle. Here the elastic force is
/// the stiffness times the element's elastic displacement `w`, `F − Et·(q − q_ref) = E0(Fz)·w`,
/// and the Valanis law governs `w`:
/// `dF = E0(Fz)·(1 + x)/(1 + k·x)·dq + d ln E0·(F − Et·(q − q_ref))`,
/// so that in stick the force is a function of the state (no drift around a closed cycle) and
/// the slip limit stays `μ·Fz`. (Releasing force on a falling load only, the rule of the
/// contact's own history, drifts too: by +34 % to +155 % in energy per cycle on the cases of
/// `docs/contact.md`.) At constant load it is the plain element.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct LoadDependentValanis {
    /// Tabulated normal loads, strictly increasing and positive (Pa or N).
    pub loads: Vec<f64>,
    /// The element's parameters at each tabulated load (same `μ`).
    pub params: Vec<ValanisParams>,
}

impl LoadDependentValanis {
    /// Build and check: at least one load, loads positive and strictly increasing, one valid
    /// parameter set per load, one friction coefficient.
    pub fn new(loads: Vec<f64>, params: Vec<ValanisParams>) -> Result<Self> {
        if loads.is_empty() || loads.len() != params.len() {
            return Err(Error::param(
                "loads",
                format!(
                    "{} loads for {} parameter sets (need the same number, at least one)",
                    loads.len(),
                    params.len()
                ),
            ));
        }
        for (i, &l) in loads.iter().enumerate() {
            crate::core::error::require_positive("loads", l)?;
            if i > 0 && l <= loads[i - 1] {
                return Err(Error::param(
                    "loads",
                    format!("must increase strictly: {} after {}", l, loads[i - 1]),
                ));
            }
        }
        for p in &params {
            p.validate()?;
            if p.mu != params[0].mu {
                return Err(Error::param(
                    "mu",
                    format!("one friction coefficient: {} and {}", params[0].mu, p.mu),
                ));
            }
        }
        Ok(Self { loads, params })
    }

    /// `d ln E0 / d ln Fz` at normal load `fz`: the power of the segment `fz` lies in (zero
    /// outside the tabulated range, where the parameters are held).
    pub fn log_slope(&self, fz: f64) -> f64 {
        let (l, p) = (&self.loads, &self.params);
        let n = l.len();
        if n == 1 || fz <= l[0] || fz >= l[n - 1] {
            return 0.0;
        }
        let i = l.partition_point(|&x| x <= fz).clamp(1, n - 1);
        (p[i].e0 / p[i - 1].e0).ln() / (l[i] / l[i - 1]).ln()
    }

    /// The parameters at normal load `fz` (see the type's documentation).
    pub fn at(&self, fz: f64) -> ValanisParams {
        let (l, p) = (&self.loads, &self.params);
        let n = l.len();
        if n == 1 || fz <= l[0] {
            return p[0];
        }
        if fz >= l[n - 1] {
            return p[n - 1];
        }
        let i = l.partition_point(|&x| x <= fz).clamp(1, n - 1);
        let t = (fz / l[i - 1]).ln() / (l[i] / l[i - 1]).ln();
        let lerp = |a: f64, b: f64| a + t * (b - a);
        let e0 = (lerp(p[i - 1].e0.ln(), p[i].e0.ln())).exp();
        ValanisParams {
            e0,
            k: lerp(p[i - 1].k, p[i].k),
            et: e0 * lerp(p[i - 1].et / p[i - 1].e0, p[i].et / p[i].e0),
            mu: p[i].mu,
        }
    }
}

/// The Valanis element whose stiffness follows the instantaneous normal load as a power law,
/// `E0(Fz) = E0_ref·(Fz/Fz_ref)^a`, with `Et/E0`, `k` and `μ` fixed: the law of
/// [`LoadDependentValanis`] on one segment of a calibration table (`E0″ ∝ p^a` between two rows),
/// stepped at a frozen load for the alternating frequency–time method with exact partials.
///
/// One increment `(q0, Fz0) → (q1, Fz1)`: the load steps to `Fz1` at `q0`, where the elastic
/// force follows the stiffness (`F − Et·(q − q_ref) = E0(Fz)·w` at fixed elastic displacement
/// `w`, so `F0' = F0·E0(Fz1)/E0(Fz0)` with `Et ∝ E0`), then the branch is integrated in closed
/// form at `Fz1` with the parameters of `Fz1` ([`frozen_load_step`]). As the load's change within
/// the increment shrinks this converges to [`load_dependent_reference_step`].
///
/// Partials: those of [`frozen_load_step_partials`] at the parameters of `Fz1`, plus the
/// stiffness's dependence on `Fz1`, which follows from the law's scaling: with `k` and `Et/E0`
/// fixed, `λ·q = q·E0/(μ·Fz·(1 − k·Et/E0))` is unchanged when `E0` is multiplied and every
/// displacement divided by the same factor, so (with the step's translation invariance)
/// `E0·∂F1/∂E0 = (q_ref0 − q0)·∂F1/∂q_ref0 + (q1 − q0)·∂F1/∂q1` and
/// `E0·∂q_ref1/∂E0 = (q_ref0 − q0)·∂q_ref1/∂q_ref0 + (q1 − q0)·∂q_ref1/∂q1 − (q_ref1 − q0)`;
/// `d ln E0/dFz1 = a/Fz1`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoadFollowingValanis {
    /// Parameters at the reference load (stiffnesses in N/m or N/m³).
    pub reference: ValanisParams,
    /// The reference load `Fz_ref` (N or Pa), > 0.
    pub reference_load: f64,
    /// The exponent `a = d ln E0 / d ln Fz`.
    pub e0_exponent: f64,
}

impl LoadFollowingValanis {
    /// Build and validate (parameters as [`ValanisParams`], `Fz_ref > 0`, `a` finite).
    pub fn new(reference: ValanisParams, reference_load: f64, e0_exponent: f64) -> Result<Self> {
        reference.validate()?;
        crate::core::error::require_positive("reference_load", reference_load)?;
        if !e0_exponent.is_finite() {
            return Err(Error::param(
                "E0_load_exponent",
                format!("{e0_exponent} is not finite"),
            ));
        }
        Ok(Self {
            reference,
            reference_load,
            e0_exponent,
        })
    }

    /// `E0(Fz)/E0_ref` (1 at a load `≤ 0`, where the element is separated).
    #[inline]
    fn ratio(&self, fz: f64) -> f64 {
        if fz > 0.0 {
            (fz / self.reference_load).powf(self.e0_exponent)
        } else {
            1.0
        }
    }

    /// The parameters at normal load `fz`.
    pub fn at(&self, fz: f64) -> ValanisParams {
        let r = self.ratio(fz);
        ValanisParams {
            e0: self.reference.e0 * r,
            et: self.reference.et * r,
            ..self.reference
        }
    }

    /// The start state with its force carried to the stiffness of `fz1` (type documentation),
    /// and `∂F0'/∂Fz0`, `∂F0'/∂Fz1`, `∂F0'/∂F0`.
    #[inline]
    fn rescaled_start(&self, state: &ValanisState, fz1: f64) -> (ValanisState, [f64; 3]) {
        if state.fz > 0.0 && fz1 > 0.0 {
            let a = self.e0_exponent;
            let r = (fz1 / state.fz).powf(a);
            let f = state.force * r;
            (
                ValanisState { force: f, ..*state },
                [-a * f / state.fz, a * f / fz1, r],
            )
        } else {
            (*state, [0.0, 0.0, 1.0])
        }
    }
}

impl FrozenLoadLaw for LoadFollowingValanis {
    fn frozen_step(&self, state: &ValanisState, q1: f64, fz1: f64) -> ValanisState {
        let (start, _) = self.rescaled_start(state, fz1);
        frozen_load_step(&self.at(fz1), &start, q1, fz1)
    }

    fn frozen_step_partials(
        &self,
        state: &ValanisState,
        q1: f64,
        fz1: f64,
    ) -> (ValanisState, ValanisPartials) {
        let (start, [df_dfz0, df_dfz1, df_df0]) = self.rescaled_start(state, fz1);
        let (out, mut d) = frozen_load_step_partials(&self.at(fz1), &start, q1, fz1);
        if fz1 <= 0.0 {
            return (out, d);
        }
        let (dq_ref, dq1) = (start.q_ref - start.q, q1 - start.q);
        let e_force = dq_ref * d.force[QR0] + dq1 * d.force[Q1];
        let e_q_ref = dq_ref * d.q_ref[QR0] + dq1 * d.q_ref[Q1] - (out.q_ref - start.q);
        let dln_e0 = self.e0_exponent / fz1;
        for (row, e) in [(&mut d.force, e_force), (&mut d.q_ref, e_q_ref)] {
            let by_f0 = row[F0];
            row[FZ1] += e * dln_e0 + by_f0 * df_dfz1;
            row[FZ0] += by_f0 * df_dfz0;
            row[F0] = by_f0 * df_df0;
        }
        (out, d)
    }
}

/// [`reference_step`] of the load-dependent element: the exact branch at the parameters of a
/// constant load; where the load changes, adaptive Dormand–Prince with the parameters evaluated
/// at every stage and the release of a falling load (see [`LoadDependentValanis`]).
pub fn load_dependent_reference_step(
    element: &LoadDependentValanis,
    state: &ValanisState,
    q1: f64,
    fz1: f64,
) -> Result<ValanisState> {
    let start = match contact_transition(state, q1, fz1) {
        Ok(s) => s,
        Err(separated) => return Ok(separated),
    };
    if start.fz == fz1 {
        return reference_step(&element.at(fz1), &start, q1, fz1);
    }
    adaptive_step_with(
        |fz| element.at(fz),
        |fz| element.log_slope(fz),
        &start,
        q1,
        fz1,
    )
}

/// Force history of a virgin load-dependent element driven by `q[i]` under `fz[i]`
/// ([`load_dependent_reference_step`]); `F[0] = 0`.
pub fn integrate_load_dependent(
    element: &LoadDependentValanis,
    q: &[f64],
    fz: &[f64],
) -> Result<Vec<f64>> {
    drive(q, fz, |state, qi, fzi| {
        load_dependent_reference_step(element, state, qi, fzi)
    })
}

/// Force history of a virgin element driven by `q[i]` under `fz[i]`, one increment at a time by
/// `step` (the history checked first); `F[0] = 0`.
fn drive(
    q: &[f64],
    fz: &[f64],
    mut step: impl FnMut(&ValanisState, f64, f64) -> Result<ValanisState>,
) -> Result<Vec<f64>> {
    check_history(q, fz)?;
    let mut out = Vec::with_capacity(q.len());
    let Some((&q_first, &fz_first)) = q.first().zip(fz.first()) else {
        return Ok(out);
    };
    let mut state = ValanisState::virgin(q_first, fz_first);
    out.push(state.force);
    for (&qi, &fzi) in q.iter().zip(fz).skip(1) {
        state = step(&state, qi, fzi)?;
        out.push(state.force);
    }
    Ok(out)
}

/// Exact force at `q1` on a monotonic branch at constant normal load `fz`, starting from
/// `(q0, f0)` with `q_ref` the reference displacement of the `Et` term.
///
/// With `a = Et/E0`, `C = a − 1`, `D = a·k − 1`, the ODE `dx/d|q| = λ·(C + D·x)/(1 + k·x)`
/// separates and integrates to
/// `λ·|q1 − q0| = (k/D)·(x1 − x0) + ((k − 1)/D²)·ln((C + D·x1)/(C + D·x0))`.
/// In the variable `w = ln((C + D·x1)/(C + D·x0)) ≤ 0` this reads
/// `ψ(w) = k·r0·(eʷ − 1) + (k − 1)·w − D²·λ·|q1 − q0| = 0` with `r0 = C + D·x0 ≤ 0`; `ψ` is
/// decreasing and concave, so Newton's method from `w = 0` converges monotonically to the root.
/// Then `x1 = (r0·eʷ − C)/D` and `F1 = Et·(q1 − q_ref) − s·x1·E0/λ`.
pub fn closed_form_branch(
    p: &ValanisParams,
    fz: f64,
    q_ref: f64,
    q0: f64,
    f0: f64,
    q1: f64,
) -> f64 {
    let dq = q1 - q0;
    if fz <= 0.0 {
        return 0.0;
    }
    if dq == 0.0 {
        return f0;
    }
    let b = branch_solution(p, fz, q_ref, q0, f0, q1);
    p.et * (q1 - q_ref) - b.x1 / b.g
}

/// The intermediate values of [`closed_form_branch`] for `fz > 0` and `q1 ≠ q0`, which its
/// derivatives ([`frozen_load_step_partials`]) need.
struct Branch {
    /// Direction `sign(q1 − q0)`, `λ(fz)` and `g = s·λ/E0`.
    s: f64,
    lam: f64,
    g: f64,
    /// Whether `x0` was clamped to `x∞`.
    clamped: bool,
    /// `r0 = C + D·x0`; when `r0 < 0`, `eʷ` with `w` the root of `ψ` (1 otherwise).
    r0: f64,
    ew: f64,
    x1: f64,
}

fn branch_solution(p: &ValanisParams, fz: f64, q_ref: f64, q0: f64, f0: f64, q1: f64) -> Branch {
    let dq = q1 - q0;
    let s = dq.signum();
    let lam = p.lambda(fz);
    let g = s * lam / p.e0;
    let a = p.et / p.e0;
    let (c, d) = (a - 1.0, a * p.k - 1.0);
    let x0_raw = g * (p.et * (q0 - q_ref) - f0);
    let clamped = x0_raw < p.x_asymptote();
    let x0 = x0_raw.max(p.x_asymptote());
    let r0 = c + d * x0;
    let mut ew = 1.0;
    let x1 = if r0 >= 0.0 {
        // On the asymptote already: the force follows it.
        x0
    } else {
        let target = d * d * lam * dq.abs();
        // Start from the root of ψ's second-order Taylor polynomial at 0,
        // `½·k·r0·w² + (k·r0 + k − 1)·w − target = 0`, within O(target³) of ψ's root (when the
        // quadratic has no real root, the first Newton step from 0 instead).
        let (b1, a2) = (p.k * r0 + p.k - 1.0, 0.5 * p.k * r0);
        let disc = b1 * b1 + 4.0 * a2 * target;
        let mut w = if disc >= 0.0 {
            // The root nearer 0, cancellation-free (b1 < 0).
            -2.0 * target / (-b1 + disc.sqrt())
        } else {
            target / b1
        };
        ew = w.exp();
        for _ in 0..100 {
            let psi = p.k * r0 * (ew - 1.0) + (p.k - 1.0) * w - target;
            let dpsi = p.k * r0 * ew + (p.k - 1.0);
            let step = psi / dpsi;
            w -= step;
            // ψ''/ψ' lies in [0, 1) (k·r0·eʷ ≤ 0 and k − 1 < 0), so the error left after a
            // step is at most step²/2: stop once that is below 1e-15, with
            // `e^(w − step) = eʷ·(1 − step + step²/2)` to O(step³) ≈ 1e-23 (no further exp).
            if step * step <= 2e-15 * w.abs().max(1.0) {
                ew *= 1.0 - step + 0.5 * step * step;
                break;
            }
            ew = w.exp();
        }
        (r0 * ew - c) / d
    };
    Branch {
        s,
        lam,
        g,
        clamped,
        r0,
        ew,
        x1,
    }
}

/// A Valanis element is reported in gross slip when its force is within 1 % of the sliding
/// asymptote, `|F − Et·(q − q_ref)| ≥ 0.99·μ·Fz·(1 − Et/E0)`; below it, stick includes microslip.
pub const GROSS_SLIP_FRACTION: f64 = 0.99;

/// Where one Valanis direction of a [`HystereticElement`] keeps its state and reads its
/// displacement (indices into the element's vectors).
///
/// [`HystereticElement`]: crate::element::HystereticElement
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Direction {
    /// Index of the force in the state vector.
    pub force: usize,
    /// Index of `q_ref` (the displacement at the last reversal) in the state vector.
    pub q_ref: usize,
    /// Index of the tangential displacement in `u` (and of the force in `f`).
    pub u: usize,
    /// Index of the normal approach `un` in `u` and the slopes `dFz/dun` at the increment's
    /// start and end (both `kn` when the normal load is `N0 + kn·un`) for a contact element;
    /// `None` for a constant normal load.
    pub normal: Option<(usize, [f64; 2])>,
}

/// A Valanis law stepped at a load frozen over each increment ([`frozen_load_step`]), with the
/// exact partials of the step: the constant-parameter element ([`ValanisParams`]) or the one
/// whose stiffness follows the load ([`LoadFollowingValanis`]).
pub trait FrozenLoadLaw {
    /// One increment from `state` to `(q1, fz1)`.
    fn frozen_step(&self, state: &ValanisState, q1: f64, fz1: f64) -> ValanisState;
    /// The increment and its partials ([`ValanisPartials`]).
    fn frozen_step_partials(
        &self,
        state: &ValanisState,
        q1: f64,
        fz1: f64,
    ) -> (ValanisState, ValanisPartials);
}

impl FrozenLoadLaw for ValanisParams {
    #[inline(always)]
    fn frozen_step(&self, state: &ValanisState, q1: f64, fz1: f64) -> ValanisState {
        frozen_load_step(self, state, q1, fz1)
    }
    #[inline(always)]
    fn frozen_step_partials(
        &self,
        state: &ValanisState,
        q1: f64,
        fz1: f64,
    ) -> (ValanisState, ValanisPartials) {
        frozen_load_step_partials(self, state, q1, fz1)
    }
}

/// One [`frozen_load_step`] of a Valanis direction `c` of an element, from state `s0` at `u0`
/// to `u1` under normal loads `fz0` → `fz1`: its force and `q_ref` into `s1`, its force into `f1`
/// and, with `partials`, the derivatives of [`frozen_load_step_partials`] in the element's
/// layout (chained through `∂Fz/∂un = kn` for a contact).
// Inlined into its two callers: the indices of `c` are then constants (one AFT period calls it
// once per sample and direction).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn direction_step<L: FrozenLoadLaw>(
    p: &L,
    c: Direction,
    s0: &[f64],
    u0: &[f64],
    u1: &[f64],
    fz0: f64,
    fz1: f64,
    s1: &mut [f64],
    f1: &mut [f64],
    partials: Option<&mut ElementPartials>,
) {
    let st = ValanisState {
        force: s0[c.force],
        q: u0[c.u],
        fz: fz0,
        q_ref: s0[c.q_ref],
    };
    let out = match partials {
        None => p.frozen_step(&st, u1[c.u], fz1),
        Some(e) => {
            let (out, d) = p.frozen_step_partials(&st, u1[c.u], fz1);
            let (m, dim) = (e.m, e.d);
            // Rows: the two states, then the force (which acts on the displacement's component).
            for (row, g) in [(c.force, d.force), (c.q_ref, d.q_ref)] {
                e.ds_ds0[row * m + c.force] = g[F0];
                e.ds_ds0[row * m + c.q_ref] = g[QR0];
                e.ds_du0[row * dim + c.u] = g[Q0];
                e.ds_du1[row * dim + c.u] = g[Q1];
                if let Some((n, [k0, k1])) = c.normal {
                    e.ds_du0[row * dim + n] = g[FZ0] * k0;
                    e.ds_du1[row * dim + n] = g[FZ1] * k1;
                }
            }
            let row = c.u;
            e.df_ds0[row * m + c.force] = d.force[F0];
            e.df_ds0[row * m + c.q_ref] = d.force[QR0];
            e.df_du0[row * dim + c.u] = d.force[Q0];
            e.df_du1[row * dim + c.u] = d.force[Q1];
            if let Some((n, [k0, k1])) = c.normal {
                e.df_du0[row * dim + n] = d.force[FZ0] * k0;
                e.df_du1[row * dim + n] = d.force[FZ1] * k1;
            }
            out
        }
    };
    s1[c.force] = out.force;
    s1[c.q_ref] = out.q_ref;
    f1[c.u] = out.force;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::{dissipated_energy, sine_history};

    fn params() -> ValanisParams {
        ValanisParams::new(1.0e13, 0.4, 0.0, 0.6).unwrap()
    }

    #[test]
    fn initial_slope_is_e0_and_force_saturates_at_mu_fz() {
        let p = params();
        let fz = 1.0e6;
        let f = closed_form_branch(&p, fz, 0.0, 0.0, 0.0, 1e-12);
        // Secant over 1e-12 m differs from the tangent by ≈ (1−k)·E0·q/(2μFz) = 5e-6.
        assert!((f / 1e-12 - p.e0).abs() / p.e0 < 1e-5, "{}", f / 1e-12);
        let f_far = closed_form_branch(&p, fz, 0.0, 0.0, 0.0, 1e-4);
        assert!((f_far - p.mu * fz).abs() / (p.mu * fz) < 1e-9);
    }

    #[test]
    fn reload_slope_after_gross_slip_is_2e0_over_1_plus_k() {
        for k in [0.0, 0.3, 0.8] {
            let p = ValanisParams::new(2.0e12, k, 0.0, 0.5).unwrap();
            let fz = 2.0e6;
            // Drive into gross slip (F ≈ μFz), then reverse by a tiny step.
            let q = [0.0, 2e-4, 2e-4 - 1e-13];
            let f = integrate_reference(&p, &q, &[fz; 3]).unwrap();
            assert!((f[1] - p.mu * fz).abs() / (p.mu * fz) < 1e-9);
            let slope = (f[1] - f[2]) / 1e-13;
            let expect = 2.0 * p.e0 / (1.0 + k);
            assert!(
                (slope - expect).abs() / expect < 1e-4,
                "k={k}: {slope} vs {expect}"
            );
            assert!((p.reload_slope() - expect).abs() < 1e-3 * expect);
        }
    }

    #[test]
    fn adaptive_integrator_matches_closed_form_on_branches() {
        let p = ValanisParams::new(1.0e13, 0.6, 1.0e12, 0.6).unwrap();
        let fz = 1.0e6;
        // Virgin loading branch, stepped with Dormand–Prince from sample to sample.
        let mut st = ValanisState::virgin(0.0, fz);
        for i in 1..=50 {
            let q1 = i as f64 * 1e-8;
            st = adaptive_step(&p, &st, q1, fz).unwrap();
            let exact = closed_form_branch(&p, fz, 0.0, 0.0, 0.0, q1);
            assert!(
                (st.force - exact).abs() < 1e-8 * p.mu * fz,
                "{} vs {exact}",
                st.force
            );
        }
        // Unloading branch from the end point, one large step each way.
        let s1 = adaptive_step(&p, &st, st.q - 3e-7, fz).unwrap();
        let exact = closed_form_branch(&p, fz, 0.0, st.q, st.force, st.q - 3e-7);
        assert!((s1.force - exact).abs() < 1e-8 * p.mu * fz);
    }

    #[test]
    fn closed_form_satisfies_the_valanis_ode() {
        // Central difference of the closed-form branch against dF/dq = E0(1+x)/(1+kx).
        let p = ValanisParams::new(3.0e12, 0.8, 2.0e11, 0.5).unwrap();
        let fz = 4.0e6;
        let (q0, f0) = (1e-6, 0.3 * p.mu * fz);
        for dq in [1e-8f64, 1e-7, 5e-7, -2e-7, -1e-6] {
            let h = 1e-12 * dq.signum();
            let f = |q: f64| closed_form_branch(&p, fz, 0.0, q0, f0, q);
            let slope = (f(q0 + dq + h) - f(q0 + dq - h)) / (2.0 * h);
            let x = p.lambda(fz) / p.e0 * dq.signum() * (p.et * (q0 + dq) - f(q0 + dq));
            let expect = force_slope(&p, x);
            assert!(
                (slope - expect).abs() < 1e-4 * p.e0,
                "dq={dq}: {slope} vs {expect}"
            );
        }
    }

    #[test]
    fn integrators_agree_on_a_loop() {
        let p = params();
        let fz = 1.0e6;
        let q = sine_history(3.0 * p.mu * fz / p.e0, 3, 2000);
        let fzs = vec![fz; q.len()];
        let fe = integrate_implicit_euler(&p, &q, &fzs).unwrap();
        let fr = integrate_reference(&p, &q, &fzs).unwrap();
        let max_dev = fe
            .iter()
            .zip(&fr)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(max_dev < 0.005 * p.mu * fz, "max deviation {max_dev}");
        let last = q.len() - 2001;
        let ee = dissipated_energy(&q[last..], &fe[last..]);
        let er = dissipated_energy(&q[last..], &fr[last..]);
        assert!((ee - er).abs() / er < 0.005, "{ee} vs {er}");
    }

    #[test]
    fn integrators_agree_on_a_loop_with_varying_normal_load() {
        // Fz(t) = N0 + kn·uz(t) with uz out of phase with q: the adaptive (Dormand–Prince)
        // path of the reference integrator against implicit Euler.
        let p = ValanisParams::new(1.0e13, 0.5, 5.0e11, 0.6).unwrap();
        let (n0, kn) = (1.0e6, 1.0e13);
        let per = 2000;
        let q = sine_history(2.0 * p.mu * n0 / p.e0, 2, per);
        let uz: Vec<f64> = (0..q.len())
            .map(|i| 0.3 * n0 / kn * (2.0 * std::f64::consts::PI * i as f64 / per as f64).cos())
            .collect();
        let fz = crate::element::unilateral::normal_load_history(n0, kn, &uz);
        let fe = integrate_implicit_euler(&p, &q, &fz).unwrap();
        let fr = integrate_reference(&p, &q, &fz).unwrap();
        let max_dev = fe
            .iter()
            .zip(&fr)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(max_dev < 0.005 * p.mu * 1.3 * n0, "max deviation {max_dev}");
        let last = q.len() - per - 1;
        let ee = dissipated_energy(&q[last..], &fe[last..]);
        let er = dissipated_energy(&q[last..], &fr[last..]);
        assert!((ee - er).abs() / er < 0.005, "{ee} vs {er}");
    }

    /// At constant load the frozen-load step is the exact branch (equal to the reference to
    /// round-off at any sampling, where implicit Euler lags by O(Δq)); under a varying load it
    /// converges to the reference as the increments shrink.
    /// The load-dependent element on a history with a closed form: `k = 0`, `Et = 0` and
    /// `E0 = κ·Fz` (two tabulated loads whose E0 ratio is the load ratio: the interpolation is
    /// then this power law exactly), loaded proportionally from `q0`, `Fz = c·q`. The equation
    /// `dF/dq = E0·(1 − F/(μFz)) + F·d ln E0/dq` becomes linear, `F' + (κ/μ − 1/q)·F = κ·c·q`,
    /// with `F(q0) = 0`: `F = μ·c·q·(1 − exp(−κ(q − q0)/μ))` (the elastic displacement `F/E0`
    /// follows the constant-load law with slip displacement `μ/κ`).
    #[test]
    fn load_dependent_element_matches_the_proportional_loading_closed_form() {
        let (kappa, mu, c) = (2.0e5, 0.6, 5.0e11); // E0 = κ·Fz (1/m), Fz = c·q (Pa/m)
        let (l0, l1) = (1.0e6, 4.0e6);
        let element = LoadDependentValanis::new(
            vec![l0, l1],
            vec![
                ValanisParams::new(kappa * l0, 0.0, 0.0, mu).unwrap(),
                ValanisParams::new(kappa * l1, 0.0, 0.0, mu).unwrap(),
            ],
        )
        .unwrap();
        // Midway in ln Fz the interpolated E0 is the power law's.
        let mid = (l0 * l1).sqrt();
        assert!((element.at(mid).e0 / (kappa * mid) - 1.0).abs() < 1e-12);
        let q0 = l0 / c;
        let q: Vec<f64> = (0..=40)
            .map(|i| q0 + (l1 / c - q0) * i as f64 / 40.0)
            .collect();
        let fz: Vec<f64> = q.iter().map(|&qi| c * qi).collect();
        let f = integrate_load_dependent(&element, &q, &fz).unwrap();
        let b = kappa / mu;
        for (&qi, &fi) in q.iter().zip(&f) {
            let exact = mu * c * qi * (1.0 - (-b * (qi - q0)).exp());
            assert!(
                (fi - exact).abs() <= 1e-8 * mu * c * qi,
                "q = {qi:e}: {fi:e} against {exact:e}"
            );
        }
        // The same element with its upper row's E0 doubled is a different element.
        let stiffer = LoadDependentValanis::new(
            vec![l0, l1],
            vec![
                element.params[0],
                ValanisParams {
                    e0: 2.0 * kappa * l1,
                    ..element.params[1]
                },
            ],
        )
        .unwrap();
        let g = integrate_load_dependent(&stiffer, &q, &fz).unwrap();
        assert!((g[20] - f[20]).abs() > 1e-3 * f[20]);
    }

    /// The load-following element stepped at frozen loads against the proportional-loading
    /// closed form above (`E0 = κ·Fz`: exponent 1, `k = 0`). The composition is exact here, at
    /// any increment: `G = F/(μ·Fz)` obeys `dG/dq = (κ/μ)·(1 − G)` whatever the load, the load
    /// jump keeps `G` (`F0' = F0·Fz1/Fz0`) and the branch at `Fz1` integrates that equation in
    /// closed form; so the force agrees to rounding at 7, 50 and 2000 increments.
    #[test]
    fn load_following_element_is_exact_under_proportional_loading() {
        let (kappa, mu, c) = (2.0e5, 0.6, 5.0e11);
        let (l0, l1) = (1.0e6, 4.0e6);
        let law = LoadFollowingValanis::new(
            ValanisParams::new(kappa * l0, 0.0, 0.0, mu).unwrap(),
            l0,
            1.0,
        )
        .unwrap();
        let q0 = l0 / c;
        let b = kappa / mu;
        let worst = |n: usize| -> f64 {
            let mut st = ValanisState::virgin(q0, l0);
            let mut worst: f64 = 0.0;
            for i in 1..=n {
                let qi = q0 + (l1 / c - q0) * i as f64 / n as f64;
                st = law.frozen_step(&st, qi, c * qi);
                let exact = mu * c * qi * (1.0 - (-b * (qi - q0)).exp());
                worst = worst.max((st.force - exact).abs() / (mu * c * qi));
            }
            worst
        };
        for n in [7, 50, 2000] {
            let w = worst(n);
            assert!(w < 1e-12, "{n} increments: {w:e}");
        }
        // A wrong exponent is not exact.
        let wrong = LoadFollowingValanis {
            e0_exponent: 0.5,
            ..law
        };
        let mut st = ValanisState::virgin(q0, l0);
        let qe = l1 / c;
        for i in 1..=50 {
            let qi = q0 + (qe - q0) * i as f64 / 50.0;
            st = wrong.frozen_step(&st, qi, c * qi);
        }
        let exact = mu * c * qe * (1.0 - (-b * (qe - q0)).exp());
        assert!((st.force - exact).abs() > 1e-3 * mu * c * qe);
    }

    /// The load-following element against the element layer's reference integration of the same
    /// law ([`load_dependent_reference_step`] with two rows on one power law, `k` fixed,
    /// `Et = 0`), on a loop with the load oscillating out of phase: within 2e-3 of `μ·N0` at
    /// 4000 increments per cycle, and first order in the increment (the load's change within
    /// one increment).
    #[test]
    fn load_following_element_follows_the_load_dependent_reference() {
        let (a, mu, k, ratio) = (0.7, 0.6, 0.4, 0.0);
        let (l0, l1, n0) = (2.0, 20.0, 8.0);
        let at = |l: f64| {
            let e0 = 1e6 * (l / n0).powf(a);
            ValanisParams::new(e0, k, ratio * e0, mu).unwrap()
        };
        let reference = LoadDependentValanis::new(vec![l0, l1], vec![at(l0), at(l1)]).unwrap();
        let law = LoadFollowingValanis::new(at(n0), n0, a).unwrap();
        let error = |n: usize| -> f64 {
            let amp = 2.0 * mu * n0 / 1e6;
            let q: Vec<f64> = (0..=2 * n)
                .map(|i| amp * (std::f64::consts::TAU * i as f64 / n as f64).sin())
                .collect();
            let fz: Vec<f64> = (0..=2 * n)
                .map(|i| {
                    n0 * (1.0 + 0.5 * (std::f64::consts::TAU * i as f64 / n as f64 + 1.0).cos())
                })
                .collect();
            let f_ref = integrate_load_dependent(&reference, &q, &fz).unwrap();
            let mut st = ValanisState::virgin(q[0], fz[0]);
            let mut worst: f64 = 0.0;
            for i in 1..q.len() {
                st = law.frozen_step(&st, q[i], fz[i]);
                worst = worst.max((st.force - f_ref[i]).abs() / (mu * n0));
            }
            worst
        };
        let (coarse, fine) = (error(1000), error(4000));
        assert!(fine < 2e-3, "{fine:e}");
        let order = (coarse / fine).log2() / 2.0;
        assert!(
            (0.8..1.3).contains(&order),
            "order {order} ({coarse:e}, {fine:e})"
        );
    }

    /// Exact partials of the load-following step against central differences, over stick,
    /// microslip, slip, a rising and a falling load and a re-contact inside the increment.
    #[test]
    fn load_following_step_partials_match_finite_differences() {
        let law =
            LoadFollowingValanis::new(ValanisParams::new(1e6, 0.4, 5e4, 0.6).unwrap(), 10.0, 0.7)
                .unwrap();
        // (F0, q_ref0, q0, Fz0, q1, Fz1)
        let cases = [
            [1.0, 0.0, 2e-6, 10.0, 4e-6, 12.0],
            [3.0, -1e-6, 5e-6, 12.0, 1e-6, 8.0],
            [-4.0, 1e-6, -6e-6, 9.0, -2e-5, 7.5],
            [0.5, 2e-6, 3e-6, 11.0, 3.5e-6, 11.0],
            [0.0, 1e-6, 1e-6, -2.0, 6e-6, 9.0],
        ];
        let run = |x: &[f64; 6]| {
            let st = ValanisState {
                force: x[F0],
                q_ref: x[QR0],
                q: x[Q0],
                fz: x[FZ0],
            };
            law.frozen_step(&st, x[Q1], x[FZ1])
        };
        for x in cases {
            let st = ValanisState {
                force: x[F0],
                q_ref: x[QR0],
                q: x[Q0],
                fz: x[FZ0],
            };
            let (out, d) = law.frozen_step_partials(&st, x[Q1], x[FZ1]);
            assert_eq!(out, run(&x));
            for i in 0..6 {
                let h = if matches!(i, QR0 | Q0 | Q1) {
                    1e-12
                } else {
                    1e-7
                };
                let (mut up, mut dn) = (x, x);
                up[i] += h;
                dn[i] -= h;
                let (su, sd) = (run(&up), run(&dn));
                let fd_f = (su.force - sd.force) / (2.0 * h);
                let fd_r = (su.q_ref - sd.q_ref) / (2.0 * h);
                let scale_f = if matches!(i, QR0 | Q0 | Q1) { 1e6 } else { 1.0 };
                let scale_r = if matches!(i, QR0 | Q0 | Q1) {
                    1.0
                } else {
                    1e-6
                };
                assert!(
                    (fd_f - d.force[i]).abs() < 1e-5 * scale_f,
                    "case {x:?}, input {i}: dF {} vs fd {fd_f}",
                    d.force[i]
                );
                assert!(
                    (fd_r - d.q_ref[i]).abs() < 1e-5 * scale_r,
                    "case {x:?}, input {i}: dq_ref {} vs fd {fd_r}",
                    d.q_ref[i]
                );
            }
        }
    }

    #[test]
    fn one_row_load_dependent_element_is_the_plain_element() {
        let p = params();
        let q = sine_history(2e-7, 3, 64);
        let fz: Vec<f64> = (0..q.len())
            .map(|i| 1e6 * (1.0 + 0.3 * (i as f64 * 0.1).sin()))
            .collect();
        let one = LoadDependentValanis::new(vec![1e6], vec![p]).unwrap();
        assert_eq!(
            integrate_load_dependent(&one, &q, &fz).unwrap(),
            integrate_reference(&p, &q, &fz).unwrap()
        );
        assert!(LoadDependentValanis::new(vec![2e6, 1e6], vec![p, p]).is_err());
        assert!(LoadDependentValanis::new(vec![1e6], vec![]).is_err());
    }

    #[test]
    fn frozen_load_step_is_exact_at_constant_load() {
        let p = params();
        let fz = 1.0e6;
        let q = sine_history(3.0 * p.mu * fz / p.e0, 2, 40);
        let fzs = vec![fz; q.len()];
        let fr = integrate_reference(&p, &q, &fzs).unwrap();
        let fe = integrate_implicit_euler(&p, &q, &fzs).unwrap();
        let mut st = ValanisState::virgin(q[0], fz);
        let (mut dev, mut dev_euler) = (0.0_f64, 0.0_f64);
        for i in 1..q.len() {
            st = frozen_load_step(&p, &st, q[i], fz);
            dev = dev.max((st.force - fr[i]).abs());
            dev_euler = dev_euler.max((fe[i] - fr[i]).abs());
        }
        assert!(dev < 1e-9 * p.mu * fz, "{dev}");
        assert!(dev_euler > 0.05 * p.mu * fz, "{dev_euler}");
        // Varying load: error falls at least linearly with the increment.
        let err = |per: usize| {
            let q = sine_history(2.0 * p.mu * fz / p.e0, 1, per);
            let fzv: Vec<f64> = (0..q.len())
                .map(|i| fz * (1.0 + 0.3 * (std::f64::consts::TAU * i as f64 / per as f64).cos()))
                .collect();
            let fr = integrate_reference(&p, &q, &fzv).unwrap();
            let mut st = ValanisState::virgin(q[0], fzv[0]);
            let mut e = 0.0_f64;
            for i in 1..q.len() {
                st = frozen_load_step(&p, &st, q[i], fzv[i]);
                e = e.max((st.force - fr[i]).abs());
            }
            e
        };
        let (e1, e2) = (err(200), err(400));
        assert!(e2 < 0.6 * e1 && e1 < 0.02 * p.mu * fz, "{e1} {e2}");
    }

    #[test]
    fn implicit_euler_is_first_order() {
        let p = params();
        let fz = 1.0e6;
        let amp = 2.0 * p.mu * fz / p.e0;
        let err = |n: usize| {
            let q = sine_history(amp, 1, n);
            let fzs = vec![fz; q.len()];
            let fe = integrate_implicit_euler(&p, &q, &fzs).unwrap();
            let fr = integrate_reference(&p, &q, &fzs).unwrap();
            fe.iter()
                .zip(&fr)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max)
        };
        let (e1, e2) = (err(400), err(800));
        let ratio = e1 / e2;
        assert!(ratio > 1.7 && ratio < 2.3, "error ratio {ratio}");
    }

    #[test]
    fn separation_zeroes_force_and_recontact_starts_virgin() {
        let p = params();
        let q = [0.0, 1e-6, 2e-6, 3e-6, 3e-6 + 1e-12];
        let fz = [1e6, 1e6, 0.0, 1e6, 1e6];
        for m in [Integrator::ImplicitEuler, Integrator::Reference] {
            let f = integrate(&p, &q, &fz, m).unwrap();
            assert_eq!(f[2], 0.0);
            // Re-contact at θ = 0 of the increment 2→3: virgin from q = 2e-6, loading slope E0.
            let slope = (f[4] - f[3]) / 1e-12;
            assert!(f[3] > 0.0 && slope > 0.0);
        }
    }

    #[test]
    fn falling_normal_load_caps_force_at_current_limit() {
        let p = params();
        let q = [0.0, 1e-5, 1e-5];
        let fz = [1e6, 1e6, 0.5e6];
        for m in [Integrator::ImplicitEuler, Integrator::Reference] {
            let f = integrate(&p, &q, &fz, m).unwrap();
            assert!((f[2] - p.mu * 0.5e6).abs() < 1e-6 * p.mu * 1e6);
        }
    }

    #[test]
    fn step_partials_match_finite_differences() {
        type Step = fn(&ValanisParams, &ValanisState, f64, f64) -> ValanisState;
        type Partials =
            fn(&ValanisParams, &ValanisState, f64, f64) -> (ValanisState, ValanisPartials);
        let p = ValanisParams::new(2.0e7, 0.5, 1.0e6, 0.6).unwrap();
        // k = 0 and Et = 0: the asymptote x∞ = −1 is reached.
        let p0 = ValanisParams::new(2.0e7, 0.0, 0.0, 0.6).unwrap();
        let slip = p.mu * 10.0 / p.e0;
        // (F0, q_ref0, q0, Fz0, q1, Fz1): loading, unloading, near the limit, re-contact, gross
        // slip, a start force above the band of a fallen load (projected first); then, with
        // k = 0, a virgin branch and one started next to the slip limit.
        let cases = [
            (p, [0.0, 0.0, 0.0, 10.0, 0.3 * slip, 10.0]),
            (p, [3.0, 0.1 * slip, 0.5 * slip, 10.0, 0.2 * slip, 12.0]),
            (p, [-2.0, 0.0, -0.4 * slip, 9.0, -0.1 * slip, 8.0]),
            (p, [0.0, 0.2 * slip, 0.1 * slip, -3.0, 0.6 * slip, 7.0]),
            (p, [1.0, 0.0, 0.2 * slip, 10.0, 5.0 * slip, 10.0]),
            (p, [5.9, 0.0, 0.3 * slip, 10.0, 0.5 * slip, 8.0]),
            (p0, [0.0, 0.0, 0.0, 10.0, 0.7 * slip, 10.0]),
            (p0, [5.99, 0.0, 0.0, 10.0, 0.2 * slip, 10.0]),
        ];
        let methods: [(&str, Step, Partials); 2] = [
            (
                "implicit Euler",
                implicit_euler_step,
                implicit_euler_step_partials,
            ),
            ("frozen load", frozen_load_step, frozen_load_step_partials),
        ];
        for (name, step, partials) in methods {
            // At Δq = 0 the derivative with respect to q1 is the slope for Δq → 0+ (E0 on a
            // virgin element).
            let st = ValanisState::virgin(0.0, 10.0);
            let (_, d0) = partials(&p, &st, 0.0, 10.0);
            assert!((d0.force[4] - p.e0).abs() < 1e-9 * p.e0 && d0.force[2] == -d0.force[4]);
            for (p, c) in cases {
                let eval = |v: &[f64; 6]| {
                    let st = ValanisState {
                        force: v[0],
                        q_ref: v[1],
                        q: v[2],
                        fz: v[3],
                    };
                    step(&p, &st, v[4], v[5])
                };
                let st = ValanisState {
                    force: c[0],
                    q_ref: c[1],
                    q: c[2],
                    fz: c[3],
                };
                let (out, d) = partials(&p, &st, c[4], c[5]);
                assert_eq!(out, eval(&c));
                let scale = [1.0, slip, slip, 10.0, slip, 10.0];
                for i in 0..6 {
                    let h = 1e-6 * scale[i];
                    let mut up = c;
                    let mut dn = c;
                    up[i] += h;
                    dn[i] -= h;
                    let (a, b) = (eval(&up), eval(&dn));
                    let fd_f = (a.force - b.force) / (2.0 * h);
                    let fd_r = (a.q_ref - b.q_ref) / (2.0 * h);
                    let typical = [1.0, p.e0, p.e0, p.mu, p.e0, p.mu][i];
                    let tol_f = 1e-5 * (typical + fd_f.abs());
                    assert!(
                        (fd_f - d.force[i]).abs() <= tol_f,
                        "{name}: case {c:?} input {i}: dF {} vs fd {fd_f}",
                        d.force[i]
                    );
                    assert!(
                        (fd_r - d.q_ref[i]).abs() <= 1e-6,
                        "{name}: case {c:?} input {i}: dq_ref {} vs fd {fd_r}",
                        d.q_ref[i]
                    );
                }
            }
        }
    }

    #[test]
    fn invalid_parameters_are_refused() {
        assert!(ValanisParams::new(1e12, 1.0, 0.0, 0.6).is_err());
        assert!(ValanisParams::new(1e12, -0.1, 0.0, 0.6).is_err());
        assert!(ValanisParams::new(-1e12, 0.5, 0.0, 0.6).is_err());
        assert!(ValanisParams::new(1e12, 0.5, 2e12, 0.6).is_err());
        assert!(ValanisParams::new(1e12, 0.5, 0.0, -0.6).is_err());
        let p = params();
        assert!(integrate_implicit_euler(&p, &[0.0, 1.0], &[1.0]).is_err());
        assert!(integrate_implicit_euler(&p, &[0.0, f64::NAN], &[1.0, 1.0]).is_err());
    }

    #[test]
    fn in_plane_directions_are_uncoupled() {
        let p = params();
        let q = sine_history(1e-7, 1, 100);
        let zero = vec![0.0; q.len()];
        let fz = vec![1e6; q.len()];
        let (fx, fy) = integrate_in_plane(&p, &q, &zero, &fz, Integrator::ImplicitEuler).unwrap();
        let alone = integrate_implicit_euler(&p, &q, &fz).unwrap();
        assert_eq!(fx, alone);
        assert!(fy.iter().all(|&v| v == 0.0));
    }
}
