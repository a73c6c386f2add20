//! Error measures of a model against a measured level, and the files of an identification or
//! a prediction: text, JSON (inputs with SHA-256), CSV, the saved model, PNG figures. Every file
//! is written atomically ([`crate::core::output`]).
//!
//! # Error measures (per level)
//!
//! With `Y` the response of the level's quantity per unit force (accelerance for an
//! accelerometer), measured and modelled at the measured rows (the model driven by the measured
//! force of each row):
//!
//! * **resonance frequency error** (Hz): model minus measured frequency of the largest `|Y|`,
//!   each refined by the vertex of the parabola through the largest row and its neighbours
//!   ([`super::backbone::resonance`]);
//! * **phase-resonance frequency error** (Hz): model minus measured frequency where the
//!   displacement is in quadrature with the force ([`super::backbone::phase_resonance`], the
//!   sign change of the dynamic stiffness `Re(1/X)` nearest to the amplitude peak, `X` the
//!   displacement receptance): the resonance of nonlinear modal
//!   testing, which a dip of the shaker's force at the peak does not shift;
//! * **peak error**: model peak `|Y|` over measured peak, minus 1 (same refinement);
//! * **RMS complex error**: `√(mean |Y_model − Y_meas|²) / max |Y_meas|` (amplitude and phase);
//! * the same RMS and the mean amplitude and phase errors per **region**: below the
//!   measured half-power band, inside it ("at resonance"), above it.

use super::backbone::{half_power_rows, phase_resonance, resonance, BackbonePoint, LevelBackbone};
use super::fit::LevelData;
use super::measured::PhaseConvention;
use super::model::{Drive, Model};
use crate::core::error::{Error, Result};
use crate::core::output::{write_atomic, write_string_atomic};
use crate::core::plot::{stacked_line_plots, LinePlot, Scale, Series};
use realfft::num_complex::Complex64;
use serde::Serialize;
use std::f64::consts::TAU;
use std::path::{Path, PathBuf};

/// Role of level `i` in an identification: "fit" (one of `fit_levels`) or "predicted".
pub fn level_role(i: usize, fit_levels: &[usize]) -> &'static str {
    if fit_levels.contains(&i) {
        "fit"
    } else {
        "predicted"
    }
}

/// Roles of levels `0..n` ([`level_role`]).
pub fn level_roles(n: usize, fit_levels: &[usize]) -> Vec<&'static str> {
    (0..n).map(|i| level_role(i, fit_levels)).collect()
}

/// Errors of one region of a sweep.
#[derive(Debug, Clone, Serialize)]
pub struct RegionErrors {
    /// "below resonance", "at resonance" (the half-power band) or "above resonance".
    pub region: &'static str,
    /// Measured rows in the region.
    pub rows: usize,
    /// RMS of the complex residual `(Y_model − Y_meas)/peak` over the region's rows (fraction of
    /// the level's peak response).
    pub rms_complex: f64,
    /// Mean of `|Y_model|/|Y_meas| − 1`.
    pub mean_amplitude_error: f64,
    /// Mean of `arg(Y_model/Y_meas)` (rad).
    pub mean_phase_error_rad: f64,
}

/// Why a phase-resonance frequency (`f_90`) is not available: the phase of the displacement
/// does not pass quadrature with the force inside the band (e.g. a constant-amplitude file).
pub const NO_PHASE_RESONANCE: &str = "the phase does not pass quadrature inside the band";

/// A phase-resonance frequency (or its error) in JSON: the number, or, where it is not
/// available (NaN), `{"not_available": NO_PHASE_RESONANCE}` — never `null` or `NaN`.
pub fn phase_resonance_or_reason<S: serde::Serializer>(
    value: &f64,
    s: S,
) -> std::result::Result<S::Ok, S::Error> {
    let v: std::result::Result<f64, String> = if value.is_finite() {
        Ok(*value)
    } else {
        Err(NO_PHASE_RESONANCE.to_string())
    };
    available_or_reason(&v, s)
}

/// A number of a text table, or `n/a` where it is not available (not finite).
pub fn number_or_na(value: f64, format: impl Fn(f64) -> String) -> String {
    if value.is_finite() {
        format(value)
    } else {
        "n/a".to_string()
    }
}

