//! The joint laws of the element layer against closed forms and time integration.

use asperity::element::hunt_crossley::{
    damping_factor, damping_factor_hunt_crossley, damping_factor_lankarani_nikravesh, restitution,
    HuntCrossleyParams,
};

/// Exit velocity of a mass `m` striking a Hunt–Crossley contact at `v_in`: `m·δ̈ = −F(δ, δ̇)`
/// from `δ = 0`, `δ̇ = v_in` by the classical Runge–Kutta scheme with `steps` steps over the
/// undamped Hertz contact time, until the contact opens (`δ < 0`; the exit velocity is
/// interpolated linearly to `δ = 0`, where the force and so the acceleration vanish).
fn impact_exit_velocity(p: &HuntCrossleyParams, m: f64, v_in: f64, steps: usize) -> f64 {
    let n = p.exponent;
    let delta_max = ((n + 1.0) * m * v_in * v_in / (2.0 * p.stiffness)).powf(1.0 / (n + 1.0));
    let dt = 4.0 * delta_max / v_in / steps as f64;
    let acc = |d: f64, v: f64| -p.force_and_partials(p.gap + d, v).0 / m;
    let (mut d, mut v) = (0.0f64, v_in);
    for _ in 0..20 * steps {
        let (k1d, k1v) = (v, acc(d, v));
        let (k2d, k2v) = (
            v + 0.5 * dt * k1v,
            acc(d + 0.5 * dt * k1d, v + 0.5 * dt * k1v),
        );
        let (k3d, k3v) = (
            v + 0.5 * dt * k2v,
            acc(d + 0.5 * dt * k2d, v + 0.5 * dt * k2v),
        );
        let (k4d, k4v) = (v + dt * k3v, acc(d + dt * k3d, v + dt * k3v));
        let d1 = d + dt / 6.0 * (k1d + 2.0 * k2d + 2.0 * k3d + k4d);
        let v1 = v + dt / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
        if d1 < 0.0 && v1 < 0.0 {
            let t = d / (d - d1);
            return v + t * (v1 - v);
        }
        d = d1;
        v = v1;
    }
    panic!("the contact did not open");
}

/// The coefficient of restitution of one impact, by time integration, equals the exact relation
/// `ln((1 − e·x)/(1 + x)) + (1 + e)·x = 0` (`x = χ·v_in`, Gonthier et al. 2004) within 1e-6, for
/// Hertz and linear contacts, with and without a gap; the explicit Hunt–Crossley and
/// Lankarani–Nikravesh factors miss a restitution of 0.5 by more than 2 %.
#[test]
fn hunt_crossley_restitution_by_time_integration_matches_the_exact_relation() {
    let (m, v_in) = (0.1, 0.5);
    for (n, k, gap) in [(1.5, 1e8, 0.0), (1.0, 2e6, 3e-5), (2.0, 5e11, 0.0)] {
        for e in [0.2, 0.5, 0.8, 0.97] {
            let chi = damping_factor(e, v_in).unwrap();
            let p = HuntCrossleyParams {
                stiffness: k,
                exponent: n,
                damping_factor: chi,
                gap,
            };
            let e_num = -impact_exit_velocity(&p, m, v_in, 40_000) / v_in;
            assert!(
                (e_num - e).abs() < 1e-6,
                "n = {n}, e = {e}: integrated {e_num}"
            );
            assert!((restitution(chi * v_in) - e).abs() < 1e-10);
        }
    }
    // The explicit formulas are small-damping approximations: visibly off at e = 0.5.
    for chi in [
        damping_factor_hunt_crossley(0.5, v_in).unwrap(),
        damping_factor_lankarani_nikravesh(0.5, v_in).unwrap(),
    ] {
        let p = HuntCrossleyParams {
            stiffness: 1e8,
            exponent: 1.5,
            damping_factor: chi,
            gap: 0.0,
        };
        let e_num = -impact_exit_velocity(&p, m, v_in, 40_000) / v_in;
        assert!((e_num - 0.5).abs() > 0.01, "χ = {chi}: e = {e_num}");
    }
}

// ---------------------------------------------------------------------------------------------
// Bilinear normal contact: harmonic balance against Newmark, linear limits, the model file.

use asperity::dynamics::aft::Harmonics;
use asperity::dynamics::hbm::{Excitation, FormulationChoice, HbmSystem};
use asperity::dynamics::model::Structure;
#[path = "support/hbm_newmark.rs"]
mod hbm_newmark;
use asperity::element::BilinearContact;
use hbm_newmark::{amplitude, ramped_hbm_against_newmark};
use nalgebra::{DMatrix, DVector};
use std::f64::consts::PI;
use std::sync::Arc;

const M: f64 = 1.0;
const ZETA: f64 = 0.02;

fn k_lin() -> f64 {
    (2.0 * PI * 10.0f64).powi(2)
}

/// `m·ẍ + c·ẋ + k·x + f(x) = F·cos ωt` with a bilinear contact `f` against ground.
fn oscillator(joint: BilinearContact, harmonics: usize, samples: usize) -> (Structure, Harmonics) {
    let k = k_lin();
    let c = 2.0 * ZETA * (k * M).sqrt();
    let mut s = Structure::lumped(
        vec!["x".into()],
        DMatrix::from_element(1, 1, M),
        DMatrix::from_element(1, 1, c),
        DMatrix::from_element(1, 1, k),
    )
    .unwrap();
    s.attach("joint", Arc::new(joint), DMatrix::from_element(1, 1, 1.0))
        .unwrap();
    (s, Harmonics::new(harmonics, false, Some(samples)).unwrap())
}
/// Where the contact stays on one branch the oscillator is linear with stiffness `k + k1`: the
/// harmonic balance gives the closed-form receptance to rounding (1e-10), whether or not the
/// motion crosses the threshold of a law with `k2 = k1`, and no other harmonic.
#[test]
fn bilinear_contact_on_one_branch_is_the_linear_oscillator() {
    let k1 = 0.5 * k_lin();
    for joint in [
        // Never reaches the threshold, never separates.
        BilinearContact::new(k1, 4.0 * k1, 1.0, 0.5).unwrap(),
        // Crosses the threshold every cycle, with k2 = k1.
        BilinearContact::new(k1, k1, 2e-4, 5e-4).unwrap(),
    ] {
        let (s, h) = oscillator(joint, 5, 64);
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
        for f_hz in [6.0, 12.0, 20.0] {
            let w = 2.0 * PI * f_hz;
            let level = 0.1;
            let p = sys.solve(w, level, None).unwrap();
            assert!(p.converged);
            let x = sys.coordinates(&p);
            let c = 2.0 * ZETA * (k_lin() * M).sqrt();
            let exact = level / ((k_lin() + k1 - M * w * w).powi(2) + (c * w).powi(2)).sqrt();
            let a = amplitude(&x, &sys.harmonics);
            assert!(exact < 4e-4, "the test must stay on one branch: {exact}");
            assert!(
                (a - exact).abs() < 1e-10 * exact,
                "{f_hz} Hz: {a} vs {exact}"
            );
            let (ci, si) = sys.harmonics.index_of(1).unwrap();
            let others = (0..x.len())
                .filter(|&i| i != ci && i != si)
                .fold(0.0f64, |m, i| m.max(x[i].abs()));
            assert!(
                others < 1e-10 * exact,
                "{f_hz} Hz: other harmonics {others:e}"
            );
        }
    }
}

