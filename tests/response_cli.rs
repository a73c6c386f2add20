//! `asperity response` end to end on a small lumped model, and every bad input of the catalogue:
//! a clear error naming the file, line or parameter, a non-zero exit, and no output written.

#[path = "support/cyclic_models.rs"]
mod cyclic_models;

use cyclic_models::{write_full_model, write_sector_model};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args(args)
        .output()
        .expect("runs")
}

const ELEMENTS: &str = "# units: N0_N in N; kn, E0, Et in N/m\n\
id,x_m,y_m,area_m2,pressure_Pa,N0_N,kn_N_per_m,E0_N_per_m,k,mu,Et_N_per_m,out_of_range\n\
7,0,0,1e-6,2e6,2.0,1e6,2.0e4,0.3,0.5,0,0\n\
11,0,0,1e-6,2e6,1.0,1e6,1.0e4,0.5,0.5,0,0\n";

/// Two masses (m1 on a ground spring, m2 on m1); the element table joins m2 to ground.
fn write_model(dir: &Path) -> PathBuf {
    let w = |name: &str, text: &str| std::fs::write(dir.join(name), text).unwrap();
    w("mass.csv", "# unit: kg\nm1.x,m2.x\n1.0,0\n0,0.5\n");
    w(
        "stiffness.csv",
        "# unit: N/m\nm1.x,m2.x\n6e4,-2e4\n-2e4,2e4\n",
    );
    w("damping.csv", "# unit: N*s/m\nm1.x,m2.x\n2,0\n0,1\n");
    w("elements.csv", ELEMENTS);
    w(
        "pairs.csv",
        "element_id,node_a,node_b\n7,m2,ground\n11,m2,ground\n",
    );
    let model = "[linear]\nmass = \"mass.csv\"\ndamping = \"damping.csv\"\nstiffness = \"stiffness.csv\"\n\n\
[[contact]]\nelements = \"elements.csv\"\nlaw = \"valanis\"\npairs = \"pairs.csv\"\n\
normal = [0.0, 0.0, 1.0]\ntangent = [1.0, 0.0, 0.0]\n\n\
[excitation]\ndofs = [\"m1.x\"]\nlevels_n = [0.02, 0.5]\n\n\
[response]\ndofs = [\"m1.x\", \"m2.x\"]\n\n\
[sweep]\nfrequency_start_hz = 15.0\nfrequency_end_hz = 50.0\npoints = 15\nharmonics = 3\nodd_only = true\n";
    w("model.toml", model);
    dir.join("model.toml")
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn response_writes_every_output_and_the_peak_falls_with_the_level() {
    let dir = tempfile::tempdir().unwrap();
    let model = write_model(dir.path());
    let out = dir.path().join("out");
    let o = run(&["response", s(&model), "--out-dir", s(&out)]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in [
        "response_level_1.csv",
        "response_level_2.csv",
        "elements_level_1.csv",
        "frf_m1.x.png",
        "frf_m2.x.png",
        "response.json",
    ] {
        assert!(out.join(f).exists(), "{f} missing");
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("response.json")).unwrap()).unwrap();
    let inputs = json["inputs"].as_array().unwrap();
    assert!(inputs
        .iter()
        .any(|i| i["role"] == "contact 1 elements" && i["sha256"].as_str().unwrap().len() == 64));
    // Friction: from stuck to microslip the peak receptance |X|/F falls as the level grows.
    let levels = json["summary"]["levels"].as_array().unwrap();
    let r: Vec<f64> = levels
        .iter()
        .map(|l| l["peak_amplitude_m"].as_f64().unwrap() / l["level_N"].as_f64().unwrap())
        .collect();
    assert!(r[1] < 0.9 * r[0], "peak receptance {r:?}");
    let csv = std::fs::read_to_string(out.join("response_level_2.csv")).unwrap();
    assert!(csv.contains("frequency_Hz,m1.x_h1_amplitude_m,m1.x_h1_phase_rad"));
    check_loops(&out, &levels[1]);
}

/// The per-element loops of a level at its largest point: one period of every component; the
/// energy `∮f·du` of each element's loop is the one `elements_level_2.csv` reports; the
/// acceleration is the displacement's second time derivative (its harmonics `−(kω)²` times the
/// displacement's, by a DFT of the samples); the two plots exist.
fn check_loops(out: &Path, level: &serde_json::Value) {
    for f in [
        "loops_level_2.csv",
        "loops_level_2_displacement.png",
        "loops_level_2_acceleration.png",
    ] {
        assert!(out.join(f).exists(), "{f} missing");
    }
    let w = 2.0 * std::f64::consts::PI * level["largest_point_frequency_Hz"].as_f64().unwrap();
    let text = std::fs::read_to_string(out.join("loops_level_2.csv")).unwrap();
    // element -> component -> (u, a, f)
    let mut loops: std::collections::BTreeMap<(String, usize), Vec<[f64; 3]>> = Default::default();
    for line in text.lines().filter(|l| !l.starts_with('#')).skip(1) {
        let c: Vec<&str> = line.split(',').collect();
        let v = |i: usize| c[i].parse::<f64>().unwrap();
        loops
            .entry((c[1].to_string(), c[3].parse().unwrap()))
            .or_default()
            .push([v(6), v(7), v(8)]);
    }
    assert_eq!(loops.len(), 2 * 3, "two 3-D contact elements");
    let elements = std::fs::read_to_string(out.join("elements_level_2.csv")).unwrap();
    for row in elements.lines().filter(|l| !l.starts_with('#')).skip(1) {
        let c: Vec<&str> = row.split(',').collect();
        let reported: f64 = c[2].parse().unwrap();
        let energy: f64 = (0..3)
            .map(|k| {
                let s = &loops[&(c[0].to_string(), k)];
                let n = s.len();
                (0..n)
                    .map(|i| 0.5 * (s[i][2] + s[(i + 1) % n][2]) * (s[(i + 1) % n][0] - s[i][0]))
                    .sum::<f64>()
            })
            .sum();
        assert!(reported > 0.0);
        assert!(
            (energy / reported - 1.0).abs() < 1e-5,
            "{}: {energy} vs {reported}",
            c[0]
        );
    }
    for s in loops.values() {
        let n = s.len() as f64;
        for k in [1.0, 3.0] {
            let dft = |j: usize| -> (f64, f64) {
                s.iter().enumerate().fold((0.0, 0.0), |(re, im), (i, v)| {
                    let th = k * std::f64::consts::TAU * i as f64 / n;
                    (re + v[j] * th.cos(), im + v[j] * th.sin())
                })
            };
            let ((ur, ui), (ar, ai)) = (dft(0), dft(1));
            let scale = (k * w).powi(2) * ur.hypot(ui) + 1e-30;
            assert!(
                (ar + (k * w).powi(2) * ur).abs() <= 1e-9 * scale
                    && (ai + (k * w).powi(2) * ui).abs() <= 1e-9 * scale,
                "harmonic {k}: acceleration ({ar}, {ai}), displacement ({ur}, {ui})"
            );
        }
    }
}

fn assert_fails(dir: &Path, needles: &[&str]) {
    let out = dir.join("out-bad");
    let o = run(&["response", s(&dir.join("model.toml")), "--out-dir", s(&out)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "should fail: {needles:?}");
    for n in needles {
        assert!(err.contains(n), "stderr should mention `{n}`: {err}");
    }
    assert!(
        !out.exists() || std::fs::read_dir(&out).unwrap().count() == 0,
        "output written"
    );
}

#[test]
fn bad_inputs_fail_clearly_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    write_model(p);
    let edit = |name: &str, from: &str, to: &str| {
        let t = std::fs::read_to_string(p.join(name)).unwrap();
        assert!(t.contains(from), "{from}");
        std::fs::write(p.join(name), t.replacen(from, to, 1)).unwrap();
    };
    let reset = || write_model(p);
    edit("stiffness.csv", "-2e4,2e4", "-1e4,2e4");
    assert_fails(p, &["stiffness.csv", "symmetric"]);
    reset();
    edit("mass.csv", "0,0.5", "0,0");
    assert_fails(p, &["mass.csv", "positive definite"]);
    reset();
    edit("damping.csv", "0,1\n", "0,-1\n");
    assert_fails(p, &["damping.csv", "negative damping"]);
    reset();
    edit("stiffness.csv", "# unit: N/m", "# unit: kN/m");
    assert_fails(p, &["stiffness.csv:1", "unit"]);
    reset();
    edit("pairs.csv", "11,m2,ground", "11,m9,ground");
    assert_fails(p, &["pairs.csv:3", "m9"]);
    reset();
    edit("elements.csv", "1.0,1e6,1.0e4", "1.0,0,1.0e4");
    assert_fails(p, &["elements.csv:4", "kn_N_per_m"]);
    reset();
    edit("elements.csv", "2.0,1e6,2.0e4", "2.0,1e6,-2.0e4");
    assert_fails(p, &["elements.csv:3", "E0_N_per_m"]);
    reset();
    edit("elements.csv", "0.3,0.5,0,0", "0.3,0.0,0,0");
    assert_fails(p, &["elements.csv:3", "mu"]);
    reset();
    edit(
        "model.toml",
        "levels_n = [0.02, 0.5]",
        "levels_n = [0.5, -5.0]",
    );
    assert_fails(p, &["model.toml:15", "excitation.levels_n"]);
    reset();
    edit("model.toml", "dofs = [\"m1.x\"]", "dofs = [\"m7.x\"]");
    assert_fails(p, &["model.toml", "m7.x"]);
    reset();
    // Resource limits before anything is allocated (these once aborted out of memory).
    edit("model.toml", "harmonics = 3", "harmonics = 100000");
    assert_fails(p, &["model.toml:24", "sweep.harmonics", "limit"]);
    reset();
    edit(
        "model.toml",
        "odd_only = true",
        "odd_only = true\ntime_samples = 100000000",
    );
    assert_fails(p, &["model.toml:26", "sweep.time_samples", "limit"]);
    reset();
    // No excitation: weights that cancel on one DOF listed twice, or cancelling DOFs.
    edit(
        "model.toml",
        "dofs = [\"m1.x\"]",
        "dofs = [\"m1.x\", \"m1.x\"]\nweights = [1.0, -1.0]",
    );
    assert_fails(p, &["model.toml", "m1.x", "listed twice"]);
    reset();
    edit(
        "model.toml",
        "dofs = [\"m1.x\"]",
        "dofs = [\"m1.x\"]\nweights = [0.0]",
    );
    assert_fails(
        p,
        &["model.toml", "excitation force on the structure is zero"],
    );
    reset();
    edit(
        "model.toml",
        "levels_n = [0.02, 0.5]",
        "levels_n = [0.02, 1e30]",
    );
    assert_fails(p, &["model.toml:15", "beyond any exciter"]);
    reset();
    // A contact between a node and itself does nothing.
    edit("pairs.csv", "11,m2,ground", "11,m2,m2");
    assert_fails(p, &["pairs.csv:3", "same node"]);
    reset();
    // A directory where an output file should go: the run fails and writes nothing else.
    let out = p.join("out-bad");
    std::fs::create_dir_all(out.join("response.json")).unwrap();
    let o = run(&["response", s(&p.join("model.toml")), "--out-dir", s(&out)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("response.json"),
        "{err}"
    );
    assert_eq!(
        std::fs::read_dir(&out).unwrap().count(),
        1,
        "other outputs written"
    );
    std::fs::remove_dir_all(&out).unwrap();
    // A modal model whose contact node has no mode shape.
    std::fs::write(
        p.join("modes.csv"),
        "mode,frequency_Hz,damping_ratio\n1,20,0.01\n2,45,0.01\n",
    )
    .unwrap();
    std::fs::write(
        p.join("shapes.csv"),
        "# mass-normalised shapes\nnode,direction,mode_1_per_sqrt_kg,mode_2_per_sqrt_kg\nm1,x,0.8,0.5\n",
    )
    .unwrap();
    edit(
        "model.toml",
        "mass = \"mass.csv\"\ndamping = \"damping.csv\"\nstiffness = \"stiffness.csv\"",
        "modes = \"modes.csv\"\nshapes = \"shapes.csv\"",
    );
    assert_fails(p, &["pairs.csv:2", "m2", "no mode shape"]);
    std::fs::write(
        p.join("modes.csv"),
        "mode,frequency_Hz,damping_ratio\n1,20,-0.01\n2,45,0.01\n",
    )
    .unwrap();
    assert_fails(p, &["modes.csv:2", "negative damping"]);
}

fn levels(out: &Path) -> Vec<serde_json::Value> {
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("response.json")).unwrap()).unwrap();
    j["summary"]["levels"].as_array().unwrap().clone()
}

