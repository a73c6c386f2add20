//! The film image as a pressure map, and the regions of it that carry pressure.
//!
//! ## Frame
//! The film frame is right-handed with x to the right and y **upwards**, in metres, origin at the
//! centre of the image's bottom-left pixel: pixel (column `c`, row `r` counted from the top of an
//! image `H` pixels high) is sample `[[i, j]] = [[c, H − 1 − r]]` at `(i·s, j·s)` with `s` the
//! pixel size, the [`crate::core::grid::Grid2`] convention. Image tools (and the authors of the
//! reference data) count y downwards from the top: `y_down = (H − 1)·s − y`.
//!
//! ## Regions
//! A region is a set of pixels: a rectangle, a polygon, or a *patch* found automatically as a
//! connected component (8-neighbour) of pressure-bearing pixels (in range or above range), with
//! the holes inside it filled (an unstained pixel enclosed by a patch is contact below the film's
//! range, not background), plus a thin rim of stained below-range pixels around it (the edge of
//! the contact, where the film is coloured but below its range). Components whose core is smaller
//! than a minimum equivalent diameter are discarded and counted. Below-range and off-curve pixels
//! never seed a patch, so the green pen marks and tape of a vendor rendering are not patches.
//!
//! **Marks are rejected by their shape** ([`PatchOptions`]): on a raw scan read by density, pen
//! strokes and handwriting are as dense as stain. A contact patch is compact; a stroke is thin
//! and elongated, a written label is thin and hollow. Each candidate (holes filled) is rejected
//! when its **elongation** `√(λ₁/λ₂)` (λ: principal second moments of its pixels) exceeds
//! `max_elongation` (default 3), or its **solidity**, the stained pixels over the area of its
//! convex hull, is below `min_solidity` (default 0.6: a filled disc has ≈ 1, the outline of a
//! written `0` ≈ 0.5, a word much less). Rejected marks are counted.

use super::colour::{ColourToPressure, PixelClass};
use super::scan::RgbImage;
use crate::core::error::{Error, Result};
use ndarray::Array2;
use std::path::Path;

/// A film image read into pressure: per-pixel class and pressure (Pa, NaN unless in range).
#[derive(Debug, Clone)]
pub struct FilmMap {
    /// Per-pixel class, shape `(nx, ny)` (see the module's frame convention).
    pub class: Array2<PixelClass>,
    /// Pressure in Pa, `NaN` unless the pixel is in range.
    pub pressure_pa: Array2<f64>,
    /// Pixel size in m (square pixels).
    pub pixel_size_m: f64,
}

impl FilmMap {
    /// Image width and height in pixels `(nx, ny)`.
    pub fn dim(&self) -> (usize, usize) {
        self.class.dim()
    }

    /// Position `(x, y)` in m of sample `[[i, j]]`.
    pub fn position(&self, i: usize, j: usize) -> (f64, f64) {
        (i as f64 * self.pixel_size_m, j as f64 * self.pixel_size_m)
    }

    /// The in-range samples of `pixels` as `(x_m, y_m, pressure_Pa)`: the data a smooth fit of a
    /// region is made from (below-, above-range and rejected pixels carry no pressure).
    pub fn pressure_points(&self, pixels: &[(usize, usize)]) -> Vec<(f64, f64, f64)> {
        pixels
            .iter()
            .filter(|&&(i, j)| self.pressure_pa[[i, j]].is_finite())
            .map(|&(i, j)| {
                let (x, y) = self.position(i, j);
                (x, y, self.pressure_pa[[i, j]])
            })
            .collect()
    }

    /// Physical extent: the map covers `[-s/2, (nx − 1/2)·s] × [-s/2, (ny − 1/2)·s]`.
    pub fn contains(&self, x: f64, y: f64) -> bool {
        let (nx, ny) = self.dim();
        let s = self.pixel_size_m;
        x >= -0.5 * s && y >= -0.5 * s && x <= (nx as f64 - 0.5) * s && y <= (ny as f64 - 0.5) * s
    }

    /// Build the map from an RGB raster (0–255 values, rows top to bottom as stored in images).
    pub fn from_rgb(
        width: usize,
        height: usize,
        rgb_at: impl Fn(usize, usize) -> [f64; 3] + Sync,
        reader: &ColourToPressure,
        pixel_size_m: f64,
    ) -> Result<Self> {
        if width == 0 || height == 0 {
            return Err(Error::Data("film image has no pixels".into()));
        }
        Self::from_image(
            &RgbImage::from_fn(width, height, rgb_at),
            reader,
            pixel_size_m,
        )
    }

