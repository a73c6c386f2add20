//! A static force (a preload that does not scale with the excitation level, `[static]` in the
//! model file) balanced by the response's mean in the harmonic balance
//! (`HbmSystem::with_static_force`), against closed forms: a Duffing oscillator preloaded by
//! `F0` sits at the root of `k·x0 + k3·x0³ = F0` and vibrates, at small amplitude, as the linear
//! oscillator of stiffness `k + 3·k3·x0²` about it.

use asperity::dynamics::aft::Harmonics;
use asperity::dynamics::hbm::{Excitation, FormulationChoice, HbmSystem, NewtonSettings};
use asperity::dynamics::model::Structure;
use asperity::element::CubicSpring;
use nalgebra::{DMatrix, DVector};
use realfft::num_complex::Complex64;
use std::f64::consts::TAU;
use std::path::Path;
use std::process::{Command, Output};
use std::sync::Arc;

/// The real root of `k·x + k3·x³ = f` (Newton from the linear solution; monotone function).
fn static_root(k: f64, k3: f64, f: f64) -> f64 {
    let mut x = (f / k3).cbrt().min(f / k);
    for _ in 0..100 {
        let step = (k * x + k3 * x.powi(3) - f) / (k + 3.0 * k3 * x * x);
        x -= step;
        if step.abs() < 1e-17 * x.abs() {
            break;
        }
    }
    x
}

#[test]
fn preloaded_duffing_oscillator_vibrates_about_its_static_equilibrium() {
    let (m, c, k, k3, f0) = (1.0, 2.0, 1e4, 1e12, 50.0);
    let one = |v: f64| DMatrix::from_element(1, 1, v);
    let mut s = Structure::lumped(vec!["mass.x".into()], one(m), one(c), one(k)).unwrap();
    s.attach("duffing", Arc::new(CubicSpring { k3 }), one(1.0))
        .unwrap();
    let h = Harmonics::new(3, false, None).unwrap();
    let excitation = Excitation {
        force: DVector::from_element(1, 1.0),
        harmonic: 1,
        force_sin: None,
    };
    let mut sys = HbmSystem::new(&s, h.clone(), excitation, FormulationChoice::Coordinates)
        .unwrap()
        .with_static_force(&DVector::from_element(1, f0))
        .unwrap();
    sys.newton = NewtonSettings {
        tolerance: 1e-13,
        max_iterations: 100,
    };
    let x0 = static_root(k, k3, f0);
    let k_eff = k + 3.0 * k3 * x0 * x0;
    let f_lin = (k_eff / m).sqrt() / TAU;
    // Without the preload the oscillator would resonate at 15.9 Hz; about x0 at 100.3 Hz.
    assert!((f_lin - 100.33).abs() < 0.01, "{f_lin}");
    let (ci, si) = h.index_of(1).unwrap();
    // A small level: the vibration's own nonlinearity (its amplitude-dependent frequency
    // shift, amplified by Q ≈ 320 at the resonance) stays below 1e-6 of the response.
    let level = 1e-5;
    let mut guess: Option<DVector<f64>> = None;
    for ratio in [0.5, 0.8, 0.95, 1.0, 1.05, 1.2, 1.5] {
        let w = TAU * f_lin * ratio;
        let p = sys.solve(w, level, guess.as_ref()).unwrap();
        let q = sys.coordinates(&p);
        // The mean: the static equilibrium, shifted only by the vibration's second order
        // (3·k3·x0·A²/(2·k_eff), below 1e-9 of x0 at the resonance's 8 nm).
        assert!(
            (q[0] / x0 - 1.0).abs() < 1e-8,
            "{ratio}: mean {:.9e} against x0 {x0:.9e}",
            q[0]
        );
        // The first harmonic: the linear oscillator about x0, X = F/(k_eff − mω² + icω).
        let x = Complex64::new(q[ci], -q[si]);
        let want = level / Complex64::new(k_eff - m * w * w, c * w);
        assert!(
            (x - want).norm() < 1e-4 * want.norm(),
            "{ratio}: X {x:.6e} against {want:.6e}"
        );
        guess = Some(p.z);
    }
    // The preload is needed: without it the same system vibrates about zero.
    let free = HbmSystem::new(
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
    let p = free.solve(TAU * f_lin, level, None).unwrap();
    assert!(free.coordinates(&p)[0].abs() < 1e-12);
}

fn asperity(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args(args)
        .output()
        .expect("runs")
}

/// A linear oscillator `m = 1 kg`, `k = 1e4 N/m`, `c = 2 N·s/m` with `[static]`.
fn write_model(dir: &Path, odd_only: bool) -> String {
    std::fs::write(dir.join("mass.csv"), "# unit: kg\nm.x\n1.0\n").unwrap();
    std::fs::write(dir.join("stiffness.csv"), "# unit: N/m\nm.x\n1e4\n").unwrap();
    std::fs::write(dir.join("damping.csv"), "# unit: N*s/m\nm.x\n2.0\n").unwrap();
    let model = dir.join("model.toml");
    std::fs::write(
        &model,
        format!(
            "[linear]\nmass = \"mass.csv\"\ndamping = \"damping.csv\"\nstiffness = \"stiffness.csv\"\n\n\
[static]\ndofs = [\"m.x\"]\nforces_n = [30.0]\n\n\
[excitation]\ndofs = [\"m.x\"]\nlevels_n = [1.0]\n\n\
[response]\ndofs = [\"m.x\"]\n\n\
[sweep]\nfrequency_start_hz = 10.0\nfrequency_end_hz = 20.0\npoints = 10\nharmonics = 1\nodd_only = {odd_only}\n"
        ),
    )
    .unwrap();
    model.to_str().unwrap().to_string()
}

#[test]
fn response_balances_the_static_section_and_other_commands_refuse_it() {
    let dir = tempfile::tempdir().unwrap();
    let model = write_model(dir.path(), false);
    let out = dir.path().join("out");
    let o = asperity(&["response", &model, "--out-dir", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let csv = std::fs::read_to_string(out.join("response_level_1.csv")).unwrap();
    let mut lines = csv.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = header.iter().position(|h| *h == "m.x_h0_mean_m").unwrap();
    let mut rows = 0;
    for l in lines {
        let mean: f64 = l.split(',').nth(col).unwrap().parse().unwrap();
        // F0/k = 3 mm at every frequency (the CSV keeps 10 significant digits).
        assert!((mean / 3e-3 - 1.0).abs() < 1e-8, "mean {mean}");
        rows += 1;
    }
    assert!(rows >= 10);
    // The mean needs harmonic 0.
    let bad = write_model(dir.path(), true);
    let o = asperity(&["response", &bad, "--out-dir", out.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("odd_only"), "{err}");
    // Modes and decay do not solve the preload: refused, naming the section.
    let model = write_model(dir.path(), false);
    for args in [
        vec!["modes", &model, "--out-dir"],
        vec!["decay", &model, "--amplitude-m", "1e-4", "--out-dir"],
    ] {
        let mut args = args.clone();
        let o_dir = dir.path().join(args[0]);
        let o_dir = o_dir.to_str().unwrap().to_string();
        args.push(&o_dir);
        let o = asperity(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success() && err.contains("[static]"),
            "{}: {err}",
            args[0]
        );
    }
}
