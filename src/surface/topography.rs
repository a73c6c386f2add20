//! What the readers return and the statistics work on: a 1-D profile or a 2-D height map.

use crate::error::{require_positive, Error, Result};
use crate::grid::Grid2;

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
    /// 2-D height map.
    Area(Grid2),
}

impl Topography {
    /// The 2-D height map, or an error saying a profile cannot be used where an area is needed.
    pub fn into_area(self, what: &str) -> Result<Grid2> {
        match self {
            Topography::Area(g) => Ok(g),
            Topography::Profile(_) => Err(Error::Data(format!(
                "{what}: a 2-D height map is needed, got a 1-D profile"
            ))),
        }
    }

    /// Whether the topography is periodic.
    pub fn periodic(&self) -> bool {
        match self {
            Topography::Profile(p) => p.periodic,
            Topography::Area(g) => g.periodic,
        }
    }
}
