//! Sharded normal-contact sweeps end to end: `asperity contact normal --shard i/n` on several
//! surfaces, then `asperity merge`, must write byte for byte the files a single run writes
//! (the table, the statistics and the plots; only the wall-time file differs), and a missing,
//! duplicated or foreign shard must fail with a message naming the files and write nothing.
//! The same for the calibration (`asperity calibrate --shard i/n`, the unit one realisation
//! with its grid- and patch-check chains): every file of a single run but
//! `calibration_timings.csv`, byte for byte.

use std::path::{Path, PathBuf};
use std::process::Command;

fn asperity(args: &[&str], threads: usize) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args(args)
        .env("RAYON_NUM_THREADS", threads.to_string())
        .output()
        .expect("run asperity");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// The reference statistics on a coarse 128² grid, five seeds, two pressures: a few ms a solve.
const CASE: [&str; 7] = [
    "contact",
    "normal",
    "--seeds",
    "2-4,7,9",
    "--grid",
    "128",
    "--pressures-pa=1e6,8e6",
];

fn run_case(extra: &[&str], threads: usize) -> (bool, String, String) {
    let mut args: Vec<&str> = CASE.to_vec();
    args.extend_from_slice(extra);
    asperity(&args, threads)
}

fn shards(dir: &Path, n: usize) -> Vec<PathBuf> {
    (1..=n)
        .map(|i| {
            let shard = format!("{i}/{n}");
            let (ok, _, err) =
                run_case(&["--out-dir", dir.to_str().unwrap(), "--shard", &shard], 1);
            assert!(ok, "shard {shard}: {err}");
            dir.join(format!("contact-normal.shard-{i}-of-{n}.json"))
        })
        .collect()
}

fn merge(paths: &[PathBuf], out: &Path) -> (bool, String, String) {
    let mut args = vec!["merge".to_string()];
    args.extend(paths.iter().map(|p| p.display().to_string()));
    args.extend(["--out-dir".into(), out.display().to_string()]);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    asperity(&args, 2)
}

const REPRODUCIBLE: [&str; 5] = [
    "normal_sweep.csv",
    "normal_sweep_statistics.csv",
    "area_ratio.png",
    "mean_gap.png",
    "kn.png",
];

#[test]
fn merged_shards_equal_the_single_run_byte_for_byte() {
    let tmp = tempfile::tempdir().unwrap();
    let single = tmp.path().join("single");
    let (ok, stdout, err) = run_case(&["--out-dir", single.to_str().unwrap()], 2);
    assert!(ok, "{err}");
    assert!(stdout.contains("over 5 surfaces"), "{stdout}");
    // Three shards (1, 2 and 2 surfaces) run single-threaded, and four (one of them holding a
    // single surface) merged from a list given out of order.
    for n in [3, 4] {
        let dir = tmp.path().join(format!("shards-{n}"));
        let mut paths = shards(&dir, n);
        paths.reverse();
        let merged = tmp.path().join(format!("merged-{n}"));
        let (ok, _, err) = merge(&paths, &merged);
        assert!(ok, "{err}");
        for f in REPRODUCIBLE {
            let a = std::fs::read(single.join(f)).unwrap();
            let b = std::fs::read(merged.join(f)).unwrap();
            assert!(
                a == b,
                "{f} differs between the single run and {n} merged shards"
            );
        }
        let timings = std::fs::read_to_string(merged.join("normal_sweep_timings.csv")).unwrap();
        assert_eq!(
            timings.lines().filter(|l| l.starts_with("seed-")).count(),
            10
        );
    }
    // The table holds every surface × pressure, and the surfaces differ (the test can fail).
    let table = std::fs::read_to_string(single.join("normal_sweep.csv")).unwrap();
    let rows: Vec<&str> = table
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("surface,"))
        .collect();
    assert_eq!(rows.len(), 10);
    assert!(rows[0].starts_with("seed-2,1e6,") && rows[9].starts_with("seed-9,8e6,"));
    assert_ne!(rows[0].split(',').nth(3), rows[2].split(',').nth(3));
}

