//! Contact elements on node pairs: the element table of `asperity elements`, the node pairs
//! they join, and the local contact frame.
//!
//! Each row of the element table (columns `id, …, N0_N, kn_N_per_m, E0_N_per_m, k, mu,
//! Et_N_per_m`, per-element units N and N/m; see [`crate::elements`]) becomes one 3-D contact
//! element ([`ContactLaw`]) between node `a` and node `b` (or ground). Its local relative
//! displacement is `u = R·(x_a − x_b)` with `R` rows `(t1, t2, n)`: `n` the contact normal
//! pointing from `a` towards `b` (so `u_n > 0` closes the contact), `t1` the given tangent made
//! orthogonal to `n`, `t2 = n × t1`.

use crate::core::error::{Error, Result};
use crate::element::{
    ContactParams, HystereticElement, JenkinsContact, LoadFollowingContact, MicroslipContact,
};
use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

/// Constitutive law named in a model file for the rows of an element table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ContactLaw {
    /// [`MicroslipContact`]: E0, k, Et, μ, kn, N0 from the table.
    Valanis,
    /// [`JenkinsContact`]: kt = E0 of the table (the initial tangential stiffness), μ, kn, N0.
    Jenkins,
}

/// One row of an element table with the line it came from.
#[derive(Debug, Clone, PartialEq)]
pub struct TableElement {
    /// Element id (the table's `element_id`).
    pub id: u64,
    /// 1-based line in the file.
    pub line: usize,
    /// Normal preload (N).
    pub n0_n: f64,
    /// kn, E0, k, μ, Et of the element (N/m).
    pub element: ContactParams,
    /// −1 / 0 / +1 as written by `asperity elements` (0 when the column is absent).
    pub out_of_range: i8,
    /// The element's pressure `pressure_Pa` (Pa), where the table has the column.
    pub pressure_pa: Option<f64>,
    /// The element's position `(x_m, y_m)` in the film frame (m), where the table has them.
    pub position_m: Option<(f64, f64)>,
    /// Exponents `(b, a)` of `kn ∝ N^b` and `E0 ∝ N^a` when the element follows the load
    /// (`load_following` in the model file; [`LoadFollowingContact`]); `None`: constant.
    pub load_exponents: Option<[f64; 2]>,
}

