//! `asperity contact normal`: pressure sweep of the normal contact solver on a rough surface.
//! Writes `normal_sweep.csv` (SI units in the column names), `area_ratio.png`, `mean_gap.png`,
//! `kn.png` (log axes) and, with `--pressure-maps`, one pressure map PNG per load: all of
//! them, or none (`asperity::output::OutputSet`).

use asperity::contact::normal::{NormalOptions, NormalProblem, NormalSolver};
use asperity::contact::sweep::{self, SweepOptions, REFERENCE_PRESSURES_PA};
use asperity::output::OutputSet;
use asperity::plot::{heatmap, line_plot, HeatMap, LinePlot, Scale, Series};
use asperity::surface::combine::composite_modulus;
use asperity::surface::missing::Fill;
use asperity::{Error, Grid2, Result};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

#[derive(clap::Args)]
pub struct NormalArgs {
    /// Surface height file (heights in m; the format is recognised from the extension).
    /// Default: the reference generated surface (Rq 0.177 µm, cl 6.6 µm, 250 µm, 1024²).
    #[arg(long, conflicts_with = "grid")]
    surface: Option<PathBuf>,
    /// Fill missing points of --surface first: `harmonic` (Laplace interpolation) or
    /// `nearest`. Without it a surface with missing points is refused.
    #[arg(long, requires = "surface")]
    fill: Option<Fill>,
    /// Grid points per side of the reference surface (same 250 µm patch and statistics;
    /// default 1024). Smaller values give a quick, coarser look.
    #[arg(long)]
    grid: Option<usize>,
    /// Nominal pressures (Pa), comma separated. Default: the reference sweep
    /// 0.1, 0.2, 1, 2, 5, 10 MPa.
    #[arg(long, value_delimiter = ',', num_args = 1..)]
    pressures_pa: Option<Vec<f64>>,
    /// Young's modulus of both bodies (Pa).
    #[arg(long, default_value_t = 210e9, allow_hyphen_values = true)]
    youngs_modulus_pa: f64,
    /// Poisson's ratio of both bodies (-).
    #[arg(long, default_value_t = 0.3, allow_hyphen_values = true)]
    poisson_ratio: f64,
    /// Output directory.
    #[arg(long, default_value = "out/contact-normal")]
    out_dir: PathBuf,
    /// Also write a pressure map PNG per load.
    #[arg(long)]
    pressure_maps: bool,
    /// Tolerance on the relative gap error of the Polonsky–Keer solver.
    #[arg(long, default_value_t = NormalOptions::DEFAULT_TOLERANCE, allow_hyphen_values = true)]
    tolerance: f64,
    /// Iteration cap per solve (exceeding it is an error).
    #[arg(long, default_value_t = NormalOptions::default().max_iterations)]
    max_iterations: usize,
    /// Relative pressure step ε of the central difference giving kn.
    #[arg(long, default_value_t = sweep::DEFAULT_DERIVATIVE_STEP, allow_hyphen_values = true)]
    derivative_step: f64,
}

/// Load the surface: a file (its missing points filled when asked), or the reference
/// generated surface (on `grid` points per side). Checked against the grid limit and for a
/// usable contact surface (`asperity::sanity::contact_surface`).
fn load_surface(
    path: Option<&Path>,
    fill: Option<Fill>,
    grid: Option<usize>,
) -> Result<(Grid2, String)> {
    let (grid, source) = match path {
        Some(p) => {
            let (grid, report) = asperity::surface::missing::load_area(p, fill)?;
            let mut source = p.display().to_string();
            if let Some(r) = report {
                eprintln!("{source}: {}", r.describe());
                source = format!("{source} ({})", r.describe());
            }
            asperity::limits::check_grid(
                &p.display().to_string(),
                grid.nx(),
                grid.ny(),
                asperity::limits::CONTACT_BYTES_PER_POINT,
            )?;
            (grid, source)
        }
        None => {
            let mut spec = asperity::surface::generate::GaussianSurfaceSpec::reference();
            if let Some(n) = grid {
                spec.nx = n;
                spec.ny = n;
                spec.validate()
                    .map_err(|e| super::rename_param(e, "--grid"))?;
            }
            asperity::limits::check_grid(
                "--grid",
                spec.nx,
                spec.ny,
                asperity::limits::CONTACT_BYTES_PER_POINT,
            )?;
            (
                asperity::surface::generate::generate(&spec)?,
                format!(
                    "reference generated surface (Rq {} m, correlation length {} m, {} m, {}², seed {})",
                    spec.rq_m, spec.clx_m, spec.lx_m, spec.nx, spec.seed
                ),
            )
        }
    };
    asperity::sanity::contact_surface(&grid, &source)?;
    Ok((grid, source))
}