    /// Build the map from an image in the film frame.
    pub fn from_image(
        img: &RgbImage,
        reader: &ColourToPressure,
        pixel_size_m: f64,
    ) -> Result<Self> {
        crate::core::error::require_positive("pixel_size_m", pixel_size_m)?;
        let (width, height) = img.dim();
        if width == 0 || height == 0 {
            return Err(Error::Data("film image has no pixels".into()));
        }
        let mut class = Array2::from_elem((width, height), PixelClass::Unstained);
        let mut pressure = Array2::from_elem((width, height), f64::NAN);
        for j in 0..height {
            for i in 0..width {
                let r = reader.read(img.rgb(i, j));
                class[[i, j]] = r.class;
                pressure[[i, j]] = r.pressure_pa;
            }
        }
        Ok(Self {
            class,
            pressure_pa: pressure,
            pixel_size_m,
        })
    }

    /// Read a PNG, JPEG or TIFF image (8 or 16 bit; 16-bit precision is kept), its size checked
    /// against the limits first (see [`crate::film::scan::read_rgb`]).
    pub fn read_image(path: &Path, reader: &ColourToPressure, pixel_size_m: f64) -> Result<Self> {
        let img = super::scan::read_rgb(path)?;
        Self::from_image(&img, reader, pixel_size_m)
    }

    /// Pixel counts per class over the whole image.
    pub fn class_counts(&self) -> ClassCounts {
        let mut c = ClassCounts::default();
        for k in self.class.iter() {
            c.add(*k);
        }
        c
    }
}

/// Number of pixels of each class.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct ClassCounts {
    /// Pixels inside the calibrated pressure range.
    pub in_range: usize,
    /// Unstained (white) pixels.
    pub unstained: usize,
    /// Stained pixels below the film's measuring range.
    pub below_range: usize,
    /// Pixels at or above the upper end of the range (saturated).
    pub above_range: usize,
    /// Pixels whose colour is far from the colour curve and every marker (rejected).
    pub off_curve: usize,
}

impl ClassCounts {
    fn add(&mut self, k: PixelClass) {
        match k {
            PixelClass::InRange => self.in_range += 1,
            PixelClass::Unstained => self.unstained += 1,
            PixelClass::BelowRange => self.below_range += 1,
            PixelClass::AboveRange => self.above_range += 1,
            PixelClass::OffCurve => self.off_curve += 1,
        }
    }

    /// Total pixel count.
    pub fn total(&self) -> usize {
        self.in_range + self.unstained + self.below_range + self.above_range + self.off_curve
    }
}

/// A region of interest given by the user, in film-frame metres.
#[derive(Debug, Clone, PartialEq)]
pub enum Roi {
    /// Axis-aligned rectangle `[x0, x1] × [y0, y1]`.
    Rectangle {
        /// Left edge (m).
        x0: f64,
        /// Bottom edge (m).
        y0: f64,
        /// Right edge (m).
        x1: f64,
        /// Top edge (m).
        y1: f64,
    },
    /// Closed polygon (vertices in order, at least 3); pixel centres inside are taken
    /// (even-odd rule).
    Polygon(Vec<(f64, f64)>),
}

/// A set of pixels of the map, with an id.
#[derive(Debug, Clone)]
pub struct Region {
    /// Region id (1-based, in the order found or given).
    pub id: usize,
    /// Pixel indices `(i, j)`.
    pub pixels: Vec<(usize, usize)>,
}

impl Region {
    /// Bounding box `[x0, x1, y0, y1]` (m) of the region's pixels, pixel edges included.
    pub fn bounds_m(&self, map: &FilmMap) -> [f64; 4] {
        let s = map.pixel_size_m;
        let i0 = self.pixels.iter().map(|p| p.0).min().unwrap_or(0);
        let i1 = self.pixels.iter().map(|p| p.0).max().unwrap_or(0);
        let j0 = self.pixels.iter().map(|p| p.1).min().unwrap_or(0);
        let j1 = self.pixels.iter().map(|p| p.1).max().unwrap_or(0);
        [
            (i0 as f64 - 0.5) * s,
            (i1 as f64 + 0.5) * s,
            (j0 as f64 - 0.5) * s,
            (j1 as f64 + 0.5) * s,
        ]
    }
}

