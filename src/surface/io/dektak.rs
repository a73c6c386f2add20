//! Bruker Dektak stylus-profiler CSV export.
//!
//! The file starts with `Scan Parameters` and key/value lines (stylus, length, resolution, …),
//! then `Analytical Results`, then a `Scan Data` section whose first line is a header naming the
//! units of the lateral position and the height (e.g. `Lateral um,Raw Micrometer,`), followed by
//! `x,z,,` rows. Lateral positions are written rounded (0.1 µm), so the spacing is not exactly
//! uniform; the profile is then kept as a nonuniform line scan with its written positions, as
//! SurfaceTopography does (see [`super::profile_text::profile_from_columns`]).

use crate::error::{Error, Result};
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

/// Read a Dektak CSV export (positions and heights converted to metres).
pub fn read(path: &Path, text: &str) -> Result<Profile> {
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
    let mut cols = read_columns(path, lines, 2, &factors)?.into_iter();
    let (x, z) = (
        cols.next().unwrap_or_default(),
        cols.next().unwrap_or_default(),
    );
    profile_from_columns(path, x, z, false)
}
