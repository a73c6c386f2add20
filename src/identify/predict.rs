//! Scoring an identified model on any measured file: a level that was not used, or another test
//! type on the same structure.
//!
//! * **Force control**: the measured force of each row is applied and the response computed
//!   (as in the fit).
//! * **Response control**: the measured response amplitude of each row is held and the force
//!   that produces it is solved for ([`crate::dynamics::hbm::HbmSystem::solve_response_controlled`]);
//!   the model's response per unit force is then `measured response / model force`, with the
//!   model's phase.
//!
//! Both report the errors of [`super::report`]. The phase convention is detected from each file
//! on its own and must be the same for every file and the one saved with the model (a file in
//! another convention is refused, naming each file's, rather than misread). A file whose
//! amplitude peaks on its first or last row (no resonance inside its band) cannot show its
//! convention and is read with the saved one, and the report says so; a file that peaks inside
//! its band but whose phase does not turn as a resonance's is refused with the likely cause.

use super::backbone;
use super::fit::LevelData;
use super::fit::Parametrised;
use super::measured::{check_agree, most_common, FileConvention, PhaseConvention, Sweep};
use super::model::{Drive, Model};
use super::pipeline::SavedModel;
use super::reduced::{ReducedModel, ReducedSpec, SavedReducedModel};
use super::report::{
    errors_table, fine_curve, fine_curve_with, plot_level, write_json, write_rows_csv, CurveRow,
    InputFile, LevelErrors,
};
use super::stationarity::{self, SideComparison};
use super::uncertainty::{bands_table, prediction_bands, Ensemble, PredictionBand};
use crate::core::error::{Error, Result};
use crate::core::output::write_string_atomic;
use realfft::num_complex::Complex64;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// How the measured test was controlled.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Control {
    /// The force amplitude of each row is the input.
    Force,
    /// The response amplitude of each row is held; the force is the outcome.
    Response,
}

impl Control {
    fn name(self) -> &'static str {
        match self {
            Control::Force => "force",
            Control::Response => "response",
        }
    }
}

/// The test control a measured file's header comments state — a comment line before the
/// header row saying "force control" or "response control" (any case, also "force-controlled",
/// "response-controlled") — with its 1-based line; `None` where they say neither (or both).
pub fn stated_control(path: &Path) -> Result<Option<(Control, usize)>> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    for (k, line) in text.lines().enumerate() {
        let Some(comment) = line.trim_start().strip_prefix('#') else {
            break;
        };
        let c = comment.to_lowercase().replace('-', " ");
        let says = |mode: &str| c.contains(&format!("{mode} control"));
        match (says("force"), says("response")) {
            (true, false) => return Ok(Some((Control::Force, k + 1))),
            (false, true) => return Ok(Some((Control::Response, k + 1))),
            _ => {}
        }
    }
    Ok(None)
}

/// The control under which the files are predicted, and where it comes from: the files'
/// headers where they state it ([`stated_control`]), the `flag` (`--control`) otherwise (force
/// control by default). Files that state different controls, or a flag that contradicts a
/// file's statement, are refused naming the file and line: a response-controlled test predicted
/// under force control gives other numbers without a word.
pub fn choose_control(sweeps: &[Sweep], flag: Option<Control>) -> Result<(Control, String)> {
    let mut stated: Option<(Control, &Sweep, usize)> = None;
    for s in sweeps {
        let Some((c, line)) = stated_control(&s.path)? else {
            continue;
        };
        if let Some(f) = flag.filter(|f| *f != c) {
            return Err(Error::param(
                "--control",
                format!(
                    "{} contradicts {}:{line}, whose header states {} control",
                    f.name(),
                    s.path.display(),
                    c.name()
                ),
            ));
        }
        match stated {
            Some((c0, s0, l0)) if c0 != c => {
                return Err(Error::Data(format!(
                    "{}:{l0} states {} control and {}:{line} {} control: predict files of one \
                     control at a time",
                    s0.path.display(),
                    c0.name(),
                    s.path.display(),
                    c.name()
                )))
            }
            None => stated = Some((c, s, line)),
            _ => {}
        }
    }
    Ok(match (stated, flag) {
        (Some((c, s, line)), _) => (
            c,
            format!("stated in the header of {}:{line}", s.path.display()),
        ),
        (None, Some(f)) => (f, "--control".to_string()),
        (None, None) => (
            Control::Force,
            "default (no file's header states its control; --control sets it)".to_string(),
        ),
    })
}

