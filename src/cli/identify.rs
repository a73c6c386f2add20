//! `asperity identify` and `asperity predict`: measured frequency responses → identified
//! single-nonlinear-mode model → errors on the levels and tests not used.
use asperity::core::output::OutputSet;
use asperity::identify::effects::Effect;
use asperity::identify::model::Family;
use asperity::identify::pipeline::FitRows;
use asperity::identify::{identify, predict, read_sweeps, Control, Options};
use asperity::{Error, Result};
use std::path::PathBuf;

/// Joint element family of the baseline.
#[derive(Clone, Copy, clap::ValueEnum)]
pub enum FamilyArg {
    Jenkins,
    Valanis,
    Iwan,
}

/// Rows of the fit levels to fit.
#[derive(Clone, Copy, clap::ValueEnum)]
pub enum RowsArg {
    All,
    Settled,
}

fn fit_rows(rows: RowsArg) -> FitRows {
    match rows {
        RowsArg::All => FitRows::All,
        RowsArg::Settled => FitRows::Settled,
    }
}

/// Identify a jointed structure's nonlinear mode from stepped-sine sweeps at several excitation
/// levels (one CSV per level: frequency_Hz, force_amplitude_N, <quantity>_amplitude_<unit>,
/// phase_rad|phase_deg); fit on some levels, find the missing effect on held-out rows, predict
/// the others.
#[derive(clap::Args)]
pub struct IdentifyArgs {
    /// Measured sweeps, one file per level (levels are numbered by increasing mean force).
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
    /// Levels to fit on (1-based, by increasing mean force), e.g. 1,4; default: lowest and highest.
    #[arg(long, value_delimiter = ',')]
    pub fit_levels: Option<Vec<usize>>,
    /// Joint element of the baseline model.
    #[arg(long, value_enum, default_value = "jenkins")]
    pub family: FamilyArg,
    /// Candidate effects to test (comma-separated ids; default: all; `none`: no search). Ids:
    /// valanis_joint, iwan_joint, amplitude_stiffness, quadratic_stiffness, quadratic_damping,
    /// power_law_damping, preload_loss, higher_harmonics, out_of_band_modes, shaker_interaction.
    /// With `--structure`: amplitude_stiffness, quadratic_stiffness, preload_loss,
    /// higher_harmonics, out_of_band_modes, shaker_interaction.
    #[arg(long, value_delimiter = ',')]
    pub candidates: Option<Vec<String>>,
    /// Maximum number of effects added (each needs strong held-out evidence).
    #[arg(long, default_value_t = 3)]
    pub max_effects: usize,
    /// The thorough search: three particle-swarm starts for the baseline and one for every
    /// candidate beside its local start, Nelder–Mead to a relative tolerance of 1e-7 with up to
    /// three restarts, every row evaluated, chains of 6000 steps (about 20 CPU-minutes on four
    /// Brake–Reuss levels where the default takes about one). The default: the baseline from
    /// the data's scales and one swarm start, each candidate by Nelder–Mead from the current
    /// optimum (in parallel), early stopping at 1e-5 with one restart as the convergence test,
    /// training rows only, chains of 3000 steps.
    #[arg(long, conflicts_with = "structure")]
    pub thorough: bool,
    /// Particle-swarm starts of the baseline fit (each followed by Nelder–Mead); default 1, 3
    /// with `--thorough`. With `--structure` (default 3), 0 is allowed: Nelder–Mead from the
    /// model as given only.
    #[arg(long)]
    pub starts: Option<usize>,
    /// Particles of the swarm (default 32).
    #[arg(long)]
    pub particles: Option<usize>,
    /// Swarm iterations per start (default 40).
    #[arg(long)]
    pub swarm_iterations: Option<u64>,
    /// Nelder–Mead iteration cap per run for up to five parameters, scaled in proportion to the
    /// parameter count beyond (each fit runs Nelder–Mead and restarts it from its optimum until
    /// a restart stops on its tolerance; one that never does has not converged, which is an
    /// error for the final models); default 600.
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    pub local_iterations: Option<u64>,
    /// Seed of the first start (start k uses seed + k).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Response amplitudes at which the identified model's response-controlled FRF is reported,
    /// in the unit of the lowest level's quantity (e.g. m/s² for accelerometers); default: the
    /// measured peak responses.
    #[arg(long, value_delimiter = ',')]
    pub response_amplitude: Option<Vec<f64>>,
    /// Steps of each of the two Metropolis chains that sample the models fitting about as well
    /// (the 95 % bands of the predictions; 0: no bands, otherwise at least 1000). Default 3000,
    /// 6000 with `--thorough` and `--structure`; with `--structure` the default bands are left out when they would take more than ten
    /// minutes (the report gives the expected time), and an explicit value runs them.
    #[arg(long)]
    pub chain_steps: Option<usize>,
    /// Rows of the fit levels to fit: `all`, or `settled` — on a fit level whose two sides of
    /// the resonance differ in damping at equal amplitude (the report's stationarity check: at
    /// least two points beyond 10 % and four noise standard deviations; the structure changed
    /// while the level was measured), only the resonance row and the rows after it in the
    /// file's order, i.e. the part of the test after the structure has been through the level's
    /// largest amplitude. Errors are always scored on every row.
    #[arg(long, value_enum, default_value = "all")]
    pub rows: RowsArg,
    /// Multi-DOF reduced model to update instead of the single nonlinear mode: a model file of
    /// `asperity response` (linear structure, contact element tables, excitation and response
    /// DOFs, harmonics). Four factors are fitted (frequencies, damping ratios, contact stiffness,
    /// friction); when they leave a residual above the measurement scatter, the effect search
    /// runs on the structure-level candidates that act on the response coordinate (by default
    /// when it is expected to take at most ten minutes; `--candidates` runs it regardless).
    #[arg(long, conflicts_with_all = ["family"])]
    pub structure: Option<PathBuf>,
    /// Output directory: identify.{txt,json}, model.json, identify-rows.csv,
    /// identify-backbone.{csv,png}, identify-response-controlled.csv, identify-level<N>.png.
    #[arg(long, default_value = "identify-out")]
    pub out_dir: PathBuf,
}

