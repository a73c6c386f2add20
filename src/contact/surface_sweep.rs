//! The normal-contact sweep over several surfaces × loads: generated realisations (one per
//! seed) or measured files, each with its whole warm-started pressure sweep
//! ([`super::sweep::run`]).
//!
//! One surface is one unit of a [sharded sweep](crate::core::shard): the load steps of a surface are
//! warm-started one from the next, so they stay together, while surfaces are independent and can
//! run in any job of a cluster array. Units: pressures in Pa, lengths in m, kn in N/m³.
//!
//! With several random realisations, [`statistics`] gives the mean and the sample standard
//! deviation over the surfaces at each pressure (results of one random surface are never
//! reported alone).

use super::normal::{NormalOptions, NormalProblem, NormalSolution, NormalSolver};
use super::sweep::{self, checked_pressures, SweepOptions, SweepPoint};
use crate::core::error::{num, Error, Result};
use crate::core::grid::Grid2;
use crate::core::material::{composite_modulus, Material};
use crate::core::shard::{ShardedSweep, UnitRecord};
use crate::surface::generate::{generate, GaussianSurfaceSpec};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Where a surface of the sweep comes from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "source", rename_all = "kebab-case")]
pub enum SurfaceSource {
    /// A generated Gaussian patch (its seed names it).
    Generated {
        /// RMS height, correlation lengths, patch size, grid and seed of the patch.
        spec: GaussianSurfaceSpec,
    },
    /// A topography file (any format [`crate::surface::io::read`] reads), with the SHA-256 of
    /// its content so that every shard provably read the same file, and how its missing points
    /// are filled (none: a file with missing points is refused).
    File {
        /// Path of the file as given.
        path: String,
        /// SHA-256 of the file's content (hex).
        sha256: String,
        /// How missing points are filled (`None`: a file with missing points is refused).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        fill: Option<crate::surface::missing::Fill>,
    },
}

/// The reference generated surface's specification ([`GaussianSurfaceSpec::reference`]) on
/// `grid × grid` points when given (same patch and statistics), validated and within the
/// contact solvers' memory limit; errors name `--grid`.
pub fn reference_spec(grid: Option<usize>) -> Result<GaussianSurfaceSpec> {
    let mut spec = GaussianSurfaceSpec::reference();
    if let Some(n) = grid {
        spec.nx = n;
        spec.ny = n;
        spec.validate().map_err(|e| e.renamed_param("--grid"))?;
    }
    crate::core::limits::check_grid(
        "--grid",
        spec.nx,
        spec.ny,
        crate::core::limits::CONTACT_BYTES_PER_POINT,
    )?;
    Ok(spec)
}

impl SurfaceSource {
    /// A topography file, hashed now.
    pub fn file(path: &Path) -> Result<Self> {
        Self::file_filled(path, None)
    }

    /// A topography file, hashed now, whose missing points are filled by `fill`.
    pub fn file_filled(path: &Path, fill: Option<crate::surface::missing::Fill>) -> Result<Self> {
        Ok(SurfaceSource::File {
            path: path.display().to_string(),
            sha256: crate::core::hash::sha256_file(path)?,
            fill,
        })
    }

    /// Label of the surface in tables: `seed-<seed>` or the file path.
    pub fn label(&self) -> String {
        match self {
            SurfaceSource::Generated { spec } => format!("seed-{}", spec.seed),
            SurfaceSource::File { path, .. } => path.clone(),
        }
    }

    /// One-line description with the parameters (for file headers).
    pub fn describe(&self) -> String {
        match self {
            SurfaceSource::Generated { spec } => format!(
                "generated Gaussian surface (Rq {:e} m, correlation lengths {:e} x {:e} m, {:e} x {:e} m, {} x {} points, seed {})",
                spec.rq_m, spec.clx_m, spec.cly_m, spec.lx_m, spec.ly_m, spec.nx, spec.ny, spec.seed
            ),
            SurfaceSource::File { path, sha256, fill } => match fill {
                None => format!("{path} (sha256 {sha256})"),
                Some(f) => format!("{path} (sha256 {sha256}; missing points filled: {f:?})"),
            },
        }
    }

