//! Contact nodes of a finite-element interface and their normal preloads.
//!
//! Nodes file: CSV with header `id,x_m,y_m` and optionally `area_m2` (tributary area), `#`
//! comment lines allowed. Coordinates are in the mesh frame; a [`Placement`] maps them onto the
//! film frame. When no areas are given, each node receives one third of the area of every
//! Delaunay triangle it belongs to (the lumped tributary area of linear triangles).
//!
//! Preload of a node: `N0 = σ(x, y) · A` with σ the pressure at the node's film position. When a
//! total normal load `F` is given, every preload (and pressure) is scaled by `F / Σ N0`, so the
//! preloads sum to `F`.

use crate::core::error::{num, Error, Result};
use std::path::Path;

/// A contact node in the mesh frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Node {
    /// Node id from the mesh.
    pub id: u64,
    /// Position x in the mesh frame (m).
    pub x_m: f64,
    /// Position y in the mesh frame (m).
    pub y_m: f64,
    /// Tributary area (m²), if the mesh provides it.
    pub area_m2: Option<f64>,
    /// 1-based line of the node in its nodes file (0 when not read from a file), for messages.
    pub line: usize,
}

impl Node {
    /// `node <id> (line <n>)` for messages.
    fn name(&self) -> String {
        if self.line > 0 {
            format!("node {} (line {})", self.id, self.line)
        } else {
            format!("node {}", self.id)
        }
    }
}

/// Mesh frame → film frame: `p_film = offset + scale · R(rotation) · p_mesh`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Placement {
    /// Translation x of the mesh origin in the film frame (m).
    pub offset_x_m: f64,
    /// Translation y of the mesh origin in the film frame (m).
    pub offset_y_m: f64,
    /// Counter-clockwise rotation (rad).
    pub rotation_rad: f64,
    /// Uniform scale (dimensionless, > 0).
    pub scale: f64,
}

impl Default for Placement {
    fn default() -> Self {
        Self {
            offset_x_m: 0.0,
            offset_y_m: 0.0,
            rotation_rad: 0.0,
            scale: 1.0,
        }
    }
}

impl Placement {
    /// Film-frame position of a mesh-frame point.
    pub fn apply(&self, x: f64, y: f64) -> (f64, f64) {
        let (s, c) = self.rotation_rad.sin_cos();
        (
            self.offset_x_m + self.scale * (c * x - s * y),
            self.offset_y_m + self.scale * (s * x + c * y),
        )
    }

    /// Check the parameters.
    pub fn validate(&self) -> Result<()> {
        crate::core::error::require_finite("node offset x", self.offset_x_m)?;
        crate::core::error::require_finite("node offset y", self.offset_y_m)?;
        crate::core::error::require_finite("node rotation", self.rotation_rad)?;
        crate::core::error::require_positive("node scale", self.scale)?;
        Ok(())
    }
}

/// Read a nodes CSV (see the module documentation).
pub fn read_nodes_csv(path: &Path) -> Result<Vec<Node>> {
    crate::core::limits::check_file_size(path, crate::core::limits::MAX_TEXT_FILE_BYTES)?;
    let mut rdr = crate::core::input::csv_reader(path)?;
    let headers = rdr
        .headers()
        .map_err(|e| Error::parse(path, 1, e.to_string()))?
        .clone();
    let col = |name: &str| headers.iter().position(|h| h == name);
    let (ci, cx, cy) = match (col("id"), col("x_m"), col("y_m")) {
        (Some(a), Some(b), Some(c)) => (a, b, c),
        _ => {
            return Err(Error::parse(
                path,
                1,
                format!(
                    "header must name columns id, x_m, y_m (and optionally area_m2); got `{}`",
                    headers.iter().collect::<Vec<_>>().join(",")
                ),
            ))
        }
    };
    let ca = col("area_m2");
    let mut nodes: Vec<Node> = Vec::new();
    let mut seen = std::collections::HashSet::new();
    for rec in rdr.records() {
        let (rec, line) = crate::core::input::csv_record(path, rec)?;
        let field = |c: usize, name: &str| -> Result<f64> {
            let s = rec.get(c).unwrap_or("");
            let v: f64 = s
                .parse()
                .map_err(|_| Error::parse(path, line, format!("{name}: `{s}` is not a number")))?;
            if !v.is_finite() {
                return Err(Error::parse(path, line, format!("{name} is not finite")));
            }
            Ok(v)
        };
        let id_s = rec.get(ci).unwrap_or("");
        let id: u64 = id_s.parse().map_err(|_| {
            Error::parse(
                path,
                line,
                format!("id: `{id_s}` is not a non-negative integer"),
            )
        })?;
        if !seen.insert(id) {
            return Err(Error::parse(path, line, format!("duplicate node id {id}")));
        }
        let area = match ca {
            Some(c) if !rec.get(c).unwrap_or("").is_empty() => {
                let a = field(c, "area_m2")?;
                if a <= 0.0 {
                    return Err(Error::parse(
                        path,
                        line,
                        format!("area_m2 must be > 0, got {a}"),
                    ));
                }
                Some(a)
            }
            _ => None,
        };
        nodes.push(Node {
            id,
            x_m: field(cx, "x_m")?,
            y_m: field(cy, "y_m")?,
            area_m2: area,
            line,
        });
    }
    if nodes.is_empty() {
        return Err(Error::parse(path, 0, "no nodes"));
    }
    let with_area = nodes.iter().filter(|n| n.area_m2.is_some()).count();
    if with_area != 0 && with_area != nodes.len() {
        return Err(Error::parse(
            path,
            0,
            format!(
                "area_m2 given for {with_area} of {} nodes: give it for all or none",
                nodes.len()
            ),
        ));
    }
    Ok(nodes)
}

