//! Free decay of a jointed structure (`dynamics::transient`) against the describing function:
//! a Jenkins slider on a single-degree-of-freedom oscillator rings down from twenty times its
//! stick limit; the envelope and the frequency read by peak picking follow the first-order
//! averaging equation `da/dt = −ζ(a)·ω(a)·a` with `ω(a)` and `ζ(a)` from Caughey's describing
//! function (the single-harmonic nonlinear mode of this oscillator).
//!
//! Model (SI units): `m = 1 kg, c = 1 N·s/m, k = 1e5 N/m`, Jenkins to ground `kt = 1e4 N/m`,
//! slip force 1 N (stick limit `a_y = 1e-4 m`); light damping (ζ ≤ kt/(2πk) + c/(2√(km)) ≈ 1.8 %),
//! where first-order averaging holds.

use asperity::dynamics::model::Structure;
use asperity::dynamics::transient::{free_decay, DecaySettings};
use asperity::element::Jenkins;
use nalgebra::{DMatrix, DVector};
use std::f64::consts::PI;
use std::sync::Arc;

const M: f64 = 1.0;
const C: f64 = 1.0;
const K: f64 = 1e5;
const KT: f64 = 1e4;
const FS: f64 = 1.0;

fn structure() -> Structure {
    let mut s = Structure::lumped(
        vec!["x".into()],
        DMatrix::from_element(1, 1, M),
        DMatrix::from_element(1, 1, C),
        DMatrix::from_element(1, 1, K),
    )
    .unwrap();
    s.attach(
        "jenkins",
        Arc::new(Jenkins::new(KT, FS).unwrap()),
        DMatrix::from_element(1, 1, 1.0),
    )
    .unwrap();
    s
}

/// Caughey's describing function of the Jenkins element (T. K. Caughey, *J. Appl. Mech.*
/// 27:640–643, 1960, zero post-yield slope): for `u = a·cos θ` the force's first harmonic is
/// `C·cos θ + S·sin θ` with, above the stick limit `a_y = Fs/kt` and `cos θ* = 1 − 2a_y/a`,
/// `C = (kt·a/π)·(θ* − ½·sin 2θ*)`, `S = −(4Fs/π)·(1 − a_y/a)`; `C = kt·a`, `S = 0` in stick.
/// The equivalent oscillator `m·ẍ + (c − S/(aω))·ẋ + (k + C/a)·x = 0` gives `ω(a)` and `ζ(a)`.
fn describing(a: f64) -> (f64, f64) {
    let ay = FS / KT;
    let (cc, ss) = if a <= ay {
        (KT * a, 0.0)
    } else {
        let t = (1.0 - 2.0 * ay / a).acos();
        (
            KT * a / PI * (t - 0.5 * (2.0 * t).sin()),
            -4.0 * FS / PI * (1.0 - ay / a),
        )
    };
    let w = ((K + cc / a) / M).sqrt();
    let zeta = (C - ss / (a * w)) / (2.0 * M * w);
    (w, zeta)
}

/// The averaging equation's envelope from `(t0, a0)` to `t1` (RK4, 2000 steps).
fn envelope(t0: f64, a0: f64, t1: f64) -> f64 {
    let rate = |a: f64| {
        let (w, z) = describing(a);
        -z * w * a
    };
    let n = 2000;
    let h = (t1 - t0) / n as f64;
    let mut a = a0;
    for _ in 0..n {
        let k1 = rate(a);
        let k2 = rate(a + 0.5 * h * k1);
        let k3 = rate(a + 0.5 * h * k2);
        let k4 = rate(a + h * k3);
        a += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
    }
    a
}