/// Why a level has no resonance-frequency error ([`LevelErrors::resonance_error`]).
pub const NO_RESONANCE_IN_BAND: &str = "no resonance inside the band";

/// Errors of a model against one level.
#[derive(Debug, Clone, Serialize)]
pub struct LevelErrors {
    /// File name of the level's sweep.
    pub file: String,
    /// "fit" (used in the fit) or "predicted".
    pub role: String,
    /// Mean measured drive force amplitude of the level (N).
    pub mean_force_n: f64,
    /// Frequency of the measured amplitude peak (Hz), interpolated between rows.
    pub resonance_measured_hz: f64,
    /// Frequency of the modelled amplitude peak (Hz); NaN when every row failed.
    pub resonance_model_hz: f64,
    /// Model minus measured resonance frequency (Hz); NaN where not available (see
    /// [`Self::resonance_error`]).
    #[serde(skip)]
    pub resonance_error_hz: f64,
    /// The resonance-frequency error, or why there is none: the measured amplitude peaks on the
    /// first or last row, so the band holds no resonance and its edge row is no resonance
    /// frequency (reported as an error of +0.000 Hz before). In JSON as `resonance_error_hz`.
    #[serde(rename = "resonance_error_hz", serialize_with = "available_or_reason")]
    pub resonance_error: std::result::Result<f64, String>,
    /// Phase resonance (quadrature) of the measured and modelled responses (Hz; NaN where the
    /// phase does not pass quadrature in the band, `n/a` in text and
    /// `{"not_available": …}` in JSON) and their difference.
    #[serde(serialize_with = "phase_resonance_or_reason")]
    pub phase_resonance_measured_hz: f64,
    /// Phase resonance of the modelled response (Hz; NaN where not available).
    #[serde(serialize_with = "phase_resonance_or_reason")]
    pub phase_resonance_model_hz: f64,
    /// Model minus measured phase resonance (Hz; NaN where either is not available).
    #[serde(serialize_with = "phase_resonance_or_reason")]
    pub phase_resonance_error_hz: f64,
    /// Peak measured response per unit force, `max |Y_meas|` interpolated at the resonance (unit of
    /// the level's quantity per newton).
    pub peak_measured: f64,
    /// Peak modelled response per unit force (same unit).
    pub peak_model: f64,
    /// Relative peak error `peak_model/peak_measured − 1` (fraction).
    pub peak_error: f64,
    /// RMS of the complex residual over all rows (fraction of the level's peak response).
    pub rms_complex: f64,
    /// The same residual by region: below, at and above resonance.
    pub regions: Vec<RegionErrors>,
    /// Rows where the harmonic balance failed.
    pub failed_rows: usize,
}