/// The model that predicts: the identified single nonlinear mode, or an updated reduced model.
#[derive(Debug, Clone)]
pub enum Predictor {
    /// The single nonlinear mode and the ensemble saved with it, if any.
    Mode(Model, Option<Ensemble>),
    /// An updated reduced model and the ensemble saved with it, if any.
    Reduced(ReducedModel, Option<Ensemble>),
}

impl Predictor {
    /// Response per unit force at a level's rows (its quantity; failed rows NaN) and the count
    /// of failed rows.
    fn frf(&self, level: &LevelData) -> Result<(Vec<Complex64>, usize)> {
        match self {
            Predictor::Mode(m, _) => level.model_frf(m),
            Predictor::Reduced(m, _) => ReducedSpec::frf(m, level),
        }
    }

    /// Response-controlled: forces (N) and receptances (m/N) holding displacement amplitudes.
    fn response_controlled(
        &self,
        omegas: &[f64],
        targets: &[f64],
        mean_force_n: f64,
    ) -> Result<(Vec<f64>, Vec<Complex64>)> {
        match self {
            Predictor::Mode(m, _) => m.response_controlled(omegas, targets, mean_force_n),
            Predictor::Reduced(m, _) => m.response_controlled(omegas, targets, mean_force_n),
        }
    }

    /// Curve for the plots on a fine frequency grid.
    fn fine_curve(&self, level: &LevelData) -> Vec<(f64, Complex64)> {
        match self {
            Predictor::Mode(m, _) => fine_curve(m, level, 4),
            Predictor::Reduced(m, _) => fine_curve_with(level, 4, &|d: &[Drive]| {
                m.receptance_tolerant(d, level.mean_force_n, true)
                    .map(|(x, _)| x)
            }),
        }
    }
}

/// Prediction of one file.
#[derive(Debug, Clone, Serialize)]
pub struct FilePrediction {
    /// The measured file.
    pub input: InputFile,
    /// The model's errors against it.
    pub errors: LevelErrors,
    /// Response control: RMS of `F_model/F_meas − 1` over the rows.
    pub force_rms_error: Option<f64>,
    /// The model's response per unit force at the file's rows (the file's quantity per newton).
    #[serde(skip)]
    pub model_frf: Vec<Complex64>,
    /// Response control: the model's force per row (N).
    pub model_force_n: Option<Vec<f64>>,
    /// Largest drive-point displacement amplitude of the file's rows (m).
    pub peak_amplitude_m: f64,
    /// Why the file lies outside the amplitudes the model was identified on (its peak more than
    /// [`EXTRAPOLATION_FACTOR`] beyond the fit levels' peaks), or `None`.
    pub extrapolation: Option<String>,
    /// Why the measured file is not one lightly damped mode (its equivalent linear fit,
    /// [`backbone::fit_linear_mode`], has no positive stiffness, damping and modal mass), or
    /// `None`: a single-mode model's errors on such a file compare it with something it does not
    /// describe, and are flagged so beside them.
    pub not_one_mode: Option<String>,
}

/// How far beyond the fit levels' peak amplitudes (above the largest, below the smallest) a
/// file's peak may lie before its prediction is flagged as an extrapolation of the joint law.
pub const EXTRAPOLATION_FACTOR: f64 = 2.0;

/// The flag of a file whose peak displacement amplitude `peak` lies more than
/// [`EXTRAPOLATION_FACTOR`] outside the identified peaks `[lo, hi]`.
pub fn extrapolation_note(peak: f64, (lo, hi): (f64, f64)) -> Option<String> {
    let beyond = if peak > EXTRAPOLATION_FACTOR * hi {
        Some(format!("{:.1}× the largest", peak / hi))
    } else if peak < lo / EXTRAPOLATION_FACTOR {
        Some(format!("1/{:.1} of the smallest", lo / peak))
    } else {
        None
    };
    beyond.map(|b| {
        format!(
            "its peak amplitude {peak:.3e} m is {b} the model was identified on ({lo:.3e}–{hi:.3e} m): the joint law is extrapolated"
        )
    })
}

