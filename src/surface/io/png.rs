//! PNG height image with a colour bar (write only), heights shown in µm over x, y in µm.

use crate::core::error::Result;
use crate::core::grid::Grid2;
use crate::core::plot::{heatmap, HeatMap};
use std::path::Path;

/// Draw `grid` as a height map with a colour bar into `path` (atomically).
pub fn write(path: &Path, grid: &Grid2, title: &str) -> Result<()> {
    heatmap(
        path,
        &grid.heights,
        grid.dx,
        grid.dy,
        &HeatMap {
            title,
            value_label: "height (µm)",
            value_scale: 1e6,
            length_scale: 1e6,
            length_unit: "µm",
        },
    )
}