impl LevelErrors {
    /// Compare a model response `y` (per unit force, the level's quantity) with the level.
    pub fn new(level: &LevelData, y: &[Complex64], role: &str, failed_rows: usize) -> Self {
        let f: Vec<f64> = level.drives.iter().map(|d| d.omega / TAU).collect();
        let am: Vec<f64> = level.measured.iter().map(|v| v.norm()).collect();
        let ay: Vec<f64> = y.iter().map(|v| v.norm()).collect();
        let (fm, pm) = resonance(&f, &am);
        let (fy, py) = if ay.iter().any(|v| v.is_finite()) {
            resonance(&f, &ay)
        } else {
            (f64::NAN, f64::NAN)
        };
        let displacement = |v: &[Complex64]| -> Vec<Complex64> {
            v.iter()
                .zip(&level.drives)
                .map(|(v, d)| v / level.quantity.from_displacement(d.omega))
                .collect()
        };
        let f90m = phase_resonance(&f, &displacement(&level.measured), fm).unwrap_or(f64::NAN);
        let f90y = phase_resonance(&f, &displacement(y), fm).unwrap_or(f64::NAN);
        let r = level.residuals(y);
        let rms = |idx: &[usize]| {
            (idx.iter().map(|&i| r[i].norm_sqr()).sum::<f64>() / idx.len().max(1) as f64).sqrt()
        };
        let (lo, hi) = half_power_rows(&am);
        let (flo, fhi) = (f[lo].min(f[hi]), f[lo].max(f[hi]));
        let mut regions = Vec::new();
        for (name, keep) in [
            (
                "below resonance",
                Box::new(|x: f64| x < flo) as Box<dyn Fn(f64) -> bool>,
            ),
            ("at resonance", Box::new(|x: f64| x >= flo && x <= fhi)),
            ("above resonance", Box::new(|x: f64| x > fhi)),
        ] {
            let idx: Vec<usize> = (0..f.len()).filter(|&i| keep(f[i])).collect();
            let valid: Vec<usize> = idx.iter().copied().filter(|&i| ay[i].is_finite()).collect();
            regions.push(RegionErrors {
                region: name,
                rows: idx.len(),
                rms_complex: rms(&idx),
                mean_amplitude_error: valid.iter().map(|&i| ay[i] / am[i] - 1.0).sum::<f64>()
                    / valid.len().max(1) as f64,
                mean_phase_error_rad: valid
                    .iter()
                    .map(|&i| (y[i] / level.measured[i]).arg())
                    .sum::<f64>()
                    / valid.len().max(1) as f64,
            });
        }
        let all: Vec<usize> = (0..f.len()).collect();
        let peak = (0..am.len())
            .max_by(|&a, &b| am[a].total_cmp(&am[b]))
            .expect("rows");
        let resonance_error = if peak == 0 || peak + 1 == am.len() {
            Err(format!(
                "{NO_RESONANCE_IN_BAND}: the measured amplitude peaks on the {} row",
                if peak == 0 { "first" } else { "last" }
            ))
        } else {
            Ok(fy - fm)
        };
        Self {
            file: level.name.clone(),
            role: role.to_string(),
            mean_force_n: level.mean_force_n,
            resonance_measured_hz: fm,
            resonance_model_hz: fy,
            resonance_error_hz: resonance_error.clone().unwrap_or(f64::NAN),
            resonance_error,
            phase_resonance_measured_hz: f90m,
            phase_resonance_model_hz: f90y,
            phase_resonance_error_hz: f90y - f90m,
            peak_measured: pm,
            peak_model: py,
            peak_error: py / pm - 1.0,
            rms_complex: rms(&all),
            regions,
            failed_rows,
        }
    }
}

/// Residual per region (below, at and above resonance) of every level: RMS complex error /
/// mean amplitude error / mean phase error; with a second model, `first → second` for each.
pub fn regions_text(title: &str, rows: &[(&LevelErrors, Option<&LevelErrors>)]) -> String {
    let mut s = format!("\n{title} (RMS complex / mean amplitude error / mean phase error):\n");
    for (a, b) in rows {
        s += &format!("  {}:", a.file);
        for (k, r) in a.regions.iter().enumerate() {
            s += &match b.and_then(|b| b.regions.get(k)) {
                _ if r.rows == 0 => format!("  {} (no rows);", r.region),
                None => format!(
                    "  {} ({} rows) {:.3} / {:+.1}% / {:+.3} rad;",
                    r.region,
                    r.rows,
                    r.rms_complex,
                    100.0 * r.mean_amplitude_error,
                    r.mean_phase_error_rad
                ),
                Some(q) => format!(
                    "  {} ({} rows) {:.3} → {:.3} / {:+.1} → {:+.1}% / {:+.3} → {:+.3} rad;",
                    r.region,
                    r.rows,
                    r.rms_complex,
                    q.rms_complex,
                    100.0 * r.mean_amplitude_error,
                    100.0 * q.mean_amplitude_error,
                    r.mean_phase_error_rad,
                    q.mean_phase_error_rad
                ),
            };
        }
        s += "\n";
    }
    s
}

/// A model's response curve on a fine frequency grid for plots: the measured force
/// interpolated linearly between rows (sweep order kept).
pub fn fine_curve(model: &Model, level: &LevelData, per_interval: usize) -> Vec<(f64, Complex64)> {
    fine_curve_with(level, per_interval, &|drives: &[Drive]| {
        model
            .receptance_tolerant(drives, level.mean_force_n, true)
            .map(|(x, _)| x)
    })
}

