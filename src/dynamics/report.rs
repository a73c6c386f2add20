//! Output files of a frequency-response run: one CSV per excitation level, the element energies
//! and contact states at each level's peak, and the PNG of the FRF family. Every file is written
//! atomically ([`crate::core::output`]).

use crate::core::error::{Error, Result};
use crate::core::plot::{line_plot, LinePlot, Scale, Series};
use crate::dynamics::aft::ElementCycle;
use crate::dynamics::continuation::Branch;
use crate::dynamics::hbm::HbmSystem;
use nalgebra::DVector;
use std::path::Path;

const TWO_PI: f64 = 2.0 * std::f64::consts::PI;

/// Everything written for one excitation level.
#[derive(Debug, Clone)]
pub struct LevelResult {
    pub level_n: f64,
    pub branch: Branch,
    /// Per point: total dissipated energy (J) and element-averaged stick/slip/separation.
    pub totals: Vec<[f64; 4]>,
    /// Index of the point with the largest first-harmonic amplitude of the first response DOF.
    pub peak: usize,
    /// Element cycles at the peak.
    pub peak_elements: Vec<ElementCycle>,
}

/// Amplitude and phase (of the complex amplitude `a − i·b`) of order `k` of `row·x`.
pub fn harmonic_of(
    system: &HbmSystem<'_>,
    x: &DVector<f64>,
    row: &DVector<f64>,
    k: usize,
) -> (f64, f64) {
    let len = system.harmonics.len();
    let n = row.len();
    if k == 0 {
        let m: f64 = (0..n).map(|r| row[r] * x[r * len]).sum();
        return (m, 0.0);
    }
    let (ci, si) = system.harmonics.index_of(k).expect("retained order");
    let a: f64 = (0..n).map(|r| row[r] * x[r * len + ci]).sum();
    let b: f64 = (0..n).map(|r| row[r] * x[r * len + si]).sum();
    (a.hypot(b), (-b).atan2(a))
}

/// Solve the element cycles along a branch and find its peak.
pub fn summarise(
    system: &HbmSystem<'_>,
    level_n: f64,
    branch: Branch,
    peak_row: &DVector<f64>,
) -> LevelResult {
    let mut totals = Vec::with_capacity(branch.points.len());
    let mut peak = 0;
    let mut best = f64::NEG_INFINITY;
    let ne = system.structure.elements.len().max(1) as f64;
    for (i, p) in branch.points.iter().enumerate() {
        let x = system.coordinates(p);
        let (a, _) = harmonic_of(system, &x, peak_row, system.excitation.harmonic);
        if a > best {
            best = a;
            peak = i;
        }
        let cycles = system.element_cycles(p);
        let mut t = [0.0; 4];
        for c in &cycles {
            t[0] += c.dissipated_energy_j;
            t[1] += c.stick_fraction / ne;
            t[2] += c.slip_fraction / ne;
            t[3] += c.separation_fraction / ne;
        }
        totals.push(t);
    }
    let peak_elements = system.element_cycles(&branch.points[peak]);
    LevelResult {
        level_n,
        branch,
        totals,
        peak,
        peak_elements,
    }
}

/// The columns of one level, named as in its CSV: `frequency_Hz`; per response DOF and retained
/// harmonic `k` the amplitude `<dof>_h<k>_amplitude_m` (m) and phase `<dof>_h<k>_phase_rad` of
/// `a − i·b` (or `<dof>_h0_mean_m`); then `dissipated_energy_J` (J per cycle, summed over the
/// elements), the element-averaged `stick_fraction`, `slip_fraction`, `separation_fraction`,
/// `newton_iterations`, `relative_residual` and `aft_periodicity_error` (the largest relative
/// periodicity error of an element's AFT state at the point; above the AFT tolerance, 1e-12 by
/// default, an element did not reach its periodic state within the period cap). One value per
/// branch point.
pub fn level_columns(
    system: &HbmSystem<'_>,
    responses: &[(String, DVector<f64>)],
    result: &LevelResult,
) -> Vec<(String, Vec<f64>)> {
    let points = &result.branch.points;
    let mut cols = vec![(
        "frequency_Hz".to_string(),
        points
            .iter()
            .map(|p| p.omega / TWO_PI)
            .collect::<Vec<f64>>(),
    )];
    let coordinates: Vec<DVector<f64>> = points.iter().map(|p| system.coordinates(p)).collect();
    for (label, row) in responses {
        for &k in system.harmonics.orders() {
            let h: Vec<(f64, f64)> = coordinates
                .iter()
                .map(|x| harmonic_of(system, x, row, k))
                .collect();
            if k == 0 {
                cols.push((
                    format!("{label}_h0_mean_m"),
                    h.iter().map(|v| v.0).collect(),
                ));
            } else {
                cols.push((
                    format!("{label}_h{k}_amplitude_m"),
                    h.iter().map(|v| v.0).collect(),
                ));
                cols.push((
                    format!("{label}_h{k}_phase_rad"),
                    h.iter().map(|v| v.1).collect(),
                ));
            }
        }
    }
    for (j, name) in [
        "dissipated_energy_J",
        "stick_fraction",
        "slip_fraction",
        "separation_fraction",
    ]
    .into_iter()
    .enumerate()
    {
        cols.push((
            name.to_string(),
            result.totals.iter().map(|t| t[j]).collect(),
        ));
    }
    cols.push((
        "newton_iterations".to_string(),
        points.iter().map(|p| p.iterations as f64).collect(),
    ));
    cols.push((
        "relative_residual".to_string(),
        points.iter().map(|p| p.residual).collect(),
    ));
    cols.push((
        "aft_periodicity_error".to_string(),
        points.iter().map(|p| p.periodicity_error).collect(),
    ));
    cols
}

