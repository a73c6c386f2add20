//! Files of a calibration run: tables (CSV, SI units in the column names), plots (PNG) and the
//! JSON sidecar, each written atomically into the output directory.
//!
//! | file | content |
//! |---|---|
//! | `calibration_table.csv` | per pressure: means over the realisations, 95 % interval half-widths ([`crate::calibrate::table`]) |
//! | `calibration_realisations.csv` | long format, one row per realisation × pressure: normal contact, fit, flags |
//! | `calibration_fits.csv` | long format, one row per realisation × pressure × amplitude: BEM and element energy per cycle, their error, the fit to that amplitude alone |
//! | `energy_vs_amplitude.csv` | per pressure × amplitude: BEM and element energy per cycle, means and 95 % intervals |
//! | `calibration_convergence.csv` | per pressure: spots per patch, points per spot, grid and patch checks with verdicts |
//! | `calibration_loops.csv` | long format: every steady loop (BEM and fitted element) |
//! | `calibration_timings.csv` | wall and CPU times of every chain per stage and per pressure (the only file that differs between two runs) |
//! | `kn_vs_pressure.png`, `e0_vs_pressure.png`, `k_vs_pressure.png` | means with 95 % bands, each realisation, the table's interpolant |
//! | `energy_vs_amplitude.png` | energy per cycle versus amplitude: BEM (mean ± interval) and fitted element |
//! | `k_vs_amplitude.png` | k of the element fitted to each amplitude alone, per pressure (the spread) |
//! | `loop_fit_<p>Pa.png` | first realisation: loops at every amplitude with the fitted element |
//! | `loops_normalised.png` | first realisation, largest amplitude: loop shape versus pressure |
//! | `calibration.json` | configuration, crate version, input hashes, verdicts, warnings |

use crate::calibrate::config::CalibrationConfig;
use crate::calibrate::pipeline::{CalibrationRun, KBound, Realisation};
use crate::calibrate::statistics::summarise;
use crate::calibrate::table::CalibrationRow;
use crate::core::error::{Error, Result};
use crate::core::hash::sha256_hex;
use crate::core::output::write_string_atomic;
use crate::core::plot::{line_plot, LinePlot, Scale, Series};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Where the configuration came from (recorded in the sidecar).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum ConfigSource {
    /// The built-in reference case.
    BuiltIn,
    /// A TOML file as given on the command line, and the SHA-256 of its bytes.
    File {
        /// Path as given on the command line.
        path: PathBuf,
        /// SHA-256 of the file's bytes (hex).
        sha256: String,
    },
}

impl ConfigSource {
    /// A configuration file and its content.
    pub fn file(path: &Path, bytes: &[u8]) -> Self {
        ConfigSource::File {
            path: path.to_path_buf(),
            sha256: sha256_hex(bytes),
        }
    }
}

/// File names written by [`write_outputs`] into the output directory.
pub mod files {
    /// Per pressure: means over the realisations of the contact area ratio, `kn`, `E0`, `k`, `μ`,
    /// `Et` (N/m³), fit R², energy per cycle (J/m²), their 95 % half-widths and the convergence
    /// verdict.
    pub const TABLE: &str = "calibration_table.csv";
    /// Every realisation's values at every pressure (long format), with its contact spots and
    /// solver facts.
    pub const REALISATIONS: &str = "calibration_realisations.csv";
    /// Per realisation, pressure and amplitude: BEM and element energy per cycle (J/m²), their
    /// relative error, the loop fit's R² and the per-amplitude element.
    pub const FITS: &str = "calibration_fits.csv";
    /// Per pressure and amplitude: mean BEM and element energy per cycle (J/m²) with 95 %
    /// half-widths, and their mean relative error.
    pub const ENERGY: &str = "energy_vs_amplitude.csv";
    /// Per pressure: contact spots and the grid and patch-size changes of `kn`, `E0` and `k` with
    /// their intervals, tolerances and verdicts.
    pub const CONVERGENCE: &str = "calibration_convergence.csv";
    /// Every steady loop sample (long format): displacement (m), BEM and fitted element shear
    /// stress (Pa).
    pub const LOOPS: &str = "calibration_loops.csv";
    /// Wall and CPU times per chain, stage and pressure (s); the only file that is not reproducible
    /// byte for byte.
    pub const TIMINGS: &str = "calibration_timings.csv";
    /// JSON sidecar: configuration, crate version, input hashes, verdicts, warnings.
    pub const SIDECAR: &str = "calibration.json";
    /// Plot of `kn` (N/m³) against pressure: means with 95 % bands, each realisation, the table's
    /// interpolant.
    pub const KN_PLOT: &str = "kn_vs_pressure.png";
    /// Plot of `E0` (N/m³) against pressure, likewise.
    pub const E0_PLOT: &str = "e0_vs_pressure.png";
    /// Plot of the Valanis shape `k` against pressure, likewise.
    pub const K_PLOT: &str = "k_vs_pressure.png";
    /// Plot of the energy per cycle (J/m²) against amplitude: BEM (mean ± interval) and fitted
    /// element.
    pub const ENERGY_PLOT: &str = "energy_vs_amplitude.png";
    /// Plot of `k` of the element fitted to each amplitude alone, per pressure (the spread).
    pub const K_AMPLITUDE_PLOT: &str = "k_vs_amplitude.png";
    /// Plot of the first realisation's loop at the largest amplitude, normalised: loop shape
    /// versus pressure.
    pub const LOOPS_PLOT: &str = "loops_normalised.png";

