//! A synthetic raw flatbed scan, rendered here: magenta stain on white paper with speckle,
//! whose green-channel optical density follows a known density → pressure table; a patch in
//! range with a below-range rim, a patch entirely below range, a saturated patch with no pixel
//! in range (cannot be fitted), a black pen stroke, a red pen ring (a written `O`) and a red
//! pen stroke, and 254 dpi declared in the PNG. `asperity film` must find the in-range patch
//! with its pressure, report the below-range one, skip the saturated one with a warning, reject
//! the marks, and take the pixel size from the image.

#[path = "support/png_density.rs"]
mod png_density;

use std::path::Path;
use std::process::Command;

const W: usize = 300; // 30 mm at 0.1 mm
const H: usize = 200; // 20 mm
const PX_MM: f64 = 0.1;

/// Green-channel density → pressure: D = 0.35 at 2.5 MPa, 1.1 at 10 MPa (linear).
fn density_of(p_mpa: f64) -> f64 {
    0.35 + (p_mpa - 2.5) * 0.1
}

/// Magenta stain of green density `d` (red absorbs 0.12 d, blue 0.85 d).
fn stain(d: f64) -> [f64; 3] {
    [
        250.0 * 10f64.powf(-0.12 * d),
        250.0 * 10f64.powf(-d),
        248.0 * 10f64.powf(-0.85 * d),
    ]
}

/// Pressure of patch A (MPa) at distance r (mm) from its centre: 6·√(1 − (r/4)²).
fn patch_a(r: f64) -> f64 {
    if r < 4.0 {
        6.0 * (1.0 - (r / 4.0).powi(2)).sqrt()
    } else {
        0.0
    }
}

/// Deterministic speckle in [-3, 3].
fn speckle(c: usize, r: usize, k: usize) -> f64 {
    let h = (c as u64)
        .wrapping_mul(0x9E37_79B9_7F4A_7C15)
        .wrapping_add((r as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F))
        .wrapping_add(k as u64 * 0x1656_67B1_9E37_79F9);
    let h = (h ^ (h >> 31)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    ((h >> 40) % 7) as f64 - 3.0
}

/// Colour at (x, y) mm (film frame, y up).
fn colour(x: f64, y: f64) -> [f64; 3] {
    let d = |cx: f64, cy: f64| (x - cx).hypot(y - cy);
    // Black pen stroke along y = 18.5 mm, x 2–14 mm, 0.5 mm wide.
    if (2.0..=14.0).contains(&x) && (y - 18.5).abs() <= 0.25 {
        return [40.0, 40.0, 45.0];
    }
    // Red pen (the stain's hue): a ring of radius 2 mm at (26, 10), 0.3 mm wide, and a
    // stroke along y = 18.5, x 17–27 mm.
    if (d(26.0, 10.0) - 2.0).abs() <= 0.15
        || ((17.0..=27.0).contains(&x) && (y - 18.5).abs() <= 0.25)
    {
        return stain(0.8);
    }
    // Patch A: in range with a below-range rim.
    let p = patch_a(d(8.0, 10.0));
    if p > 0.0 {
        return stain(density_of(p));
    }
    // Patch B: entirely below range (density 0.25 < 0.35), radius 3 mm.
    if d(17.0, 12.0) <= 3.0 {
        return stain(0.25);
    }
    // Patch C: saturated (above range), radius 2.5 mm.
    if d(17.0, 4.5) <= 2.5 {
        return stain(1.5);
    }
    [250.0, 250.0, 248.0]
}

fn write_scan(path: &Path) {
    let mut data = Vec::with_capacity(W * H * 3);
    for r in 0..H {
        for c in 0..W {
            let (x, y) = (c as f64 * PX_MM, (H - 1 - r) as f64 * PX_MM);
            let rgb = colour(x, y);
            for (k, v) in rgb.iter().enumerate() {
                data.push((v + speckle(c, r, k)).round().clamp(0.0, 255.0) as u8);
            }
        }
    }
    // 254 dpi = 10000 pixels per metre: 0.1 mm pixels.
    let png = png_density::rgb_png_with_density(W as u32, H as u32, &data, 10000);
    std::fs::write(path, png).unwrap();
}

fn rows(path: &Path) -> Vec<std::collections::HashMap<String, String>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let head: Vec<String> = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_string)
        .collect();
    lines
        .map(|l| {
            head.iter()
                .cloned()
                .zip(l.split(',').map(str::to_string))
                .collect()
        })
        .collect()
}

