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

/// A region's fitted pressure field as the contact nodes read it: the polynomial evaluated only
/// on the region's own pixels (its stained core, its rim and its filled holes). Its bounding box
/// is not enough: in the corners of a round patch's box the film is white, the nearest fitted
/// data lie up to `(√2 − 1)·r` away, and an order-4 fit there reads anything. On the reference
/// LW film, nodes 4 mm from patch 1's centre in x and in y (white film inside its box) read
/// 2.39 and 0.99 MPa, and two negative values set to 0, before this check.
pub struct FittedRegion<'a> {
    map: &'a regions::FilmMap,
    region: &'a regions::Region,
    fit: &'a polyfit::PolyFit2,
    pixels: std::collections::HashSet<(usize, usize)>,
}

impl<'a> FittedRegion<'a> {
    pub fn new(
        map: &'a regions::FilmMap,
        region: &'a regions::Region,
        fit: &'a polyfit::PolyFit2,
    ) -> Self {
        Self {
            map,
            region,
            fit,
            pixels: region.pixels.iter().copied().collect(),
        }
    }

    /// Fitted pressure (Pa) at a film point (m): an error when the point lies outside the film
    /// map, or on a pixel that is not the region's, where the polynomial would extrapolate.
    pub fn pressure_at(&self, x: f64, y: f64) -> Result<f64> {
        let map = self.map;
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
        let pixel = |v: f64, n: usize| ((v / s).round().max(0.0) as usize).min(n - 1);
        if !self.pixels.contains(&(pixel(x, nx), pixel(y, ny))) {
            let [x0, x1, y0, y1] = self.region.bounds_m(map);
            return Err(Error::Data(format!(
                "lies at ({:.3}, {:.3}) mm, off region {} (its {} pixels within {:.3}–{:.3} × \
                 {:.3}–{:.3} mm), where the fit would extrapolate: check the node placement, or \
                 give a region that covers every node (--roi-rect-mm, --roi-polygon-mm)",
                x * 1e3,
                y * 1e3,
                self.region.id,
                self.region.pixels.len(),
                x0 * 1e3,
                x1 * 1e3,
                y0 * 1e3,
                y1 * 1e3
            )));
        }
        Ok(self.fit.eval(x, y))
    }
}

#[cfg(test)]
mod tests {
    use super::colour::PixelClass;
    use super::*;
    use ndarray::Array2;

    /// A disc of radius 8 px stained with a linear pressure field on a 40 × 40 map (0.1 mm
    /// pixels), its region the disc's pixels, fitted at order 1: a node inside the disc reads
    /// the fit; one in a corner of the disc's bounding box (white film) and one off the map are
    /// errors naming why.
    #[test]
    fn nodes_read_the_fit_on_the_region_and_nowhere_else() {
        let (n, s, c, r) = (40, 1e-4, 20.0, 8.0);
        let inside = |i: usize, j: usize| (i as f64 - c).hypot(j as f64 - c) <= r;
        let sigma = |i: usize, j: usize| 3e6 + 1e5 * i as f64 + 2e4 * j as f64;
        let map = regions::FilmMap {
            class: Array2::from_shape_fn((n, n), |(i, j)| {
                if inside(i, j) {
                    PixelClass::InRange
                } else {
                    PixelClass::Unstained
                }
            }),
            pressure_pa: Array2::from_shape_fn((n, n), |(i, j)| {
                if inside(i, j) {
                    sigma(i, j)
                } else {
                    f64::NAN
                }
            }),
            pixel_size_m: s,
        };
        let region = regions::Region {
            id: 1,
            pixels: (0..n)
                .flat_map(|i| (0..n).map(move |j| (i, j)))
                .filter(|&(i, j)| inside(i, j))
                .collect(),
        };
        let fit = polyfit::fit(&map.pressure_points(&region.pixels), 1, None).unwrap();
        let field = FittedRegion::new(&map, &region, &fit);
        let p = field.pressure_at(23.2 * s, 18.9 * s).unwrap();
        assert!((p - (3e6 + 1e5 * 23.2 + 2e4 * 18.9)).abs() < 1e-3, "{p}");
        // Inside the disc's bounding box (12–28 px), 9.9 px from its centre: white film.
        let e = field
            .pressure_at(13.0 * s, 13.0 * s)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("off region 1") && e.contains("extrapolate"),
            "{e}"
        );
        let e = field.pressure_at(-s, 5.0 * s).unwrap_err().to_string();
        assert!(e.contains("outside the film map"), "{e}");
    }
}
