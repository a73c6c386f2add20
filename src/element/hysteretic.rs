//! The hysteretic-element interface: a time-discrete element with memory, advanced sample by
//! sample, with the exact partial derivatives of each increment. Every constitutive law of
//! [`crate::element`] implements it once, in its own file; the harmonic-balance solver, the time
//! integrator, the identification and the diagnosis drive the laws only through it.
//!
//! # The trait
//!
//! An element acts on `d` relative displacements `u` (its local frame: for contact elements
//! `u = (t1, t2, n)`, two tangential components and the normal approach, `n > 0` closing the
//! contact) and returns `d` forces `f` (the force the element exerts against `u`, i.e. it enters
//! the equation of motion like `K·x`). Its memory is a state vector `s` of length `m`. One
//! increment from sample `u0` to sample `u1` maps `(s0, u0, u1) → (s1, f1)`; the same update
//! serves the alternating frequency–time method of the harmonic balance and the reference time
//! integrator. The partial derivatives of the update ([`StepPartials`]) are what an analytic
//! Jacobian is built from.
//!
//! Conventions shared by all elements:
//! * `u = 0` is the preloaded static equilibrium: the element's virgin state is taken there
//!   ([`HystereticElement::virgin_state`]) and forces are changes from the static preload (a
//!   contact with preload `N0` returns `N(t) − N0` in its normal component; the preload itself
//!   is balanced by the static loads that produced it).
//! * A rate-dependent law (friction with a Stribeck curve, impact damping) reads the increment's
//!   kinematics besides its end displacements: its duration `Δt` and the velocities `v0`, `v1`
//!   at both ends ([`Kinematics`]), exact where the caller knows them (the harmonics in the AFT,
//!   the integrator's velocities in a time integration). It says so with
//!   [`HystereticElement::rate_dependent`] and implements [`HystereticElement::step_at_rate`],
//!   with the partial derivatives with respect to the kinematics in [`RatePartials`]; its plain
//!   [`HystereticElement::step`] is its quasi-static limit (zero velocity). Rate-independent
//!   laws implement `step` only.
//! * To add a law, write one file with its parameters, its pure update and its implementation
//!   of [`HystereticElement`] (or [`MemorylessSpring`] for an elastic law), and check its
//!   derivatives against finite differences with [`check_partials`] in that file's tests.
//!
//! Units: per element (m, N, N/m), as the dynamic solvers use them.

use crate::core::error::{Error, Result};

/// Contact state of an element at one time sample (for stick / slip / separation fractions).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ContactStatus {
    /// Tangential force inside the slip limit (Jenkins), or below 99 % of it (Valanis: stick
    /// includes microslip).
    Stick,
    /// Tangential force on the slip limit (Jenkins), or within 1 % of its asymptote (Valanis:
    /// gross slip).
    Slip,
    /// Normal load zero: the contact is open.
    Separated,
}

impl ContactStatus {
    /// The status of a friction contact: [`Self::Separated`] when the normal load is `≤ 0`,
    /// [`Self::Slip`] when the tangential force measure `used` has reached `slip_threshold` (the
    /// law's slip limit times its tolerance), [`Self::Stick`] otherwise.
    pub fn classify(normal_load: f64, used: f64, slip_threshold: f64) -> Self {
        if normal_load <= 0.0 {
            Self::Separated
        } else if used >= slip_threshold {
            Self::Slip
        } else {
            Self::Stick
        }
    }
}

/// Partial derivatives of one element increment `(s0, u0, u1) → (s1, f1)`, row-major dense
/// matrices (`ds_ds0` is `m × m`, `ds_du0` and `ds_du1` are `m × d`, `df_ds0` is `d × m`,
/// `df_du0` and `df_du1` are `d × d`). Entries an element leaves untouched are zero.
#[derive(Debug, Clone, PartialEq)]
pub struct StepPartials {
    /// Number of state variables of the element.
    pub m: usize,
    /// Number of displacement (and force) components.
    pub d: usize,
    /// `∂s1/∂s0` (`m × m`).
    pub ds_ds0: Vec<f64>,
    /// `∂s1/∂u0` (`m × d`).
    pub ds_du0: Vec<f64>,
    /// `∂s1/∂u1` (`m × d`).
    pub ds_du1: Vec<f64>,
    /// `∂f1/∂s0` (`d × m`).
    pub df_ds0: Vec<f64>,
    /// `∂f1/∂u0` (`d × d`).
    pub df_du0: Vec<f64>,
    /// `∂f1/∂u1` (`d × d`): the element's tangent stiffness over the increment.
    pub df_du1: Vec<f64>,
}

