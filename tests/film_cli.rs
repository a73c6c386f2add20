//! End to end through the binary: a synthetic film with one round patch of known pressure
//! `σ = 6 − 3 (r/R)²` MPa → patch, fit, node preloads (placed by offset + rotation), rescaling to
//! a total load, node reduction, and the element table joined with an example calibration table.
//! Then the error paths: unreadable images, empty regions, non-monotone colour tables, nodes
//! outside the map.

use asperity::calibrate::table::{CalibrationRow, CalibrationTable};
use asperity::element::ContactParamsPerArea;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

#[path = "support/lw_scale.rs"]
mod lw_scale;
use lw_scale::lw_green;

const LW_TABLE: &str = ";Pressure,R,G,B\n0.00,255.0,255.0,255.0\n2.00,0.0,255.0,0.0\n2.50,255.0,227.0,227.0\n3.44,255.0,198.0,198.0\n4.38,255.0,170.0,170.0\n5.31,255.0,142.0,142.0\n6.25,255.0,113.0,113.0\n7.19,255.0,85.0,85.0\n8.13,255.0,57.0,57.0\n9.06,255.0,28.0,28.0\n10.00,255.0,255.0,0.0\n";

const PIXEL_MM: f64 = 0.1;
const N: u32 = 200;
/// Patch centre (mm, film frame) and radius (mm).
const CX: f64 = 10.0;
const CY: f64 = 10.0;
const R: f64 = 4.0;

fn sigma_pa(x_mm: f64, y_mm: f64) -> f64 {
    let r2 = ((x_mm - CX).powi(2) + (y_mm - CY).powi(2)) / (R * R);
    6e6 - 3e6 * r2
}

/// 8-bit film: the patch, a green pen stroke and a blue ink blot on white.
fn render(path: &Path) {
    let mut img = image::RgbImage::from_pixel(N, N, image::Rgb([255, 255, 255]));
    for (c, r, px) in img.enumerate_pixels_mut() {
        let (x, y) = (c as f64 * PIXEL_MM, (N - 1 - r) as f64 * PIXEL_MM);
        if (x - CX).hypot(y - CY) <= R {
            let g = lw_green(sigma_pa(x, y)).round() as u8;
            *px = image::Rgb([255, g, g]);
        } else if (2.0..18.0).contains(&x) && (16.0..18.0).contains(&y) {
            *px = image::Rgb([0, 255, 0]);
        } else if (1.0..3.0).contains(&x) && (1.0..3.0).contains(&y) {
            *px = image::Rgb([20, 30, 200]);
        }
    }
    img.save(path).unwrap();
}

/// Mesh-frame nodes on a 0.25 mm grid inside a disc of radius 3.5 mm about the origin.
fn write_nodes(path: &Path, with_area: bool) {
    let mut s = String::from(if with_area {
        "id,x_m,y_m,area_m2\n"
    } else {
        "id,x_m,y_m\n"
    });
    let mut id = 100;
    for i in -14i32..=14 {
        for j in -14i32..=14 {
            let (x, y) = (i as f64 * 0.25e-3, j as f64 * 0.25e-3);
            if x.hypot(y) <= 3.5e-3 {
                id += 1;
                if with_area {
                    s += &format!("{id},{x},{y},6.25e-8\n");
                } else {
                    s += &format!("{id},{x},{y}\n");
                }
            }
        }
    }
    std::fs::write(path, s).unwrap();
}

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args(args)
        .output()
        .unwrap()
}

/// `asperity film --image <image> --colour-table <table> --pixel-size-mm 0.1 <extra>
/// --out-dir <out>` (the synthetic films' pixel size).
fn film_at_0_1_mm(image: &Path, table: &Path, out: &Path, extra: &[&str]) -> Output {
    let mut a = vec![
        "film",
        "--image",
        s(image),
        "--colour-table",
        s(table),
        "--pixel-size-mm",
        "0.1",
    ];
    a.extend_from_slice(extra);
    a.extend(["--out-dir", s(out)]);
    run(&a)
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

struct Setup {
    _dir: tempfile::TempDir,
    root: PathBuf,
    image: PathBuf,
    table: PathBuf,
    nodes: PathBuf,
}

fn setup() -> Setup {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().to_path_buf();
    let image = root.join("film.png");
    render(&image);
    let table = root.join("lw.csv");
    std::fs::write(&table, LW_TABLE).unwrap();
    let nodes = root.join("nodes.csv");
    write_nodes(&nodes, false);
    Setup {
        _dir: dir,
        root,
        image,
        table,
        nodes,
    }
}

/// Rows of a `#`-commented CSV as maps column → value.
fn read_rows(path: &Path) -> Vec<std::collections::HashMap<String, String>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    lines
        .map(|l| {
            header
                .iter()
                .cloned()
                .zip(l.split(',').map(String::from))
                .collect()
        })
        .collect()
}

fn num(row: &std::collections::HashMap<String, String>, col: &str) -> f64 {
    row[col].parse().unwrap()
}

