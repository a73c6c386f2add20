//! What the readers return and the statistics work on: a 1-D profile or a 2-D height map,
//! complete or with missing points (see [`crate::surface::missing`]).

use crate::core::error::{require_positive, Error, Result};
use crate::core::grid::Grid2;
use crate::surface::missing::MaskedGrid;

/// A line scan: heights (m) at `x = i·dx` (uniform) or at measured positions (nonuniform, e.g.
/// a stylus profiler that writes rounded lateral positions).
#[derive(Debug, Clone, PartialEq)]
pub struct Profile {
    /// Heights (m).
    pub heights: Vec<f64>,
    /// Sample spacing (m); for a nonuniform profile the mean spacing `(x_last - x_first)/(n-1)`.
    pub dx: f64,
    /// Measured positions (m, strictly increasing, starting at 0) when the profile is
    /// nonuniform; `None` for a uniform profile.
    pub positions: Option<Vec<f64>>,
    /// True when the profile is one period of a periodic line (uniform profiles only).
    pub periodic: bool,
}

impl Profile {
    /// Build a profile, checking the spacing, the length (≥ 2 points) and that every height is
    /// finite (the error names the 0-based sample index).
    pub fn new(heights: Vec<f64>, dx: f64, periodic: bool) -> Result<Self> {
        require_positive("dx", dx)?;
        if heights.len() < 2 {
            return Err(Error::param(
                "heights",
                format!("a profile needs at least 2 points, got {}", heights.len()),
            ));
        }
        if let Some((i, v)) = heights.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(Error::param(
                "heights",
                format!("non-finite value {v} at sample {i}"),
            ));
        }
        Ok(Self {
            heights,
            dx,
            positions: None,
            periodic,
        })
    }

    /// Build a uniform profile whose missing samples are `NaN` (a measurement with dropouts):
    /// infinite values are errors, and at least 2 samples must be measured.
    pub fn with_missing(heights: Vec<f64>, dx: f64, periodic: bool) -> Result<Self> {
        require_positive("dx", dx)?;
        if let Some((i, v)) = heights.iter().enumerate().find(|(_, v)| v.is_infinite()) {
            return Err(Error::param(
                "heights",
                format!("infinite value {v} at sample {i}"),
            ));
        }
        let measured = heights.iter().filter(|v| !v.is_nan()).count();
        if measured < 2 {
            return Err(Error::param(
                "heights",
                format!("a profile needs at least 2 measured points, got {measured}"),
            ));
        }
        Ok(Self {
            heights,
            dx,
            positions: None,
            periodic,
        })
    }

    /// Number of missing (NaN) samples.
    pub fn missing(&self) -> usize {
        self.heights.iter().filter(|v| v.is_nan()).count()
    }

    /// Build a nonuniform profile from positions and heights (m). Positions are shifted to start
    /// at 0 and must increase strictly (the error names the 0-based sample index).
    pub fn nonuniform(positions: Vec<f64>, heights: Vec<f64>) -> Result<Self> {
        if positions.len() != heights.len() {
            return Err(Error::param(
                "positions",
                format!(
                    "{} positions for {} heights",
                    positions.len(),
                    heights.len()
                ),
            ));
        }
        if let Some((i, v)) = positions.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(Error::param(
                "positions",
                format!("non-finite position {v} at sample {i}"),
            ));
        }
        if let Some(i) = (1..positions.len()).find(|&i| positions[i] <= positions[i - 1]) {
            return Err(Error::param(
                "positions",
                format!(
                    "positions must increase strictly: sample {i} at {} follows {}",
                    positions[i],
                    positions[i - 1]
                ),
            ));
        }
        let n = heights.len();
        let x0 = positions.first().copied().unwrap_or(0.0);
        let positions: Vec<f64> = positions.iter().map(|x| x - x0).collect();
        let dx = if n >= 2 {
            positions[n - 1] / (n - 1) as f64
        } else {
            0.0
        };
        let mut p = Self::new(heights, dx, false)?;
        p.positions = Some(positions);
        Ok(p)
    }

    /// True for a uniformly spaced profile.
    pub fn is_uniform(&self) -> bool {
        self.positions.is_none()
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.heights.len()
    }

    /// Always false (a profile has at least 2 points); here for clippy's `len_without_is_empty`.
    pub fn is_empty(&self) -> bool {
        self.heights.is_empty()
    }

    /// Physical length (m): `n·dx` for a uniform profile (SurfaceTopography's convention), the
    /// span `x_last - x_first` for a nonuniform one.
    pub fn length(&self) -> f64 {
        match &self.positions {
            None => self.len() as f64 * self.dx,
            Some(x) => x[x.len() - 1] - x[0],
        }
    }
}

/// A measured or generated topography.
#[derive(Debug, Clone, PartialEq)]
pub enum Topography {
    /// 1-D line scan.
    Profile(Profile),
    /// 2-D height map, every point measured.
    Area(Grid2),
    /// 2-D height map with missing points (NaN).
    MaskedArea(MaskedGrid),
}

impl Topography {
    /// The complete 2-D height map, or an error saying a profile cannot be used where an area
    /// is needed, or that points are missing (with the `--fill` flag that fills them).
    pub fn into_area(self, what: &str) -> Result<Grid2> {
        crate::surface::missing::complete_area(self, what, None).map(|(g, _)| g)
    }

    /// Whether the topography is periodic.
    pub fn periodic(&self) -> bool {
        match self {
            Topography::Profile(p) => p.periodic,
            Topography::Area(g) => g.periodic,
            Topography::MaskedArea(m) => m.periodic,
        }
    }

    /// A height map from a reader: [`Topography::MaskedArea`] when any height is NaN (a
    /// missing point), [`Topography::Area`] otherwise; checked by the grid constructors.
    pub fn from_heights(
        heights: ndarray::Array2<f64>,
        dx: f64,
        dy: f64,
        periodic: bool,
    ) -> Result<Self> {
        if heights.iter().any(|v| v.is_nan()) {
            MaskedGrid::new(heights, dx, dy, periodic).map(Topography::MaskedArea)
        } else {
            Grid2::new(heights, dx, dy, periodic).map(Topography::Area)
        }
    }

    /// Number of missing points (0 for a complete topography).
    pub fn missing(&self) -> usize {
        match self {
            Topography::Profile(p) => p.missing(),
            Topography::Area(_) => 0,
            Topography::MaskedArea(m) => m.missing(),
        }
    }
}