impl StepPartials {
    /// Zero partials for an element with `m` states and `d` displacement components.
    pub fn new(m: usize, d: usize) -> Self {
        Self {
            m,
            d,
            ds_ds0: vec![0.0; m * m],
            ds_du0: vec![0.0; m * d],
            ds_du1: vec![0.0; m * d],
            df_ds0: vec![0.0; d * m],
            df_du0: vec![0.0; d * d],
            df_du1: vec![0.0; d * d],
        }
    }

    /// Zero partials for `m` states and `d` components, reusing the buffers.
    pub fn reset(&mut self, m: usize, d: usize) {
        self.m = m;
        self.d = d;
        for (v, n) in [
            (&mut self.ds_ds0, m * m),
            (&mut self.ds_du0, m * d),
            (&mut self.ds_du1, m * d),
            (&mut self.df_ds0, d * m),
            (&mut self.df_du0, d * d),
            (&mut self.df_du1, d * d),
        ] {
            v.clear();
            v.resize(n, 0.0);
        }
    }

    /// Reset every entry to zero. Called before every sample's step: a one-state,
    /// one-component element's six single entries are stored directly rather than through six
    /// `memset` calls, which took a tenth of an identification's time.
    pub fn clear(&mut self) {
        for v in [
            &mut self.ds_ds0,
            &mut self.ds_du0,
            &mut self.ds_du1,
            &mut self.df_ds0,
            &mut self.df_du0,
            &mut self.df_du1,
        ] {
            if let [x] = v.as_mut_slice() {
                *x = 0.0;
            } else {
                v.fill(0.0);
            }
        }
    }
}

/// The kinematics of one increment that a rate-dependent law reads besides its end
/// displacements: the duration `Δt` (s) and the velocities at the start and the end (`d`
/// components each, m/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Kinematics<'a> {
    /// Duration of the increment `Δt` (s), > 0.
    pub dt: f64,
    /// Velocity at the start of the increment (`d`, m/s).
    pub v0: &'a [f64],
    /// Velocity at the end of the increment (`d`, m/s).
    pub v1: &'a [f64],
}

/// Partial derivatives of a rate-dependent increment with respect to its kinematics
/// ([`Kinematics`]), row-major (`ds_dv0`, `ds_dv1` are `m × d`, `df_dv0`, `df_dv1` are `d × d`,
/// `ds_ddt` has `m` and `df_ddt` `d` entries). They complete the [`StepPartials`] of the same
/// increment; entries an element leaves untouched are zero.
#[derive(Debug, Clone, PartialEq)]
pub struct RatePartials {
    /// `∂s1/∂v0` (`m × d`).
    pub ds_dv0: Vec<f64>,
    /// `∂s1/∂v1` (`m × d`).
    pub ds_dv1: Vec<f64>,
    /// `∂s1/∂Δt` (`m`).
    pub ds_ddt: Vec<f64>,
    /// `∂f1/∂v0` (`d × d`).
    pub df_dv0: Vec<f64>,
    /// `∂f1/∂v1` (`d × d`): the element's tangent damping at the end of the increment.
    pub df_dv1: Vec<f64>,
    /// `∂f1/∂Δt` (`d`).
    pub df_ddt: Vec<f64>,
}

impl RatePartials {
    /// Zero partials for an element with `m` states and `d` displacement components.
    pub fn new(m: usize, d: usize) -> Self {
        Self {
            ds_dv0: vec![0.0; m * d],
            ds_dv1: vec![0.0; m * d],
            ds_ddt: vec![0.0; m],
            df_dv0: vec![0.0; d * d],
            df_dv1: vec![0.0; d * d],
            df_ddt: vec![0.0; d],
        }
    }

    /// Reset every entry to zero.
    pub fn clear(&mut self) {
        for v in [
            &mut self.ds_dv0,
            &mut self.ds_dv1,
            &mut self.ds_ddt,
            &mut self.df_dv0,
            &mut self.df_dv1,
            &mut self.df_ddt,
        ] {
            v.fill(0.0);
        }
    }
}

