//! Done-when 1: `asperity surface stats --json` reproduces the values SurfaceTopography 1.27
//! publishes for its own test files (see ../shared/data/README.md), to 1e-9 relative.

use std::process::Command;

fn stats_json(file: &std::path::Path) -> serde_json::Value {
    let dir = tempfile::tempdir().unwrap();
    let psd = dir.path().join("psd.csv");
    let o = Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args(["surface", "stats", "--json", "--psd-out"])
        .arg(&psd)
        .arg(file)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(psd.exists() && psd.with_extension("png").exists());
    serde_json::from_slice(&o.stdout).unwrap()
}

fn assert_rel(got: f64, want: f64, tol: f64, what: &str) {
    let rel = (got - want).abs() / want.abs();
    assert!(
        rel < tol,
        "{what}: got {got:e}, want {want:e} (rel {rel:e})"
    );
}

#[test]
fn dektak_profile_matches_surface_topography() {
    let Some(f) = asperity::core::testdata::reference_file("topography/dektak-1.csv") else {
        return;
    };
    let v = stats_json(&f);
    assert_eq!(v["kind"], "profile");
    assert_eq!(v["nx"], 9600);
    assert_eq!(v["uniform"], false);
    assert_rel(v["lx_m"].as_f64().unwrap(), 1499.8e-6, 1e-12, "length");
    // Published in µm; the tool works in m.
    assert_rel(
        v["rq_m"].as_f64().unwrap(),
        4.763596104697675e-6,
        1e-9,
        "rms height",
    );
    assert_rel(
        v["rms_slope"].as_f64().unwrap(),
        0.015447980655979321,
        1e-9,
        "rms slope",
    );
}

#[test]
fn x3p_area_matches_surface_topography() {
    let Some(f) = asperity::core::testdata::reference_file("topography/x3p-2.x3p") else {
        return;
    };
    let v = stats_json(&f);
    assert_eq!(v["kind"], "area");
    assert_eq!((v["nx"].as_u64(), v["ny"].as_u64()), (Some(650), Some(650)));
    assert_eq!(v["periodic"], false);
    assert_rel(
        v["lx_m"].as_f64().unwrap(),
        8.29767313942749e-05,
        1e-9,
        "size x",
    );
    assert_rel(
        v["ly_m"].as_f64().unwrap(),
        0.0002044783737930349,
        1e-9,
        "size y",
    );
    assert_rel(
        v["rq_m"].as_f64().unwrap(),
        7.728033273597876e-08,
        1e-9,
        "rms height",
    );
    assert_rel(
        v["rms_gradient"].as_f64().unwrap(),
        0.06207007399844295,
        1e-9,
        "rms gradient",
    );
}

#[test]
fn x3p_converted_to_every_format_keeps_its_statistics() {
    let Some(f) = asperity::core::testdata::reference_file("topography/x3p-2.x3p") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let mut want = stats_json(&f);
    for ext in ["npy", "x3p", "csv"] {
        let out = dir.path().join(format!("converted.{ext}"));
        let o = Command::new(env!("CARGO_BIN_EXE_asperity"))
            .args(["surface", "convert"])
            .arg(&f)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let mut got = stats_json(&out);
        for v in [&mut want, &mut got] {
            for k in ["file", "psd_csv", "psd_png", "read_time_s", "stats_time_s"] {
                v.as_object_mut().unwrap().remove(k);
            }
        }
        assert_eq!(got, want, "{ext}");
    }
    let png = dir.path().join("x3p-2.png");
    let o = Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args(["surface", "convert"])
        .arg(&f)
        .arg("-o")
        .arg(&png)
        .output()
        .unwrap();
    assert!(o.status.success());
    assert!(image::open(&png).is_ok());
}