/// A Delaunay triangle spans a gap of the node set — a bolt hole, the space between separate
/// patches, a concave notch — when its longest edge exceeds this multiple of the local node
/// spacing: the largest, over its vertices, of the vertex's spacing, the longest edge of its
/// smallest triangle (the smallest longest edge among the triangles at the vertex). On a mesh
/// of uniform spacing every triangle has the same longest edge, whatever the elements' aspect
/// ratio, and none is left out; nor on a smoothly graded one. A triangle across a gap has an
/// edge at least as long as the gap, while each of its vertices also belongs to a triangle of
/// the mesh beside it. Every vertex keeps its smallest triangle, so no node loses all its area.
///
/// From positions alone a gap cannot be told from an element more than 2.5 times larger than
/// every element round it (a coarse band between refined ones): such an element is left out
/// too, and the caller warns with the area left out (give the mesh's `area_m2` then).
pub const GAP_EDGE_FACTOR: f64 = 2.5;

/// Lumped tributary areas from the Delaunay triangulation of the points: each node receives a
/// third of the area of each triangle it is a vertex of. Triangles that span a gap of the node
/// set ([`GAP_EDGE_FACTOR`]) are left out, so the areas sum to the area the nodes cover, not
/// to their convex hull's (an annulus of nodes round a bolt hole does not get the hole).
pub fn tributary_areas(points: &[(f64, f64)]) -> Result<Vec<f64>> {
    let t = triangulated_areas(points)?;
    if let Some(k) = t.area.iter().position(|a| *a <= 0.0) {
        return Err(Error::Data(format!(
            "point {k} belongs to no triangle (duplicate position?): give area_m2 in the nodes file"
        )));
    }
    Ok(t.area)
}

/// The lumped areas of [`tributary_areas`] (zero for a point in no kept triangle) and the area
/// of the triangles left out as gaps.
struct Triangulated {
    area: Vec<f64>,
    gap_area: f64,
    gap_triangles: usize,
}

/// Triangle area by the shoelace formula.
fn triangle_area(a: (f64, f64), b: (f64, f64), c: (f64, f64)) -> f64 {
    0.5 * ((b.0 - a.0) * (c.1 - a.1) - (c.0 - a.0) * (b.1 - a.1)).abs()
}

