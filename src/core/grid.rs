//! `Grid2`: heights on a regular rectangular grid, the data every stage passes along.
//!
//! Convention (used everywhere in the crate): the array has shape `(nx, ny)` and element
//! `[[i, j]]` is the value at `x = i·dx`, `y = j·dy`. Lengths are in metres. `periodic` says
//! whether the patch is one period of an infinite surface (generated surfaces are) or a finite
//! window (measured files, a sphere): it selects the periodic or zero-padded FFT convolution.

use crate::core::error::{Error, Result};
use ndarray::Array2;

/// A field sampled on a regular grid (heights in m, or pressures in Pa, ...).
#[derive(Debug, Clone, PartialEq)]
pub struct Grid2 {
    /// Values, shape `(nx, ny)`, `[[i, j]]` at `(i·dx, j·dy)`.
    pub heights: Array2<f64>,
    /// Grid spacing along x (m).
    pub dx: f64,
    /// Grid spacing along y (m).
    pub dy: f64,
    /// True when the patch is one period of a periodic surface.
    pub periodic: bool,
}

impl Grid2 {
    /// Build a grid, checking spacings and that every value is finite.
    pub fn new(heights: Array2<f64>, dx: f64, dy: f64, periodic: bool) -> Result<Self> {
        crate::core::error::require_positive("dx", dx)?;
        crate::core::error::require_positive("dy", dy)?;
        if heights.is_empty() {
            return Err(Error::param("heights", "grid has no points"));
        }
        if let Some(((i, j), v)) = heights.indexed_iter().find(|(_, v)| !v.is_finite()) {
            return Err(Error::param(
                "heights",
                format!("non-finite value {v} at grid point ({i}, {j})"),
            ));
        }
        Ok(Self {
            heights,
            dx,
            dy,
            periodic,
        })
    }

    /// Number of points along x.
    pub fn nx(&self) -> usize {
        self.heights.nrows()
    }

    /// Number of points along y.
    pub fn ny(&self) -> usize {
        self.heights.ncols()
    }

    /// Physical size along x (m): `nx·dx` (the period for a periodic patch).
    pub fn lx(&self) -> f64 {
        self.nx() as f64 * self.dx
    }

    /// Physical size along y (m).
    pub fn ly(&self) -> f64 {
        self.ny() as f64 * self.dy
    }

    /// Nominal (apparent) area of the patch (m²).
    pub fn area(&self) -> f64 {
        self.lx() * self.ly()
    }

    /// Area of one grid cell (m²).
    pub fn cell_area(&self) -> f64 {
        self.dx * self.dy
    }
}

/// `"nx × ny points, spacing dx × dy m, periodic"` (or `non-periodic (zero-padded kernels)`):
/// a grid as the commands describe it on stderr.
pub fn describe(surface: &Grid2) -> String {
    format!(
        "{} × {} points, spacing {:.4e} × {:.4e} m, {}",
        surface.nx(),
        surface.ny(),
        surface.dx,
        surface.dy,
        if surface.periodic {
            "periodic"
        } else {
            "non-periodic (zero-padded kernels)"
        }
    )
}

/// The `# grid: …` provenance line of the contact CSVs.
pub fn csv_header(surface: &Grid2) -> String {
    format!(
        "# grid: {} x {} points, dx_m = {:e}, dy_m = {:e}, periodic = {}",
        surface.nx(),
        surface.ny(),
        surface.dx,
        surface.dy,
        surface.periodic
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_nan_and_bad_spacing() {
        let mut h = Array2::zeros((4, 3));
        assert!(Grid2::new(h.clone(), 1.0, 1.0, true).is_ok());
        assert!(Grid2::new(h.clone(), 0.0, 1.0, true).is_err());
        assert!(Grid2::new(h.clone(), 1.0, -1.0, true).is_err());
        h[[2, 1]] = f64::NAN;
        let e = Grid2::new(h, 1.0, 1.0, true).unwrap_err().to_string();
        assert!(e.contains("(2, 1)"), "{e}");
    }

    #[test]
    fn sizes() {
        let g = Grid2::new(Array2::zeros((4, 3)), 0.5, 2.0, false).unwrap();
        assert_eq!((g.nx(), g.ny()), (4, 3));
        assert_eq!(g.lx(), 2.0);
        assert_eq!(g.ly(), 6.0);
        assert_eq!(g.area(), 12.0);
    }
}
