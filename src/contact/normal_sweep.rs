//! `asperity contact normal` as a library call: the pressure sweep of the normal contact solver
//! on one or several rough surfaces (generated seeds or files). [`NormalSweepConfig::sweep`]
//! checks the parameters and gives the [`SurfaceSweep`]; [`run`] solves the surfaces of a shard
//! ([`SurfaceSweep::run_unit`], warm-started loads), writing the pressure maps and residual
//! surfaces of each as it goes; [`write_outputs`] writes the sweep's table, timings,
//! statistics and plots (for a single run and for `asperity merge` of shards alike).
//!
//! Outputs: `normal_sweep.csv` (one row per surface and pressure, SI units in the column names,
//! reproducible bit for bit), `normal_sweep_timings.csv` (wall times), with several surfaces
//! `normal_sweep_statistics.csv` (mean and sample standard deviation over the surfaces),
//! `area_ratio.png`, `mean_gap.png`, `kn.png` (log axes) and, when asked, one pressure map PNG
//! per surface and load and, with a hardness, the residual surface after unloading from each
//! load (`.npy` with its sidecar).

use super::normal::{NormalMethod, NormalOptions, NormalSolution};
use super::surface_sweep::{self, SurfaceResult, SurfaceSource, SurfaceSweep};
use super::sweep::{self, REFERENCE_PRESSURES_PA};
use crate::core::error::{Error, Result};
use crate::core::material::Hardness;
use crate::core::output::OutputSet;
use crate::core::plot::{heatmap, line_plot, HeatMap, LinePlot, Scale, Series};
use crate::core::shard::{self, Shard, ShardedSweep, UnitRecord};
use crate::surface::generate::GaussianSurfaceSpec;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The parameters of `asperity contact normal`, one per flag (SI units; errors name the flags).
#[derive(Debug, Clone, PartialEq)]
pub struct NormalSweepConfig {
    /// Surface height files: realisations of one surface, averaged (empty: generated surfaces).
    pub surface: Vec<PathBuf>,
    /// Fill missing points of the files first.
    pub fill: Option<crate::surface::missing::Fill>,
    /// Seeds of generated reference surfaces, one surface each (`None`: the reference seed).
    pub seeds: Option<Vec<u64>>,
    /// Grid points per side of the generated surfaces (`None`: the reference 1024).
    pub grid: Option<usize>,
    /// Nominal pressures (Pa); `None`: [`REFERENCE_PRESSURES_PA`].
    pub pressures_pa: Option<Vec<f64>>,
    /// Young's modulus of both bodies (Pa).
    pub youngs_modulus_pa: f64,
    /// Poisson's ratio of both bodies (-).
    pub poisson_ratio: f64,
    /// Hardness H bounding the pressure; `None`: elastic contact.
    pub hardness: Option<Hardness>,
    /// Write the residual surface after unloading from each load (with a hardness).
    pub residual_surfaces: bool,
    /// Write a pressure map PNG per load and surface.
    pub pressure_maps: bool,
    /// Tolerance on the relative gap error of the contact solver.
    pub tolerance: f64,
    /// Iteration cap per solve.
    pub max_iterations: usize,
    /// Iteration of the solver.
    pub method: NormalMethod,
    /// Solve only this shard of the surfaces (`None`: all of them).
    pub shard: Option<Shard>,
}

