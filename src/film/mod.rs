//! Pressure-measurement film: colour to pressure, smooth polynomial fit, preload per node.
//!
//! * [`colour`]: colour table / density calibration → per-pixel pressure or range class.
//! * [`regions`]: the image as a [`regions::FilmMap`], regions of interest, automatic patch
//!   detection, per-region summaries.
//! * [`polyfit`]: 2-D polynomial least-squares fit with R².
//! * [`nodes`]: contact nodes, placement on the film, tributary areas, preloads `N0 = σ·A`.
//! * [`reduce`]: node reduction on a coarse triangular mesh (area and load preserved).
//! * [`scan`]: raw scans: reading the image (limits, dpi), smoothing, density channel, paper level.
//! * [`pipeline`]: `asperity film` as one call, [`pipeline::FilmConfig`] in,
//!   [`pipeline::FilmReport`] out (maps, regions, fits, node preloads, reduction, messages).

pub mod colour;
pub mod nodes;
pub mod pipeline;
pub mod polyfit;
pub mod reduce;
pub mod regions;
pub mod scan;

use crate::core::error::{Error, Result};

/// What the film says under a contact node: the class of the pixel it lies on. Only these
/// pixels of a region are read by the nodes (see [`FittedRegion`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum NodePixel {
    /// In the film's range: the fit is made from such pixels.
    InRange,
    /// Stained above the film's range (saturated): the pressure is at least the range's top,
    /// whatever the fit, extrapolated there, reads.
    AboveRange,
    /// Stained below the film's range: the pressure is below the range's bottom.
    BelowRange,
    /// Unstained or rejected (ink) pixel enclosed by the region's stain: pressure unknown.
    Hole,
}

impl NodePixel {
    /// Every class, in the order of their names.
    pub const ALL: [NodePixel; 4] = [
        NodePixel::InRange,
        NodePixel::AboveRange,
        NodePixel::BelowRange,
        NodePixel::Hole,
    ];

    /// The class of a `pixel_class` name ([`NodePixel::name`]), `None` for any other text.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|c| c.name() == name)
    }

    /// Name used in output files (`pixel_class` of `preload.csv`).
    pub fn name(self) -> &'static str {
        match self {
            NodePixel::InRange => "in_range",
            NodePixel::AboveRange => "above_range",
            NodePixel::BelowRange => "below_range",
            NodePixel::Hole => "hole",
        }
    }
}

/// A region's fitted pressure field as the contact nodes read it: the polynomial evaluated only
/// on the region's stained pixels (in range, above or below range) and on the unstained or
/// rejected pixels they enclose (holes). Its bounding box is not enough: in the corners of a
/// round patch's box the film is white, the nearest fitted data lie up to `(√2 − 1)·r` away,
/// and an order-4 fit there reads anything. On the reference LW film, nodes 4 mm from patch
/// 1's centre in x and in y (white film inside its box) read 2.39 and 0.99 MPa, and two
/// negative values set to 0, without this check. A region of interest (`--roi-rect-mm`,
/// `--roi-polygon-mm`) holds white film too: its unstained pixels that are not enclosed by
/// stain (4-connected to a pixel outside the region) are refused like white film outside an
/// automatic patch, so an ROI is no way round the check. For an automatic
/// patch (stained core and rim, holes filled) the rule accepts exactly its pixels.
pub struct FittedRegion<'a> {
    map: &'a regions::FilmMap,
    region: &'a regions::Region,
    fit: &'a polyfit::PolyFit2,
    /// The pixels a node may lie on, with their class.
    pixels: std::collections::HashMap<(usize, usize), NodePixel>,
    /// The region's pixels (for the message about a node on white film inside it).
    all: std::collections::HashSet<(usize, usize)>,
}

impl<'a> FittedRegion<'a> {
    /// The fitted field of `region` of `map` read only on its stained pixels and the holes they
    /// enclose.
    pub fn new(
        map: &'a regions::FilmMap,
        region: &'a regions::Region,
        fit: &'a polyfit::PolyFit2,
    ) -> Self {
        use colour::PixelClass;
        let all: std::collections::HashSet<(usize, usize)> =
            region.pixels.iter().copied().collect();
        let (nx, ny) = map.dim();
        let mut pixels = std::collections::HashMap::new();
        let mut unstained = Vec::new();
        for &(i, j) in &region.pixels {
            match map.class[[i, j]] {
                PixelClass::InRange => pixels.insert((i, j), NodePixel::InRange),
                PixelClass::AboveRange => pixels.insert((i, j), NodePixel::AboveRange),
                PixelClass::BelowRange => pixels.insert((i, j), NodePixel::BelowRange),
                PixelClass::Unstained | PixelClass::OffCurve => {
                    unstained.push((i, j));
                    None
                }
            };
        }
        // Holes: 4-connected components of the region's unstained (or rejected) pixels none
        // of whose pixels has a 4-neighbour outside the region or the map.
        let open: std::collections::HashSet<(usize, usize)> = unstained.iter().copied().collect();
        let mut seen = std::collections::HashSet::new();
        for &start in &unstained {
            if !seen.insert(start) {
                continue;
            }
            let mut component = vec![start];
            let mut stack = vec![start];
            let mut enclosed = true;
            while let Some((i, j)) = stack.pop() {
                let nbrs = [
                    (i.checked_sub(1), Some(j)),
                    (Some(i + 1).filter(|&a| a < nx), Some(j)),
                    (Some(i), j.checked_sub(1)),
                    (Some(i), Some(j + 1).filter(|&b| b < ny)),
                ];
                for n in nbrs {
                    let (Some(a), Some(b)) = n else {
                        enclosed = false;
                        continue;
                    };
                    if !all.contains(&(a, b)) {
                        enclosed = false;
                    } else if open.contains(&(a, b)) && seen.insert((a, b)) {
                        component.push((a, b));
                        stack.push((a, b));
                    }
                }
            }
            if enclosed {
                pixels.extend(component.into_iter().map(|p| (p, NodePixel::Hole)));
            }
        }
        Self {
            map,
            region,
            fit,
            pixels,
            all,
        }
    }

