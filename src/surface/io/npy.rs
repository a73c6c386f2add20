//! NumPy `.npy` height maps (readable by numpy `np.load` and MATLAB's npy-matlab).
//!
//! The `.npy` file holds the heights in metres, float64, shape `(nx, ny)` in C order
//! (`[[i, j]]` at `(i·dx, j·dy)`, the crate's [`Grid2`] convention); NaN marks a missing point.
//! The `.npy` format has no place for the grid spacing, so it travels in a JSON sidecar
//! `<file>.npy.json`: `{"unit": "m", "dx_m": …, "dy_m": …, "periodic": …}`. Other fields on a
//! regular grid use the same layout with their own unit (e.g. `film`'s `pressure_map_Pa.npy`
//! with `"unit": "Pa"`, read back by [`read_field`]). Both files are written atomically.
//!
//! Before the data are read, the header is checked against the file: the shape must be 2-D,
//! within [`crate::core::limits::MAX_GRID_POINTS`], and the file must hold exactly the bytes the shape
//! promises (a header claiming 10⁶ × 10⁶ values over 32 kB of data is reported as truncated,
//! not allocated).

use crate::core::error::{Error, Result};
use crate::core::grid::Grid2;
use crate::core::output::write_atomic;
use crate::surface::topography::Topography;
use ndarray::Array2;
use ndarray_npy::{ReadNpyExt, WriteNpyExt};
use std::io::Read;
use std::path::{Path, PathBuf};

/// Grid metadata stored beside the `.npy` file.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NpySidecar {
    /// Unit of the heights; always `"m"`.
    pub unit: String,
    /// Grid spacing along x (first array axis), m.
    pub dx_m: f64,
    /// Grid spacing along y (second array axis), m.
    pub dy_m: f64,
    /// Whether the patch is one period of a periodic surface.
    pub periodic: bool,
    /// What the values are, for fields other than heights (e.g. `"contact pressure"`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub quantity: Option<String>,
}

/// Path of the sidecar of `path` (`surface.npy` → `surface.npy.json`).
pub fn sidecar_path(path: &Path) -> PathBuf {
    let mut s = path.as_os_str().to_owned();
    s.push(".json");
    PathBuf::from(s)
}

/// Write `grid` to `path` (.npy) and its sidecar.
pub fn write(path: &Path, grid: &Grid2) -> Result<()> {
    write_field(
        path,
        &grid.heights,
        grid.dx,
        grid.dy,
        grid.periodic,
        "m",
        None,
    )
}

/// Write any field on a regular grid (NaN allowed: missing points) to `path` (.npy) and its
/// sidecar, with its unit and, for fields other than heights, what it is.
pub fn write_field(
    path: &Path,
    values: &Array2<f64>,
    dx: f64,
    dy: f64,
    periodic: bool,
    unit: &str,
    quantity: Option<&str>,
) -> Result<()> {
    let meta = NpySidecar {
        unit: unit.to_string(),
        dx_m: dx,
        dy_m: dy,
        periodic,
        quantity: quantity.map(str::to_string),
    };
    let text = serde_json::to_string_pretty(&meta).expect("JSON of plain numbers") + "\n";
    write_atomic(path, |w| {
        values
            .as_standard_layout()
            .write_npy(w)
            .map_err(|e| Error::parse(path, 0, format!("writing .npy: {e}")))
    })?;
    crate::core::output::write_string_atomic(&sidecar_path(path), &text)
}

/// Header of a `.npy` file: element type, memory order, shape and where the data start.
#[derive(Debug, Clone, PartialEq)]
pub struct NpyHeader {
    /// Numpy type string, e.g. `<f8` (little-endian float64).
    pub descr: String,
    /// Column-major (Fortran) memory order.
    pub fortran_order: bool,
    /// Array shape.
    pub shape: Vec<usize>,
    /// Byte offset of the data from the start of the file.
    pub data_offset: u64,
}

/// The value of `'key':` in a numpy header dict (text up to the next top-level comma).
fn header_value<'a>(dict: &'a str, key: &str) -> Option<&'a str> {
    let start = dict.find(&format!("'{key}'"))? + key.len() + 2;
    let rest = dict[start..].trim_start().strip_prefix(':')?.trim_start();
    let end = if rest.starts_with('(') {
        rest.find(')')? + 1
    } else {
        rest.find(',').unwrap_or(rest.len())
    };
    Some(rest[..end].trim())
}