/// A prediction.
#[derive(Debug, Clone, Serialize)]
pub struct Prediction {
    /// The model file (`model.json`) that predicted.
    pub model_file: PathBuf,
    /// How the measured tests were controlled (force or response amplitude held).
    pub control: Control,
    /// Where the control comes from ([`choose_control`]).
    pub control_source: String,
    /// Phase convention of the measured files.
    pub convention: PhaseConvention,
    /// Where the convention comes from (detected from the files, or the model file's).
    pub convention_source: String,
    /// One prediction per measured file, in the order given.
    pub files: Vec<FilePrediction>,
    /// The measured sweeps as read, kept for the files.
    #[serde(skip)]
    pub sweeps: Vec<Sweep>,
    /// The model that predicted.
    #[serde(skip)]
    pub model: Predictor,
    /// 95 % bands of each file's peak and resonances over the ensemble saved with the model
    /// (force control only; the reason where there are none).
    #[serde(serialize_with = "super::report::available_or_reason")]
    pub bands: std::result::Result<Vec<PredictionBand>, String>,
    /// Force control: each file's two sides at equal amplitude ([`stationarity::compare_sides`];
    /// `None` for a file with too few points to compare), or why they could not be compared
    /// (response control holds the amplitude, so a test has no two sides; a file that is not one
    /// lightly damped mode).
    #[serde(serialize_with = "super::report::available_or_reason")]
    pub stationarity: std::result::Result<Vec<Option<SideComparison>>, String>,
}

/// `(role, path)` of a saved model file and, for a reduced model, of the response-model file
/// it updates and every file that one names: the inputs of `predict` besides the measured
/// files. A file that cannot be read as a model gives the model file alone (its reader reports
/// the error).
pub fn model_inputs(model_file: &Path) -> Result<Vec<(String, std::path::PathBuf)>> {
    let mut files = vec![("--model".to_string(), model_file.to_path_buf())];
    let reduced = std::fs::read_to_string(model_file)
        .ok()
        .and_then(|t| serde_json::from_str::<SavedReducedModel>(&t).ok());
    if let Some(r) = reduced {
        if let Ok(refs) = crate::dynamics::model_file::referenced_files(&r.model_file) {
            files.extend(
                refs.into_iter()
                    .map(|(role, p)| (format!("{role} of the --model's structure"), p)),
            );
        }
    }
    Ok(files)
}

