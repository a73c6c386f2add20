//! `asperity modes` end to end on a small lumped model (the two-mass model of
//! tests/response_cli.rs): the backbone runs from the linear mode with the elements stuck to the
//! mode with them slipping (both closed-form eigenvalues of 2 × 2 problems), every file is
//! written with its units, and bad input is refused with the parameter named and nothing written.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args(args)
        .output()
        .expect("runs")
}

const ELEMENTS: &str = "# units: N0_N in N; kn, E0, Et in N/m\n\
id,x_m,y_m,area_m2,pressure_Pa,N0_N,kn_N_per_m,E0_N_per_m,k,mu,Et_N_per_m,out_of_range\n\
7,0,0,1e-6,2e6,2.0,1e6,2.0e4,0.3,0.5,0,0\n\
11,0,0,1e-6,2e6,1.0,1e6,1.0e4,0.5,0.5,0,0\n";

/// Two masses (m1 on a ground spring, m2 on m1); the element table joins m2 to ground along x.
fn write_model(dir: &Path, elements: &str) -> PathBuf {
    let w = |name: &str, text: &str| std::fs::write(dir.join(name), text).unwrap();
    w("mass.csv", "# unit: kg\nm1.x,m2.x\n1.0,0\n0,0.5\n");
    w(
        "stiffness.csv",
        "# unit: N/m\nm1.x,m2.x\n6e4,-2e4\n-2e4,2e4\n",
    );
    w("damping.csv", "# unit: N*s/m\nm1.x,m2.x\n2,0\n0,1\n");
    w(elements, ELEMENTS);
    w(
        "pairs.csv",
        "element_id,node_a,node_b\n7,m2,ground\n11,m2,ground\n",
    );
    let model = format!("[linear]\nmass = \"mass.csv\"\ndamping = \"damping.csv\"\nstiffness = \"stiffness.csv\"\n\n\
[[contact]]\nelements = \"{elements}\"\nlaw = \"valanis\"\npairs = \"pairs.csv\"\n\
normal = [0.0, 0.0, 1.0]\ntangent = [1.0, 0.0, 0.0]\n\n\
[excitation]\ndofs = [\"m1.x\"]\nlevels_n = [0.02, 0.5]\n\n\
[response]\ndofs = [\"m1.x\", \"m2.x\"]\n\n\
[sweep]\nfrequency_start_hz = 15.0\nfrequency_end_hz = 50.0\npoints = 15\nharmonics = 3\nodd_only = true\n");
    w("model.toml", &model);
    dir.join("model.toml")
}

/// Lowest eigenvalue of `det(K − λM) = 0` for `K = [[k11, k12], [k12, k22]]`, `M = diag(m1, m2)`.
fn lowest_frequency_hz(k11: f64, k12: f64, k22: f64, m1: f64, m2: f64) -> f64 {
    let (a, b, c) = (m1 * m2, -(k11 * m2 + k22 * m1), k11 * k22 - k12 * k12);
    let lambda = (-b - (b * b - 4.0 * a * c).sqrt()) / (2.0 * a);
    lambda.sqrt() / (2.0 * std::f64::consts::PI)
}

/// From stick (the elements' E0 = 3e4 N/m in parallel at m2) to gross slip (Et = 0: the chain
/// alone): the first and last backbone frequencies against the two closed-form eigenvalues
/// (0.1 % at the smallest amplitude, where the microslip softening is of order a/slip onset
/// ≈ 1e-4; 3 % at the largest, where the slip force adds an equivalent stiffness of about 1 %);
/// the frequency falls monotonically, the damping ratio rises above the viscous one, and the
/// energy balance closes.
#[test]
fn modes_runs_from_stick_to_slip() {
    let dir = tempfile::tempdir().unwrap();
    let model = write_model(dir.path(), "elements.csv");
    let out = dir.path().join("out");
    let o = run(&[
        "modes",
        model.to_str().unwrap(),
        "--amplitude-min-m-sqrt-kg",
        "1e-9",
        "--amplitude-max-m-sqrt-kg",
        "1e-2",
        "--points",
        "30",
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    for f in [
        "modes.csv",
        "modes_shapes.csv",
        "modes_elements.csv",
        "modes_synthesis.csv",
        "modes.png",
        "modes.json",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let csv = std::fs::read_to_string(out.join("modes.csv")).unwrap();
    assert!(csv.contains("# units:"));
    let mut lines = csv.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    for name in [
        "modal_amplitude_m_sqrt_kg",
        "frequency_Hz",
        "damping_ratio",
        "element_energy_J",
        "energy_balance_error",
        "m2.x_h1_amplitude_m",
    ] {
        assert!(header.contains(&name), "column {name} in {header:?}");
    }
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 30);
    let (f, z) = (col("frequency_Hz"), col("damping_ratio"));
    let stuck = lowest_frequency_hz(6e4, -2e4, 2e4 + 3e4, 1.0, 0.5);
    let slipping = lowest_frequency_hz(6e4, -2e4, 2e4, 1.0, 0.5);
    let (first, last) = (rows[0][f], rows[29][f]);
    assert!(
        (first / stuck - 1.0).abs() < 1e-3,
        "{first} Hz at the smallest amplitude, stuck {stuck} Hz"
    );
    assert!(
        last > slipping && last / slipping - 1.0 < 3e-2,
        "{last} Hz at the largest amplitude, slipping {slipping} Hz"
    );
    assert!(rows.windows(2).all(|w| w[1][f] <= w[0][f] * (1.0 + 1e-9)));
    assert!(rows.iter().map(|r| r[z]).fold(0.0, f64::max) > 3.0 * rows[0][z]);
    // The energy balance closes to the trapezoidal rule's error over 64 samples,
    // about (2π/64)²/12 ≈ 8e-4 of a smooth loop's energy.
    let balance = col("energy_balance_error");
    assert!(rows.iter().all(|r| r[balance] < 3e-3));
    assert!(stdout.contains("30 of 30 amplitudes"), "{stdout}");
}

/// Bad input: a mode beyond the model's, an element table named like an output, an empty
/// amplitude range — an error naming the parameter or the file, exit 1, nothing written.
#[test]
fn modes_refuses_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let model = write_model(dir.path(), "elements.csv");
    let out = dir.path().join("out");
    for (args, expected) in [
        (vec!["--mode", "3"], "--mode"),
        (
            vec![
                "--amplitude-min-m-sqrt-kg",
                "1e-3",
                "--amplitude-max-m-sqrt-kg",
                "1e-4",
            ],
            "--amplitude-max-m-sqrt-kg",
        ),
        (vec!["--points", "1"], "--points"),
    ] {
        let mut a = vec!["modes", model.to_str().unwrap()];
        a.extend(args);
        a.extend(["--out-dir", out.to_str().unwrap()]);
        let o = run(&a);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{stderr}");
        assert!(stderr.contains(expected), "{expected}: {stderr}");
        assert!(!out.exists(), "nothing written");
    }
    // An element table that would be overwritten by an output.
    let model = write_model(dir.path(), "modes.csv");
    let o = run(&[
        "modes",
        model.to_str().unwrap(),
        "--out-dir",
        dir.path().to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("modes.csv") && stderr.contains("contact 1 elements"),
        "{stderr}"
    );
    assert_eq!(
        std::fs::read_to_string(dir.path().join("modes.csv")).unwrap(),
        ELEMENTS
    );
}