#[test]
fn raw_scan_patches_ranges_marks_and_dpi() {
    let dir = tempfile::tempdir().unwrap();
    let scan = dir.path().join("scan.png");
    write_scan(&scan);
    if let Ok(p) = std::env::var("KEEP_SCAN") {
        std::fs::copy(&scan, p).unwrap();
    }
    let cal = dir.path().join("density.csv");
    std::fs::write(&cal, "density,pressure_MPa\n0.35,2.5\n1.1,10\n").unwrap();
    let run = |extra: &[&str], out: &Path| {
        Command::new(env!("CARGO_BIN_EXE_asperity"))
            .args(["film", "--image"])
            .arg(&scan)
            .arg("--density-calibration")
            .arg(&cal)
            .args(["--stain-rgb", "230,110,125", "--channel", "complement"])
            .args(["--fit-order", "2", "--out-dir"])
            .arg(out)
            .args(extra)
            .output()
            .unwrap()
    };
    // The pressure of the in-range pixels of patch A, from the rendering.
    let (mut sum, mut n) = (0.0, 0);
    for c in 0..W {
        for j in 0..H {
            let p = patch_a((c as f64 * PX_MM - 8.0).hypot(j as f64 * PX_MM - 10.0));
            if p >= 2.5 {
                sum += p;
                n += 1;
            }
        }
    }
    let want = sum / n as f64 * 1e6;
    for (extra, name) in [
        (&[][..], "plain"),
        (&["--smooth-mm", "0.1"][..], "smoothed"),
    ] {
        let out = dir.path().join(name);
        let o = run(extra, &out);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{name}: {err}");
        // Pixel size from the PNG's pHYs, density in green (the stain's complement).
        assert!(
            err.contains("at 0.1 mm (254 dpi declared by the image (PNG pHYs))"),
            "{err}"
        );
        assert!(err.contains("green channel"), "{err}");
        // Stain paler than the first calibration point is below range, and counted.
        assert!(
            err.contains("stained below the film's measuring range"),
            "{err}"
        );
        // The saturated patch is a region but cannot be fitted: skipped with a warning.
        let stdout = String::from_utf8_lossy(&o.stdout);
        // (Smoothing blurs the saturated patch's edge into range: it is then fitted.)
        let plain = name == "plain";
        assert_eq!(
            err.contains("warning: region") && err.contains("skipped"),
            plain,
            "{err}\n{stdout}"
        );
        let r = rows(&out.join("regions.csv"));
        assert_eq!(r.len(), 2, "{name}: {r:?}");
        let a = r
            .iter()
            .find(|r| (r["centre_x_m"].parse::<f64>().unwrap() - 8e-3).abs() < 0.3e-3)
            .expect("patch A");
        let got: f64 = a["mean_pressure_Pa"].parse().unwrap();
        assert!(
            (got / want - 1.0).abs() < 0.03,
            "{name}: mean in-range pressure {got:e}, rendered {want:e}"
        );
        assert!(a["n_below_range"].parse::<usize>().unwrap() > 50, "{a:?}");
        assert!(!a["fit_R2"].is_empty());
        let c = r
            .iter()
            .find(|r| (r["centre_x_m"].parse::<f64>().unwrap() - 17e-3).abs() < 0.3e-3)
            .expect("patch C");
        if plain {
            assert!(c["fit_R2"].is_empty(), "{c:?}");
            assert_eq!(c["n_in_range"], "0");
        }
        // The marks are not regions: the red ring and stroke are rejected by shape, the black
        // stroke by its hue; patch B is reported as below range.
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("film.json")).unwrap()).unwrap();
        let s = &json["summary"];
        // (Smoothed, the thin red stroke falls below the minimum size instead.)
        let marks = s["rejected_marks"].as_u64().unwrap();
        if plain {
            assert_eq!(marks, 2, "{name}: {s}");
        } else {
            assert!(marks + s["discarded_small_components"].as_u64().unwrap() >= 2);
        }
        let below = s["below_range_patches"].as_array().unwrap();
        assert_eq!(below.len(), 1, "{name}: {below:?}");
        assert!((below[0]["centre_x_m"].as_f64().unwrap() - 17e-3).abs() < 0.3e-3);
        assert!(s["image_pixels"]["off_curve"].as_u64().unwrap() > 100);
        assert_eq!(json["parameters"]["pixel_size_m"], 1e-4);
        // The pressure map reads back with its sidecar.
        let (m, side) =
            asperity::surface::io::npy::read_field(&out.join("pressure_map_Pa.npy")).unwrap();
        assert_eq!(
            (m.dim(), side.unit.as_str(), side.dx_m),
            ((W, H), "Pa", 1e-4)
        );
    }
}

#[test]
fn patches_entirely_below_range_are_named_as_such() {
    let dir = tempfile::tempdir().unwrap();
    let scan = dir.path().join("scan.png");
    write_scan(&scan);
    // A calibration whose range starts above every stain of the scan: nothing bears pressure,
    // the stained patches are all below range, and the error says so.
    let cal = dir.path().join("density.csv");
    std::fs::write(&cal, "density,pressure_MPa\n1.6,2.5\n2.0,10\n").unwrap();
    let out = dir.path().join("out");
    let o = Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args(["film", "--image"])
        .arg(&scan)
        .arg("--density-calibration")
        .arg(&cal)
        .args(["--stain-rgb", "230,110,125", "--out-dir"])
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("lie entirely below the film's measuring range"),
        "{err}"
    );
    assert!(!out.exists(), "nothing is written");
}
