//! Missing points of measured topographies, and filling them explicitly.
//!
//! Optical profilometers (confocal microscopes, white-light interferometers) leave points they
//! could not measure. The readers keep them as **missing**: an x3p validity mask
//! (`Record3/DataLink/ValidPointsLink`, one bit per point, least-significant bit first, 1 =
//! valid) or a NaN height in any format (`.npy`, x3p, `nan` in a height matrix or profile).
//! A height map with missing points is a [`MaskedGrid`] (heights NaN where missing).
//!
//! * **Statistics** are computed over the measured points only, with SurfaceTopography's
//!   definitions (see [`crate::surface::stats`](mod@crate::surface::stats)); the PSD needs every point and is refused
//!   until the points are filled.
//! * **Contact** needs every point: a command refuses a map with missing points unless it is
//!   told how to fill them (`--fill harmonic` or `--fill nearest`), and then reports how many
//!   points it filled. Nothing is ever filled silently.
//!
//! Fill methods ([`fill`]):
//!
//! * [`Fill::Harmonic`]: the missing heights solve the discrete Laplace equation
//!   `Σ_{n ∈ N(p)} (h_n − h_p) = 0` at every missing point `p` (N: the 4 nearest neighbours,
//!   2 for a profile), with the measured heights as Dirichlet values; for a non-periodic map the
//!   neighbours outside the domain are dropped (zero normal derivative at the border). This is
//!   SurfaceTopography's `interpolate_undefined_data(method="harmonic")`; the system is solved
//!   by Jacobi-preconditioned conjugate gradients to a relative residual of 1e-14.
//! * [`Fill::Nearest`]: each missing point takes the height of the nearest measured point in
//!   physical distance `√((Δi·dx)² + (Δj·dy)²)` (periodic images included for a periodic map),
//!   by the exact Euclidean distance transform of Felzenszwalb & Huttenlocher (Theory of
//!   Computing 8 (2012) 415–428); ties go to the lower index along y, then x.
//!
//! Commands that need a complete height map adopt this with one call:
//! [`load_area`]`(path, fill)` reads the file and returns the map with the fill report, or an
//! error naming the file, the number of missing points and the `--fill` flag.

use crate::core::error::{num, Error, Result};
use crate::core::grid::Grid2;
use crate::surface::topography::Topography;
use ndarray::Array2;
use std::path::Path;

/// A height map with missing points (NaN), same grid convention as [`Grid2`].
#[derive(Debug, Clone, PartialEq)]
pub struct MaskedGrid {
    /// Heights (m), `NaN` where the point is missing; shape `(nx, ny)`.
    pub heights: Array2<f64>,
    /// Grid spacing along x (m).
    pub dx: f64,
    /// Grid spacing along y (m).
    pub dy: f64,
    /// True when the patch is one period of a periodic surface.
    pub periodic: bool,
}

impl MaskedGrid {
    /// Build a masked grid: spacings finite and > 0, every height finite or NaN (infinities are
    /// errors, naming the point), at least one measured point.
    pub fn new(heights: Array2<f64>, dx: f64, dy: f64, periodic: bool) -> Result<Self> {
        crate::core::error::require_positive("dx", dx)?;
        crate::core::error::require_positive("dy", dy)?;
        if heights.is_empty() {
            return Err(Error::param("heights", "grid has no points"));
        }
        if let Some(((i, j), v)) = heights.indexed_iter().find(|(_, v)| v.is_infinite()) {
            return Err(Error::param(
                "heights",
                format!("infinite value {v} at grid point ({i}, {j})"),
            ));
        }
        let g = Self {
            heights,
            dx,
            dy,
            periodic,
        };
        if g.missing() == g.heights.len() {
            return Err(Error::param(
                "heights",
                "every point is missing: nothing was measured",
            ));
        }
        Ok(g)
    }

    /// Number of points along x.
    pub fn nx(&self) -> usize {
        self.heights.nrows()
    }

    /// Number of points along y.
    pub fn ny(&self) -> usize {
        self.heights.ncols()
    }

    /// Number of missing points.
    pub fn missing(&self) -> usize {
        self.heights.iter().filter(|v| v.is_nan()).count()
    }

    /// Whether point `(i, j)` was measured.
    pub fn valid(&self, i: usize, j: usize) -> bool {
        !self.heights[[i, j]].is_nan()
    }
}

