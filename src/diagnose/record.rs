//! A measured hysteresis record: time (s), tangential displacement (m), tangential force (N) and,
//! when measured, normal force (N), read from a CSV file whose columns are chosen by name.
//!
//! The shared friction-damper loops use `time_s, displacement_m, friction_force_N,
//! velocity_m_per_s`; those names are the defaults. Every value must be finite, time strictly
//! increasing, and every row complete: a malformed file is reported with its path and line.

use crate::core::error::{Error, Result};
use std::path::Path;

/// Largest |displacement| a record may hold (10 m: no friction rig moves further).
pub const MAX_DISPLACEMENT_M: f64 = 10.0;
/// Largest |force| a record may hold (10¹² N).
pub const MAX_FORCE_N: f64 = 1e12;

/// Names of the CSV columns to read (units in the names, e.g. `displacement_m`).
#[derive(Debug, Clone)]
pub struct Columns {
    /// Time column (s).
    pub time: String,
    /// Tangential displacement column (m).
    pub displacement: String,
    /// Tangential force column (N).
    pub force: String,
    /// Optional normal force column (N).
    pub normal_force: Option<String>,
    /// The `displacement` column holds the relative acceleration across the joint (m/s²): the
    /// displacement is its double integral in the frequency domain
    /// ([`super::acceleration::displacement_from_acceleration`]).
    pub displacement_is_acceleration: bool,
    /// The `force` column holds the acceleration (m/s²) of a mass (kg) whose inertia is the
    /// joint force: `F = m·a`.
    pub force_mass_kg: Option<f64>,
}

impl Default for Columns {
    fn default() -> Self {
        Self {
            time: "time_s".into(),
            displacement: "displacement_m".into(),
            force: "friction_force_N".into(),
            normal_force: None,
            displacement_is_acceleration: false,
            force_mass_kg: None,
        }
    }
}

impl Columns {
    /// The columns with measured accelerations in place of the displacement and/or force:
    /// `relative_acceleration` (m/s², across the joint) replaces the displacement column,
    /// `inertia_acceleration` (m/s², of a mass `mass_kg` whose inertia is the joint force)
    /// replaces the force column. The acceleration column and its mass come together; errors
    /// name `mass_kg` or `inertia_acceleration_column`.
    pub fn with_accelerations(
        mut self,
        relative_acceleration: Option<String>,
        inertia_acceleration: Option<String>,
        mass_kg: Option<f64>,
    ) -> Result<Self> {
        if let Some(c) = relative_acceleration {
            self.displacement = c;
            self.displacement_is_acceleration = true;
        }
        match (inertia_acceleration, mass_kg) {
            (Some(c), Some(m)) => {
                self.force = c;
                self.force_mass_kg = Some(m);
            }
            (Some(_), None) => {
                return Err(Error::param(
                    "mass_kg",
                    "required with an inertia acceleration column (F = m·a)",
                ))
            }
            (None, Some(_)) => {
                return Err(Error::param(
                    "inertia_acceleration_column",
                    "required with mass_kg (the acceleration whose inertia is the joint force)",
                ))
            }
            (None, None) => {}
        }
        Ok(self)
    }
}

/// Largest |acceleration| an acceleration column may hold (10⁷ m/s², about 10⁶ g).
pub const MAX_ACCELERATION_M_PER_S2: f64 = 1e7;

/// An acceleration column must be in m/s²: a name with a unit suffix says which (`_g` is refused:
/// no column is converted).
fn check_acceleration_unit(path: &Path, name: &str, flag: &str) -> Result<()> {
    let lower = name.to_ascii_lowercase();
    let si = ["m_per_s2", "m_per_s^2", "m_s2", "m_s-2", "mps2"];
    if si.iter().any(|u| lower.ends_with(u)) {
        return Ok(());
    }
    if let Some((_, suffix)) = name.rsplit_once('_') {
        if ["g", "mm_per_s2", "in_per_s2", "ft_per_s2"].contains(&suffix) || lower.ends_with("_g") {
            return Err(Error::param(
                flag,
                format!(
                    "{}: column `{name}` is not in m/s² (no column is converted: write it in m/s²)",
                    path.display()
                ),
            ));
        }
    }
    Ok(())
}

