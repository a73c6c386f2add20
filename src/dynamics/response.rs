//! `asperity response` as a library call: the nonlinear forced response of a model file, one
//! frequency sweep per excitation level ([`run`] takes the loaded model file and returns a
//! [`ForcedResponse`]; [`ForcedResponse::write`] writes the command's files into the output set
//! that [`output_set`] declares).
//!
//! The steps, in order:
//!
//! 1. **Settings** from the model file's `[sweep]` ([`ResponseSettings::of_model_file`]): the
//!    harmonic basis ([`Harmonics`]), the formulation and the continuation settings (points
//!    over the span, the cap on a branch's points).
//! 2. **System**: the harmonic-balance problem of the structure with its elements under the
//!    excitation ([`HbmSystem`]); described to the caller's log.
//! 3. **Sweeps**: every level is an independent pseudo-arclength continuation over the span
//!    ([`sweep_partial`]), run concurrently, and summarised: element cycles along the branch and
//!    the peak of the first response ([`report::summarise`]), and the stability of every point
//!    with the bifurcations between them ([`stability::branch_stability`], Hill's method; as
//!    the [`StabilityChoice`] says); [`sweep_level`] is one of them.
//!    A level whose sweep stops early keeps its points (reported with the reason); one whose
//!    first point fails has nothing to report. Either way the other levels are reported; the
//!    run fails only when no level has a point.
//! 4. **Files** ([`ForcedResponse::write`]): per level `response_level_<i>.csv` and
//!    `elements_level_<i>.csv` (`i` the level's 1-based position in the model file), one FRF
//!    plot per response `frf_<label>.png`, and `response.json` (provenance, settings, a summary
//!    per level and the failed levels).

use crate::core::error::{Error, Result};
use crate::core::output::{write_string_atomic, OutputSet};
use crate::dynamics::aft::Harmonics;
use crate::dynamics::continuation::{sweep_partial, ContinuationSettings};
use crate::dynamics::hbm::{Excitation, FormulationChoice, HbmSystem};
use crate::dynamics::model_file::{self, LoadedModel, SweepSection};
use crate::dynamics::report::{self, LevelResult};
use crate::dynamics::stability::{self, StabilityChoice};
use crate::elements::{provenance_json, InputFile};
use nalgebra::DVector;
use rayon::prelude::*;
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};

/// How a level is swept: the harmonic basis, the formulation of the balance and the
/// continuation settings.
#[derive(Clone)]
pub struct ResponseSettings {
    /// Harmonics retained and time samples per period.
    pub harmonics: Harmonics,
    /// Unknowns of the balance: the fewer, the coordinates or the receptance-condensed contact
    /// DOFs.
    pub formulation: FormulationChoice,
    /// Span, points and step control of the continuation.
    pub continuation: ContinuationSettings,
}

impl ResponseSettings {
    /// The settings of a model file's `[sweep]`: its harmonics, formulation, span and points;
    /// the cap on a branch's points is its `max_points`, by default the larger of the
    /// continuation's default and 20 × points.
    pub fn of_model_file(sweep: &SweepSection) -> Result<Self> {
        let harmonics = Harmonics::new(sweep.harmonics, sweep.odd_only, sweep.time_samples)
            .map_err(|e| e.renamed_param("sweep.harmonics / sweep.time_samples"))?;
        let mut continuation =
            ContinuationSettings::new(sweep.frequency_start_hz, sweep.frequency_end_hz);
        continuation.points = sweep.points;
        continuation.max_points = sweep
            .max_points
            .unwrap_or(continuation.max_points.max(20 * sweep.points));
        Ok(Self {
            harmonics,
            formulation: sweep.formulation,
            continuation,
        })
    }
}