#[test]
fn sharded_surface_files_merge_too() {
    let tmp = tempfile::tempdir().unwrap();
    // Two measured-like files: generated surfaces written as .npy.
    let mut files = Vec::new();
    for seed in ["5", "6"] {
        let f = tmp.path().join(format!("s{seed}.npy"));
        let (ok, _, err) = asperity(
            &[
                "surface",
                "generate",
                "--nx",
                "48",
                "--ny",
                "48",
                "--lx-m",
                "100e-6",
                "--ly-m",
                "100e-6",
                "--clx-m",
                "8e-6",
                "--cly-m",
                "8e-6",
                "--seed",
                seed,
                "-o",
                f.to_str().unwrap(),
            ],
            2,
        );
        assert!(ok, "{err}");
        files.push(f.display().to_string());
    }
    let base = |out: &Path| -> Vec<String> {
        vec![
            "contact".into(),
            "normal".into(),
            "--surface".into(),
            files[0].clone(),
            "--surface".into(),
            files[1].clone(),
            "--pressures-pa=2e6".into(),
            "--out-dir".into(),
            out.display().to_string(),
        ]
    };
    let single = tmp.path().join("single");
    let args = base(&single);
    let (ok, _, err) = asperity(&args.iter().map(String::as_str).collect::<Vec<_>>(), 2);
    assert!(ok, "{err}");
    let dir = tmp.path().join("shards");
    let mut paths = Vec::new();
    for i in 1..=2 {
        let mut args = base(&dir);
        args.extend(["--shard".into(), format!("{i}/2")]);
        let (ok, _, err) = asperity(&args.iter().map(String::as_str).collect::<Vec<_>>(), 1);
        assert!(ok, "{err}");
        paths.push(dir.join(format!("contact-normal.shard-{i}-of-2.json")));
    }
    let merged = tmp.path().join("merged");
    let (ok, _, err) = merge(&paths, &merged);
    assert!(ok, "{err}");
    for f in REPRODUCIBLE {
        assert_eq!(
            std::fs::read(single.join(f)).unwrap(),
            std::fs::read(merged.join(f)).unwrap(),
            "{f}"
        );
    }
}

fn assert_fails_without_output(result: (bool, String, String), needles: &[&str], out: &Path) {
    let (ok, _, err) = result;
    assert!(!ok, "should fail");
    for n in needles {
        assert!(err.contains(n), "`{n}` not in: {err}");
    }
    assert!(!out.exists(), "output written: {}", out.display());
}

