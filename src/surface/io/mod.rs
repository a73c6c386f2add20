//! Topography files: readers (one module per format) and writers, with [`read`] and [`write`]
//! choosing the format from the file name (and, for text files, the content).
//!
//! | extension | read | write | content |
//! |---|---|---|---|
//! | `.npy` (+ `.npy.json` sidecar) | 2-D | 2-D | float64 heights in m, spacing in the sidecar |
//! | `.png` | — | 2-D | height image (µm) with a colour bar |

pub mod npy;
pub mod png;

use crate::error::{Error, Result};
use crate::grid::Grid2;
use crate::surface::topography::Topography;
use std::path::Path;

fn extension(path: &Path) -> String {
    path.extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default()
}

/// Read a topography, choosing the reader from the extension (and content for text files).
pub fn read(path: &Path) -> Result<Topography> {
    match extension(path).as_str() {
        "npy" => npy::read(path).map(Topography::Area),
        other => Err(Error::parse(
            path,
            0,
            format!("unknown topography format `.{other}` (known: .npy)"),
        )),
    }
}

/// Extensions [`write`] accepts.
pub const WRITABLE: &[&str] = &["npy", "png"];

/// Check, before any work is done, that `path` names a format [`write`] knows.
pub fn check_writable_format(path: &Path) -> Result<()> {
    let ext = extension(path);
    if WRITABLE.contains(&ext.as_str()) {
        Ok(())
    } else {
        Err(Error::param(
            "output",
            format!(
                "cannot write `{}`: known formats {}",
                path.display(),
                WRITABLE
                    .iter()
                    .map(|e| format!(".{e}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        ))
    }
}

/// Write a height map, choosing the format from the extension.
pub fn write(path: &Path, grid: &Grid2) -> Result<()> {
    match extension(path).as_str() {
        "npy" => npy::write(path, grid),
        "png" => png::write(path, grid, "height map"),
        _ => check_writable_format(path),
    }
}
