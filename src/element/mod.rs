//! Contact elements for nonlinear dynamic solvers: Valanis microslip, Gaul–Lenz, Jenkins (1-D and
//! 2-D with a circular slip limit), Iwan (power-law slip-strength density), Bouc–Wen, the
//! cubic spring used to validate solvers and the quadratic spring of amplitude-proportional stiffness.
//!
//! Each element is a parameters struct, a pure force update for one displacement increment and a
//! loop integrator mapping a displacement history (and a normal-load history) to a force history.
//! Units: either per unit nominal area (displacement m, force Pa, stiffness N/m³) or per element
//! (m, N, N/m) — the mathematics is the same; see [`valanis`].

pub mod bouc_wen;
pub mod cubic;
pub mod gaul_lenz;
pub mod iwan;
pub mod jenkins;
pub mod quadratic_spring;
pub mod valanis;

pub use bouc_wen::BoucWenParams;
pub use gaul_lenz::GaulLenzParams;
pub use iwan::{IwanElement, IwanParams};
pub use jenkins::JenkinsParams;
pub use valanis::{Integrator, ValanisParams, ValanisState};

/// Energy dissipated over a closed cycle, `W = ∮ F dq` (trapezoidal rule over consecutive
/// samples, J/m² per area or J per element). Positive for a friction loop traversed clockwise in
/// the (q, F) plane, which is how friction loops are traversed. Pass exactly one period (first
/// and last sample at the same point of the cycle).
pub fn dissipated_energy(q: &[f64], f: &[f64]) -> f64 {
    q.windows(2)
        .zip(f.windows(2))
        .map(|(qw, fw)| 0.5 * (fw[0] + fw[1]) * (qw[1] - qw[0]))
        .sum()
}

/// Sinusoidal displacement history `q_i = amplitude·sin(2π·i/points_per_cycle)` over `cycles`
/// periods: `cycles·points_per_cycle + 1` samples, starting at 0 (virgin element) and ending at 0.
pub fn sine_history(amplitude: f64, cycles: usize, points_per_cycle: usize) -> Vec<f64> {
    let n = cycles * points_per_cycle;
    (0..=n)
        .map(|i| {
            amplitude * (2.0 * std::f64::consts::PI * i as f64 / points_per_cycle as f64).sin()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn energy_of_a_jenkins_rectangle_loop() {
        // Rigid-plastic loop: F = +Fs on the way up, −Fs on the way down: W = 4·A·Fs.
        let q = [0.0, 1.0, 0.0, -1.0, 0.0];
        let f = [1.0, 1.0, -1.0, -1.0, 1.0];
        // Trapezoid on the sign changes averages; use a rectangle with vertical edges instead.
        let q2 = [-1.0, -1.0, 1.0, 1.0, -1.0];
        let f2 = [-1.0, 1.0, 1.0, -1.0, -1.0];
        assert!((dissipated_energy(&q2, &f2) - 4.0).abs() < 1e-12);
        assert!(dissipated_energy(&q, &f).is_finite());
    }

    #[test]
    fn sine_history_has_expected_length_and_ends() {
        let q = sine_history(2.0, 3, 8);
        assert_eq!(q.len(), 25);
        assert_eq!(q[0], 0.0);
        assert!((q[2] - 2.0).abs() < 1e-12);
        assert!(q[24].abs() < 1e-12);
    }
}