/// Predict measured files with a saved model.
/// `control` is the test control and where it comes from ([`choose_control`]).
pub fn predict(
    model_file: &Path,
    sweeps: Vec<Sweep>,
    (control, control_source): (Control, String),
) -> Result<Prediction> {
    let (model, saved_convention) = if SavedReducedModel::is_reduced(model_file)? {
        let (m, c, e) = SavedReducedModel::read(model_file)?;
        (Predictor::Reduced(m, e), c)
    } else {
        let saved = SavedModel::read(model_file)?;
        (
            Predictor::Mode(saved.model, saved.ensemble),
            saved.phase_convention,
        )
    };
    if sweeps.is_empty() {
        return Err(Error::param("files", "at least one measured file"));
    }
    let (convention, source) = files_convention(&sweeps, saved_convention)?;
    // A single-mode model describes the response near its natural frequency only: a file more
    // than a factor 2 away from it is another mode, or in another frequency unit.
    if let Predictor::Mode(m, _) = &model {
        let f_s = m.physical().omega_s / std::f64::consts::TAU;
        for s in &sweeps {
            let (lo, hi) = super::pipeline::frequency_span(s);
            if f_s < 0.5 * lo || f_s > 2.0 * hi {
                return Err(Error::Data(format!(
                    "{}: its frequencies ({lo:.6}–{hi:.6} Hz) lie more than a factor 2 from the \
                     model's natural frequency ({f_s:.6} Hz): not the mode the model was \
                     identified on, or frequencies in another unit (e.g. kHz in a \
                     `frequency_Hz` column)",
                    s.path.display()
                )));
            }
        }
    }
    let mut files = Vec::new();
    let mut levels = Vec::new();
    for s in &sweeps {
        let level = LevelData::new(s, &convention);
        levels.push(level.clone());
        let named = |e: Error| match e {
            Error::NonConvergence { .. } | Error::Data(_) => {
                Error::Data(format!("{}: {e}", s.path.display()))
            }
            e => e,
        };
        // Drive-point displacement amplitude of every row (m): the targets under response
        // control, and the file's peak against the identified amplitudes.
        let om: Vec<f64> = level.drives.iter().map(|d| d.omega).collect();
        let amplitudes_m: Vec<f64> = s
            .rows
            .iter()
            .zip(&om)
            .map(|(r, &w)| r.response / s.quantity.from_displacement(w).norm())
            .collect();
        let (y, failed, forces) = match control {
            Control::Force => {
                let (y, failed) = model.frf(&level).map_err(named)?;
                (y, failed, None)
            }
            Control::Response => {
                let (f, x) = model
                    .response_controlled(&om, &amplitudes_m, level.mean_force_n)
                    .map_err(named)?;
                let y: Vec<Complex64> = x
                    .iter()
                    .zip(&om)
                    .map(|(xi, &w)| xi * s.quantity.from_displacement(w))
                    .collect();
                (y, 0, Some(f))
            }
        };
        let force_rms_error = forces.as_ref().map(|f| {
            (f.iter()
                .zip(&s.rows)
                .map(|(m, r)| (m / r.force_n - 1.0).powi(2))
                .sum::<f64>()
                / f.len() as f64)
                .sqrt()
        });
        let peak_amplitude_m = amplitudes_m.iter().copied().fold(0.0, f64::max);
        let extrapolation = match &model {
            Predictor::Mode(m, _) => extrapolation_note(
                peak_amplitude_m,
                (m.spec.scales.amplitude_min_m, m.spec.scales.amplitude_max_m),
            ),
            Predictor::Reduced(..) => None,
        };
        let not_one_mode = {
            let x = backbone::receptance(s.quantity, &om, &level.measured);
            backbone::fit_linear_mode(&om, &x)
                .err()
                .map(|e| e.to_string())
        };
        files.push(FilePrediction {
            not_one_mode,
            peak_amplitude_m,
            extrapolation,
            input: InputFile::of(s),
            errors: LevelErrors::new(&level, &y, "predicted", failed),
            force_rms_error,
            model_frf: y,
            model_force_n: forces,
        });
    }
    let roles = vec!["predicted"; levels.len()];
    let bands = match (&model, control) {
        (Predictor::Mode(_, None) | Predictor::Reduced(_, None), _) => {
            Err("the model file holds no ensemble".to_string())
        }
        (_, Control::Response) => Err("bands are computed under force control only".to_string()),
        (Predictor::Mode(m, Some(e)), Control::Force) => {
            prediction_bands(&m.spec, m, e, &levels, &roles).map_err(|e| e.to_string())
        }
        (Predictor::Reduced(m, Some(e)), Control::Force) => {
            prediction_bands(&m.spec, m, e, &levels, &roles).map_err(|e| e.to_string())
        }
    };
    let stationarity = match control {
        Control::Response => Err("response control holds the amplitude: no two sides".to_string()),
        Control::Force => {
            let frfs: Vec<Vec<Complex64>> = levels.iter().map(|l| l.measured.clone()).collect();
            backbone::from_data(&sweeps, &frfs)
                .map(|b| stationarity::compare_levels(&b, &levels))
                .map_err(|e| e.to_string())
        }
    };
    Ok(Prediction {
        bands,
        stationarity,
        model_file: model_file.to_path_buf(),
        control,
        control_source,
        convention,
        convention_source: source,
        files,
        sweeps,
        model,
    })
}

/// The phase convention of the files to predict (see the module documentation): each file's
/// own ([`PhaseConvention::detect_file`]), which must be one for all files and the model's saved
/// convention; the saved convention where no file passes through a resonance inside its band.
/// A file that peaks inside its band without the phase of a resonance is refused (never read
/// with the saved convention), as is a file whose convention differs.
fn files_convention(sweeps: &[Sweep], saved: PhaseConvention) -> Result<(PhaseConvention, String)> {
    let own: Vec<FileConvention> = sweeps
        .iter()
        .map(PhaseConvention::detect_file)
        .collect::<Result<_>>()?;
    let without: Vec<&str> = own
        .iter()
        .filter_map(|c| match c {
            FileConvention::NoResonance(why) => Some(why.as_str()),
            FileConvention::Detected(_) => None,
        })
        .collect();
    let Some(most) = most_common(&own) else {
        return Ok((
            saved,
            format!("saved with the model ({})", without.join("; ")),
        ));
    };
    check_agree(sweeps, &own, None, most)?;
    check_agree(
        sweeps,
        &own,
        Some("of the files the model was identified from, saved with it"),
        saved,
    )?;
    let source = if without.is_empty() {
        "detected from the files".to_string()
    } else {
        format!(
            "detected from the files that pass through a resonance, the same as the model's \
             saved convention; used for the others too ({})",
            without.join("; ")
        )
    };
    Ok((saved, source))
}

