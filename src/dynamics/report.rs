//! Output files of a frequency-response run: one CSV per excitation level, the element energies
//! and contact states at each level's peak, and the PNG of the FRF family. Every file is written
//! atomically ([`crate::core::output`]).

use crate::core::error::{Error, Result};
use crate::core::plot::{line_plot, LinePlot, Scale, Series};
use crate::dynamics::aft::ElementCycle;
use crate::dynamics::continuation::Branch;
use crate::dynamics::hbm::{HbmPoint, HbmSystem};
use crate::dynamics::stability::BranchStability;
use nalgebra::DVector;
use std::path::Path;

const TWO_PI: f64 = 2.0 * std::f64::consts::PI;

/// Everything written for one excitation level.
#[derive(Debug, Clone)]
pub struct LevelResult {
    /// Excitation force amplitude of the level (N).
    pub level_n: f64,
    /// The computed frequency-response branch.
    pub branch: Branch,
    /// Per point: total dissipated energy (J) and element-averaged stick/slip/separation.
    pub totals: Vec<[f64; 4]>,
    /// Index of the point with the largest first-harmonic amplitude of the first response DOF.
    pub peak: usize,
    /// The peak between the points ([`interpolated_peak`]).
    pub interpolated_peak: Peak,
    /// Element cycles at the peak.
    pub peak_elements: Vec<ElementCycle>,
    /// Stability of every point by Hill's method (`None`: not assessed).
    pub stability: Option<BranchStability>,
}

/// The resonance peak of a branch: amplitude (at the excitation's harmonic) and frequency.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Peak {
    /// Peak displacement amplitude at the excitation's harmonic (m).
    pub amplitude_m: f64,
    /// Frequency of the peak (Hz).
    pub frequency_hz: f64,
    /// The largest amplitude is at the first or the last point of the branch: the peak may lie
    /// outside the span (or the branch stopped before it); not interpolated.
    pub at_sweep_end: bool,
}

/// Most solves on the branch spent locating a peak ([`refined_peak`]).
const PEAK_SOLVES: usize = 12;

/// The peak of a branch located on the branch itself, not on an interpolant: successive
/// parabolic interpolation (Brent's parabolic step; Press et al., *Numerical Recipes*, 3rd ed.,
/// §10.3) of the amplitude `a(s)` of `row·x` at the excitation's harmonic along the branch's
/// arclength `s`, starting from the largest point and its neighbours, each new abscissa solved
/// on the branch ([`crate::dynamics::continuation::point_between`]) and replacing the worst of
/// the three, until the vertex moves by less than 1e-6 of the bracket (at most `PEAK_SOLVES`
/// solves). Its accuracy is that of the harmonic balance, not of the point spacing: a parabola
/// through three points of a skewed friction peak errs by up to 0.1 % in amplitude and frequency
/// at the default spacing. `None` when a solve fails (the caller keeps [`interpolated_peak`]).
pub fn refined_peak(
    system: &HbmSystem<'_>,
    level: f64,
    branch: &Branch,
    i: usize,
    row: &DVector<f64>,
) -> Option<Peak> {
    use crate::dynamics::continuation::{point_arclengths, point_between};
    let pts = &branch.points;
    if i == 0 || i + 1 >= pts.len() {
        return None;
    }
    let frame = [&pts[i - 1], &pts[i], &pts[i + 1]];
    let (_, _, s) = point_arclengths(frame);
    let amplitude = |p: &HbmPoint| {
        let x = system.coordinates(p);
        harmonic_of(system, &x, row, system.excitation.harmonic).0
    };
    // (s, a, ω) of the three points kept, the middle one the largest.
    let mut best: Vec<(f64, f64, f64)> = (0..3)
        .map(|k| (s[k], amplitude(frame[k]), frame[k].omega))
        .collect();
    let (lo, hi) = (s[0], s[2]);
    for _ in 0..PEAK_SOLVES {
        best.sort_by(|a, b| a.0.total_cmp(&b.0));
        let [(x0, a0, _), (x1, a1, _), (x2, a2, _)] = [best[0], best[1], best[2]];
        let d01 = (a1 - a0) / (x1 - x0);
        let d12 = (a2 - a1) / (x2 - x1);
        let c = (d12 - d01) / (x2 - x0);
        if c.is_nan() || c >= 0.0 {
            break;
        }
        let vertex = (0.5 * (x0 + x1) - d01 / (2.0 * c)).clamp(lo, hi);
        if best
            .iter()
            .any(|p| (p.0 - vertex).abs() <= 1e-6 * (hi - lo))
        {
            break;
        }
        let p = point_between(system, level, frame, vertex)?;
        let a = amplitude(&p);
        best.push((vertex, a, p.omega));
        // Keep the largest and its nearest neighbours on either side.
        best.sort_by(|a, b| b.1.total_cmp(&a.1));
        let top = best[0];
        let left = best
            .iter()
            .filter(|p| p.0 < top.0)
            .max_by(|a, b| a.0.total_cmp(&b.0))
            .copied();
        let right = best
            .iter()
            .filter(|p| p.0 > top.0)
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .copied();
        match (left, right) {
            (Some(l), Some(r)) => best = vec![l, top, r],
            _ => break,
        }
    }
    let top = best.iter().max_by(|a, b| a.1.total_cmp(&b.1))?;
    Some(Peak {
        amplitude_m: top.1,
        frequency_hz: top.2 / TWO_PI,
        at_sweep_end: false,
    })
}

