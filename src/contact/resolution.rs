//! How well the grid resolves a contact solution: the width, in grid points, of the contact
//! spots and of the free (non-contact) regions, from the perimeter of the contact set.
//!
//! Units: dimensionless (grid points, grid edges).
//!
//! # Measure
//! With `A_c` contact points, `A_f` free points and `P` interface edges (pairs of 4-neighbours of
//! which one is in contact and the other not; for a zero-padded window also the window edges of
//! contact points, beyond which the surfaces are free), the mean widths
//!
//! `w_c = 4 A_c / P`, `w_f = 4 A_f / P`
//!
//! count the grid points across a typical contact spot and a typical free region: a `k × k`
//! square spot gives `w = k`, a digitised disk of `D` points across `w ≈ πD/4` (its staircase
//! perimeter is `4D`). The discretisation error of the contact area sits on the interface, about
//! half a cell per interface edge, so the relative error of the contact area is of order
//! `1/w_c` and that of the free area of order `1/w_f`. The grid resolves the contact when the
//! narrower phase spans enough points, `min(w_c, w_f) ≥` [`RESOLVED_POINTS_ACROSS`]: at light
//! load the spots are the narrow phase, near full contact the free islands are. Counting points
//! per spot instead (the smallest or the median spot) flags every near-full contact, where the
//! contact set is one connected network with a few isolated single-point spots beside it, and
//! says nothing about the free islands that carry the remaining compliance.

use ndarray::Array2;

/// Points across the narrower phase (contact spots or free regions) from which a solution is
/// considered resolved: the grid-refinement study in BENCHMARKS.md ("Resolution criterion")
/// finds the contact area and kn within a few per cent of the twice-finer grid above it.
pub const RESOLVED_POINTS_ACROSS: f64 = 4.0;

/// Resolution of one contact set (see the module documentation): the counts, from which the
/// widths follow.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct ContactResolution {
    /// Grid points in contact.
    pub contact_points: usize,
    /// Grid points not in contact.
    pub free_points: usize,
    /// Grid edges between a contact point and a free point (or the window's outside).
    pub interface_edges: usize,
    /// Contact points on the border rows and columns of a non-periodic (zero-padded) window;
    /// always 0 for a periodic patch. Any such point means the contact reaches the window's
    /// edge: the surface is cut there and the solution depends on the window, not on the grid
    /// spacing (see [`ContactResolution::reaches_window_edge`]). Absent in shard files written
    /// before it existed (read as 0).
    #[serde(default)]
    pub border_contact_points: usize,
}

impl ContactResolution {
    /// Resolution of the contact set `mask` (`true` in contact). With `periodic`, edges wrap
    /// around; otherwise the window's outside counts as free.
    pub fn of(mask: &Array2<bool>, periodic: bool) -> Self {
        let (nx, ny) = mask.dim();
        let contact_points = mask.iter().filter(|c| **c).count();
        let mut edges = 0usize;
        let mut border = 0usize;
        for i in 0..nx {
            for j in 0..ny {
                let c = mask[[i, j]];
                // Each edge counted once: towards +x and +y, with the wrap or the outside.
                let right = if i + 1 < nx {
                    Some(mask[[i + 1, j]])
                } else if periodic {
                    Some(mask[[0, j]])
                } else {
                    None
                };
                let up = if j + 1 < ny {
                    Some(mask[[i, j + 1]])
                } else if periodic {
                    Some(mask[[i, 0]])
                } else {
                    None
                };
                for nb in [right, up] {
                    match nb {
                        Some(other) => edges += usize::from(other != c),
                        None => edges += usize::from(c),
                    }
                }
                if !periodic {
                    // Edges towards −x and −y at the window's border.
                    edges += usize::from(c && i == 0) + usize::from(c && j == 0);
                    let on_border = i == 0 || j == 0 || i + 1 == nx || j + 1 == ny;
                    border += usize::from(c && on_border);
                }
            }
        }
        Self {
            contact_points,
            free_points: nx * ny - contact_points,
            interface_edges: edges,
            border_contact_points: border,
        }
    }

    /// The warning for the pressures `(p̄ in Pa, resolution)` at which the contact reaches the
    /// edge of a non-periodic window ([`Self::reaches_window_edge`]), or `None` when it reaches
    /// it at none.
    pub fn window_edge_warning<'a>(
        points: impl IntoIterator<Item = (f64, &'a ContactResolution)>,
    ) -> Option<String> {
        let at: Vec<String> = points
            .into_iter()
            .filter(|(_, r)| r.reaches_window_edge())
            .map(|(p, r)| {
                format!(
                    "{p:e} Pa ({} of {} contact points)",
                    r.border_contact_points, r.contact_points
                )
            })
            .collect();
        (!at.is_empty()).then(|| {
            format!(
                "the contact reaches the edge of the non-periodic window (contact points on its \
                 border rows/columns) at {}: the result depends on the window; enlarge the window \
                 (a finer grid does not help)",
                at.join(", ")
            )
        })
    }

    /// True when contact points lie on the border rows/columns of a non-periodic window: the
    /// contact is cut by the window, so area and kn depend on the window size (enlarge the
    /// window); refining the grid does not help.
    pub fn reaches_window_edge(&self) -> bool {
        self.border_contact_points > 0
    }

    /// Mean width of a phase of `points` points, `4 points / P` (infinite without interface).
    fn width(&self, points: usize) -> f64 {
        if self.interface_edges == 0 {
            f64::INFINITY
        } else {
            4.0 * points as f64 / self.interface_edges as f64
        }
    }

