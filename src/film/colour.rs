//! Colour → pressure for pressure-measurement film.
//!
//! Two readings of a pixel are offered:
//!
//! * [`ColourTable`]: a vendor colour table (pressure, R, G, B), as exported by the Fujifilm
//!   Prescale mobile app. The table rows inside the film's measuring range form a piecewise-linear
//!   *colour curve* in RGB space; a pixel is projected onto the nearest point of that curve and its
//!   pressure is interpolated linearly along the segment it projects to. Pixels farther than
//!   `max_distance` (Euclidean, in 0–255 RGB units) from the curve are *off-curve* (pen marks, tape,
//!   dirt) and are rejected, not mapped.
//! * [`DensityCalibration`]: calibration points (optical density → pressure) for raw grey or colour
//!   scans, interpolated piecewise-linearly.
//!
//! Both report below-range and above-range pixels as such: a pressure is only ever given to a
//! pixel whose colour lies inside the calibrated range.
//!
//! ## Colour-table file format
//! CSV, one row per table entry: `pressure, R, G, B` with R, G, B in 0–255. Lines starting with `;`
//! or `#` are comments (the vendor app writes its header that way). An optional header row names
//! the pressure unit: `pressure_Pa` → Pa, `pressure_MPa`, `MPa` or `Pressure` → MPa. Without a
//! header the vendor convention (MPa) applies. Pressures must increase strictly down the table.
//!
//! ## Marker rows
//! Vendor tables carry *marker* rows that are not part of the graded colour scale: the Prescale LW
//! table starts with white (0 MPa, no colour), then green (2.0 MPa, the app's "below range" mark),
//! the pink scale 2.5–9.06 MPa, and ends with yellow (10 MPa, "at or above range"). Markers are
//! found by the size of the colour step between consecutive rows: a step longer than
//! [`MARKER_STEP_FACTOR`] × the median step breaks the curve, and the longest unbroken run of rows
//! is the graded curve. Rows before it are below-range markers, rows after it above-range markers.
//! The measuring range is therefore `[first graded pressure, last graded pressure]`. A marker row
//! at pressure 0 is the colour of unstained film; a table must have one (as its first row):
//! without it unstained paper could not be told from stain below the range.

use crate::core::error::{Error, Result};
use std::path::Path;

/// A colour step longer than this multiple of the table's median step separates a marker row
/// from the graded colour curve.
pub const MARKER_STEP_FACTOR: f64 = 3.0;

/// Tolerance on the segment parameter at the ends of the colour curve.
const END_TOLERANCE: f64 = 1e-6;

/// Default off-curve rejection distance in RGB units (0–255 scale, Euclidean): half of one step of
/// the Prescale LW pink scale (whose steps are ≈ 40 units long).
pub const DEFAULT_MAX_COLOUR_DISTANCE: f64 = 20.0;

/// Smallest plausible largest pressure of a film calibration (Pa). Pressure films measure from
/// about 0.005 MPa (the most sensitive grades) to 300 MPa; a colour table or density
/// calibration whose pressures all lie below 1 kPa was written in another unit than its header
/// says (MPa values under a `pressure_Pa` header), and would read every patch as ≈ 0 MPa.
pub const MIN_PLAUSIBLE_CALIBRATION_PA: f64 = 1e3;

/// Largest plausible pressure of a film calibration (Pa). The highest-range films (Prescale
/// HHS) end at 300 MPa; a calibration reaching beyond 1 GPa was written in Pa under an MPa
/// header (or under none: the vendor convention is MPa), and would read every patch 10⁶ times
/// too high (a total load of 1.9e8 N for a 190 N contact).
pub const MAX_PLAUSIBLE_CALIBRATION_PA: f64 = 1e9;

