//! Calibration table: Valanis element parameters per unit nominal area versus nominal pressure.
//!
//! # File format
//!
//! A CSV file with these columns, in this order (units in the names, SI):
//!
//! ```text
//! pressure_Pa,contact_area_ratio,kn_N_per_m3,E0_N_per_m3,k,mu,Et_N_per_m3,fit_R2,energy_per_cycle_J_per_m2
//! ```
//!
//! one row per nominal pressure, pressures strictly increasing and positive. `kn` is the normal
//! contact stiffness per unit area `dp/dδ` (N/m³), `E0`, `Et` the Valanis stiffnesses per unit area
//! (N/m³), `k` the Valanis shape parameter, `mu` the friction coefficient, `fit_R2` the coefficient
//! of determination of the Valanis fit against the BEM loops, `energy_per_cycle_J_per_m2` the
//! energy the BEM loop dissipates per cycle per unit nominal area (in a calibration over several
//! amplitudes: at the largest).
//!
//! A table computed over several realisations (random surfaces of the same statistics) holds
//! their **means** in these columns and carries, after them, the number of realisations and the
//! half-widths of the 95 % confidence intervals of the means ([`INTERVAL_COLUMNS`];
//! [`crate::calibrate::statistics`]):
//!
//! ```text
//! ...,energy_per_cycle_J_per_m2,realisations,contact_area_ratio_ci95,kn_ci95_N_per_m3,E0_ci95_N_per_m3,k_ci95,Et_ci95_N_per_m3,energy_per_cycle_ci95_J_per_m2
//! ```
//!
//! A table written by `asperity calibrate` ends with one more column, `convergence`: the worse
//! of the row's grid and patch-size verdicts ([`crate::calibrate::convergence`]: `converged`,
//! `undetermined`, `not-converged`, `not-checked`), so that a row the calibration itself did not
//! trust is known wherever the table goes (`asperity elements` counts the elements resting on
//! such rows).
//!
//! Lines starting with `#` before the header are comments: a table from `asperity calibrate` says
//! there which normal stiffness `kn` is ([`kn_comment`]): the elastic contact stiffness, or, with
//! a hardness, the unloading/reloading stiffness about the plastically deformed state (the
//! stiffness an element carries; the loading tangent is smaller). They are read back with the
//! table ([`CalibrationTable::comments`]).
//!
//! [`CalibrationTable::read_csv`] reads every form; interpolation uses the means.
//!
//! # Interpolation
//!
//! [`CalibrationTable::interpolate`] interpolates every column with the monotone piecewise-cubic
//! Hermite scheme of Fritsch & Carlson (1980, *SIAM J. Numer. Anal.* 17:238) in `ln p`: it passes
//! through the rows, is C¹, and never overshoots: where a column is monotonic in the data it is
//! monotonic in between, and it stays within the range of the two neighbouring rows.
//!
//! **Outside the table's range** the stiffnesses follow the power law of the two end rows, the
//! form rough-surface contact stiffness takes over decades of pressure (`kn ∝ p^m`, `m` about 1
//! in Persson's theory and 0.8–0.95 in Greenwood–Williamson's; Pohrt & Popov 2012,
//! *Phys. Rev. Lett.* 108:104301, for the Boussinesq BEM): `v(p) = v_end·(p/p_end)^m` with
//! `m = ln(v₂/v₁)/ln(p₂/p₁)` from the end pair, for `kn`, `E0` and the contact area ratio (at most
//! 1); `Et` keeps the end row's ratio `Et/E0`, and the shape `k` and `μ` keep the end row's values.
//! A column whose end values are not both positive, or that falls with pressure at that end
//! (`m < 0`, not a contact stiffness), keeps its end value. So a node below the table is softer
//! than the first row, not as stiff (at the low end of the reference table `kn ∝ p^0.62`: clamped
//! to the first row, a node at 10 kPa would be 4.1× too stiff), and a zero pressure — an open
//! contact — gives zero stiffness. The result is flagged ([`RangeFlag::Below`] /
//! [`RangeFlag::Above`], `in_range = false`) so that the caller can count and report the nodes
//! concerned: no BEM loop was computed there. A negative pressure reads as zero, NaN gives NaN.

use crate::calibrate::convergence::Verdict;
use crate::core::error::{Error, Result};
use crate::core::output::write_atomic;
use crate::element::ContactParamsPerArea;
use std::path::Path;

/// The CSV header, exactly.
pub const COLUMNS: [&str; 9] = [
    "pressure_Pa",
    "contact_area_ratio",
    "kn_N_per_m3",
    "E0_N_per_m3",
    "k",
    "mu",
    "Et_N_per_m3",
    "fit_R2",
    "energy_per_cycle_J_per_m2",
];

/// The columns after [`COLUMNS`] in a table over several realisations.
pub const INTERVAL_COLUMNS: [&str; 7] = [
    "realisations",
    "contact_area_ratio_ci95",
    "kn_ci95_N_per_m3",
    "E0_ci95_N_per_m3",
    "k_ci95",
    "Et_ci95_N_per_m3",
    "energy_per_cycle_ci95_J_per_m2",
];

/// The last column of a table written by `asperity calibrate`: the row's convergence verdict.
pub const CONVERGENCE_COLUMN: &str = "convergence";

