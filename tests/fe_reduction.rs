//! Craig–Bampton reduction (src/dynamics/craig_bampton.rs), the FE matrix readers
//! (src/dynamics/fe_matrices.rs) and FE models in the model file of `asperity response`.
//!
//! - Closed form, no FE code: an Euler–Bernoulli cantilever of Hermite-cubic beam elements built
//!   here. Its full eigen-solve matches the clamped–free beam's closed form to 1e-5 (40
//!   elements, error falling as h⁴; roots of `cos β·cosh β = −1`, Rayleigh 1877); the reduced
//!   model with every interior mode kept reproduces the full model's frequencies to 1e-8, and
//!   with fewer modes its frequencies are upper bounds that converge monotonically
//!   (Rayleigh–Ritz). Through the model file (Matrix Market) and `asperity response`, the tip's
//!   response below resonance equals the full model's harmonic solution (1e-6).
//! - CalculiX: the cantilever of scripts/fe (gmsh mesh, 20-node hexahedra) exported by ccx, read,
//!   reduced on its tip face, against ccx's own `*FREQUENCY` solution of the same mesh (0.1 %)
//!   and Euler–Bernoulli (1 % for the first three bending frequencies, slenderness L/h = 40);
//!   `asperity response` on it puts the resonance peak at ccx's first frequency (1e-4).
//!   Skipped when `gmsh` or `ccx` is missing, unless `ASPERITY_REQUIRE_DATA=1` (CI).