    /// Every fixed name above.
    pub const ALL: [&str; 14] = [
        TABLE,
        REALISATIONS,
        FITS,
        ENERGY,
        CONVERGENCE,
        LOOPS,
        TIMINGS,
        SIDECAR,
        KN_PLOT,
        E0_PLOT,
        K_PLOT,
        ENERGY_PLOT,
        K_AMPLITUDE_PLOT,
        LOOPS_PLOT,
    ];

    /// Per-pressure loops-with-fit figure, e.g. `loop_fit_100000Pa.png`.
    pub fn loop_plot(pressure_pa: f64) -> String {
        format!("loop_fit_{pressure_pa}Pa.png")
    }
}

/// Shape of a sequence along increasing pressure, in words: "rises monotonically",
/// "falls monotonically", "non-monotonic: … maximum … at … MPa", etc.
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
            |b, (i, &v)| {
                if v > b.1 {
                    (i, v)
                } else {
                    b
                }
            },
        );
    let (imin, vmin) =
        values.iter().enumerate().fold(
            (0, f64::INFINITY),
            |b, (i, &v)| {
                if v < b.1 {
                    (i, v)
                } else {
                    b
                }
            },
        );
    let mpa = |i: usize| pressures_pa[i] / 1e6;
    let ends = |word: &str| {
        format!(
            "{word} monotonically from {:.4} at {} MPa to {:.4} at {} MPa",
            values[0],
            mpa(0),
            values[n - 1],
            mpa(n - 1)
        )
    };
    if rising {
        ends("rises")
    } else if falling {
        ends("falls")
    } else {
        let (what, i, v) = if imax > 0 && imax < n - 1 {
            ("maximum", imax, vmax)
        } else {
            ("minimum", imin, vmin)
        };
        format!(
            "non-monotonic: {:.4} at {} MPa, {what} {v:.4} at {} MPa, {:.4} at {} MPa",
            values[0],
            mpa(0),
            mpa(i),
            values[n - 1],
            mpa(n - 1)
        )
    }
}

fn seed_text(r: &Realisation) -> String {
    r.seed
        .map_or_else(|| "given".to_string(), |s| s.to_string())
}

