//! NumPy `.npy` height maps (readable by numpy `np.load` and MATLAB's npy-matlab).
//!
//! The `.npy` file holds the heights in metres, float64, shape `(nx, ny)` in C order
//! (`[[i, j]]` at `(i·dx, j·dy)`, the crate's [`Grid2`] convention). The `.npy` format has no
//! place for the grid spacing, so it travels in a JSON sidecar `<file>.npy.json`:
//! `{"unit": "m", "dx_m": …, "dy_m": …, "periodic": …}`. Both are written atomically.

use crate::error::{Error, Result};
use crate::grid::Grid2;
use crate::output::write_atomic;
use ndarray::Array2;
use ndarray_npy::{ReadNpyExt, WriteNpyExt};
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
}

/// Path of the sidecar of `path` (`surface.npy` → `surface.npy.json`).
pub fn sidecar_path(path: &Path) -> PathBuf {
    let mut s = path.as_os_str().to_owned();
    s.push(".json");
    PathBuf::from(s)
}

/// Write `grid` to `path` (.npy) and its sidecar.
pub fn write(path: &Path, grid: &Grid2) -> Result<()> {
    let meta = serde_json::json!({
        "unit": "m",
        "dx_m": grid.dx,
        "dy_m": grid.dy,
        "periodic": grid.periodic,
    });
    let text = serde_json::to_string_pretty(&meta).expect("JSON of plain numbers") + "\n";
    write_atomic(path, |w| {
        grid.heights
            .as_standard_layout()
            .write_npy(w)
            .map_err(|e| Error::parse(path, 0, format!("writing .npy: {e}")))
    })?;
    crate::output::write_string_atomic(&sidecar_path(path), &text)
}

/// Read a `.npy` height map (float64, 2-D, m) and its sidecar.
pub fn read(path: &Path) -> Result<Grid2> {
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
    if meta.unit != "m" {
        return Err(Error::parse(
            &side,
            0,
            format!("unit must be \"m\", got {:?}", meta.unit),
        ));
    }
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let heights = Array2::<f64>::read_npy(std::io::BufReader::new(file))
        .map_err(|e| Error::parse(path, 0, format!("not a 2-D float64 .npy array: {e}")))?;
    Grid2::new(heights, meta.dx_m, meta.dy_m, meta.periodic)
        .map_err(|e| Error::parse(path, 0, e.to_string()))
}
