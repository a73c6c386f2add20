//! The commands `asperity identify` and `asperity predict` as library functions: a config with
//! one field per flag goes in, a report comes out. The CLI parses its flags into the config and
//! prints the report; Python's `asperity.identify` and `asperity.predict` call the same
//! functions.
//!
//! Each command runs in two steps so that a caller can show progress: [`prepare_identify`]
//! (or [`prepare_predict`]) checks the settings, declares the output set and reads the
//! measured files — every error of the inputs is raised here, before any fit — then the
//! prepared run's `run` fits or predicts, and the outcome's `write` writes the command's files
//! through the output set (all appear or none).

use super::effects::Effect;
use super::measured::Sweep;
use super::model::Family;
use super::pipeline::{choose_fit_levels, identify, read_sweeps, FitRows, Identification, Options};
use super::predict::{choose_control, model_inputs, predict, Control, Prediction};
use super::reduced::{
    identify_reduced, EffectSearch, ReducedIdentification, ReducedOptions, ReducedSpec,
    REDUCED_EFFECTS,
};
use super::report::LevelErrors;
use super::uncertainty::{ParameterInterval, Uncertainty};
use crate::core::error::{Error, Result};
use crate::core::output::OutputSet;
use std::path::{Path, PathBuf};

/// The parameters of `asperity identify`, one per flag (the flag's name is in each field's
/// errors). [`IdentifyConfig::new`] gives the command's defaults.
#[derive(Debug, Clone, PartialEq)]
pub struct IdentifyConfig {
    /// Measured sweeps, one file per level (levels are numbered by increasing mean force).
    pub files: Vec<PathBuf>,
    /// Levels to fit on (1-based, by increasing mean force); `None`: lowest and highest.
    pub fit_levels: Option<Vec<usize>>,
    /// Joint element of the baseline model (single nonlinear mode only).
    pub family: Family,
    /// Candidate effect ids to test (`["none"]`: no search); `None`: all.
    pub candidates: Option<Vec<String>>,
    /// Maximum number of effects added.
    pub max_effects: usize,
    /// The thorough search (single nonlinear mode only).
    pub thorough: bool,
    /// Particle-swarm starts of the baseline fit; `None`: the search's default.
    pub starts: Option<usize>,
    /// Particles of the swarm; `None`: the default.
    pub particles: Option<usize>,
    /// Swarm iterations per start; `None`: the default.
    pub swarm_iterations: Option<u64>,
    /// Nelder–Mead iteration cap per run (up to five parameters); `None`: the default.
    pub local_iterations: Option<u64>,
    /// Seed of the first start (start k uses seed + k).
    pub seed: u64,
    /// Response amplitudes of the response-controlled FRFs (unit of the lowest level's
    /// quantity); `None`: the measured peak responses.
    pub response_amplitude: Option<Vec<f64>>,
    /// Steps of each Metropolis chain of the prediction bands (0: none, else ≥ 1000); `None`:
    /// the default.
    pub chain_steps: Option<usize>,
    /// Rows of the fit levels to fit.
    pub rows: FitRows,
    /// Response-model file of a multi-DOF reduced model to update instead of the single mode.
    pub structure: Option<PathBuf>,
}

impl IdentifyConfig {
    /// The command's defaults for `files`.
    pub fn new(files: Vec<PathBuf>) -> Self {
        Self {
            files,
            fit_levels: None,
            family: Family::Jenkins,
            candidates: None,
            max_effects: 3,
            thorough: false,
            starts: None,
            particles: None,
            swarm_iterations: None,
            local_iterations: None,
            seed: 1,
            response_amplitude: None,
            chain_steps: None,
            rows: FitRows::All,
            structure: None,
        }
    }

    /// The search settings within the resource limits (before anything is read or fitted).
    pub fn check(&self) -> Result<()> {
        use crate::core::limits::*;
        check_count("--starts", self.starts.unwrap_or(0), MAX_FIT_STARTS)?;
        check_count("--particles", self.particles.unwrap_or(0), MAX_PARTICLES)?;
        check_count(
            "--swarm-iterations",
            self.swarm_iterations.unwrap_or(0) as usize,
            MAX_SWARM_ITERATIONS as usize,
        )?;
        check_count(
            "--local-iterations",
            self.local_iterations.unwrap_or(0) as usize,
            MAX_LOCAL_ITERATIONS as usize,
        )?;
        check_count(
            "--chain-steps",
            self.chain_steps.unwrap_or(0),
            MAX_CHAIN_STEPS,
        )?;
        if let Some(a) = &self.response_amplitude {
            if let Some(v) = a.iter().find(|v| !(v.is_finite() && **v > 0.0)) {
                return Err(Error::param(
                    "--response-amplitude",
                    format!("amplitudes must be finite and > 0, got {v}"),
                ));
            }
        }
        Ok(())
    }

