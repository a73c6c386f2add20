//! `asperity contact normal` end to end: outputs and error paths (non-zero exit, message naming
//! the parameter, no output left behind). Units: SI.

use std::path::Path;
use std::process::Command;

#[path = "support/hertz_window.rs"]
mod hertz_window;
use hertz_window::write_hertz_window;

fn asperity(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args(args)
        .output()
        .expect("run asperity");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn assert_no_output(dir: &Path) {
    if dir.exists() {
        let left: Vec<_> = std::fs::read_dir(dir).unwrap().collect();
        assert!(left.is_empty(), "output left behind: {left:?}");
    }
}

#[test]
fn bad_parameters_fail_cleanly() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let out_s = out.to_str().unwrap();
    for (args, needle) in [
        (vec!["--pressures-pa", "0"], "--pressures-pa"),
        (vec!["--pressures-pa", "1e6,-2e6"], "--pressures-pa"),
        (vec!["--pressures-pa", "NaN"], "--pressures-pa"),
        (vec!["--pressures-pa", "1e6,1e6"], "twice"),
        (vec!["--poisson-ratio", "0.7"], "--poisson-ratio"),
        (vec!["--youngs-modulus-pa=-2e11"], "--youngs-modulus-pa"),
        (vec!["--tolerance", "0"], "--tolerance"),
        (vec!["--method", "multigrid"], "--method"),
    ] {
        let mut full = vec!["contact", "normal", "--out-dir", out_s];
        full.extend(args.iter());
        let (ok, _, err) = asperity(&full);
        assert!(!ok, "{args:?} should fail");
        assert!(err.contains(needle), "{args:?}: {err}");
        assert_no_output(&out);
    }
}

#[test]
fn non_convergence_is_an_error_without_output() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let (ok, _, err) = asperity(&[
        "contact",
        "normal",
        "--out-dir",
        out.to_str().unwrap(),
        "--pressures-pa",
        "1e6",
        "--max-iterations",
        "2",
    ]);
    assert!(!ok);
    assert!(err.contains("did not converge"), "{err}");
    assert_no_output(&out);
}

/// A small periodic height matrix: sum of two cosines (heights in m, 32² points of 1 µm).
fn write_wavy_matrix(path: &Path, nan_at: Option<(usize, usize)>) {
    let n = 32;
    let mut text = String::from(
        "# asperity height matrix\n# unit: m, dx_m: 1e-6, dy_m: 1e-6, periodic: true\n",
    );
    for j in 0..n {
        let row: Vec<String> = (0..n)
            .map(|i| {
                if nan_at == Some((i, j)) {
                    return "nan".to_string();
                }
                let (x, y) = (i as f64 / n as f64, j as f64 / n as f64);
                let h = 0.2e-6
                    * ((2.0 * std::f64::consts::PI * x).cos()
                        + (2.0 * std::f64::consts::PI * y).cos())
                    + 0.05e-6 * (6.0 * std::f64::consts::PI * x).sin();
                format!("{h:e}")
            })
            .collect();
        text.push_str(&row.join(", "));
        text.push('\n');
    }
    std::fs::write(path, text).unwrap();
}

