//! Report of a diagnosis: text, JSON, a CSV of the time series and PNG figures (measured,
//! before, after), every file written atomically.
//!
//! Units: displacement m (figures in mm), force N, energy J, stiffness N/m. Error measures are
//! dimensionless (see [`super::select::Errors`]).

use super::cycles::classify_phases;
use super::select::{Candidate, Diagnosis, Errors, FitInfo, PhaseStats, Round};
use super::{Baseline, Effect};
use crate::error::{Error, Result};
use crate::output::{write_atomic, write_string_atomic};
use crate::plot::{line_plot, LinePlot, Scale, Series};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Description of the input, carried into every output.
#[derive(Debug, Clone, Serialize)]
pub struct InputInfo {
    pub file: String,
    pub columns: Vec<String>,
    /// Baseline description, e.g. "fitted to the training cycles" or the table and pressure.
    pub baseline_source: String,
}

/// The JSON report.
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    pub input: InputInfo,
    pub samples_analysed: usize,
    pub block_average_factor: usize,
    pub complete_cycles: usize,
    pub training_cycles: Vec<usize>,
    pub held_out_cycles: Vec<usize>,
    pub period_s: f64,
    pub amplitude_m: f64,
    pub force_scale_n: f64,
    pub baseline: Baseline,
    pub baseline_fit: FitInfo,
    pub residual_before: Vec<PhaseStats>,
    pub residual_after: Vec<PhaseStats>,
    pub rounds: Vec<Round>,
    /// Effects added, in order; empty means "no effect needed".
    pub effects_added: Vec<Effect>,
    pub conclusion: String,
    pub final_model: super::Model,
    /// Fitted parameters of the effects added, with units: `(effect, name (unit), value)`.
    pub final_effect_parameters: Vec<(Effect, String, f64)>,
    pub parameters_before: usize,
    pub parameters_after: usize,
    pub errors_before: Errors,
    pub errors_after: Errors,
    /// 1 − nrms_after / nrms_before.
    pub nrms_reduction: f64,
}

impl Report {
    pub fn new(d: &Diagnosis, input: InputInfo) -> Self {
        let p = &d.prepared;
        let nc = p.cycles.cycles.len();
        let added = d.effects_added();
        let conclusion = conclusion(&added, &d.rounds);
        Self {
            input,
            samples_analysed: p.record.len(),
            block_average_factor: p.decimation,
            complete_cycles: nc,
            training_cycles: (0..nc).step_by(2).collect(),
            held_out_cycles: (1..nc).step_by(2).collect(),
            period_s: p.cycles.period_s,
            amplitude_m: p.cycles.amplitude_m,
            force_scale_n: p.drive.force_scale_n,
            baseline: d.baseline.baseline,
            baseline_fit: d.baseline_fit.clone(),
            residual_before: d.phases_before.clone(),
            residual_after: d.phases_after.clone(),
            rounds: d.rounds.clone(),
            effects_added: added,
            conclusion,
            final_model: d.final_model.clone(),
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
            nrms_reduction: 1.0 - d.errors_after.nrms / d.errors_before.nrms,
        }
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
        s += &format!(
            "analysed: {} samples (block average ×{}), {} complete cycles, period {:.4} s, \
             amplitude {:.4e} m, force amplitude {:.4e} N\n",
            self.samples_analysed,
            self.block_average_factor,
            self.complete_cycles,
            self.period_s,
            self.amplitude_m,
            self.force_scale_n
        );
        s += &format!(
            "fit on cycles {:?}, scored on held-out cycles {:?}\n\n",
            self.training_cycles, self.held_out_cycles
        );
        s += &format!(
            "baseline Valanis element ({}): E0 = {:.4e} N/m, k = {:.4}, Et = {:.4e} N/m, \
             mu = {:.4e}, N = {:.4e} N, slip force mu*N = {:.4e} N\n",
            self.input.baseline_source,
            b.valanis.e0,
            b.valanis.k,
            b.valanis.et,
            b.valanis.mu,
            b.normal_n,
            b.slip_force_n()
        );
        s += &format!(
            "  fit: {} iterations, final cost {:.3e}, converged {}, {:.2} s\n\n",
            self.baseline_fit.iterations,
            self.baseline_fit.final_cost,
            self.baseline_fit.converged,
            self.baseline_fit.wall_time_s
        );
        s += "residual before (measured − baseline, / force amplitude; mean signed with the \
              direction of motion):\n";
        s += &phase_table(&self.residual_before);
        for (r, round) in self.rounds.iter().enumerate() {
            s += &format!(
                "\nround {}: candidate effects (ΔBIC on held-out cycles; accepted when < {})\n",
                r + 1,
                super::select::BIC_THRESHOLD
            );
            s += &format!(
                "  {:<28} {:>3} {:>11} {:>11} {:>8} {:>10}  parameters\n",
                "effect", "Δp", "train nrms", "held nrms", "n_eff", "ΔBIC"
            );
            let mut cands: Vec<&Candidate> = round.candidates.iter().collect();
            cands.sort_by(|a, b| a.delta_bic.total_cmp(&b.delta_bic));
            for c in cands {
                let params: Vec<String> = c
                    .parameters
                    .iter()
                    .map(|(n, v)| format!("{n} = {v:.4e}"))
                    .collect();
                s += &format!(
                    "  {:<28} {:>3} {:>11.4e} {:>11.4e} {:>8.1} {:>10.1}  {}\n",
                    c.effect.id(),
                    c.extra_parameters,
                    c.train_nrms,
                    c.held_out_nrms,
                    c.n_eff,
                    c.delta_bic,
                    params.join(", ")
                );
            }
            s += &match round.accepted {
                Some(e) => format!("  → accepted: {} ({})\n", e.id(), e.meaning()),
                None => "  → no candidate has sufficient evidence: no further effect needed\n"
                    .to_string(),
            };
        }
        s += &format!("\nconclusion: {}\n", self.conclusion);
        for (e, name, v) in &self.final_effect_parameters {
            s += &format!("  {}: {name} = {v:.4e}\n", e.id());
        }
        s += "\n";
        s += &format!(
            "errors (all complete cycles)     before       after\n\
             normalised RMS force error  {:>11.4e} {:>11.4e}\n\
             peak force error            {:>11.4e} {:>11.4e}\n\
             energy-per-cycle error      {:>11.4e} {:>11.4e}\n\
             held-out normalised RMS     {:>11.4e} {:>11.4e}\n\
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
            self.parameters_before,
            self.parameters_after,
            100.0 * self.nrms_reduction
        );
        if !self.effects_added.is_empty() {
            s += "\nresidual after:\n";
            s += &phase_table(&self.residual_after);
        }
        s
    }
}