/// An element with memory, advanced from sample to sample (rate-independent unless it says
/// otherwise, [`HystereticElement::rate_dependent`]).
pub trait HystereticElement: Send + Sync + std::fmt::Debug {
    /// Short name of the constitutive law (`"valanis"`, `"jenkins"`, ...).
    fn name(&self) -> &'static str;
    /// Number `d` of relative displacement components the element acts on.
    fn dofs(&self) -> usize;
    /// Length `m` of the state vector.
    fn state_len(&self) -> usize;
    /// State of the virgin element at the static equilibrium `u = 0`.
    fn virgin_state(&self, s: &mut [f64]);
    /// Characteristic magnitude of each state component (the periodicity tolerance of the AFT
    /// is relative to it), e.g. the slip force for a force state.
    fn state_scales(&self, scales: &mut [f64]);
    /// Characteristic force (N), e.g. the slip force; used for tolerances and reports.
    fn force_scale(&self) -> f64;
    /// One increment: state `s1` and force `f1` at `u1`, from state `s0` at `u0`. With
    /// `partials`, also its exact derivatives (the buffer is cleared by the caller).
    fn step(
        &self,
        s0: &[f64],
        u0: &[f64],
        u1: &[f64],
        s1: &mut [f64],
        f1: &mut [f64],
        partials: Option<&mut StepPartials>,
    );
    /// Contact status at a sample with state `s`, displacement `u` and force `f`.
    fn status(&self, s: &[f64], u: &[f64], f: &[f64]) -> ContactStatus;
    /// Whether the law reads the increment's kinematics ([`Self::step_at_rate`]), e.g. LuGre or
    /// Hunt–Crossley. Such an element is driven through `step_at_rate` with the exact velocities
    /// by the AFT and the time integration, from sample to sample (a rate-dependent law has no
    /// velocity reversals to locate: its state depends on the whole path). Rate-independent by
    /// default.
    fn rate_dependent(&self) -> bool {
        false
    }
    /// One increment of a rate-dependent law over the kinematics `kin` (duration and end
    /// velocities), with its [`StepPartials`] and, in the second buffer, its [`RatePartials`]
    /// (both cleared by the caller). The default, for rate-independent laws, is [`Self::step`]
    /// (the kinematics do not enter; the rate partials stay zero).
    #[allow(clippy::too_many_arguments)]
    fn step_at_rate(
        &self,
        s0: &[f64],
        u0: &[f64],
        u1: &[f64],
        kin: Kinematics<'_>,
        s1: &mut [f64],
        f1: &mut [f64],
        partials: Option<(&mut StepPartials, &mut RatePartials)>,
    ) {
        let _ = kin;
        self.step(s0, u0, u1, s1, f1, partials.map(|(p, _)| p));
    }
}

/// A memoryless spring `f(u)` on one displacement component: an elastic nonlinearity as a
/// [`HystereticElement`] without state (always [`ContactStatus::Stick`]).
pub trait MemorylessSpring: Send + Sync + std::fmt::Debug {
    /// Short name of the law.
    fn law_name(&self) -> &'static str;
    /// Force `f(u)` and tangent stiffness `f'(u)`.
    fn force_and_stiffness(&self, u: f64) -> (f64, f64);
    /// Characteristic force (the stiffness coefficient's magnitude).
    fn scale(&self) -> f64;
}

impl<T: MemorylessSpring> HystereticElement for T {
    fn name(&self) -> &'static str {
        self.law_name()
    }
    fn dofs(&self) -> usize {
        1
    }
    fn state_len(&self) -> usize {
        0
    }
    fn virgin_state(&self, _s: &mut [f64]) {}
    fn state_scales(&self, _scales: &mut [f64]) {}
    fn force_scale(&self) -> f64 {
        self.scale()
    }
    fn step(
        &self,
        _s0: &[f64],
        _u0: &[f64],
        u1: &[f64],
        _s1: &mut [f64],
        f1: &mut [f64],
        partials: Option<&mut StepPartials>,
    ) {
        let (f, k) = self.force_and_stiffness(u1[0]);
        f1[0] = f;
        if let Some(p) = partials {
            p.df_du1[0] = k;
        }
    }
    fn status(&self, _s: &[f64], _u: &[f64], _f: &[f64]) -> ContactStatus {
        ContactStatus::Stick
    }
}