    /// The height map: generated, or read (refused when the file changed since it was hashed).
    pub fn load(&self) -> Result<Grid2> {
        match self {
            SurfaceSource::Generated { spec } => generate(spec),
            SurfaceSource::File { path, sha256, fill } => {
                let p = Path::new(path);
                let now = crate::core::hash::sha256_file(p)?;
                if &now != sha256 {
                    return Err(Error::Data(format!(
                        "{path}: content changed during the sweep (sha256 {now}, expected {sha256})"
                    )));
                }
                let (grid, report) = crate::surface::missing::load_area(p, *fill)?;
                crate::core::sanity::contact_file_grid(path, grid.nx(), grid.ny())?;
                if let Some(w) = crate::surface::stats::contact_surface_tilt(path, &grid) {
                    eprintln!("warning: {w}");
                }
                if let Some(r) = report {
                    eprintln!("{path}: {}", r.describe());
                }
                Ok(grid)
            }
        }
    }
}

/// The sweep: every surface × every pressure, one material for both bodies.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SurfaceSweep {
    /// The surfaces, one unit each.
    pub surfaces: Vec<SurfaceSource>,
    /// Nominal pressures (Pa), increasing (see [`checked_pressures`]).
    pub pressures_pa: Vec<f64>,
    /// Material of both bodies.
    pub material: Material,
    /// Hardness H bounding the contact pressure (Pa); `None` for elastic contact (see
    /// [`crate::contact::normal`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hardness_pa: Option<f64>,
    /// Contact solver settings.
    pub options: NormalOptions,
}

/// Grid of one surface of the sweep.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GridInfo {
    /// Points along x.
    pub nx: usize,
    /// Points along y.
    pub ny: usize,
    /// Spacing along x (m).
    pub dx_m: f64,
    /// Spacing along y (m).
    pub dy_m: f64,
    /// The surface is periodic (FFT kernels) rather than zero-padded.
    pub periodic: bool,
}

/// Result of one surface: the surface it was computed from, its grid and one point per
/// pressure.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SurfaceResult {
    /// The surface (as the sweep's configuration gives it) this result was computed from: a
    /// sharded sweep's merge checks it against the configuration's surface of the unit, so a
    /// result moved to another unit is refused (the grids of a sweep are usually all alike).
    pub surface: SurfaceSource,
    /// The surface's grid.
    pub grid: GridInfo,
    /// One point per sweep pressure, in increasing pressure.
    pub points: Vec<SweepPoint>,
}

impl ShardedSweep for SurfaceSweep {
    const KIND: &'static str = "contact-normal";
    type Unit = SurfaceResult;
    fn unit_labels(&self) -> Vec<String> {
        self.surfaces.iter().map(SurfaceSource::label).collect()
    }

