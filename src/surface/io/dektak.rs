//! Bruker Dektak stylus-profiler CSV export.
//!
//! The file starts with `Scan Parameters` and key/value lines (stylus, length, resolution, …),
//! then `Analytical Results`, then a `Scan Data` section whose first line is a header naming the
//! units of the lateral position and the height (e.g. `Lateral um,Raw Micrometer,`), followed by
//! `x,z,,` rows. Lateral positions are written rounded (0.1 µm), so the spacing is not exactly
//! uniform; the profile is then kept as a nonuniform line scan with its written positions, as
//! SurfaceTopography does (see [`super::profile_text::profile_from_columns`]).
//!
//! The header's `Length` (e.g. `Length,1500.0 um`) is checked against the data: scan data
//! that end more than two samples (`Resolution`) short of it are a truncated export, reported
//! as such rather than read as a shorter profile.

use crate::core::error::{Error, Result};
use crate::surface::io::profile_text::{profile_from_columns, read_columns};
use crate::surface::io::text::numbered_lines;
use crate::surface::io::units::unit_in_header;
use crate::surface::topography::Profile;
use std::path::Path;

/// First line of a Dektak export.
pub const MAGIC: &str = "Scan Parameters";

/// Whether `text` looks like a Dektak export.
pub fn detect(text: &str) -> bool {
    text.trim_start_matches('\u{feff}').starts_with(MAGIC)
}

/// A `key,<number> <unit>` header value in metres (e.g. `Length,1500.0 um`).
fn header_length(text: &str, key: &str) -> Option<(usize, f64)> {
    numbered_lines(text)
        .take_while(|(_, l)| !l.starts_with("Scan Data"))
        .find_map(|(ln, l)| {
            let rest = l.strip_prefix(key)?.strip_prefix(',')?;
            let mut words = rest.split_whitespace();
            let v: f64 = words.next()?.parse().ok()?;
            let unit = words.next()?.split('/').next()?;
            let f = crate::surface::io::units::metres_per_unit(unit)?;
            Some((ln, v * f))
        })
}

/// Read a Dektak CSV export (positions and heights converted to metres).
pub fn read(path: &Path, text: &str) -> Result<Profile> {
    let declared = header_length(text, "Length");
    let resolution = header_length(text, "Resolution").map(|r| r.1);
    let mut lines = numbered_lines(text);
    lines
        .by_ref()
        .find(|(_, l)| l.starts_with("Scan Data"))
        .ok_or_else(|| Error::parse(path, 0, "Dektak export without a `Scan Data` section"))?;
    let (hl, header) = lines
        .by_ref()
        .find(|(_, l)| !l.trim().is_empty())
        .ok_or_else(|| Error::parse(path, 0, "`Scan Data` section is empty"))?;
    let names: Vec<&str> = header.split(',').map(str::trim).collect();
    if names.len() < 2 {
        return Err(Error::parse(
            path,
            hl,
            format!("expected a header `Lateral <unit>,<height unit>`, found `{header}`"),
        ));
    }
    let mut factors = Vec::new();
    for n in &names[..2] {
        let (f, _) = unit_in_header(n).ok_or_else(|| {
            Error::parse(
                path,
                hl,
                format!("column `{n}` does not name a length unit"),
            )
        })?;
        factors.push(f);
    }
    let (cols, rows) = read_columns(path, lines, 2, &factors)?;
    let mut cols = cols.into_iter();
    let (x, z) = (
        cols.next().unwrap_or_default(),
        cols.next().unwrap_or_default(),
    );
    if let (Some((ln, length)), Some(first), Some(last)) = (declared, x.first(), x.last()) {
        let step = resolution.unwrap_or(0.0).max(0.0);
        let span = last - first;
        if span + 2.0 * step < length * (1.0 - 1e-3) {
            let expected = if step > 0.0 {
                format!(
                    " (about {:.0} samples at the header's Resolution)",
                    length / step
                )
            } else {
                String::new()
            };
            return Err(Error::parse(
                path,
                rows.last().copied().unwrap_or(0),
                format!(
                    "truncated export: the scan data end at {} µm after {} samples, but the \
                     header's Length (line {ln}) is {} µm{expected}",
                    crate::core::error::num(span * 1e6),
                    x.len(),
                    crate::core::error::num(length * 1e6)
                ),
            ));
        }
    }
    profile_from_columns(path, x, z, false, &rows)
}
