//! `asperity calibrate [CONFIG.toml] [--grid N] [--out-dir calib]`: the whole chain surface →
//! normal sweep → tangential loops → Valanis fits → calibration table, on the built-in
//! reference case when no configuration is given. Outputs (SI units, per unit nominal area):
//! the table CSV, a fit report CSV, the loops CSV, PNGs of kn, E0, k versus pressure and of the
//! loops with their fits, and a JSON sidecar (config, crate version, input hashes).

use asperity::calibrate::config::CalibrationConfig;
use asperity::calibrate::pipeline::{self, describe_shape, ConfigSource};
use asperity::{Error, Result};
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct CalibrateArgs {
    /// Calibration configuration (TOML; see calib/reference.toml). Default: the built-in
    /// reference case (Rq 0.177 µm, cl 6.6 µm, 250 µm, 1024², steel, μ = 0.6,
    /// 0.1 0.2 1 2 5 10 MPa).
    config: Option<PathBuf>,
    /// Grid points per side, overriding the configuration (same patch size): a quick look.
    #[arg(long)]
    grid: Option<usize>,
    /// Output directory.
    #[arg(long, default_value = "calib")]
    out_dir: PathBuf,
}

pub fn run(args: CalibrateArgs) -> Result<()> {
    // Refused now, before the computation: an --out-dir that is a file or not writable.
    let mut out = asperity::output::OutputSet::in_dir(&args.out_dir, "--out-dir")?;
    let (mut config, source) = match &args.config {
        Some(path) => {
            let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
            (
                CalibrationConfig::read(path)?,
                ConfigSource::File {
                    path: path.clone(),
                    bytes,
                },
            )
        }
        None => (CalibrationConfig::reference(), ConfigSource::BuiltIn),
    };
    if let Some(n) = args.grid {
        config.surface.nx = n;
        config.surface.ny = n;
        config.validate().map_err(|e| match e {
            Error::InvalidParameter { message, .. } => Error::param("--grid", message),
            Error::Limit { message, .. } => Error::limit("--grid", message),
            other => other,
        })?;
    }
    let s = &config.surface;
    eprintln!(
        "calibrate: {}×{} grid over {:e} m × {:e} m (Rq {:e} m, cl {:e} m), μ = {}, {} pressures",
        s.nx,
        s.ny,
        s.lx_m,
        s.ly_m,
        s.rq_m,
        s.clx_m,
        config.contact.mu,
        config.loading.pressures_pa.len()
    );
    let bar = super::progress_bar("calibrate", pipeline::progress_units(&config));
    let result = pipeline::run(&config, &bar)?;
    bar.finish_and_clear();
    // Every file is staged and appears at once (or not at all, on an error or an interrupt).
    pipeline::write_outputs(&result, &source, &out.staging_dir()?)?;
    let written = out.commit()?;

    println!(
        "pressure_MPa  area_ratio   kn_N_per_m3   E0_N_per_m3       k   fit_R2  nrmse   energy_err"
    );
    for (r, pc) in result.table.rows.iter().zip(&result.pressures) {
        println!(
            "{:>12.3}  {:>10.3e}  {:>12.4e}  {:>12.4e}  {:>6.4}  {:>7.5}  {:>5.3}  {:>+10.2e}",
            r.pressure_pa / 1e6,
            r.contact_area_ratio,
            r.kn_n_per_m3,
            r.e0_n_per_m3,
            r.k,
            r.fit_r2,
            pc.fit.nrmse,
            pc.fit.energy_rel_error
        );
    }
    let p: Vec<f64> = result.table.rows.iter().map(|r| r.pressure_pa).collect();
    let k: Vec<f64> = result.table.rows.iter().map(|r| r.k).collect();
    println!("k(p): {}", describe_shape(&p, &k));
    let at_bound: Vec<String> = result
        .table
        .rows
        .iter()
        .filter(|r| r.k < pipeline::K_BOUND_FLAG)
        .map(|r| format!("{} MPa", r.pressure_pa / 1e6))
        .collect();
    if !at_bound.is_empty() {
        println!(
            "note: k reached its lower bound 0 at {} (the BEM loop's microslip transition is \
             more gradual than any Valanis element with k >= 0 gives; the fit is the best k = 0 \
             element)",
            at_bound.join(", ")
        );
    }
    let t = result.times;
    println!(
        "time: surface {:.1} s, normal sweep {:.1} s, loops {:.1} s, fits {:.1} s, total {:.1} s",
        t.surface_s, t.normal_sweep_s, t.tangential_loops_s, t.fits_s, t.total_s
    );
    for w in written {
        println!("wrote {}", w.display());
    }
    Ok(())
}