#[test]
fn jenkins_free_decay_follows_the_describing_function() {
    let s = structure();
    let settings = DecaySettings {
        mode: 1,
        amplitude_m: 2e-3,
        periods: 120,
        steps_per_period: 256,
    };
    let r = free_decay(&s, &DVector::from_element(1, 1.0), &settings, &mut |_| {}).unwrap();
    // The stuck structure's frequency: √((k + kt)/m).
    let f_stick = ((K + KT) / M).sqrt() / (2.0 * PI);
    assert!((r.linear_frequency_hz / f_stick - 1.0).abs() < 1e-12);
    assert!((r.response_m[0] - 2e-3).abs() < 1e-15);
    // From the first period on, the averaging equation's envelope, frequency and damping at
    // the period's amplitude. First-order averaging drops terms of the order of ζ·d ln ζ/d ln a
    // per period: small while the damping is light and varies slowly (a ≥ 4 a_y here, ζ ≤ 1.3 %),
    // growing to 5 % in the last periods of slip (1.5–3 a_y), where ζ(a) peaks at 1.8 %.
    let first = r.cycles[0];
    let ay = FS / KT;
    let (mut env, mut freq, mut damp, mut n_light) = (0.0f64, 0.0f64, 0.0f64, 0);
    let mut freq_slip = 0.0f64;
    for c in &r.cycles {
        let a_df = envelope(first.time_s, first.amplitude_m, c.time_s);
        let (w, z) = describing(c.amplitude_m);
        let e_f = (c.frequency_hz / (w / (2.0 * PI)) - 1.0).abs();
        if c.amplitude_m > 1.5 * ay {
            freq_slip = freq_slip.max(e_f);
        }
        if c.amplitude_m >= 4.0 * ay {
            n_light += 1;
            env = env.max((c.amplitude_m / a_df - 1.0).abs());
            freq = freq.max(e_f);
            damp = damp.max((c.damping_ratio / z - 1.0).abs());
        }
    }
    eprintln!(
        "a >= 4 a_y ({n_light} periods): envelope {env:.2e}, frequency {freq:.2e}, damping {damp:.2e}; \
         frequency over all of slip {freq_slip:.2e}"
    );
    assert!(n_light >= 20, "{n_light} periods");
    assert!(env < 0.02, "envelope {env}");
    assert!(damp < 0.02, "damping ratio {damp}");
    assert!(
        freq < 5e-4 && freq_slip < 5e-4,
        "frequency {freq} {freq_slip}"
    );
    // Ends stuck: the last periods ring at the stuck frequency with the viscous damping only.
    let last = r.cycles.last().unwrap();
    assert!(last.amplitude_m < ay);
    assert!((last.frequency_hz / f_stick - 1.0).abs() < 5e-4, "{last:?}");
    let zeta_stuck = C / (2.0 * (M * (K + KT)).sqrt());
    assert!(
        (last.damping_ratio / zeta_stuck - 1.0).abs() < 0.01,
        "{last:?}"
    );
}

