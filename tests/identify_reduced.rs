//! Updating a multi-DOF reduced model (`asperity identify --structure`): synthetic sweeps of a
//! two-mode modal model with a Jenkins contact element, computed by the harmonic-balance solver
//! with known updating factors plus 1 % noise, fitted on the lowest and highest level; the
//! factors come back within 2 % and the middle level is predicted, in 10 of 10 noise
//! realisations. The CLI writes its report and refuses bad input.

use asperity::identify::effects::Effect;
use asperity::identify::fit::{FitOptions, Parametrised};
use asperity::identify::measured::Sweep;
use asperity::identify::model::{Drive, Scales};
use asperity::identify::reduced::{
    identify_reduced, EffectSearch, ReducedIdentification, ReducedModel, ReducedOptions,
    ReducedSpec, SavedReducedModel, REDUCED_EFFECTS,
};
use asperity::identify::report::LevelErrors;
use asperity::identify::select::{Extensible, Verdict};
use rayon::prelude::*;
use std::f64::consts::TAU;

#[path = "support/synthetic_sweep.rs"]
mod synthetic_sweep;
use std::path::{Path, PathBuf};
use std::process::Command;
use synthetic_sweep::noisy_sweep;

/// Two modes (100 Hz and 400 Hz, ζ = 0.5 %, mass-normalised shapes), driven and measured at
/// `tip.x`; one Jenkins contact element between `joint` and ground (tangent x, normal z):
/// E0 = 4e5 N/m adds a quarter of it, 1e5 N/m, to the first mode's modal stiffness when stuck
/// (about 113 Hz as given), and slips at μ·N0 = 0.6 × 1 N (a slip displacement of 1.5 µm).
fn write_model(dir: &Path, damping_ratio: f64) -> PathBuf {
    let w = |name: &str, text: &str| std::fs::write(dir.join(name), text).unwrap();
    w(
        "modes.csv",
        &format!(
            "mode,frequency_Hz,damping_ratio\n1,100.0,{damping_ratio}\n2,400.0,{damping_ratio}\n"
        ),
    );
    w(
        "shapes.csv",
        "# mass-normalised shapes\nnode,direction,mode_1_per_sqrt_kg,mode_2_per_sqrt_kg\n\
tip,x,1.0,0.6\njoint,x,0.5,-0.8\n",
    );
    w(
        "elements.csv",
        "# units: m, m2, Pa, N, N/m\nid,x_m,y_m,area_m2,pressure_Pa,N0_N,kn_N_per_m,E0_N_per_m,k,mu,Et_N_per_m,out_of_range\n\
1,0,0,1e-6,1e6,1.0,1e6,4e5,0,0.6,0,0\n",
    );
    w(
        "model.toml",
        "[linear]\nmodes = \"modes.csv\"\nshapes = \"shapes.csv\"\n\n\
[[contact]]\nelements = \"elements.csv\"\nlaw = \"jenkins\"\nnode_a = \"joint\"\nnode_b = \"ground\"\n\
normal = [0.0, 0.0, 1.0]\ntangent = [1.0, 0.0, 0.0]\n\n\
[excitation]\ndofs = [\"tip.x\"]\nlevels_n = [0.1]\n\n\
[response]\ndofs = [\"tip.x\"]\n\n\
[sweep]\nfrequency_start_hz = 95.0\nfrequency_end_hz = 108.0\npoints = 15\nharmonics = 3\nodd_only = true\n",
    );
    dir.join("model.toml")
}

/// Truth: frequencies +3 %, damping ratios × 1.6, contact stiffness × 0.7, friction × 1.4.
const TRUTH: [f64; 4] = [1.03, 1.6, 0.7, 1.4];

/// Force of each level (N): the joint nearly stuck, slipping, well into slip.
const LEVELS_N: [f64; 3] = [0.03, 0.15, 0.6];

/// A force-controlled sweep: 57 rows from 100 to 114 Hz (0.25 Hz; the truth's first mode lies
/// at 111.3 Hz with the joint stuck, 103 Hz with it sliding), the force dipping by up to 20 % near
/// 107 Hz, acceleration with 1 % amplitude and 0.01 rad phase noise.
fn sweep(spec: &ReducedSpec, force: f64, seed: u64) -> Sweep {
    sweep_with_noise(spec, force, seed, 0.01)
}

/// The rows of every synthetic sweep: 100–114 Hz in 0.25 Hz steps, the force `force` dipping
/// by up to 20 % near 107 Hz.
fn sweep_drives(force: f64) -> Vec<Drive> {
    (0..57)
        .map(|i| {
            let f = 100.0 + 0.25 * i as f64;
            let dip = 0.2 / (1.0 + ((f - 107.0) / 1.0).powi(2));
            Drive {
                omega: TAU * f,
                force_n: force * (1.0 - dip),
            }
        })
        .collect()
}

/// [`sweep`] with relative amplitude noise and phase noise (rad) of standard deviation `noise`.
fn sweep_with_noise(spec: &ReducedSpec, force: f64, seed: u64, noise: f64) -> Sweep {
    let truth = spec.model(TRUTH.to_vec());
    let drives = sweep_drives(force);
    let (x, _) = truth.receptance_tolerant(&drives, force, false).unwrap();
    noisy_sweep(
        format!("synthetic-{force}N-{seed}.csv"),
        &drives,
        &x,
        noise,
        seed,
    )
}

