//! The calibration chain: surface → normal sweep → tangential loops → Valanis fits → table.
//!
//! Units: SI; per unit nominal area throughout (pressures and shear stresses in Pa,
//! displacements in m, stiffnesses kn, E0, Et in N/m³, energies in J/m²).
//!
//! 1. **Surface**: the Gaussian-correlated patch of the configuration
//!    ([`crate::surface::generate`]).
//! 2. **Normal sweep** ([`crate::contact::sweep`]): the normal contact solver at each nominal
//!    pressure, with `kn = dp̄/dδ` from the tangent problem on the contact set.
//! 3. **Tangential loops** ([`crate::contact::tangential`]): on each pressure field, the rigid
//!    shift `δ(t) = δa·sin(2πt)` along x from the virgin state over a quarter cycle (initial
//!    loading) and one full cycle: the **steady cycle** runs from the first peak `+δa` through
//!    `−δa` back to `+δa` (with the normal load constant and no normal–tangential coupling the
//!    loop closes after the first reversal — Masing behaviour). The amplitude is
//!    `δa = amplitude_factor × δ_gs(p̄)`, `δ_gs` the gross-slip displacement of monotonic loading
//!    at that pressure, so every loop spans stick, microslip and gross slip.
//! 4. **Fit** ([`crate::calibrate::fit`]): E0, k (optionally Et) of a Valanis element per unit
//!    area with `Fz = p̄` and μ fixed, by least squares on the steady cycle.
//! 5. **Table** ([`crate::calibrate::table`]) and outputs ([`write_outputs`]).

use crate::calibrate::config::CalibrationConfig;
use crate::calibrate::fit::{fit_valanis, FitOptions, FitResult, LoopData};
use crate::calibrate::table::{CalibrationRow, CalibrationTable};
use crate::contact::normal::{NormalOptions, NormalProblem, NormalSolver};
use crate::contact::sweep::{self, SweepOptions, SweepPoint};
use crate::contact::tangential::{Control, TangentialOptions, TangentialProblem, TangentialSolver};
use crate::element::dissipated_energy;
use crate::error::{Error, Result};
use crate::halfspace::Boundary;
use crate::output::write_string_atomic;
use crate::plot::{line_plot, LinePlot, Scale, Series};
use crate::surface::combine::{composite_modulus, Material};
use crate::surface::generate::generate;
use indicatif::ProgressBar;
use sha2::{Digest, Sha256};
use std::fmt::Write as _;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The BEM hysteresis loop at one pressure.
#[derive(Debug, Clone, serde::Serialize)]
pub struct BemLoop {
    /// Nominal pressure (Pa).
    pub pressure_pa: f64,
    /// Gross-slip displacement of monotonic loading (m).
    pub gross_slip_displacement_m: f64,
    /// Displacement amplitude δa (m).
    pub amplitude_m: f64,
    /// Rigid tangential shift at every step, from the virgin state (m).
    pub displacement_m: Vec<f64>,
    /// Mean shear stress (tangential force over nominal area) at every step (Pa).
    pub shear_stress_pa: Vec<f64>,
    /// Steps of the steady cycle (peak to peak).
    #[serde(skip)]
    pub steady: Range<usize>,
    /// Energy dissipated over the steady cycle per unit nominal area, ∮τ dδ (J/m²).
    pub energy_per_cycle_j_per_m2: f64,
    /// Contact points carrying shear.
    pub contact_points: usize,
    /// Largest solver iteration count of a step.
    pub max_step_iterations: usize,
    /// Largest final residual of a step.
    pub max_step_residual: f64,
    /// Wall time of solver set-up and all steps (s).
    pub wall_time_s: f64,
}

/// Everything computed at one pressure.
#[derive(Debug, Clone)]
pub struct PressureCalibration {
    pub sweep: SweepPoint,
    pub bem: BemLoop,
    pub fit: FitResult,
}