/// Read an element table (CSV written by `asperity elements`; extra columns are ignored).
/// Every value is checked: `N0, kn, E0, μ > 0`, `0 ≤ k < 1`, `0 ≤ Et < E0`, ids unique;
/// errors name the file, the line and the column.
pub fn read_element_table(path: &Path) -> Result<Vec<TableElement>> {
    let mut rdr = crate::core::input::csv_reader(path)?;
    let headers = rdr
        .headers()
        .map_err(|e| crate::core::input::csv_error(path, e))?
        .clone();
    let col = |name: &str| -> Result<usize> {
        headers.iter().position(|h| h == name).ok_or_else(|| {
            Error::parse(
                path,
                0,
                format!("missing column `{name}` (expected the table of `asperity elements`: id,…,N0_N,kn_N_per_m,E0_N_per_m,k,mu,Et_N_per_m)"),
            )
        })
    };
    let ci = [
        col("id")?,
        col("N0_N")?,
        col("kn_N_per_m")?,
        col("E0_N_per_m")?,
        col("k")?,
        col("mu")?,
        col("Et_N_per_m")?,
    ];
    let flag_col = headers.iter().position(|h| h == "out_of_range");
    let pressure_col = headers.iter().position(|h| h == "pressure_Pa");
    let position_cols = headers
        .iter()
        .position(|h| h == "x_m")
        .zip(headers.iter().position(|h| h == "y_m"));
    let mut out: Vec<TableElement> = Vec::new();
    let mut seen: HashMap<u64, usize> = HashMap::new();
    for rec in rdr.records() {
        let (rec, line) = crate::core::input::csv_record(path, rec)?;
        let field = |i: usize, name: &str| -> Result<f64> {
            let s = rec
                .get(i)
                .ok_or_else(|| Error::parse(path, line, format!("missing value of `{name}`")))?;
            let v: f64 = s.parse().map_err(|_| {
                Error::parse(path, line, format!("`{name}` = `{s}` is not a number"))
            })?;
            if !v.is_finite() {
                return Err(Error::parse(
                    path,
                    line,
                    format!("`{name}` = {v} is not finite"),
                ));
            }
            Ok(v)
        };
        let id_s = rec.get(ci[0]).unwrap_or("");
        let id: u64 = id_s.parse().map_err(|_| {
            Error::parse(
                path,
                line,
                format!("`id` = `{id_s}` is not a non-negative integer"),
            )
        })?;
        if let Some(first) = seen.insert(id, line) {
            return Err(Error::parse(
                path,
                line,
                format!("element id {id} repeats the row on line {first}"),
            ));
        }
        let e = TableElement {
            id,
            line,
            n0_n: field(ci[1], "N0_N")?,
            element: ContactParams {
                kn_n_per_m: field(ci[2], "kn_N_per_m")?,
                e0_n_per_m: field(ci[3], "E0_N_per_m")?,
                k: field(ci[4], "k")?,
                mu: field(ci[5], "mu")?,
                et_n_per_m: field(ci[6], "Et_N_per_m")?,
            },
            out_of_range: match flag_col {
                Some(i) => field(i, "out_of_range")? as i8,
                None => 0,
            },
            pressure_pa: pressure_col.map(|i| field(i, "pressure_Pa")).transpose()?,
            load_exponents: None,
            position_m: match position_cols {
                Some((ix, iy)) => Some((field(ix, "x_m")?, field(iy, "y_m")?)),
                None => None,
            },
        };
        for (name, v) in [
            ("N0_N", e.n0_n),
            ("kn_N_per_m", e.element.kn_n_per_m),
            ("E0_N_per_m", e.element.e0_n_per_m),
            ("mu", e.element.mu),
        ] {
            if v <= 0.0 {
                return Err(Error::parse(
                    path,
                    line,
                    format!("element {id}: `{name}` must be > 0, got {v}"),
                ));
            }
        }
        e.element
            .valanis()
            .map_err(|err| Error::parse(path, line, format!("element {id}: {err}")))?;
        out.push(e);
    }
    if out.is_empty() {
        return Err(Error::parse(path, 0, "no element rows"));
    }
    Ok(out)
}

/// One row of a node-pair file.
#[derive(Debug, Clone, PartialEq)]
pub struct PairRow {
    /// Node on the first side.
    pub node_a: String,
    /// Node on the second side (`ground` allowed).
    pub node_b: String,
    /// 1-based line in the file.
    pub line: usize,
    /// The element's own contact frame (rows `t1, t2, n`), where the file gives one.
    pub frame: Option<[[f64; 3]; 3]>,
}

/// Columns of an element's own contact frame in a node-pair file (all six or none).
pub const PAIR_FRAME_COLUMNS: [&str; 6] = [
    "normal_x",
    "normal_y",
    "normal_z",
    "tangent_x",
    "tangent_y",
    "tangent_z",
];

