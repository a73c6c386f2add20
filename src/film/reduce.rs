//! Node reduction: a coarse set of contact elements from a fine set of preloaded nodes.
//!
//! As in the reference study: a coarse triangular mesh is superimposed on the interface; in every
//! coarse triangle that holds fine nodes, the node nearest the triangle's centroid is kept and
//! receives the triangle's area. Here the triangle's area *on the interface* is the sum of the
//! tributary areas of the fine nodes inside it (so a triangle straddling the interface edge gets
//! only its covered part), and the kept node's preload is the sum of their preloads. Its pressure
//! becomes `ΣN0 / ΣA`, the area-weighted mean, so that the area-normalised parameters evaluated
//! at it (pressure, kn, E0 per unit area) scale with the new area. Total area and total load are
//! preserved exactly (up to floating-point summation).
//!
//! The stiffnesses are not summed: a kept node's `kn = kn″(ΣN0/ΣA)·ΣA` (likewise `E0`, `Et`), as
//! in the reference study, where the parallel fine elements would give `Σ kn″(p_i)·A_i`. The two
//! differ by the table's curvature in the pressure over a triangle. With the committed
//! `calib/calibration_table.csv`, a triangle holding equal areas at 1 and 9 MPa gets kn +3.1 %
//! above the sum (one at 0 and 4 MPa: +2.5 %); on the film example of docs/film.md (725 nodes reduced to 110 on a 1 mm mesh, 1.6–2.8 MPa) Σkn and ΣE0 within 5e-5 of the fine nodes'.
//!
//! The coarse mesh is structured: squares of side `h` aligned with the film axes, starting at the
//! fine nodes' lower-left bounding corner, each split into two right triangles by its diagonal
//! from lower-left to upper-right.

use super::nodes::Preload;
use crate::core::error::{Error, Result};
use std::collections::BTreeMap;

/// Result of a reduction.
#[derive(Debug, Clone)]
pub struct Reduction {
    /// The kept nodes with summed areas and loads.
    pub nodes: Vec<Preload>,
    /// Number of fine nodes.
    pub n_fine: usize,
    /// Coarse triangle side (m).
    pub mesh_size_m: f64,
}

/// Reduce `fine` nodes on a coarse triangular mesh of side `mesh_size_m`.
pub fn reduce(fine: &[Preload], mesh_size_m: f64) -> Result<Reduction> {
    crate::core::error::require_positive("mesh_size_m", mesh_size_m)?;
    if fine.is_empty() {
        return Err(Error::Data("node reduction of an empty node set".into()));
    }
    let x0 = fine.iter().map(|p| p.x_m).fold(f64::INFINITY, f64::min);
    let y0 = fine.iter().map(|p| p.y_m).fold(f64::INFINITY, f64::min);
    let h = mesh_size_m;
    // Triangle key: (cell i, cell j, upper?) ; upper triangle is above the diagonal.
    let mut groups: BTreeMap<(i64, i64, bool), Vec<usize>> = BTreeMap::new();
    for (k, p) in fine.iter().enumerate() {
        let (u, v) = ((p.x_m - x0) / h, (p.y_m - y0) / h);
        let (ci, cj) = (u.floor(), v.floor());
        let upper = (v - cj) > (u - ci);
        groups
            .entry((ci as i64, cj as i64, upper))
            .or_default()
            .push(k);
    }
    let mut nodes = Vec::with_capacity(groups.len());
    for ((ci, cj, upper), members) in groups {
        // Centroid of the triangle: lower (0,0),(1,0),(1,1) → (2/3, 1/3); upper → (1/3, 2/3).
        let (fu, fv) = if upper {
            (1.0 / 3.0, 2.0 / 3.0)
        } else {
            (2.0 / 3.0, 1.0 / 3.0)
        };
        let cx = x0 + (ci as f64 + fu) * h;
        let cy = y0 + (cj as f64 + fv) * h;
        let kept = *members
            .iter()
            .min_by(|&&a, &&b| {
                let da = (fine[a].x_m - cx).powi(2) + (fine[a].y_m - cy).powi(2);
                let db = (fine[b].x_m - cx).powi(2) + (fine[b].y_m - cy).powi(2);
                da.total_cmp(&db).then(fine[a].id.cmp(&fine[b].id))
            })
            .expect("groups are non-empty");
        let area: f64 = members.iter().map(|&k| fine[k].area_m2).sum();
        let load: f64 = members.iter().map(|&k| fine[k].n0_n).sum();
        nodes.push(Preload {
            id: fine[kept].id,
            x_m: fine[kept].x_m,
            y_m: fine[kept].y_m,
            area_m2: area,
            pressure_pa: load / area,
            n0_n: load,
        });
    }
    nodes.sort_by_key(|p| p.id);
    Ok(Reduction {
        nodes,
        n_fine: fine.len(),
        mesh_size_m,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reduction_preserves_area_and_load_and_keeps_centroid_nodes() {
        let h = 1e-4;
        let mut fine = Vec::new();
        for i in 0..40 {
            for j in 0..30 {
                let (x, y) = (i as f64 * h, j as f64 * h);
                let p = 1e6 * (1.0 + 10.0 * x + 3.0 * (y * 1e3).sin());
                fine.push(Preload {
                    id: (i * 30 + j) as u64,
                    x_m: x,
                    y_m: y,
                    area_m2: h * h,
                    pressure_pa: p,
                    n0_n: p * h * h,
                });
            }
        }
        let r = reduce(&fine, 1e-3).unwrap();
        assert!(r.nodes.len() < fine.len() / 10 && r.nodes.len() > 20);
        let a0: f64 = fine.iter().map(|p| p.area_m2).sum();
        let a1: f64 = r.nodes.iter().map(|p| p.area_m2).sum();
        let l0: f64 = fine.iter().map(|p| p.n0_n).sum();
        let l1: f64 = r.nodes.iter().map(|p| p.n0_n).sum();
        assert!((a1 - a0).abs() <= 1e-12 * a0);
        assert!((l1 - l0).abs() <= 1e-12 * l0);
        for p in &r.nodes {
            assert!((p.n0_n - p.pressure_pa * p.area_m2).abs() <= 1e-12 * p.n0_n);
        }
        // Every kept node is one of the fine nodes.
        assert!(r
            .nodes
            .iter()
            .all(|p| fine.iter().any(|q| q.id == p.id && q.x_m == p.x_m)));
    }

    #[test]
    fn bad_mesh_size_is_an_error() {
        assert!(reduce(&[], 1e-3).is_err());
        let p = Preload {
            id: 1,
            x_m: 0.0,
            y_m: 0.0,
            area_m2: 1.0,
            pressure_pa: 1.0,
            n0_n: 1.0,
        };
        assert!(reduce(&[p], 0.0).is_err());
    }
}