/// With separation and the stiffness change both inside the cycle, the harmonic balance (15
/// harmonics, 1024 samples) and Newmark's average-acceleration integration of the same equations
/// (2048 steps per period, to the periodic steady state) agree on the first harmonic within 1e-4.
#[test]
fn bilinear_contact_harmonic_balance_matches_newmark() {
    let k1 = 0.5 * k_lin();
    // Preloaded by 1 mm, stiffening at 2 mm of indentation: the motion of about ±1.5 mm opens
    // the contact and passes the threshold each cycle.
    let joint = BilinearContact::new(k1, 3.0 * k1, 2e-3, 1e-3).unwrap();
    let (s, h) = oscillator(joint, 15, 1024);
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
    for (f_hz, level) in [(7.0, 6.0), (9.0, 3.0)] {
        let w = 2.0 * PI * f_hz;
        // Continue in level from the linear regime to the nonlinear one.
        let (x, a_hbm, a_ti) =
            ramped_hbm_against_newmark(&sys, w, level, &format!("{f_hz} Hz"), 2048);
        // The motion must visit all three branches for the test to mean something.
        let mut samples = vec![0.0; sys.harmonics.n_time()];
        sys.harmonics.to_time(x.as_slice(), &mut samples);
        let (lo, hi) = samples
            .iter()
            .fold((f64::MAX, f64::MIN), |(a, b), &v| (a.min(v), b.max(v)));
        assert!(lo < -1e-3 && hi > 1e-3, "{f_hz} Hz: x in [{lo}, {hi}]");
        let err = (a_hbm - a_ti).abs() / a_ti;
        eprintln!("{f_hz} Hz: HBM {a_hbm:.6e}, Newmark {a_ti:.6e}, relative {err:.1e}");
        assert!(err < 1e-4, "{f_hz} Hz: {err:.2e}");
    }
}

/// A `[[joint]]` of the model file attaches the law (bilinear, thin layer) between a node and
/// ground along its direction; a missing or foreign parameter, an unknown node or a bad value is refused with the
/// file, the line and the key.
#[test]
fn model_file_joint_attaches_bilinear_and_thin_layer_laws() {
    use asperity::dynamics::model_file::load;
    let dir = tempfile::tempdir().unwrap();
    let w = |name: &str, text: &str| std::fs::write(dir.path().join(name), text).unwrap();
    w("mass.csv", "# unit: kg\ntip.x,tip.z\n1.0,0\n0,1.0\n");
    w("damping.csv", "# unit: N*s/m\ntip.x,tip.z\n1.0,0\n0,1.0\n");
    w("stiffness.csv", "# unit: N/m\ntip.x,tip.z\n1e4,0\n0,1e4\n");
    let head = "[linear]\nmass = \"mass.csv\"\ndamping = \"damping.csv\"\nstiffness = \"stiffness.csv\"\n\n";
    let tail = "\n[excitation]\ndofs = [\"tip.z\"]\nlevels_n = [1.0]\n\n[response]\ndofs = [\"tip.z\"]\n\n\
                [sweep]\nfrequency_start_hz = 10.0\nfrequency_end_hz = 20.0\nharmonics = 3\n";
    let joint = "[[joint]]\nlaw = \"bilinear\"\nnode_a = \"tip\"\nnode_b = \"ground\"\n\
                 direction = [0.0, 0.0, -2.0]\nk1_n_per_m = 2e4\nk2_n_per_m = 6e4\n\
                 threshold_m = 1e-3\nstatic_indentation_m = -1e-4\n";
    let model = dir.path().join("model.toml");
    std::fs::write(&model, format!("{head}{joint}{tail}")).unwrap();
    let loaded = load(&model).unwrap();
    let els = &loaded.structure.elements;
    assert_eq!(els.len(), 1);
    // u = direction·(x_tip − 0) with the direction normalised: −z closes.
    assert_eq!(els[0].map.shape(), (1, 2));
    assert_eq!((els[0].map[(0, 0)], els[0].map[(0, 1)]), (0.0, -1.0));
    let mut f = [0.0];
    els[0]
        .element
        .step(&[], &[0.0], &[3e-4], &mut [], &mut f, None);
    // Gap 1e-4 closed by 3e-4: 2e-4 of indentation on k1.
    assert!((f[0] - 2e4 * 2e-4).abs() < 1e-12);
    for (from, to, needles) in [
        (
            "k2_n_per_m = 6e4\n",
            "",
            vec!["model.toml:", "k2_n_per_m", "needs"],
        ),
        (
            "threshold_m = 1e-3\n",
            "threshold_m = 1e-3\nextra_m = 1.0\n",
            vec!["model.toml:", "extra_m"],
        ),
        (
            "node_a = \"tip\"",
            "node_a = \"tap\"",
            vec!["model.toml:", "`tap`"],
        ),
        (
            "threshold_m = 1e-3",
            "threshold_m = 0.0",
            vec!["model.toml:13", "threshold_m"],
        ),
        (
            "law = \"bilinear\"",
            "law = \"dahl\"",
            vec!["model.toml:", "dahl"],
        ),
        (
            "[0.0, 0.0, -2.0]",
            "[0.0, 0.0, 0.0]",
            vec!["model.toml:", "direction"],
        ),
    ] {
        let bad = joint.replace(from, to);
        assert_ne!(bad, joint);
        std::fs::write(&model, format!("{head}{bad}{tail}")).unwrap();
        let e = load(&model).unwrap_err().to_string();
        for n in needles {
            assert!(e.contains(n), "{from} → {to}: {e}");
        }
    }
    // A thin layer: the virgin curve σ/Sy = b·x + (1 − b)·x/(1 + xⁿ)^{1/n} at x = ε/εy = 2.
    let layer = "[[joint]]\nlaw = \"thin-layer\"\nnode_a = \"tip\"\nnode_b = \"ground\"\n\
                 direction = [1.0, 0.0, 0.0]\nelastic_modulus_pa = 8e3\nplastic_modulus_pa = 8e2\n\
                 yield_stress_pa = 2e4\ntransition_exponent = 2.0\narea_m2 = 1e-4\nthickness_m = 1e-4\n";
    std::fs::write(&model, format!("{head}{layer}{tail}")).unwrap();
    let loaded = load(&model).unwrap();
    let el = &loaded.structure.elements[0];
    assert_eq!((el.map[(0, 0)], el.map[(0, 1)]), (1.0, 0.0));
    let (mut s1, mut f) = ([0.0; 3], [0.0]);
    el.element
        .step(&[0.0; 3], &[0.0], &[5e-4], &mut s1, &mut f, None);
    let x: f64 = 2.0;
    let exact = 2.0 * (0.1 * x + 0.9 * x / (1.0 + x * x).sqrt());
    assert!((f[0] - exact).abs() < 1e-12 * exact, "{} vs {exact}", f[0]);
    let bad = layer.replace("plastic_modulus_pa = 8e2", "plastic_modulus_pa = 9e3");
    std::fs::write(&model, format!("{head}{bad}{tail}")).unwrap();
    let e = load(&model).unwrap_err().to_string();
    assert!(
        e.contains("model.toml:") && e.contains("plastic_modulus_pa"),
        "{e}"
    );
}

