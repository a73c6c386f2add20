//! Hardness-limited (elastic–perfectly plastic, pressure-saturated) normal contact against
//! closed forms: the fully plastic limit `A = P/H`, Hertz below and above the saturation load
//! `P_H = (πH)³R²/(6E*²)`, the unloading stiffness `2E*a` of a flat punch and of a plastically
//! flattened sphere (Barber's theorem), the residual surface, and the elastic limit `H → ∞`.
//! The comparison with tamaas' `KatoSaturated` on the same surface is at the end (it runs when
//! the peers' venv exists, `benches/peers/setup.sh`).
//! Units: SI (m, Pa, N).

use asperity::contact::analytic::{flat_punch_stiffness, hertz_saturation_load, Hertz};
use asperity::contact::normal::{NormalMethod, NormalOptions, NormalProblem, NormalSolver};
use asperity::surface::self_affine::{generate_self_affine, SelfAffineSpec};
use asperity::Grid2;
use ndarray::Array2;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

fn solver(surface: &Grid2, e_star: f64, hardness: Option<f64>) -> NormalSolver {
    NormalSolver::new(
        &NormalProblem {
            surface,
            e_star_pa: e_star,
            hardness_pa: hardness,
        },
        NormalOptions::default(),
    )
    .unwrap()
}

/// Sphere of radius `radius` with its apex on the centre point of an `n × n` zero-padded window.
fn sphere(n: usize, dx: f64, radius: f64) -> Grid2 {
    let c = (n / 2) as f64;
    let heights = Array2::from_shape_fn((n, n), |(i, j)| {
        let (x, y) = ((i as f64 - c) * dx, (j as f64 - c) * dx);
        -(x * x + y * y) / (2.0 * radius)
    });
    Grid2::new(heights, dx, dx, false).unwrap()
}

/// Rigid flat-ended circular punch of radius `a` (its face at height 0, the rest 1 mm lower) at
/// the centre of an `n × n` zero-padded window.
fn flat_punch(n: usize, dx: f64, a: f64) -> Grid2 {
    let c = (n / 2) as f64;
    let heights = Array2::from_shape_fn((n, n), |(i, j)| {
        let r = ((i as f64 - c) * dx).hypot((j as f64 - c) * dx);
        if r <= a {
            0.0
        } else {
            -1e-3
        }
    });
    Grid2::new(heights, dx, dx, false).unwrap()
}

fn self_affine(n: usize, seed: u64) -> Grid2 {
    generate_self_affine(&SelfAffineSpec::benchmark(n, 1e-3, seed)).unwrap()
}

/// Hertz with cut-off: below `P_H` no point saturates (the solution is Hertz's), just above it
/// the centre saturates; well above it the contact is larger than Hertz's at the same load and
/// carries the load between its plastic and its whole area at H.
///
/// Tolerances: the grid's peak pressure is within 0.01 % of Hertz's p0 at 84 points across
/// (`tests/normal_contact.rs`); 60 points across here, so the onset is bracketed at ±1 % of
/// `P_H` (±0.33 % in p0).
#[test]
fn sphere_saturates_at_the_hertz_load_and_spreads_beyond_it() {
    let (radius, e_star, hardness) = (0.01, 1.0e11, 2.0e9);
    let p_h = hertz_saturation_load(radius, hardness, e_star);
    let a_h = Hertz::new(radius, p_h, e_star).radius;
    assert!((Hertz::new(radius, p_h, e_star).peak_pressure / hardness - 1.0).abs() < 1e-12);
    let n = 128;
    // 60 points across the contact at P_H; window 2.1 × that diameter.
    let dx = 2.0 * a_h / 60.0;
    let s = sphere(n, dx, radius);
    let mut plastic = solver(&s, e_star, Some(hardness));
    let mut elastic = solver(&s, e_star, None);
    let area = s.area();
    let below = plastic.solve_load(0.99 * p_h / area, None).unwrap();
    assert_eq!(below.plastic_points, 0, "0.99 P_H: no saturation");
    let reference = elastic.solve_load(0.99 * p_h / area, None).unwrap();
    assert_eq!(below.contact_points, reference.contact_points);
    let dp = (&below.pressure - &reference.pressure)
        .iter()
        .fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(
        dp < 1e-6 * hardness,
        "below P_H the solution is elastic: {dp:e} Pa"
    );
    let above = plastic.solve_load(1.01 * p_h / area, None).unwrap();
    assert!(above.plastic_points > 0, "1.01 P_H: the centre saturates");
    for factor in [3.0, 10.0, 30.0] {
        let force = factor * p_h;
        // A coarser window for the larger contacts (the contact radius grows ~ √P at full
        // plasticity).
        let radius_pl = (force / (PI * hardness)).sqrt();
        let dx = 2.0 * radius_pl / 60.0;
        let s = sphere(n, dx, radius);
        let sol = solver(&s, e_star, Some(hardness))
            .solve_load(force / s.area(), None)
            .unwrap();
        let dx2 = dx * dx;
        let a_contact = (sol.contact_points as f64 * dx2 / PI).sqrt();
        let hz = Hertz::new(radius, force, e_star);
        let max_p = sol.pressure.iter().fold(0.0f64, |m, &p| m.max(p));
        assert_eq!(max_p, hardness, "the pressure is capped at H exactly");
        assert!(
            a_contact > hz.radius,
            "{factor} P_H: contact radius {a_contact:e} ≥ Hertz {:e}",
            hz.radius
        );
        // A_pl·H ≤ P ≤ A·H (the elastic points carry less than H each).
        let a_pl = sol.plastic_points as f64 * dx2;
        let a_all = sol.contact_points as f64 * dx2;
        assert!(a_pl * hardness <= force * (1.0 + 1e-9) && force <= a_all * hardness);
        eprintln!(
            "{factor} P_H: a/a_Hertz = {:.4}, A·H/P = {:.4}, plastic fraction {:.3}",
            a_contact / hz.radius,
            a_all * hardness / force,
            sol.plastic_points as f64 / sol.contact_points as f64
        );
    }
}