/// Realisation count and 95 % interval half-widths of one row's means (same units as the row).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RowInterval {
    /// Realisations the means are taken over (≥ 2).
    pub realisations: usize,
    /// Half-width of the contact area ratio's interval (dimensionless).
    pub contact_area_ratio: f64,
    /// Half-width of `kn`'s interval (N/m³).
    pub kn_n_per_m3: f64,
    /// Half-width of `E0`'s interval (N/m³).
    pub e0_n_per_m3: f64,
    /// Half-width of `k`'s interval (dimensionless).
    pub k: f64,
    /// Half-width of `Et`'s interval (N/m³).
    pub et_n_per_m3: f64,
    /// Half-width of the energy per cycle's interval (J/m²).
    pub energy_per_cycle_j_per_m2: f64,
}

impl RowInterval {
    fn values(&self) -> [f64; 7] {
        [
            self.realisations as f64,
            self.contact_area_ratio,
            self.kn_n_per_m3,
            self.e0_n_per_m3,
            self.k,
            self.et_n_per_m3,
            self.energy_per_cycle_j_per_m2,
        ]
    }

    fn from_values(v: [f64; 7]) -> std::result::Result<Self, String> {
        if !(v[0].fract() == 0.0 && v[0] >= 2.0) {
            return Err(format!(
                "`realisations` must be an integer >= 2, got {}",
                v[0]
            ));
        }
        for (name, x) in INTERVAL_COLUMNS.iter().zip(v).skip(1) {
            if !(x.is_finite() && x >= 0.0) {
                return Err(format!("`{name}` must be finite and >= 0, got {x}"));
            }
        }
        Ok(Self {
            realisations: v[0] as usize,
            contact_area_ratio: v[1],
            kn_n_per_m3: v[2],
            e0_n_per_m3: v[3],
            k: v[4],
            et_n_per_m3: v[5],
            energy_per_cycle_j_per_m2: v[6],
        })
    }
}

/// One row of the calibration table (per unit nominal area, SI).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CalibrationRow {
    /// Nominal (mean) contact pressure (Pa).
    pub pressure_pa: f64,
    /// Real over nominal contact area (–).
    pub contact_area_ratio: f64,
    /// kn, E0, k, μ, Et per unit area (N/m³).
    #[serde(flatten)]
    pub element: ContactParamsPerArea,
    /// Coefficient of determination of the fit (–).
    pub fit_r2: f64,
    /// Energy dissipated per cycle by the BEM loop, per unit nominal area (J/m²).
    pub energy_per_cycle_j_per_m2: f64,
}

impl CalibrationRow {
    fn values(&self) -> [f64; 9] {
        [
            self.pressure_pa,
            self.contact_area_ratio,
            self.element.kn_n_per_m3,
            self.element.e0_n_per_m3,
            self.element.k,
            self.element.mu,
            self.element.et_n_per_m3,
            self.fit_r2,
            self.energy_per_cycle_j_per_m2,
        ]
    }

    fn from_values(v: [f64; 9]) -> Self {
        Self {
            pressure_pa: v[0],
            contact_area_ratio: v[1],
            element: ContactParamsPerArea {
                kn_n_per_m3: v[2],
                e0_n_per_m3: v[3],
                k: v[4],
                mu: v[5],
                et_n_per_m3: v[6],
            },
            fit_r2: v[7],
            energy_per_cycle_j_per_m2: v[8],
        }
    }

    /// Physical admissibility of one row; the message names the offending column.
    fn check(&self) -> std::result::Result<(), String> {
        for (name, v) in COLUMNS.iter().zip(self.values()) {
            if !v.is_finite() {
                return Err(format!("`{name}` is not a finite number ({v})"));
            }
        }
        let positive = [
            ("pressure_Pa", self.pressure_pa),
            ("kn_N_per_m3", self.element.kn_n_per_m3),
            ("E0_N_per_m3", self.element.e0_n_per_m3),
            ("mu", self.element.mu),
        ];
        for (name, v) in positive {
            if v <= 0.0 {
                return Err(format!("`{name}` must be > 0, got {v}"));
            }
        }
        let e = &self.element;
        if !(0.0..1.0).contains(&e.k) {
            return Err(format!("`k` must satisfy 0 <= k < 1, got {}", e.k));
        }
        if !(0.0..=1.0).contains(&self.contact_area_ratio) {
            return Err(format!(
                "`contact_area_ratio` must be in [0, 1], got {}",
                self.contact_area_ratio
            ));
        }
        if e.et_n_per_m3 < 0.0 || e.et_n_per_m3 >= e.e0_n_per_m3 {
            return Err(format!(
                "`Et_N_per_m3` must satisfy 0 <= Et < E0 = {}, got {}",
                e.e0_n_per_m3, e.et_n_per_m3
            ));
        }
        // R² = 1 − SS_res/SS_tot with SS_res ≥ 0: a coefficient of determination above 1 is
        // not the result of any fit (a hand-edited or corrupted table).
        if self.fit_r2 > 1.0 {
            return Err(format!(
                "`fit_R2` must be <= 1 (a coefficient of determination), got {}",
                self.fit_r2
            ));
        }
        if self.energy_per_cycle_j_per_m2 < 0.0 {
            return Err(format!(
                "`energy_per_cycle_J_per_m2` must be >= 0, got {}",
                self.energy_per_cycle_j_per_m2
            ));
        }
        Ok(())
    }
}