/// The output set of a run into `out_dir` (`flag` names it in errors), declared before any
/// work: without a shard the files of [`OUTPUT_FILES`] and every pressure map and residual
/// surface (an earlier run's at other pressures are removed); the surface files are inputs.
/// Per-surface files are refused with a shard (its file holds no fields for `asperity merge`).
pub fn output_set(config: &NormalSweepConfig, out_dir: &Path, flag: &str) -> Result<OutputSet> {
    if config.shard.is_some() && config.residual_surfaces {
        return Err(Error::param(
            "--residual-surfaces",
            "not with --shard: the shard files hold no surfaces, so `asperity merge` cannot \
             give the residual surfaces a single run writes; write them in a run without --shard",
        ));
    }
    if config.shard.is_some() && config.pressure_maps {
        // `merge` rebuilds the sweep's tables and plots from the shard files, which hold no
        // pressure fields: a merged run would lack the maps a single run writes.
        return Err(Error::param(
            "--pressure-maps",
            "not with --shard: the shard files hold no pressure fields, so `asperity merge` \
             cannot give the maps a single run writes; draw them in a run without --shard of \
             the pressures wanted",
        ));
    }
    let mut out = OutputSet::in_dir(out_dir, flag)?;
    if config.shard.is_none() {
        // An earlier run's maps at pressures this run does not have are removed.
        out.owns("pressure_map_", "Pa.png")?;
        out.owns("residual_surface_", "Pa.npy")?;
        out.owns("residual_surface_", "Pa.npy.json")?;
        out.writes(&OUTPUT_FILES)?;
    }
    crate::surface::io::declare_inputs(&mut out, &config.surface, "--surface")?;
    Ok(out)
}

/// Solve the surfaces of the configuration's shard (all without one) of `sweep`, writing the
/// pressure maps and residual surfaces asked for into `out_dir` as each surface is done.
/// `progress` makes the progress bar for a number of solves; `log` takes the description of
/// the run.
pub fn run(
    config: &NormalSweepConfig,
    sweep: &SurfaceSweep,
    out_dir: &Path,
    progress: &dyn Fn(u64) -> indicatif::ProgressBar,
    log: &mut dyn FnMut(&str),
) -> Result<Vec<UnitRecord<SurfaceResult>>> {
    let shard = config.shard.unwrap_or(Shard::WHOLE);
    let e_star = sweep.e_star_pa()?;
    let labels = sweep.unit_labels();
    shard
        .check_units(labels.len(), "surfaces")
        .map_err(|e| e.renamed_param("--shard"))?;
    let block = shard.units(labels.len());
    log(&format!(
        "{} surface(s), E* = {e_star:.4e} Pa{}, {} pressures{}",
        labels.len(),
        match sweep.hardness_pa {
            Some(h) => format!(", hardness H = {h:.4e} Pa (elastic–perfectly plastic)"),
            None => String::new(),
        },
        sweep.pressures_pa.len(),
        if config.shard.is_some() {
            format!(
                "; shard {shard}: surfaces {}..{} ({} of them)",
                block.start + 1,
                block.end,
                block.len()
            )
        } else {
            String::new()
        }
    ));
    if config.surface.len() > 1 {
        // `contact tangential` takes two --surface files as two bodies; here they are
        // realisations. Say so, so that two bodies are not silently averaged.
        log(&realisations_note(config.surface.len()));
    }
    let per_unit = sweep.pressures_pa.len() as u64;
    let bar = progress(block.len() as u64 * per_unit);
    let mut done = 0;
    let units = shard::run_units(sweep, shard, |k| {
        bar.set_message(labels[k].clone());
        let keep = config.pressure_maps || config.residual_surfaces;
        let (result, solutions) = sweep.run_unit(k, keep, |j| bar.set_position(done + j as u64))?;
        done += per_unit;
        if config.pressure_maps {
            write_pressure_maps(out_dir, sweep, k, &solutions)?;
        }
        if config.residual_surfaces {
            write_residual_surfaces(out_dir, sweep, k, &solutions)?;
        }
        Ok(result)
    });
    bar.finish_and_clear();
    units
}

/// Seeds from `1-8`, `1,2,5-7`, ...: each once, in the order given.
pub fn parse_seeds(text: &str) -> Result<Vec<u64>> {
    let bad = |m: String| Error::param("--seeds", m);
    let mut seeds = Vec::new();
    for part in text.split(',').map(str::trim) {
        let num = |t: &str| {
            t.trim()
                .parse::<u64>()
                .map_err(|_| bad(format!("`{t}` is not a seed (a non-negative integer)")))
        };
        match part.split_once('-') {
            Some((a, b)) => {
                let (a, b) = (num(a)?, num(b)?);
                if a > b {
                    return Err(bad(format!("range `{part}` is empty")));
                }
                seeds.extend(a..=b);
            }
            None => seeds.push(num(part)?),
        }
    }
    let mut seen = std::collections::HashSet::new();
    if let Some(s) = seeds.iter().find(|s| !seen.insert(**s)) {
        return Err(bad(format!("seed {s} given twice")));
    }
    Ok(seeds)
}

