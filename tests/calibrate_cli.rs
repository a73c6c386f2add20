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

/// `asperity calibrate <cfg> --surface <each file> --out-dir <out> <extra>`.
fn calibrate_surfaces(cfg: &Path, surfaces: &[&Path], out: &Path, extra: &[&str]) -> Output {
    let mut a = vec!["calibrate", cfg.to_str().unwrap()];
    for f in surfaces {
        a.extend(["--surface", f.to_str().unwrap()]);
    }
    a.extend(["--out-dir", out.to_str().unwrap()]);
    a.extend_from_slice(extra);
    asperity(&a)
}

/// `asperity contact tangential --surface <file> <extra>` at 10 MPa, one cycle of 8 steps.
fn tangential_on(surface: &Path, out: &Path, extra: &[&str]) -> Output {
    let mut a = vec![
        "contact",
        "tangential",
        "--surface",
        surface.to_str().unwrap(),
        "--pressures-pa",
        "1e7",
        "--cycles",
        "1",
        "--steps-per-cycle",
        "8",
        "--out-dir",
        out.to_str().unwrap(),
    ];
    a.extend_from_slice(extra);
    asperity(&a)
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
        "--realisations",
        "3",
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("mean k(p):"), "{stdout}");
    assert!(stdout.contains("spots_per_patch"), "{stdout}");

    let table = CalibrationTable::read_csv(&out.join("calibration_table.csv")).unwrap();
    let p: Vec<f64> = table.rows.iter().map(|r| r.pressure_pa).collect();
    assert_eq!(p, vec![0.1e6, 0.2e6, 1e6, 2e6, 5e6, 10e6]);
    let intervals = table
        .intervals
        .as_ref()
        .expect("intervals over 3 realisations");
    assert!(intervals
        .iter()
        .all(|i| i.realisations == 3 && i.kn_n_per_m3 > 0.0));
    for w in table.rows.windows(2) {
        assert!(
            w[1].element.kn_n_per_m3 > w[0].element.kn_n_per_m3,
            "kn not rising: {w:?}"
        );
        assert!(w[1].contact_area_ratio > w[0].contact_area_ratio);
        // Energy per cycle at the largest amplitude grows with pressure (μp and δ_gs grow).
        assert!(w[1].energy_per_cycle_j_per_m2 > w[0].energy_per_cycle_j_per_m2);
    }
    let nu: f64 = 0.3;
    let mindlin = 2.0 * (1.0 - nu) / (2.0 - nu);
    for r in &table.rows {
        let e = &r.element;
        assert_eq!(e.mu, 0.6);
        assert_eq!(e.et_n_per_m3, 0.0);
        assert!(r.fit_r2 > 0.95, "R² {} at {} Pa", r.fit_r2, r.pressure_pa);
        // Independent physics check: the initial tangential stiffness of the contact is
        // Mindlin's kt = kn·2(1−ν)/(2−ν) for quasi-identical elastic bodies; the element's
        // stiffness lies between its initial slope E0 and its reload slope 2E0/(1+k).
        let kt = mindlin * e.kn_n_per_m3;
        let (lo, hi) = (e.e0_n_per_m3, 2.0 * e.e0_n_per_m3 / (1.0 + e.k));
        assert!(
            lo < 1.3 * kt && hi > 0.5 * kt,
            "E0 {lo:e} .. {hi:e} vs Mindlin kt {kt:e} at {} Pa",
            r.pressure_pa
        );
    }
    for f in [
        "calibration_realisations.csv",
        "calibration_fits.csv",
        "energy_vs_amplitude.csv",
        "calibration_convergence.csv",
        "calibration_loops.csv",
        "kn_vs_pressure.png",
        "e0_vs_pressure.png",
        "k_vs_pressure.png",
        "energy_vs_amplitude.png",
        "k_vs_amplitude.png",
        "loops_normalised.png",
        "loop_fit_100000Pa.png",
        "loop_fit_10000000Pa.png",
    ] {
        assert!(out.join(f).is_file(), "missing {f}");
    }
    let img = image::open(out.join("k_vs_pressure.png")).unwrap();
    assert!(img.width() > 100);
    // Long format: one row per realisation × pressure, and per realisation × pressure × amplitude.
    let rows = |f: &str| {
        std::fs::read_to_string(out.join(f))
            .unwrap()
            .lines()
            .count()
            - 1
    };
    assert_eq!(rows("calibration_realisations.csv"), 3 * 6);
    assert_eq!(rows("calibration_fits.csv"), 3 * 6 * 5);
    assert_eq!(rows("energy_vs_amplitude.csv"), 6 * 5);
    let fits = std::fs::read_to_string(out.join("calibration_fits.csv")).unwrap();
    assert!(fits.lines().next().unwrap().contains("energy_rel_error"));

    let sidecar: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("calibration.json")).unwrap())
            .unwrap();
    assert_eq!(sidecar["crate_version"], env!("CARGO_PKG_VERSION"));
    assert_eq!(sidecar["config_source"], "built-in reference case");
    assert_eq!(sidecar["config"]["surface"]["nx"], 256);
    assert_eq!(sidecar["config"]["realisations"]["count"], 3);
    let table_bytes = std::fs::read(out.join("calibration_table.csv")).unwrap();
    let table_sha = format!("{:x}", Sha256::digest(&table_bytes));
    assert_eq!(sidecar["outputs"]["table_sha256"], table_sha.as_str());
    let hashes = sidecar["input_hashes"]["surface_heights_sha256"]
        .as_array()
        .unwrap();
    assert_eq!(hashes.len(), 3);
    assert!(hashes.iter().all(|h| h.as_str().unwrap().len() == 64));
    assert_ne!(hashes[0], hashes[1]);
    let pressures = sidecar["convergence"]["pressures"].as_array().unwrap();
    assert_eq!(pressures.len(), 6);
    // The table's last column carries each row's worse verdict of the report's two checks.
    let verdicts = table.convergence.as_ref().expect("a convergence column");
    let rank = |v: &str| {
        ["converged", "not-checked", "undetermined", "not-converged"]
            .iter()
            .position(|&n| n == v)
            .unwrap()
    };
    for (pc, v) in pressures.iter().zip(verdicts) {
        let (g, p) = (
            pc["grid_verdict"].as_str().unwrap(),
            pc["patch_verdict"].as_str().unwrap(),
        );
        assert_eq!(v.name(), if rank(g) >= rank(p) { g } else { p }, "{pc}");
    }
    // A pressure whose element misses the BEM energy per cycle by more than a fifth at some
    // amplitude (energy_vs_amplitude.csv) is warned about, and only such a pressure.
    let energy = std::fs::read_to_string(out.join("energy_vs_amplitude.csv")).unwrap();
    let warnings: Vec<&str> = sidecar["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|w| w.as_str().unwrap())
        .collect();
    for p in [0.1, 0.2, 1.0, 2.0, 5.0, 10.0] {
        let worst = energy
            .lines()
            .skip(1)
            .map(|l| l.split(',').collect::<Vec<_>>())
            .filter(|f| f[0].parse::<f64>().unwrap() == p * 1e6)
            // Empty where the BEM energy is within its numerical floor (no error given).
            .filter_map(|f| f[7].parse::<f64>().ok().map(f64::abs))
            .fold(0.0, f64::max);
        let warned = warnings
            .iter()
            .any(|w| w.starts_with(&format!("{p} MPa: the fitted element's energy")));
        assert_eq!(warned, worst > 0.2, "{p} MPa: worst energy error {worst}");
    }
}