fn fit_options(seed: u64) -> FitOptions {
    FitOptions {
        particles: 16,
        swarm_iterations: 15,
        starts: 1,
        seed,
        local_iterations: 600,
        ..FitOptions::default()
    }
}

/// [`fit_options`] without prediction bands (their chains would dominate the test's time).
/// The test options: no uncertainty chains, and every candidate effect named. Left to the
/// default, the search is left out when a timed evaluation predicts more than its budget
/// (`default_search_follows_the_cost_of_an_evaluation`), which on a heavily loaded machine it
/// did: the tests would then depend on the wall clock.
fn options(seed: u64) -> ReducedOptions {
    ReducedOptions {
        chain_steps: Some(0),
        candidates: Some(REDUCED_EFFECTS.to_vec()),
        ..ReducedOptions::new(fit_options(seed))
    }
}

#[test]
fn updating_factors_come_back_within_two_percent_in_ten_of_ten_realisations() {
    let dir = tempfile::tempdir().unwrap();
    let spec = ReducedSpec::load(&write_model(dir.path(), 0.005)).unwrap();
    // Realisations in parallel (one identification is nearly serial): per realisation its
    // factor errors, level 2's peak and phase-resonance errors, the largest backbone frequency
    // error and whether the search was not needed.
    let per_realisation: Vec<([f64; 4], f64, f64, f64, bool)> = (0..10u64)
        .into_par_iter()
        .map(|r| {
            let mut worst = [0.0f64; 4];
            let mut worst_backbone = 0.0f64;
            let sweeps: Vec<Sweep> = LEVELS_N
                .iter()
                .enumerate()
                .map(|(k, &f)| sweep(&spec, f, 100 * r + k as u64))
                .collect();
            let id = identify_reduced(&spec, sweeps, vec![0, 2], &options(r + 1), None).unwrap();
            assert!(id.fit.converged, "realisation {r}: fit not converged");
            // The truth has no effect beyond the four factors: none is added (the search is not
            // needed at the scatter, or finds no candidate with strong held-out evidence).
            let not_needed = matches!(id.effect_search, EffectSearch::NotNeeded);
            match &id.effect_search {
                EffectSearch::NotNeeded => {}
                EffectSearch::Run(sel) => assert!(
                    sel.final_spec.effects.is_empty(),
                    "realisation {r}: effects forced on data without one: {:?}",
                    sel.final_spec.effects
                ),
                EffectSearch::NotRun { reason } => {
                    panic!("realisation {r}: search not run: {reason}")
                }
            }
            for (k, (&v, &t)) in id.fit.model.values.iter().zip(&TRUTH).enumerate() {
                let e = (v / t - 1.0).abs();
                worst[k] = worst[k].max(e);
                assert!(
                    e < 0.02,
                    "realisation {r}: {} = {v} against {t} ({:.2} %)",
                    id.parameters[k].name,
                    100.0 * e
                );
            }
            // The model as given misses the middle level badly; the updated one predicts it: peak
            // and phase resonance against the truth's noise-free response (the measured peak row of
            // a flat, noisy top is biased upwards by the noise), RMS complex error against the data.
            let (b, a) = (&id.errors_before[1], &id.errors_after[1]);
            assert_eq!(a.role, "predicted");
            assert!(b.rms_complex > 0.2, "as given: RMS {}", b.rms_complex);
            let level = &id.levels[1];
            let (y_truth, _) = ReducedSpec::frf(&spec.model(TRUTH.to_vec()), level).unwrap();
            let (y_fit, _) = ReducedSpec::frf(&id.fit.model, level).unwrap();
            let peak = |y: &[realfft::num_complex::Complex64]| {
                y.iter().map(|v| v.norm()).fold(0.0, f64::max)
            };
            let peak_error = peak(&y_fit) / peak(&y_truth) - 1.0;
            let truth_errors = LevelErrors::new(level, &y_truth, "truth", 0);
            let phase_res = a.phase_resonance_model_hz - truth_errors.phase_resonance_model_hz;
            assert!(
                peak_error.abs() < 0.01 && phase_res.abs() < 0.02 && a.rms_complex < 0.02,
                "realisation {r}: level 2 predicted at {:+.2} % peak, {:+.3} Hz phase resonance \
             against the truth, RMS {:.4} against the data",
                100.0 * peak_error,
                phase_res,
                a.rms_complex
            );
            // Backbone: the same estimator (equivalent linear mode per level) on the measured sweep
            // and on the updated model's response agrees within the estimator's scatter under 1 %
            // noise (frequency 0.05 %, damping ratio 3 %); the model as given does not (its mode
            // sits 5 % low at the highest level, where the joint slips).
            let data = id.data_backbone.as_ref().unwrap();
            for (l, d) in data.iter().enumerate() {
                let a = id.backbone_after[l].unwrap();
                let df = a.frequency_hz / d.linear.frequency_hz - 1.0;
                let dz = a.damping_ratio / d.linear.damping_ratio - 1.0;
                assert!(
                    df.abs() < 5e-4 && dz.abs() < 0.03,
                    "realisation {r}, level {}: updated mode {:.4} Hz, ζ {:.5} against the data's \
                 {:.4} Hz, ζ {:.5}",
                    l + 1,
                    a.frequency_hz,
                    a.damping_ratio,
                    d.linear.frequency_hz,
                    d.linear.damping_ratio
                );
                worst_backbone = worst_backbone.max(df.abs());
            }
            let given = id.backbone_before[2].unwrap();
            assert!(given.frequency_hz / data[2].linear.frequency_hz - 1.0 < -0.02);
            // Response control at the measured peak responses: with the joint stuck (level 1) the
            // structure is linear and both controls give the same peak as the truth's noise-free
            // force-controlled sweep (1.5 %); with more slip the peak falls (damping grows).
            let rc = &id.response_controlled;
            assert_eq!(rc.len(), 3);
            let (y1, _) = ReducedSpec::frf(&spec.model(TRUTH.to_vec()), &id.levels[0]).unwrap();
            let e1 = rc[0].peak_frf / peak(&y1) - 1.0;
            assert!(
                e1.abs() < 0.015,
                "realisation {r}: response-controlled peak {e1:+.4}"
            );
            assert!(rc[0].peak_frf > rc[1].peak_frf && rc[1].peak_frf > rc[2].peak_frf);
            (
                worst,
                peak_error.abs(),
                phase_res.abs(),
                worst_backbone,
                not_needed,
            )
        })
        .collect();
    let mut worst = [0.0f64; 4];
    let (mut worst_peak, mut worst_res, mut worst_backbone) = (0.0f64, 0.0f64, 0.0f64);
    let mut searches_not_needed = 0;
    for (w, peak, res, backbone, not_needed) in per_realisation {
        for (a, b) in worst.iter_mut().zip(w) {
            *a = a.max(b);
        }
        worst_peak = worst_peak.max(peak);
        worst_res = worst_res.max(res);
        worst_backbone = worst_backbone.max(backbone);
        searches_not_needed += usize::from(not_needed);
    }
    eprintln!(
        "largest factor errors {:.2?} %, level 2 predicted within {:.2} % peak and {:.3} Hz \
         phase resonance of the truth; backbone frequencies within {:.3} % of the data's; the \
         factors fitted to the scatter (no search needed) in {searches_not_needed} of 10",
        worst.map(|e| 100.0 * e),
        100.0 * worst_peak,
        worst_res,
        100.0 * worst_backbone
    );
}

