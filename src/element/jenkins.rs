//! Jenkins (macroslip) element: a linear spring `kt` in series with a Coulomb slider `μ·Fz`.
//!
//! Force update (return map, exact for a piecewise-linear displacement path at constant load):
//! `F_trial = F + kt·Δq`, `F = clamp(F_trial, −μ·Fz, +μ·Fz)`. On separation (`Fz ≤ 0`) the force
//! is zero and the slider position is forgotten. A falling normal load caps the force at the new
//! limit (same policy as [`crate::element::valanis`]). Units as in [`crate::element`]: `kt` in
//! N/m³ with forces in Pa, or N/m with forces in N.

use crate::core::error::{Error, Result};
use crate::element::hysteretic::{ContactStatus, HystereticElement, StepPartials};

/// Jenkins element parameters.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct JenkinsParams {
    /// Tangential stiffness of the stuck element (N/m³ or N/m).
    pub kt: f64,
    /// Friction coefficient.
    pub mu: f64,
}

impl JenkinsParams {
    /// Build and validate (`kt > 0`, `μ > 0`).
    pub fn new(kt: f64, mu: f64) -> Result<Self> {
        crate::core::error::require_positive("kt", kt)?;
        crate::core::error::require_positive("mu", mu)?;
        Ok(Self { kt, mu })
    }
}

/// One increment: force after moving by `dq` from force `f0`, under normal load `fz1`.
pub fn step(p: &JenkinsParams, f0: f64, dq: f64, fz1: f64) -> f64 {
    let limit = p.mu * fz1.max(0.0);
    (f0 + p.kt * dq).clamp(-limit, limit)
}

/// Force history of an initially unloaded element driven by `q` under normal loads `fz`.
pub fn integrate(p: &JenkinsParams, q: &[f64], fz: &[f64]) -> Result<Vec<f64>> {
    JenkinsParams::new(p.kt, p.mu)?;
    if q.len() != fz.len() {
        return Err(Error::param(
            "fz",
            format!(
                "{} normal-load samples for {} displacements",
                fz.len(),
                q.len()
            ),
        ));
    }
    if q.iter().chain(fz).any(|v| !v.is_finite()) {
        return Err(Error::param(
            "q",
            "displacement or normal-load history is not finite",
        ));
    }
    let mut out = Vec::with_capacity(q.len());
    let mut f = 0.0;
    for i in 0..q.len() {
        if i > 0 {
            f = step(p, f, q[i] - q[i - 1], fz[i]);
        }
        out.push(f);
    }
    Ok(out)
}

/// Two-dimensional Jenkins element with a circular slip limit (isotropic Coulomb friction in the
/// tangential plane): trial force `T = F0 + kt·Δq`, `F1 = T` if `|T| ≤ μ·Fz1`, else the radial
/// return `F1 = μ·Fz1·T/|T|` (the return map of Coulomb friction with an elastic predictor, exact
/// for a straight displacement path at constant normal load). `Fz1 ≤ 0` is separation: `F1 = 0`.
pub fn step_2d(p: &JenkinsParams, f0: [f64; 2], dq: [f64; 2], fz1: f64) -> [f64; 2] {
    step_2d_partials(p, f0, dq, fz1).0
}

/// [`step_2d`] with its exact derivatives: `∂F1/∂F0` (2×2, equal to `∂F1/∂Δq / kt`) and
/// `∂F1/∂Fz1` (2). In stick `∂F1/∂F0 = I`; in slip `∂F1/∂T = (μFz1/|T|)·(I − t̂t̂ᵀ)` and
/// `∂F1/∂Fz1 = μ·t̂` with `t̂ = T/|T|`.
pub fn step_2d_partials(
    p: &JenkinsParams,
    f0: [f64; 2],
    dq: [f64; 2],
    fz1: f64,
) -> ([f64; 2], [[f64; 2]; 2], [f64; 2]) {
    if fz1 <= 0.0 {
        return ([0.0; 2], [[0.0; 2]; 2], [0.0; 2]);
    }
    let t = [f0[0] + p.kt * dq[0], f0[1] + p.kt * dq[1]];
    let norm = t[0].hypot(t[1]);
    let limit = p.mu * fz1;
    if norm <= limit {
        return (t, [[1.0, 0.0], [0.0, 1.0]], [0.0; 2]);
    }
    let u = [t[0] / norm, t[1] / norm];
    let r = limit / norm;
    let dt = [
        [r * (1.0 - u[0] * u[0]), -r * u[0] * u[1]],
        [-r * u[1] * u[0], r * (1.0 - u[1] * u[1])],
    ];
    ([limit * u[0], limit * u[1]], dt, [p.mu * u[0], p.mu * u[1]])
}

