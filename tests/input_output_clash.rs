//! No command writes over, or removes, one of its own inputs: for every command an output path
//! that is an input — the same path, another spelling of it, a symbolic or a hard link, or a
//! file the stale-file cleanup would remove — is refused with an error naming both paths, a
//! non-zero exit, the input byte for byte as it was and nothing written.

use std::path::{Path, PathBuf};
use std::process::Command;

/// Every file below `dir` with its content.
fn snapshot(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() && !p.is_symlink() {
                stack.push(p.clone());
                out.push((p, Vec::new()));
            } else {
                out.push((p.clone(), std::fs::read(&p).unwrap_or_default()));
            }
        }
    }
    out.sort();
    out
}

/// Run `asperity args` in `dir` (paths relative to it) and check the refusal: exit 1, the
/// message names `output` and `input` (as given on the command line) and says it would be
/// overwritten or removed, and every file of `dir` is as it was (nothing new, nothing changed).
fn refused(dir: &Path, args: &[&str], output: &str, input: &str) -> String {
    let before = snapshot(dir);
    let o = Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
    assert!(
        err.contains(output) && err.contains(input),
        "{args:?}: the message must name `{output}` and `{input}`: {err}"
    );
    assert!(
        err.contains("overwritten") || err.contains("removed"),
        "{args:?}: {err}"
    );
    assert!(
        !err.contains(".asperity-"),
        "{args:?}: a staged file named: {err}"
    );
    let after = snapshot(dir);
    assert!(
        before == after,
        "{args:?}: files changed or left behind: {:?}",
        after
            .iter()
            .filter(|a| !before.contains(a))
            .map(|a| &a.0)
            .collect::<Vec<_>>()
    );
    err
}

fn write(dir: &Path, name: &str, content: impl AsRef<[u8]>) {
    let p = dir.join(name);
    std::fs::create_dir_all(p.parent().unwrap()).unwrap();
    std::fs::write(p, content).unwrap();
}

/// A `.npy` file (float64, C order, `n × n`) of a rough height map, with its sidecar.
fn npy(dir: &Path, name: &str, n: usize, phase: usize) {
    let mut h = format!("{{'descr': '<f8', 'fortran_order': False, 'shape': ({n}, {n}), }}");
    while (h.len() + 11) % 64 != 0 {
        h.push(' ');
    }
    h.push('\n');
    let mut v = b"\x93NUMPY\x01\x00".to_vec();
    v.extend_from_slice(&(h.len() as u16).to_le_bytes());
    v.extend_from_slice(h.as_bytes());
    for k in 0..n * n {
        let z = 1e-7 * (((k * 37 + phase * 11) % 17) as f64 - 8.0);
        v.extend_from_slice(&z.to_le_bytes());
    }
    write(dir, name, v);
    write(
        dir,
        &format!("{name}.json"),
        "{\"unit\": \"m\", \"dx_m\": 1e-6, \"dy_m\": 1e-6, \"periodic\": false}",
    );
}

/// A rough `n × n` height matrix (CSV text, heights in m, 1 µm spacing).
fn matrix(n: usize) -> String {
    let mut t = String::from("# unit: m, dx_m: 1e-6, dy_m: 1e-6\n");
    for j in 0..n {
        let row: Vec<String> = (0..n)
            .map(|i| format!("{:e}", 1e-7 * (((i * 37 + j * 11) % 17) as f64 - 8.0)))
            .collect();
        t += &row.join(",");
        t.push('\n');
    }
    t
}

const PROFILE: &str = "x_um,height_nm\n0,1\n1,2\n2,0\n3,1\n4,3\n5,-1\n";

#[test]
fn surface_commands_refuse_their_input_as_output() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    npy(d, "p.npy", 16, 0);
    npy(d, "q.npy", 16, 3);
    write(d, "p.csv", PROFILE);
    // stats: the profile replaced by its PSD.
    refused(
        d,
        &["surface", "stats", "p.csv", "--psd-out", "p.csv"],
        "p.csv",
        "p.csv",
    );
    // stats: another spelling of the same path.
    refused(
        d,
        &["surface", "stats", "p.csv", "--psd-out", "sub/../p.csv"],
        "sub/../p.csv",
        "p.csv",
    );
    // combine: body 1 replaced by the difference (and its sidecar).
    refused(
        d,
        &["surface", "combine", "p.npy", "q.npy", "-o", "p.npy"],
        "p.npy",
        "p.npy",
    );
    refused(
        d,
        &[
            "surface", "combine", "p.npy", "q.npy", "-o", "x.npy", "-o", "q.npy",
        ],
        "q.npy",
        "SURFACE2",
    );
    // convert: the input among the outputs.
    refused(
        d,
        &["surface", "convert", "p.npy", "-o", "a.x3p", "-o", "p.npy"],
        "p.npy",
        "p.npy",
    );
    // generate: the configuration file as an output.
    write(
        d,
        "spec.npy",
        "rq_m = 1e-7\nclx_m = 3e-6\ncly_m = 3e-6\nlx_m = 3.2e-5\nly_m = 3.2e-5\nnx = 32\nny = 32\nseed = 1\n",
    );
    refused(
        d,
        &[
            "surface", "generate", "--config", "spec.npy", "-o", "spec.npy",
        ],
        "spec.npy",
        "--config",
    );
}

