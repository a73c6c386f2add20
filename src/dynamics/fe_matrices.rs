//! Stiffness and mass matrices exported by a finite-element code: the readers.
//!
//! Two formats, both read into a [`SparseMatrix`] (full storage: a symmetric file is expanded to
//! both triangles) and, where the file names them, the DOF of every row ([`FeDof`]):
//!
//! - **Matrix Market** coordinate format (NIST's exchange format; Boisvert, Pozo & Remington,
//!   "The Matrix Market exchange formats: initial design", NISTIR 5935, 1996): a banner
//!   `%%MatrixMarket matrix coordinate real|integer symmetric|general`, `%` comment lines, a size
//!   line `rows cols entries` and one `row col value` line per entry, indices one-based. A
//!   symmetric file holds one triangle (either); a duplicate entry is added to the first, as
//!   assembly does.
//! - **CalculiX** matrix export (ccx 2.x, a `*FREQUENCY, SOLVER=MATRIXSTORAGE` step): `<job>.sti`
//!   (stiffness) and `<job>.mas` (mass), one `row col value` line per entry of the upper triangle
//!   (`row ≤ col`, one-based), and `<job>.dof`, one `node.direction` line per row (direction 1, 2,
//!   3 = x, y, z). The DOFs fixed by `*BOUNDARY` are not among the rows: the matrices are those
//!   of the constrained structure.
//!
//! The DOF map of a Matrix Market pair uses the `.dof` format as well ([`read_dof_map`]). Every
//! error names the file and the line. Units are those of the FE model (SI if the model was built
//! in SI: N/m and kg).

use crate::core::error::{Error, Result};
use std::path::{Path, PathBuf};

/// A sparse matrix in coordinate form, full storage, zero-based `(row, col, value)` entries;
/// duplicates allowed (they add up).
#[derive(Debug, Clone, PartialEq)]
pub struct SparseMatrix {
    /// Rows.
    pub nrows: usize,
    /// Columns.
    pub ncols: usize,
    /// Entries `(row, col, value)`, zero-based.
    pub entries: Vec<(usize, usize, f64)>,
}

impl SparseMatrix {
    /// The matrix in compressed-column form (duplicates summed).
    pub fn to_csc(&self) -> Result<faer::sparse::SparseColMat<usize, f64>> {
        let triplets: Vec<faer::sparse::Triplet<usize, usize, f64>> = self
            .entries
            .iter()
            .map(|&(r, c, v)| faer::sparse::Triplet::new(r, c, v))
            .collect();
        faer::sparse::SparseColMat::try_new_from_triplets(self.nrows, self.ncols, &triplets)
            .map_err(|e| Error::Data(format!("sparse matrix assembly failed: {e:?}")))
    }

    /// The matrix as a dense nalgebra matrix (duplicates summed); for small models and tests.
    pub fn to_dense(&self) -> nalgebra::DMatrix<f64> {
        let mut a = nalgebra::DMatrix::zeros(self.nrows, self.ncols);
        for &(r, c, v) in &self.entries {
            a[(r, c)] += v;
        }
        a
    }
}

/// One degree of freedom of an FE model: a node and a direction (1, 2, 3 = x, y, z; 4, 5, 6 =
/// rotations about x, y, z where the code has them).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct FeDof {
    /// Node number of the FE model.
    pub node: u64,
    /// Direction 1..=6.
    pub direction: u8,
}

/// The matrices of an FE model and the DOF of every row.
#[derive(Debug, Clone, PartialEq)]
pub struct FeMatrices {
    /// Stiffness matrix (N/m in SI), square, symmetric, full storage.
    pub stiffness: SparseMatrix,
    /// Mass matrix (kg in SI), same DOFs.
    pub mass: SparseMatrix,
    /// The DOF of every row, in row order.
    pub dofs: Vec<FeDof>,
}

impl FeMatrices {
    /// The rows of all DOFs of `nodes` (every direction present in the DOF map), in the order of
    /// `nodes` and then of direction. A node that has no DOF is an error (a node fixed by
    /// `*BOUNDARY`, or one not in the model).
    pub fn rows_of_nodes(&self, nodes: &[u64]) -> Result<Vec<usize>> {
        let mut rows = Vec::new();
        for &node in nodes {
            let mut of_node: Vec<(u8, usize)> = self
                .dofs
                .iter()
                .enumerate()
                .filter(|(_, d)| d.node == node)
                .map(|(i, d)| (d.direction, i))
                .collect();
            if of_node.is_empty() {
                return Err(Error::Data(format!(
                    "node {node} has no free DOF in the FE model (not a node of the mesh, or fixed)"
                )));
            }
            of_node.sort_unstable();
            rows.extend(of_node.into_iter().map(|(_, i)| i));
        }
        Ok(rows)
    }
}