/// Wall time of each stage (s).
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct StageTimes {
    pub surface_s: f64,
    pub normal_sweep_s: f64,
    pub tangential_loops_s: f64,
    pub fits_s: f64,
    pub total_s: f64,
}

/// Result of [`run`].
#[derive(Debug, Clone)]
pub struct CalibrationRun {
    pub config: CalibrationConfig,
    pub table: CalibrationTable,
    pub pressures: Vec<PressureCalibration>,
    /// SHA-256 of the surface heights (f64 little-endian, row-major).
    pub surface_sha256: String,
    pub times: StageTimes,
}

fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .fold(String::with_capacity(64), |mut s, b| {
            let _ = write!(s, "{b:02x}");
            s
        })
}

/// Number of work units [`run`] reports to its progress bar for a configuration.
pub fn progress_units(config: &CalibrationConfig) -> u64 {
    let n = config.loading.pressures_pa.len() as u64;
    let steps = (config.loading.steps_per_cycle + config.loading.steps_per_cycle / 4) as u64;
    1 + n + n * steps + n
}

/// Run the whole chain. `bar` receives [`progress_units`] increments (pass
/// `ProgressBar::hidden()` for none).
pub fn run(config: &CalibrationConfig, bar: &ProgressBar) -> Result<CalibrationRun> {
    config.validate()?;
    let t0 = Instant::now();
    let mut times = StageTimes::default();

    // 1. Surface.
    bar.set_message("surface");
    let surface = generate(&config.surface)?;
    let mut bytes = Vec::with_capacity(surface.heights.len() * 8);
    for h in surface.heights.iter() {
        bytes.extend_from_slice(&h.to_le_bytes());
    }
    let surface_sha256 = sha256_hex(&bytes);
    drop(bytes);
    times.surface_s = t0.elapsed().as_secs_f64();
    bar.inc(1);

    // 2. Normal sweep.
    let material = Material {
        youngs_modulus_pa: config.material.youngs_modulus_pa,
        poisson_ratio: config.material.poisson_ratio,
    }
    .validated("material")?;
    let e_star = composite_modulus(material, material)?;
    let t1 = Instant::now();
    bar.set_message("normal sweep");
    let mut normal = NormalSolver::new(
        &NormalProblem {
            surface: &surface,
            e_star_pa: e_star,
        },
        NormalOptions {
            tolerance: config.contact.normal_tolerance,
            ..NormalOptions::default()
        },
    )?;
    let sweep = sweep::run(
        &mut normal,
        &config.loading.pressures_pa,
        SweepOptions {
            keep_solutions: true,
        },
        |_| bar.inc(1),
    )?;
    drop(normal);
    times.normal_sweep_s = t1.elapsed().as_secs_f64();

    // 3. Tangential loops.
    let t2 = Instant::now();
    let mu = config.contact.mu;
    let n = config.loading.steps_per_cycle;
    let total_steps = n + n / 4;
    let steady = n / 4..n / 4 + n + 1;
    let mut loops = Vec::with_capacity(sweep.points.len());
    for (point, sol) in sweep.points.iter().zip(&sweep.solutions) {
        let p = point.pressure_pa;
        bar.set_message(format!("loop {:.3} MPa", p / 1e6));
        let started = Instant::now();
        let mut solver = TangentialSolver::new(
            &TangentialProblem {
                pressure: &sol.pressure,
                dx: sol.dx,
                dy: sol.dy,
                boundary: Boundary::Periodic,
                friction_coefficient: mu,
                body1: material,
                body2: material,
            },
            TangentialOptions {
                tolerance: config.contact.tangential_tolerance,
                ..TangentialOptions::default()
            },
        )?;
        let gross_slip = solver.gross_slip_displacement([1.0, 0.0])?;
        let amplitude = config.loading.amplitude_factor * gross_slip;
        solver.reset();
        let mut displacement = Vec::with_capacity(total_steps + 1);
        let mut shear = Vec::with_capacity(total_steps + 1);
        displacement.push(0.0);
        shear.push(0.0);
        let (mut max_it, mut max_res) = (0usize, 0.0f64);
        for k in 1..=total_steps {
            // Exact zeros at multiples of half a period, so that the cycle closes exactly.
            let s = if (2 * k) % n == 0 {
                0.0
            } else if (4 * k) % n == 0 {
                if (4 * k / n) % 4 == 1 {
                    1.0
                } else {
                    -1.0
                }
            } else {
                (2.0 * std::f64::consts::PI * k as f64 / n as f64).sin()
            };
            let step = solver.step(Control::Displacement([amplitude * s, 0.0]))?;
            displacement.push(step.shift_m[0]);
            shear.push(step.mean_shear_pa[0]);
            max_it = max_it.max(step.iterations);
            max_res = max_res.max(step.residual);
            bar.inc(1);
        }
        let energy = dissipated_energy(&displacement[steady.clone()], &shear[steady.clone()]);
        loops.push(BemLoop {
            pressure_pa: p,
            gross_slip_displacement_m: gross_slip,
            amplitude_m: amplitude,
            displacement_m: displacement,
            shear_stress_pa: shear,
            steady: steady.clone(),
            energy_per_cycle_j_per_m2: energy,
            contact_points: solver.contact_points().len(),
            max_step_iterations: max_it,
            max_step_residual: max_res,
            wall_time_s: started.elapsed().as_secs_f64(),
        });
    }
    drop(sweep.solutions);
    times.tangential_loops_s = t2.elapsed().as_secs_f64();

    // 4. Fits.
    let t3 = Instant::now();
    let opts = FitOptions {
        mu,
        fit_et: config.fit.fit_et,
        max_iters: config.fit.max_iterations,
        k_starts: config.fit.k_starts.clone(),
    };
    let mut pressures = Vec::with_capacity(loops.len());
    let mut rows = Vec::with_capacity(loops.len());
    for (point, bem) in sweep.points.into_iter().zip(loops) {
        bar.set_message(format!("fit {:.3} MPa", bem.pressure_pa / 1e6));
        let data = LoopData::constant_load(
            bem.displacement_m.clone(),
            bem.shear_stress_pa.clone(),
            bem.pressure_pa,
            bem.steady.clone(),
        );
        let fit = fit_valanis(&data, &opts).map_err(|e| {
            Error::Data(format!("Valanis fit at {} Pa failed: {e}", bem.pressure_pa))
        })?;
        rows.push(CalibrationRow {
            pressure_pa: point.pressure_pa,
            contact_area_ratio: point.contact_area_ratio,
            kn_n_per_m3: point.kn_n_per_m3,
            e0_n_per_m3: fit.params.e0,
            k: fit.params.k,
            mu,
            et_n_per_m3: fit.params.et,
            fit_r2: fit.r2,
            energy_per_cycle_j_per_m2: bem.energy_per_cycle_j_per_m2,
        });
        pressures.push(PressureCalibration {
            sweep: point,
            bem,
            fit,
        });
        bar.inc(1);
    }
    times.fits_s = t3.elapsed().as_secs_f64();
    times.total_s = t0.elapsed().as_secs_f64();
    let table = CalibrationTable::new(rows)?;
    Ok(CalibrationRun {
        config: config.clone(),
        table,
        pressures,
        surface_sha256,
        times,
    })
}

