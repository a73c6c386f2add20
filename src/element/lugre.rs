//! LuGre friction (Canudas de Wit, Olsson, Åström & Lischinsky 1995, *IEEE Trans. Autom.
//! Control* 40:419): the average deflection `z` of elastic bristles,
//!
//! ```text
//! ż = v − σ0·|v|·z/g(v),     g(v) = Fc + (Fs − Fc)·exp(−(v/vs)²),
//! F = σ0·z + σ1·ż + σ2·v
//! ```
//!
//! with `v` the sliding velocity (m/s), `σ0` the bristle stiffness (N/m), `σ1` the bristle
//! damping (N·s/m), `σ2` the viscous friction (N·s/m), `Fc` the Coulomb and `Fs ≥ Fc` the static
//! (stiction) force (N), `vs` the Stribeck velocity (m/s). In steady sliding `ż = 0`, so
//! `z = sgn(v)·g(v)/σ0` and `F = sgn(v)·g(v) + σ2·v` (the Stribeck curve); at small motion the
//! bristles act as a spring `σ0` (presliding).
//!
//! # Update over one increment
//!
//! With the displacement linear over the increment `Δu = u1 − u0` at the constant velocity
//! `v = Δu/Δt`, the bristle equation is linear in `z` with constant coefficients,
//! `dz/du = 1 − σ0·sgn(Δu)·z/g(v)`, and its exact solution is
//!
//! ```text
//! z1 = z∞ + (z0 − z∞)·exp(−σ0·|Δu|/g(v)),       z∞ = sgn(Δu)·g(v)/σ0
//! ```
//!
//! (the exponential integrator of the implicit family: unconditionally stable, exact at constant
//! velocity for any step, and `|z1| ≤ g/σ0` whenever `|z0| ≤ g/σ0`). The force at the end of the
//! increment takes `ż1` from the bristle equation at `(v, z1)`. The partial derivatives of `z1`
//! and `F1` with respect to `z0`, `u0` and `u1` are exact (their derivation is in
//! [`LuGreParams::step`]).
//!
//! Units: m, m/s, N, N/m, N·s/m.

use crate::core::error::{require_positive, Error, Result};
use crate::element::hysteretic::{ContactStatus, HystereticElement, StepPartials};

/// LuGre parameters (module documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LuGreParams {
    /// Bristle stiffness `σ0` (N/m), > 0.
    pub sigma0: f64,
    /// Bristle damping `σ1` (N·s/m), ≥ 0.
    pub sigma1: f64,
    /// Viscous friction `σ2` (N·s/m), ≥ 0.
    pub sigma2: f64,
    /// Coulomb friction force `Fc` (N), > 0.
    pub coulomb: f64,
    /// Static friction force `Fs` (N), ≥ `Fc`.
    pub stiction: f64,
    /// Stribeck velocity `vs` (m/s), > 0.
    pub stribeck_velocity: f64,
}

/// One increment of the LuGre element: end state, end force and their exact derivatives.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LuGreStep {
    /// Bristle deflection `z1` (m).
    pub z1: f64,
    /// Friction force `F1` (N).
    pub force: f64,
    /// `∂z1/∂z0`.
    pub dz_dz0: f64,
    /// `∂z1/∂Δu` (`= ∂z1/∂u1 = −∂z1/∂u0`).
    pub dz_ddu: f64,
    /// `∂F1/∂z0` (N/m).
    pub df_dz0: f64,
    /// `∂F1/∂Δu` (N/m).
    pub df_ddu: f64,
}