/// The fully plastic limit: with H far below the elastic contact pressures every contact point
/// but a few saturates and the real area is `P/H` (closed form), between the plastic area and
/// the whole contact area; load and displacement control agree. p̄/H = 0.25 and 0.5 are loads
/// of a whole number of points at H (4096 and 8192 of 128²), where every contact point can be
/// plastic and the free set no longer fixes the approach (the solver once stalled there).
#[test]
fn fully_plastic_limit_area_is_load_over_hardness() {
    let s = self_affine(128, 3);
    let e_star = 1e11;
    // rms gradient 0.1: elastic contact pressures ~ E*·h'rms/2 = 5 GPa; H = 50 MPa.
    let hardness = 5e7;
    let mut solver = solver(&s, e_star, Some(hardness));
    for ratio in [0.01, 0.05, 0.2, 0.25, 0.5] {
        let p_mean = ratio * hardness;
        let sol = solver.solve_load(p_mean, None).unwrap();
        let n = sol.pressure.len() as f64;
        let load = sol.pressure.sum() / n;
        assert!((load / p_mean - 1.0).abs() < 1e-12, "load {load:e}");
        // P/H lies between the plastic and the whole contact area, which differ by the few
        // elastic points (< 2 % of the contact).
        assert!(sol.plastic_area_ratio <= ratio * (1.0 + 1e-12));
        assert!(ratio <= sol.contact_area_ratio * (1.0 + 1e-12));
        assert!(
            (sol.elastic_points as f64) < 0.02 * sol.contact_points as f64,
            "{} elastic of {} contact points",
            sol.elastic_points,
            sol.contact_points
        );
        assert!((sol.contact_area_ratio / ratio - 1.0).abs() < 0.02);
        eprintln!(
            "p̄/H = {ratio}: A/A0 = {:.5}, plastic {:.5}, elastic points {}, V_p = {:.3e} m³",
            sol.contact_area_ratio,
            sol.plastic_area_ratio,
            sol.elastic_points,
            sol.plastic_volume_m3
        );
        // Displacement control at the same approach gives the same load.
        let dc = solver.solve_approach(sol.approach_m, Some(&sol)).unwrap();
        assert!((dc.mean_pressure_pa / p_mean - 1.0).abs() < 1e-5);
        assert_eq!(dc.plastic_points, sol.plastic_points);
    }
    assert!(solver.solve_load(hardness, None).is_err(), "p̄ = H refused");
    // Displacement control from a cold start at a deep approach: the bracketing stays below H.
    let shallow = solver.solve_load(0.05 * hardness, None).unwrap();
    let target = 1.5 * shallow.approach_m;
    let deep = solver.solve_approach(target, None).unwrap();
    assert!((deep.approach_m / target - 1.0).abs() < 1e-6);
    assert!(deep.mean_pressure_pa > 0.05 * hardness && deep.mean_pressure_pa < hardness);
    // The fully plastic patch has a finite approach (the lowest point touches at p̄ = H): a
    // target far beyond it is refused with the reason, not searched for ever.
    let beyond = solver
        .solve_approach(1e3 * shallow.approach_m, None)
        .unwrap_err()
        .to_string();
    assert!(
        beyond.contains("approach_m") && beyond.contains("fully plastic"),
        "{beyond}"
    );
}