#[test]
fn missing_duplicated_or_foreign_shards_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("shards");
    let paths = shards(&dir, 3);
    let out = tmp.path().join("merged");
    // Missing shard 2: named by its file name.
    assert_fails_without_output(
        merge(&[paths[0].clone(), paths[2].clone()], &out),
        &["missing", "contact-normal.shard-2-of-3.json"],
        &out,
    );
    // Duplicated: the same shard under another name.
    let copy = tmp.path().join("copy-of-shard-3.json");
    std::fs::copy(&paths[2], &copy).unwrap();
    let mut with_copy = paths.clone();
    with_copy.push(copy.clone());
    assert_fails_without_output(
        merge(&with_copy, &out),
        &[
            "given twice",
            "copy-of-shard-3.json",
            "contact-normal.shard-3-of-3.json",
        ],
        &out,
    );
    // Another configuration (other pressures): both files named.
    let other = tmp.path().join("other");
    let (ok, _, err) = asperity(
        &[
            "contact",
            "normal",
            "--seeds",
            "2-4,7,9",
            "--grid",
            "128",
            "--pressures-pa=1e6,9e6",
            "--shard",
            "3/3",
            "--out-dir",
            other.to_str().unwrap(),
        ],
        2,
    );
    assert!(ok, "{err}");
    let foreign = other.join("contact-normal.shard-3-of-3.json");
    assert_fails_without_output(
        merge(&[paths[0].clone(), paths[1].clone(), foreign.clone()], &out),
        &["different configurations", foreign.to_str().unwrap()],
        &out,
    );
    // Results swapped between two shard files, their labels kept (shard 1 holds seed 2,
    // shard 2 seeds 3 and 4, all on the same grid): refused naming the file, the unit and
    // both surfaces.
    let (swapped, labels) = swap_first_results(&paths[0], &paths[1], tmp.path(), "swapped");
    assert_eq!(labels, ["seed-2", "seed-3"]);
    let read = |p: &Path| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
    };
    assert_fails_without_output(
        merge(
            &[swapped[0].clone(), swapped[1].clone(), paths[2].clone()],
            &out,
        ),
        &[
            "swapped-1.json",
            "unit 0 (`seed-2`)",
            "`surface`",
            "seed 3)",
            "seed 2)",
        ],
        &out,
    );
    // A shard of another build (as a rebuilt binary writes it: another commit and sources):
    // refused naming both files and both builds.
    let mut c = read(&paths[2]);
    let ours = c["build"].clone();
    assert_eq!(ours["crate_version"], env!("CARGO_PKG_VERSION"));
    c["build"]["git_commit"] = "0123456789abcdef0123456789abcdef01234567".into();
    c["build"]["source_sha256"] = "cd".repeat(32).into();
    let rebuilt = tmp.path().join("rebuilt-3-of-3.json");
    std::fs::write(&rebuilt, c.to_string()).unwrap();
    let source = ours["source_sha256"].as_str().unwrap();
    assert_fails_without_output(
        merge(&[paths[0].clone(), paths[1].clone(), rebuilt.clone()], &out),
        &[
            "different builds",
            "contact-normal.shard-1-of-3.json",
            "rebuilt-3-of-3.json",
            "commit 0123456789ab",
            "sources cdcdcdcdcdcd",
            &source[..12],
        ],
        &out,
    );
    // All shards of one other build: merged (they agree), with a warning that this build
    // writes the outputs.
    let others: Vec<PathBuf> = paths
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let mut j = read(p);
            j["build"] = c["build"].clone();
            let q = tmp.path().join(format!("other-build-{}-of-3.json", i + 1));
            std::fs::write(&q, j.to_string()).unwrap();
            q
        })
        .collect();
    let merged_other = tmp.path().join("merged-other-build");
    let (ok, _, err) = merge(&others, &merged_other);
    assert!(ok, "{err}");
    assert!(
        err.contains("warning: the shards were computed by")
            && err.contains("commit 0123456789ab")
            && err.contains(&source[..12]),
        "{err}"
    );
    assert!(merged_other.join("normal_sweep.csv").is_file());
    // A file of the format v1 (which recorded only the crate version).
    let mut v1 = read(&paths[2]);
    let obj = v1.as_object_mut().unwrap();
    obj.remove("build");
    obj.insert("crate_version".into(), env!("CARGO_PKG_VERSION").into());
    obj.insert("format".into(), "asperity-shard-v1".into());
    let old = tmp.path().join("old-3-of-3.json");
    std::fs::write(&old, v1.to_string()).unwrap();
    assert_fails_without_output(
        merge(&[paths[0].clone(), paths[1].clone(), old], &out),
        &[
            "old-3-of-3.json",
            "asperity-shard-v1",
            "no build identity",
            "rerun the shards",
        ],
        &out,
    );
    // Not a shard file, and a missing file.
    let junk = tmp.path().join("junk.json");
    std::fs::write(&junk, "[1, 2]").unwrap();
    assert_fails_without_output(merge(&[junk], &out), &["junk.json"], &out);
    assert_fails_without_output(
        merge(&[tmp.path().join("absent.json")], &out),
        &["absent.json"],
        &out,
    );
}

#[test]
fn bad_shard_and_seed_flags_fail_cleanly() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let o = out.to_str().unwrap();
    for (extra, needle) in [
        (vec!["--shard", "0/4"], "--shard"),
        (vec!["--shard", "5/4"], "--shard"),
        (vec!["--shard", "two"], "--shard"),
    ] {
        let mut args = extra.clone();
        args.extend(["--out-dir", o]);
        assert_fails_without_output(run_case(&args, 2), &[needle], &out);
    }
    for (seeds, needle) in [("4-2", "empty"), ("1,x", "not a seed"), ("1-3,2", "twice")] {
        assert_fails_without_output(
            asperity(
                &[
                    "contact",
                    "normal",
                    "--seeds",
                    seeds,
                    "--grid",
                    "128",
                    "--out-dir",
                    o,
                ],
                2,
            ),
            &["--seeds", needle],
            &out,
        );
    }
}

// ---------------------------------------------------------------- calibration