    /// `chain_steps`, checked: 0 (no bands) or at least 1000.
    fn checked_chain_steps(&self) -> Result<Option<usize>> {
        match self.chain_steps {
            Some(n) if n != 0 && n < 1000 => Err(Error::param(
                "--chain-steps",
                format!("{n} (0 for no bands, or at least 1000)"),
            )),
            n => Ok(n),
        }
    }

    /// The swarm and Nelder–Mead settings of `particles`, `swarm_iterations`,
    /// `local_iterations` and `seed` applied to `fit` (those not given keep its values).
    fn apply_search(&self, fit: super::fit::FitOptions) -> super::fit::FitOptions {
        super::fit::FitOptions {
            particles: self.particles.unwrap_or(fit.particles),
            swarm_iterations: self.swarm_iterations.unwrap_or(fit.swarm_iterations),
            local_iterations: self.local_iterations.unwrap_or(fit.local_iterations),
            seed: self.seed,
            ..fit
        }
    }
}

/// The search settings must allow a swarm.
fn check_search(starts: usize, particles: usize) -> Result<()> {
    if starts == 0 || particles < 2 {
        return Err(Error::param(
            "--starts/--particles",
            "at least one start and two particles",
        ));
    }
    Ok(())
}

/// The effects of `ids` (`["none"]`: no search), each one of `allowed`.
fn parse_candidates(ids: &[String], allowed: &[Effect]) -> Result<Vec<Effect>> {
    if ids.len() == 1 && ids[0].trim() == "none" {
        return Ok(Vec::new());
    }
    ids.iter()
        .map(|id| {
            Effect::from_id(id.trim())
                .filter(|e| allowed.contains(e))
                .ok_or_else(|| {
                    Error::param(
                        "--candidates",
                        format!(
                            "effect {id:?} is not a candidate here; candidates: {} (or none)",
                            allowed
                                .iter()
                                .map(|e| e.id())
                                .collect::<Vec<_>>()
                                .join(", ")
                        ),
                    )
                })
        })
        .collect()
}

/// The files `identify` writes (besides `identify-level<N>.png`, one per level).
pub const IDENTIFY_OUTPUTS: [&str; 7] = [
    "identify.txt",
    "identify.json",
    "model.json",
    "identify-rows.csv",
    "identify-backbone.csv",
    "identify-backbone.png",
    "identify-response-controlled.csv",
];

/// The files `predict` writes (besides `predict-<N>.png`, one per file).
pub const PREDICT_OUTPUTS: [&str; 3] = ["predict.txt", "predict.json", "predict-rows.csv"];

/// The output set of `identify` in `out_dir` (`flag` names it in errors) with its inputs
/// declared: the measured files and the `structure` file are never written over.
fn identify_output_set(config: &IdentifyConfig, out_dir: &Path, flag: &str) -> Result<OutputSet> {
    let mut out = OutputSet::in_dir(out_dir, flag)?;
    out.owns("identify-level", ".png")?;
    out.writes(&IDENTIFY_OUTPUTS)?;
    out.inputs(&config.files, "measured file")?;
    out.inputs(&config.structure, "--structure")?;
    Ok(out)
}

/// A command's report with the output set its files go into, not yet written (so that a
/// caller can close its progress display first).
#[derive(Debug)]
pub struct Outcome<R> {
    /// The report.
    pub report: R,
    out: Option<OutputSet>,
}

impl<R> Outcome<R> {
    /// Write the report's files through the output set (all appear or none; `write` writes
    /// them into a staging directory) and return the report and the files' final paths; no
    /// output directory: nothing written.
    fn write_with(
        self,
        write: impl FnOnce(&R, &Path) -> Result<Vec<PathBuf>>,
    ) -> Result<(R, Vec<PathBuf>)> {
        let Some(mut out) = self.out else {
            return Ok((self.report, Vec::new()));
        };
        let staged = out.staging_dir()?;
        write(&self.report, &staged)?;
        Ok((self.report, out.commit()?))
    }
}

impl Outcome<IdentifyReport> {
    /// Write `identify`'s files through the output set (all appear or none); returns the
    /// report and the files' final paths (none without an output directory).
    pub fn write(self) -> Result<(IdentifyReport, Vec<PathBuf>)> {
        self.write_with(|r, d| r.write(d))
    }
}