/// The peak of the amplitudes `a_i` at the frequencies `f_i` of a branch's points, between the
/// points: the parabola through the largest point and its two neighbours in the branch's
/// arclength `s` (distances in `a/a_max` and `f/(f_max − f_min)`, so that a peak on a fold,
/// where `a(f)` has two values, is as well defined as any) gives `s*` at its vertex and the
/// amplitude there; the frequency is the parabola through the three `f_i` at `s*`. Both are
/// exact for a quadratic branch and err by O(h³) on a smooth one (h the point spacing): the
/// sweep's step control puts some twenty points on a peak, so this removes the error of taking
/// the largest point, which is of the order of the point spacing in frequency (Press et al.,
/// *Numerical Recipes*, 3rd ed., §10.3, the parabolic step of Brent's method). At a sweep end
/// the largest point is returned as it is, flagged.
pub fn interpolated_peak(amplitudes: &[f64], frequencies: &[f64]) -> Peak {
    let n = amplitudes.len();
    let i = (0..n)
        .max_by(|&a, &b| amplitudes[a].total_cmp(&amplitudes[b]))
        .unwrap_or(0);
    let largest = Peak {
        amplitude_m: amplitudes.get(i).copied().unwrap_or(f64::NAN),
        frequency_hz: frequencies.get(i).copied().unwrap_or(f64::NAN),
        at_sweep_end: true,
    };
    if n < 3 || i == 0 || i == n - 1 {
        return largest;
    }
    let amax = amplitudes[i].abs().max(f64::MIN_POSITIVE);
    let (fmin, fmax) = frequencies
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &f| {
            (lo.min(f), hi.max(f))
        });
    let fspan = (fmax - fmin).max(f64::MIN_POSITIVE);
    let dist = |a: usize, b: usize| {
        ((amplitudes[b] - amplitudes[a]) / amax).hypot((frequencies[b] - frequencies[a]) / fspan)
    };
    let s = [-dist(i - 1, i), 0.0, dist(i, i + 1)];
    let a = [amplitudes[i - 1], amplitudes[i], amplitudes[i + 1]];
    let f = [frequencies[i - 1], frequencies[i], frequencies[i + 1]];
    if !(s[0] < 0.0 && s[2] > 0.0) {
        return Peak {
            at_sweep_end: false,
            ..largest
        };
    }
    // Newton's divided differences of the parabola through (s_k, y_k).
    let parabola = |y: [f64; 3]| {
        let d01 = (y[1] - y[0]) / (s[1] - s[0]);
        let d12 = (y[2] - y[1]) / (s[2] - s[1]);
        let d012 = (d12 - d01) / (s[2] - s[0]);
        move |x: f64| y[0] + d01 * (x - s[0]) + d012 * (x - s[0]) * (x - s[1])
    };
    let d01 = (a[1] - a[0]) / (s[1] - s[0]);
    let d12 = (a[2] - a[1]) / (s[2] - s[1]);
    let curvature = (d12 - d01) / (s[2] - s[0]);
    if curvature.is_nan() || curvature >= 0.0 {
        return Peak {
            at_sweep_end: false,
            ..largest
        };
    }
    // Vertex of y0 + d01·(x − s0) + c·(x − s0)(x − s1): d01 + c·(2x − s0 − s1) = 0.
    let vertex = (0.5 * (s[0] + s[1]) - d01 / (2.0 * curvature)).clamp(s[0], s[2]);
    Peak {
        amplitude_m: parabola(a)(vertex),
        frequency_hz: parabola(f)(vertex),
        at_sweep_end: false,
    }
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
    let mut amplitudes = Vec::with_capacity(branch.points.len());
    let ne = system.structure.elements.len().max(1) as f64;
    for (i, p) in branch.points.iter().enumerate() {
        let x = system.coordinates(p);
        let (a, _) = harmonic_of(system, &x, peak_row, system.excitation.harmonic);
        amplitudes.push(a);
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
    let frequencies: Vec<f64> = branch.points.iter().map(|p| p.omega / TWO_PI).collect();
    let between = interpolated_peak(&amplitudes, &frequencies);
    let refined = if between.at_sweep_end {
        between
    } else {
        refined_peak(system, level_n, &branch, peak, peak_row).unwrap_or(between)
    };
    LevelResult {
        level_n,
        interpolated_peak: refined,
        branch,
        totals,
        peak,
        peak_elements,
        stability: None,
    }
}