/// The reference statistics on a 128² grid over 128 µm (1 µm spacing, so the grid check at 64²
/// and the patch check on 64 µm both run), 3 realisations, 2 pressures, 2 amplitudes:
/// under a second in all.
fn small_config(dir: &Path, realisations: usize) -> PathBuf {
    let reference =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("calib/reference.toml"))
            .unwrap();
    let text: String = reference
        .lines()
        .map(|l| {
            let key = l.split('=').next().unwrap_or("").trim();
            match key {
                "lx_m" | "ly_m" => format!("{key} = 1.28e-4"),
                "nx" | "ny" => format!("{key} = 128"),
                "count" => format!("count = {realisations}"),
                "pressures_pa" => "pressures_pa = [1e6, 5e6]".into(),
                "amplitude_factors" => "amplitude_factors = [0.5, 1.0]".into(),
                "steps_per_cycle" => "steps_per_cycle = 20".into(),
                _ => l.to_string(),
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    let path = dir.join(format!("small-{realisations}.toml"));
    std::fs::write(&path, text).unwrap();
    path
}

fn calibration_shards(config: &Path, dir: &Path, n: usize) -> Vec<PathBuf> {
    (1..=n)
        .map(|i| {
            let shard = format!("{i}/{n}");
            let (ok, _, err) = asperity(
                &[
                    "calibrate",
                    config.to_str().unwrap(),
                    "--out-dir",
                    dir.to_str().unwrap(),
                    "--shard",
                    &shard,
                ],
                1,
            );
            assert!(ok, "shard {shard}: {err}");
            dir.join(format!("calibrate.shard-{i}-of-{n}.json"))
        })
        .collect()
}

fn files_of(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| !n.ends_with(".json") || n == "calibration.json")
        .collect();
    names.sort();
    names
}

#[test]
fn merged_calibration_shards_equal_the_single_run_byte_for_byte() {
    let tmp = tempfile::tempdir().unwrap();
    let config = small_config(tmp.path(), 3);
    let single = tmp.path().join("single");
    let (ok, stdout, err) = asperity(
        &[
            "calibrate",
            config.to_str().unwrap(),
            "--out-dir",
            single.to_str().unwrap(),
        ],
        2,
    );
    assert!(ok, "{err}");
    assert!(stdout.contains("3 grid-check, 3 patch-check"), "{stdout}");
    let expected = files_of(&single);
    assert!(expected.len() >= 15, "{expected:?}");
    // Two shards (1 and 2 realisations) and three (one each, given out of order).
    for n in [2, 3] {
        let dir = tmp.path().join(format!("shards-{n}"));
        let mut paths = calibration_shards(&config, &dir, n);
        paths.reverse();
        let merged = tmp.path().join(format!("merged-{n}"));
        let (ok, stdout, err) = merge(&paths, &merged);
        assert!(ok, "{err}");
        assert!(stdout.contains("3 realisations"), "{stdout}");
        assert_eq!(files_of(&merged), expected);
        for f in &expected {
            if f == "calibration_timings.csv" {
                continue;
            }
            let a = std::fs::read(single.join(f)).unwrap();
            let b = std::fs::read(merged.join(f)).unwrap();
            assert!(
                a == b,
                "{f} differs between the single run and {n} merged shards"
            );
        }
        // The timings are the shards' own: 9 chains × (5 stage rows + 3 rows per pressure).
        let timings = std::fs::read_to_string(merged.join("calibration_timings.csv")).unwrap();
        assert_eq!(timings.lines().count(), 2 + 9 * (5 + 3 * 2), "{timings}");
    }
    // The realisations differ (the comparison can fail) and the sidecar names the config file.
    let rows = std::fs::read_to_string(single.join("calibration_realisations.csv")).unwrap();
    let kn: Vec<&str> = rows
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(7).unwrap())
        .collect();
    assert_eq!(kn.len(), 6);
    assert_ne!(kn[0], kn[2]);
    let sidecar = std::fs::read_to_string(single.join("calibration.json")).unwrap();
    assert!(sidecar.contains("small-3.toml"), "{sidecar}");
}

