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
//! velocity for any step, and `|z1| ≤ g/σ0` whenever `|z0| ≤ g/σ0`). Where the velocity varies
//! over the increment, taking its mean `v̄ = Δu/Δt` is the exponential midpoint rule, second
//! order in `Δt`. The force at the end of the increment takes `ż1` from the bristle equation
//! at `(v1, z1)`, with `v1` the velocity at the end of the increment when the caller knows it
//! exactly (the harmonics of the AFT, the integrator's velocity; [`LuGreParams::increment`]),
//! or the mean velocity ([`LuGreParams::step`]). The partial derivatives of `z1` and `F1` with
//! respect to `z0`, `u0`, `u1`, `Δt` and `v1` are exact (their derivation is in
//! [`LuGreParams::increment`]).
//!
//! Units: m, m/s, N, N/m, N·s/m.

use crate::core::error::{require_positive, Error, Result};
use crate::element::hysteretic::{
    ContactStatus, HystereticElement, Kinematics, RatePartials, StepPartials,
};

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

    /// One increment from deflection `z0` over `Δu` (m) at the constant velocity
    /// `v = Δu·rate` (`rate = 1/Δt`, 1/s), the force taken at that velocity: [`Self::increment`]
    /// with `v1 = v`, its derivatives with respect to `Δu` at fixed `Δt` (`∂/∂Δu + rate·∂/∂v1`).
    pub fn step(&self, z0: f64, du: f64, rate: f64) -> LuGreStep {
        let r = self.increment(z0, du, 1.0 / rate, du * rate);
        LuGreStep {
            z1: r.z1,
            force: r.force,
            dz_dz0: r.dz_dz0,
            dz_ddu: r.dz_ddu,
            df_dz0: r.df_dz0,
            df_ddu: r.df_ddu + r.df_dv1 * rate,
        }
    }

    /// One increment from deflection `z0` over `Δu` (m) in `Δt` (s), the force at the end
    /// velocity `v1` (m/s): the bristles follow the exact solution at the increment's mean
    /// velocity `v̄ = Δu/Δt` (module documentation), the force is `σ0·z1 + σ1·ż1 + σ2·v1` with
    /// `ż1 = v1 − σ0·|v1|·z1/g(v1)` from the bristle equation at the end of the increment. `Δt =
    /// ∞` is the quasi-static limit (`v̄ = 0`).
    ///
    /// With `s = sgn(Δu)`, `a = σ0·|Δu|/g(v̄)`, `E = e^{−a}`, `z∞ = s·g(v̄)/σ0`:
    /// `∂z1/∂z0 = E`, `∂z1/∂Δu|_v̄ = −(z0 − z∞)·E·σ0·s/g`,
    /// `∂z1/∂v̄ = (1 − E)·s·g'/σ0 + (z0 − z∞)·E·σ0·|Δu|·g'/g²`, and through `v̄ = Δu/Δt`:
    /// `∂z1/∂Δu = ∂z1/∂Δu|_v̄ + ∂z1/∂v̄/Δt`, `∂z1/∂Δt = −∂z1/∂v̄·v̄/Δt`. The force:
    /// `∂F1/∂z1 = σ0 − σ1·σ0·|v1|/g(v1)` times each of those, and
    /// `∂F1/∂v1 = σ1·(1 − σ0·sgn(v1)·z1/g + σ0·|v1|·z1·g'/g²) + σ2` (at `v1`).
    pub fn increment(&self, z0: f64, du: f64, dt: f64, v1: f64) -> LuGreIncrement {
        let vbar = if dt.is_finite() { du / dt } else { 0.0 };
        let (g, dg) = self.stribeck(vbar);
        let s = sign(du);
        let a = self.sigma0 * du.abs() / g;
        let e = (-a).exp();
        let z_inf = s * g / self.sigma0;
        // z1 = z∞ + (z0 − z∞)·e^{−a}, written as a change of z0 through `expm1`: in presliding
        // (a ≪ 1) the other form loses the increment to the rounding of z∞ = ±g/σ0.
        let z1 = z0 - (z_inf - z0) * (-a).exp_m1();
        // At Δu = 0 the update is continuous with one-sided slopes `1 ∓ σ0·z0/g`; the
        // derivatives take the forward one (at rest the bristles load like a spring σ0, the
        // harmonic balance's start from zero needs that tangent).
        let sd = if du < 0.0 { -1.0 } else { 1.0 };
        let dz_ddu_at_v = -(z0 - sd * g / self.sigma0) * e * self.sigma0 * sd / g;
        let dz_dvbar = (1.0 - e) * s * dg / self.sigma0
            + (z0 - z_inf) * e * self.sigma0 * du.abs() * dg / (g * g);
        let (dz_ddu, dz_ddt) = if dt.is_finite() {
            (dz_ddu_at_v + dz_dvbar / dt, -dz_dvbar * vbar / dt)
        } else {
            (dz_ddu_at_v, 0.0)
        };
        let (g1, dg1) = self.stribeck(v1);
        let zdot = v1 - self.sigma0 * v1.abs() * z1 / g1;
        let stiff = self.sigma0 - self.sigma1 * self.sigma0 * v1.abs() / g1;
        let dzdot_dv1 =
            1.0 - self.sigma0 * sign(v1) * z1 / g1 + self.sigma0 * v1.abs() * z1 * dg1 / (g1 * g1);
        LuGreIncrement {
            z1,
            force: self.sigma0 * z1 + self.sigma1 * zdot + self.sigma2 * v1,
            dz_dz0: e,
            dz_ddu,
            dz_ddt,
            df_dz0: stiff * e,
            df_ddu: stiff * dz_ddu,
            df_ddt: stiff * dz_ddt,
            df_dv1: self.sigma1 * dzdot_dv1 + self.sigma2,
        }
    }
}