impl Prediction {
    /// Human-readable report.
    pub fn text(&self) -> String {
        let mut s = format!(
            "asperity predict — identified model {} on measured files\n\
             control: {} ({})\n\
             phase convention: {} ({})\n\n",
            self.model_file.display(),
            match self.control {
                Control::Force => "force: the measured force of each row applied",
                Control::Response =>
                    "response: the measured response of each row held, force solved for",
            },
            self.control_source,
            self.convention.describe(),
            self.convention_source
        );
        // A file that is not one lightly damped mode is marked in the table, beside its errors.
        let marked: Vec<LevelErrors> = self
            .files
            .iter()
            .map(|f| {
                let mut e = f.errors.clone();
                if f.not_one_mode.is_some() {
                    e.file += " [NOT ONE MODE]";
                }
                e
            })
            .collect();
        let rows: Vec<_> = marked.iter().map(|e| (e, None)).collect();
        s += &errors_table("errors per file (model − measured):", &rows);
        for f in &self.files {
            if let Some(why) = &f.not_one_mode {
                s += &format!(
                    "  warning: {} [NOT ONE MODE]: {why}; its errors compare the single-mode model \
                     with data it does not describe\n",
                    f.errors.file
                );
            }
        }
        match &self.bands {
            Ok(b) => {
                s += "95 % bands over the ensemble saved with the model (models of its form that \
                      fit its data about as well; model-form error is not in the band):\n";
                s += &bands_table(b);
            }
            Err(why) => s += &format!("no 95 % bands: {why}\n"),
        }
        for f in &self.files {
            if let Some(why) = &f.extrapolation {
                s += &format!("  warning: {}: {why}\n", f.errors.file);
            }
        }
        for f in &self.files {
            if let Some(e) = f.force_rms_error {
                s += &format!(
                    "  {}: RMS relative error of the force needed: {:.1}%\n",
                    f.errors.file,
                    100.0 * e
                );
            }
            for r in &f.errors.regions {
                if r.rows == 0 {
                    s += &format!("  {} {}: no rows\n", f.errors.file, r.region);
                    continue;
                }
                s += &format!(
                    "  {} {} ({} rows): RMS {:.3}, amplitude {:+.1}%, phase {:+.3} rad\n",
                    f.errors.file,
                    r.region,
                    r.rows,
                    r.rms_complex,
                    100.0 * r.mean_amplitude_error,
                    r.mean_phase_error_rad
                );
            }
        }
        match &self.stationarity {
            Ok(c) => {
                let files: Vec<(String, Option<&SideComparison>)> = c
                    .iter()
                    .enumerate()
                    .map(|(i, c)| (format!("file {}", i + 1), c.as_ref()))
                    .collect();
                s += &stationarity::section(&files);
            }
            Err(why) => s += &format!("\nstationarity not checked: {why}\n"),
        }
        s
    }