/// `calibration_realisations.csv`.
fn realisations_csv(run: &CalibrationRun) -> String {
    let mut s = String::from(
        "realisation,seed,pressure_Pa,contact_area_ratio,contact_spots,smallest_spot_points,median_spot_points,kn_N_per_m3,mean_gap_m,gross_slip_displacement_m,E0_N_per_m3,k,Et_N_per_m3,k_bound,fit_R2,fit_worst_abs_energy_rel_error,fit_iterations,fit_converged,normal_iterations,tangential_contact_points,tangential_steps,tangential_max_step_iterations,max_loop_closure_error\n",
    );
    for (r_i, r) in run.realisations.iter().enumerate() {
        for pc in &r.pressures {
            let (sw, a, f) = (&pc.sweep, &pc.amplitudes, &pc.fit);
            let worst_energy = f
                .loops
                .iter()
                .map(|l| l.energy_rel_error.abs())
                .fold(0.0, f64::max);
            let closure = a.loops.iter().map(|l| l.closure_error).fold(0.0, f64::max);
            let bound = match KBound::of(f.params.k) {
                KBound::Lower => "lower",
                KBound::Upper => "upper",
                KBound::Inside => "",
            };
            let _ = writeln!(
                s,
                "{},{},{},{:e},{},{},{},{:e},{:e},{:e},{:e},{},{:e},{bound},{},{:e},{},{},{},{},{},{},{:e}",
                r_i + 1,
                seed_text(r),
                sw.pressure_pa,
                sw.contact_area_ratio,
                sw.contact_spots,
                sw.smallest_spot_points,
                sw.median_spot_points,
                sw.kn_n_per_m3,
                sw.mean_gap_m,
                a.gross_slip_displacement_m,
                f.params.e0,
                f.params.k,
                f.params.et,
                f.r2,
                worst_energy,
                f.iterations,
                f.converged,
                sw.iterations,
                a.contact_points,
                a.steps,
                a.max_step_iterations,
                closure
            );
        }
    }
    s
}

/// `calibration_timings.csv`: wall and thread-CPU times of every chain (main realisations and
/// checks), per stage and per pressure point. Not reproducible, so kept out of every other file:
/// a sharded run merged (`asperity merge`) writes the other files byte for byte as a single
/// run does, and here the times the shards measured.
fn timings_csv(run: &CalibrationRun) -> String {
    let mut s = String::from(
        "# asperity calibrate: wall and CPU times (s) of each chain; stage rows have an empty pressure, point rows an empty CPU time; not reproducible\n\
         chain,realisation,seed,stage,pressure_Pa,wall_time_s,cpu_time_s\n",
    );
    for (chain, realisations) in [
        ("main", &run.realisations),
        ("grid-check", &run.grid_check),
        ("patch-check", &run.patch_check),
    ] {
        for (r_i, r) in realisations.iter().enumerate() {
            let t = &r.times;
            let seed = seed_text(r);
            let mut row = |stage: &str, p: String, wall: f64, cpu: String| {
                let _ = writeln!(s, "{chain},{},{seed},{stage},{p},{wall:.3},{cpu}", r_i + 1);
            };
            for (stage, wall, cpu) in [
                ("surface", t.surface_s, t.surface_cpu_s),
                ("normal", t.normal_s, t.normal_cpu_s),
                ("tangential", t.tangential_s, t.tangential_cpu_s),
                ("fit", t.fit_s, t.fit_cpu_s),
            ] {
                row(stage, String::new(), wall, format!("{cpu:.3}"));
            }
            row("chain", String::new(), t.total_s, String::new());
            for pc in &r.pressures {
                let p = pc.sweep.pressure_pa.to_string();
                row("normal", p.clone(), pc.sweep.wall_time_s, String::new());
                row(
                    "tangential",
                    p.clone(),
                    pc.amplitudes.wall_time_s + pc.tangential_setup_s,
                    String::new(),
                );
                let fit = pc.fit.wall_time.as_secs_f64()
                    + pc.per_amplitude
                        .iter()
                        .map(|f| f.wall_time.as_secs_f64())
                        .sum::<f64>();
                row("fit", p, fit, String::new());
            }
        }
    }
    s
}

/// `calibration_fits.csv`.
fn fits_csv(run: &CalibrationRun) -> String {
    let mut s = String::from(
        "realisation,seed,pressure_Pa,amplitude_factor,amplitude_m,energy_bem_J_per_m2,dissipation_bem_J_per_m2,energy_element_J_per_m2,energy_rel_error,element_R2,element_nrmse,E0_this_amplitude_N_per_m3,k_this_amplitude,R2_this_amplitude,energy_rel_error_this_amplitude,loop_closure_error\n",
    );
    for (r_i, r) in run.realisations.iter().enumerate() {
        for pc in &r.pressures {
            for ((l, lf), own) in pc
                .amplitudes
                .loops
                .iter()
                .zip(&pc.fit.loops)
                .zip(&pc.per_amplitude)
            {
                let _ = writeln!(
                    s,
                    "{},{},{},{},{:e},{:e},{:e},{:e},{:e},{},{:e},{:e},{},{},{:e},{:e}",
                    r_i + 1,
                    seed_text(r),
                    pc.sweep.pressure_pa,
                    l.amplitude_factor,
                    l.amplitude_m,
                    l.loop_area_j_per_m2,
                    l.dissipation_j_per_m2,
                    lf.energy_model,
                    lf.energy_rel_error,
                    lf.r2,
                    lf.nrmse,
                    own.params.e0,
                    own.params.k,
                    own.r2,
                    own.loops[0].energy_rel_error,
                    l.closure_error
                );
            }
        }
    }
    s
}