/// Refuse a calibration file whose largest pressure `max_pa` (Pa, on line `max_line`) is below
/// [`MIN_PLAUSIBLE_CALIBRATION_PA`] or above [`MAX_PLAUSIBLE_CALIBRATION_PA`]; `unit` is the
/// factor to Pa and `unit_line` the line declaring it (0: none, the MPa default).
fn check_plausible_pressures(
    path: &Path,
    max_pa: f64,
    max_line: usize,
    unit: f64,
    unit_line: usize,
) -> Result<()> {
    let unit_name = if unit == 1.0 { "Pa" } else { "MPa" };
    if max_pa < MIN_PLAUSIBLE_CALIBRATION_PA {
        return Err(Error::parse(
            path,
            unit_line,
            format!(
                "every pressure is below 1 kPa (largest {} {unit_name} = {} Pa), but pressure \
                 films measure about 0.005–300 MPa: are the values in MPa under a {unit_name} \
                 header? Name the column pressure_MPa",
                crate::core::error::num(max_pa / unit),
                crate::core::error::num(max_pa)
            ),
        ));
    }
    if max_pa > MAX_PLAUSIBLE_CALIBRATION_PA {
        let header = if unit_line == 0 {
            "no header (the vendor convention: MPa)".to_string()
        } else {
            format!("the {unit_name} header of line {unit_line}")
        };
        return Err(Error::parse(
            path,
            max_line,
            format!(
                "pressure {} read as {unit_name} is {} Pa, above 1 GPa, but pressure films \
                 measure about 0.005–300 MPa: are the values in Pa under {header}? Name the \
                 column pressure_Pa",
                crate::core::error::num(max_pa / unit),
                crate::core::error::num(max_pa)
            ),
        ));
    }
    Ok(())
}

/// What a pixel's colour says about the pressure there.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PixelClass {
    /// Inside the calibrated range: the pressure is known.
    InRange,
    /// Unstained film: the colour of a 0-pressure marker row (white paper).
    Unstained,
    /// Stained, but below the film's measuring range (the below-range mark, or paler than the
    /// palest graded colour).
    BelowRange,
    /// At or above the upper end of the measuring range (saturated, or the above-range mark).
    AboveRange,
    /// Colour far from the colour curve and from every marker (pen, tape, dirt): rejected.
    OffCurve,
}

impl PixelClass {
    /// Name used in output files.
    pub fn name(self) -> &'static str {
        match self {
            PixelClass::InRange => "in_range",
            PixelClass::Unstained => "unstained",
            PixelClass::BelowRange => "below_range",
            PixelClass::AboveRange => "above_range",
            PixelClass::OffCurve => "off_curve",
        }
    }
}

/// The reading of one pixel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PixelReading {
    /// What the colour says about the pressure.
    pub class: PixelClass,
    /// Pressure in Pa; `NaN` unless `class == InRange`.
    pub pressure_pa: f64,
}

impl PixelReading {
    fn of(class: PixelClass) -> Self {
        Self {
            class,
            pressure_pa: f64::NAN,
        }
    }
}

/// One row of a colour table.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ColourRow {
    /// Pressure of the row (Pa).
    pub pressure_pa: f64,
    /// R, G, B in 0–255.
    pub rgb: [f64; 3],
}

/// A colour → pressure table split into its graded colour curve and its marker rows.
#[derive(Debug, Clone)]
pub struct ColourTable {
    rows: Vec<ColourRow>,
    /// Index range (inclusive start, exclusive end) of the graded rows in `rows`.
    graded: std::ops::Range<usize>,
    /// Off-curve rejection distance in RGB units.
    pub max_distance: f64,
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// Closest point of the (infinite) line through `a`, `b` to `c`: returns the line parameter `t`
/// (0 at `a`, 1 at `b`) and the distance from `c` to the point at the clamped parameter when
/// `clamp` is set, else to the point at `t` itself.
fn project(a: [f64; 3], b: [f64; 3], c: [f64; 3], clamp: bool) -> (f64, f64) {
    let ab = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let ac = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
    let l2 = ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2];
    let t = (ab[0] * ac[0] + ab[1] * ac[1] + ab[2] * ac[2]) / l2;
    let tt = if clamp { t.clamp(0.0, 1.0) } else { t };
    let p = [a[0] + tt * ab[0], a[1] + tt * ab[1], a[2] + tt * ab[2]];
    (t, dist(p, c))
}

