//! Quadratic spring `F = k2·|q|·q`: an odd restoring force whose stiffness changes in proportion
//! to the amplitude (a hardening spring for `k2 > 0`, softening for `k2 < 0`). It is the lowest
//! odd power-law term of a stiffness that varies smoothly with amplitude: under `q = a·cos θ` its
//! first harmonic is `(8/3π)·k2·a·q` (describing function, Gelb & Vander Velde, *Multiple-Input
//! Describing Functions and Nonlinear System Design*, 1968, §2.5: for `|q|^n·q` the equivalent
//! gain is `a^n·I(n+2)/π` with `I(m) = ∫₀^{2π}|cos θ|^m dθ`, here `I(3) = 8/3`), where the cubic
//! spring's is `¾·k3·a²`. Units: `q` in m, `F` in N, `k2` in N/m².

use crate::element::hysteretic::MemorylessSpring;
use std::f64::consts::PI;

/// Force of the quadratic spring.
pub fn force(k2: f64, q: f64) -> f64 {
    k2 * q.abs() * q
}

/// Tangent stiffness `dF/dq = 2·k2·|q|`.
pub fn stiffness(k2: f64, q: f64) -> f64 {
    2.0 * k2 * q.abs()
}

/// Quadratic spring `f = k2·|u|·u` on one displacement component (stiffness changing in
/// proportion to the amplitude), no memory.
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
        (force(self.k2, u), stiffness(self.k2, u))
    }
    fn scale(&self) -> f64 {
        self.k2.abs()
    }
}

/// Equivalent (describing-function) stiffness `8·k2·a/(3π)` (N/m) under `q = a·cos θ`.
pub fn equivalent_stiffness(k2: f64, a: f64) -> f64 {
    8.0 * k2 * a / (3.0 * PI)
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI;

    #[test]
    fn tangent_is_the_derivative() {
        for q in [1.3e-3, -0.7e-3] {
            let (k2, h) = (-4.0e8, 1e-9);
            let fd = (super::force(k2, q + h) - super::force(k2, q - h)) / (2.0 * h);
            assert!((fd - super::stiffness(k2, q)).abs() < 1e-6 * fd.abs());
        }
    }

    /// The first Fourier coefficient of `F(a·cos θ)`, by the midpoint rule on 4096 samples
    /// (exact to ~1e-7 for this piecewise-smooth integrand), equals the closed form.
    #[test]
    fn describing_function_is_the_first_harmonic() {
        let (k2, a, n) = (3.0e8, 2.0e-4, 4096);
        let a1: f64 = (0..n)
            .map(|i| {
                let th = 2.0 * PI * (i as f64 + 0.5) / n as f64;
                super::force(k2, a * th.cos()) * th.cos()
            })
            .sum::<f64>()
            * 2.0
            / n as f64;
        let closed = super::equivalent_stiffness(k2, a) * a;
        assert!((a1 - closed).abs() < 1e-6 * closed, "{a1} vs {closed}");
    }
}