impl Outcome<Prediction> {
    /// Write `predict`'s files through the output set (all appear or none); returns the
    /// report and the files' final paths (none without an output directory).
    pub fn write(self) -> Result<(Prediction, Vec<PathBuf>)> {
        self.write_with(|r, d| r.write(d))
    }
}

/// What `identify` found: the single nonlinear mode, or the update of a reduced model.
#[derive(Debug, Clone)]
pub enum IdentifyReport {
    /// The single-nonlinear-mode identification.
    Mode(Box<Identification>),
    /// The update of a reduced model (`structure`).
    Reduced(Box<ReducedIdentification>),
}

impl IdentifyReport {
    /// The report as `identify.txt` holds it.
    pub fn text(&self) -> String {
        match self {
            Self::Mode(id) => id.text(),
            Self::Reduced(id) => id.text(),
        }
    }

    /// Write the command's files into `dir`; returns their paths.
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>> {
        match self {
            Self::Mode(id) => id.write(dir),
            Self::Reduced(id) => id.write(dir),
        }
    }

    /// The effects of the final model, in the order they were accepted (the reduced model:
    /// those the search added to the four factors).
    pub fn selected_effects(&self) -> &[Effect] {
        match self {
            Self::Mode(id) => &id.after.model.spec.effects,
            Self::Reduced(id) => &id.fit.model.spec.effects,
        }
    }

    /// 0-based indices (by increasing mean force) of the levels fitted on.
    pub fn fit_levels(&self) -> &[usize] {
        match self {
            Self::Mode(id) => &id.fit_levels,
            Self::Reduced(id) => &id.fit_levels,
        }
    }

    /// Every parameter of the final model with its 95 % interval where the prediction bands
    /// were estimated (`lo_95`/`hi_95` `None` otherwise, and for a parameter held on a bound).
    pub fn parameters(&self) -> Vec<ParameterInterval> {
        let (uncertainty, params, values) = match self {
            Self::Mode(id) => (
                &id.uncertainty,
                id.after.model.spec.params(),
                &id.after.model.values,
            ),
            Self::Reduced(id) => (&id.uncertainty, id.parameters.clone(), &id.fit.model.values),
        };
        if let Uncertainty::Estimated(e) = uncertainty {
            return e.intervals.clone();
        }
        params
            .iter()
            .zip(values)
            .map(|(p, &v)| ParameterInterval {
                name: p.name.to_string(),
                unit: p.unit.to_string(),
                value: v,
                lo_95: None,
                hi_95: None,
                at_bound: super::model::at_bound(p, v),
            })
            .collect()
    }

    /// Why the parameters have no intervals, or `None` where they have.
    pub fn uncertainty_reason(&self) -> Option<&str> {
        let u = match self {
            Self::Mode(id) => &id.uncertainty,
            Self::Reduced(id) => &id.uncertainty,
        };
        match u {
            Uncertainty::Estimated(_) => None,
            Uncertainty::NotEstimated { reason } => Some(reason),
        }
    }

    /// Per level (by increasing mean force): errors of the baseline (the reduced model: as
    /// given, every factor 1).
    pub fn errors_before(&self) -> &[LevelErrors] {
        match self {
            Self::Mode(id) => &id.errors_before,
            Self::Reduced(id) => &id.errors_before,
        }
    }

    /// Per level (by increasing mean force): errors of the final model; those of role
    /// `predicted` are on levels the fit did not use.
    pub fn errors_after(&self) -> &[LevelErrors] {
        match self {
            Self::Mode(id) => &id.errors_after,
            Self::Reduced(id) => &id.errors_after,
        }
    }

    /// The search's conclusion in words, as the report gives it.
    pub fn verdict(&self) -> String {
        match self {
            Self::Mode(id) => super::pipeline::verdict_text(&id.selection.verdict),
            Self::Reduced(id) => match &id.effect_search {
                EffectSearch::Run(sel) => super::pipeline::verdict_text(&sel.verdict),
                EffectSearch::NotNeeded => "effect search not needed: the four factors fit the \
                                            fit levels to the measurement scatter"
                    .to_string(),
                EffectSearch::NotRun { reason } => format!("effect search not run: {reason}"),
            },
        }
    }

    /// Wall-clock time of the identification (s).
    pub fn wall_time_s(&self) -> f64 {
        match self {
            Self::Mode(id) => id.wall_time_s,
            Self::Reduced(id) => id.wall_time_s,
        }
    }
}

/// The search a prepared identification runs.
#[derive(Debug)]
enum Search {
    Mode {
        sweeps: Vec<Sweep>,
        options: Box<Options>,
    },
    Reduced {
        spec: Box<ReducedSpec>,
        sweeps: Vec<Sweep>,
        fit_levels: Vec<usize>,
        options: ReducedOptions,
        estimate: u64,
    },
}