impl ColourTable {
    /// Build a table from rows (pressures strictly increasing), finding the graded curve and the
    /// marker rows (see the module documentation). `source` names the table in error messages.
    pub fn from_rows(rows: Vec<ColourRow>, max_distance: f64, source: &str) -> Result<Self> {
        crate::core::error::require_positive("max_colour_distance", max_distance)?;
        if rows.len() < 2 {
            return Err(Error::Data(format!(
                "{source}: a colour table needs at least 2 rows, got {}",
                rows.len()
            )));
        }
        for (k, w) in rows.windows(2).enumerate() {
            if w[1].pressure_pa <= w[0].pressure_pa {
                return Err(Error::Data(format!(
                    "{source}: colour table is not monotone in pressure: row {} ({} Pa) does not exceed row {} ({} Pa)",
                    k + 2,
                    w[1].pressure_pa,
                    k + 1,
                    w[0].pressure_pa
                )));
            }
            if dist(w[0].rgb, w[1].rgb) == 0.0 {
                return Err(Error::Data(format!(
                    "{source}: rows {} and {} have the same colour, so colour cannot identify pressure",
                    k + 1,
                    k + 2
                )));
            }
        }
        // The paper's colour is what tells unstained film from stain below the range: without
        // it every pixel paler than the palest graded colour, white paper included, would be
        // "stained below range" (94.7 % of a test image), and the rim joined to each patch
        // would grow into white film (+33 % area). Guessing "near white" instead would misread
        // tinted paper, a grey scanner lid, or a sensitive film's faint graded colours.
        if rows[0].pressure_pa != 0.0 {
            return Err(Error::Data(format!(
                "{source}: no row at pressure 0: a colour table must give the colour of \
                 unstained film as its first row, `0,R,G,B` (e.g. `0,255,255,255` for white \
                 paper, or the paper's colour sampled from the scan); without it unstained \
                 paper would read as stain below the film's range"
            )));
        }
        let graded = if rows.len() > 1 && rows[0].pressure_pa == 0.0 && rows.len() < 3 {
            1..1
        } else {
            graded_run(&rows)
        };
        if graded.len() < 2 {
            return Err(Error::Data(format!(
                "{source}: no graded colour curve of at least 2 rows found (every step is a jump)"
            )));
        }
        Ok(Self {
            rows,
            graded,
            max_distance,
        })
    }

    /// Read a colour table file (format in the module documentation).
    pub fn read_csv(path: &Path, max_distance: f64) -> Result<Self> {
        crate::core::limits::check_file_size(path, crate::core::limits::MAX_TEXT_FILE_BYTES)?;
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        // A byte-order mark (spreadsheets write one in front of UTF-8 CSV) is no part of the
        // first field: without this, a header read "unknown pressure column `\u{feff};`".
        let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
        let mut unit = 1e6; // vendor convention: MPa
        let mut rows = Vec::new();
        let mut seen_header = false;
        let mut unit_line = 0;
        for (k, raw) in text.lines().enumerate() {
            let line_no = k + 1;
            let line = raw.trim();
            if line.is_empty() || line.starts_with(';') || line.starts_with('#') {
                continue;
            }
            let fields: Vec<&str> = line.split(',').map(str::trim).collect();
            if fields.len() < 4 {
                return Err(Error::parse(
                    path,
                    line_no,
                    format!(
                        "expected 4 columns (pressure, R, G, B), got {}",
                        fields.len()
                    ),
                ));
            }
            if fields[0].parse::<f64>().is_err() && rows.is_empty() && !seen_header {
                let name = fields[0].to_ascii_lowercase();
                unit = if name.ends_with("_pa") {
                    1.0
                } else if name.contains("mpa") || name == "pressure" {
                    1e6
                } else {
                    return Err(Error::parse(
                        path,
                        line_no,
                        format!(
                            "unknown pressure column `{}` (use pressure_Pa or pressure_MPa)",
                            fields[0]
                        ),
                    ));
                };
                seen_header = true;
                unit_line = line_no;
                continue;
            }
            let mut v = [0.0; 4];
            for (c, f) in fields.iter().take(4).enumerate() {
                v[c] = f.parse::<f64>().map_err(|_| {
                    Error::parse(
                        path,
                        line_no,
                        format!("column {}: `{f}` is not a number", c + 1),
                    )
                })?;
                if !v[c].is_finite() {
                    return Err(Error::parse(
                        path,
                        line_no,
                        format!("column {} is not finite", c + 1),
                    ));
                }
            }
            if v[1..].iter().any(|c| !(0.0..=255.0).contains(c)) {
                return Err(Error::parse(path, line_no, "R, G, B must lie in 0–255"));
            }
            if v[0] < 0.0 {
                return Err(Error::parse(path, line_no, "negative pressure"));
            }
            if let Some(prev) = rows.last().map(|r: &(ColourRow, usize)| r.0.pressure_pa) {
                if v[0] * unit <= prev {
                    return Err(Error::parse(
                        path,
                        line_no,
                        format!(
                            "colour table is not monotone in pressure: {} does not exceed the previous row's {}",
                            v[0],
                            prev / unit
                        ),
                    ));
                }
            }
            rows.push((
                ColourRow {
                    pressure_pa: v[0] * unit,
                    rgb: [v[1], v[2], v[3]],
                },
                line_no,
            ));
        }
        if let Some((last, line)) = rows.last() {
            check_plausible_pressures(path, last.pressure_pa, *line, unit, unit_line)?;
        }
        let source = path.display().to_string();
        Self::from_rows(
            rows.into_iter().map(|r| r.0).collect(),
            max_distance,
            &source,
        )
    }

