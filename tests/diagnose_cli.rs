//! End-to-end tests of `asperity diagnose` through the binary: the measured friction-damper loops
//! (done-when 2) and the error paths (done-when 3).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_asperity"))
        .arg("diagnose")
        .args(args)
        .output()
        .expect("run asperity")
}

/// Diagnose one measured record; check that the report names an effect, that the
/// normalised RMS force error drops, on all cycles and on the held-out ones, that a noise floor
/// is reported and every residual is compared with it, and that the verdict tells the truth:
/// these loops keep a residual well above the noise floor (impacts at the closing of the
/// clearance, ringing, cycle-to-cycle variation), so the verdict is "model inadequate", with
/// what characterises the residual, never "no effect needed".
fn measured(name: &str) {
    let Some(path) = asperity::core::testdata::reference_file(&format!("loops/{name}")) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let o = run(&[path.to_str().unwrap(), "--out-dir", out.to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    eprintln!("{stdout}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("diagnose.json")).unwrap()).unwrap();
    let added = json["effects_added"].as_array().unwrap();
    assert!(!added.is_empty(), "no effect found on {name}");
    let before = json["errors_before"]["nrms"].as_f64().unwrap();
    let after = json["errors_after"]["nrms"].as_f64().unwrap();
    let held_before = json["errors_before"]["held_out_nrms"].as_f64().unwrap();
    let held_after = json["errors_after"]["held_out_nrms"].as_f64().unwrap();
    assert!(after < 0.9 * before, "nrms {before} -> {after}");
    assert!(
        held_after < 0.9 * held_before,
        "held-out nrms {held_before} -> {held_after}"
    );
    let sigma = json["noise"]["sigma_n"].as_f64().unwrap();
    assert!(sigma > 0.0 && sigma < 0.1 * json["force_scale_n"].as_f64().unwrap());
    let ratio = json["errors_after"]["held_out_rms_over_noise"]
        .as_f64()
        .unwrap();
    assert_eq!(json["verdict"], "model_inadequate", "ratio {ratio}");
    assert!(ratio > 2.0, "{ratio}");
    let conclusion = json["conclusion"].as_str().unwrap();
    for needle in [
        "residual unexplained",
        "× the noise floor",
        "explained in part by",
    ] {
        assert!(
            conclusion.contains(needle),
            "`{needle}` not in {conclusion}"
        );
    }
    // The drift clause: a trend test over n steady cycles has n − 2 degrees of freedom and
    // no power below 3 (5 cycles); these loops hold 3 steady cycles, so drift cannot be judged
    // and "no drift" would claim what the test cannot show.
    let steady = json["stationarity"]["cycles"].as_array().unwrap().len();
    let drift_clause = if steady < 5 {
        "; drift not testable"
    } else if json["stationarity"]["findings"]
        .as_array()
        .unwrap()
        .is_empty()
    {
        "; no drift"
    } else {
        "; drifts: "
    };
    assert!(
        conclusion.contains(drift_clause),
        "`{drift_clause}` not in {conclusion} ({steady} steady cycles)"
    );
    if steady < 5 {
        assert!(!conclusion.contains("; no drift"), "{conclusion}");
    }
    // The free play is seen in the measured force itself, model-free, in most half-cycles,
    // and the clearance is among the effects that explain part of the residual.
    let c = &json["clearance"];
    assert!(
        2 * c["half_cycles_with_plateau"].as_u64().unwrap() >= c["half_cycles"].as_u64().unwrap(),
        "{c}"
    );
    assert!(json["effects_added"]
        .as_array()
        .unwrap()
        .iter()
        .any(|e| e == "backlash"));
    let text = std::fs::read_to_string(out.join("diagnose.txt")).unwrap();
    assert!(text.contains("verdict: model inadequate"), "{text}");
    // Direction-dependent friction moves both slip plateaus by d·F_slip, as a load-cell zero
    // offset would: wherever it is accepted the report names that alias, and only there.
    let asymmetric = added.iter().any(|e| e == "directional_friction");
    assert_eq!(
        text.contains("alias: a load-cell zero offset"),
        asymmetric,
        "{text}"
    );
    assert!(!text.contains("-0.0000e0"), "{text}");
    // No friction coefficient without a normal load.
    assert!(json["baseline"]["friction_coefficient"].is_null());
    assert!(text.contains("no friction coefficient"), "{text}");
    for png in ["diagnose-loops.png", "diagnose-residual.png"] {
        let img = image::open(out.join(png)).unwrap();
        assert!(img.width() > 100);
    }
    let csv = std::fs::read_to_string(out.join("diagnose.csv")).unwrap();
    assert!(csv.contains(
        "time_s,displacement_m,measured_force_N,baseline_force_N,final_force_N,\
         residual_before_N,residual_after_N,phase"
    ));
}

#[test]
fn measured_loops_half_inch() {
    measured("brfd-dataset2-0.5Hz30lbtension0.5amplitude.csv");
}

#[test]
fn measured_loops_one_inch() {
    measured("brfd-dataset2-0.5Hz30lbtension1amplitude.csv");
}

#[test]
fn measured_loops_one_and_a_half_inch() {
    measured("brfd-dataset2-0.5Hz30lbtension1.5amplitude.csv");
}

fn write_record(dir: &Path, name: &str, rows: &[String]) -> PathBuf {
    let p = dir.join(name);
    let mut s = String::from("time_s,displacement_m,friction_force_N\n");
    for r in rows {
        s += r;
        s += "\n";
    }
    std::fs::write(&p, s).unwrap();
    p
}

fn sine_rows(cycles: f64, per_cycle: usize, amplitude: f64) -> Vec<String> {
    let n = (cycles * per_cycle as f64) as usize;
    (0..n)
        .map(|i| {
            let t = i as f64 / per_cycle as f64;
            let x = amplitude * (std::f64::consts::TAU * t).sin();
            format!("{t},{x},{}", 100.0 * (x / 1e-4).tanh())
        })
        .collect()
}

/// The command fails with a message containing every `needle`, and writes no output.
fn fails_with(input: &Path, needles: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let o = run(&[input.to_str().unwrap(), "--out-dir", out.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "should fail: {err}");
    for n in needles {
        assert!(err.contains(n), "`{n}` not in: {err}");
    }
    assert!(!out.exists(), "no output may be written on error");
}

#[test]
fn record_without_a_complete_cycle_is_rejected() {
    let dir = tempfile::tempdir().unwrap();
    let p = write_record(dir.path(), "short.csv", &sine_rows(0.9, 200, 1e-3));
    fails_with(&p, &["short.csv", "no complete cycle"]);
}

#[test]
fn mismatched_column_lengths_are_rejected_with_the_line() {
    let dir = tempfile::tempdir().unwrap();
    let mut rows = sine_rows(3.0, 200, 1e-3);
    rows[100] = "0.5,1e-4".into();
    let p = write_record(dir.path(), "ragged.csv", &rows);
    // Header is line 1, so rows[100] is line 102.
    fails_with(&p, &["ragged.csv:102", "mismatched column lengths"]);
}

#[test]
fn constant_displacement_is_rejected() {
    let dir = tempfile::tempdir().unwrap();
    let rows: Vec<String> = (0..600)
        .map(|i| format!("{},{},{}", i as f64 * 1e-3, 2e-3, 5.0))
        .collect();
    let p = write_record(dir.path(), "constant.csv", &rows);
    fails_with(&p, &["constant.csv", "displacement is constant"]);
}

#[test]
fn missing_column_and_file_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let p = write_record(dir.path(), "ok.csv", &sine_rows(3.0, 200, 1e-3));
    let o = run(&[p.to_str().unwrap(), "--force-column", "force_kN"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("ok.csv:1") && err.contains("force_kN"),
        "{err}"
    );
    let o = run(&["/nonexistent/record.csv"]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("/nonexistent/record.csv"));
}

#[test]
fn one_complete_cycle_is_not_enough_to_score() {
    let dir = tempfile::tempdir().unwrap();
    let p = write_record(dir.path(), "one.csv", &sine_rows(1.6, 200, 1e-3));
    fails_with(&p, &["one.csv", "at least 2"]);
}

/// The `--table` path: the baseline element comes from a calibration table (per unit area) at
/// the given pressure and area, unchanged. The record is synthesised from that same element
/// behind a 50 µm clearance, so the report must keep the tabulated element (E0·A, μ, N = p·A)
/// and find the clearance.
#[test]
fn baseline_from_a_calibration_table() {
    use asperity::diagnose::effects::Drive;
    use asperity::diagnose::{Baseline, Effect, Model};
    use asperity::element::valanis::ValanisParams;
    let dir = tempfile::tempdir().unwrap();
    let table = dir.path().join("table.csv");
    std::fs::write(
        &table,
        "pressure_Pa,contact_area_ratio,kn_N_per_m3,E0_N_per_m3,k,mu,Et_N_per_m3,fit_R2,energy_per_cycle_J_per_m2\n\
         1.0e5,0.01,1.0e11,2.0e9,0.3,0.5,0.0,0.99,1.0\n\
         1.0e7,0.10,1.0e12,2.0e10,0.3,0.5,0.0,0.99,10.0\n",
    )
    .unwrap();
    // At 1e5 Pa over 1e-3 m²: E0 = 2e6 N/m, N = 100 N, slip force 50 N.
    let (amp, per_cycle, tau) = (1e-3, 160usize, std::f64::consts::TAU);
    let n = 4 * per_cycle + per_cycle / 2;
    let t: Vec<f64> = (0..n).map(|i| i as f64 / per_cycle as f64).collect();
    let x: Vec<f64> = t.iter().map(|&t| amp * (tau * t).sin()).collect();
    let drive = Drive {
        q_m: x.clone(),
        velocity_m_per_s: t.iter().map(|&t| amp * tau * (tau * t).cos()).collect(),
        normal_ratio: None,
        phase_rad: t.iter().map(|&t| tau * t).collect(),
        time_s: t.clone(),
        initial_force_n: 0.0,
        force_scale_n: 50.0,
        amplitude_m: amp,
        velocity_scale: amp * tau,
    };
    let model = Model {
        baseline: Baseline {
            valanis: ValanisParams::new(2e6, 0.3, 0.0, 0.5).unwrap(),
            normal_n: 100.0,
        },
        effects: vec![(Effect::Backlash, vec![5e-5])],
    };
    let f = model.simulate(&drive);
    let rows: Vec<String> = (0..n)
        .map(|i| format!("{},{},{}", t[i], x[i], f[i]))
        .collect();
    let rec = write_record(dir.path(), "rig.csv", &rows);
    let out = dir.path().join("out");
    let o = run(&[
        rec.to_str().unwrap(),
        "--table",
        table.to_str().unwrap(),
        "--pressure-pa",
        "1e5",
        "--area-m2",
        "1e-3",
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("diagnose.json")).unwrap()).unwrap();
    let b = &json["baseline"];
    assert!((b["e0_n_per_m"].as_f64().unwrap() / 2e6 - 1.0).abs() < 1e-12);
    assert!((b["normal_load_n"].as_f64().unwrap() / 100.0 - 1.0).abs() < 1e-12);
    assert!((b["friction_coefficient"].as_f64().unwrap() - 0.5).abs() < 1e-12);
    assert!((b["slip_force_n"].as_f64().unwrap() - 50.0).abs() < 1e-9);
    assert!(json["input"]["baseline_source"]
        .as_str()
        .unwrap()
        .contains("calibration table"));
    assert_eq!(json["effects_added"][0], "backlash");
    let gap = json["final_effect_parameters"][0][2].as_f64().unwrap();
    assert_eq!(json["final_effect_parameters"][0][1], "gap (m)");
    assert!((gap / 5e-5 - 1.0).abs() < 0.05, "gap {gap}");
    // A pressure outside the table is continued by the end rows' power law, with a warning.
    let o = run(&[
        rec.to_str().unwrap(),
        "--table",
        table.to_str().unwrap(),
        "--pressure-pa",
        "1e4",
        "--area-m2",
        "1e-3",
        "--max-effects",
        "0",
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("outside the table's range"));
    // A negative area is an error naming the flag.
    let o = run(&[
        rec.to_str().unwrap(),
        "--table",
        table.to_str().unwrap(),
        "--pressure-pa",
        "1e5",
        "--area-m2=-1",
    ]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("--area-m2"));
}

/// A Valanis element with `k = 0`, `Et = 0`, `E0 = 2e6 N/m` (exact exponential branches
/// `s·F → Fs(t) − (Fs(t) − s·F₀)·exp(−E0|Δx|/Fs(t))`) driven by x = 1 mm·sin(2πt), 200 samples
/// per cycle, with white force noise of σ = 0.5 N: rows `t, x, F`.
fn valanis_rows(cycles: f64, slip_force: impl Fn(f64) -> f64, seed: u64) -> Vec<String> {
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let noise = Normal::new(0.0, 0.5).unwrap();
    let n = (cycles * 200.0) as usize + 1;
    let (mut f, mut x_prev) = (0.0_f64, 0.0_f64);
    (0..n)
        .map(|i| {
            let t = i as f64 / 200.0;
            let x = 1e-3 * (std::f64::consts::TAU * t).sin();
            if i > 0 {
                let (dq, fs) = (x - x_prev, slip_force(t));
                let s = if dq > 0.0 { 1.0 } else { -1.0 };
                f = s * (fs - (fs - s * f) * (-2e6 * dq.abs() / fs).exp());
            }
            x_prev = x;
            format!("{t},{x},{}", f + noise.sample(&mut rng))
        })
        .collect()
}

fn diagnose_json(dir: &Path, input: &Path) -> (serde_json::Value, String) {
    let out = dir.join("out");
    let o = run(&[input.to_str().unwrap(), "--out-dir", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("diagnose.json")).unwrap()).unwrap();
    let text = std::fs::read_to_string(out.join("diagnose.txt")).unwrap();
    (json, text)
}

/// Two complete cycles whose slip force grows 10 % per cycle: the noise floor can only come
/// from first differences across two cycles, in which the drift does not cancel. The record
/// truly drifts, so "model adequate … no effect needed" would be false; the conclusion must
/// say that the record is too short to tell noise from drift, and how many cycles are needed
/// (3: the drift-free floor compares each half-cycle with the next two in its direction).
#[test]
fn two_cycles_with_drift_are_too_short_to_judge() {
    let dir = tempfile::tempdir().unwrap();
    let rows = valanis_rows(2.6, |t| 100.0 * (1.0 + 0.1 * t), 5);
    let p = write_record(dir.path(), "drift2.csv", &rows);
    let (json, text) = diagnose_json(dir.path(), &p);
    assert_eq!(json["noise"]["across_cycles"], 2, "{}", json["noise"]);
    assert_eq!(
        json["verdict"], "record_too_short",
        "{}",
        json["conclusion"]
    );
    let conclusion = json["conclusion"].as_str().unwrap();
    for needle in [
        "record too short to tell noise from drift",
        "3 complete cycles at the same stroke are needed",
    ] {
        assert!(
            conclusion.contains(needle),
            "`{needle}` not in {conclusion}"
        );
    }
    for wrong in ["model adequate", "no effect needed"] {
        assert!(!conclusion.contains(wrong), "`{wrong}` in {conclusion}");
        assert!(!text.contains(wrong), "`{wrong}` in {text}");
    }
}

/// A record generated by the baseline element itself plus white noise (6.5 cycles): the
/// baseline is at the noise floor, so the search is skipped. The report must not claim that
/// no effect is needed — an effect below about 2σ RMS was never looked for.
#[test]
fn an_adequate_baseline_does_not_claim_no_effect_is_needed() {
    let dir = tempfile::tempdir().unwrap();
    let rows = valanis_rows(6.5, |_| 100.0, 1);
    let p = write_record(dir.path(), "clean.csv", &rows);
    let (json, text) = diagnose_json(dir.path(), &p);
    assert_eq!(json["verdict"], "model_adequate", "{}", json["conclusion"]);
    let conclusion = json["conclusion"].as_str().unwrap();
    assert!(
        conclusion.contains("no effect larger than about 2σ RMS was looked for")
            && conclusion.contains("smaller effects were not tested"),
        "{conclusion}"
    );
    assert!(!conclusion.contains("no effect needed"), "{conclusion}");
    assert!(!text.contains("no effect needed"), "{text}");
}

/// Loops from accelerations: the record of `an_adequate_baseline_does_not_claim_no_effect_is_needed`
/// (a drive with a third harmonic here) written as the relative acceleration across the joint
/// (the exact second derivative of the drive) and the acceleration of a 2.5 kg mass whose
/// inertia is the force. Diagnosed from those columns it gives the baseline, errors and verdict
/// of the displacement and force columns, and the report says how the columns were derived.
/// Columns in g, a mass ≤ 0 and an inertia column without its mass are refused by flag.
#[test]
fn loops_from_accelerations_match_loops_from_displacement_and_force() {
    let dir = tempfile::tempdir().unwrap();
    let w = std::f64::consts::TAU;
    let drive = |t: f64| 1e-3 * (w * t).sin() + 1e-4 * (3.0 * w * t + 0.3).sin();
    let accel = |t: f64| -w * w * (1e-3 * (w * t).sin() + 9e-4 * (3.0 * w * t + 0.3).sin());
    let rows = valanis_rows(6.5, |_| 100.0, 1);
    // valanis_rows drives with 1 mm·sin(2πt); recompute the force on this drive, same noise.
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};
    let mut rng = rand::rngs::StdRng::seed_from_u64(1);
    let noise = Normal::new(0.0, 0.5).unwrap();
    let (mut f, mut x_prev) = (0.0_f64, 0.0_f64);
    let mass = 2.5;
    let mut text =
        String::from("time_s,displacement_m,friction_force_N,a_rel_m_per_s2,a_mass_m_per_s2\n");
    for i in 0..rows.len() {
        let t = i as f64 / 200.0;
        let x = drive(t);
        if i > 0 {
            let dq = x - x_prev;
            let s = if dq > 0.0 { 1.0 } else { -1.0 };
            f = s * (100.0 - (100.0 - s * f) * (-2e6 * dq.abs() / 100.0).exp());
        }
        x_prev = x;
        let force = f + noise.sample(&mut rng);
        text += &format!("{t},{x},{force},{},{}\n", accel(t), force / mass);
    }
    let p = dir.path().join("acc.csv");
    std::fs::write(&p, text).unwrap();
    let diag = |name: &str, extra: &[&str]| -> (serde_json::Value, String) {
        let out = dir.path().join(name);
        let mut args = vec![p.to_str().unwrap(), "--out-dir", out.to_str().unwrap()];
        args.extend_from_slice(extra);
        let o = run(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        (
            serde_json::from_str(&std::fs::read_to_string(out.join("diagnose.json")).unwrap())
                .unwrap(),
            std::fs::read_to_string(out.join("diagnose.txt")).unwrap(),
        )
    };
    let (direct, _) = diag("direct", &[]);
    let (from_acc, report) = diag(
        "acc",
        &[
            "--relative-acceleration-column",
            "a_rel_m_per_s2",
            "--inertia-acceleration-column",
            "a_mass_m_per_s2",
            "--mass-kg",
            "2.5",
        ],
    );
    assert_eq!(direct["verdict"], from_acc["verdict"]);
    for key in ["e0_n_per_m", "k", "slip_force_n"] {
        let (a, b) = (
            direct["baseline"][key].as_f64().unwrap(),
            from_acc["baseline"][key].as_f64().unwrap(),
        );
        assert!(
            (a - b).abs() <= 1e-6 * a.abs().max(1e-12),
            "{key}: {a} vs {b}"
        );
    }
    for needle in [
        "double integral of `a_rel_m_per_s2`",
        "1.000000 Hz",
        "force = 2.5 kg × `a_mass_m_per_s2`",
    ] {
        assert!(report.contains(needle), "`{needle}` not in {report}");
    }
    for (extra, flag) in [
        (
            vec!["--inertia-acceleration-column", "a_mass_m_per_s2"],
            "--mass-kg",
        ),
        (
            vec![
                "--inertia-acceleration-column",
                "a_mass_m_per_s2",
                "--mass-kg",
                "-1",
            ],
            "--mass-kg",
        ),
    ] {
        let out = dir.path().join("bad");
        let mut args = vec![p.to_str().unwrap(), "--out-dir", out.to_str().unwrap()];
        args.extend(extra.iter().copied());
        let o = run(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success() && err.contains(flag),
            "{extra:?}: {err}"
        );
        assert!(!out.join("diagnose.json").exists());
    }
    let g = dir.path().join("g.csv");
    std::fs::write(
        &g,
        std::fs::read_to_string(&p)
            .unwrap()
            .replacen("a_rel_m_per_s2", "a_rel_g", 1),
    )
    .unwrap();
    let out = dir.path().join("bad_g");
    let o = run(&[
        g.to_str().unwrap(),
        "--relative-acceleration-column",
        "a_rel_g",
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success()
            && err.contains("--relative-acceleration-column")
            && err.contains("m/s²"),
        "{err}"
    );
}