fn asperity(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args(args)
        .output()
        .unwrap()
}

fn write_csv(path: &Path, s: &Sweep) {
    let mut t = String::from(
        "# synthetic sweep of the reduced model\nfrequency_Hz,force_amplitude_N,acceleration_amplitude_m_per_s2,phase_rad\n",
    );
    for r in &s.rows {
        t += &format!(
            "{},{},{},{}\n",
            r.frequency_hz, r.force_n, r.response, r.phase_rad
        );
    }
    std::fs::write(path, t).unwrap();
}

#[test]
fn cli_updates_the_reduced_model_and_refuses_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let model = write_model(dir.path(), 0.005);
    let spec = ReducedSpec::load(&model).unwrap();
    let mut files = Vec::new();
    for (k, &f) in LEVELS_N.iter().enumerate() {
        let p = dir.path().join(format!("level{}.csv", k + 1));
        write_csv(&p, &sweep(&spec, f, 7 + k as u64));
        files.push(p.to_str().unwrap().to_string());
    }
    let out = dir.path().join("out");
    let mut args = vec!["identify", "--structure", model.to_str().unwrap()];
    args.extend(files.iter().map(|s| s.as_str()));
    args.extend([
        "--fit-levels",
        "1,3",
        "--particles",
        "16",
        "--swarm-iterations",
        "15",
        "--starts",
        "1",
        "--response-amplitude",
        "2,10",
        "--chain-steps",
        "3000",
        "--rows",
        "settled",
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    let o = asperity(&args);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{text}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(text.contains("contact_stiffness_factor") && text.contains("predicted"));
    for section in [
        "residual per region, model as given → updated",
        "backbone: equivalent linear mode per level",
        "response amplitude 2.0000 m/s²",
        "prediction uncertainty of the updated model",
    ] {
        assert!(
            text.contains(section),
            "report without `{section}`:\n{text}"
        );
    }
    for f in [
        "identify.txt",
        "identify.json",
        "model.json",
        "identify-rows.csv",
        "identify-level1.png",
        "identify-level2.png",
        "identify-level3.png",
        "identify-backbone.csv",
        "identify-backbone.png",
        "identify-response-controlled.csv",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    // identify.json has the single-mode report's shape: the data's backbone and the
    // model-free check as values (not nested under serde's "Ok").
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("identify.json")).unwrap()).unwrap();
    assert_eq!(
        report["model_free"]["laws"].as_array().map(Vec::len),
        Some(6),
        "{}",
        report["model_free"]
    );
    assert!(
        report["data_backbone"].is_array(),
        "{}",
        report["data_backbone"]
    );
    // The stationarity check, as a value too: the model's own sweeps are stationary.
    let st = report["stationarity"]
        .as_array()
        .expect("stationarity array");
    assert!(
        st.iter().all(|c| c.is_null() || c["stationary"] == true),
        "{}",
        report["stationarity"]
    );
    // `--rows settled` (accepted with --structure) leaves a stationary level's rows alone.
    assert_eq!(report["options"]["rows"], "settled");
    assert_eq!(report["settled_from"], serde_json::json!([null, null]));
    assert!(report["model_free_settled"].is_null());
    assert!(!text.contains("fit rows (--rows settled)"), "{text}");
    // Two response amplitudes asked for, 81 frequencies each, after two header lines.
    let rc = std::fs::read_to_string(out.join("identify-response-controlled.csv")).unwrap();
    assert_eq!(rc.lines().count(), 2 + 2 * 81);
    let saved: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("model.json")).unwrap()).unwrap();
    let stiffness = saved["factors"][2][1].as_f64().unwrap();
    assert!((stiffness / TRUTH[2] - 1.0).abs() < 0.02, "{stiffness}");

    // The saved model predicts any file: force control (the measured forces applied) and
    // response control (the measured responses held, the force solved for) of the level not
    // used, here without noise, within 1 % (RMS complex) and the force within 1 % (RMS).
    let clean = dir.path().join("level2-clean.csv");
    write_csv(&clean, &sweep_with_noise(&spec, LEVELS_N[1], 0, 0.0));
    for control in ["force", "response"] {
        let pout = dir.path().join(format!("predict-{control}"));
        let o = asperity(&[
            "predict",
            "--model",
            out.join("model.json").to_str().unwrap(),
            clean.to_str().unwrap(),
            "--control",
            control,
            "--out-dir",
            pout.to_str().unwrap(),
        ]);
        let text = String::from_utf8_lossy(&o.stdout);
        assert!(
            o.status.success(),
            "{text}{}",
            String::from_utf8_lossy(&o.stderr)
        );
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(pout.join("predict.json")).unwrap())
                .unwrap();
        let e = &json["prediction"]["files"][0]["errors"];
        let rms = e["rms_complex"].as_f64().unwrap();
        assert!(rms < 0.01, "{control} control: RMS {rms}\n{text}");
        if control == "response" {
            let f = json["prediction"]["files"][0]["force_rms_error"]
                .as_f64()
                .unwrap();
            assert!(f < 0.01, "force RMS error {f}\n{text}");
        }
        assert!(pout.join("predict-1.png").is_file());
        // Under force control, `predict` gives the 95 % bands of the ensemble saved with the
        // model. One noise realisation cannot test their coverage (that is tested on the single
        // mode, `identify_synthetic`, over 20); it can test their scale: the truth's peak and
        // phase resonance lie within twice the band's half-width of the band's centre (≈ 3.9
        // standard deviations of a Gaussian prediction; a band too narrow by more than a factor
        // of two fails), and the peak band is narrower than 5 % of the peak.
        if control == "force" {
            let b = &json["prediction"]["bands"][0];
            let within = |q: &str, m: &str| {
                let (lo, hi) = (
                    b[q]["lo_95"].as_f64().unwrap(),
                    b[q]["hi_95"].as_f64().unwrap(),
                );
                let v = b[m].as_f64().unwrap();
                let (centre, half) = (0.5 * (lo + hi), 0.5 * (hi - lo));
                assert!(
                    half > 0.0 && (v - centre).abs() <= 2.0 * half,
                    "{q}: truth {v} against the band [{lo}, {hi}]\n{text}"
                );
                2.0 * half / v
            };
            let width = within("peak", "peak_measured");
            assert!(width < 0.05, "peak band {width}\n{text}");
            within("phase_resonance_hz", "phase_resonance_measured_hz");
            assert!(b["r_hat"].as_f64().unwrap() < 1.1, "{text}");
        }
    }
    // A response-model file changed since the identification is refused.
    let toml = std::fs::read_to_string(&model).unwrap();
    std::fs::write(&model, toml.replace("levels_n = [0.1]", "levels_n = [0.2]")).unwrap();
    let o = asperity(&[
        "predict",
        "--model",
        out.join("model.json").to_str().unwrap(),
        &files[1],
        "--out-dir",
        dir.path().join("predict-changed").to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("has changed"), "{err}");

    // An undamped linear structure: nothing for the damping factor to scale.
    let bad_dir = tempfile::tempdir().unwrap();
    let bad = write_model(bad_dir.path(), 0.0);
    let bad_out = bad_dir.path().join("out");
    let mut args = vec!["identify", "--structure", bad.to_str().unwrap()];
    args.extend(files.iter().map(|s| s.as_str()));
    args.extend(["--out-dir", bad_out.to_str().unwrap()]);
    let o = asperity(&args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("model.toml") && err.contains("no damping"),
        "{err}"
    );
    assert!(!bad_out.exists(), "nothing written on bad input");

    // A model without contact elements: nothing for the contact factors to act on.
    let toml = std::fs::read_to_string(&bad).unwrap();
    let i = toml.find("[[contact]]").unwrap();
    let j = toml.find("[excitation]").unwrap();
    std::fs::write(&bad, format!("{}{}", &toml[..i], &toml[j..])).unwrap();
    let mut args = vec!["identify", "--structure", bad.to_str().unwrap()];
    args.extend(files.iter().map(|s| s.as_str()));
    args.extend(["--out-dir", bad_out.to_str().unwrap()]);
    let o = asperity(&args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("no `[[contact]]` elements"),
        "{err}"
    );
    assert!(!bad_out.exists(), "nothing written on bad input");

    // A candidate the reduced model does not take (a velocity-dependent damper is defined on
    // the single mode's coordinate only) is refused, naming the option and the candidates.
    let mut args = vec!["identify", "--structure", model.to_str().unwrap()];
    args.extend(files.iter().map(|s| s.as_str()));
    args.extend(["--candidates", "quadratic_damping"]);
    let o = asperity(&args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("--candidates") && err.contains("amplitude_stiffness"),
        "{err}"
    );
}