    /// All rows, markers included.
    pub fn rows(&self) -> &[ColourRow] {
        &self.rows
    }

    /// The graded rows (the colour curve).
    pub fn graded_rows(&self) -> &[ColourRow] {
        &self.rows[self.graded.clone()]
    }

    /// Measuring range `(min, max)` in Pa: the pressures of the first and last graded rows.
    pub fn range_pa(&self) -> (f64, f64) {
        let g = self.graded_rows();
        (g[0].pressure_pa, g[g.len() - 1].pressure_pa)
    }

    /// Colour of a pressure inside the measuring range (linear interpolation along the curve).
    /// Used to render synthetic films; `None` outside the range.
    pub fn colour_of(&self, pressure_pa: f64) -> Option<[f64; 3]> {
        let g = self.graded_rows();
        let (lo, hi) = self.range_pa();
        if !(lo..=hi).contains(&pressure_pa) {
            return None;
        }
        let k = g
            .windows(2)
            .position(|w| pressure_pa <= w[1].pressure_pa)
            .unwrap_or(g.len() - 2);
        let (a, b) = (g[k], g[k + 1]);
        let t = (pressure_pa - a.pressure_pa) / (b.pressure_pa - a.pressure_pa);
        Some([
            a.rgb[0] + t * (b.rgb[0] - a.rgb[0]),
            a.rgb[1] + t * (b.rgb[1] - a.rgb[1]),
            a.rgb[2] + t * (b.rgb[2] - a.rgb[2]),
        ])
    }

    /// Read one pixel (RGB in 0–255, fractional values allowed for 16-bit images).
    ///
    /// 1. Project onto every graded segment (clamped); the nearest wins. Within `max_distance` and
    ///    strictly inside the curve → in range, pressure interpolated along the segment.
    /// 2. Otherwise, within `max_distance` of a marker row → that marker's side (below/above).
    /// 3. Otherwise, if the pixel lies within `max_distance` of the curve's straight extension
    ///    beyond its first (last) row → below (above) range: e.g. a paler pink than the palest
    ///    table entry is below range, not the lowest pressure.
    /// 4. Otherwise off-curve (rejected).
    pub fn read(&self, rgb: [f64; 3]) -> PixelReading {
        let g = self.graded_rows();
        let n = g.len();
        let mut best = (f64::INFINITY, 0usize, 0.0);
        for k in 0..n - 1 {
            let (t, d) = project(g[k].rgb, g[k + 1].rgb, rgb, true);
            if d < best.0 {
                best = (d, k, t);
            }
        }
        let (d, k, t) = best;
        // `t` is the unclamped line parameter: < 0 beyond the first row, > 1 beyond the last.
        // A small tolerance keeps a pixel of exactly the end row's colour (read back from a
        // 16-bit or float image with rounding) in range.
        let before_start = k == 0 && t < -END_TOLERANCE;
        let after_end = k == n - 2 && t > 1.0 + END_TOLERANCE;
        if d <= self.max_distance && !before_start && !after_end {
            let p =
                g[k].pressure_pa + t.clamp(0.0, 1.0) * (g[k + 1].pressure_pa - g[k].pressure_pa);
            return PixelReading {
                class: PixelClass::InRange,
                pressure_pa: p,
            };
        }
        // Nearest marker row within the distance.
        let mut marker: Option<(f64, PixelClass)> = None;
        for (idx, row) in self.rows.iter().enumerate() {
            if self.graded.contains(&idx) {
                continue;
            }
            let dm = dist(row.rgb, rgb);
            if dm <= self.max_distance && marker.is_none_or(|m| dm < m.0) {
                let side = if row.pressure_pa == 0.0 {
                    PixelClass::Unstained
                } else if idx < self.graded.start {
                    PixelClass::BelowRange
                } else {
                    PixelClass::AboveRange
                };
                marker = Some((dm, side));
            }
        }
        if let Some((_, side)) = marker {
            return PixelReading::of(side);
        }
        // Beyond an end of the curve, on its straight extension.
        if before_start && project(g[0].rgb, g[1].rgb, rgb, false).1 <= self.max_distance {
            return PixelReading::of(PixelClass::BelowRange);
        }
        if after_end && project(g[n - 2].rgb, g[n - 1].rgb, rgb, false).1 <= self.max_distance {
            return PixelReading::of(PixelClass::AboveRange);
        }
        PixelReading::of(PixelClass::OffCurve)
    }
}