fn conclusion(added: &[Effect], rounds: &[Round]) -> String {
    if added.is_empty() {
        return "no effect needed: no candidate improves the held-out cycles enough to pay for \
                its parameters"
            .into();
    }
    let parts: Vec<String> = rounds
        .iter()
        .filter_map(|r| {
            let e = r.accepted?;
            let c = r.candidates.iter().find(|c| c.effect == e)?;
            Some(format!(
                "{} (ΔBIC {:.0}; {})",
                e.id(),
                c.delta_bic,
                e.meaning()
            ))
        })
        .collect();
    format!("effect found: {}", parts.join("; then "))
}

fn phase_table(stats: &[PhaseStats]) -> String {
    let mut s = format!(
        "  {:<10} {:>8} {:>14} {:>13}\n",
        "phase", "samples", "mean residual", "rms residual"
    );
    for p in stats {
        s += &format!(
            "  {:<10} {:>8} {:>14.4e} {:>13.4e}\n",
            p.phase.name(),
            p.samples,
            p.mean_residual,
            p.rms_residual
        );
    }
    s
}

/// Paths of the files written by [`write`].
#[derive(Debug, Clone)]
pub struct Outputs {
    pub text: PathBuf,
    pub json: PathBuf,
    pub csv: PathBuf,
    pub loops_png: PathBuf,
    pub residual_png: PathBuf,
}

impl Outputs {
    /// Files `diagnose.{txt,json,csv}`, `diagnose-loops.png`, `diagnose-residual.png` in `dir`.
    pub fn in_dir(dir: &Path) -> Self {
        Self {
            text: dir.join("diagnose.txt"),
            json: dir.join("diagnose.json"),
            csv: dir.join("diagnose.csv"),
            loops_png: dir.join("diagnose-loops.png"),
            residual_png: dir.join("diagnose-residual.png"),
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
            "# asperity diagnose: {}; baseline {}; effects added: {}",
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
            }
        )
        .map_err(io)?;
        writeln!(
            w,
            "time_s,displacement_m,measured_force_N,baseline_force_N,final_force_N,\
             residual_before_N,residual_after_N,phase"
        )
        .map_err(io)?;
        let phases = classify_phases(x, &d.baseline_force, &p.cycles);
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
    // Loops over the complete cycles.
    let (a, b) = (
        p.cycles.cycles[0].0,
        p.cycles.cycles.last().map_or(t.len() - 1, |c| c.1),
    );
    let pts = |f: &[f64]| -> Vec<(f64, f64)> { (a..=b).map(|i| (x[i] * 1e3, f[i])).collect() };
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
        "nrms {:.3} → {:.3}; energy error {:.3} → {:.3}",
        report.errors_before.nrms,
        report.errors_after.nrms,
        report.errors_before.energy_error,
        report.errors_after.energy_error
    );
    line_plot(
        &out.loops_png,
        &LinePlot {
            title: &title,
            x_label: "displacement (mm)",
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
    line_plot(
        &out.residual_png,
        &LinePlot {
            title: "residual: measured − model",
            x_label: "time (s)",
            y_label: "force residual (N)",
            x_scale: Scale::Linear,
            y_scale: Scale::Linear,
        },
        &[
            Series::line("before", res(&d.baseline_force)),
            Series::line(after_label, res(&d.final_force)),
        ],
    )?;
    Ok(())
}
