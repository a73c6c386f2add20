//! The 3-D contact elements of the element table: a friction law in the tangential plane behind a
//! unilateral normal spring ([`crate::element::unilateral`]), in the local frame
//! `u = (t1, t2, n)` (two tangential components and the normal approach, `n > 0` closing the
//! contact). Both return the force `(F_t1, F_t2, N − N0)` with `N = max(0, N0 + kn·un)`; the
//! tangential slip limit is `μ·N(t)`, the contact separates when `N = 0` (its tangential force
//! vanishes and its history is forgotten) and closes again at the interpolated re-contact point.
//!
//! * [`MicroslipContact`]: two Valanis elements ([`crate::element::valanis`]), uncoupled and
//!   sharing the normal load.
//! * [`JenkinsContact`]: isotropic Coulomb friction with a circular slip limit behind a
//!   tangential spring ([`crate::element::jenkins::step_2d`]).
//!
//! Units: per element (m, N, N/m).

use crate::core::error::Result;
use crate::element::hysteretic::{ContactStatus, HystereticElement, StepPartials};
use crate::element::jenkins::{self, JenkinsParams, JENKINS_SLIP_THRESHOLD};
use crate::element::params::ContactParams;
use crate::element::unilateral::{recontact_fraction, PowerLawNormal, UnilateralNormal};
use crate::element::valanis::{
    self, Direction, LoadFollowingValanis, ValanisParams, GROSS_SLIP_FRACTION,
};

/// Index of the normal approach in the local frame `u = (t1, t2, n)`.
const NORMAL: usize = 2;

/// Write the normal component of a contact element's force, `N − N0` at the trial load `n1`
/// (the load at the end of the increment), and its derivative `∂f_n/∂u1_n`.
#[inline]
fn normal_force(
    normal: &UnilateralNormal,
    n1: f64,
    f1: &mut [f64],
    partials: Option<&mut StepPartials>,
) {
    let (f, k) = normal.force_change(n1);
    f1[NORMAL] = f;
    if let Some(p) = partials {
        p.df_du1[NORMAL * 3 + NORMAL] = k;
    }
}

/// The 3-D microslip contact element: two Valanis elements in the tangential plane (uncoupled,
/// sharing the normal load) and a unilateral normal spring (module documentation; see
/// [`crate::element::valanis`] for the constitutive equation and the policies on a falling load,
/// separation and re-contact). State: `(F_t1, F_t2, q_ref_t1, q_ref_t2)`. Each sample increment
/// takes the normal load at its end and integrates the tangential branch exactly at that load
/// ([`valanis::frozen_load_step`]: no first-order lag; the load's change within one increment
/// is the remaining error).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MicroslipContact {
    /// Valanis parameters of each tangential direction (per element: `E0`, `Et` in N/m).
    pub valanis: ValanisParams,
    /// The unilateral normal spring (`kn`, `N0`).
    pub normal: UnilateralNormal,
}

impl MicroslipContact {
    /// Build and validate (`kn > 0`, `N0 > 0`, Valanis parameters as in [`ValanisParams`]).
    pub fn new(valanis: ValanisParams, kn: f64, n0: f64) -> Result<Self> {
        valanis.validate()?;
        Ok(Self {
            valanis,
            normal: UnilateralNormal::new(kn, n0)?,
        })
    }

    /// The element of a row of the element table at its preload `n0` (N).
    pub fn from_params(p: &ContactParams, n0: f64) -> Result<Self> {
        Self::new(p.valanis()?, p.kn_n_per_m, n0)
    }