use asperity::dynamics::craig_bampton::{reduce, ReductionSettings};
use asperity::dynamics::fe_matrices::{
    read_calculix, read_dof_map, read_matrix_market, read_matrix_market_pair, SparseMatrix,
};
use asperity::dynamics::model::undamped_modes;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Clamped–free Euler–Bernoulli beam of `n` Hermite-cubic elements (Przemieniecki, *Theory of
/// Matrix Structural Analysis*, 1968, §5 and §11): DOFs `(w, θ)` of nodes 1..=n (node 0
/// clamped), consistent mass.
fn eb_cantilever(n: usize, ei: f64, rho_a: f64, length: f64) -> (SparseMatrix, SparseMatrix) {
    let l = length / n as f64;
    let ke = [
        [12.0, 6.0 * l, -12.0, 6.0 * l],
        [6.0 * l, 4.0 * l * l, -6.0 * l, 2.0 * l * l],
        [-12.0, -6.0 * l, 12.0, -6.0 * l],
        [6.0 * l, 2.0 * l * l, -6.0 * l, 4.0 * l * l],
    ];
    let me = [
        [156.0, 22.0 * l, 54.0, -13.0 * l],
        [22.0 * l, 4.0 * l * l, 13.0 * l, -3.0 * l * l],
        [54.0, 13.0 * l, 156.0, -22.0 * l],
        [-13.0 * l, -3.0 * l * l, -22.0 * l, 4.0 * l * l],
    ];
    let (kf, mf) = (ei / l.powi(3), rho_a * l / 420.0);
    let mut k = Vec::new();
    let mut m = Vec::new();
    for e in 0..n {
        // Element e joins nodes e and e+1; global DOF of node j ≥ 1 is 2(j−1) + {0, 1}.
        let dof = |a: usize| -> Option<usize> {
            let node = e + a / 2;
            (node > 0).then(|| 2 * (node - 1) + a % 2)
        };
        for a in 0..4 {
            for b in 0..4 {
                if let (Some(i), Some(j)) = (dof(a), dof(b)) {
                    k.push((i, j, kf * ke[a][b]));
                    m.push((i, j, mf * me[a][b]));
                }
            }
        }
    }
    let s = |entries| SparseMatrix {
        nrows: 2 * n,
        ncols: 2 * n,
        entries,
    };
    (s(k), s(m))
}

/// Roots of `cos β·cosh β = −1` (clamped–free beam), by Newton from the asymptotic values.
fn clamped_free_roots(count: usize) -> Vec<f64> {
    (0..count)
        .map(|j| {
            let mut b = (j as f64 + 0.5) * PI;
            for _ in 0..50 {
                let f = b.cos() * b.cosh() + 1.0;
                let df = -b.sin() * b.cosh() + b.cos() * b.sinh();
                b -= f / df;
            }
            b
        })
        .collect()
}

fn hz(lambdas: &[f64]) -> Vec<f64> {
    lambdas.iter().map(|l| l.sqrt() / (2.0 * PI)).collect()
}

/// Steel bar 10 mm × 10 mm × 0.4 m: EI (N·m²), ρA (kg/m), L (m).
const EI: f64 = 210e9 * 1e-8 / 12.0;
const RHO_A: f64 = 7800.0 * 1e-4;
const LENGTH: f64 = 0.4;

fn eb_frequency_hz(beta: f64) -> f64 {
    beta * beta / (2.0 * PI) * (EI / (RHO_A * LENGTH.powi(4))).sqrt()
}

#[test]
fn beam_reduction_is_exact_with_every_mode_and_converges_from_above() {
    let n = 40;
    let (k, m) = eb_cantilever(n, EI, RHO_A, LENGTH);
    let (full, _) = undamped_modes(&m.to_dense(), &k.to_dense()).unwrap();
    let full = hz(&full);
    // The FE beam itself against the closed form (cubic elements converge as h⁴).
    for (j, beta) in clamped_free_roots(3).into_iter().enumerate() {
        let exact = eb_frequency_hz(beta);
        let err = (full[j] - exact).abs() / exact;
        println!(
            "EB mode {}: FE {:.6} Hz, closed form {exact:.6} Hz, rel {err:.2e}",
            j + 1,
            full[j]
        );
        assert!(
            err < 1e-5,
            "FE beam mode {} off the closed form by {err:.2e}",
            j + 1
        );
    }
    // Boundary: the tip's deflection and rotation (the last node).
    let tip = [2 * n - 2, 2 * n - 1];
    let interior = 2 * n - 2;
    let all = reduce(
        &k,
        &m,
        &tip,
        &ReductionSettings {
            modes: interior,
            ..Default::default()
        },
    )
    .unwrap();
    let (red, _) = undamped_modes(&all.mass, &all.stiffness).unwrap();
    let red = hz(&red);
    let worst = (0..2 * n)
        .map(|j| (red[j] - full[j]).abs() / full[j])
        .fold(0.0f64, f64::max);
    println!("all {interior} interior modes kept: worst relative frequency error {worst:.2e}");
    assert!(
        worst < 1e-8,
        "every mode kept: reduced off the full model by {worst:.2e}"
    );
    // Fewer modes: upper bounds on the first four frequencies, decreasing towards the full ones.
    let mut previous = [f64::INFINITY; 4];
    for modes in [0, 1, 2, 4, 8, 16] {
        let r = reduce(
            &k,
            &m,
            &tip,
            &ReductionSettings {
                modes,
                ..Default::default()
            },
        )
        .unwrap();
        assert!(r.residuals.iter().all(|&x| x <= 1e-8), "{:?}", r.residuals);
        let (red, _) = undamped_modes(&r.mass, &r.stiffness).unwrap();
        let red = hz(&red);
        let errs: Vec<f64> = (0..4.min(red.len()))
            .map(|j| (red[j] - full[j]) / full[j])
            .collect();
        println!("{modes:2} modes: relative errors of the first frequencies {errs:?}");
        for (j, &e) in errs.iter().enumerate() {
            assert!(
                e > -1e-12,
                "{modes} modes: mode {} below the full model ({e:.3e})",
                j + 1
            );
            assert!(
                e <= previous[j] + 1e-12,
                "{modes} modes: mode {} not converging",
                j + 1
            );
            previous[j] = e;
        }
        if modes == 16 {
            assert!(errs.iter().all(|&e| e < 5e-5), "16 modes: {errs:?}");
        }
    }
}

fn write(path: &Path, text: &str) {
    std::fs::write(path, text).unwrap();
}

/// The lower triangle (the Matrix Market convention) of a symmetric matrix, in %.17e.
fn matrix_market(a: &SparseMatrix) -> String {
    let d = a.to_dense();
    let mut rows = Vec::new();
    for j in 0..a.ncols {
        for i in j..a.nrows {
            if d[(i, j)] != 0.0 {
                rows.push(format!("{} {} {:.17e}", i + 1, j + 1, d[(i, j)]));
            }
        }
    }
    format!(
        "%%MatrixMarket matrix coordinate real symmetric\n% test\n{} {} {}\n{}\n",
        a.nrows,
        a.ncols,
        rows.len(),
        rows.join("\n")
    )
}

/// DOF map of the beam of `n` elements: node j+1 carries w (z, direction 3) and θ (about y, 5).
fn beam_dofs(n: usize) -> String {
    (1..=n)
        .flat_map(|j| [format!("{}.3", j + 1), format!("{}.5", j + 1)])
        .collect::<Vec<_>>()
        .join("\n")
        + "\n"
}

#[test]
fn model_file_reduces_an_fe_model_and_response_gives_the_static_tip_compliance() {
    let dir = tempfile::tempdir().unwrap();
    let n = 40;
    let (k, m) = eb_cantilever(n, EI, RHO_A, LENGTH);
    write(&dir.path().join("k.mtx"), &matrix_market(&k));
    write(&dir.path().join("m.mtx"), &matrix_market(&m));
    write(&dir.path().join("beam.dof"), &beam_dofs(n));
    let (alpha, beta) = (2.0, 1e-5);
    let tip = n + 1;
    let model = dir.path().join("model.toml");
    write(
        &model,
        &format!(
            "[linear]\nfe_stiffness = \"k.mtx\"\nfe_mass = \"m.mtx\"\nfe_dofs = \"beam.dof\"\n\
             interface_nodes = [{tip}]\nfixed_interface_modes = 10\n\
             rayleigh_alpha_per_s = {alpha}\nrayleigh_beta_s = {beta}\n\n\
             [excitation]\ndofs = [\"n{tip}.z\"]\nlevels_n = [1.0]\n\n\
             [response]\ndofs = [\"n{tip}.z\"]\n\n\
             [sweep]\nfrequency_start_hz = 1.0\nfrequency_end_hz = 2.0\npoints = 3\nharmonics = 1\n\
             odd_only = true\n"
        ),
    );
    let loaded = asperity::dynamics::model_file::load(&model).unwrap();
    let s = &loaded.structure;
    assert_eq!(s.labels[..2], [format!("n{tip}.z"), format!("n{tip}.ry")]);
    assert_eq!(s.labels[2], "cb_mode_1");
    assert_eq!(s.n(), 12);
    // Rayleigh damping on the reduced model: modal damping ζ = α/(2ω) + β·ω/2 of mode 1.
    let (w2, shapes) = undamped_modes(&s.mass, &s.stiffness).unwrap();
    let w = w2[0].sqrt();
    let zeta = (shapes[0].transpose() * &s.damping * &shapes[0])[(0, 0)] / (2.0 * w);
    let expected = alpha / (2.0 * w) + beta * w / 2.0;
    assert!(
        (zeta / expected - 1.0).abs() < 1e-10,
        "ζ {zeta} vs {expected}"
    );
    let f1 = w / (2.0 * PI);
    let eb = eb_frequency_hz(clamped_free_roots(1)[0]);
    assert!(
        (f1 / eb - 1.0).abs() < 1e-5,
        "{f1} Hz vs Euler–Bernoulli {eb} Hz"
    );
    // A bad interface node is refused with the DOF map's name.
    write(
        &dir.path().join("bad.toml"),
        &std::fs::read_to_string(&model)
            .unwrap()
            .replace(&format!("[{tip}]"), "[1]"),
    );
    let e = asperity::dynamics::model_file::load(&dir.path().join("bad.toml"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("beam.dof") && e.contains("node 1"), "{e}");

    // End to end: the tip's response to 1 N at 1–2 Hz (f1 = 52.4 Hz) against the full
    // (unreduced) beam's harmonic solution `(K − ω²M + iωC)·u = f`, and near the static
    // compliance L³/(3EI) (dynamic amplification ≈ 1/(1 − (f/f1)²) ≤ 1.0015).
    let out = dir.path().join("out");
    let o = Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args([
            "response",
            model.to_str().unwrap(),
            "--out-dir",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let csv = std::fs::read_to_string(out.join("response_level_1.csv")).unwrap();
    let mut lines = csv.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = header
        .iter()
        .position(|h| h.starts_with(&format!("n{tip}.z_h1_amplitude")))
        .unwrap_or_else(|| panic!("no amplitude column in {header:?}"));
    let fcol = header.iter().position(|h| *h == "frequency_Hz").unwrap();
    let (kd, md) = (k.to_dense(), m.to_dense());
    let cd = &md * alpha + &kd * beta;
    let nd = kd.nrows();
    let full_amplitude = |f: f64| {
        let w = 2.0 * PI * f;
        let d = &kd - &md * (w * w);
        let mut a = nalgebra::DMatrix::zeros(2 * nd, 2 * nd);
        a.view_mut((0, 0), (nd, nd)).copy_from(&d);
        a.view_mut((nd, nd), (nd, nd)).copy_from(&d);
        a.view_mut((0, nd), (nd, nd)).copy_from(&(&cd * -w));
        a.view_mut((nd, 0), (nd, nd)).copy_from(&(&cd * w));
        let mut rhs = nalgebra::DVector::zeros(2 * nd);
        rhs[2 * n - 2] = 1.0;
        let u = a.lu().solve(&rhs).unwrap();
        u[2 * n - 2].hypot(u[nd + 2 * n - 2])
    };
    let compliance = LENGTH.powi(3) / (3.0 * EI);
    let mut rows = 0;
    for l in lines {
        let cells: Vec<&str> = l.split(',').collect();
        let a: f64 = cells[col].parse().unwrap();
        let f: f64 = cells[fcol].parse().unwrap();
        let full = full_amplitude(f);
        println!("{f:.3} Hz: tip {a:.6e} m, full model {full:.6e} m, L³/(3EI) {compliance:.6e} m");
        assert!(
            (a / full - 1.0).abs() < 1e-6,
            "{f} Hz: reduced {a} vs full {full}"
        );
        assert!(
            (1.0..1.002).contains(&(a / compliance)),
            "{f} Hz: {a} vs {compliance}"
        );
        rows += 1;
    }
    assert!(rows >= 3);
}

#[test]
fn matrix_market_files_round_trip_and_errors_name_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let n = 6;
    let (k, m) = eb_cantilever(n, EI, RHO_A, LENGTH);
    let (kp, mp, dp) = (
        dir.path().join("k.mtx"),
        dir.path().join("m.mtx"),
        dir.path().join("beam.dof"),
    );
    write(&kp, &matrix_market(&k));
    write(&mp, &matrix_market(&m));
    let dofs: Vec<String> = (1..=n)
        .flat_map(|j| [format!("{}.3", j + 1), format!("{}.5", j + 1)])
        .collect();
    write(&dp, &(dofs.join("\n") + "\n"));
    let fe = read_matrix_market_pair(&kp, &mp, &dp).unwrap();
    assert_eq!(fe.stiffness.to_dense(), k.to_dense());
    assert_eq!(fe.mass.to_dense(), m.to_dense());
    assert_eq!(
        fe.rows_of_nodes(&[n as u64 + 1]).unwrap(),
        vec![2 * n - 2, 2 * n - 1]
    );
    assert!(fe.rows_of_nodes(&[1]).is_err(), "node 1 is clamped: no DOF");

    // Bad inputs: the message names the file and the line.
    let bad = dir.path().join("bad.mtx");
    let cases = [
        (
            "%%MatrixMarket matrix array real general\n2 2\n1\n",
            ":1:",
            "coordinate",
        ),
        (
            "%%MatrixMarket matrix coordinate real symmetric\n2 2 1\n3 1 1.0\n",
            ":3:",
            "outside",
        ),
        (
            "%%MatrixMarket matrix coordinate real general\n2 2 1\n1 1 x\n",
            ":3:",
            "not a number",
        ),
        (
            "%%MatrixMarket matrix coordinate real general\n2 2 2\n1 1 1.0\n",
            "bad.mtx",
            "announces 2",
        ),
        (
            "%%MatrixMarket matrix coordinate real symmetric\n2 2 2\n1 2 1.0\n2 1 1.0\n",
            "bad.mtx",
            "one triangle",
        ),
        (
            "%%MatrixMarket matrix coordinate real general\n%\n2 2\n",
            ":3:",
            "size line",
        ),
    ];
    for (text, place, what) in cases {
        write(&bad, text);
        let e = read_matrix_market(&bad).unwrap_err().to_string();
        assert!(
            e.contains("bad.mtx") && e.contains(place) && e.contains(what),
            "{e}"
        );
    }
    write(&bad, "2.1\n3.x\n");
    let e = read_dof_map(&bad).unwrap_err().to_string();
    assert!(e.contains("bad.mtx:2:"), "{e}");
    // CalculiX files: an entry below the diagonal is refused with its line.
    let job = dir.path().join("job");
    write(&dir.path().join("job.dof"), "1.1\n1.2\n");
    write(&dir.path().join("job.sti"), "1 1 2.0\n1 2 -1.0\n2 2 2.0\n");
    write(&dir.path().join("job.mas"), "1 1 1.0\n2 1 0.5\n2 2 1.0\n");
    let e = read_calculix(&job).unwrap_err().to_string();
    assert!(
        e.contains("job.mas:2:") && e.contains("upper triangle"),
        "{e}"
    );
    write(&dir.path().join("job.mas"), "1 1 1.0\n1 2 0.5\n2 2 1.0\n");
    let fe = read_calculix(&job).unwrap();
    assert_eq!(fe.mass.to_dense()[(1, 0)], 0.5);
    assert_eq!(fe.stiffness.to_dense()[(0, 1)], -1.0);
}

/// Is the program on the PATH? Without it the test is skipped, or fails under
/// `ASPERITY_REQUIRE_DATA=1`.
fn have(program: &str) -> bool {
    // Spawning fails only when the program is not there (ccx -v and gmsh --version both exit).
    let flag = if program == "gmsh" { "--version" } else { "-v" };
    let found = Command::new(program).arg(flag).output().is_ok();
    if !found {
        let required = std::env::var("ASPERITY_REQUIRE_DATA").is_ok_and(|v| v == "1");
        assert!(
            !required,
            "`{program}` is missing and ASPERITY_REQUIRE_DATA=1"
        );
        eprintln!("skipped: `{program}` is not installed (Debian: calculix-ccx, gmsh)");
    }
    found
}

/// The node numbers of node set `name` in a CalculiX/Abaqus input file.
fn node_set(inp: &Path, name: &str) -> Vec<u64> {
    let text = std::fs::read_to_string(inp).unwrap();
    let mut nodes = Vec::new();
    let mut inside = false;
    for line in text.lines() {
        if line.starts_with('*') {
            inside = line
                .replace(' ', "")
                .eq_ignore_ascii_case(&format!("*NSET,NSET={name}"));
            continue;
        }
        if inside {
            nodes.extend(line.split(',').filter_map(|t| t.trim().parse::<u64>().ok()));
        }
    }
    nodes
}

/// Frequencies (Hz) of ccx's eigenvalue table in a `.dat` file.
fn ccx_frequencies(dat: &Path) -> Vec<f64> {
    let text = std::fs::read_to_string(dat).unwrap();
    let mut out = Vec::new();
    let mut inside = false;
    for line in text.lines() {
        if line.contains("E I G E N V A L U E   O U T P U T") {
            inside = true;
            continue;
        }
        if inside && line.contains("P A R T I C I P A T I O N") {
            break;
        }
        let tok: Vec<&str> = line.split_whitespace().collect();
        if inside && tok.len() == 5 && tok[0].parse::<usize>().is_ok() {
            out.push(tok[3].parse().unwrap());
        }
    }
    out
}

#[test]
fn calculix_cantilever_reduced_on_its_tip_matches_ccx_and_euler_bernoulli() {
    if !have("gmsh") || !have("ccx") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let script = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scripts/fe/cantilever.sh");
    let status = Command::new("bash")
        .arg(&script)
        .arg(dir.path())
        .status()
        .unwrap();
    assert!(status.success(), "scripts/fe/cantilever.sh failed");
    let reference = ccx_frequencies(&dir.path().join("cantilever_frequency.dat"));
    assert_eq!(reference.len(), 10, "ccx's eigenvalue table");
    let fe = read_calculix(&dir.path().join("cantilever_matrices")).unwrap();
    let tip = node_set(&dir.path().join("cantilever_mesh.inp"), "Surface2");
    assert_eq!(
        tip.len(),
        21,
        "the tip face of 2 × 2 quadratic quadrilaterals"
    );
    let boundary = fe.rows_of_nodes(&tip).unwrap();
    let t0 = std::time::Instant::now();
    let r = reduce(
        &fe.stiffness,
        &fe.mass,
        &boundary,
        &ReductionSettings {
            modes: 30,
            ..Default::default()
        },
    )
    .unwrap();
    println!(
        "{} DOFs reduced to {} ({} boundary + 30 modes) in {:.2} s, {} subspace iterations, \
         largest eigen-residual {:.1e}",
        fe.dofs.len(),
        r.stiffness.nrows(),
        boundary.len(),
        t0.elapsed().as_secs_f64(),
        r.iterations,
        r.residuals.iter().fold(0.0f64, |a, &b| a.max(b))
    );
    let (red, _) = undamped_modes(&r.mass, &r.stiffness).unwrap();
    let red = hz(&red);
    for (j, &f) in reference.iter().enumerate() {
        let err = (red[j] - f).abs() / f;
        println!(
            "mode {:2}: reduced {:10.4} Hz, ccx {f:10.4} Hz, rel {err:.2e}",
            j + 1,
            red[j]
        );
        assert!(
            err < 1e-3,
            "mode {}: reduced {} Hz vs ccx {f} Hz",
            j + 1,
            red[j]
        );
    }
    // Euler–Bernoulli: modes 1–2, 3–4, 5–6 are the bending pairs (square section). At L/h = 40
    // shear and rotary inertia lower the third bending frequency by ≈ 0.5 %; the clamped face's
    // Poisson constraint stiffens the first by ≈ 0.2 %.
    for (pair, beta) in clamped_free_roots(3).into_iter().enumerate() {
        let exact = eb_frequency_hz(beta);
        for j in [2 * pair, 2 * pair + 1] {
            let err = (red[j] - exact).abs() / exact;
            println!(
                "bending {}: reduced {:.4} Hz, Euler–Bernoulli {exact:.4} Hz, rel {err:.2e}",
                pair + 1,
                red[j]
            );
            assert!(
                err < 1e-2,
                "bending mode {}: {} Hz vs EB {exact} Hz",
                pair + 1,
                red[j]
            );
        }
    }

    // End to end: `asperity response` on the CalculiX export, reduced on the tip face, forced
    // at a tip node along z with light Rayleigh damping (ζ1 = β·ω1/2 = 1.6e-3): the resonance
    // peak sits at ccx's first frequency (the damped peak is lower by ζ² ≈ 3e-6; limit 1e-4).
    let model = dir.path().join("model.toml");
    let corner = tip[0];
    std::fs::write(
        &model,
        format!(
            "[linear]\ncalculix = \"cantilever_matrices\"\ninterface_nodes = {tip:?}\n\
             fixed_interface_modes = 30\nrayleigh_beta_s = 1.0e-5\n\n\
             [excitation]\ndofs = [\"n{corner}.z\"]\nlevels_n = [1.0]\n\n\
             [response]\ndofs = [\"n{corner}.z\"]\n\n\
             [sweep]\nfrequency_start_hz = 45.0\nfrequency_end_hz = 60.0\npoints = 60\n\
             harmonics = 1\nodd_only = true\n"
        ),
    )
    .unwrap();
    let out = dir.path().join("out");
    let o = Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args([
            "response",
            model.to_str().unwrap(),
            "--out-dir",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // The peak as the run locates it (interpolated between the sweep's points).
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("response.json")).unwrap()).unwrap();
    let f_peak = json["summary"]["levels"][0]["peak_frequency_Hz"]
        .as_f64()
        .unwrap();
    let err = (f_peak - reference[0]).abs() / reference[0];
    println!(
        "response peak at {f_peak:.4} Hz, ccx f1 {:.4} Hz, rel {err:.1e}",
        reference[0]
    );
    assert!(err < 1e-4, "peak at {f_peak} Hz vs ccx {} Hz", reference[0]);
}