/// The same file under another name: a symbolic link and a hard link to the input.
#[cfg(unix)]
#[test]
fn a_link_to_an_input_is_the_input() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(d, "p.csv", PROFILE);
    std::os::unix::fs::symlink(d.join("p.csv"), d.join("sym.csv")).unwrap();
    std::fs::hard_link(d.join("p.csv"), d.join("hard.csv")).unwrap();
    for link in ["sym.csv", "hard.csv"] {
        let e = refused(
            d,
            &["surface", "stats", "p.csv", "--psd-out", link],
            link,
            "p.csv",
        );
        assert!(e.contains("link"), "{e}");
    }
    // A measured record reached through a linked name in the output directory.
    write(
        d,
        "r.csv",
        "time_s,displacement_m,friction_force_N\n0,0,0\n",
    );
    std::fs::create_dir(d.join("out")).unwrap();
    std::fs::hard_link(d.join("r.csv"), d.join("out/diagnose.csv")).unwrap();
    refused(
        d,
        &["diagnose", "r.csv", "--out-dir", "out"],
        "out/diagnose.csv",
        "r.csv",
    );
}

#[test]
fn contact_and_calibrate_refuse_their_surface_as_output() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(d, "out/normal_sweep.csv", matrix(16));
    refused(
        d,
        &[
            "contact",
            "normal",
            "--surface",
            "out/normal_sweep.csv",
            "--pressures-pa",
            "1e6",
            "--out-dir",
            "out",
        ],
        "normal_sweep.csv",
        "--surface",
    );
    write(d, "out/tangential_loops.csv", matrix(16));
    refused(
        d,
        &[
            "contact",
            "tangential",
            "--surface",
            "out/tangential_loops.csv",
            "--out-dir",
            "out",
        ],
        "tangential_loops.csv",
        "--surface",
    );
    write(d, "calib/calibration_table.csv", matrix(16));
    refused(
        d,
        &[
            "calibrate",
            "--surface",
            "calib/calibration_table.csv",
            "--out-dir",
            "calib",
        ],
        "calibration_table.csv",
        "--surface",
    );
}

#[test]
fn calibrate_refuses_its_configuration_as_output() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(
        d,
        "calib/calibration.json",
        std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("calib/reference.toml")).unwrap(),
    );
    refused(
        d,
        &["calibrate", "calib/calibration.json", "--out-dir", "calib"],
        "calibration.json",
        "configuration",
    );
}

#[test]
fn film_and_elements_refuse_their_inputs_as_outputs() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(d, "img.png", b"not read");
    write(
        d,
        "out/preload.csv",
        "pressure_MPa,R,G,B\n0,255,255,255\n2.5,255,200,200\n10,255,0,0\n",
    );
    refused(
        d,
        &[
            "film",
            "--image",
            "img.png",
            "--colour-table",
            "out/preload.csv",
            "--pixel-size-mm",
            "0.1",
            "--out-dir",
            "out",
        ],
        "preload.csv",
        "--colour-table",
    );
    write(
        d,
        "p.csv",
        "id,x_m,y_m,area_m2,pressure_Pa,N0_N\n1,0,0,1e-6,1.5e6,1.5\n",
    );
    write(d, "t.csv", "pressure_Pa\n1e6\n");
    refused(
        d,
        &[
            "elements",
            "--preload",
            "p.csv",
            "--table",
            "t.csv",
            "--out",
            "p.csv",
        ],
        "p.csv",
        "--preload",
    );
    // The JSON sidecar of --out is an output too.
    write(d, "t.json", "{}");
    refused(
        d,
        &[
            "elements",
            "--preload",
            "p.csv",
            "--table",
            "t.json",
            "--out",
            "t.csv",
        ],
        "t.json",
        "--table",
    );
}