/// The surfaces of the sweep: files, or generated reference surfaces (seeds, grid).
fn surfaces(args: &NormalSweepConfig) -> Result<Vec<SurfaceSource>> {
    if !args.surface.is_empty() {
        return args
            .surface
            .iter()
            .map(|p| SurfaceSource::file_filled(p, args.fill))
            .collect();
    }
    let seeds = match &args.seeds {
        Some(s) => s.clone(),
        None => vec![GaussianSurfaceSpec::REFERENCE_SEED],
    };
    let spec = surface_sweep::reference_spec(args.grid)?;
    Ok(seeds
        .into_iter()
        .map(|seed| SurfaceSource::Generated {
            spec: GaussianSurfaceSpec { seed, ..spec },
        })
        .collect())
}

/// The meaning of several --surface files in `contact normal` (printed with them): realisations
/// of one surface, averaged; not two bodies, as in `contact tangential`.
pub fn realisations_note(n: usize) -> String {
    format!(
        "{n} surfaces: treated as {n} realisations of one surface (mean ± std); two bodies in \
         contact: give their composite surface (h1 − h2, `asperity surface combine`) as one file"
    )
}

impl NormalSweepConfig {
    /// The sweep of the configuration, every input checked, errors naming the flag.
    pub fn sweep(&self) -> Result<SurfaceSweep> {
        let args = self;
        crate::core::sanity::tolerance("--tolerance", args.tolerance)?;
        if let Some(p) = &args.pressures_pa {
            crate::core::limits::check_count(
                "--pressures-pa",
                p.len(),
                crate::core::limits::MAX_PRESSURES,
            )?;
        }
        let material =
            crate::core::material::from_flags(args.youngs_modulus_pa, args.poisson_ratio)?;
        let pressures_pa = sweep::checked_pressures(
            args.pressures_pa
                .as_deref()
                .unwrap_or(&REFERENCE_PRESSURES_PA),
        )
        .map_err(|e| e.renamed_param("--pressures-pa"))?;
        let method = args.method;
        let options = NormalOptions {
            tolerance: args.tolerance,
            max_iterations: args.max_iterations,
            method,
            ..NormalOptions::default()
        };
        options.validate().map_err(|e| match e {
            Error::InvalidParameter { name, message } => {
                Error::param(format!("--{}", name.replace('_', "-")), message)
            }
            other => other,
        })?;
        let hardness_pa = args
            .hardness
            .as_ref()
            .map(|h| h.pa("--hardness-pa"))
            .transpose()?;
        let sweep = SurfaceSweep {
            surfaces: surfaces(args)?,
            pressures_pa,
            material,
            hardness_pa,
            options,
        };
        sweep.validate().map_err(|e| match e {
            Error::InvalidParameter { ref name, .. } if name == "units" => {
                e.renamed_param("--surface / --seeds")
            }
            Error::InvalidParameter { ref name, .. } if name == "pressures_pa" => {
                e.renamed_param("--pressures-pa")
            }
            Error::InvalidParameter { ref name, .. } if name == "method" => {
                e.renamed_param("--method")
            }
            e => e,
        })?;
        Ok(sweep)
    }
}

/// File name of the pressure map of `surface` (index `k` of `n`) at `pressure_pa`.
fn pressure_map_name(sweep: &SurfaceSweep, k: usize, pressure_pa: f64) -> String {
    per_load_name(sweep, k, pressure_pa, "pressure_map", "png")
}

/// `<stem>_<p>Pa.<ext>` with one surface, `<stem>_<slug>_<p>Pa.<ext>` with several.
fn per_load_name(
    sweep: &SurfaceSweep,
    k: usize,
    pressure_pa: f64,
    stem: &str,
    ext: &str,
) -> String {
    if sweep.surfaces.len() == 1 {
        return format!("{stem}_{pressure_pa:e}Pa.{ext}");
    }
    let slug = match &sweep.surfaces[k] {
        SurfaceSource::Generated { spec } => format!("seed-{}", spec.seed),
        SurfaceSource::File { .. } => format!("surface-{}", k + 1),
    };
    format!("{stem}_{slug}_{pressure_pa:e}Pa.{ext}")
}

