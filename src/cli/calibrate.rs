//! `asperity calibrate [CONFIG.toml] [--grid N] [--realisations N] [--surface FILE [--surface
//! FILE2]] [--out-dir calib]`: the whole chain surface → normal sweep → tangential loops at
//! several amplitudes → Valanis fits → calibration table (means and 95 % intervals over the
//! realisations), with grid and patch-size convergence checks, on the built-in reference case
//! when no configuration is given. Outputs (SI units, per unit nominal area): see
//! `asperity::calibrate::output`.

use asperity::calibrate::config::CalibrationConfig;
use asperity::calibrate::convergence::Verdict;
use asperity::calibrate::output::{self, describe_shape, ConfigSource};
use asperity::calibrate::pipeline::{self, CalibrationRun, RealisationChains, SurfaceSource};
use asperity::calibrate::sweep::CalibrationSweep;
use asperity::core::output::OutputSet;
use asperity::core::shard::{self, Shard, ShardedSweep, UnitRecord};
use asperity::{Error, Result};
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct CalibrateArgs {
    /// Calibration configuration (TOML; see calib/reference.toml). Default: the built-in
    /// reference case (Rq 0.177 µm, cl 6.6 µm, 250 µm, 1024², 8 realisations, steel, μ = 0.6,
    /// 0.1 0.2 1 2 5 10 MPa, amplitudes 0.2–1.5 × the gross-slip displacement).
    config: Option<PathBuf>,
    /// Grid points per side, overriding the configuration (same patch size): a quick look.
    #[arg(long)]
    grid: Option<usize>,
    /// Number of realisations (random surfaces of the configured statistics), overriding the
    /// configuration.
    #[arg(long)]
    realisations: Option<usize>,
    /// A measured surface instead of the generated ones (heights in m; every format `asperity
    /// surface stats` reads). Give it twice for two rough bodies: body 1, then body 2 in the
    /// common frame (as `asperity surface combine`); their equivalent surface h1 − h2 is used.
    /// Both bodies have the configuration's material. Non-periodic files use the zero-padded
    /// kernels. One surface is one realisation: no interval, no convergence checks.
    #[arg(long, num_args = 1)]
    surface: Vec<PathBuf>,
    /// Fill missing points of the --surface files first: `harmonic` (Laplace interpolation) or
    /// `nearest`. Without it a surface with missing points is refused.
    #[arg(long, requires = "surface")]
    fill: Option<asperity::surface::missing::Fill>,
    /// Output directory.
    #[arg(long, default_value = "calib")]
    out_dir: PathBuf,
    /// Run only shard i of n (1-based, e.g. `3/8`): the realisations are split into n
    /// contiguous blocks, each realisation with its grid- and patch-check chains, and the
    /// results go to `<out-dir>/calibrate.shard-i-of-n.json`; `asperity merge` writes from all n
    /// the files of a single run. Generated surfaces only.
    #[arg(long, value_name = "I/N")]
    shard: Option<String>,
}