/// A measured (or synthetic) record, SI units, all columns of equal length.
#[derive(Debug, Clone)]
pub struct Record {
    /// Sample times (s), strictly increasing.
    pub time_s: Vec<f64>,
    /// Tangential (drive) displacement (m).
    pub displacement_m: Vec<f64>,
    /// Tangential force (N).
    pub force_n: Vec<f64>,
    /// Normal force (N), when measured.
    pub normal_force_n: Option<Vec<f64>>,
    /// How columns were derived from what was measured (e.g. a displacement integrated from an
    /// acceleration), one line each; empty when every column was read as it is.
    pub derived: Vec<String>,
}

impl Record {
    /// Build a record, checking lengths, finiteness and monotonic time.
    pub fn new(
        time_s: Vec<f64>,
        displacement_m: Vec<f64>,
        force_n: Vec<f64>,
        normal_force_n: Option<Vec<f64>>,
    ) -> Result<Self> {
        let n = time_s.len();
        let mut lens = vec![
            ("displacement", displacement_m.len()),
            ("force", force_n.len()),
        ];
        if let Some(nf) = &normal_force_n {
            lens.push(("normal force", nf.len()));
        }
        for (name, len) in lens {
            if len != n {
                return Err(Error::Data(format!(
                    "record columns have mismatched lengths: time has {n} samples, {name} has {len}"
                )));
            }
        }
        if n < 8 {
            return Err(Error::Data(format!(
                "record has {n} samples; at least 8 are needed"
            )));
        }
        let all = [
            ("time", &time_s),
            ("displacement", &displacement_m),
            ("force", &force_n),
        ];
        for (name, col) in all {
            if let Some(i) = col.iter().position(|v| !v.is_finite()) {
                return Err(Error::Data(format!(
                    "record {name} sample {i} is not finite ({})",
                    col[i]
                )));
            }
        }
        if let Some(nf) = &normal_force_n {
            if let Some(i) = nf.iter().position(|v| !v.is_finite() || *v <= 0.0) {
                return Err(Error::Data(format!(
                    "record normal force sample {i} must be finite and > 0, got {}",
                    nf[i]
                )));
            }
        }
        if let Some(i) = time_s.windows(2).position(|w| w[1] <= w[0]) {
            return Err(Error::Data(format!(
                "record time is not strictly increasing at sample {}: {} after {}",
                i + 1,
                time_s[i + 1],
                time_s[i]
            )));
        }
        Ok(Self {
            time_s,
            displacement_m,
            force_n,
            normal_force_n,
            derived: Vec::new(),
        })
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.time_s.len()
    }

    /// Whether the record is empty (never true for a record built by [`Record::new`]).
    pub fn is_empty(&self) -> bool {
        self.time_s.is_empty()
    }

    /// Drive velocity (m/s) by central differences (one-sided at the ends).
    pub fn velocity(&self) -> Vec<f64> {
        let (t, x) = (&self.time_s, &self.displacement_m);
        let n = t.len();
        (0..n)
            .map(|i| {
                let (a, b) = (i.saturating_sub(1), (i + 1).min(n - 1));
                (x[b] - x[a]) / (t[b] - t[a])
            })
            .collect()
    }

