//! `asperity identify` and `asperity predict`: measured frequency responses → identified
//! single-nonlinear-mode model → errors on the levels and tests not used.
use asperity::identify::command::{
    prepare_identify, prepare_predict, IdentifyConfig, PredictConfig,
};
use asperity::identify::model::Family;
use asperity::identify::pipeline::FitRows;
use asperity::identify::Control;
use asperity::Result;
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

/// Print the report and the files written.
fn report(text: &str, written: &[PathBuf]) {
    print!("{text}");
    println!("\nwrote:");
    for p in written {
        println!("  {}", p.display());
    }
}

impl IdentifyArgs {
    /// The library's config of these flags.
    fn config(&self) -> IdentifyConfig {
        IdentifyConfig {
            files: self.files.clone(),
            fit_levels: self.fit_levels.clone(),
            family: match self.family {
                FamilyArg::Jenkins => Family::Jenkins,
                FamilyArg::Valanis => Family::Valanis,
                FamilyArg::Iwan => Family::Iwan,
            },
            candidates: self.candidates.clone(),
            max_effects: self.max_effects,
            thorough: self.thorough,
            starts: self.starts,
            particles: self.particles,
            swarm_iterations: self.swarm_iterations,
            local_iterations: self.local_iterations,
            seed: self.seed,
            response_amplitude: self.response_amplitude.clone(),
            chain_steps: self.chain_steps,
            rows: match self.rows {
                RowsArg::All => FitRows::All,
                RowsArg::Settled => FitRows::Settled,
            },
            structure: self.structure.clone(),
        }
    }
}

pub fn run_identify(args: IdentifyArgs) -> Result<()> {
    let run = prepare_identify(&args.config(), Some((&args.out_dir, "--out-dir")))?;
    if let Some(note) = run.note() {
        eprintln!("{note}");
    }
    let bar = super::progress_bar(run.title(), run.estimated_evaluations());
    bar.set_message("model evaluations");
    let result = run.run(Some(&bar));
    bar.finish_and_clear();
    let (id, written) = result?.write()?;
    report(&id.text(), &written);
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
    let config = PredictConfig {
        model: args.model,
        files: args.files,
        control: args.control.map(|c| match c {
            ControlArg::Force => Control::Force,
            ControlArg::Response => Control::Response,
        }),
    };
    let run = prepare_predict(&config, Some((&args.out_dir, "--out-dir")))?;
    let bar = super::spinner(&run.title());
    let result = run.run();
    bar.finish_and_clear();
    let (p, written) = result?.write()?;
    report(&p.text(), &written);
    Ok(())
}