/// Largest deviation between an element's analytic partials and central finite differences of
/// its step (steps `u_step` for displacements, `s_steps` per state component), relative to the
/// largest entry of each column. Used by the unit tests of every element; new elements should
/// be checked with it.
pub fn check_partials(
    element: &dyn HystereticElement,
    s0: &[f64],
    u0: &[f64],
    u1: &[f64],
    u_step: f64,
    s_steps: &[f64],
) -> Result<f64> {
    let (m, d) = (element.state_len(), element.dofs());
    if s0.len() != m || u0.len() != d || u1.len() != d {
        return Err(Error::param("s0", "state or displacement length mismatch"));
    }
    let mut p = StepPartials::new(m, d);
    let mut s1 = vec![0.0; m];
    let mut f1 = vec![0.0; d];
    element.step(s0, u0, u1, &mut s1, &mut f1, Some(&mut p));
    let eval = |s: &[f64], a: &[f64], b: &[f64]| {
        let mut s1 = vec![0.0; m];
        let mut f1 = vec![0.0; d];
        element.step(s, a, b, &mut s1, &mut f1, None);
        (s1, f1)
    };
    let mut worst: f64 = 0.0;
    // Columns: s0 (m), u0 (d), u1 (d).
    for col in 0..(m + 2 * d) {
        let h = if col < m { s_steps[col] } else { u_step };
        let perturb = |sign: f64| {
            let mut s = s0.to_vec();
            let mut a = u0.to_vec();
            let mut b = u1.to_vec();
            if col < m {
                s[col] += sign * h;
            } else if col < m + d {
                a[col - m] += sign * h;
            } else {
                b[col - m - d] += sign * h;
            }
            eval(&s, &a, &b)
        };
        let (sp, fp) = perturb(1.0);
        let (sm, fm) = perturb(-1.0);
        let ds: Vec<f64> = sp
            .iter()
            .zip(&sm)
            .map(|(a, b)| (a - b) / (2.0 * h))
            .collect();
        let df: Vec<f64> = fp
            .iter()
            .zip(&fm)
            .map(|(a, b)| (a - b) / (2.0 * h))
            .collect();
        let (an_s, an_f): (Vec<f64>, Vec<f64>) = if col < m {
            (
                (0..m).map(|r| p.ds_ds0[r * m + col]).collect(),
                (0..d).map(|r| p.df_ds0[r * m + col]).collect(),
            )
        } else if col < m + d {
            let c = col - m;
            (
                (0..m).map(|r| p.ds_du0[r * d + c]).collect(),
                (0..d).map(|r| p.df_du0[r * d + c]).collect(),
            )
        } else {
            let c = col - m - d;
            (
                (0..m).map(|r| p.ds_du1[r * d + c]).collect(),
                (0..d).map(|r| p.df_du1[r * d + c]).collect(),
            )
        };
        // Relative to the largest entry of the column (derivatives of different units).
        let fd_all: Vec<f64> = ds.iter().chain(&df).copied().collect();
        let an_all: Vec<f64> = an_s.iter().chain(&an_f).copied().collect();
        let colmax = fd_all
            .iter()
            .chain(&an_all)
            .fold(f64::MIN_POSITIVE, |a, b| a.max(b.abs()));
        for (a, b) in fd_all.iter().zip(&an_all) {
            worst = worst.max((a - b).abs() / colmax);
        }
    }
    Ok(worst)
}