/// Reference scales of the truth's cubic spring: `k_ref = m·(2π·f)²` with the first mode's
/// modal mass at the tip (1 kg: mass-normalised shape 1.0) and 106 Hz; `A_ref` 40 µm (the
/// tip's peak displacement at the highest level is about 25 µm).
const EFFECT_SCALES: Scales = Scales {
    frequency_hz: 106.0,
    modal_mass_kg: 1.0,
    amplitude_max_m: 4e-5,
    amplitude_min_m: 4e-6,
    force_n: 0.6,
};

/// The truth's value of each effect tested: a hardening cubic spring at the tip giving +2 %
/// stiffness at `A_ref` = 40 µm; a preload loss taking 30 % of the contact's slip force and
/// stiffness at 0.6 N (7.5 % at the middle level).
fn truth_value(effect: Effect) -> f64 {
    match effect {
        Effect::AmplitudeStiffness => 0.02,
        Effect::PreloadLoss => 0.3,
        e => panic!("no truth for {e:?}"),
    }
}

/// The truth (the four factors of [`TRUTH`]) with one effect the four factors cannot express.
fn truth_with(spec: &ReducedSpec, effect: Effect) -> ReducedModel {
    let mut values = TRUTH.to_vec();
    values.push(truth_value(effect));
    spec.with_scales(EFFECT_SCALES).with(effect).model(values)
}

