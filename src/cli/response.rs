//! `asperity response`: nonlinear forced response of a model file (HBM + AFT + continuation).

use asperity::core::output::{write_string_atomic, OutputSet};
use asperity::dynamics::aft::Harmonics;
use asperity::dynamics::continuation::{sweep_partial, ContinuationSettings};
use asperity::dynamics::hbm::{Excitation, HbmSystem};
use asperity::dynamics::model_file;
use asperity::dynamics::report::{self, LevelResult};
use asperity::elements::{provenance_json, InputFile};
use asperity::{Error, Result};
use rayon::prelude::*;
use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};

/// Frequency response of a structure with contact elements: multi-harmonic balance with the
/// alternating frequency–time method and pseudo-arclength continuation, one sweep per excitation
/// level of the model file.
#[derive(clap::Args)]
pub struct ResponseArgs {
    /// Model file (TOML: linear part, element tables and node pairs, excitation, sweep).
    model: PathBuf,
    /// Output directory (CSV per level, element CSV at each peak, FRF PNG, response.json).
    #[arg(long, default_value = "out/response")]
    out_dir: PathBuf,
}

pub fn run(args: ResponseArgs) -> Result<()> {
    // Every output appears together or not at all; an unusable --out-dir is refused now.
    let mut out = OutputSet::in_dir(&args.out_dir, "--out-dir")?;
    for (prefix, suffix) in [
        ("response_level_", ".csv"),
        ("elements_level_", ".csv"),
        ("frf_", ".png"),
    ] {
        out.owns(prefix, suffix)?;
    }
    out.writes(&["response.json"])?;
    // The model file and every file it names are inputs: none may be written over or removed
    // (checked before the model is built and swept).
    for (role, p) in model_file::referenced_files(&args.model)? {
        out.input(&p, &format!("{role} of {}", args.model.display()))?;
    }
    let model = model_file::load(&args.model)?;
    let f = &model.file;
    let harmonics = Harmonics::new(f.sweep.harmonics, f.sweep.odd_only, f.sweep.time_samples)
        .map_err(|e| super::rename_param(e, "sweep.harmonics / sweep.time_samples"))?;
    let system = HbmSystem::new(
        &model.structure,
        harmonics,
        Excitation {
            force: model.force.clone(),
            harmonic: f.excitation.harmonic,
        },
        f.sweep.formulation,
    )?;
    let mut settings =
        ContinuationSettings::new(f.sweep.frequency_start_hz, f.sweep.frequency_end_hz);
    settings.points = f.sweep.points;
    settings.max_points = f
        .sweep
        .max_points
        .unwrap_or(settings.max_points.max(20 * f.sweep.points));
    let n_el = model.structure.elements.len();
    println!(
        "{} coordinates ({:?}), {} elements ({} contact DOFs{}); harmonics {:?}, {} samples per period; formulation: {:?} with {} unknowns",
        model.structure.n(),
        model.structure.kind,
        n_el,
        model.structure.contact_dofs(),
        if model.out_of_range > 0 {
            format!(", {} outside their calibration table's range", model.out_of_range)
        } else {
            String::new()
        },
        system.harmonics.orders(),
        system.harmonics.n_time(),
        system.formulation(),
        system.unknowns()
    );
    let levels = f.excitation.levels_n.clone();
    let bar = super::progress_bar("response", (levels.len() * 1000) as u64);
    bar.set_message(format!("{} levels", levels.len()));
    // The levels are independent sweeps: they run concurrently (rayon tasks; the element loop
    // inside each evaluation is parallel too and rayon shares the cores between both), so the
    // slow gross-slip level overlaps the fast microslip ones. Progress: the sum of the levels'
    // fractions of their span. A level whose sweep stops early keeps its points (written, and
    // reported with the reason); one whose first point fails has nothing to write. Either way
    // the other levels are written, and the run ends with an error naming the levels.
    let progress: Vec<AtomicU64> = levels.iter().map(|_| AtomicU64::new(0)).collect();
    let outcomes: Vec<Result<LevelResult>> = levels
        .par_iter()
        .enumerate()
        .map(|(i, &level)| {
            let branch = sweep_partial(&system, level, &settings, &mut |frac| {
                progress[i].store((frac * 1000.0) as u64, Ordering::Relaxed);
                bar.set_position(progress.iter().map(|p| p.load(Ordering::Relaxed)).sum());
            })?;
            Ok(report::summarise(
                &system,
                level,
                branch,
                &model.responses[0].1,
            ))
        })
        .collect();
    bar.finish_and_clear();
    let mut failures: Vec<String> = Vec::new();
    let mut results: Vec<LevelResult> = Vec::new();
    // 1-based position of each result's level in the model file (its files' number).
    let mut numbers: Vec<usize> = Vec::new();
    for (i, (&level, outcome)) in levels.iter().zip(outcomes).enumerate() {
        match outcome {
            Ok(r) => {
                if let Some(why) = &r.branch.stopped {
                    failures.push(format!(
                        "level {level} N: {why} (the points up to there are written)"
                    ));
                }
                results.push(r);
                numbers.push(i + 1);
            }
            Err(e) => failures.push(format!("level {level} N: nothing computed: {e}")),
        }
    }
    if results.is_empty() {
        return Err(Error::Data(failures.join("; ")));
    }
    // Everything computed: write the files.
    let header = format!(
        "asperity {} response: model {}; {:?} formulation, {} unknowns; harmonics {:?}, {} samples per period",
        env!("CARGO_PKG_VERSION"),
        args.model.display(),
        system.formulation(),
        system.unknowns(),
        system.harmonics.orders(),
        system.harmonics.n_time()
    );
    let mut level_summaries = Vec::new();
    for (&number, r) in numbers.iter().zip(&results) {
        let csv = out.path(&format!("response_level_{number}.csv"))?;
        report::write_level_csv(&csv, &system, &model.responses, r, &header)?;
        let el = out.path(&format!("elements_level_{number}.csv"))?;
        report::write_elements_csv(&el, &system, r)?;
        let tol = system.aft.periodicity_tolerance;
        let non_periodic = r.branch.non_periodic_points(tol);
        let worst = asperity::dynamics::aft::worst_periodicity_error(
            r.branch.points.iter().map(|p| p.periodicity_error),
        );
        if non_periodic > 0 {
            println!(
                "warning: level {} N: at {non_periodic} of {} points an element's AFT state did not become periodic within {} periods (largest relative periodicity error {worst:.2e}, tolerance {tol:.0e}); their element forces are those of the last period integrated (column aft_periodicity_error)",
                r.level_n,
                r.branch.points.len(),
                system.aft.max_periods
            );
        }
        let pk = r.interpolated_peak;
        println!(
            "level {} N: {} points, peak {:.6e} m at {:.4} Hz ({}, interpolated), energy/cycle at the largest point {:.4e} J, slip {:.3}, separation {:.3}; {} steps rejected, {} kinks, {} turning points, {:.2} s{}",
            r.level_n,
            r.branch.points.len(),
            pk.amplitude_m,
            pk.frequency_hz,
            model.responses[0].0,
            r.totals[r.peak][0],
            r.totals[r.peak][2],
            r.totals[r.peak][3],
            r.branch.rejected_steps,
            r.branch.kinks,
            r.branch.turning_points,
            r.branch.wall_time_s,
            if r.branch.stopped.is_some() { "; INCOMPLETE" } else { "" }
        );
        if pk.at_sweep_end {
            println!(
                "warning: level {} N: the largest amplitude is at the end of the sweep ({:.4} Hz): the peak may lie outside the span; widen it",
                r.level_n, pk.frequency_hz
            );
        }
        level_summaries.push(serde_json::json!({
            "level_N": r.level_n,
            "csv": out.final_path(&csv).display().to_string(),
            "elements_csv": out.final_path(&el).display().to_string(),
            "points": r.branch.points.len(),
            "complete": r.branch.stopped.is_none(),
            "stopped": r.branch.stopped,
            "peak_frequency_Hz": pk.frequency_hz,
            "peak_amplitude_m": pk.amplitude_m,
            "peak_at_sweep_end": pk.at_sweep_end,
            "largest_point_frequency_Hz": r.branch.points[r.peak].omega / (2.0 * std::f64::consts::PI),
            "peak_dissipated_energy_J": r.totals[r.peak][0],
            "peak_slip_fraction": r.totals[r.peak][2],
            "peak_separation_fraction": r.totals[r.peak][3],
            "rejected_steps": r.branch.rejected_steps,
            "turning_points": r.branch.turning_points,
            "kinks": r.branch.kinks,
            "jacobians": r.branch.jacobians,
            "max_relative_residual": r.branch.points.iter().map(|p| p.residual).fold(0.0, f64::max),
            "max_periodicity_error": worst,
            "points_not_periodic": non_periodic,
            "wall_time_s": r.branch.wall_time_s,
        }));
    }
    for (k, (label, row)) in model.responses.iter().enumerate() {
        let safe: String = label
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || c == '.' || c == '-' {
                    c
                } else {
                    '_'
                }
            })
            .collect();
        let png = out.path(&format!("frf_{safe}.png"))?;
        report::plot_frf_family(&png, &system, label, row, &results, k == 0)?;
    }
    let inputs: Vec<InputFile> = model
        .inputs
        .iter()
        .map(|(role, p)| InputFile::new(role, p))
        .collect::<Result<_>>()?;
    let json = provenance_json(
        "response",
        &inputs,
        serde_json::json!({
            "model": serde_json::to_value(f).map_err(|e| Error::Data(e.to_string()))?,
            "harmonics": system.harmonics.orders(),
            "time_samples": system.harmonics.n_time(),
            "formulation": system.formulation(),
            "unknowns": system.unknowns(),
            "coordinates": model.structure.kind,
            "newton": system.newton,
            "aft": system.aft,
            "continuation": settings,
        }),
        serde_json::json!({
            "elements": n_el,
            "elements_out_of_calibration_range": model.out_of_range,
            "levels": level_summaries,
            "failed_levels": failures,
        }),
    );
    write_string_atomic(
        &out.path("response.json")?,
        &serde_json::to_string_pretty(&json).map_err(|e| Error::Data(e.to_string()))?,
    )?;
    out.commit()?;
    println!("wrote {}", args.out_dir.display());
    if !failures.is_empty() {
        return Err(Error::Data(format!(
            "{} of {} levels did not complete: {}",
            failures.len(),
            levels.len(),
            failures.join("; ")
        )));
    }
    Ok(())
}