/// [`fine_curve`] of any model given by its drive-point receptance along a list of drives
/// (m/N, sweep order; failed rows NaN).
pub fn fine_curve_with(
    level: &LevelData,
    per_interval: usize,
    receptance: &dyn Fn(&[Drive]) -> Result<Vec<Complex64>>,
) -> Vec<(f64, Complex64)> {
    let mut drives = Vec::new();
    for w in level.drives.windows(2) {
        for k in 0..per_interval {
            let t = k as f64 / per_interval as f64;
            drives.push(Drive {
                omega: w[0].omega + t * (w[1].omega - w[0].omega),
                force_n: w[0].force_n + t * (w[1].force_n - w[0].force_n),
            });
        }
    }
    drives.push(*level.drives.last().expect("rows"));
    let x = receptance(&drives)
        .unwrap_or_else(|_| vec![Complex64::new(f64::NAN, f64::NAN); drives.len()]);
    drives
        .iter()
        .zip(x)
        .map(|(d, xi)| {
            (
                d.omega / TAU,
                xi * level.quantity.from_displacement(d.omega),
            )
        })
        .collect()
}

/// Amplitude and phase panels of one level: measured rows and model curves.
pub fn plot_level(
    path: &Path,
    level: &LevelData,
    conv: &PhaseConvention,
    curves: &[(String, Vec<(f64, Complex64)>)],
    title: &str,
) -> Result<()> {
    let meas_f: Vec<f64> = level.drives.iter().map(|d| d.omega / TAU).collect();
    let q = level.quantity;
    let amp_label = format!("{} ({}/N)", q.frf_name(), q.unit());
    let mut amp = vec![Series::markers(
        "measured",
        meas_f
            .iter()
            .zip(&level.measured)
            .map(|(&f, y)| (f, y.norm()))
            .collect(),
    )];
    let mut phase = vec![Series::markers(
        "measured",
        meas_f
            .iter()
            .zip(&level.measured)
            .map(|(&f, y)| (f, conv.to_file_phase(*y)))
            .collect(),
    )];
    for (label, c) in curves {
        amp.push(Series::line(
            label.clone(),
            c.iter().map(|(f, y)| (*f, y.norm())).collect(),
        ));
        phase.push(Series::line(
            label.clone(),
            c.iter()
                .map(|(f, y)| (*f, conv.to_file_phase(*y)))
                .collect(),
        ));
    }
    let t2 = format!("{title}: phase (the file's convention)");
    stacked_line_plots(
        path,
        &[
            (
                LinePlot {
                    title,
                    x_label: "frequency (Hz)",
                    y_label: &amp_label,
                    x_scale: Scale::Linear,
                    y_scale: Scale::Linear,
                },
                amp,
            ),
            (
                LinePlot {
                    title: &t2,
                    x_label: "frequency (Hz)",
                    y_label: "phase (rad)",
                    x_scale: Scale::Linear,
                    y_scale: Scale::Linear,
                },
                phase,
            ),
        ],
    )
}