/// Node pairs of the elements: `element_id,node_a,node_b` (`node_b` may be `ground`),
/// optionally followed by the element's own contact frame `normal_x,normal_y,normal_z,
/// tangent_x,tangent_y,tangent_z` (structure axes; as `normal` and `tangent` of the model file):
/// several frames on one interface, e.g. a curved or faceted contact face.
pub fn read_pairs(path: &Path) -> Result<HashMap<u64, PairRow>> {
    let mut rdr = crate::core::input::csv_reader(path)?;
    let headers = rdr
        .headers()
        .map_err(|e| crate::core::input::csv_error(path, e))?
        .clone();
    let expect = ["element_id", "node_a", "node_b"];
    let with_frame = headers.len() == 9
        && headers
            .iter()
            .skip(3)
            .eq(PAIR_FRAME_COLUMNS.iter().copied());
    if headers.len() < 3
        || headers.iter().take(3).ne(expect.iter().copied())
        || (headers.len() > 3 && !with_frame)
    {
        return Err(Error::parse(
            path,
            0,
            format!(
                "expected the header `element_id,node_a,node_b`, optionally followed by `,{}`",
                PAIR_FRAME_COLUMNS.join(",")
            ),
        ));
    }
    let mut out = HashMap::new();
    for rec in rdr.records() {
        let (rec, line) = crate::core::input::csv_record(path, rec)?;
        let id_s = rec.get(0).unwrap_or("");
        let id: u64 = id_s.parse().map_err(|_| {
            Error::parse(
                path,
                line,
                format!("`element_id` = `{id_s}` is not an integer"),
            )
        })?;
        let (a, b) = (rec.get(1).unwrap_or(""), rec.get(2).unwrap_or(""));
        if a.is_empty() || b.is_empty() {
            return Err(Error::parse(path, line, "empty node name"));
        }
        let frame = if with_frame {
            let mut v = [0.0; 6];
            for (k, name) in PAIR_FRAME_COLUMNS.iter().enumerate() {
                let s = rec.get(3 + k).unwrap_or("");
                v[k] = s
                    .parse()
                    .ok()
                    .filter(|x: &f64| x.is_finite())
                    .ok_or_else(|| {
                        Error::parse(
                            path,
                            line,
                            format!("`{name}` = `{s}` is not a finite number"),
                        )
                    })?;
            }
            Some(
                contact_frame([v[0], v[1], v[2]], [v[3], v[4], v[5]])
                    .map_err(|e| Error::parse(path, line, e.to_string()))?,
            )
        } else {
            None
        };
        let row = PairRow {
            node_a: a.to_string(),
            node_b: b.to_string(),
            line,
            frame,
        };
        if out.insert(id, row).is_some() {
            return Err(Error::parse(
                path,
                line,
                format!("element {id} is listed twice"),
            ));
        }
    }
    Ok(out)
}

/// Rows `(t1, t2, n)` of the local frame from a normal and a first tangent (global x, y, z).
pub fn contact_frame(normal: [f64; 3], tangent: [f64; 3]) -> Result<[[f64; 3]; 3]> {
    let nn = (normal.iter().map(|v| v * v).sum::<f64>()).sqrt();
    if !(nn.is_finite() && nn > 0.0) {
        return Err(Error::param("normal", "must be a non-zero finite vector"));
    }
    let n = normal.map(|v| v / nn);
    let dot: f64 = tangent.iter().zip(&n).map(|(a, b)| a * b).sum();
    let t: Vec<f64> = tangent.iter().zip(&n).map(|(a, b)| a - dot * b).collect();
    let tn = (t.iter().map(|v| v * v).sum::<f64>()).sqrt();
    if !(tn.is_finite() && tn > 1e-9 * (tangent.iter().map(|v| v * v).sum::<f64>()).sqrt())
        || tn == 0.0
    {
        return Err(Error::param(
            "tangent",
            "must not be parallel to the normal",
        ));
    }
    let t1 = [t[0] / tn, t[1] / tn, t[2] / tn];
    let t2 = [
        n[1] * t1[2] - n[2] * t1[1],
        n[2] * t1[0] - n[0] * t1[2],
        n[0] * t1[1] - n[1] * t1[0],
    ];
    Ok([t1, t2, n])
}