/// The unloading stiffness of a rigid circular flat punch, `2E*a` (Johnson 1985 §3.8; Sneddon
/// 1965), does not depend on the plastic ring at its edge (the elastic pressure is singular
/// there, so any hardness saturates it): the unloading stiffness about the plastic state equals
/// the elastic punch's and 2E*a within 1.5 % (29 points across the radius, the radius taken
/// from the contact area), while the loading tangent is smaller.
#[test]
fn flat_punch_unloading_stiffness_is_2_e_star_a() {
    let e_star = 1e11;
    let (n, dx) = (128, 1e-6);
    let a = 29.0 * dx;
    let s = flat_punch(n, dx, a);
    let mean_on_punch = 2e8;
    let force = mean_on_punch * PI * a * a;
    let p_mean = force / s.area();
    let hardness = 1.5 * mean_on_punch;
    let mut plastic = solver(&s, e_star, Some(hardness));
    let sol = plastic.solve_load(p_mean, None).unwrap();
    assert!(sol.plastic_points > 0, "the punch edge saturates");
    let a_grid = (sol.contact_points as f64 * dx * dx / PI).sqrt();
    let unloading = plastic.contact_stiffness(&sol).unwrap().kn_n_per_m3 * s.area();
    let loading = plastic.loading_stiffness(&sol).unwrap().kn_n_per_m3 * s.area();
    let mut elastic = solver(&s, e_star, None);
    let el = elastic.solve_load(p_mean, None).unwrap();
    assert_eq!(
        el.contact_points, sol.contact_points,
        "the whole face in contact"
    );
    let k_elastic = elastic.contact_stiffness(&el).unwrap().kn_n_per_m3 * s.area();
    let closed = flat_punch_stiffness(a_grid, e_star);
    eprintln!(
        "punch: unloading {:.5e}, elastic {:.5e}, 2E*a {:.5e} N/m, loading {:.5e}; {} of {} points plastic",
        unloading, k_elastic, closed, loading, sol.plastic_points, sol.contact_points
    );
    assert!((unloading / k_elastic - 1.0).abs() < 1e-8);
    assert!((unloading / closed - 1.0).abs() < 0.015);
    assert!(loading < 0.99 * unloading);
}

/// A sphere flattened plastically at 20 P_H: its unloading stiffness is 2E*a of its contact
/// radius (Barber's theorem; within 1.5 %, the contact area's radius on a 128² grid, 60 points
/// across); the residual surface `h − penetration` solved elastically at the same load gives the
/// same pressure (the plastic state is the elastic state of the residual surface) and the same
/// stiffness; unloading to half the load stays below H everywhere (elastic unloading).
#[test]
fn flattened_sphere_unloads_elastically_from_its_residual_surface() {
    let (radius, e_star, hardness) = (0.01, 1.0e11, 2.0e9);
    let force = 20.0 * hertz_saturation_load(radius, hardness, e_star);
    let dx = 2.0 * (force / (PI * hardness)).sqrt() / 60.0;
    let s = sphere(128, dx, radius);
    let p_mean = force / s.area();
    let mut plastic = solver(&s, e_star, Some(hardness));
    let sol = plastic.solve_load(p_mean, None).unwrap();
    assert!(sol.plastic_points > sol.elastic_points / 2);
    let a = (sol.contact_points as f64 * dx * dx / PI).sqrt();
    let unloading = plastic.contact_stiffness(&sol).unwrap().kn_n_per_m3 * s.area();
    let loading = plastic.loading_stiffness(&sol).unwrap().kn_n_per_m3 * s.area();
    let closed = flat_punch_stiffness(a, e_star);
    eprintln!(
        "flattened sphere: unloading {unloading:.5e}, 2E*a {closed:.5e}, loading {loading:.5e} N/m, V_p {:.4e} m³",
        sol.plastic_volume_m3
    );
    assert!((unloading / closed - 1.0).abs() < 0.015);
    assert!(loading < unloading);
    // The plastically displaced volume is the residual surface's missing volume.
    let residual = sol.residual_surface(&s).unwrap();
    let removed = (&s.heights - &residual.heights).sum() * dx * dx;
    assert!((removed / sol.plastic_volume_m3 - 1.0).abs() < 1e-12);
    assert!(sol.plastic_volume_m3 > 0.0);
    // Elastic reloading of the residual surface to the same load: the same state.
    let mut elastic = solver(&residual, e_star, None);
    let re = elastic.solve_load(p_mean, None).unwrap();
    assert_eq!(re.contact_points, sol.contact_points);
    let dp = (&re.pressure - &sol.pressure)
        .iter()
        .fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(dp < 1e-4 * hardness, "max pressure difference {dp:e} Pa");
    let k_re = elastic.contact_stiffness(&re).unwrap().kn_n_per_m3 * s.area();
    assert!((k_re / unloading - 1.0).abs() < 1e-4);
    // Unloading to half the load: elastic, below H everywhere.
    let half = elastic.solve_load(0.5 * p_mean, Some(&re)).unwrap();
    let max_p = half.pressure.iter().fold(0.0f64, |m, &p| m.max(p));
    assert!(max_p < hardness, "unloaded peak {max_p:e} Pa");
}