fn parse_err(path: &Path, line: usize, message: impl Into<String>) -> Error {
    Error::Parse {
        path: path.to_path_buf(),
        line,
        message: message.into(),
    }
}

fn read_text(path: &Path) -> Result<String> {
    crate::core::limits::check_file_size(path, crate::core::limits::MAX_TEXT_FILE_BYTES)?;
    std::fs::read_to_string(path).map_err(|source| Error::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// One-based index `token` of a line, as a zero-based index below `n`.
fn index(path: &Path, line: usize, token: &str, what: &str, n: usize) -> Result<usize> {
    let i: usize = token.parse().map_err(|_| {
        parse_err(
            path,
            line,
            format!("{what} index `{token}` is not a positive integer"),
        )
    })?;
    if i == 0 || i > n {
        return Err(parse_err(
            path,
            line,
            format!("{what} index {i} outside 1..={n}"),
        ));
    }
    Ok(i - 1)
}

fn value(path: &Path, line: usize, token: &str) -> Result<f64> {
    let v: f64 = token
        .parse()
        .map_err(|_| parse_err(path, line, format!("value `{token}` is not a number")))?;
    if !v.is_finite() {
        return Err(parse_err(
            path,
            line,
            format!("value `{token}` is not finite"),
        ));
    }
    Ok(v)
}

/// Reads a Matrix Market coordinate file (`real` or `integer`, `symmetric` or `general`).
/// A symmetric file is returned in full storage.
pub fn read_matrix_market(path: &Path) -> Result<SparseMatrix> {
    let text = read_text(path)?;
    let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l));
    let (_, banner) = lines
        .next()
        .ok_or_else(|| parse_err(path, 1, "empty file: expected a `%%MatrixMarket` banner"))?;
    let words: Vec<String> = banner
        .split_whitespace()
        .map(|w| w.to_ascii_lowercase())
        .collect();
    if words.len() != 5 || words[0] != "%%matrixmarket" || words[1] != "matrix" {
        return Err(parse_err(
            path,
            1,
            "expected the banner `%%MatrixMarket matrix coordinate real symmetric|general`",
        ));
    }
    if words[2] != "coordinate" {
        return Err(parse_err(
            path,
            1,
            format!("format `{}` not read: only `coordinate`", words[2]),
        ));
    }
    if words[3] != "real" && words[3] != "integer" {
        return Err(parse_err(
            path,
            1,
            format!("field `{}` not read: only `real` or `integer`", words[3]),
        ));
    }
    let symmetric = match words[4].as_str() {
        "symmetric" => true,
        "general" => false,
        other => {
            return Err(parse_err(
                path,
                1,
                format!("symmetry `{other}` not read: only `symmetric` or `general`"),
            ))
        }
    };
    let mut size: Option<(usize, usize, usize)> = None;
    let mut entries = Vec::new();
    let (mut strict_upper, mut strict_lower) = (0usize, 0usize);
    let mut last_line = 1;
    for (ln, line) in lines {
        last_line = ln;
        let t = line.trim();
        if t.is_empty() || t.starts_with('%') {
            continue;
        }
        let tok: Vec<&str> = t.split_whitespace().collect();
        match size {
            None => {
                if tok.len() != 3 {
                    return Err(parse_err(
                        path,
                        ln,
                        "expected the size line `rows cols entries`",
                    ));
                }
                let mut v = [0usize; 3];
                for (k, s) in tok.iter().enumerate() {
                    v[k] = s.parse().map_err(|_| {
                        parse_err(
                            path,
                            ln,
                            format!("size `{s}` is not a non-negative integer"),
                        )
                    })?;
                }
                if symmetric && v[0] != v[1] {
                    return Err(parse_err(
                        path,
                        ln,
                        format!("a symmetric matrix must be square, not {} × {}", v[0], v[1]),
                    ));
                }
                size = Some((v[0], v[1], v[2]));
            }
            Some((nr, nc, _)) => {
                if tok.len() != 3 {
                    return Err(parse_err(path, ln, "expected an entry `row col value`"));
                }
                let r = index(path, ln, tok[0], "row", nr)?;
                let c = index(path, ln, tok[1], "column", nc)?;
                let v = value(path, ln, tok[2])?;
                entries.push((r, c, v));
                if symmetric && r != c {
                    entries.push((c, r, v));
                    if r < c {
                        strict_upper += 1;
                    } else {
                        strict_lower += 1;
                    }
                }
            }
        }
    }
    let (nrows, ncols, nnz) = size.ok_or_else(|| {
        parse_err(
            path,
            last_line,
            "no size line `rows cols entries` in the file",
        )
    })?;
    let read = if symmetric {
        entries.len() - strict_upper - strict_lower
    } else {
        entries.len()
    };
    if read != nnz {
        return Err(parse_err(
            path,
            0,
            format!("the size line announces {nnz} entries, the file holds {read}"),
        ));
    }
    if symmetric && strict_upper > 0 && strict_lower > 0 {
        // An entry given in both triangles would be counted twice.
        return Err(parse_err(
            path,
            0,
            format!(
                "a symmetric file holds one triangle; this one has {strict_lower} entries below \
                 and {strict_upper} above the diagonal"
            ),
        ));
    }
    Ok(SparseMatrix {
        nrows,
        ncols,
        entries,
    })
}