/// `[cyclic]` end to end: a sector with a friction damper to the next sector's blade against
/// the full assembly of its `N` sectors under the travelling wave (`phases_deg`) at engine orders
/// 0 (standing), 1 (travelling) and N/2 (standing), at a level in partial slip and one in gross
/// slip. The two systems give the same solution at a frequency to rounding
/// (tests/dynamics_cyclic.rs, with the travelling engine orders); here the sweeps' points
/// differ, and the located peaks agree to the parabolic refinement's accuracy on a branch with
/// kinks where the slip onset crosses a time sample: amplitudes within 3e-4 in partial slip
/// (1e-7 in gross slip); the partial-slip peak of EO = 2 is flat within 1e-4 over 2 Hz, and its
/// located frequency moves by 0.7 %.
#[test]
fn cyclic_sector_gives_the_full_assemblys_peaks() {
    let sectors = 4;
    for eo in [0, 1, 2] {
        let dir = tempfile::tempdir().unwrap();
        let (ds, df) = (dir.path().join("sector"), dir.path().join("full"));
        std::fs::create_dir_all(&ds).unwrap();
        std::fs::create_dir_all(&df).unwrap();
        let (ms, mf) = (
            write_sector_model(&ds, sectors, eo),
            write_full_model(&df, sectors, eo),
        );
        let mut peaks = Vec::new();
        for (model, dir) in [(&ms, &ds), (&mf, &df)] {
            let out = dir.join("out");
            let o = run(&["response", s(model), "--out-dir", s(&out)]);
            assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
            peaks.push(levels(&out));
        }
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(ds.join("out/response.json")).unwrap())
                .unwrap();
        let cyc = &json["parameters"]["cyclic"];
        assert_eq!(cyc["sectors"], sectors, "{json}");
        // Harmonics 1 and 3 of engine order EO of 4 are both of index EO (3·1 mod 4 = 3 → 1).
        let index: Vec<u64> = cyc["harmonic_index"]
            .as_array()
            .unwrap()
            .iter()
            .map(|h| h["index"].as_u64().unwrap())
            .collect();
        assert_eq!(index, vec![eo as u64; 2]);
        for (a, b) in peaks[0].iter().zip(&peaks[1]) {
            for (key, tolerance) in [("peak_amplitude_m", 1e-3), ("peak_frequency_Hz", 1e-2)] {
                let (x, y) = (a[key].as_f64().unwrap(), b[key].as_f64().unwrap());
                assert!(
                    (x / y - 1.0).abs() < tolerance,
                    "EO = {eo}, level {}: {key} sector {x}, full {y}",
                    a["level_N"]
                );
            }
            assert_eq!(a["peak_at_sweep_end"], false);
        }
        // Friction matters: the gross-slip level's peak is far below the partial-slip one's
        // scaled by the level (a linear structure would scale exactly).
        let ratio = peaks[0][1]["peak_amplitude_m"].as_f64().unwrap()
            / peaks[0][0]["peak_amplitude_m"].as_f64().unwrap();
        assert!(
            (ratio / 10.0 - 1.0).abs() > 0.2,
            "EO = {eo}: peak ratio {ratio}"
        );
    }
}