/// `sgn(x)`, zero at zero.
fn sign(x: f64) -> f64 {
    if x > 0.0 {
        1.0
    } else if x < 0.0 {
        -1.0
    } else {
        0.0
    }
}

/// One increment of the LuGre element over a duration with the end velocity given
/// ([`LuGreParams::increment`]): end state, end force and their exact derivatives.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LuGreIncrement {
    /// Bristle deflection `z1` (m).
    pub z1: f64,
    /// Friction force `F1` (N).
    pub force: f64,
    /// `∂z1/∂z0`.
    pub dz_dz0: f64,
    /// `∂z1/∂Δu` at fixed `Δt` (`= ∂z1/∂u1 = −∂z1/∂u0`).
    pub dz_ddu: f64,
    /// `∂z1/∂Δt` (m/s).
    pub dz_ddt: f64,
    /// `∂F1/∂z0` (N/m).
    pub df_dz0: f64,
    /// `∂F1/∂Δu` at fixed `Δt` and `v1` (N/m).
    pub df_ddu: f64,
    /// `∂F1/∂Δt` (N/s).
    pub df_ddt: f64,
    /// `∂F1/∂v1` (N·s/m).
    pub df_dv1: f64,
}

/// LuGre friction on one displacement component as a rate-dependent [`HystereticElement`]
/// (state: the bristle deflection `z`): an increment of duration `Δt` integrates the bristles
/// exactly at its mean velocity `(u1 − u0)/Δt` and takes the force at its end velocity
/// ([`LuGreParams::increment`]); the AFT gives it `Δt = 2π/(ω·N)` and the velocities of the
/// harmonics, a time integration its step and velocities. Its plain `step` is the quasi-static
/// limit (`Δt = ∞`, zero velocity: a Dahl-like presliding law with the static force `Fs`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LuGre {
    /// The law's parameters.
    pub params: LuGreParams,
}