/// `energy_vs_amplitude.csv`.
fn energy_csv(run: &CalibrationRun) -> String {
    let mut s = String::from(
        "pressure_Pa,amplitude_factor,realisations,energy_bem_J_per_m2,energy_bem_ci95_J_per_m2,energy_element_J_per_m2,energy_element_ci95_J_per_m2,mean_rel_error,energy_floor_J_per_m2\n",
    );
    for (i, &p) in run.config.loading.pressures_pa.iter().enumerate() {
        for e in super::pipeline::energy_summaries(&run.config, &run.realisations, i) {
            let (f, bem, el) = (e.factor, &e.bem, &e.element);
            let _ = writeln!(
                s,
                "{p},{f},{},{:e},{:e},{:e},{:e},{},{:e}",
                bem.n,
                bem.mean,
                bem.ci95,
                el.mean,
                el.ci95,
                // Empty where the BEM energy is within its numerical floor.
                e.relative_error()
                    .map_or(String::new(), |r| format!("{r:e}")),
                e.floor
            );
        }
    }
    s
}

/// `calibration_convergence.csv`.
fn convergence_csv(run: &CalibrationRun) -> String {
    let mut s = String::from("pressure_Pa,contact_spots_mean,contact_spots_ci95,median_spot_points,min_median_spot_points");
    for check in ["grid", "patch"] {
        for q in ["kn_N_per_m3", "E0_N_per_m3", "k"] {
            let _ = write!(
                s,
                ",{check}_change_{q},{check}_change_ci95_{q},{check}_tolerance_{q},{check}_verdict_{q}"
            );
        }
        let _ = write!(s, ",{check}_verdict");
    }
    s.push('\n');
    for pc in &run.convergence.pressures {
        let _ = write!(
            s,
            "{},{},{},{},{}",
            pc.pressure_pa,
            pc.contact_spots.mean,
            pc.contact_spots.ci95,
            pc.median_spot_points,
            pc.min_median_spot_points
        );
        for (checks, verdict) in [(&pc.grid, pc.grid_verdict), (&pc.patch, pc.patch_verdict)] {
            for c in checks.iter() {
                let _ = write!(
                    s,
                    ",{:e},{:e},{:e},{}",
                    c.change.mean,
                    c.change.ci95,
                    c.tolerance,
                    c.verdict.as_str()
                );
            }
            let _ = write!(s, ",{}", verdict.as_str());
        }
        s.push('\n');
    }
    s
}

/// `calibration_loops.csv`.
fn loops_csv(run: &CalibrationRun) -> String {
    let n = run.config.loading.steps_per_cycle;
    let mut s = String::from(
        "realisation,seed,pressure_Pa,amplitude_factor,sample,displacement_m,shear_stress_bem_Pa,shear_stress_element_Pa\n",
    );
    for (r_i, r) in run.realisations.iter().enumerate() {
        for pc in &r.pressures {
            for (l, lf) in pc.amplitudes.loops.iter().zip(&pc.fit.loops) {
                let model = &lf.model_force[n / 4..];
                for (k, ((d, t), m)) in l
                    .displacement_m
                    .iter()
                    .zip(&l.shear_stress_pa)
                    .zip(model)
                    .enumerate()
                {
                    let _ = writeln!(
                        s,
                        "{},{},{},{},{k},{d:e},{t:e},{m:e}",
                        r_i + 1,
                        seed_text(r),
                        pc.sweep.pressure_pa,
                        l.amplitude_factor
                    );
                }
            }
        }
    }
    s
}