/// Bad `[cyclic]` inputs: a clear error naming the file, line and key, and nothing written.
#[test]
fn bad_cyclic_inputs_fail_clearly_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    let edit = |from: &str, to: &str| {
        write_sector_model(p, 4, 1);
        let t = std::fs::read_to_string(p.join("model.toml")).unwrap();
        assert!(t.contains(from), "{from}");
        std::fs::write(p.join("model.toml"), t.replacen(from, to, 1)).unwrap();
    };
    edit("left = [\"disk_l.x\"]", "left = [\"disk_q.x\"]");
    assert_fails(p, &["model.toml:9", "cyclic.left", "disk_q.x"]);
    edit(
        "right = [\"disk_r.x\"]",
        "right = [\"disk_r.x\", \"blade.x\"]",
    );
    assert_fails(
        p,
        &[
            "model.toml:10",
            "cyclic.right",
            "2 right boundary DOFs for 1",
        ],
    );
    edit("right = [\"disk_r.x\"]", "right = [\"disk_l.x\"]");
    assert_fails(p, &["model.toml:10", "cyclic.right", "twice"]);
    edit("sectors = 4", "sectors = 1");
    assert_fails(p, &["model.toml:7", "cyclic.sectors", "at least 2"]);
    edit(
        "odd_only = true",
        "odd_only = true\nformulation = \"receptance\"",
    );
    assert_fails(p, &["model.toml", "sweep.formulation", "coordinates"]);
    edit(
        "dofs = [\"blade.x\"]",
        "dofs = [\"blade.x\"]\nphases_deg = [0.0, 90.0]",
    );
    assert_fails(
        p,
        &["model.toml", "excitation.phases_deg", "one finite phase"],
    );
    edit("node_b = \"next:blade\"", "node_b = \"next:blad\"");
    assert_fails(p, &["damper.csv:3", "next:blad", "not a node"]);
    // A node of the next sector in a model without [cyclic].
    edit(
        "[cyclic]\nsectors = 4\nengine_order = 1\nleft = [\"disk_l.x\"]\nright = [\"disk_r.x\"]\n",
        "",
    );
    assert_fails(p, &["model.toml", "contact.node_b", "no [cyclic] section"]);
}