/// The effect's physical parameter, independent of the data's reference scales: `k3` (N/m³)
/// of the cubic spring, the preload loss per newton of mean force `λ/F_ref` (1/N).
fn physical(model: &ReducedModel, effect: Effect) -> f64 {
    match effect {
        Effect::AmplitudeStiffness => model.cubic_stiffness().unwrap(),
        Effect::PreloadLoss => (1.0 - model.preload_factor(0.1)) / 0.1, // λ/F_ref
        e => panic!("no physical parameter for {e:?}"),
    }
}

/// Sweeps of a model at the three levels (57 rows as [`sweep`]), 1 % noise.
fn sweeps_of(truth: &ReducedModel, seed: u64) -> Vec<Sweep> {
    LEVELS_N
        .iter()
        .enumerate()
        .map(|(k, &force)| {
            let drives = sweep_drives(force);
            let mean = drives.iter().map(|d| d.force_n).sum::<f64>() / drives.len() as f64;
            let (x, _) = truth.receptance_tolerant(&drives, mean, false).unwrap();
            noisy_sweep(
                format!("effect-{force}N-{}.csv", seed + k as u64),
                &drives,
                &x,
                0.01,
                seed + k as u64,
            )
        })
        .collect()
}

/// Closing the loop on a reduced model, `realisations` noise realisations of the truth with
/// `effect`, fitted on the lowest and highest level: the four factors alone leave a residual
/// above the scatter; the search adds `effect` and nothing else, the factors come back within
/// 2 % (the friction factor 3 % beside the preload loss) and the effect's physical parameter
/// within 10 %, and the middle level's prediction improves on the factors-only update's.
fn search_finds(effect: Effect, realisations: u64) {
    let dir = tempfile::tempdir().unwrap();
    let spec = ReducedSpec::load(&write_model(dir.path(), 0.005)).unwrap();
    let truth = truth_with(&spec, effect);
    // Realisations in parallel (one identification is nearly serial): per realisation the
    // effect parameter's and the factors' relative errors.
    let errors: Vec<(f64, [f64; 4])> = (0..realisations)
        .into_par_iter()
        .map(|r| {
            let mut worst_factor = [0.0f64; 4];
            let sweeps = sweeps_of(&truth, 1000 + 100 * r);
            let id = identify_reduced(&spec, sweeps, vec![0, 2], &options(r + 1), None).unwrap();
            let EffectSearch::Run(sel) = &id.effect_search else {
                panic!("realisation {r}: search {:?}", id.effect_search);
            };
            assert_eq!(sel.final_spec.effects, vec![effect], "realisation {r}");
            let (got, want) = (physical(&id.fit.model, effect), physical(&truth, effect));
            eprintln!(
                "{} realisation {r}: factors {:.4?}, effect parameter {got:.4e} against {want:.4e}",
                effect.id(),
                id.fit.model.values
            );
            for (k, (&v, &t)) in id.fit.model.values.iter().zip(&TRUTH).enumerate() {
                // With the preload loss, the friction factor alone (the slip force without loss)
                // is seen where the loss is small, at the lowest level, where the joint is nearly
                // stuck: it trades off against λ (in a probe of 4 realisations up to +2.04 %, where
                // λ/F_ref was +1.6 % and the highest level's slip force within 1.4 %), hence 3 %.
                let tolerance = if effect == Effect::PreloadLoss && k == 3 {
                    0.03
                } else {
                    0.02
                };
                worst_factor[k] = worst_factor[k].max((v / t - 1.0).abs());
                assert!(
                    (v / t - 1.0).abs() < tolerance,
                    "realisation {r}: {} = {v} against {t}",
                    id.parameters[k].name
                );
            }
            assert!(
                (got / want - 1.0).abs() < 0.1,
                "realisation {r}: {} parameter {got:.4e} against {want:.4e}",
                effect.id()
            );
            if r == 0 {
                // The saved model carries the effect: read back, it gives the same response.
                let out = dir.path().join("out");
                id.write(&out).unwrap();
                let (saved, _, _) = SavedReducedModel::read(&out.join("model.json")).unwrap();
                assert_eq!(saved.spec.effects, vec![effect]);
                let (a, _) = ReducedSpec::frf(&saved, &id.levels[1]).unwrap();
                let (b, _) = ReducedSpec::frf(&id.fit.model, &id.levels[1]).unwrap();
                assert!(a
                    .iter()
                    .zip(&b)
                    .all(|(x, y)| (x - y).norm() <= 1e-9 * y.norm()));
                let report = std::fs::read_to_string(out.join("identify.txt")).unwrap();
                assert!(
                    report.contains("← accepted")
                        && report.contains("before and after the effects")
                );
            }
            let (_, before) = id.factors_only.as_ref().unwrap();
            assert!(
                id.errors_after[1].rms_complex < before[1].rms_complex,
                "realisation {r}: middle level RMS {} with the effect, {} without",
                id.errors_after[1].rms_complex,
                before[1].rms_complex
            );
            ((got / want - 1.0).abs(), worst_factor)
        })
        .collect();
    let worst = errors.iter().map(|e| e.0).fold(0.0f64, f64::max);
    let mut worst_factor = [0.0f64; 4];
    for (_, f) in &errors {
        for (a, b) in worst_factor.iter_mut().zip(f) {
            *a = a.max(*b);
        }
    }
    eprintln!(
        "{}: found alone in {realisations} of {realisations} realisations, physical parameter \
         within {:.2} %, factors within {:.2?} %",
        effect.id(),
        100.0 * worst,
        worst_factor.map(|e| 100.0 * e)
    );
}

