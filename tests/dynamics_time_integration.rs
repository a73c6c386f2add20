//! Harmonic balance against time integration of the same equations to the periodic steady state
//! (Newmark average acceleration, the same time-discrete element updates): Duffing within 0.5 %,
//! Jenkins, Valanis and a two-mass resonator with a Valanis (Gaul–Lenz) joint within 1 %.

use asperity::dynamics::aft::Harmonics;
use asperity::dynamics::continuation::{sweep, Branch, ContinuationSettings};
use asperity::dynamics::hbm::{Excitation, FormulationChoice, HbmPoint, HbmSystem};
use asperity::dynamics::model::Structure;
use asperity::dynamics::time_integration::{
    initial_conditions, steady_state, TimeIntegrationSettings,
};
use asperity::element::{CubicSpring, GaulLenz, Jenkins, MicroslipContact};
use asperity::element::{GaulLenzParams, ValanisParams};
use nalgebra::{DMatrix, DVector};
use std::f64::consts::PI;
use std::sync::Arc;

fn sdof(m: f64, c: f64, k: f64) -> Structure {
    Structure::lumped(
        vec!["x".into()],
        DMatrix::from_element(1, 1, m),
        DMatrix::from_element(1, 1, c),
        DMatrix::from_element(1, 1, k),
    )
    .unwrap()
}

/// First-harmonic amplitude of every coordinate.
fn first_harmonic(x: &DVector<f64>, h: &Harmonics, n: usize) -> Vec<f64> {
    let (ci, si) = h.index_of(1).unwrap();
    let len = h.len();
    (0..n)
        .map(|r| x[r * len + ci].hypot(x[r * len + si]))
        .collect()
}

/// Time-integrate from the HBM solution at `p` and return the largest relative deviation of the
/// first-harmonic amplitudes, and of every harmonic relative to the first.
fn compare(sys: &HbmSystem<'_>, p: &HbmPoint, periods: usize) -> (f64, f64) {
    let s = sys.structure;
    let n = s.n();
    let x = sys.coordinates(p);
    let (q0, v0) = initial_conditions(&x, &sys.harmonics, n, p.omega);
    let settings = TimeIntegrationSettings {
        steps_per_period: 1024,
        max_periods: periods,
        tolerance: 1e-7,
    };
    let ti = steady_state(
        s,
        &sys.excitation.force,
        1,
        p.level,
        p.omega,
        &sys.harmonics,
        &q0,
        &v0,
        &settings,
    )
    .unwrap();
    eprintln!(
        "TI: {} periods, {:.2} s, change {:.1e}",
        ti.periods, ti.wall_time_s, ti.change
    );
    assert!(
        ti.converged,
        "time integration not steady: change {:.2e} after {} periods",
        ti.change, ti.periods
    );
    let a_hbm = first_harmonic(&x, &sys.harmonics, n);
    let a_ti = first_harmonic(&ti.harmonics, &sys.harmonics, n);
    let first = a_hbm
        .iter()
        .zip(&a_ti)
        .map(|(a, b)| (a - b).abs() / b)
        .fold(0.0, f64::max);
    let scale = a_ti.iter().fold(0.0f64, |m, v| m.max(*v));
    let all = (&x - &ti.harmonics).amax() / scale;
    eprintln!(
        "  {:.3} Hz: first harmonic {first:.2e}, every harmonic {all:.2e}",
        p.omega / (2.0 * PI)
    );
    (first, all)
}

fn peak(b: &Branch, h: &Harmonics) -> usize {
    let (ci, si) = h.index_of(1).unwrap();
    let len = h.len();
    (0..b.points.len())
        .max_by(|&i, &j| {
            let a = |p: &HbmPoint| p.z[ci].hypot(p.z[si]) + 0.0 * len as f64;
            a(&b.points[i]).partial_cmp(&a(&b.points[j])).unwrap()
        })
        .unwrap()
}

#[test]
fn duffing_with_seven_harmonics_matches_time_integration() {
    let (m, zeta) = (1.0, 0.02);
    let k = (2.0 * PI * 10.0f64).powi(2);
    let c = 2.0 * zeta * (k * m).sqrt();
    let mut s = sdof(m, c, k);
    s.attach(
        "cubic",
        Arc::new(CubicSpring { k3: 4.0e7 }),
        DMatrix::from_element(1, 1, 1.0),
    )
    .unwrap();
    let h = Harmonics::new(7, true, Some(64)).unwrap();
    let sys = HbmSystem::new(
        &s,
        h,
        Excitation {
            force: DVector::from_element(1, 1.0),
            harmonic: 1,
            force_sin: None,
        },
        FormulationChoice::Auto,
    )
    .unwrap();
    let mut settings = ContinuationSettings::new(8.0, 16.0);
    settings.points = 40;
    let b = sweep(&sys, 1.5, &settings, &mut |_| {}).unwrap();
    eprintln!(
        "duffing sweep {:.2} s {} points",
        b.wall_time_s,
        b.points.len()
    );
    assert_eq!(b.turning_points, 2);
    // Stable upper branch: below the first fold, at 90 % of its frequency; and a point below
    // the resonance.
    let ip = peak(&b, &sys.harmonics);
    let f_fold = b.points[ip].omega;
    let upper = (0..ip)
        .min_by(|&i, &j| {
            let d = |p: &HbmPoint| (p.omega - 0.9 * f_fold).abs();
            d(&b.points[i]).partial_cmp(&d(&b.points[j])).unwrap()
        })
        .unwrap();
    for idx in [upper, ip / 3] {
        let (first, all) = compare(&sys, &b.points[idx], 600);
        eprintln!("HBM against Newmark at point {idx}: first harmonic {first:.2e}, all {all:.2e}");
        assert!(
            first < 5e-3 && all < 5e-3,
            "Duffing at {:.3} Hz: first harmonic {first:.2e}, all {all:.2e}",
            b.points[idx].omega / (2.0 * PI)
        );
    }
}