/// Near-stuck loops on a coarse grid: the BEM loop area at 0.2 × the gross-slip displacement can
/// be smaller than the solve resolves (at 128², 0.2 MPa, one such mean came out −4e-8 J/m², and
/// its "energy error" was printed as −114435 %). Every energy is compared with its numerical
/// floor (`4a·ε·μp_max·n_c/N`): below it no relative error is given (an empty
/// `mean_rel_error`) and a warning says so; above it the error is given. No warning states an
/// error of a thousand per cent or more.
#[test]
fn unresolved_small_energies_get_no_relative_error() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("calib");
    let o = asperity(&[
        "calibrate",
        "--grid",
        "128",
        "--realisations",
        "2",
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    let stderr = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(o.status.success(), "{stderr}");
    let energy = std::fs::read_to_string(out.join("energy_vs_amplitude.csv")).unwrap();
    let header: Vec<&str> = energy.lines().next().unwrap().split(',').collect();
    assert_eq!(header[7], "mean_rel_error");
    assert_eq!(header[8], "energy_floor_J_per_m2");
    let mut below = 0;
    for line in energy.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let (bem, floor): (f64, f64) = (f[3].parse().unwrap(), f[8].parse().unwrap());
        assert!(floor > 0.0 && floor.is_finite(), "{line}");
        if f[7].is_empty() {
            below += 1;
            assert!(bem <= floor, "no error given above the floor: {line}");
        } else {
            assert!(bem > floor, "an error given within the floor: {line}");
            f[7].parse::<f64>().unwrap();
        }
    }
    for w in stderr.lines().filter(|l| l.contains("energy per cycle")) {
        if let Some(pct) = w.split(" by ").nth(1).and_then(|r| r.split(' ').next()) {
            let v: f64 = pct.trim_start_matches('+').parse().unwrap();
            assert!(v.abs() < 1000.0, "{w}");
        }
    }
    if below > 0 {
        assert!(stderr.contains("within its numerical floor"), "{stderr}");
    }
}