/// Largest deviation between a rate-dependent element's analytic partials of
/// [`HystereticElement::step_at_rate`] and central finite differences, relative to the largest
/// entry of each column, over the columns `s0` (steps `s_steps`), `u0`, `u1` (`u_step`), `v0`,
/// `v1` (`v_step`) and `Δt` (`dt_step`). The rate-dependent counterpart of [`check_partials`].
#[allow(clippy::too_many_arguments)]
pub fn check_rate_partials(
    element: &dyn HystereticElement,
    s0: &[f64],
    u0: &[f64],
    u1: &[f64],
    kin: Kinematics<'_>,
    steps: (f64, f64, f64),
    s_steps: &[f64],
) -> Result<f64> {
    let (m, d) = (element.state_len(), element.dofs());
    if s0.len() != m || u0.len() != d || u1.len() != d || kin.v0.len() != d || kin.v1.len() != d {
        return Err(Error::param(
            "s0",
            "state, displacement or velocity length mismatch",
        ));
    }
    let (u_step, v_step, dt_step) = steps;
    let mut p = StepPartials::new(m, d);
    let mut rp = RatePartials::new(m, d);
    let mut s1 = vec![0.0; m];
    let mut f1 = vec![0.0; d];
    element.step_at_rate(s0, u0, u1, kin, &mut s1, &mut f1, Some((&mut p, &mut rp)));
    // Input vector: s0 (m), u0 (d), u1 (d), v0 (d), v1 (d), dt (1).
    let x: Vec<f64> = s0
        .iter()
        .chain(u0)
        .chain(u1)
        .chain(kin.v0)
        .chain(kin.v1)
        .copied()
        .chain([kin.dt])
        .collect();
    let eval = |x: &[f64]| {
        let mut s1 = vec![0.0; m];
        let mut f1 = vec![0.0; d];
        let k = Kinematics {
            dt: x[m + 4 * d],
            v0: &x[m + 2 * d..m + 3 * d],
            v1: &x[m + 3 * d..m + 4 * d],
        };
        element.step_at_rate(
            &x[..m],
            &x[m..m + d],
            &x[m + d..m + 2 * d],
            k,
            &mut s1,
            &mut f1,
            None,
        );
        (s1, f1)
    };
    let mut worst: f64 = 0.0;
    for col in 0..x.len() {
        let h = if col < m {
            s_steps[col]
        } else if col < m + 2 * d {
            u_step
        } else if col < m + 4 * d {
            v_step
        } else {
            dt_step
        };
        let perturb = |sign: f64| {
            let mut y = x.clone();
            y[col] += sign * h;
            eval(&y)
        };
        let (sp, fp) = perturb(1.0);
        let (sm, fm) = perturb(-1.0);
        let fd: Vec<f64> = sp
            .iter()
            .zip(&sm)
            .chain(fp.iter().zip(&fm))
            .map(|(a, b)| (a - b) / (2.0 * h))
            .collect();
        let (sv, fv): (Vec<f64>, Vec<f64>) = if col < m {
            (
                (0..m).map(|r| p.ds_ds0[r * m + col]).collect(),
                (0..d).map(|r| p.df_ds0[r * m + col]).collect(),
            )
        } else if col < m + d {
            let c = col - m;
            (
                (0..m).map(|r| p.ds_du0[r * d + c]).collect(),
                (0..d).map(|r| p.df_du0[r * d + c]).collect(),
            )
        } else if col < m + 2 * d {
            let c = col - m - d;
            (
                (0..m).map(|r| p.ds_du1[r * d + c]).collect(),
                (0..d).map(|r| p.df_du1[r * d + c]).collect(),
            )
        } else if col < m + 3 * d {
            let c = col - m - 2 * d;
            (
                (0..m).map(|r| rp.ds_dv0[r * d + c]).collect(),
                (0..d).map(|r| rp.df_dv0[r * d + c]).collect(),
            )
        } else if col < m + 4 * d {
            let c = col - m - 3 * d;
            (
                (0..m).map(|r| rp.ds_dv1[r * d + c]).collect(),
                (0..d).map(|r| rp.df_dv1[r * d + c]).collect(),
            )
        } else {
            (rp.ds_ddt.clone(), rp.df_ddt.clone())
        };
        let an: Vec<f64> = sv.into_iter().chain(fv).collect();
        // A column below what central differences resolve (rounding of the outputs over the
        // step, e.g. a Stribeck term far in its tail) is compared at that resolution.
        let outputs = s1.iter().chain(&f1).fold(0.0f64, |a, b| a.max(b.abs()));
        let resolution = 1e4 * f64::EPSILON * outputs / h;
        let colmax = fd
            .iter()
            .chain(&an)
            .fold(resolution.max(f64::MIN_POSITIVE), |a, b| a.max(b.abs()));
        for (a, b) in fd.iter().zip(&an) {
            worst = worst.max((a - b).abs() / colmax);
        }
    }
    Ok(worst)
}