fn point_in_polygon(x: f64, y: f64, poly: &[(f64, f64)]) -> bool {
    let mut inside = false;
    let n = poly.len();
    let mut j = n - 1;
    for i in 0..n {
        let (xi, yi) = poly[i];
        let (xj, yj) = poly[j];
        if (yi > y) != (yj > y) && x < (xj - xi) * (y - yi) / (yj - yi) + xi {
            inside = !inside;
        }
        j = i;
    }
    inside
}

/// The pixels of `map` whose centres lie inside `roi`. Errors when the ROI is malformed or
/// holds no pixel.
pub fn roi_region(map: &FilmMap, roi: &Roi, id: usize) -> Result<Region> {
    let (nx, ny) = map.dim();
    let inside: Box<dyn Fn(f64, f64) -> bool> = match roi {
        Roi::Rectangle { x0, y0, x1, y1 } => {
            for (n, v) in [("x0", x0), ("y0", y0), ("x1", x1), ("y1", y1)] {
                crate::core::error::require_finite(&format!("roi rectangle {n}"), *v)?;
            }
            if x1 <= x0 || y1 <= y0 {
                return Err(Error::param(
                    "roi rectangle",
                    format!("needs x0 < x1 and y0 < y1, got x {x0}..{x1}, y {y0}..{y1}"),
                ));
            }
            let (x0, y0, x1, y1) = (*x0, *y0, *x1, *y1);
            Box::new(move |x, y| x >= x0 && x <= x1 && y >= y0 && y <= y1)
        }
        Roi::Polygon(p) => {
            if p.len() < 3 || p.iter().any(|(x, y)| !x.is_finite() || !y.is_finite()) {
                return Err(Error::param(
                    "roi polygon",
                    "needs at least 3 finite vertices",
                ));
            }
            let p = p.clone();
            Box::new(move |x, y| point_in_polygon(x, y, &p))
        }
    };
    let mut pixels = Vec::new();
    for i in 0..nx {
        for j in 0..ny {
            let (x, y) = map.position(i, j);
            if inside(x, y) {
                pixels.push((i, j));
            }
        }
    }
    if pixels.is_empty() {
        let what = match roi {
            Roi::Rectangle { x0, y0, x1, y1 } => format!(
                "the rectangle {:.4}–{:.4} × {:.4}–{:.4} mm",
                x0 * 1e3,
                x1 * 1e3,
                y0 * 1e3,
                y1 * 1e3
            ),
            Roi::Polygon(p) => format!("the polygon of {} vertices", p.len()),
        };
        return Err(Error::Data(format!(
            "region of interest: {what} contains no pixel of the {nx} × {ny} film map (extent {:.4} × {:.4} mm)",
            nx as f64 * map.pixel_size_m * 1e3,
            ny as f64 * map.pixel_size_m * 1e3
        )));
    }
    Ok(Region { id, pixels })
}

/// Result of automatic patch detection.
#[derive(Debug, Clone)]
pub struct PatchDetection {
    /// Patches, numbered 1, 2, … from the top of the image, then left to right.
    pub patches: Vec<Region>,
    /// Connected components discarded as smaller than the minimum diameter.
    pub discarded_small: usize,
    /// Components of the minimum size rejected by their shape as marks (pen strokes, labels).
    pub rejected_marks: usize,
}

/// Settings of automatic patch detection (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct PatchOptions {
    /// Smallest equivalent diameter `√(4A/π)` of a patch's pressure-bearing core (m).
    pub min_diameter_m: f64,
    /// Width of the below-range rim joined to a patch (pixels).
    pub rim_pixels: usize,
    /// Largest elongation `√(λ₁/λ₂)` of a patch.
    pub max_elongation: f64,
    /// Smallest solidity (stained pixels / convex hull area) of a patch.
    pub min_solidity: f64,
}

/// Default largest elongation of a patch.
pub const DEFAULT_MAX_ELONGATION: f64 = 3.0;
/// Default smallest solidity of a patch.
pub const DEFAULT_MIN_SOLIDITY: f64 = 0.6;

impl PatchOptions {
    /// Options with the default shape limits.
    pub fn new(min_diameter_m: f64, rim_pixels: usize) -> Self {
        Self {
            min_diameter_m,
            rim_pixels,
            max_elongation: DEFAULT_MAX_ELONGATION,
            min_solidity: DEFAULT_MIN_SOLIDITY,
        }
    }
}