    /// Write `predict.{txt,json}`, `predict-rows.csv` and one PNG per file into `dir`.
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>> {
        let mut written = Vec::new();
        let mut rows = Vec::new();
        for (f, s) in self.files.iter().zip(&self.sweeps) {
            let level = LevelData::new(s, &self.convention);
            for (k, r) in s.rows.iter().enumerate() {
                rows.push(CurveRow {
                    file: f.errors.file.clone(),
                    role: "predicted".into(),
                    line: r.line,
                    frequency_hz: r.frequency_hz,
                    force_n: r.force_n,
                    measured: level.measured[k],
                    models: vec![f.model_frf[k]],
                });
            }
        }
        let p = dir.join("predict-rows.csv");
        let conv = self.convention;
        write_rows_csv(
            &p,
            "response per unit force in the unit of each file's quantity per N; phases in the files' convention",
            &["model"],
            &rows,
            &|_| conv,
        )?;
        written.push(p);
        for (i, (f, s)) in self.files.iter().zip(&self.sweeps).enumerate() {
            let level = LevelData::new(s, &self.convention);
            let curve = match self.control {
                Control::Force => self.model.fine_curve(&level),
                Control::Response => level
                    .drives
                    .iter()
                    .zip(&f.model_frf)
                    .map(|(d, y)| (d.omega / std::f64::consts::TAU, *y))
                    .collect(),
            };
            let p = dir.join(format!("predict-{}.png", i + 1));
            plot_level(
                &p,
                &level,
                &self.convention,
                &[("model (predicted)".into(), curve)],
                &format!("{} predicted", f.errors.file),
            )?;
            written.push(p);
        }
        let p = dir.join("predict.json");
        write_json(
            &p,
            &serde_json::json!({
                "tool": "asperity predict",
                "crate_version": env!("CARGO_PKG_VERSION"),
                "model_file_sha256": crate::core::hash::sha256_hex(
                    &std::fs::read(&self.model_file).map_err(|e| Error::io(&self.model_file, e))?),
                "prediction": self,
                "stationarity_criterion": super::stationarity::criterion_json(),
            }),
        )?;
        written.push(p);
        let p = dir.join("predict.txt");
        write_string_atomic(&p, &self.text())?;
        written.push(p);
        Ok(written)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::identify::measured::{synthetic_sweep_csv, Quantity};

    /// Each file's own convention must be the model's; the saved one is used only for files
    /// with no resonance inside their band, never for a file that peaks inside its band without
    /// a resonance's phase (before, any failure of one joint detection fell back to it).
    #[test]
    fn a_file_far_outside_the_identified_amplitudes_is_flagged() {
        let range = (1e-4, 3e-4);
        assert_eq!(extrapolation_note(2e-4, range), None);
        assert_eq!(extrapolation_note(5.9e-4, range), None);
        assert_eq!(extrapolation_note(0.51e-4, range), None);
        let above = extrapolation_note(1.4e-2, range).unwrap();
        assert!(above.contains("46.7× the largest"), "{above}");
        let below = extrapolation_note(2e-5, range).unwrap();
        assert!(below.contains("1/5.0 of the smallest"), "{below}");
    }

    #[test]
    fn every_file_shows_the_models_convention_or_none() {
        let d = tempfile::tempdir().unwrap();
        let (a, v) = (Quantity::Acceleration, Quantity::Velocity);
        let inverted = PhaseConvention {
            time_sign: 1.0,
            inverted: true,
        };
        let file = |name: &str, column: Quantity, conv: PhaseConvention, f0: f64| {
            let p = d.path().join(name);
            std::fs::write(&p, synthetic_sweep_csv(a, column, conv, f0, false)).unwrap();
            Sweep::read_csv(&p).unwrap()
        };
        let good = file("a.csv", a, inverted, 76.0);
        let good2 = file("b.csv", a, inverted, 76.4);
        let plain = file("plain.csv", a, PhaseConvention::MODEL, 76.0);
        let below = file("below.csv", a, inverted, 70.0);
        let as_velocity = file("as-velocity.csv", v, inverted, 76.0);
        let (c, source) = files_convention(&[good.clone(), good2.clone()], inverted).unwrap();
        assert_eq!((c, source.as_str()), (inverted, "detected from the files"));
        let e = files_convention(&[good.clone(), good2, plain.clone()], inverted)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("plain.csv is not in the phase convention of the other files"),
            "{e}"
        );
        let e = files_convention(std::slice::from_ref(&plain), inverted)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains(
                "plain.csv is not in the phase convention of the files the model was \
                        identified from"
            ) && e.contains("plain.csv: e^{iωt}.")
                && e.contains("(e^{iωt}, channel inverted)"),
            "{e}"
        );
        let (c, source) = files_convention(std::slice::from_ref(&below), inverted).unwrap();
        assert!(
            c == inverted
                && source.contains(
                    "saved with the model (below.csv: the amplitude peaks on its last row"
                ),
            "{source}"
        );
        let (c, source) = files_convention(&[good, below], inverted).unwrap();
        assert!(
            c == inverted && source.contains("used for the others too (below.csv"),
            "{source}"
        );
        let e = files_convention(&[as_velocity], inverted)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("as-velocity.csv") && e.contains("`velocity_amplitude_m_per_s`"),
            "{e}"
        );
    }
}
