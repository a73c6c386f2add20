//! `asperity merge`: the shard files of a sharded sweep (`--shard i/n`) → the outputs a single
//! run writes, byte for byte. Every shard must be present once and all must come from the same
//! configuration (see [`asperity::shard`]); every result read must be physical (see
//! [`check_surface`], [`check_realisation`]); the outputs appear together or not at all.

use asperity::calibrate::pipeline::RealisationChains;
use asperity::calibrate::sweep::CalibrationSweep;
use asperity::contact::surface_sweep::{SurfaceResult, SurfaceSource, SurfaceSweep};
use asperity::contact::sweep::SweepPoint;
use asperity::element::valanis::ValanisParams;
use asperity::error::num;
use asperity::output::OutputSet;
use asperity::shard::{self, ShardedSweep, UnitRecord};
use asperity::{Error, Result};
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct MergeArgs {
    /// Shard files (`<kind>.shard-<i>-of-<n>.json`): all n shards of one sweep, in any order.
    #[arg(required = true)]
    shards: Vec<PathBuf>,
    /// Output directory: receives the same files a single run of the sweep writes.
    #[arg(long)]
    out_dir: PathBuf,
}

/// Physical ranges of one solved pressure of a normal-contact sweep, as the solver guarantees
/// them (`asperity::sanity` refuses anything else when the shard is computed): the message
/// names the field.
fn check_point(p: &SweepPoint) -> std::result::Result<(), String> {
    // Pressing harder never loosens a contact: dp/dδ > 0.
    if !(p.kn_n_per_m3.is_finite() && p.kn_n_per_m3 > 0.0) {
        return Err(format!(
            "`kn_n_per_m3` = {} must be finite and > 0 (a contact stiffens under load)",
            num(p.kn_n_per_m3)
        ));
    }
    // A loaded contact touches somewhere, and never over more than the nominal area.
    if !(p.contact_area_ratio > 0.0 && p.contact_area_ratio <= 1.0) {
        return Err(format!(
            "`contact_area_ratio` = {} must lie in (0, 1] (real over nominal area)",
            num(p.contact_area_ratio)
        ));
    }
    for (name, v) in [("mean_gap_m", p.mean_gap_m), ("approach_m", p.approach_m)] {
        if !v.is_finite() {
            return Err(format!("`{name}` = {} is not finite", num(v)));
        }
    }
    Ok(())
}

/// One surface of a contact-normal shard: its grid is the one its configuration generates
/// (every shard of a sweep shares the configuration, so the grids agree across shards), it
/// holds exactly the configuration's pressures, and every point is physical.
fn check_surface(
    sweep: &SurfaceSweep,
    u: &UnitRecord<SurfaceResult>,
) -> std::result::Result<(), String> {
    let g = u.result.grid;
    if g.nx == 0
        || g.ny == 0
        || !(g.dx_m > 0.0 && g.dx_m.is_finite())
        || !(g.dy_m > 0.0 && g.dy_m.is_finite())
    {
        return Err(format!(
            "`grid` {} x {} points of {} x {} m is no grid",
            g.nx,
            g.ny,
            num(g.dx_m),
            num(g.dy_m)
        ));
    }
    if let Some(SurfaceSource::Generated { spec }) = sweep.surfaces.get(u.id) {
        if (g.nx, g.ny, g.dx_m, g.dy_m) != (spec.nx, spec.ny, spec.dx(), spec.dy()) {
            return Err(format!(
                "`grid` is {} x {} points of {} x {} m, but the configuration generates {} x {} \
                 points of {} x {} m",
                g.nx,
                g.ny,
                num(g.dx_m),
                num(g.dy_m),
                spec.nx,
                spec.ny,
                num(spec.dx()),
                num(spec.dy())
            ));
        }
    }
    let got: Vec<f64> = u.result.points.iter().map(|p| p.pressure_pa).collect();
    if got != sweep.pressures_pa {
        let list = |v: &[f64]| v.iter().map(|&p| num(p)).collect::<Vec<_>>().join(", ");
        return Err(format!(
            "`points` hold the pressures [{}] Pa, the configuration's are [{}] Pa",
            list(&got),
            list(&sweep.pressures_pa)
        ));
    }
    for p in &u.result.points {
        check_point(p).map_err(|m| format!("at {} Pa: {m}", num(p.pressure_pa)))?;
    }
    Ok(())
}