/// The element of `law` for one table row: with load exponents, the Valanis element whose
/// `kn` and `E0` follow the normal load ([`LoadFollowingContact`]).
pub fn element_for(law: ContactLaw, e: &TableElement) -> Result<Arc<dyn HystereticElement>> {
    Ok(match (law, e.load_exponents) {
        (ContactLaw::Valanis, None) => Arc::new(MicroslipContact::from_params(&e.element, e.n0_n)?),
        (ContactLaw::Valanis, Some([b, a])) => Arc::new(LoadFollowingContact::new(
            e.element.valanis()?,
            e.element.kn_n_per_m,
            e.n0_n,
            b,
            a,
        )?),
        (ContactLaw::Jenkins, None) => Arc::new(JenkinsContact::from_params(&e.element, e.n0_n)?),
        (ContactLaw::Jenkins, Some(_)) => {
            return Err(Error::param(
                "load_following",
                "is a property of the `valanis` law (kn(N), E0(N) of the microslip element)",
            ))
        }
    })
}

/// Exponents `[b, a]` of the load-following element (`kn ∝ N^b`, `E0 ∝ N^a`) of every row of
/// an element table from the calibration table the elements were interpolated from, at each
/// element's pressure ([`crate::calibrate::table::CalibrationTable::load_exponents`]; at fixed
/// area `d ln kn/d ln N = d ln kn″/d ln p`). Errors name the element table's file and line.
pub fn set_load_exponents(
    elements: &mut [TableElement],
    elements_path: &Path,
    table: &crate::calibrate::table::CalibrationTable,
) -> Result<()> {
    for e in elements {
        let p = e.pressure_pa.ok_or_else(|| {
            Error::parse(
                elements_path,
                e.line,
                "`load_following` needs the element's `pressure_Pa` column (the table of `asperity elements`)",
            )
        })?;
        e.load_exponents = Some(table.load_exponents(p));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_is_orthonormal_and_right_handed() {
        let r = contact_frame([0.0, 0.0, 2.0], [1.0, 0.0, 0.3]).unwrap();
        assert_eq!(r[0], [1.0, 0.0, 0.0]);
        assert_eq!(r[1], [0.0, 1.0, 0.0]);
        assert_eq!(r[2], [0.0, 0.0, 1.0]);
        assert!(contact_frame([0.0, 0.0, 1.0], [0.0, 0.0, 3.0]).is_err());
        assert!(contact_frame([0.0, 0.0, 0.0], [1.0, 0.0, 0.0]).is_err());
    }

    #[test]
    fn bad_element_rows_are_refused_with_file_and_line() {
        let dir = tempfile::tempdir().unwrap();
        let head = "# units\nid,x_m,y_m,area_m2,pressure_Pa,N0_N,kn_N_per_m,E0_N_per_m,k,mu,Et_N_per_m,out_of_range\n";
        let good = "7,0,0,1e-7,2e6,0.5,7e6,3e6,0.3,0.6,0,0\n";
        let p = dir.path().join("e.csv");
        std::fs::write(&p, format!("{head}{good}")).unwrap();
        assert_eq!(read_element_table(&p).unwrap().len(), 1);
        for (row, needle) in [
            ("8,0,0,1e-7,2e6,0.5,0,3e6,0.3,0.6,0,0", "kn_N_per_m"),
            ("8,0,0,1e-7,2e6,0.5,7e6,-3e6,0.3,0.6,0,0", "E0_N_per_m"),
            ("8,0,0,1e-7,2e6,0.5,7e6,3e6,0.3,0,0,0", "mu"),
            ("8,0,0,1e-7,2e6,0.5,7e6,3e6,1.3,0.6,0,0", "k"),
            ("8,0,0,1e-7,2e6,-1,7e6,3e6,0.3,0.6,0,0", "N0_N"),
            ("8,0,0,1e-7,2e6,0.5,7e6,NaN,0.3,0.6,0,0", "E0_N_per_m"),
            ("7,0,0,1e-7,2e6,0.5,7e6,3e6,0.3,0.6,0,0", "repeats"),
        ] {
            std::fs::write(&p, format!("{head}{good}{row}\n")).unwrap();
            let e = read_element_table(&p).unwrap_err().to_string();
            assert!(e.contains("e.csv:4") && e.contains(needle), "{e}");
        }
    }
}
