//! Power-law damper `f = c·|u̇|^p·u̇` at a fixed excitation frequency (`p = 1`: the
//! velocity-squared damper of air drag; `p → 0` the linear viscous damper), with its
//! equivalent viscous coefficient under harmonic motion. Units: `u` in m, `f` in N, `c` in
//! N·(s/m)^{p+1}, `p` dimensionless.

use crate::element::hysteretic::{ContactStatus, HystereticElement, StepPartials};
use std::f64::consts::PI;

/// `I(n) = ∫₀^{2π} |sin θ|ⁿ dθ = 2√π·Γ((n+1)/2)/Γ(n/2+1)` (Gradshteyn & Ryzhik 3.621.5), the
/// cycle integral of the power-law damper's dissipation: `W = c·(aω)^{p+2}·I(p+2)/ω` under
/// `u = a·cos ωt`. `I(2) = π`, `I(3) = 8/3`.
pub fn sine_power_cycle_integral(n: f64) -> f64 {
    use statrs::function::gamma::gamma;
    2.0 * PI.sqrt() * gamma(0.5 * (n + 1.0)) / gamma(0.5 * n + 1.0)
}

/// A power-law damper `f = c·|u̇|^p·u̇` at a fixed excitation frequency, as a
/// [`HystereticElement`] (`p = 1`: the velocity-squared damper of air drag): the velocity is the
/// backward difference of the displacement samples, `u̇ ≈ (u1 − u0)·ω·N/2π` (a lag of half a
/// sample, `π/N` rad of the fundamental, e.g. 0.05 rad at `N = 64`, which turns 0.1 % of the
/// damping force into stiffness). Built for one frequency (an identification's), it is to the
/// solvers a memoryless function of the increment's end points, not a law that reads the
/// kinematics ([`HystereticElement::rate_dependent`] is false).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PowerLawDamper {
    /// `c` (N·(s/m)^{p+1}).
    pub c: f64,
    /// `p` (–).
    pub exponent: f64,
    /// `ω·N/2π`: samples per second.
    pub sample_rate: f64,
}

impl PowerLawDamper {
    /// Equivalent viscous coefficient `c_eq = c·(aω)^p·I(p+2)/π` (N·s/m) under `u = a·cos ωt`:
    /// the viscous damper dissipating the same energy per cycle, `π·c_eq·ω·a²`.
    pub fn equivalent_viscous(c: f64, exponent: f64, a: f64, omega: f64) -> f64 {
        c * (a * omega).powf(exponent) * sine_power_cycle_integral(exponent + 2.0) / PI
    }
}

impl HystereticElement for PowerLawDamper {
    fn name(&self) -> &'static str {
        "power-law-damper"
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
        self.c.abs()
    }
    fn step(
        &self,
        _s0: &[f64],
        u0: &[f64],
        u1: &[f64],
        _s1: &mut [f64],
        f1: &mut [f64],
        partials: Option<&mut StepPartials>,
    ) {
        let v = (u1[0] - u0[0]) * self.sample_rate;
        let vp = v.abs().powf(self.exponent);
        f1[0] = self.c * vp * v;
        if let Some(p) = partials {
            let d = (self.exponent + 1.0) * self.c * vp * self.sample_rate;
            p.df_du1[0] = d;
            p.df_du0[0] = -d;
        }
    }
    fn status(&self, _s: &[f64], _u: &[f64], _f: &[f64]) -> ContactStatus {
        ContactStatus::Stick
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::hysteretic::check_partials;
    use std::f64::consts::TAU;

    #[test]
    fn power_law_damper_partials_match_finite_differences() {
        for exponent in [0.25, 1.0, 1.6, 3.0] {
            let q = PowerLawDamper {
                c: 3.0,
                exponent,
                sample_rate: 5000.0,
            };
            let w = check_partials(&q, &[], &[1e-4], &[1.3e-4], 1e-10, &[]).unwrap();
            assert!(w < 1e-6, "p = {exponent}: {w}");
        }
    }

    /// `I(n)` against the closed forms `I(2) = π`, `I(3) = 8/3`, `I(4) = 3π/4`, `I(5) = 32/15`
    /// (Wallis) and a midpoint quadrature at a non-integer order.
    #[test]
    fn sine_power_cycle_integral_matches_wallis() {
        for (n, exact) in [
            (2.0, PI),
            (3.0, 8.0 / 3.0),
            (4.0, 0.75 * PI),
            (5.0, 32.0 / 15.0),
        ] {
            let i = sine_power_cycle_integral(n);
            assert!(
                (i - exact).abs() < 1e-12 * exact,
                "I({n}) = {i}, not {exact}"
            );
        }
        let m = 200_000;
        let quad: f64 = (0..m)
            .map(|k| (TAU * (k as f64 + 0.5) / m as f64).sin().abs().powf(3.6))
            .sum::<f64>()
            * TAU
            / m as f64;
        let i = sine_power_cycle_integral(3.6);
        assert!((i - quad).abs() < 1e-9 * quad, "{i} vs {quad}");
    }
}
