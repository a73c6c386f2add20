//! Report of a diagnosis: text, JSON, a CSV of the time series and PNG figures (measured,
//! before, after; residual against the noise floor), every file written atomically.
//!
//! Units: displacement m (figures in nm, µm or mm, whichever suits the amplitude), force N,
//! energy J, stiffness N/m. Residuals are given in N and as multiples of the noise floor σ.
//! The baseline's slip force is reported in N; a friction coefficient `μ` only when the normal
//! load is known (a measured normal-force column, or a calibration table's `N = p·A`).

use super::cycles::Phase;
use super::noise::{NoiseFloor, CYCLES_FOR_DRIFT_FREE_FLOOR};
use super::residual::PhaseStats;
use super::select::{
    Candidate, Character, Diagnosis, Errors, FitInfo, Round, SwappedSplit, Verdict, ADEQUATE_RATIO,
};
use super::stationarity::{Stationarity, Trend, MIN_DEGREES_OF_FREEDOM};
use super::{Bound, Effect};
use crate::core::error::{Error, Result};
use crate::core::output::{write_atomic, write_string_atomic};
use crate::core::plot::{length_unit, line_plot, LinePlot, Scale, Series};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Description of the input, carried into every output.
#[derive(Debug, Clone, Serialize)]
pub struct InputInfo {
    /// Path of the measured record as given.
    pub file: String,
    /// Names of the record's columns used (time, displacement, force, and normal force if any).
    pub columns: Vec<String>,
    /// How columns were derived from what was measured (acceleration integrated, force from a
    /// mass), one line each; empty when read as they are.
    pub derived: Vec<String>,
    /// Baseline description, e.g. "fitted to the training cycles" or the table and pressure.
    pub baseline_source: String,
}

/// The baseline element as reported: stiffnesses in N/m, slip force in N; the normal load and
/// friction coefficient only when the normal load is known.
#[derive(Debug, Clone, Serialize)]
pub struct BaselineReport {
    /// Initial-loading tangential stiffness `E0` of the baseline Valanis element (N/m).
    pub e0_n_per_m: f64,
    /// Valanis shape parameter `k`, `0 ≤ k < 1` (dimensionless): the reload slope after a reversal
    /// is `2E0/(1+k)`.
    pub k: f64,
    /// Residual (post-slip) tangential stiffness `Et` (N/m), `0 ≤ Et < E0`.
    pub et_n_per_m: f64,
    /// Slip force `μ·N` of the baseline (N).
    pub slip_force_n: f64,
    /// Normal load `N` (N), when it is known (a measured normal-force column or a table's `p·A`).
    pub normal_load_n: Option<f64>,
    /// Friction coefficient `μ` (dimensionless), when the normal load is known.
    pub friction_coefficient: Option<f64>,
    /// Fitted parameters on a bound.
    pub at_bound: Vec<(String, Bound)>,
}

/// Zero-force plateaus found in the measured force.
#[derive(Debug, Clone, Serialize)]
pub struct ClearanceSummary {
    /// Half-cycles in which a zero-force plateau was found.
    pub half_cycles_with_plateau: usize,
    /// Half-cycles of the record in all.
    pub half_cycles: usize,
    /// Mean displacement span of the plateaus: the free play (m).
    pub mean_free_play_m: f64,
}

