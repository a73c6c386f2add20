//! Sharded calibration end to end: `asperity calibrate --shard i/n` (the unit is one
//! realisation with its grid- and patch-check chains), then `asperity merge`, must write byte
//! for byte every file a single `asperity calibrate` run writes (tables, sidecar, plots; only
//! `calibration_timings.csv` differs), and a missing, duplicated or foreign shard must fail
//! with a message naming the files and write nothing.

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

fn shards(config: &Path, dir: &Path, n: usize) -> Vec<PathBuf> {
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

fn merge(paths: &[PathBuf], out: &Path) -> (bool, String, String) {
    let mut args = vec!["merge".to_string()];
    args.extend(paths.iter().map(|p| p.display().to_string()));
    args.extend(["--out-dir".into(), out.display().to_string()]);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    asperity(&args, 2)
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
        let mut paths = shards(&config, &dir, n);
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

fn assert_fails_without_output(result: (bool, String, String), needles: &[&str], out: &Path) {
    let (ok, _, err) = result;
    assert!(!ok, "should fail");
    for n in needles {
        assert!(err.contains(n), "`{n}` not in: {err}");
    }
    assert!(!out.exists(), "output written: {}", out.display());
}

#[test]
fn missing_duplicated_or_foreign_calibration_shards_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let config = small_config(tmp.path(), 3);
    let paths = shards(&config, &tmp.path().join("shards"), 3);
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
    let foreign = shards(&other, &tmp.path().join("other"), 3);
    assert_fails_without_output(
        merge(
            &[paths[0].clone(), paths[1].clone(), foreign[2].clone()],
            &out,
        ),
        &["different configurations", "other"],
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
