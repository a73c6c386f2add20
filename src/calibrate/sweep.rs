//! The calibration as a sharded sweep (`asperity calibrate --shard i/n`, see
//! [`crate::core::shard`]): the unit is one **realisation** — its main chain over all pressures and
//! amplitudes (one Masing amplitude history per pressure) and its grid- and patch-check chains
//! ([`RealisationChains`]) — so realisation `r` computes the same numbers, bit for bit, in a
//! single run and in any shard. The merge assembles the table, convergence verdicts and
//! warnings from all realisations ([`pipeline::assemble`]) and writes the files of a single run
//! ([`crate::calibrate::output::write_outputs`]); only `calibration_timings.csv` differs.
//!
//! Units: SI, as [`crate::calibrate::pipeline`].

use crate::calibrate::config::CalibrationConfig;
use crate::calibrate::output::ConfigSource;
use crate::calibrate::pipeline::{
    self, CalibrationRun, Chain, Realisation, RealisationChains, SurfaceSource,
};
use crate::core::error::{num, Result};
use crate::core::shard::{ShardedSweep, UnitRecord};
use crate::element::valanis::ValanisParams;
use crate::surface::generate::GaussianSurfaceSpec;
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

    /// One realisation read back from a shard: it holds exactly the chains the configuration
    /// runs, each computed from the surface the configuration prescribes for this realisation
    /// (seed, grid and patch of [`pipeline::chain_spec`]: a realisation's result moved to
    /// another unit, or a grid-check chain put in the main chain's place, is refused); every
    /// chain holds the configuration's pressures (in order), each with a physical normal contact
    /// ([`crate::contact::sweep::SweepPoint::check_physical`]), an admissible Valanis element
    /// (`E0 > 0`, `0 ≤ k < 1`, `0 ≤ Et < E0`, `μ > 0`, [`ValanisParams::new`]) and a fit `r2`
    /// ≤ 1.
    fn check_unit(&self, u: &UnitRecord<RealisationChains>) -> std::result::Result<(), String> {
        let pressures = &self.config.loading.pressures_pa;
        let chains = [
            (Chain::Main, Some(&u.result.main)),
            (Chain::GridCheck, u.result.grid_check.as_ref()),
            (Chain::PatchCheck, u.result.patch_check.as_ref()),
        ];
        // Which surface each chain was computed from, for all chains before their numbers: a
        // result of another unit or chain is named as such.
        let mut present = Vec::with_capacity(chains.len());
        for (which, r) in chains {
            let chain = which.name();
            match (r, pipeline::chain_spec(&self.config, which, u.id)) {
                (None, None) => {}
                (Some(_), None) => {
                    return Err(format!(
                        "{chain} chain present, but the configuration does not run that check"
                    ))
                }
                (None, Some(_)) => {
                    return Err(format!(
                        "{chain} chain missing, but the configuration runs that check"
                    ))
                }
                (Some(r), Some(spec)) => {
                    check_surface(r, &spec).map_err(|m| format!("{chain} chain: {m}"))?;
                    present.push((chain, r));
                }
            }
        }
        for (chain, r) in present {
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

/// The chain `r` was computed from the generated surface `spec`: same seed, grid and patch.
fn check_surface(r: &Realisation, spec: &GaussianSurfaceSpec) -> std::result::Result<(), String> {
    // As the generated grid records it: n points of spacing l/n.
    let patch = (spec.nx as f64 * spec.dx(), spec.ny as f64 * spec.dy());
    if r.seed == Some(spec.seed) && r.grid == (spec.nx, spec.ny) && r.patch_m == patch {
        return Ok(());
    }
    let seed = r.seed.map_or("none".to_string(), |s| s.to_string());
    Err(format!(
        "computed from seed {seed}, {} x {} points, patch {} x {} m; the configuration \
         prescribes seed {}, {} x {} points, patch {} x {} m for this unit (results of another \
         realisation or chain?)",
        r.grid.0,
        r.grid.1,
        num(r.patch_m.0),
        num(r.patch_m.1),
        spec.seed,
        spec.nx,
        spec.ny,
        num(patch.0),
        num(patch.1)
    ))
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibrate::pipeline::StageTimes;

    fn sweep() -> CalibrationSweep {
        CalibrationSweep {
            config: CalibrationConfig::reference(),
            source: ConfigSource::BuiltIn,
        }
    }

    /// The chain `chain` of realisation `r` as the pipeline records it (no pressure: the
    /// identity is checked before the pressures).
    fn chain(sweep: &CalibrationSweep, chain: Chain, r: usize) -> Realisation {
        let spec = pipeline::chain_spec(&sweep.config, chain, r).expect("the check runs");
        Realisation {
            seed: Some(spec.seed),
            grid: (spec.nx, spec.ny),
            patch_m: (spec.nx as f64 * spec.dx(), spec.ny as f64 * spec.dy()),
            surface_sha256: String::new(),
            pressures: Vec::new(),
            times: StageTimes::default(),
        }
    }

    fn unit(sweep: &CalibrationSweep, id: usize, r: usize) -> UnitRecord<RealisationChains> {
        UnitRecord {
            id,
            label: sweep.unit_labels()[id].clone(),
            wall_time_s: 0.0,
            result: RealisationChains {
                main: chain(sweep, Chain::Main, r),
                grid_check: Some(chain(sweep, Chain::GridCheck, r)),
                patch_check: Some(chain(sweep, Chain::PatchCheck, r)),
            },
        }
    }

    /// The specs the pipeline generates: main seed s + r, grid check the same seed at half the
    /// points, patch check seed s + count + r on the half patch.
    #[test]
    fn chain_specs_follow_the_pipeline() {
        let c = CalibrationConfig::reference();
        let s = c.surface;
        let main = pipeline::chain_spec(&c, Chain::Main, 2).unwrap();
        assert_eq!(
            main,
            GaussianSurfaceSpec {
                seed: s.seed + 2,
                ..s
            }
        );
        let grid = pipeline::chain_spec(&c, Chain::GridCheck, 2).unwrap();
        assert_eq!(
            (grid.seed, grid.nx, grid.lx_m),
            (s.seed + 2, s.nx / 2, s.lx_m)
        );
        let patch = pipeline::chain_spec(&c, Chain::PatchCheck, 2).unwrap();
        assert_eq!(patch.seed, s.seed + c.realisations.count as u64 + 2);
        assert_eq!((patch.nx, patch.dx()), (s.nx / 2, s.dx()));
    }

    /// A realisation's chains at their own unit pass the identity check (and fail later, on
    /// the pressures this fake holds none of); moved to another unit, swapped between chains
    /// or missing a chain, they are refused naming the chain.
    #[test]
    fn chains_must_be_the_units_own() {
        let sw = sweep();
        let own = sw.check_unit(&unit(&sw, 1, 1)).unwrap_err();
        assert!(
            own.starts_with("main chain: `pressures` holds 0 entries"),
            "{own}"
        );

        // Realisation 0's results under unit 1's label (a swap of `result` blocks).
        let e = sw.check_unit(&unit(&sw, 1, 0)).unwrap_err();
        assert!(
            e.starts_with("main chain: computed from seed 1,") && e.contains("seed 2,"),
            "{e}"
        );
        // The grid check's chain in the main chain's place: same seed, another grid.
        let mut u = unit(&sw, 1, 1);
        u.result.main = u.result.grid_check.clone().unwrap();
        let e = sw.check_unit(&u).unwrap_err();
        assert!(
            e.starts_with("main chain: computed from seed 2, 512 x 512 points")
                && e.contains("1024 x 1024 points"),
            "{e}"
        );
        // Grid and patch checks swapped.
        let mut u = unit(&sw, 1, 1);
        std::mem::swap(&mut u.result.grid_check, &mut u.result.patch_check);
        let e = sw.check_unit(&u).unwrap_err();
        assert!(
            e.starts_with("grid check chain: computed from seed 10,"),
            "{e}"
        );
        // Only the patch check's seed differs (its grid and patch are the same for every unit).
        let mut u = unit(&sw, 1, 1);
        u.result.patch_check = Some(chain(&sw, Chain::PatchCheck, 3));
        let e = sw.check_unit(&u).unwrap_err();
        assert!(
            e.starts_with("patch check chain: computed from seed 12,"),
            "{e}"
        );
        // A chain of a check the configuration runs is missing.
        let mut u = unit(&sw, 1, 1);
        u.result.patch_check = None;
        let e = sw.check_unit(&u).unwrap_err();
        assert!(e.starts_with("patch check chain missing"), "{e}");
    }

    /// A check the configuration does not run (the grid check of a grid too coarse to halve)
    /// must not be present.
    #[test]
    fn chains_of_checks_not_run_are_refused() {
        let mut sw = sweep();
        let mut u = unit(&sw, 0, 0);
        sw.config.surface.nx = 8;
        sw.config.surface.ny = 8;
        assert!(pipeline::chain_spec(&sw.config, Chain::GridCheck, 0).is_none());
        u.result.main = chain(&sw, Chain::Main, 0);
        let e = sw.check_unit(&u).unwrap_err();
        assert!(e.starts_with("grid check chain present"), "{e}");
    }
}