/// The JSON report.
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    /// The measured record and the baseline's source.
    pub input: InputInfo,
    /// Samples of the (block-averaged) record analysed.
    pub samples_analysed: usize,
    /// Block-averaging factor applied to the input record (1: none).
    pub block_average_factor: usize,
    /// Complete displacement cycles found.
    pub complete_cycles: usize,
    /// 0-based cycles the models were fitted on (even ones).
    pub training_cycles: Vec<usize>,
    /// 0-based cycles the models were scored on (odd ones).
    pub held_out_cycles: Vec<usize>,
    /// Mean cycle period (s).
    pub period_s: f64,
    /// Mean displacement amplitude, half the mean peak-to-peak stroke (m).
    pub amplitude_m: f64,
    /// Force amplitude used to make residuals and parameters dimensionless (N): half the 0.5–99.5 %
    /// range of the measured force.
    pub force_scale_n: f64,
    /// Noise floor of the measured force.
    pub noise: NoiseFloor,
    /// The baseline Valanis element.
    pub baseline: BaselineReport,
    /// Convergence of the baseline's fit.
    pub baseline_fit: FitInfo,
    /// What characterises the baseline's residual.
    pub residual_before: Character,
    /// What characterises the final model's residual.
    pub residual_after: Character,
    /// Zero-force plateaus (free play) found in the measured force, if any.
    pub clearance: Option<ClearanceSummary>,
    /// Trends of slip force, stiffness and loop area over the cycles.
    pub stationarity: Stationarity,
    /// The effect search's rounds, in order.
    pub rounds: Vec<Round>,
    /// Effects added, in order.
    pub effects_added: Vec<Effect>,
    /// What the search concluded.
    pub verdict: Verdict,
    /// The conclusion in words, as printed at the end of the text report.
    pub conclusion: String,
    /// Fitted parameters of the effects added, with units: `(effect, name (unit), value)`.
    pub final_effect_parameters: Vec<(Effect, String, f64)>,
    /// Fitted parameters of the baseline.
    pub parameters_before: usize,
    /// Fitted parameters of the final model.
    pub parameters_after: usize,
    /// Error measures of the baseline.
    pub errors_before: Errors,
    /// Error measures of the final model.
    pub errors_after: Errors,
    /// Baseline and final model refitted on the held-out cycles, scored on the training cycles
    /// (which chose nothing); `None` when no effect was added.
    pub swapped_split: Option<SwappedSplit>,
    /// 1 − nrms_after / nrms_before.
    pub nrms_reduction: f64,
}

/// A length in the unit that suits it, e.g. `1.59 mm`, `85 nm`.
fn length(v: f64) -> String {
    let (f, u) = length_unit(v);
    format!("{:.3} {u}", v * f)
}

fn opt(v: Option<f64>, prec: usize) -> String {
    v.map_or("—".to_string(), |x| format!("{x:.prec$}"))
}

/// The share of the excess residual an effect explains, in words. `None`: the relevance test
/// was not run (the model before it had no excess over the noise floor overall), so the share
/// is not known — never "all".
fn explained_words(fraction: Option<f64>) -> String {
    fraction.map_or(
        "share of the excess residual not tested (the model before it was at the noise floor \
         overall)"
            .to_string(),
        |e| format!("explains {:.0} % of the excess residual", 100.0 * e),
    )
}

impl Report {
    /// The report of a diagnosis of the record described by `input`.
    pub fn new(d: &Diagnosis, input: InputInfo) -> Self {
        let p = &d.prepared;
        let nc = p.cycles.cycles.len();
        let added = d.effects_added();
        let b = d.baseline.baseline;
        let clearance = (!d.clearances.is_empty()).then(|| ClearanceSummary {
            half_cycles_with_plateau: d.clearances.len(),
            half_cycles: p.cycles.half_cycles.len(),
            mean_free_play_m: d.clearances.iter().map(|c| c.span_m).sum::<f64>()
                / d.clearances.len() as f64,
        });
        let mut r = Self {
            input,
            samples_analysed: p.record.len(),
            block_average_factor: p.decimation,
            complete_cycles: nc,
            training_cycles: (0..nc).step_by(2).collect(),
            held_out_cycles: (1..nc).step_by(2).collect(),
            period_s: p.cycles.period_s,
            amplitude_m: p.cycles.amplitude_m,
            force_scale_n: p.drive.force_scale_n,
            noise: p.noise.clone(),
            baseline: BaselineReport {
                e0_n_per_m: b.valanis.e0,
                k: b.valanis.k,
                et_n_per_m: b.valanis.et,
                slip_force_n: b.slip_force_n(),
                normal_load_n: d.normal_load_known.then_some(b.normal_n),
                friction_coefficient: d.normal_load_known.then_some(b.valanis.mu),
                at_bound: d.baseline_at_bound.clone(),
            },
            baseline_fit: d.baseline_fit.clone(),
            residual_before: d.before.clone(),
            residual_after: d.after.clone(),
            clearance,
            stationarity: d.stationarity.clone(),
            rounds: d.rounds.clone(),
            effects_added: added,
            verdict: d.verdict,
            conclusion: String::new(),
            final_effect_parameters: d
                .final_model
                .effects
                .iter()
                .flat_map(|(e, v)| {
                    e.params(&p.drive)
                        .into_iter()
                        .zip(v.clone())
                        .map(move |(s, x)| (*e, format!("{} ({})", s.name, s.unit), x))
                })
                .collect(),
            parameters_before: d.n_parameters_before,
            parameters_after: d.n_parameters_after,
            errors_before: d.errors_before,
            errors_after: d.errors_after,
            swapped_split: d.swapped_split,
            nrms_reduction: 1.0 - d.errors_after.nrms / d.errors_before.nrms,
        };
        r.conclusion = r.conclusion_text();
        r
    }