fn triangulated_areas(points: &[(f64, f64)]) -> Result<Triangulated> {
    let pts: Vec<delaunator::Point> = points
        .iter()
        .map(|&(x, y)| delaunator::Point { x, y })
        .collect();
    let tri = delaunator::triangulate(&pts);
    if tri.triangles.is_empty() {
        return Err(Error::Data(format!(
            "cannot triangulate {} nodes (fewer than 3, or all collinear): give area_m2 in the nodes file",
            points.len()
        )));
    }
    let length = |i: usize, j: usize| (points[i].0 - points[j].0).hypot(points[i].1 - points[j].1);
    let longest_edge = |t: &[usize]| {
        length(t[0], t[1])
            .max(length(t[1], t[2]))
            .max(length(t[2], t[0]))
    };
    // Spacing of each vertex: the longest edge of its smallest triangle.
    let mut spacing = vec![f64::INFINITY; points.len()];
    for t in tri.triangles.chunks(3) {
        let l = longest_edge(t);
        for &k in t {
            spacing[k] = spacing[k].min(l);
        }
    }
    let mut area = vec![0.0; points.len()];
    let (mut gap_area, mut gap_triangles) = (0.0, 0);
    for t in tri.triangles.chunks(3) {
        let at = triangle_area(points[t[0]], points[t[1]], points[t[2]]);
        let longest = longest_edge(t);
        let local = t.iter().map(|&k| spacing[k]).fold(0.0, f64::max);
        if longest > GAP_EDGE_FACTOR * local {
            gap_area += at;
            gap_triangles += 1;
            continue;
        }
        for &k in t {
            area[k] += at / 3.0;
        }
    }
    Ok(Triangulated {
        area,
        gap_area,
        gap_triangles,
    })
}

/// Tributary areas of `nodes` (at their film positions `film`) by triangulation. Two nodes at
/// one position would share a point of the mesh: one of them gets no area and no load, so the
/// load it carries in the real joint would be lost; both are named instead.
fn node_areas(nodes: &[Node], film: &[(f64, f64)]) -> Result<Triangulated> {
    let mut at = std::collections::HashMap::new();
    for n in nodes {
        // `+ 0.0` makes −0 and +0 one position.
        if let Some(other) = at.insert(((n.x_m + 0.0).to_bits(), (n.y_m + 0.0).to_bits()), n) {
            return Err(Error::Data(format!(
                "{} and {} lie at the same position ({}, {}) m: remove the duplicate, or give \
                 area_m2 for every node",
                other.name(),
                n.name(),
                num(n.x_m),
                num(n.y_m)
            )));
        }
    }
    let t = triangulated_areas(film)?;
    if let Some(k) = t.area.iter().position(|a| *a <= 0.0) {
        return Err(Error::Data(format!(
            "{} belongs to no triangle of the nodes' triangulation: give area_m2 in the nodes file",
            nodes[k].name()
        )));
    }
    Ok(t)
}

/// A node with its preload.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Preload {
    /// Node id from the mesh.
    pub id: u64,
    /// Film-frame position x (m).
    pub x_m: f64,
    /// Film-frame position y (m).
    pub y_m: f64,
    /// Tributary area `A` (m²).
    pub area_m2: f64,
    /// Local contact pressure (Pa) = N0 / area.
    #[serde(rename = "pressure_Pa")]
    pub pressure_pa: f64,
    /// Normal preload (N).
    #[serde(rename = "N0_N")]
    pub n0_n: f64,
}

/// What happened while computing preloads.
#[derive(Debug, Clone, serde::Serialize)]
pub struct PreloadSummary {
    /// Nodes with a preload.
    pub n_nodes: usize,
    /// Total tributary area (m²).
    pub total_area_m2: f64,
    /// Σ N0 before any rescaling (N).
    pub raw_total_load_n: f64,
    /// Σ N0 after rescaling (N).
    pub total_load_n: f64,
    /// Factor applied to every preload (1 without a target load).
    pub load_scale: f64,
    /// Nodes whose pressure evaluated negative (polynomial undershoot) and were set to zero.
    pub clamped_negative: usize,
    /// Whether areas came from a Delaunay triangulation.
    pub areas_from_triangulation: bool,
    /// Area of the Delaunay triangles left out as gaps of the node set (holes, space between
    /// patches; [`GAP_EDGE_FACTOR`]), 0 with given areas (m², film frame).
    pub gap_area_m2: f64,
    /// Number of those triangles.
    pub gap_triangles: usize,
}