#[test]
fn missing_duplicated_or_foreign_calibration_shards_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let config = small_config(tmp.path(), 3);
    let paths = calibration_shards(&config, &tmp.path().join("shards"), 3);
    let out = tmp.path().join("merged");
    assert_fails_without_output(
        merge(&[paths[0].clone(), paths[2].clone()], &out),
        &["missing", "calibrate.shard-2-of-3.json"],
        &out,
    );
    let copy = tmp.path().join("copy.json");
    std::fs::copy(&paths[1], &copy).unwrap();
    assert_fails_without_output(
        merge(
            &[paths[0].clone(), paths[1].clone(), copy, paths[2].clone()],
            &out,
        ),
        &["given twice", "copy.json"],
        &out,
    );
    // Another configuration: 4 realisations split in 3 (shard 3 holds realisations 3..4).
    let other = small_config(tmp.path(), 4);
    let foreign = calibration_shards(&other, &tmp.path().join("other"), 3);
    assert_fails_without_output(
        merge(
            &[paths[0].clone(), paths[1].clone(), foreign[2].clone()],
            &out,
        ),
        &["different configurations", "other"],
        &out,
    );
    // An edited result (k = 1.7 is no Valanis element): the shard file and the field named.
    let mut json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&paths[1]).unwrap()).unwrap();
    json["units"][0]["result"]["main"]["pressures"][0]["fit"]["params"]["k"] =
        serde_json::json!(1.7);
    let edited = tmp.path().join("edited-calibrate.json");
    std::fs::write(&edited, json.to_string()).unwrap();
    assert_fails_without_output(
        merge(&[paths[0].clone(), edited, paths[2].clone()], &out),
        &["edited-calibrate.json", "main chain", "k", "1.7"],
        &out,
    );
    // A result moved to another pressure than the configuration's (1e6 Pa): named, not merged.
    json["units"][0]["result"]["main"]["pressures"][0]["fit"]["params"]["k"] =
        serde_json::json!(0.5);
    json["units"][0]["result"]["main"]["pressures"][0]["sweep"]["pressure_pa"] =
        serde_json::json!(3e6);
    let moved = tmp.path().join("moved-calibrate.json");
    std::fs::write(&moved, json.to_string()).unwrap();
    assert_fails_without_output(
        merge(&[paths[0].clone(), moved, paths[2].clone()], &out),
        &[
            "moved-calibrate.json",
            "main chain at 1e6 Pa",
            "pressure_pa",
            "3e6",
        ],
        &out,
    );
    // Two realisations' results swapped between shard files, their labels kept: refused
    // naming the file, the unit and the seeds (realisation 0 is seed 1, realisation 1 seed 2).
    let (swapped, _) = swap_first_results(&paths[0], &paths[1], tmp.path(), "swapped-calibrate");
    let read = |p: &Path| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
    };
    assert_fails_without_output(
        merge(
            &[swapped[0].clone(), swapped[1].clone(), paths[2].clone()],
            &out,
        ),
        &[
            "swapped-calibrate-1.json",
            "unit 0 (`seed-1`)",
            "main chain: computed from seed 2,",
            "prescribes seed 1,",
        ],
        &out,
    );
    // The grid check's chain pasted into the main chain's place (same seed, 64² not 128²).
    let mut c = read(&paths[1]);
    c["units"][0]["result"]["main"] = c["units"][0]["result"]["grid_check"].clone();
    let pasted = tmp.path().join("pasted-calibrate.json");
    std::fs::write(&pasted, c.to_string()).unwrap();
    assert_fails_without_output(
        merge(&[paths[0].clone(), pasted, paths[2].clone()], &out),
        &[
            "pasted-calibrate.json",
            "main chain: computed from seed 2, 64 x 64 points",
            "128 x 128 points",
        ],
        &out,
    );
    // A normal-sweep shard is another kind.
    let (ok, _, err) = asperity(
        &[
            "contact",
            "normal",
            "--seeds",
            "1",
            "--grid",
            "128",
            "--pressures-pa=1e6",
            "--shard",
            "1/1",
            "--out-dir",
            tmp.path().join("normal").to_str().unwrap(),
        ],
        1,
    );
    assert!(ok, "{err}");
    assert_fails_without_output(
        merge(
            &[
                paths[0].clone(),
                tmp.path().join("normal/contact-normal.shard-1-of-1.json"),
            ],
            &out,
        ),
        &["contact-normal", "expected `calibrate`"],
        &out,
    );
    // --shard needs generated surfaces, and a valid i/n.
    let surface = tmp.path().join("s.npy");
    let (ok, _, err) = asperity(
        &[
            "surface",
            "generate",
            "--nx",
            "32",
            "--ny",
            "32",
            "--lx-m",
            "64e-6",
            "--ly-m",
            "64e-6",
            "-o",
            surface.to_str().unwrap(),
        ],
        1,
    );
    assert!(ok, "{err}");
    for (extra, needle) in [
        (
            vec!["--surface", surface.to_str().unwrap(), "--shard", "1/2"],
            "--shard",
        ),
        (vec!["--shard", "3/2"], "--shard"),
    ] {
        let mut args = vec!["calibrate", config.to_str().unwrap(), "--out-dir"];
        args.push(out.to_str().unwrap());
        args.extend(extra);
        assert_fails_without_output(asperity(&args, 1), &[needle], &out);
    }
}

