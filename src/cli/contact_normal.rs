//! `asperity contact normal`: pressure sweep of the normal contact solver on one or several
//! rough surfaces (generated seeds or files). Writes `normal_sweep.csv` (one row per surface and
//! pressure, SI units in the column names, reproducible bit for bit), `normal_sweep_timings.csv`
//! (wall times), with several surfaces `normal_sweep_statistics.csv` (mean and sample standard
//! deviation over the surfaces), `area_ratio.png`, `mean_gap.png`, `kn.png` (log axes) and, with
//! `--pressure-maps`, one pressure map PNG per surface and load.
//!
//! With `--hardness-pa` the contact is elastic–perfectly plastic (pressure ≤ H, see
//! [`asperity::contact::normal`]): the table gains the unloading and loading stiffnesses and the
//! elastic and plastic areas and the plastically displaced volume, and `--residual-surfaces`
//! writes the residual surface after unloading from each load (`.npy` with its sidecar).
//!
//! With `--shard i/n` only the surfaces of shard i are solved and their results go to
//! `<out-dir>/contact-normal.shard-i-of-n.json`; `asperity merge` turns the n files into the
//! same outputs a single run writes (see [`asperity::core::shard`]).

use asperity::contact::normal::{NormalMethod, NormalOptions};
use asperity::contact::normal_sweep::{self, NormalSweepConfig};
use asperity::contact::surface_sweep::{self, SurfaceResult};
use asperity::contact::sweep;
use asperity::core::material::Hardness;
use asperity::core::shard::{self, Shard, ShardedSweep, UnitRecord};
use asperity::Result;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct NormalArgs {
    /// Surface height file (heights in m; the format is recognised from the extension). Repeat
    /// the flag for several surfaces: realisations of one surface, averaged (mean ± std), not
    /// two bodies (give two bodies as their composite surface h1 − h2, `surface combine`). Default: the reference generated surface (Rq 0.177 µm,
    /// cl 6.6 µm, 250 µm, 1024², seed 1).
    #[arg(long, conflicts_with_all = ["seeds", "grid"])]
    surface: Vec<PathBuf>,
    /// Fill missing points of the --surface files first: `harmonic` (Laplace interpolation) or
    /// `nearest`. Without it a surface with missing points is refused.
    #[arg(long, requires = "surface")]
    fill: Option<asperity::surface::missing::Fill>,
    /// Seeds of generated reference surfaces, one surface each: a list and/or ranges, e.g.
    /// `1-8` or `1,2,5-7`.
    #[arg(long)]
    seeds: Option<String>,
    /// Grid points per side of the generated surfaces (same 250 µm patch and statistics;
    /// default 1024). Smaller values give a quick, coarser look.
    #[arg(long)]
    grid: Option<usize>,
    /// Nominal pressures (Pa), comma separated. Default: the reference sweep
    /// 0.1, 0.2, 1, 2, 5, 10 MPa.
    /// One comma-separated list per flag; values starting with `-` are taken as values, so
    /// that a negative pressure reaches the flag's own check, which names it.
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    pressures_pa: Option<Vec<f64>>,
    /// Young's modulus of both bodies (Pa).
    #[arg(long, default_value_t = 210e9, allow_hyphen_values = true)]
    youngs_modulus_pa: f64,
    /// Poisson's ratio of both bodies (-).
    #[arg(long, default_value_t = 0.3, allow_hyphen_values = true)]
    poisson_ratio: f64,
    /// Hardness H bounding the contact pressure (elastic–perfectly plastic contact): a value in
    /// Pa, or a material whose documented hardness to use: `steel-42crmo4` (340 HV,
    /// 3.334 GPa) or `inconel-718` (450 HV, 4.413 GPa); sources in docs/contact.md. The
    /// elastic constants stay those of --youngs-modulus-pa and --poisson-ratio. Without it the
    /// contact is elastic.
    #[arg(long, allow_hyphen_values = true)]
    hardness_pa: Option<String>,
    /// With --hardness-pa: also write the residual (plastically deformed) surface after
    /// unloading from each load, `residual_surface_<p>Pa.npy` (heights in m; sidecar
    /// `.npy.json`), for an elastic re-analysis (unloading and reloading are elastic on it).
    #[arg(long, requires = "hardness_pa")]
    residual_surfaces: bool,
    /// Output directory.
    #[arg(long, default_value = "out/contact-normal")]
    out_dir: PathBuf,
    /// Also write a pressure map PNG per load (and surface).
    #[arg(long)]
    pressure_maps: bool,
    /// Tolerance on the relative gap error of the contact solver.
    #[arg(long, default_value_t = NormalOptions::DEFAULT_TOLERANCE, allow_hyphen_values = true)]
    tolerance: f64,
    /// Iteration cap per solve (exceeding it is an error).
    #[arg(long, default_value_t = NormalOptions::default().max_iterations)]
    max_iterations: usize,
    /// Iteration: `auto` (= `preconditioned`: projected CG preconditioned by the inverse
    /// half-space compliance) or `polonsky-keer` (the reference path).
    #[arg(long, default_value = "auto")]
    method: String,
    /// Solve only shard i of n (1-based, e.g. `3/8`; the surfaces are split into n contiguous
    /// blocks) and write `<out-dir>/contact-normal.shard-i-of-n.json` for `asperity merge`.
    #[arg(long)]
    shard: Option<String>,
}