/// The columns of one level, named as in its CSV: `frequency_Hz`; per response DOF and retained
/// harmonic `k` the amplitude `<dof>_h<k>_amplitude_m` (m; `_rad` for a rotation `node.rx|ry|rz`)
/// and phase `<dof>_h<k>_phase_rad` of `a − i·b` (or `<dof>_h0_mean_m`); then `dissipated_energy_J` (J per cycle, summed over the
/// elements), the element-averaged `stick_fraction`, `slip_fraction`, `separation_fraction`,
/// `newton_iterations`, `relative_residual` and `aft_periodicity_error` (the largest relative
/// periodicity error of an element's AFT state at the point; above the AFT tolerance, 1e-12 by
/// default, an element did not reach its periodic state within the period cap); when the
/// stability was assessed, `stable` (1 or 0, Hill's method,
/// [`crate::dynamics::stability`]) and `floquet_max_real_part_per_s` (the largest real part of
/// the kept Floquet exponents, 1/s). One value per branch point.
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
            let unit = crate::dynamics::model_file::dof_unit(label);
            if k == 0 {
                cols.push((
                    format!("{label}_h0_mean_{unit}"),
                    h.iter().map(|v| v.0).collect(),
                ));
            } else {
                cols.push((
                    format!("{label}_h{k}_amplitude_{unit}"),
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
    if let Some(st) = &result.stability {
        cols.push((
            "stable".to_string(),
            st.points
                .iter()
                .map(|s| f64::from(u8::from(s.stable)))
                .collect(),
        ));
        cols.push((
            "floquet_max_real_part_per_s".to_string(),
            st.points.iter().map(|s| s.max_real_part).collect(),
        ));
    }
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
        let pk = &result.interpolated_peak;
        writeln!(
            w,
            "# peak of the first response DOF (interpolated between the points): {:.9e} m at {:.9e} Hz{}",
            pk.amplitude_m,
            pk.frequency_hz,
            if pk.at_sweep_end {
                "; WARNING: at the end of the sweep, the peak may lie outside the span"
            } else {
                ""
            }
        )
        .map_err(io)?;
        if let Some(why) = &result.branch.stopped {
            writeln!(
                w,
                "# INCOMPLETE: the sweep stopped before the end of its span: {why}"
            )
            .map_err(io)?;
        }
        writeln!(w, "# units: frequency_Hz in Hz; amplitudes in m (h0: mean displacement); phase_rad = arg(a − i·b) of x = a·cos(kωt) + b·sin(kωt), relative to the force cos(ωt);").map_err(io)?;
        writeln!(w, "#   dissipated_energy_J: sum over elements of ∮f·du per cycle; stick/slip/separation: element-averaged fractions of the period;").map_err(io)?;
        writeln!(w, "#   relative_residual: harmonic-balance residual / its scale; aft_periodicity_error: largest relative periodicity error of an element's AFT state (above {:.0e}: not periodic within {} periods)", system.aft.periodicity_tolerance, system.aft.max_periods).map_err(io)?;
        if result.stability.is_some() {
            writeln!(w, "#   stable: 1 if no Floquet exponent of Hill's method has a real part above {:.0e}·ω, else 0; floquet_max_real_part_per_s: the largest real part of the kept exponents (1/s)", crate::dynamics::stability::UNSTABLE_TOLERANCE).map_err(io)?;
        }
        let names: Vec<&str> = cols.iter().map(|(n, _)| n.as_str()).collect();
        writeln!(w, "{}", names.join(",")).map_err(io)?;
        for i in 0..result.branch.points.len() {
            let v: Vec<String> = cols
                .iter()
                .map(|(name, values)| {
                    let x = values[i];
                    if name.ends_with("_phase_rad") {
                        format!("{x:.6}")
                    } else if name == "newton_iterations" || name == "stable" {
                        format!("{}", x as usize)
                    } else if name == "relative_residual" || name == "aft_periodicity_error" {
                        format!("{x:.3e}")
                    } else if name.ends_with("_fraction")
                        || name == "dissipated_energy_J"
                        || name == "floquet_max_real_part_per_s"
                    {
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

/// A branch's polyline cut into pieces by stability: a segment is drawn dashed when either of
/// its points is unstable; consecutive segments of one style form one piece (`(points, dashed)`).
fn stability_pieces(pts: &[(f64, f64)], stable: &[bool]) -> Vec<(Vec<(f64, f64)>, bool)> {
    if pts.len() < 2 {
        return vec![(pts.to_vec(), stable.first().is_some_and(|s| !s))];
    }
    let mut pieces: Vec<(Vec<(f64, f64)>, bool)> = Vec::new();
    for i in 0..pts.len() - 1 {
        let dashed = !(stable[i] && stable[i + 1]);
        match pieces.last_mut() {
            Some((piece, d)) if *d == dashed => piece.push(pts[i + 1]),
            _ => pieces.push((vec![pts[i], pts[i + 1]], dashed)),
        }
    }
    pieces
}

/// PNG of the FRF family: the receptance at the excitation's harmonic `e`, `|X_e|/F` (m/N), of
/// one response DOF versus frequency, one curve per level (`e = 1` unless the drive is at a
/// higher harmonic), dashed where Hill's method finds the points unstable; with `row_is_peak_row` (the DOF the peaks are found on) a marker at each
/// level's interpolated peak.
pub fn plot_frf_family(
    path: &Path,
    system: &HbmSystem<'_>,
    label: &str,
    row: &DVector<f64>,
    results: &[LevelResult],
    row_is_peak_row: bool,
) -> Result<()> {
    let mut series = Vec::new();
    let mut any_unstable = false;
    for (i, r) in results.iter().enumerate() {
        let pts: Vec<(f64, f64)> = r
            .branch
            .points
            .iter()
            .map(|p| {
                let x = system.coordinates(p);
                let (a, _) = harmonic_of(system, &x, row, system.excitation.harmonic);
                (p.omega / TWO_PI, a / r.level_n)
            })
            .collect();
        let stable: Vec<bool> = match &r.stability {
            Some(st) => st.points.iter().map(|s| s.stable).collect(),
            None => vec![true; pts.len()],
        };
        any_unstable |= stable.iter().any(|s| !s);
        for (k, (piece, dashed)) in stability_pieces(&pts, &stable).into_iter().enumerate() {
            let label = if k == 0 {
                format!("F = {} N", r.level_n)
            } else {
                String::new()
            };
            let s = Series::line(label, piece).with_colour(i);
            series.push(if dashed { s.dashed() } else { s });
        }
    }
    if any_unstable {
        series.push(
            Series::line("unstable (Hill's method)", Vec::new())
                .with_colour(7)
                .dashed(),
        );
    }
    // On the first response DOF's plot, the interpolated peaks: one marker per level in its
    // colour.
    if row_is_peak_row {
        for (i, r) in results.iter().enumerate() {
            let pk = &r.interpolated_peak;
            if pk.amplitude_m.is_finite() {
                let label = if pk.at_sweep_end {
                    format!("peak {} N (at the sweep end)", r.level_n)
                } else {
                    format!("peak {} N", r.level_n)
                };
                series.push(
                    Series::markers(label, vec![(pk.frequency_hz, pk.amplitude_m / r.level_n)])
                        .with_colour(i),
                );
            }
        }
    }
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