// ---------------------------------------------------------------------------------------------
// LuGre friction: steady sliding against the Stribeck curve, harmonic balance against Newmark.

use asperity::element::{LuGre, LuGreParams};

fn lugre_params() -> LuGreParams {
    LuGreParams {
        sigma0: 2e4,
        sigma1: 5.0,
        sigma2: 0.4,
        coulomb: 1.0,
        stiction: 1.5,
        stribeck_velocity: 0.01,
    }
}

/// Driven at a constant velocity from unloaded bristles, the deflection follows the closed form
/// `z(t) = z∞·(1 − exp(−σ0·|v|·t/g(v)))` at any step (the update is exact at constant velocity)
/// and the force tends to the steady sliding force `sgn(v)·g(v) + σ2·v` (the Stribeck curve):
/// within 1e-12 and 1e-11 (the force sums terms of σ0·z's size), across the Stribeck range, in both directions.
#[test]
fn lugre_steady_sliding_is_the_stribeck_curve() {
    let p = lugre_params();
    for v in [-0.05, -0.004, 1e-4, 0.002, 0.01, 0.3] {
        let rate = 1000.0;
        let (g, _) = p.stribeck(v);
        let mut z = 0.0;
        let mut f = 0.0;
        // Long enough for the transient to fall below 1e-16: exp(−40).
        let steps = (40.0 * g / (p.sigma0 * v.abs()) * rate).ceil() as usize;
        for i in 1..=steps {
            let r = p.step(z, v / rate, rate);
            z = r.z1;
            f = r.force;
            let t = i as f64 / rate;
            let exact = v.signum() * g / p.sigma0 * (1.0 - (-p.sigma0 * v.abs() * t / g).exp());
            assert!(
                (z - exact).abs() <= 1e-12 * g / p.sigma0,
                "v = {v}, t = {t}: z = {z}, closed form {exact}"
            );
        }
        let steady = p.steady_sliding_force(v);
        assert!(
            (f - steady).abs() < 1e-11 * steady.abs(),
            "v = {v}: F = {f}, Stribeck curve {steady}"
        );
        // The curve itself: Fs at vanishing speed, Fc + σ2·v far beyond vs.
        assert!((p.steady_sliding_force(1e-9) - 1.5).abs() < 1e-6);
        assert!((p.steady_sliding_force(1.0) - (1.0 + 0.4)).abs() < 1e-12);
    }
}

/// The oscillator `m·ẍ + c·ẋ + k·x + f(x, ẋ) = level·cos ωt` with the rate-dependent element
/// `joint` against ground, solved by the harmonic balance (`harmonics`, `samples` per period,
/// continued in level from a sixth of it; the element reads the harmonics' exact velocity) and
/// by Newmark's average-acceleration integration with `samples` steps per period (the element
/// reads the scheme's velocity); the first-harmonic amplitudes `(HBM, Newmark)` and the HBM
/// samples. The same element serves every frequency: it has no sample rate of its own.
fn rate_dependent_hbm_and_newmark(
    joint: Arc<dyn asperity::element::HystereticElement>,
    f_hz: f64,
    level: f64,
    harmonics: usize,
    samples: usize,
) -> (f64, f64, Vec<f64>) {
    let k = k_lin();
    let c = 2.0 * ZETA * (k * M).sqrt();
    let w = 2.0 * PI * f_hz;
    let mut s = Structure::lumped(
        vec!["x".into()],
        DMatrix::from_element(1, 1, M),
        DMatrix::from_element(1, 1, c),
        DMatrix::from_element(1, 1, k),
    )
    .unwrap();
    s.attach("joint", joint, DMatrix::from_element(1, 1, 1.0))
        .unwrap();
    let h = Harmonics::new(harmonics, false, Some(samples)).unwrap();
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
    let (x, a_hbm, a_ti) =
        ramped_hbm_against_newmark(&sys, w, level, &format!("{f_hz} Hz"), samples);
    let mut t = vec![0.0; samples];
    sys.harmonics.to_time(x.as_slice(), &mut t);
    (a_hbm, a_ti, t)
}