/// The residual surfaces after unloading from each load of surface `k`
/// ([`NormalSolution::residual_surface`]), as `.npy` with their sidecars.
fn write_residual_surfaces(
    out_dir: &Path,
    sweep: &SurfaceSweep,
    k: usize,
    solutions: &[NormalSolution],
) -> Result<()> {
    let surface = sweep.surfaces[k].load()?;
    for sol in solutions {
        let residual = sol.residual_surface(&surface)?;
        let name = per_load_name(sweep, k, sol.mean_pressure_pa, "residual_surface", "npy");
        crate::surface::io::write(&out_dir.join(name), &residual)?;
    }
    Ok(())
}

/// The pressure maps of surface `k` at each of its loads, as PNG heat maps.
fn write_pressure_maps(
    out_dir: &Path,
    sweep: &SurfaceSweep,
    k: usize,
    solutions: &[NormalSolution],
) -> Result<()> {
    for sol in solutions {
        let title = format!(
            "Contact pressure at p̄ = {:.4} MPa ({})",
            sol.mean_pressure_pa / 1e6,
            sweep.surfaces[k].label()
        );
        heatmap(
            &out_dir.join(pressure_map_name(sweep, k, sol.mean_pressure_pa)),
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
    Ok(())
}

/// The fixed file names a run without `--shard` may write (besides the pressure maps).
pub const OUTPUT_FILES: [&str; 6] = [
    "normal_sweep.csv",
    "normal_sweep_timings.csv",
    "normal_sweep_statistics.csv",
    "area_ratio.png",
    "mean_gap.png",
    "kn.png",
];

/// The table of a whole sweep (every surface, in unit order): the same bytes whether the units
/// ran in one process or in merged shards (no wall times: they go to the timings file).
pub fn sweep_table(sweep: &SurfaceSweep, units: &[UnitRecord<SurfaceResult>]) -> Result<String> {
    let material = sweep.material;
    let mut csv = String::new();
    let _ = writeln!(
        csv,
        "# asperity contact normal: pressure sweep over {} surface(s), method {}",
        units.len(),
        sweep.options.method.name()
    );
    for (source, u) in sweep.surfaces.iter().zip(units) {
        let g = &u.result.grid;
        let _ = writeln!(csv, "# surface {}: {}", u.label, source.describe());
        let _ = writeln!(
            csv,
            "# grid {}: {} x {} points, dx_m = {:e}, dy_m = {:e}, periodic = {}",
            u.label, g.nx, g.ny, g.dx_m, g.dy_m, g.periodic
        );
    }
    let _ = writeln!(
        csv,
        "# youngs_modulus_Pa = {:e} (both bodies), poisson_ratio = {}, e_star_Pa = {:e}",
        material.youngs_modulus_pa,
        material.poisson_ratio,
        sweep.e_star_pa()?
    );
    let _ = writeln!(
        csv,
        "# tolerance = {:e} (relative gap error); kn = dp/d(approach) from the tangent problem on the contact set; points_across_* = 4 x points / interface edges (resolved when the smaller is >= {})",
        sweep.options.tolerance,
        crate::contact::resolution::RESOLVED_POINTS_ACROSS
    );
    if let Some(h) = sweep.hardness_pa {
        let _ = writeln!(
            csv,
            "# hardness_Pa = {h:e}: elastic-perfectly plastic contact (pressure <= H); kn_unloading = unloading/reloading stiffness about the plastically deformed state (tangent problem on the whole contact set; the one an element carries), kn_loading = loading tangent (plastic points held at H); elastic/plastic area = points with 0 < p < H / p = H; plastic_volume_m3 = sum over plastic points of the penetration max(-gap, 0) x dx x dy"
        );
    }
    let _ = writeln!(
        csv,
        "# configuration sha256 = {} (asperity {}); wall times in normal_sweep_timings.csv",
        shard::config_sha256(sweep)?,
        env!("CARGO_PKG_VERSION")
    );
    for u in units {
        if let Some(w) = window_edge_warning(u) {
            let _ = writeln!(csv, "# warning: {w}");
        }
    }
    let plastic = sweep.hardness_pa.is_some();
    let mut header: Vec<String> = [
        "surface",
        "pressure_Pa",
        "contact_area_ratio",
        "mean_gap_m",
        "kn_N_per_m3",
        "approach_m",
        "contact_spots",
        "smallest_spot_points",
        "median_spot_points",
        "points_across_contact",
        "points_across_free",
        "method",
        "iterations",
        "stiffness_iterations",
        "residual",
    ]
    .map(String::from)
    .to_vec();
    if plastic {
        header[4] = "kn_unloading_N_per_m3".into();
        header.insert(5, "kn_loading_N_per_m3".into());
        header.extend(
            [
                "elastic_area_ratio",
                "plastic_area_ratio",
                "plastic_points",
                "plastic_volume_m3",
                "loading_stiffness_iterations",
            ]
            .map(String::from),
        );
    }
    let mut rows = vec![header];
    for u in units {
        for p in &u.result.points {
            let mut row = vec![
                u.label.clone(),
                format!("{:e}", p.pressure_pa),
                format!("{:e}", p.contact_area_ratio),
                format!("{:e}", p.mean_gap_m),
                format!("{:e}", p.kn_n_per_m3),
                format!("{:e}", p.approach_m),
                p.contact_spots.to_string(),
                p.smallest_spot_points.to_string(),
                p.median_spot_points.to_string(),
                format!("{:e}", p.resolution.points_across_contact()),
                format!("{:e}", p.resolution.points_across_free()),
                p.method.name().to_string(),
                p.iterations.to_string(),
                p.stiffness_iterations.to_string(),
                format!("{:e}", p.residual),
            ];
            if plastic {
                let pl = p.plastic.ok_or_else(|| {
                    Error::Data(format!(
                        "{} at {:e} Pa: no plastic part in a hardness-limited sweep",
                        u.label, p.pressure_pa
                    ))
                })?;
                row.insert(5, format!("{:e}", pl.kn_loading_n_per_m3));
                row.extend([
                    format!("{:e}", pl.elastic_area_ratio),
                    format!("{:e}", pl.plastic_area_ratio),
                    pl.plastic_points.to_string(),
                    format!("{:e}", pl.plastic_volume_m3),
                    pl.loading_stiffness_iterations.to_string(),
                ]);
            }
            rows.push(row);
        }
    }
    csv.push_str(&csv_records(&rows)?);
    Ok(csv)
}

/// The warning for a surface whose contact reaches the edge of its non-periodic window at some
/// pressures (contact points on the window's border rows/columns): there the surface is cut, so
/// area and kn depend on the window, and refining the grid does not help. None otherwise.
pub fn window_edge_warning(u: &UnitRecord<SurfaceResult>) -> Option<String> {
    crate::contact::resolution::ContactResolution::window_edge_warning(
        u.result
            .points
            .iter()
            .map(|p| (p.pressure_pa, &p.resolution)),
    )
    .map(|w| format!("{}: {w}", u.label))
}

/// Records as CSV text (fields quoted where needed, e.g. file paths holding commas).
fn csv_records(rows: &[Vec<String>]) -> Result<String> {
    let mut w = csv::Writer::from_writer(Vec::new());
    for r in rows {
        w.write_record(r)
            .map_err(|e| Error::Data(format!("CSV: {e}")))?;
    }
    let bytes = w
        .into_inner()
        .map_err(|e| Error::Data(format!("CSV: {e}")))?;
    String::from_utf8(bytes).map_err(|e| Error::Data(format!("CSV: {e}")))
}

/// Every output of a whole sweep into `out_dir`: the table, the timings, the statistics over
/// the surfaces (with several) and the plots. Used by the single run and by `asperity merge`.
pub fn write_outputs(
    sweep: &SurfaceSweep,
    units: &[UnitRecord<SurfaceResult>],
    out_dir: &Path,
) -> Result<()> {
    let table = sweep_table(sweep, units)?;
    let mut timings = vec![["surface", "pressure_Pa", "wall_time_s"]
        .map(String::from)
        .to_vec()];
    for u in units {
        for p in &u.result.points {
            timings.push(vec![
                u.label.clone(),
                format!("{:e}", p.pressure_pa),
                format!("{:.3}", p.wall_time_s),
            ]);
        }
    }
    let timings = String::from(
        "# asperity contact normal: wall time of the three solves of each point (s); not reproducible\n",
    ) + &csv_records(&timings)?;
    let results: Vec<&SurfaceResult> = units.iter().map(|u| &u.result).collect();
    let stats = surface_sweep::statistics(&results)?;
    crate::core::output::write_string_atomic(&out_dir.join("normal_sweep.csv"), &table)?;
    crate::core::output::write_string_atomic(&out_dir.join("normal_sweep_timings.csv"), &timings)?;
    if units.len() > 1 {
        let mut csv = format!(
            "# asperity contact normal: mean and sample standard deviation over {} surfaces at each pressure\n\
             pressure_Pa,surfaces,contact_area_ratio_mean,contact_area_ratio_std,mean_gap_m_mean,mean_gap_m_std,kn_N_per_m3_mean,kn_N_per_m3_std,approach_m_mean,approach_m_std\n",
            units.len()
        );
        for s in &stats {
            let _ = writeln!(
                csv,
                "{:e},{},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e}",
                s.pressure_pa,
                s.surfaces,
                s.contact_area_ratio.mean,
                s.contact_area_ratio.std,
                s.mean_gap_m.mean,
                s.mean_gap_m.std,
                s.kn_n_per_m3.mean,
                s.kn_n_per_m3.std,
                s.approach_m.mean,
                s.approach_m.std
            );
        }
        crate::core::output::write_string_atomic(
            &out_dir.join("normal_sweep_statistics.csv"),
            &csv,
        )?;
    }

    type Quantity = (
        &'static str,
        &'static str,
        &'static str,
        fn(&sweep::SweepPoint) -> f64,
        f64,
    );
    let quantities: [Quantity; 3] = [
        (
            "area_ratio.png",
            "Real contact area ratio",
            "A_real / A_nominal (-)",
            |p| p.contact_area_ratio,
            1.0,
        ),
        (
            "mean_gap.png",
            "Mean gap",
            "mean gap (µm)",
            |p| p.mean_gap_m,
            1e6,
        ),
        (
            "kn.png",
            "Normal contact stiffness per unit area",
            "kn (10¹² N/m³)",
            |p| p.kn_n_per_m3,
            1e-12,
        ),
    ];
    for (file, title, y_label, value, scale) in quantities {
        let curve = |r: &SurfaceResult| -> Vec<(f64, f64)> {
            r.points
                .iter()
                .map(|p| (p.pressure_pa / 1e6, value(p) * scale))
                .collect()
        };
        let series = if units.len() == 1 {
            let pts = curve(&units[0].result);
            vec![
                Series::line("sweep", pts.clone()),
                Series::markers("solved pressures", pts),
            ]
        } else {
            let mut s: Vec<Series> = units
                .iter()
                .map(|u| Series::line(u.label.clone(), curve(&u.result)))
                .collect();
            let mean: Vec<(f64, f64)> = (0..sweep.pressures_pa.len())
                .map(|j| {
                    let vals: Vec<f64> = results.iter().map(|r| value(&r.points[j])).collect();
                    (
                        sweep.pressures_pa[j] / 1e6,
                        surface_sweep::MeanStd::of(&vals).mean * scale,
                    )
                })
                .collect();
            s.push(Series::markers(
                format!("mean over {} surfaces", units.len()),
                mean,
            ));
            s
        };
        line_plot(
            &out_dir.join(file),
            &LinePlot {
                title,
                x_label: "nominal pressure (MPa)",
                y_label,
                x_scale: Scale::Log,
                y_scale: Scale::Log,
            },
            &series,
        )?;
    }
    Ok(())
}