/// Where a queried pressure lies relative to the table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum RangeFlag {
    /// Below the first row (or non-positive / NaN): the first pair's power law.
    Below,
    /// Within `[p_first, p_last]`: interpolated.
    Within,
    /// Above the last row: the last pair's power law.
    Above,
}

/// Element parameters at one pressure, interpolated from a [`CalibrationTable`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Interpolated {
    /// The queried pressure (Pa).
    pub pressure_pa: f64,
    /// Real over nominal contact area (–).
    pub contact_area_ratio: f64,
    /// kn, E0, k, μ, Et per unit area (N/m³).
    pub element: ContactParamsPerArea,
    /// True when the pressure lies within the table's range (values interpolated, not
    /// extrapolated).
    pub in_range: bool,
    /// Which side of the table the pressure fell on.
    pub range: RangeFlag,
}

/// The calibration table: rows sorted by strictly increasing pressure.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct CalibrationTable {
    /// The rows (means over the realisations when `intervals` is present).
    pub rows: Vec<CalibrationRow>,
    /// Per row: realisation count and 95 % intervals of the means (tables over several
    /// realisations), or `None`.
    pub intervals: Option<Vec<RowInterval>>,
    /// Per row: the worse of its grid and patch-size convergence verdicts, or `None` (a table
    /// written without them).
    pub convergence: Option<Vec<Verdict>>,
    /// Comment lines written before the header (without the leading `# `), e.g. what kn is.
    pub comments: Vec<String>,
}

/// The comment that says which normal stiffness the `kn_N_per_m3` column holds: with a hardness
/// H (Pa), the unloading/reloading stiffness about the plastically deformed state; without, the
/// elastic contact stiffness.
pub fn kn_comment(hardness_pa: Option<f64>) -> String {
    match hardness_pa {
        Some(h) => format!(
            "kn_N_per_m3 = unloading/reloading stiffness about the plastically deformed state \
             (hardness_Pa = {h:e}, elastic-perfectly plastic contact, pressure <= H; the loading \
             tangent is smaller); tangential loops on the hardness-limited pressure"
        ),
        None => "kn_N_per_m3 = elastic contact stiffness dp/d(approach) (no hardness: elastic \
                 contact)"
            .to_string(),
    }
}

impl CalibrationTable {
    /// Build from rows, checking each row and the pressure ordering.
    pub fn new(rows: Vec<CalibrationRow>) -> Result<Self> {
        let table = Self {
            rows,
            intervals: None,
            convergence: None,
            comments: Vec::new(),
        };
        table.validate()?;
        Ok(table)
    }

    /// The table with a convergence verdict per row.
    pub fn with_convergence(mut self, verdicts: Vec<Verdict>) -> Result<Self> {
        if verdicts.len() != self.rows.len() {
            return Err(Error::param(
                "convergence",
                format!("{} verdicts for {} rows", verdicts.len(), self.rows.len()),
            ));
        }
        self.convergence = Some(verdicts);
        Ok(self)
    }

    /// The table with these comment lines before its header (each one line, without `#`).
    pub fn with_comments(mut self, comments: Vec<String>) -> Result<Self> {
        if let Some(c) = comments.iter().find(|c| c.contains(['\n', '\r'])) {
            return Err(Error::param(
                "comments",
                format!("a comment must be one line, got {c:?}"),
            ));
        }
        self.comments = comments;
        Ok(self)
    }

    /// The worst convergence verdict of the rows a value at `pressure_pa` is taken from: the row
    /// itself at a tabulated pressure, the two neighbours between rows, the end pair outside
    /// (its power law). `None` for a table without verdicts.
    pub fn convergence_at(&self, pressure_pa: f64) -> Option<Verdict> {
        let verdicts = self.convergence.as_ref()?;
        let n = self.rows.len();
        let used = match self.rows.iter().position(|r| r.pressure_pa >= pressure_pa) {
            Some(i) if self.rows[i].pressure_pa == pressure_pa => i..i + 1,
            Some(0) => 0..n.min(2),
            Some(i) => i - 1..i + 1,
            None => n.saturating_sub(2)..n,
        };
        Some(Verdict::worst(verdicts[used].iter().copied()))
    }

    /// Build from rows of means and their intervals (one per row).
    pub fn with_intervals(rows: Vec<CalibrationRow>, intervals: Vec<RowInterval>) -> Result<Self> {
        if intervals.len() != rows.len() {
            return Err(Error::param(
                "intervals",
                format!("{} intervals for {} rows", intervals.len(), rows.len()),
            ));
        }
        for (i, iv) in intervals.iter().enumerate() {
            RowInterval::from_values(iv.values())
                .map_err(|m| Error::param(format!("intervals[{i}]"), m))?;
        }
        let table = Self {
            rows,
            intervals: Some(intervals),
            convergence: None,
            comments: Vec::new(),
        };
        table.validate()?;
        Ok(table)
    }

