//! Nonlinear elements as the harmonic-balance solver sees them: a time-discrete hysteretic
//! element advanced sample by sample ([`HystereticElement`]), and adapters that drive the
//! constitutive laws of [`crate::element`] through it.
//!
//! # The trait
//!
//! An element acts on `d` relative displacements `u` (its local frame: for contact elements
//! `u = (t1, t2, n)`, two tangential components and the normal approach, `n > 0` closing the
//! contact) and returns `d` forces `f` (the force the element exerts against `u`, i.e. it enters
//! the equation of motion like `K·x`). Its memory is a state vector `s` of length `m`. One
//! increment from sample `u0` to sample `u1` maps `(s0, u0, u1) → (s1, f1)`; the same update is
//! used by the alternating frequency–time method ([`crate::dynamics::aft`]) and by the reference
//! time integrator ([`crate::dynamics::time_integration`]). The partial derivatives of the
//! update ([`StepPartials`]) are what the analytic Jacobian is built from.
//!
//! Conventions shared by all elements:
//! * `u = 0` is the preloaded static equilibrium: the element's virgin state is taken there
//!   ([`HystereticElement::virgin_state`]) and forces are changes from the static preload (a
//!   contact with preload `N0` returns `N(t) − N0` in its normal component; the preload itself
//!   is balanced by the static loads that produced it).
//! * To add an element (e.g. an Iwan joint), implement the trait; nothing else in the solver
//!   changes. The unit tests in [`crate::dynamics::aft`] check any element's derivatives
//!   against finite differences through `check_partials`.

use crate::element::jenkins::{self, JenkinsParams};
use crate::element::valanis::{self, ValanisParams, ValanisState};
// Index of the inputs in `valanis::StepPartials`.
use crate::core::error::{Error, Result};
use crate::element::valanis::{
    F0 as VF0, FZ0 as VFZ0, FZ1 as VFZ1, Q0 as VQ0, Q1 as VQ1, QR0 as VQR0,
};

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

/// Partial derivatives of one element increment `(s0, u0, u1) → (s1, f1)`, row-major dense
/// matrices (`ds_ds0` is `m × m`, `ds_du0` and `ds_du1` are `m × d`, `df_ds0` is `d × m`,
/// `df_du0` and `df_du1` are `d × d`). Entries an element leaves untouched are zero.
#[derive(Debug, Clone, PartialEq)]
pub struct StepPartials {
    pub m: usize,
    pub d: usize,
    pub ds_ds0: Vec<f64>,
    pub ds_du0: Vec<f64>,
    pub ds_du1: Vec<f64>,
    pub df_ds0: Vec<f64>,
    pub df_du0: Vec<f64>,
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

/// A rate-independent element with memory, advanced from sample to sample.
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

/// Cubic spring `f = k3·u³` on one displacement component (the Duffing nonlinearity), no memory.
/// Law: [`crate::element::cubic`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CubicSpring {
    /// Cubic stiffness (N/m³).
    pub k3: f64,
}

impl MemorylessSpring for CubicSpring {
    fn law_name(&self) -> &'static str {
        "cubic"
    }
    fn force_and_stiffness(&self, u: f64) -> (f64, f64) {
        (
            crate::element::cubic::force(self.k3, u),
            crate::element::cubic::stiffness(self.k3, u),
        )
    }
    fn scale(&self) -> f64 {
        self.k3.abs()
    }
}

/// Quadratic spring `f = k2·|u|·u` on one displacement component (stiffness changing in
/// proportion to the amplitude), no memory. Law: [`crate::element::quadratic_spring`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QuadraticSpring {
    /// Quadratic stiffness (N/m²).
    pub k2: f64,
}

impl MemorylessSpring for QuadraticSpring {
    fn law_name(&self) -> &'static str {
        "quadratic-spring"
    }
    fn force_and_stiffness(&self, u: f64) -> (f64, f64) {
        (
            crate::element::quadratic_spring::force(self.k2, u),
            crate::element::quadratic_spring::stiffness(self.k2, u),
        )
    }
    fn scale(&self) -> f64 {
        self.k2.abs()
    }
}

/// One-dimensional Jenkins element (spring `kt` in series with a Coulomb slider) at a constant
/// normal load: slip force `μ·N`. State: the force. Uses [`jenkins::step`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Jenkins {
    pub params: JenkinsParams,
    /// Constant normal load `N` (N).
    pub normal_load: f64,
}