/// How missing points are filled.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Fill {
    /// Harmonic (Laplace) interpolation from the measured neighbours.
    Harmonic,
    /// Height of the nearest measured point.
    Nearest,
}

impl std::str::FromStr for Fill {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "harmonic" => Ok(Fill::Harmonic),
            "nearest" => Ok(Fill::Nearest),
            _ => Err(Error::param(
                "--fill",
                format!("must be `harmonic` or `nearest`, got `{s}`"),
            )),
        }
    }
}

/// What a fill did.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct FillReport {
    /// The method.
    pub method: Fill,
    /// Points filled.
    pub filled_points: usize,
    /// Points of the map.
    pub total_points: usize,
    /// `filled_points / total_points`.
    pub filled_fraction: f64,
    /// Conjugate-gradient iterations (harmonic fill; 0 for nearest).
    pub iterations: usize,
    /// Final relative residual of the Laplace system (harmonic fill; 0 for nearest).
    pub residual: f64,
}

impl FillReport {
    /// One line for the terminal and file headers.
    pub fn describe(&self) -> String {
        let how = match self.method {
            Fill::Harmonic => format!(
                "harmonic interpolation ({} CG iterations, relative residual {:.1e})",
                self.iterations, self.residual
            ),
            Fill::Nearest => "the nearest measured point".to_string(),
        };
        format!(
            "filled {} of {} points ({:.3} %) missing in the measurement by {how}",
            self.filled_points,
            self.total_points,
            100.0 * self.filled_fraction
        )
    }
}

/// Neighbours of `(i, j)` on an `nx × ny` grid along the axes that exist (`ny == 1`: a
/// profile, x only): periodic wrap-around, or dropped at a non-periodic border.
fn neighbours(
    i: usize,
    j: usize,
    nx: usize,
    ny: usize,
    periodic: bool,
) -> impl Iterator<Item = (usize, usize)> {
    let mut v: Vec<(usize, usize)> = Vec::with_capacity(4);
    let axes: &[(usize, usize)] = if ny == 1 {
        &[(0, nx)]
    } else {
        &[(0, nx), (1, ny)]
    };
    for &(axis, n) in axes {
        let k = if axis == 0 { i } else { j };
        for step in [1isize, -1] {
            let m = k as isize + step;
            let m = if periodic {
                m.rem_euclid(n as isize) as usize
            } else if m < 0 || m >= n as isize {
                continue;
            } else {
                m as usize
            };
            v.push(if axis == 0 { (m, j) } else { (i, m) });
        }
    }
    v.into_iter()
}

