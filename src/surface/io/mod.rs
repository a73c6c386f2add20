//! Topography files: readers (one module per format) and writers, with [`read`] and [`write`](fn@write)
//! choosing the format from the file name and, for text files, the content.
//!
//! | file | read | write | content |
//! |---|---|---|---|
//! | `.npy` (+ `.npy.json` sidecar) | area | area | float64 heights in m, spacing in the sidecar |
//! | `.x3p` | area | area | ISO 25178-72 zip: `main.xml` + binary heights |
//! | text starting with `Scan Parameters` | profile | — | Bruker Dektak CSV export |
//! | text with a `# unit: …, dx_m: …, dy_m: …` header | area | area (`.csv`, `.txt`, `.asc`) | height matrix |
//! | other text | profile | — | CSV / whitespace columns with a header naming units |
//! | `.png` | — | area | height image with a colour bar |
//!
//! Missing points (NaN heights, the x3p validity mask, `nan` in text) are kept: such a map is
//! read as [`Topography::MaskedArea`] (a profile keeps NaN samples) and written back with its
//! missing points by [`write_topography`] (see [`crate::surface::missing`]). Text files larger
//! than [`crate::core::limits::MAX_TEXT_FILE_BYTES`] are refused before they are read.

pub mod dektak;
pub mod matrix;
pub mod npy;
pub mod png;
pub mod profile_text;
pub mod text;
pub mod units;
pub mod x3p;

use crate::core::error::{Error, Result};
use crate::core::grid::Grid2;
use crate::surface::topography::Topography;
use std::path::Path;

fn extension(path: &Path) -> String {
    path.extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default()
}

/// Read a topography, choosing the reader from the extension and, for text, the content. Its
/// spacings are bounded as every command bounds them ([`crate::core::sanity::grid_spacing`]: 1 pm to
/// 1 m), so that no statistic is computed from a spacing in the wrong unit.
pub fn read(path: &Path) -> Result<Topography> {
    let topo = read_any_spacing(path)?;
    let spacings = match &topo {
        Topography::Profile(p) => vec![("x", p.dx)],
        Topography::Area(g) => vec![("x", g.dx), ("y", g.dy)],
        Topography::MaskedArea(g) => vec![("x", g.dx), ("y", g.dy)],
    };
    for (axis, d) in spacings {
        crate::core::sanity::grid_spacing(d)
            .map_err(|m| Error::parse(path, 0, format!("along {axis}, {m}")))?;
    }
    Ok(topo)
}

fn read_any_spacing(path: &Path) -> Result<Topography> {
    match extension(path).as_str() {
        "npy" => npy::read_topography(path),
        "x3p" => x3p::read_topography(path),
        "png" | "jpg" | "jpeg" | "tif" | "tiff" | "zip" | "json" => Err(Error::parse(
            path,
            0,
            "not a topography format that can be read (known: .npy, .x3p, Dektak CSV, \
             height-matrix or profile text)",
        )),
        _ => {
            let text = text::read_text(path)?;
            if text.trim().is_empty() {
                return Err(Error::parse(path, 0, "empty file"));
            }
            if text.contains('\0') {
                return Err(Error::parse(
                    path,
                    0,
                    "binary file of unknown format (known: .npy, .x3p, Dektak CSV, \
                     height-matrix or profile text)",
                ));
            }
            if dektak::detect(&text) {
                dektak::read(path, &text).map(Topography::Profile)
            } else if matrix::detect(&text) {
                matrix::read(path, &text)
            } else {
                profile_text::read(path, &text).map(Topography::Profile)
            }
        }
    }
}

/// Extensions [`write`](fn@write) accepts.
pub const WRITABLE: &[&str] = &["npy", "x3p", "csv", "txt", "asc", "png"];

/// Check, before any work is done, that `path` names a format [`write`](fn@write) knows.
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