/// A mass on a spring rubbing on a LuGre contact, driven through stick and slip at two
/// frequencies with the same element: the harmonic balance (H = 25, 1024 samples, exact
/// velocities and increment durations) and Newmark's average-acceleration integration (1024
/// steps per period, the scheme's velocities) agree on the first harmonic within 1e-4.
#[test]
fn lugre_harmonic_balance_matches_newmark() {
    let joint: Arc<dyn asperity::element::HystereticElement> = Arc::new(LuGre {
        params: lugre_params(),
    });
    for (f_hz, level) in [(7.0, 6.0), (12.0, 8.0)] {
        let (a_hbm, a_ti, _) = rate_dependent_hbm_and_newmark(joint.clone(), f_hz, level, 25, 1024);
        // Gross sliding for part of the cycle: the amplitude is many presliding lengths Fs/σ0.
        let presliding = 1.5 / lugre_params().sigma0;
        assert!(a_hbm > 5.0 * presliding, "{f_hz} Hz: amplitude {a_hbm}");
        let err = (a_hbm - a_ti).abs() / a_ti;
        eprintln!("LuGre {f_hz} Hz: HBM {a_hbm:.6e}, Newmark {a_ti:.6e}, relative {err:.1e}");
        assert!(err < 1e-4, "{f_hz} Hz: {err:.2e}");
    }
}

/// A mass on a spring striking a Hunt–Crossley stop across a gap (a vibro-impact oscillator)
/// at two frequencies with the same element: the harmonic balance (exact approach rates) and
/// Newmark (the scheme's) agree on the first harmonic within 1e-4, with the stop closing and
/// opening every cycle.
#[test]
fn hunt_crossley_harmonic_balance_matches_newmark() {
    use asperity::element::HuntCrossley;
    let gap = 1e-3;
    let chi = damping_factor(0.7, 0.05).unwrap();
    let joint: Arc<dyn asperity::element::HystereticElement> = Arc::new(HuntCrossley {
        params: HuntCrossleyParams {
            stiffness: 2e5,
            exponent: 1.5,
            damping_factor: chi,
            gap,
        },
    });
    for (f_hz, level) in [(7.0, 5.0), (12.0, 4.0)] {
        let (a_hbm, a_ti, x) =
            rate_dependent_hbm_and_newmark(joint.clone(), f_hz, level, HC_HARMONICS, 2048);
        let hi = x.iter().fold(f64::MIN, |a, &b| a.max(b));
        assert!(hi > gap * 1.05, "{f_hz} Hz: the stop is not struck ({hi})");
        let err = (a_hbm - a_ti).abs() / a_ti;
        eprintln!("Hunt–Crossley {f_hz} Hz: HBM {a_hbm:.6e}, Newmark {a_ti:.6e}, relative {err:.1e}, max x {hi:.3e}");
        assert!(err < 1e-4, "{f_hz} Hz: {err:.2e}");
    }
}

const HC_HARMONICS: usize = 40;

// ---------------------------------------------------------------------------------------------
// Thin-layer interface law.

use asperity::element::ThinLayer;

/// A virtual layer of `k_e = Ee·A/t = 8 kN/m`, yield force `Sy·A = 2 N`, `Ep = Ee/10`.
fn layer(n: f64) -> ThinLayer {
    ThinLayer::new(8e3, 8e2, 2e4, n, 1e-4, 1e-4).unwrap()
}

/// A mass held by a thin-layer joint yielding every cycle (amplitude several yield
/// displacements): the harmonic balance (H = 15, 1024 samples, reversals located) and Newmark
/// (2048 steps per period) agree on the first harmonic within 1e-4, for a smooth (n = 2) and a
/// sharp (n = 8) transition.
#[test]
fn thin_layer_harmonic_balance_matches_newmark() {
    for n in [2.0, 8.0] {
        let l = layer(n);
        let u_yield = l.yield_strain() * l.thickness;
        for (f_hz, level) in [(5.0, 8.0), (9.0, 4.0)] {
            let k = k_lin();
            let c = 2.0 * ZETA * (k * M).sqrt();
            let w = 2.0 * PI * f_hz;
            let mut s = Structure::lumped(
                vec!["x".into()],
                DMatrix::from_element(1, 1, M),
                DMatrix::from_element(1, 1, c),
                DMatrix::from_element(1, 1, k),
            )
            .unwrap();
            s.attach("layer", Arc::new(l), DMatrix::from_element(1, 1, 1.0))
                .unwrap();
            let sys = HbmSystem::new(
                &s,
                Harmonics::new(15, false, Some(1024)).unwrap(),
                Excitation {
                    force: DVector::from_element(1, 1.0),
                    harmonic: 1,
                    force_sin: None,
                },
                FormulationChoice::Coordinates,
            )
            .unwrap();
            let (_, a_hbm, a_ti) =
                ramped_hbm_against_newmark(&sys, w, level, &format!("{f_hz} Hz"), 2048);
            assert!(a_hbm > 3.0 * u_yield, "{f_hz} Hz: amplitude {a_hbm}");
            let err = (a_hbm - a_ti).abs() / a_ti;
            eprintln!(
                "thin layer n = {n}, {f_hz} Hz: HBM {a_hbm:.6e}, Newmark {a_ti:.6e}, relative {err:.1e}"
            );
            assert!(err < 1e-4, "n = {n}, {f_hz} Hz: {err:.2e}");
        }
    }
}

