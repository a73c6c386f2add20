//! Measured stepped-sine frequency responses: one CSV file per excitation level.
//!
//! # File format
//!
//! A CSV file with a header row (lines starting with `#` are comments), one row per frequency
//! step, the fundamental-harmonic amplitudes of the excitation force and of the response:
//!
//! | column | meaning |
//! |---|---|
//! | `frequency_Hz` | excitation frequency (Hz), strictly monotonic (the sweep order: up or down) |
//! | `force_amplitude_N` | measured force amplitude of this row (N), > 0 |
//! | one of `acceleration_amplitude_m_per_s2`, `velocity_amplitude_m_per_s`, `displacement_amplitude_m` | response amplitude, its quantity and unit named by the column, > 0 |
//! | `phase_rad` or `phase_deg` | phase of the response relative to the force |
//!
//! The force of every row is used as measured (force controllers hold the level only
//! approximately, and the force drops at resonance when the shaker and the structure interact).
//!
//! # Phase convention
//!
//! Acquisition systems differ in two conventions: the sign of the time dependence (`e^{iωt}`,
//! where the phase of a receptance falls from 0 to −π through a resonance, or `e^{−iωt}`,
//! where it rises) and the sign of the response channel (sensor orientation, a channel
//! reported as `−a`). [`PhaseConvention::detect`] finds both from the data: the direction in which
//! the phase turns through the resonance, and the phase at the response peak (for a
//! single dominant mode in the `e^{iωt}` convention: −π/2 for displacement, 0 for velocity,
//! +π/2 for acceleration; a value π away means the response channel is inverted). The detected
//! convention is reported, never silently assumed. Inside the crate every response is a complex
//! amplitude per unit force in the `e^{iωt}` convention with the model's sign.
//!
//! # Errors
//!
//! Missing columns, non-numeric or non-finite values, a missing or non-positive force or
//! response, duplicate or non-monotonic frequencies, and a column declared in radians whose
//! values are degrees (a value beyond ±4π, or a span beyond 3π: radians unwrapped beyond ±2π are
//! accepted, see [`MAX_RADIAN_PHASE_SPAN`]) are errors naming the file and the line.

use crate::core::error::{Error, Result};
use crate::core::hash::sha256_hex;
use crate::core::input::{csv_reader, csv_record};
use crate::core::sanity::{MAX_FORCE_AMPLITUDE_N, MAX_VIBRATION_AMPLITUDE_M};
use realfft::num_complex::Complex64;
use serde::{Deserialize, Serialize};
use std::f64::consts::{FRAC_PI_2, PI, TAU};
use std::path::{Path, PathBuf};

/// Which response quantity a file holds (named by its column).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Quantity {
    /// Displacement amplitude (m); its FRF is the receptance (m/N).
    Displacement,
    /// Velocity amplitude (m/s); its FRF is the mobility (m/(s·N)).
    Velocity,
    /// Acceleration amplitude (m/s²); its FRF is the accelerance (m/(s²·N)).
    Acceleration,
}

impl Quantity {
    /// The CSV column of this quantity's amplitude, with its unit.
    pub fn column(self) -> &'static str {
        match self {
            Quantity::Displacement => "displacement_amplitude_m",
            Quantity::Velocity => "velocity_amplitude_m_per_s",
            Quantity::Acceleration => "acceleration_amplitude_m_per_s2",
        }
    }

    /// Unit of the amplitude.
    pub fn unit(self) -> &'static str {
        match self {
            Quantity::Displacement => "m",
            Quantity::Velocity => "m/s",
            Quantity::Acceleration => "m/s²",
        }
    }

    /// Name of the response-per-force ratio (receptance, mobility, accelerance).
    pub fn frf_name(self) -> &'static str {
        match self {
            Quantity::Displacement => "receptance",
            Quantity::Velocity => "mobility",
            Quantity::Acceleration => "accelerance",
        }
    }

    /// Complex factor `(iω)^p` from displacement to this quantity in the `e^{iωt}` convention.
    pub fn from_displacement(self, omega: f64) -> Complex64 {
        match self {
            Quantity::Displacement => Complex64::new(1.0, 0.0),
            Quantity::Velocity => Complex64::new(0.0, omega),
            Quantity::Acceleration => Complex64::new(-omega * omega, 0.0),
        }
    }

    /// Phase of this quantity at a phase resonance (displacement in quadrature, −π/2).
    pub fn resonance_phase(self) -> f64 {
        match self {
            Quantity::Displacement => -FRAC_PI_2,
            Quantity::Velocity => 0.0,
            Quantity::Acceleration => FRAC_PI_2,
        }
    }

    const ALL: [Quantity; 3] = [
        Quantity::Displacement,
        Quantity::Velocity,
        Quantity::Acceleration,
    ];
}

/// One row of a measured sweep.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Row {
    /// 1-based line in the file.
    pub line: usize,
    /// Excitation frequency (Hz).
    pub frequency_hz: f64,
    /// Fundamental-harmonic force amplitude (N).
    pub force_n: f64,
    /// Fundamental-harmonic response amplitude (unit of the file's quantity).
    pub response: f64,
    /// Phase of the response relative to the force, as in the file, in radians.
    pub phase_rad: f64,
}

impl Row {
    /// Angular frequency (rad/s).
    pub fn omega(&self) -> f64 {
        TAU * self.frequency_hz
    }
}