pub fn run(args: CalibrateArgs) -> Result<()> {
    // Refused now, before the computation: an --out-dir that is a file or not writable.
    let mut out = OutputSet::in_dir(&args.out_dir, "--out-dir")?;
    out.writes(&output::files::ALL)?;
    out.owns("loop_fit_", "Pa.png")?;
    out.inputs(&args.config, "the configuration")?;
    super::surface_inputs(&mut out, &args.surface, "--surface")?;
    let (mut config, source) = match &args.config {
        Some(path) => {
            let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
            (
                CalibrationConfig::read(path)?,
                ConfigSource::file(path, &bytes),
            )
        }
        None => (CalibrationConfig::reference(), ConfigSource::BuiltIn),
    };
    if let Some(n) = args.grid {
        if !args.surface.is_empty() {
            return Err(Error::param(
                "--grid",
                "applies to the generated surfaces, not to a --surface file",
            ));
        }
        config.surface.nx = n;
        config.surface.ny = n;
        config.validate().map_err(|e| match e {
            Error::Limit { message, .. } => Error::limit("--grid", message),
            e => super::rename_param(e, "--grid"),
        })?;
    }
    if let Some(n) = args.realisations {
        if !args.surface.is_empty() && n != 1 {
            return Err(Error::param(
                "--realisations",
                "a --surface file is one realisation",
            ));
        }
        config.realisations.count = n;
        config
            .validate()
            .map_err(|e| super::rename_param(e, "--realisations"))?;
    }
    let shard = match &args.shard {
        Some(_) if !args.surface.is_empty() => return Err(Error::param(
            "--shard",
            "splits the realisations of generated surfaces; a --surface file is one realisation",
        )),
        Some(text) => Some(
            text.parse::<Shard>()
                .map_err(|e| super::rename_param(e, "--shard"))?,
        ),
        None => None,
    };
    let surfaces = if args.surface.is_empty() {
        SurfaceSource::Generated
    } else {
        let (surface, description) =
            asperity::surface::io::read_equivalent_surface(&args.surface, args.fill)
                .map_err(|e| super::rename_param(e, "--surface"))?;
        // A flat (or identical-bodies) surface has no rough contact: say so now, not as a
        // failed loop fit after the sweep.
        asperity::core::sanity::contact_surface(&surface, &description)?;
        config.realisations.count = 1;
        SurfaceSource::Given {
            surface,
            description,
        }
    };
    match &surfaces {
        SurfaceSource::Generated => {
            let s = &config.surface;
            eprintln!(
                "calibrate: {} realisation(s), {}×{} grid over {:e} m × {:e} m (Rq {:e} m, cl {:e} m)",
                config.realisations.count, s.nx, s.ny, s.lx_m, s.ly_m, s.rq_m, s.clx_m
            );
        }
        SurfaceSource::Given {
            surface,
            description,
        } => eprintln!(
            "calibrate: {description}, {}",
            super::surface_summary(surface)
        ),
    }
    eprintln!("calibrate: {}", output::describe_config(&config));
    if let Some(shard) = shard {
        return run_shard(CalibrationSweep { config, source }, shard, out);
    }
    let bar = super::progress_bar("calibrate", pipeline::progress_units(&config, &surfaces));
    let result = pipeline::run(&config, &surfaces, &bar);
    bar.finish_and_clear();
    write_and_report(&result?, &source, out)
}

/// `--shard i/n`: the chains of the shard's realisations → `calibrate.shard-i-of-n.json`.
fn run_shard(sweep: CalibrationSweep, shard: Shard, mut out: OutputSet) -> Result<()> {
    let labels = sweep.unit_labels();
    shard::check_labels(&labels)?;
    shard
        .check_units(labels.len(), "realisations")
        .map_err(|e| super::rename_param(e, "--shard"))?;
    let block = shard.units(labels.len());
    eprintln!(
        "calibrate: shard {shard}: realisations {}..{} ({} of {})",
        block.start + 1,
        block.end,
        block.len(),
        labels.len()
    );
    let source = SurfaceSource::Generated;
    let bar = super::progress_bar(
        "calibrate",
        pipeline::progress_units_of(&sweep.config, &source, block.len()),
    );
    let chains = pipeline::run_realisations(
        &sweep.config,
        &source,
        block.clone(),
        &bar,
        pipeline::Parallelism::ChainsConcurrently,
    );
    bar.finish_and_clear();
    let units: Vec<UnitRecord<RealisationChains>> = block
        .zip(chains?)
        .map(|(id, c)| UnitRecord {
            id,
            label: labels[id].clone(),
            wall_time_s: [Some(&c.main), c.grid_check.as_ref(), c.patch_check.as_ref()]
                .into_iter()
                .flatten()
                .map(|r| r.times.total_s)
                .sum(),
            result: c,
        })
        .collect();
    let staged = out.staging_dir()?;
    let path = out.final_path(&shard::write_shard(&staged, &sweep, shard, &units)?);
    out.commit()?;
    println!(
        "wrote {} (shard {shard}: {} of {} realisations); merge all {} shards with `asperity merge`",
        path.display(),
        units.len(),
        labels.len(),
        shard.count
    );
    Ok(())
}