/// Shape of a set of pixels: `(elongation, solidity)` with solidity = stained pixels of the
/// set over the area of the convex hull of the pixels' squares.
pub fn shape(map: &FilmMap, pixels: &[(usize, usize)]) -> (f64, f64) {
    let n = pixels.len() as f64;
    let (mx, my) = (
        pixels.iter().map(|p| p.0 as f64).sum::<f64>() / n,
        pixels.iter().map(|p| p.1 as f64).sum::<f64>() / n,
    );
    let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
    for &(i, j) in pixels {
        let (a, b) = (i as f64 - mx, j as f64 - my);
        sxx += a * a;
        syy += b * b;
        sxy += a * b;
    }
    // A pixel is a unit square: its own second moment 1/12 along each axis.
    let (sxx, syy, sxy) = (sxx / n + 1.0 / 12.0, syy / n + 1.0 / 12.0, sxy / n);
    let tr = 0.5 * (sxx + syy);
    let disc = (0.25 * (sxx - syy).powi(2) + sxy * sxy).sqrt();
    let elongation = ((tr + disc) / (tr - disc).max(1e-12)).sqrt();
    // Convex hull of the pixel squares: the extreme squares of every row suffice.
    let mut rows: std::collections::BTreeMap<usize, (usize, usize)> = Default::default();
    for &(i, j) in pixels {
        let e = rows.entry(j).or_insert((i, i));
        e.0 = e.0.min(i);
        e.1 = e.1.max(i);
    }
    let mut pts: Vec<(f64, f64)> = Vec::with_capacity(4 * rows.len());
    for (&j, &(a, b)) in &rows {
        let (y0, y1) = (j as f64 - 0.5, j as f64 + 0.5);
        pts.extend([
            (a as f64 - 0.5, y0),
            (a as f64 - 0.5, y1),
            (b as f64 + 0.5, y0),
            (b as f64 + 0.5, y1),
        ]);
    }
    let hull = convex_hull_area(pts);
    let stained = pixels
        .iter()
        .filter(|&&(i, j)| {
            matches!(
                map.class[[i, j]],
                PixelClass::InRange | PixelClass::AboveRange | PixelClass::BelowRange
            )
        })
        .count() as f64;
    (elongation, stained / hull.max(1.0))
}

/// Area of the convex hull of points (Andrew's monotone chain, shoelace formula).
fn convex_hull_area(mut p: Vec<(f64, f64)>) -> f64 {
    p.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    p.dedup();
    if p.len() < 3 {
        return 0.0;
    }
    let cross = |o: (f64, f64), a: (f64, f64), b: (f64, f64)| {
        (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0)
    };
    let mut hull: Vec<(f64, f64)> = Vec::with_capacity(2 * p.len());
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &(f64, f64)>> = if pass == 0 {
            Box::new(p.iter())
        } else {
            Box::new(p.iter().rev())
        };
        for &q in iter {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], q) <= 0.0
            {
                hull.pop();
            }
            hull.push(q);
        }
        hull.pop();
    }
    let m = hull.len();
    0.5 * (0..m)
        .map(|k| {
            let (a, b) = (hull[k], hull[(k + 1) % m]);
            a.0 * b.1 - b.0 * a.1
        })
        .sum::<f64>()
        .abs()
}

/// Default width of the below-range rim joined to a patch (pixels).
pub const DEFAULT_RIM_PIXELS: usize = 3;

/// Find patches: 8-connected components of pressure-bearing pixels (in range or above range),
/// extended by the stained below-range pixels within `rim_pixels` 8-neighbour steps of them (the
/// contact edge, where the film is stained but below its range), holes filled. Only components
/// whose pressure-bearing core alone has an equivalent diameter `√(4A/π)` of at least
/// `min_diameter_m` are kept (specks of faint colour inside pen marks or tape are not). The rim is
/// bounded so that a pen mark or tape touching a patch is not swallowed whole.
pub fn detect_patches(
    map: &FilmMap,
    min_diameter_m: f64,
    rim_pixels: usize,
) -> Result<PatchDetection> {
    detect_patches_with(map, &PatchOptions::new(min_diameter_m, rim_pixels))
}

