//! `asperity contact normal` end to end: outputs and error paths (non-zero exit, message naming
//! the parameter, no output left behind). Units: SI.

use std::path::Path;
use std::process::Command;

fn asperity(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args(args)
        .output()
        .expect("run asperity");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn assert_no_output(dir: &Path) {
    if dir.exists() {
        let left: Vec<_> = std::fs::read_dir(dir).unwrap().collect();
        assert!(left.is_empty(), "output left behind: {left:?}");
    }
}

#[test]
fn bad_parameters_fail_cleanly() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let out_s = out.to_str().unwrap();
    for (args, needle) in [
        (vec!["--pressures-pa", "0"], "--pressures-pa"),
        (vec!["--pressures-pa", "1e6,-2e6"], "--pressures-pa"),
        (vec!["--pressures-pa", "NaN"], "--pressures-pa"),
        (vec!["--pressures-pa", "1e6,1e6"], "twice"),
        (vec!["--poisson-ratio", "0.7"], "--poisson-ratio"),
        (vec!["--youngs-modulus-pa=-2e11"], "--youngs-modulus-pa"),
        (vec!["--tolerance", "0"], "--tolerance"),
        (vec!["--method", "multigrid"], "--method"),
    ] {
        let mut full = vec!["contact", "normal", "--out-dir", out_s];
        full.extend(args.iter());
        let (ok, _, err) = asperity(&full);
        assert!(!ok, "{args:?} should fail");
        assert!(err.contains(needle), "{args:?}: {err}");
        assert_no_output(&out);
    }
}

#[test]
fn non_convergence_is_an_error_without_output() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let (ok, _, err) = asperity(&[
        "contact",
        "normal",
        "--out-dir",
        out.to_str().unwrap(),
        "--pressures-pa",
        "1e6",
        "--max-iterations",
        "2",
    ]);
    assert!(!ok);
    assert!(err.contains("did not converge"), "{err}");
    assert_no_output(&out);
}

/// A small periodic height matrix: sum of two cosines (heights in m, 32² points of 1 µm).
fn write_wavy_matrix(path: &Path, nan_at: Option<(usize, usize)>) {
    let n = 32;
    let mut text = String::from(
        "# asperity height matrix\n# unit: m, dx_m: 1e-6, dy_m: 1e-6, periodic: true\n",
    );
    for j in 0..n {
        let row: Vec<String> = (0..n)
            .map(|i| {
                if nan_at == Some((i, j)) {
                    return "nan".to_string();
                }
                let (x, y) = (i as f64 / n as f64, j as f64 / n as f64);
                let h = 0.2e-6
                    * ((2.0 * std::f64::consts::PI * x).cos()
                        + (2.0 * std::f64::consts::PI * y).cos())
                    + 0.05e-6 * (6.0 * std::f64::consts::PI * x).sin();
                format!("{h:e}")
            })
            .collect();
        text.push_str(&row.join(", "));
        text.push('\n');
    }
    std::fs::write(path, text).unwrap();
}

#[test]
fn sweep_on_a_surface_file_writes_csv_and_plots() {
    let tmp = tempfile::tempdir().unwrap();
    let surf = tmp.path().join("wavy.txt");
    write_wavy_matrix(&surf, None);
    let out = tmp.path().join("out");
    let (ok, stdout, err) = asperity(&[
        "contact",
        "normal",
        "--surface",
        surf.to_str().unwrap(),
        "--pressures-pa",
        "20e6,5e6,50e6",
        "--out-dir",
        out.to_str().unwrap(),
        "--pressure-maps",
    ]);
    assert!(ok, "{err}");
    assert!(stdout.contains("β ="), "{stdout}");
    let csv = std::fs::read_to_string(out.join("normal_sweep.csv")).unwrap();
    let mut lines = csv.lines().filter(|l| !l.starts_with('#'));
    let header = lines.next().unwrap();
    assert!(header.starts_with("surface,pressure_Pa,contact_area_ratio,mean_gap_m,kn_N_per_m3"));
    let label = surf.to_str().unwrap();
    let rows: Vec<Vec<f64>> = lines
        .map(|l| {
            let (surface, values) = l.split_once(',').unwrap();
            assert_eq!(surface, label);
            values
                .split(',')
                .take(4)
                .map(|v| v.parse().unwrap())
                .collect()
        })
        .collect();
    assert_eq!(rows.len(), 3);
    // Sorted by pressure; area grows, mean gap closes, kn rises.
    assert_eq!(rows[0][0], 5e6);
    for w in rows.windows(2) {
        assert!(w[1][0] > w[0][0] && w[1][1] > w[0][1] && w[1][2] < w[0][2] && w[1][3] > w[0][3]);
    }
    for f in [
        "area_ratio.png",
        "mean_gap.png",
        "kn.png",
        "pressure_map_5e6Pa.png",
        "pressure_map_2e7Pa.png",
        "pressure_map_5e7Pa.png",
    ] {
        assert!(image::open(out.join(f)).is_ok(), "{f}");
    }
}

#[test]
fn nan_surface_and_missing_file_fail_cleanly() {
    let tmp = tempfile::tempdir().unwrap();
    let surf = tmp.path().join("nan.txt");
    write_wavy_matrix(&surf, Some((3, 5)));
    let out = tmp.path().join("out");
    let (ok, _, err) = asperity(&[
        "contact",
        "normal",
        "--surface",
        surf.to_str().unwrap(),
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(err.contains("nan.txt"), "{err}");
    assert_no_output(&out);
    let (ok, _, err) = asperity(&[
        "contact",
        "normal",
        "--surface",
        tmp.path().join("absent.npy").to_str().unwrap(),
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(err.contains("absent.npy"), "{err}");
    assert_no_output(&out);
}