/// The output set of a run of the model file `model` into `out_dir` (`flag` names it in
/// errors), declared before any work: the level CSVs, the FRF plots and `response.json`; the
/// model file and every file it names are inputs that no output may be or remove.
pub fn output_set(model: &Path, out_dir: &Path, flag: &str) -> Result<OutputSet> {
    let mut out = OutputSet::in_dir(out_dir, flag)?;
    for (prefix, suffix) in [
        ("response_level_", ".csv"),
        ("elements_level_", ".csv"),
        ("frf_", ".png"),
        ("loops_level_", ".csv"),
        ("loops_level_", ".png"),
    ] {
        out.owns(prefix, suffix)?;
    }
    out.writes(&["response.json"])?;
    model_file::declare_inputs(&mut out, model)?;
    Ok(out)
}

/// One level: the continuation over the settings' span at excitation `level_n` (N), kept up to
/// where it stopped ([`sweep_partial`]), summarised with the peak of the response `peak_row`
/// ([`report::summarise`]), with the stability of its points when Hill's problem is small
/// ([`StabilityChoice::Auto`]). `progress(fraction)` follows the span covered.
pub fn sweep_level(
    system: &HbmSystem<'_>,
    level_n: f64,
    settings: &ContinuationSettings,
    peak_row: &DVector<f64>,
    progress: &mut dyn FnMut(f64),
) -> Result<LevelResult> {
    sweep_level_with(
        system,
        level_n,
        settings,
        peak_row,
        StabilityChoice::Auto,
        progress,
    )
}

/// [`sweep_level`] with the stability of every point assessed as `stability` says
/// ([`crate::dynamics::stability`]; in [`LevelResult::stability`]).
pub fn sweep_level_with(
    system: &HbmSystem<'_>,
    level_n: f64,
    settings: &ContinuationSettings,
    peak_row: &DVector<f64>,
    stability: StabilityChoice,
    progress: &mut dyn FnMut(f64),
) -> Result<LevelResult> {
    let branch = sweep_partial(system, level_n, settings, progress)?;
    let mut result = report::summarise(system, level_n, branch, peak_row);
    if stability.assesses(system) {
        result.stability = Some(stability::branch_stability(system, &result.branch)?);
    }
    Ok(result)
}

/// What `asperity response` computed: the system and a result per level that has points.
pub struct ForcedResponse<'a> {
    /// The model file, loaded.
    pub model: &'a LoadedModel,
    /// The settings of the sweeps.
    pub settings: ResponseSettings,
    /// The harmonic-balance problem.
    pub system: HbmSystem<'a>,
    /// The levels with points, in the model file's order.
    pub results: Vec<LevelResult>,
    /// The 1-based position of each result's level in the model file (its files' number).
    pub numbers: Vec<usize>,
    /// Levels that stopped early (their points are in [`Self::results`]) or have no point,
    /// with the reason.
    pub failures: Vec<String>,
    /// How the stability was to be assessed, and whether it was.
    pub stability: serde_json::Value,
}