    /// Check every row (finite, physical) and that pressures strictly increase.
    pub fn validate(&self) -> Result<()> {
        if self.rows.is_empty() {
            return Err(Error::Data("calibration table has no rows".into()));
        }
        for (i, r) in self.rows.iter().enumerate() {
            r.check()
                .map_err(|m| Error::param(format!("rows[{i}]"), m))?;
            if i > 0 && r.pressure_pa <= self.rows[i - 1].pressure_pa {
                return Err(Error::param(
                    format!("rows[{i}].pressure_Pa"),
                    "pressures must be strictly increasing",
                ));
            }
        }
        Ok(())
    }

    /// Read a table written by [`write_csv`](Self::write_csv) (or by hand). Errors name the file
    /// and the 1-based line: wrong header, wrong field count, unparsable number, unphysical
    /// value, pressures not strictly increasing, no rows.
    pub fn read_csv(path: &Path) -> Result<Self> {
        let mut rdr = crate::core::input::csv_reader_any_length(path)?;
        let headers = rdr
            .headers()
            .map_err(|e| Error::parse(path, 1, format!("cannot read header: {e}")))?
            .clone();
        let got: Vec<&str> = headers.iter().collect();
        let with_convergence = got.last() == Some(&CONVERGENCE_COLUMN);
        let numeric = &got[..got.len() - usize::from(with_convergence)];
        let long: Vec<&str> = COLUMNS.iter().chain(&INTERVAL_COLUMNS).copied().collect();
        let with_intervals = numeric == long;
        if numeric != COLUMNS && !with_intervals {
            return Err(Error::parse(
                path,
                1,
                format!(
                    "header must be `{}` (optionally followed by `,{}`, then optionally by `,{CONVERGENCE_COLUMN}`), got `{}`",
                    COLUMNS.join(","),
                    INTERVAL_COLUMNS.join(","),
                    got.join(",")
                ),
            ));
        }
        let width = got.len();
        let mut convergence: Vec<Verdict> = Vec::new();
        let mut rows: Vec<CalibrationRow> = Vec::new();
        let mut intervals: Vec<RowInterval> = Vec::new();
        for rec in rdr.records() {
            let (rec, line) = crate::core::input::csv_record(path, rec)?;
            if rec.len() == 1 && rec.get(0) == Some("") {
                continue; // blank line
            }
            if rec.len() != width {
                return Err(Error::parse(
                    path,
                    line,
                    crate::core::input::field_count_message(width, rec.len()),
                ));
            }
            if with_convergence {
                let field = &rec[width - 1];
                convergence.push(Verdict::parse(field).ok_or_else(|| {
                    Error::parse(
                        path,
                        line,
                        format!("column `{CONVERGENCE_COLUMN}`: `{field}` is not one of converged, undetermined, not-converged, not-checked"),
                    )
                })?);
            }
            let mut all = Vec::with_capacity(width);
            for (j, field) in rec.iter().take(numeric.len()).enumerate() {
                all.push(field.parse::<f64>().map_err(|_| {
                    Error::parse(
                        path,
                        line,
                        format!("column `{}`: `{field}` is not a number", got[j]),
                    )
                })?);
            }
            let mut v = [0.0; 9];
            v.copy_from_slice(&all[..9]);
            if with_intervals {
                let mut w = [0.0; 7];
                w.copy_from_slice(&all[9..]);
                intervals
                    .push(RowInterval::from_values(w).map_err(|m| Error::parse(path, line, m))?);
            }
            let row = CalibrationRow::from_values(v);
            row.check().map_err(|m| Error::parse(path, line, m))?;
            if let Some(prev) = rows.last() {
                if row.pressure_pa <= prev.pressure_pa {
                    return Err(Error::parse(
                        path,
                        line,
                        format!(
                            "`pressure_Pa` must increase strictly: {} after {}",
                            row.pressure_pa, prev.pressure_pa
                        ),
                    ));
                }
            }
            rows.push(row);
        }
        if rows.is_empty() {
            return Err(Error::parse(path, 0, "calibration table has no data rows"));
        }
        Ok(Self {
            rows,
            intervals: with_intervals.then_some(intervals),
            convergence: with_convergence.then_some(convergence),
            comments: leading_comments(path)?,
        })
    }

    /// Write the table atomically (complete file or none).
    pub fn write_csv(&self, path: &Path) -> Result<()> {
        self.validate()?;
        write_atomic(path, |w| {
            for c in &self.comments {
                writeln!(w, "# {c}").map_err(|e| Error::io(path, e))?;
            }
            let mut wtr = csv::Writer::from_writer(w);
            let io = |e: csv::Error| Error::Data(format!("{}: {e}", path.display()));
            let mut header: Vec<&str> = COLUMNS.to_vec();
            if self.intervals.is_some() {
                header.extend(INTERVAL_COLUMNS);
            }
            if self.convergence.is_some() {
                header.push(CONVERGENCE_COLUMN);
            }
            wtr.write_record(&header).map_err(io)?;
            for (i, r) in self.rows.iter().enumerate() {
                let mut fields: Vec<String> = r.values().iter().map(|v| format!("{v}")).collect();
                if let Some(iv) = &self.intervals {
                    fields.extend(iv[i].values().iter().map(|v| format!("{v}")));
                }
                if let Some(c) = &self.convergence {
                    fields.push(c[i].name().to_string());
                }
                wtr.write_record(fields).map_err(io)?;
            }
            wtr.flush().map_err(|e| Error::io(path, e))?;
            Ok(())
        })
    }