/// H → ∞: a hardness no point reaches runs the same arithmetic as the elastic solve, so the
/// solution is bit for bit the elastic one (load and displacement control, nested and warm
/// starts), and both stiffnesses equal the elastic kn.
#[test]
fn unreached_hardness_gives_the_elastic_solution_bit_for_bit() {
    let s = self_affine(128, 5);
    let e_star = 1e11;
    let mut elastic = solver(&s, e_star, None);
    let mut capped = solver(&s, e_star, Some(1e300));
    let mut warm = None;
    for p in [5e7, 5.2e7, 5e8] {
        let a = elastic.solve_load(p, warm.as_ref()).unwrap();
        let b = capped.solve_load(p, warm.as_ref()).unwrap();
        assert_eq!(a.pressure, b.pressure);
        assert_eq!(a.gap, b.gap);
        assert_eq!(a.approach_m.to_bits(), b.approach_m.to_bits());
        assert_eq!(a.iterations, b.iterations);
        assert_eq!(b.plastic_points, 0);
        assert_eq!(b.plastic_volume_m3, 0.0);
        let ka = elastic.contact_stiffness(&a).unwrap().kn_n_per_m3;
        let kb = capped.contact_stiffness(&b).unwrap().kn_n_per_m3;
        let kl = capped.loading_stiffness(&b).unwrap().kn_n_per_m3;
        assert_eq!(ka.to_bits(), kb.to_bits());
        assert_eq!(ka.to_bits(), kl.to_bits());
        warm = Some(a);
    }
    let a = elastic.solve_approach(3e-6, warm.as_ref()).unwrap();
    let b = capped.solve_approach(3e-6, warm.as_ref()).unwrap();
    assert_eq!(a.pressure, b.pressure);
}

#[test]
fn bad_hardness_is_refused_by_name() {
    let s = self_affine(128, 1);
    for h in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let e = NormalSolver::new(
            &NormalProblem {
                surface: &s,
                e_star_pa: 1e11,
                hardness_pa: Some(h),
            },
            NormalOptions::default(),
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("hardness_pa"), "{e}");
    }
    let e = NormalSolver::new(
        &NormalProblem {
            surface: &s,
            e_star_pa: 1e11,
            hardness_pa: Some(1e9),
        },
        NormalOptions {
            method: NormalMethod::PolonskyKeer,
            ..NormalOptions::default()
        },
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("method"), "{e}");
}

/// The peers' venv (benches/peers/setup.sh), if it exists.
fn peers_python() -> Option<PathBuf> {
    let dir = std::env::var("ASPERITY_PEERS_VENV").unwrap_or("/tmp/asperity-peers-venv".into());
    let py = Path::new(&dir).join("bin/python");
    py.exists().then_some(py)
}

