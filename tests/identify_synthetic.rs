//! Identification of synthetic frequency responses computed by the harmonic-balance solver
//! with known parameters plus 1 % noise: the parameters come back within 2 %, no effect is
//! accepted where none was put in, and the effect put in is the one chosen — in 10 of 10 noise
//! realisations each.

use asperity::element::PowerLawDamper;
use asperity::identify::backbone::resonance;
use asperity::identify::effects::Effect;
use asperity::identify::fit::FitOptions;
use asperity::identify::measured::Sweep;
use asperity::identify::model::{Drive, Family, Model, ModelSpec};
use asperity::identify::select::Verdict;
use asperity::identify::{identify, Options};
use rayon::prelude::*;
use std::f64::consts::TAU;

#[path = "support/synthetic_sweep.rs"]
mod synthetic_sweep;
use synthetic_sweep::{noisy_sweep, SCALES};

/// Truth: f_s = 80 Hz, ζ0 = 0.1 %, m = 2 kg, κ = 2 %, δ = 30 µm (Jenkins joint): the joint is
/// stuck at the lowest level (20 µm) and well into slip at the highest (about 370 µm, 79.2 Hz).
const TRUTH: [f64; 5] = [80.0, 1e-3, 2.0, 0.02, 3e-5];

/// Nominal force of each level (N): the joint stuck, slipping, well slipping.
const LEVELS_N: [f64; 3] = [0.02, 0.15, 0.6];

/// A force-controlled sweep of `model`: 31 rows from 79.0 to 80.5 Hz (the Brake–Reuss beam's
/// 0.05 Hz steps, over a band that holds every level's resonance: 0.1 Hz steps lose the
/// lowest level's peak, 0.16 Hz wide at ζ0 = 0.1 %, and the global search then fails), the force
/// dipping by up to 20 % near 79.6 Hz (as a shaker's does at resonance), acceleration amplitude
/// and phase with 1 % relative amplitude noise and 0.01 rad phase noise.
fn sweep(model: &Model, force: f64, seed: u64) -> Sweep {
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
    let x = model.receptance(&drives, force).unwrap();
    noisy_sweep(
        format!("synthetic-{force}N-{seed}.csv"),
        &drives,
        &x,
        0.01,
        seed,
    )
}

fn options(candidates: Vec<Effect>) -> Options {
    let mut o = Options::thorough(Family::Jenkins);
    o.fit_levels = Some(vec![1, 3]);
    o.select.candidates = candidates;
    o.select.max_effects = 1;
    // Affordable settings: one small swarm for the baseline (beside its start from the data's
    // scales), local refinement only for the candidates (from the baseline optimum with the
    // effect at its neutral value).
    o.select.baseline_fit = FitOptions {
        particles: 12,
        swarm_iterations: 10,
        starts: 1,
        seed: 1,
        local_iterations: 600,
        ..FitOptions::default()
    };
    o.select.candidate_fit = FitOptions {
        starts: 0,
        ..o.select.baseline_fit
    };
    o.response_amplitudes = Some(vec![5.0]);
    // The bands are validated on their own below (`prediction_band_covers_…`).
    o.chain_steps = 0;
    o
}

/// Two candidates that compete for the same misfit (the resonance moving with amplitude, the
/// damping growing with it).
const CANDIDATES: [Effect; 2] = [Effect::AmplitudeStiffness, Effect::QuadraticDamping];

/// The truth with effect `e` added, its parameters `extra`.
fn truth_with(e: Effect, extra: &[f64]) -> Model {
    let mut v = TRUTH.to_vec();
    v.extend(extra);
    Model::new(ModelSpec::baseline(Family::Jenkins, SCALES).with(e), v).unwrap()
}

/// The three levels' sweeps of `truth`, noise seeds `seed + level index`.
fn sweeps(truth: &Model, seed: u64) -> Vec<Sweep> {
    LEVELS_N
        .iter()
        .enumerate()
        .map(|(k, &f)| sweep(truth, f, seed + k as u64))
        .collect()
}

/// The search accepted exactly `effect`.
fn assert_chosen(verdict: &Verdict, effect: Effect, r: u64) {
    match verdict {
        Verdict::EffectsFound { effects, .. } => {
            assert_eq!(effects, &vec![effect], "realisation {r}")
        }
        v => panic!("realisation {r} ({}): {v:?}", effect.id()),
    }
}