    /// One surface read back from a shard: it was computed from the configuration's surface of
    /// this unit (`surface`: the seed and statistics of a generated one, the path, SHA-256 and
    /// fill of a file), its grid is the one its configuration generates
    /// (every shard of a sweep shares the configuration, so the grids agree across shards; a
    /// measured file's grid is not re-read here), it holds exactly the configuration's
    /// pressures, and every point is physical ([`SweepPoint::check_physical`]).
    fn check_unit(&self, u: &UnitRecord<SurfaceResult>) -> std::result::Result<(), String> {
        match self.surfaces.get(u.id) {
            Some(s) if *s == u.result.surface => {}
            Some(s) => {
                return Err(format!(
                    "`surface`: computed from {}, but the configuration's surface of this unit \
                     is {} (the result of another unit?)",
                    u.result.surface.describe(),
                    s.describe()
                ))
            }
            None => return Err(format!("the configuration has no surface {}", u.id)),
        }
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
        if let Some(SurfaceSource::Generated { spec }) = self.surfaces.get(u.id) {
            if (g.nx, g.ny, g.dx_m, g.dy_m) != (spec.nx, spec.ny, spec.dx(), spec.dy()) {
                return Err(format!(
                    "`grid` is {} x {} points of {} x {} m, but the configuration generates \
                     {} x {} points of {} x {} m",
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
        if got != self.pressures_pa {
            let list = |v: &[f64]| v.iter().map(|&p| num(p)).collect::<Vec<_>>().join(", ");
            return Err(format!(
                "`points` hold the pressures [{}] Pa, the configuration's are [{}] Pa",
                list(&got),
                list(&self.pressures_pa)
            ));
        }
        for p in &u.result.points {
            p.check_physical()
                .map_err(|m| format!("at {} Pa: {m}", num(p.pressure_pa)))?;
        }
        Ok(())
    }
}

impl SurfaceSweep {
    /// Check every setting before any work: pressures, material, solver options, at least one
    /// surface and unique labels.
    pub fn validate(&self) -> Result<()> {
        let sorted = checked_pressures(&self.pressures_pa)?;
        if sorted != self.pressures_pa {
            return Err(Error::param(
                "pressures_pa",
                "must be given in increasing order",
            ));
        }
        self.e_star_pa()?;
        self.options.validate()?;
        if let Some(h) = self.hardness_pa {
            crate::core::error::require_positive("hardness_pa", h)?;
            if let Some(&p) = self.pressures_pa.iter().find(|&&p| p >= h) {
                return Err(Error::param(
                    "pressures_pa",
                    format!(
                        "{} Pa is not below the hardness {} Pa (the whole patch at the \
                         hardness carries no more)",
                        num(p),
                        num(h)
                    ),
                ));
            }
            if self.options.method == crate::contact::normal::NormalMethod::PolonskyKeer {
                return Err(Error::param(
                    "method",
                    "the hardness-limited solve uses the preconditioned projected CG",
                ));
            }
        }
        for s in &self.surfaces {
            if let SurfaceSource::Generated { spec } = s {
                spec.validate()?;
            }
        }
        crate::core::shard::check_labels(&self.unit_labels())
    }

    /// Composite modulus E* of the two bodies (Pa).
    pub fn e_star_pa(&self) -> Result<f64> {
        composite_modulus(self.material, self.material)
    }

    fn sweep_options(&self, keep_solutions: bool) -> SweepOptions {
        SweepOptions { keep_solutions }
    }

    /// Unit `k`: load surface `k` and run its warm-started pressure sweep. With
    /// `keep_solutions` the converged solutions at the sweep pressures are returned too.
    /// `progress(j)` is called after the j-th pressure.
    pub fn run_unit(
        &self,
        k: usize,
        keep_solutions: bool,
        progress: impl FnMut(usize),
    ) -> Result<(SurfaceResult, Vec<NormalSolution>)> {
        let source = self
            .surfaces
            .get(k)
            .ok_or_else(|| Error::param("unit", format!("no surface {k}")))?;
        let surface = source.load()?;
        // Limits and physical sanity (asperity::limits, asperity::sanity) before the solver
        // allocates, and finite, positive results after it.
        let label = source.label();
        crate::core::limits::check_grid(
            &label,
            surface.nx(),
            surface.ny(),
            crate::core::limits::CONTACT_BYTES_PER_POINT,
        )?;
        crate::core::sanity::contact_surface(&surface, &label)?;
        crate::core::sanity::contact_pressures(
            "--pressures-pa",
            &self.pressures_pa,
            self.e_star_pa()?,
            &surface,
        )?;
        let mut solver = NormalSolver::new(
            &NormalProblem {
                surface: &surface,
                e_star_pa: self.e_star_pa()?,
                hardness_pa: self.hardness_pa,
            },
            self.options,
        )?;
        let sw = sweep::run(
            &mut solver,
            &self.pressures_pa,
            self.sweep_options(keep_solutions),
            progress,
        )
        .map_err(|e| match e {
            Error::Data(m) => Error::Data(format!("{}: {m}", source.label())),
            other => other,
        })?;
        for p in &sw.points {
            let at = |q: &str| {
                format!(
                    "{label}: {q} at {} Pa",
                    crate::core::error::num(p.pressure_pa)
                )
            };
            if p.contact_area_ratio >= 1.0 {
                // Full contact: the gap is closed everywhere and more load no longer moves the
                // bodies together in the half-space model, so kn is infinite — a limit of the
                // model, not a failed solve; say so rather than "kn is inf".
                return Err(Error::Data(format!(
                    "{label}: full contact at {} Pa (every point in contact, mean gap {:.3e} m): the half-space model's normal stiffness is infinite there; lower the pressure below the one that closes the last gap",
                    crate::core::error::num(p.pressure_pa),
                    p.mean_gap_m
                )));
            }
            crate::core::sanity::positive_result(&at("kn"), p.kn_n_per_m3)?;
            crate::core::sanity::finite_result(&at("the mean gap"), p.mean_gap_m)?;
            crate::core::sanity::finite_result(&at("the approach"), p.approach_m)?;
            crate::core::sanity::positive_result(
                &at("the contact area ratio"),
                p.contact_area_ratio,
            )?;
        }
        Ok((
            SurfaceResult {
                surface: source.clone(),
                grid: GridInfo {
                    nx: surface.nx(),
                    ny: surface.ny(),
                    dx_m: surface.dx,
                    dy_m: surface.dy,
                    periodic: surface.periodic,
                },
                points: sw.points,
            },
            sw.solutions,
        ))
    }
}

/// Mean and sample standard deviation of a quantity over the surfaces.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct MeanStd {
    /// Mean over the surfaces (unit of the quantity).
    pub mean: f64,
    /// Sample standard deviation (n − 1 in the denominator); NaN for one surface.
    pub std: f64,
}

impl MeanStd {
    /// Mean and sample standard deviation of `values` (summed in the given order).
    pub fn of(values: &[f64]) -> Self {
        let n = values.len() as f64;
        let mean = values.iter().sum::<f64>() / n;
        let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
        Self {
            mean,
            std: var.sqrt(),
        }
    }
}

/// Statistics over the surfaces at one pressure.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PressureStatistics {
    /// Nominal pressure `p̄` (Pa).
    pub pressure_pa: f64,
    /// Number of surfaces the statistics are over.
    pub surfaces: usize,
    /// Real over nominal contact area (dimensionless, 0–1).
    pub contact_area_ratio: MeanStd,
    /// Mean gap between the surfaces over the nominal area (m).
    pub mean_gap_m: MeanStd,
    /// Normal contact stiffness per unit area `dp̄/dδ` (N/m³).
    pub kn_n_per_m3: MeanStd,
    /// Rigid approach `δ` from first contact (m).
    pub approach_m: MeanStd,
}

/// Per-pressure mean and sample standard deviation over the surfaces (every result must hold
/// the same pressures).
pub fn statistics(results: &[&SurfaceResult]) -> Result<Vec<PressureStatistics>> {
    let Some(first) = results.first() else {
        return Err(Error::Data("no surface result".into()));
    };
    let pressures: Vec<f64> = first.points.iter().map(|p| p.pressure_pa).collect();
    for r in results {
        if r.points
            .iter()
            .map(|p| p.pressure_pa)
            .ne(pressures.iter().copied())
        {
            return Err(Error::Data(
                "surface results hold different pressures".into(),
            ));
        }
    }
    Ok(pressures
        .iter()
        .enumerate()
        .map(|(j, &p)| {
            let of = |f: fn(&SweepPoint) -> f64| {
                MeanStd::of(&results.iter().map(|r| f(&r.points[j])).collect::<Vec<_>>())
            };
            PressureStatistics {
                pressure_pa: p,
                surfaces: results.len(),
                contact_area_ratio: of(|s| s.contact_area_ratio),
                mean_gap_m: of(|s| s.mean_gap_m),
                kn_n_per_m3: of(|s| s.kn_n_per_m3),
                approach_m: of(|s| s.approach_m),
            }
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::shard::{merge, run_units, write_shard, Shard};

    fn small_sweep(seeds: &[u64]) -> SurfaceSweep {
        SurfaceSweep {
            surfaces: seeds
                .iter()
                .map(|&seed| SurfaceSource::Generated {
                    spec: GaussianSurfaceSpec {
                        nx: 32,
                        ny: 32,
                        lx_m: 100e-6,
                        ly_m: 100e-6,
                        clx_m: 10e-6,
                        cly_m: 10e-6,
                        seed,
                        ..GaussianSurfaceSpec::reference()
                    },
                })
                .collect(),
            pressures_pa: vec![1e6, 1e7],
            material: Material::STEEL,
            hardness_pa: None,
            options: NormalOptions::default(),
        }
    }

    /// A result moved to another unit (its label kept) is refused: the grids of the sweep's
    /// surfaces are alike, only the recorded surface tells them apart.
    #[test]
    fn results_must_be_the_units_own() {
        let sweep = small_sweep(&[1, 2]);
        let result = |k: usize| {
            let SurfaceSource::Generated { spec } = &sweep.surfaces[k] else {
                unreachable!()
            };
            UnitRecord {
                id: k,
                label: sweep.unit_labels()[k].clone(),
                wall_time_s: 0.0,
                result: SurfaceResult {
                    surface: sweep.surfaces[k].clone(),
                    grid: GridInfo {
                        nx: spec.nx,
                        ny: spec.ny,
                        dx_m: spec.dx(),
                        dy_m: spec.dy(),
                        periodic: true,
                    },
                    points: Vec::new(),
                },
            }
        };
        // Its own: past the identity and grid checks (then no point at the pressures).
        let e = sweep.check_unit(&result(1)).unwrap_err();
        assert!(e.starts_with("`points` hold the pressures []"), "{e}");
        // Unit 0's result in unit 1's place.
        let mut swapped = result(1);
        swapped.result = result(0).result;
        let e = sweep.check_unit(&swapped).unwrap_err();
        assert!(
            e.starts_with("`surface`: computed from generated") && e.contains("seed 1)"),
            "{e}"
        );
        assert!(e.contains("seed 2)") && e.contains("another unit"), "{e}");
    }

    #[test]
    fn mean_and_sample_std() {
        let m = MeanStd::of(&[1.0, 2.0, 3.0, 4.0]);
        assert_eq!(m.mean, 2.5);
        assert!((m.std - (5.0f64 / 3.0).sqrt()).abs() < 1e-15);
        assert!(MeanStd::of(&[3.0]).std.is_nan());
    }

    #[test]
    fn validation_names_the_problem() {
        let mut s = small_sweep(&[1, 1]);
        assert!(s.validate().unwrap_err().to_string().contains("twice"));
        s = small_sweep(&[1, 2]);
        s.pressures_pa = vec![2e6, 1e6];
        assert!(s.validate().unwrap_err().to_string().contains("increasing"));
        s = small_sweep(&[]);
        assert!(s.validate().unwrap_err().to_string().contains("no unit"));
    }

    /// Units are independent: sharded in any split, the results equal the single run's bit for
    /// bit (wall times aside), in a pool of one thread and of two.
    #[test]
    fn shards_reproduce_the_single_run() {
        let sweep = small_sweep(&[1, 2, 3]);
        sweep.validate().unwrap();
        let run = |shard: Shard, threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| {
                    run_units(&sweep, shard, |k| {
                        sweep.run_unit(k, false, |_| {}).map(|(r, _)| r)
                    })
                    .unwrap()
                })
        };
        let strip = |mut r: SurfaceResult| {
            r.points.iter_mut().for_each(|p| p.wall_time_s = 0.0);
            r
        };
        let whole: Vec<SurfaceResult> = run(Shard::WHOLE, 2)
            .into_iter()
            .map(|u| strip(u.result))
            .collect();
        let dir = tempfile::tempdir().unwrap();
        let paths: Vec<_> = (1..=2)
            .map(|i| {
                let shard = Shard::new(i, 2).unwrap();
                write_shard(dir.path(), &sweep, shard, &run(shard, 1)).unwrap()
            })
            .collect();
        let merged = merge::<SurfaceSweep>(&paths).unwrap();
        assert_eq!(merged.config, sweep);
        let merged: Vec<SurfaceResult> =
            merged.units.into_iter().map(|u| strip(u.result)).collect();
        assert_eq!(whole, merged);
        // Different surfaces give different answers (the comparison above can fail).
        assert_ne!(whole[0].points[0].mean_gap_m, whole[1].points[0].mean_gap_m);
        let stats = statistics(&whole.iter().collect::<Vec<_>>()).unwrap();
        assert_eq!(stats.len(), 2);
        assert_eq!(stats[0].surfaces, 3);
        assert!(stats[0].kn_n_per_m3.std > 0.0);
    }
}