/// A coarse grid (contact spots 1–3 points across) is flagged, with the pressure.
#[test]
fn coarse_grid_warns_about_under_resolved_spots() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("coarse");
    let o = asperity(&[
        "calibrate",
        "--grid",
        "128",
        "--realisations",
        "2",
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.contains("warning: 0.1 MPa: under-resolved contact spots"),
        "{stdout}"
    );
    assert!(stdout.contains("grid check not run"), "{stdout}");
    let sidecar: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("calibration.json")).unwrap())
            .unwrap();
    let warnings = sidecar["warnings"].as_array().unwrap();
    assert!(warnings
        .iter()
        .any(|w| w.as_str().unwrap().contains("under-resolved")));
}

/// A measured (non-periodic) surface in each writable format goes through the chain with the
/// zero-padded kernels and gives the same table; two files are combined into their
/// equivalent surface; a profile is refused.
#[test]
fn measured_surfaces_go_through_the_chain() {
    use asperity::surface::generate::{generate, GaussianSurfaceSpec};
    use asperity::Grid2;
    let dir = tempfile::tempdir().unwrap();
    // Two non-periodic 48 × 48 windows cut from a generated patch (0.49 µm spacing).
    let big = generate(&GaussianSurfaceSpec {
        nx: 256,
        ny: 256,
        lx_m: 125e-6,
        ly_m: 125e-6,
        ..GaussianSurfaceSpec::reference()
    })
    .unwrap();
    let window = |i0: usize| {
        Grid2::new(
            big.heights
                .slice(ndarray::s![i0..i0 + 48, i0..i0 + 48])
                .to_owned(),
            big.dx,
            big.dy,
            false,
        )
        .unwrap()
    };
    let (w1, w2) = (window(0), window(100));
    let cfg = dir.path().join("measured.toml");
    std::fs::write(
        &cfg,
        reference_config().replace(
            "pressures_pa = [1e5, 2e5, 1e6, 2e6, 5e6, 1e7]",
            "pressures_pa = [5e6, 1e7]",
        ),
    )
    .unwrap();
    let mut tables = Vec::new();
    for ext in ["npy", "x3p", "csv"] {
        let f = dir.path().join(format!("w1.{ext}"));
        asperity::surface::io::write(&f, &w1).unwrap();
        let out = dir.path().join(format!("out-{ext}"));
        let o = calibrate_surfaces(&cfg, &[&f], &out, &[]);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{ext}: {stderr}");
        assert!(
            stderr.contains("non-periodic (zero-padded kernels)"),
            "{stderr}"
        );
        let stdout = String::from_utf8_lossy(&o.stdout);
        assert!(stdout.contains("one realisation"), "{stdout}");
        let t = CalibrationTable::read_csv(&out.join("calibration_table.csv")).unwrap();
        assert!(t.intervals.is_none());
        assert_eq!(t.rows.len(), 2);
        tables.push(t);
    }
    // The three formats carry the same heights (x3p within its float precision).
    for t in &tables[1..] {
        for (a, b) in t.rows.iter().zip(&tables[0].rows) {
            assert!(
                (a.element.kn_n_per_m3 / b.element.kn_n_per_m3 - 1.0).abs() < 1e-4,
                "{a:?} vs {b:?}"
            );
            assert!(
                (a.element.e0_n_per_m3 / b.element.e0_n_per_m3 - 1.0).abs() < 1e-3,
                "{a:?} vs {b:?}"
            );
        }
    }
    // Two bodies.
    let (f1, f2) = (dir.path().join("b1.npy"), dir.path().join("b2.npy"));
    asperity::surface::io::write(&f1, &w1).unwrap();
    asperity::surface::io::write(&f2, &w2).unwrap();
    let out = dir.path().join("out-two");
    let o = calibrate_surfaces(&cfg, &[&f1, &f2], &out, &[]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert!(stderr.contains("equivalent surface h1 - h2"), "{stderr}");
    let two = CalibrationTable::read_csv(&out.join("calibration_table.csv")).unwrap();
    // The rougher equivalent surface (Rq √2 larger) is less stiff at the same pressure.
    assert!(two.rows[0].element.kn_n_per_m3 < tables[0].rows[0].element.kn_n_per_m3);
    // A profile is not an area; --grid does not apply to a file.
    let profile = Path::new(env!("CARGO_MANIFEST_DIR")).join("surfaces/example-profile.csv");
    let out = dir.path().join("out-profile");
    let o = asperity(&[
        "calibrate",
        "--surface",
        profile.to_str().unwrap(),
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("profile") && err.contains("example-profile.csv"),
        "{err}"
    );
    assert!(!out.exists());
    let o = asperity(&[
        "calibrate",
        "--surface",
        f1.to_str().unwrap(),
        "--grid",
        "64",
    ]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("--grid"));
    // contact tangential on the same measured file.
    let out = dir.path().join("tangential");
    let o = tangential_on(&f1, &out, &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("zero-padded"), "{err}");
    let csv = std::fs::read_to_string(out.join("tangential_loops.csv")).unwrap();
    assert!(
        csv.contains("periodic = false") && csv.contains("b1.npy"),
        "{csv}"
    );
    // The same body twice (a flat equivalent surface): refused before the sweep, naming it.
    let out = dir.path().join("out-same");
    let o = calibrate_surfaces(&cfg, &[&f1, &f1], &out, &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("b1.npy") && err.contains("identical bodies"),
        "{err}"
    );
    assert!(!out.exists());
    // Missing points: refused with the --fill flag named, and filled when it is given (calibrate
    // and contact tangential take it as contact normal does).
    let mut holed = w1.heights.clone();
    holed[[10, 10]] = f64::NAN;
    let fh = dir.path().join("holed.npy");
    let topo = asperity::surface::topography::Topography::from_heights(holed, w1.dx, w1.dy, false)
        .unwrap();
    asperity::surface::io::write_topography(&fh, &topo).unwrap();
    let out = dir.path().join("out-holed");
    let o = calibrate_surfaces(&cfg, &[&fh], &out, &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("holed.npy") && err.contains("--fill"),
        "{err}"
    );
    let o = calibrate_surfaces(&cfg, &[&fh], &out, &["--fill", "harmonic"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let json = std::fs::read_to_string(out.join("calibration.json")).unwrap();
    assert!(
        json.contains("1 of 2304 missing points filled, harmonic fill"),
        "{json}"
    );
    let out_t = dir.path().join("tangential-holed");
    let o = tangential_on(&fh, &out_t, &["--fill", "nearest"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn config_file_run_records_the_file_hash() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("small.toml");
    let text = reference_config()
        .replace("nx = 1024", "nx = 128")
        .replace("ny = 1024", "ny = 128")
        .replace("count = 8 ", "count = 2 ")
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
    assert_eq!(sidecar["config"]["realisations"]["count"], 2);
}

#[test]
fn invalid_configs_are_refused_naming_the_key_without_output() {
    let dir = tempfile::tempdir().unwrap();
    let base = reference_config();
    let cases: [(&str, &str, &str); 9] = [
        (
            "amplitude_factors = [0.2, 0.4,",
            "amplitude_factors = [0.4, 0.2,",
            "loading.amplitude_factors",
        ),
        ("count = 8 ", "count = 0 ", "realisations.count"),
        ("[fit]\n", "[fit]\nk_initial = 0.5\n", "k_initial"),
        (
            "k_starts = [0.1, 0.5, 0.9]",
            "k_starts = [0.1, 1.0]",
            "fit.k_starts",
        ),
        ("mu = 0.6 ", "mu = -0.6 ", "contact.mu"),
        ("mu = 0.6 ", "mu = 1e9 ", "contact.mu"),
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

/// `hardness_pa` in the config: the same surfaces calibrated elastic and hardness-limited
/// (steel-42crmo4, 3.33 GPa). The table says which kn it holds (elastic, or unloading/reloading
/// about the plastic state); where the hardness binds the contact is larger and the unloading
/// kn stiffer than the elastic one (the stiffness of the flattened contact, Barber's theorem),
/// and the loops change; where no point reaches H every value is the elastic one.
#[test]
fn hardness_in_the_config_bounds_the_pressure_and_labels_kn() {
    let dir = tempfile::tempdir().unwrap();
    let hard = dir.path().join("hard.toml");
    let text = reference_config().replace(
        "poisson_ratio = 0.3\n",
        "poisson_ratio = 0.3\nhardness_pa = \"steel-42crmo4\"\n",
    );
    assert!(text.contains("hardness_pa"));
    std::fs::write(&hard, text).unwrap();
    let run = |cfg: &str, name: &str| {
        let out = dir.path().join(name);
        let o = asperity(&[
            "calibrate",
            cfg,
            "--grid",
            "256",
            "--realisations",
            "2",
            "--out-dir",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        CalibrationTable::read_csv(&out.join("calibration_table.csv")).unwrap()
    };
    let reference = Path::new(env!("CARGO_MANIFEST_DIR")).join("calib/reference.toml");
    let elastic = run(reference.to_str().unwrap(), "elastic");
    let plastic = run(hard.to_str().unwrap(), "plastic");
    assert!(elastic.comments[0].contains("elastic contact stiffness"));
    assert!(
        plastic.comments[0].contains("unloading/reloading") && plastic.comments[0].contains("3.33"),
        "{:?}",
        plastic.comments
    );
    let mut bound = 0;
    for (e, p) in elastic.rows.iter().zip(&plastic.rows) {
        if p.contact_area_ratio == e.contact_area_ratio {
            assert_eq!(
                p.element.kn_n_per_m3, e.element.kn_n_per_m3,
                "{} Pa",
                e.pressure_pa
            );
        } else {
            bound += 1;
            assert!(p.contact_area_ratio > e.contact_area_ratio);
            assert!(
                p.element.kn_n_per_m3 > e.element.kn_n_per_m3,
                "{} Pa",
                e.pressure_pa
            );
            assert!(p.energy_per_cycle_j_per_m2 != e.energy_per_cycle_j_per_m2);
        }
    }
    assert!(bound >= 2, "the hardness binds at the higher pressures");
}
