//! Harmonic balance against independent references: exact linear FRF, the Duffing oscillator's
//! first-harmonic closed form, Caughey's describing function of the Jenkins element, and
//! Segalman's dissipation of the Iwan element.
//! (Time-integration comparisons: tests/dynamics_time_integration.rs.)

use asperity::dynamics::aft::{self, AftSettings, Harmonics};
use asperity::dynamics::continuation::{sweep, ContinuationSettings};
use asperity::dynamics::hbm::{Excitation, FormulationChoice, HbmSystem};
use asperity::dynamics::model::Structure;
use asperity::element::cubic::CubicSpring;
use asperity::element::iwan::{IwanElement, IwanParams};
use asperity::element::jenkins::Jenkins;
use nalgebra::{Complex, DMatrix, DVector};
use std::f64::consts::PI;
use std::sync::Arc;

/// Three masses in a chain, grounded at one end, with a non-proportional damping matrix.
fn chain() -> Structure {
    let m = DMatrix::from_diagonal(&DVector::from_vec(vec![1.0, 0.5, 0.8]));
    let k = DMatrix::from_row_slice(
        3,
        3,
        &[
            3.0e4, -1.0e4, 0.0, -1.0e4, 2.5e4, -1.5e4, 0.0, -1.5e4, 1.5e4,
        ],
    );
    let c = DMatrix::from_row_slice(3, 3, &[4.0, -1.0, 0.0, -1.0, 2.0, -0.5, 0.0, -0.5, 1.5]);
    Structure::lumped(vec!["a.x".into(), "b.x".into(), "c.x".into()], m, c, k).unwrap()
}

/// Exact first-harmonic response `(K − ω²M + iωC)⁻¹F` as (cos, sin) coefficients.
fn exact_frf(
    m: &DMatrix<f64>,
    c: &DMatrix<f64>,
    k: &DMatrix<f64>,
    f: &DVector<f64>,
    w: f64,
) -> Vec<(f64, f64)> {
    let n = f.len();
    let z = DMatrix::from_fn(n, n, |r, s| {
        Complex::new(k[(r, s)] - w * w * m[(r, s)], w * c[(r, s)])
    });
    let x = z.lu().solve(&f.map(|v| Complex::new(v, 0.0))).unwrap();
    // x(t) = Re(X e^{iωt}) = Re X cos − Im X sin.
    x.iter().map(|v| (v.re, -v.im)).collect()
}

#[test]
fn linear_frf_is_exact_in_both_formulations() {
    let s0 = chain();
    let f = DVector::from_vec(vec![0.0, 0.0, 1.0]);
    // Without elements (coordinates), and with an always-stuck Jenkins element between masses
    // a and c (a linear spring kt), in both formulations.
    let kt = 2.0e4;
    let mut s1 = chain();
    let map = DMatrix::from_row_slice(1, 3, &[1.0, 0.0, -1.0]);
    s1.attach(
        "link",
        Arc::new(Jenkins::new(kt, 1e9).unwrap()),
        map.clone(),
    )
    .unwrap();
    let k1 = &s1.stiffness + map.transpose() * &map * kt;
    for (s, k, choice) in [
        (&s0, s0.stiffness.clone(), FormulationChoice::Coordinates),
        (&s1, k1.clone(), FormulationChoice::Coordinates),
        (&s1, k1.clone(), FormulationChoice::Receptance),
    ] {
        let h = Harmonics::new(3, false, Some(32)).unwrap();
        let mut sys = HbmSystem::new(
            s,
            h,
            Excitation {
                force: f.clone(),
                harmonic: 1,
                force_sin: None,
            },
            choice,
        )
        .unwrap();
        sys.newton.tolerance = 1e-13;
        let mut settings = ContinuationSettings::new(5.0, 40.0);
        settings.points = 60;
        let b = sweep(&sys, 2.0, &settings, &mut |_| {}).unwrap();
        assert!(b.points.len() >= 60);
        let len = sys.harmonics.len();
        let (ci, si) = sys.harmonics.index_of(1).unwrap();
        let mut worst: f64 = 0.0;
        for p in &b.points {
            let x = sys.coordinates(p);
            let ex = exact_frf(&s.mass, &s.damping, &k, &(&f * 2.0), p.omega);
            let scale = ex.iter().map(|(a, b)| a.hypot(*b)).fold(0.0, f64::max);
            for (r, (a, bb)) in ex.iter().enumerate() {
                worst = worst.max((x[r * len + ci] - a).abs() / scale);
                worst = worst.max((x[r * len + si] - bb).abs() / scale);
                // No other harmonic is excited.
                for hc in (0..len).filter(|&hc| hc != ci && hc != si) {
                    worst = worst.max(x[r * len + hc].abs() / scale);
                }
            }
        }
        assert!(
            worst < 1e-10,
            "{choice:?}: worst relative deviation {worst:.3e}"
        );
        // The sweep crossed the three resonances (5.9, 18.9 and 30.7 Hz for the stiffened chain).
        assert!(b.points.last().unwrap().omega > 2.0 * PI * 39.99);
    }
}