/// An identification with its settings checked and its files read, ready to run.
#[derive(Debug)]
pub struct IdentifyRun {
    search: Search,
    out: Option<OutputSet>,
}

/// Seconds per model evaluation per measured row of the single-mode identification: measured
/// as the wall time of `identify` with its defaults (`--max-effects 0 --chain-steps 0`) on the
/// four Brake–Reuss files of `../shared/data/frf` (164 rows), 23 s on the 2-core machine shared
/// with other builds, over its estimated evaluations × rows; rounded up.
const SECONDS_PER_ROW_EVALUATION: f64 = 2e-5;

/// Above this estimate (s) a command says up front how long it will take and what bounds it.
const LONG_WORK_S: f64 = 600.0;

/// A note before a search estimated at more than [`LONG_WORK_S`]: its size, and the flags and
/// files that bound it.
fn work_note(evaluations: u64, sweeps: &[Sweep]) -> Option<String> {
    let rows: usize = sweeps.iter().map(|s| s.rows.len()).sum();
    let seconds = evaluations as f64 * rows as f64 * SECONDS_PER_ROW_EVALUATION;
    if seconds <= LONG_WORK_S {
        return None;
    }
    let largest = sweeps.iter().max_by_key(|s| s.rows.len())?;
    Some(format!(
        "note: about {evaluations} model evaluations over {rows} measured rows: roughly {:.0} \
         min; bounded by --starts, --particles, --swarm-iterations, --local-iterations, \
         --max-effects and --candidates, and by the rows of the files (largest: {}, {} rows; \
         thin it to shorten every evaluation)",
        seconds / 60.0,
        largest.path.display(),
        largest.rows.len()
    ))
}

/// Check `config`, declare the output set in `out_dir` (`(directory, name in errors)`; `None`:
/// nothing is written) and read the measured files (and the `structure` model): every error of
/// the inputs is raised here, before any fit.
pub fn prepare_identify(
    config: &IdentifyConfig,
    out_dir: Option<(&Path, &str)>,
) -> Result<IdentifyRun> {
    config.check()?;
    let out_set = |c| {
        out_dir
            .map(|(d, flag)| identify_output_set(c, d, flag))
            .transpose()
    };
    if let Some(structure) = &config.structure {
        use super::fit::{local_iteration_cap, FitOptions, Parametrised};
        let starts = config.starts.unwrap_or(FitOptions::default().starts);
        if starts > 0 {
            check_search(
                starts,
                config.particles.unwrap_or(FitOptions::default().particles),
            )?;
        }
        let mut out = out_set(config)?;
        if let Some(out) = &mut out {
            for (role, p) in crate::dynamics::model_file::referenced_files(structure)? {
                out.input(&p, &format!("--structure {role}"))?;
            }
        }
        let spec = ReducedSpec::load(structure)?;
        let sweeps = read_sweeps(&config.files)?;
        let fit_levels = choose_fit_levels(&sweeps, config.fit_levels.as_deref())?;
        let fit = FitOptions {
            starts,
            ..config.apply_search(FitOptions::default())
        };
        let local = local_iteration_cap(fit.local_iterations, spec.params().len());
        // The update; the effect search, if it runs, lengthens the progress by its own
        // estimate.
        let estimate = fit.swarm_evaluations() + (fit.starts as u64 + 1) * local;
        let options = ReducedOptions {
            fit,
            response_amplitudes: config.response_amplitude.clone(),
            chain_steps: config.checked_chain_steps()?,
            candidates: config
                .candidates
                .as_ref()
                .map(|c| parse_candidates(c, &REDUCED_EFFECTS))
                .transpose()?,
            max_effects: config.max_effects,
            rows: config.rows,
        };
        return Ok(IdentifyRun {
            search: Search::Reduced {
                spec: Box::new(spec),
                sweeps,
                fit_levels,
                options,
                estimate,
            },
            out,
        });
    }
    let mut opts = if config.thorough {
        Options::thorough(config.family)
    } else {
        Options::new(config.family)
    };
    opts.fit_levels = config.fit_levels.clone();
    if let Some(c) = &config.candidates {
        opts.select.candidates = parse_candidates(c, &Effect::ALL)?;
    }
    opts.select.max_effects = config.max_effects;
    if let Some(n) = config.starts {
        opts.select.baseline_fit.starts = n;
    }
    check_search(
        opts.select.baseline_fit.starts,
        config
            .particles
            .unwrap_or(opts.select.baseline_fit.particles),
    )?;
    opts.select.baseline_fit = config.apply_search(opts.select.baseline_fit);
    opts.select.candidate_fit = config.apply_search(opts.select.candidate_fit);
    opts.final_fit = config.apply_search(opts.final_fit);
    opts.response_amplitudes = config.response_amplitude.clone();
    opts.rows = config.rows;
    if let Some(n) = config.checked_chain_steps()? {
        opts.chain_steps = n;
    }
    let out = out_set(config)?;
    let sweeps = read_sweeps(&config.files)?;
    Ok(IdentifyRun {
        search: Search::Mode {
            sweeps,
            options: Box::new(opts),
        },
        out,
    })
}