/// Against tamaas 2.9's pressure-saturated solver (`KatoSaturated`, run by
/// `benches/peers/tamaas_saturated.py` in this test, on the same 128² self-affine surface, E*,
/// H and loads): the same contact and plastic sets point for point, loads within 1e-6. Runs
/// only when the peers' venv exists (`ASPERITY_PEERS_VENV`, default /tmp/asperity-peers-venv);
/// otherwise it says so and passes. The benchmark (`cargo bench --bench normal -- --plastic`)
/// makes the same comparison at 1024².
#[test]
fn same_contact_and_plastic_sets_as_tamaas_kato_saturated() {
    let Some(py) = peers_python() else {
        eprintln!(
            "skipped: no peers' venv (benches/peers/setup.sh) — the tamaas comparison did not run"
        );
        return;
    };
    let s = self_affine(128, 2);
    let e_star = 1e11;
    // h'rms = 0.1: elastic peaks of a few GPa; H = 1 GPa saturates part of the contact.
    let hardness = 1e9;
    let loads = [0.005e9, 0.02e9, 0.1e9];
    let dir = tempfile::tempdir().unwrap();
    let npy = dir.path().join("surface.npy");
    ndarray_npy::write_npy(&npy, &s.heights).unwrap();
    let case = serde_json::json!({
        "surface_npy": npy,
        "lx_m": s.dx * s.nx() as f64,
        "ly_m": s.dy * s.ny() as f64,
        "e_star_pa": e_star,
        "hardness_pa": hardness,
        "tolerance": 1e-12,
        "pressures_pa": loads,
        "repeats": 1,
        "write_fields": true,
    });
    let case_path = dir.path().join("case.json");
    std::fs::write(&case_path, case.to_string()).unwrap();
    let out = dir.path().join("out.json");
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/peers/tamaas_saturated.py");
    let status = std::process::Command::new(&py)
        .arg(&script)
        .arg(&case_path)
        .arg(&out)
        .env("OMP_NUM_THREADS", "1")
        .status()
        .unwrap();
    assert!(status.success(), "{} failed", script.display());
    let res: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    let mut solver = solver(&s, e_star, Some(hardness));
    for (k, &p) in loads.iter().enumerate() {
        let r = &res["results"][k];
        let field: Array2<f64> =
            ndarray_npy::read_npy(r["pressure_npy"].as_str().unwrap()).unwrap();
        let sol = solver.solve_load(p, None).unwrap();
        let contact_diff = sol
            .pressure
            .iter()
            .zip(field.iter())
            .filter(|(a, b)| (**a > 0.0) != (**b > 0.0))
            .count();
        // tamaas clamps at pmax exactly, as asperity does.
        let plastic_diff = sol
            .pressure
            .iter()
            .zip(field.iter())
            .filter(|(a, b)| (**a >= hardness) != (**b >= hardness))
            .count();
        let theirs = field.mean().unwrap();
        eprintln!(
            "p̄ = {p:e}: contact {} / {} points, plastic {} / {} (asperity / tamaas {}); differing: contact {contact_diff}, plastic {plastic_diff}; load {:e} / {theirs:e}",
            sol.contact_points,
            field.iter().filter(|v| **v > 0.0).count(),
            sol.plastic_points,
            field.iter().filter(|v| **v >= hardness).count(),
            res["tamaas_version"],
            sol.mean_pressure_pa
        );
        assert!(sol.plastic_points > 0);
        assert_eq!(contact_diff, 0, "contact sets differ at {p:e} Pa");
        assert_eq!(plastic_diff, 0, "plastic sets differ at {p:e} Pa");
        assert!((sol.pressure.mean().unwrap() / p - 1.0).abs() < 1e-6);
        assert!((theirs / p - 1.0).abs() < 1e-6);
    }
}

fn asperity(args: &[&str]) -> (bool, String, String) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args(args)
        .output()
        .expect("run asperity");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// A periodic 32² two-wave surface (amplitude 0.2 µm, wavelength 32 µm) as a height matrix.
fn write_wavy_matrix(path: &Path) {
    let n = 32;
    let mut text = String::from(
        "# asperity height matrix\n# unit: m, dx_m: 1e-6, dy_m: 1e-6, periodic: true\n",
    );
    for j in 0..n {
        let row: Vec<String> = (0..n)
            .map(|i| {
                let (x, y) = (i as f64 / n as f64, j as f64 / n as f64);
                let h = 0.2e-6 * ((2.0 * PI * x).cos() + (2.0 * PI * y).cos())
                    + 0.05e-6 * (6.0 * PI * x).sin();
                format!("{h:e}")
            })
            .collect();
        text.push_str(&row.join(", "));
        text.push('\n');
    }
    std::fs::write(path, text).unwrap();
}