impl NormalArgs {
    /// The configuration of the flags (each parsed; checked by the library).
    fn config(&self) -> Result<NormalSweepConfig> {
        Ok(NormalSweepConfig {
            surface: self.surface.clone(),
            fill: self.fill,
            seeds: self
                .seeds
                .as_deref()
                .map(normal_sweep::parse_seeds)
                .transpose()?,
            grid: self.grid,
            pressures_pa: self.pressures_pa.clone(),
            youngs_modulus_pa: self.youngs_modulus_pa,
            poisson_ratio: self.poisson_ratio,
            hardness: self.hardness_pa.as_deref().map(Hardness::parse),
            residual_surfaces: self.residual_surfaces,
            pressure_maps: self.pressure_maps,
            tolerance: self.tolerance,
            max_iterations: self.max_iterations,
            method: self
                .method
                .parse::<NormalMethod>()
                .map_err(|e| e.renamed_param("--method"))?,
            shard: self
                .shard
                .as_deref()
                .map(|t| t.parse::<Shard>().map_err(|e| e.renamed_param("--shard")))
                .transpose()?,
        })
    }
}

pub fn run(args: NormalArgs) -> Result<()> {
    let config = args.config()?;
    // Check every input before any work or output; the files are staged and appear together
    // at the end (asperity::core::output::OutputSet).
    let mut out = normal_sweep::output_set(&config, &args.out_dir, "--out-dir")?;
    let sweep = config.sweep()?;
    let staged = out.staging_dir()?;
    let units = normal_sweep::run(
        &config,
        &sweep,
        &staged,
        &|len| super::progress_bar("normal contact", len),
        &mut |m| eprintln!("{m}"),
    )?;
    if let Some(shard) = config.shard {
        let path = out.final_path(&shard::write_shard(&staged, &sweep, shard, &units)?);
        out.commit()?;
        println!(
            "wrote {} (shard {shard}: {} of {} surfaces); merge all {} shards with `asperity merge`",
            path.display(),
            units.len(),
            sweep.unit_labels().len(),
            shard.count
        );
        return Ok(());
    }
    normal_sweep::write_outputs(&sweep, &units, &staged)?;
    print_summary(&units)?;
    let written = out.commit()?;
    println!(
        "wrote {} files in {}",
        written.len(),
        args.out_dir.display()
    );
    Ok(())
}

/// The console summary: each surface's sweep, its kn power law, and the statistics.
pub fn print_summary(units: &[UnitRecord<SurfaceResult>]) -> Result<()> {
    for u in units {
        if units.len() > 1 {
            println!("surface {}", u.label);
        }
        println!(
            "{:>12} {:>12} {:>12} {:>12} {:>7} {:>9} {:>9} {:>6}",
            "p (MPa)",
            "area ratio",
            "gap (µm)",
            "kn (N/m³)",
            "spots",
            "across c",
            "across f",
            "iter"
        );
        for p in &u.result.points {
            let r = &p.resolution;
            println!(
                "{:>12.4} {:>12.5} {:>12.5} {:>12.4e} {:>7} {:>9.1} {:>9.1} {:>6}{}",
                p.pressure_pa / 1e6,
                p.contact_area_ratio,
                p.mean_gap_m * 1e6,
                p.kn_n_per_m3,
                p.contact_spots,
                r.points_across_contact(),
                r.points_across_free(),
                p.iterations,
                if r.reaches_window_edge() {
                    // Free islands that look narrow are the window's cut, not the grid's; narrow
                    // contact spots are still the grid's.
                    if p.under_resolved() && r.contact_is_narrower() {
                        "  (contact reaches the window's edge: enlarge the window; contact spots under-resolved: refine the grid)"
                    } else {
                        "  (contact reaches the window's edge: enlarge the window)"
                    }
                } else if !p.under_resolved() {
                    ""
                } else if r.contact_is_narrower() {
                    "  (contact spots under-resolved: refine the grid)"
                } else {
                    "  (free islands under-resolved: refine the grid)"
                }
            );
        }
        if u.result.points.iter().any(|p| p.plastic.is_some()) {
            println!(
                "{:>12} {:>12} {:>12} {:>14} {:>14} {:>14}",
                "p (MPa)",
                "plastic area",
                "elastic area",
                "V_p (m³)",
                "kn unload",
                "kn load (N/m³)"
            );
            for p in &u.result.points {
                if let Some(pl) = &p.plastic {
                    println!(
                        "{:>12.4} {:>12.5} {:>12.5} {:>14.4e} {:>14.4e} {:>14.4e}",
                        p.pressure_pa / 1e6,
                        pl.plastic_area_ratio,
                        pl.elastic_area_ratio,
                        pl.plastic_volume_m3,
                        p.kn_n_per_m3,
                        pl.kn_loading_n_per_m3
                    );
                }
            }
            println!(
                "kn above is the unloading/reloading stiffness (the one an element carries); kn load is the loading tangent"
            );
        }
        if let Ok((beta, _)) = sweep::power_law_fit(&u.result.points) {
            println!("kn ∝ p^β fit over the sweep: β = {beta:.4}");
        }
        if let Some(w) = normal_sweep::window_edge_warning(u) {
            println!("warning: {w}");
        }
    }
    if units.len() > 1 {
        let results: Vec<&SurfaceResult> = units.iter().map(|u| &u.result).collect();
        println!(
            "over {} surfaces (mean ± sample standard deviation):",
            units.len()
        );
        println!(
            "{:>12} {:>24} {:>24} {:>26}",
            "p (MPa)", "area ratio", "gap (µm)", "kn (N/m³)"
        );
        for s in surface_sweep::statistics(&results)? {
            println!(
                "{:>12.4} {:>12.5} ± {:<9.3e} {:>12.5} ± {:<9.3e} {:>12.4e} ± {:<9.3e}",
                s.pressure_pa / 1e6,
                s.contact_area_ratio.mean,
                s.contact_area_ratio.std,
                s.mean_gap_m.mean * 1e6,
                s.mean_gap_m.std * 1e6,
                s.kn_n_per_m3.mean,
                s.kn_n_per_m3.std
            );
        }
    }
    Ok(())
}
