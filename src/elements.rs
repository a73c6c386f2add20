//! Per-element table for the dynamic solver: preload map joined with the calibration table.
//!
//! For each contact element (a node with tributary area `A`, local pressure `p`, preload
//! `N0 = p·A`), the calibration table is interpolated at `p` (see
//! [`crate::calibrate::table::CalibrationTable::interpolate`]) and its per-unit-area record
//! becomes the element's ([`crate::element::ContactParamsPerArea::over_area`]):
//! `kn = kn″(p)·A`, `E0 = E0″(p)·A`, `Et = Et″(p)·A` (N/m from N/m³ × m²); the shape parameter
//! `k` and friction coefficient `mu` are taken as they are.
//! Elements whose pressure lies outside the table's range get the end pair's power law
//! (`kn ∝ p^m`, see [`crate::calibrate::table`]; the end row's values would leave a node at a
//! tenth of the first row's pressure about four times too stiff), are flagged in the
//! `out_of_range` column (−1 below, +1 above, 0 within) and counted in the summary.
//!
//! A table written by `asperity calibrate` carries each row's convergence verdict; the elements
//! whose values come from rows judged not converged (grid or patch size) or undetermined are
//! listed in the summary (`not_converged_row_ids`, `undetermined_row_ids`) and counted on stdout.
//!
//! Not tabulated, or refused:
//! - a node of **zero pressure** (a polynomial fit clamped at zero near a patch edge, or a node
//!   off the contact) is an open contact: no preload, and the power law gives it no stiffness.
//!   It is left out of the table and counted (`n_open`, `open_ids`, `open_area_m2`); the dynamic
//!   solver's element reader refuses `N0 ≤ 0` anyway.
//! - a join in which **no** loaded element lies within the table is refused: every value would
//!   be extrapolated, and the usual cause is a pressure column in another unit (MPa for Pa: 10⁶)
//!   or a table computed for another joint.
//! - an element more than a decade of pressure **above** the table (`p > 10·p_last`) is refused:
//!   a stiffening power law continued that far is a guess, not a calibration. Below the table the
//!   law falls towards the open contact's zero, the direction of the physics, and is kept
//!   however far.

use crate::calibrate::convergence::Verdict;
use crate::calibrate::table::{CalibrationTable, RangeFlag};
use crate::core::error::{Error, Result};
use crate::element::ContactParams;
use crate::film::nodes::Preload;
use std::path::Path;

/// One contact element.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ElementRow {
    /// Node id of the preload map (the element's id in the dynamic model).
    pub id: u64,
    /// Node position x in the film's frame (m).
    pub x_m: f64,
    /// Node position y in the film's frame (m).
    pub y_m: f64,
    /// Tributary (nominal) area `A` of the node (m²).
    pub area_m2: f64,
    /// Local contact pressure `p` at the node (Pa).
    pub pressure_pa: f64,
    /// Normal preload `N0 = p·A` (N).
    pub n0_n: f64,
    /// The element's record: `kn`, `E0`, `Et` (N/m), `k` and `μ` (dimensionless), the table at
    /// `p` times `A`.
    #[serde(flatten)]
    pub element: ContactParams,
    /// −1 below the table's range, 0 within, +1 above.
    pub out_of_range: i8,
}

/// Largest pressure, as a multiple of the table's last row, at which an element is accepted.
pub const MAX_ABOVE_TABLE_FACTOR: f64 = 10.0;

