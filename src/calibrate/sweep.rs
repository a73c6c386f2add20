//! The calibration as a sharded sweep (`asperity calibrate --shard i/n`, see
//! [`crate::shard`]): the unit is one **realisation** — its main chain over all pressures and
//! amplitudes (one Masing amplitude history per pressure) and its grid- and patch-check chains
//! ([`RealisationChains`]) — so realisation `r` computes the same numbers, bit for bit, in a
//! single run and in any shard. The merge assembles the table, convergence verdicts and
//! warnings from all realisations ([`pipeline::assemble`]) and writes the files of a single run
//! ([`crate::calibrate::output::write_outputs`]); only `calibration_timings.csv` differs.
//!
//! Units: SI, as [`crate::calibrate::pipeline`].

use crate::calibrate::config::CalibrationConfig;
use crate::calibrate::output::ConfigSource;
use crate::calibrate::pipeline::{self, CalibrationRun, RealisationChains, SurfaceSource};
use crate::error::Result;
use crate::shard::{ShardedSweep, UnitRecord};
use serde::{Deserialize, Serialize};

/// A calibration over generated surfaces: the effective configuration (overrides applied) and
/// where it came from (recorded in the sidecar, so part of the sweep's identity).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CalibrationSweep {
    /// The configuration the realisations ran with.
    pub config: CalibrationConfig,
    /// Its source (built-in case or file with the file's SHA-256).
    pub source: ConfigSource,
}

impl ShardedSweep for CalibrationSweep {
    const KIND: &'static str = "calibrate";
    type Unit = RealisationChains;
    /// `seed-<seed>` of each realisation's main surface.
    fn unit_labels(&self) -> Vec<String> {
        let s = &self.config.surface;
        (0..self.config.realisations.count)
            .map(|r| format!("seed-{}", s.seed.wrapping_add(r as u64)))
            .collect()
    }
}

impl CalibrationSweep {
    /// The run of a single process from the realisations' chains in order (e.g. merged from the
    /// shards); `total_s` is the wall time to report.
    pub fn assemble(
        &self,
        units: &[UnitRecord<RealisationChains>],
        total_s: f64,
    ) -> Result<CalibrationRun> {
        pipeline::assemble(
            &self.config,
            &SurfaceSource::Generated,
            units.iter().map(|u| u.result.clone()).collect(),
            total_s,
        )
    }
}