/// The stiffening spring, two realisations (each about a minute on two cores).
#[test]
fn the_search_finds_a_stiffening_spring_the_factors_cannot_express() {
    search_finds(Effect::AmplitudeStiffness, 2);
}

/// Offered only candidates that cannot express a stiffening spring (a force delay, the same at
/// every level; more harmonics), the search says that the residual stays above the scatter and
/// no candidate explains it, and the update keeps the four factors: nothing is forced.
#[test]
fn without_the_right_candidate_the_residual_is_reported_unexplained() {
    let dir = tempfile::tempdir().unwrap();
    let spec = ReducedSpec::load(&write_model(dir.path(), 0.005)).unwrap();
    let truth = truth_with(&spec, Effect::AmplitudeStiffness);
    let options = ReducedOptions {
        candidates: Some(vec![Effect::ShakerInteraction, Effect::HigherHarmonics]),
        ..options(1)
    };
    let id = identify_reduced(&spec, sweeps_of(&truth, 1000), vec![0, 2], &options, None).unwrap();
    let EffectSearch::Run(sel) = &id.effect_search else {
        panic!("search {:?}", id.effect_search);
    };
    assert!(
        matches!(sel.verdict, Verdict::Unexplained { .. }),
        "{:?}\n{}",
        sel.verdict,
        id.text()
    );
    assert!(id.fit.model.spec.effects.is_empty() && id.factors_only.is_none());
    assert!(!id.at_scatter);
    assert!(id.text().contains("no candidate effect explains it"));
    // The model-free check is in the report, with a comparison on the level not used.
    let mf = id.model_free.as_ref().expect("model-free check");
    assert_eq!(mf.comparisons.len(), 1);
    assert_eq!(mf.comparisons[0].level, 2);
    assert!(id.text().contains("model-free check"));
}

/// Ten realisations each of the stiffening spring and the preload loss (about 20 minutes on
/// two cores): `cargo test --release --test identify_reduced -- --ignored`.
#[test]
#[ignore]
fn the_search_finds_each_effect_in_ten_of_ten_realisations() {
    search_finds(Effect::AmplitudeStiffness, 10);
    search_finds(Effect::PreloadLoss, 10);
}