/// `asperity decay` on the same oscillator written as a model file (the Jenkins law of the
/// contact section, slip force μ·N0 = 1 N): the files, the stuck frequency, the first period's
/// frequency against the describing function, and refused input without output.
#[test]
fn cli_decay_writes_the_ring_down_and_refuses_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let write = |name: &str, text: &str| std::fs::write(d.join(name), text).unwrap();
    write("mass.csv", "# unit: kg\nm.x\n1.0\n");
    write("stiffness.csv", "# unit: N/m\nm.x\n1e5\n");
    write("damping.csv", "# unit: N*s/m\nm.x\n1.0\n");
    write(
        "elements.csv",
        "# units: N0_N in N; kn, E0, Et in N/m\n\
         id,x_m,y_m,area_m2,pressure_Pa,N0_N,kn_N_per_m,E0_N_per_m,k,mu,Et_N_per_m,out_of_range\n\
         1,0,0,1e-6,1e6,1.0,1e6,1e4,0,1.0,0,0\n",
    );
    write("pairs.csv", "element_id,node_a,node_b\n1,m,ground\n");
    write(
        "model.toml",
        "[linear]\nmass = \"mass.csv\"\ndamping = \"damping.csv\"\nstiffness = \"stiffness.csv\"\n\n\
         [[contact]]\nelements = \"elements.csv\"\nlaw = \"jenkins\"\npairs = \"pairs.csv\"\n\
         normal = [0.0, 0.0, 1.0]\ntangent = [1.0, 0.0, 0.0]\n\n\
         [excitation]\ndofs = [\"m.x\"]\nlevels_n = [1.0]\n\n\
         [response]\ndofs = [\"m.x\"]\n\n\
         [sweep]\nfrequency_start_hz = 40\nfrequency_end_hz = 60\nharmonics = 1\n",
    );
    let run = |args: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_asperity"))
            .arg("decay")
            .arg(d.join("model.toml"))
            .args(args)
            .output()
            .unwrap()
    };
    let out = d.join("out");
    let o = run(&[
        "--amplitude-m",
        "2e-3",
        "--periods",
        "40",
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in ["decay.png", "decay_backbone.png"] {
        assert!(image::open(out.join(f)).is_ok(), "{f}");
    }
    let rows = |name: &str| -> Vec<Vec<f64>> {
        std::fs::read_to_string(out.join(name))
            .unwrap()
            .lines()
            .filter(|l| !l.starts_with('#'))
            .skip(1)
            .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
            .collect()
    };
    let history = rows("decay.csv");
    assert_eq!(history.len(), 40 * 256 + 1);
    assert!((history[0][1] - 2e-3).abs() < 1e-15);
    let cycles = rows("decay_cycles.csv");
    assert!(cycles.len() >= 30);
    let (w, z) = describing(cycles[0][1]);
    assert!(
        (cycles[0][2] / (w / (2.0 * PI)) - 1.0).abs() < 5e-4,
        "{:?}",
        cycles[0]
    );
    assert!((cycles[0][3] / z - 1.0).abs() < 0.02, "{:?}", cycles[0]);
    let text = String::from_utf8_lossy(&o.stdout);
    let f_stick = ((K + KT) / M).sqrt() / (2.0 * PI);
    assert!(text.contains(&format!("{f_stick:.4} Hz")), "{text}");
    // Refused, by flag, with nothing written.
    for (args, name) in [
        (vec!["--amplitude-m", "-1e-3"], "--amplitude-m"),
        (vec!["--amplitude-m", "nan"], "--amplitude-m"),
        (vec!["--amplitude-m", "1e-3", "--mode", "2"], "--mode"),
        (vec!["--amplitude-m", "1e-3", "--periods", "2"], "--periods"),
        (
            vec!["--amplitude-m", "1e-3", "--steps-per-period", "8"],
            "--steps-per-period",
        ),
    ] {
        let bad = d.join("bad");
        let mut a = args.clone();
        let bad_s = bad.to_str().unwrap().to_string();
        a.extend(["--out-dir", bad_s.as_str()]);
        let o = run(&a);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains(name), "{args:?}: {err}");
        assert!(!bad.join("decay.csv").exists());
    }
    // An output directory that is the model file is refused; the model is untouched.
    let model = d.join("model.toml");
    let before = std::fs::read(&model).unwrap();
    let o = run(&[
        "--amplitude-m",
        "1e-3",
        "--out-dir",
        model.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert_eq!(std::fs::read(&model).unwrap(), before);
}

/// The same ring-down against the nonlinear mode computed by the extended periodic motion
/// concept (`dynamics::nonlinear_modes`, harmonics 0..7, 1024 samples): the envelope of the
/// averaging equation with the EPMC's `ω(a)`, `ζ(a)` (interpolated in ln a), and the damping
/// ratio per period, within 2 % while the damping is light (a ≥ 4 a_y).
#[test]
fn jenkins_free_decay_follows_the_epmc_backbone() {
    use asperity::dynamics::aft::Harmonics;
    use asperity::dynamics::hbm::{Excitation, FormulationChoice, HbmSystem};
    use asperity::dynamics::nonlinear_modes::{log_spaced, nonlinear_mode, ModeSettings};
    let s = structure();
    let sys = HbmSystem::new(
        &s,
        Harmonics::new(7, false, Some(1024)).unwrap(),
        Excitation {
            force: DVector::zeros(1),
            harmonic: 1,
            force_sin: None,
        },
        FormulationChoice::Coordinates,
    )
    .unwrap();
    let ay = FS / KT;
    // m = 1 kg: the modal amplitude (m·kg^½) is the displacement amplitude.
    let amps = log_spaced(0.5 * ay, 25.0 * ay, 60).unwrap();
    let mode = nonlinear_mode(&sys, ModeSettings::new(1, amps), &mut |_| {}).unwrap();
    assert!(mode.stopped.is_none(), "{:?}", mode.stopped);
    let la: Vec<f64> = mode.points.iter().map(|p| p.amplitude.ln()).collect();
    let at = |a: f64, v: &dyn Fn(usize) -> f64| -> f64 {
        let x = a.ln();
        let i = la.partition_point(|&l| l <= x).clamp(1, la.len() - 1);
        let t = (x - la[i - 1]) / (la[i] - la[i - 1]);
        v(i - 1) + t * (v(i) - v(i - 1))
    };
    let omega = |a: f64| at(a, &|i| mode.points[i].omega);
    let zeta = |a: f64| at(a, &|i| mode.points[i].damping_ratio());
    let settings = DecaySettings {
        mode: 1,
        amplitude_m: 2e-3,
        periods: 120,
        steps_per_period: 256,
    };
    let r = free_decay(&s, &DVector::from_element(1, 1.0), &settings, &mut |_| {}).unwrap();
    let first = r.cycles[0];
    // RK4 of da/dt = −ζ(a)·ω(a)·a from the first period.
    let envelope = |t1: f64| {
        let n = 2000;
        let h = (t1 - first.time_s) / n as f64;
        let rate = |a: f64| -zeta(a) * omega(a) * a;
        let mut a = first.amplitude_m;
        for _ in 0..n {
            let k1 = rate(a);
            let k2 = rate(a + 0.5 * h * k1);
            let k3 = rate(a + 0.5 * h * k2);
            let k4 = rate(a + h * k3);
            a += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
        }
        a
    };
    let (mut env, mut damp, mut freq, mut n) = (0.0f64, 0.0f64, 0.0f64, 0);
    for c in r.cycles.iter().filter(|c| c.amplitude_m >= 4.0 * ay) {
        n += 1;
        env = env.max((c.amplitude_m / envelope(c.time_s) - 1.0).abs());
        damp = damp.max((c.damping_ratio / zeta(c.amplitude_m) - 1.0).abs());
        freq = freq.max((c.frequency_hz * 2.0 * PI / omega(c.amplitude_m) - 1.0).abs());
    }
    eprintln!(
        "against EPMC ({n} periods): envelope {env:.2e}, damping {damp:.2e}, frequency {freq:.2e}"
    );
    assert!(n >= 20);
    assert!(
        env < 0.02 && damp < 0.02 && freq < 1e-3,
        "{env} {damp} {freq}"
    );
}