pub fn run(args: NormalArgs) -> Result<()> {
    // Check every input before any work or output.
    let mut out = OutputSet::in_dir(&args.out_dir, "--out-dir")?;
    asperity::sanity::tolerance("--tolerance", args.tolerance)?;
    if let Some(p) = &args.pressures_pa {
        asperity::limits::check_count("--pressures-pa", p.len(), asperity::limits::MAX_PRESSURES)?;
    }
    let material = super::material_from_flags(args.youngs_modulus_pa, args.poisson_ratio)?;
    let e_star = composite_modulus(material, material)?;
    let pressures = sweep::checked_pressures(
        args.pressures_pa
            .as_deref()
            .unwrap_or(&REFERENCE_PRESSURES_PA),
    )
    .map_err(|e| super::rename_param(e, "--pressures-pa"))?;
    let options = NormalOptions {
        tolerance: args.tolerance,
        max_iterations: args.max_iterations,
        ..NormalOptions::default()
    };
    let sweep_options = SweepOptions {
        derivative_step: args.derivative_step,
        keep_solutions: args.pressure_maps,
    };
    options.validate().map_err(|e| match e {
        Error::InvalidParameter { name, message } => {
            Error::param(format!("--{}", name.replace('_', "-")), message)
        }
        other => other,
    })?;
    sweep_options
        .validate()
        .map_err(|e| super::rename_param(e, "--derivative-step"))?;
    let (surface, source) = load_surface(args.surface.as_deref(), args.fill, args.grid)?;
    asperity::sanity::contact_pressures("--pressures-pa", &pressures, e_star, &surface)?;
    let mut solver = NormalSolver::new(
        &NormalProblem {
            surface: &surface,
            e_star_pa: e_star,
        },
        options,
    )?;
    eprintln!(
        "surface: {source}, {} × {} points, spacing {:.4e} × {:.4e} m, {}; E* = {:.4e} Pa",
        surface.nx(),
        surface.ny(),
        surface.dx,
        surface.dy,
        if surface.periodic {
            "periodic"
        } else {
            "non-periodic (zero-padded)"
        },
        e_star
    );

    let bar = super::progress_bar("normal contact (pressures)", pressures.len() as u64);
    let result = sweep::run(&mut solver, &pressures, sweep_options, |k| {
        bar.set_position(k as u64)
    });
    bar.finish_and_clear();
    let result = result?;
    // Non-finite or non-physical results are refused, never written.
    for p in &result.points {
        let at = |q: &str| format!("{q} at {} Pa", asperity::error::num(p.pressure_pa));
        asperity::sanity::positive_result(&at("kn"), p.kn_n_per_m3)?;
        asperity::sanity::finite_result(&at("the mean gap"), p.mean_gap_m)?;
        asperity::sanity::finite_result(&at("the approach"), p.approach_m)?;
        asperity::sanity::positive_result(&at("the contact area ratio"), p.contact_area_ratio)?;
    }

    // CSV with a provenance header.
    let mut csv = String::new();
    let _ = writeln!(
        csv,
        "# asperity contact normal: Polonsky–Keer pressure sweep"
    );
    let _ = writeln!(csv, "# surface: {source}");
    let _ = writeln!(
        csv,
        "# grid: {} x {} points, dx_m = {:e}, dy_m = {:e}, periodic = {}",
        surface.nx(),
        surface.ny(),
        surface.dx,
        surface.dy,
        surface.periodic
    );
    let _ = writeln!(
        csv,
        "# youngs_modulus_Pa = {:e} (both bodies), poisson_ratio = {}, e_star_Pa = {:e}",
        args.youngs_modulus_pa, args.poisson_ratio, e_star
    );
    let _ = writeln!(
        csv,
        "# tolerance = {:e} (relative gap error), kn = -dp/d(mean gap) by central difference at p(1 +- {})",
        args.tolerance, args.derivative_step
    );
    let _ = writeln!(
        csv,
        "pressure_Pa,contact_area_ratio,mean_gap_m,kn_N_per_m3,approach_m,contact_spots,smallest_spot_points,median_spot_points,iterations,residual,wall_time_s"
    );
    for p in &result.points {
        let _ = writeln!(
            csv,
            "{:e},{:e},{:e},{:e},{:e},{},{},{},{},{:e},{:.3}",
            p.pressure_pa,
            p.contact_area_ratio,
            p.mean_gap_m,
            p.kn_n_per_m3,
            p.approach_m,
            p.contact_spots,
            p.smallest_spot_points,
            p.median_spot_points,
            p.iterations,
            p.residual,
            p.wall_time_s
        );
    }
    asperity::output::write_string_atomic(&out.path("normal_sweep.csv")?, &csv)?;

    let mpa = |f: fn(&sweep::SweepPoint) -> f64| -> Vec<(f64, f64)> {
        result
            .points
            .iter()
            .map(|p| (p.pressure_pa / 1e6, f(p)))
            .collect()
    };
    type Plot<'a> = (&'a str, &'a str, &'a str, Vec<(f64, f64)>);
    let plots: [Plot; 3] = [
        (
            "area_ratio.png",
            "Real contact area ratio",
            "A_real / A_nominal (-)",
            mpa(|p| p.contact_area_ratio),
        ),
        (
            "mean_gap.png",
            "Mean gap",
            "mean gap (µm)",
            mpa(|p| p.mean_gap_m * 1e6),
        ),
        (
            "kn.png",
            "Normal contact stiffness per unit area",
            "kn (10¹² N/m³)",
            mpa(|p| p.kn_n_per_m3 * 1e-12),
        ),
    ];
    for (file, title, y_label, pts) in plots {
        line_plot(
            &out.path(file)?,
            &LinePlot {
                title,
                x_label: "nominal pressure (MPa)",
                y_label,
                x_scale: Scale::Log,
                y_scale: Scale::Log,
            },
            &[
                Series::line("sweep", pts.clone()),
                Series::markers("solved pressures", pts),
            ],
        )?;
    }
    for sol in &result.solutions {
        let title = format!(
            "Contact pressure at p̄ = {:.4} MPa",
            sol.mean_pressure_pa / 1e6
        );
        heatmap(
            &out.path(&format!("pressure_map_{:e}Pa.png", sol.mean_pressure_pa))?,
            &sol.pressure,
            sol.dx,
            sol.dy,
            &HeatMap {
                title: &title,
                value_label: "pressure (MPa)",
                value_scale: 1e-6,
                length_scale: 1e6,
                length_unit: "µm",
            },
        )?;
    }

    println!(
        "{:>12} {:>12} {:>12} {:>12} {:>7} {:>9} {:>9} {:>6}",
        "p (MPa)", "area ratio", "gap (µm)", "kn (N/m³)", "spots", "min spot", "med spot", "iter"
    );
    for p in &result.points {
        println!(
            "{:>12.4} {:>12.5} {:>12.5} {:>12.4e} {:>7} {:>9} {:>9} {:>6}{}",
            p.pressure_pa / 1e6,
            p.contact_area_ratio,
            p.mean_gap_m * 1e6,
            p.kn_n_per_m3,
            p.contact_spots,
            p.smallest_spot_points,
            p.median_spot_points,
            p.iterations,
            if p.under_resolved() {
                "  (spots under-resolved: refine the grid)"
            } else {
                ""
            }
        );
    }
    if let Ok((beta, _)) = sweep::power_law_fit(&result.points) {
        println!("kn ∝ p^β fit over the sweep: β = {beta:.4}");
    }
    let written = out.commit()?;
    println!(
        "wrote {} files in {}",
        written.len(),
        args.out_dir.display()
    );
    Ok(())
}