/// The response-model cases: an element table named like a per-level output is overwritten (level
/// 1) or removed by the stale-file cleanup (level 3 of a one-level model); a matrix too.
#[test]
fn response_refuses_the_files_its_model_names() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let model = |elements: &str, mass: &str| {
        format!(
            "[linear]\nmass = \"{mass}\"\ndamping = \"damping.csv\"\nstiffness = \"stiffness.csv\"\n\n\
[[contact]]\nelements = \"{elements}\"\nlaw = \"valanis\"\nnode_a = \"m2\"\nnode_b = \"ground\"\n\
normal = [0.0, 0.0, 1.0]\ntangent = [1.0, 0.0, 0.0]\n\n\
[excitation]\ndofs = [\"m1.x\"]\nlevels_n = [0.02]\n\n\
[response]\ndofs = [\"m1.x\"]\n\n\
[sweep]\nfrequency_start_hz = 15.0\nfrequency_end_hz = 50.0\npoints = 15\nharmonics = 3\nodd_only = true\n"
        )
    };
    let elements =
        "id,x_m,y_m,area_m2,pressure_Pa,N0_N,kn_N_per_m,E0_N_per_m,k,mu,Et_N_per_m,out_of_range\n\
7,0,0,1e-6,2e6,2.0,1e6,2.0e4,0.3,0.5,0,0\n";
    write(d, "m/mass.csv", "# unit: kg\nm1.x,m2.x\n1.0,0\n0,0.5\n");
    write(
        d,
        "m/stiffness.csv",
        "# unit: N/m\nm1.x,m2.x\n6e4,-2e4\n-2e4,2e4\n",
    );
    write(d, "m/damping.csv", "# unit: N*s/m\nm1.x,m2.x\n2,0\n0,1\n");
    for table in ["elements_level_1.csv", "elements_level_3.csv"] {
        write(d, &format!("m/{table}"), elements);
        write(d, "m/model.toml", model(table, "mass.csv"));
        refused(
            d,
            &["response", "m/model.toml", "--out-dir", "m"],
            table,
            "contact 1 elements",
        );
        std::fs::remove_file(d.join("m").join(table)).unwrap();
    }
    // A matrix the model names.
    write(d, "m/elements.csv", elements);
    std::fs::rename(d.join("m/mass.csv"), d.join("m/response.json")).unwrap();
    write(d, "m/model.toml", model("elements.csv", "response.json"));
    refused(
        d,
        &["response", "m/model.toml", "--out-dir", "m"],
        "response.json",
        "mass matrix",
    );
}

#[test]
fn diagnose_identify_predict_refuse_the_measured_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(
        d,
        "out/diagnose.csv",
        "time_s,displacement_m,friction_force_N\n0,0,0\n1,1e-4,1\n",
    );
    refused(
        d,
        &["diagnose", "out/diagnose.csv", "--out-dir", "out"],
        "out/diagnose.csv",
        "measured record",
    );
    write(d, "out/diagnose.json", "pressure_Pa\n1\n");
    write(
        d,
        "r.csv",
        "time_s,displacement_m,friction_force_N\n0,0,0\n1,1e-4,1\n",
    );
    refused(
        d,
        &[
            "diagnose",
            "r.csv",
            "--table",
            "out/diagnose.json",
            "--pressure-pa",
            "1e6",
            "--area-m2",
            "1e-4",
            "--out-dir",
            "elsewhere/../out",
        ],
        "diagnose.json",
        "--table",
    );
    let sweep = "frequency_Hz,force_amplitude_N,displacement_amplitude_m,phase_rad\n99,1,1e-6,-0.1\n100,1,2e-6,-1.5\n101,1,1e-6,-3\n";
    write(d, "id/identify-rows.csv", sweep);
    write(d, "id/b.csv", sweep.replace(",1,", ",2,"));
    refused(
        d,
        &[
            "identify",
            "id/identify-rows.csv",
            "id/b.csv",
            "--out-dir",
            "id",
        ],
        "identify-rows.csv",
        "measured file",
    );
    // Per-level plots of an earlier run are removed by the cleanup: a measured file named so.
    write(d, "id/identify-level9.png", sweep);
    refused(
        d,
        &[
            "identify",
            "id/identify-level9.png",
            "id/b.csv",
            "--out-dir",
            "id",
        ],
        "identify-level9.png",
        "measured file",
    );
    write(d, "m.json", "{}");
    write(d, "out/predict-rows.csv", sweep);
    refused(
        d,
        &[
            "predict",
            "--model",
            "m.json",
            "out/predict-rows.csv",
            "--out-dir",
            "out",
        ],
        "out/predict-rows.csv",
        "measured file",
    );
    write(d, "out/predict.json", "{}");
    write(d, "a.csv", sweep);
    refused(
        d,
        &[
            "predict",
            "--model",
            "out/predict.json",
            "a.csv",
            "--out-dir",
            "out",
        ],
        "predict.json",
        "--model",
    );
}

/// `merge`: a shard file that is one of the outputs (caught at the commit, after the shards are
/// read: nothing is moved).
#[test]
fn merge_refuses_a_shard_as_output() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(d, "s.csv", matrix(16));
    let o = Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args([
            "contact",
            "normal",
            "--surface",
            "s.csv",
            "--pressures-pa",
            "1e6,2e6",
            "--shard",
            "1/1",
            "--out-dir",
            "sh",
        ])
        .current_dir(d)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let shard = std::fs::read_dir(d.join("sh"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.to_string_lossy().ends_with(".json"))
        .unwrap();
    std::fs::rename(&shard, d.join("sh/normal_sweep.csv")).unwrap();
    refused(
        d,
        &["merge", "sh/normal_sweep.csv", "--out-dir", "sh"],
        "normal_sweep.csv",
        "shard file",
    );
}