impl LuGre {
    fn write(r: &LuGreIncrement, s1: &mut [f64], f1: &mut [f64], p: Option<&mut StepPartials>) {
        s1[0] = r.z1;
        f1[0] = r.force;
        if let Some(p) = p {
            p.ds_ds0[0] = r.dz_dz0;
            p.ds_du1[0] = r.dz_ddu;
            p.ds_du0[0] = -r.dz_ddu;
            p.df_ds0[0] = r.df_dz0;
            p.df_du1[0] = r.df_ddu;
            p.df_du0[0] = -r.df_ddu;
        }
    }
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
        let r = self
            .params
            .increment(s0[0], u1[0] - u0[0], f64::INFINITY, 0.0);
        Self::write(&r, s1, f1, partials);
    }
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
        let r = self
            .params
            .increment(s0[0], u1[0] - u0[0], kin.dt, kin.v1[0]);
        match partials {
            Some((p, rp)) => {
                Self::write(&r, s1, f1, Some(p));
                rp.ds_ddt[0] = r.dz_ddt;
                rp.df_ddt[0] = r.df_ddt;
                rp.df_dv1[0] = r.df_dv1;
            }
            None => Self::write(&r, s1, f1, None),
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
    use crate::element::hysteretic::{check_partials, check_rate_partials};

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
        let el = LuGre { params: params() };
        let dt = 1.0 / 2000.0;
        // Presliding, Stribeck range and sliding, both directions, bristles loaded either way,
        // end velocities of either sign.
        for (z0, u0, u1, v1) in [
            (2e-6, 0.0, 1e-6, 1.5e-3),
            (-5e-6, 1e-5, 3e-6, -0.02),
            (1.2e-5, 0.0, 2e-5, 0.05),
            (-1.4e-5, 0.0, -8e-5, -0.1),
            (3e-6, 2e-6, 4e-6, -0.004),
        ] {
            let kin = Kinematics {
                dt,
                v0: &[0.0],
                v1: &[v1],
            };
            let w =
                check_rate_partials(&el, &[z0], &[u0], &[u1], kin, (1e-11, 1e-6, 1e-8), &[1e-11])
                    .unwrap();
            // The Δt column goes through the Stribeck decay exp(−(v̄/vs)²) far out in its
            // tail: central differences resolve it to about 1e-6 of the column.
            assert!(w < 1e-5, "{z0}, {u0} → {u1} at {v1}: {w}");
            // The quasi-static step.
            let w = check_partials(&el, &[z0], &[u0], &[u1], 1e-11, &[1e-11]).unwrap();
            assert!(w < 1e-6, "quasi-static {z0}, {u0} → {u1}: {w}");
        }
    }

    /// At constant velocity the increment is the exact solution of the bristle equation for
    /// any `Δt`: one increment over `Δt` equals ten over `Δt/10` (to rounding), and the
    /// quasi-static step is the limit of long increments.
    #[test]
    fn increments_at_constant_velocity_compose_exactly() {
        let p = params();
        for v in [-0.03, 2e-3, 0.2] {
            let dt = 1e-3;
            let one = p.increment(1e-6, v * dt, dt, v);
            let mut z = 1e-6;
            let mut f = 0.0;
            for _ in 0..10 {
                let r = p.increment(z, v * dt / 10.0, dt / 10.0, v);
                z = r.z1;
                f = r.force;
            }
            assert!((one.z1 - z).abs() < 1e-15, "{v}: {} vs {z}", one.z1);
            assert!(
                (one.force - f).abs() < 1e-9 * f.abs(),
                "{v}: {} vs {f}",
                one.force
            );
        }
        let qs = p.increment(1e-6, 3e-6, f64::INFINITY, 0.0);
        let slow = p.increment(1e-6, 3e-6, 1e9, 0.0);
        assert!((qs.z1 - slow.z1).abs() < 1e-15 && (qs.force - slow.force).abs() < 1e-9);
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