/// `asperity film` on the synthetic setup with the nodes placed (offset 10 mm, rotated 30°),
/// rescaled to a total load of 150 N and reduced on a 1 mm coarse mesh; returns the output dir.
fn film_reduced(st: &Setup, name: &str) -> PathBuf {
    let out = st.root.join(name);
    let o = film_at_0_1_mm(
        &st.image,
        &st.table,
        &out,
        &[
            "--nodes",
            s(&st.nodes),
            "--node-offset-mm",
            "10,10",
            "--node-rotation-deg",
            "30",
            "--total-load-n",
            "150",
            "--reduce-mesh-size-mm",
            "1.0",
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    out
}

#[test]
fn film_to_preloads_to_reduced_nodes_to_elements() {
    let st = setup();
    let out = st.root.join("out");
    let o = film_at_0_1_mm(
        &st.image,
        &st.table,
        &out,
        &[
            "--fit-order",
            "4",
            "--nodes",
            s(&st.nodes),
            "--node-offset-mm",
            "10,10",
            "--node-rotation-deg",
            "30",
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // One patch (the pen stroke and the ink blot are not patches), of radius 4 mm.
    let regions = read_rows(&out.join("regions.csv"));
    assert_eq!(regions.len(), 1);
    let d = num(&regions[0], "equivalent_diameter_m");
    assert!((d - 8e-3).abs() < 0.1e-3, "{d}");
    assert!((num(&regions[0], "centre_x_m") - 10e-3).abs() < 0.05e-3);
    assert!(num(&regions[0], "fit_R2") > 0.999);
    for f in [
        "pressure_map.png",
        "pressure_map_Pa.npy",
        "pressure_map.csv",
        "region_1_fitted.png",
        "region_1_residual.png",
        "film.json",
        "fit_coefficients.csv",
    ] {
        assert!(out.join(f).exists(), "{f}");
    }
    // Preloads follow the known field at the placed node positions (mesh (x, y) rotated 30° and
    // offset by 10 mm: the radius is unchanged) and N0 = σ·A.
    let pre = read_rows(&out.join("preload.csv"));
    let mut raw_total = 0.0;
    for r in &pre {
        let (x, y) = (num(r, "x_m") * 1e3, num(r, "y_m") * 1e3);
        let want = sigma_pa(x, y);
        let got = num(r, "pressure_Pa");
        assert!(
            (got - want).abs() < 0.01 * want,
            "node {}: {got} vs {want}",
            r["id"]
        );
        assert!((num(r, "N0_N") - got * num(r, "area_m2")).abs() < 1e-9 * num(r, "N0_N"));
        raw_total += num(r, "N0_N");
    }
    // Areas from the Delaunay triangulation sum to the hull of the node cloud (a bit under π·3.5²).
    let area: f64 = pre.iter().map(|r| num(r, "area_m2")).sum();
    assert!(
        area < std::f64::consts::PI * 3.5e-3 * 3.5e-3
            && area > 0.95 * std::f64::consts::PI * 3.5e-3 * 3.5e-3,
        "{area}"
    );

    // Rescaled to a total load, then reduced.
    let out2 = film_reduced(&st, "out2");
    let pre2 = read_rows(&out2.join("preload.csv"));
    let total: f64 = pre2.iter().map(|r| num(r, "N0_N")).sum();
    assert!((total - 150.0).abs() <= 1e-9 * 150.0, "{total}");
    // Rescaling multiplies every preload by the same factor.
    let factor = 150.0 / raw_total;
    for (a, b) in pre.iter().zip(&pre2) {
        assert!((num(b, "N0_N") - factor * num(a, "N0_N")).abs() <= 1e-9 * num(b, "N0_N"));
    }
    let red = read_rows(&out2.join("preload_reduced.csv"));
    assert!(
        red.len() < pre2.len() / 5 && red.len() > 20,
        "{} of {}",
        red.len(),
        pre2.len()
    );
    let red_area: f64 = red.iter().map(|r| num(r, "area_m2")).sum();
    let red_load: f64 = red.iter().map(|r| num(r, "N0_N")).sum();
    assert!(
        (red_area - area).abs() <= 1e-9 * area,
        "{red_area} vs {area}"
    );
    assert!((red_load - 150.0).abs() <= 1e-9 * 150.0, "{red_load}");

    // Elements: an EXAMPLE calibration table written for this test (values of a plausible
    // magnitude, not the reference table of calib/), 2–4 MPa, so that the hottest elements fall
    // above its range.
    let example = CalibrationTable::new(
        [2e6, 3e6, 4e6]
            .iter()
            .map(|&p| CalibrationRow {
                pressure_pa: p,
                contact_area_ratio: 0.05 * p / 2e6,
                element: ContactParamsPerArea {
                    kn_n_per_m3: 4e13 * p / 2e6,
                    e0_n_per_m3: 8e13 * p / 2e6,
                    k: 0.9,
                    mu: 0.6,
                    et_n_per_m3: 1e11,
                },
                fit_r2: 0.99,
                energy_per_cycle_j_per_m2: 10.0,
            })
            .collect(),
    )
    .unwrap();
    let table_csv = st.root.join("example-calibration-table.csv");
    example.write_csv(&table_csv).unwrap();
    let elements = st.root.join("elements.csv");
    let o = run(&[
        "elements",
        "--preload",
        s(&out2.join("preload_reduced.csv")),
        "--table",
        s(&table_csv),
        "--out",
        s(&elements),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rows = read_rows(&elements);
    assert_eq!(rows.len(), red.len());
    let mut above = 0;
    for (e, r) in rows.iter().zip(&red) {
        assert_eq!(e["id"], r["id"]);
        let p = num(e, "pressure_Pa");
        let a = num(e, "area_m2");
        let v = example.interpolate(p);
        assert!(
            (num(e, "kn_N_per_m") - v.element.kn_n_per_m3 * a).abs()
                <= 1e-8 * v.element.kn_n_per_m3 * a
        );
        assert!(
            (num(e, "E0_N_per_m") - v.element.e0_n_per_m3 * a).abs()
                <= 1e-8 * v.element.e0_n_per_m3 * a
        );
        assert!(
            (num(e, "Et_N_per_m") - v.element.et_n_per_m3 * a).abs()
                <= 1e-8 * v.element.et_n_per_m3 * a
        );
        assert_eq!(num(e, "mu"), 0.6);
        let flag: i32 = e["out_of_range"].parse().unwrap();
        assert_eq!(
            flag,
            if p > 4e6 {
                1
            } else if p < 2e6 {
                -1
            } else {
                0
            }
        );
        above += (flag == 1) as usize;
    }
    assert!(
        above > 0,
        "the example table should leave the hottest elements above its range"
    );
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains(&format!("{above} above")), "{stdout}");
    let sidecar: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(st.root.join("elements.json")).unwrap())
            .unwrap();
    assert_eq!(sidecar["summary"]["n_above_range"], above);
    assert_eq!(sidecar["crate_version"], env!("CARGO_PKG_VERSION"));
    let table_hash = asperity::core::hash::sha256_file(&table_csv).unwrap();
    assert!(sidecar["inputs"]
        .as_array()
        .unwrap()
        .iter()
        .any(|i| i["sha256"] == table_hash.as_str()));
}

/// Done-when 3 of the film stage: an element table produced end to end from the reference
/// calibration table committed in `calib/` (produced by `asperity calibrate`).
#[test]
fn element_table_from_the_reference_calibration_table() {
    let st = setup();
    let out = film_reduced(&st, "out-ref");
    let reference = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("calib/calibration_table.csv");
    let table = CalibrationTable::read_csv(&reference).unwrap();
    let elements = st.root.join("elements-ref.csv");
    let o = run(&[
        "elements",
        "--preload",
        s(&out.join("preload_reduced.csv")),
        "--table",
        s(&reference),
        "--out",
        s(&elements),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let red = read_rows(&out.join("preload_reduced.csv"));
    let rows = read_rows(&elements);
    assert_eq!(rows.len(), red.len());
    let total_n0: f64 = rows.iter().map(|e| num(e, "N0_N")).sum();
    assert!((total_n0 - 150.0).abs() <= 1e-9 * 150.0, "{total_n0}");
    for e in &rows {
        let (p, a) = (num(e, "pressure_Pa"), num(e, "area_m2"));
        let v = table.interpolate(p);
        let flag: i32 = e["out_of_range"].parse().unwrap();
        assert_eq!(
            flag == 0,
            (1e5..=1e7).contains(&p),
            "pressure {p} Pa, flag {flag}"
        );
        assert!(
            (num(e, "kn_N_per_m") - v.element.kn_n_per_m3 * a).abs()
                <= 1e-8 * v.element.kn_n_per_m3 * a
        );
        assert!(
            (num(e, "E0_N_per_m") - v.element.e0_n_per_m3 * a).abs()
                <= 1e-8 * v.element.e0_n_per_m3 * a
        );
        assert!((num(e, "k") - v.element.k).abs() <= 1e-9);
        assert_eq!(num(e, "mu"), 0.6);
    }
}

#[test]
fn given_areas_are_used_and_scaled_by_the_placement() {
    let st = setup();
    let nodes = st.root.join("nodes_area.csv");
    write_nodes(&nodes, true);
    let out = st.root.join("out");
    let o = film_at_0_1_mm(
        &st.image,
        &st.table,
        &out,
        &[
            "--nodes",
            s(&nodes),
            "--node-offset-mm",
            "10,10",
            "--node-scale",
            "1.0",
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let pre = read_rows(&out.join("preload.csv"));
    assert!(pre
        .iter()
        .all(|r| (num(r, "area_m2") - 6.25e-8).abs() < 1e-20));
}

fn assert_fails(o: &Output, needles: &[&str]) {
    assert!(!o.status.success(), "should fail");
    let err = String::from_utf8_lossy(&o.stderr);
    for n in needles {
        assert!(err.contains(n), "stderr should mention `{n}`: {err}");
    }
}

#[test]
fn bad_inputs_fail_clearly_and_write_nothing() {
    let st = setup();
    let out = st.root.join("out");
    let film =
        |image: &Path, table: &Path, extra: &[&str]| film_at_0_1_mm(image, table, &out, extra);

    // Unreadable image: text with a .png name, and a missing file.
    let bogus = st.root.join("bogus.png");
    std::fs::write(&bogus, "not an image").unwrap();
    assert_fails(
        &film(&bogus, &st.table, &[]),
        &["bogus.png", "cannot read image"],
    );
    assert_fails(
        &film(&st.root.join("missing.png"), &st.table, &[]),
        &["missing.png"],
    );

    // Colour table not monotone in pressure: the file and line are named.
    let bad_table = st.root.join("bad_table.csv");
    std::fs::write(
        &bad_table,
        ";Pressure,R,G,B\n2.5,255,227,227\n4.0,255,198,198\n3.9,255,170,170\n",
    )
    .unwrap();
    assert_fails(
        &film(&st.image, &bad_table, &[]),
        &["bad_table.csv:4", "not monotone in pressure"],
    );

    // Empty region of interest.
    assert_fails(
        &film(&st.image, &st.table, &["--roi-rect-mm", "500,500,600,600"]),
        &["contains no pixel"],
    );

    // A region with no in-range pixel (the white corner).
    assert_fails(
        &film(&st.image, &st.table, &["--roi-rect-mm", "15,1,19,5"]),
        &["no in-range pixel"],
    );

    // An image without any patch.
    let blank = st.root.join("blank.png");
    image::RgbImage::from_pixel(50, 50, image::Rgb([255, 255, 255]))
        .save(&blank)
        .unwrap();
    assert_fails(&film(&blank, &st.table, &[]), &["no pressure patch"]);

    // Nodes outside the map (placement far off), and outside the fitted patch.
    assert_fails(
        &film(
            &st.image,
            &st.table,
            &["--nodes", s(&st.nodes), "--node-offset-mm", "1000,1000"],
        ),
        &["outside the film map", "node "],
    );
    assert_fails(
        &film(
            &st.image,
            &st.table,
            &["--nodes", s(&st.nodes), "--node-offset-mm", "8,10"],
        ),
        &["extrapolate"],
    );

    // Malformed nodes file.
    let bad_nodes = st.root.join("bad_nodes.csv");
    std::fs::write(&bad_nodes, "id,x_m,y_m\n1,0.0,0.0\n2,abc,0.0\n").unwrap();
    assert_fails(
        &film(
            &st.image,
            &st.table,
            &["--nodes", s(&bad_nodes), "--node-offset-mm", "10,10"],
        ),
        &["bad_nodes.csv:3", "x_m"],
    );

    // Bad pixel size.
    let o = run(&[
        "film",
        "--image",
        s(&st.image),
        "--colour-table",
        s(&st.table),
        "--pixel-size-mm",
        "-0.1",
        "--out-dir",
        s(&out),
    ]);
    assert_fails(&o, &["pixel-size-mm"]);

    // None of the failures left output behind.
    assert!(!out.exists() || std::fs::read_dir(&out).unwrap().count() == 0);

    // Elements: malformed preload file.
    let bad_pre = st.root.join("bad_preload.csv");
    std::fs::write(
        &bad_pre,
        "id,x_m,y_m,area_m2,pressure_Pa,N0_N\n1,0,0,-1,1e6,1\n",
    )
    .unwrap();
    let o = run(&[
        "elements",
        "--preload",
        s(&bad_pre),
        "--table",
        s(&st.table),
        "--out",
        s(&st.root.join("e.csv")),
    ]);
    assert_fails(&o, &["bad_preload.csv"]);
    assert!(!st.root.join("e.csv").exists());
}

/// Flags are named as the user types them, calibration files in the wrong unit and nodes that
/// cannot be triangulated are refused naming the file, and a patch of one flat colour (fitted
/// exactly by a constant) has an empty R² field instead of NaN.
#[test]
fn film_flags_units_nodes_and_uniform_patches() {
    let st = setup();
    let out = st.root.join("out-flags");
    let base = |extra: &[&str]| film_at_0_1_mm(&st.image, &st.table, &out, extra);
    assert_fails(
        &base(&["--max-colour-distance", "1000"]),
        &["--max-colour-distance", "441.7"],
    );
    let nodes = s(&st.nodes);
    for (flag, value) in [("--total-load-n", "0"), ("--node-scale", "0")] {
        let o = base(&["--nodes", nodes, "--node-offset-mm", "10,10", flag, value]);
        assert_fails(&o, &[flag]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            !err.contains("total_load_n") && !err.contains("node scale"),
            "{err}"
        );
    }

    // MPa values under a pressure_Pa header.
    let mpa = st.root.join("ct-pa-but-mpa.csv");
    std::fs::write(
        &mpa,
        "pressure_Pa,R,G,B\n2.5,255,227,227\n5,255,100,100\n10,255,0,0\n",
    )
    .unwrap();
    let o = film_at_0_1_mm(&st.image, &mpa, &out, &[]);
    assert_fails(&o, &["ct-pa-but-mpa.csv:1", "pressure_MPa"]);

    // Two nodes at one position, and collinear nodes: the nodes file is named.
    let same = st.root.join("nodes-samepos.csv");
    std::fs::write(&same, "id,x_m,y_m\n1,0,0\n2,0,0\n3,1e-3,0\n4,0,1e-3\n").unwrap();
    assert_fails(
        &base(&["--nodes", s(&same), "--node-offset-mm", "10,10"]),
        &[
            "nodes-samepos.csv",
            "node 1 (line 2)",
            "node 2 (line 3)",
            "same position",
        ],
    );
    let line = st.root.join("nodes-collinear.csv");
    std::fs::write(&line, "id,x_m,y_m\n1,0,0\n2,1e-3,0\n3,2e-3,0\n").unwrap();
    assert_fails(
        &base(&["--nodes", s(&line), "--node-offset-mm", "10,10"]),
        &["nodes-collinear.csv", "collinear"],
    );
    assert!(!out.exists());

    // A second patch of one flat colour (the 5.31 MPa row): R² undefined, no NaN anywhere.
    let mut img = image::open(&st.image).unwrap().to_rgb8();
    for (c, r, px) in img.enumerate_pixels_mut() {
        let (x, y) = (c as f64 * PIXEL_MM, (N - 1 - r) as f64 * PIXEL_MM);
        if (x - 16.5).hypot(y - 4.5) <= 1.5 {
            *px = image::Rgb([255, 142, 142]);
        }
    }
    let flat = st.root.join("flat.png");
    img.save(&flat).unwrap();
    let o = film_at_0_1_mm(&flat, &st.table, &out, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("same pressure") && err.contains("R² undefined"),
        "{err}"
    );
    let regions = read_rows(&out.join("regions.csv"));
    assert_eq!(regions.len(), 2);
    assert_eq!(regions.iter().filter(|r| r["fit_R2"].is_empty()).count(), 1);
    for f in ["regions.csv", "film.json"] {
        let text = std::fs::read_to_string(out.join(f)).unwrap();
        assert!(!text.contains("NaN"), "{f}: {text}");
    }
    assert!(!String::from_utf8_lossy(&o.stdout).contains("NaN"));
}

/// `elements` refuses an --out that is one of its inputs (it would overwrite it), a preload
/// that pulls a node or is not pressure × area, and a table whose fit_R2 exceeds 1; each error
/// names the flag or the file, line and column, and no output is left.
#[test]
fn elements_refuses_overwriting_inputs_and_unphysical_values() {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path();
    let reference = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("calib/calibration_table.csv");
    let table = root.join("table.csv");
    std::fs::copy(&reference, &table).unwrap();
    let preload = root.join("preload.csv");
    let header = "id,x_m,y_m,area_m2,pressure_Pa,N0_N\n";
    std::fs::write(
        &preload,
        format!("{header}1,0,0,1e-6,2e6,2\n2,1e-3,0,1e-6,3e6,3\n"),
    )
    .unwrap();
    let elements = |pre: &Path, tab: &Path, out: &Path| {
        run(&[
            "elements",
            "--preload",
            s(pre),
            "--table",
            s(tab),
            "--out",
            s(out),
        ])
    };
    let ok = elements(&preload, &table, &root.join("e.csv"));
    assert!(
        ok.status.success(),
        "{}",
        String::from_utf8_lossy(&ok.stderr)
    );

    // The output is an input: refused, the input unchanged (also through `..`).
    let before = std::fs::read(&table).unwrap();
    assert_fails(&elements(&preload, &table, &table), &["--out", "--table"]);
    std::fs::create_dir(root.join("sub")).unwrap();
    assert_fails(
        &elements(&preload, &table, &root.join("sub/../preload.csv")),
        &["--out", "--preload"],
    );
    assert_eq!(std::fs::read(&table).unwrap(), before);
    // The sidecar of --out (same stem, .json) would overwrite an input.
    let pre_json = root.join("pre.json");
    std::fs::copy(&preload, &pre_json).unwrap();
    assert_fails(
        &elements(&pre_json, &table, &root.join("pre.csv")),
        &["--out", "sidecar", "pre.json"],
    );
    assert!(!root.join("pre.csv").exists());

    // A negative preload, and one that is not pressure × area (5000 N for 2 MPa × 0.28 mm²).
    let bad = root.join("pl-bad.csv");
    let out = root.join("e-bad.csv");
    std::fs::write(
        &bad,
        format!("{header}1,0,0,1e-6,2e6,2\n7,0,0,2.8125e-7,2e6,-0.576\n"),
    )
    .unwrap();
    assert_fails(
        &elements(&bad, &table, &out),
        &["pl-bad.csv:3", "N0_N", "≥ 0"],
    );
    std::fs::write(&bad, format!("{header}7,0,0,2.8125e-7,2e6,5000\n")).unwrap();
    assert_fails(
        &elements(&bad, &table, &out),
        &["pl-bad.csv:2", "N0_N", "0.5625"],
    );

    // fit_R2 = 5 in the table's fourth line.
    let text = std::fs::read_to_string(&table).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let mut fields: Vec<&str> = lines[3].split(',').collect();
    fields[7] = "5.0";
    lines[3] = fields.join(",");
    let bad_table = root.join("tb-R2bad.csv");
    std::fs::write(&bad_table, lines.join("\n") + "\n").unwrap();
    assert_fails(
        &elements(&preload, &bad_table, &out),
        &["tb-R2bad.csv:4", "fit_R2", "<= 1"],
    );
    assert!(!out.exists() && !out.with_extension("json").exists());
}

#[test]
fn raw_grey_scan_with_density_calibration() {
    let dir = tempfile::tempdir().unwrap();
    // A grey disc of radius 3 mm (30 px at 0.1 mm) on white paper: luma 113 → optical density
    // D = log10(255/113) = 0.35347.
    let img = dir.path().join("scan.png");
    let mut im = image::RgbImage::from_pixel(100, 100, image::Rgb([255, 255, 255]));
    for (c, r, px) in im.enumerate_pixels_mut() {
        if (c as f64 - 50.0).hypot(r as f64 - 50.0) <= 30.0 {
            *px = image::Rgb([113, 113, 113]);
        }
    }
    im.save(&img).unwrap();
    let cal = dir.path().join("density.csv");
    std::fs::write(
        &cal,
        "# optical density of luma -> MPa\ndensity,pressure_MPa\n0.1,1.0\n0.6,6.0\n",
    )
    .unwrap();
    let out = dir.path().join("out");
    let o = run(&[
        "film",
        "--image",
        s(&img),
        "--density-calibration",
        s(&cal),
        "--pixel-size-mm",
        "0.1",
        "--fit-order",
        "0",
        "--out-dir",
        s(&out),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let regions = read_rows(&out.join("regions.csv"));
    assert_eq!(regions.len(), 1);
    let d = (255.0f64 / 113.0).log10();
    let want = 1e6 + (d - 0.1) / 0.5 * 5e6;
    assert!((num(&regions[0], "mean_pressure_Pa") - want).abs() < 1e-6 * want);
    // 2821 pixel centres within 30 px of the centre: the disc, no rim of paper.
    assert_eq!(regions[0]["n_pixels"], "2821");
}

#[test]
fn polygon_roi_and_jpeg_input() {
    let st = setup();
    // An octagon enclosing the patch (radius 4 mm about (10, 10) mm) but not the pen stroke.
    let poly: Vec<String> = (0..8)
        .map(|k| {
            let a = k as f64 * std::f64::consts::FRAC_PI_4;
            format!("{},{}", 10.0 + 5.0 * a.cos(), 10.0 + 5.0 * a.sin())
        })
        .collect();
    let out = st.root.join("poly");
    let o = film_at_0_1_mm(
        &st.image,
        &st.table,
        &out,
        &["--roi-polygon-mm", &poly.join(";")],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r = read_rows(&out.join("regions.csv"));
    assert_eq!(r.len(), 1);
    // Every pixel centre within 4 mm of the centre is in range; the rest of the octagon is paper.
    let inside = (0..N * N)
        .filter(|k| {
            let (c, rr) = (k % N, k / N);
            let (x, y) = (c as f64 * PIXEL_MM, (N - 1 - rr) as f64 * PIXEL_MM);
            (x - CX).hypot(y - CY) <= R
        })
        .count();
    assert_eq!(r[0]["n_in_range"], inside.to_string());
    assert_eq!(
        num(&r[0], "n_in_range") + num(&r[0], "n_unstained"),
        num(&r[0], "n_pixels")
    );

    // The same film as a JPEG (quality 95): compression noise stays within the colour distance
    // inside the patch; the patch is found with the same size and mean pressure within 1 %.
    let jpg = st.root.join("film.jpg");
    image::open(&st.image)
        .unwrap()
        .to_rgb8()
        .save_with_format(&jpg, image::ImageFormat::Jpeg)
        .unwrap();
    let out_j = st.root.join("jpg");
    let o = film_at_0_1_mm(&jpg, &st.table, &out_j, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let j = read_rows(&out_j.join("regions.csv"));
    assert_eq!(j.len(), 1, "{j:?}");
    let (dj, pj) = (
        num(&j[0], "equivalent_diameter_m"),
        num(&j[0], "mean_pressure_Pa"),
    );
    let pp = num(&r[0], "mean_pressure_Pa");
    assert!((dj - 8e-3).abs() < 0.2e-3, "{dj}");
    assert!((pj - pp).abs() < 0.01 * pp, "{pj} vs {pp}");
}

/// A second patch of one flat colour (the 5.31 MPa row, 1.5 mm radius at (16.5, 4.5) mm)
/// added to the setup's film: two regions.
fn two_patch_film(st: &Setup) -> PathBuf {
    let mut img = image::open(&st.image).unwrap().to_rgb8();
    for (c, r, px) in img.enumerate_pixels_mut() {
        let (x, y) = (c as f64 * PIXEL_MM, (N - 1 - r) as f64 * PIXEL_MM);
        if (x - 16.5).hypot(y - 4.5) <= 1.5 {
            *px = image::Rgb([255, 142, 142]);
        }
    }
    let path = st.root.join("two-patches.png");
    img.save(&path).unwrap();
    path
}

/// Re-using an --out-dir: the files of an earlier run that this run does not write (a reduced
/// preload file, the plots of a region that no longer exists, the preloads of a run with
/// nodes) are removed, so that `elements` cannot read a stale `preload_reduced.csv`; a file
/// that is not film's stays. Before the fix every one of them was left in place.
#[test]
fn a_rerun_into_the_same_out_dir_leaves_no_stale_file() {
    let st = setup();
    let out = st.root.join("reused");
    let two = two_patch_film(&st);
    let nodes = s(&st.nodes);
    let placed = ["--nodes", nodes, "--node-offset-mm", "10,10"];
    let mut first = placed.to_vec();
    first.extend(["--nodes-region", "1", "--reduce-mesh-size-mm", "1"]);
    let o = film_at_0_1_mm(&two, &st.table, &out, &first);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    for f in [
        "preload.csv",
        "preload_reduced.csv",
        "region_1_fitted.png",
        "region_2_fitted.png",
        "region_2_residual.png",
    ] {
        assert!(out.join(f).exists(), "{f}");
    }
    // One region, no reduction.
    let o = film_at_0_1_mm(&st.image, &st.table, &out, &placed);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in [
        "preload_reduced.csv",
        "region_2_fitted.png",
        "region_2_residual.png",
    ] {
        assert!(!out.join(f).exists(), "{f} of the first run left behind");
    }
    for f in [
        "preload.csv",
        "region_1_fitted.png",
        "notes.txt",
        "film.json",
    ] {
        assert!(out.join(f).exists(), "{f}");
    }
    // No nodes: no preload file.
    let o = film_at_0_1_mm(&st.image, &st.table, &out, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(!out.join("preload.csv").exists());
    assert!(out.join("notes.txt").exists() && out.join("regions.csv").exists());
}

/// Pressures in Pa under an MPa header, or under no header (the vendor convention is MPa),
/// would be read 10⁶ times too high (before the fix: silently, a total load of 1.9e8 N).
/// Refused, naming the file and the line of the largest pressure, with the fix (a
/// pressure_Pa header); the same for a density calibration.
#[test]
fn calibrations_in_pa_read_as_mpa_are_refused() {
    let st = setup();
    let out = st.root.join("out-pa");
    let in_pa: String = LW_TABLE
        .lines()
        .skip(1)
        .map(|l| {
            let (p, rgb) = l.split_once(',').unwrap();
            format!("{},{rgb}\n", p.parse::<f64>().unwrap() * 1e6)
        })
        .collect();
    let headerless = st.root.join("ct-pa-headerless.csv");
    std::fs::write(&headerless, &in_pa).unwrap();
    let o = film_at_0_1_mm(&st.image, &headerless, &out, &[]);
    assert_fails(
        &o,
        &[
            "ct-pa-headerless.csv:11",
            "1 GPa",
            "no header",
            "pressure_Pa",
        ],
    );
    let mpa_header = st.root.join("ct-pa-under-mpa.csv");
    std::fs::write(&mpa_header, format!("pressure_MPa,R,G,B\n{in_pa}")).unwrap();
    let o = film_at_0_1_mm(&st.image, &mpa_header, &out, &[]);
    assert_fails(
        &o,
        &["ct-pa-under-mpa.csv:12", "1 GPa", "line 1", "pressure_Pa"],
    );
    // With the header that names the unit, the same values are read right.
    let pa_header = st.root.join("ct-pa.csv");
    std::fs::write(&pa_header, format!("pressure_Pa,R,G,B\n{in_pa}")).unwrap();
    let o = film_at_0_1_mm(&st.image, &pa_header, &out, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));

    use asperity::film::colour::DensityCalibration;
    let d = st.root.join("dc.csv");
    std::fs::write(&d, "density,pressure_MPa\n0.25,2.5e6\n0.9,1e7\n").unwrap();
    let e = DensityCalibration::read_csv(&d).unwrap_err().to_string();
    assert!(
        e.contains("dc.csv:3") && e.contains("1 GPa") && e.contains("pressure_Pa"),
        "{e}"
    );
    std::fs::write(&d, "density,pressure_Pa\n0.25,2.5e6\n0.9,1e7\n").unwrap();
    assert_eq!(
        DensityCalibration::read_csv(&d).unwrap().range_pa(),
        (2.5e6, 1e7)
    );
}

/// A UTF-8 byte-order mark in front of a colour table or a density calibration (as
/// spreadsheets write them) is not part of the first field: before the fix the table read
/// "unknown pressure column `\u{feff};`".
#[test]
fn a_byte_order_mark_is_ignored() {
    let st = setup();
    let bom = st.root.join("bom.csv");
    std::fs::write(&bom, format!("\u{feff}{LW_TABLE}")).unwrap();
    let (out_bom, out_plain) = (st.root.join("out-bom"), st.root.join("out-plain"));
    let o = film_at_0_1_mm(&st.image, &bom, &out_bom, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = film_at_0_1_mm(&st.image, &st.table, &out_plain, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(
        std::fs::read_to_string(out_bom.join("regions.csv")).unwrap(),
        std::fs::read_to_string(out_plain.join("regions.csv")).unwrap()
    );
    // A header row behind the mark is read as the header.
    let bom_header = st.root.join("bom-header.csv");
    std::fs::write(
        &bom_header,
        "\u{feff}pressure_MPa,R,G,B\n0,255,255,255\n2.5,255,227,227\n9.06,255,28,28\n",
    )
    .unwrap();
    let t = asperity::film::colour::ColourTable::read_csv(&bom_header, 20.0).unwrap();
    assert_eq!(t.range_pa(), (2.5e6, 9.06e6));
    let d = st.root.join("dc-bom.csv");
    std::fs::write(&d, "\u{feff}density,pressure_MPa\n0.25,2.5\n0.9,10\n").unwrap();
    let c = asperity::film::colour::DensityCalibration::read_csv(&d).unwrap();
    assert_eq!(c.range_pa(), (2.5e6, 1e7));
}

/// LW colour of a pressure inside the range 2.5–9.06 MPa (linear along the pink scale).
fn lw_colour(p: f64) -> [u8; 3] {
    let g = lw_green(p).round() as u8;
    [255, g, g]
}

/// A Hertz-like disc `p = 14·√(1 − (r/R)²)` MPa (R = 4.5 mm, 0.1 mm pixels) on LW film: its
/// core is above the range (yellow), its edge below (green). Nodes (the setup's, a disc of
/// 3.5 mm) placed on its centre lie mostly on the saturated core, where the order-4 fit of the
/// in-range ring reads 6–9.6 MPa although the film says ≥ 9.06 MPa (R² 0.9985). Before the fix
/// nothing said so; now a warning gives the count and the contradiction, preload.csv marks
/// each node's pixel class, film.json counts them, and regions.csv gives the saturated share.
#[test]
fn nodes_on_saturated_film_are_counted_flagged_and_warned_about() {
    let st = setup();
    let n = 120u32;
    let img = image::RgbImage::from_fn(n, n, |c, r| {
        let d = (c as f64 - 60.0).hypot(r as f64 - 60.0);
        if d >= 45.0 {
            return image::Rgb([255, 255, 255]);
        }
        let p = 14e6 * (1.0 - (d / 45.0).powi(2)).sqrt();
        image::Rgb(if p < 2.5e6 {
            [0, 255, 0]
        } else if p > 9.06e6 {
            [255, 255, 0]
        } else {
            lw_colour(p)
        })
    });
    let sat = st.root.join("saturated.png");
    img.save(&sat).unwrap();
    let out = st.root.join("out-sat");
    let o = film_at_0_1_mm(
        &sat,
        &st.table,
        &out,
        &["--nodes", s(&st.nodes), "--node-offset-mm", "6,6"],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("nodes lie on pixels above the film's range (≥ 9.060 MPa)")
            && err.contains("lower bound at best")
            && err.contains("below the range's top"),
        "{err}"
    );
    assert!(
        err.contains("region 1: 60.") && err.contains("saturated"),
        "{err}"
    );
    let pre = read_rows(&out.join("preload.csv"));
    let above = pre
        .iter()
        .filter(|r| r["pixel_class"] == "above_range")
        .count();
    assert!(above > pre.len() / 2, "{above} of {}", pre.len());
    assert!(pre
        .iter()
        .all(|r| ["in_range", "above_range", "below_range", "hole"]
            .contains(&r["pixel_class"].as_str())));
    // No silent clamping: the fit's readings below the range's top are kept.
    assert!(pre
        .iter()
        .any(|r| r["pixel_class"] == "above_range" && num(r, "pressure_Pa") < 9.06e6));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("film.json")).unwrap()).unwrap();
    let classes = &json["summary"]["nodes"]["pixel_classes"];
    assert_eq!(classes["above_range"]["n_nodes"], above);
    assert_eq!(
        classes["in_range"]["n_nodes"].as_u64().unwrap() as usize
            + above
            + classes["below_range"]["n_nodes"].as_u64().unwrap() as usize
            + classes["hole"]["n_nodes"].as_u64().unwrap() as usize,
        pre.len()
    );
    let regions = read_rows(&out.join("regions.csv"));
    let f = num(&regions[0], "saturated_fraction");
    let expected = num(&regions[0], "n_above_range")
        / (num(&regions[0], "n_above_range") + num(&regions[0], "n_in_range"));
    assert!((f - expected).abs() < 1e-6 && f > 0.5, "{f} vs {expected}");
    // The preload file with its class column still feeds `elements`.
    let reference = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("calib/calibration_table.csv");
    let o = run(&[
        "elements",
        "--preload",
        s(&out.join("preload.csv")),
        "--table",
        s(&reference),
        "--out",
        s(&st.root.join("el.csv")),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// A region of interest holds white film as well as the patch: nodes are read only on its
/// stained pixels (and the holes they enclose), as on an automatic patch. Before the fix a node
/// on white film inside an ROI read the polynomial's extrapolation, and the error for a node
/// off an automatic patch suggested an ROI as the way round the check.
#[test]
fn a_region_of_interest_reads_nodes_only_on_its_stain() {
    let st = setup();
    let roi = ["--roi-rect-mm", "4,4,16,16"];
    // The setup's nodes (radius 3.5 mm) on the patch (radius 4 mm): fine.
    let mut ok = roi.to_vec();
    ok.extend(["--nodes", s(&st.nodes), "--node-offset-mm", "10,10"]);
    let out = st.root.join("out-roi");
    let o = film_at_0_1_mm(&st.image, &st.table, &out, &ok);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // One node 5 mm from the patch centre: inside the ROI, on white film.
    let white = st.root.join("nodes-white.csv");
    std::fs::write(&white, "id,x_m,y_m\n1,0,0\n2,1e-3,0\n3,0,1e-3\n4,5e-3,0\n").unwrap();
    let out_w = st.root.join("out-roi-white");
    let mut bad = roi.to_vec();
    bad.extend(["--nodes", s(&white), "--node-offset-mm", "10,10"]);
    let o = film_at_0_1_mm(&st.image, &st.table, &out_w, &bad);
    assert_fails(
        &o,
        &[
            "nodes-white.csv",
            "node 4 (line 5)",
            "unstained and not enclosed by its stain",
            "would extrapolate",
        ],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("--roi"), "{err}");
    assert!(!out_w.exists());
    // The same node off an automatic patch: the same refusal, with no ROI suggested.
    let auto = ["--nodes", s(&white), "--node-offset-mm", "10,10"];
    let o = film_at_0_1_mm(&st.image, &st.table, &out_w, &auto);
    assert_fails(
        &o,
        &["node 4 (line 5)", "off region 1", "would extrapolate"],
    );
    assert!(!String::from_utf8_lossy(&o.stderr).contains("--roi"));
}

/// A colour table without a 0-pressure row does not say what unstained paper looks like:
/// before the fix, white paper was read as "stained below range" (94.7 % of a film) and every
/// patch grew by a rim of white film (+33 % area). Refused, naming the file and the fix.
#[test]
fn a_colour_table_without_the_paper_colour_is_refused() {
    let st = setup();
    let no_paper = st.root.join("ct-no-paper.csv");
    let text: String = LW_TABLE
        .lines()
        .filter(|l| !l.starts_with("0.00,"))
        .map(|l| format!("{l}\n"))
        .collect();
    assert_eq!(text.lines().count(), LW_TABLE.lines().count() - 1);
    std::fs::write(&no_paper, text).unwrap();
    let out = st.root.join("out-no-paper");
    let o = film_at_0_1_mm(&st.image, &no_paper, &out, &[]);
    assert_fails(
        &o,
        &["ct-no-paper.csv", "no row at pressure 0", "0,255,255,255"],
    );
    assert!(!out.exists());
}

/// An uncompressed 8-bit RGB TIFF of `w × h` pixels (`px(column, row from the top)`) declaring
/// `Orientation = orientation` and 254 dpi.
fn write_tiff(path: &Path, w: u32, h: u32, px: impl Fn(u32, u32) -> [u8; 3], orientation: u16) {
    let mut data = Vec::new();
    for r in 0..h {
        for c in 0..w {
            data.extend_from_slice(&px(c, r));
        }
    }
    let off_data = 8u32;
    let off_bps = off_data + data.len() as u32;
    let off_xres = off_bps + 6;
    let off_yres = off_xres + 8;
    let off_ifd = off_yres + 8;
    // (tag, type, count, value): type 3 SHORT, 4 LONG, 5 RATIONAL.
    let tags: [(u16, u16, u32, u32); 13] = [
        (256, 3, 1, w),
        (257, 3, 1, h),
        (258, 3, 3, off_bps),
        (259, 3, 1, 1),
        (262, 3, 1, 2),
        (273, 4, 1, off_data),
        (274, 3, 1, orientation as u32),
        (277, 3, 1, 3),
        (278, 3, 1, h),
        (279, 4, 1, data.len() as u32),
        (282, 5, 1, off_xres),
        (283, 5, 1, off_yres),
        (296, 3, 1, 2),
    ];
    let mut out = b"II*\0".to_vec();
    out.extend(off_ifd.to_le_bytes());
    out.extend(&data);
    for v in [8u16, 8, 8] {
        out.extend(v.to_le_bytes());
    }
    for _ in 0..2 {
        out.extend(254u32.to_le_bytes());
        out.extend(1u32.to_le_bytes());
    }
    out.extend((tags.len() as u16).to_le_bytes());
    for (tag, typ, count, value) in tags {
        out.extend(tag.to_le_bytes());
        out.extend(typ.to_le_bytes());
        out.extend(count.to_le_bytes());
        if typ == 3 && count == 1 {
            out.extend((value as u16).to_le_bytes());
            out.extend(0u16.to_le_bytes());
        } else {
            out.extend(value.to_le_bytes());
        }
    }
    out.extend(0u32.to_le_bytes());
    std::fs::write(path, out).unwrap();
}

/// A TIFF whose pixels are stored 200 × 100 with a disc at column 40, row 30, tagged
/// Orientation = 6 (display rotated 90° clockwise: 100 × 200, the disc at column 69, row 40).
/// The film frame is the displayed image: the patch is found there. Before the fix the tag was
/// ignored and the patch came out at the stored position (4.0, 6.9) mm, not (6.9, 15.9) mm.
#[test]
fn the_exif_orientation_of_an_image_is_applied() {
    let dir = tempfile::tempdir().unwrap();
    let table = dir.path().join("lw.csv");
    std::fs::write(&table, LW_TABLE).unwrap();
    let disc = |c: u32, r: u32| {
        if (c as f64 - 40.0).hypot(r as f64 - 30.0) < 20.0 {
            [255, 142, 142]
        } else {
            [255, 255, 255]
        }
    };
    let centre = |orientation: u16| {
        let tif = dir.path().join(format!("o{orientation}.tif"));
        write_tiff(&tif, 200, 100, disc, orientation);
        let out = dir.path().join(format!("out{orientation}"));
        let o = film_at_0_1_mm(&tif, &table, &out, &[]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let err = String::from_utf8_lossy(&o.stderr).to_string();
        let r = read_rows(&out.join("regions.csv"));
        assert_eq!(r.len(), 1);
        (
            num(&r[0], "centre_x_m") * 1e3,
            num(&r[0], "centre_y_m") * 1e3,
            err,
        )
    };
    let (x1, y1, e1) = centre(1);
    assert!(e1.contains("200 × 100 px"), "{e1}");
    assert!(
        (x1 - 4.0).abs() < 0.05 && (y1 - 6.9).abs() < 0.05,
        "{x1} {y1}"
    );
    let (x6, y6, e6) = centre(6);
    assert!(e6.contains("100 × 200 px"), "{e6}");
    assert!(
        (x6 - 6.9).abs() < 0.05 && (y6 - 15.9).abs() < 0.05,
        "{x6} {y6}"
    );
}
