//! `asperity contact normal`: pressure sweep of the normal contact solver on a rough surface.
//! Writes `normal_sweep.csv` (SI units in the column names), `area_ratio.png`, `mean_gap.png`,
//! `kn.png` (log axes) and, with `--pressure-maps`, one pressure map PNG per load.

use asperity::contact::normal::{NormalMethod, NormalOptions, NormalProblem, NormalSolver};
use asperity::contact::sweep::{self, SweepOptions, REFERENCE_PRESSURES_PA};
use asperity::plot::{heatmap, line_plot, HeatMap, LinePlot, Scale, Series};
use asperity::surface::combine::composite_modulus;
use asperity::{Error, Grid2, Result};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

#[derive(clap::Args)]
pub struct NormalArgs {
    /// Surface height file (heights in m; the format is recognised from the extension).
    /// Default: the reference generated surface (Rq 0.177 µm, cl 6.6 µm, 250 µm, 1024²).
    #[arg(long)]
    surface: Option<PathBuf>,
    /// Nominal pressures (Pa), comma separated. Default: the reference sweep
    /// 0.1, 0.2, 1, 2, 5, 10 MPa.
    #[arg(long, value_delimiter = ',', num_args = 1..)]
    pressures_pa: Option<Vec<f64>>,
    /// Young's modulus of both bodies (Pa).
    #[arg(long, default_value_t = 210e9)]
    youngs_modulus_pa: f64,
    /// Poisson's ratio of both bodies (-).
    #[arg(long, default_value_t = 0.3)]
    poisson_ratio: f64,
    /// Output directory.
    #[arg(long, default_value = "out/contact-normal")]
    out_dir: PathBuf,
    /// Also write a pressure map PNG per load.
    #[arg(long)]
    pressure_maps: bool,
    /// Tolerance on the relative gap error of the contact solver.
    #[arg(long, default_value_t = NormalOptions::DEFAULT_TOLERANCE)]
    tolerance: f64,
    /// Iteration cap per solve (exceeding it is an error).
    #[arg(long, default_value_t = NormalOptions::default().max_iterations)]
    max_iterations: usize,
    /// Iteration: `auto` (by the expected contact fraction), `preconditioned` (projected CG
    /// preconditioned by the inverse half-space compliance) or `polonsky-keer`.
    #[arg(long, default_value = "auto")]
    method: String,
}

/// Load the surface: a file, or the reference generated surface.
fn load_surface(path: Option<&Path>) -> Result<(Grid2, String)> {
    match path {
        Some(p) => {
            let grid = asperity::surface::io::read(p)?.into_area(&p.display().to_string())?;
            Ok((grid, p.display().to_string()))
        }
        None => {
            let spec = asperity::surface::generate::GaussianSurfaceSpec::reference();
            Ok((
                asperity::surface::generate::generate(&spec)?,
                format!(
                    "reference generated surface (Rq {} m, correlation length {} m, {} m, {}², seed {})",
                    spec.rq_m, spec.clx_m, spec.lx_m, spec.nx, spec.seed
                ),
            ))
        }
    }
}

pub fn run(args: NormalArgs) -> Result<()> {
    // Check every input before any work or output.
    let material = super::material_from_flags(args.youngs_modulus_pa, args.poisson_ratio)?;
    let e_star = composite_modulus(material, material)?;
    let pressures = sweep::checked_pressures(
        args.pressures_pa
            .as_deref()
            .unwrap_or(&REFERENCE_PRESSURES_PA),
    )
    .map_err(|e| super::rename_param(e, "--pressures-pa"))?;
    let method: NormalMethod = args
        .method
        .parse()
        .map_err(|e| super::rename_param(e, "--method"))?;
    let options = NormalOptions {
        tolerance: args.tolerance,
        max_iterations: args.max_iterations,
        method,
        ..NormalOptions::default()
    };
    let sweep_options = SweepOptions {
        keep_solutions: args.pressure_maps,
    };
    options.validate().map_err(|e| match e {
        Error::InvalidParameter { name, message } => {
            Error::param(format!("--{}", name.replace('_', "-")), message)
        }
        other => other,
    })?;
    let (surface, source) = load_surface(args.surface.as_deref())?;
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

    // CSV with a provenance header.
    let mut csv = String::new();
    let _ = writeln!(
        csv,
        "# asperity contact normal: pressure sweep, method {}",
        args.method
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
        "# tolerance = {:e} (relative gap error); kn = dp/d(approach) from the tangent problem on the contact set; points_across_* = 4 x points / interface edges (resolved when the smaller is >= {})",
        args.tolerance,
        asperity::contact::resolution::RESOLVED_POINTS_ACROSS
    );
    let _ = writeln!(
        csv,
        "pressure_Pa,contact_area_ratio,mean_gap_m,kn_N_per_m3,approach_m,contact_spots,smallest_spot_points,median_spot_points,points_across_contact,points_across_free,method,iterations,stiffness_iterations,residual,wall_time_s"
    );
    for p in &result.points {
        let _ = writeln!(
            csv,
            "{:e},{:e},{:e},{:e},{:e},{},{},{},{:.3},{:.3},{},{},{},{:e},{:.3}",
            p.pressure_pa,
            p.contact_area_ratio,
            p.mean_gap_m,
            p.kn_n_per_m3,
            p.approach_m,
            p.contact_spots,
            p.smallest_spot_points,
            p.median_spot_points,
            p.resolution.points_across_contact,
            p.resolution.points_across_free,
            p.method.name(),
            p.iterations,
            p.stiffness_iterations,
            p.residual,
            p.wall_time_s
        );
    }
    let csv_path = args.out_dir.join("normal_sweep.csv");
    asperity::output::write_string_atomic(&csv_path, &csv)?;

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
            &args.out_dir.join(file),
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
            &args
                .out_dir
                .join(format!("pressure_map_{:e}Pa.png", sol.mean_pressure_pa)),
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
        "p (MPa)", "area ratio", "gap (µm)", "kn (N/m³)", "spots", "across c", "across f", "iter"
    );
    for p in &result.points {
        let r = &p.resolution;
        println!(
            "{:>12.4} {:>12.5} {:>12.5} {:>12.4e} {:>7} {:>9.1} {:>9.1} {:>6}{}",
            p.pressure_pa / 1e6,
            p.contact_area_ratio,
            p.mean_gap_m * 1e6,
            p.kn_n_per_m3,
            p.contact_spots,
            r.points_across_contact,
            r.points_across_free,
            p.iterations,
            if !p.under_resolved() {
                ""
            } else if r.points_across_contact <= r.points_across_free {
                "  (contact spots under-resolved: refine the grid)"
            } else {
                "  (free islands under-resolved: refine the grid)"
            }
        );
    }
    if let Ok((beta, _)) = sweep::power_law_fit(&result.points) {
        println!("kn ∝ p^β fit over the sweep: β = {beta:.4}");
    }
    println!("wrote {}", args.out_dir.display());
    Ok(())
}