/// The plots of kn, E0 and k versus pressure: 95 % band, mean, every realisation, and the
/// table's interpolant.
fn parameter_plots(run: &CalibrationRun, out_dir: &Path, written: &mut Vec<PathBuf>) -> Result<()> {
    type Getter = fn(&CalibrationRow) -> f64;
    let rows = &run.table.rows;
    let mpa: Vec<f64> = rows.iter().map(|r| r.pressure_pa / 1e6).collect();
    let (p_lo, p_hi) = run.table.pressure_range();
    let n = run.realisations.len();
    let specs: [(&str, &str, &str, Scale, f64, Getter, usize); 3] = [
        (
            files::KN_PLOT,
            "Normal contact stiffness per unit area vs pressure",
            "kn (10¹² N/m³)",
            Scale::Log,
            1e-12,
            |r| r.element.kn_n_per_m3,
            0,
        ),
        (
            files::E0_PLOT,
            "Valanis E0 (initial tangential stiffness) per unit area vs pressure",
            "E0 (10¹² N/m³)",
            Scale::Log,
            1e-12,
            |r| r.element.e0_n_per_m3,
            1,
        ),
        (
            files::K_PLOT,
            "Valanis shape parameter k vs pressure",
            "k (-)",
            Scale::Linear,
            1.0,
            |r| r.element.k,
            2,
        ),
    ];
    for (name, title, ylabel, yscale, scale, get, q) in specs {
        let per_real = |pc: &crate::calibrate::pipeline::PressureCalibration| match q {
            0 => pc.sweep.kn_n_per_m3,
            1 => pc.fit.params.e0,
            _ => pc.fit.params.k,
        };
        let mut series = Vec::new();
        if let Some(iv) = &run.table.intervals {
            let band: Vec<(f64, f64, f64)> = rows
                .iter()
                .zip(iv)
                .zip(&mpa)
                .map(|((r, iv), &x)| {
                    let (m, h) = match q {
                        0 => (r.element.kn_n_per_m3, iv.kn_n_per_m3),
                        1 => (r.element.e0_n_per_m3, iv.e0_n_per_m3),
                        _ => (r.element.k, iv.k),
                    };
                    let lo = m - h;
                    // A log axis cannot show a non-positive lower edge.
                    let lo = if yscale == Scale::Log && lo <= 0.0 {
                        m * 1e-3
                    } else {
                        lo
                    };
                    (x, lo * scale, (m + h) * scale)
                })
                .collect();
            series.push(
                Series::band(
                    format!("95 % interval of the mean ({n} realisations)"),
                    &band,
                )
                .with_colour(0),
            );
        }
        let interp: Vec<(f64, f64)> = (0..=200)
            .map(|i| {
                let p = p_lo * (p_hi / p_lo).powf(i as f64 / 200.0);
                let v = run.table.interpolate(p);
                let y = match q {
                    0 => v.element.kn_n_per_m3,
                    1 => v.element.e0_n_per_m3,
                    _ => v.element.k,
                };
                (p / 1e6, y * scale)
            })
            .collect();
        series.push(
            Series::line(
                "mean: table interpolation (monotone cubic in log p)",
                interp,
            )
            .with_colour(0),
        );
        let each: Vec<(f64, f64)> = run
            .realisations
            .iter()
            .flat_map(|r| {
                r.pressures
                    .iter()
                    .map(|pc| (pc.sweep.pressure_pa / 1e6, per_real(pc) * scale))
            })
            .collect();
        series.push(Series::markers("each realisation", each).with_colour(7));
        series.push(
            Series::markers(
                "mean",
                mpa.iter()
                    .zip(rows)
                    .map(|(&x, r)| (x, get(r) * scale))
                    .collect(),
            )
            .with_colour(3),
        );
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
            &series,
        )?;
        written.push(path);
    }
    Ok(())
}