/// Reads a DOF map: one `node.direction` line per row (CalculiX's `<job>.dof`).
pub fn read_dof_map(path: &Path) -> Result<Vec<FeDof>> {
    let text = read_text(path)?;
    let mut dofs = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let ln = i + 1;
        let t = line.trim();
        if t.is_empty() {
            continue;
        }
        let bad = || {
            parse_err(
                path,
                ln,
                format!("expected `node.direction` (direction 1..6), got `{t}`"),
            )
        };
        let (node, dir) = t.split_once('.').ok_or_else(bad)?;
        let node: u64 = node.trim().parse().map_err(|_| bad())?;
        let direction: u8 = dir.trim().parse().map_err(|_| bad())?;
        if !(1..=6).contains(&direction) {
            return Err(bad());
        }
        dofs.push(FeDof { node, direction });
    }
    if dofs.is_empty() {
        return Err(parse_err(path, 0, "no DOF in the file"));
    }
    let mut seen = std::collections::HashMap::new();
    for (row, d) in dofs.iter().enumerate() {
        if let Some(first) = seen.insert(*d, row) {
            return Err(parse_err(
                path,
                0,
                format!(
                    "DOF {}.{} appears on rows {} and {}",
                    d.node,
                    d.direction,
                    first + 1,
                    row + 1
                ),
            ));
        }
    }
    Ok(dofs)
}

/// Reads a CalculiX upper-triangle matrix file (`.sti`, `.mas`) of `n` rows into full storage.
pub fn read_calculix_matrix(path: &Path, n: usize) -> Result<SparseMatrix> {
    let text = read_text(path)?;
    let mut entries = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let ln = i + 1;
        let t = line.trim();
        if t.is_empty() {
            continue;
        }
        let tok: Vec<&str> = t.split_whitespace().collect();
        if tok.len() != 3 {
            return Err(parse_err(path, ln, "expected an entry `row col value`"));
        }
        let r = index(path, ln, tok[0], "row", n)?;
        let c = index(path, ln, tok[1], "column", n)?;
        if r > c {
            return Err(parse_err(
                path,
                ln,
                format!(
                    "entry ({}, {}) below the diagonal: a CalculiX matrix file holds the upper triangle",
                    r + 1,
                    c + 1
                ),
            ));
        }
        let v = value(path, ln, tok[2])?;
        entries.push((r, c, v));
        if r != c {
            entries.push((c, r, v));
        }
    }
    if entries.is_empty() {
        return Err(parse_err(path, 0, "no entry in the file"));
    }
    Ok(SparseMatrix {
        nrows: n,
        ncols: n,
        entries,
    })
}

/// The three files of a CalculiX matrix export of job `job` (a path without extension):
/// `<job>.sti`, `<job>.mas`, `<job>.dof`.
pub fn calculix_paths(job: &Path) -> [PathBuf; 3] {
    let with = |ext: &str| {
        let mut p = job.as_os_str().to_owned();
        p.push(ext);
        PathBuf::from(p)
    };
    [with(".sti"), with(".mas"), with(".dof")]
}

/// Reads a CalculiX matrix export: `<job>.sti`, `<job>.mas` and the DOF map `<job>.dof`.
pub fn read_calculix(job: &Path) -> Result<FeMatrices> {
    let [sti, mas, dof] = calculix_paths(job);
    let dofs = read_dof_map(&dof)?;
    let stiffness = read_calculix_matrix(&sti, dofs.len())?;
    let mass = read_calculix_matrix(&mas, dofs.len())?;
    Ok(FeMatrices {
        stiffness,
        mass,
        dofs,
    })
}

/// Reads a stiffness and a mass matrix in Matrix Market format with their DOF map (`.dof`
/// format, one `node.direction` line per row).
pub fn read_matrix_market_pair(stiffness: &Path, mass: &Path, dofs: &Path) -> Result<FeMatrices> {
    let dof_map = read_dof_map(dofs)?;
    let k = read_matrix_market(stiffness)?;
    let m = read_matrix_market(mass)?;
    for (path, a) in [(stiffness, &k), (mass, &m)] {
        if a.nrows != a.ncols || a.nrows != dof_map.len() {
            return Err(parse_err(
                path,
                0,
                format!(
                    "{} × {} matrix, but the DOF map {} has {} rows",
                    a.nrows,
                    a.ncols,
                    dofs.display(),
                    dof_map.len()
                ),
            ));
        }
    }
    Ok(FeMatrices {
        stiffness: k,
        mass: m,
        dofs: dof_map,
    })
}