/// Counts and totals of a join.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ElementSummary {
    /// Elements written (nodes of non-zero pressure).
    pub n_elements: usize,
    /// Nodes of zero pressure (open contact), left out of the table.
    pub n_open: usize,
    /// Ids of the open nodes.
    pub open_ids: Vec<u64>,
    /// Total tributary area of the open nodes (m²).
    pub open_area_m2: f64,
    /// Elements whose pressure lies below the table's first row.
    pub n_below_range: usize,
    /// Elements whose pressure lies above the table's last row (at most 10× it).
    pub n_above_range: usize,
    /// Ids of the elements below the table's range.
    pub below_range_ids: Vec<u64>,
    /// Ids of the elements above the table's range.
    pub above_range_ids: Vec<u64>,
    /// Elements whose values come from table rows the calibration judged not converged in grid
    /// or patch size; empty for a table without verdicts ([`CalibrationTable::convergence_at`]).
    pub not_converged_row_ids: Vec<u64>,
    /// Elements whose values come from rows whose convergence could not be judged.
    pub undetermined_row_ids: Vec<u64>,
    /// Total tributary area of the elements (m²).
    pub total_area_m2: f64,
    /// Total normal preload `Σ N0` of the elements (N).
    pub total_load_n: f64,
    /// Smallest pressure of the calibration table (Pa).
    pub table_pressure_min_pa: f64,
    /// Largest pressure of the calibration table (Pa).
    pub table_pressure_max_pa: f64,
    /// Smallest element pressure (Pa).
    pub element_pressure_min_pa: f64,
    /// Largest element pressure (Pa).
    pub element_pressure_max_pa: f64,
}

/// Join preloaded nodes with a calibration table: one element per node of non-zero pressure
/// (module documentation: open nodes left out, a join with no element within the table or one
/// more than a decade above it refused).
pub fn join(
    preloads: &[Preload],
    table: &CalibrationTable,
) -> Result<(Vec<ElementRow>, ElementSummary)> {
    table.validate()?;
    if preloads.is_empty() {
        return Err(Error::Data("no preloaded nodes to join".into()));
    }
    let (open, loaded): (Vec<&Preload>, Vec<&Preload>) =
        preloads.iter().partition(|p| p.pressure_pa <= 0.0);
    if loaded.is_empty() {
        return Err(Error::Data(format!(
            "all {} nodes have zero pressure (open contact): no element to tabulate",
            preloads.len()
        )));
    }
    let (tmin, tmax) = table.pressure_range();
    let mut rows = Vec::with_capacity(loaded.len());
    let (mut below, mut above) = (Vec::new(), Vec::new());
    for p in loaded {
        let v = table.interpolate(p.pressure_pa);
        let flag = match v.range {
            RangeFlag::Below => {
                below.push(p.id);
                -1
            }
            RangeFlag::Within => 0,
            RangeFlag::Above => {
                above.push(p.id);
                1
            }
        };
        rows.push(ElementRow {
            id: p.id,
            x_m: p.x_m,
            y_m: p.y_m,
            area_m2: p.area_m2,
            pressure_pa: p.pressure_pa,
            n0_n: p.n0_n,
            element: v.element.over_area(p.area_m2),
            out_of_range: flag,
        });
    }
    let (pmin, pmax) = rows
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), r| {
            (lo.min(r.pressure_pa), hi.max(r.pressure_pa))
        });
    if below.len() + above.len() == rows.len() {
        return Err(Error::Data(format!(
            "none of the {} loaded nodes lies within the calibration table's pressure range ({tmin:.4e}–{tmax:.4e} Pa; nodes {pmin:.4e}–{pmax:.4e} Pa): every value would be extrapolated; is one of the pressure columns in another unit (MPa for Pa), or the table computed for another joint?",
            rows.len()
        )));
    }
    let on_rows = |verdict: Verdict| -> Vec<u64> {
        rows.iter()
            .filter(|r| table.convergence_at(r.pressure_pa) == Some(verdict))
            .map(|r| r.id)
            .collect()
    };
    let (not_converged_row_ids, undetermined_row_ids) = (
        on_rows(Verdict::NotConverged),
        on_rows(Verdict::Undetermined),
    );
    if let Some(p) = rows
        .iter()
        .find(|p| p.pressure_pa > MAX_ABOVE_TABLE_FACTOR * tmax)
    {
        return Err(Error::Data(format!(
            "node {} at {:.4e} Pa lies more than {MAX_ABOVE_TABLE_FACTOR}× above the calibration table's last row ({tmax:.4e} Pa): its stiffness would be the table's power law continued over more than a decade; compute the table up to the nodes' pressures",
            p.id, p.pressure_pa
        )));
    }
    let summary = ElementSummary {
        n_elements: rows.len(),
        n_open: open.len(),
        open_ids: open.iter().map(|p| p.id).collect(),
        open_area_m2: open.iter().fold(0.0, |a, p| a + p.area_m2),
        n_below_range: below.len(),
        n_above_range: above.len(),
        below_range_ids: below,
        above_range_ids: above,
        not_converged_row_ids,
        undetermined_row_ids,
        total_area_m2: rows.iter().map(|r| r.area_m2).sum(),
        total_load_n: rows.iter().map(|r| r.n0_n).sum(),
        table_pressure_min_pa: tmin,
        table_pressure_max_pa: tmax,
        element_pressure_min_pa: pmin,
        element_pressure_max_pa: pmax,
    };
    Ok((rows, summary))
}

