//! End-to-end tests of `asperity identify` and `asperity predict` through the binary: bad input
//! (file and line named, non-zero exit, nothing written), a small identification, and
//! predictions of force- and response-controlled files with the saved model.

use asperity::identify::measured::Quantity;
use asperity::identify::model::{Drive, Family, Model, ModelSpec, Scales};
use asperity::identify::SavedModel;
use std::f64::consts::{PI, TAU};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn run(cmd: &str, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_asperity"))
        .arg(cmd)
        .args(args)
        .output()
        .expect("run asperity")
}

fn truth() -> Model {
    let scales = Scales {
        frequency_hz: 80.0,
        modal_mass_kg: 2.0,
        amplitude_max_m: 2e-4,
        amplitude_min_m: 2e-5,
        force_n: 0.6,
    };
    Model::new(
        ModelSpec::baseline(Family::Jenkins, scales),
        vec![80.0, 1e-3, 2.0, 0.02, 3e-5],
    )
    .unwrap()
}

/// A force-controlled sweep of `model` at force `force` (N), 21 rows 78.9–80.9 Hz, written
/// with the acquisition convention of the shared Brake–Reuss files (response channel
/// inverted).
fn write_sweep(dir: &Path, name: &str, model: &Model, force: f64) -> PathBuf {
    let drives: Vec<Drive> = (0..21)
        .map(|i| Drive {
            omega: TAU * (78.9 + 0.1 * i as f64),
            force_n: force,
        })
        .collect();
    let x = model.receptance(&drives, force).unwrap();
    let mut text = String::from(
        "# synthetic\nfrequency_Hz,force_amplitude_N,acceleration_amplitude_m_per_s2,phase_rad\n",
    );
    for (d, xi) in drives.iter().zip(&x) {
        let y = -xi * Quantity::Acceleration.from_displacement(d.omega);
        text += &format!(
            "{:.4},{},{:.12e},{:.12e}\n",
            d.omega / TAU,
            force,
            y.norm() * force,
            y.arg()
        );
    }
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// A copy of the sweep `src` at `dst` with every frequency multiplied by `factor` (a unit
/// mistake).
fn frequencies_scaled(src: &Path, dst: &Path, factor: f64) -> PathBuf {
    let mut lines: Vec<String> = std::fs::read_to_string(src)
        .unwrap()
        .lines()
        .map(str::to_string)
        .collect();
    for l in lines.iter_mut().skip(2) {
        let (f, rest) = l.split_once(',').unwrap();
        *l = format!("{},{rest}", f.parse::<f64>().unwrap() * factor);
    }
    std::fs::write(dst, lines.join("\n") + "\n").unwrap();
    dst.to_path_buf()
}

/// A fit small enough for a test of the command's plumbing: no effect search, one start of a
/// four-particle swarm.
const QUICK_FIT: &[&str] = &["--max-effects", "0", "--starts", "1", "--particles", "4"];

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn bad_input_names_file_and_line_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let m = truth();
    let good1 = write_sweep(dir.path(), "good1.csv", &m, 0.02);
    let good2 = write_sweep(dir.path(), "good2.csv", &m, 0.6);
    let text = std::fs::read_to_string(&good2).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    // (edit of data line k (0-based after the 2 header lines), expected fragment).
    type Edit = fn(&str) -> String;
    let cases: Vec<(usize, Edit, &str)> = vec![
        (5, |l| l.replacen("79.4", "79.2", 1), "not monotonic"),
        (5, |l| l.replacen("79.4", "79.3", 1), "duplicate frequency"),
        (
            5,
            |l| {
                let f: Vec<&str> = l.split(',').collect();
                format!("{},,{},{}", f[0], f[2], f[3])
            },
            "missing value of `force_amplitude_N`",
        ),
        (
            5,
            |l| {
                let f: Vec<&str> = l.split(',').collect();
                format!("{},0,{},{}", f[0], f[2], f[3])
            },
            "must be > 0",
        ),
        (
            5,
            |l| {
                let f: Vec<&str> = l.split(',').collect();
                let deg = f[3].parse::<f64>().unwrap() * 180.0 / PI;
                format!("{},{},{},{}", f[0], f[1], f[2], deg)
            },
            "look like degrees",
        ),
    ];
    for (k, edit, fragment) in cases {
        let mut l = lines.clone();
        let edited = edit(l[2 + k]);
        l[2 + k] = &edited;
        let bad = dir.path().join("bad.csv");
        std::fs::write(&bad, l.join("\n") + "\n").unwrap();
        let out = dir.path().join("out");
        let o = run("identify", &[s(&good1), s(&bad), "--out-dir", s(&out)]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{fragment}");
        assert!(
            err.contains(&format!("bad.csv:{}", 3 + k)) && err.contains(fragment),
            "{err}"
        );
        assert!(!out.exists(), "output written on error");
    }
    let out = dir.path().join("out");
    let o = run("identify", &[s(&good1), "--out-dir", s(&out)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("good1.csv") && err.contains("single level"),
        "{err}"
    );
    let o = run(
        "identify",
        &[
            s(&good1),
            s(&good2),
            "--fit-levels",
            "2",
            "--out-dir",
            s(&out),
        ],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("--fit-levels") && err.contains("good2.csv"),
        "{err}"
    );
    // No convergence of the fit: a Nelder–Mead cap of 3 iterations.
    let o = run(
        "identify",
        &[
            &[s(&good1), s(&good2)][..],
            QUICK_FIT,
            &[
                "--swarm-iterations",
                "1",
                "--local-iterations",
                "3",
                "--out-dir",
                s(&out),
            ],
        ]
        .concat(),
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("did not converge"),
        "{err}"
    );
    assert!(!out.exists(), "output written on error");
    let o = run(
        "predict",
        &["--model", s(&good1), s(&good2), "--out-dir", s(&out)],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("good1.csv") && err.contains("identified model"),
        "{err}"
    );
    assert!(!out.exists());
    // Too short a chain for the bands is refused before any work.
    let o = run(
        "identify",
        &[
            s(&good1),
            s(&good2),
            "--chain-steps",
            "50",
            "--out-dir",
            s(&out),
        ],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("--chain-steps"),
        "{err}"
    );
    assert!(!out.exists());
    // Resource limits and impossible amplitudes are refused before any work.
    for (flag, value) in [
        ("--chain-steps", "1000000000000"),
        ("--particles", "1000000000"),
        ("--swarm-iterations", "1000000000000000"),
        ("--response-amplitude", "-5"),
    ] {
        let o = run(
            "identify",
            &[
                s(&good1),
                s(&good2),
                &format!("{flag}={value}"),
                "--out-dir",
                s(&out),
            ],
        );
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains(flag), "{flag}: {err}");
        assert!(!out.exists());
    }
    // The same measurement twice is not two levels.
    let copy = dir.path().join("copy.csv");
    std::fs::copy(&good1, &copy).unwrap();
    let o = run("identify", &[s(&good1), s(&copy), "--out-dir", s(&out)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("copy.csv") && err.contains("given twice"),
        "{err}"
    );
    // Frequencies scaled by 1000 (a unit mistake): at 1/1000 the rows imply a vibration of
    // tens of metres (refused row by row); at ×1000 the file lies 1000× above the other
    // level, which is not the same mode (refused by the band check).
    let scaled =
        |factor: f64, name: &str| frequencies_scaled(&good2, &dir.path().join(name), factor);
    for (file, needle) in [
        (scaled(1e-3, "khz.csv"), "check the units"),
        (scaled(1e3, "mhz.csv"), "more than a factor 2 apart"),
    ] {
        let o = run("identify", &[s(&good1), s(&file), "--out-dir", s(&out)]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success()
                && err.contains(file.file_name().unwrap().to_str().unwrap())
                && err.contains(needle),
            "{err}"
        );
        assert!(!out.exists());
    }
    // With three files the odd one out is named.
    let mhz = dir.path().join("mhz.csv");
    let good3 = write_sweep(dir.path(), "good3.csv", &m, 0.3);
    let o = run(
        "identify",
        &[s(&good1), s(&mhz), s(&good3), "--out-dir", s(&out)],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success()
            && err.contains("mhz.csv (")
            && !err.contains("good1.csv")
            && err.contains("far from the other files'"),
        "{err}"
    );
    // An output that cannot be written (a directory in the way of model.json) fails after the
    // fit with nothing else written: the outputs appear together or not at all.
    std::fs::create_dir_all(out.join("model.json")).unwrap();
    let o = run(
        "identify",
        &[
            &[s(&good1), s(&good2)][..],
            QUICK_FIT,
            &[
                "--swarm-iterations",
                "2",
                "--chain-steps",
                "0",
                "--out-dir",
                s(&out),
            ],
        ]
        .concat(),
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("model.json"), "{err}");
    let left: Vec<_> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(
        left,
        vec![std::ffi::OsString::from("model.json")],
        "{left:?}"
    );
    let parent_left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .filter(|n| n.starts_with(".asperity"))
        .collect();
    assert!(parent_left.is_empty(), "{parent_left:?}");
    // An --out-dir that is a file is refused before any work, naming the flag.
    let file = dir.path().join("afile");
    std::fs::write(&file, "x").unwrap();
    let o = run("identify", &[s(&good1), s(&good2), "--out-dir", s(&file)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("--out-dir") && err.contains("not a directory"),
        "{err}"
    );
}

#[test]
fn identify_then_predict_both_controls() {
    let dir = tempfile::tempdir().unwrap();
    let m = truth();
    let files: Vec<PathBuf> = [0.02, 0.15, 0.6]
        .iter()
        .enumerate()
        .map(|(i, &f)| write_sweep(dir.path(), &format!("level{}.csv", i + 1), &m, f))
        .collect();
    let out = dir.path().join("id");
    let o = run(
        "identify",
        &[
            s(&files[0]),
            s(&files[1]),
            s(&files[2]),
            "--candidates",
            "shaker_interaction",
            "--max-effects",
            "1",
            "--starts",
            "1",
            "--particles",
            "10",
            "--swarm-iterations",
            "10",
            "--response-amplitude",
            "5",
            "--out-dir",
            s(&out),
        ],
    );
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    for f in [
        "identify.txt",
        "identify.json",
        "model.json",
        "identify-rows.csv",
        "identify-backbone.csv",
        "identify-backbone.png",
        "identify-response-controlled.csv",
        "identify-level1.png",
        "identify-level2.png",
        "identify-level3.png",
    ] {
        assert!(out.join(f).exists(), "{f} missing");
    }
    assert!(stdout.contains("response channel inverted"), "{stdout}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("identify.json")).unwrap()).unwrap();
    let json_id = json.clone();
    assert_eq!(
        json["uncertainty"]["status"], "estimated",
        "{}",
        json["uncertainty"]
    );
    assert_eq!(json["inputs"][0]["sha256"].as_str().unwrap().len(), 64);
    // Exact data: the offered delay is not accepted for fitting the solver's rounding (both
    // misfits lie below the numerical floor, `NUMERICAL_RESIDUAL_FLOOR`), and the posterior
    // chains move (before the floor, ln J jumped at the noise level: acceptance 0 % after a
    // rounding-level change to the AFT's sums).
    assert_eq!(
        json["selection"]["verdict"], "NoEffectNeeded",
        "{}",
        json["selection"]
    );
    let acceptance = json["uncertainty"]["acceptance_rate"].as_f64().unwrap();
    assert!(acceptance > 0.1, "acceptance {acceptance}");
    // Exact data: the level not used is predicted within 1 % in peak.
    let e = &json["errors_after"][1];
    assert_eq!(e["role"], "predicted");
    assert!(e["peak_error"].as_f64().unwrap().abs() < 0.01, "{e}");
    // The model-free check is reported: six laws, each level's spread, and a verdict per
    // level not used.
    let mf = &json["model_free"];
    assert_eq!(mf["laws"].as_array().map(Vec::len), Some(6), "{mf}");
    assert_eq!(mf["levels"][1]["role"], "predicted", "{mf}");
    let text = std::fs::read_to_string(out.join("identify.txt")).unwrap();
    assert!(
        text.contains("model-free check") && text.contains("level 2: "),
        "{text}"
    );
    // Exact data of one mode: every level that can be compared is stationary, so there is no
    // settled-rows check and every row is fitted.
    let st = &json["stationarity"]["levels"];
    assert!(
        st.as_array().unwrap().iter().any(|c| !c.is_null())
            && st
                .as_array()
                .unwrap()
                .iter()
                .all(|c| c.is_null() || c["stationary"] == true),
        "{st}"
    );
    // The criterion's constants travel with the verdicts.
    let crit = &json["stationarity"]["criterion"];
    assert_eq!(crit["damping_tolerance"], 0.1, "{crit}");
    assert_eq!(crit["noise_sigmas"], 4.0, "{crit}");
    assert_eq!(crit["min_differing_points"], 2, "{crit}");
    assert_eq!(crit["band_fraction_of_peak"], 0.5, "{crit}");
    assert!(json["model_free_settled_rows"].is_null());
    assert!(json["fit_rows"]
        .as_array()
        .unwrap()
        .iter()
        .all(|r| r["settled_only"] == false));
    assert!(text.contains("\nstationarity: "), "{text}");
    // The laws' backbones sit beside the data's and the models' in the backbone CSV.
    let backbone = std::fs::read_to_string(out.join("identify-backbone.csv")).unwrap();
    assert_eq!(
        backbone
            .lines()
            .filter(|l| l.starts_with("model-free-wn-quadratic-zeta-power-law,"))
            .count(),
        40
    );

    // A response-controlled test of the saved model: rows whose response amplitudes come from
    // the model's own force-controlled response at known forces; holding them must need those
    // forces back (two different solver paths: fixed force, and force as an unknown).
    let saved = SavedModel::read(&out.join("model.json")).unwrap();
    let forces: Vec<f64> = (0..21)
        .map(|i| 0.1 + 0.02 * (i as f64 - 10.0).abs())
        .collect();
    let mut text =
        String::from("frequency_Hz,force_amplitude_N,acceleration_amplitude_m_per_s2,phase_rad\n");
    for (i, &f) in forces.iter().enumerate() {
        let d = Drive {
            omega: TAU * (78.9 + 0.1 * i as f64),
            force_n: f,
        };
        let x = saved.model.receptance(&[d], 0.3).unwrap()[0];
        let y = -x * Quantity::Acceleration.from_displacement(d.omega);
        text += &format!(
            "{},{f},{:.12e},{:.12e}\n",
            d.omega / TAU,
            y.norm() * f,
            y.arg()
        );
    }
    let rc = dir.path().join("response-controlled.csv");
    std::fs::write(&rc, text).unwrap();
    // A file whose frequencies are scaled by 1000 lies 1000× above the model's mode: refused,
    // nothing written.
    let khz = frequencies_scaled(&files[1], &dir.path().join("khz.csv"), 1000.0);
    let kout = dir.path().join("pred-khz");
    let o = run(
        "predict",
        &[
            "--model",
            s(&out.join("model.json")),
            s(&khz),
            "--out-dir",
            s(&kout),
        ],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("khz.csv") && err.contains("natural frequency"),
        "{err}"
    );
    assert!(!kout.exists());
    let pout = dir.path().join("pred");
    let o = run(
        "predict",
        &[
            "--model",
            s(&out.join("model.json")),
            "--control",
            "response",
            s(&rc),
            "--out-dir",
            s(&pout),
        ],
    );
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(pout.join("predict.json")).unwrap()).unwrap();
    let p = &json["prediction"]["files"][0];
    let model_forces: Vec<f64> = p["model_force_n"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    for (a, b) in model_forces.iter().zip(&forces) {
        assert!((a / b - 1.0).abs() < 1e-6, "{a} vs {b}");
    }
    assert!(p["errors"]["rms_complex"].as_f64().unwrap() < 1e-6, "{p}");
    // Response control holds the amplitude: no two sides to compare, and the report says why.
    assert!(
        json["prediction"]["stationarity"]["not_available"].is_string(),
        "{}",
        json["prediction"]["stationarity"]
    );
    // Force control on a level: the same model errors as in the identification report. The
    // directory holds a two-file run's second plot and a file of the user's: the stale plot
    // goes, the user's file stays.
    std::fs::write(pout.join("predict-2.png"), "an earlier run's plot").unwrap();
    std::fs::write(pout.join("notes.txt"), "mine").unwrap();
    let o = run(
        "predict",
        &[
            "--model",
            s(&out.join("model.json")),
            s(&files[1]),
            "--out-dir",
            s(&pout),
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(pout.join("predict-1.png").exists() && pout.join("predict-rows.csv").exists());
    assert!(!pout.join("predict-2.png").exists() && pout.join("notes.txt").exists());
    // The ensemble saved with the model gives the same 95 % band as the identification's report
    // for the level not used (same models).
    let id_band = &json_id["uncertainty"]["bands"][1]["peak"];
    let pred: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(pout.join("predict.json")).unwrap()).unwrap();
    let band = &pred["prediction"]["bands"][0]["peak"];
    // Force control: the file's two sides are compared (exact data: stationary).
    assert_eq!(
        pred["prediction"]["stationarity"][0]["stationary"], true,
        "{}",
        pred["prediction"]["stationarity"]
    );
    assert_eq!(
        pred["stationarity_criterion"],
        json_id["stationarity"]["criterion"]
    );
    for k in ["value", "lo_95", "hi_95"] {
        let (a, b) = (band[k].as_f64().unwrap(), id_band[k].as_f64().unwrap());
        assert!(
            (a / b - 1.0).abs() < 1e-9,
            "{k}: predict {a} vs identify {b}"
        );
    }
    // An ensemble with a model outside the bounds is refused, naming the model file.
    let mut saved_json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("model.json")).unwrap()).unwrap();
    saved_json["ensemble"]["draws"][0][0] = serde_json::json!(1e6);
    let bad = dir.path().join("bad-model.json");
    std::fs::write(&bad, serde_json::to_string(&saved_json).unwrap()).unwrap();
    let bad_out = dir.path().join("bad-pred");
    let o = run(
        "predict",
        &["--model", s(&bad), s(&files[1]), "--out-dir", s(&bad_out)],
    );
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && stderr.contains("bad-model.json"),
        "{stderr}"
    );
    assert!(stderr.contains("ensemble draw 0"), "{stderr}");
    assert!(!bad_out.exists(), "nothing written");
}

/// A copy of the sweep `src` at `dst` with every phase moved by π (an inverted channel).
fn phase_flipped(src: &Path, dst: &Path) -> PathBuf {
    let mut lines: Vec<String> = std::fs::read_to_string(src)
        .unwrap()
        .lines()
        .map(str::to_string)
        .collect();
    for l in lines.iter_mut().skip(2) {
        let (rest, ph) = l.rsplit_once(',').unwrap();
        let ph = ph.parse::<f64>().unwrap() + PI;
        *l = format!("{rest},{}", if ph > PI { ph - TAU } else { ph });
    }
    std::fs::write(dst, lines.join("\n") + "\n").unwrap();
    dst.to_path_buf()
}

/// A file in another phase convention among files in one is refused by `identify` and
/// `predict`, naming it (before: `predict` read it with the others' convention, exit 0, and
/// `identify` failed later on "not a single lightly damped mode"); nothing is written.
#[test]
fn a_file_in_another_phase_convention_is_refused_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let m = truth();
    let good1 = write_sweep(dir.path(), "good1.csv", &m, 0.02);
    let good2 = write_sweep(dir.path(), "good2.csv", &m, 0.3);
    let good3 = write_sweep(dir.path(), "good3.csv", &m, 0.6);
    let flipped = phase_flipped(&good3, &dir.path().join("flipped.csv"));
    let out = dir.path().join("out");
    let o = run(
        "identify",
        &[s(&good1), s(&good2), s(&flipped), "--out-dir", s(&out)],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success()
            && err.contains("flipped.csv is not in the phase convention of the other files")
            && err.contains("flipped.csv: e^{iωt}.")
            && err.contains("good1.csv: e^{iωt}, channel inverted"),
        "{err}"
    );
    assert!(!out.exists(), "output written on error");
    let model = Path::new(env!("CARGO_MANIFEST_DIR")).join("calib/identify/model.json");
    let o = run(
        "predict",
        &[
            "--model",
            s(&model),
            s(&good1),
            s(&good2),
            s(&flipped),
            "--out-dir",
            s(&out),
        ],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("flipped.csv is not in the phase convention"),
        "{err}"
    );
    assert!(!out.exists(), "output written on error");
}