/// Patches as [`detect_patches`], with shape limits against marks (see the module
/// documentation).
pub fn detect_patches_with(map: &FilmMap, opts: &PatchOptions) -> Result<PatchDetection> {
    detect_components(map, opts, |c| {
        matches!(c, PixelClass::InRange | PixelClass::AboveRange)
    })
}

/// Stained regions entirely below the measuring range: components of below-range pixels of at
/// least the minimum diameter that pass the shape test (for the message that says so when no
/// pressure-bearing patch is found).
pub fn detect_below_range(map: &FilmMap, opts: &PatchOptions) -> Result<PatchDetection> {
    detect_components(
        map,
        &PatchOptions {
            rim_pixels: 0,
            ..*opts
        },
        |c| c == PixelClass::BelowRange,
    )
}

fn detect_components(
    map: &FilmMap,
    opts: &PatchOptions,
    seed: impl Fn(PixelClass) -> bool,
) -> Result<PatchDetection> {
    let (min_diameter_m, rim_pixels) = (opts.min_diameter_m, opts.rim_pixels);
    crate::core::error::require_positive("min_patch_diameter_m", min_diameter_m)?;
    crate::core::error::require_positive("max_elongation", opts.max_elongation)?;
    if !(opts.min_solidity.is_finite() && (0.0..=1.0).contains(&opts.min_solidity)) {
        return Err(Error::param(
            "min_solidity",
            format!(
                "must lie in [0, 1], got {}",
                crate::core::error::num(opts.min_solidity)
            ),
        ));
    }
    let (nx, ny) = map.dim();
    let bearing = |i: usize, j: usize| seed(map.class[[i, j]]);
    let mut label = Array2::<usize>::zeros((nx, ny));
    let mut comps: Vec<Vec<(usize, usize)>> = Vec::new();
    // label: 0 = none, k = component k (1-based).
    for i0 in 0..nx {
        for j0 in 0..ny {
            if label[[i0, j0]] != 0 || !bearing(i0, j0) {
                continue;
            }
            let id = comps.len() + 1;
            let mut stack = vec![(i0, j0)];
            label[[i0, j0]] = id;
            let mut pix = Vec::new();
            while let Some((i, j)) = stack.pop() {
                pix.push((i, j));
                for di in -1i64..=1 {
                    for dj in -1i64..=1 {
                        let (a, b) = (i as i64 + di, j as i64 + dj);
                        if a < 0 || b < 0 || a >= nx as i64 || b >= ny as i64 {
                            continue;
                        }
                        let (a, b) = (a as usize, b as usize);
                        if label[[a, b]] == 0 && bearing(a, b) {
                            label[[a, b]] = id;
                            stack.push((a, b));
                        }
                    }
                }
            }
            comps.push(pix);
        }
    }
    // Cores smaller than the minimum diameter are discarded before the rim is added: a speck of
    // faint colour inside a pen mark or tape must not grow a rim of the mark into a "patch".
    let px_area = map.pixel_size_m * map.pixel_size_m;
    let min_area = std::f64::consts::PI / 4.0 * min_diameter_m * min_diameter_m;
    let mut discarded_small = 0;
    let mut kept = Vec::new();
    for (k, pix) in comps.into_iter().enumerate() {
        if (pix.len() as f64) * px_area < min_area {
            discarded_small += 1;
            for &(i, j) in &pix {
                label[[i, j]] = usize::MAX;
            }
        } else {
            kept.push((k + 1, pix));
        }
    }
    // Rim: stained below-range pixels within `rim_pixels` steps (8-neighbour) of a core.
    let mut rim_taken = Array2::from_elem((nx, ny), false);
    for (id, pix) in kept.iter_mut() {
        let id = *id;
        let mut frontier = pix.clone();
        for _ in 0..rim_pixels {
            let mut next = Vec::new();
            for &(i, j) in &frontier {
                for di in -1i64..=1 {
                    for dj in -1i64..=1 {
                        let (a, b) = (i as i64 + di, j as i64 + dj);
                        if a < 0 || b < 0 || a >= nx as i64 || b >= ny as i64 {
                            continue;
                        }
                        let (a, b) = (a as usize, b as usize);
                        if label[[a, b]] == 0
                            && !rim_taken[[a, b]]
                            && map.class[[a, b]] == PixelClass::BelowRange
                        {
                            rim_taken[[a, b]] = true;
                            label[[a, b]] = id;
                            next.push((a, b));
                        }
                    }
                }
            }
            pix.extend_from_slice(&next);
            frontier = next;
        }
    }
    let mut rejected_marks = 0;
    let mut patches: Vec<Vec<(usize, usize)>> = Vec::with_capacity(kept.len());
    for (id, pix) in &kept {
        let filled = fill_holes(pix, &label, *id);
        let (elongation, solidity) = shape(map, &filled);
        if elongation > opts.max_elongation || solidity < opts.min_solidity {
            rejected_marks += 1;
        } else {
            patches.push(filled);
        }
    }
    // Reading order: rows of patches from the top of the image (largest y first), left to right
    // within a row. A patch joins the current row when its centre lies less than the row's first
    // patch's equivalent diameter below it.
    let centre = |p: &Vec<(usize, usize)>| {
        let n = p.len() as f64;
        (
            p.iter().map(|q| q.0 as f64).sum::<f64>() / n,
            p.iter().map(|q| q.1 as f64).sum::<f64>() / n,
        )
    };
    patches.sort_by(|a, b| centre(b).1.total_cmp(&centre(a).1));
    let mut ordered: Vec<Vec<(usize, usize)>> = Vec::with_capacity(patches.len());
    let mut row: Vec<Vec<(usize, usize)>> = Vec::new();
    let mut row_top = (f64::NAN, 0.0);
    for p in patches {
        let c = centre(&p);
        if row.is_empty() || row_top.0 - c.1 >= row_top.1 {
            row.sort_by(|a, b| centre(a).0.total_cmp(&centre(b).0));
            ordered.append(&mut row);
            row_top = (c.1, (4.0 * p.len() as f64 / std::f64::consts::PI).sqrt());
        }
        row.push(p);
    }
    row.sort_by(|a, b| centre(a).0.total_cmp(&centre(b).0));
    ordered.append(&mut row);
    let patches = ordered;
    Ok(PatchDetection {
        patches: patches
            .into_iter()
            .enumerate()
            .map(|(k, pixels)| Region { id: k + 1, pixels })
            .collect(),
        discarded_small,
        rejected_marks,
    })
}