/// Cycled between ±a after virgin loading with a sharp transition (n = 60), the layer's loop is
/// the bilinear kinematic-hardening parallelogram: dissipated energy per cycle
/// `W = 4·Fy·(1 − b)·(a − u_y)` (loop of height `2·Fy·(1 − b)` between elastic unloading lines
/// `2·u_y` apart) within 0.5 %; at n = 2 the smooth transition dissipates less.
#[test]
fn thin_layer_with_a_sharp_transition_dissipates_like_bilinear_plasticity() {
    use asperity::element::HystereticElement;
    let energy = |l: &ThinLayer, a: f64| {
        let q = asperity::element::sine_history(a, 3, 4000);
        let mut s = [0.0; 3];
        let mut f = vec![0.0; q.len()];
        for i in 1..q.len() {
            let mut s1 = [0.0; 3];
            let mut fi = [0.0];
            l.step(&s, &[q[i - 1]], &[q[i]], &mut s1, &mut fi, None);
            s = s1;
            f[i] = fi[0];
        }
        // The last cycle.
        let k0 = q.len() - 4001;
        asperity::element::dissipated_energy(&q[k0..], &f[k0..])
    };
    let sharp = layer(60.0);
    let (fy, b) = (sharp.yield_stress * sharp.area, sharp.hardening_ratio());
    let uy = sharp.yield_strain() * sharp.thickness;
    let a = 4.0 * uy;
    let exact = 4.0 * fy * (1.0 - b) * (a - uy);
    let w = energy(&sharp, a);
    assert!((w - exact).abs() < 5e-3 * exact, "{w} vs {exact}");
    assert!(energy(&layer(2.0), a) < 0.9 * exact);
}

/// The layer's loading direction is a discrete state: in the AFT the periodic cycle may arrive at
/// its first sample moving the other way than the initial loading reached it (here descending
/// after loading upwards), and the period must still close (periodicity error 1e-12).
#[test]
fn thin_layer_cycle_is_periodic_whichever_way_it_reaches_the_first_sample() {
    use asperity::dynamics::aft::{evaluate, AftSettings};
    let l = layer(2.0);
    let a = 4.0 * l.yield_strain() * l.thickness;
    let h = Harmonics::new(3, false, Some(64)).unwrap();
    for phase in [0.3f64, 2.0, 4.0, 5.5] {
        // u = a·sin(θ + phase): [a0, a1, b1, …] = [0, a·sin φ, a·cos φ, 0, …].
        let mut u = vec![0.0; h.len()];
        u[1] = a * phase.sin();
        u[2] = a * phase.cos();
        let r = evaluate(&l, &h, &u, 1.0, false, &AftSettings::default());
        assert!(
            r.periodic && r.periodicity_error < 1e-12,
            "phase {phase}: error {:.2e} after {} periods",
            r.periodicity_error,
            r.periods
        );
    }
}

/// `asperity response` sweeps a model with a bilinear and a thin-layer joint through separation
/// and yield: every level completes, every AFT cycle is periodic (no warning), and the
/// separation fraction of the bilinear contact is reported.
#[test]
fn response_sweeps_a_model_with_joints() {
    let dir = tempfile::tempdir().unwrap();
    let w = |name: &str, text: &str| std::fs::write(dir.path().join(name), text).unwrap();
    w("mass.csv", "# unit: kg\ntip.z\n1.0\n");
    w("damping.csv", "# unit: N*s/m\ntip.z\n2.5\n");
    w("stiffness.csv", "# unit: N/m\ntip.z\n3948\n");
    w(
        "model.toml",
        "[linear]\nmass = \"mass.csv\"\ndamping = \"damping.csv\"\nstiffness = \"stiffness.csv\"\n\n\
         [[joint]]\nlaw = \"bilinear\"\nnode_a = \"tip\"\nnode_b = \"ground\"\ndirection = [0.0, 0.0, 1.0]\n\
         k1_n_per_m = 2.0e3\nk2_n_per_m = 6.0e3\nthreshold_m = 2.0e-3\nstatic_indentation_m = 1.0e-3\n\n\
         [[joint]]\nlaw = \"thin-layer\"\nnode_a = \"tip\"\nnode_b = \"ground\"\ndirection = [0.0, 0.0, 1.0]\n\
         elastic_modulus_pa = 8e3\nplastic_modulus_pa = 8e2\nyield_stress_pa = 2e4\n\
         transition_exponent = 2.0\narea_m2 = 1e-4\nthickness_m = 1e-4\n\n\
         [excitation]\ndofs = [\"tip.z\"]\nlevels_n = [0.5, 4.0]\n\n[response]\ndofs = [\"tip.z\"]\n\n\
         [sweep]\nfrequency_start_hz = 5.0\nfrequency_end_hz = 25.0\npoints = 80\nharmonics = 7\n",
    );
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_asperity"))
        .arg("response")
        .arg(dir.path().join("model.toml"))
        .arg("--out-dir")
        .arg(dir.path().join("out"))
        .output()
        .unwrap();
    let err = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.status.success(), "{err}");
    assert!(
        !err.contains("warning") && !err.contains("INCOMPLETE"),
        "{err}"
    );
    // At 4 N the tip swings several millimetres: the 1 mm preload of the bilinear contact is
    // lost for part of the cycle.
    let line = err.lines().find(|l| l.starts_with("level 4 N:")).unwrap();
    let sep: f64 = line
        .split("separation ")
        .nth(1)
        .and_then(|s| s.split(';').next())
        .and_then(|s| s.parse().ok())
        .unwrap();
    assert!(sep > 0.05, "{line}");
}

// ---------------------------------------------------------------------------------------------
// Rate-dependent joints: exact velocities in closed forms, the frequency column, the model file.

