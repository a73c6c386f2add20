//! The default (fast) identification against the thorough search (`--thorough`): the same
//! model within its own reported uncertainty — every parameter of either inside the other's
//! 95 % interval, the errors on the levels not used within 0.5 percentage points.
//!
//! * synthetic sweeps (harmonic-balance responses with 1 % noise, an effect put in): both
//!   searches run here;
//! * the shared Brake–Reuss levels: the fast default here against the thorough result
//!   committed in `calib/identify/identify.json` (the thorough search itself takes over 20
//!   CPU-minutes: `#[ignore]`d below, run with `--ignored`).

use asperity::identify::effects::Effect;
use asperity::identify::model::{Drive, Family, Model, ModelSpec};
use asperity::identify::uncertainty::Uncertainty;
use asperity::identify::{identify, read_sweeps, Identification, Options};
use std::f64::consts::TAU;

#[path = "support/synthetic_sweep.rs"]
mod synthetic_sweep;
use synthetic_sweep::{noisy_sweep, SCALES};

/// One parameter of an identified model: name, value, 95 % interval (`None` on a bound).
#[derive(Debug, Clone)]
struct Stated {
    name: String,
    value: f64,
    interval: Option<(f64, f64)>,
}

/// The final model's parameters with their intervals.
fn stated(id: &Identification) -> Vec<Stated> {
    let Uncertainty::Estimated(e) = &id.uncertainty else {
        panic!("no intervals: {:?}", id.uncertainty);
    };
    e.intervals
        .iter()
        .map(|i| Stated {
            name: i.name.clone(),
            value: i.value,
            interval: i.lo_95.zip(i.hi_95),
        })
        .collect()
}

/// Every parameter of `a` inside `b`'s interval and the other way round. A parameter held on
/// a bound by both (no interval) must sit on the same bound. One held on a bound by only one of
/// them (its posterior piled against the bound, so the other's sampled interval can stop just
/// short of it) must lie within one interval width of the other's interval.
fn assert_inside_each_other(a: &[Stated], b: &[Stated], what: &str) {
    assert_eq!(a.len(), b.len(), "{what}: parameter counts");
    for (x, y) in a.iter().zip(b) {
        assert_eq!(x.name, y.name, "{what}");
        for (p, q, label) in [(x, y, "first in second"), (y, x, "second in first")] {
            if let Some((lo, hi)) = q.interval {
                let slack = if p.interval.is_none() { hi - lo } else { 0.0 };
                assert!(
                    p.value >= lo - slack && p.value <= hi + slack,
                    "{what}: {} = {} outside [{lo}, {hi}] ({label})",
                    p.name,
                    p.value
                );
            } else if p.interval.is_none() {
                // Both on a bound: the same bound, to within the looser final tolerance of the
                // fast search (1 %: a parameter spanning decades stopped 0.2 % short of its
                // bound is the same statement, "at the bound").
                assert!(
                    (p.value / q.value - 1.0).abs() < 1e-2 || (p.value - q.value).abs() < 1e-12,
                    "{what}: {} on a bound at {} and {}",
                    p.name,
                    p.value,
                    q.value
                );
            }
        }
    }
}

/// Peak error (%) and RMS complex error (% of the peak) of every level not used.
fn held_out_errors(id: &Identification) -> Vec<(String, f64, f64)> {
    id.errors_after
        .iter()
        .filter(|e| e.role == "predicted")
        .map(|e| (e.file.clone(), 100.0 * e.peak_error, 100.0 * e.rms_complex))
        .collect()
}

fn assert_errors_within_half_a_point(a: &[(String, f64, f64)], b: &[(String, f64, f64)]) {
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(b) {
        assert_eq!(x.0, y.0);
        assert!(
            (x.1 - y.1).abs() <= 0.5,
            "{}: peak error {:.2} % against {:.2} %",
            x.0,
            x.1,
            y.1
        );
        assert!(
            (x.2 - y.2).abs() <= 0.5,
            "{}: RMS complex error {:.2} % against {:.2} %",
            x.0,
            x.2,
            y.2
        );
    }
}

/// Truth of the synthetic case: f_s = 80 Hz, ζ0 = 0.1 %, m = 2 kg, κ = 2 %, δ = 30 µm (Jenkins)
/// with quadratic damping, ζ_q = 0.1 % at 200 µm.
fn synthetic_truth() -> Model {
    let spec = ModelSpec::baseline(Family::Jenkins, SCALES).with(Effect::QuadraticDamping);
    Model::new(spec, vec![80.0, 1e-3, 2.0, 0.02, 3e-5, 1e-3]).unwrap()
}

/// Levels at 0.02, 0.15, 0.6 N: 31 rows 79.0–80.5 Hz with a 20 % force dip, 1 % amplitude and
/// 0.01 rad phase noise (as `tests/identify_synthetic.rs`).
fn synthetic_sweeps(truth: &Model, seed: u64) -> Vec<asperity::identify::measured::Sweep> {
    [0.02, 0.15, 0.6]
        .iter()
        .enumerate()
        .map(|(k, &force)| {
            let drives: Vec<Drive> = (0..31)
                .map(|i| {
                    let f = 79.0 + 0.05 * i as f64;
                    let dip = 0.2 / (1.0 + ((f - 79.6) / 0.3).powi(2));
                    Drive {
                        omega: TAU * f,
                        force_n: force * (1.0 - dip),
                    }
                })
                .collect();
            let x = truth.receptance(&drives, force).unwrap();
            noisy_sweep(
                format!("synthetic-{force}N.csv"),
                &drives,
                &x,
                0.01,
                seed + k as u64,
            )
        })
        .collect()
}