/// One measured sweep (one excitation level).
#[derive(Debug, Clone, Serialize)]
pub struct Sweep {
    /// Path of the file as given.
    pub path: PathBuf,
    /// SHA-256 of the file's bytes.
    pub sha256: String,
    /// Response quantity the file measures (from its header).
    pub quantity: Quantity,
    /// Rows in file order (the sweep direction).
    pub rows: Vec<Row>,
    /// Line of the header row.
    pub header_line: usize,
}

fn find_column(
    path: &Path,
    header: &csv::StringRecord,
    header_line: usize,
    names: &[&str],
) -> Result<Option<(usize, usize)>> {
    let hits: Vec<(usize, usize)> = names
        .iter()
        .enumerate()
        .filter_map(|(k, n)| header.iter().position(|h| h == *n).map(|c| (c, k)))
        .collect();
    match hits.len() {
        0 => Ok(None),
        1 => Ok(Some(hits[0])),
        _ => Err(Error::parse(
            path,
            header_line,
            format!(
                "several alternative columns present ({}); keep one",
                hits.iter()
                    .map(|&(_, k)| names[k])
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        )),
    }
}

fn field(path: &Path, rec: &csv::StringRecord, line: usize, col: usize, name: &str) -> Result<f64> {
    let s = rec.get(col).unwrap_or("").trim();
    if s.is_empty() {
        return Err(Error::parse(
            path,
            line,
            format!("missing value of `{name}`"),
        ));
    }
    let v: f64 = s
        .parse()
        .map_err(|_| Error::parse(path, line, format!("`{name}` = {s:?} is not a number")))?;
    if !v.is_finite() {
        return Err(Error::parse(
            path,
            line,
            format!("`{name}` = {s} is not finite"),
        ));
    }
    Ok(v)
}

/// Minimum number of rows of a sweep.
pub const MIN_ROWS: usize = 5;

impl Sweep {
    /// Read and validate a measured sweep (see the module documentation).
    pub fn read_csv(path: &Path) -> Result<Self> {
        crate::core::limits::check_file_size(path, crate::core::limits::MAX_TEXT_FILE_BYTES)?;
        let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
        let sha256 = sha256_hex(&bytes);
        let mut rdr = csv_reader(path)?;
        let header = rdr
            .headers()
            .map_err(|e| crate::core::input::csv_error(path, e))?
            .clone();
        let header_line = header.position().map(|p| p.line() as usize).unwrap_or(1);
        let need = |names: &[&str], what: &str| -> Result<(usize, usize)> {
            find_column(path, &header, header_line, names)?.ok_or_else(|| {
                Error::parse(
                    path,
                    header_line,
                    format!(
                        "no {what} column (expected {}); header: {}",
                        names.join(" or "),
                        header.iter().collect::<Vec<_>>().join(",")
                    ),
                )
            })
        };
        let (c_f, _) = need(&["frequency_Hz"], "frequency")?;
        let (c_force, _) = need(&["force_amplitude_N"], "force")?;
        let qnames: Vec<&str> = Quantity::ALL.iter().map(|q| q.column()).collect();
        let (c_resp, qk) = need(&qnames, "response amplitude")?;
        let quantity = Quantity::ALL[qk];
        let (c_phase, pk) = need(&["phase_rad", "phase_deg"], "phase")?;
        let degrees = pk == 1;
        let mut rows: Vec<Row> = Vec::new();
        for rec in rdr.records() {
            let (rec, line) = csv_record(path, rec)?;
            if rows.len() == crate::core::limits::MAX_SWEEP_ROWS {
                return Err(Error::limit(
                    path.display().to_string(),
                    format!(
                        "more than {} data rows (line {line}); a stepped-sine sweep has tens to a \
                         few thousand, and every model evaluation of the identification visits \
                         each row: thin the file (every k-th row) or split the band",
                        crate::core::limits::MAX_SWEEP_ROWS
                    ),
                ));
            }
            let frequency_hz = field(path, &rec, line, c_f, "frequency_Hz")?;
            let force_n = field(path, &rec, line, c_force, "force_amplitude_N")?;
            let response = field(path, &rec, line, c_resp, quantity.column())?;
            let phase = field(path, &rec, line, c_phase, header.get(c_phase).unwrap_or(""))?;
            if frequency_hz <= 0.0 {
                return Err(Error::parse(
                    path,
                    line,
                    format!("frequency {frequency_hz} Hz must be > 0"),
                ));
            }
            if force_n <= 0.0 {
                return Err(Error::parse(
                    path,
                    line,
                    format!("force amplitude {force_n} N must be > 0"),
                ));
            }
            if response <= 0.0 {
                return Err(Error::parse(
                    path,
                    line,
                    format!(
                        "response amplitude {response} {} must be > 0",
                        quantity.unit()
                    ),
                ));
            }
            // A displacement amplitude of a metre or more, or a force of a meganewton, is no
            // vibration test's: a unit or column error (kHz as Hz, mm/s² as m/s², …).
            let displacement_m = response / quantity.from_displacement(TAU * frequency_hz).norm();
            if displacement_m > MAX_VIBRATION_AMPLITUDE_M {
                return Err(Error::parse(
                    path,
                    line,
                    format!(
                        "response amplitude {response} {} at {frequency_hz} Hz is a vibration of \
                         {displacement_m:.3e} m (more than {MAX_VIBRATION_AMPLITUDE_M} m): check \
                         the units of the frequency and response columns",
                        quantity.unit()
                    ),
                ));
            }
            if force_n > MAX_FORCE_AMPLITUDE_N {
                return Err(Error::parse(
                    path,
                    line,
                    format!(
                        "force amplitude {force_n} N is more than {MAX_FORCE_AMPLITUDE_N:e} N: \
                         check the unit of the force column"
                    ),
                ));
            }
            let phase_rad = if degrees { phase.to_radians() } else { phase };
            rows.push(Row {
                line,
                frequency_hz,
                force_n,
                response,
                phase_rad,
            });
        }
        if rows.len() < MIN_ROWS {
            return Err(Error::parse(
                path,
                0,
                format!(
                    "{} data rows; a sweep needs at least {MIN_ROWS}",
                    rows.len()
                ),
            ));
        }
        check_monotonic(path, &rows)?;
        if !degrees {
            check_radians(path, &rows)?;
        }
        Ok(Self {
            path: path.to_path_buf(),
            sha256,
            quantity,
            rows,
            header_line,
        })
    }

    /// Mean measured force amplitude (N): the level's nominal value for ordering and reports.
    pub fn mean_force_n(&self) -> f64 {
        self.rows.iter().map(|r| r.force_n).sum::<f64>() / self.rows.len() as f64
    }

    /// Row of the largest response per unit force.
    pub fn peak_row(&self) -> usize {
        (0..self.rows.len())
            .max_by(|&a, &b| {
                let fa = self.rows[a].response / self.rows[a].force_n;
                let fb = self.rows[b].response / self.rows[b].force_n;
                fa.total_cmp(&fb)
            })
            .expect("at least MIN_ROWS rows")
    }

    /// Whether the amplitude (response per unit force) peaks inside the band: not on the first
    /// or last row.
    pub fn peak_inside_band(&self) -> bool {
        let k = self.peak_row();
        k > 0 && k + 1 < self.rows.len()
    }

    /// Complex response per unit force of every row in the crate's convention.
    pub fn frf(&self, conv: &PhaseConvention) -> Vec<Complex64> {
        self.rows
            .iter()
            .map(|r| conv.to_model(r.response / r.force_n, r.phase_rad))
            .collect()
    }

    /// File name for reports.
    pub fn name(&self) -> String {
        self.path
            .file_name()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| self.path.display().to_string())
    }
}