/// The longest run of consecutive rows whose colour steps are all at most
/// `MARKER_STEP_FACTOR` × the median step (all rows for tables of fewer than 4 rows).
/// A leading row at pressure 0 is always a marker (the unstained film colour): no film's graded
/// scale starts at zero pressure.
fn graded_run(rows: &[ColourRow]) -> std::ops::Range<usize> {
    if rows[0].pressure_pa == 0.0 {
        let r = graded_run(&rows[1..]);
        return r.start + 1..r.end + 1;
    }
    if rows.len() < 4 {
        return 0..rows.len();
    }
    let steps: Vec<f64> = rows.windows(2).map(|w| dist(w[0].rgb, w[1].rgb)).collect();
    let mut sorted = steps.clone();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[sorted.len() / 2];
    let limit = MARKER_STEP_FACTOR * median;
    let mut best = 0..1;
    let mut start = 0;
    for (k, s) in steps.iter().enumerate() {
        if *s > limit {
            start = k + 1;
        } else if k + 2 - start > best.len() {
            best = start..k + 2;
        }
    }
    best
}

/// Optical density of a pixel: `D = log10(255 / L)`, with `L` the Rec. 709 luma of the 0–255
/// RGB values (floored at 0.5 to keep black finite). White paper has `D = 0`; darker = denser.
pub fn optical_density(rgb: [f64; 3]) -> f64 {
    let l = 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2];
    (255.0 / l.max(0.5)).log10()
}

/// Calibration points optical density → pressure for raw scans, interpolated piecewise-linearly.
///
/// File format: CSV with header `density,pressure_MPa` (or `density,pressure_Pa`), `#` comments;
/// both columns strictly increasing. The density is read in [`DensityCalibration::channel`]
/// (luma by default; see [`crate::film::scan::Channel`]). A pixel whose density is at most
/// [`DensityCalibration::unstained_density`] (the paper level, estimated from the scan by
/// [`crate::film::scan::paper_level`] or given) is unstained; stained but below the first point
/// is **below range**; above the last point above range. Density alone cannot tell pen marks
/// from stain: automatic patch detection rejects marks by their shape
/// ([`crate::film::regions::PatchOptions`]).
#[derive(Debug, Clone)]
pub struct DensityCalibration {
    /// `(optical density, pressure in Pa)`, both strictly increasing.
    pub points: Vec<(f64, f64)>,
    /// The channel the densities are read in.
    pub channel: crate::film::scan::Channel,
    /// Densities at or below this are unstained paper (default: the first point's density,
    /// i.e. no below-range class until the paper level is set).
    pub unstained_density: f64,
    /// Hue check against marks: `(weak channel, limit)`. A stained pixel whose density in the
    /// channel the stain hardly absorbs exceeds `limit ×` its density in the read channel is not
    /// stain but ink (black or blue pen), and is off-curve (see [`Self::with_stain`]).
    pub hue_check: Option<(crate::film::scan::Channel, f64)>,
}

/// A stained pixel is ink, not stain, when its density in the channel the stain absorbs least
/// exceeds this fraction of its density in the read channel (Prescale's magenta-red: ≈ 0.12;
/// black ink ≈ 1).
pub const INK_DENSITY_RATIO: f64 = 0.5;

impl DensityCalibration {
    /// Build from points; checks both columns increase strictly.
    pub fn new(points: Vec<(f64, f64)>, source: &str) -> Result<Self> {
        if points.len() < 2 {
            return Err(Error::Data(format!(
                "{source}: density calibration needs at least 2 points"
            )));
        }
        for (k, w) in points.windows(2).enumerate() {
            if w[1].0 <= w[0].0 || w[1].1 <= w[0].1 {
                return Err(Error::Data(format!(
                    "{source}: density calibration is not monotone: point {} ({}, {} Pa) does not exceed point {} ({}, {} Pa) in both density and pressure",
                    k + 2, w[1].0, w[1].1, k + 1, w[0].0, w[0].1
                )));
            }
        }
        let unstained_density = points[0].0;
        Ok(Self {
            points,
            channel: crate::film::scan::Channel::Luma,
            unstained_density,
            hue_check: None,
        })
    }