#[test]
fn jenkins_sdof_with_fifteen_harmonics_matches_time_integration() {
    let (m, k, c) = (1.0, 4.0e4, 2.0);
    let mut s = sdof(m, c, k);
    s.attach(
        "jenkins",
        Arc::new(Jenkins::new(3.0e4, 1.0).unwrap()),
        DMatrix::from_element(1, 1, 1.0),
    )
    .unwrap();
    let h = Harmonics::new(15, true, Some(512)).unwrap();
    let sys = HbmSystem::new(
        &s,
        h,
        Excitation {
            force: DVector::from_element(1, 1.0),
            harmonic: 1,
            force_sin: None,
        },
        FormulationChoice::Auto,
    )
    .unwrap();
    let mut settings = ContinuationSettings::new(28.0, 44.0);
    settings.points = 15;
    let b = sweep(&sys, 2.0, &settings, &mut |_| {}).unwrap();
    eprintln!("sweep {:.2} s {} points", b.wall_time_s, b.points.len());
    let ip = peak(&b, &sys.harmonics);
    for idx in [ip, b.points.len() / 4] {
        let (first, all) = compare(&sys, &b.points[idx], 400);
        eprintln!("HBM against Newmark at point {idx}: first harmonic {first:.2e}, all {all:.2e}");
        assert!(
            first < 1e-2 && all < 1e-2,
            "Jenkins at {:.3} Hz: {first:.2e}, {all:.2e}",
            b.points[idx].omega / (2.0 * PI)
        );
    }
}

#[test]
fn valanis_sdof_matches_time_integration() {
    // The 3-D microslip element of the element table on one tangential direction (un = 0: the
    // normal load stays N0).
    let (m, k, c) = (1.0, 4.0e4, 2.0);
    let mut s = sdof(m, c, k);
    let v = ValanisParams::new(3.0e4, 0.5, 0.0, 0.5).unwrap();
    let el = MicroslipContact::new(v, 1e6, 2.0).unwrap();
    s.attach(
        "valanis",
        Arc::new(el),
        DMatrix::from_column_slice(3, 1, &[1.0, 0.0, 0.0]),
    )
    .unwrap();
    let h = Harmonics::new(9, true, Some(1024)).unwrap();
    let sys = HbmSystem::new(
        &s,
        h,
        Excitation {
            force: DVector::from_element(1, 1.0),
            harmonic: 1,
            force_sin: None,
        },
        FormulationChoice::Coordinates,
    )
    .unwrap();
    let mut settings = ContinuationSettings::new(28.0, 44.0);
    settings.points = 15;
    let b = sweep(&sys, 1.5, &settings, &mut |_| {}).unwrap();
    eprintln!("sweep {:.2} s {} points", b.wall_time_s, b.points.len());
    let ip = peak(&b, &sys.harmonics);
    for idx in [ip, b.points.len() - 3] {
        let (first, all) = compare(&sys, &b.points[idx], 400);
        eprintln!("HBM against Newmark at point {idx}: first harmonic {first:.2e}, all {all:.2e}");
        assert!(
            first < 1e-2 && all < 1e-2,
            "Valanis at {:.3} Hz: {first:.2e}, {all:.2e}",
            b.points[idx].omega / (2.0 * PI)
        );
    }
}

#[test]
fn two_mass_resonator_with_a_valanis_joint_matches_time_integration() {
    // m1 on a ground spring; m2 joined to m1 by a linear spring in parallel with a Gaul–Lenz
    // (Valanis, constant stick limit) joint; force on m1.
    let m = DMatrix::from_diagonal(&DVector::from_vec(vec![1.0, 0.5]));
    let (k1, k12) = (1.0e5, 1.0e4);
    let k = DMatrix::from_row_slice(2, 2, &[k1 + k12, -k12, -k12, k12]);
    let c = DMatrix::from_row_slice(2, 2, &[3.0, -0.5, -0.5, 0.5]);
    let mut s = Structure::lumped(vec!["m1.x".into(), "m2.x".into()], m, c, k).unwrap();
    let joint = GaulLenz::new(&GaulLenzParams {
        e0: 4.0e4,
        k: 0.4,
        et: 0.0,
        sigma0: 3.0,
    })
    .unwrap();
    s.attach(
        "joint",
        Arc::new(joint),
        DMatrix::from_row_slice(1, 2, &[1.0, -1.0]),
    )
    .unwrap();
    let h = Harmonics::new(9, true, Some(1024)).unwrap();
    let sys = HbmSystem::new(
        &s,
        h,
        Excitation {
            force: DVector::from_vec(vec![1.0, 0.0]),
            harmonic: 1,
            force_sin: None,
        },
        FormulationChoice::Auto,
    )
    .unwrap();
    // First mode: stuck ≈ 36 Hz, joint slipping ≈ 28 Hz.
    let mut settings = ContinuationSettings::new(20.0, 45.0);
    settings.points = 15;
    let b = sweep(&sys, 20.0, &settings, &mut |_| {}).unwrap();
    eprintln!("sweep {:.2} s {} points", b.wall_time_s, b.points.len());
    let ip = peak(&b, &sys.harmonics);
    for idx in [ip, 2] {
        let (first, all) = compare(&sys, &b.points[idx], 400);
        eprintln!("HBM against Newmark at point {idx}: first harmonic {first:.2e}, all {all:.2e}");
        assert!(
            first < 1e-2 && all < 1e-2,
            "two-mass at {:.3} Hz: {first:.2e}, {all:.2e}",
            b.points[idx].omega / (2.0 * PI)
        );
    }
}