/// The component's pixels plus every pixel of its bounding box not connected (4-neighbour,
/// through non-component pixels) to the bounding box border.
fn fill_holes(pix: &[(usize, usize)], label: &Array2<usize>, id: usize) -> Vec<(usize, usize)> {
    let i0 = pix.iter().map(|p| p.0).min().unwrap_or(0);
    let i1 = pix.iter().map(|p| p.0).max().unwrap_or(0);
    let j0 = pix.iter().map(|p| p.1).min().unwrap_or(0);
    let j1 = pix.iter().map(|p| p.1).max().unwrap_or(0);
    let (w, h) = (i1 - i0 + 1, j1 - j0 + 1);
    let is_comp = |a: usize, b: usize| label[[i0 + a, j0 + b]] == id;
    let mut outside = Array2::from_elem((w, h), false);
    let mut stack = Vec::new();
    for a in 0..w {
        for b in 0..h {
            if (a == 0 || b == 0 || a == w - 1 || b == h - 1) && !is_comp(a, b) {
                outside[[a, b]] = true;
                stack.push((a, b));
            }
        }
    }
    while let Some((a, b)) = stack.pop() {
        let nbrs = [
            (a.wrapping_sub(1), b),
            (a + 1, b),
            (a, b.wrapping_sub(1)),
            (a, b + 1),
        ];
        for (c, d) in nbrs {
            if c < w && d < h && !outside[[c, d]] && !is_comp(c, d) {
                outside[[c, d]] = true;
                stack.push((c, d));
            }
        }
    }
    let mut out = Vec::new();
    for a in 0..w {
        for b in 0..h {
            if !outside[[a, b]] {
                out.push((i0 + a, j0 + b));
            }
        }
    }
    out
}