impl Jenkins {
    /// Jenkins element with stiffness `kt` (N/m) and slip force `slip_force` (N) (`μ = 1`,
    /// `N = slip force`).
    pub fn new(kt: f64, slip_force: f64) -> Result<Self> {
        crate::core::error::require_positive("slip_force", slip_force)?;
        Ok(Self {
            params: JenkinsParams::new(kt, 1.0)?,
            normal_load: slip_force,
        })
    }
    fn slip_force(&self) -> f64 {
        self.params.mu * self.normal_load
    }
}

impl HystereticElement for Jenkins {
    fn name(&self) -> &'static str {
        "jenkins-1d"
    }
    fn dofs(&self) -> usize {
        1
    }
    fn state_len(&self) -> usize {
        1
    }
    fn virgin_state(&self, s: &mut [f64]) {
        s[0] = 0.0;
    }
    fn state_scales(&self, scales: &mut [f64]) {
        scales[0] = self.slip_force();
    }
    fn force_scale(&self) -> f64 {
        self.slip_force()
    }
    fn step(
        &self,
        s0: &[f64],
        u0: &[f64],
        u1: &[f64],
        s1: &mut [f64],
        f1: &mut [f64],
        partials: Option<&mut StepPartials>,
    ) {
        let f = jenkins::step(&self.params, s0[0], u1[0] - u0[0], self.normal_load);
        s1[0] = f;
        f1[0] = f;
        if let Some(p) = partials {
            let trial = s0[0] + self.params.kt * (u1[0] - u0[0]);
            if trial.abs() <= self.slip_force() {
                let kt = self.params.kt;
                p.ds_ds0[0] = 1.0;
                p.ds_du0[0] = -kt;
                p.ds_du1[0] = kt;
                p.df_ds0[0] = 1.0;
                p.df_du0[0] = -kt;
                p.df_du1[0] = kt;
            }
        }
    }
    fn status(&self, s: &[f64], _u: &[f64], _f: &[f64]) -> ContactStatus {
        if s[0].abs() >= (1.0 - 1e-12) * self.slip_force() {
            ContactStatus::Slip
        } else {
            ContactStatus::Stick
        }
    }
}

/// Gaul–Lenz element: the Valanis element with a constant stick limit `σ0` (N) on one
/// displacement component ([`crate::element::gaul_lenz`]). State: force and `q_ref`. Each
/// sample increment is integrated exactly for the piecewise-linear displacement between the
/// samples ([`valanis::frozen_load_step`], exact at a constant normal load); a
/// backward-Euler step's first-order lag would bias the harmonic forces by up to
/// 2–3 % at 64 samples per period (test `valanis_aft_forces_converge_with_the_sampling`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GaulLenz {
    /// Valanis parameters with `μ = 1`, driven at the normal load `σ0`.
    pub valanis: ValanisParams,
    pub sigma0: f64,
}

impl GaulLenz {
    /// From the Gaul–Lenz parameters (E0 and Et in N/m, σ0 in N).
    pub fn new(p: &crate::element::GaulLenzParams) -> Result<Self> {
        Ok(Self {
            valanis: p.as_valanis()?,
            sigma0: p.sigma0,
        })
    }
}

impl HystereticElement for GaulLenz {
    fn name(&self) -> &'static str {
        "gaul-lenz"
    }
    fn dofs(&self) -> usize {
        1
    }
    fn state_len(&self) -> usize {
        2
    }
    fn virgin_state(&self, s: &mut [f64]) {
        s[0] = 0.0;
        s[1] = 0.0;
    }
    fn state_scales(&self, scales: &mut [f64]) {
        scales[0] = self.sigma0;
        scales[1] = self.sigma0 / self.valanis.e0;
    }
    fn force_scale(&self) -> f64 {
        self.sigma0
    }
    fn step(
        &self,
        s0: &[f64],
        u0: &[f64],
        u1: &[f64],
        s1: &mut [f64],
        f1: &mut [f64],
        partials: Option<&mut StepPartials>,
    ) {
        let st = ValanisState {
            force: s0[0],
            q: u0[0],
            fz: self.sigma0,
            q_ref: s0[1],
        };
        match partials {
            None => {
                let out = valanis::frozen_load_step(&self.valanis, &st, u1[0], self.sigma0);
                s1[0] = out.force;
                s1[1] = out.q_ref;
            }
            Some(p) => {
                let (out, d) =
                    valanis::frozen_load_step_partials(&self.valanis, &st, u1[0], self.sigma0);
                s1[0] = out.force;
                s1[1] = out.q_ref;
                for (row, g) in [d.force, d.q_ref].iter().enumerate() {
                    p.ds_ds0[row * 2] = g[VF0];
                    p.ds_ds0[row * 2 + 1] = g[VQR0];
                    p.ds_du0[row] = g[VQ0];
                    p.ds_du1[row] = g[VQ1];
                }
                p.df_ds0[0] = d.force[VF0];
                p.df_ds0[1] = d.force[VQR0];
                p.df_du0[0] = d.force[VQ0];
                p.df_du1[0] = d.force[VQ1];
            }
        }
        f1[0] = s1[0];
    }
    fn status(&self, s: &[f64], u: &[f64], _f: &[f64]) -> ContactStatus {
        let centre = self.valanis.et * (u[0] - s[1]);
        if (s[0] - centre).abs() >= 0.99 * self.valanis.slip_limit(self.sigma0) {
            ContactStatus::Slip
        } else {
            ContactStatus::Stick
        }
    }
}