/// Largest span (max − min) of a phase column in radians: more than this, the values are degrees.
///
/// The phase of one resonance sweep turns by about π (a single mode; two modes in the band, 2π);
/// wrapped into any interval of width 2π the values span at most 2π, unwrapped they span the
/// turn itself, whatever multiple of 2π the unwrapping started from. 3π leaves a π margin for
/// noise and an extra mode. The same sweep in degrees spans tens to hundreds (the half-power
/// band alone turns 90°), so a span beyond 3π (9.4) is degrees; a sweep whose degrees span less
/// than 9.4° does not pass through a resonance and is refused later by the convention check.
pub const MAX_RADIAN_PHASE_SPAN: f64 = 3.0 * PI;

/// Largest magnitude of a phase in radians: unwrapped phases start within one turn of zero and a
/// sweep adds at most [`MAX_RADIAN_PHASE_SPAN`], so values beyond 4π are degrees (this catches a
/// column in degrees that spans little, e.g. −178…−170).
pub const MAX_RADIAN_PHASE: f64 = 4.0 * PI;

/// A `phase_rad` column holds radians, possibly unwrapped beyond ±2π: refused as degrees when a
/// value exceeds [`MAX_RADIAN_PHASE`] (naming its line) or the column spans more than
/// [`MAX_RADIAN_PHASE_SPAN`] (naming the line farthest from the column's median).
fn check_radians(path: &Path, rows: &[Row]) -> Result<()> {
    let hint = "in a column declared in radians (phase_rad): the values look like degrees; \
                convert them or name the column phase_deg";
    if let Some(r) = rows.iter().find(|r| r.phase_rad.abs() > MAX_RADIAN_PHASE) {
        return Err(Error::parse(
            path,
            r.line,
            format!("phase {} is outside [−4π, 4π] {hint}", r.phase_rad),
        ));
    }
    let lo = rows
        .iter()
        .map(|r| r.phase_rad)
        .fold(f64::INFINITY, f64::min);
    let hi = rows
        .iter()
        .map(|r| r.phase_rad)
        .fold(f64::NEG_INFINITY, f64::max);
    if hi - lo > MAX_RADIAN_PHASE_SPAN {
        let mut sorted: Vec<f64> = rows.iter().map(|r| r.phase_rad).collect();
        sorted.sort_by(f64::total_cmp);
        let median = sorted[sorted.len() / 2];
        let r = rows
            .iter()
            .max_by(|a, b| {
                (a.phase_rad - median)
                    .abs()
                    .total_cmp(&(b.phase_rad - median).abs())
            })
            .expect("rows");
        return Err(Error::parse(
            path,
            r.line,
            format!(
                "phase {} (the column's median is {median}): the column spans {:.2} rad, more \
                 than the 3π of any resonance sweep, {hint}",
                r.phase_rad,
                hi - lo
            ),
        ));
    }
    Ok(())
}