/// Results edited in a shard file (the configuration hash does not cover them) are refused
/// naming the file and the field; an --out-dir that is a file is refused before any shard is
/// read; and when one output cannot be written, none is left behind.
#[test]
fn edited_shard_results_and_blocked_outputs_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let paths = shards(&tmp.path().join("shards"), 2);
    let out = tmp.path().join("merged");
    let edit = |name: &str, change: &dyn Fn(&mut serde_json::Value)| -> Vec<PathBuf> {
        let mut json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&paths[1]).unwrap()).unwrap();
        change(&mut json);
        let path = tmp.path().join(name);
        std::fs::write(&path, json.to_string()).unwrap();
        vec![paths[0].clone(), path]
    };
    let point = |j: &mut serde_json::Value, field: &str, v: serde_json::Value| {
        j["units"][0]["result"]["points"][0][field] = v;
    };
    let cases: Vec<(Vec<PathBuf>, Vec<&str>)> = vec![
        (
            edit("negkn.json", &|j| point(j, "kn_n_per_m3", (-1e13).into())),
            vec!["negkn.json", "kn_n_per_m3", "-1e13"],
        ),
        (
            edit("area2.json", &|j| {
                point(j, "contact_area_ratio", 2.0.into())
            }),
            vec!["area2.json", "contact_area_ratio", "(0, 1]"],
        ),
        (
            edit("pressure.json", &|j| point(j, "pressure_pa", 3e6.into())),
            vec!["pressure.json", "3e6", "1e6, 8e6"],
        ),
        (
            edit("grid.json", &|j| {
                j["units"][0]["result"]["grid"]["nx"] = 64.into();
            }),
            vec!["grid.json", "64 x 128", "128 x 128"],
        ),
        (
            edit("total.json", &|j| j["units_total"] = 6.into()),
            vec!["total.json", "units_total = 6", "5 units"],
        ),
    ];
    for (files, needles) in cases {
        assert_fails_without_output(merge(&files, &out), &needles, &out);
    }

    // --out-dir is a file: refused first (the missing shard is not even read).
    let file = tmp.path().join("afile");
    std::fs::write(&file, "x").unwrap();
    let (ok, _, err) = merge(&[tmp.path().join("absent.json")], &file);
    assert!(
        !ok && err.contains("--out-dir") && !err.contains("absent.json"),
        "{err}"
    );

    // One output blocked by a directory: the merge fails and writes no other file.
    let blocked = tmp.path().join("blocked");
    std::fs::create_dir_all(blocked.join("kn.png")).unwrap();
    let (ok, _, err) = merge(&paths, &blocked);
    assert!(!ok, "should fail");
    assert!(err.contains("kn.png"), "{err}");
    let left: Vec<_> = std::fs::read_dir(&blocked)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(left, vec!["kn.png"], "files left behind");
}