#[test]
fn sweep_on_a_surface_file_writes_csv_and_plots() {
    let tmp = tempfile::tempdir().unwrap();
    let surf = tmp.path().join("wavy.txt");
    write_wavy_matrix(&surf, None);
    let out = tmp.path().join("out");
    let (ok, stdout, err) = asperity(&[
        "contact",
        "normal",
        "--surface",
        surf.to_str().unwrap(),
        "--pressures-pa",
        "20e6,5e6,50e6",
        "--out-dir",
        out.to_str().unwrap(),
        "--pressure-maps",
    ]);
    assert!(ok, "{err}");
    assert!(stdout.contains("β ="), "{stdout}");
    let csv = std::fs::read_to_string(out.join("normal_sweep.csv")).unwrap();
    let mut lines = csv.lines().filter(|l| !l.starts_with('#'));
    let header = lines.next().unwrap();
    assert!(header.starts_with("surface,pressure_Pa,contact_area_ratio,mean_gap_m,kn_N_per_m3"));
    let label = surf.to_str().unwrap();
    let rows: Vec<Vec<f64>> = lines
        .map(|l| {
            let (surface, values) = l.split_once(',').unwrap();
            assert_eq!(surface, label);
            values
                .split(',')
                .take(4)
                .map(|v| v.parse().unwrap())
                .collect()
        })
        .collect();
    assert_eq!(rows.len(), 3);
    // Sorted by pressure; area grows, mean gap closes, kn rises.
    assert_eq!(rows[0][0], 5e6);
    for w in rows.windows(2) {
        assert!(w[1][0] > w[0][0] && w[1][1] > w[0][1] && w[1][2] < w[0][2] && w[1][3] > w[0][3]);
    }
    for f in [
        "area_ratio.png",
        "mean_gap.png",
        "kn.png",
        "pressure_map_5e6Pa.png",
        "pressure_map_2e7Pa.png",
        "pressure_map_5e7Pa.png",
    ] {
        assert!(image::open(out.join(f)).is_ok(), "{f}");
    }
}

