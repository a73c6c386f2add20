//! What `asperity predict` reports where a number does not exist or the data do not fit the
//! model's kind: `n/a` (never `NaN`) for a phase resonance the file does not pass, in text and
//! JSON; a file that is not one lightly damped mode flagged beside its errors; single-model
//! columns without `bef→aft`; the test control taken from the files' headers, a contradicting
//! `--control` refused.

use asperity::identify::measured::{PhaseConvention, Quantity};
use asperity::identify::model::{Drive, Family, Model, ModelSpec, Scales};
use asperity::identify::SavedModel;
use std::f64::consts::TAU;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args(args)
        .output()
        .expect("run asperity")
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
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

/// The model saved as `asperity identify` saves it (no ensemble), in the crate's convention.
fn save_model(dir: &Path) -> PathBuf {
    let saved = SavedModel {
        format: asperity::identify::pipeline::MODEL_FORMAT.into(),
        version: 1,
        model: truth(),
        phase_convention: PhaseConvention::MODEL,
        parameters: Vec::new(),
        identified_from: Vec::new(),
        ensemble: None,
    };
    let p = dir.join("model.json");
    std::fs::write(&p, serde_json::to_string_pretty(&saved).unwrap()).unwrap();
    p
}

const HEADER: &str = "frequency_Hz,force_amplitude_N,acceleration_amplitude_m_per_s2,phase_rad\n";

/// A sweep of the model at `force` N, 21 rows 78.9–80.9 Hz, after the comment lines `comments`.
fn model_sweep(dir: &Path, name: &str, force: f64, comments: &str) -> PathBuf {
    let m = truth();
    let drives: Vec<Drive> = (0..21)
        .map(|i| Drive {
            omega: TAU * (78.9 + 0.1 * i as f64),
            force_n: force,
        })
        .collect();
    let x = m.receptance(&drives, force).unwrap();
    let mut text = format!("{comments}{HEADER}");
    for (d, xi) in drives.iter().zip(&x) {
        let y = xi * Quantity::Acceleration.from_displacement(d.omega);
        text += &format!(
            "{:.4},{force},{:.12e},{:.12e}\n",
            d.omega / TAU,
            y.norm() * force,
            y.arg()
        );
    }
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// The case: a file whose amplitude is constant across the band (and whose phase stays
/// far from quadrature): no phase resonance, and not one lightly damped mode.
#[test]
fn a_constant_amplitude_file_gets_n_a_and_is_flagged_beside_its_error() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let model = save_model(d);
    let mut text = String::from(HEADER);
    for i in 0..21 {
        let f = 78.9 + 0.1 * i as f64;
        let phase = -0.1 - 0.001 * i as f64;
        text += &format!("{f:.4},0.2,3.0,{phase}\n");
    }
    let flat = d.join("flat.csv");
    std::fs::write(&flat, text).unwrap();
    let out = d.join("out");
    let o = run(&[
        "predict",
        "--model",
        s(&model),
        s(&flat),
        "--out-dir",
        s(&out),
    ]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let report = std::fs::read_to_string(out.join("predict.txt")).unwrap();
    for t in [&*stdout, &*report] {
        assert!(!t.contains("NaN"), "{t}");
        assert!(t.contains("f_90 n/a:"), "{t}");
        assert!(!t.contains("bef→aft"), "one model, single values: {t}");
        // The flag stands on the row of the file's errors.
        let row = t
            .lines()
            .find(|l| l.starts_with("flat.csv") || l.contains("flat.csv [NOT ONE MODE]"))
            .unwrap_or_else(|| panic!("no row of flat.csv: {t}"));
        assert!(
            row.contains("[NOT ONE MODE]") && row.contains("n/a"),
            "{row}"
        );
        assert!(t.contains("not a single lightly damped mode"), "{t}");
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("predict.json")).unwrap()).unwrap();
    let f = &json["prediction"]["files"][0];
    for key in ["phase_resonance_measured_hz", "phase_resonance_error_hz"] {
        assert!(
            f["errors"][key]["not_available"].is_string(),
            "{key}: {}",
            f["errors"][key]
        );
    }
    assert!(f["not_one_mode"].is_string(), "{f}");
}