/// Summary of one region.
#[derive(Debug, Clone, serde::Serialize)]
pub struct RegionSummary {
    /// Region id, as in [`Region::id`].
    pub id: usize,
    /// Centroid x of the region's pixels, film frame (m).
    pub centre_x_m: f64,
    /// Centroid y, film frame (m).
    pub centre_y_m: f64,
    /// Pixel count × pixel area (m²).
    pub area_m2: f64,
    /// `√(4·area/π)` (m).
    pub equivalent_diameter_m: f64,
    /// Mean pressure over the in-range pixels (Pa); NaN when none is in range.
    pub mean_pressure_pa: f64,
    /// Largest in-range pressure (Pa).
    pub max_pressure_pa: f64,
    /// Σ pressure × pixel area over in-range pixels (N): a lower bound of the load, since
    /// below- and above-range pixels carry unknown pressure.
    pub in_range_load_n: f64,
    /// Pixels of each class in the region.
    pub counts: ClassCounts,
    /// Above-range (saturated) pixels over the pressure-bearing ones (in range + above range):
    /// the share of the contact whose pressure the fit, made from in-range pixels only, does
    /// not know (at least the film's range there). NaN when the region has neither.
    pub saturated_fraction: f64,
}

/// Summarise a region. Errors when the region holds no pixel.
pub fn summarise(map: &FilmMap, region: &Region) -> Result<RegionSummary> {
    if region.pixels.is_empty() {
        return Err(Error::Data(format!("region {} is empty", region.id)));
    }
    let s = map.pixel_size_m;
    let n = region.pixels.len() as f64;
    let mut counts = ClassCounts::default();
    let (mut sx, mut sy, mut sp, mut pmax) = (0.0, 0.0, 0.0, f64::NAN);
    for &(i, j) in &region.pixels {
        counts.add(map.class[[i, j]]);
        let (x, y) = map.position(i, j);
        sx += x;
        sy += y;
        let p = map.pressure_pa[[i, j]];
        if p.is_finite() {
            sp += p;
            pmax = if pmax.is_nan() { p } else { pmax.max(p) };
        }
    }
    let area = n * s * s;
    Ok(RegionSummary {
        id: region.id,
        centre_x_m: sx / n,
        centre_y_m: sy / n,
        area_m2: area,
        equivalent_diameter_m: (4.0 * area / std::f64::consts::PI).sqrt(),
        mean_pressure_pa: if counts.in_range > 0 {
            sp / counts.in_range as f64
        } else {
            f64::NAN
        },
        max_pressure_pa: pmax,
        in_range_load_n: sp * s * s,
        saturated_fraction: if counts.in_range + counts.above_range > 0 {
            counts.above_range as f64 / (counts.in_range + counts.above_range) as f64
        } else {
            f64::NAN
        },
        counts,
    })
}

/// Write the per-pixel readings of `regions` as CSV (`region_id,x_m,y_m,pressure_Pa,class`),
/// pressure empty unless in range.
pub fn write_region_pixels_csv(path: &Path, map: &FilmMap, regions: &[Region]) -> Result<()> {
    crate::core::output::write_atomic(path, |w| {
        let io = |e: std::io::Error| Error::io(path, e);
        writeln!(w, "# film pressure map, pixels of the regions of interest; x_m, y_m in m (film frame, y up), pressure_Pa in Pa").map_err(io)?;
        writeln!(w, "# class: in_range (pressure given), unstained, below_range, above_range, off_curve (rejected colour); pixel size {} m", map.pixel_size_m).map_err(io)?;
        writeln!(w, "region_id,x_m,y_m,pressure_Pa,class").map_err(io)?;
        for r in regions {
            for &(i, j) in &r.pixels {
                let (x, y) = map.position(i, j);
                let p = map.pressure_pa[[i, j]];
                let ps = if p.is_finite() {
                    format!("{p:.6e}")
                } else {
                    String::new()
                };
                writeln!(
                    w,
                    "{},{x:.6e},{y:.6e},{ps},{}",
                    r.id,
                    map.class[[i, j]].name()
                )
                .map_err(io)?;
            }
        }
        Ok(())
    })
}

/// Column header of the region summary CSV.
pub const SUMMARY_COLUMNS: &str = "id,centre_x_m,centre_y_m,equivalent_diameter_m,area_m2,mean_pressure_Pa,max_pressure_Pa,in_range_load_N,n_pixels,n_in_range,n_unstained,n_below_range,n_above_range,n_off_curve,fit_order,fit_R2,fit_rms_residual_Pa,saturated_fraction";