/// Energy per cycle versus amplitude (all pressures) and k per amplitude.
///
/// The energy is plotted dimensionless, `W/(μ p̄ δ_gs)` of each realisation (its own gross-slip
/// displacement), so that all pressures share one axis; the CSVs hold the values in J/m².
fn amplitude_plots(run: &CalibrationRun, out_dir: &Path, written: &mut Vec<PathBuf>) -> Result<()> {
    let mu = run.config.contact.mu;
    let factors = &run.config.loading.amplitude_factors;
    let mut series = Vec::new();
    for (i, &p) in run.config.loading.pressures_pa.iter().enumerate() {
        let normalised =
            |f: &dyn Fn(&crate::calibrate::pipeline::PressureCalibration, usize) -> f64,
             j: usize| {
                let v: Vec<f64> = run
                    .realisations
                    .iter()
                    .map(|r| {
                        let pc = &r.pressures[i];
                        f(pc, j) / (mu * p * pc.amplitudes.gross_slip_displacement_m)
                    })
                    .collect();
                summarise(&v)
            };
        let bem: Vec<_> = (0..factors.len())
            .map(|j| normalised(&|pc, j| pc.amplitudes.loops[j].loop_area_j_per_m2, j))
            .collect();
        let el: Vec<_> = (0..factors.len())
            .map(|j| normalised(&|pc, j| pc.fit.loops[j].energy_model, j))
            .collect();
        if run.realisations.len() >= 2 {
            let band: Vec<(f64, f64, f64)> = factors
                .iter()
                .zip(&bem)
                .map(|(&f, b)| (f, (b.mean - b.ci95).max(b.mean * 1e-2), b.mean + b.ci95))
                .collect();
            series.push(
                Series::band(format!("{} MPa: BEM 95 % interval", p / 1e6), &band).with_colour(i),
            );
        }
        series.push(
            Series::markers(
                format!("{} MPa: BEM (mean)", p / 1e6),
                factors
                    .iter()
                    .zip(&bem)
                    .map(|(&f, b)| (f, b.mean))
                    .collect(),
            )
            .with_colour(i),
        );
        series.push(
            Series::line(
                format!("{} MPa: fitted element (mean)", p / 1e6),
                factors.iter().zip(&el).map(|(&f, e)| (f, e.mean)).collect(),
            )
            .with_colour(i),
        );
    }
    let path = out_dir.join(files::ENERGY_PLOT);
    line_plot(
        &path,
        &LinePlot {
            title: "Energy per cycle vs amplitude: BEM (markers, 95 % band), fitted Valanis element (lines)",
            x_label: "amplitude / gross-slip displacement δa/δgs (-)",
            y_label: "energy per cycle / (μ p δgs) (-)",
            x_scale: Scale::Log,
            y_scale: Scale::Log,
        },
        &series,
    )?;
    written.push(path);

    let series: Vec<Series> = run
        .config
        .loading
        .pressures_pa
        .iter()
        .enumerate()
        .map(|(i, &p)| {
            let pts = (0..factors.len())
                .map(|j| {
                    let ks: Vec<f64> = run
                        .realisations
                        .iter()
                        .map(|r| r.pressures[i].per_amplitude[j].params.k)
                        .collect();
                    (factors[j], summarise(&ks).mean)
                })
                .collect();
            Series::line(format!("{} MPa", p / 1e6), pts).with_colour(i)
        })
        .collect();
    let path = out_dir.join(files::K_AMPLITUDE_PLOT);
    line_plot(
        &path,
        &LinePlot {
            title: "k of the element fitted to each amplitude alone (mean over realisations)",
            x_label: "amplitude / gross-slip displacement δa/δgs (-)",
            y_label: "k (-)",
            x_scale: Scale::Log,
            y_scale: Scale::Linear,
        },
        &series,
    )?;
    written.push(path);
    Ok(())
}