#[test]
fn modal_model_frf_matches_the_modal_sum() {
    let (f1, f2, z1, z2) = (12.0, 31.0, 0.02, 0.01);
    let s = Structure::modal(&[f1, f2], &[z1, z2]).unwrap();
    let phi_drive = [0.7, -0.4];
    let h = Harmonics::new(1, true, None).unwrap();
    let sys = HbmSystem::new(
        &s,
        h,
        Excitation {
            force: DVector::from_row_slice(&phi_drive),
            harmonic: 1,
            force_sin: None,
        },
        FormulationChoice::Auto,
    )
    .unwrap();
    let mut settings = ContinuationSettings::new(5.0, 40.0);
    settings.points = 50;
    let b = sweep(&sys, 1.0, &settings, &mut |_| {}).unwrap();
    for p in &b.points {
        let w = p.omega;
        // Drive-point receptance Σ φ²/(ω_r² − ω² + 2iζ_r ω_r ω).
        let mut hdp = Complex::new(0.0, 0.0);
        for (r, (fr, zr)) in [(f1, z1), (f2, z2)].iter().enumerate() {
            let wr = 2.0 * PI * fr;
            hdp += phi_drive[r] * phi_drive[r] / Complex::new(wr * wr - w * w, 2.0 * zr * wr * w);
        }
        let x = sys.coordinates(p);
        let (a, bb) = (
            phi_drive[0] * x[0] + phi_drive[1] * x[2],
            phi_drive[0] * x[1] + phi_drive[1] * x[3],
        );
        let err = (Complex::new(a, -bb) - hdp).norm() / hdp.norm();
        assert!(err < 1e-10, "{err}");
    }
}