impl LuGreParams {
    /// Validate: `σ0, Fc, vs > 0`, `σ1, σ2 ≥ 0`, `Fs ≥ Fc`, all finite.
    pub fn validate(&self) -> Result<()> {
        require_positive("sigma0", self.sigma0)?;
        require_positive("coulomb", self.coulomb)?;
        require_positive("stribeck_velocity", self.stribeck_velocity)?;
        for (name, v) in [("sigma1", self.sigma1), ("sigma2", self.sigma2)] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::param(
                    name,
                    format!("must be finite and ≥ 0, got {v}"),
                ));
            }
        }
        if !(self.stiction.is_finite() && self.stiction >= self.coulomb) {
            return Err(Error::param(
                "stiction",
                format!(
                    "the static force must be finite and ≥ the Coulomb force {}, got {}",
                    self.coulomb, self.stiction
                ),
            ));
        }
        Ok(())
    }

    /// Stribeck function `g(v)` (N) and its derivative `g'(v)` (N·s/m).
    pub fn stribeck(&self, v: f64) -> (f64, f64) {
        let r = v / self.stribeck_velocity;
        let e = (-r * r).exp();
        let g = self.coulomb + (self.stiction - self.coulomb) * e;
        let dg = (self.stiction - self.coulomb) * e * (-2.0 * r / self.stribeck_velocity);
        (g, dg)
    }

    /// Steady-sliding friction force `sgn(v)·g(v) + σ2·v` (N).
    pub fn steady_sliding_force(&self, v: f64) -> f64 {
        v.signum() * self.stribeck(v).0 + self.sigma2 * v
    }

    /// One increment from deflection `z0` over `Δu` (m) at sample rate `rate = 1/Δt` (1/s).
    ///
    /// With `v = Δu·rate`, `s = sgn(Δu)`, `a = σ0·|Δu|/g(v)`, `E = e^{−a}`:
    /// `∂z1/∂z0 = E`, `∂z1/∂Δu = (1 − E)·∂z∞/∂Δu − (z0 − z∞)·E·∂a/∂Δu` with
    /// `∂z∞/∂Δu = s·g'·rate/σ0` and `∂a/∂Δu = σ0·s/g − σ0·|Δu|·g'·rate/g²`; and with
    /// `ż1 = v − σ0·|v|·z1/g`, `∂ż1/∂z1 = −σ0·|v|/g`,
    /// `∂ż1/∂v|_z1 = 1 − σ0·s·z1/g + σ0·|v|·z1·g'/g²`:
    /// `∂F1/∂z0 = (σ0 + σ1·∂ż1/∂z1)·E` and
    /// `∂F1/∂Δu = (σ0 + σ1·∂ż1/∂z1)·∂z1/∂Δu + (σ1·∂ż1/∂v + σ2)·rate`.
    pub fn step(&self, z0: f64, du: f64, rate: f64) -> LuGreStep {
        let v = du * rate;
        let (g, dg) = self.stribeck(v);
        let s = if du > 0.0 {
            1.0
        } else if du < 0.0 {
            -1.0
        } else {
            0.0
        };
        let a = self.sigma0 * du.abs() / g;
        let e = (-a).exp();
        let z_inf = s * g / self.sigma0;
        let z1 = z_inf + (z0 - z_inf) * e;
        let dzinf = s * dg * rate / self.sigma0;
        let da = self.sigma0 * s / g - self.sigma0 * du.abs() * dg * rate / (g * g);
        let dz_ddu = (1.0 - e) * dzinf - (z0 - z_inf) * e * da;
        let zdot = v - self.sigma0 * v.abs() * z1 / g;
        let dzdot_dz1 = -self.sigma0 * v.abs() / g;
        let dzdot_dv = 1.0 - self.sigma0 * s * z1 / g + self.sigma0 * v.abs() * z1 * dg / (g * g);
        let stiff = self.sigma0 + self.sigma1 * dzdot_dz1;
        LuGreStep {
            z1,
            force: self.sigma0 * z1 + self.sigma1 * zdot + self.sigma2 * v,
            dz_dz0: e,
            dz_ddu,
            df_dz0: stiff * e,
            df_ddu: stiff * dz_ddu + (self.sigma1 * dzdot_dv + self.sigma2) * rate,
        }
    }
}

/// LuGre friction on one displacement component at a fixed sample rate as a
/// [`HystereticElement`] (state: the bristle deflection `z`): the velocity of an increment is
/// `(u1 − u0)·sample_rate` (`ω·N/2π` in the AFT, `1/Δt` in a time integration), so the element
/// is rate-dependent and is stepped from sample to sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LuGre {
    /// The law's parameters.
    pub params: LuGreParams,
    /// Samples per second (1/s).
    pub sample_rate: f64,
}

impl HystereticElement for LuGre {
    fn name(&self) -> &'static str {
        "lugre"
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
        scales[0] = self.params.stiction / self.params.sigma0;
    }
    fn force_scale(&self) -> f64 {
        self.params.stiction
    }
    fn rate_dependent(&self) -> bool {
        true
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
        let r = self.params.step(s0[0], u1[0] - u0[0], self.sample_rate);
        s1[0] = r.z1;
        f1[0] = r.force;
        if let Some(p) = partials {
            p.ds_ds0[0] = r.dz_dz0;
            p.ds_du1[0] = r.dz_ddu;
            p.ds_du0[0] = -r.dz_ddu;
            p.df_ds0[0] = r.df_dz0;
            p.df_du1[0] = r.df_ddu;
            p.df_du0[0] = -r.df_ddu;
        }
    }
    fn status(&self, s: &[f64], _u: &[f64], _f: &[f64]) -> ContactStatus {
        // Sliding once the bristles carry 99 % of the Coulomb force.
        ContactStatus::classify(
            1.0,
            (self.params.sigma0 * s[0]).abs(),
            0.99 * self.params.coulomb,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::hysteretic::check_partials;

    fn params() -> LuGreParams {
        LuGreParams {
            sigma0: 1e5,
            sigma1: 300.0,
            sigma2: 0.4,
            coulomb: 1.0,
            stiction: 1.5,
            stribeck_velocity: 0.01,
        }
    }

    #[test]
    fn partials_match_finite_differences() {
        let el = LuGre {
            params: params(),
            sample_rate: 2000.0,
        };
        // Presliding, Stribeck range and sliding, both directions, bristles loaded either way.
        for (z0, u0, u1) in [
            (2e-6, 0.0, 1e-6),
            (-5e-6, 1e-5, 3e-6),
            (1.2e-5, 0.0, 2e-5),
            (-1.4e-5, 0.0, -8e-5),
        ] {
            let w = check_partials(&el, &[z0], &[u0], &[u1], 1e-11, &[1e-11]).unwrap();
            assert!(w < 1e-6, "{z0}, {u0} → {u1}: {w}");
        }
    }

    #[test]
    fn parameters_are_validated() {
        assert!(params().validate().is_ok());
        for bad in [
            LuGreParams {
                sigma0: 0.0,
                ..params()
            },
            LuGreParams {
                stiction: 0.5,
                ..params()
            },
            LuGreParams {
                sigma1: -1.0,
                ..params()
            },
            LuGreParams {
                stribeck_velocity: 0.0,
                ..params()
            },
        ] {
            assert!(bad.validate().is_err());
        }
    }
}