/// Loops of the first realisation: per pressure all amplitudes with the fitted element, and
/// the normalised loop shapes at the largest amplitude.
fn loop_plots(run: &CalibrationRun, out_dir: &Path, written: &mut Vec<PathBuf>) -> Result<()> {
    let n = run.config.loading.steps_per_cycle;
    let first = &run.realisations[0];
    for pc in &first.pressures {
        let p = pc.sweep.pressure_pa;
        let mut series = Vec::new();
        for (j, (l, lf)) in pc.amplitudes.loops.iter().zip(&pc.fit.loops).enumerate() {
            series.push(
                Series::markers(
                    format!("BEM, δa = {} δgs", l.amplitude_factor),
                    l.displacement_m
                        .iter()
                        .zip(&l.shear_stress_pa)
                        .map(|(d, t)| (d * 1e6, t / 1e6))
                        .collect(),
                )
                .with_colour(j),
            );
            series.push(
                Series::line(
                    format!("element (energy {:+.1} %)", 100.0 * lf.energy_rel_error),
                    l.displacement_m
                        .iter()
                        .zip(&lf.model_force[n / 4..])
                        .map(|(d, t)| (d * 1e6, t / 1e6))
                        .collect(),
                )
                .with_colour(j),
            );
        }
        let title = format!(
            "Steady loops at {} MPa ({}): BEM and one Valanis element (E0 {:.3e} N/m³, k {:.3}, mean R² {:.4})",
            p / 1e6,
            first.seed.map_or("given surface".to_string(), |s| format!("seed {s}")),
            pc.fit.params.e0,
            pc.fit.params.k,
            pc.fit.r2
        );
        let path = out_dir.join(files::loop_plot(p));
        line_plot(
            &path,
            &LinePlot {
                title: &title,
                x_label: "tangential displacement (µm)",
                y_label: "mean shear stress (MPa)",
                x_scale: Scale::Linear,
                y_scale: Scale::Linear,
            },
            &series,
        )?;
        written.push(path);
    }
    let mu = run.config.contact.mu;
    let series: Vec<Series> = first
        .pressures
        .iter()
        .map(|pc| {
            let l = pc.amplitudes.loops.last().expect("at least one amplitude");
            let scale = mu * pc.sweep.pressure_pa;
            Series::line(
                format!("{} MPa", pc.sweep.pressure_pa / 1e6),
                l.displacement_m
                    .iter()
                    .zip(&l.shear_stress_pa)
                    .map(|(d, t)| (d / l.amplitude_m, t / scale))
                    .collect(),
            )
        })
        .collect();
    let path = out_dir.join(files::LOOPS_PLOT);
    line_plot(
        &path,
        &LinePlot {
            title:
                "Steady BEM loops at the largest amplitude, normalised: loop shape versus pressure",
            x_label: "displacement / amplitude δ/δa (-)",
            y_label: "shear stress / (μ p) (-)",
            x_scale: Scale::Linear,
            y_scale: Scale::Linear,
        },
        &series,
    )?;
    written.push(path);
    Ok(())
}

