//! End-to-end: `asperity surface generate` writes a readable patch with the requested Rq, and
//! refuses impossible parameters with a named error, a non-zero exit and no output file.

use std::path::Path;
use std::process::Command;

fn asperity(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args(args)
        .output()
        .expect("run asperity")
}

/// The area written by a successful run.
fn written_area(o: &std::process::Output, path: &Path) -> asperity::Grid2 {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    asperity::surface::io::read(path)
        .unwrap()
        .into_area("test")
        .unwrap()
}

#[test]
fn generate_writes_npy_with_requested_rq() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("patch.npy");
    let o = asperity(&[
        "surface",
        "generate",
        "--rq-m",
        "2e-7",
        "--cl-m",
        "5e-6",
        "--size-m",
        "1e-4",
        "--n",
        "128",
        "--seed",
        "3",
        "--out",
        out.to_str().unwrap(),
    ]);
    let g = written_area(&o, &out);
    // cl/L = 0.05: the expected 1/e length is within 2 % of cl, no note.
    assert!(!String::from_utf8_lossy(&o.stderr).contains("note"));
    assert_eq!((g.nx(), g.ny()), (128, 128));
    assert!(g.periodic);
    assert!((g.dx - 1e-4 / 128.0).abs() < 1e-18);
    let n = g.heights.len() as f64;
    let rq = (g.heights.iter().map(|v| v * v).sum::<f64>() / n).sqrt();
    assert!((rq / 2e-7 - 1.0).abs() < 1e-12, "Rq {rq}");
    // Same as the library with the same spec, bit for bit.
    let lib = asperity::surface::generate(&asperity::surface::GaussianSurfaceSpec {
        rq_m: 2e-7,
        clx_m: 5e-6,
        cly_m: 5e-6,
        lx_m: 1e-4,
        ly_m: 1e-4,
        nx: 128,
        ny: 128,
        seed: 3,
    })
    .unwrap();
    assert_eq!(lib.heights, g.heights);
}

/// A patch four correlation lengths across: the surface's expected 1/e length is 84 % of the
/// requested one along both axes (`surface::generate::expected_correlation_length_x`, checked
/// there against generated surfaces), and the note says so.
#[test]
fn generate_notes_a_patch_too_small_for_its_correlation_length() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("small.npy");
    let o = asperity(&[
        "surface",
        "generate",
        "--rq-m",
        "1e-6",
        "--cl-m",
        "16e-6",
        "--size-m",
        "64e-6",
        "--n",
        "64",
        "--out",
        out.to_str().unwrap(),
    ]);
    written_area(&o, &out);
    let err = String::from_utf8_lossy(&o.stderr);
    for axis in ["x", "y"] {
        assert!(
            err.contains(&format!("along {axis}: the generated")),
            "{err}"
        );
    }
    assert_eq!(err.matches("84.2 %").count(), 2, "{err}");
}

fn assert_fails_without_output(args: &[&str], out: &Path, want: &str) {
    let o = asperity(args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{args:?} should fail");
    assert!(
        err.contains(want),
        "{args:?}: `{err}` should mention `{want}`"
    );
    assert!(!out.exists(), "{args:?} left {}", out.display());
}

#[test]
fn generate_rejects_bad_parameters() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bad.npy");
    let o = out.to_str().unwrap();
    let base = ["surface", "generate", "--out", o];
    let cases: &[(&[&str], &str)] = &[
        (&["--rq-m", "0"], "--rq-m"),
        (&["--rq-m", "-1e-6"], "--rq-m"),
        (&["--rq-m", "nan"], "--rq-m"),
        (&["--cl-m", "0"], "--cl-m"),
        (&["--cly-m", "-1e-6"], "--cly-m"),
        (&["--size-m", "0"], "--size-m"),
        (&["--ly-m", "-1"], "--ly-m"),
        (&["--n", "0"], "--n"),
        (&["--ny", "1"], "--ny"),
        (&["--cl-m", "4e-7"], "under-resolved"),
    ];
    for (extra, want) in cases {
        let mut args: Vec<&str> = base.to_vec();
        args.extend_from_slice(extra);
        assert_fails_without_output(&args, &out, want);
    }
    // A malformed config names file and line.
    let cfg = dir.path().join("bad.toml");
    std::fs::write(&cfg, "rq_m = 1e-7\nclx_m = \"a\"\n").unwrap();
    assert_fails_without_output(
        &[
            "surface",
            "generate",
            "--config",
            cfg.to_str().unwrap(),
            "--out",
            o,
        ],
        &out,
        "bad.toml:2",
    );
    // An unknown output format is refused before anything is computed or written.
    let bad = dir.path().join("bad.xyz");
    assert_fails_without_output(
        &[
            "surface",
            "generate",
            "--n",
            "64",
            "--size-m",
            "1e-4",
            "--out",
            bad.to_str().unwrap(),
        ],
        &bad,
        "known formats",
    );
}