/// Under response control with a residual receptance `r`, the measured amplitude `|x + r|·F`
/// is held (fixed point on the structure's target), not the structure's `|x|·F` alone.
#[test]
fn response_control_holds_the_measured_amplitude_with_a_residual_receptance() {
    let dir = tempfile::tempdir().unwrap();
    let spec = ReducedSpec::load(&write_model(dir.path(), 0.005)).unwrap();
    let mut values = TRUTH.to_vec();
    values.push(1.0); // ρ = 1: r = 1/k_ref ≈ 2.3e-6 m/N, a few per cent of the response
    let with_r = spec
        .with_scales(EFFECT_SCALES)
        .with(Effect::OutOfBandModes)
        .model(values);
    let without_r = spec.model(TRUTH.to_vec());
    let omegas: Vec<f64> = [104.0, 106.0, 108.0].iter().map(|f| TAU * f).collect();
    let target = [5e-6; 3];
    let (forces, recs) = with_r.response_controlled(&omegas, &target, 0.15).unwrap();
    let (forces0, _) = without_r
        .response_controlled(&omegas, &target, 0.15)
        .unwrap();
    for i in 0..3 {
        let held = recs[i].norm() * forces[i];
        assert!(
            (held / target[i] - 1.0).abs() < 1e-8,
            "row {i}: held {held}"
        );
        assert!(
            (forces[i] / forces0[i] - 1.0).abs() > 1e-3,
            "row {i}: the residual receptance changed nothing ({} N vs {} N)",
            forces[i],
            forces0[i]
        );
    }
}

/// Level 3 (0.6 N) as `early` responds on the rows before its resonance row and as the truth
/// from it on: a joint that changed during that level's test. Noise as [`sweep`].
fn sweeps_changing(spec: &ReducedSpec, early: &ReducedModel, seed: u64) -> (Vec<Sweep>, usize) {
    let truth = spec.model(TRUTH.to_vec());
    let drives = sweep_drives(LEVELS_N[2]);
    let (mut x, _) = truth
        .receptance_tolerant(&drives, LEVELS_N[2], false)
        .unwrap();
    let row = (0..x.len())
        .max_by(|&a, &b| x[a].norm().total_cmp(&x[b].norm()))
        .unwrap();
    let (xe, _) = early
        .receptance_tolerant(&drives[..row], LEVELS_N[2], false)
        .unwrap();
    x[..row].copy_from_slice(&xe);
    let mut sweeps: Vec<Sweep> = LEVELS_N[..2]
        .iter()
        .enumerate()
        .map(|(k, &f)| sweep(spec, f, seed + k as u64))
        .collect();
    sweeps.push(noisy_sweep(
        format!("synthetic-changing-{seed}.csv"),
        &drives,
        &x,
        0.01,
        seed + 2,
    ));
    (sweeps, row)
}

/// One realisation of a level that changed during its test: level 3 responding as `early` on
/// its rows before the resonance ([`sweeps_changing`]), fitted on levels 1 and 3 on every row
/// and on the settled rows. Asserts what holds for any such change: the stationarity check
/// flags level 3 and never levels 1 and 2, and the settled fit cuts level 3 at its resonance
/// row (the noise may move it by a row). Returns level 3's check and the two fits.
fn fit_a_changing_level(
    spec: &ReducedSpec,
    early: &ReducedModel,
    r: u64,
) -> (
    asperity::identify::stationarity::SideComparison,
    ReducedIdentification,
    ReducedIdentification,
) {
    use asperity::identify::pipeline::FitRows;
    let (sweeps, row) = sweeps_changing(spec, early, 7000 + 10 * r);
    let fit = |rows| {
        let opts = ReducedOptions {
            rows,
            ..options(r + 1)
        };
        identify_reduced(spec, sweeps.clone(), vec![0, 2], &opts, None).unwrap()
    };
    let (all, settled) = (fit(FitRows::All), fit(FitRows::Settled));
    let sides = settled.stationarity.as_ref().unwrap();
    assert!(
        sides[..2]
            .iter()
            .all(|c| c.as_ref().is_none_or(|c| c.stationary)),
        "realisation {r}: level 1 or 2 flagged: {:?}",
        sides[..2]
            .iter()
            .map(|c| c.as_ref().map(|c| c.describe()))
            .collect::<Vec<_>>()
    );
    let c = sides[2].clone().expect("level 3 compared");
    assert!(!c.stationary, "realisation {r}: {}", c.describe());
    assert_eq!(all.settled_from, vec![None, None]);
    let first = settled.settled_from[1].expect("level 3 cut");
    assert!(
        first.abs_diff(row) <= 1 && settled.settled_from[0].is_none(),
        "realisation {r}: cut at {:?}, the truth's resonance row {row}",
        settled.settled_from
    );
    assert!(settled.model_free_settled.is_some() && all.model_free_settled.is_some());
    let text = settled.text();
    assert!(
        text.contains("fit rows (--rows settled): level 3 is not stationary"),
        "{text}"
    );
    (c, all, settled)
}

/// The test model (in a directory kept alive by the returned guard) and the truth with its
/// updating factor `index` multiplied by `factor`: level 3's response before its resonance in
/// [`fit_a_changing_level`].
fn model_changed_early(
    index: usize,
    factor: f64,
) -> (tempfile::TempDir, ReducedSpec, ReducedModel) {
    let dir = tempfile::tempdir().unwrap();
    let spec = ReducedSpec::load(&write_model(dir.path(), 0.005)).unwrap();
    let mut early = TRUTH.to_vec();
    early[index] *= factor;
    let early = spec.model(early);
    (dir, spec, early)
}

