//! End-to-end tests of `asperity calibrate`: the whole chain on a coarse grid (the full 1024²
//! reference run belongs to the CLI and BENCHMARKS.md), outputs, sidecar, and refused configs.

use asperity::calibrate::table::CalibrationTable;
use sha2::{Digest, Sha256};
use std::path::Path;
use std::process::{Command, Output};

fn asperity(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args(args)
        .output()
        .expect("run asperity")
}

fn reference_config() -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("calib/reference.toml"))
        .unwrap()
}

#[test]
fn reference_chain_on_a_coarse_grid_writes_table_plots_and_sidecar() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("calib");
    let o = asperity(&[
        "calibrate",
        "--grid",
        "256",
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("k(p):"), "{stdout}");

    let table = CalibrationTable::read_csv(&out.join("calibration_table.csv")).unwrap();
    let p: Vec<f64> = table.rows.iter().map(|r| r.pressure_pa).collect();
    assert_eq!(p, vec![0.1e6, 0.2e6, 1e6, 2e6, 5e6, 10e6]);
    for w in table.rows.windows(2) {
        assert!(w[1].kn_n_per_m3 > w[0].kn_n_per_m3, "kn not rising: {w:?}");
        assert!(w[1].contact_area_ratio > w[0].contact_area_ratio);
        // Energy per cycle grows with pressure (the loops scale with μp and δ_gs).
        assert!(w[1].energy_per_cycle_j_per_m2 > w[0].energy_per_cycle_j_per_m2);
    }
    let nu: f64 = 0.3;
    let mindlin = 2.0 * (1.0 - nu) / (2.0 - nu);
    for r in &table.rows {
        assert_eq!(r.mu, 0.6);
        assert_eq!(r.et_n_per_m3, 0.0);
        assert!(r.fit_r2 > 0.98, "R² {} at {} Pa", r.fit_r2, r.pressure_pa);
        // Independent physics check: after reversal from gross slip the Valanis slope is
        // 2E0/(1+k); the BEM loop's unloading slope equals its initial tangential stiffness,
        // which for quasi-identical elastic bodies is Mindlin's kt = kn·2(1−ν)/(2−ν).
        let reload = 2.0 * r.e0_n_per_m3 / (1.0 + r.k);
        let kt = mindlin * r.kn_n_per_m3;
        assert!(
            (reload / kt - 1.0).abs() < 0.3,
            "reload slope {reload:e} vs Mindlin kt {kt:e} at {} Pa",
            r.pressure_pa
        );
    }
    for f in [
        "calibration_fits.csv",
        "calibration_loops.csv",
        "kn_vs_pressure.png",
        "e0_vs_pressure.png",
        "k_vs_pressure.png",
        "loops_normalised.png",
        "loop_fit_100000Pa.png",
        "loop_fit_10000000Pa.png",
    ] {
        assert!(out.join(f).is_file(), "missing {f}");
    }
    let img = image::open(out.join("k_vs_pressure.png")).unwrap();
    assert!(img.width() > 100);

    let sidecar: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("calibration.json")).unwrap())
            .unwrap();
    assert_eq!(sidecar["crate_version"], env!("CARGO_PKG_VERSION"));
    assert_eq!(sidecar["config_source"], "built-in reference case");
    assert_eq!(sidecar["config"]["surface"]["nx"], 256);
    let table_bytes = std::fs::read(out.join("calibration_table.csv")).unwrap();
    let table_sha = format!("{:x}", Sha256::digest(&table_bytes));
    assert_eq!(sidecar["outputs"]["table_sha256"], table_sha.as_str());
    assert_eq!(
        sidecar["input_hashes"]["surface_heights_sha256"]
            .as_str()
            .unwrap()
            .len(),
        64
    );
    assert!(sidecar["summary"]["k_shape"].as_str().unwrap().len() > 10);
}

#[test]
fn config_file_run_records_the_file_hash() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("small.toml");
    let text = reference_config()
        .replace("nx = 1024", "nx = 128")
        .replace("ny = 1024", "ny = 128")
        .replace(
            "pressures_pa = [1e5, 2e5, 1e6, 2e6, 5e6, 1e7]",
            "pressures_pa = [1e6, 5e6]",
        );
    std::fs::write(&cfg, &text).unwrap();
    let out = dir.path().join("out");
    let o = asperity(&[
        "calibrate",
        cfg.to_str().unwrap(),
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let table = CalibrationTable::read_csv(&out.join("calibration_table.csv")).unwrap();
    assert_eq!(table.rows.len(), 2);
    let sidecar: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("calibration.json")).unwrap())
            .unwrap();
    let sha = format!("{:x}", Sha256::digest(text.as_bytes()));
    assert_eq!(sidecar["input_hashes"]["config_file_sha256"], sha.as_str());
    assert_eq!(sidecar["config"]["loading"]["pressures_pa"][1], 5e6);
}

#[test]
fn invalid_configs_are_refused_naming_the_key_without_output() {
    let dir = tempfile::tempdir().unwrap();
    let base = reference_config();
    let cases: [(&str, &str, &str); 6] = [
        ("[fit]\n", "[fit]\nk_initial = 0.5\n", "k_initial"),
        (
            "k_starts = [0.1, 0.5, 0.9]",
            "k_starts = [0.1, 1.0]",
            "fit.k_starts",
        ),
        ("mu = 0.6 ", "mu = -0.6 ", "contact.mu"),
        (
            "pressures_pa = [1e5, 2e5,",
            "pressures_pa = [2e5, 1e5,",
            "loading.pressures_pa",
        ),
        (
            "pressures_pa = [1e5,",
            "pressures_pa = [-1e5,",
            "loading.pressures_pa",
        ),
        ("[surface]", "[surfaces]", "surfaces"),
    ];
    for (i, (from, to, key)) in cases.iter().enumerate() {
        assert!(base.contains(from), "{from}");
        let cfg = dir.path().join(format!("bad{i}.toml"));
        std::fs::write(&cfg, base.replacen(from, to, 1)).unwrap();
        let out = dir.path().join(format!("out{i}"));
        let o = asperity(&[
            "calibrate",
            cfg.to_str().unwrap(),
            "--out-dir",
            out.to_str().unwrap(),
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{err}");
        assert!(err.contains(key), "case {i}: {err}");
        assert!(err.contains(&format!("bad{i}.toml")), "case {i}: {err}");
        assert!(!out.exists(), "case {i}: output written");
    }
    // Missing file and a grid override that under-resolves the correlation length.
    let o = asperity(&["calibrate", "/nonexistent/cal.toml"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("/nonexistent/cal.toml"));
    let out = dir.path().join("coarse");
    let o = asperity(&[
        "calibrate",
        "--grid",
        "16",
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--grid"));
    assert!(!out.exists());
}