    /// The accepted candidates, in order.
    fn accepted(&self) -> Vec<&Candidate> {
        self.rounds
            .iter()
            .filter_map(|r| {
                let e = r.accepted?;
                r.candidates.iter().find(|c| c.effect == e)
            })
            .collect()
    }

    fn effect_sentence(c: &Candidate) -> String {
        let params: Vec<String> = c
            .parameters
            .iter()
            .map(|(n, v)| {
                if n.ends_with("(m)") {
                    format!("{} = {}", n.trim_end_matches(" (m)"), length(*v))
                } else {
                    format!("{n} = {v:.4e}")
                }
            })
            .collect();
        format!(
            "{} ({}; z = {:.0}, {}; {})",
            c.effect.id(),
            params.join(", "),
            c.evidence_z,
            explained_words(c.explained_fraction),
            c.effect.meaning()
        )
    }

    /// The verdict in words (module documentation of [`super::select`]).
    fn conclusion_text(&self) -> String {
        let sigma = self.noise.sigma_n;
        let after = &self.residual_after;
        let r = after.held_out_rms_over_noise;
        let found: Vec<String> = self
            .accepted()
            .into_iter()
            .map(Self::effect_sentence)
            .collect();
        // A floor set by slow, cycle-to-cycle scatter is that of any periodic model, not of the
        // measurement: say so beside every verdict.
        let fast = self.noise.high_pass_n;
        let caveat = if fast > 0.0 && fast < 0.5 * sigma {
            format!(
                "; note: the record is not repeatable cycle to cycle — its scatter σ is {:.1}× \
                 the fast measurement noise ({fast:.3e} N), so the floor is that of any \
                 periodic model, not of the instrument",
                sigma / fast
            )
        } else {
            String::new()
        };
        let short_floor = if self.noise.from_first_differences() {
            format!(
                "; note: the noise floor compares only two cycles (first differences), in which \
                 a drift does not cancel, so σ may be too large; {} complete cycles at the same \
                 stroke are needed to tell noise from drift",
                CYCLES_FOR_DRIFT_FREE_FLOOR
            )
        } else {
            String::new()
        };
        let verdict = match self.verdict {
            Verdict::ModelAdequate => format!(
                "model adequate: the baseline's held-out residual is {r:.2}× the noise floor \
                 (σ = {sigma:.4e} N){}; no effect larger than about {ADEQUATE_RATIO}σ RMS was \
                 looked for (the candidate search runs only above {ADEQUATE_RATIO}× the noise \
                 floor): smaller effects were not tested",
                worst(after)
            ),
            Verdict::RecordTooShort => format!(
                "record too short to tell noise from drift: the noise floor (σ = {sigma:.4e} N) \
                 comes from first differences across two cycles, in which a drift from cycle to \
                 cycle does not cancel, so σ may be inflated by drift; against it the \
                 baseline's held-out residual is {r:.2}×{}; {} complete cycles at the same \
                 stroke are needed (the record has {}); no verdict on adequacy, and no effect \
                 search",
                worst(after),
                CYCLES_FOR_DRIFT_FREE_FLOOR,
                self.complete_cycles
            ),
            Verdict::EffectsFound => format!(
                "effect(s) found: {}; the held-out residual is now {r:.2}× the noise floor \
                 (σ = {sigma:.4e} N){}",
                found.join("; then "),
                worst(after)
            ),
            Verdict::ModelInadequate => {
                let mut s = format!(
                    "model inadequate, residual unexplained: the held-out residual is {r:.1}× \
                     the noise floor (σ = {sigma:.4e} N){}",
                    worst(after)
                );
                let shares: Vec<String> = after
                    .concentrated_at
                    .iter()
                    .filter_map(|ph| after.phases.iter().find(|p| p.phase == *ph))
                    .map(|p| {
                        format!(
                            "{} ({:.0} % of the excess in {} samples, {:.1}× σ)",
                            p.phase.description(),
                            100.0 * p.excess_share,
                            p.samples,
                            p.rms_over_noise.unwrap_or(f64::NAN)
                        )
                    })
                    .collect();
                s += &if shares.is_empty() {
                    "; spread over the whole loop".to_string()
                } else {
                    format!("; concentrated {}", shares.join(" and "))
                };
                s += &match &after.ringing {
                    Some(ri) => format!(
                        "; periodic: ringing at {:.3} Hz, damping ratio {}, {:.3e} N RMS \
                         (a lightly damped mode in the load path)",
                        ri.frequency_hz,
                        opt(ri.damping_ratio, 3),
                        ri.rms_n
                    ),
                    None => "; no ringing".to_string(),
                };
                s += &if self.stationarity.drifts() {
                    format!("; drifts: {}", self.stationarity.findings.join("; "))
                } else if self.stationarity.testable {
                    "; no drift".to_string()
                } else {
                    let dof = self.stationarity.degrees_of_freedom();
                    format!(
                        "; drift not testable ({} steady cycle(s): the trend test has {dof} \
                         degree(s) of freedom, {MIN_DEGREES_OF_FREEDOM} needed, i.e. {} cycles)",
                        self.stationarity.cycles.len(),
                        MIN_DEGREES_OF_FREEDOM + 2
                    )
                };
                if !found.is_empty() {
                    s += &format!("; explained in part by {}", found.join("; then "));
                }
                s
            }
        };
        let short_floor = if self.verdict == Verdict::RecordTooShort {
            String::new()
        } else {
            short_floor
        };
        verdict + &caveat + &short_floor
    }