/// The 3-D microslip contact element of the element table: two Valanis elements in the
/// tangential plane (uncoupled, sharing the normal load) and a unilateral normal spring,
/// `N = max(0, N0 + kn·un)`, slip limit `μ·N(t)`, separation when `N = 0` (see
/// [`crate::element::valanis`] for the constitutive equation and the policies on a falling load,
/// separation and re-contact). Local frame `u = (t1, t2, n)`. State:
/// `(F_t1, F_t2, q_ref_t1, q_ref_t2)`. Force: `(F_t1, F_t2, N − N0)`. Each sample increment
/// takes the normal load at its end and integrates the tangential branch exactly at that load
/// ([`valanis::frozen_load_step`]: no first-order lag; the load's change within one increment
/// is the remaining error).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MicroslipContact {
    pub valanis: ValanisParams,
    /// Normal contact stiffness kn (N/m).
    pub kn: f64,
    /// Normal preload N0 (N), > 0.
    pub n0: f64,
}

impl MicroslipContact {
    /// Build and validate (`kn > 0`, `N0 > 0`, Valanis parameters as in [`ValanisParams`]).
    pub fn new(valanis: ValanisParams, kn: f64, n0: f64) -> Result<Self> {
        valanis.validate()?;
        crate::core::error::require_positive("kn", kn)?;
        crate::core::error::require_positive("N0", n0)?;
        Ok(Self { valanis, kn, n0 })
    }
}

impl HystereticElement for MicroslipContact {
    fn name(&self) -> &'static str {
        "valanis"
    }
    fn dofs(&self) -> usize {
        3
    }
    fn state_len(&self) -> usize {
        4
    }
    fn virgin_state(&self, s: &mut [f64]) {
        s.fill(0.0);
    }
    fn state_scales(&self, scales: &mut [f64]) {
        let f = self.valanis.mu * self.n0;
        scales[0] = f;
        scales[1] = f;
        scales[2] = f / self.valanis.e0;
        scales[3] = f / self.valanis.e0;
    }
    fn force_scale(&self) -> f64 {
        self.valanis.mu * self.n0
    }
    fn step(
        &self,
        s0: &[f64],
        u0: &[f64],
        u1: &[f64],
        s1: &mut [f64],
        f1: &mut [f64],
        mut partials: Option<&mut StepPartials>,
    ) {
        let fz0 = self.n0 + self.kn * u0[2];
        let fz1 = self.n0 + self.kn * u1[2];
        for j in 0..2 {
            let st = ValanisState {
                force: s0[j],
                q: u0[j],
                fz: fz0,
                q_ref: s0[2 + j],
            };
            match partials.as_deref_mut() {
                None => {
                    let out = valanis::frozen_load_step(&self.valanis, &st, u1[j], fz1);
                    s1[j] = out.force;
                    s1[2 + j] = out.q_ref;
                }
                Some(p) => {
                    let (out, d) =
                        valanis::frozen_load_step_partials(&self.valanis, &st, u1[j], fz1);
                    s1[j] = out.force;
                    s1[2 + j] = out.q_ref;
                    for (row, g) in [(j, d.force), (2 + j, d.q_ref)] {
                        p.ds_ds0[row * 4 + j] = g[VF0];
                        p.ds_ds0[row * 4 + 2 + j] = g[VQR0];
                        p.ds_du0[row * 3 + j] = g[VQ0];
                        p.ds_du0[row * 3 + 2] = g[VFZ0] * self.kn;
                        p.ds_du1[row * 3 + j] = g[VQ1];
                        p.ds_du1[row * 3 + 2] = g[VFZ1] * self.kn;
                    }
                    p.df_ds0[j * 4 + j] = d.force[VF0];
                    p.df_ds0[j * 4 + 2 + j] = d.force[VQR0];
                    p.df_du0[j * 3 + j] = d.force[VQ0];
                    p.df_du0[j * 3 + 2] = d.force[VFZ0] * self.kn;
                    p.df_du1[j * 3 + j] = d.force[VQ1];
                    p.df_du1[j * 3 + 2] = d.force[VFZ1] * self.kn;
                }
            }
            f1[j] = s1[j];
        }
        f1[2] = fz1.max(0.0) - self.n0;
        if let Some(p) = partials {
            if fz1 > 0.0 {
                p.df_du1[8] = self.kn;
            }
        }
    }
    fn status(&self, s: &[f64], u: &[f64], _f: &[f64]) -> ContactStatus {
        let fz = self.n0 + self.kn * u[2];
        if fz <= 0.0 {
            return ContactStatus::Separated;
        }
        let half = self.valanis.slip_limit(fz);
        let used = (0..2)
            .map(|j| (s[j] - self.valanis.et * (u[j] - s[2 + j])).abs())
            .fold(0.0, f64::max);
        if used >= 0.99 * half {
            ContactStatus::Slip
        } else {
            ContactStatus::Stick
        }
    }
}