#[test]
fn nan_surface_and_missing_file_fail_cleanly() {
    let tmp = tempfile::tempdir().unwrap();
    let surf = tmp.path().join("nan.txt");
    write_wavy_matrix(&surf, Some((3, 5)));
    let out = tmp.path().join("out");
    let (ok, _, err) = asperity(&[
        "contact",
        "normal",
        "--surface",
        surf.to_str().unwrap(),
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(err.contains("nan.txt"), "{err}");
    assert_no_output(&out);
    let (ok, _, err) = asperity(&[
        "contact",
        "normal",
        "--surface",
        tmp.path().join("absent.npy").to_str().unwrap(),
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(err.contains("absent.npy"), "{err}");
    assert_no_output(&out);
}

/// A Hertz contact inside its window matches Hertz and gives no window warning; loaded until its
/// radius (Hertz: 130 µm) exceeds the half-window (100 µm), the contact is cut by the window:
/// the sweep warns that it reaches the window's edge (console and CSV) and does not advise a
/// finer grid, which would not help.
#[test]
fn contact_reaching_the_window_edge_is_flagged() {
    let tmp = tempfile::tempdir().unwrap();
    let (n, l) = (32, 200e-6);
    let surf = tmp.path().join("hertz.csv");
    write_hertz_window(&surf, n, l);
    let e_star = 210e9 / (2.0 * (1.0 - 0.09)); // two steel bodies
                                               // Nominal pressures giving Hertz radii a = 60 µm and 130 µm: p = 4E*a³/(3R L²).
    let p_of = |a: f64| 4.0 * e_star * a * a * a / (3.0 * 0.01 * l * l);
    let (p_in, p_edge) = (p_of(60e-6), p_of(130e-6));
    let out = tmp.path().join("out");
    let (ok, stdout, err) = asperity(&[
        "contact",
        "normal",
        "--surface",
        surf.to_str().unwrap(),
        "--pressures-pa",
        &format!("{p_in:e},{p_edge:e}"),
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let csv = std::fs::read_to_string(out.join("normal_sweep.csv")).unwrap();
    let rows: Vec<Vec<String>> = csv
        .lines()
        .filter(|l| !l.starts_with('#'))
        .skip(1)
        .map(|l| l.split(',').map(String::from).collect())
        .collect();
    // Inside the window: Hertz area π a² / L² and kn = 2E*a / L² (9.6 points per radius; the
    // solver gives +1.2 % and −0.7 %).
    let area: f64 = rows[0][2].parse().unwrap();
    let kn: f64 = rows[0][4].parse().unwrap();
    let a = 60e-6;
    assert!(
        (area / (std::f64::consts::PI * a * a / (l * l)) - 1.0).abs() < 0.05,
        "{area}"
    );
    assert!(
        (kn / (2.0 * e_star * a / (l * l)) - 1.0).abs() < 0.03,
        "{kn}"
    );
    // Only the second pressure is flagged, in the console and in the CSV header.
    let lines: Vec<&str> = stdout.lines().collect();
    let row_of = |p: &str| {
        *lines
            .iter()
            .find(|l| l.trim_start().starts_with(p))
            .unwrap()
    };
    let edge_row = row_of(&format!("{:.4}", p_edge / 1e6));
    assert!(edge_row.contains("reaches the window's edge"), "{stdout}");
    assert!(!edge_row.contains("refine the grid"), "{stdout}");
    assert!(
        !row_of(&format!("{:.4}", p_in / 1e6)).contains("window"),
        "{stdout}"
    );
    assert!(
        stdout.contains("warning:") && stdout.contains("enlarge the window"),
        "{stdout}"
    );
    let warning: Vec<&str> = csv
        .lines()
        .filter(|l| l.starts_with("# warning:"))
        .collect();
    assert_eq!(warning.len(), 1, "{csv}");
    assert!(
        warning[0].contains("edge of the non-periodic window")
            && warning[0].contains(&format!("{p_edge:e} Pa"))
            && !warning[0].contains(&format!("{p_in:e} Pa")),
        "{csv}"
    );
}

/// Two --surface files are realisations of one surface (mean ± std), not two bodies as in
/// `contact tangential`: the command says so. Two copies of one surface give a zero standard
/// deviation and the single surface's mean.
#[test]
fn several_surfaces_are_named_realisations() {
    let tmp = tempfile::tempdir().unwrap();
    let (a, b) = (tmp.path().join("a.txt"), tmp.path().join("b.txt"));
    write_wavy_matrix(&a, None);
    write_wavy_matrix(&b, None);
    let out = tmp.path().join("out");
    let (ok, _, err) = asperity(&[
        "contact",
        "normal",
        "--surface",
        a.to_str().unwrap(),
        "--surface",
        b.to_str().unwrap(),
        "--pressures-pa",
        "5e6",
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(
        err.contains("2 surfaces: treated as 2 realisations of one surface (mean ± std)")
            && err.contains("composite surface (h1 − h2"),
        "{err}"
    );
    let stats = std::fs::read_to_string(out.join("normal_sweep_statistics.csv")).unwrap();
    let row: Vec<f64> = stats
        .lines()
        .filter(|l| !l.starts_with('#'))
        .nth(1)
        .unwrap()
        .split(',')
        .map(|v| v.parse().unwrap())
        .collect();
    assert_eq!(row[1], 2.0);
    assert_eq!(row[3], 0.0, "std of two identical surfaces: {stats}");
}

/// Westergaard's sinusoid (periodic, `h = g·cos(2πx/λ)`) is in full contact above
/// `p* = π E* g/λ`: there the half-space's normal stiffness is infinite, and the sweep says
/// "full contact" instead of "kn is inf". Below `p*` it runs.
#[test]
fn full_contact_is_named_as_such() {
    let dir = tempfile::tempdir().unwrap();
    let (n, dx, g) = (16usize, 1e-6, 0.02e-6);
    let mut text = format!(
        "# asperity height matrix\n# unit: m, dx_m: {dx:e}, dy_m: {dx:e}, periodic: true\n"
    );
    for _ in 0..n {
        let row: Vec<String> = (0..n)
            .map(|i| {
                format!(
                    "{:e}",
                    g * (2.0 * std::f64::consts::PI * i as f64 / n as f64).cos()
                )
            })
            .collect();
        text += &row.join(",");
        text.push('\n');
    }
    let wave = dir.path().join("wave.csv");
    std::fs::write(&wave, text).unwrap();
    let e_star = 210e9 / (1.0 - 0.3f64 * 0.3);
    let p_star = std::f64::consts::PI * e_star * g / (n as f64 * dx);
    let out = dir.path().join("full");
    let (ok, _, err) = asperity(&[
        "contact",
        "normal",
        "--surface",
        wave.to_str().unwrap(),
        "--pressures-pa",
        &format!("{:e}", 1.2 * p_star),
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    assert!(
        !ok && err.contains("full contact") && err.contains("wave.csv"),
        "{err}"
    );
    assert_no_output(&out);
    let out = dir.path().join("partial");
    let (ok, _, err) = asperity(&[
        "contact",
        "normal",
        "--surface",
        wave.to_str().unwrap(),
        "--pressures-pa",
        &format!("{:e}", 0.5 * p_star),
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
}

/// A 32 × 32 non-periodic window of the wavy pattern of [`write_wavy_matrix`] plus a plane
/// rising `tilt_m` along x across the window.
fn write_tilted_window(path: &Path, tilt_m: f64) {
    let n = 32;
    let mut text = String::from(
        "# asperity height matrix\n# unit: m, dx_m: 1e-6, dy_m: 1e-6, periodic: false\n",
    );
    for j in 0..n {
        let row: Vec<String> = (0..n)
            .map(|i| {
                let (x, y) = (i as f64 / n as f64, j as f64 / n as f64);
                let h = 0.2e-6
                    * ((2.0 * std::f64::consts::PI * x).cos()
                        + (2.0 * std::f64::consts::PI * y).cos())
                    + 0.05e-6 * (6.0 * std::f64::consts::PI * x).sin()
                    + tilt_m * i as f64 / (n - 1) as f64;
                format!("{h:e}")
            })
            .collect();
        text.push_str(&row.join(", "));
        text.push('\n');
    }
    std::fs::write(path, text).unwrap();
}

/// `(pressure_Pa, contact_area_ratio, mean_gap_m, kn_N_per_m3)` rows of a sweep's CSV.
fn sweep_rows(dir: &Path) -> Vec<[f64; 4]> {
    let csv = std::fs::read_to_string(dir.join("normal_sweep.csv")).unwrap();
    csv.lines()
        .filter(|l| !l.starts_with('#'))
        .skip(1)
        .map(|l| {
            let v: Vec<f64> = l
                .split(',')
                .skip(1)
                .take(4)
                .map(|v| v.parse().unwrap())
                .collect();
            [v[0], v[1], v[2], v[3]]
        })
        .collect()
}

/// The tilt warning names the remedy, and the remedy works: `surface convert --detrend plane`
/// of the tilted window gives, to round-off, the contact of the same window levelled from its
/// untilted heights (removing the least-squares plane is linear, so the added tilt leaves no
/// trace), with no warning; the tilted window's own contact differs (kn 45 % lower here).
#[test]
fn a_tilted_window_is_flagged_and_levelled_by_convert() {
    let tmp = tempfile::tempdir().unwrap();
    let p = |name: &str| tmp.path().join(name).to_str().unwrap().to_string();
    write_tilted_window(&tmp.path().join("tilted.txt"), 2e-6);
    write_tilted_window(&tmp.path().join("flat.txt"), 0.0);
    let normal = |surface: &str, out: &str| {
        asperity(&[
            "contact",
            "normal",
            "--surface",
            surface,
            "--pressures-pa",
            "20e6,50e6",
            "--out-dir",
            out,
        ])
    };
    let (ok, _, err) = normal(&p("tilted.txt"), &p("out-tilted"));
    assert!(ok, "{err}");
    assert!(
        err.contains("least-squares plane of the heights rises")
            && err.contains("surface convert <file> --detrend plane"),
        "{err}"
    );
    for name in ["tilted", "flat"] {
        let (ok, _, err) = asperity(&[
            "surface",
            "convert",
            &p(&format!("{name}.txt")),
            "--detrend",
            "plane",
            "-o",
            &p(&format!("{name}-level.npy")),
        ]);
        assert!(ok, "{err}");
        assert!(err.contains("removed the least-squares plane"), "{err}");
    }
    let (ok, _, err) = normal(&p("tilted-level.npy"), &p("out-tilted-level"));
    assert!(ok, "{err}");
    assert!(
        !err.contains("least-squares plane of the heights rises"),
        "{err}"
    );
    let (ok, _, err) = normal(&p("flat-level.npy"), &p("out-flat-level"));
    assert!(ok, "{err}");
    let tilted = sweep_rows(&tmp.path().join("out-tilted"));
    let levelled = sweep_rows(&tmp.path().join("out-tilted-level"));
    let reference = sweep_rows(&tmp.path().join("out-flat-level"));
    for ((l, r), t) in levelled.iter().zip(&reference).zip(&tilted) {
        for k in 0..4 {
            assert!((l[k] - r[k]).abs() <= 1e-6 * r[k].abs(), "{l:?} vs {r:?}");
        }
        assert!(
            (t[3] / r[3] - 1.0).abs() > 0.1,
            "tilted kn {} vs {}",
            t[3],
            r[3]
        );
    }
    // A bad value is refused naming the flag, nothing written.
    let (ok, _, err) = asperity(&[
        "surface",
        "convert",
        &p("flat.txt"),
        "--detrend",
        "tilt",
        "-o",
        &p("bad.npy"),
    ]);
    assert!(!ok && err.contains("--detrend"), "{err}");
    assert!(!tmp.path().join("bad.npy").exists());
}

/// One small-strain limit through every door: the benchmark's self-affine surface (rms gradient
/// 0.1) at p̄ = 0.053·E* (BENCHMARKS.md, p̄/E*h' = 0.53) runs through the CLI, and 0.11·E* is
/// refused by the CLI and by the library's solver alike, each naming its own parameter.
#[test]
fn one_pressure_limit_through_every_door() {
    use asperity::contact::normal::{NormalOptions, NormalProblem, NormalSolver};
    let tmp = tempfile::tempdir().unwrap();
    let sa = tmp.path().join("sa.npy");
    let (ok, _, err) = asperity(&[
        "surface",
        "self-affine",
        "--n",
        "128",
        "-o",
        sa.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let e_star = 210e9 / (2.0 * (1.0 - 0.3 * 0.3));
    let out = tmp.path().join("out");
    let (ok, stdout, err) = asperity(&[
        "contact",
        "normal",
        "--surface",
        sa.to_str().unwrap(),
        "--pressures-pa",
        &format!("{:e}", 0.053 * e_star),
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "0.053·E* refused: {err}");
    assert!(stdout.contains("wrote"), "{stdout}");
    let out2 = tmp.path().join("out2");
    let (ok, _, err) = asperity(&[
        "contact",
        "normal",
        "--surface",
        sa.to_str().unwrap(),
        "--pressures-pa",
        &format!("{:e}", 0.11 * e_star),
        "--out-dir",
        out2.to_str().unwrap(),
    ]);
    assert!(
        !ok && err.contains("--pressures-pa") && err.contains("0.1 × E*"),
        "{err}"
    );
    assert_no_output(&out2);
    let grid = asperity::surface::io::read(&sa).unwrap();
    let asperity::surface::Topography::Area(grid) = grid else {
        panic!("an area")
    };
    let mut solver = NormalSolver::new(
        &NormalProblem {
            surface: &grid,
            e_star_pa: e_star,
            hardness_pa: None,
        },
        NormalOptions::default(),
    )
    .unwrap();
    let e = solver
        .solve_load(0.11 * e_star, None)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("mean_pressure_pa") && e.contains("0.1 × E*"),
        "{e}"
    );
    let sol = solver.solve_load(0.053 * e_star, None).unwrap();
    assert!(
        (0.5..0.95).contains(&sol.contact_area_ratio),
        "{}",
        sol.contact_area_ratio
    );
}