/// Backbone figure: natural frequency and damping ratio versus drive-point amplitude, from the
/// data (per-level equivalent modes and pointwise inversion) and from models.
pub fn plot_backbone(
    path: &Path,
    data: &[LevelBackbone],
    models: &[(String, Vec<BackbonePoint>)],
) -> Result<()> {
    let mut fr = Vec::new();
    let mut zr = Vec::new();
    let pts: Vec<&BackbonePoint> = data.iter().flat_map(|b| &b.points).collect();
    fr.push(Series::markers(
        "data, pointwise (half-power rows)",
        pts.iter()
            .map(|p| (p.amplitude_m * 1e6, p.frequency_hz))
            .collect(),
    ));
    zr.push(Series::markers(
        "data, pointwise (half-power rows)",
        pts.iter()
            .map(|p| (p.amplitude_m * 1e6, p.damping_ratio * 100.0))
            .collect(),
    ));
    fr.push(Series::markers(
        "data, equivalent linear mode per level",
        data.iter()
            .map(|b| (b.peak_amplitude_m * 1e6, b.linear.frequency_hz))
            .collect(),
    ));
    zr.push(Series::markers(
        "data, equivalent linear mode per level",
        data.iter()
            .map(|b| (b.peak_amplitude_m * 1e6, b.linear.damping_ratio * 100.0))
            .collect(),
    ));
    for (label, m) in models {
        fr.push(Series::line(
            label.clone(),
            m.iter()
                .map(|p| (p.amplitude_m * 1e6, p.frequency_hz))
                .collect(),
        ));
        zr.push(Series::line(
            label.clone(),
            m.iter()
                .map(|p| (p.amplitude_m * 1e6, p.damping_ratio * 100.0))
                .collect(),
        ));
    }
    // The same, restricted to the amplitudes the pointwise estimates span: a model's backbone
    // far outside them (a slipping joint's drop) otherwise sets the scale and flattens the data.
    let (lo, hi) = pts.iter().fold((f64::INFINITY, 0.0f64), |(l, h), p| {
        (l.min(p.amplitude_m * 1e6), h.max(p.amplitude_m * 1e6))
    });
    let within = |v: &[Series]| -> Vec<Series> {
        v.iter()
            .enumerate()
            .map(|(k, s)| Series {
                points: s
                    .points
                    .iter()
                    .copied()
                    .filter(|p| p.0 >= lo && p.0 <= hi)
                    .collect(),
                colour: s.colour.or(Some(k)),
                ..s.clone()
            })
            .collect()
    };
    let (fz, zz) = (within(&fr), within(&zr));
    let panel = |title, y_label| LinePlot {
        title,
        x_label: "drive-point displacement amplitude (µm)",
        y_label,
        x_scale: Scale::Log,
        y_scale: Scale::Linear,
    };
    let mut panels = vec![
        (
            panel(
                "Backbone: natural frequency versus amplitude",
                "natural frequency (Hz)",
            ),
            fr,
        ),
        (
            panel(
                "Backbone: damping ratio versus amplitude",
                "damping ratio (%)",
            ),
            zr,
        ),
    ];
    if lo < hi {
        panels.push((
            panel(
                "Natural frequency over the amplitudes of the pointwise estimates",
                "natural frequency (Hz)",
            ),
            fz,
        ));
        panels.push((
            panel(
                "Damping ratio over the amplitudes of the pointwise estimates",
                "damping ratio (%)",
            ),
            zz,
        ));
    }
    stacked_line_plots(path, &panels)
}

/// Rows of the per-row CSV: one per measured row and model.
#[derive(Debug, Clone)]
pub struct CurveRow {
    /// File name of the level's sweep.
    pub file: String,
    /// "fit" or "predicted" ([`level_role`]).
    pub role: String,
    /// 1-based line of the row in its file.
    pub line: usize,
    /// Excitation frequency (Hz).
    pub frequency_hz: f64,
    /// Measured drive force amplitude (N).
    pub force_n: f64,
    /// Measured response per unit force (the level's quantity per newton, the crate's phase
    /// convention).
    pub measured: Complex64,
    /// Named model responses at this row.
    pub models: Vec<Complex64>,
}

/// Write the per-row CSV (`frequency_Hz`, measured force, measured and model amplitude and phase
/// in the file's convention, per model).
pub fn write_rows_csv(
    path: &Path,
    unit_note: &str,
    model_names: &[&str],
    rows: &[CurveRow],
    conv_of: &dyn Fn(&str) -> PhaseConvention,
) -> Result<()> {
    write_atomic(path, |w| {
        let io = |e| Error::io(path, e);
        writeln!(w, "# {unit_note}").map_err(io)?;
        write!(
            w,
            "file,role,line,frequency_Hz,force_amplitude_N,measured_per_force,measured_phase_rad"
        )
        .map_err(io)?;
        for m in model_names {
            write!(w, ",{m}_per_force,{m}_phase_rad").map_err(io)?;
        }
        writeln!(w).map_err(io)?;
        for r in rows {
            let c = conv_of(&r.file);
            write!(
                w,
                "{},{},{},{},{:.9e},{:.9e},{:.9e}",
                r.file,
                r.role,
                r.line,
                r.frequency_hz,
                r.force_n,
                r.measured.norm(),
                c.to_file_phase(r.measured)
            )
            .map_err(io)?;
            for y in &r.models {
                write!(w, ",{:.9e},{:.9e}", y.norm(), c.to_file_phase(*y)).map_err(io)?;
            }
            writeln!(w).map_err(io)?;
        }
        Ok(())
    })
}