/// A shard file records the build of the binary that wrote it: in a git checkout, the commit
/// checked out now (build.rs reruns when HEAD or its branch moves) and whether the build
/// inputs have uncommitted changes; always the hash of the sources and the compiler.
#[test]
fn shard_files_record_the_build() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("shards");
    let (ok, _, err) = asperity(
        &[
            "contact",
            "normal",
            "--seeds",
            "1,2",
            "--grid",
            "128",
            "--pressures-pa=1e6",
            "--shard",
            "2/2",
            "--out-dir",
            dir.to_str().unwrap(),
        ],
        1,
    );
    assert!(ok, "{err}");
    let json: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join("contact-normal.shard-2-of-2.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(json["format"], "asperity-shard-v2");
    let build = &json["build"];
    assert_eq!(build["crate_version"], env!("CARGO_PKG_VERSION"));
    assert_eq!(
        build["source_sha256"].as_str().unwrap().len(),
        64,
        "{build}"
    );
    assert!(
        build["rustc"].as_str().unwrap().starts_with("rustc "),
        "{build}"
    );
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let git = |args: &[&str]| -> Option<String> {
        let out = Command::new("git")
            .arg("-C")
            .arg(root)
            .args(args)
            .output()
            .ok()?;
        out.status
            .success()
            .then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
    };
    let top = git(&["rev-parse", "--show-toplevel"]);
    let in_checkout =
        top.is_some_and(|t| Path::new(&t).canonicalize().ok() == root.canonicalize().ok());
    if !in_checkout {
        // A tarball: no commit, the source hash identifies the build.
        assert!(
            build["git_commit"].is_null() && build["git_dirty"].is_null(),
            "{build}"
        );
        return;
    }
    // The checkout must still be the one built: a build input, HEAD or its branch changed
    // after the binary was linked (an edit or a commit while the tests run) is no failure of
    // build.rs. Cargo rebuilt the binary before the tests if any of them was newer.
    let binary = std::fs::metadata(env!("CARGO_BIN_EXE_asperity"))
        .and_then(|m| m.modified())
        .unwrap();
    let mut watched: Vec<PathBuf> = ["build.rs", "Cargo.toml", "Cargo.lock"]
        .iter()
        .map(|f| root.join(f))
        .collect();
    let branch = git(&["symbolic-ref", "-q", "HEAD"]);
    for p in ["HEAD", "packed-refs"].into_iter().chain(branch.as_deref()) {
        if let Some(path) = git(&["rev-parse", "--git-path", p]) {
            watched.push(root.join(path));
        }
    }
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        for e in std::fs::read_dir(dir).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                walk(&p, out);
            }
            out.push(p);
        }
    }
    walk(&root.join("src"), &mut watched);
    let newer: Vec<&PathBuf> = watched
        .iter()
        .filter(|p| {
            std::fs::metadata(p)
                .and_then(|m| m.modified())
                .is_ok_and(|t| t > binary)
        })
        .collect();
    if !newer.is_empty() {
        eprintln!("skipped: changed since the build: {newer:?}");
        return;
    }
    assert_eq!(
        build["git_commit"].as_str(),
        git(&["rev-parse", "HEAD"]).as_deref(),
        "the binary's commit is not the checkout's: build.rs did not rerun"
    );
    let status = git(&[
        "status",
        "--porcelain",
        "--untracked-files=all",
        "--",
        "src",
        "build.rs",
        "Cargo.toml",
        "Cargo.lock",
    ])
    .unwrap();
    assert_eq!(
        build["git_dirty"].as_bool(),
        Some(!status.is_empty()),
        "{status}"
    );
}

/// Two shard files with the `result` blocks of their first units swapped (labels kept), written
/// as `<prefix>-1.json` and `<prefix>-2.json` in `dir`; also returns the two units' labels.
fn swap_first_results(a: &Path, b: &Path, dir: &Path, prefix: &str) -> ([PathBuf; 2], [String; 2]) {
    let read = |p: &Path| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
    };
    let (mut a, mut b) = (read(a), read(b));
    std::mem::swap(&mut a["units"][0]["result"], &mut b["units"][0]["result"]);
    let label = |v: &serde_json::Value| v["units"][0]["label"].as_str().unwrap().to_string();
    let paths = [
        dir.join(format!("{prefix}-1.json")),
        dir.join(format!("{prefix}-2.json")),
    ];
    std::fs::write(&paths[0], a.to_string()).unwrap();
    std::fs::write(&paths[1], b.to_string()).unwrap();
    (paths, [label(&a), label(&b)])
}