fn sidecar(
    run: &CalibrationRun,
    source: &ConfigSource,
    table_sha: &str,
    written: &[PathBuf],
) -> Result<String> {
    let config_toml = run.config.to_toml_string()?;
    let (source_desc, file_hash) = match source {
        ConfigSource::BuiltIn => ("built-in reference case".to_string(), None),
        ConfigSource::File { path, sha256 } => (path.display().to_string(), Some(sha256.clone())),
    };
    let pressures: Vec<f64> = run.table.rows.iter().map(|r| r.pressure_pa).collect();
    let ks: Vec<f64> = run.table.rows.iter().map(|r| r.element.k).collect();
    let kn: Vec<f64> = run
        .table
        .rows
        .iter()
        .map(|r| r.element.kn_n_per_m3)
        .collect();
    let e0: Vec<f64> = run
        .table
        .rows
        .iter()
        .map(|r| r.element.e0_n_per_m3)
        .collect();
    let realisations: Vec<serde_json::Value> = run
        .realisations
        .iter()
        .map(|r| {
            serde_json::json!({
                "seed": r.seed,
                "grid": r.grid,
                "patch_m": r.patch_m,
                "surface_heights_sha256": r.surface_sha256,
            })
        })
        .collect();
    let json = serde_json::json!({
        "tool": "asperity calibrate",
        "crate_version": env!("CARGO_PKG_VERSION"),
        "units": "SI, per unit nominal area: pressures and shear in Pa, displacements in m, kn/E0/Et in N/m^3, energies in J/m^2",
        "config_source": source_desc,
        "config": run.config,
        "surfaces": run.surface_description,
        "input_hashes": {
            "config_file_sha256": file_hash,
            "config_canonical_toml_sha256": sha256_hex(config_toml.as_bytes()),
            "surface_heights_sha256": run.realisations.iter().map(|r| r.surface_sha256.clone()).collect::<Vec<_>>(),
        },
        "realisations": realisations,
        "outputs": {
            "table": crate::calibrate::output::files::TABLE,
            "table_sha256": table_sha,
            "files": written.iter().filter_map(|p| p.file_name().map(|f| f.to_string_lossy().to_string())).collect::<Vec<_>>(),
        },
        "method": {
            "realisations": "Gaussian surfaces of the [surface] statistics with seeds seed, seed+1, ...; per pressure the mean and the half-width of the 95 % Student-t confidence interval of the mean",
            "loading": "per pressure one history of increasing displacement amplitudes (amplitude_factors x gross-slip displacement) along x: virgin quarter cycle, then per amplitude one half cycle (its point reflection completes the steady loop, Masing) and the continuation to the next amplitude",
            "fit": "one Valanis element per pressure and realisation fitted to all amplitudes together (mean of 1 - R^2 over the loops, each loop from the element's virgin state), and one per amplitude; Fz = nominal pressure, mu fixed; Nelder-Mead (argmin) on E0 = E0ref*exp(t0), k = logistic(t1), Et = E0*logistic(t2)",
            "kn": crate::calibrate::table::kn_comment(run.config.material.hardness()?),
            "convergence": "grid: the same surfaces with half the points per side (paired differences); patch: independent surfaces on the half-size patch at the same spacing (Welch); converged when the 95 % interval of the change lies within the tolerance",
            "tangential_assumption": crate::contact::tangential::QUASI_IDENTICAL_ASSUMPTION,
        },
        "summary": {
            "realisations": run.realisations.len(),
            "mean_kn_rises_monotonically": kn.windows(2).all(|w| w[1] > w[0]),
            "mean_E0_rises_monotonically": e0.windows(2).all(|w| w[1] > w[0]),
            "mean_k_shape": describe_shape(&pressures, &ks),
            "min_fit_R2": run.realisations.iter().flat_map(|r| r.pressures.iter().map(|pc| pc.fit.r2)).fold(f64::INFINITY, f64::min),
        },
        "convergence": run.convergence,
        "warnings": run.warnings,
        "times": crate::calibrate::output::files::TIMINGS,
    });
    serde_json::to_string_pretty(&json)
        .map(|t| t + "\n")
        .map_err(|e| Error::Data(format!("cannot serialise sidecar: {e}")))
}

/// Write every file of the table above into `out_dir` (each atomically). Returns the paths
/// written and the time it took (s).
pub fn write_outputs(
    run: &CalibrationRun,
    source: &ConfigSource,
    out_dir: &Path,
) -> Result<(Vec<PathBuf>, f64)> {
    let started = Instant::now();
    let mut written = Vec::new();
    let table_path = out_dir.join(files::TABLE);
    run.table.write_csv(&table_path)?;
    written.push(table_path.clone());
    for (name, text) in [
        (files::REALISATIONS, realisations_csv(run)),
        (files::FITS, fits_csv(run)),
        (files::ENERGY, energy_csv(run)),
        (files::CONVERGENCE, convergence_csv(run)),
        (files::LOOPS, loops_csv(run)),
        (files::TIMINGS, timings_csv(run)),
    ] {
        let path = out_dir.join(name);
        write_string_atomic(&path, &text)?;
        written.push(path);
    }
    parameter_plots(run, out_dir, &mut written)?;
    amplitude_plots(run, out_dir, &mut written)?;
    loop_plots(run, out_dir, &mut written)?;
    let table_sha = sha256_hex(&std::fs::read(&table_path).map_err(|e| Error::io(&table_path, e))?);
    let path = out_dir.join(files::SIDECAR);
    let mut all = written.clone();
    all.push(path.clone());
    let text = sidecar(run, source, &table_sha, &all)?;
    write_string_atomic(&path, &text)?;
    written.push(path);
    Ok((written, started.elapsed().as_secs_f64()))
}

/// Used by the CLI to print the configuration in one line.
pub fn describe_config(config: &CalibrationConfig) -> String {
    let l = &config.loading;
    format!(
        "{} pressure(s) {:?} Pa, amplitudes {:?} x gross-slip displacement, {} steps per cycle, mu = {}",
        l.pressures_pa.len(),
        l.pressures_pa,
        l.amplitude_factors,
        l.steps_per_cycle,
        config.contact.mu
    )
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
}