/// Sweep every excitation level of `model` (steps in the [module documentation](self)), with the
/// stability of the points assessed as `stability` says.
/// `progress` makes the progress bar for a length (1000 per level); `log` takes the description
/// of the system before the sweeps. Errors: invalid settings or system, or no level with a
/// point (naming each level's failure).
pub fn run<'a>(
    model: &'a LoadedModel,
    stability: StabilityChoice,
    progress: &dyn Fn(u64) -> indicatif::ProgressBar,
    log: &mut dyn FnMut(&str),
) -> Result<ForcedResponse<'a>> {
    let f = &model.file;
    let settings = ResponseSettings::of_model_file(&f.sweep)?;
    // A static force is balanced in the coordinates formulation.
    let formulation = match (&model.static_force, settings.formulation) {
        (Some(_), FormulationChoice::Auto) => FormulationChoice::Coordinates,
        (_, choice) => choice,
    };
    let mut system = HbmSystem::new(
        &model.structure,
        settings.harmonics.clone(),
        Excitation {
            force: model.force.clone(),
            harmonic: f.excitation.harmonic,
            force_sin: model.force_sin.clone(),
        },
        formulation,
    )?;
    if let Some(f0) = &model.static_force {
        system = system
            .with_static_force(f0)
            .map_err(|e| e.renamed_param("static (sweep.formulation = \"receptance\")"))?;
    }
    log(&format!(
        "{} coordinates ({:?}), {} elements ({} contact DOFs{}); harmonics {:?}, {} samples per period; formulation: {:?} with {} unknowns",
        model.structure.n(),
        model.structure.kind,
        model.structure.elements.len(),
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
    ));
    if let Some(c) = system.cyclic() {
        log(&format!(
            "cyclic sector: {} sectors, engine order {}, inter-sector phase {:.4} rad; harmonic index per harmonic {}",
            c.sectors,
            c.engine_order,
            c.phase(),
            system
                .harmonics
                .orders()
                .iter()
                .map(|&h| format!("{h}→{}", c.harmonic_index(h)))
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    let assessed = stability.assesses(&system);
    log(&format!(
        "stability (Hill's method, {0} × {0} companion matrix per point): {1}",
        stability::companion_size(&system),
        match (stability, assessed) {
            (_, true) => "assessed at every point",
            _ if system.cyclic().is_some() => {
                "not assessed: not implemented for a cyclic sector (Hill's method would see \
                 perturbations of the solution's harmonic indices only)"
            }
            (StabilityChoice::Off, false) => "not assessed (--stability off)",
            _ => "not assessed: the matrix is large and its eigen-solve would dominate the run (--stability on to assess)",
        }
    ));
    let levels = &f.excitation.levels_n;
    let bar = progress((levels.len() * 1000) as u64);
    bar.set_message(format!("{} levels", levels.len()));
    // The levels are independent sweeps: they run concurrently (rayon tasks; the element loop
    // inside each evaluation is parallel too and rayon shares the cores between both), so the
    // slow gross-slip level overlaps the fast microslip ones. Progress: the sum of the levels'
    // fractions of their span.
    let covered: Vec<AtomicU64> = levels.iter().map(|_| AtomicU64::new(0)).collect();
    let outcomes: Vec<Result<LevelResult>> = levels
        .par_iter()
        .enumerate()
        .map(|(i, &level)| {
            sweep_level_with(
                &system,
                level,
                &settings.continuation,
                &model.responses[0].1,
                if assessed {
                    StabilityChoice::On
                } else {
                    StabilityChoice::Off
                },
                &mut |frac| {
                    covered[i].store((frac * 1000.0) as u64, Ordering::Relaxed);
                    bar.set_position(covered.iter().map(|p| p.load(Ordering::Relaxed)).sum());
                },
            )
        })
        .collect();
    bar.finish_and_clear();
    let mut failures: Vec<String> = Vec::new();
    let mut results = Vec::new();
    let mut numbers = Vec::new();
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
    Ok(ForcedResponse {
        model,
        settings,
        stability: serde_json::json!({
            "choice": stability,
            "assessed": assessed,
            "companion_size": stability::companion_size(&system),
            "auto_max_companion": stability::AUTO_MAX_COMPANION,
            "unstable_tolerance_per_omega": stability::UNSTABLE_TOLERANCE,
        }),
        system,
        results,
        numbers,
        failures,
    })
}

/// A level's stability summary in `response.json`: the method, the unstable points, the
/// bifurcations named between points, the eigen-solves' largest backward error and the time.
fn stability_json(st: &stability::BranchStability) -> serde_json::Value {
    serde_json::json!({
        "method": "Hill (harmonic balance Jacobian, smallest |Im| sorting)",
        "unstable_points": st.unstable_points(),
        "bifurcations": st.bifurcations,
        "max_schur_residual": st.max_schur_residual(),
        "wall_time_s": st.wall_time_s,
    })
}

/// A response label as a file-name part: ASCII letters, digits, `.` and `-` kept, anything
/// else `_`.
fn file_safe(label: &str) -> String {
    label
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '.' || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

impl ForcedResponse<'_> {
    /// Points of a level at which an element's AFT state did not become periodic, and the
    /// largest relative periodicity error.
    pub fn periodicity(&self, r: &LevelResult) -> (usize, f64) {
        (
            r.branch
                .non_periodic_points(self.system.aft.periodicity_tolerance),
            crate::dynamics::aft::worst_periodicity_error(
                r.branch.points.iter().map(|p| p.periodicity_error),
            ),
        )
    }

    /// Write the command's files into the output set `out` (declared by [`output_set`]; step 4
    /// of the [module documentation](self)).
    pub fn write(&self, out: &mut OutputSet) -> Result<()> {
        let (model, system) = (self.model, &self.system);
        let header = format!(
            "asperity {} response: model {}; {:?} formulation, {} unknowns; harmonics {:?}, {} samples per period",
            env!("CARGO_PKG_VERSION"),
            model.path.display(),
            system.formulation(),
            system.unknowns(),
            system.harmonics.orders(),
            system.harmonics.n_time()
        );
        let mut level_summaries = Vec::new();
        for (number, r) in self.numbers.iter().zip(&self.results) {
            let csv = out.path(&format!("response_level_{number}.csv"))?;
            report::write_level_csv(&csv, system, &model.responses, r, &header)?;
            let el = out.path(&format!("elements_level_{number}.csv"))?;
            report::write_elements_csv(&el, system, r)?;
            // Every element's loop at the level's largest computed point.
            let peak_point = &r.branch.points[r.peak];
            let loops = super::loops::element_loops(system, peak_point);
            let loops_csv = out.path(&format!("loops_level_{number}.csv"))?;
            super::loops::write_loops_csv(&loops_csv, &loops, peak_point, &header)?;
            super::loops::plot_loops(
                &out.path(&format!("loops_level_{number}_displacement.png"))?,
                &out.path(&format!("loops_level_{number}_acceleration.png"))?,
                &loops,
                6,
                &format!(
                    "Level {} N at {:.2} Hz: the six elements dissipating most",
                    r.level_n,
                    peak_point.omega / std::f64::consts::TAU
                ),
            )?;
            let (non_periodic, worst) = self.periodicity(r);
            let pk = r.interpolated_peak;
            level_summaries.push(serde_json::json!({
                "level_N": r.level_n,
                "csv": out.final_path(&csv).display().to_string(),
                "elements_csv": out.final_path(&el).display().to_string(),
                "loops_csv": out.final_path(&loops_csv).display().to_string(),
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
                "stability": r.stability.as_ref().map(stability_json),
            }));
        }
        for (k, (label, row)) in model.responses.iter().enumerate() {
            let png = out.path(&format!("frf_{}.png", file_safe(label)))?;
            report::plot_frf_family(&png, system, label, row, &self.results, k == 0)?;
        }
        let inputs: Vec<InputFile> = model
            .inputs
            .iter()
            .map(|(role, p)| InputFile::new(role, p))
            .collect::<Result<_>>()?;
        let mut parameters = serde_json::json!({
            "model": serde_json::to_value(&model.file).map_err(|e| Error::Data(e.to_string()))?,
            "harmonics": system.harmonics.orders(),
            "time_samples": system.harmonics.n_time(),
            "formulation": system.formulation(),
            "unknowns": system.unknowns(),
            "coordinates": model.structure.kind,
            "newton": system.newton,
            "aft": system.aft,
            "continuation": self.settings.continuation,
            "stability": self.stability,
        });
        if let Some(c) = system.cyclic() {
            parameters["cyclic"] = serde_json::json!({
                "sectors": c.sectors,
                "engine_order": c.engine_order,
                "inter_sector_phase_rad": c.phase(),
                "harmonic_index": system
                    .harmonics
                    .orders()
                    .iter()
                    .map(|&h| serde_json::json!({"harmonic": h, "index": c.harmonic_index(h)}))
                    .collect::<Vec<_>>(),
            });
        }
        let json = provenance_json(
            "response",
            &inputs,
            parameters,
            serde_json::json!({
                "elements": model.structure.elements.len(),
                "elements_out_of_calibration_range": model.out_of_range,
                "levels": level_summaries,
                "failed_levels": self.failures,
            }),
        );
        write_string_atomic(
            &out.path("response.json")?,
            &serde_json::to_string_pretty(&json).map_err(|e| Error::Data(e.to_string()))?,
        )
    }
}