/// Harmonic fill of the NaN points of `h` (see the module documentation). Returns the
/// iterations and the final relative residual.
fn fill_harmonic(h: &mut Array2<f64>, periodic: bool) -> Result<(usize, f64)> {
    let (nx, ny) = h.dim();
    let unknown: Vec<(usize, usize)> = h
        .indexed_iter()
        .filter(|(_, v)| v.is_nan())
        .map(|(p, _)| p)
        .collect();
    if unknown.is_empty() {
        return Ok((0, 0.0));
    }
    let mut index = Array2::<usize>::from_elem((nx, ny), usize::MAX);
    for (k, &(i, j)) in unknown.iter().enumerate() {
        index[[i, j]] = k;
    }
    // Heights about the mean of the measured points (less round-off).
    let (s, n) = h
        .iter()
        .filter(|v| !v.is_nan())
        .fold((0.0, 0usize), |(s, n), v| (s + v, n + 1));
    let mean = s / n as f64;
    // A = D − N on the unknowns (D: in-domain neighbours), b = Σ measured neighbours.
    let m = unknown.len();
    let mut diag = vec![0.0; m];
    let mut b = vec![0.0; m];
    let mut links: Vec<Vec<usize>> = vec![Vec::new(); m];
    for (k, &(i, j)) in unknown.iter().enumerate() {
        for (a, c) in neighbours(i, j, nx, ny, periodic) {
            diag[k] += 1.0;
            let v = h[[a, c]];
            if v.is_nan() {
                links[k].push(index[[a, c]]);
            } else {
                b[k] += v - mean;
            }
        }
    }
    // Every connected region of missing points needs a measured neighbour.
    let mut anchored = vec![false; m];
    let mut stack: Vec<usize> = (0..m)
        .filter(|&k| links[k].len() < diag[k] as usize)
        .collect();
    for &k in &stack {
        anchored[k] = true;
    }
    while let Some(k) = stack.pop() {
        for &l in &links[k] {
            if !anchored[l] {
                anchored[l] = true;
                stack.push(l);
            }
        }
    }
    if let Some(k) = anchored.iter().position(|a| !a) {
        let (i, j) = unknown[k];
        return Err(Error::Data(format!(
            "the missing points around ({i}, {j}) form a region with no measured neighbour: \
             they cannot be interpolated"
        )));
    }
    let apply = |x: &[f64], y: &mut [f64]| {
        for k in 0..m {
            let mut s = diag[k] * x[k];
            for &l in &links[k] {
                s -= x[l];
            }
            y[k] = s;
        }
    };
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let bnorm = dot(&b, &b).sqrt();
    let mut x = vec![0.0; m];
    let (mut iterations, mut rel) = (0, 0.0);
    if bnorm > 0.0 {
        let mut r = b.clone();
        let mut z: Vec<f64> = r.iter().zip(&diag).map(|(r, d)| r / d).collect();
        let mut p = z.clone();
        let mut q = vec![0.0; m];
        let mut rz = dot(&r, &z);
        let max_iterations = 10 * m + 1000;
        let tol = 1e-14;
        rel = 1.0;
        while iterations < max_iterations {
            apply(&p, &mut q);
            let alpha = rz / dot(&p, &q);
            for k in 0..m {
                x[k] += alpha * p[k];
                r[k] -= alpha * q[k];
            }
            iterations += 1;
            rel = dot(&r, &r).sqrt() / bnorm;
            if rel <= tol {
                break;
            }
            for k in 0..m {
                z[k] = r[k] / diag[k];
            }
            let rz_new = dot(&r, &z);
            let beta = rz_new / rz;
            rz = rz_new;
            for k in 0..m {
                p[k] = z[k] + beta * p[k];
            }
        }
        // Recompute the true residual (the recursive one drifts).
        let mut ax = vec![0.0; m];
        apply(&x, &mut ax);
        let true_res = ax
            .iter()
            .zip(&b)
            .map(|(a, b)| (a - b) * (a - b))
            .sum::<f64>()
            .sqrt()
            / bnorm;
        rel = rel.max(true_res);
        if rel.is_nan() || rel > 1e-10 {
            return Err(Error::NonConvergence {
                solver: "harmonic fill of missing points (conjugate gradients)".into(),
                iterations,
                residual: rel,
                tolerance: 1e-10,
            });
        }
    }
    for (k, &(i, j)) in unknown.iter().enumerate() {
        h[[i, j]] = x[k] + mean;
    }
    Ok((iterations, rel))
}

/// 1-D squared-distance transform with feature indices (Felzenszwalb & Huttenlocher): for
/// sample values `f` (squared distance so far, `INFINITY` where unknown) at positions
/// `k·step`, returns `(d, arg)` with `d[q] = min_k (f[k] + ((q − k)·step)²)`; ties to the lower
/// `k`. With `periodic`, distances wrap around (three copies of the line are used).
fn edt_1d(f: &[f64], step: f64, periodic: bool) -> (Vec<f64>, Vec<usize>) {
    let n = f.len();
    let copies = if periodic { 3 } else { 1 };
    let len = n * copies;
    let off = if periodic { n } else { 0 };
    let val = |k: usize| f[k % n];
    let pos = |k: usize| k as f64 * step;
    let mut v: Vec<usize> = Vec::with_capacity(len);
    let mut z: Vec<f64> = Vec::with_capacity(len + 1);
    for q in 0..len {
        if !val(q).is_finite() {
            continue;
        }
        loop {
            match v.last() {
                None => {
                    v.push(q);
                    z.push(f64::NEG_INFINITY);
                    break;
                }
                Some(&p) => {
                    // Intersection of the parabolas from p and q.
                    let s = ((val(q) + pos(q) * pos(q)) - (val(p) + pos(p) * pos(p)))
                        / (2.0 * (pos(q) - pos(p)));
                    if s <= *z.last().expect("one boundary per parabola") {
                        v.pop();
                        z.pop();
                    } else {
                        v.push(q);
                        z.push(s);
                        break;
                    }
                }
            }
        }
    }
    let mut d = vec![f64::INFINITY; n];
    let mut arg = vec![usize::MAX; n];
    if v.is_empty() {
        return (d, arg);
    }
    let mut k = 0;
    for q in off..off + n {
        let x = pos(q);
        while k + 1 < v.len() && z[k + 1] < x {
            k += 1;
        }
        let p = v[k];
        d[q - off] = val(p) + (x - pos(p)) * (x - pos(p));
        arg[q - off] = p % n;
    }
    (d, arg)
}