/// Frequencies strictly increasing or strictly decreasing over the whole file.
fn check_monotonic(path: &Path, rows: &[Row]) -> Result<()> {
    let up = rows[1].frequency_hz > rows[0].frequency_hz;
    for w in rows.windows(2) {
        let (a, b) = (&w[0], &w[1]);
        if b.frequency_hz == a.frequency_hz {
            return Err(Error::parse(
                path,
                b.line,
                format!(
                    "duplicate frequency {} Hz (also on line {})",
                    b.frequency_hz, a.line
                ),
            ));
        }
        if (b.frequency_hz > a.frequency_hz) != up {
            return Err(Error::parse(
                path,
                b.line,
                format!(
                    "frequencies are not monotonic: {} Hz after {} Hz on line {} (the sweep runs {} \
                     before)",
                    b.frequency_hz,
                    a.frequency_hz,
                    a.line,
                    if up { "upwards" } else { "downwards" }
                ),
            ));
        }
    }
    Ok(())
}

/// Wrap an angle into `(−π, π]`.
pub fn wrap(a: f64) -> f64 {
    let r = a.rem_euclid(TAU);
    if r > PI {
        r - TAU
    } else {
        r
    }
}

/// Unwrapped phase change of a sweep from its lowest to its highest frequency (rad).
fn phase_turn(s: &Sweep) -> f64 {
    let mut rows = s.rows.clone();
    rows.sort_by(|a, b| a.frequency_hz.total_cmp(&b.frequency_hz));
    rows.windows(2)
        .map(|w| wrap(w[1].phase_rad - w[0].phase_rad))
        .sum()
}

/// Phase at the response peak, with the time sign applied, minus the quantity's resonance
/// phase (not wrapped).
fn peak_phase_offset(s: &Sweep, time_sign: f64) -> f64 {
    let r = &s.rows[s.peak_row()];
    time_sign * r.phase_rad - s.quantity.resonance_phase()
}

/// The phase convention one file shows on its own ([`PhaseConvention::detect_file`]).
#[derive(Debug, Clone, PartialEq)]
pub enum FileConvention {
    /// The file's resonance phase shows this convention.
    Detected(PhaseConvention),
    /// The file's amplitude peaks on its first or last row: the reason, naming the file.
    NoResonance(String),
}

/// The convention most files show on their own (the first of equally many), if any shows one.
pub fn most_common(own: &[FileConvention]) -> Option<PhaseConvention> {
    let detected: Vec<PhaseConvention> = own
        .iter()
        .filter_map(|c| match c {
            FileConvention::Detected(c) => Some(*c),
            FileConvention::NoResonance(_) => None,
        })
        .collect();
    detected.iter().copied().max_by_key(|c| {
        // `max_by_key` keeps the last maximum: rank the earlier ones higher on ties.
        let n = detected.iter().filter(|d| *d == c).count();
        let first = detected.iter().position(|d| d == c).unwrap_or(0);
        (n, usize::MAX - first)
    })
}

/// Every file that shows a convention of its own shows `common`; otherwise an error naming each
/// file's convention (and, where given, what `common` is: e.g. the model's saved convention).
pub fn check_agree(
    sweeps: &[Sweep],
    own: &[FileConvention],
    common_source: Option<&str>,
    common: PhaseConvention,
) -> Result<()> {
    let odd: Vec<usize> = (0..sweeps.len())
        .filter(|&i| matches!(own[i], FileConvention::Detected(c) if c != common))
        .collect();
    if odd.is_empty() {
        return Ok(());
    }
    let agreeing = own
        .iter()
        .filter(|c| matches!(c, FileConvention::Detected(c) if *c == common))
        .count();
    let list = sweeps
        .iter()
        .zip(own)
        .map(|(s, c)| {
            format!(
                "{}: {}",
                s.path.display(),
                match c {
                    FileConvention::Detected(c) => c.short(),
                    FileConvention::NoResonance(_) => "none (no resonance inside the band)".into(),
                }
            )
        })
        .collect::<Vec<_>>()
        .join("; ");
    if common_source.is_none() && odd.len() >= agreeing {
        // No convention is shared by most files (two files, one inverted): the files alone
        // cannot tell which is odd, so none is singled out (before, the lowest level's
        // convention won the tie and the other file, maybe the good one, was blamed).
        return Err(Error::Data(format!(
            "the files are in different phase conventions and none is shared by most of them: \
             {list}. Measurements of one structure with one acquisition set-up share one \
             convention: correct the phases (or the response column) of the file whose channel \
             is inverted or conjugated — the files alone cannot tell which one it is"
        )));
    }
    let against = format!(
        "{} ({})",
        common_source.unwrap_or("of the other files"),
        common.short()
    );
    Err(Error::Data(format!(
        "{} {} not in the phase convention {against}. Each file's own convention: \
         {list}. Measurements of one structure with one acquisition set-up share one convention: \
         a response channel inverted or conjugated in some files (sensor orientation, export \
         settings), or a response column naming another quantity than the one measured \
         (displacement and acceleration are π apart), would be misread; correct the phases (or \
         the column) of the odd file",
        odd.iter()
            .map(|&i| sweeps[i].path.display().to_string())
            .collect::<Vec<_>>()
            .join(", "),
        if odd.len() == 1 { "is" } else { "are" }
    )))
}

/// How the phases of a file map onto the crate's convention (`e^{iωt}`, model sign):
/// `phase_model = time_sign·phase_file + (π if inverted)`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PhaseConvention {
    /// +1: the file uses `e^{iωt}` (phase falls through a resonance); −1: `e^{−iωt}`.
    pub time_sign: f64,
    /// The response channel is inverted (phase π away from the model's).
    pub inverted: bool,
}