/// Write the files of a calibration run (single or merged) into `out` and print its summary.
pub fn write_and_report(
    result: &CalibrationRun,
    source: &ConfigSource,
    mut out: OutputSet,
) -> Result<()> {
    // Every file is staged and appears at once (or not at all, on an error or an interrupt);
    // an earlier run's loop plots at pressures this run does not have are removed.
    out.owns("loop_fit_", "Pa.png")?;
    let (_, output_s) = output::write_outputs(result, source, &out.staging_dir()?)?;
    let written = out.commit()?;

    let n = result.realisations.len();
    println!(
        "means over {n} realisation(s){}:",
        if n >= 2 {
            ", ± half-width of the 95 % interval"
        } else {
            ""
        }
    );
    println!(
        "pressure_MPa  area_ratio    kn_N_per_m3              E0_N_per_m3              k                 mean_R2"
    );
    for (i, r) in result.table.rows.iter().enumerate() {
        let iv = result.table.intervals.as_ref().map(|v| v[i]);
        let pm = |h: Option<f64>| h.map_or(String::new(), |h| format!(" ± {h:.2e}"));
        println!(
            "{:>12.3}  {:>10.3e}  {:>10.4e}{:<13}  {:>10.4e}{:<13}  {:>6.4}{:<10}  {:>7.5}",
            r.pressure_pa / 1e6,
            r.contact_area_ratio,
            r.element.kn_n_per_m3,
            pm(iv.map(|v| v.kn_n_per_m3)),
            r.element.e0_n_per_m3,
            pm(iv.map(|v| v.e0_n_per_m3)),
            r.element.k,
            iv.map_or(String::new(), |v| format!(" ± {:.3}", v.k)),
            r.fit_r2
        );
    }
    let p: Vec<f64> = result.table.rows.iter().map(|r| r.pressure_pa).collect();
    let k: Vec<f64> = result.table.rows.iter().map(|r| r.element.k).collect();
    println!("mean k(p): {}", describe_shape(&p, &k));
    println!(
        "resolution and convergence (grid: same surfaces at half the points per side; patch: half the patch side, same spacing):"
    );
    println!("pressure_MPa  spots_per_patch  median_points_per_spot  grid          patch");
    for c in &result.convergence.pressures {
        println!(
            "{:>12.3}  {:>15.1}  {:>22}  {:<12}  {:<12}",
            c.pressure_pa / 1e6,
            c.contact_spots.mean,
            c.median_spot_points,
            c.grid_verdict.as_str(),
            c.patch_verdict.as_str()
        );
    }
    let converged = result
        .convergence
        .pressures
        .iter()
        .filter(|c| c.grid_verdict == Verdict::Converged && c.patch_verdict == Verdict::Converged)
        .count();
    println!(
        "{converged} of {} pressure(s) converged in both grid and patch size",
        result.convergence.pressures.len()
    );
    for w in &result.warnings {
        println!("warning: {w}");
    }
    let t = result.times;
    println!(
        "time: wall {:.1} s + output {:.1} s; CPU time of the stages summed over all chains ({} main{}): surface {:.1} s, normal {:.1} s, tangential {:.1} s, fit {:.1} s",
        t.total_s,
        output_s,
        result.realisations.len(),
        if result.grid_check.len() + result.patch_check.len() > 0 {
            format!(
                ", {} grid-check, {} patch-check",
                result.grid_check.len(),
                result.patch_check.len()
            )
        } else {
            String::new()
        },
        t.surface_cpu_s,
        t.normal_cpu_s,
        t.tangential_cpu_s,
        t.fit_cpu_s
    );
    for w in written {
        println!("wrote {}", w.display());
    }
    Ok(())
}