    /// Tangential direction `j` (0 or 1): state `(F_tj, q_ref_tj)`, normal load from `un`.
    #[inline]
    fn direction(&self, j: usize) -> Direction {
        Direction {
            force: j,
            q_ref: 2 + j,
            u: j,
            normal: Some((NORMAL, [self.normal.kn; 2])),
        }
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
        let f = self.force_scale();
        scales[0] = f;
        scales[1] = f;
        scales[2] = f / self.valanis.e0;
        scales[3] = f / self.valanis.e0;
    }
    fn force_scale(&self) -> f64 {
        self.valanis.mu * self.normal.n0
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
        let fz0 = self.normal.trial_load(u0[NORMAL]);
        let fz1 = self.normal.trial_load(u1[NORMAL]);
        for j in 0..2 {
            valanis::direction_step(
                &self.valanis,
                self.direction(j),
                s0,
                u0,
                u1,
                fz0,
                fz1,
                s1,
                f1,
                partials.as_deref_mut(),
            );
        }
        normal_force(&self.normal, fz1, f1, partials);
    }
    fn status(&self, s: &[f64], u: &[f64], _f: &[f64]) -> ContactStatus {
        let fz = self.normal.trial_load(u[NORMAL]);
        if fz <= 0.0 {
            return ContactStatus::Separated;
        }
        let used = (0..2)
            .map(|j| (s[j] - self.valanis.et * (u[j] - s[2 + j])).abs())
            .fold(0.0, f64::max);
        ContactStatus::classify(fz, used, GROSS_SLIP_FRACTION * self.valanis.slip_limit(fz))
    }
}

/// The 3-D microslip contact element whose stiffnesses follow the instantaneous normal load
/// (the element the reference underplatform-damper study proposes): [`MicroslipContact`] with
/// `kn(N) = kn0·(N/N0)^b` ([`PowerLawNormal`]) and `E0(N) = E0_0·(N/N0)^a`
/// ([`LoadFollowingValanis`]; `Et/E0`, `k`, `μ` fixed), the exponents those of the calibration
/// table at the element's pressure (`kn″ ∝ p^b`, `E0″ ∝ p^a`). With `a = b = 0` it is
/// [`MicroslipContact`]. State `(F_t1, F_t2, q_ref_t1, q_ref_t2)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoadFollowingContact {
    /// Valanis law of each tangential direction, about the preload.
    pub valanis: LoadFollowingValanis,
    /// The load-following normal spring.
    pub normal: PowerLawNormal,
}

impl LoadFollowingContact {
    /// Build and validate: the element at the preload `n0` (N) as [`MicroslipContact::new`],
    /// `kn_exponent` `b` in `[0, 1]`, `e0_exponent` `a` finite.
    pub fn new(
        valanis: ValanisParams,
        kn: f64,
        n0: f64,
        kn_exponent: f64,
        e0_exponent: f64,
    ) -> Result<Self> {
        Ok(Self {
            valanis: LoadFollowingValanis::new(valanis, n0, e0_exponent)?,
            normal: PowerLawNormal::new(kn, n0, kn_exponent)?,
        })
    }
}

impl HystereticElement for LoadFollowingContact {
    fn name(&self) -> &'static str {
        "valanis-load-following"
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
        let f = self.force_scale();
        let e0 = self.valanis.reference.e0;
        scales.copy_from_slice(&[f, f, f / e0, f / e0]);
    }
    fn force_scale(&self) -> f64 {
        self.valanis.reference.mu * self.normal.n0
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
        let (fz0, k0) = self.normal.trial_load_and_slope(u0[NORMAL]);
        let (fz1, k1) = self.normal.trial_load_and_slope(u1[NORMAL]);
        for j in 0..2 {
            let c = Direction {
                force: j,
                q_ref: 2 + j,
                u: j,
                normal: Some((NORMAL, [k0, k1])),
            };
            valanis::direction_step(
                &self.valanis,
                c,
                s0,
                u0,
                u1,
                fz0,
                fz1,
                s1,
                f1,
                partials.as_deref_mut(),
            );
        }
        f1[NORMAL] = fz1.max(0.0) - self.normal.n0;
        if let Some(p) = partials {
            p.df_du1[NORMAL * 3 + NORMAL] = if fz1 > 0.0 { k1 } else { 0.0 };
        }
    }
    fn status(&self, s: &[f64], u: &[f64], _f: &[f64]) -> ContactStatus {
        let fz = self.normal.trial_load(u[NORMAL]);
        if fz <= 0.0 {
            return ContactStatus::Separated;
        }
        let p = self.valanis.at(fz);
        let used = (0..2)
            .map(|j| (s[j] - p.et * (u[j] - s[2 + j])).abs())
            .fold(0.0, f64::max);
        ContactStatus::classify(fz, used, GROSS_SLIP_FRACTION * p.slip_limit(fz))
    }
}

