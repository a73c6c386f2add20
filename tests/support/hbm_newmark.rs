//! The harmonic balance against Newmark time integration of the same equations, shared by the
//! element-law tests (`tests/joint_laws.rs`, `tests/load_following.rs`).

#![allow(dead_code)]

use asperity::dynamics::aft::Harmonics;
use asperity::dynamics::hbm::HbmSystem;
use asperity::dynamics::time_integration::{
    initial_conditions, steady_state, TimeIntegrationSettings,
};
use nalgebra::DVector;

/// The HBM point at `level` reached by a ramp in six steps from the linear regime, and the
/// Newmark steady state (`steps_per_period`) started from it: `(coordinates, HBM first-
/// harmonic amplitude of the first coordinate, Newmark's)`. `what` names the case in failures.
pub fn ramped_hbm_against_newmark(
    sys: &HbmSystem<'_>,
    w: f64,
    level: f64,
    what: &str,
    steps_per_period: usize,
) -> (DVector<f64>, f64, f64) {
    let mut guess: Option<DVector<f64>> = None;
    let mut p = None;
    for i in 1..=6 {
        let q = sys
            .solve(w, level * i as f64 / 6.0, guess.as_ref())
            .unwrap();
        assert!(q.converged, "{what}: HBM did not converge");
        guess = Some(q.z.clone());
        p = Some(q);
    }
    let p = p.unwrap();
    let x = sys.coordinates(&p);
    let n = sys.structure.n();
    let (q0, v0) = initial_conditions(&x, &sys.harmonics, n, p.omega);
    let ti = steady_state(
        sys.structure,
        &sys.excitation.force,
        1,
        p.level,
        p.omega,
        &sys.harmonics,
        &q0,
        &v0,
        &TimeIntegrationSettings {
            steps_per_period,
            max_periods: 400,
            tolerance: 1e-9,
        },
    )
    .unwrap();
    assert!(
        ti.converged,
        "{what}: Newmark not steady: {:.1e}",
        ti.change
    );
    let (a_hbm, a_ti) = (
        amplitude(&x, &sys.harmonics),
        amplitude(&ti.harmonics, &sys.harmonics),
    );
    (x, a_hbm, a_ti)
}

/// First-harmonic amplitude of the first coordinate (coordinates stored coordinate by
/// coordinate, each with its harmonics).
pub fn amplitude(x: &DVector<f64>, h: &Harmonics) -> f64 {
    let (ci, si) = h.index_of(1).unwrap();
    x[ci].hypot(x[si])
}