    /// Smallest and largest tabulated pressure (Pa).
    pub fn pressure_range(&self) -> (f64, f64) {
        (
            self.rows.first().map_or(f64::NAN, |r| r.pressure_pa),
            self.rows.last().map_or(f64::NAN, |r| r.pressure_pa),
        )
    }

    /// Local power-law exponents `[d ln kn″/d ln p, d ln E0″/d ln p]` at `pressure_pa`: those of
    /// the table segment (pair of adjacent rows) the pressure lies in, the end pair's beyond the
    /// table (the power law [`Self::interpolate`] continues with), `[0, 0]` for a one-row table.
    /// The exponents of the element whose stiffnesses follow the load
    /// ([`crate::element::LoadFollowingContact`]).
    pub fn load_exponents(&self, pressure_pa: f64) -> [f64; 2] {
        let rows = &self.rows;
        let n = rows.len();
        if n < 2 {
            return [0.0, 0.0];
        }
        let i = rows
            .partition_point(|r| r.pressure_pa <= pressure_pa)
            .clamp(1, n - 1);
        let (lo, hi) = (&rows[i - 1], &rows[i]);
        let lp = (hi.pressure_pa / lo.pressure_pa).ln();
        let slope = |f: fn(&CalibrationRow) -> f64| (f(hi) / f(lo)).ln() / lp;
        [
            slope(|r| r.element.kn_n_per_m3),
            slope(|r| r.element.e0_n_per_m3),
        ]
    }

    /// Parameters at `pressure_pa`: monotone cubic (Fritsch–Carlson) in `ln p` within the range,
    /// the end pair's power law outside it, flagged (see the module documentation).
    pub fn interpolate(&self, pressure_pa: f64) -> Interpolated {
        let rows = &self.rows;
        assert!(
            !rows.is_empty(),
            "interpolate on an empty calibration table"
        );
        let (p_lo, p_hi) = self.pressure_range();
        if pressure_pa.is_nan() || pressure_pa < p_lo {
            // Also non-positive pressures.
            let pair = (&rows[0], rows.get(1));
            return extrapolate(pair, pressure_pa, RangeFlag::Below);
        }
        if pressure_pa > p_hi {
            let n = rows.len();
            let pair = (&rows[n - 1], n.checked_sub(2).map(|i| &rows[i]));
            return extrapolate(pair, pressure_pa, RangeFlag::Above);
        }
        if rows.len() == 1 {
            return extrapolate((&rows[0], None), pressure_pa, RangeFlag::Within);
        }
        let x: Vec<f64> = rows.iter().map(|r| r.pressure_pa.ln()).collect();
        let xq = pressure_pa.ln();
        let column = |f: fn(&CalibrationRow) -> f64| {
            let y: Vec<f64> = rows.iter().map(f).collect();
            pchip(&x, &y, xq)
        };
        Interpolated {
            pressure_pa,
            contact_area_ratio: column(|r| r.contact_area_ratio),
            element: ContactParamsPerArea {
                kn_n_per_m3: column(|r| r.element.kn_n_per_m3),
                e0_n_per_m3: column(|r| r.element.e0_n_per_m3),
                k: column(|r| r.element.k),
                mu: column(|r| r.element.mu),
                et_n_per_m3: column(|r| r.element.et_n_per_m3),
            },
            in_range: true,
            range: RangeFlag::Within,
        }
    }
}

/// The `#` lines before a CSV file's header, without the `#` and surrounding blanks.
fn leading_comments(path: &Path) -> Result<Vec<String>> {
    use std::io::BufRead;
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let mut comments = Vec::new();
    for line in std::io::BufReader::new(file).lines() {
        let line = line.map_err(|e| Error::io(path, e))?;
        match line.trim_start().strip_prefix('#') {
            Some(c) => comments.push(c.trim().to_string()),
            None => break,
        }
    }
    Ok(comments)
}

/// Power-law continuation `v(p) = v_end·(p/p_end)^m` of one column beyond the end row, `m` from
/// the end pair `(p_end, v_end)`, `(p_next, v_next)`; the end value where the pair gives no
/// stiffening power law (a value not positive, or `m < 0`). `p = 0` gives 0 for `m > 0`.
pub fn power_law_beyond(end: (f64, f64), next: Option<(f64, f64)>, pressure_pa: f64) -> f64 {
    let (p_end, v_end) = end;
    match next {
        Some((p_next, v_next)) if v_end > 0.0 && v_next > 0.0 => {
            let m = (v_next / v_end).ln() / (p_next / p_end).ln();
            if m >= 0.0 {
                v_end * (pressure_pa.max(0.0) / p_end).powf(m)
            } else {
                v_end
            }
        }
        _ => v_end,
    }
}

