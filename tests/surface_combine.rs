//! `asperity surface combine`: equivalent surface on a common grid, equivalent statistics,
//! composite modulus; mismatched grids are refused without output.

use std::path::Path;
use std::process::{Command, Output};

fn asperity(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args(args)
        .output()
        .expect("run asperity")
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn gen(path: &Path, n: &str, seed: &str, rq: &str) {
    let o = asperity(&[
        "surface",
        "generate",
        "--n",
        n,
        "--size-m",
        "6.4e-5",
        "--cl-m",
        "4e-6",
        "--rq-m",
        rq,
        "--seed",
        seed,
        "--out",
        s(path),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn combine_surfaces_statistics_and_moduli() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (a, b, eq) = (d.join("a.npy"), d.join("b.x3p"), d.join("eq.npy"));
    gen(&a, "64", "1", "3e-7");
    gen(&b, "64", "2", "4e-7");
    let o = asperity(&[
        "surface",
        "combine",
        s(&a),
        s(&b),
        "--out",
        s(&eq),
        "--rq1-m",
        "3e-7",
        "--rq2-m",
        "4e-7",
        "--slope1",
        "0.03",
        "--slope2",
        "0.04",
        "--e1-pa",
        "210e9",
        "--nu1",
        "0.3",
        "--e2-pa",
        "70e9",
        "--nu2",
        "0.33",
    ]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        out.contains("equivalent Rq          5.000000e-7 m"),
        "{out}"
    );
    assert!(out.contains("equivalent rms slope   5.000000e-2"), "{out}");
    // 1/E* = (1-0.09)/210e9 + (1-0.1089)/70e9 (Johnson 1985, eq. 4.22).
    let e_star = 1.0 / ((1.0 - 0.09) / 210e9 + (1.0 - 0.1089) / 70e9);
    assert!(out.contains(&format!("{e_star:.6e} Pa")), "{out}");
    let read = |p: &Path| {
        asperity::surface::io::read(p)
            .unwrap()
            .into_area("test")
            .unwrap()
    };
    let (ga, gb, ge) = (read(&a), read(&b), read(&eq));
    assert_eq!(ge.heights, &ga.heights - &gb.heights);
    // x3p carries the periodic flag, so the equivalent patch stays periodic.
    assert!(ge.periodic);

    // Different grids: error, exit 1, no output.
    let c = d.join("c.npy");
    gen(&c, "32", "3", "1e-7");
    let bad = d.join("bad.npy");
    let o = asperity(&["surface", "combine", s(&a), s(&c), "--out", s(&bad)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("different grids"));
    assert!(!bad.exists());
    // Negative Rq is named.
    let o = asperity(&["surface", "combine", "--rq1-m", "-1e-7", "--rq2-m", "1e-7"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("rq1_m"));
}