    /// Findings beside the verdict: drift, clearance, noise notes.
    pub fn findings(&self) -> Vec<String> {
        let mut v: Vec<String> = self
            .stationarity
            .findings
            .iter()
            .map(|f| format!("drift: {f}"))
            .collect();
        if let Some(c) = &self.clearance {
            v.push(format!(
                "clearance: the measured force has a zero-force plateau in {} of {} half-cycles; \
                 free play {}",
                c.half_cycles_with_plateau,
                c.half_cycles,
                length(c.mean_free_play_m)
            ));
        }
        v.extend(self.noise.notes.iter().map(|n| format!("noise: {n}")));
        if let Some(alias) = self.offset_alias() {
            v.push(alias);
        }
        if let Some(w) = self.swapped_split_warning() {
            v.push(w);
        }
        v
    }

    /// The swapped split's warning for this report ([`selection_warning`]).
    fn swapped_split_warning(&self) -> Option<String> {
        selection_warning(
            self.errors_before.held_out_rms_over_noise,
            self.errors_after.held_out_rms_over_noise,
            self.swapped_split?,
        )
    }

    /// Direction-dependent friction `c_d = 1 + d·sign(ẋ)` moves both slip plateaus by
    /// `d·F_slip`, which is what a load-cell zero offset `F₀ = d·F_slip` does in macroslip; the
    /// two differ only in stick and microslip (the offset shifts them too, the asymmetry does
    /// not). An offset is not a candidate (it would be chosen about as often: with it, the
    /// measured 1.5 in record took an offset of 1076 N before the asymmetry), so
    /// the report names the alias wherever the asymmetry is accepted.
    fn offset_alias(&self) -> Option<String> {
        let c = self
            .accepted()
            .into_iter()
            .find(|c| c.effect == Effect::DirectionalFriction)?;
        let d = c.parameters.first()?.1;
        Some(format!(
            "alias: a load-cell zero offset of d·F_slip = {:.3e} N would look the same in \
             macroslip (both move the two slip plateaus by that force); only the stick and \
             microslip phases tell them apart, and an offset is not among the candidates: \
             check the force channel's zero before reading d = {d:.3} as friction",
            d * self.baseline.slip_force_n
        ))
    }

