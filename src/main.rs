//! `asperity` command-line tool: a thin layer over the library, one function per subcommand.

mod cli;

use clap::{Parser, Subcommand};

/// Contact parameters for microslip elements, computed from the rough surface.
/// SI units throughout (m, Pa, N); every flag names its unit.
#[derive(Parser)]
#[command(name = "asperity", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Generate, analyse, convert and combine rough surfaces.
    #[command(subcommand)]
    Surface(cli::surface::SurfaceCommand),
    /// Normal and tangential contact of a rough patch on the elastic half-space.
    #[command(subcommand)]
    Contact(cli::contact::ContactCommand),
    /// Whole chain surface → normal sweep → loops → Valanis fits → table (reference case by default).
    Calibrate(cli::calibrate::CalibrateArgs),
    /// Pressure-measurement film image → pressure map, polynomial fit, preload per node.
    Film(cli::film::FilmArgs),
    /// Join a preload map with a calibration table: one row per contact element.
    Elements(cli::elements::ElementsArgs),
    /// Compare a model with a measured hysteresis record; find and add the missing effect.
    Diagnose(cli::diagnose::DiagnoseArgs),
    /// Nonlinear forced response (harmonic balance, AFT, continuation) driven by element tables.
    Response(cli::response::ResponseArgs),
    /// Free decay (ring-down) of a model's structure by time integration: frequency and damping
    /// ratio per period against amplitude.
    Decay(cli::decay::DecayArgs),
    /// Nonlinear modes (extended periodic motion concept): backbone and modal damping against
    /// amplitude, for the same model file.
    Modes(cli::modes::ModesArgs),
    /// Merge the shard files of a sharded sweep (`--shard i/n`) into the single-run outputs.
    Merge(cli::merge::MergeArgs),
    /// Identify a jointed structure's nonlinear mode from measured frequency responses at
    /// several levels; find the missing effect; predict the levels not used.
    Identify(Box<cli::identify::IdentifyArgs>),
    /// Score an identified model on measured files (force- or response-controlled).
    Predict(cli::identify::PredictArgs),
}

/// Keep freed work arrays in the process instead of handing them back to the kernel after every
/// use. glibc's defaults return blocks above 128 KiB (`munmap`, and `MADV_DONTNEED` when the
/// thread arenas of rayon's workers are trimmed), so a solver that allocates its FFT grids per
/// product faults them in again each time: `contact tangential --operator fft` on a zero-padded
/// 128² Hertz case spent 6.4 of 11.4 s wall in the kernel (3.5 M page faults); with these two
/// settings 0.5 of 5.7 s (BENCHMARKS.md, "Tangential contact"). The cost is up to 256 MiB of
/// freed memory kept per arena; arrays above 32 MiB (glibc's ceiling for the threshold) are
/// still mapped on their own. Called before any thread starts. The library does not do this (a
/// host process such as Python owns its allocator).
fn keep_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only changes allocator parameters; called once, before other threads.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 32 << 20);
        libc::mallopt(libc::M_TRIM_THRESHOLD, 256 << 20);
    }
}

fn main() {
    keep_freed_memory();
    let cli = Cli::parse();
    // An interrupt removes staged and temporary files and reports whether the previous or the
    // new outputs are in place (asperity::core::output: exit 130 or 3).
    asperity::core::output::install_interrupt_handler();
    let result = match cli.command {
        Command::Surface(c) => cli::surface::run(c),
        Command::Contact(c) => cli::contact::run(c),
        Command::Calibrate(a) => cli::calibrate::run(a),
        Command::Film(a) => cli::film::run(a),
        Command::Elements(a) => cli::elements::run(a),
        Command::Diagnose(a) => cli::diagnose::run(a),
        Command::Response(a) => cli::response::run(a),
        Command::Decay(a) => cli::decay::run(a),
        Command::Modes(a) => cli::modes::run(a),
        Command::Merge(a) => cli::merge::run(a),
        Command::Identify(a) => cli::identify::run_identify(*a),
        Command::Predict(a) => cli::identify::run_predict(a),
    };
    if let Err(e) = result {
        if asperity::core::output::interrupted() {
            // The error comes from the interrupt's cleanup (a writer whose staging directory was
            // removed): the handler reports what happened and exits.
            loop {
                std::thread::park();
            }
        }
        eprintln!("error: {e}");
        std::process::exit(1);
    }
    // Tests of the interrupt after a complete output set hold the process here.
    if let Some(ms) = std::env::var("ASPERITY_TEST_PAUSE_BEFORE_EXIT_MS")
        .ok()
        .and_then(|v| v.parse::<u64>().ok())
    {
        std::thread::sleep(std::time::Duration::from_millis(ms));
    }
}