/// The strength of `effect` in the identified model is within 10 % of the truth's: the cubic or
/// quadratic stiffness coefficient, or the damper's coefficient.
fn assert_strength(got: &Model, truth: &Model, effect: Effect, r: u64) {
    let strength = |m: &Model| match effect {
        Effect::AmplitudeStiffness => m.cubic_stiffness().unwrap(),
        Effect::QuadraticStiffness => m.quadratic_stiffness().unwrap(),
        _ => m.damper().unwrap().0,
    };
    let (got, want) = (strength(got), strength(truth));
    eprintln!(
        "realisation {r}: {} found, strength {:+.1}%",
        effect.id(),
        100.0 * (got / want - 1.0)
    );
    assert!(
        (got / want - 1.0).abs() < 0.1,
        "realisation {r}: {} strength {got:.4e} vs {want:.4e}",
        effect.id()
    );
}

#[test]
fn parameters_come_back_and_no_effect_is_invented() {
    let truth = Model::new(ModelSpec::baseline(Family::Jenkins, SCALES), TRUTH.to_vec()).unwrap();
    // Realisations in parallel: both cores busy even when this test runs alone.
    (0..10u64).into_par_iter().for_each(|r| {
        let id = identify(sweeps(&truth, 100 * r), &options(CANDIDATES.to_vec()), None).unwrap();
        assert!(
            matches!(id.selection.verdict, Verdict::NoEffectNeeded),
            "realisation {r}: {:?}",
            id.selection.verdict
        );
        let got = &id.after.model.values;
        eprintln!(
            "realisation {r}: relative errors {:?}, J = {:.3e}, {} evaluations",
            got.iter()
                .zip(TRUTH)
                .map(|(g, t)| format!("{:+.2}%", 100.0 * (g / t - 1.0)))
                .collect::<Vec<_>>(),
            id.after.cost,
            id.selection.baseline_train_fit.evaluations
        );
        for ((p, g), t) in id.after.model.spec.params().iter().zip(got).zip(TRUTH) {
            assert!(
                (g / t - 1.0).abs() < 0.02,
                "realisation {r}: {} = {g:.5e}, truth {t:.5e}",
                p.name
            );
        }
        // The level not used is predicted: against the noise-free truth at the same rows and
        // forces, peak within 2 % (the parameters' tolerance) and resonance within 0.01 Hz.
        let l = &id.sweeps[1];
        let drives: Vec<Drive> = l
            .rows
            .iter()
            .map(|r| Drive {
                omega: r.omega(),
                force_n: r.force_n,
            })
            .collect();
        let f: Vec<f64> = l.rows.iter().map(|r| r.frequency_hz).collect();
        let peak = |m: &Model| {
            let x = m.receptance(&drives, l.mean_force_n()).unwrap();
            let a: Vec<f64> = x
                .iter()
                .zip(&drives)
                .map(|(x, d)| x.norm() * d.omega.powi(2))
                .collect();
            resonance(&f, &a)
        };
        let ((ft, pt), (fm, pm)) = (peak(&truth), peak(&id.after.model));
        assert!(
            (pm / pt - 1.0).abs() < 0.02 && (fm - ft).abs() < 0.01,
            "realisation {r}: predicted level: model {fm:.4} Hz {pm:.4}, truth {ft:.4} Hz {pt:.4}"
        );
    });
}

#[test]
fn the_effect_put_in_is_chosen() {
    // Two effects that compete for the same misfit, each put in alone, alternating over the
    // ten noise realisations: hardening, +0.5 % in ω² at 200 µm (k3 = 4·0.005·k_s/(3·A²)),
    // about +0.7 Hz at the highest level; quadratic damping, ζ_q = 0.1 % at 200 µm (the
    // damping doubled there without any loss of stiffness).
    let truths = [
        (Effect::AmplitudeStiffness, 0.005),
        (Effect::QuadraticDamping, 1e-3),
    ]
    .map(|(e, value)| (e, truth_with(e, &[value])));
    // Realisations in parallel: both cores busy even when this test runs alone.
    (0..10u64).into_par_iter().for_each(|r| {
        let (effect, truth) = &truths[r as usize % 2];
        let id = identify(
            sweeps(truth, 1000 + 100 * r),
            &options(CANDIDATES.to_vec()),
            None,
        )
        .unwrap();
        assert_chosen(&id.selection.verdict, *effect, r);
        // The effect's strength comes back within 10 %.
        assert_strength(&id.after.model, truth, *effect, r);
    });
}

