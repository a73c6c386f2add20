//! `asperity response`: nonlinear forced response of a model file (HBM + AFT + continuation).

use asperity::dynamics::model_file;
use asperity::dynamics::response;
use asperity::dynamics::stability::StabilityChoice;
use asperity::{Error, Result};
use std::path::PathBuf;

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
    /// Stability of every point by Hill's method: `auto` assesses it when Hill's companion
    /// matrix (2 × coordinates × harmonic coefficients rows) has at most 256 rows, where it adds
    /// about half the sweep's time; `on` always (its eigen-solve grows as the cube of the size);
    /// `off` never.
    #[arg(long, default_value = "auto", value_parser = ["auto", "on", "off"])]
    stability: String,
}

pub fn run(args: ResponseArgs) -> Result<()> {
    // Every output appears together or not at all; an unusable --out-dir, or one whose files
    // would be the model file or a file it names, is refused now.
    let mut out = response::output_set(&args.model, &args.out_dir, "--out-dir")?;
    let model = model_file::load(&args.model)?;
    let stability = match args.stability.as_str() {
        "on" => StabilityChoice::On,
        "off" => StabilityChoice::Off,
        _ => StabilityChoice::Auto,
    };
    let run = response::run(
        &model,
        stability,
        &|len| super::progress_bar("response", len),
        &mut |m| println!("{m}"),
    )?;
    // Everything computed: write the files.
    run.write(&mut out)?;
    for r in &run.results {
        let (non_periodic, worst) = run.periodicity(r);
        if non_periodic > 0 {
            println!(
                "warning: level {} N: at {non_periodic} of {} points an element's AFT state did not become periodic within {} periods (largest relative periodicity error {worst:.2e}, tolerance {:.0e}); their element forces are those of the last period integrated (column aft_periodicity_error)",
                r.level_n,
                r.branch.points.len(),
                run.system.aft.max_periods,
                run.system.aft.periodicity_tolerance
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
        if let Some(st) = &r.stability {
            let named: Vec<String> = st
                .bifurcations
                .iter()
                .map(|b| format!("{} at {:.4} Hz", b.kind.name(), b.frequency_hz))
                .collect();
            println!(
                "level {} N: stability (Hill): {} of {} points unstable; bifurcations: {}",
                r.level_n,
                st.unstable_points(),
                st.points.len(),
                if named.is_empty() {
                    "none".to_string()
                } else {
                    named.join(", ")
                }
            );
        }
        if pk.at_sweep_end {
            println!(
                "warning: level {} N: the largest amplitude is at the end of the sweep ({:.4} Hz): the peak may lie outside the span; widen it",
                r.level_n, pk.frequency_hz
            );
        }
    }
    out.commit()?;
    println!("wrote {}", args.out_dir.display());
    if !run.failures.is_empty() {
        return Err(Error::Data(format!(
            "{} of {} levels did not complete: {}",
            run.failures.len(),
            model.file.excitation.levels_n.len(),
            run.failures.join("; ")
        )));
    }
    Ok(())
}