/// Nearest-point fill of the NaN points of `h` (see the module documentation).
fn fill_nearest(h: &mut Array2<f64>, dx: f64, dy: f64, periodic: bool) {
    let (nx, ny) = h.dim();
    // Pass 1 along x: for every (i, j) the nearest measured point in row j.
    let mut d1 = Array2::from_elem((nx, ny), f64::INFINITY);
    let mut src_i = Array2::from_elem((nx, ny), usize::MAX);
    for j in 0..ny {
        let f: Vec<f64> = (0..nx)
            .map(|i| {
                if h[[i, j]].is_nan() {
                    f64::INFINITY
                } else {
                    0.0
                }
            })
            .collect();
        let (d, a) = edt_1d(&f, dx, periodic);
        for i in 0..nx {
            d1[[i, j]] = d[i];
            src_i[[i, j]] = a[i];
        }
    }
    // Pass 2 along y over the row minima.
    let mut filled = h.clone();
    for i in 0..nx {
        let f: Vec<f64> = (0..ny).map(|j| d1[[i, j]]).collect();
        let (_, a) = edt_1d(&f, dy, periodic && ny > 1);
        for j in 0..ny {
            if h[[i, j]].is_nan() && a[j] != usize::MAX {
                let sj = a[j];
                let si = src_i[[i, sj]];
                filled[[i, j]] = h[[si, sj]];
            }
        }
    }
    *h = filled;
}

/// Fill the missing points of `heights` (NaN) in place; `ny == 1` is a profile.
pub fn fill_array(
    heights: &mut Array2<f64>,
    dx: f64,
    dy: f64,
    periodic: bool,
    method: Fill,
) -> Result<FillReport> {
    let total = heights.len();
    let missing = heights.iter().filter(|v| v.is_nan()).count();
    if missing == total {
        return Err(Error::Data(
            "every point is missing: there is nothing to fill from".into(),
        ));
    }
    let (iterations, residual) = match method {
        Fill::Harmonic => fill_harmonic(heights, periodic)?,
        Fill::Nearest => {
            fill_nearest(heights, dx, dy, periodic);
            (0, 0.0)
        }
    };
    Ok(FillReport {
        method,
        filled_points: missing,
        total_points: total,
        filled_fraction: missing as f64 / total as f64,
        iterations,
        residual,
    })
}

/// Fill the missing points of a masked grid: a complete [`Grid2`] and what was done.
pub fn fill(grid: &MaskedGrid, method: Fill) -> Result<(Grid2, FillReport)> {
    let mut h = grid.heights.clone();
    let report = fill_array(&mut h, grid.dx, grid.dy, grid.periodic, method)?;
    Ok((Grid2::new(h, grid.dx, grid.dy, grid.periodic)?, report))
}

/// The error for a map with missing points where a complete one is needed.
pub fn missing_points_error(source: &str, missing: usize, total: usize) -> Error {
    Error::Data(format!(
        "{source}: {missing} of {total} points ({} %) are missing in the measurement (NaN \
         heights or invalid in the x3p validity mask); contact needs every point: fill them \
         explicitly with --fill harmonic (Laplace interpolation) or --fill nearest",
        num(100.0 * missing as f64 / total as f64)
    ))
}