    /// Enable the hue check for a stain of colour `stain_rgb` (0–255): the weak channel is the
    /// one in which the stain is brightest. Refused when the stain itself is nearly neutral
    /// (its own ratio at least [`INK_DENSITY_RATIO`]): ink could not be told from it.
    pub fn with_stain(mut self, stain_rgb: [f64; 3]) -> Result<Self> {
        use crate::film::scan::Channel;
        let weak = [Channel::Red, Channel::Green, Channel::Blue][(0..3)
            .max_by(|&a, &b| stain_rgb[a].total_cmp(&stain_rgb[b]))
            .unwrap_or(0)];
        let ratio = weak.density(stain_rgb) / self.channel.density(stain_rgb).max(1e-12);
        if ratio.is_nan() || ratio >= INK_DENSITY_RATIO {
            return Err(Error::param(
                "stain colour",
                format!(
                    "the stain {stain_rgb:?} is too neutral to tell from ink (density ratio {ratio:.2} \
                     ≥ {INK_DENSITY_RATIO}): read it in a channel where it is coloured"
                ),
            ));
        }
        self.hue_check = Some((weak, INK_DENSITY_RATIO));
        Ok(self)
    }

    /// Read a density calibration CSV (format above).
    pub fn read_csv(path: &Path) -> Result<Self> {
        crate::core::limits::check_file_size(path, crate::core::limits::MAX_TEXT_FILE_BYTES)?;
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        // A byte-order mark (spreadsheets write one in front of UTF-8 CSV) is no part of the
        // first field.
        let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
        let mut unit = None;
        let mut unit_line = 0;
        let mut pts = Vec::new();
        let mut lines = Vec::new();
        for (k, raw) in text.lines().enumerate() {
            let line = raw.trim();
            if line.is_empty() || line.starts_with('#') || line.starts_with(';') {
                continue;
            }
            let f: Vec<&str> = line.split(',').map(str::trim).collect();
            if f.len() < 2 {
                return Err(Error::parse(
                    path,
                    k + 1,
                    "expected 2 columns: density, pressure",
                ));
            }
            if unit.is_none() {
                let name = f[1].to_ascii_lowercase();
                unit = Some(if name.ends_with("_pa") {
                    1.0
                } else if name.ends_with("_mpa") {
                    1e6
                } else {
                    return Err(Error::parse(
                        path,
                        k + 1,
                        "header must be `density,pressure_MPa` or `density,pressure_Pa`",
                    ));
                });
                unit_line = k + 1;
                continue;
            }
            let d: f64 = f[0]
                .parse()
                .map_err(|_| Error::parse(path, k + 1, format!("`{}` is not a number", f[0])))?;
            let p: f64 = f[1]
                .parse()
                .map_err(|_| Error::parse(path, k + 1, format!("`{}` is not a number", f[1])))?;
            if !d.is_finite() || !p.is_finite() || p < 0.0 {
                return Err(Error::parse(
                    path,
                    k + 1,
                    "density and pressure must be finite, pressure ≥ 0",
                ));
            }
            // D = log10(I_paper / I): a film never transmits or reflects more light than
            // unstained paper, so a negative density is no reading of a film.
            if d < 0.0 {
                return Err(Error::parse(
                    path,
                    k + 1,
                    format!(
                        "density {} is negative: an optical density (log10 of paper over stain \
                         brightness) is ≥ 0",
                        crate::core::error::num(d)
                    ),
                ));
            }
            pts.push((d, p * unit.unwrap_or(1e6)));
            lines.push(k + 1);
        }
        if let Some(at) = (0..pts.len()).max_by(|&a, &b| pts[a].1.total_cmp(&pts[b].1)) {
            check_plausible_pressures(path, pts[at].1, lines[at], unit.unwrap_or(1e6), unit_line)?;
        }
        Self::new(pts, &path.display().to_string())
    }

    /// Read one pixel.
    pub fn read(&self, rgb: [f64; 3]) -> PixelReading {
        let d = self.channel.density(rgb);
        let (first, last) = (self.points[0], self.points[self.points.len() - 1]);
        if d <= self.unstained_density && d < first.0 {
            return PixelReading::of(PixelClass::Unstained);
        }
        if let Some((weak, limit)) = self.hue_check {
            if weak.density(rgb) > limit * d {
                return PixelReading::of(PixelClass::OffCurve);
            }
        }
        if d < first.0 {
            // Stained, but paler than the film's first calibrated density.
            return PixelReading::of(PixelClass::BelowRange);
        }
        if d > last.0 {
            return PixelReading::of(PixelClass::AboveRange);
        }
        let k = self
            .points
            .windows(2)
            .position(|w| d <= w[1].0)
            .unwrap_or(self.points.len() - 2);
        let (a, b) = (self.points[k], self.points[k + 1]);
        PixelReading {
            class: PixelClass::InRange,
            pressure_pa: a.1 + (d - a.0) / (b.0 - a.0) * (b.1 - a.1),
        }
    }

