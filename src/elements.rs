//! Per-element table for the dynamic solver: preload map joined with the calibration table.
//!
//! For each contact element (a node with tributary area `A`, local pressure `p`, preload
//! `N0 = p·A`), the calibration table is interpolated at `p` (see
//! [`crate::calibrate::table::CalibrationTable::interpolate`]) and its per-unit-area stiffnesses
//! are scaled by the element's area: `kn = kn″(p)·A`, `E0 = E0″(p)·A`, `Et = Et″(p)·A` (N/m from
//! N/m³ × m²); the shape parameter `k` and friction coefficient `mu` are taken as they are.
//! Elements whose pressure lies outside the table's range get the end row's values (no
//! extrapolation) and are flagged in the `out_of_range` column (−1 below, +1 above, 0 within) and
//! counted in the summary.

use crate::calibrate::table::{CalibrationTable, RangeFlag};
use crate::error::{Error, Result};
use crate::film::nodes::Preload;
use sha2::{Digest, Sha256};
use std::path::Path;

/// One contact element.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ElementRow {
    pub id: u64,
    pub x_m: f64,
    pub y_m: f64,
    pub area_m2: f64,
    pub pressure_pa: f64,
    pub n0_n: f64,
    pub kn_n_per_m: f64,
    pub e0_n_per_m: f64,
    pub k: f64,
    pub mu: f64,
    pub et_n_per_m: f64,
    /// −1 below the table's range, 0 within, +1 above.
    pub out_of_range: i8,
}

/// Counts and totals of a join.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ElementSummary {
    pub n_elements: usize,
    pub n_below_range: usize,
    pub n_above_range: usize,
    /// Ids of the out-of-range elements (below, then above).
    pub below_range_ids: Vec<u64>,
    pub above_range_ids: Vec<u64>,
    pub total_area_m2: f64,
    pub total_load_n: f64,
    /// Pressure range of the calibration table (Pa).
    pub table_pressure_min_pa: f64,
    pub table_pressure_max_pa: f64,
    /// Pressure range of the elements (Pa).
    pub element_pressure_min_pa: f64,
    pub element_pressure_max_pa: f64,
}

/// Join preloaded nodes with a calibration table: one element per node.
pub fn join(
    preloads: &[Preload],
    table: &CalibrationTable,
) -> Result<(Vec<ElementRow>, ElementSummary)> {
    table.validate()?;
    if preloads.is_empty() {
        return Err(Error::Data("no preloaded nodes to join".into()));
    }
    let mut rows = Vec::with_capacity(preloads.len());
    let (mut below, mut above) = (Vec::new(), Vec::new());
    for p in preloads {
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
            kn_n_per_m: v.kn_n_per_m3 * p.area_m2,
            e0_n_per_m: v.e0_n_per_m3 * p.area_m2,
            k: v.k,
            mu: v.mu,
            et_n_per_m: v.et_n_per_m3 * p.area_m2,
            out_of_range: flag,
        });
    }
    let (tmin, tmax) = table.pressure_range();
    let summary = ElementSummary {
        n_elements: rows.len(),
        n_below_range: below.len(),
        n_above_range: above.len(),
        below_range_ids: below,
        above_range_ids: above,
        total_area_m2: rows.iter().map(|r| r.area_m2).sum(),
        total_load_n: rows.iter().map(|r| r.n0_n).sum(),
        table_pressure_min_pa: tmin,
        table_pressure_max_pa: tmax,
        element_pressure_min_pa: rows
            .iter()
            .map(|r| r.pressure_pa)
            .fold(f64::INFINITY, f64::min),
        element_pressure_max_pa: rows
            .iter()
            .map(|r| r.pressure_pa)
            .fold(f64::NEG_INFINITY, f64::max),
    };
    Ok((rows, summary))
}

/// Column header of the element table.
pub const COLUMNS: &str =
    "id,x_m,y_m,area_m2,pressure_Pa,N0_N,kn_N_per_m,E0_N_per_m,k,mu,Et_N_per_m,out_of_range";

/// Write the element table (CSV with a `#` units header), atomically.
pub fn write_csv(path: &Path, rows: &[ElementRow]) -> Result<()> {
    crate::output::write_atomic(path, |w| {
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
        writeln!(w, "#   out_of_range: -1 pressure below the calibration table (first row's values used), 0 within, +1 above (last row's values)").map_err(io)?;
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
                r.kn_n_per_m,
                r.e0_n_per_m,
                r.k,
                r.mu,
                r.et_n_per_m,
                r.out_of_range
            )
            .map_err(io)?;
        }
        Ok(())
    })
}

/// Hex SHA-256 of a file's bytes.
pub fn sha256_file(path: &Path) -> Result<String> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let digest = Sha256::digest(&bytes);
    Ok(digest.iter().map(|b| format!("{b:02x}")).collect())
}

/// One input file in a provenance record.
#[derive(Debug, Clone, serde::Serialize)]
pub struct InputFile {
    pub role: String,
    pub path: String,
    pub sha256: String,
}

impl InputFile {
    /// Record `path` (hashing its content) under `role`.
    pub fn new(role: &str, path: &Path) -> Result<Self> {
        Ok(Self {
            role: role.to_string(),
            path: path.display().to_string(),
            sha256: sha256_file(path)?,
        })
    }
}

/// Provenance JSON written beside an output: tool, version, inputs with hashes, parameters and
/// a summary.
pub fn provenance_json(
    command: &str,
    inputs: &[InputFile],
    parameters: serde_json::Value,
    summary: serde_json::Value,
) -> serde_json::Value {
    let now = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0);
    serde_json::json!({
        "tool": "asperity",
        "crate_version": env!("CARGO_PKG_VERSION"),
        "command": command,
        "created_unix_s": now,
        "inputs": inputs,
        "parameters": parameters,
        "summary": summary,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibrate::table::CalibrationRow;

    fn table() -> CalibrationTable {
        let row = |p: f64, kn: f64| CalibrationRow {
            pressure_pa: p,
            contact_area_ratio: 0.1,
            kn_n_per_m3: kn,
            e0_n_per_m3: 2.0 * kn,
            k: 0.5,
            mu: 0.6,
            et_n_per_m3: 0.01 * kn,
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

    #[test]
    fn stiffnesses_scale_with_area_and_range_is_flagged() {
        let (rows, s) = join(
            &[node(1, 2e6, 1e-6), node(2, 0.5e6, 2e-6), node(3, 5e6, 1e-6)],
            &table(),
        )
        .unwrap();
        // At a tabulated pressure the interpolation passes through the row.
        assert!((rows[0].kn_n_per_m - 2e13 * 1e-6).abs() < 1e-6 * 2e7);
        assert!((rows[0].e0_n_per_m - 4e13 * 1e-6).abs() < 1e-6 * 4e7);
        assert_eq!(rows[0].out_of_range, 0);
        assert_eq!(rows[1].out_of_range, -1);
        assert!((rows[1].kn_n_per_m - 1e13 * 2e-6).abs() < 1.0);
        assert_eq!(rows[2].out_of_range, 1);
        assert_eq!((s.n_below_range, s.n_above_range), (1, 1));
        assert_eq!(s.below_range_ids, vec![2]);
    }

    #[test]
    fn sha256_of_known_bytes() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("abc");
        std::fs::write(&p, b"abc").unwrap();
        assert_eq!(
            sha256_file(&p).unwrap(),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
    }
}