#[test]
fn the_damping_law_put_in_is_chosen() {
    // Damping growing as A² (power law p = 2, ζ_p = 0.1 % at 200 µm) in the even realisations,
    // as A (the quadratic damper, ζ_q = 0.1 % at 200 µm) in the odd ones; both laws and
    // hardening offered each time. The power law nests the quadratic damper, so the odd ones
    // test parsimony: its extra exponent must not be taken without held-out evidence. A damping
    // exponent needs three fitted levels: with ζ0, the strength and p unknown, two levels are
    // matched by any exponent (the held-out rows of levels 1 and 3 alone chose the power law in
    // 8 of 10 realisations, p from 1.8 to 2.7).
    let truths = [
        (Effect::PowerLawDamping, vec![1e-3, 2.0]),
        (Effect::QuadraticDamping, vec![1e-3]),
    ]
    .map(|(e, extra)| (e, truth_with(e, &extra)));
    let candidates = vec![
        Effect::AmplitudeStiffness,
        Effect::QuadraticDamping,
        Effect::PowerLawDamping,
    ];
    // Strength as the equivalent damping ratio the damper adds at 200 µm and 80 Hz.
    let zeta_at = |m: &Model| {
        let (c, p) = m.damper().expect("a damping law");
        let w = TAU * 80.0;
        PowerLawDamper::equivalent_viscous(c, p, 2e-4, w) / (2.0 * m.physical().mass_kg * w)
    };
    // Realisations in parallel: both cores busy even when this test runs alone.
    (0..10u64).into_par_iter().for_each(|r| {
        let (effect, truth) = &truths[r as usize % 2];
        let mut o = options(candidates.clone());
        o.fit_levels = Some(vec![1, 2, 3]);
        let id = identify(sweeps(truth, 5000 + 100 * r), &o, None).unwrap();
        assert_chosen(&id.selection.verdict, *effect, r);
        let (got, want) = (zeta_at(&id.after.model), zeta_at(truth));
        let p = id.after.model.damper().unwrap().1;
        eprintln!(
            "realisation {r}: {} found, p = {p:.3}, strength at 200 µm {:+.1}%",
            effect.id(),
            100.0 * (got / want - 1.0)
        );
        // Strength within 15 % and the exponent within 0.35 (1 % noise; the exponent is the
        // least determined parameter: 1.71–2.17 over these realisations).
        assert!(
            (got / want - 1.0).abs() < 0.15,
            "realisation {r}: ζ {got:.4e} vs {want:.4e}"
        );
        if *effect == Effect::PowerLawDamping {
            assert!((p - 2.0).abs() < 0.35, "realisation {r}: p = {p}");
        }
    });
}

#[test]
fn the_stiffness_law_put_in_is_chosen() {
    // A stiffness changing in proportion to the amplitude (quadratic spring, softening: −0.5 %
    // in ω² at 200 µm, k2 = 3π·ε1·k_s/(8·A)) in the even realisations, as its square (cubic
    // spring, hardening +0.5 % at 200 µm) in the odd ones; both offered each time, with the
    // quadratic damper as a third competitor for the misfit. Fit on levels 1 and 3 (the
    // validation protocol): the two laws differ in how the resonance moves between and within the
    // levels, not only in its size at one amplitude.
    let truths = [
        (Effect::QuadraticStiffness, -0.005),
        (Effect::AmplitudeStiffness, 0.005),
    ]
    .map(|(e, value)| (e, truth_with(e, &[value])));
    let candidates = vec![
        Effect::AmplitudeStiffness,
        Effect::QuadraticStiffness,
        Effect::QuadraticDamping,
    ];
    // Realisations in parallel: both cores busy even when this test runs alone.
    (0..10u64).into_par_iter().for_each(|r| {
        let (effect, truth) = &truths[r as usize % 2];
        let id = identify(
            sweeps(truth, 9000 + 100 * r),
            &options(candidates.clone()),
            None,
        )
        .unwrap();
        assert_chosen(&id.selection.verdict, *effect, r);
        assert_strength(&id.after.model, truth, *effect, r);
    });
}