/// Column header of the element table.
pub const COLUMNS: &str =
    "id,x_m,y_m,area_m2,pressure_Pa,N0_N,kn_N_per_m,E0_N_per_m,k,mu,Et_N_per_m,out_of_range";

/// Write the element table (CSV with a `#` units header), atomically.
pub fn write_csv(path: &Path, rows: &[ElementRow]) -> Result<()> {
    crate::core::output::write_atomic(path, |w| {
        let io = |e: std::io::Error| Error::io(path, e);
        writeln!(
            w,
            "# asperity {} element table: one row per contact element",
            env!("CARGO_PKG_VERSION")
        )
        .map_err(io)?;
        writeln!(w, "# units: x_m, y_m in m (film frame); area_m2 in m²; pressure_Pa in Pa; N0_N (normal preload) in N;").map_err(io)?;
        writeln!(
            w,
            "#   kn, E0, Et in N/m (per-area table values × area); k, mu dimensionless;"
        )
        .map_err(io)?;
        writeln!(w, "#   out_of_range: -1 pressure below the calibration table, +1 above (values continued by the end pair's power law), 0 within; nodes of zero pressure (open) are not in the table").map_err(io)?;
        writeln!(w, "{COLUMNS}").map_err(io)?;
        for r in rows {
            writeln!(
                w,
                "{},{:.9e},{:.9e},{:.9e},{:.9e},{:.12e},{:.9e},{:.9e},{:.9e},{:.9e},{:.9e},{}",
                r.id,
                r.x_m,
                r.y_m,
                r.area_m2,
                r.pressure_pa,
                r.n0_n,
                r.element.kn_n_per_m,
                r.element.e0_n_per_m,
                r.element.k,
                r.element.mu,
                r.element.et_n_per_m,
                r.out_of_range
            )
            .map_err(io)?;
        }
        Ok(())
    })
}