/// Shape of a sequence along increasing pressure, in words: "rises monotonically",
/// "falls monotonically", "rises to a maximum of … at … MPa, then falls", etc.
pub fn describe_shape(pressures_pa: &[f64], values: &[f64]) -> String {
    let n = values.len();
    if n < 2 {
        return "single point".into();
    }
    let rising = values.windows(2).all(|w| w[1] > w[0]);
    let falling = values.windows(2).all(|w| w[1] < w[0]);
    let (imax, vmax) =
        values.iter().enumerate().fold(
            (0, f64::NEG_INFINITY),
            |b, (i, &v)| if v > b.1 { (i, v) } else { b },
        );
    let (imin, vmin) =
        values.iter().enumerate().fold(
            (0, f64::INFINITY),
            |b, (i, &v)| if v < b.1 { (i, v) } else { b },
        );
    let mpa = |i: usize| pressures_pa[i] / 1e6;
    if rising {
        format!(
            "rises monotonically from {:.4} at {} MPa to {:.4} at {} MPa",
            values[0],
            mpa(0),
            values[n - 1],
            mpa(n - 1)
        )
    } else if falling {
        format!(
            "falls monotonically from {:.4} at {} MPa to {:.4} at {} MPa",
            values[0],
            mpa(0),
            values[n - 1],
            mpa(n - 1)
        )
    } else if imax > 0 && imax < n - 1 {
        format!(
            "non-monotonic: {:.4} at {} MPa, maximum {:.4} at {} MPa, {:.4} at {} MPa",
            values[0],
            mpa(0),
            vmax,
            mpa(imax),
            values[n - 1],
            mpa(n - 1)
        )
    } else {
        format!(
            "non-monotonic: {:.4} at {} MPa, minimum {:.4} at {} MPa, {:.4} at {} MPa",
            values[0],
            mpa(0),
            vmin,
            mpa(imin),
            values[n - 1],
            mpa(n - 1)
        )
    }
}