/// The table's values at a pressure outside its range (or the only row's): power laws of the end
/// pair `(end, next)` for `kn`, `E0` and the contact area ratio, `Et/E0`, `k` and `μ` of the end
/// row (module documentation). NaN pressure gives NaN stiffnesses.
fn extrapolate(
    (end, next): (&CalibrationRow, Option<&CalibrationRow>),
    pressure_pa: f64,
    range: RangeFlag,
) -> Interpolated {
    let column = |f: fn(&CalibrationRow) -> f64| {
        if pressure_pa.is_nan() {
            return f64::NAN;
        }
        power_law_beyond(
            (end.pressure_pa, f(end)),
            next.map(|r| (r.pressure_pa, f(r))),
            pressure_pa,
        )
    };
    let e0 = column(|r| r.element.e0_n_per_m3);
    let et_ratio = if end.element.e0_n_per_m3 > 0.0 {
        end.element.et_n_per_m3 / end.element.e0_n_per_m3
    } else {
        0.0
    };
    Interpolated {
        pressure_pa,
        contact_area_ratio: column(|r| r.contact_area_ratio).min(1.0),
        element: ContactParamsPerArea {
            kn_n_per_m3: column(|r| r.element.kn_n_per_m3),
            e0_n_per_m3: e0,
            k: end.element.k,
            mu: end.element.mu,
            et_n_per_m3: et_ratio * e0,
        },
        in_range: range == RangeFlag::Within,
        range,
    }
}