#[test]
fn interacting_stiffness_laws_are_found_together() {
    // Softening ∝ A (ε1 = −1 % in ω² at 200 µm) and hardening ∝ A² (ε2 = +1 %) together: the
    // resonance falls from level 1 to level 2 and rises to level 3, so either law alone moves
    // some level's resonance the wrong way. Fit on all three levels; both laws and the
    // quadratic damper offered, up to two effects. Both must be found, each strength within
    // 10 % (measured: 4.9 % at most), and at least once by the pair step (measured: 10 of 10;
    // with pairs tried only when no single effect passed, realisation 1 ended with the
    // quadratic damper alone; with only the two strongest paired, realisation 3 with nothing).
    let mut v = TRUTH.to_vec();
    v.extend([0.01, -0.01]);
    let spec = ModelSpec::baseline(Family::Jenkins, SCALES)
        .with(Effect::AmplitudeStiffness)
        .with(Effect::QuadraticStiffness);
    let truth = Model::new(spec, v).unwrap();
    let candidates = vec![
        Effect::AmplitudeStiffness,
        Effect::QuadraticStiffness,
        Effect::QuadraticDamping,
    ];
    // Realisations in parallel: both cores busy even when this test runs alone. Each returns
    // whether its effects were accepted as a pair.
    let pairs: Vec<bool> = (0..10u64)
        .into_par_iter()
        .map(|r| {
            let mut o = options(candidates.clone());
            o.fit_levels = Some(vec![1, 2, 3]);
            o.select.max_effects = 2;
            let id = identify(sweeps(&truth, 13000 + 100 * r), &o, None).unwrap();
            for (k, round) in id.selection.rounds.iter().enumerate() {
                for c in &round.candidates {
                    eprintln!(
                        "  round {k}: {}{} ΔBIC {:.1}, every level {}",
                        c.effect.id(),
                        c.jointly_with
                            .map_or(String::new(), |w| format!(" + {}", w.id())),
                        c.delta_bic,
                        c.improves_every_level
                    );
                }
            }
            let found = match &id.selection.verdict {
                Verdict::EffectsFound { effects, .. } => effects.clone(),
                v => panic!("realisation {r}: {v:?}"),
            };
            let pair = id
                .selection
                .rounds
                .iter()
                .any(|k| k.accepted_with.is_some());
            let m = &id.after.model;
            let (k3, k2) = (m.cubic_stiffness(), m.quadratic_stiffness());
            eprintln!(
                "realisation {r}: {:?}{}, k3 {:+.1}%, k2 {:+.1}%",
                found.iter().map(|e| e.id()).collect::<Vec<_>>(),
                if pair { " (as a pair)" } else { "" },
                100.0 * (k3.unwrap_or(0.0) / truth.cubic_stiffness().unwrap() - 1.0),
                100.0 * (k2.unwrap_or(0.0) / truth.quadratic_stiffness().unwrap() - 1.0),
            );
            assert!(
                found.len() == 2
                    && found.contains(&Effect::AmplitudeStiffness)
                    && found.contains(&Effect::QuadraticStiffness),
                "realisation {r}: {found:?}"
            );
            for (got, want) in [
                (k3.unwrap(), truth.cubic_stiffness().unwrap()),
                (k2.unwrap(), truth.quadratic_stiffness().unwrap()),
            ] {
                assert!(
                    (got / want - 1.0).abs() < 0.1,
                    "realisation {r}: {got:.4e} vs {want:.4e}"
                );
            }
            pair
        })
        .collect();
    let jointly = pairs.iter().filter(|&&p| p).count();
    eprintln!("found as a pair in {jointly} of 10 realisations");
    assert!(jointly > 0, "the pair step was never needed");
}

