//! Constitutive laws of contact elements and joints, one file each, and the interface through
//! which every solver drives them.
//!
//! | file | law | implements [`HystereticElement`] as |
//! |---|---|---|
//! | [`hysteretic`] | the interface: state, step with exact partial derivatives, status, the kinematics of rate-dependent laws; [`check_partials`], [`check_rate_partials`] | – |
//! | [`valanis`] | Valanis microslip, time-varying normal load (implicit Euler, frozen-load, reference integrators) | (through [`gaul_lenz`] and [`contact3d`]) |
//! | [`gaul_lenz`] | Valanis with a constant stick limit `σ0` | [`GaulLenz`] |
//! | [`jenkins`] | spring + Coulomb slider (1-D, and 2-D with a circular limit) | [`Jenkins`] |
//! | [`iwan`] | Segalman's four-parameter Iwan element, parallel Jenkins sliders | [`IwanElement`] |
//! | [`bilinear`] | bilinear normal contact: stiffness `k1` then `k2` beyond an indentation, gap, separation | [`BilinearContact`] (memoryless; separated status where open) |
//! | [`bouc_wen`] | Bouc–Wen | [`BoucWen`] |
//! | [`cubic`] | cubic (Duffing) spring | [`CubicSpring`] (memoryless) |
//! | [`quadratic_spring`] | quadratic spring `k2·|q|·q` | [`QuadraticSpring`] (memoryless) |
//! | [`hunt_crossley`] | Hunt–Crossley normal contact `k·δⁿ·(1 + χ·δ̇)` with gap, separation and impact; exact `χ(e, v_in)` | [`HuntCrossley`] |
//! | [`lugre`] | LuGre friction (bristle state, Stribeck curve), exact exponential update at the increment's velocity | [`LuGre`] |
//! | [`power_law_damper`] | power-law damper `c·|u̇|^p·u̇` | [`PowerLawDamper`] |
//! | [`contact3d`] | 3-D contact elements: Valanis or Jenkins friction behind a unilateral normal spring; the Valanis element with kn(N), E0(N) | [`MicroslipContact`], [`JenkinsContact`], [`LoadFollowingContact`] |
//! | [`thin_layer`] | thin-layer interface: elastic–plastic virtual material (Ee, Ep, Sy, smooth transition n; Menegotto–Pinto) | [`ThinLayer`] |
//! | [`unilateral`] | unilateral normal contact `N = max(0, N0 + kn·un)`, re-contact point | – |
//! | [`params`] | the contact-element record `(kn, E0, k, μ, Et)` per area and per element | – |
//!
//! Each law is a parameters struct, a pure update for one displacement increment, a loop
//! integrator mapping a displacement history (and a normal-load history) to a force history, and
//! its [`HystereticElement`] implementation. A new law is one more file here.
//! Units: either per unit nominal area (displacement m, force Pa, stiffness N/m³) or per element
//! (m, N, N/m) — the mathematics is the same; see [`valanis`]. The solvers use per-element units.

pub mod bilinear;
pub mod bouc_wen;
pub mod contact3d;
pub mod cubic;
pub mod gaul_lenz;
pub mod hunt_crossley;
pub mod hysteretic;
pub mod iwan;
pub mod jenkins;
pub mod lugre;
pub mod params;
pub mod power_law_damper;
pub mod quadratic_spring;
pub mod thin_layer;
pub mod unilateral;
pub mod valanis;

pub use bilinear::BilinearContact;
pub use bouc_wen::{BoucWen, BoucWenParams};
pub use contact3d::{JenkinsContact, LoadFollowingContact, MicroslipContact};
pub use cubic::CubicSpring;
pub use gaul_lenz::{GaulLenz, GaulLenzParams};
pub use hunt_crossley::{HuntCrossley, HuntCrossleyParams};
pub use hysteretic::{
    check_partials, check_rate_partials, ContactStatus, HystereticElement, Kinematics,
    MemorylessSpring, RatePartials, StepPartials,
};
pub use iwan::{IwanElement, IwanParams};
pub use jenkins::{Jenkins, JenkinsParams};
pub use lugre::{LuGre, LuGreParams};
pub use params::{ContactParams, ContactParamsPerArea};
pub use power_law_damper::PowerLawDamper;
pub use quadratic_spring::QuadraticSpring;
pub use thin_layer::ThinLayer;
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