/// Serialise to pretty JSON and write atomically.
pub fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<()> {
    let text = serde_json::to_string_pretty(value)
        .map_err(|e| Error::Data(format!("{}: cannot serialise: {e}", path.display())))?;
    write_string_atomic(path, &(text + "\n"))
}

/// Serialises a result that may be unavailable with one shape in every JSON file of `identify`
/// and `predict`: the value itself when available, `{"not_available": reason}` when not (serde's
/// default would nest the value under `"Ok"`). For `#[serde(serialize_with = …)]`.
pub fn available_or_reason<T: Serialize, S: serde::Serializer>(
    value: &std::result::Result<T, String>,
    s: S,
) -> std::result::Result<S::Ok, S::Error> {
    use serde::ser::SerializeMap;
    match value {
        Ok(v) => v.serialize(s),
        Err(reason) => {
            let mut m = s.serialize_map(Some(1))?;
            m.serialize_entry("not_available", reason)?;
            m.end()
        }
    }
}

/// [`available_or_reason`] for a result that may also be absent (`null`).
pub fn optional_available_or_reason<T: Serialize, S: serde::Serializer>(
    value: &Option<std::result::Result<T, String>>,
    s: S,
) -> std::result::Result<S::Ok, S::Error> {
    match value {
        None => s.serialize_none(),
        Some(v) => available_or_reason(v, s),
    }
}

/// Input file description for JSON sidecars.
#[derive(Debug, Clone, Serialize)]
pub struct InputFile {
    /// Path as given on the command line.
    pub path: PathBuf,
    /// SHA-256 of the file's bytes (hex).
    pub sha256: String,
    /// Response quantity the file measures.
    pub quantity: super::measured::Quantity,
    /// Data rows read.
    pub rows: usize,
    /// Mean drive force amplitude of the rows (N).
    pub mean_force_n: f64,
}

impl InputFile {
    /// The record of a measured sweep.
    pub fn of(s: &super::measured::Sweep) -> Self {
        Self {
            path: s.path.clone(),
            sha256: s.sha256.clone(),
            quantity: s.quantity,
            rows: s.rows.len(),
            mean_force_n: s.mean_force_n(),
        }
    }
}