    /// Human-readable report.
    pub fn text(&self) -> String {
        let mut s = String::new();
        let b = &self.baseline;
        s += "asperity diagnose — model versus measured hysteresis\n\n";
        s += &format!(
            "input: {} (columns: {})\n",
            self.input.file,
            self.input.columns.join(", ")
        );
        for d in &self.input.derived {
            s += &format!("  {d}\n");
        }
        s += &format!(
            "analysed: {} samples (block average ×{}), {} complete cycles, period {:.4} s, \
             amplitude {}, force amplitude {:.4e} N\n",
            self.samples_analysed,
            self.block_average_factor,
            self.complete_cycles,
            self.period_s,
            length(self.amplitude_m),
            self.force_scale_n
        );
        s += &format!(
            "fit on cycles {:?}, scored on held-out cycles {:?}\n\n",
            self.training_cycles, self.held_out_cycles
        );
        let nf = &self.noise;
        s += &format!(
            "noise floor σ = {:.4e} N (cycle-to-cycle repeatability, {} differences across {} \
             cycles{}); high-pass cross-check {:.4e} N; noise lag-1 autocorrelation {:.2}\n",
            nf.sigma_n,
            nf.repeatability_samples,
            nf.across_cycles,
            nf.relative_standard_error
                .map_or(String::new(), |se| format!(
                    ", standard error ±{:.0} %",
                    100.0 * se
                )),
            nf.high_pass_n,
            nf.lag1_autocorrelation
        );
        for n in &nf.notes {
            s += &format!("  note: {n}\n");
        }
        s += &format!(
            "\nbaseline Valanis element ({}): E0 = {:.4e} N/m, k = {:.4}, Et = {:.4e} N/m, \
             slip force = {:.4e} N",
            self.input.baseline_source, b.e0_n_per_m, b.k, b.et_n_per_m, b.slip_force_n
        );
        s += &match (b.normal_load_n, b.friction_coefficient) {
            (Some(n), Some(mu)) => format!(" (normal load {n:.4e} N, μ = {mu:.4})\n"),
            _ => " (normal load not known: no friction coefficient)\n".to_string(),
        };
        for (name, bound) in &b.at_bound {
            s += &format!("  {name} is on its {} bound\n", bound.name());
        }
        s += &format!(
            "  fit: {} iterations, final cost {:.3e}, converged {}, {:.2} s\n\n",
            self.baseline_fit.iterations,
            self.baseline_fit.final_cost,
            self.baseline_fit.converged,
            self.baseline_fit.wall_time_s
        );
        s += &format!(
            "residual before (measured − baseline, held-out cycles): RMS {:.2}× the noise floor\n",
            self.residual_before.held_out_rms_over_noise
        );
        s += &phase_table(&self.residual_before.phases);
        for (r, round) in self.rounds.iter().enumerate() {
            s += &format!(
                "\nround {}: candidate effects, scored on the held-out cycles (accepted when \
                 z ≥ {}, explaining ≥ {:.0} % of the excess, better in every held-out cycle, \
                 no parameter on a bound)\n",
                r + 1,
                super::select::EVIDENCE_Z,
                100.0 * super::select::MIN_EXPLAINED
            );
            s += &format!(
                "  {:<28} {:>3} {:>9} {:>9} {:>9} {:>7}  {:<44} parameters\n",
                "effect", "Δp", "held/σ", "z", "explains", "cycles", "decision"
            );
            let mut cands: Vec<&Candidate> = round.candidates.iter().collect();
            cands.sort_by(|a, b| b.delta_rss.total_cmp(&a.delta_rss));
            for c in cands {
                let params: Vec<String> = c
                    .parameters
                    .iter()
                    .map(|(n, v)| {
                        let mark = c
                            .at_bound
                            .iter()
                            .find(|(m, _)| m == n)
                            .map_or(String::new(), |(_, b)| format!(" [{} bound]", b.name()));
                        format!("{n} = {v:.4e}{mark}")
                    })
                    .collect();
                s += &format!(
                    "  {:<28} {:>3} {:>9.2} {:>9.1} {:>9} {:>7}  {:<44} {}\n",
                    c.effect.id(),
                    c.extra_parameters,
                    c.held_out_rms_over_noise,
                    c.evidence_z,
                    c.explained_fraction
                        .map_or("—".to_string(), |e| format!("{:.0} %", 100.0 * e)),
                    format!("{}/{}", c.improved_cycles.0, c.improved_cycles.1),
                    c.decision,
                    params.join(", ")
                );
            }
            s += &match round.accepted {
                Some(e) => format!("  → accepted: {} ({})\n", e.id(), e.meaning()),
                None => "  → no candidate passes\n".to_string(),
            };
        }
        s += &format!("\nverdict: {}\n", self.verdict.name());
        s += &format!("conclusion: {}\n", self.conclusion);
        for (e, name, v) in &self.final_effect_parameters {
            s += &format!("  {}: {name} = {v:.4e}\n", e.id());
        }
        let findings = self.findings();
        if !findings.is_empty() {
            s += "findings:\n";
            for f in findings {
                s += &format!("  {f}\n");
            }
        }
        s += &format!(
            "\nstationarity over the cycles at the steady amplitude {:?} (baseline fitted to each \
             cycle alone; Student-t trend test, 1 % level, reported when the change is ≥ 5 %):\n",
            self.stationarity.cycles
        );
        s += &trend_table(&self.stationarity);
        s += "\n";
        s += &format!(
            "errors (all complete cycles)     before       after\n\
             normalised RMS force error  {:>11.4e} {:>11.4e}\n\
             peak force error            {:>11.4e} {:>11.4e}\n\
             energy-per-cycle error      {:>11.4e} {:>11.4e}\n\
             held-out normalised RMS     {:>11.4e} {:>11.4e}\n\
             held-out RMS / noise floor  {:>11.2} {:>11.2}\n\
             {}\
             parameters                  {:>11} {:>11}\n\
             RMS error reduction: {:.1} %\n",
            self.errors_before.nrms,
            self.errors_after.nrms,
            self.errors_before.peak_force_error,
            self.errors_after.peak_force_error,
            self.errors_before.energy_error,
            self.errors_after.energy_error,
            self.errors_before.held_out_nrms,
            self.errors_after.held_out_nrms,
            self.errors_before.held_out_rms_over_noise,
            self.errors_after.held_out_rms_over_noise,
            self.swapped_split.map_or(String::new(), |sw| format!(
                "swapped split RMS / noise   {:>11.2} {:>11.2}   (refitted on the held-out \
                 cycles, scored on the training cycles; the held-out cycles chose the effects)\n",
                sw.before_rms_over_noise, sw.after_rms_over_noise
            )),
            self.parameters_before,
            self.parameters_after,
            100.0 * self.nrms_reduction
        );
        if !self.effects_added.is_empty() {
            s += "\nresidual after (measured − final model, held-out cycles):\n";
            s += &phase_table(&self.residual_after.phases);
        }
        s
    }
}