/// Print level 3's check, factor `k` of both fits and their errors on level 2; returns those
/// errors (every row, settled).
fn print_fits<'a>(
    r: u64,
    k: usize,
    c: &asperity::identify::stationarity::SideComparison,
    all: &'a ReducedIdentification,
    settled: &'a ReducedIdentification,
) -> (&'a LevelErrors, &'a LevelErrors) {
    let (e_all, e_settled) = (&all.errors_after[1], &settled.errors_after[1]);
    eprintln!(
        "realisation {r}: level 3 {}; {} every row {:.4}, settled {:.4} (truth {}); level 2 \
         predicted at peak {:+.2} / {:+.2} %, RMS {:.4} / {:.4}",
        c.describe(),
        settled.parameters[k].name,
        all.fit.model.values[k],
        settled.fit.model.values[k],
        TRUTH[k],
        100.0 * e_all.peak_error,
        100.0 * e_settled.peak_error,
        e_all.rms_complex,
        e_settled.rms_complex
    );
    (e_all, e_settled)
}

/// The settled fit's four factors within 2 % of the truth.
fn settled_factors_within_two_percent(settled: &ReducedIdentification, r: u64) {
    for (k, (&v, &t)) in settled.fit.model.values.iter().zip(&TRUTH).enumerate() {
        assert!(
            (v / t - 1.0).abs() < 0.02,
            "realisation {r}: settled {} = {v} against {t}",
            settled.parameters[k].name
        );
    }
}

/// Level 3's damping ratios twice as high on the rows before its resonance as from it on (a
/// joint that ran in during that level's test), 1 % noise, five realisations: the stationarity
/// check flags level 3 and never levels 1 and 2 — level 2 is swept where the joint starts to
/// slip and its pointwise damping triples within 20 % of amplitude, which the check called not
/// stationary (realisation 1) before it allowed for the amplitude's noise. `--rows settled` fits
/// level 3 from its resonance row on and brings the four factors back within 2 % and level 2's
/// prediction within 2 % RMS, where the fit on every row carries the earlier side's damping into
/// both (its damping factor and level 2's RMS error are the larger in every realisation).
/// Measured: damping factor settled 1.593–1.607, every row 1.614–1.629 (truth 1.6); level 2's
/// peak −1.5…+0.8 % against +4.0…+6.3 %, RMS 0.009–0.011 against 0.056–0.059.
#[test]
fn a_level_whose_damping_falls_during_its_test_is_fitted_on_its_settled_rows() {
    let (_dir, spec, early) = model_changed_early(1, 2.0);
    // Realisations in parallel (one identification is nearly serial).
    (0..5u64).into_par_iter().for_each(|r| {
        let (c, all, settled) = fit_a_changing_level(&spec, &early, r);
        assert!(c.differing >= 2, "realisation {r}: {}", c.describe());
        settled_factors_within_two_percent(&settled, r);
        let (e_all, e_settled) = print_fits(r, 1, &c, &all, &settled);
        assert!(
            e_settled.rms_complex < 0.02 && e_all.rms_complex > e_settled.rms_complex,
            "realisation {r}: level 2 RMS every row {:.4}, settled {:.4}",
            e_all.rms_complex,
            e_settled.rms_complex
        );
        assert!(all.fit.model.values[1] > settled.fit.model.values[1]);
    });
}

/// Level 3's friction 30 % higher on the rows before its resonance than from it on (a joint
/// whose slip force fell during that level's test), 1 % noise, three realisations. At the
/// amplitudes both sides share the damping hardly differs (no point beyond the damping's
/// tolerance), which is why the check once called this level stationary; the natural
/// frequency's shift between the sides, measured from level 1's, flags it. `--rows settled`
/// then fits level 3 from its resonance row on: the four factors come back within 2 % and
/// level 2's peak within 2 %, where the fit on every row misses it by more than 5 %.
/// Measured: level 3's shift −0.23…−0.31 from level 1's median (noise sd 0.018–0.029), its
/// damping −4.9…+7.0 % (0 points differ); friction factor settled 1.399–1.402, every row
/// 1.606–1.611 (truth 1.4); level 2's peak −1.5…+0.8 % against +10.6…+13.0 %, RMS 0.010–0.011
/// against 0.102–0.107.
#[test]
fn a_level_whose_slip_force_changes_during_its_test_is_flagged_by_its_natural_frequency() {
    let (_dir, spec, early) = model_changed_early(3, 1.3);
    // Realisations in parallel (one identification is nearly serial).
    (0..3u64).into_par_iter().for_each(|r| {
        let (c, all, settled) = fit_a_changing_level(&spec, &early, r);
        let (e_all, e_settled) = print_fits(r, 3, &c, &all, &settled);
        assert!(
            c.differing < 2 && c.frequency_differing >= 2,
            "realisation {r}: {}",
            c.describe()
        );
        settled_factors_within_two_percent(&settled, r);
        assert!(
            e_settled.peak_error.abs() < 0.02 && e_all.peak_error.abs() > 0.05,
            "realisation {r}: level 2 peak every row {:+.4}, settled {:+.4}",
            e_all.peak_error,
            e_settled.peak_error
        );
    });
}