    /// Read the chosen columns of a CSV file (header row with column names, then numbers).
    /// Errors name the file and line: non-numbers, non-finite values, time not increasing, a
    /// normal force ≤ 0, and magnitudes no instrument records (|x| > [`MAX_DISPLACEMENT_M`],
    /// |F| > [`MAX_FORCE_N`]: a unit or format error).
    pub fn read_csv(path: &Path, columns: &Columns) -> Result<Self> {
        crate::core::limits::check_file_size(path, crate::core::limits::MAX_TEXT_FILE_BYTES)?;
        let mut rdr = crate::core::input::csv_reader_any_length(path)?;
        let headers = rdr
            .headers()
            .map_err(|e| Error::parse(path, 1, e.to_string()))?
            .clone();
        let find = |name: &str| -> Result<usize> {
            headers.iter().position(|h| h == name).ok_or_else(|| {
                Error::parse(
                    path,
                    1,
                    format!(
                        "no column `{name}` in header (columns: {})",
                        headers.iter().collect::<Vec<_>>().join(", ")
                    ),
                )
            })
        };
        let it = find(&columns.time)?;
        let ix = find(&columns.displacement)?;
        let iff = find(&columns.force)?;
        let inf = columns.normal_force.as_deref().map(find).transpose()?;
        let (x_flag, x_unit, x_max) = if columns.displacement_is_acceleration {
            (
                "--relative-acceleration-column",
                "m/s²",
                MAX_ACCELERATION_M_PER_S2,
            )
        } else {
            ("--displacement-column", "m", MAX_DISPLACEMENT_M)
        };
        let (f_flag, f_unit, f_max) = if columns.force_mass_kg.is_some() {
            (
                "--inertia-acceleration-column",
                "m/s²",
                MAX_ACCELERATION_M_PER_S2,
            )
        } else {
            ("--force-column", "N", MAX_FORCE_N)
        };
        let roles = [
            (Some(&columns.time), "--time-column", "s"),
            (Some(&columns.displacement), x_flag, x_unit),
            (Some(&columns.force), f_flag, f_unit),
            (columns.normal_force.as_ref(), "--normal-force-column", "N"),
        ];
        if let Some(m) = columns.force_mass_kg {
            crate::core::error::require_positive("--mass-kg", m)?;
        }
        for (k, (name, flag, unit)) in roles.iter().enumerate() {
            let Some(name) = name else { continue };
            if *unit == "m/s²" {
                check_acceleration_unit(path, name, flag)?;
            } else {
                check_column_unit(path, name, flag, unit)?;
            }
            if let Some((_, other, _)) = roles[..k]
                .iter()
                .find(|(n, _, _)| n.is_some_and(|n| n == *name))
            {
                return Err(Error::param(
                    *flag,
                    format!(
                        "{}: column `{name}` is already read by {other}",
                        path.display()
                    ),
                ));
            }
        }
        let (mut t, mut x, mut f) = (Vec::new(), Vec::new(), Vec::new());
        let mut nf = inf.map(|_| Vec::new());
        let mut lines: Vec<usize> = Vec::new();
        for rec in rdr.records() {
            let (rec, line) = crate::core::input::csv_record(path, rec)?;
            if rec.len() != headers.len() {
                return Err(Error::parse(
                    path,
                    line,
                    format!(
                        "row has {} fields but the header has {} (mismatched column lengths)",
                        rec.len(),
                        headers.len()
                    ),
                ));
            }
            let get = |i: usize, name: &str| -> Result<f64> {
                let s = &rec[i];
                let v: f64 = s.parse().map_err(|_| {
                    Error::parse(
                        path,
                        line,
                        format!("column `{name}`: `{s}` is not a number"),
                    )
                })?;
                if v.is_finite() {
                    Ok(v)
                } else {
                    Err(Error::parse(
                        path,
                        line,
                        format!("column `{name}`: value {v} is not finite"),
                    ))
                }
            };
            let bounded = |i: usize, name: &str, max: f64, unit: &str| -> Result<f64> {
                let v = get(i, name)?;
                if v.abs() > max {
                    return Err(Error::parse(
                        path,
                        line,
                        format!(
                            "column `{name}`: {} exceeds {} {unit} in magnitude (a unit or \
                             format error)",
                            crate::core::error::num(v),
                            crate::core::error::num(max)
                        ),
                    ));
                }
                Ok(v)
            };
            let time = get(it, &columns.time)?;
            if let Some(&prev) = t.last() {
                if time <= prev {
                    return Err(Error::parse(
                        path,
                        line,
                        format!(
                            "column `{}`: time {} does not increase (previous row: {})",
                            columns.time,
                            crate::core::error::num(time),
                            crate::core::error::num(prev)
                        ),
                    ));
                }
            }
            t.push(time);
            x.push(bounded(ix, &columns.displacement, x_max, x_unit)?);
            f.push(bounded(iff, &columns.force, f_max, f_unit)?);
            if let (Some(i), Some(v)) = (inf, nf.as_mut()) {
                let name = columns.normal_force.as_deref().unwrap_or("");
                let n = bounded(i, name, MAX_FORCE_N, "N")?;
                if n <= 0.0 {
                    return Err(Error::parse(
                        path,
                        line,
                        format!(
                            "column `{name}`: a normal force must be > 0, got {}",
                            crate::core::error::num(n)
                        ),
                    ));
                }
                v.push(n);
            }
            lines.push(line);
        }
        check_uniform_sampling(path, &columns.time, &t, &lines)?;
        let mut derived = Vec::new();
        if columns.displacement_is_acceleration {
            let r = super::acceleration::displacement_from_acceleration(&t, &x, x_flag).map_err(
                |e| match e {
                    Error::InvalidParameter { name, message } => Error::InvalidParameter {
                        name,
                        message: format!(
                            "{}: column `{}`: {message}",
                            path.display(),
                            columns.displacement
                        ),
                    },
                    other => other,
                },
            )?;
            derived.push(r.describe(&columns.displacement));
            x = r.displacement_m;
        }
        if let Some(m) = columns.force_mass_kg {
            for v in &mut f {
                *v *= m;
            }
            derived.push(format!(
                "force = {} kg × `{}` (m/s²): the joint force from the inertia of the mass",
                crate::core::error::num(m),
                columns.force
            ));
        }
        let mut record = Record::new(t, x, f, nf).map_err(|e| match e {
            Error::Data(m) => Error::parse(path, 0, m),
            other => other,
        })?;
        record.derived = derived;
        check_dissipation(path, &columns.force, &record)?;
        Ok(record)
    }
}