/// The held-out cycles chose the effects and also give the "after" error, so that error is
/// optimistic; the swapped split ([`SwappedSplit`]) is not. Where the gain the swapped split
/// shows (in RMS over the noise floor) is less than a quarter of the held-out gain
/// `held_before − held_after`, a finding says so.
fn selection_warning(held_before: f64, held_after: f64, sw: SwappedSplit) -> Option<String> {
    let held_gain = held_before - held_after;
    let swapped_gain = sw.before_rms_over_noise - sw.after_rms_over_noise;
    if swapped_gain >= 0.25 * held_gain {
        return None;
    }
    let how = if swapped_gain <= 0.0 {
        "does not carry over"
    } else {
        "carries over only in part"
    };
    Some(format!(
        "selection: the effects' gain on the held-out cycles that chose them ({held_before:.2}σ \
         → {held_after:.2}σ) {how} to the swapped split (refitted on those cycles, scored on the \
         training cycles: {:.2}σ → {:.2}σ); read the effects as fitted to this record, not as \
         established",
        sw.before_rms_over_noise, sw.after_rms_over_noise
    ))
}

/// ", at most 1.4× in any phase" / ", 3.1× in microslip".
fn worst(c: &Character) -> String {
    match c.worst_phase {
        Some((ph, r)) if c.adequate => format!(", at most {r:.1}× in any phase ({})", ph.name()),
        Some((ph, r)) => format!(", {r:.1}× {}", ph.description()),
        None => String::new(),
    }
}