    /// Mean width of the contact spots in grid points, `4 A_c / P`: 0 without contact, infinite
    /// without interface (full periodic contact).
    pub fn points_across_contact(&self) -> f64 {
        if self.contact_points == 0 {
            0.0
        } else {
            self.width(self.contact_points)
        }
    }

    /// Mean width of the free regions in grid points, `4 A_f / P`: infinite without free points
    /// or without interface.
    pub fn points_across_free(&self) -> f64 {
        if self.free_points == 0 {
            f64::INFINITY
        } else {
            self.width(self.free_points)
        }
    }

    /// Points across the narrower phase, `min(w_c, w_f)`.
    pub fn points_across(&self) -> f64 {
        self.points_across_contact().min(self.points_across_free())
    }

    /// True when the contact spots are the narrower phase (or as narrow as the free regions):
    /// [`Self::points_across`] is theirs.
    pub fn contact_is_narrower(&self) -> bool {
        self.points_across_contact() <= self.points_across_free()
    }

    /// True when the narrower phase spans at least [`RESOLVED_POINTS_ACROSS`] points.
    pub fn resolved(&self) -> bool {
        self.points_across() >= RESOLVED_POINTS_ACROSS
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `k × k` square from `at`, wrapping around the grid.
    fn square(n: usize, k: usize, at: (usize, usize)) -> Array2<bool> {
        Array2::from_shape_fn((n, n), |(i, j)| {
            (i + n - at.0) % n < k && (j + n - at.1) % n < k
        })
    }

    #[test]
    fn square_spot_is_k_points_across() {
        for k in [1, 3, 8] {
            let r = ContactResolution::of(&square(20, k, (5, 6)), true);
            assert_eq!(r.interface_edges, 4 * k);
            assert_eq!(r.points_across_contact(), k as f64);
            assert_eq!(
                r.points_across_free(),
                4.0 * (400 - k * k) as f64 / (4 * k) as f64
            );
        }
        // The same spot at a periodic corner (split over the wrap) is unchanged; at a window's
        // corner its outside edges count.
        let r = ContactResolution::of(&square(20, 4, (18, 18)), true);
        assert_eq!(r.points_across_contact(), 4.0);
        let w = ContactResolution::of(&square(20, 4, (0, 0)), false);
        assert_eq!(w.interface_edges, 16);
    }

    /// Contact points on a non-periodic window's border rows/columns are counted (the 4 × 4
    /// square at the corner has 7 of its 16 points on row 0 or column 0); inside the window, or
    /// on a periodic patch (no edge), none.
    #[test]
    fn border_contact_counted_only_for_a_window() {
        let corner = ContactResolution::of(&square(20, 4, (0, 0)), false);
        assert_eq!(corner.border_contact_points, 7);
        assert!(corner.reaches_window_edge());
        let far = ContactResolution::of(&square(20, 4, (16, 16)), false);
        assert_eq!(far.border_contact_points, 7);
        let inside = ContactResolution::of(&square(20, 4, (5, 6)), false);
        assert_eq!(inside.border_contact_points, 0);
        assert!(!inside.reaches_window_edge());
        let periodic = ContactResolution::of(&square(20, 4, (0, 0)), true);
        assert_eq!(periodic.border_contact_points, 0);
        assert!(!periodic.reaches_window_edge());
    }

    #[test]
    fn disk_width_is_pi_over_four_of_its_diameter() {
        let (n, d) = (200, 80.0);
        let m = Array2::from_shape_fn((n, n), |(i, j)| {
            let (x, y) = (i as f64 - 99.5, j as f64 - 99.5);
            x * x + y * y <= d * d / 4.0
        });
        let r = ContactResolution::of(&m, false);
        let want = std::f64::consts::PI * d / 4.0;
        assert!(
            (r.points_across_contact() / want - 1.0).abs() < 0.03,
            "{r:?}"
        );
    }

    /// Near full contact with many isolated one-point spots beside a connected contact network
    /// (the case that the median-spot criterion flagged): resolved when the free islands are
    /// wide; a sparse pattern of one-point spots at light load is not.
    #[test]
    fn near_full_contact_resolved_sparse_points_not() {
        let n = 128;
        // Contact everywhere except 8 × 8 free islands on a 16-point lattice, plus single-point
        // contact spots inside some islands.
        let m = Array2::from_shape_fn((n, n), |(i, j)| {
            let (a, b) = (i % 16, j % 16);
            let in_island = (4..12).contains(&a) && (4..12).contains(&b);
            !in_island || (a == 7 && b == 7)
        });
        let r = ContactResolution::of(&m, true);
        assert!(r.points_across_free() > 4.0 && r.resolved(), "{r:?}");
        let sparse = Array2::from_shape_fn((n, n), |(i, j)| i % 8 == 0 && j % 8 == 0);
        let s = ContactResolution::of(&sparse, true);
        assert_eq!(s.points_across_contact(), 1.0);
        assert!(!s.resolved());
        let none = ContactResolution::of(&Array2::from_elem((4, 4), false), true);
        assert_eq!(none.points_across_contact(), 0.0);
        assert!(!none.resolved());
        let full = ContactResolution::of(&Array2::from_elem((4, 4), true), true);
        assert!(full.resolved() && full.points_across_free().is_infinite());
    }
}
