//! What the readers return and the statistics work on: a 1-D profile or a 2-D height map.

use crate::error::{require_positive, Error, Result};
use crate::grid::Grid2;

/// A line scan: heights (m) at `x = i·dx`, uniformly spaced.
#[derive(Debug, Clone, PartialEq)]
pub struct Profile {
    /// Heights (m).
    pub heights: Vec<f64>,
    /// Sample spacing (m).
    pub dx: f64,
    /// True when the profile is one period of a periodic line.
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
            periodic,
        })
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.heights.len()
    }

    /// Always false (a profile has at least 2 points); here for clippy's `len_without_is_empty`.
    pub fn is_empty(&self) -> bool {
        self.heights.is_empty()
    }

    /// Physical length (m): `n·dx`.
    pub fn length(&self) -> f64 {
        self.len() as f64 * self.dx
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
