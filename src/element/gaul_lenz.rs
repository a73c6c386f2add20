//! Valanis element in the Gaul–Lenz form: a constant stick limit `σ0` instead of `μ·Fz(t)`.
//!
//! Gaul & Lenz (1997), "Nonlinear dynamics of structures assembled by bolted joints", *Acta
//! Mechanica* 125, used the endochronic Valanis model with
//! `dF/dt = E0·q̇·[1 + (λ/E0)·s·(Et·q − F)] / [1 + k·(λ/E0)·s·(Et·q − F)]`,
//! `λ = E0 / (σ0·(1 − k·Et/E0))`, i.e. [`crate::element::valanis`] with `μ·Fz ≡ σ0`. This module
//! maps onto that implementation (one code path for the physics). Units: `σ0` in Pa (per area) or
//! N (per element), `E0`, `Et` in N/m³ or N/m.

use crate::core::error::Result;
use crate::element::hysteretic::{ContactStatus, HystereticElement, StepPartials};
use crate::element::valanis::{self, Direction, Integrator, ValanisParams};

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

/// The Gaul–Lenz element on one displacement component as a [`HystereticElement`]. State: force
/// and `q_ref`. Each sample increment is integrated exactly for the piecewise-linear displacement
/// between the samples ([`valanis::frozen_load_step`], exact at a constant normal load; a
/// backward-Euler step would bias the harmonic forces by a first-order lag, 2–3 % at 64 samples
/// per period).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GaulLenz {
    /// Valanis parameters with `μ = 1`, driven at the normal load `σ0`.
    pub valanis: ValanisParams,
    /// Slip force `σ0` (N), the normal load the Valanis law is driven at.
    pub sigma0: f64,
}

impl GaulLenz {
    /// From the Gaul–Lenz parameters (E0 and Et in N/m, σ0 in N).
    pub fn new(p: &GaulLenzParams) -> Result<Self> {
        Ok(Self {
            valanis: p.as_valanis()?,
            sigma0: p.sigma0,
        })
    }
}

/// The single Valanis direction of [`GaulLenz`]: state `(F, q_ref)`, constant normal load.
const ONE_DIRECTION: Direction = Direction {
    force: 0,
    q_ref: 1,
    u: 0,
    normal: None,
};

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
        valanis::direction_step(
            &self.valanis,
            ONE_DIRECTION,
            s0,
            u0,
            u1,
            self.sigma0,
            self.sigma0,
            s1,
            f1,
            partials,
        );
    }
    fn status(&self, s: &[f64], u: &[f64], _f: &[f64]) -> ContactStatus {
        let used = (s[0] - self.valanis.et * (u[0] - s[1])).abs();
        ContactStatus::classify(
            self.sigma0,
            used,
            valanis::GROSS_SLIP_FRACTION * self.valanis.slip_limit(self.sigma0),
        )
    }
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

    #[test]
    fn element_partials_match_finite_differences() {
        let gl = GaulLenz::new(&GaulLenzParams {
            e0: 1e6,
            k: 0.3,
            et: 1e4,
            sigma0: 2.0,
        })
        .unwrap();
        let w = crate::element::hysteretic::check_partials(
            &gl,
            &[0.5, 1e-7],
            &[1e-6],
            &[2e-6],
            1e-10,
            &[1e-6, 1e-10],
        )
        .unwrap();
        assert!(w < 1e-5, "gaul-lenz: {w}");
    }
}
