//! Jenkins (macroslip) element: a linear spring `kt` in series with a Coulomb slider `μ·Fz`.
//!
//! Force update (return map, exact for a piecewise-linear displacement path at constant load):
//! `F_trial = F + kt·Δq`, `F = clamp(F_trial, −μ·Fz, +μ·Fz)`. On separation (`Fz ≤ 0`) the force
//! is zero and the slider position is forgotten. A falling normal load caps the force at the new
//! limit (same policy as [`crate::element::valanis`]). Units as in [`crate::element`]: `kt` in
//! N/m³ with forces in Pa, or N/m with forces in N.

use crate::error::{Error, Result};

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
        crate::error::require_positive("kt", kt)?;
        crate::error::require_positive("mu", mu)?;
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

#[cfg(test)]
mod tests {
    use super::*;
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
    fn separation_releases_the_force() {
        let p = JenkinsParams::new(1.0, 1.0).unwrap();
        let f = integrate(&p, &[0.0, 0.5, 0.5], &[1.0, 1.0, 0.0]).unwrap();
        assert_eq!(f, vec![0.0, 0.5, 0.0]);
        assert!(JenkinsParams::new(0.0, 1.0).is_err());
    }
}