/// One realisation of a calibrate shard: every chain holds the configuration's pressures (in
/// order), each with a physical normal contact ([`check_point`]), an admissible Valanis
/// element (`E0 > 0`, `0 ≤ k < 1`, `0 ≤ Et < E0`, `μ > 0`) and a fit `r2` ≤ 1.
fn check_realisation(
    sweep: &CalibrationSweep,
    u: &UnitRecord<RealisationChains>,
) -> std::result::Result<(), String> {
    let pressures = &sweep.config.loading.pressures_pa;
    let chains = [
        ("main", Some(&u.result.main)),
        ("grid check", u.result.grid_check.as_ref()),
        ("patch check", u.result.patch_check.as_ref()),
    ];
    for (chain, r) in chains {
        let Some(r) = r else { continue };
        if r.pressures.len() != pressures.len() {
            return Err(format!(
                "{chain} chain: `pressures` holds {} entries, the configuration has {} pressures",
                r.pressures.len(),
                pressures.len()
            ));
        }
        for (pc, &p) in r.pressures.iter().zip(pressures) {
            let at = |m: String| format!("{chain} chain at {} Pa: {m}", num(p));
            // The table is indexed by the configuration's pressures: a result solved (or
            // edited) at another pressure would be reported as the configured one's.
            if pc.sweep.pressure_pa != p {
                return Err(at(format!(
                    "`pressure_pa` = {} Pa is not the configuration's pressure",
                    num(pc.sweep.pressure_pa)
                )));
            }
            check_point(&pc.sweep).map_err(at)?;
            let v = pc.fit.params;
            ValanisParams::new(v.e0, v.k, v.et, v.mu).map_err(|e| at(format!("fit: {e}")))?;
            if pc.fit.r2.is_nan() || pc.fit.r2 > 1.0 {
                return Err(at(format!(
                    "fit `r2` = {} must be <= 1 (a coefficient of determination)",
                    num(pc.fit.r2)
                )));
            }
        }
    }
    Ok(())
}

pub fn run(args: MergeArgs) -> Result<()> {
    // Refused now, before any shard is read: an --out-dir that is a file or not writable.
    let mut out = OutputSet::in_dir(&args.out_dir, "--out-dir")?;
    let kind = shard::read_kind(&args.shards[0])?;
    match kind.as_str() {
        SurfaceSweep::KIND => {
            let merged = shard::merge_checked::<SurfaceSweep>(&args.shards, check_surface)?;
            let staged = out.staging_dir()?;
            super::contact_normal::write_outputs(&merged.config, &merged.units, &staged)?;
            out.commit()?;
            super::contact_normal::print_summary(&merged.units)?;
            println!(
                "merged {} shards ({} surfaces, configuration {}) into {}",
                merged.shards,
                merged.units.len(),
                &merged.config_sha256[..12],
                args.out_dir.display()
            );
            Ok(())
        }
        CalibrationSweep::KIND => {
            let merged = shard::merge_checked::<CalibrationSweep>(&args.shards, check_realisation)?;
            // The run's wall time: the realisations' chains summed (they ran in other jobs).
            let chains_s = merged.units.iter().map(|u| u.wall_time_s).sum();
            let run = merged.config.assemble(&merged.units, chains_s)?;
            super::calibrate::write_and_report(&run, &merged.config.source, out)?;
            println!(
                "merged {} shards ({} realisations, configuration {}) into {}",
                merged.shards,
                merged.units.len(),
                &merged.config_sha256[..12],
                args.out_dir.display()
            );
            Ok(())
        }
        other => Err(Error::parse(
            &args.shards[0],
            0,
            format!(
                "shards of an unknown sweep kind `{other}` (known: {}, {})",
                SurfaceSweep::KIND,
                CalibrationSweep::KIND
            ),
        )),
    }
}