fn phase_table(stats: &[PhaseStats]) -> String {
    let mut s = format!(
        "  {:<10} {:>8} {:>13} {:>13} {:>8} {:>14}\n",
        "phase", "samples", "mean (N)", "rms (N)", "rms/σ", "excess share"
    );
    let e = |v: Option<f64>| v.map_or("—".to_string(), |x| format!("{x:.4e}"));
    for p in stats {
        if p.samples == 0 && matches!(p.phase, Phase::Clearance | Phase::Closing) {
            continue;
        }
        s += &format!(
            "  {:<10} {:>8} {:>13} {:>13} {:>8} {:>13.0}%\n",
            p.phase.name(),
            p.samples,
            e(p.mean_residual_n),
            e(p.rms_residual_n),
            opt(p.rms_over_noise, 2),
            100.0 * p.excess_share
        );
    }
    s
}

fn trend_table(st: &Stationarity) -> String {
    let row = |t: &Trend| {
        let vals: Vec<String> = t.per_cycle.iter().map(|v| format!("{v:.4e}")).collect();
        format!(
            "  {:<28} {}  change {:+.1} %, t = {:.1} (critical {}){}\n",
            t.name,
            vals.join(" "),
            100.0 * t.relative_change,
            t.t,
            opt(t.t_critical, 2),
            if t.drift { "  DRIFT" } else { "" }
        )
    };
    row(&st.slip_force) + &row(&st.stiffness) + &row(&st.loop_area)
}

/// Paths of the files written by [`write`](fn@write).
#[derive(Debug, Clone)]
pub struct Outputs {
    /// The text report.
    pub text: PathBuf,
    /// The JSON report ([`Report`]).
    pub json: PathBuf,
    /// The time series: displacement, measured, baseline and final forces, residuals and phase.
    pub csv: PathBuf,
    /// Figure of the measured, baseline and final loops.
    pub loops_png: PathBuf,
    /// Figure of the residuals against the noise floor.
    pub residual_png: PathBuf,
}

impl Outputs {
    /// The names of the files, without a directory.
    pub fn file_names() -> [&'static str; 5] {
        [
            "diagnose.txt",
            "diagnose.json",
            "diagnose.csv",
            "diagnose-loops.png",
            "diagnose-residual.png",
        ]
    }

    /// Files `diagnose.{txt,json,csv}`, `diagnose-loops.png`, `diagnose-residual.png` in `dir`.
    pub fn in_dir(dir: &Path) -> Self {
        let [text, json, csv, loops_png, residual_png] = Self::file_names().map(|n| dir.join(n));
        Self {
            text,
            json,
            csv,
            loops_png,
            residual_png,
        }
    }
}