/// A negative loop area counts as a reversed sign once it exceeds this fraction of the
/// loop's bounding box ΔF·Δx per cycle: a nearly elastic record's ∮F dx is noise-sized and
/// may take either sign, a friction loop with its force negated is clearly negative (a
/// Jenkins loop's area is up to the whole box).
pub const REVERSED_LOOP_FRACTION: f64 = 0.01;

/// Refuse a record whose loops, taken over the complete cycles, generate energy
/// (∮F dx < 0): the force column's sign convention is the reverse of the element's.
/// Records without a complete cycle are left to the analysis, which reports them.
fn check_dissipation(path: &Path, force_column: &str, record: &Record) -> Result<()> {
    let (x, f) = (&record.displacement_m, &record.force_n);
    let Ok(cycles) = super::cycles::segment(&record.time_s, x) else {
        return Ok(());
    };
    let range = |v: &[f64]| {
        let (lo, hi) = v
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &y| {
                (a.min(y), b.max(y))
            });
        hi - lo
    };
    let area = super::cycles::energy_per_cycle(x, f, &cycles);
    if area < -REVERSED_LOOP_FRACTION * range(f) * range(x) {
        return Err(Error::parse(
            path,
            0,
            format!(
                "column `{force_column}`: force sign convention reversed? (∮F dx = {area:.4e} J \
                 per cycle over {} complete cycle(s)); a friction loop dissipates energy, \
                 ∮F dx > 0: the force must have the sign of the displacement in slip \
                 (negate the column)",
                cycles.cycles.len()
            ),
        ));
    }
    Ok(())
}

/// Largest time step a record may hold, as a multiple of its median step. The analysis
/// (smoothing, block averaging, phases, the noise floor) works on sample indices and assumes
/// uniform sampling; a DAQ's clock jitter stays within a few per cent of the step, so a step
/// 1.5× the median means samples are missing (one dropped sample doubles the step).
pub const MAX_TIME_STEP_OVER_MEDIAN: f64 = 1.5;

/// Refuse a record with a gap in time (a step larger than [`MAX_TIME_STEP_OVER_MEDIAN`] × the
/// median step), naming the line of the sample after the gap and the two times.
fn check_uniform_sampling(path: &Path, column: &str, t: &[f64], lines: &[usize]) -> Result<()> {
    if t.len() < 3 {
        return Ok(());
    }
    let steps: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    let median = crate::core::stats::median(&steps);
    let (i, &largest) = steps
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))
        .expect("at least two steps");
    if largest > MAX_TIME_STEP_OVER_MEDIAN * median {
        return Err(Error::parse(
            path,
            lines[i + 1],
            format!(
                "column `{column}`: time jumps from {} s to {} s, a step {:.1}× the median step \
                 {median:.4e} s (more than {MAX_TIME_STEP_OVER_MEDIAN}×): samples are missing, \
                 and the analysis needs uniform sampling",
                crate::core::error::num(t[i]),
                crate::core::error::num(t[i + 1]),
                largest / median,
            ),
        ));
    }
    Ok(())
}