pub use crate::core::hash::{provenance_json, InputFile};

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibrate::table::CalibrationRow;
    use crate::element::ContactParamsPerArea;

    fn table() -> CalibrationTable {
        let row = |p: f64, kn: f64| CalibrationRow {
            pressure_pa: p,
            contact_area_ratio: 0.1,
            element: ContactParamsPerArea {
                kn_n_per_m3: kn,
                e0_n_per_m3: 2.0 * kn,
                k: 0.5,
                mu: 0.6,
                et_n_per_m3: 0.01 * kn,
            },
            fit_r2: 0.99,
            energy_per_cycle_j_per_m2: 1.0,
        };
        CalibrationTable::new(vec![row(1e6, 1e13), row(2e6, 2e13), row(4e6, 4e13)]).unwrap()
    }

    fn node(id: u64, p: f64, a: f64) -> Preload {
        Preload {
            id,
            x_m: 0.0,
            y_m: 0.0,
            area_m2: a,
            pressure_pa: p,
            n0_n: p * a,
        }
    }

    /// Elements resting on rows the calibration did not trust are listed (rows at 1, 2, 4 MPa).
    #[test]
    fn elements_on_unconverged_rows_are_listed() {
        use Verdict::*;
        let t = table()
            .with_convergence(vec![Converged, Converged, NotConverged])
            .unwrap();
        let nodes = [
            node(1, 1.5e6, 1e-6),
            node(2, 2e6, 1e-6),
            node(3, 3e6, 1e-6),
            node(4, 8e6, 1e-6),
        ];
        let (_, s) = join(&nodes, &t).unwrap();
        assert_eq!(s.not_converged_row_ids, vec![3, 4]);
        assert!(s.undetermined_row_ids.is_empty());
        let (_, s) = join(&nodes, &table()).unwrap();
        assert!(s.not_converged_row_ids.is_empty());
    }

    #[test]
    fn open_nodes_are_left_out_and_counted() {
        let (rows, s) = join(
            &[node(1, 2e6, 1e-6), node(2, 0.0, 3e-6), node(3, 1e6, 1e-6)],
            &table(),
        )
        .unwrap();
        assert_eq!(rows.iter().map(|r| r.id).collect::<Vec<_>>(), vec![1, 3]);
        assert_eq!(
            (s.n_open, s.open_ids.clone(), s.open_area_m2),
            (1, vec![2], 3e-6)
        );
        assert_eq!(s.element_pressure_min_pa, 1e6);
        let all_open = join(&[node(1, 0.0, 1e-6)], &table()).unwrap_err();
        assert!(all_open.to_string().contains("zero pressure"), "{all_open}");
    }

    /// A preload in MPa read as Pa (or a table for another joint) leaves every node outside the
    /// table: refused, not extrapolated; so is a node more than a decade above the table.
    #[test]
    fn a_join_with_no_node_in_the_table_or_far_above_it_is_refused() {
        let err = join(&[node(1, 2.0, 1e-6), node(2, 3.0, 1e-6)], &table()).unwrap_err();
        let msg = err.to_string();
        assert!(
            msg.contains("none of the 2 loaded nodes") && msg.contains("another unit"),
            "{msg}"
        );
        // Within a decade above the last row (4 MPa): accepted and flagged.
        let (rows, _) = join(&[node(1, 2e6, 1e-6), node(2, 39e6, 1e-6)], &table()).unwrap();
        assert_eq!(rows[1].out_of_range, 1);
        let err = join(&[node(1, 2e6, 1e-6), node(7, 41e6, 1e-6)], &table()).unwrap_err();
        assert!(err.to_string().contains("node 7"), "{err}");
    }

    #[test]
    fn stiffnesses_scale_with_area_and_range_is_flagged() {
        let (rows, s) = join(
            &[node(1, 2e6, 1e-6), node(2, 0.5e6, 2e-6), node(3, 5e6, 1e-6)],
            &table(),
        )
        .unwrap();
        // At a tabulated pressure the interpolation passes through the row.
        assert!((rows[0].element.kn_n_per_m - 2e13 * 1e-6).abs() < 1e-6 * 2e7);
        assert!((rows[0].element.e0_n_per_m - 4e13 * 1e-6).abs() < 1e-6 * 4e7);
        assert_eq!(rows[0].out_of_range, 0);
        assert_eq!(rows[1].out_of_range, -1);
        // Below the table: its first pair's power law (here kn ∝ p), times the area.
        assert!((rows[1].element.kn_n_per_m - 0.5e13 * 2e-6).abs() < 1e-9 * 1e7);
        assert_eq!(rows[2].out_of_range, 1);
        assert_eq!((s.n_below_range, s.n_above_range), (1, 1));
        assert_eq!(s.below_range_ids, vec![2]);
    }
}