/// Text table of level errors (before/after).
pub fn errors_table(title: &str, rows: &[(&LevelErrors, Option<&LevelErrors>)]) -> String {
    // Columns of two models read `before → after`; of one model, a single value each.
    let compare = rows.iter().any(|(_, a)| a.is_some());
    let head = |h: &str| {
        if compare {
            format!("{h} bef→aft")
        } else {
            h.to_string()
        }
    };
    let mut s = format!("{title}\n");
    s += &format!(
        "{:<34} {:>9} {:>8} {:>10} {:>21} {:>9} {:>21} {:>19} {:>17}\n",
        "level",
        "role",
        "F (N)",
        "f_res (Hz)",
        head("Δf_res (Hz)"),
        "f_90 (Hz)",
        head("Δf_90 (Hz)"),
        head("peak err"),
        head("RMS cplx")
    );
    let mut missing_f90 = false;
    for (b, a) in rows {
        let resonance_pair = match (&b.resonance_error, a.map(|a| &a.resonance_error)) {
            (Err(_), _) | (_, Some(Err(_))) => "n/a (see below)".to_string(),
            (Ok(x), None) => format!("{x:+.3}"),
            (Ok(x), Some(Ok(y))) => format!("{x:+.3} → {y:+.3}"),
        };
        let one = |x: f64, scale: f64, prec: usize, unit: &str| {
            number_or_na(x, |x| format!("{:+.p$}{unit}", x * scale, p = prec))
        };
        let pair = |x: f64, y: Option<f64>, scale: f64, prec: usize, unit: &str| match y {
            Some(y) => format!(
                "{} → {}",
                one(x, scale, prec, unit),
                one(y, scale, prec, unit)
            ),
            None => one(x, scale, prec, unit),
        };
        missing_f90 |= !b.phase_resonance_error_hz.is_finite()
            || a.is_some_and(|a| !a.phase_resonance_error_hz.is_finite());
        s += &format!(
            "{:<34} {:>9} {:>8.3} {:>10.3} {:>21} {:>9} {:>21} {:>19} {:>17}\n",
            b.file,
            b.role,
            b.mean_force_n,
            b.resonance_measured_hz,
            resonance_pair,
            number_or_na(b.phase_resonance_measured_hz, |v| format!("{v:.3}")),
            pair(
                b.phase_resonance_error_hz,
                a.map(|a| a.phase_resonance_error_hz),
                1.0,
                3,
                ""
            ),
            pair(b.peak_error, a.map(|a| a.peak_error), 100.0, 1, "%"),
            match a {
                Some(a) => format!(
                    "{} → {}",
                    number_or_na(b.rms_complex, |v| format!("{v:.3}")),
                    number_or_na(a.rms_complex, |v| format!("{v:.3}"))
                ),
                None => number_or_na(b.rms_complex, |v| format!("{v:.3}")),
            }
        );
    }
    for (b, _) in rows {
        if let Err(why) = &b.resonance_error {
            s += &format!("  {}: Δf_res n/a, {why}\n", b.file);
        }
    }
    if missing_f90 {
        s += &format!("  f_90 n/a: {NO_PHASE_RESONANCE}\n");
    }
    s
}

#[cfg(test)]
mod tests {
    use super::available_or_reason;
    use super::*;
    use crate::identify::measured::{synthetic_sweep_csv, Quantity, Sweep};

    /// A sweep whose amplitude peaks on its last row holds no resonance: no resonance-frequency
    /// error in text or JSON (before: the edge row was taken for the resonance, error +0.000).
    #[test]
    fn no_resonance_frequency_error_without_a_resonance_in_the_band() {
        let d = tempfile::tempdir().unwrap();
        let a = Quantity::Acceleration;
        for (f0, inside) in [(70.0, false), (76.0, true)] {
            let p = d.path().join("s.csv");
            std::fs::write(
                &p,
                synthetic_sweep_csv(a, a, PhaseConvention::MODEL, f0, false),
            )
            .unwrap();
            let level = LevelData::new(&Sweep::read_csv(&p).unwrap(), &PhaseConvention::MODEL);
            let e = LevelErrors::new(&level, &level.measured, "predicted", 0);
            let json = serde_json::to_value(&e).unwrap();
            let text = errors_table("t", &[(&e, Some(&e))]);
            if inside {
                assert_eq!(e.resonance_error, Ok(0.0));
                assert_eq!(json["resonance_error_hz"], 0.0);
                assert!(
                    text.contains("+0.000 → +0.000") && !text.contains("n/a"),
                    "{text}"
                );
            } else {
                assert!(e.resonance_error_hz.is_nan());
                let why = json["resonance_error_hz"]["not_available"]
                    .as_str()
                    .unwrap();
                assert!(why.contains("no resonance inside the band") && why.contains("last row"));
                assert!(
                    text.contains("n/a (see below)")
                        && text.contains("s.csv: Δf_res n/a, no resonance inside the band"),
                    "{text}"
                );
            }
        }
    }

    #[test]
    fn unavailable_results_have_one_json_shape() {
        let ok: std::result::Result<Vec<f64>, String> = Ok(vec![1.0, 2.0]);
        let err: std::result::Result<Vec<f64>, String> = Err("no resonance in band".into());
        let json = |r| available_or_reason(r, serde_json::value::Serializer).unwrap();
        assert_eq!(json(&ok), serde_json::json!([1.0, 2.0]));
        assert_eq!(
            json(&err),
            serde_json::json!({"not_available": "no resonance in band"})
        );
    }
}