/// A Hunt–Crossley contact with `n = 1` that never opens, driven by `u = δ0 + a·cos θ +
/// b·sin θ` (θ = ωt): `F = k·(δ0 + x)·(1 + χ·ẋ)` is a trigonometric polynomial of degree 2,
/// `kδ0 + k·x + kχδ0·ẋ + kχ·x·ẋ` with `x·ẋ = ω·(ab·cos 2θ − (a² − b²)/2·sin 2θ)`, which the AFT
/// transforms exactly: its force harmonics and their frequency derivative equal the closed form
/// to 1e-12 of `k·a`, at two frequencies with the same element (a velocity from a fixed sample
/// rate would be right at one frequency at most, and lag half a sample there).
#[test]
fn hunt_crossley_linear_contact_forces_are_the_closed_form_at_any_frequency() {
    use asperity::dynamics::aft::{evaluate, AftSettings};
    use asperity::element::HuntCrossley;
    let (k, chi) = (3e5, 0.8);
    let el = HuntCrossley {
        params: HuntCrossleyParams {
            stiffness: k,
            exponent: 1.0,
            damping_factor: chi,
            gap: 0.0,
        },
    };
    let h = Harmonics::new(4, false, Some(32)).unwrap();
    let (c1, s1) = h.index_of(1).unwrap();
    let (c2, s2) = h.index_of(2).unwrap();
    let (d0, a, b): (f64, f64, f64) = (2e-3, 6e-4, -5e-4);
    let mut u = vec![0.0; h.len()];
    u[0] = d0;
    u[c1] = a;
    u[s1] = b;
    for f_hz in [3.0, 40.0] {
        let w = 2.0 * PI * f_hz;
        // In contact throughout, and 1 + χ·ẋ > 0.
        assert!(chi * w * a.hypot(b) < 1.0);
        let r = evaluate(&el, &h, &u, w, true, &AftSettings::default());
        let mut exact = vec![0.0; h.len()];
        exact[0] = k * d0;
        exact[c1] = k * a + k * chi * d0 * w * b;
        exact[s1] = k * b - k * chi * d0 * w * a;
        exact[c2] = k * chi * w * a * b;
        exact[s2] = -k * chi * w * (a * a - b * b) / 2.0;
        let mut d_exact = vec![0.0; h.len()];
        d_exact[c1] = k * chi * d0 * b;
        d_exact[s1] = -k * chi * d0 * a;
        d_exact[c2] = k * chi * a * b;
        d_exact[s2] = -k * chi * (a * a - b * b) / 2.0;
        let scale = k * a;
        let err = r
            .forces
            .iter()
            .zip(&exact)
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs() / scale));
        let err_w = r
            .d_omega
            .iter()
            .zip(&d_exact)
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs() * w / scale));
        eprintln!("Hunt–Crossley n = 1 at {f_hz} Hz: forces {err:.1e}, ∂/∂ω {err_w:.1e}");
        assert!(
            err < 1e-12 && err_w < 1e-12,
            "{f_hz} Hz: {err:.2e}, {err_w:.2e}"
        );
    }
}

/// At vanishing amplitude a LuGre contact is the linear spring–damper `σ0·u + (σ1 + σ2)·u̇`
/// (`ż = u̇ − σ0·|u̇|·z/g` with `z ~ u`: the bristle term is smaller by `σ0·|u|/Fs`). A mass on
/// a spring rubbing on it, at an amplitude of 1e-14 m (`σ0·|u|/Fs ≈ 1e-10`), solved by the
/// harmonic balance, is the closed-form receptance of `m·ẍ + (c + σ1 + σ2)·ẋ + (k + σ0)·x`
/// within 1e-8, below and above resonance, with the same element.
#[test]
fn lugre_at_vanishing_amplitude_is_the_linear_spring_damper() {
    let p = lugre_params();
    let joint: Arc<dyn asperity::element::HystereticElement> = Arc::new(LuGre { params: p });
    let k = k_lin();
    let c = 2.0 * ZETA * (k * M).sqrt();
    let mut s = Structure::lumped(
        vec!["x".into()],
        DMatrix::from_element(1, 1, M),
        DMatrix::from_element(1, 1, c),
        DMatrix::from_element(1, 1, k),
    )
    .unwrap();
    s.attach("joint", joint, DMatrix::from_element(1, 1, 1.0))
        .unwrap();
    let mut sys = HbmSystem::new(
        &s,
        Harmonics::new(3, false, Some(64)).unwrap(),
        Excitation {
            force: DVector::from_element(1, 1.0),
            harmonic: 1,
            force_sin: None,
        },
        FormulationChoice::Coordinates,
    )
    .unwrap();
    sys.newton.tolerance = 1e-10;
    let (kt, ct) = (k + p.sigma0, c + p.sigma1 + p.sigma2);
    let wn = (kt / M).sqrt();
    let (ci, si) = sys.harmonics.index_of(1).unwrap();
    for ratio in [0.6, 1.0, 1.7] {
        let w = ratio * wn;
        let (re, im) = (kt - M * w * w, w * ct);
        let z2 = re * re + im * im;
        let level = 1e-14 * z2.sqrt();
        // x = Re(X·e^{iωt}), X = F/(re + i·im): a = Re X, b = −Im X.
        let (a, b) = (level * re / z2, level * im / z2);
        let point = sys.solve(w, level, None).unwrap();
        let x = sys.coordinates(&point);
        let err = (x[ci] - a).hypot(x[si] - b) / a.hypot(b);
        eprintln!("LuGre linear limit at {ratio}·ωn: relative {err:.1e} ({} iterations, residual {:.1e}, periodicity {:.1e})", point.iterations, point.residual, point.periodicity_error);
        assert!(err < 1e-8, "{ratio}·ωn: {err:.2e}");
    }
}

