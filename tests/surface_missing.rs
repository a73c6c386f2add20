//! Topographies with missing points: statistics over the measured points reproduce
//! SurfaceTopography 1.27.1 to 1e-9, on test files of our own with missing points (an x3p with a
//! validity mask and uint16 heights, height matrices with `nan`, periodic and not, a profile).
//!
//! Reference numbers: SurfaceTopography 1.27.1 (numpy 2.4.6) on the same files, computed by
//!
//!     benches/peers/setup_surfacetopography.sh /tmp/st-venv
//!     /tmp/st-venv/bin/python benches/peers/missing_points_reference.py surfaces
//!
//! (which also writes the files into surfaces/): `rms_height_from_area` / `_from_profile`,
//! `rms_gradient`, `rms_slope_from_profile`, and the same after
//! `interpolate_undefined_data()` (harmonic fill).

use std::path::{Path, PathBuf};
use std::process::Command;

fn surfaces(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("surfaces")
        .join(name)
}

fn stats(file: &Path, extra: &[&str]) -> serde_json::Value {
    let o = Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args(["surface", "stats", "--json"])
        .args(extra)
        .arg(file)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&o.stdout).unwrap()
}

fn assert_rel(v: &serde_json::Value, key: &str, want: f64, what: &str) {
    let got = v[key].as_f64().unwrap_or(f64::NAN);
    let rel = (got - want).abs() / want.abs();
    assert!(
        rel < 1e-9,
        "{what} {key}: got {got:e}, SurfaceTopography {want:e} (rel {rel:e})"
    );
}

/// (file, missing points, [rq, rms gradient (areas), rms slope], [same after harmonic fill]).
type Reference = (&'static str, u64, [f64; 3], [f64; 3]);

const REFERENCE: [Reference; 4] = [
    (
        "missing-points.x3p",
        58,
        [9.61113475010857e-07, 2.95423867364633, 2.169630459260077],
        [
            9.482879493667512e-07,
            2.8942742642007073,
            2.1313257239296144,
        ],
    ),
    (
        "missing-points-matrix.csv",
        62,
        [
            7.688766141944543e-08,
            0.10604066681197791,
            0.08449342450954102,
        ],
        [
            7.607385066802141e-08,
            0.1032336471199715,
            0.0826317049450782,
        ],
    ),
    (
        "missing-points-periodic.csv",
        32,
        [
            4.851409652601028e-07,
            0.46967605571128884,
            0.335581316558742,
        ],
        [
            4.749435836894495e-07,
            0.46954437839192775,
            0.33821531887272327,
        ],
    ),
    (
        "missing-points-profile.csv",
        12,
        [3.2533604743918344e-08, f64::NAN, 0.010056857080448855],
        [3.200386962274362e-08, f64::NAN, 0.009764439212076937],
    ),
];

#[test]
fn statistics_over_measured_points_match_surface_topography() {
    for (name, missing, measured, filled) in REFERENCE {
        let f = surfaces(name);
        let v = stats(&f, &[]);
        assert_eq!(v["missing_points"].as_u64(), Some(missing), "{name}");
        assert_rel(&v, "rq_m", measured[0], name);
        if measured[1].is_finite() {
            assert_rel(&v, "rms_gradient", measured[1], name);
        }
        assert_rel(&v, "rms_slope", measured[2], name);
        // Harmonic fill: SurfaceTopography's interpolate_undefined_data().
        let v = stats(&f, &["--fill", "harmonic"]);
        assert_eq!(v["missing_points"].as_u64(), Some(0), "{name}");
        assert_eq!(v["fill"]["filled_points"].as_u64(), Some(missing), "{name}");
        assert_rel(&v, "rq_m", filled[0], &format!("{name} filled"));
        if filled[1].is_finite() {
            assert_rel(&v, "rms_gradient", filled[1], &format!("{name} filled"));
        }
        assert_rel(&v, "rms_slope", filled[2], &format!("{name} filled"));
    }
}

#[test]
fn missing_points_survive_conversion_to_every_format() {
    let dir = tempfile::tempdir().unwrap();
    let src = surfaces("missing-points.x3p");
    let mut want = stats(&src, &[]);
    let strip = |v: &mut serde_json::Value| {
        for k in ["file", "read_time_s", "stats_time_s"] {
            v.as_object_mut().unwrap().remove(k);
        }
    };
    strip(&mut want);
    for ext in ["npy", "x3p", "csv"] {
        let out = dir.path().join(format!("m.{ext}"));
        let o = Command::new(env!("CARGO_BIN_EXE_asperity"))
            .args(["surface", "convert"])
            .arg(&src)
            .arg("-o")
            .arg(&out)
            .arg("-o")
            .arg(dir.path().join(format!("m-{ext}.png")))
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let mut got = stats(&out, &[]);
        strip(&mut got);
        assert_eq!(got, want, "{ext}");
    }
    // The x3p written by asperity carries a validity mask.
    let mut z =
        zip::ZipArchive::new(std::fs::File::open(dir.path().join("m.x3p")).unwrap()).unwrap();
    assert!(z.by_name("bindata/valid.bin").is_ok());
}

#[test]
fn nothing_is_filled_silently() {
    let dir = tempfile::tempdir().unwrap();
    let f = surfaces("missing-points-matrix.csv");
    // The PSD needs every point: refused without --fill, naming the flag and the file.
    let psd = dir.path().join("psd.csv");
    let o = Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args(["surface", "stats", "--psd-out"])
        .arg(&psd)
        .arg(&f)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("--psd-out") && err.contains("--fill"), "{err}");
    assert!(!psd.exists());
    // With --fill nearest the PSD is written, and the fill is reported.
    let o = Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args(["surface", "stats", "--fill", "nearest", "--psd-out"])
        .arg(&psd)
        .arg(&f)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("filled 62 of 1008 points"), "{err}");
    assert!(psd.exists() && psd.with_extension("png").exists());
    // Contact needs every point: refused without --fill, naming the file and the flag.
    let o = Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args(["contact", "normal", "--surface"])
        .arg(&f)
        .arg("--out-dir")
        .arg(dir.path().join("contact"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("missing-points-matrix.csv") && err.contains("--fill"),
        "{err}"
    );
    assert!(!dir.path().join("contact").exists());
}