/// 2-D Jenkins contact element: isotropic Coulomb friction with a circular slip limit
/// `|F_t| ≤ μ·N(t)` ([`jenkins::step_2d`]) behind a tangential spring `kt`, and the same
/// unilateral normal spring as [`MicroslipContact`] (`N = max(0, N0 + kn·un)`, separation resets
/// the tangential force; re-contact at the interpolated closing point). Local frame
/// `u = (t1, t2, n)`; state `(F_t1, F_t2)`; force `(F_t1, F_t2, N − N0)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JenkinsContact {
    pub params: JenkinsParams,
    /// Normal contact stiffness kn (N/m).
    pub kn: f64,
    /// Normal preload N0 (N), > 0.
    pub n0: f64,
}

impl JenkinsContact {
    /// Build and validate (`kt, μ, kn, N0 > 0`).
    pub fn new(kt: f64, mu: f64, kn: f64, n0: f64) -> Result<Self> {
        let params = JenkinsParams::new(kt, mu)?;
        crate::core::error::require_positive("kn", kn)?;
        crate::core::error::require_positive("N0", n0)?;
        Ok(Self { params, kn, n0 })
    }
}

impl HystereticElement for JenkinsContact {
    fn name(&self) -> &'static str {
        "jenkins"
    }
    fn dofs(&self) -> usize {
        3
    }
    fn state_len(&self) -> usize {
        2
    }
    fn virgin_state(&self, s: &mut [f64]) {
        s.fill(0.0);
    }
    fn state_scales(&self, scales: &mut [f64]) {
        scales.fill(self.params.mu * self.n0);
    }
    fn force_scale(&self) -> f64 {
        self.params.mu * self.n0
    }
    fn step(
        &self,
        s0: &[f64],
        u0: &[f64],
        u1: &[f64],
        s1: &mut [f64],
        f1: &mut [f64],
        partials: Option<&mut StepPartials>,
    ) {
        let kn = self.kn;
        let fz0 = self.n0 + kn * u0[2];
        let fz1 = self.n0 + kn * u1[2];
        // Start of the increment: the state, or a virgin element at the re-contact point.
        let (start, theta, dth_dfz0, dth_dfz1) = if fz0 <= 0.0 && fz1 > 0.0 {
            let den = (fz0 - fz1) * (fz0 - fz1);
            ([0.0; 2], fz0 / (fz0 - fz1), -fz1 / den, fz0 / den)
        } else {
            ([s0[0], s0[1]], 0.0, 0.0, 0.0)
        };
        let dq = [
            (1.0 - theta) * (u1[0] - u0[0]),
            (1.0 - theta) * (u1[1] - u0[1]),
        ];
        let (f, df_dt, df_dfz) = jenkins::step_2d_partials(&self.params, start, dq, fz1);
        s1[0] = f[0];
        s1[1] = f[1];
        f1[0] = f[0];
        f1[1] = f[1];
        f1[2] = fz1.max(0.0) - self.n0;
        if let Some(p) = partials {
            if fz1 <= 0.0 {
                return;
            }
            let kt = self.params.kt;
            let recontact = fz0 <= 0.0;
            for i in 0..2 {
                for j in 0..2 {
                    // ∂F_i/∂F0_j (zero after a re-contact: the history is forgotten).
                    let a = if recontact { 0.0 } else { df_dt[i][j] };
                    p.ds_ds0[i * 2 + j] = a;
                    p.df_ds0[i * 2 + j] = a;
                    let b = df_dt[i][j] * kt * (1.0 - theta);
                    p.ds_du1[i * 3 + j] = b;
                    p.ds_du0[i * 3 + j] = -b;
                    p.df_du1[i * 3 + j] = b;
                    p.df_du0[i * 3 + j] = -b;
                }
                // Through the normal load and the re-contact fraction θ.
                let mut d_fz1 = df_dfz[i];
                let mut d_fz0 = 0.0;
                if recontact {
                    for j in 0..2 {
                        let g = df_dt[i][j] * kt * (u1[j] - u0[j]);
                        d_fz1 -= g * dth_dfz1;
                        d_fz0 -= g * dth_dfz0;
                    }
                }
                p.ds_du1[i * 3 + 2] = d_fz1 * kn;
                p.ds_du0[i * 3 + 2] = d_fz0 * kn;
                p.df_du1[i * 3 + 2] = d_fz1 * kn;
                p.df_du0[i * 3 + 2] = d_fz0 * kn;
            }
            p.df_du1[8] = kn;
        }
    }
    fn status(&self, s: &[f64], u: &[f64], _f: &[f64]) -> ContactStatus {
        let fz = self.n0 + self.kn * u[2];
        if fz <= 0.0 {
            ContactStatus::Separated
        } else if s[0].hypot(s[1]) >= (1.0 - 1e-12) * self.params.mu * fz {
            ContactStatus::Slip
        } else {
            ContactStatus::Stick
        }
    }
}