/// The complete height map of a topography: unchanged when complete, filled by `fill` when
/// points are missing, or an error naming `source` and `--fill` when they are missing and no
/// fill is given. Profiles are refused (an area is needed).
pub fn complete_area(
    topo: Topography,
    source: &str,
    fill_method: Option<Fill>,
) -> Result<(Grid2, Option<FillReport>)> {
    match topo {
        Topography::Area(g) => Ok((g, None)),
        Topography::MaskedArea(m) => match fill_method {
            None => Err(missing_points_error(source, m.missing(), m.heights.len())),
            Some(f) => {
                let (g, r) = fill(&m, f).map_err(|e| match e {
                    Error::Data(msg) => Error::Data(format!("{source}: {msg}")),
                    other => other,
                })?;
                Ok((g, Some(r)))
            }
        },
        Topography::Profile(_) => Err(Error::Data(format!(
            "{source}: a 2-D height map is needed, got a 1-D profile"
        ))),
    }
}

/// A topography with its missing points filled (profiles and areas); unchanged when complete.
pub fn fill_topography(topo: Topography, method: Fill) -> Result<(Topography, Option<FillReport>)> {
    match topo {
        Topography::MaskedArea(m) => {
            let (g, r) = fill(&m, method)?;
            Ok((Topography::Area(g), Some(r)))
        }
        Topography::Profile(mut p) if p.missing() > 0 => {
            let mut h = Array2::from_shape_vec((p.heights.len(), 1), p.heights.clone())
                .expect("shape matches");
            let r = fill_array(&mut h, p.dx, p.dx, p.periodic, method)?;
            p.heights = h.iter().copied().collect();
            Ok((Topography::Profile(p), Some(r)))
        }
        other => Ok((other, None)),
    }
}

/// Read a height map for a command that needs every point (contact, combination): see
/// [`complete_area`]. The one call such commands make.
pub fn load_area(path: &Path, fill_method: Option<Fill>) -> Result<(Grid2, Option<FillReport>)> {
    let topo = crate::surface::io::read(path)?;
    complete_area(topo, &path.display().to_string(), fill_method)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn harmonic_fill_is_exact_for_linear_fields() {
        // A linear field is harmonic: the fill must reproduce it inside the domain.
        let mut h = Array2::from_shape_fn((9, 7), |(i, j)| 2.0 * i as f64 - 3.0 * j as f64 + 1.0);
        let want = h.clone();
        for (i, j) in [(4, 3), (4, 4), (5, 3), (2, 2), (6, 5)] {
            h[[i, j]] = f64::NAN;
        }
        let r = fill_array(&mut h, 1.0, 1.0, false, Fill::Harmonic).unwrap();
        assert_eq!(r.filled_points, 5);
        for (a, b) in h.iter().zip(&want) {
            assert!((a - b).abs() < 1e-12, "{a} vs {b}");
        }
    }

    #[test]
    fn nearest_fill_takes_the_closest_measured_point() {
        let mut h = Array2::from_elem((6, 4), f64::NAN);
        h[[0, 0]] = 1.0;
        h[[5, 3]] = 2.0;
        // dy ≫ dx: distance along y is expensive.
        fill_array(&mut h, 1.0, 10.0, false, Fill::Nearest).unwrap();
        assert_eq!(h[[1, 0]], 1.0);
        assert_eq!(h[[4, 3]], 2.0);
        assert_eq!(h[[5, 0]], 1.0); // 5 along x is closer than 30 along y
        assert_eq!(h[[0, 3]], 2.0);
        // Periodic: the wrap-around neighbour is the nearest.
        let mut p = Array2::from_elem((8, 1), f64::NAN);
        p[[1, 0]] = 1.0;
        p[[5, 0]] = 2.0;
        fill_array(&mut p, 1.0, 1.0, true, Fill::Nearest).unwrap();
        assert_eq!(p[[0, 0]], 1.0);
        assert_eq!(p[[6, 0]], 2.0);
        let mut q = Array2::from_elem((8, 1), f64::NAN);
        q[[1, 0]] = 1.0;
        q[[4, 0]] = 2.0;
        fill_array(&mut q, 1.0, 1.0, true, Fill::Nearest).unwrap();
        assert_eq!(q[[7, 0]], 1.0); // 2 through the wrap, 3 to 4
    }

    #[test]
    fn fully_missing_maps_are_refused() {
        let h = Array2::from_elem((3, 3), f64::NAN);
        assert!(MaskedGrid::new(h, 1.0, 1.0, false).is_err());
        let e = missing_points_error("a.x3p", 5, 100).to_string();
        assert!(e.contains("a.x3p") && e.contains("--fill"), "{e}");
    }
}