impl PhaseConvention {
    /// The crate's own convention.
    pub const MODEL: PhaseConvention = PhaseConvention {
        time_sign: 1.0,
        inverted: false,
    };

    /// A convention read from a file is one of the four: `time_sign` ±1 (the error names the
    /// field).
    pub fn check(&self) -> std::result::Result<(), String> {
        if self.time_sign == 1.0 || self.time_sign == -1.0 {
            Ok(())
        } else {
            Err(format!(
                "time_sign = {}: must be 1 (e^{{iωt}}) or -1 (e^{{−iωt}})",
                self.time_sign
            ))
        }
    }

    /// Complex response per unit force from an amplitude ratio and the file's phase.
    pub fn to_model(&self, ratio: f64, phase_file: f64) -> Complex64 {
        let s = if self.inverted { -1.0 } else { 1.0 };
        Complex64::from_polar(s * ratio, self.time_sign * phase_file)
    }

    /// Phase in the file's convention of a model response (inverse of [`Self::to_model`]).
    pub fn to_file_phase(&self, z: Complex64) -> f64 {
        let z = if self.inverted { -z } else { z };
        self.time_sign * z.arg()
    }

    /// Detect the convention from the sweeps (see the module documentation): the direction of
    /// the phase change through the resonance (unwrapped phase from the lowest to the highest
    /// frequency, summed over the sweeps) and the circular mean, over the sweeps, of the phase at
    /// the response peak relative to the quantity's resonance phase. An ambiguous result is an
    /// error naming the files.
    pub fn detect(sweeps: &[Sweep]) -> Result<Self> {
        let names = || {
            sweeps
                .iter()
                .map(|s| s.path.display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        };
        let turn: f64 = sweeps.iter().map(phase_turn).sum();
        if turn.abs() < PI / 4.0 * sweeps.len() as f64 {
            return Err(Error::Data(format!(
                "{}: the phase turns by only {:.2} rad per sweep across the band; the sweeps must \
                 pass through the resonance to identify a mode (and to tell the phase convention)",
                names(),
                turn / sweeps.len() as f64
            )));
        }
        let time_sign = if turn < 0.0 { 1.0 } else { -1.0 };
        let (mut c, mut s) = (0.0, 0.0);
        for sw in sweeps {
            let d = peak_phase_offset(sw, time_sign);
            c += d.cos();
            s += d.sin();
        }
        let d = wrap(s.atan2(c));
        let inverted = if d.abs() <= PI / 3.0 {
            false
        } else if d.abs() >= 2.0 * PI / 3.0 {
            true
        } else {
            return Err(Error::Data(format!(
                "{}: cannot tell the phase convention: at the response peaks the phase is {:.2} \
                 rad away from the resonance phase of the measured quantity, neither ≈ 0 nor ≈ π",
                names(),
                d
            )));
        };
        Ok(Self {
            time_sign,
            inverted,
        })
    }

    /// The convention of one file on its own ([`Self::detect`] of that file), telling a file
    /// that cannot show it (its amplitude peaks on its first or last row: no resonance inside the
    /// band, [`FileConvention::NoResonance`]) from a file that peaks inside its band but whose
    /// phase does not behave as a resonance's: the latter is an error naming the file and the
    /// likely cause (the phase column's unit, or a response column naming another quantity).
    pub fn detect_file(sweep: &Sweep) -> Result<FileConvention> {
        let detected = Self::detect(std::slice::from_ref(sweep));
        if detected.is_ok() {
            return detected.map(FileConvention::Detected);
        }
        if !sweep.peak_inside_band() {
            return Ok(FileConvention::NoResonance(format!(
                "{}: the amplitude peaks on its {} row, no resonance inside the band",
                sweep.name(),
                if sweep.peak_row() == 0 {
                    "first"
                } else {
                    "last"
                }
            )));
        }
        let peak = &sweep.rows[sweep.peak_row()];
        let turn = phase_turn(sweep);
        let at = format!(
            "{}: the amplitude peaks inside the band (line {}, {} Hz)",
            sweep.path.display(),
            peak.line,
            peak.frequency_hz
        );
        if turn.abs() < PI / 4.0 {
            return Err(Error::Data(format!(
                "{at} but the phase turns by only {turn:.2} rad across the band, where a \
                 resonance turns it by about π: the phase column is likely in another unit than \
                 its name says (radians in a `phase_deg` column?), or the file is not a resonance \
                 sweep"
            )));
        }
        let time_sign = if turn < 0.0 { 1.0 } else { -1.0 };
        let d = wrap(peak_phase_offset(sweep, time_sign));
        Err(Error::Data(format!(
            "{at} where its phase is {d:+.2} rad from the resonance phase of a {q} ({r:+.2} rad for \
             the column `{c}`), neither ≈ 0 nor ≈ π: the column likely names another quantity \
             than the one measured (displacement, velocity and acceleration are π/2 apart), or \
             the phase is in another unit",
            q = sweep.quantity.frf_name(),
            r = sweep.quantity.resonance_phase(),
            c = sweep.quantity.column(),
        )))
    }

    /// The one convention of a set of sweeps (identification, `predict`): [`Self::detect`] over
    /// all of them (the same numbers as before files were checked one by one), and every file
    /// whose amplitude peaks inside its band must show that convention on its own
    /// ([`Self::detect_file`]); a file that disagrees is refused, naming each file's convention:
    /// reading it with the others' would misread it silently.
    pub fn detect_common(sweeps: &[Sweep]) -> Result<Self> {
        let own: Vec<FileConvention> = sweeps
            .iter()
            .map(Self::detect_file)
            .collect::<Result<_>>()?;
        if let Some(most) = most_common(&own) {
            check_agree(sweeps, &own, None, most)?;
        }
        let common = Self::detect(sweeps)?;
        check_agree(sweeps, &own, None, common)?;
        Ok(common)
    }

    /// A few words for lists: `e^{iωt}` or `e^{−iωt} (conjugated)`, and `channel inverted`.
    pub fn short(&self) -> String {
        format!(
            "{}{}",
            if self.time_sign > 0.0 {
                "e^{iωt}"
            } else {
                "e^{−iωt} (conjugated)"
            },
            if self.inverted {
                ", channel inverted"
            } else {
                ""
            }
        )
    }

    /// One-line description for reports.    /// One-line description for reports.
    pub fn describe(&self) -> String {
        format!(
            "{}{}",
            if self.time_sign > 0.0 {
                "e^{iωt} (phase falls through the resonance)"
            } else {
                "e^{−iωt} (phase rises through the resonance; conjugated)"
            },
            if self.inverted {
                "; response channel inverted (phase π from the model's: sensor sign or a channel \
                 reported as −response)"
            } else {
                ""
            }
        )
    }
}

/// CSV text of a synthetic single-mode sweep (80 Hz, ζ = 1 %, unit force, 21 rows from `f0` Hz
/// in steps of 0.4 Hz) of the quantity `data`, written under the column of `column` in the
/// convention `conv`, phases in degrees if `degrees`.
#[cfg(test)]
pub(crate) fn synthetic_sweep_csv(
    data: Quantity,
    column: Quantity,
    conv: PhaseConvention,
    f0: f64,
    degrees: bool,
) -> String {
    let (wn, z) = (TAU * 80.0, 0.01);
    let mut text = format!(
        "frequency_Hz,force_amplitude_N,{},{}\n",
        column.column(),
        if degrees { "phase_deg" } else { "phase_rad" }
    );
    for i in 0..21 {
        let f = f0 + 0.4 * i as f64;
        let w = TAU * f;
        let h = data.from_displacement(w) / Complex64::new(wn * wn - w * w, 2.0 * z * wn * w);
        let ph = conv.to_file_phase(h);
        let ph = if degrees { ph.to_degrees() } else { ph };
        text += &format!("{f},1,{},{ph}\n", h.norm());
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    const HEAD: &str =
        "# test\nfrequency_Hz,force_amplitude_N,acceleration_amplitude_m_per_s2,phase_rad\n";

    fn rows(lines: &[&str]) -> String {
        format!("{HEAD}{}\n", lines.join("\n"))
    }

    #[test]
    fn reads_a_valid_sweep() {
        let d = tempfile::tempdir().unwrap();
        let p = write(
            d.path(),
            "a.csv",
            &rows(&[
                "10,1,1,-0.1",
                "11,1,2,-0.5",
                "12,1.1,5,-1.6",
                "13,1,2,-2.6",
                "14,1,1,-3.0",
            ]),
        );
        let s = Sweep::read_csv(&p).unwrap();
        assert_eq!(s.quantity, Quantity::Acceleration);
        assert_eq!(s.rows.len(), 5);
        assert_eq!(s.rows[0].line, 3);
        assert_eq!(s.peak_row(), 2);
        assert_eq!(s.sha256.len(), 64);
    }

    #[test]
    fn bad_rows_name_file_and_line() {
        let d = tempfile::tempdir().unwrap();
        let cases: &[(&[&str], &str, &str)] = &[
            (
                &["10,1,1,0", "11,1,1,0", "11,1,1,0", "12,1,1,0", "13,1,1,0"],
                ":5:",
                "duplicate frequency",
            ),
            (
                &["10,1,1,0", "12,1,1,0", "11,1,1,0", "13,1,1,0", "14,1,1,0"],
                ":5:",
                "not monotonic",
            ),
            (
                &["10,1,1,0", "11,,1,0", "12,1,1,0", "13,1,1,0", "14,1,1,0"],
                ":4:",
                "missing value of `force_amplitude_N`",
            ),
            (
                &[
                    "10,1,1,0",
                    "11,1,1,0",
                    "12,-0.2,1,0",
                    "13,1,1,0",
                    "14,1,1,0",
                ],
                ":5:",
                "force amplitude -0.2 N must be > 0",
            ),
            (
                &[
                    "10,1,1,-5",
                    "11,1,1,-20",
                    "12,1,1,-90",
                    "13,1,1,-160",
                    "14,1,1,-175",
                ],
                ":4:",
                "look like degrees",
            ),
            (
                &["10,1,1,0", "11,1,nan,0", "12,1,1,0", "13,1,1,0", "14,1,1,0"],
                ":4:",
                "not finite",
            ),
            (&["10,1,1,0", "11,1,1,0"], "b.csv", "at least 5"),
            (
                // A decimal comma: 7,6 read as two fields.
                &["10,1,1,0", "11,1,1,0", "12,1,7,6,0", "13,1,1,0", "14,1,1,0"],
                ":5:",
                "expected 4 fields, found 5 (decimal comma?)",
            ),
            (
                &["10,1,1,0", "11,1,1", "12,1,1,0", "13,1,1,0", "14,1,1,0"],
                ":4:",
                "expected 4 fields, found 3",
            ),
            (
                // 1e9 m/s² at 11 Hz: a vibration of 2e5 m.
                &["10,1,1,0", "11,1,1e9,0", "12,1,1,0", "13,1,1,0", "14,1,1,0"],
                ":4:",
                "check the units",
            ),
            (
                &["10,1,1,0", "11,1,1,0", "12,1,1,0", "13,2e6,1,0", "14,1,1,0"],
                ":6:",
                "unit of the force",
            ),
        ];
        for (lines, at, msg) in cases {
            let p = write(d.path(), "b.csv", &rows(lines));
            let e = Sweep::read_csv(&p).unwrap_err().to_string();
            assert!(
                e.contains("b.csv") && e.contains(at) && e.contains(msg),
                "{e}"
            );
        }
        let p = write(
            d.path(),
            "c.csv",
            "frequency_Hz,force_amplitude_N,phase_rad\n1,1,0\n",
        );
        let e = Sweep::read_csv(&p).unwrap_err().to_string();
        assert!(
            e.contains("c.csv:1:") && e.contains("no response amplitude column"),
            "{e}"
        );
    }

    #[test]
    fn degrees_column_and_downward_sweep_are_accepted() {
        let d = tempfile::tempdir().unwrap();
        let p = write(
            d.path(),
            "deg.csv",
            "frequency_Hz,force_amplitude_N,displacement_amplitude_m,phase_deg\n\
             14,1,1e-3,-175\n13,1,2e-3,-160\n12,1,5e-3,-90\n11,1,2e-3,-20\n10,1,1e-3,-5\n",
        );
        let s = Sweep::read_csv(&p).unwrap();
        assert_eq!(s.quantity, Quantity::Displacement);
        assert!((s.rows[2].phase_rad + FRAC_PI_2).abs() < 1e-12);
    }

    /// Synthetic single-mode FRFs in all four conventions are recognised.
    #[test]
    fn detects_the_phase_convention() {
        let d = tempfile::tempdir().unwrap();
        let (wn, z) = (TAU * 80.0, 0.01);
        for q in Quantity::ALL {
            for time_sign in [1.0, -1.0] {
                for inverted in [false, true] {
                    let conv = PhaseConvention {
                        time_sign,
                        inverted,
                    };
                    let mut text =
                        format!("frequency_Hz,force_amplitude_N,{},phase_rad\n", q.column());
                    for i in 0..21 {
                        let f = 76.0 + 0.4 * i as f64;
                        let w = TAU * f;
                        let h = q.from_displacement(w)
                            / Complex64::new(wn * wn - w * w, 2.0 * z * wn * w);
                        text += &format!("{f},1,{},{}\n", h.norm(), conv.to_file_phase(h));
                    }
                    let p = write(d.path(), "s.csv", &text);
                    let s = Sweep::read_csv(&p).unwrap();
                    let got = PhaseConvention::detect(std::slice::from_ref(&s)).unwrap();
                    assert_eq!(got, conv, "{q:?}");
                    // Round trip to the model's complex response.
                    let h0 = q.from_displacement(TAU * 76.0)
                        / Complex64::new(
                            wn * wn - (TAU * 76.0f64).powi(2),
                            2.0 * z * wn * TAU * 76.0,
                        );
                    assert!((s.frf(&got)[0] - h0).norm() < 1e-9 * h0.norm());
                }
            }
        }
    }

    const PLAIN: PhaseConvention = PhaseConvention::MODEL;
    const INVERTED: PhaseConvention = PhaseConvention {
        time_sign: 1.0,
        inverted: true,
    };
    const CONJUGATED: PhaseConvention = PhaseConvention {
        time_sign: -1.0,
        inverted: false,
    };

    fn sweep(dir: &Path, name: &str, text: &str) -> Sweep {
        Sweep::read_csv(&write(dir, name, text)).unwrap()
    }

    /// A file in another convention among files in one is refused naming it and both
    /// conventions (it was read with the others' convention: the joint detection is outvoted).
    #[test]
    fn a_file_in_another_convention_is_refused_naming_it() {
        let d = tempfile::tempdir().unwrap();
        let a = Quantity::Acceleration;
        for (odd, odd_short) in [(PLAIN, "odd.csv: e^{iωt}."), (CONJUGATED, "(conjugated)")] {
            let sweeps = vec![
                sweep(
                    d.path(),
                    "a.csv",
                    &synthetic_sweep_csv(a, a, INVERTED, 76.0, false),
                ),
                sweep(
                    d.path(),
                    "b.csv",
                    &synthetic_sweep_csv(a, a, INVERTED, 76.4, false),
                ),
                sweep(
                    d.path(),
                    "odd.csv",
                    &synthetic_sweep_csv(a, a, odd, 76.0, false),
                ),
            ];
            // The joint detection alone takes the majority's convention for all three.
            assert_eq!(PhaseConvention::detect(&sweeps).unwrap(), INVERTED);
            let e = PhaseConvention::detect_common(&sweeps)
                .unwrap_err()
                .to_string();
            assert!(
                e.contains(
                    "odd.csv is not in the phase convention of the other files \
                            (e^{iωt}, channel inverted)"
                ) && e.contains(odd_short)
                    && e.contains("a.csv: e^{iωt}, channel inverted"),
                "{e}"
            );
            assert_eq!(
                PhaseConvention::detect_common(&sweeps[..2]).unwrap(),
                INVERTED
            );
        }
    }

    /// Acceleration data under a velocity column among correct levels: the others outvote it in
    /// the joint detection; its own phase at the peak (π/2 from a velocity's) refuses it, naming
    /// the file and the column.
    #[test]
    fn a_mislabelled_quantity_is_refused_even_when_outvoted() {
        let d = tempfile::tempdir().unwrap();
        let (a, v) = (Quantity::Acceleration, Quantity::Velocity);
        let sweeps = vec![
            sweep(
                d.path(),
                "a.csv",
                &synthetic_sweep_csv(a, a, PLAIN, 76.0, false),
            ),
            sweep(
                d.path(),
                "b.csv",
                &synthetic_sweep_csv(a, a, PLAIN, 76.4, false),
            ),
            sweep(
                d.path(),
                "vel.csv",
                &synthetic_sweep_csv(a, v, PLAIN, 76.0, false),
            ),
        ];
        assert_eq!(PhaseConvention::detect(&sweeps).unwrap(), PLAIN);
        let e = PhaseConvention::detect_common(&sweeps)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("vel.csv")
                && e.contains("`velocity_amplitude_m_per_s`")
                && e.contains("names another quantity"),
            "{e}"
        );
    }

    /// One file on its own: a band below the resonance (peak on the last row) cannot show a
    /// convention; radians under `phase_deg` peak inside the band but hardly turn: refused.
    #[test]
    fn a_file_without_resonance_is_told_from_a_wrong_phase_unit() {
        let d = tempfile::tempdir().unwrap();
        let a = Quantity::Acceleration;
        let below = sweep(
            d.path(),
            "below.csv",
            &synthetic_sweep_csv(a, a, PLAIN, 70.0, false),
        );
        assert!(!below.peak_inside_band());
        match PhaseConvention::detect_file(&below).unwrap() {
            FileConvention::NoResonance(why) => {
                assert!(
                    why.contains("below.csv") && why.contains("last row"),
                    "{why}"
                )
            }
            c => panic!("{c:?}"),
        }
        let radians =
            synthetic_sweep_csv(a, a, PLAIN, 76.0, false).replacen("phase_rad", "phase_deg", 1);
        let s = sweep(d.path(), "rad.csv", &radians);
        let e = PhaseConvention::detect_file(&s).unwrap_err().to_string();
        assert!(
            e.contains("rad.csv") && e.contains("radians in a `phase_deg` column?"),
            "{e}"
        );
        let deg = sweep(
            d.path(),
            "deg.csv",
            &synthetic_sweep_csv(a, a, CONJUGATED, 76.0, true),
        );
        assert_eq!(
            PhaseConvention::detect_file(&deg).unwrap(),
            FileConvention::Detected(CONJUGATED)
        );
    }

    /// Radians unwrapped beyond ±2π are radians; degrees are refused however they wrap.
    #[test]
    fn unwrapped_radians_are_accepted_and_degrees_refused() {
        let d = tempfile::tempdir().unwrap();
        let a = Quantity::Acceleration;
        let text = synthetic_sweep_csv(a, a, PLAIN, 76.0, false);
        let shift = |text: &str, by: f64, scale: f64| -> String {
            let mut out = String::new();
            for (k, l) in text.lines().enumerate() {
                if k == 0 {
                    out += l;
                } else {
                    let (head, ph) = l.rsplit_once(',').unwrap();
                    let ph: f64 = ph.parse().unwrap();
                    out += &format!("{head},{}", (ph + by) * scale);
                }
                out += "\n";
            }
            out
        };
        for by in [-TAU, TAU, -2.0 * TAU + 0.5] {
            let s = sweep(d.path(), "u.csv", &shift(&text, by, 1.0));
            assert_eq!(
                PhaseConvention::detect_file(&s).unwrap(),
                FileConvention::Detected(PLAIN),
                "{by}"
            );
        }
        // Degrees: all of them (the first value beyond 4π named), and degrees that span little
        // far from zero (−178…−170).
        let p = write(d.path(), "deg.csv", &shift(&text, 0.0, 180.0 / PI));
        let e = Sweep::read_csv(&p).unwrap_err().to_string();
        assert!(
            e.contains("deg.csv:") && e.contains("look like degrees"),
            "{e}"
        );
        let p = write(
            d.path(),
            "far.csv",
            &rows(&[
                "10,1,1,-178",
                "11,1,2,-176",
                "12,1,5,-174",
                "13,1,2,-172",
                "14,1,1,-170",
            ]),
        );
        let e = Sweep::read_csv(&p).unwrap_err().to_string();
        assert!(
            e.contains("far.csv:3:") && e.contains("look like degrees"),
            "{e}"
        );
        // A span of more than 3π without any value beyond 4π: the line farthest from the median.
        let p = write(
            d.path(),
            "span.csv",
            &rows(&[
                "10,1,1,-1",
                "11,1,2,-1.5",
                "12,1,5,-2",
                "13,1,2,9",
                "14,1,1,-2.5",
            ]),
        );
        let e = Sweep::read_csv(&p).unwrap_err().to_string();
        assert!(
            e.contains("span.csv:6:") && e.contains("spans 11.50 rad"),
            "{e}"
        );
    }
}