/// A column named with a unit suffix (`_s`, `_ms`, `_m`, `_mm`, `_um`, `_in`, `_ft`, `_N`, `_kN`,
/// `_kip`, `_lbf`, `_g`, `_V`, …) must carry the unit its role reads in (SI, no scaling is
/// applied): a displacement column given as the
/// force would otherwise be read as newtons. Names without a recognised suffix are taken as
/// given.
fn check_column_unit(path: &Path, name: &str, flag: &str, unit: &str) -> Result<()> {
    // Units a rig's CSV may carry; none is converted, so each must be the role's SI unit.
    const SUFFIXES: [&str; 37] = [
        // time
        "s", "ms", "us", "µs", "ns", "min", // length
        "m", "mm", "um", "µm", "nm", "cm", "km", "in", "inch", "inches", "ft", "mil",
        // force, mass, acceleration
        "N", "kN", "MN", "mN", "uN", "µN", "lb", "lbs", "lbf", "kip", "kips", "kgf", "ozf", "kg",
        "g", // raw transducer signals
        "V", "mV", "uV", "counts",
    ];
    if let Some((quantity, per)) = name.split_once("_per_") {
        // A rate (velocity `m_per_s`, …): no role of a record is one.
        let unit_from = quantity.rsplit_once('_').map_or(quantity, |(_, u)| u);
        return Err(Error::param(
            flag,
            format!(
                "{}: column `{name}` is in {unit_from}/{per}, this column must be in {unit}",
                path.display()
            ),
        ));
    }
    let Some((_, suffix)) = name.rsplit_once('_') else {
        return Ok(());
    };
    if SUFFIXES.contains(&suffix) && suffix != unit {
        return Err(Error::param(
            flag,
            format!(
                "{}: column `{name}` is in {suffix}, this column must be in {unit}",
                path.display()
            ),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_column_in_the_wrong_unit_or_read_twice_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("r.csv");
        let mut s = String::from("time_s,displacement_m,friction_force_N,velocity_m_per_s\n");
        for i in 0..10 {
            s += &format!("{},{},{},0.0\n", 0.1 * i as f64, 1e-6 * i as f64, i as f64);
        }
        std::fs::write(&p, s).unwrap();
        let read = |force: &str, displacement: &str| {
            Record::read_csv(
                &p,
                &Columns {
                    force: force.into(),
                    displacement: displacement.into(),
                    ..Columns::default()
                },
            )
            .map(|_| ())
            .map_err(|e| e.to_string())
        };
        assert!(read("friction_force_N", "displacement_m").is_ok());
        let e = read("displacement_m", "displacement_m").unwrap_err();
        assert!(e.contains("--force-column") && e.contains("in m"), "{e}");
        let e = read("friction_force_N", "velocity_m_per_s").unwrap_err();
        assert!(
            e.contains("--displacement-column") && e.contains("m/s") && e.contains("r.csv"),
            "{e}"
        );
        let e = read("friction_force_N", "friction_force_N").unwrap_err();
        assert!(e.contains("in N, this column must be in m"), "{e}");
    }

    /// Rows `t, x, F` of a Jenkins element (stiffness 2e6 N/m, slip force 100 N) driven by
    /// x = 1 mm·sin(2πt), 200 samples per cycle, for `cycles` cycles.
    fn jenkins_rows(cycles: f64) -> Vec<(f64, f64, f64)> {
        let (k, fs, a) = (2e6, 100.0, 1e-3);
        let n = (cycles * 200.0) as usize + 1;
        let mut f = 0.0_f64;
        let mut x_prev = 0.0;
        (0..n)
            .map(|i| {
                let t = i as f64 / 200.0;
                let x = a * (std::f64::consts::TAU * t).sin();
                f = (f + k * (x - x_prev)).clamp(-fs, fs);
                x_prev = x;
                (t, x, f)
            })
            .collect()
    }

    fn write_rows(p: &Path, header: &str, rows: &[(f64, f64, f64)]) {
        let mut s = format!("{header}\n");
        for (t, x, f) in rows {
            s += &format!("{t},{x},{f}\n");
        }
        std::fs::write(p, s).unwrap();
    }

    /// Uniform sampling is assumed by the analysis: 60 samples removed from a 200 Hz record
    /// leave a 0.305 s step (61 × 5 ms) between 1.495 s and 1.8 s; the record is refused at the
    /// line after the gap. Clock jitter of ±2 % of the step is not a gap.
    #[test]
    fn a_gap_in_time_is_refused_with_its_line_and_times() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("gap.csv");
        let rows = jenkins_rows(6.5);
        let mut gapped = rows[..300].to_vec();
        gapped.extend_from_slice(&rows[360..]);
        write_rows(&p, "time_s,displacement_m,friction_force_N", &gapped);
        let e = Record::read_csv(&p, &Columns::default())
            .unwrap_err()
            .to_string();
        // Header is line 1: row 300 (the first after the gap) is line 302.
        assert!(e.contains("gap.csv:302"), "{e}");
        assert!(
            e.contains("1.495 s to 1.8 s") && e.contains("time_s"),
            "{e}"
        );
        assert!(e.contains("61.0×"), "{e}");
        let jittered: Vec<(f64, f64, f64)> = rows
            .iter()
            .enumerate()
            .map(|(i, &(t, x, f))| (t + 1e-4 * if i % 2 == 0 { 1.0 } else { -1.0 }, x, f))
            .collect();
        write_rows(&p, "time_s,displacement_m,friction_force_N", &jittered);
        assert!(Record::read_csv(&p, &Columns::default()).is_ok());
    }

    /// A Jenkins loop dissipates 4·Fs·(A − Fs/k) = 4·100·(1e-3 − 5e-5) = 0.38 J per cycle; with
    /// the force negated ∮F dx = −0.38 J and the record is refused, naming file and column. A
    /// purely elastic record (∮F dx = 0 up to rounding) is not refused here.
    #[test]
    fn a_loop_that_generates_energy_is_refused_as_a_reversed_sign() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("neg.csv");
        let rows = jenkins_rows(6.5);
        let header = "time_s,displacement_m,friction_force_N";
        write_rows(&p, header, &rows);
        let r = Record::read_csv(&p, &Columns::default()).unwrap();
        let c = crate::diagnose::cycles::segment(&r.time_s, &r.displacement_m).unwrap();
        let area = crate::diagnose::cycles::energy_per_cycle(&r.displacement_m, &r.force_n, &c);
        assert!((area - 0.38).abs() < 0.01 * 0.38, "{area}");
        let negated: Vec<_> = rows.iter().map(|&(t, x, f)| (t, x, -f)).collect();
        write_rows(&p, header, &negated);
        let e = Record::read_csv(&p, &Columns::default())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("neg.csv")
                && e.contains("`friction_force_N`")
                && e.contains("force sign convention reversed? (∮F dx = ")
                && e.contains("J per cycle"),
            "{e}"
        );
        let reported: f64 = e
            .split("∮F dx = ")
            .nth(1)
            .and_then(|s| s.split(' ').next())
            .and_then(|s| s.parse().ok())
            .unwrap();
        assert!((reported + 0.38).abs() < 0.01 * 0.38, "{reported}");
        let elastic: Vec<_> = rows.iter().map(|&(t, x, _)| (t, x, -2e4 * x)).collect();
        write_rows(&p, header, &elastic);
        assert!(Record::read_csv(&p, &Columns::default()).is_ok());
    }

    /// Inches, kips, pounds, grams, volts, minutes are not converted: a column named in one of
    /// them is refused, naming the column and the unit the role needs (m for the displacement,
    /// N for the force, s for the time).
    #[test]
    fn a_column_in_a_non_si_unit_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("imperial.csv");
        let names = [
            "time_s",
            "time_min",
            "displacement_m",
            "displacement_in",
            "displacement_ft",
            "friction_force_N",
            "friction_force_kip",
            "friction_force_lb",
            "friction_force_g",
            "friction_force_V",
            "friction_force_mV",
        ];
        let mut s = names.join(",") + "\n";
        for (t, x, f) in jenkins_rows(3.0) {
            let row = [t, t / 60.0, x, x / 0.0254, x / 0.3048, f];
            let mut v: Vec<String> = row.iter().map(|v| v.to_string()).collect();
            v.extend(std::iter::repeat_n(f.to_string(), 5));
            s += &(v.join(",") + "\n");
        }
        std::fs::write(&p, s).unwrap();
        let read = |time: &str, displacement: &str, force: &str| {
            Record::read_csv(
                &p,
                &Columns {
                    time: time.into(),
                    displacement: displacement.into(),
                    force: force.into(),
                    ..Columns::default()
                },
            )
            .map(|_| ())
            .map_err(|e| e.to_string())
        };
        assert!(read("time_s", "displacement_m", "friction_force_N").is_ok());
        for (t, x, f, flag, column, unit) in [
            (
                "time_min",
                "displacement_m",
                "friction_force_N",
                "--time-column",
                "time_min",
                "s",
            ),
            (
                "time_s",
                "displacement_in",
                "friction_force_N",
                "--displacement-column",
                "displacement_in",
                "m",
            ),
            (
                "time_s",
                "displacement_ft",
                "friction_force_N",
                "--displacement-column",
                "displacement_ft",
                "m",
            ),
            (
                "time_s",
                "displacement_m",
                "friction_force_kip",
                "--force-column",
                "friction_force_kip",
                "N",
            ),
            (
                "time_s",
                "displacement_m",
                "friction_force_lb",
                "--force-column",
                "friction_force_lb",
                "N",
            ),
            (
                "time_s",
                "displacement_m",
                "friction_force_g",
                "--force-column",
                "friction_force_g",
                "N",
            ),
            (
                "time_s",
                "displacement_m",
                "friction_force_V",
                "--force-column",
                "friction_force_V",
                "N",
            ),
            (
                "time_s",
                "displacement_m",
                "friction_force_mV",
                "--force-column",
                "friction_force_mV",
                "N",
            ),
        ] {
            let e = read(t, x, f).unwrap_err();
            assert!(
                e.contains(flag)
                    && e.contains(&format!("`{column}`"))
                    && e.contains(&format!("must be in {unit}"))
                    && e.contains("imperial.csv"),
                "{e}"
            );
        }
    }

    #[test]
    fn reads_named_columns_in_any_order() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("r.csv");
        let mut s = String::from("friction_force_N,time_s,displacement_m\n");
        for i in 0..10 {
            s += &format!(
                "{},{},{}\n",
                2.0 * i as f64,
                0.1 * i as f64,
                1e-3 * i as f64
            );
        }
        std::fs::write(&p, s).unwrap();
        let r = Record::read_csv(&p, &Columns::default()).unwrap();
        assert_eq!(r.len(), 10);
        assert_eq!(r.force_n[3], 6.0);
        assert!((r.velocity()[4] - 1e-2).abs() < 1e-12);
    }

    #[test]
    fn short_row_is_reported_with_its_line() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("r.csv");
        let mut s = String::from("time_s,displacement_m,friction_force_N\n");
        for i in 0..10 {
            s += &format!("{},{},{}\n", i, i, i);
        }
        s += "10,10\n";
        std::fs::write(&p, s).unwrap();
        let e = Record::read_csv(&p, &Columns::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("r.csv:12"), "{e}");
        assert!(e.contains("mismatched"), "{e}");
    }

    #[test]
    fn mismatched_lengths_and_time_order_rejected() {
        let t: Vec<f64> = (0..10).map(f64::from).collect();
        let e = Record::new(t.clone(), t.clone(), t[..9].to_vec(), None).unwrap_err();
        assert!(e.to_string().contains("mismatched"));
        let mut t2 = t.clone();
        t2[5] = 3.0;
        assert!(Record::new(t2, t.clone(), t.clone(), None).is_err());
        let e = Record::read_csv(Path::new("/nonexistent/x.csv"), &Columns::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("/nonexistent/x.csv"), "{e}");
    }
}