/// Write a result's files through the output set (all appear or none) and return their final
/// paths.
fn write_all(
    mut out: OutputSet,
    write: impl FnOnce(&std::path::Path) -> Result<Vec<PathBuf>>,
) -> Result<Vec<PathBuf>> {
    let staged = out.staging_dir()?;
    write(&staged)?;
    out.commit()
}

/// Print the report and the files written.
fn report(text: &str, written: &[PathBuf]) {
    print!("{text}");
    println!("\nwrote:");
    for p in written {
        println!("  {}", p.display());
    }
}

/// `--chain-steps`, checked: 0 (no bands) or at least 1000.
fn chain_steps(args: &IdentifyArgs) -> Result<Option<usize>> {
    match args.chain_steps {
        Some(n) if n != 0 && n < 1000 => Err(Error::param(
            "--chain-steps",
            format!("{n} (0 for no bands, or at least 1000)"),
        )),
        n => Ok(n),
    }
}

/// The search settings within the resource limits (before anything is read or fitted).
fn check_limits(args: &IdentifyArgs) -> Result<()> {
    use asperity::core::limits::*;
    check_count("--starts", args.starts.unwrap_or(0), MAX_FIT_STARTS)?;
    check_count("--particles", args.particles.unwrap_or(0), MAX_PARTICLES)?;
    check_count(
        "--swarm-iterations",
        args.swarm_iterations.unwrap_or(0) as usize,
        MAX_SWARM_ITERATIONS as usize,
    )?;
    check_count(
        "--local-iterations",
        args.local_iterations.unwrap_or(0) as usize,
        MAX_LOCAL_ITERATIONS as usize,
    )?;
    check_count(
        "--chain-steps",
        args.chain_steps.unwrap_or(0),
        MAX_CHAIN_STEPS,
    )?;
    if let Some(a) = &args.response_amplitude {
        if let Some(v) = a.iter().find(|v| !(v.is_finite() && **v > 0.0)) {
            return Err(Error::param(
                "--response-amplitude",
                format!("amplitudes must be finite and > 0, got {v}"),
            ));
        }
    }
    Ok(())
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

/// The swarm and Nelder–Mead settings of `--particles`, `--swarm-iterations`,
/// `--local-iterations` and `--seed` applied to `fit` (those not given keep its values).
fn apply_search_args(
    fit: asperity::identify::fit::FitOptions,
    args: &IdentifyArgs,
) -> asperity::identify::fit::FitOptions {
    asperity::identify::fit::FitOptions {
        particles: args.particles.unwrap_or(fit.particles),
        swarm_iterations: args.swarm_iterations.unwrap_or(fit.swarm_iterations),
        local_iterations: args.local_iterations.unwrap_or(fit.local_iterations),
        seed: args.seed,
        ..fit
    }
}

pub fn run_identify(args: IdentifyArgs) -> Result<()> {
    check_limits(&args)?;
    if let Some(structure) = &args.structure {
        return run_identify_reduced(structure, &args);
    }
    let family = match args.family {
        FamilyArg::Jenkins => Family::Jenkins,
        FamilyArg::Valanis => Family::Valanis,
        FamilyArg::Iwan => Family::Iwan,
    };
    let mut opts = if args.thorough {
        Options::thorough(family)
    } else {
        Options::new(family)
    };
    opts.fit_levels = args.fit_levels.clone();
    if let Some(c) = &args.candidates {
        opts.select.candidates = parse_candidates(c, &Effect::ALL)?;
    }
    opts.select.max_effects = args.max_effects;
    if let Some(n) = args.starts {
        opts.select.baseline_fit.starts = n;
    }
    check_search(
        opts.select.baseline_fit.starts,
        args.particles.unwrap_or(opts.select.baseline_fit.particles),
    )?;
    opts.select.baseline_fit = apply_search_args(opts.select.baseline_fit, &args);
    opts.select.candidate_fit = apply_search_args(opts.select.candidate_fit, &args);
    opts.final_fit = apply_search_args(opts.final_fit, &args);
    opts.response_amplitudes = args.response_amplitude.clone();
    opts.rows = fit_rows(args.rows);
    if let Some(n) = chain_steps(&args)? {
        opts.chain_steps = n;
    }
    let out = identify_outputs(&args)?;
    let sweeps = read_sweeps(&args.files)?;
    if let Some(note) = work_note(opts.estimated_evaluations(), &sweeps) {
        eprintln!("{note}");
    }
    let bar = super::progress_bar("identify", opts.estimated_evaluations());
    bar.set_message("model evaluations");
    let result = identify(sweeps, &opts, Some(&bar));
    bar.finish_and_clear();
    let id = result?;
    report(&id.text(), &write_all(out, |d| id.write(d))?);
    Ok(())
}

/// The output set of `identify` with its inputs declared: the measured files (and the model
/// file of `--structure` with the files it names, added by the caller) are never written over.
fn identify_outputs(args: &IdentifyArgs) -> Result<OutputSet> {
    let mut out = OutputSet::in_dir(&args.out_dir, "--out-dir")?;
    out.owns("identify-level", ".png")?;
    out.writes(&[
        "identify.txt",
        "identify.json",
        "model.json",
        "identify-rows.csv",
        "identify-backbone.csv",
        "identify-backbone.png",
        "identify-response-controlled.csv",
    ])?;
    out.inputs(&args.files, "measured file")?;
    out.inputs(&args.structure, "--structure")?;
    Ok(out)
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
fn work_note(evaluations: u64, sweeps: &[asperity::identify::measured::Sweep]) -> Option<String> {
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

/// The effects of `--candidates` (`none`: no search), each one of `allowed`.
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

/// `asperity identify --structure`: update the reduced model of a response-model file.
fn run_identify_reduced(structure: &std::path::Path, args: &IdentifyArgs) -> Result<()> {
    use asperity::identify::fit::{FitOptions, Parametrised};
    use asperity::identify::reduced::{
        identify_reduced, ReducedOptions, ReducedSpec, REDUCED_EFFECTS,
    };
    let starts = args.starts.unwrap_or(FitOptions::default().starts);
    if starts > 0 {
        check_search(
            starts,
            args.particles.unwrap_or(FitOptions::default().particles),
        )?;
    }
    let mut out = identify_outputs(args)?;
    for (role, p) in asperity::dynamics::model_file::referenced_files(structure)? {
        out.input(&p, &format!("--structure {role}"))?;
    }
    let spec = ReducedSpec::load(structure)?;
    let sweeps = read_sweeps(&args.files)?;
    let fit_levels =
        asperity::identify::pipeline::choose_fit_levels(&sweeps, args.fit_levels.as_deref())?;
    let opts = FitOptions {
        starts,
        ..apply_search_args(FitOptions::default(), args)
    };
    let dim = spec.params().len() as u64;
    let local = asperity::identify::fit::local_iteration_cap(opts.local_iterations, dim as usize);
    // The update; the effect search, if it runs, lengthens the bar by its own estimate.
    let estimate = opts.swarm_evaluations() + (opts.starts as u64 + 1) * local;
    let bar = super::progress_bar("identify (reduced model)", estimate);
    bar.set_message("model evaluations");
    let options = ReducedOptions {
        fit: opts,
        response_amplitudes: args.response_amplitude.clone(),
        chain_steps: chain_steps(args)?,
        candidates: args
            .candidates
            .as_ref()
            .map(|c| parse_candidates(c, &REDUCED_EFFECTS))
            .transpose()?,
        max_effects: args.max_effects,
        rows: fit_rows(args.rows),
    };
    let result = identify_reduced(&spec, sweeps, fit_levels, &options, Some(&bar));
    bar.finish_and_clear();
    let id = result?;
    report(&id.text(), &write_all(out, |d| id.write(d))?);
    Ok(())
}

/// Score an identified model (model.json from `asperity identify`) on measured files:
/// force-controlled (each row's force applied) or response-controlled (each row's response
/// amplitude held, the force solved for).
#[derive(clap::Args)]
pub struct PredictArgs {
    /// Identified model file (model.json written by `asperity identify`).
    #[arg(long)]
    pub model: PathBuf,
    /// Measured files to predict.
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
    /// How the measured test was controlled. Default: what the files' headers state (a comment
    /// line saying "Force control" or "Response control"), force control where they state
    /// nothing; a flag that contradicts a file's header is refused.
    #[arg(long, value_enum)]
    pub control: Option<ControlArg>,
    /// Output directory: predict.{txt,json}, predict-rows.csv, predict-<N>.png.
    #[arg(long, default_value = "predict-out")]
    pub out_dir: PathBuf,
}

/// Test control of the measured files.
#[derive(Clone, Copy, clap::ValueEnum)]
pub enum ControlArg {
    /// Force amplitude of each row applied.
    Force,
    /// Response amplitude of each row held.
    Response,
}

pub fn run_predict(args: PredictArgs) -> Result<()> {
    let flag = args.control.map(|c| match c {
        ControlArg::Force => Control::Force,
        ControlArg::Response => Control::Response,
    });
    let mut out = OutputSet::in_dir(&args.out_dir, "--out-dir")?;
    out.owns("predict-", ".png")?;
    out.writes(&["predict.txt", "predict.json", "predict-rows.csv"])?;
    out.inputs(&args.files, "measured file")?;
    for (role, p) in asperity::identify::predict::model_inputs(&args.model)? {
        out.input(&p, &role)?;
    }
    let sweeps = read_sweeps(&args.files)?;
    let control = asperity::identify::predict::choose_control(&sweeps, flag)?;
    let rows: usize = sweeps.iter().map(|s| s.rows.len()).sum();
    let bar = super::spinner(&format!(
        "predicting {rows} rows of {} file(s)",
        sweeps.len()
    ));
    let p = predict(&args.model, sweeps, control);
    bar.finish_and_clear();
    let p = p?;
    let written = write_all(out, |d| p.write(d))?;
    print!("{}", p.text());
    println!("\nwrote:");
    for w in written {
        println!("  {}", w.display());
    }
    Ok(())
}