/// Constitutive law named in a model file for the rows of an element table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ContactLaw {
    /// [`MicroslipContact`]: E0, k, Et, μ, kn, N0 from the table.
    Valanis,
    /// [`JenkinsContact`]: kt = E0 of the table (the initial tangential stiffness), μ, kn, N0.
    Jenkins,
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn element_partials_match_finite_differences() {
        let v = ValanisParams::new(2.0e6, 0.4, 1.0e5, 0.6).unwrap();
        let micro = MicroslipContact::new(v, 5.0e6, 10.0).unwrap();
        let slip = 6.0 / 2.0e6;
        let h = 1e-4 * slip;
        // Microslip element: loading in contact, unloading, re-contact inside the increment.
        for (s0, u0, u1) in [
            (
                vec![1.0, -0.5, 0.0, 0.0],
                vec![0.2 * slip, 0.1 * slip, 1e-7],
                vec![0.5 * slip, -0.2 * slip, 3e-7],
            ),
            (
                vec![3.0, 2.0, 0.1 * slip, 0.0],
                vec![slip, 0.5 * slip, -1e-6],
                vec![0.4 * slip, 0.7 * slip, -5e-7],
            ),
            (
                vec![0.0, 0.0, 0.3 * slip, 0.2 * slip],
                vec![slip, 0.5 * slip, -3e-6],
                vec![1.3 * slip, 0.2 * slip, 1e-6],
            ),
        ] {
            let w = check_partials(&micro, &s0, &u0, &u1, h, &[1e-5, 1e-5, h, h]).unwrap();
            assert!(w < 1e-5, "microslip: {w}");
        }
        let jc = JenkinsContact::new(3.0e6, 0.5, 5.0e6, 10.0).unwrap();
        let slip = 5.0 / 3.0e6;
        for (s0, u0, u1) in [
            (
                vec![1.0, -0.5],
                vec![0.0, 0.0, 1e-7],
                vec![0.2 * slip, 0.1 * slip, 2e-7],
            ),
            (
                vec![3.0, 2.0],
                vec![0.0, 0.0, 0.0],
                vec![slip, 0.8 * slip, -5e-7],
            ),
            (
                vec![0.0, 0.0],
                vec![slip, 0.5 * slip, -3e-6],
                vec![1.6 * slip, 0.2 * slip, 1e-6],
            ),
        ] {
            let w = check_partials(&jc, &s0, &u0, &u1, 1e-4 * slip, &[1e-5, 1e-5]).unwrap();
            assert!(w < 1e-5, "jenkins contact: {w}");
        }
        let gl = GaulLenz::new(&crate::element::GaulLenzParams {
            e0: 1e6,
            k: 0.3,
            et: 1e4,
            sigma0: 2.0,
        })
        .unwrap();
        let w = check_partials(&gl, &[0.5, 1e-7], &[1e-6], &[2e-6], 1e-10, &[1e-6, 1e-10]).unwrap();
        assert!(w < 1e-5, "gaul-lenz: {w}");
        let j = Jenkins::new(1e5, 1.0).unwrap();
        let w = check_partials(&j, &[0.2], &[0.0], &[3e-6], 1e-10, &[1e-6]).unwrap();
        assert!(w < 1e-6, "jenkins: {w}");
    }
}
