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
//! comment. Units: `m`, `mm`, `um`/`µm`, `nm`, `Å`, also spelled out (`Micrometer`). A missing
//! height is written `nan`; only a uniform profile can have missing points. Errors name the
//! file line.

use crate::core::error::{Error, Result};
use crate::surface::io::text::{
    comment_pairs, fields, height_or_missing, is_numeric_line, number, numbered_lines,
    periodic_flag,
};
use crate::surface::io::units::unit_in_header;
use crate::surface::topography::Profile;
use std::path::Path;

/// Relative tolerance on the spacing below which positions count as uniform.
pub const UNIFORM_TOLERANCE: f64 = 1e-3;

/// Profile from positions and heights already in metres (`lines`: the file line of each
/// sample, for errors): uniform when the spacing is constant to [`UNIFORM_TOLERANCE`],
/// nonuniform otherwise. Missing heights (NaN) are allowed in a uniform profile only.
pub fn profile_from_columns(
    path: &Path,
    x: Vec<f64>,
    z: Vec<f64>,
    periodic: bool,
    lines: &[usize],
) -> Result<Profile> {
    let n = z.len();
    if n < 2 {
        return Err(Error::parse(
            path,
            0,
            format!("a profile needs at least 2 data points, found {n}"),
        ));
    }
    let line = |k: usize| lines.get(k).copied().unwrap_or(0);
    if let Some(k) = (1..n).find(|&k| x[k] <= x[k - 1]) {
        return Err(Error::parse(
            path,
            line(k),
            format!(
                "positions must increase strictly: {} m follows {} m (line {})",
                crate::core::error::num(x[k]),
                crate::core::error::num(x[k - 1]),
                line(k - 1)
            ),
        ));
    }
    let d = (x[n - 1] - x[0]) / (n - 1) as f64;
    let uniform = d > 0.0
        && x.windows(2)
            .all(|w| ((w[1] - w[0]) - d).abs() <= UNIFORM_TOLERANCE * d);
    let missing = z.iter().position(|v| v.is_nan());
    let p = if uniform {
        if missing.is_some() {
            Profile::with_missing(z, d, periodic)
        } else {
            Profile::new(z, d, periodic)
        }
    } else if let Some(k) = missing {
        return Err(Error::parse(
            path,
            line(k),
            "missing height (nan) in a nonuniform profile: only a uniformly spaced profile can \
             have missing points; remove the row",
        ));
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

/// Read the numeric rows after a header into positions and heights (m), with the line of each
/// row. `lines` yields `(line number, text)`; blank lines are skipped; a row with fewer than
/// `ncols` fields or a non-numeric field is an error naming the line. The last column (the
/// heights) may hold `nan` (a missing point).
pub fn read_columns<'a>(
    path: &Path,
    lines: impl Iterator<Item = (usize, &'a str)>,
    ncols: usize,
    factors: &[f64],
) -> Result<(Vec<Vec<f64>>, Vec<usize>)> {
    let mut cols: Vec<Vec<f64>> = vec![Vec::new(); ncols];
    let mut rows = Vec::new();
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
            let v = if c + 1 == ncols {
                height_or_missing(path, ln, c + 1, f[c])?
            } else {
                number(path, ln, c + 1, f[c])?
            };
            cols[c].push(v * factors[c]);
        }
        rows.push(ln);
    }
    Ok((cols, rows))
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
                        "periodic" => periodic = periodic_flag(path, ln, &v)?,
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
    let (cols, rows) = read_columns(path, lines, names.len(), &factors)?;
    if cols[0].is_empty() {
        return Err(Error::parse(path, 0, "no data rows after the header"));
    }
    if names.len() == 2 {
        let mut it = cols.into_iter();
        let (x, z) = (it.next().unwrap_or_default(), it.next().unwrap_or_default());
        profile_from_columns(path, x, z, periodic, &rows)
    } else {
        let dx = dx_m.ok_or_else(|| {
            Error::parse(
                path,
                0,
                "a height-only profile needs its spacing in a `# dx_m: …` comment",
            )
        })?;
        let z = cols.into_iter().next().unwrap_or_default();
        let p = if z.iter().any(|v| v.is_nan()) {
            Profile::with_missing(z, dx, periodic)
        } else {
            Profile::new(z, dx, periodic)
        };
        p.map_err(|e| Error::parse(path, 0, e.to_string()))
    }
}
