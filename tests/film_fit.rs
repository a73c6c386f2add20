//! Done-when 2: a synthetic film rendered from a known order-4 pressure field through the Prescale
//! LW colour table is fitted back (R² > 0.999, coefficients within 1e-3 relative), through the
//! binary, from a 16-bit PNG and a 16-bit TIFF.

use std::path::Path;
use std::process::Command;

#[path = "support/lw_scale.rs"]
mod lw_scale;
use lw_scale::lw_green;

/// The Prescale LW vendor table as the app exports it (MPa, R, G, B; `;` comments).
const LW_TABLE: &str = ";,,,\n;LW,,,\n;Pressure,R,G,B\n0.00,255.0,255.0,255.0\n2.00,0.0,255.0,0.0\n2.50,255.0,227.0,227.0\n3.44,255.0,198.0,198.0\n4.38,255.0,170.0,170.0\n5.31,255.0,142.0,142.0\n6.25,255.0,113.0,113.0\n7.19,255.0,85.0,85.0\n8.13,255.0,57.0,57.0\n9.06,255.0,28.0,28.0\n10.00,255.0,255.0,0.0\n";

const W: u32 = 240;
const H: u32 = 200;
const PIXEL_MM: f64 = 0.1;

/// Known coefficients c_ab (Pa) of σ = Σ c_ab u^a v^b, in the order 1, u, v, u², uv, v², u³, …
/// with u, v ∈ [−1, 1] over the image's pixel centres. σ stays within 3.2–8.4 MPa.
const TRUTH: [f64; 15] = [
    5.8e6, 0.25e6, -0.20e6, -0.18e6, 0.15e6, 0.22e6, 0.12e6, -0.14e6, 0.16e6, -0.13e6, 0.17e6,
    -0.12e6, 0.14e6, 0.13e6, -0.15e6,
];

fn sigma(u: f64, v: f64) -> f64 {
    let mut k = 0;
    let mut s = 0.0;
    for d in 0..=4 {
        for b in 0..=d {
            s += TRUTH[k] * u.powi(d - b) * v.powi(b);
            k += 1;
        }
    }
    s
}

/// LW colour of a pressure (linear along the graded rows 2.5–9.06 MPa).
fn lw_colour(p: f64) -> [f64; 3] {
    let g = lw_green(p);
    [255.0, g, g]
}

fn render(path: &Path) {
    let mut img = image::ImageBuffer::<image::Rgb<u16>, Vec<u16>>::new(W, H);
    for (c, r, px) in img.enumerate_pixels_mut() {
        // Film frame: x = c·s, y = (H − 1 − r)·s; scaled coordinates over the pixel centres.
        let u = 2.0 * c as f64 / (W - 1) as f64 - 1.0;
        let v = 2.0 * (H - 1 - r) as f64 / (H - 1) as f64 - 1.0;
        let rgb = lw_colour(sigma(u, v));
        *px = image::Rgb(rgb.map(|x| (x / 255.0 * 65535.0).round() as u16));
    }
    img.save(path).unwrap();
}

fn fit_back(image: &Path, out: &Path, table: &Path) -> (f64, Vec<f64>) {
    let st = Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args(["film", "--image"])
        .arg(image)
        .arg("--colour-table")
        .arg(table)
        .args([
            "--pixel-size-mm",
            "0.1",
            "--fit-order",
            "4",
            "--roi-rect-mm",
            "-1,-1,100,100",
        ])
        .arg("--out-dir")
        .arg(out)
        .output()
        .unwrap();
    assert!(
        st.status.success(),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
    let regions = std::fs::read_to_string(out.join("regions.csv")).unwrap();
    let mut lines = regions.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let row: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |n: &str| header.iter().position(|h| *h == n).unwrap();
    let r2: f64 = row[col("fit_R2")].parse().unwrap();
    assert_eq!(row[col("n_in_range")], (W * H).to_string());
    let coefs = std::fs::read_to_string(out.join("fit_coefficients.csv")).unwrap();
    let c: Vec<f64> = coefs
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("region_id"))
        .map(|l| l.split(',').nth(8).unwrap().parse().unwrap())
        .collect();
    // The fit frame is the bounding box of the pixel centres, the frame TRUTH is written in.
    let frame: Vec<f64> = coefs
        .lines()
        .find(|l| l.starts_with("1,"))
        .unwrap()
        .split(',')
        .skip(2)
        .take(4)
        .map(|s| s.parse().unwrap())
        .collect();
    let xc = (W - 1) as f64 * PIXEL_MM * 1e-3 / 2.0;
    let yc = (H - 1) as f64 * PIXEL_MM * 1e-3 / 2.0;
    for (got, want) in frame.iter().zip([xc, yc, xc, yc]) {
        assert!((got - want).abs() < 1e-12, "{frame:?}");
    }
    (r2, c)
}

#[test]
fn order_4_field_rendered_through_the_lw_table_is_fitted_back() {
    let dir = tempfile::tempdir().unwrap();
    let table = dir.path().join("lw.csv");
    std::fs::write(&table, LW_TABLE).unwrap();
    for ext in ["png", "tiff"] {
        let img = dir.path().join(format!("synthetic.{ext}"));
        render(&img);
        let (r2, c) = fit_back(&img, &dir.path().join(format!("out-{ext}")), &table);
        eprintln!("{ext}: R² = {r2}");
        assert!(r2 > 0.999, "R² = {r2}");
        assert_eq!(c.len(), TRUTH.len());
        for (k, (got, want)) in c.iter().zip(TRUTH).enumerate() {
            let rel = (got - want).abs() / want.abs();
            eprintln!("c[{k}] = {got:.6e} (truth {want:.6e}), relative error {rel:.2e}");
            assert!(rel < 1e-3, "coefficient {k}: {got} vs {want}");
        }
    }
}
