//! `asperity decay`: free decay of a model file's structure (time integration), with the
//! frequency and damping per period.

use asperity::dynamics::model_file;
use asperity::dynamics::transient::{self, DecaySettings};
use asperity::Result;
use std::path::PathBuf;

/// Free decay (ring-down) of the structure of a model file: Newmark time integration with the
/// contact elements, from rest in a linearised mode; frequency and damping ratio per period
/// against amplitude, read by peak picking from the first response DOF of the model file.
#[derive(clap::Args)]
pub struct DecayArgs {
    /// Model file (TOML, as for `asperity response`; its excitation and sweep are not used).
    model: PathBuf,
    /// Initial amplitude of the model's first response DOF (m).
    #[arg(long)]
    amplitude_m: f64,
    /// Linearised mode to start in (1 = the lowest, elements stuck).
    #[arg(long, default_value_t = 1)]
    mode: usize,
    /// Periods of the linearised mode to integrate.
    #[arg(long, default_value_t = 100)]
    periods: usize,
    /// Time steps per period of the linearised mode.
    #[arg(long, default_value_t = 256)]
    steps_per_period: usize,
    /// Output directory (decay.csv, decay_cycles.csv, decay.png, decay_backbone.png).
    #[arg(long, default_value = "out/decay")]
    out_dir: PathBuf,
}

pub fn run(args: DecayArgs) -> Result<()> {
    let mut out = transient::output_set(&args.model, &args.out_dir, "--out-dir")?;
    let model = model_file::load(&args.model)?;
    model.refuse_static("asperity decay")?;
    let (label, row) = &model.responses[0];
    let settings = DecaySettings {
        mode: args.mode,
        amplitude_m: args.amplitude_m,
        periods: args.periods,
        steps_per_period: args.steps_per_period,
    };
    let bar = super::progress_bar("decay", 1000);
    let result = transient::free_decay(&model.structure, row, &settings, &mut |f| {
        bar.set_position((f * 1000.0) as u64)
    })?;
    bar.finish_and_clear();
    let header = format!(
        "asperity {} decay: model {}; response {label} (m)",
        env!("CARGO_PKG_VERSION"),
        args.model.display()
    );
    result.write(&mut out, &header)?;
    out.commit()?;
    let (first, last) = (result.cycles.first(), result.cycles.last());
    println!(
        "stuck mode {}: {:.4} Hz; {} period estimates (one per half period), {:.3} s",
        args.mode,
        result.linear_frequency_hz,
        result.cycles.len(),
        result.wall_time_s
    );
    if let (Some(a), Some(b)) = (first, last) {
        println!(
            "from {:.3e} m: {:.4} Hz, damping ratio {:.3} %; to {:.3e} m: {:.4} Hz, {:.3} %",
            a.amplitude_m,
            a.frequency_hz,
            100.0 * a.damping_ratio,
            b.amplitude_m,
            b.frequency_hz,
            100.0 * b.damping_ratio
        );
    }
    println!("wrote {}", args.out_dir.display());
    Ok(())
}