/// Both searches' settings on the synthetic case: fit levels 1 and 3, the stiffness and damping
/// candidates, one effect.
fn synthetic_options(mut o: Options) -> Options {
    o.fit_levels = Some(vec![1, 3]);
    o.select.candidates = vec![Effect::AmplitudeStiffness, Effect::QuadraticDamping];
    o.select.max_effects = 1;
    o.response_amplitudes = Some(vec![5.0]);
    o
}

#[test]
fn fast_default_matches_the_thorough_search_on_synthetic_sweeps() {
    let truth = synthetic_truth();
    let sweeps = synthetic_sweeps(&truth, 700);
    let fast = identify(
        sweeps.clone(),
        &synthetic_options(Options::new(Family::Jenkins)),
        None,
    )
    .unwrap();
    let thorough = identify(
        sweeps,
        &synthetic_options(Options::thorough(Family::Jenkins)),
        None,
    )
    .unwrap();
    eprintln!(
        "fast: {:.1} s, effects {:?}; thorough: {:.1} s, effects {:?}",
        fast.wall_time_s,
        fast.after.model.spec.effects,
        thorough.wall_time_s,
        thorough.after.model.spec.effects
    );
    assert_eq!(
        fast.after.model.spec.effects,
        vec![Effect::QuadraticDamping]
    );
    assert_eq!(fast.after.model.spec, thorough.after.model.spec);
    let (a, b) = (stated(&fast), stated(&thorough));
    for (x, y) in a.iter().zip(&b) {
        eprintln!(
            "{:<44} fast {:.6e} {:?}   thorough {:.6e} {:?}",
            x.name, x.value, x.interval, y.value, y.interval
        );
    }
    assert_inside_each_other(&a, &b, "synthetic");
    assert_errors_within_half_a_point(&held_out_errors(&fast), &held_out_errors(&thorough));
}

/// The committed thorough identification of the Brake–Reuss levels (fit on levels 1 and 4).
fn committed_thorough() -> serde_json::Value {
    let p = concat!(env!("CARGO_MANIFEST_DIR"), "/calib/identify/identify.json");
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

fn brake_reuss_sweeps() -> Option<Vec<asperity::identify::measured::Sweep>> {
    let files: Option<Vec<_>> = (1..=4)
        .map(|l| {
            asperity::core::testdata::reference_file(&format!("frf/brb-force-control-level{l}.csv"))
        })
        .collect();
    read_sweeps(&files?).ok()
}

fn stated_of_json(v: &serde_json::Value) -> Vec<Stated> {
    v["uncertainty"]["intervals"]
        .as_array()
        .unwrap()
        .iter()
        .map(|i| Stated {
            name: i["name"].as_str().unwrap().to_string(),
            value: i["value"].as_f64().unwrap(),
            interval: i["lo_95"].as_f64().zip(i["hi_95"].as_f64()),
        })
        .collect()
}

fn held_out_errors_of_json(v: &serde_json::Value) -> Vec<(String, f64, f64)> {
    v["errors_after"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|e| e["role"] == "predicted")
        .map(|e| {
            (
                e["file"].as_str().unwrap().to_string(),
                100.0 * e["peak_error"].as_f64().unwrap(),
                100.0 * e["rms_complex"].as_f64().unwrap(),
            )
        })
        .collect()
}

/// The fast default on the four shared Brake–Reuss levels (fit on levels 1 and 4) finds the
/// committed thorough model's effects, every parameter inside the thorough 95 % interval (and
/// the thorough values inside the fast intervals), the predicted levels' errors within 0.5
/// percentage points of the thorough ones.
#[test]
fn fast_default_on_the_brake_reuss_levels_lies_within_the_thorough_intervals() {
    let Some(sweeps) = brake_reuss_sweeps() else {
        return;
    };
    let thorough = committed_thorough();
    let fast = identify(sweeps, &Options::new(Family::Jenkins), None).unwrap();
    eprint!("{}", fast.text());
    let effects: Vec<&str> = fast
        .after
        .model
        .spec
        .effects
        .iter()
        .map(|e| e.id())
        .collect();
    let committed: Vec<&str> = thorough["final"]["fit"]["model"]["spec"]["effects"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e.as_str().unwrap())
        .collect();
    assert_eq!(effects, committed);
    let a = stated(&fast);
    let b = stated_of_json(&thorough);
    for (x, y) in a.iter().zip(&b) {
        eprintln!(
            "{:<44} fast {:.6e} {:?}   thorough {:.6e} {:?}",
            x.name, x.value, x.interval, y.value, y.interval
        );
    }
    assert_inside_each_other(&a, &b, "Brake–Reuss");
    assert_errors_within_half_a_point(&held_out_errors(&fast), &held_out_errors_of_json(&thorough));
}

/// The thorough search itself on the shared levels against the fast default (over 20
/// CPU-minutes; `cargo test --release --test identify_fast -- --ignored`).
#[test]
#[ignore]
fn fast_default_matches_a_thorough_run_on_the_brake_reuss_levels() {
    let Some(sweeps) = brake_reuss_sweeps() else {
        return;
    };
    let fast = identify(sweeps.clone(), &Options::new(Family::Jenkins), None).unwrap();
    let thorough = identify(sweeps, &Options::thorough(Family::Jenkins), None).unwrap();
    eprintln!(
        "fast {:.1} s, thorough {:.1} s",
        fast.wall_time_s, thorough.wall_time_s
    );
    assert_eq!(fast.after.model.spec, thorough.after.model.spec);
    assert_inside_each_other(&stated(&fast), &stated(&thorough), "Brake–Reuss");
    assert_errors_within_half_a_point(&held_out_errors(&fast), &held_out_errors(&thorough));
}
