//! Valanis element in the Gaul–Lenz form: a constant stick limit `σ0` instead of `μ·Fz(t)`.
//!
//! Gaul & Lenz (1997), "Nonlinear dynamics of structures assembled by bolted joints", *Acta
//! Mechanica* 125, used the endochronic Valanis model with
//! `dF/dt = E0·q̇·[1 + (λ/E0)·s·(Et·q − F)] / [1 + k·(λ/E0)·s·(Et·q − F)]`,
//! `λ = E0 / (σ0·(1 − k·Et/E0))`, i.e. [`crate::element::valanis`] with `μ·Fz ≡ σ0`. This module
//! maps onto that implementation (one code path for the physics). Units: `σ0` in Pa (per area) or
//! N (per element), `E0`, `Et` in N/m³ or N/m.

use crate::core::error::Result;
use crate::element::valanis::{self, Integrator, ValanisParams};

/// Gaul–Lenz (constant stick limit) Valanis parameters.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct GaulLenzParams {
    /// Initial-loading stiffness `E0`.
    pub e0: f64,
    /// Shape parameter `0 ≤ k < 1`.
    pub k: f64,
    /// Residual stiffness `0 ≤ Et < E0`.
    pub et: f64,
    /// Stick limit `σ0 > 0` (the slip force for `Et = 0`).
    pub sigma0: f64,
}

impl GaulLenzParams {
    /// The equivalent Valanis parameters with `μ = 1`, to be driven with `Fz ≡ σ0`.
    pub fn as_valanis(&self) -> Result<ValanisParams> {
        crate::core::error::require_positive("sigma0", self.sigma0)?;
        ValanisParams::new(self.e0, self.k, self.et, 1.0)
    }
}

/// One implicit-Euler increment: force at `q1` from force `f0` at `q0` (`q_ref` as in
/// [`valanis::ValanisState`]).
pub fn step(p: &GaulLenzParams, f0: f64, q0: f64, q_ref: f64, q1: f64) -> Result<f64> {
    let v = p.as_valanis()?;
    let state = valanis::ValanisState {
        force: f0,
        q: q0,
        fz: p.sigma0,
        q_ref,
    };
    Ok(valanis::implicit_euler_step(&v, &state, q1, p.sigma0).force)
}

/// Force history of a virgin element driven by `q`.
pub fn integrate(p: &GaulLenzParams, q: &[f64], method: Integrator) -> Result<Vec<f64>> {
    let v = p.as_valanis()?;
    valanis::integrate(&v, q, &vec![p.sigma0; q.len()], method)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn saturates_at_the_stick_limit() {
        let p = GaulLenzParams {
            e0: 1e8,
            k: 0.5,
            et: 0.0,
            sigma0: 100.0,
        };
        let f = integrate(&p, &[0.0, 1e-3, 1e-2], Integrator::Reference).unwrap();
        assert!((f[2] - 100.0).abs() < 1e-6);
        assert!(step(&p, 0.0, 0.0, 0.0, 1e-9).unwrap() > 0.0);
        let bad = GaulLenzParams { sigma0: 0.0, ..p };
        assert!(integrate(&bad, &[0.0], Integrator::Reference).is_err());
    }
}