/// CSV of one level: the [`level_columns`], amplitudes to 10 significant digits.
pub fn write_level_csv(
    path: &Path,
    system: &HbmSystem<'_>,
    responses: &[(String, DVector<f64>)],
    result: &LevelResult,
    header: &str,
) -> Result<()> {
    let cols = level_columns(system, responses, result);
    crate::core::output::write_atomic(path, |w| {
        let io = |e: std::io::Error| Error::io(path, e);
        for l in header.lines() {
            writeln!(w, "# {l}").map_err(io)?;
        }
        writeln!(
            w,
            "# excitation level {} N (force amplitude of cos(ωt) on the excitation DOF)",
            result.level_n
        )
        .map_err(io)?;
        writeln!(w, "# units: frequency_Hz in Hz; amplitudes in m (h0: mean displacement); phase_rad = arg(a − i·b) of x = a·cos(kωt) + b·sin(kωt), relative to the force cos(ωt);").map_err(io)?;
        writeln!(w, "#   dissipated_energy_J: sum over elements of ∮f·du per cycle; stick/slip/separation: element-averaged fractions of the period;").map_err(io)?;
        writeln!(w, "#   relative_residual: harmonic-balance residual / its scale; aft_periodicity_error: largest relative periodicity error of an element's AFT state (above {:.0e}: not periodic within {} periods)", system.aft.periodicity_tolerance, system.aft.max_periods).map_err(io)?;
        let names: Vec<&str> = cols.iter().map(|(n, _)| n.as_str()).collect();
        writeln!(w, "{}", names.join(",")).map_err(io)?;
        for i in 0..result.branch.points.len() {
            let v: Vec<String> = cols
                .iter()
                .map(|(name, values)| {
                    let x = values[i];
                    if name.ends_with("_phase_rad") {
                        format!("{x:.6}")
                    } else if name == "newton_iterations" {
                        format!("{}", x as usize)
                    } else if name == "relative_residual" || name == "aft_periodicity_error" {
                        format!("{x:.3e}")
                    } else if name.ends_with("_fraction") || name == "dissipated_energy_J" {
                        format!("{x:.6e}")
                    } else {
                        format!("{x:.9e}")
                    }
                })
                .collect();
            writeln!(w, "{}", v.join(",")).map_err(io)?;
        }
        Ok(())
    })
}

/// CSV of the elements at a level's peak.
pub fn write_elements_csv(path: &Path, system: &HbmSystem<'_>, result: &LevelResult) -> Result<()> {
    let peak = &result.branch.points[result.peak];
    crate::core::output::write_atomic(path, |w| {
        let io = |e: std::io::Error| Error::io(path, e);
        writeln!(
            w,
            "# elements at the resonance peak of level {} N: {:.6} Hz",
            result.level_n,
            peak.omega / TWO_PI
        )
        .map_err(io)?;
        writeln!(
            w,
            "# units: dissipated_energy_J in J per cycle; fractions of the period"
        )
        .map_err(io)?;
        writeln!(
            w,
            "element,law,dissipated_energy_J,stick_fraction,slip_fraction,separation_fraction"
        )
        .map_err(io)?;
        for (e, c) in system.structure.elements.iter().zip(&result.peak_elements) {
            writeln!(
                w,
                "{},{},{:.6e},{:.6},{:.6},{:.6}",
                e.label,
                e.element.name(),
                c.dissipated_energy_j,
                c.stick_fraction,
                c.slip_fraction,
                c.separation_fraction
            )
            .map_err(io)?;
        }
        Ok(())
    })
}

/// PNG of the FRF family: the receptance at the excitation's harmonic `e`, `|X_e|/F` (m/N), of
/// one response DOF versus frequency, one curve per level (`e = 1` unless the drive is at a
/// higher harmonic).
pub fn plot_frf_family(
    path: &Path,
    system: &HbmSystem<'_>,
    label: &str,
    row: &DVector<f64>,
    results: &[LevelResult],
) -> Result<()> {
    let series: Vec<Series> = results
        .iter()
        .map(|r| {
            let pts = r
                .branch
                .points
                .iter()
                .map(|p| {
                    let x = system.coordinates(p);
                    let (a, _) = harmonic_of(system, &x, row, system.excitation.harmonic);
                    (p.omega / TWO_PI, a / r.level_n)
                })
                .collect();
            Series::line(format!("F = {} N", r.level_n), pts)
        })
        .collect();
    let e = system.excitation.harmonic;
    let title = if e == 1 {
        format!("FRF family at {label}: first-harmonic receptance")
    } else {
        format!("FRF family at {label}: receptance at harmonic {e} (the excitation's)")
    };
    let y_label = format!("|X{e}| / F (m/N)");
    line_plot(
        path,
        &LinePlot {
            title: &title,
            x_label: "frequency (Hz)",
            y_label: &y_label,
            x_scale: Scale::Linear,
            y_scale: Scale::Log,
        },
        &series,
    )
}