#[test]
fn duffing_first_harmonic_closed_form_through_the_fold() {
    // m ẍ + c ẋ + k x + k3 x³ = F cos ωt; one harmonic: the amplitude A satisfies
    // [(k − mω² + ¾k3A²)² + (cω)²]·A² = F² (Nayfeh & Mook 1979, §4.1).
    let (m, f0, zeta) = (1.0, 10.0, 0.01);
    let k = m * (2.0 * PI * f0).powi(2);
    let c = 2.0 * zeta * (k * m).sqrt();
    let k3 = 1.05e7;
    let force = 0.79;
    let mut s = Structure::lumped(
        vec!["x".into()],
        DMatrix::from_element(1, 1, m),
        DMatrix::from_element(1, 1, c),
        DMatrix::from_element(1, 1, k),
    )
    .unwrap();
    s.attach(
        "duffing",
        Arc::new(CubicSpring { k3 }),
        DMatrix::from_element(1, 1, 1.0),
    )
    .unwrap();
    let h = Harmonics::new(1, true, Some(16)).unwrap();
    let mut sys = HbmSystem::new(
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
    sys.newton.tolerance = 1e-12;
    let mut settings = ContinuationSettings::new(8.0, 14.0);
    settings.points = 100;
    let b = sweep(&sys, force, &settings, &mut |_| {}).unwrap();
    assert_eq!(
        b.turning_points, 2,
        "the hardening fold has two turning points"
    );
    let mut worst: f64 = 0.0;
    let mut amax: f64 = 0.0;
    for p in &b.points {
        let a = p.z[0].hypot(p.z[1]);
        amax = amax.max(a);
        let w = p.omega;
        let f_cf = a * ((k - m * w * w + 0.75 * k3 * a * a).powi(2) + (c * w).powi(2)).sqrt();
        worst = worst.max((f_cf / force - 1.0).abs());
    }
    assert!(worst < 1e-9, "closed-form residual {worst:.3e}");
    // The peak is where the backbone meets the damping line: A = F/(cω) at ω² = k/m + ¾k3A²/m.
    let a_peak = {
        let mut a: f64 = 0.01;
        for _ in 0..100 {
            let w = ((k + 0.75 * k3 * a * a) / m).sqrt();
            a = force / (c * w);
        }
        a
    };
    assert!((amax / a_peak - 1.0).abs() < 2e-3, "{amax} vs {a_peak}");
}

/// Caughey (1960) equivalent stiffness and viscous coefficient·ω of the Jenkins element
/// (stiffness kt, slip force Fs) at amplitude A.
fn caughey(kt: f64, fs: f64, a: f64) -> (f64, f64) {
    let xy = fs / kt;
    if a <= xy {
        return (kt, 0.0);
    }
    let phi = (1.0 - 2.0 * xy / a).acos();
    (
        kt / PI * (phi - 0.5 * (2.0 * phi).sin()),
        4.0 * fs / (PI * a) * (1.0 - xy / a),
    )
}

#[test]
fn jenkins_sdof_matches_caughey_describing_function() {
    let (m, k, c) = (1.0, 4.0e4, 2.0);
    let (kt, fs) = (3.0e4, 1.0);
    let mut s = Structure::lumped(
        vec!["x".into()],
        DMatrix::from_element(1, 1, m),
        DMatrix::from_element(1, 1, c),
        DMatrix::from_element(1, 1, k),
    )
    .unwrap();
    s.attach(
        "jenkins",
        Arc::new(Jenkins::new(kt, fs).unwrap()),
        DMatrix::from_element(1, 1, 1.0),
    )
    .unwrap();
    let h = Harmonics::new(1, true, Some(1 << 14)).unwrap();
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
    let mut worst: f64 = 0.0;
    let mut slipping = 0;
    for level in [0.5, 2.0, 8.0] {
        let mut settings = ContinuationSettings::new(25.0, 45.0);
        settings.points = 30;
        let b = sweep(&sys, level, &settings, &mut |_| {}).unwrap();
        for p in &b.points {
            let w = p.omega;
            let a = p.z[0].hypot(p.z[1]);
            let (keq, ceqw) = caughey(kt, fs, a);
            if a > fs / kt {
                slipping += 1;
            }
            let f_cf = a * ((k + keq - m * w * w).powi(2) + (c * w + ceqw).powi(2)).sqrt();
            worst = worst.max((f_cf / level - 1.0).abs());
        }
    }
    assert!(slipping >= 30, "too few points in slip: {slipping}");
    assert!(worst < 1e-6, "describing-function residual {worst:.3e}");
}

/// The AFT cycle dissipates Segalman's closed form `D = 4R·A^{χ+3}/((χ+2)(χ+3))` within the
/// discretisation error (40 sliders: 2 %), and its fundamental in-phase stiffness lies
/// between the secant of the backbone and the stick stiffness.
#[test]
fn iwan_aft_cycle_dissipates_segalmans_energy() {
    let p = IwanParams::new(2.0, 1e5, -0.3, 0.5).unwrap();
    let el = IwanElement::new(p, 40).unwrap();
    let h = Harmonics::new(3, true, Some(2048)).unwrap();
    for frac in [0.2, 0.5, 0.9] {
        let a = frac * p.phi_max();
        let c = aft::cycle_summary(&el, &h, &[a, 0.0, 0.0, 0.0], 1.0, &AftSettings::default());
        let exact = p.dissipation_per_cycle(a);
        assert!(
            (c.dissipated_energy_j / exact - 1.0).abs() < 0.02,
            "A = {frac} φmax: {} vs {exact}",
            c.dissipated_energy_j
        );
        let r = aft::evaluate(
            &el,
            &h,
            &[a, 0.0, 0.0, 0.0],
            1.0,
            false,
            &AftSettings::default(),
        );
        let keq = r.forces[0] / a;
        assert!(keq < p.stiffness && keq > p.backbone(a) / a * 0.9, "{keq}");
    }
}