/// The harmonic-balance Jacobian and its frequency column with rate-dependent joints are exact:
/// two masses with a Hunt–Crossley stop (struck across its gap) and a LuGre contact between
/// them (in stick–slip), at a point near a solution: `J·δz` and `∂R/∂ω` against central
/// differences of the residual within 1e-6, in the coordinates and the receptance
/// formulations.
#[test]
fn rate_dependent_joints_give_an_exact_harmonic_balance_jacobian() {
    use asperity::element::HuntCrossley;
    let k = k_lin();
    let mut s = Structure::lumped(
        vec!["a".into(), "b".into()],
        DMatrix::from_row_slice(2, 2, &[M, 0.0, 0.0, 0.5 * M]),
        DMatrix::from_row_slice(2, 2, &[0.6, -0.2, -0.2, 0.4]),
        DMatrix::from_row_slice(2, 2, &[2.0 * k, -k, -k, 1.5 * k]),
    )
    .unwrap();
    s.attach(
        "stop",
        Arc::new(HuntCrossley {
            params: HuntCrossleyParams {
                stiffness: 2e5,
                exponent: 1.5,
                damping_factor: 0.5,
                gap: 1e-3,
            },
        }),
        DMatrix::from_row_slice(1, 2, &[1.0, 0.0]),
    )
    .unwrap();
    s.attach(
        "rub",
        Arc::new(LuGre {
            params: lugre_params(),
        }),
        DMatrix::from_row_slice(1, 2, &[1.0, -1.0]),
    )
    .unwrap();
    for choice in [
        FormulationChoice::Coordinates,
        FormulationChoice::Receptance,
    ] {
        let sys = HbmSystem::new(
            &s,
            Harmonics::new(9, false, Some(512)).unwrap(),
            Excitation {
                force: DVector::from_row_slice(&[1.0, 0.3]),
                harmonic: 1,
                force_sin: None,
            },
            choice,
        )
        .unwrap();
        let w = 2.0 * PI * 9.0;
        let mut guess = None;
        let mut p = None;
        for i in 1..=4 {
            let q = sys.solve(w, 5.0 * i as f64 / 4.0, guess.as_ref()).unwrap();
            guess = Some(q.z.clone());
            p = Some(q);
        }
        let p = p.unwrap();
        let z = &p.z * 1.02;
        let ev = sys.evaluate(&z, w, p.level, true);
        let dz = DVector::from_fn(z.len(), |i, _| ((i * 7919) % 13) as f64 / 13.0 - 0.5)
            * (z.amax() * 1e-6);
        let fd = (sys.evaluate(&(&z + &dz), w, p.level, false).residual
            - sys.evaluate(&(&z - &dz), w, p.level, false).residual)
            / 2.0;
        let exact = &ev.jacobian * &dz;
        let err = (&fd - &exact).amax() / exact.amax();
        let dw = w * 1e-6;
        let fd_w = (sys.evaluate(&z, w + dw, p.level, false).residual
            - sys.evaluate(&z, w - dw, p.level, false).residual)
            / (2.0 * dw);
        let err_w = (&fd_w - &ev.d_omega).amax() / ev.d_omega.amax();
        // Without the elements' frequency derivative the column would be off by their share.
        let x = sys.coordinates(&p);
        let tip = x.rows(0, sys.harmonics.len()).amax();
        eprintln!(
            "{:?}: Jacobian {err:.1e}, frequency column {err_w:.1e}, stop amplitude {tip:.2e}",
            sys.formulation()
        );
        assert!(tip > 1e-3, "the stop is not struck: {tip:.2e}");
        assert!(err < 1e-6, "{:?}: Jacobian {err:.2e}", sys.formulation());
        assert!(
            err_w < 1e-6,
            "{:?}: frequency column {err_w:.2e}",
            sys.formulation()
        );
    }
}

/// The model file's `hunt-crossley` and `lugre` joints: parameters with their units, the
/// damping of an impact from a coefficient of restitution (the exact relation), and errors
/// naming the file, the line and the key.
#[test]
fn model_file_joint_attaches_hunt_crossley_and_lugre_laws() {
    use asperity::dynamics::model_file::load;
    use asperity::element::{Kinematics, StepPartials};
    let dir = tempfile::tempdir().unwrap();
    let w = |name: &str, text: &str| std::fs::write(dir.path().join(name), text).unwrap();
    w("mass.csv", "# unit: kg\ntip.z\n1.0\n");
    w("damping.csv", "# unit: N*s/m\ntip.z\n1.0\n");
    w("stiffness.csv", "# unit: N/m\ntip.z\n1e4\n");
    let head = "[linear]\nmass = \"mass.csv\"\ndamping = \"damping.csv\"\nstiffness = \"stiffness.csv\"\n\n";
    let tail = "\n[excitation]\ndofs = [\"tip.z\"]\nlevels_n = [1.0]\n\n[response]\ndofs = [\"tip.z\"]\n\n\
                [sweep]\nfrequency_start_hz = 10.0\nfrequency_end_hz = 20.0\nharmonics = 3\n";
    let model = dir.path().join("model.toml");
    let hc = "[[joint]]\nlaw = \"hunt-crossley\"\nnode_a = \"tip\"\nnode_b = \"ground\"\n\
              direction = [0.0, 0.0, 1.0]\nk_n_per_m_pow_n = 2e5\nexponent = 1.5\n\
              static_indentation_m = -1e-3\nrestitution = 0.7\nimpact_velocity_m_per_s = 0.05\n";
    std::fs::write(&model, format!("{head}{hc}{tail}")).unwrap();
    let loaded = load(&model).unwrap();
    let el = &loaded.structure.elements[0].element;
    assert!(el.rate_dependent());
    // 0.5 mm past the 1 mm gap, closing at 0.1 m/s.
    let chi = damping_factor(0.7, 0.05).unwrap();
    let (mut f, mut p) = ([0.0], StepPartials::new(0, 1));
    let kin = Kinematics {
        dt: 1e-4,
        v0: &[0.1],
        v1: &[0.1],
    };
    el.step_at_rate(&[], &[1.4e-3], &[1.5e-3], kin, &mut [], &mut f, None);
    let exact = 2e5 * (5e-4f64).powf(1.5) * (1.0 + chi * 0.1);
    assert!((f[0] - exact).abs() < 1e-12 * exact, "{} vs {exact}", f[0]);
    el.step(&[], &[1.4e-3], &[1.5e-3], &mut [], &mut f, Some(&mut p));
    assert!((f[0] - 2e5 * (5e-4f64).powf(1.5)).abs() < 1e-15);
    // The damping factor given directly is the same joint.
    let direct = hc.replace(
        "restitution = 0.7\nimpact_velocity_m_per_s = 0.05\n",
        &format!("damping_factor_s_per_m = {chi:e}\n"),
    );
    std::fs::write(&model, format!("{head}{direct}{tail}")).unwrap();
    let el2 = load(&model).unwrap().structure.elements[0].element.clone();
    let mut f2 = [0.0];
    el2.step_at_rate(&[], &[1.4e-3], &[1.5e-3], kin, &mut [], &mut f2, None);
    el.step_at_rate(&[], &[1.4e-3], &[1.5e-3], kin, &mut [], &mut f, None);
    assert!((f2[0] - f[0]).abs() < 1e-12 * f[0]);
    let lugre = "[[joint]]\nlaw = \"lugre\"\nnode_a = \"tip\"\nnode_b = \"ground\"\n\
                 direction = [0.0, 0.0, 1.0]\nsigma0_n_per_m = 2e4\nsigma1_n_s_per_m = 5.0\n\
                 sigma2_n_s_per_m = 0.4\ncoulomb_force_n = 1.0\nstatic_force_n = 1.5\n\
                 stribeck_velocity_m_per_s = 0.01\n";
    std::fs::write(&model, format!("{head}{lugre}{tail}")).unwrap();
    let el = load(&model).unwrap().structure.elements[0].element.clone();
    assert_eq!(el.name(), "lugre");
    // Steady sliding at 0.3 m/s reaches the Stribeck curve Fc + (Fs − Fc)·e^{−900} + σ2·v.
    let (mut z, mut f) = ([0.0], [0.0]);
    for i in 0..200 {
        let kin = Kinematics {
            dt: 1e-3,
            v0: &[0.3],
            v1: &[0.3],
        };
        let (u0, u1) = (0.3e-3 * i as f64, 0.3e-3 * (i + 1) as f64);
        let mut z1 = [0.0];
        el.step_at_rate(&z, &[u0], &[u1], kin, &mut z1, &mut f, None);
        z = z1;
    }
    assert!((f[0] - (1.0 + 0.4 * 0.3)).abs() < 1e-12, "{}", f[0]);
    for (text, from, to, needles) in [
        (
            hc,
            "exponent = 1.5",
            "exponent = 0.5",
            vec!["model.toml:12", "exponent"],
        ),
        (
            hc,
            "static_indentation_m = -1e-3",
            "static_indentation_m = 1e-3",
            vec!["model.toml:13", "static_indentation_m", "bilinear"],
        ),
        (
            hc,
            "impact_velocity_m_per_s = 0.05\n",
            "",
            vec!["model.toml:", "impact_velocity_m_per_s"],
        ),
        (
            hc,
            "restitution = 0.7\nimpact_velocity_m_per_s = 0.05\n",
            "",
            vec!["model.toml:", "damping_factor_s_per_m", "restitution"],
        ),
        (
            hc,
            "restitution = 0.7\n",
            "restitution = 0.7\ndamping_factor_s_per_m = 1.0\n",
            vec!["model.toml:", "not both"],
        ),
        (
            hc,
            "restitution = 0.7",
            "restitution = 1.5",
            vec!["model.toml:14", "restitution"],
        ),
        (
            hc,
            "exponent = 1.5\n",
            "exponent = 1.5\nsample_rate = 1e4\n",
            vec!["model.toml:", "sample_rate"],
        ),
        (
            lugre,
            "static_force_n = 1.5",
            "static_force_n = 0.5",
            vec!["model.toml:15", "static_force_n"],
        ),
        (
            lugre,
            "sigma0_n_per_m = 2e4\n",
            "",
            vec!["model.toml:", "sigma0_n_per_m", "needs"],
        ),
        (
            lugre,
            "stribeck_velocity_m_per_s = 0.01",
            "stribeck_velocity_m_per_s = 0.0",
            vec!["model.toml:16", "stribeck_velocity_m_per_s"],
        ),
    ] {
        let bad = text.replace(from, to);
        assert_ne!(bad, text);
        std::fs::write(&model, format!("{head}{bad}{tail}")).unwrap();
        let e = load(&model).unwrap_err().to_string();
        for n in needles {
            assert!(e.contains(n), "{from} → {to}: {e}");
        }
    }
}