/// Preloads of `nodes` placed by `placement` on a pressure field. `pressure_at(x, y)` returns the
/// pressure (Pa) at a film-frame point or an error (e.g. point outside the map). Negative
/// pressures (a polynomial undershooting near a patch edge) are set to zero and counted.
pub fn preloads(
    nodes: &[Node],
    placement: &Placement,
    pressure_at: impl Fn(f64, f64) -> Result<f64>,
    total_load_n: Option<f64>,
) -> Result<(Vec<Preload>, PreloadSummary)> {
    placement.validate()?;
    if let Some(f) = total_load_n {
        crate::core::error::require_positive("total_load_n", f)?;
    }
    let film: Vec<(f64, f64)> = nodes
        .iter()
        .map(|n| placement.apply(n.x_m, n.y_m))
        .collect();
    let from_tri = nodes.iter().any(|n| n.area_m2.is_none());
    let (areas, gap_area, gap_triangles) = if from_tri {
        let t = node_areas(nodes, &film)?;
        (t.area, t.gap_area, t.gap_triangles)
    } else {
        // Given areas are in the mesh frame: scale² maps them onto the film.
        let given = nodes
            .iter()
            .map(|n| n.area_m2.unwrap_or(0.0) * placement.scale * placement.scale)
            .collect();
        (given, 0.0, 0)
    };
    let mut clamped = 0;
    let mut out = Vec::with_capacity(nodes.len());
    for ((n, &(x, y)), &a) in nodes.iter().zip(&film).zip(&areas) {
        let mut p = pressure_at(x, y).map_err(|e| match e {
            Error::Data(m) => Error::Data(format!("{}: {m}", n.name())),
            other => other,
        })?;
        if p < 0.0 {
            p = 0.0;
            clamped += 1;
        }
        out.push(Preload {
            id: n.id,
            x_m: x,
            y_m: y,
            area_m2: a,
            pressure_pa: p,
            n0_n: p * a,
        });
    }
    let raw: f64 = out.iter().map(|p| p.n0_n).sum();
    let scale = match total_load_n {
        Some(f) => {
            if raw <= 0.0 {
                return Err(Error::Data(
                    "cannot rescale preloads to the total load: the pressure is zero at every node"
                        .into(),
                ));
            }
            f / raw
        }
        None => 1.0,
    };
    for p in out.iter_mut() {
        p.n0_n *= scale;
        p.pressure_pa *= scale;
    }
    let summary = PreloadSummary {
        n_nodes: out.len(),
        total_area_m2: areas.iter().sum(),
        raw_total_load_n: raw,
        total_load_n: out.iter().map(|p| p.n0_n).sum(),
        load_scale: scale,
        clamped_negative: clamped,
        areas_from_triangulation: from_tri,
        gap_area_m2: gap_area,
        gap_triangles,
    };
    Ok((out, summary))
}

/// Write preloads as CSV with a units header.
pub fn write_preloads_csv(path: &Path, rows: &[Preload], comment: &str) -> Result<()> {
    write_preloads(path, rows, None, comment)
}

/// Write preloads as [`write_preloads_csv`] with one more column, `pixel_class`: what the film
/// says under each node (`in_range`, `above_range`, `below_range`, `hole`; see
/// [`crate::film::NodePixel`]). [`read_preloads_csv`] reads such a file too.
pub fn write_preloads_csv_with_classes(
    path: &Path,
    rows: &[Preload],
    classes: &[crate::film::NodePixel],
    comment: &str,
) -> Result<()> {
    if classes.len() != rows.len() {
        return Err(Error::Data(format!(
            "{} pixel classes for {} preloads",
            classes.len(),
            rows.len()
        )));
    }
    write_preloads(path, rows, Some(classes), comment)
}

fn write_preloads(
    path: &Path,
    rows: &[Preload],
    classes: Option<&[crate::film::NodePixel]>,
    comment: &str,
) -> Result<()> {
    crate::core::output::write_atomic(path, |w| {
        let io = |e: std::io::Error| Error::io(path, e);
        for line in comment.lines() {
            writeln!(w, "# {line}").map_err(io)?;
        }
        writeln!(
            w,
            "# units: x_m, y_m in m (film frame), area_m2 in m², pressure_Pa in Pa, N0_N in N"
        )
        .map_err(io)?;
        if classes.is_some() {
            writeln!(
                w,
                "# pixel_class: the film under the node: in_range; above_range (saturated: the \
                 pressure is at least the film's range, the fit there a lower bound at best); \
                 below_range (stained below the range: the fit an upper bound at best); hole \
                 (unstained pixel enclosed by the stain)"
            )
            .map_err(io)?;
            writeln!(w, "id,x_m,y_m,area_m2,pressure_Pa,N0_N,pixel_class").map_err(io)?;
        } else {
            writeln!(w, "id,x_m,y_m,area_m2,pressure_Pa,N0_N").map_err(io)?;
        }
        for (k, p) in rows.iter().enumerate() {
            write!(
                w,
                "{},{:.12e},{:.12e},{:.15e},{:.12e},{:.15e}",
                p.id, p.x_m, p.y_m, p.area_m2, p.pressure_pa, p.n0_n
            )
            .map_err(io)?;
            match classes {
                Some(c) => writeln!(w, ",{}", c[k].name()),
                None => writeln!(w),
            }
            .map_err(io)?;
        }
        Ok(())
    })
}