/// Monotone piecewise-cubic Hermite interpolation (Fritsch & Carlson 1980), with the end slopes
/// of Moler's `pchip` (one-sided three-point formula, limited). `x` strictly increasing,
/// `x[0] ≤ xq ≤ x[n−1]`, `n ≥ 2`.
pub fn pchip(x: &[f64], y: &[f64], xq: f64) -> f64 {
    let n = x.len();
    debug_assert!(n >= 2 && y.len() == n);
    let h: Vec<f64> = x.windows(2).map(|w| w[1] - w[0]).collect();
    let delta: Vec<f64> = (0..n - 1).map(|i| (y[i + 1] - y[i]) / h[i]).collect();
    let mut d = vec![0.0; n];
    if n == 2 {
        d[0] = delta[0];
        d[1] = delta[0];
    } else {
        for i in 1..n - 1 {
            if delta[i - 1] * delta[i] > 0.0 {
                // Weighted harmonic mean (Fritsch–Butland form used by Fritsch–Carlson/pchip).
                let w1 = 2.0 * h[i] + h[i - 1];
                let w2 = h[i] + 2.0 * h[i - 1];
                d[i] = (w1 + w2) / (w1 / delta[i - 1] + w2 / delta[i]);
            }
        }
        let end = |h0: f64, h1: f64, d0: f64, d1: f64| {
            let s = ((2.0 * h0 + h1) * d0 - h0 * d1) / (h0 + h1);
            if s.signum() != d0.signum() {
                0.0
            } else if d0.signum() != d1.signum() && s.abs() > 3.0 * d0.abs() {
                3.0 * d0
            } else {
                s
            }
        };
        d[0] = end(h[0], h[1], delta[0], delta[1]);
        d[n - 1] = end(h[n - 2], h[n - 3], delta[n - 2], delta[n - 3]);
    }
    // Locate the interval.
    let i = match x.iter().rposition(|&xi| xi <= xq) {
        Some(i) if i >= n - 1 => n - 2,
        Some(i) => i,
        None => 0,
    };
    let t = (xq - x[i]) / h[i];
    let (h00, h10, h01, h11) = (
        (1.0 + 2.0 * t) * (1.0 - t) * (1.0 - t),
        t * (1.0 - t) * (1.0 - t),
        t * t * (3.0 - 2.0 * t),
        t * t * (t - 1.0),
    );
    h00 * y[i] + h10 * h[i] * d[i] + h01 * y[i + 1] + h11 * h[i] * d[i + 1]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(p: f64, kn: f64, e0: f64, k: f64) -> CalibrationRow {
        CalibrationRow {
            pressure_pa: p,
            contact_area_ratio: 0.01,
            element: ContactParamsPerArea {
                kn_n_per_m3: kn,
                e0_n_per_m3: e0,
                k,
                mu: 0.6,
                et_n_per_m3: 0.0,
            },
            fit_r2: 0.99,
            energy_per_cycle_j_per_m2: 1e-3,
        }
    }

    fn table() -> CalibrationTable {
        CalibrationTable::new(vec![
            row(1e5, 1e12, 1e12, 0.2),
            row(1e6, 5e12, 3e12, 0.5),
            row(2e6, 8e12, 5e12, 0.4),
            row(1e7, 3e13, 1e13, 0.45),
        ])
        .unwrap()
    }

    #[test]
    fn passes_through_rows_and_is_monotone_between() {
        let t = table();
        for r in &t.rows {
            let i = t.interpolate(r.pressure_pa);
            assert!(i.in_range);
            assert!(
                (i.element.kn_n_per_m3 - r.element.kn_n_per_m3).abs()
                    < 1e-6 * r.element.kn_n_per_m3
            );
            assert!((i.element.k - r.element.k).abs() < 1e-12);
        }
        let mut prev = 0.0;
        for j in 0..=400 {
            let p = 1e5 * 100f64.powf(j as f64 / 400.0);
            let i = t.interpolate(p);
            assert!(i.element.kn_n_per_m3 >= prev, "kn not monotone at {p}");
            prev = i.element.kn_n_per_m3;
            // No overshoot in the non-monotone k column: stays within neighbours' range.
            assert!(i.element.k >= 0.2 - 1e-12 && i.element.k <= 0.5 + 1e-12);
        }
    }

    #[test]
    fn linear_in_log_p_data_is_reproduced() {
        let x = [0.0, 1.0, 3.0, 4.0];
        let y = [1.0, 3.0, 7.0, 9.0];
        for xq in [0.5, 2.0, 3.7] {
            assert!((pchip(&x, &y, xq) - (1.0 + 2.0 * xq)).abs() < 1e-12);
        }
    }

    /// A table drawn from power laws (`kn ∝ p^0.8`, `E0 ∝ p^0.9`, area ∝ p, the forms of
    /// rough-contact stiffness and area at light load) is continued by those laws outside its
    /// range, exactly; a zero pressure (open contact) has no stiffness.
    #[test]
    fn outside_range_the_end_pairs_power_law_is_followed_and_flagged() {
        let law = |p: f64| CalibrationRow {
            pressure_pa: p,
            contact_area_ratio: 1e-9 * p,
            element: ContactParamsPerArea {
                kn_n_per_m3: 3e8 * p.powf(0.8),
                e0_n_per_m3: 2e7 * p.powf(0.9),
                k: 0.5 + 1e-8 * p,
                mu: 0.6,
                et_n_per_m3: 0.1 * 2e7 * p.powf(0.9),
            },
            fit_r2: 0.99,
            energy_per_cycle_j_per_m2: 1e-3,
        };
        let t = CalibrationTable::new([1e5, 3e5, 1e6, 4e6, 1e7].map(law).to_vec()).unwrap();
        let rel = |a: f64, b: f64| (a / b - 1.0).abs();
        for (p, flag) in [
            (1e3, RangeFlag::Below),
            (5e4, RangeFlag::Below),
            (3e7, RangeFlag::Above),
        ] {
            let v = t.interpolate(p);
            let truth = law(p);
            assert_eq!(v.range, flag);
            assert!(!v.in_range);
            assert!(
                rel(v.element.kn_n_per_m3, truth.element.kn_n_per_m3) < 1e-12,
                "kn at {p}"
            );
            assert!(
                rel(v.element.e0_n_per_m3, truth.element.e0_n_per_m3) < 1e-12,
                "E0 at {p}"
            );
            assert!(
                rel(v.element.et_n_per_m3, truth.element.et_n_per_m3) < 1e-12,
                "Et at {p}"
            );
            assert!(rel(v.contact_area_ratio, truth.contact_area_ratio) < 1e-12);
            // k and μ keep the end row's values.
            let end = if flag == RangeFlag::Below {
                &t.rows[0]
            } else {
                &t.rows[4]
            };
            assert_eq!((v.element.k, v.element.mu), (end.element.k, end.element.mu));
        }
        // Open contact: no stiffness, no area; a negative pressure reads as zero.
        for p in [0.0, -1e3] {
            let v = t.interpolate(p);
            assert_eq!(v.range, RangeFlag::Below);
            assert_eq!(
                (
                    v.element.kn_n_per_m3,
                    v.element.e0_n_per_m3,
                    v.element.et_n_per_m3
                ),
                (0.0, 0.0, 0.0)
            );
            assert_eq!(v.contact_area_ratio, 0.0);
        }
        let nan = t.interpolate(f64::NAN);
        assert_eq!(nan.range, RangeFlag::Below);
        assert!(nan.element.kn_n_per_m3.is_nan());
        // The contact area ratio is a fraction: at most 1 however far above.
        assert_eq!(t.interpolate(1e13).contact_area_ratio, 1.0);
    }

    /// A column that falls with pressure at an end (not a contact stiffness) or a one-row table
    /// gives no power law: the end value is kept.
    #[test]
    fn without_a_stiffening_end_pair_the_end_value_is_kept() {
        let t = table(); // E0: 5e12 at 2 MPa, 1e13 at 10 MPa; k falls 0.5 → 0.4 → 0.45
        let mut rows = t.rows.clone();
        rows[0].element.kn_n_per_m3 = 6e12; // kn falls from the first to the second row
        let falling = CalibrationTable::new(rows).unwrap();
        assert_eq!(falling.interpolate(1e3).element.kn_n_per_m3, 6e12);
        let one = CalibrationTable::new(vec![t.rows[1]]).unwrap();
        for p in [1e3, 1e6, 1e9] {
            assert_eq!(one.interpolate(p).element.kn_n_per_m3, 5e12);
        }
        assert_eq!(one.interpolate(1e6).range, RangeFlag::Within);
    }

    #[test]
    fn convergence_verdicts_round_trip_and_follow_the_rows_used() {
        use Verdict::*;
        let t = table()
            .with_convergence(vec![Converged, NotConverged, Undetermined, Converged])
            .unwrap();
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("t.csv");
        t.write_csv(&p).unwrap();
        let text = std::fs::read_to_string(&p).unwrap();
        assert!(text.lines().next().unwrap().ends_with(",convergence"));
        assert!(text.lines().nth(2).unwrap().ends_with(",not-converged"));
        assert_eq!(CalibrationTable::read_csv(&p).unwrap(), t);
        // Rows at 0.1, 1, 2 and 10 MPa.
        assert_eq!(t.convergence_at(1e5), Some(Converged)); // on a row: that row
        assert_eq!(t.convergence_at(5e5), Some(NotConverged)); // between: the worse neighbour
        assert_eq!(t.convergence_at(5e6), Some(Undetermined));
        assert_eq!(t.convergence_at(1e7), Some(Converged));
        assert_eq!(t.convergence_at(1e3), Some(NotConverged)); // below: the first pair
        assert_eq!(t.convergence_at(3e7), Some(Undetermined)); // above: the last pair
        assert_eq!(table().convergence_at(1e6), None);
        assert!(table().with_convergence(vec![Converged]).is_err());
        // An unknown verdict names the file, the line and the column.
        std::fs::write(&p, text.replace(",not-converged", ",maybe")).unwrap();
        let err = CalibrationTable::read_csv(&p).unwrap_err().to_string();
        assert!(
            err.contains("t.csv:3") && err.contains("convergence"),
            "{err}"
        );
    }

    #[test]
    fn csv_round_trip() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("t.csv");
        let t = table();
        t.write_csv(&p).unwrap();
        let text = std::fs::read_to_string(&p).unwrap();
        assert!(text.starts_with(&COLUMNS.join(",")));
        assert_eq!(CalibrationTable::read_csv(&p).unwrap(), t);
    }

    #[test]
    fn malformed_csv_errors_name_file_and_line() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("bad.csv");
        let header = COLUMNS.join(",");
        let long = format!("{header},{}", INTERVAL_COLUMNS.join(","));
        let cases = [
            (format!("{header}\n1e5,0.1,1e12,1e12,0.2,0.6,0,0.99,1e-3\n1e6,0.1,abc,1e12,0.2,0.6,0,0.99,1e-3\n"), ":3", "kn_N_per_m3"),
            (format!("{header}\n1e5,0.1,1e12,1e12,1.2,0.6,0,0.99,1e-3\n"), ":2", "`k`"),
            (format!("{header}\n1e6,0.1,1e12,1e12,0.2,0.6,0,0.99,1e-3\n1e5,0.1,1e12,1e12,0.2,0.6,0,0.99,1e-3\n"), ":3", "increase"),
            (format!("{header}\n1e5,0.1,1e12\n"), ":2", "fields"),
            ("pressure,kn\n1,2\n".to_string(), ":1", "header"),
            (format!("{header}\n"), "bad.csv", "no data"),
            (
                format!(
                    "{long}\n1e5,0.1,1e12,1e12,0.2,0.6,0,0.99,1e-3,1,0,1e11,1e11,0.01,0,1e-4\n"
                ),
                ":2",
                "realisations",
            ),
            (
                format!(
                    "{long}\n1e5,0.1,1e12,1e12,0.2,0.6,0,0.99,1e-3,8,0,-1e11,1e11,0.01,0,1e-4\n"
                ),
                ":2",
                "kn_ci95",
            ),
            (
                format!("{long}\n1e5,0.1,1e12,1e12,0.2,0.6,0,0.99,1e-3\n"),
                ":2",
                "fields",
            ),
        ];
        for (text, loc, what) in cases {
            std::fs::write(&p, text).unwrap();
            let msg = CalibrationTable::read_csv(&p).unwrap_err().to_string();
            assert!(
                msg.contains("bad.csv") && msg.contains(loc) && msg.contains(what),
                "{msg}"
            );
        }
        assert!(CalibrationTable::read_csv(&dir.path().join("missing.csv")).is_err());
    }

    #[test]
    fn csv_round_trip_with_intervals() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("t.csv");
        let t = table();
        let iv = RowInterval {
            realisations: 8,
            contact_area_ratio: 1e-4,
            kn_n_per_m3: 1e11,
            e0_n_per_m3: 2e11,
            k: 0.05,
            et_n_per_m3: 0.0,
            energy_per_cycle_j_per_m2: 1e-4,
        };
        let t = CalibrationTable::with_intervals(t.rows.clone(), vec![iv; t.rows.len()]).unwrap();
        t.write_csv(&p).unwrap();
        let back = CalibrationTable::read_csv(&p).unwrap();
        assert_eq!(back, t);
        // Interpolation uses the means, as for a table without intervals.
        assert_eq!(back.interpolate(2e6), table().interpolate(2e6));
        assert!(CalibrationTable::with_intervals(t.rows.clone(), vec![iv]).is_err());
    }

    /// The comment that says which kn the table holds is written before the header and read
    /// back; a multi-line comment is refused.
    #[test]
    fn kn_comment_round_trips() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.csv");
        let t = table()
            .with_comments(vec![kn_comment(Some(3.3e9))])
            .unwrap();
        t.write_csv(&path).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(
            text.starts_with("# kn_N_per_m3 = unloading/reloading stiffness"),
            "{text}"
        );
        let back = CalibrationTable::read_csv(&path).unwrap();
        assert_eq!(back, t);
        assert!(kn_comment(None).contains("elastic"));
        assert!(table().with_comments(vec!["a\nb".into()]).is_err());
    }
}