/// Parse and check the header of a `.npy` file (version 1, 2 or 3) without reading its data.
pub fn read_header(path: &Path) -> Result<NpyHeader> {
    let bad = |m: String| Error::parse(path, 0, m);
    let mut f = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let mut magic = [0u8; 10];
    f.read_exact(&mut magic)
        .map_err(|_| bad("not a .npy file (too short for its header)".into()))?;
    if &magic[..6] != b"\x93NUMPY" {
        return Err(bad("not a .npy file (no \\x93NUMPY magic)".into()));
    }
    let (len, prefix) = match magic[6] {
        1 => (u16::from_le_bytes([magic[8], magic[9]]) as u64, 10u64),
        2 | 3 => {
            let mut rest = [0u8; 2];
            f.read_exact(&mut rest)
                .map_err(|_| bad("truncated .npy header".into()))?;
            (
                u32::from_le_bytes([magic[8], magic[9], rest[0], rest[1]]) as u64,
                12u64,
            )
        }
        v => return Err(bad(format!(".npy format version {v} is not supported"))),
    };
    if len > 1 << 20 {
        return Err(bad(format!(".npy header of {len} bytes: corrupt")));
    }
    let mut dict = vec![0u8; len as usize];
    f.read_exact(&mut dict)
        .map_err(|_| bad("truncated .npy header".into()))?;
    let dict = String::from_utf8_lossy(&dict).into_owned();
    let descr = header_value(&dict, "descr")
        .map(|v| v.trim_matches(|c| c == '\'' || c == '"').to_string())
        .ok_or_else(|| bad("the .npy header has no 'descr'".into()))?;
    let fortran_order = header_value(&dict, "fortran_order")
        .map(|v| v == "True")
        .ok_or_else(|| bad("the .npy header has no 'fortran_order'".into()))?;
    let shape_text =
        header_value(&dict, "shape").ok_or_else(|| bad("the .npy header has no 'shape'".into()))?;
    let shape = shape_text
        .trim_matches(|c| c == '(' || c == ')')
        .split(',')
        .map(str::trim)
        .filter(|t| !t.is_empty())
        .map(|t| t.parse::<usize>())
        .collect::<std::result::Result<Vec<usize>, _>>()
        .map_err(|_| {
            bad(format!(
                "the .npy shape `{shape_text}` is not a tuple of sizes"
            ))
        })?;
    Ok(NpyHeader {
        descr,
        fortran_order,
        shape,
        data_offset: prefix + len,
    })
}

/// Check a height-map header against the file and the limits before reading the data.
fn check_header(path: &Path) -> Result<(usize, usize)> {
    let h = read_header(path)?;
    let bad = |m: String| Error::parse(path, 0, m);
    if h.descr != "<f8" && h.descr != ">f8" {
        return Err(bad(format!(
            "element type `{}`: a height map must be float64 (`<f8`)",
            h.descr
        )));
    }
    if h.shape.len() != 2 {
        return Err(bad(format!(
            "a height map must be a 2-D array, this one has shape {:?}",
            h.shape
        )));
    }
    let (nx, ny) = (h.shape[0], h.shape[1]);
    let file_len = std::fs::metadata(path)
        .map_err(|e| Error::io(path, e))?
        .len();
    let data = file_len.saturating_sub(h.data_offset);
    let want = (nx as u64)
        .checked_mul(ny as u64)
        .and_then(|n| n.checked_mul(8));
    if want != Some(data) {
        return Err(bad(format!(
            "the header promises {nx} × {ny} float64 values ({} bytes) but the file holds {data} \
             bytes of data: truncated or corrupt",
            want.map_or("more than 2^64".to_string(), |w| w.to_string())
        )));
    }
    crate::core::limits::check_grid(
        &path.display().to_string(),
        nx,
        ny,
        crate::core::limits::STATS_BYTES_PER_POINT,
    )?;
    Ok((nx, ny))
}

/// Read a `.npy` field (float64, 2-D) and its sidecar: the values (NaN allowed) and the
/// sidecar. The header is checked against the file first.
pub fn read_field(path: &Path) -> Result<(Array2<f64>, NpySidecar)> {
    if !path.exists() {
        return Err(Error::io(
            path,
            std::io::Error::new(std::io::ErrorKind::NotFound, "no such file"),
        ));
    }
    let side = sidecar_path(path);
    let meta_text = std::fs::read_to_string(&side).map_err(|e| {
        Error::parse(
            path,
            0,
            format!(
                "the grid spacing of a .npy file is read from its sidecar {}: {e}",
                side.display()
            ),
        )
    })?;
    let meta: NpySidecar = serde_json::from_str(&meta_text)
        .map_err(|e| Error::parse(&side, e.line(), format!("bad sidecar: {e}")))?;
    for (k, v) in [("dx_m", meta.dx_m), ("dy_m", meta.dy_m)] {
        if !(v.is_finite() && v > 0.0) {
            return Err(Error::parse(
                &side,
                0,
                format!(
                    "`{k}` must be finite and > 0, got {}",
                    crate::core::error::num(v)
                ),
            ));
        }
    }
    check_header(path)?;
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let values = Array2::<f64>::read_npy(std::io::BufReader::new(file))
        .map_err(|e| Error::parse(path, 0, format!("not a 2-D float64 .npy array: {e}")))?;
    Ok((values, meta))
}

/// Read a `.npy` height map (float64, 2-D, m; NaN = missing point) and its sidecar.
pub fn read_topography(path: &Path) -> Result<Topography> {
    let (heights, meta) = read_field(path)?;
    if meta.unit != "m" || meta.quantity.is_some() {
        return Err(Error::parse(
            sidecar_path(path),
            0,
            format!(
                "holds {} in {:?}, not heights in \"m\"",
                meta.quantity.as_deref().unwrap_or("values"),
                meta.unit
            ),
        ));
    }
    Topography::from_heights(heights, meta.dx_m, meta.dy_m, meta.periodic)
        .map_err(|e| Error::parse(path, 0, e.to_string()))
}

/// Read a complete `.npy` height map (an error when points are missing).
pub fn read(path: &Path) -> Result<Grid2> {
    read_topography(path)?.into_area(&path.display().to_string())
}