    /// Measuring range `(min, max)` in Pa.
    pub fn range_pa(&self) -> (f64, f64) {
        (self.points[0].1, self.points[self.points.len() - 1].1)
    }
}

/// How colour becomes pressure.
#[derive(Debug, Clone)]
pub enum ColourToPressure {
    /// A colour table: nearest point on the graded colour curve, markers for the classes.
    Table(ColourTable),
    /// An optical-density calibration in one channel.
    Density(DensityCalibration),
}

impl ColourToPressure {
    /// Read one pixel (RGB in 0–255).
    pub fn read(&self, rgb: [f64; 3]) -> PixelReading {
        match self {
            ColourToPressure::Table(t) => t.read(rgb),
            ColourToPressure::Density(d) => d.read(rgb),
        }
    }

    /// Measuring range `(min, max)` in Pa.
    pub fn range_pa(&self) -> (f64, f64) {
        match self {
            ColourToPressure::Table(t) => t.range_pa(),
            ColourToPressure::Density(d) => d.range_pa(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Prescale LW vendor table (values as printed in the app's export).
    pub(crate) fn lw_rows() -> Vec<ColourRow> {
        let t = [
            (0.00, 255.0, 255.0, 255.0),
            (2.00, 0.0, 255.0, 0.0),
            (2.50, 255.0, 227.0, 227.0),
            (3.44, 255.0, 198.0, 198.0),
            (4.38, 255.0, 170.0, 170.0),
            (5.31, 255.0, 142.0, 142.0),
            (6.25, 255.0, 113.0, 113.0),
            (7.19, 255.0, 85.0, 85.0),
            (8.13, 255.0, 57.0, 57.0),
            (9.06, 255.0, 28.0, 28.0),
            (10.00, 255.0, 255.0, 0.0),
        ];
        t.iter()
            .map(|&(p, r, g, b)| ColourRow {
                pressure_pa: p * 1e6,
                rgb: [r, g, b],
            })
            .collect()
    }

    fn lw() -> ColourTable {
        ColourTable::from_rows(lw_rows(), DEFAULT_MAX_COLOUR_DISTANCE, "lw").unwrap()
    }

    #[test]
    fn markers_split_off_the_lw_table() {
        let t = lw();
        assert_eq!(t.graded_rows().len(), 8);
        assert_eq!(t.range_pa(), (2.5e6, 9.06e6));
    }

    #[test]
    fn table_colours_read_back_their_pressure() {
        let t = lw();
        for row in t.graded_rows() {
            let r = t.read(row.rgb);
            assert_eq!(r.class, PixelClass::InRange);
            assert!((r.pressure_pa - row.pressure_pa).abs() < 1e-6);
        }
        // Midway between two rows: linear interpolation along the segment.
        let r = t.read([255.0, 184.0, 184.0]);
        assert!((r.pressure_pa - 3.91e6).abs() < 1e-6 * 3.91e6, "{r:?}");
    }

    #[test]
    fn markers_and_off_curve_colours_are_not_mapped() {
        let t = lw();
        assert_eq!(t.read([255.0; 3]).class, PixelClass::Unstained);
        assert_eq!(t.read([0.0, 255.0, 0.0]).class, PixelClass::BelowRange);
        assert_eq!(t.read([5.0, 250.0, 3.0]).class, PixelClass::BelowRange);
        assert_eq!(t.read([255.0, 255.0, 0.0]).class, PixelClass::AboveRange);
        // Paler than the palest pink: below range, not 2.5 MPa.
        assert_eq!(t.read([255.0, 238.0, 238.0]).class, PixelClass::BelowRange);
        // Deeper than the deepest red: above range.
        assert_eq!(t.read([255.0, 5.0, 5.0]).class, PixelClass::AboveRange);
        // Blue ink, black pen: rejected.
        assert_eq!(t.read([20.0, 40.0, 200.0]).class, PixelClass::OffCurve);
        assert_eq!(t.read([0.0, 0.0, 0.0]).class, PixelClass::OffCurve);
    }

    #[test]
    fn colour_of_inverts_read() {
        let t = lw();
        for p in [2.5e6, 3.0e6, 5.55e6, 9.06e6] {
            let c = t.colour_of(p).unwrap();
            assert!((t.read(c).pressure_pa - p).abs() < 1e-6 * p);
        }
        assert!(t.colour_of(1e6).is_none());
    }

    #[test]
    fn non_monotone_table_is_an_error() {
        let mut rows = lw_rows();
        rows.swap(4, 5);
        let e = ColourTable::from_rows(rows, 20.0, "t.csv").unwrap_err();
        assert!(e.to_string().contains("not monotone in pressure"), "{e}");
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("t.csv");
        std::fs::write(
            &p,
            ";Pressure,R,G,B\n2.5,255,227,227\n3.44,255,198,198\n3.0,255,170,170\n",
        )
        .unwrap();
        let e = ColourTable::read_csv(&p, 20.0).unwrap_err();
        assert!(e.to_string().contains("t.csv:4"), "{e}");
        assert!(e.to_string().contains("not monotone"), "{e}");
    }

    /// MPa values under a `pressure_Pa` header (every pressure below 1 kPa) and a negative
    /// optical density are refused, naming the file and line.
    #[test]
    fn implausible_calibration_files_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("ct.csv");
        std::fs::write(
            &p,
            "pressure_Pa,R,G,B\n2.5,255,227,227\n5,255,100,100\n10,255,0,0\n",
        )
        .unwrap();
        let e = ColourTable::read_csv(&p, 20.0).unwrap_err().to_string();
        assert!(e.contains("ct.csv:1") && e.contains("pressure_MPa"), "{e}");
        // The same values in MPa, and in Pa, are fine.
        std::fs::write(
            &p,
            "pressure_MPa,R,G,B\n0,255,255,255\n2.5,255,227,227\n5,255,100,100\n10,255,0,0\n",
        )
        .unwrap();
        assert_eq!(
            ColourTable::read_csv(&p, 20.0).unwrap().range_pa(),
            (2.5e6, 1e7)
        );
        std::fs::write(
            &p,
            "pressure_Pa,R,G,B\n0,255,255,255\n2.5e6,255,227,227\n5e6,255,100,100\n1e7,255,0,0\n",
        )
        .unwrap();
        assert!(ColourTable::read_csv(&p, 20.0).is_ok());
        let d = dir.path().join("dc.csv");
        std::fs::write(&d, "density,pressure_MPa\n-0.3,2.5\n1,10\n").unwrap();
        let e = DensityCalibration::read_csv(&d).unwrap_err().to_string();
        assert!(e.contains("dc.csv:2") && e.contains("negative"), "{e}");
        std::fs::write(&d, "density,pressure_Pa\n0.3,2.5\n1,10\n").unwrap();
        let e = DensityCalibration::read_csv(&d).unwrap_err().to_string();
        assert!(e.contains("dc.csv:1") && e.contains("1 kPa"), "{e}");
        std::fs::write(&d, "density,pressure_MPa\n0.3,2.5\n1,10\n").unwrap();
        assert!(DensityCalibration::read_csv(&d).is_ok());
    }

    #[test]
    fn density_calibration_interpolates_and_flags_range() {
        let mut d = DensityCalibration::new(vec![(0.1, 1e6), (0.5, 5e6)], "d").unwrap();
        assert_eq!(d.read([255.0; 3]).class, PixelClass::Unstained);
        // With the paper level set, faint stain is below range, not unstained.
        let faint = 255.0 / 10f64.powf(0.05);
        assert_eq!(d.read([faint; 3]).class, PixelClass::Unstained);
        d.unstained_density = 0.02;
        assert_eq!(d.read([faint; 3]).class, PixelClass::BelowRange);
        assert_eq!(d.read([255.0; 3]).class, PixelClass::Unstained);
        assert_eq!(d.read([0.0; 3]).class, PixelClass::AboveRange);
        let grey = 255.0 / 10f64.powf(0.3);
        let r = d.read([grey; 3]);
        assert!((r.pressure_pa - 3e6).abs() < 1e-3, "{r:?}");
        assert!(DensityCalibration::new(vec![(0.1, 1e6), (0.5, 0.5e6)], "d").is_err());
        // A magenta stain read in green; black and blue ink are off-curve, the stain is not.
        let mut m = DensityCalibration::new(vec![(0.1, 1e6), (0.5, 5e6)], "d").unwrap();
        m.channel = crate::film::scan::Channel::Green;
        let m = m.with_stain([230.0, 110.0, 125.0]).unwrap();
        assert_eq!(m.read([240.0, 120.0, 130.0]).class, PixelClass::InRange);
        assert_eq!(m.read([60.0, 60.0, 60.0]).class, PixelClass::OffCurve);
        assert_eq!(m.read([40.0, 60.0, 160.0]).class, PixelClass::OffCurve);
    }
}
