//! ASCII height matrices (CSV or whitespace-separated) with the units in a header comment.
//!
//! ```text
//! # asperity height matrix
//! # unit: m, dx_m: 2.44140625e-7, dy_m: 2.44140625e-7, periodic: true
//! # rows: y (j = 0..ny-1), columns: x (i = 0..nx-1)
//! 1.2e-7, 3.4e-8, ...
//! ```
//!
//! `unit` is the unit of the heights (`m`, `mm`, `um`, `nm`); `dx_m`, `dy_m` are the grid
//! spacings in metres; `periodic` is optional (`true` or `false`, default false; any other value is
//! refused). A missing point is written
//! `nan` (any case); a matrix with missing points is read as a
//! [`MaskedGrid`](crate::surface::missing::MaskedGrid). As in Gwyddion and
//! SurfaceTopography, each text row holds the heights at successive x for one y. The writer
//! prints every value with Rust's shortest round-trip representation, so a written matrix reads
//! back bit for bit.

use crate::core::error::{Error, Result};
use crate::core::grid::Grid2;
use crate::core::output::write_atomic;
use crate::surface::io::text::{
    comment_pairs, fields, height_or_missing, number, numbered_lines, periodic_flag,
};
use crate::surface::io::units::metres_per_unit;
use crate::surface::topography::Topography;
use ndarray::Array2;
use std::path::Path;

/// Whether the comment header declares a height matrix (has a `dy_m`: only areas have a y
/// spacing; a missing `dx_m` or `unit` is then reported by [`read`]).
pub fn detect(text: &str) -> bool {
    let keys: Vec<String> = numbered_lines(text)
        .take_while(|(_, l)| l.trim_start().starts_with('#') || l.trim().is_empty())
        .flat_map(|(_, l)| comment_pairs(l).into_iter().map(|(k, _)| k))
        .collect();
    keys.iter().any(|k| k == "dy_m")
}

/// Read a height matrix (see the module documentation).
pub fn read(path: &Path, text: &str) -> Result<Topography> {
    let (mut unit, mut dx, mut dy, mut periodic) = (None, None, None, false);
    let mut rows: Vec<Vec<f64>> = Vec::new();
    let mut first_row_line = 0;
    for (ln, line) in numbered_lines(text) {
        let t = line.trim();
        if t.is_empty() {
            continue;
        }
        if t.starts_with('#') {
            for (k, v) in comment_pairs(t) {
                match k.as_str() {
                    "unit" => {
                        unit = Some(metres_per_unit(&v).ok_or_else(|| {
                            Error::parse(path, ln, format!("unknown height unit `{v}`"))
                        })?)
                    }
                    "dx_m" => dx = Some(number(path, ln, 1, &v)?),
                    "dy_m" => dy = Some(number(path, ln, 1, &v)?),
                    "periodic" => periodic = periodic_flag(path, ln, &v)?,
                    _ => {}
                }
            }
            continue;
        }
        let f = fields(t);
        if let Some(first) = rows.first() {
            if f.len() != first.len() {
                return Err(Error::parse(
                    path,
                    ln,
                    format!(
                        "row has {} values, the first row (line {first_row_line}) has {}",
                        f.len(),
                        first.len()
                    ),
                ));
            }
        } else {
            first_row_line = ln;
        }
        let row = f
            .iter()
            .enumerate()
            .map(|(c, s)| height_or_missing(path, ln, c + 1, s))
            .collect::<Result<Vec<f64>>>()?;
        rows.push(row);
    }
    let missing = |k: &str| {
        Error::parse(
            path,
            0,
            format!("height matrix header lacks `{k}` (e.g. `# unit: m, dx_m: 1e-6, dy_m: 1e-6`)"),
        )
    };
    let unit = unit.ok_or_else(|| missing("unit"))?;
    let dx = dx.ok_or_else(|| missing("dx_m"))?;
    let dy = dy.ok_or_else(|| missing("dy_m"))?;
    if rows.is_empty() {
        return Err(Error::parse(path, 0, "height matrix has no data rows"));
    }
    let (ny, nx) = (rows.len(), rows[0].len());
    let heights = Array2::from_shape_fn((nx, ny), |(i, j)| rows[j][i] * unit);
    Topography::from_heights(heights, dx, dy, periodic)
        .map_err(|e| Error::parse(path, 0, e.to_string()))
}

/// Write a height matrix (comma-separated, heights in m) atomically.
pub fn write(path: &Path, grid: &Grid2) -> Result<()> {
    write_values(path, &grid.heights, grid.dx, grid.dy, grid.periodic)
}

/// Write heights (m; NaN written `NaN`: a missing point) as a matrix, atomically.
pub fn write_values(path: &Path, h: &Array2<f64>, dx: f64, dy: f64, periodic: bool) -> Result<()> {
    let (nx, ny) = h.dim();
    write_atomic(path, |w| {
        let io = |e| Error::io(path, e);
        writeln!(w, "# asperity height matrix").map_err(io)?;
        writeln!(w, "# unit: m, dx_m: {dx}, dy_m: {dy}, periodic: {periodic}").map_err(io)?;
        writeln!(
            w,
            "# rows: y (j = 0..{}), columns: x (i = 0..{})",
            ny - 1,
            nx - 1
        )
        .map_err(io)?;
        let mut line = String::new();
        for j in 0..ny {
            line.clear();
            for i in 0..nx {
                if i > 0 {
                    line.push(',');
                }
                line.push_str(&format!("{:?}", h[[i, j]]));
            }
            line.push('\n');
            w.write_all(line.as_bytes()).map_err(io)?;
        }
        Ok(())
    })
}