impl IdentifyRun {
    /// What the progress shows: `identify`, or `identify (reduced model)`.
    pub fn title(&self) -> &'static str {
        match self.search {
            Search::Mode { .. } => "identify",
            Search::Reduced { .. } => "identify (reduced model)",
        }
    }

    /// Model evaluations the run is expected to take (the reduced model's effect search, if
    /// it runs, adds its own estimate to the progress).
    pub fn estimated_evaluations(&self) -> u64 {
        match &self.search {
            Search::Mode { options, .. } => options.estimated_evaluations(),
            Search::Reduced { estimate, .. } => *estimate,
        }
    }

    /// A note to print before a search expected to take more than ten minutes: its size and
    /// the settings and files that bound it; `None` otherwise.
    pub fn note(&self) -> Option<String> {
        match &self.search {
            Search::Mode { sweeps, options } => work_note(options.estimated_evaluations(), sweeps),
            Search::Reduced { .. } => None,
        }
    }

    /// Run the identification (advancing `progress`, whose length the run may extend); the
    /// outcome's `write` writes its files into the output directory, if one was given.
    pub fn run(self, progress: Option<&indicatif::ProgressBar>) -> Result<Outcome<IdentifyReport>> {
        let report = match self.search {
            Search::Mode { sweeps, options } => {
                IdentifyReport::Mode(Box::new(identify(sweeps, &options, progress)?))
            }
            Search::Reduced {
                spec,
                sweeps,
                fit_levels,
                options,
                ..
            } => IdentifyReport::Reduced(Box::new(identify_reduced(
                &spec, sweeps, fit_levels, &options, progress,
            )?)),
        };
        Ok(Outcome {
            report,
            out: self.out,
        })
    }
}

/// The parameters of `asperity predict`, one per flag.
#[derive(Debug, Clone, PartialEq)]
pub struct PredictConfig {
    /// Identified model file (`model.json` written by `identify`).
    pub model: PathBuf,
    /// Measured files to predict.
    pub files: Vec<PathBuf>,
    /// How the measured tests were controlled; `None`: what the files' headers state, force
    /// control where they state nothing.
    pub control: Option<Control>,
}

/// A prediction with its files read and its control chosen, ready to run.
#[derive(Debug)]
pub struct PredictRun {
    model: PathBuf,
    sweeps: Vec<Sweep>,
    control: (Control, String),
    out: Option<OutputSet>,
}

/// Declare the output set of `predict` in `out_dir` (`(directory, name in errors)`; `None`:
/// nothing is written), read the measured files and choose the control: every error of the
/// inputs except the model file's is raised here.
pub fn prepare_predict(
    config: &PredictConfig,
    out_dir: Option<(&Path, &str)>,
) -> Result<PredictRun> {
    let out = match out_dir {
        Some((dir, flag)) => {
            let mut out = OutputSet::in_dir(dir, flag)?;
            out.owns("predict-", ".png")?;
            out.writes(&PREDICT_OUTPUTS)?;
            out.inputs(&config.files, "measured file")?;
            for (role, p) in model_inputs(&config.model)? {
                out.input(&p, &role)?;
            }
            Some(out)
        }
        None => None,
    };
    let sweeps = read_sweeps(&config.files)?;
    let control = choose_control(&sweeps, config.control)?;
    Ok(PredictRun {
        model: config.model.clone(),
        sweeps,
        control,
        out,
    })
}

impl PredictRun {
    /// What the progress shows: the rows and files predicted.
    pub fn title(&self) -> String {
        let rows: usize = self.sweeps.iter().map(|s| s.rows.len()).sum();
        format!("predicting {rows} rows of {} file(s)", self.sweeps.len())
    }

    /// Predict the files; the outcome's `write` writes the command's files into the output
    /// directory, if one was given.
    pub fn run(self) -> Result<Outcome<Prediction>> {
        Ok(Outcome {
            report: predict(&self.model, self.sweeps, self.control)?,
            out: self.out,
        })
    }
}
