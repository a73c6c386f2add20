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
use crate::element::valanis::ValanisParams;
use crate::error::{num, Result};
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

    /// One realisation read back from a shard: every chain holds the configuration's
    /// pressures (in order), each with a physical normal contact
    /// ([`crate::contact::sweep::SweepPoint::check_physical`]), an admissible Valanis element
    /// (`E0 > 0`, `0 ≤ k < 1`, `0 ≤ Et < E0`, `μ > 0`, [`ValanisParams::new`]) and a fit `r2`
    /// ≤ 1.
    fn check_unit(&self, u: &UnitRecord<RealisationChains>) -> std::result::Result<(), String> {
        let pressures = &self.config.loading.pressures_pa;
        let chains = [
            ("main", Some(&u.result.main)),
            ("grid check", u.result.grid_check.as_ref()),
            ("patch check", u.result.patch_check.as_ref()),
        ];
        for (chain, r) in chains {
            let Some(r) = r else { continue };
            if r.pressures.len() != pressures.len() {
                return Err(format!(
                    "{chain} chain: `pressures` holds {} entries, the configuration has {} \
                     pressures",
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
                pc.sweep.check_physical().map_err(at)?;
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