/// `asperity response` sweeps a vibro-impact oscillator (a Hunt–Crossley stop across a 1 mm
/// gap, struck at the higher level: the stop is open for part of every cycle) and a mass
/// rubbing on a LuGre contact, both to the end without warnings.
#[test]
fn response_sweeps_models_with_rate_dependent_joints() {
    let joints = [
        (
            "hunt-crossley",
            "[[joint]]\nlaw = \"hunt-crossley\"\nnode_a = \"tip\"\nnode_b = \"ground\"\n\
             direction = [0.0, 0.0, 1.0]\nk_n_per_m_pow_n = 2.0e5\nexponent = 1.5\n\
             static_indentation_m = -1.0e-3\nrestitution = 0.7\nimpact_velocity_m_per_s = 0.05\n",
            "[excitation]\ndofs = [\"tip.z\"]\nlevels_n = [1.0, 5.0]\n",
        ),
        (
            "lugre",
            "[[joint]]\nlaw = \"lugre\"\nnode_a = \"tip\"\nnode_b = \"ground\"\n\
             direction = [0.0, 0.0, 1.0]\nsigma0_n_per_m = 2.0e4\nsigma1_n_s_per_m = 5.0\n\
             sigma2_n_s_per_m = 0.4\ncoulomb_force_n = 1.0\nstatic_force_n = 1.5\n\
             stribeck_velocity_m_per_s = 0.01\n",
            "[excitation]\ndofs = [\"tip.z\"]\nlevels_n = [2.0, 8.0]\n",
        ),
    ];
    for (name, joint, excitation) in joints {
        let dir = tempfile::tempdir().unwrap();
        let w = |f: &str, text: &str| std::fs::write(dir.path().join(f), text).unwrap();
        w("mass.csv", "# unit: kg\ntip.z\n1.0\n");
        w("damping.csv", "# unit: N*s/m\ntip.z\n2.5\n");
        w("stiffness.csv", "# unit: N/m\ntip.z\n3948\n");
        w(
            "model.toml",
            &format!(
                "[linear]\nmass = \"mass.csv\"\ndamping = \"damping.csv\"\nstiffness = \"stiffness.csv\"\n\n\
                 {joint}\n{excitation}\n[response]\ndofs = [\"tip.z\"]\n\n\
                 [sweep]\nfrequency_start_hz = 5.0\nfrequency_end_hz = 25.0\npoints = 60\nharmonics = 15\n"
            ),
        );
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_asperity"))
            .arg("response")
            .arg(dir.path().join("model.toml"))
            .arg("--out-dir")
            .arg(dir.path().join("out"))
            .output()
            .unwrap();
        let err = format!(
            "{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        eprintln!("{name}:\n{err}");
        assert!(out.status.success(), "{name}: {err}");
        assert!(
            !err.contains("warning") && !err.contains("INCOMPLETE"),
            "{name}: {err}"
        );
        if name == "hunt-crossley" {
            let line = err.lines().find(|l| l.starts_with("level 5 N:")).unwrap();
            let sep: f64 = line
                .split("separation ")
                .nth(1)
                .and_then(|s| s.split(';').next())
                .and_then(|s| s.parse().ok())
                .unwrap();
            assert!(sep > 0.05 && sep < 0.95, "{line}");
        }
    }
}
