//! 1-D profiles as CSV or whitespace-separated text with a header that names the units.
//!
//! ```text
//! # periodic: false            (optional comment lines, `key: value`)
//! x_um, height_nm              (header: one or two columns, each naming its length unit)
//! 0.0, 12.5
//! 0.5, 13.1
//! ```
//!
//! With two columns the first is the position and the second the height; positions must
//! increase strictly. When the positions are uniformly spaced (to 1e-3 of the spacing, which
//! allows for positions written with few digits) the
//! profile is uniform with spacing `(x_last - x_first)/(n-1)`, otherwise it is kept as a
//! nonuniform profile. With one column (heights only) the spacing comes from a `# dx_m: …`
//! comment. Units: `m`, `mm`, `um`/`µm`, `nm`, `Å`, also spelled out (`Micrometer`).

use crate::error::{Error, Result};
use crate::surface::io::text::{comment_pairs, fields, is_numeric_line, number, numbered_lines};
use crate::surface::io::units::unit_in_header;
use crate::surface::topography::Profile;
use std::path::Path;

/// Relative tolerance on the spacing below which positions count as uniform.
pub const UNIFORM_TOLERANCE: f64 = 1e-3;

/// Profile from positions and heights already in metres: uniform when the spacing is constant
/// to [`UNIFORM_TOLERANCE`], nonuniform otherwise.
pub fn profile_from_columns(
    path: &Path,
    x: Vec<f64>,
    z: Vec<f64>,
    periodic: bool,
) -> Result<Profile> {
    let n = z.len();
    if n < 2 {
        return Err(Error::parse(
            path,
            0,
            format!("a profile needs at least 2 data points, found {n}"),
        ));
    }
    let d = (x[n - 1] - x[0]) / (n - 1) as f64;
    let uniform = d > 0.0
        && x.windows(2)
            .all(|w| ((w[1] - w[0]) - d).abs() <= UNIFORM_TOLERANCE * d);
    let p = if uniform {
        Profile::new(z, d, periodic)
    } else {
        if periodic {
            return Err(Error::parse(
                path,
                0,
                "a nonuniform profile cannot be periodic",
            ));
        }
        Profile::nonuniform(x, z)
    };
    p.map_err(|e| Error::parse(path, 0, e.to_string()))
}

/// Read the numeric rows after a header into positions and heights (m). `lines` yields
/// `(line number, text)`; blank lines are skipped; a row with fewer than `ncols` fields or a
/// non-numeric field is an error naming the line.
pub fn read_columns<'a>(
    path: &Path,
    lines: impl Iterator<Item = (usize, &'a str)>,
    ncols: usize,
    factors: &[f64],
) -> Result<Vec<Vec<f64>>> {
    let mut cols: Vec<Vec<f64>> = vec![Vec::new(); ncols];
    for (ln, line) in lines {
        if line.trim().is_empty() || line.trim_start().starts_with('#') {
            continue;
        }
        let f = fields(line);
        if f.len() < ncols {
            return Err(Error::parse(
                path,
                ln,
                format!("expected {ncols} columns, found {}", f.len()),
            ));
        }
        for c in 0..ncols {
            cols[c].push(number(path, ln, c + 1, f[c])? * factors[c]);
        }
    }
    Ok(cols)
}

/// Read a profile text file (see the module documentation).
pub fn read(path: &Path, text: &str) -> Result<Profile> {
    let mut lines = numbered_lines(text).peekable();
    let (mut dx_m, mut periodic) = (None, false);
    // Comments and blank lines before the header.
    let (hl, header) = loop {
        match lines.next() {
            None => return Err(Error::parse(path, 0, "empty file: no header and no data")),
            Some((ln, l)) if l.trim_start().starts_with('#') => {
                for (k, v) in comment_pairs(l) {
                    match k.as_str() {
                        "dx_m" => dx_m = Some(number(path, ln, 1, &v)?),
                        "periodic" => periodic = v.eq_ignore_ascii_case("true"),
                        _ => {}
                    }
                }
            }
            Some((_, l)) if l.trim().is_empty() => {}
            Some(h) => break h,
        }
    };
    if is_numeric_line(header) {
        return Err(Error::parse(
            path,
            hl,
            "expected a header naming the columns and their units (e.g. `x_m,height_m` or \
             `x (um), z (nm)`), found numbers",
        ));
    }
    let names: Vec<&str> = header
        .split([',', ';', '\t'])
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .collect();
    let names: Vec<&str> = if names.len() == 1 && header.contains(' ') {
        header.split_whitespace().collect()
    } else {
        names
    };
    if names.is_empty() || names.len() > 2 {
        return Err(Error::parse(
            path,
            hl,
            format!(
                "a profile has one column (height) or two (position, height), header has {}",
                names.len()
            ),
        ));
    }
    let mut factors = Vec::new();
    for n in &names {
        let (f, _) = unit_in_header(n).ok_or_else(|| {
            Error::parse(
                path,
                hl,
                format!("column `{n}` does not name its unit (m, mm, um, nm; e.g. `height_um`)"),
            )
        })?;
        factors.push(f);
    }
    let cols = read_columns(path, lines, names.len(), &factors)?;
    if cols[0].is_empty() {
        return Err(Error::parse(path, 0, "no data rows after the header"));
    }
    if names.len() == 2 {
        let mut it = cols.into_iter();
        let (x, z) = (it.next().unwrap_or_default(), it.next().unwrap_or_default());
        profile_from_columns(path, x, z, periodic)
    } else {
        let dx = dx_m.ok_or_else(|| {
            Error::parse(
                path,
                0,
                "a height-only profile needs its spacing in a `# dx_m: …` comment",
            )
        })?;
        let z = cols.into_iter().next().unwrap_or_default();
        Profile::new(z, dx, periodic).map_err(|e| Error::parse(path, 0, e.to_string()))
    }
}
