//! `asperity contact tangential`: hysteresis loops of the rough contact under an oscillating
//! tangential displacement δ(t) = δa·sin(ωt) along x, one loop per nominal pressure.
//!
//! Writes `tangential_loops.csv` (every step, SI units in the column names),
//! `tangential_energy.csv` (energy per cycle, J/m²), `tangential_timings.csv` (wall times, s,
//! kept apart so that the other files are reproducible), `tangential_loops.png` (mean shear stress vs
//! displacement, all pressures) and `tangential_loops_normalised.png` (τ/(μ p̄), so that the
//! low-pressure loops are visible too).
//!
//! With `--normal-amplitude-ratio r` the normal load oscillates with the displacement,
//! p̄(t) = p̄·(1 + r·sin(ωt + φ)) (`--normal-phase-deg φ`): the loops, energies and plots are then
//! those of the varying load, `tangential_loops.csv` gains the normal pressure and the element's
//! shear stress of each step, and the Valanis element of the table (λ ∝ 1/Fz, E0 and k fitted to
//! the constant-load loop at p̄) is run on the same history: `tangential_element.csv` (energies
//! per cycle and the element's error), `tangential_element_loops.png`,
//! `tangential_element_energy.png`.

use asperity::calibrate::tangential_sweep::{self, TangentialSweepConfig};
use asperity::contact::tangential::TangentialOptions;
use asperity::core::material::Hardness;
use asperity::Result;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct TangentialArgs {
    /// Nominal pressures (Pa), comma separated. Default: the reference sweep
    /// 0.1, 0.2, 1, 2, 5, 10 MPa.
    /// One comma-separated list per flag; values starting with `-` are taken as values, so
    /// that a negative pressure reaches the flag's own check, which names it.
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    pressures_pa: Option<Vec<f64>>,
    /// Coulomb friction coefficient μ (-).
    #[arg(long, default_value_t = 0.6, allow_hyphen_values = true)]
    friction_coefficient: f64,
    /// Displacement amplitude δa (m). Default: 1.5 × the gross-slip displacement of the highest
    /// pressure, so that every loop at that pressure reaches gross slip.
    #[arg(long, allow_hyphen_values = true)]
    amplitude_m: Option<f64>,
    /// Number of cycles.
    #[arg(long, default_value_t = 3)]
    cycles: usize,
    /// Load steps per cycle.
    #[arg(long, default_value_t = 40)]
    steps_per_cycle: usize,
    /// Grid points per side of the reference surface (same 250 µm patch and statistics;
    /// default 1024). Smaller values give a quick, coarser look.
    #[arg(long)]
    grid: Option<usize>,
    /// A measured surface instead of the reference generated one (heights in m; every format
    /// `asperity surface stats` reads). Give it twice for two rough bodies: body 1, then body 2
    /// in the common frame (as `asperity surface combine`); their equivalent surface h1 − h2 is
    /// used. Non-periodic files use the zero-padded kernels (normal and tangential).
    #[arg(long, num_args = 1)]
    surface: Vec<PathBuf>,
    /// Fill missing points of the --surface files first: `harmonic` (Laplace interpolation) or
    /// `nearest`. Without it a surface with missing points is refused.
    #[arg(long, requires = "surface")]
    fill: Option<asperity::surface::missing::Fill>,
    /// Young's modulus of both bodies (Pa).
    #[arg(long, default_value_t = 210e9, allow_hyphen_values = true)]
    youngs_modulus_pa: f64,
    /// Poisson's ratio of both bodies (-).
    #[arg(long, default_value_t = 0.3, allow_hyphen_values = true)]
    poisson_ratio: f64,
    /// Hardness H bounding the contact pressure (elastic–perfectly plastic normal contact; the
    /// loops run on the bounded pressure): a value in Pa, or a material whose documented
    /// hardness to use: `steel-42crmo4` (340 HV, 3.334 GPa) or `inconel-718` (450 HV,
    /// 4.413 GPa); sources in docs/contact.md. Without it the contact is elastic.
    #[arg(long, allow_hyphen_values = true)]
    hardness_pa: Option<String>,
    /// Normal load oscillating with the tangential displacement: p̄(t) = p̄·(1 + r·sin(ωt + φ))
    /// about each pressure p̄, with this amplitude ratio r in [0, 1) (0: constant normal load).
    /// The Valanis element fitted at constant load is then run on the same history
    /// (`tangential_element.csv`).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    normal_amplitude_ratio: f64,
    /// Phase φ of the normal load ahead of the tangential displacement (degrees): 0 in phase,
    /// 180 out of phase, any value.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    normal_phase_deg: f64,
    /// In-plane direction of the displacement, angle from x towards y (degrees).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    direction_deg: f64,
    /// Elliptical path: the second semi-axis over the amplitude, perpendicular to the direction
    /// (turned +90°): δ(t) = δa·(e1·sin ωt + e·e2·(1 − cos ωt)), an ellipse through the origin;
    /// 1 a circle of radius δa, 0 (default) the straight to-and-fro. Not with a varying normal
    /// load.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    path_minor_ratio: f64,
    /// Compliance operator of the tangential solver: auto, dense or fft.
    #[arg(long, default_value = "auto")]
    operator: String,
    /// Tolerance of the tangential solver (relative natural residual).
    #[arg(long, default_value_t = TangentialOptions::default().tolerance)]
    tolerance: f64,
    /// Iteration cap per step (exceeding it is an error).
    #[arg(long, default_value_t = TangentialOptions::default().max_iterations)]
    max_iterations: usize,
    /// Output directory.
    #[arg(long, default_value = "out/contact-tangential")]
    out_dir: PathBuf,
}