/// A fitted `k` below this is reported as "at the lower bound 0". `k → 1` gives a sharp,
/// Jenkins-like corner (slope E0 until saturation); `k = 0` the most gradual transition the
/// Valanis form allows (exponential approach to μFz). A loop whose microslip transition is still
/// more gradual drives the fit to k = 0; the fit is then the best k = 0 element, and the report
/// says so.
pub const K_BOUND_FLAG: f64 = 1e-3;

/// Where the configuration came from (recorded in the sidecar).
#[derive(Debug, Clone)]
pub enum ConfigSource {
    /// The built-in reference case.
    BuiltIn,
    /// A TOML file and its bytes.
    File { path: PathBuf, bytes: Vec<u8> },
}

/// File names written by [`write_outputs`] into the output directory.
pub mod files {
    pub const TABLE: &str = "calibration_table.csv";
    pub const FITS: &str = "calibration_fits.csv";
    pub const LOOPS: &str = "calibration_loops.csv";
    pub const SIDECAR: &str = "calibration.json";
    pub const KN_PLOT: &str = "kn_vs_pressure.png";
    pub const E0_PLOT: &str = "e0_vs_pressure.png";
    pub const K_PLOT: &str = "k_vs_pressure.png";
    pub const LOOPS_PLOT: &str = "loops_normalised.png";

    /// Per-pressure loop-with-fit figure, e.g. `loop_fit_100000Pa.png`.
    pub fn loop_plot(pressure_pa: f64) -> String {
        format!("loop_fit_{pressure_pa}Pa.png")
    }
}