    /// The fit itself.
    pub fn fit(&self) -> &polyfit::PolyFit2 {
        self.fit
    }

    /// The class of the pixel under a film point (m): an error when the point lies outside the
    /// film map, off the region, or on unstained film of the region not enclosed by its stain,
    /// where the polynomial would extrapolate.
    pub fn pixel_at(&self, x: f64, y: f64) -> Result<NodePixel> {
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
        let p = (pixel(x, nx), pixel(y, ny));
        if let Some(c) = self.pixels.get(&p) {
            return Ok(*c);
        }
        let [x0, x1, y0, y1] = self.region.bounds_m(map);
        let where_ = if self.all.contains(&p) {
            let what = match self.map.class[[p.0, p.1]] {
                colour::PixelClass::OffCurve => "of a rejected colour",
                _ => "unstained",
            };
            format!(
                "on a pixel of region {} that is {what} and not enclosed by its stain",
                self.region.id
            )
        } else {
            format!("off region {}", self.region.id)
        };
        Err(Error::Data(format!(
            "lies at ({:.3}, {:.3}) mm, {where_} (its {} pixels within {:.3}–{:.3} × \
             {:.3}–{:.3} mm), where the fit would extrapolate: check the node placement (nodes \
             are read only on the region's stained pixels and the holes they enclose)",
            x * 1e3,
            y * 1e3,
            self.region.pixels.len(),
            x0 * 1e3,
            x1 * 1e3,
            y0 * 1e3,
            y1 * 1e3
        )))
    }

    /// Fitted pressure (Pa) at a film point (m): an error where [`Self::pixel_at`] is one.
    pub fn pressure_at(&self, x: f64, y: f64) -> Result<f64> {
        self.pixel_at(x, y)?;
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

    /// A region of interest covering the whole 40 × 40 map around a stained disc (radius 8 px)
    /// whose core (radius 3 px) is above range, with an unstained pixel enclosed at (26, 20), a
    /// below-range rim (8–10 px): nodes are read on the stain and on the enclosed pixel, each
    /// with its class; a node on the white film of the ROI is refused as off the stain.
    #[test]
    fn a_region_of_interest_is_read_only_on_its_stain() {
        let (n, s, c) = (40, 1e-4, 20.0);
        let r = |i: usize, j: usize| (i as f64 - c).hypot(j as f64 - c);
        let class = |i: usize, j: usize| match r(i, j) {
            _ if (i, j) == (26, 20) => PixelClass::Unstained,
            d if d <= 3.0 => PixelClass::AboveRange,
            d if d <= 8.0 => PixelClass::InRange,
            d if d <= 10.0 => PixelClass::BelowRange,
            _ => PixelClass::Unstained,
        };
        let map = regions::FilmMap {
            class: Array2::from_shape_fn((n, n), |(i, j)| class(i, j)),
            pressure_pa: Array2::from_shape_fn((n, n), |(i, j)| {
                if class(i, j) == PixelClass::InRange {
                    9e6 - 1e5 * r(i, j)
                } else {
                    f64::NAN
                }
            }),
            pixel_size_m: s,
        };
        let region = regions::roi_region(
            &map,
            &regions::Roi::Rectangle {
                x0: 0.0,
                y0: 0.0,
                x1: 1.0,
                y1: 1.0,
            },
            1,
        )
        .unwrap();
        assert_eq!(region.pixels.len(), n * n);
        let fit = polyfit::fit(&map.pressure_points(&region.pixels), 2, None).unwrap();
        let field = FittedRegion::new(&map, &region, &fit);
        let at = |i: f64, j: f64| field.pixel_at(i * s, j * s);
        assert_eq!(at(20.0, 20.0).unwrap(), NodePixel::AboveRange);
        assert_eq!(at(25.0, 20.0).unwrap(), NodePixel::InRange);
        assert_eq!(at(26.0, 20.0).unwrap(), NodePixel::Hole);
        assert_eq!(at(20.0, 29.0).unwrap(), NodePixel::BelowRange);
        // White film inside the ROI (and at its border): refused, as off an automatic patch.
        for (i, j) in [(20.0, 32.0), (2.0, 2.0), (0.0, 39.0)] {
            let e = at(i, j).unwrap_err().to_string();
            assert!(
                e.contains("region 1 that is unstained") && e.contains("extrapolate"),
                "{e}"
            );
            assert!(!e.contains("--roi"), "{e}");
            assert!(field.pressure_at(i * s, j * s).is_err());
        }
    }
}
