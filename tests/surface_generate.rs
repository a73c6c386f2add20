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
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let g = asperity::surface::io::read(&out)
        .unwrap()
        .into_area("test")
        .unwrap();
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
        (&["--rq-m", "0"], "rq_m"),
        (&["--rq-m", "-1e-6"], "rq_m"),
        (&["--rq-m", "nan"], "rq_m"),
        (&["--cl-m", "0"], "clx_m"),
        (&["--cly-m", "-1e-6"], "cly_m"),
        (&["--size-m", "0"], "lx_m"),
        (&["--ly-m", "-1"], "ly_m"),
        (&["--n", "0"], "nx"),
        (&["--ny", "1"], "ny"),
        (&["--cl-m", "4e-7"], "under-resolved"),
    ];
    for (extra, want) in cases {
        let mut args: Vec<&str> = base.to_vec();
        args.extend_from_slice(extra);
        assert_fails_without_output(&args, &out, want);
    }
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