/// Largest relative difference between a preload `N0_N` and `pressure_Pa × area_m2` accepted
/// by [`read_preloads_csv`]. `N0 = σ·A` by definition of the preload (and `ΣN0/ΣA` is the
/// pressure of a reduced node, so that holds after a reduction too); the film command writes
/// 13–16 significant digits, so its files agree to about 1e-12, and a file re-saved by a
/// spreadsheet (15 digits) passes too. A larger difference means an edited column or a column
/// in another unit (N0 in kN, area in mm²): the element's stiffness (from σ and A) and its
/// preload (N0) would describe two different contacts.
pub const PRELOAD_CONSISTENCY_TOLERANCE: f64 = 1e-6;

/// Read a preload CSV written by [`write_preloads_csv`]. Errors name the file, line and column:
/// missing columns, unparsable or non-finite values, area ≤ 0, a negative pressure or preload
/// (a contact node is pressed, never pulled: a tensile "preload" is no contact), `N0_N` not
/// equal to `pressure_Pa × area_m2` (within [`PRELOAD_CONSISTENCY_TOLERANCE`]), a duplicate
/// node id.
pub fn read_preloads_csv(path: &Path) -> Result<Vec<Preload>> {
    crate::core::limits::check_file_size(path, crate::core::limits::MAX_TEXT_FILE_BYTES)?;
    let mut rdr = crate::core::input::csv_reader(path)?;
    let headers = rdr
        .headers()
        .map_err(|e| crate::core::input::csv_error(path, e))?
        .clone();
    let mut out: Vec<Preload> = Vec::new();
    let mut seen = std::collections::HashMap::new();
    for rec in rdr.records() {
        let (rec, line) = crate::core::input::csv_record(path, rec)?;
        let p: Preload = rec.deserialize(Some(&headers)).map_err(|e| {
            Error::parse(
                path,
                line,
                format!("expected columns id,x_m,y_m,area_m2,pressure_Pa,N0_N: {e}"),
            )
        })?;
        let bad = |column: &str, why: String| {
            Error::parse(path, line, format!("node {}: column {column}: {why}", p.id))
        };
        for (column, v) in [
            ("x_m", p.x_m),
            ("y_m", p.y_m),
            ("area_m2", p.area_m2),
            ("pressure_Pa", p.pressure_pa),
            ("N0_N", p.n0_n),
        ] {
            if !v.is_finite() {
                return Err(bad(column, format!("{} is not finite", num(v))));
            }
        }
        if p.area_m2 <= 0.0 {
            return Err(bad(
                "area_m2",
                format!("must be > 0, got {}", num(p.area_m2)),
            ));
        }
        if p.pressure_pa < 0.0 {
            return Err(bad(
                "pressure_Pa",
                format!(
                    "must be ≥ 0 (a contact pressure is compressive), got {}",
                    num(p.pressure_pa)
                ),
            ));
        }
        if p.n0_n < 0.0 {
            return Err(bad(
                "N0_N",
                format!(
                    "must be ≥ 0 (a normal preload presses the contact; a pulled node is not in \
                     contact), got {}",
                    num(p.n0_n)
                ),
            ));
        }
        let load = p.pressure_pa * p.area_m2;
        if (p.n0_n - load).abs() > PRELOAD_CONSISTENCY_TOLERANCE * p.n0_n.max(load) {
            return Err(bad(
                "N0_N",
                format!(
                    "{} N is not pressure_Pa × area_m2 = {} Pa × {} m² = {} N (relative \
                     tolerance {}): an edited column, or a column in another unit?",
                    num(p.n0_n),
                    num(p.pressure_pa),
                    num(p.area_m2),
                    num(load),
                    num(PRELOAD_CONSISTENCY_TOLERANCE)
                ),
            ));
        }
        if let Some(first) = seen.insert(p.id, line) {
            return Err(Error::parse(
                path,
                line,
                format!("duplicate node id {} (first at line {first})", p.id),
            ));
        }
        out.push(p);
    }
    if out.is_empty() {
        return Err(Error::parse(path, 0, "no preload rows"));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid_nodes(n: usize, h: f64) -> Vec<Node> {
        let mut v = Vec::new();
        for i in 0..n {
            for j in 0..n {
                v.push(Node {
                    id: (i * n + j) as u64 + 1,
                    x_m: i as f64 * h,
                    y_m: j as f64 * h,
                    area_m2: None,
                    line: 0,
                });
            }
        }
        v
    }

    #[test]
    fn tributary_areas_sum_to_the_hull_area() {
        let nodes = grid_nodes(6, 1e-3);
        let pts: Vec<_> = nodes.iter().map(|n| (n.x_m, n.y_m)).collect();
        let a = tributary_areas(&pts).unwrap();
        let total: f64 = a.iter().sum();
        assert!((total - 25e-6).abs() < 1e-15, "{total}");
        assert!(a.iter().all(|&x| x > 0.0 && x < 2e-6));
    }

    /// Elements of aspect ratio 5 keep every triangle: the areas still sum to the rectangle.
    #[test]
    fn an_anisotropic_structured_mesh_keeps_every_triangle() {
        let mut pts = Vec::new();
        for i in 0..8 {
            for j in 0..6 {
                pts.push((i as f64 * 5e-4, j as f64 * 1e-4));
            }
        }
        let t = triangulated_areas(&pts).unwrap();
        let total: f64 = t.area.iter().sum();
        assert!((total - 3.5e-3 * 5e-4).abs() < 1e-15, "{total}");
        assert_eq!(t.gap_area, 0.0);
    }

    /// An annulus of nodes round a bolt hole (radii 4 and 8 mm, about 0.5 mm apart, jittered
    /// off the cocircular positions): the areas sum to the annulus, π·(8² − 4²) = 150.8 mm²,
    /// within 0.5 % (+0.18 %: the polygons of the rings are not circles, and small triangles
    /// between neighbouring nodes of the inner ring remain), not to the disc's 201.1 mm² that
    /// the convex hull gives. Two 4 × 4 mm squares of nodes 5 mm apart: exactly their two areas.
    #[test]
    fn holes_and_separate_patches_get_no_area() {
        let (r_in, r_out, h): (f64, f64, f64) = (4e-3, 8e-3, 5e-4);
        let mut pts = Vec::new();
        let rings = ((r_out - r_in) / h).round() as usize;
        for k in 0..=rings {
            let r = r_in + k as f64 * h;
            let n = (2.0 * std::f64::consts::PI * r / h).round() as usize;
            for i in 0..n {
                let jitter = 0.02 * h * (((i * 7919 + k * 104729) % 997) as f64 / 498.0 - 1.0);
                let phi = 2.0 * std::f64::consts::PI * (i as f64 + 0.5 * (k % 2) as f64) / n as f64;
                pts.push(((r + jitter) * phi.cos(), (r + jitter) * phi.sin()));
            }
        }
        let t = triangulated_areas(&pts).unwrap();
        let total: f64 = t.area.iter().sum();
        let annulus = std::f64::consts::PI * (r_out * r_out - r_in * r_in);
        assert!(
            (total / annulus - 1.0).abs() < 0.005,
            "{total:e} m² against {annulus:e} m²"
        );
        assert!(t.gap_area > 0.9 * std::f64::consts::PI * r_in * r_in);
        assert!(t.area.iter().all(|&a| a > 0.0));

        let mut pts = Vec::new();
        for x0 in [0.0, 9e-3] {
            for i in 0..5 {
                for j in 0..5 {
                    pts.push((x0 + i as f64 * 1e-3, j as f64 * 1e-3));
                }
            }
        }
        let t = triangulated_areas(&pts).unwrap();
        let total: f64 = t.area.iter().sum();
        assert!((total - 32e-6).abs() < 1e-15, "{total:e}");
        assert!(
            (t.gap_area - (13e-3 * 4e-3 - 32e-6)).abs() < 1e-15,
            "{}",
            t.gap_area
        );
    }

    /// The limit of the rule: a column of elements 4 mm wide between columns 1 mm wide (rows
    /// 1 mm apart) cannot be told from a gap, and is left out; 2 mm wide it is kept.
    #[test]
    fn an_element_far_larger_than_its_neighbours_reads_as_a_gap() {
        for (xs, expected_gap) in [
            ([0.0, 1.0, 2.0, 6.0, 7.0, 8.0], 4.0 * 4.0),
            ([0.0, 1.0, 2.0, 4.0, 5.0, 6.0], 0.0),
        ] {
            let mut pts = Vec::new();
            for x in xs {
                for j in 0..5 {
                    pts.push((x * 1e-3, j as f64 * 1e-3));
                }
            }
            let t = triangulated_areas(&pts).unwrap();
            assert!(
                (t.gap_area - expected_gap * 1e-6).abs() < 1e-15,
                "{xs:?}: {}",
                t.gap_area
            );
            let total: f64 = t.area.iter().sum();
            assert!((total + t.gap_area - xs[5] * 4e-6).abs() < 1e-15);
        }
    }

    #[test]
    fn preloads_follow_pressure_and_rescale_to_total() {
        let nodes = grid_nodes(5, 1e-3);
        let place = Placement {
            offset_x_m: 0.01,
            offset_y_m: 0.02,
            rotation_rad: 0.3,
            scale: 1.0,
        };
        let sigma = |x: f64, y: f64| Ok(1e6 + 1e8 * (x - 0.01) + 5e7 * (y - 0.02));
        let (p, s) = preloads(&nodes, &place, sigma, None).unwrap();
        assert!((s.total_area_m2 - 16e-6).abs() < 1e-15);
        for q in &p {
            assert!((q.n0_n - q.pressure_pa * q.area_m2).abs() < 1e-12);
        }
        let (p, s) = preloads(&nodes, &place, sigma, Some(123.0)).unwrap();
        let total: f64 = p.iter().map(|q| q.n0_n).sum();
        assert!((total - 123.0).abs() <= 1e-9 * 123.0);
        assert!((s.total_load_n - 123.0).abs() <= 1e-9 * 123.0);
    }

    /// Preload files as `film` writes them read back; a negative preload, a preload that is not
    /// pressure × area, and the errors name file, line and column.
    #[test]
    fn preload_files_are_checked_row_by_row() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("pl.csv");
        let rows = vec![
            Preload {
                id: 7,
                x_m: 0.01,
                y_m: 0.02,
                area_m2: 2.8125e-7,
                pressure_pa: 2.049197055422e6,
                n0_n: 2.049197055422e6 * 2.8125e-7,
            },
            Preload {
                id: 8,
                x_m: 0.011,
                y_m: 0.02,
                area_m2: 1.0 / 3.0 * 1e-6,
                pressure_pa: 0.0,
                n0_n: 0.0,
            },
        ];
        write_preloads_csv(&path, &rows, "test").unwrap();
        assert_eq!(read_preloads_csv(&path).unwrap().len(), 2);
        let header = "id,x_m,y_m,area_m2,pressure_Pa,N0_N\n";
        let bad = |row: &str| {
            std::fs::write(&path, format!("# comment\n{header}{row}\n")).unwrap();
            read_preloads_csv(&path).unwrap_err().to_string()
        };
        let e = bad("7,0.048637,0.222796,2.8125e-7,2e6,-0.576");
        assert!(
            e.contains("pl.csv:3") && e.contains("N0_N") && e.contains("≥ 0"),
            "{e}"
        );
        let e = bad("7,0.048637,0.222796,2.8125e-7,2e6,5000");
        assert!(
            e.contains("pl.csv:3") && e.contains("N0_N") && e.contains("0.5625"),
            "{e}"
        );
        let e = bad("7,0.048637,0.222796,2.8125e-7,-2e6,0");
        assert!(e.contains("pl.csv:3") && e.contains("pressure_Pa"), "{e}");
        let e = bad("7,0.048637,0.222796,0,2e6,0");
        assert!(e.contains("pl.csv:3") && e.contains("area_m2"), "{e}");
    }

    #[test]
    fn placement_rotates_counter_clockwise() {
        let p = Placement {
            offset_x_m: 1.0,
            offset_y_m: 2.0,
            rotation_rad: std::f64::consts::FRAC_PI_2,
            scale: 2.0,
        };
        let (x, y) = p.apply(1.0, 0.0);
        assert!((x - 1.0).abs() < 1e-12 && (y - 4.0).abs() < 1e-12);
    }
}