/// `contact normal --hardness-pa`: the unloading and loading stiffness columns (loading ≤
/// unloading), the plastic areas and volume, the residual surfaces (heights ≤ the surface's,
/// lower by the plastic volume); a material name is taken; bad values name the flag and leave
/// no output.
#[test]
fn cli_hardness_columns_and_residual_surfaces() {
    let tmp = tempfile::tempdir().unwrap();
    let surf = tmp.path().join("wavy.txt");
    write_wavy_matrix(&surf);
    let out = tmp.path().join("out");
    let (ok, stdout, err) = asperity(&[
        "contact",
        "normal",
        "--surface",
        surf.to_str().unwrap(),
        "--pressures-pa",
        "5e6,5e7,2e8",
        "--hardness-pa",
        "1e9",
        "--residual-surfaces",
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(stdout.contains("kn load"), "{stdout}");
    let csv = std::fs::read_to_string(out.join("normal_sweep.csv")).unwrap();
    assert!(csv.contains("# hardness_Pa = 1e9"), "{csv}");
    let mut lines = csv.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).expect(name);
    let rows: Vec<Vec<String>> = lines
        .map(|l| l.split(',').map(String::from).collect())
        .collect();
    assert_eq!(rows.len(), 3);
    let v = |r: &Vec<String>, name: &str| -> f64 { r[col(name)].parse().unwrap() };
    let s = asperity::surface::io::read_equivalent_surface(std::slice::from_ref(&surf), None)
        .unwrap()
        .0;
    for r in &rows {
        let (ku, kl) = (v(r, "kn_unloading_N_per_m3"), v(r, "kn_loading_N_per_m3"));
        assert!(kl > 0.0 && kl <= ku, "loading {kl:e} ≤ unloading {ku:e}");
        let (area, el, pl) = (
            v(r, "contact_area_ratio"),
            v(r, "elastic_area_ratio"),
            v(r, "plastic_area_ratio"),
        );
        assert!((el + pl - area).abs() < 1e-12);
        let p = v(r, "pressure_Pa");
        let residual: Array2<f64> =
            ndarray_npy::read_npy(out.join(format!("residual_surface_{p:e}Pa.npy"))).unwrap();
        let removed: f64 = (&s.heights - &residual).sum() * 1e-12;
        assert!(
            (&s.heights - &residual).iter().all(|d| *d >= 0.0),
            "material is only removed"
        );
        let volume = v(r, "plastic_volume_m3");
        assert!(
            (removed - volume).abs() <= 1e-9 * volume.max(1e-30),
            "{removed:e} {volume:e}"
        );
    }
    assert!(v(&rows[2], "plastic_area_ratio") > 0.0, "2e8 Pa saturates");
    assert!(v(&rows[2], "kn_loading_N_per_m3") < v(&rows[2], "kn_unloading_N_per_m3"));
    // A documented material is accepted.
    let (ok, _, err) = asperity(&[
        "contact",
        "normal",
        "--surface",
        surf.to_str().unwrap(),
        "--pressures-pa",
        "5e7",
        "--hardness-pa",
        "inconel-718",
        "--out-dir",
        tmp.path().join("out2").to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    // Bad values.
    let bad = tmp.path().join("bad");
    for (value, pressures, needle) in [
        ("0", "5e7", "--hardness-pa"),
        ("brass", "5e7", "steel-42crmo4"),
        ("1e7", "5e7", "--pressures-pa"),
    ] {
        let (ok, _, err) = asperity(&[
            "contact",
            "normal",
            "--surface",
            surf.to_str().unwrap(),
            "--pressures-pa",
            pressures,
            "--hardness-pa",
            value,
            "--out-dir",
            bad.to_str().unwrap(),
        ]);
        assert!(!ok, "{value} accepted");
        assert!(err.contains(needle), "{value}: {err}");
        assert!(!bad.exists() || std::fs::read_dir(&bad).unwrap().next().is_none());
    }
}

/// Tangential loops on the hardness-limited contact: a sphere flattened at 20 `P_H` (its
/// contact a disc of radius `a` larger than Hertz's) under a small tangential force
/// `T = 0.01 μP` (load control, Coulomb bound μ·p with the bounded pressure). Its tangential
/// stiffness `T/δ` is Mindlin's `8a/s`, `s = Σ (2−ν_k)/G_k` (Mindlin 1949; Johnson 1985,
/// §7.2: the stiffness of a stuck circular contact of radius `a`, whatever its pressure
/// distribution), with `a` the actual (plastic) contact radius, and the ratio to the
/// unloading normal stiffness is Mindlin's `kt/kn = 2(1−ν)/(2−ν)` (`kn = 2E*a`).
///
/// Tolerance 1 %: the discretisation error of the stuck disc at 60 points across (−0.6 % for
/// the elastic Hertz contact on the same kind of grid, run alongside; −0.4 % measured for the
/// plastic one) plus the microslip at `T = 0.01 μP` (the Cattaneo–Mindlin secant is
/// `1 − x/6 ≈ 0.2 %` below the initial slope at `x = T/μP`). The plastic radius is 35 % larger
/// than Hertz's at this load, so the test tells the radii apart.
#[test]
fn flattened_sphere_tangential_stiffness_is_mindlins_with_the_plastic_radius() {
    use asperity::contact::tangential::{
        Control, TangentialOptions, TangentialProblem, TangentialSolver,
    };
    use asperity::core::fft::Boundary;
    use asperity::core::material::{composite_modulus, Material};
    let body = Material::STEEL;
    let (radius, hardness, mu) = (0.01, 2.0e9, 0.5);
    let e_star = composite_modulus(body, body).unwrap();
    let g = body.shear_modulus_pa();
    let nu = body.poisson_ratio;
    let s_t = 2.0 * (2.0 - nu) / g;
    let p_h = hertz_saturation_load(radius, hardness, e_star);
    for (case, hardness, force) in [
        ("hardness-limited, 20 P_H", Some(hardness), 20.0 * p_h),
        ("elastic Hertz, 20 P_H", None, 20.0 * p_h),
    ] {
        let a_expected = match hardness {
            Some(h) => (force / (PI * h)).sqrt(),
            None => Hertz::new(radius, force, e_star).radius,
        };
        let dx = 2.0 * a_expected / 60.0;
        let s = sphere(128, dx, radius);
        let mut normal = solver(&s, e_star, hardness);
        let sol = normal.solve_load(force / s.area(), None).unwrap();
        let a = (sol.contact_points as f64 * dx * dx / PI).sqrt();
        let kn = normal.contact_stiffness(&sol).unwrap().kn_n_per_m3 * s.area();
        let mut t = TangentialSolver::new(
            &TangentialProblem {
                pressure: &sol.pressure,
                dx,
                dy: dx,
                boundary: Boundary::ZeroPadded,
                friction_coefficient: mu,
                body1: body,
                body2: body,
            },
            TangentialOptions {
                tolerance: 1e-8,
                ..TangentialOptions::default()
            },
        )
        .unwrap();
        // The Coulomb bound is μ times the bounded pressure.
        assert!(t.traction_bound_pa() <= mu * hardness.unwrap_or(f64::INFINITY));
        let x = 0.01;
        let tf = x * t.friction_limit_n();
        let st = t.step(Control::Force([tf, 0.0])).unwrap();
        let kt = tf / st.shift_m[0];
        let mindlin = 8.0 * a / s_t;
        eprintln!(
            "{case}: plastic points {}, a = {a:.5e} m (Hertz {:.5e}), kt = {kt:.5e} N/m, \
             8a/s = {mindlin:.5e} ({:+.2} %), kt/kn = {:.4} vs 2(1−ν)/(2−ν) = {:.4}",
            sol.plastic_points,
            Hertz::new(radius, force, e_star).radius,
            100.0 * (kt / mindlin - 1.0),
            kt / kn,
            2.0 * (1.0 - nu) / (2.0 - nu)
        );
        assert!(
            (kt / mindlin - 1.0).abs() < 0.01,
            "{case}: {kt:e} vs {mindlin:e}"
        );
        let ratio = 2.0 * (1.0 - nu) / (2.0 - nu);
        assert!(
            (kt / kn / ratio - 1.0).abs() < 0.01,
            "{case}: kt/kn {}",
            kt / kn
        );
        if hardness.is_some() {
            assert!(sol.plastic_points > sol.elastic_points / 2);
            // The plastic radius exceeds Hertz's by more than the tolerance: the test tells
            // the two apart.
            assert!(a > 1.1 * Hertz::new(radius, force, e_star).radius);
        }
    }
}