/// One-dimensional Jenkins element at a constant normal load `N` (slip force `μ·N`) as a
/// [`HystereticElement`]. State: the force. Update: [`step`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Jenkins {
    /// Stiffness `kt` (N/m) and friction coefficient `μ`.
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
    /// In stick the force follows the spring (`∂F1/∂F0 = 1`, `∂F1/∂u1 = −∂F1/∂u0 = kt`); on the
    /// slip limit it is constant.
    fn step(
        &self,
        s0: &[f64],
        u0: &[f64],
        u1: &[f64],
        s1: &mut [f64],
        f1: &mut [f64],
        partials: Option<&mut StepPartials>,
    ) {
        let f = step(&self.params, s0[0], u1[0] - u0[0], self.normal_load);
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
        ContactStatus::classify(
            self.normal_load,
            s[0].abs(),
            JENKINS_SLIP_THRESHOLD * self.slip_force(),
        )
    }
}

/// A Jenkins slider is reported slipping when its force is within round-off of the limit.
pub const JENKINS_SLIP_THRESHOLD: f64 = 1.0 - 1e-12;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::hysteretic::check_partials;
    use crate::element::{dissipated_energy, sine_history};

    #[test]
    fn energy_per_cycle_matches_closed_form() {
        // Jenkins loop energy: W = 4·Fs·(A − Fs/kt) for A > Fs/kt.
        let p = JenkinsParams::new(1.0e6, 0.5).unwrap();
        let fz = 10.0;
        let fs = p.mu * fz;
        let a = 3.0 * fs / p.kt;
        let q = sine_history(a, 2, 20_000);
        let f = integrate(&p, &q, &vec![fz; q.len()]).unwrap();
        let n = q.len();
        let w = dissipated_energy(&q[n - 20_001..], &f[n - 20_001..]);
        let exact = 4.0 * fs * (a - fs / p.kt);
        assert!((w - exact).abs() / exact < 1e-3, "{w} vs {exact}");
    }

    #[test]
    fn circular_limit_and_its_derivatives() {
        let p = JenkinsParams::new(2.0, 0.5).unwrap();
        // Slip along a diagonal: the force lands on the circle μ·Fz in the trial direction.
        let f = step_2d(&p, [0.0, 0.0], [3.0, 3.0], 4.0);
        assert!((f[0].hypot(f[1]) - 2.0).abs() < 1e-14 && (f[0] - f[1]).abs() < 1e-14);
        // One-dimensional motion reduces to the 1-D element.
        let f1 = step_2d(&p, [0.5, 0.0], [0.3, 0.0], 4.0);
        assert!((f1[0] - step(&p, 0.5, 0.3, 4.0)).abs() < 1e-15 && f1[1] == 0.0);
        // Finite differences in slip.
        let (f0, dq, fz) = ([0.7, -0.4], [0.9, 0.2], 3.0);
        let (_, dt, dfz) = step_2d_partials(&p, f0, dq, fz);
        let h = 1e-7;
        for j in 0..2 {
            let mut a = f0;
            let mut b = f0;
            a[j] += h;
            b[j] -= h;
            let (fa, fb) = (step_2d(&p, a, dq, fz), step_2d(&p, b, dq, fz));
            for i in 0..2 {
                assert!(((fa[i] - fb[i]) / (2.0 * h) - dt[i][j]).abs() < 1e-7);
            }
        }
        let (fa, fb) = (step_2d(&p, f0, dq, fz + h), step_2d(&p, f0, dq, fz - h));
        for i in 0..2 {
            assert!(((fa[i] - fb[i]) / (2.0 * h) - dfz[i]).abs() < 1e-7);
        }
        assert_eq!(step_2d(&p, f0, dq, -1.0), [0.0, 0.0]);
    }

    #[test]
    fn separation_releases_the_force() {
        let p = JenkinsParams::new(1.0, 1.0).unwrap();
        let f = integrate(&p, &[0.0, 0.5, 0.5], &[1.0, 1.0, 0.0]).unwrap();
        assert_eq!(f, vec![0.0, 0.5, 0.0]);
        assert!(JenkinsParams::new(0.0, 1.0).is_err());
    }

    #[test]
    fn element_partials_match_finite_differences() {
        let j = Jenkins::new(1e5, 1.0).unwrap();
        let w = check_partials(&j, &[0.2], &[0.0], &[3e-6], 1e-10, &[1e-6]).unwrap();
        assert!(w < 1e-6, "jenkins: {w}");
    }
}