pub fn run(args: TangentialArgs) -> Result<()> {
    let config = TangentialSweepConfig {
        pressures_pa: args.pressures_pa.clone(),
        friction_coefficient: args.friction_coefficient,
        amplitude_m: args.amplitude_m,
        cycles: args.cycles,
        steps_per_cycle: args.steps_per_cycle,
        grid: args.grid,
        surface: args.surface.clone(),
        fill: args.fill,
        youngs_modulus_pa: args.youngs_modulus_pa,
        poisson_ratio: args.poisson_ratio,
        hardness: args.hardness_pa.as_deref().map(Hardness::parse),
        normal_amplitude_ratio: args.normal_amplitude_ratio,
        normal_phase_deg: args.normal_phase_deg,
        direction_deg: args.direction_deg,
        path_minor_ratio: args.path_minor_ratio,
        options: TangentialOptions {
            tolerance: args.tolerance,
            max_iterations: args.max_iterations,
            operator: args
                .operator
                .parse()
                .map_err(|e: asperity::Error| e.renamed_param("--operator"))?,
        },
    };
    // Every input is checked before any work or output; the files are staged and appear
    // together at the end (asperity::core::output::OutputSet).
    let mut out = tangential_sweep::output_set(&config, &args.out_dir, "--out-dir")?;
    let started = std::time::Instant::now();
    let sweep = tangential_sweep::run(
        &config,
        &|len| super::progress_bar("tangential", len),
        &mut |m| eprintln!("{m}"),
    )?;
    sweep.write(&mut out)?;

    println!("pressure_MPa  contact_points  operator  W_last_cycle_J_per_m2  time_s");
    for (&p, r) in sweep.pressures_pa.iter().zip(&sweep.results) {
        println!(
            "{:>12.3}  {:>14}  {:>8?}  {:>21.4e}  {:>6.2}",
            p / 1e6,
            r.metadata.contact_points,
            r.metadata.operator,
            r.cycles.last().map_or(0.0, |c| c.dissipated_j_per_m2),
            r.wall_time_s + r.metadata.setup_time_s
        );
    }
    let written = out.commit()?;
    println!(
        "wrote {} files in {} (total {:.1} s)",
        written.len(),
        args.out_dir.display(),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}