/// Write an area (complete or with missing points), choosing the format from the extension.
/// Missing points are written as NaN (`.npy`, matrix text, x3p with its validity mask) and
/// left blank in a `.png`. A profile cannot be written.
pub fn write_topography(path: &Path, topo: &Topography) -> Result<()> {
    match topo {
        Topography::Area(g) => write(path, g),
        Topography::MaskedArea(m) => {
            check_writable_format(path)?;
            match extension(path).as_str() {
                "npy" => npy::write_field(path, &m.heights, m.dx, m.dy, m.periodic, "m", None),
                "x3p" => x3p::write_masked(path, m),
                "png" => crate::core::plot::heatmap(
                    path,
                    &m.heights,
                    m.dx,
                    m.dy,
                    &crate::core::plot::HeatMap {
                        title: "height map (blank: missing points)",
                        value_label: "height (µm)",
                        value_scale: 1e6,
                        length_scale: 1e6,
                        length_unit: "µm",
                    },
                ),
                _ => matrix::write_values(path, &m.heights, m.dx, m.dy, m.periodic),
            }
        }
        Topography::Profile(_) => Err(Error::param(
            "output",
            format!(
                "cannot write `{}`: profiles are read, not written",
                path.display()
            ),
        )),
    }
}

/// Write a height map, choosing the format from the extension.
pub fn write(path: &Path, grid: &Grid2) -> Result<()> {
    check_writable_format(path)?;
    match extension(path).as_str() {
        "npy" => npy::write(path, grid),
        "x3p" => x3p::write(path, grid),
        "png" => png::write(path, grid, "height map"),
        _ => matrix::write(path, grid),
    }
}

/// Declare topography files read by a command as inputs of its output set `out` (`role` names
/// them in errors), each with its `.npy.json` sidecar where it has one: no output may be either.
pub fn declare_inputs(
    out: &mut crate::core::output::OutputSet,
    files: &[std::path::PathBuf],
    role: &str,
) -> Result<()> {
    for f in files {
        out.input(f, role)?;
        if f.extension().is_some_and(|e| e.eq_ignore_ascii_case("npy")) {
            out.input(
                &npy::sidecar_path(f),
                &format!("the sidecar of {role} {}", f.display()),
            )?;
        }
    }
    Ok(())
}

/// The equivalent rough surface for the contact solvers from one or two topography files
/// (areas of at least [`crate::core::sanity::MIN_CONTACT_FILE_POINTS`] points per side; a profile is
/// refused): one file is the equivalent surface itself; two files are
/// body 1 and body 2 on the same grid, body 2's heights in the common frame (`z` from body 1
/// towards body 2, as `asperity surface combine` takes them), reduced to `h1 − h2` by
/// [`crate::surface::combine::equivalent_surface`] (periodic only when both are). Returns the
/// surface and a description naming the files. Missing points are filled by `fill` (refused
/// without it, naming the file and the `--fill` flag); the description says how many were.
pub fn read_equivalent_surface(
    paths: &[std::path::PathBuf],
    fill: Option<crate::surface::missing::Fill>,
) -> Result<(Grid2, String)> {
    let area = |p: &Path| -> Result<(Grid2, String)> {
        let name = p.display().to_string();
        let (g, report) = crate::surface::missing::complete_area(read(p)?, &name, fill)?;
        crate::core::sanity::contact_file_grid(&name, g.nx(), g.ny())?;
        Ok(match report {
            Some(r) => (
                g,
                format!(
                    "{name} ({} of {} missing points filled, {} fill)",
                    r.filled_points,
                    r.total_points,
                    format!("{:?}", r.method).to_lowercase()
                ),
            ),
            None => (g, name),
        })
    };
    match paths {
        [one] => {
            let (g, name) = area(one)?;
            if let Some(w) = crate::surface::stats::contact_surface_tilt(&name, &g) {
                eprintln!("warning: {w}");
            }
            Ok((g, format!("measured surface {name}")))
        }
        [a, b] => {
            let ((g1, n1), (g2, n2)) = (area(a)?, area(b)?);
            let h = crate::surface::combine::equivalent_surface(&g1, &g2)
                .map_err(|e| Error::Data(format!("{} and {}: {e}", a.display(), b.display())))?;
            // The bodies' tilts count through their difference only.
            let pair = format!("{} − {}", a.display(), b.display());
            if let Some(w) = crate::surface::stats::contact_surface_tilt(&pair, &h) {
                eprintln!("warning: {w}");
            }
            Ok((
                h,
                format!("equivalent surface h1 - h2 of {n1} (body 1) and {n2} (body 2)"),
            ))
        }
        _ => Err(Error::param(
            "surface",
            format!("give one or two surface files, got {}", paths.len()),
        )),
    }
}
