//! `asperity merge`: the shard files of a sharded sweep (`--shard i/n`) → the outputs a single
//! run writes, byte for byte. Every shard must be present once and all must come from the same
//! configuration and every result read must be physical (see [`asperity::core::shard::merge`] and
//! each sweep's `check_unit`); the outputs appear together or not at all.

use asperity::calibrate::sweep::CalibrationSweep;
use asperity::contact::surface_sweep::SurfaceSweep;
use asperity::core::build_info::BuildId;
use asperity::core::output::OutputSet;
use asperity::core::shard::{self, ShardedSweep};
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

/// The shards agree on their build ([`shard::merge`] refuses otherwise); a merge by another
/// build still combines their results, but the files are written by this build's code, so the
/// outputs may differ from a single run of the shards' build: say so.
fn warn_other_build(shards: &BuildId) {
    let ours = BuildId::current();
    if *shards != ours {
        eprintln!(
            "warning: the shards were computed by {}; this merge runs {}: the outputs are written by this build's code and may differ from a single run of the shards' build",
            shards.describe(),
            ours.describe()
        );
    }
}

pub fn run(args: MergeArgs) -> Result<()> {
    // Refused now, before any shard is read: an --out-dir that is a file or not writable.
    let mut out = OutputSet::in_dir(&args.out_dir, "--out-dir")?;
    out.inputs(&args.shards, "shard file")?;
    let kind = shard::read_kind(&args.shards[0])?;
    match kind.as_str() {
        SurfaceSweep::KIND => {
            let merged = shard::merge::<SurfaceSweep>(&args.shards)?;
            warn_other_build(&merged.build);
            let staged = out.staging_dir()?;
            asperity::contact::normal_sweep::write_outputs(&merged.config, &merged.units, &staged)?;
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
            let merged = shard::merge::<CalibrationSweep>(&args.shards)?;
            warn_other_build(&merged.build);
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