/// The 95 % prediction band is calibrated. Over 20 noise realisations the baseline is fitted on
/// levels 1 and 3 (local search from the truth, all rows), its posterior sampled (two adaptive
/// Metropolis chains of 3000 steps, 200 models kept) and level 2 predicted: the truth's
/// (noise-free) level-2 peak lies inside the band in at least 17 of 20 (at a true 95 %
/// coverage, 16 or fewer happen with probability 1.6 %), and the band's mean half-width is
/// within a factor 1.6 of 1.96 times the spread of the 20 predicted peaks about the truth (the
/// band is neither a rubber bound nor overconfident; the robust spread of 20 samples is itself
/// uncertain by about ±26 %).
#[test]
fn prediction_band_covers_the_truth_at_its_stated_rate() {
    use asperity::identify::fit::{fit_local, LevelData};
    use asperity::identify::measured::PhaseConvention;
    use asperity::identify::uncertainty::{
        parameter_covariance, posterior_ensemble, prediction_bands,
    };
    let spec = ModelSpec::baseline(Family::Jenkins, SCALES);
    let truth = Model::new(spec.clone(), TRUTH.to_vec()).unwrap();
    let fit_opts = FitOptions {
        local_iterations: 600,
        ..options(vec![]).select.baseline_fit
    };
    // Realisations in parallel: both cores busy even when this test runs alone. Each returns
    // whether the band holds the truth's peak, the band's half-width, the predicted peak's
    // error and the truth's peak.
    let results: Vec<(bool, f64, f64, f64)> = (0..20u64)
        .into_par_iter()
        .map(|r| {
        let sw = sweeps(&truth, 5000 + 10 * r);
        let conv = PhaseConvention::detect(&sw).unwrap();
        let levels: Vec<LevelData> = sw.iter().map(|s| LevelData::new(s, &conv)).collect();
        let fit_levels = vec![levels[0].clone(), levels[2].clone()];
        let all: Vec<Vec<bool>> = fit_levels
            .iter()
            .map(|l| vec![true; l.drives.len()])
            .collect();
        let fit = fit_local(
            &spec,
            &fit_levels,
            &all,
            std::slice::from_ref(&TRUTH.to_vec()),
            &fit_opts,
            None,
        )
        .unwrap();
        let cov = parameter_covariance(&fit.model.spec, &fit.model, &fit_levels).unwrap();
        let ensemble =
            posterior_ensemble(&fit.model.spec, &fit.model, &cov, &fit_levels, 200, 3000, r)
                .unwrap();
        let bands = prediction_bands(
            &fit.model.spec,
            &fit.model,
            &ensemble,
            &levels[1..2],
            &["predicted"],
        )
        .unwrap();
        // The truth's peak on the same rows (same forces), without noise.
        let (y, _) = levels[1].model_frf(&truth).unwrap();
        let f: Vec<f64> = levels[1].drives.iter().map(|d| d.omega / TAU).collect();
        let a: Vec<f64> = y.iter().map(|v| v.norm()).collect();
        let truth_peak = resonance(&f, &a).1;
        let b = bands[0].peak;
        let truth_cost =
            asperity::identify::select::cost_all_rows(&truth.spec, &truth, &fit_levels);
        eprintln!(
            "realisation {r}: predicted peak {:.3} [{:.3}, {:.3}], truth {truth_peak:.3}; \
             J {:.3e} (truth's {truth_cost:.3e}), residual sd {:.2e}, rho {:.2}, acceptance {:.2}, R̂ {:.3}",
            b.value,
            b.lo_95,
            b.hi_95,
            fit.cost,
            cov.residual_sd,
            cov.lag1_autocorrelation,
            ensemble.acceptance_rate,
            bands[0].r_hat
        );
        (
            b.contains(truth_peak),
            0.5 * (b.hi_95 - b.lo_95),
            b.value - truth_peak,
            truth_peak,
        )
        })
        .collect();
    let inside = results.iter().filter(|r| r.0).count();
    let half_widths: Vec<f64> = results.iter().map(|r| r.1).collect();
    let errors: Vec<f64> = results.iter().map(|r| r.2).collect();
    let truth_peak = results[19].3;
    // Robust spread of the predicted peaks about the truth: median |error| / 0.6745 (the
    // standard deviation for Gaussian errors; the Jenkins slider's stick–slip kink gives the
    // estimates heavier tails, which the coverage count sees).
    let mut abs: Vec<f64> = errors.iter().map(|e| e.abs()).collect();
    abs.sort_by(f64::total_cmp);
    let spread = 0.5 * (abs[9] + abs[10]) / 0.6745;
    let mean_half = half_widths.iter().sum::<f64>() / half_widths.len() as f64;
    let ratio = mean_half / (1.96 * spread);
    eprintln!(
        "coverage {inside}/20, mean half-width {mean_half:.4} ({:.2} % of the peak), \
         1.96 × robust spread {:.4}: ratio {ratio:.2}",
        100.0 * mean_half / truth_peak,
        1.96 * spread
    );
    assert!(inside >= 17, "coverage {inside}/20");
    assert!(
        (1.0 / 1.6..=1.6).contains(&ratio),
        "half-width / 1.96·spread = {ratio:.2}"
    );
}