/// Write the table, per-pressure fit report, loops, plots and JSON sidecar into `out_dir`
/// (each file atomically). Returns the paths written.
pub fn write_outputs(
    run: &CalibrationRun,
    source: &ConfigSource,
    out_dir: &Path,
) -> Result<Vec<PathBuf>> {
    let mut written = Vec::new();
    let pressures: Vec<f64> = run.table.rows.iter().map(|r| r.pressure_pa).collect();

    // Table.
    let table_path = out_dir.join(files::TABLE);
    run.table.write_csv(&table_path)?;
    written.push(table_path.clone());

    // Fit report.
    let mut fits = String::from(
        "pressure_Pa,gross_slip_displacement_m,amplitude_m,E0_N_per_m3,k,Et_N_per_m3,fit_R2,fit_nrmse,energy_bem_J_per_m2,energy_valanis_J_per_m2,energy_rel_error,fit_iterations,fit_converged,contact_points,median_spot_points,normal_iterations,tangential_max_step_iterations,tangential_wall_time_s,fit_wall_time_s\n",
    );
    for pc in &run.pressures {
        let (b, f, s) = (&pc.bem, &pc.fit, &pc.sweep);
        let _ = writeln!(
            fits,
            "{},{:e},{:e},{:e},{},{:e},{},{:e},{:e},{:e},{:e},{},{},{},{},{},{},{:.3},{:.3}",
            b.pressure_pa,
            b.gross_slip_displacement_m,
            b.amplitude_m,
            f.params.e0,
            f.params.k,
            f.params.et,
            f.r2,
            f.nrmse,
            f.energy_data,
            f.energy_model,
            f.energy_rel_error,
            f.iterations,
            f.converged,
            b.contact_points,
            s.median_spot_points,
            s.iterations,
            b.max_step_iterations,
            b.wall_time_s,
            f.wall_time.as_secs_f64()
        );
    }
    let fits_path = out_dir.join(files::FITS);
    write_string_atomic(&fits_path, &fits)?;
    written.push(fits_path);

    // Loops with fits.
    let mut loops = String::from(
        "pressure_Pa,step,displacement_m,shear_stress_bem_Pa,shear_stress_valanis_Pa,steady_cycle\n",
    );
    for pc in &run.pressures {
        let b = &pc.bem;
        for (i, ((d, t), m)) in b
            .displacement_m
            .iter()
            .zip(&b.shear_stress_pa)
            .zip(&pc.fit.model_force)
            .enumerate()
        {
            let _ = writeln!(
                loops,
                "{},{i},{d:e},{t:e},{m:e},{}",
                b.pressure_pa,
                u8::from(b.steady.contains(&i))
            );
        }
    }
    let loops_path = out_dir.join(files::LOOPS);
    write_string_atomic(&loops_path, &loops)?;
    written.push(loops_path);

    // Plots.
    let mpa: Vec<f64> = pressures.iter().map(|p| p / 1e6).collect();
    let column = |f: fn(&CalibrationRow) -> f64| -> Vec<(f64, f64)> {
        mpa.iter()
            .zip(&run.table.rows)
            .map(|(&p, r)| (p, f(r)))
            .collect()
    };
    type PlotSpec<'a> = (&'a str, &'a str, &'a str, Scale, Vec<(f64, f64)>);
    let plots: [PlotSpec; 3] = [
        (
            files::KN_PLOT,
            "Normal contact stiffness per unit area vs pressure",
            "kn (10¹² N/m³)",
            Scale::Log,
            column(|r| r.kn_n_per_m3 * 1e-12),
        ),
        (
            files::E0_PLOT,
            "Valanis E0 (initial tangential stiffness) per unit area vs pressure",
            "E0 (10¹² N/m³)",
            Scale::Log,
            column(|r| r.e0_n_per_m3 * 1e-12),
        ),
        (
            files::K_PLOT,
            "Valanis shape parameter k vs pressure",
            "k (-)",
            Scale::Linear,
            column(|r| r.k),
        ),
    ];
    // The interpolant users get from the table, drawn on a fine log grid.
    let (p_lo, p_hi) = run.table.pressure_range();
    let interp = |name: &str| -> Vec<(f64, f64)> {
        (0..=200)
            .map(|i| {
                let p = p_lo * (p_hi / p_lo).powf(i as f64 / 200.0);
                let v = run.table.interpolate(p);
                let y = match name {
                    files::KN_PLOT => v.kn_n_per_m3 * 1e-12,
                    files::E0_PLOT => v.e0_n_per_m3 * 1e-12,
                    _ => v.k,
                };
                (p / 1e6, y)
            })
            .collect()
    };
    for (name, title, ylabel, yscale, pts) in plots {
        let path = out_dir.join(name);
        line_plot(
            &path,
            &LinePlot {
                title,
                x_label: "nominal pressure (MPa)",
                y_label: ylabel,
                x_scale: Scale::Log,
                y_scale: yscale,
            },
            &[
                Series::line(
                    "table interpolation (monotone cubic in log p)",
                    interp(name),
                ),
                Series::markers("calibrated pressures", pts),
            ],
        )?;
        written.push(path);
    }
    for pc in &run.pressures {
        let b = &pc.bem;
        let path = out_dir.join(files::loop_plot(b.pressure_pa));
        let r = b.steady.clone();
        let title = format!(
            "Steady loop at {} MPa: BEM and Valanis fit (E0 {:.3e} N/m³, k {:.3}, R² {:.4})",
            b.pressure_pa / 1e6,
            pc.fit.params.e0,
            pc.fit.params.k,
            pc.fit.r2
        );
        line_plot(
            &path,
            &LinePlot {
                title: &title,
                x_label: "tangential displacement (µm)",
                y_label: "mean shear stress (MPa)",
                x_scale: Scale::Linear,
                y_scale: Scale::Linear,
            },
            &[
                Series::markers(
                    "BEM (steady cycle)",
                    r.clone()
                        .map(|i| (b.displacement_m[i] * 1e6, b.shear_stress_pa[i] / 1e6))
                        .collect(),
                ),
                Series::line(
                    "Valanis fit",
                    r.map(|i| (b.displacement_m[i] * 1e6, pc.fit.model_force[i] / 1e6))
                        .collect(),
                ),
            ],
        )?;
        written.push(path);
    }
    let series: Vec<Series> = run
        .pressures
        .iter()
        .map(|pc| {
            let b = &pc.bem;
            let scale = run.config.contact.mu * b.pressure_pa;
            Series::line(
                format!("{} MPa (fit R² {:.4})", b.pressure_pa / 1e6, pc.fit.r2),
                b.steady
                    .clone()
                    .map(|i| {
                        (
                            b.displacement_m[i] / b.amplitude_m,
                            b.shear_stress_pa[i] / scale,
                        )
                    })
                    .collect(),
            )
        })
        .collect();
    let loops_plot = out_dir.join(files::LOOPS_PLOT);
    line_plot(
        &loops_plot,
        &LinePlot {
            title: "Steady BEM loops, normalised: loop shape versus pressure",
            x_label: "displacement / amplitude δ/δa (-)",
            y_label: "shear stress / (μ p) (-)",
            x_scale: Scale::Linear,
            y_scale: Scale::Linear,
        },
        &series,
    )?;
    written.push(loops_plot);

    // Sidecar.
    let config_toml = run.config.to_toml_string()?;
    let (source_desc, file_hash) = match source {
        ConfigSource::BuiltIn => ("built-in reference case".to_string(), None),
        ConfigSource::File { path, bytes } => (path.display().to_string(), Some(sha256_hex(bytes))),
    };
    let table_sha = sha256_hex(&std::fs::read(&table_path).map_err(|e| Error::io(&table_path, e))?);
    let ks: Vec<f64> = run.table.rows.iter().map(|r| r.k).collect();
    let kn: Vec<f64> = run.table.rows.iter().map(|r| r.kn_n_per_m3).collect();
    let e0: Vec<f64> = run.table.rows.iter().map(|r| r.e0_n_per_m3).collect();
    let per_pressure: Vec<serde_json::Value> = run
        .pressures
        .iter()
        .map(|pc| {
            serde_json::json!({
                "pressure_Pa": pc.bem.pressure_pa,
                "normal": pc.sweep,
                "tangential": {
                    "gross_slip_displacement_m": pc.bem.gross_slip_displacement_m,
                    "amplitude_m": pc.bem.amplitude_m,
                    "contact_points": pc.bem.contact_points,
                    "max_step_iterations": pc.bem.max_step_iterations,
                    "max_step_residual": pc.bem.max_step_residual,
                    "energy_per_cycle_J_per_m2": pc.bem.energy_per_cycle_j_per_m2,
                    "wall_time_s": pc.bem.wall_time_s,
                },
                "fit": {
                    "E0_N_per_m3": pc.fit.params.e0,
                    "k": pc.fit.params.k,
                    "Et_N_per_m3": pc.fit.params.et,
                    "R2": pc.fit.r2,
                    "nrmse": pc.fit.nrmse,
                    "energy_valanis_J_per_m2": pc.fit.energy_model,
                    "energy_rel_error": pc.fit.energy_rel_error,
                    "iterations": pc.fit.iterations,
                    "converged": pc.fit.converged,
                    "k_at_lower_bound": pc.fit.params.k < K_BOUND_FLAG,
                    "final_cost": pc.fit.final_cost,
                    "wall_time_s": pc.fit.wall_time.as_secs_f64(),
                },
            })
        })
        .collect();
    let sidecar = serde_json::json!({
        "tool": "asperity calibrate",
        "crate_version": env!("CARGO_PKG_VERSION"),
        "units": "SI, per unit nominal area: pressures and shear in Pa, displacements in m, kn/E0/Et in N/m^3, energies in J/m^2",
        "config_source": source_desc,
        "config": run.config,
        "input_hashes": {
            "config_file_sha256": file_hash,
            "config_canonical_toml_sha256": sha256_hex(config_toml.as_bytes()),
            "surface_heights_sha256": run.surface_sha256,
        },
        "outputs": {
            "table": files::TABLE,
            "table_sha256": table_sha,
            "fits": files::FITS,
            "loops": files::LOOPS,
            "plots": [files::KN_PLOT, files::E0_PLOT, files::K_PLOT, files::LOOPS_PLOT],
            "loop_plots": run.pressures.iter().map(|pc| files::loop_plot(pc.bem.pressure_pa)).collect::<Vec<_>>(),
        },
        "method": {
            "loading": "virgin quarter cycle + one steady cycle (peak to peak) of delta = amplitude*sin(2 pi t) along x, amplitude = amplitude_factor x gross-slip displacement at each pressure",
            "fit": "Valanis element per unit area, Fz = nominal pressure, mu fixed; Nelder-Mead (argmin) on E0 = E0ref*exp(t0), k = logistic(t1), Et = E0*logistic(t2); cost 1 - R^2 on the steady cycle; element driven by the exact closed-form branch solution",
            "kn": "dp/d(approach) from the tangent problem on the contact set",
            "tangential_assumption": crate::contact::tangential::QUASI_IDENTICAL_ASSUMPTION,
        },
        "summary": {
            "kn_rises_monotonically": kn.windows(2).all(|w| w[1] > w[0]),
            "E0_rises_monotonically": e0.windows(2).all(|w| w[1] > w[0]),
            "k_shape": describe_shape(&pressures, &ks),
            "min_fit_R2": run.table.rows.iter().map(|r| r.fit_r2).fold(f64::INFINITY, f64::min),
        },
        "per_pressure": per_pressure,
        "wall_time_s": run.times,
    });
    let sidecar_path = out_dir.join(files::SIDECAR);
    let text = serde_json::to_string_pretty(&sidecar)
        .map_err(|e| Error::Data(format!("cannot serialise sidecar: {e}")))?;
    write_string_atomic(&sidecar_path, &(text + "\n"))?;
    written.push(sidecar_path);
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shape_descriptions() {
        let p = [1e5, 1e6, 1e7];
        assert!(describe_shape(&p, &[0.1, 0.2, 0.3]).starts_with("rises"));
        assert!(describe_shape(&p, &[0.3, 0.2, 0.1]).starts_with("falls"));
        assert!(describe_shape(&p, &[0.1, 0.5, 0.3]).contains("maximum 0.5000 at 1 MPa"));
        assert!(describe_shape(&p, &[0.4, 0.1, 0.3]).contains("minimum 0.1000 at 1 MPa"));
    }

    #[test]
    fn progress_units_count_every_step() {
        let c = CalibrationConfig::reference();
        assert_eq!(progress_units(&c), 1 + 6 + 6 * 50 + 6);
    }
}
