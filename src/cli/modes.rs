//! `asperity modes`: nonlinear modes (EPMC) of a model file of `asperity response`.

use asperity::dynamics::model_file;
use asperity::dynamics::modes::{self, ModesRequest};
use asperity::Result;
use std::path::PathBuf;

/// Nonlinear mode of a structure with contact elements by the extended periodic motion concept
/// (Krack 2015): frequency and modal damping ratio against modal amplitude, the mode shape's
/// harmonics and the energy every element dissipates, continued in amplitude from the linear
/// mode with the elements stuck; and the forced response of each excitation level of the model
/// synthesised from it as a single nonlinear mode.
#[derive(clap::Args)]
pub struct ModesArgs {
    /// Model file of `asperity response` (TOML: linear part, element tables and node pairs,
    /// excitation, response DOFs; `[sweep]` gives the harmonics and time samples).
    model: PathBuf,
    /// Linear mode to continue (1-based, ascending frequency of the structure with its elements
    /// stuck).
    #[arg(long, default_value_t = 1)]
    mode: usize,
    /// Smallest modal amplitude (m·kg^½: the mass-normalised amplitude of the first harmonic);
    /// default: 1/100 of the linear mode's resonance amplitude at the lowest excitation level.
    #[arg(long)]
    amplitude_min_m_sqrt_kg: Option<f64>,
    /// Largest modal amplitude (m·kg^½); default: the linear mode's resonance amplitude at the
    /// highest excitation level.
    #[arg(long)]
    amplitude_max_m_sqrt_kg: Option<f64>,
    /// Amplitudes on the backbone, log-spaced.
    #[arg(long, default_value_t = 60)]
    points: usize,
    /// Output directory (modes.csv, modes_shapes.csv, modes_elements.csv, modes_synthesis.csv,
    /// modes.png, modes.json).
    #[arg(long, default_value = "out/modes")]
    out_dir: PathBuf,
}

pub fn run(args: ModesArgs) -> Result<()> {
    // Every output appears together or not at all; an unusable --out-dir, or one whose files
    // would be the model file or a file it names, is refused now.
    let mut out = modes::output_set(&args.model, &args.out_dir, "--out-dir")?;
    let model = model_file::load(&args.model)?;
    let request = ModesRequest {
        mode: args.mode,
        amplitude_min: args.amplitude_min_m_sqrt_kg,
        amplitude_max: args.amplitude_max_m_sqrt_kg,
        points: args.points,
    };
    let run = modes::run(
        &model,
        &request,
        &|len| super::progress_bar("modes", len),
        &mut |m| println!("{m}"),
    )?;
    run.write(&mut out)?;
    let m = &run.mode;
    let (first, last) = (&m.points[0], m.points.last().expect("at least one point"));
    println!(
        "mode {}: {} of {} amplitudes, {:.6} Hz → {:.6} Hz, damping ratio {:.4e} → {:.4e} (largest {:.4e}); {} retries, {} subdivisions, {:.2} s{}",
        m.linear.index,
        m.points.len(),
        run.settings.amplitudes.len(),
        first.frequency_hz(),
        last.frequency_hz(),
        first.damping_ratio(),
        last.damping_ratio(),
        m.points.iter().map(|p| p.damping_ratio()).fold(f64::NEG_INFINITY, f64::max),
        m.retries,
        m.subdivisions,
        m.wall_time_s,
        if m.stopped.is_some() { "; INCOMPLETE" } else { "" }
    );
    out.commit()?;
    println!("wrote {}", args.out_dir.display());
    if let Some(why) = &m.stopped {
        return Err(asperity::Error::Data(format!(
            "the continuation stopped {why} (the points before it are written)"
        )));
    }
    Ok(())
}
