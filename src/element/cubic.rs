//! Cubic (Duffing) spring `F = k3·q³`: the memoryless hardening nonlinearity used to validate
//! harmonic-balance solvers against the Duffing oscillator's closed-form first-harmonic response
//! (e.g. Nayfeh & Mook, *Nonlinear Oscillations*, 1979, §4.1). Units: `q` in m, `F` in N,
//! `k3` in N/m³ (or per unit area: Pa and N/m⁵).

use crate::element::hysteretic::MemorylessSpring;

/// Force of the cubic spring.
pub fn force(k3: f64, q: f64) -> f64 {
    k3 * q * q * q
}

/// Tangent stiffness `dF/dq = 3·k3·q²`.
pub fn stiffness(k3: f64, q: f64) -> f64 {
    3.0 * k3 * q * q
}

/// Cubic spring `f = k3·u³` on one displacement component (the Duffing nonlinearity), no memory.
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
        (force(self.k3, u), stiffness(self.k3, u))
    }
    fn scale(&self) -> f64 {
        self.k3.abs()
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn tangent_is_the_derivative() {
        let (k3, q, h) = (2.5e9, 1.3e-3, 1e-9);
        let fd = (super::force(k3, q + h) - super::force(k3, q - h)) / (2.0 * h);
        assert!((fd - super::stiffness(k3, q)).abs() < 1e-6 * fd);
    }
}
