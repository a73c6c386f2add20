//! Pressure-measurement film: colour to pressure, smooth polynomial fit, preload per node.
//!
//! * [`colour`]: colour table / density calibration → per-pixel pressure or range class.
//! * [`regions`]: the image as a [`regions::FilmMap`], regions of interest, automatic patch
//!   detection, per-region summaries.
//! * [`polyfit`]: 2-D polynomial least-squares fit with R².
//! * [`nodes`]: contact nodes, placement on the film, tributary areas, preloads `N0 = σ·A`.
//! * [`reduce`]: node reduction on a coarse triangular mesh (area and load preserved).
//! * [`scan`]: raw scans: reading the image (limits, dpi), smoothing, density channel, paper level.

pub mod colour;
pub mod nodes;
pub mod polyfit;
pub mod reduce;
pub mod regions;
pub mod scan;

use crate::error::{Error, Result};

/// Fitted pressure (Pa) at a film point (m) for a node placed on `region`: an error when the point
/// lies outside the film map, or outside the region's bounding box (pixel edges included), where the
/// polynomial would extrapolate.
pub fn fitted_pressure_at(
    map: &regions::FilmMap,
    region: &regions::Region,
    fit: &polyfit::PolyFit2,
    x: f64,
    y: f64,
) -> Result<f64> {
    let (nx, ny) = map.dim();
    let s = map.pixel_size_m;
    if !map.contains(x, y) {
        return Err(Error::Data(format!(
            "lies at ({:.3}, {:.3}) mm, outside the film map (0–{:.3} × 0–{:.3} mm): check the node placement",
            x * 1e3,
            y * 1e3,
            nx as f64 * s * 1e3,
            ny as f64 * s * 1e3
        )));
    }
    let [x0, x1, y0, y1] = region.bounds_m(map);
    if x < x0 || x > x1 || y < y0 || y > y1 {
        return Err(Error::Data(format!(
            "lies at ({:.3}, {:.3}) mm, outside region {} ({:.3}–{:.3} × {:.3}–{:.3} mm), where the fit would extrapolate",
            x * 1e3,
            y * 1e3,
            region.id,
            x0 * 1e3,
            x1 * 1e3,
            y0 * 1e3,
            y1 * 1e3
        )));
    }
    Ok(fit.eval(x, y))
}