/// The test control comes from the header where it says so; a contradicting flag, or files
/// stating different controls, are refused naming file and line; nothing written.
#[test]
fn the_control_mode_comes_from_the_file_header() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let model = save_model(d);
    let rc = model_sweep(
        d,
        "rc.csv",
        0.2,
        "# Brake-Reuss beam, stepped sine\n# Response control; level 1\n",
    );
    let out = d.join("out");
    let o = run(&[
        "predict",
        "--model",
        s(&model),
        s(&rc),
        "--out-dir",
        s(&out),
    ]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        stdout.contains("response: the measured response of each row held")
            && stdout.contains("rc.csv:2"),
        "{stdout}"
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("predict.json")).unwrap()).unwrap();
    assert_eq!(json["prediction"]["control"], "response");
    // The flag contradicting the header: refused, nothing written.
    let out2 = d.join("out2");
    let o = run(&[
        "predict",
        "--model",
        s(&model),
        "--control",
        "force",
        s(&rc),
        "--out-dir",
        s(&out2),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("--control") && err.contains("rc.csv:2") && err.contains("response control"),
        "{err}"
    );
    assert!(!out2.exists());
    // Files that state different controls.
    let fc = model_sweep(d, "fc.csv", 0.3, "# Force control; level 2\n");
    let o = run(&[
        "predict",
        "--model",
        s(&model),
        s(&rc),
        s(&fc),
        "--out-dir",
        s(&out2),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("rc.csv:2") && err.contains("fc.csv:1"),
        "{err}"
    );
    assert!(!out2.exists());
    // A file that states nothing: force control by default, and the report says why.
    let plain = model_sweep(d, "plain.csv", 0.2, "# synthetic\n");
    let o = run(&[
        "predict",
        "--model",
        s(&model),
        s(&plain),
        "--out-dir",
        s(&out2),
    ]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        stdout.contains("force: the measured force of each row applied")
            && stdout.contains("no file's header states its control"),
        "{stdout}"
    );
}

/// A file whose response channel is inverted (phases moved by π): with a majority of files in
/// one convention the odd file is named; with two files, one of each, neither is blamed — the
/// files alone cannot tell which is inverted (before, the lower level's convention won the tie
/// and the good file was named as the odd one).
#[test]
fn an_inverted_file_is_blamed_only_where_the_others_outvote_it() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let invert = |src: &Path, name: &str| {
        let text = std::fs::read_to_string(src).unwrap();
        let flipped: Vec<String> = text
            .lines()
            .map(|l| {
                let f: Vec<&str> = l.split(',').collect();
                match f.get(3).map(|v| v.parse::<f64>()) {
                    Some(Ok(p)) => {
                        let q = if p > 0.0 {
                            p - std::f64::consts::PI
                        } else {
                            p + std::f64::consts::PI
                        };
                        format!("{},{},{},{q}", f[0], f[1], f[2])
                    }
                    _ => l.to_string(),
                }
            })
            .collect();
        let p = d.join(name);
        std::fs::write(&p, flipped.join("\n") + "\n").unwrap();
        p
    };
    let low = model_sweep(d, "low.csv", 0.02, "# synthetic\n");
    let mid = model_sweep(d, "mid.csv", 0.15, "# synthetic\n");
    let high = model_sweep(d, "high.csv", 0.6, "# synthetic\n");
    let low_inverted = invert(&low, "low-inverted.csv");
    let out = d.join("out");
    let identify = |files: &[&Path]| {
        let mut args = vec!["identify"];
        args.extend(files.iter().map(|p| s(p)));
        args.extend(["--max-effects", "0", "--starts", "1", "--particles", "4"]);
        args.extend(["--out-dir", s(&out)]);
        run(&args)
    };
    // Two files, one of each convention: no file is named the odd one.
    let o = identify(&[&low_inverted, &mid]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("none is shared by most")
            && err.contains("low-inverted.csv")
            && err.contains("mid.csv")
            && !err.contains("is not in the phase convention"),
        "{err}"
    );
    // Three files, the inverted one outvoted: it, and only it, is named.
    let o = identify(&[&low_inverted, &mid, &high]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("low-inverted.csv is not in the phase convention"),
        "{err}"
    );
    assert!(!out.exists());
}