/// Write the report, the time series and the figures (each file atomically).
pub fn write(d: &Diagnosis, report: &Report, out: &Outputs) -> Result<()> {
    let p = &d.prepared;
    let (t, x, y) = (
        &p.record.time_s,
        &p.record.displacement_m,
        &p.record.force_n,
    );
    let json = serde_json::to_string_pretty(report)
        .map_err(|e| Error::Data(format!("serialising the report: {e}")))?;
    write_string_atomic(&out.json, &json)?;
    write_string_atomic(&out.text, &report.text())?;
    write_atomic(&out.csv, |w| {
        let io = |e| Error::io(&out.csv, e);
        writeln!(
            w,
            "# asperity diagnose: {}; baseline {}; effects added: {}; verdict: {}; noise floor {:.6e} N",
            report.input.file,
            report.input.baseline_source,
            if report.effects_added.is_empty() {
                "none".to_string()
            } else {
                report
                    .effects_added
                    .iter()
                    .map(|e| e.id())
                    .collect::<Vec<_>>()
                    .join(", ")
            },
            report.verdict.name(),
            report.noise.sigma_n
        )
        .map_err(io)?;
        writeln!(
            w,
            "time_s,displacement_m,measured_force_N,baseline_force_N,final_force_N,\
             residual_before_N,residual_after_N,phase"
        )
        .map_err(io)?;
        let phases = d.phases();
        for i in 0..t.len() {
            writeln!(
                w,
                "{:.9e},{:.9e},{:.9e},{:.9e},{:.9e},{:.9e},{:.9e},{}",
                t[i],
                x[i],
                y[i],
                d.baseline_force[i],
                d.final_force[i],
                y[i] - d.baseline_force[i],
                y[i] - d.final_force[i],
                phases[i].map_or("outside_cycles", |ph| ph.name())
            )
            .map_err(io)?;
        }
        Ok(())
    })?;
    // Loops over the complete cycles, displacement in the unit that suits the amplitude.
    let (a, b) = (
        p.cycles.cycles[0].0,
        p.cycles.cycles.last().map_or(t.len() - 1, |c| c.1),
    );
    let xmax = (a..=b).fold(0.0_f64, |m, i| m.max(x[i].abs()));
    let (scale, unit) = length_unit(xmax);
    let pts = |f: &[f64]| -> Vec<(f64, f64)> { (a..=b).map(|i| (x[i] * scale, f[i])).collect() };
    let after_label = if report.effects_added.is_empty() {
        "after (no effect added)".to_string()
    } else {
        format!(
            "after: + {}",
            report
                .effects_added
                .iter()
                .map(|e| e.id())
                .collect::<Vec<_>>()
                .join(" + ")
        )
    };
    let title = format!(
        "{}: residual {:.1}σ → {:.1}σ (σ = {:.3e} N)",
        report.verdict.name(),
        report.errors_before.held_out_rms_over_noise,
        report.errors_after.held_out_rms_over_noise,
        report.noise.sigma_n
    );
    let x_label = format!("displacement ({unit})");
    line_plot(
        &out.loops_png,
        &LinePlot {
            title: &title,
            x_label: &x_label,
            y_label: "tangential force (N)",
            x_scale: Scale::Linear,
            y_scale: Scale::Linear,
        },
        &[
            Series::line("measured", pts(y)),
            Series::line("before: baseline Valanis", pts(&d.baseline_force)),
            Series::line(after_label.clone(), pts(&d.final_force)),
        ],
    )?;
    let res = |f: &[f64]| -> Vec<(f64, f64)> { (a..=b).map(|i| (t[i], y[i] - f[i])).collect() };
    let two_sigma = 2.0 * report.noise.sigma_n;
    let band = |s: f64| vec![(t[a], s * two_sigma), (t[b], s * two_sigma)];
    line_plot(
        &out.residual_png,
        &LinePlot {
            title: "residual: measured − model, against twice the noise floor",
            x_label: "time (s)",
            y_label: "force residual (N)",
            x_scale: Scale::Linear,
            y_scale: Scale::Linear,
        },
        &[
            Series::line("before", res(&d.baseline_force)),
            Series::line(after_label, res(&d.final_force)),
            Series::line("+2σ noise floor", band(1.0)),
            Series::line("−2σ noise floor", band(-1.0)),
        ],
    )?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The swapped split's warning: none when at least a quarter of the held-out gain carries
    /// over, "only in part" below that, "does not carry over" with no gain or a loss.
    #[test]
    fn selection_warning_follows_the_share_of_the_gain_that_carries_over() {
        let sw = |b, a| SwappedSplit {
            before_rms_over_noise: b,
            after_rms_over_noise: a,
        };
        // Held-out gain 4σ (8 → 4).
        assert!(selection_warning(8.0, 4.0, sw(9.0, 7.0)).is_none());
        assert!(selection_warning(8.0, 4.0, sw(9.0, 8.0)).is_none()); // exactly a quarter
        let w = selection_warning(8.0, 4.0, sw(9.0, 8.5)).unwrap();
        assert!(w.contains("carries over only in part"), "{w}");
        assert!(
            w.contains("8.00σ → 4.00σ") && w.contains("9.00σ → 8.50σ"),
            "{w}"
        );
        let w = selection_warning(8.0, 4.0, sw(9.0, 9.2)).unwrap();
        assert!(w.contains("does not carry over"), "{w}");
    }

    /// Without a relevance test (no excess over the floor before the effect) the share an
    /// effect explains is unknown: the report must say so, never "explains all".
    #[test]
    fn an_untested_share_is_not_all_of_the_excess() {
        let none = explained_words(None);
        assert!(
            none.contains("not tested") && !none.contains("explains all"),
            "{none}"
        );
        assert_eq!(
            explained_words(Some(0.76)),
            "explains 76 % of the excess residual"
        );
    }
}