/// The 3-D Jenkins contact element: isotropic Coulomb friction with a circular slip limit
/// `|F_t| ≤ μ·N(t)` ([`jenkins::step_2d`]) behind a tangential spring `kt`, and the unilateral
/// normal spring of [`MicroslipContact`] (module documentation). State `(F_t1, F_t2)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JenkinsContact {
    /// Tangential stiffness `kt` (N/m) and friction coefficient `μ`.
    pub params: JenkinsParams,
    /// The unilateral normal spring (`kn`, `N0`).
    pub normal: UnilateralNormal,
}

impl JenkinsContact {
    /// Build and validate (`kt, μ, kn, N0 > 0`).
    pub fn new(kt: f64, mu: f64, kn: f64, n0: f64) -> Result<Self> {
        let params = JenkinsParams::new(kt, mu)?;
        Ok(Self {
            params,
            normal: UnilateralNormal::new(kn, n0)?,
        })
    }

    /// The element of a row of the element table at its preload `n0` (N): `kt = E0` (the
    /// initial tangential stiffness), `μ`, `kn`.
    pub fn from_params(p: &ContactParams, n0: f64) -> Result<Self> {
        Self::new(p.e0_n_per_m, p.mu, p.kn_n_per_m, n0)
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
        scales.fill(self.force_scale());
    }
    fn force_scale(&self) -> f64 {
        self.params.mu * self.normal.n0
    }
    /// Exact derivatives of the return map ([`jenkins::step_2d_partials`]), chained through the
    /// normal load `N0 + kn·un` and, after a re-contact inside the increment, through the
    /// re-contact fraction `θ` (the slide starts from a virgin element at `θ`).
    #[allow(clippy::needless_range_loop)]
    fn step(
        &self,
        s0: &[f64],
        u0: &[f64],
        u1: &[f64],
        s1: &mut [f64],
        f1: &mut [f64],
        partials: Option<&mut StepPartials>,
    ) {
        let kn = self.normal.kn;
        let fz0 = self.normal.trial_load(u0[NORMAL]);
        let fz1 = self.normal.trial_load(u1[NORMAL]);
        // Start of the increment: the state, or a virgin element at the re-contact point.
        let (start, theta, dth_dfz0, dth_dfz1) = if fz0 <= 0.0 && fz1 > 0.0 {
            let (theta, d0, d1) = recontact_fraction(fz0, fz1);
            ([0.0; 2], theta, d0, d1)
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
        let Some(p) = partials else {
            normal_force(&self.normal, fz1, f1, None);
            return;
        };
        if fz1 > 0.0 {
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
                p.ds_du1[i * 3 + NORMAL] = d_fz1 * kn;
                p.ds_du0[i * 3 + NORMAL] = d_fz0 * kn;
                p.df_du1[i * 3 + NORMAL] = d_fz1 * kn;
                p.df_du0[i * 3 + NORMAL] = d_fz0 * kn;
            }
        }
        normal_force(&self.normal, fz1, f1, Some(p));
    }
    fn status(&self, s: &[f64], u: &[f64], _f: &[f64]) -> ContactStatus {
        let fz = self.normal.trial_load(u[NORMAL]);
        ContactStatus::classify(
            fz,
            s[0].hypot(s[1]),
            JENKINS_SLIP_THRESHOLD * self.params.mu * fz,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::hysteretic::check_partials;

    /// Loading in contact, unloading, and re-contact inside the increment.
    #[test]
    fn microslip_partials_match_finite_differences() {
        let v = ValanisParams::new(2.0e6, 0.4, 1.0e5, 0.6).unwrap();
        let micro = MicroslipContact::new(v, 5.0e6, 10.0).unwrap();
        let slip = 6.0 / 2.0e6;
        let h = 1e-4 * slip;
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
    }

    #[test]
    fn jenkins_contact_partials_match_finite_differences() {
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
    }
}