/// Done-when 2: the reference patch (1024², Rq 0.177 µm, cl 6.6 µm, 250 µm) over seeds 1..=10.
///
/// Rq is exact per seed (1e-12) and the mean 1/e correlation length is within 3 % of 6.6 µm.
/// Height-distribution shape: a Gaussian generator has no bias, so the seed means of Rsk and
/// Rku - 3 must vanish (|mean Rsk| < 0.05, |mean Rku - 3| < 0.1). The seed means of |Rsk| and
/// |Rku - 3| are sampling noise of a finite patch; they must lie within 3 standard errors of the
/// Gaussian-field expectation: for an ACF ρ(r) = exp(-r²/cl²) the sample skewness has variance
/// 6/N₃ and the excess kurtosis 24/N₄ with N_k = A / ∫ρᵏ d²r = A k/(π cl²), and E|X| = σ√(2/π).
#[test]
fn reference_patch_statistics_over_ten_seeds() {
    use asperity::surface::{generate, stats, Detrend, GaussianSurfaceSpec, Topography};
    let base = GaussianSurfaceSpec::reference();
    let seeds = 1..=10u64;
    let n = seeds.clone().count() as f64;
    let (mut cl, mut rsk, mut rku, mut abs_rsk, mut abs_rku) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for seed in seeds {
        let g = generate(&GaussianSurfaceSpec { seed, ..base }).unwrap();
        let s = stats(&Topography::Area(g), Detrend::Mean).unwrap();
        assert!(
            ((s.rq_m - base.rq_m) / base.rq_m).abs() < 1e-12,
            "seed {seed}: Rq {}",
            s.rq_m
        );
        cl += s.correlation_length_1_over_e_m.unwrap() / n;
        rsk += s.rsk / n;
        rku += (s.rku - 3.0) / n;
        abs_rsk += s.rsk.abs() / n;
        abs_rku += (s.rku - 3.0).abs() / n;
    }
    eprintln!(
        "mean cl {cl:e} m, mean Rsk {rsk:.4}, mean Rku-3 {rku:.4}, \
         mean |Rsk| {abs_rsk:.4}, mean |Rku-3| {abs_rku:.4}"
    );
    assert!(((cl - 6.6e-6) / 6.6e-6).abs() < 0.03, "mean cl {cl:e}");
    assert!(rsk.abs() < 0.05, "mean Rsk {rsk}");
    assert!(rku.abs() < 0.1, "mean Rku - 3 {rku}");
    let area = base.lx_m * base.ly_m;
    let pi_cl2 = std::f64::consts::PI * base.clx_m * base.cly_m;
    for (what, got, var_n) in [
        ("|Rsk|", abs_rsk, 6.0 / (3.0 * area / pi_cl2)),
        ("|Rku-3|", abs_rku, 24.0 / (4.0 * area / pi_cl2)),
    ] {
        let sd = var_n.sqrt();
        let expect = sd * (2.0 / std::f64::consts::PI).sqrt();
        let se = sd * (1.0 - 2.0 / std::f64::consts::PI).sqrt() / n.sqrt();
        assert!(
            (got - expect).abs() < 3.0 * se,
            "mean {what} = {got:.4}, Gaussian-field expectation {expect:.4} ± {se:.4}"
        );
    }
}

#[test]
fn shipped_reference_config_is_the_reference_case() {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("surfaces/reference.toml");
    let spec: asperity::surface::GaussianSurfaceSpec =
        toml::from_str(&std::fs::read_to_string(p).unwrap()).unwrap();
    assert_eq!(spec, asperity::surface::GaussianSurfaceSpec::reference());
}

/// `asperity surface self-affine` writes the library's self-affine patch (same seed, same
/// heights) with the requested rms gradient, and names the flag of an impossible parameter.
#[test]
fn self_affine_writes_npy_and_rejects_bad_flags() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("fractal.npy");
    let o = asperity(&[
        "surface",
        "self-affine",
        "--hurst",
        "0.7",
        "--rms-gradient",
        "0.2",
        "--size-m",
        "1e-4",
        "--n",
        "128",
        "--seed",
        "5",
        "--out",
        out.to_str().unwrap(),
    ]);
    let g = written_area(&o, &out);
    let lib = asperity::surface::generate_self_affine(&asperity::surface::SelfAffineSpec {
        hurst: 0.7,
        rms_gradient: 0.2,
        ..asperity::surface::SelfAffineSpec::benchmark(128, 1e-4, 5)
    })
    .unwrap();
    assert_eq!(lib.heights, g.heights);
    assert!(g.periodic);
    let st = asperity::surface::stats(
        &asperity::surface::Topography::Area(g),
        asperity::surface::Detrend::Mean,
    )
    .unwrap();
    assert!((st.rms_gradient.unwrap() - 0.2).abs() < 1e-12);
    for (args, flag) in [
        (vec!["--hurst", "1.5"], "--hurst"),
        (vec!["--n", "1"], "--n"),
        (
            vec!["--cutoff-wavelength-m", "1e-9"],
            "--cutoff-wavelength-m",
        ),
    ] {
        let bad = dir.path().join("bad.npy");
        let mut full = vec!["surface", "self-affine", "--out", bad.to_str().unwrap()];
        full.extend(args.iter());
        let o = asperity(&full);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains(flag), "{args:?}: {err}");
        assert!(!bad.exists());
    }
}