/// Write region summaries (with their fit quality, if any) as CSV.
pub fn write_summary_csv(
    path: &Path,
    summaries: &[(RegionSummary, Option<&super::polyfit::PolyFit2>)],
) -> Result<()> {
    crate::core::output::write_atomic(path, |w| {
        let io = |e: std::io::Error| Error::io(path, e);
        writeln!(w, "# film regions: centre in m (film frame, y up), area in m², pressures in Pa, load in N; mean/max over in-range pixels; counts in pixels; saturated_fraction = n_above_range / (n_in_range + n_above_range), the share the fit (from in-range pixels) does not know").map_err(io)?;
        writeln!(w, "{SUMMARY_COLUMNS}").map_err(io)?;
        for (s, f) in summaries {
            let c = s.counts;
            let (fo, fr, fe) = match f {
                Some(f) => (
                    f.order.to_string(),
                    f.r_squared_text(9),
                    format!("{:.6e}", f.rms_residual_pa),
                ),
                None => Default::default(),
            };
            writeln!(
                w,
                "{},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{},{},{},{},{},{},{fo},{fr},{fe},{}",
                s.id,
                s.centre_x_m,
                s.centre_y_m,
                s.equivalent_diameter_m,
                s.area_m2,
                s.mean_pressure_pa,
                s.max_pressure_pa,
                s.in_range_load_n,
                c.total(),
                c.in_range,
                c.unstained,
                c.below_range,
                c.above_range,
                c.off_curve,
                if s.saturated_fraction.is_finite() {
                    format!("{:.6}", s.saturated_fraction)
                } else {
                    String::new()
                }
            )
            .map_err(io)?;
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::super::colour::{ColourRow, ColourTable};
    use super::*;

    fn table() -> ColourToPressure {
        let rows = vec![
            ColourRow {
                pressure_pa: 0.0,
                rgb: [255.0; 3],
            },
            ColourRow {
                pressure_pa: 1e6,
                rgb: [255.0, 200.0, 200.0],
            },
            ColourRow {
                pressure_pa: 5e6,
                rgb: [255.0, 0.0, 0.0],
            },
        ];
        ColourToPressure::Table(ColourTable::from_rows(rows, 20.0, "t").unwrap())
    }

    /// A white 60 × 40 image with a red disc of radius 8 px at column 20, row 15 (a white hole at
    /// its centre) and a blue square (ink) elsewhere.
    fn synthetic() -> FilmMap {
        FilmMap::from_rgb(
            60,
            40,
            |c, r| {
                let (dx, dy) = (c as f64 - 20.0, r as f64 - 15.0);
                if dx * dx + dy * dy <= 64.0 && (dx != 0.0 || dy != 0.0) {
                    [255.0, 100.0, 100.0]
                } else if (40..50).contains(&c) && (20..30).contains(&r) {
                    [0.0, 0.0, 255.0]
                } else {
                    [255.0; 3]
                }
            },
            &table(),
            1e-4,
        )
        .unwrap()
    }

    #[test]
    fn disc_is_found_with_its_hole_filled_and_ink_is_not() {
        let map = synthetic();
        let d = detect_patches(&map, 5e-4, DEFAULT_RIM_PIXELS).unwrap();
        assert_eq!(d.patches.len(), 1);
        let s = summarise(&map, &d.patches[0]).unwrap();
        // Disc of radius 8 px: 197 pixel centres inside; the filled hole counts.
        assert_eq!(d.patches[0].pixels.len(), 197);
        assert_eq!(s.counts.unstained, 1);
        assert!((s.centre_x_m - 20e-4).abs() < 1e-9);
        assert!((s.centre_y_m - (39.0 - 15.0) * 1e-4).abs() < 1e-9);
        assert!(
            (s.mean_pressure_pa - 3e6).abs() < 1.0,
            "{}",
            s.mean_pressure_pa
        );
        assert_eq!(map.class_counts().off_curve, 100);
    }

    #[test]
    fn empty_roi_is_an_error() {
        let map = synthetic();
        let roi = Roi::Rectangle {
            x0: 1.0,
            y0: 1.0,
            x1: 2.0,
            y1: 2.0,
        };
        let e = roi_region(&map, &roi, 1).unwrap_err();
        assert!(e.to_string().contains("contains no pixel"), "{e}");
        let poly = Roi::Polygon(vec![(0.0, 0.0), (1e-3, 0.0), (0.0, 1e-3)]);
        let r = roi_region(&map, &poly, 1).unwrap();
        // Pixel centres with i + j <= 10 (on the diagonal counted by the even-odd rule's
        // half-open edges: strictly below it).
        assert!(
            r.pixels.len() >= 55 && r.pixels.len() <= 66,
            "{}",
            r.pixels.len()
        );
    }
}
