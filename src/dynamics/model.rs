//! The linear part of a structure and the elements attached to it, in generalised coordinates.
//!
//! `M·q̈ + C·q̇ + K·q + Σ_e P_eᵀ·f_e(P_e·q) = F(t)`, where `q` are either the physical degrees of
//! freedom of a lumped model ([`Structure::lumped`]: M, C, K given) or the modal coordinates of a
//! reduced modal model ([`Structure::modal`]: `M = I`, `C = diag(2ζ_r ω_r)`, `K = diag(ω_r²)`,
//! mass-normalised mode shapes), and `P_e` (`d × n`) maps the coordinates onto element `e`'s
//! local relative displacements `u_e = P_e·q` (for a node pair `a`–`b` with local frame `R`:
//! `u_e = R·(x_a − x_b)`; against ground `x_b = 0`; in modal coordinates `x = Φ·q`, so
//! `P_e = R·(Φ_a − Φ_b)`). Units: SI (kg, N/m, N·s/m; modal coordinates in m·kg^½ with mass
//! normalised shapes in kg^-½).

use crate::core::error::{Error, Result};
use crate::dynamics::cyclic::CyclicSymmetry;
use crate::element::HystereticElement;
use nalgebra::{DMatrix, DVector};
use std::sync::Arc;

/// What the coordinates of a [`Structure`] are.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum CoordinateKind {
    /// Physical degrees of freedom of a lumped model.
    Physical,
    /// Modal coordinates of a reduced modal model.
    Modal,
}

/// An element and the map from the structure's coordinates to its local displacements.
#[derive(Debug, Clone)]
pub struct AttachedElement {
    /// Name used in outputs (e.g. the element table id).
    pub label: String,
    /// The element law with its parameters.
    pub element: Arc<dyn HystereticElement>,
    /// `P_e`, `d × n`: `u_e = P_e·q` (plus `P'_e·q_next` for an element across sectors).
    pub map: DMatrix<f64>,
    /// `P'_e`, `d × n`, of an element joining a cyclic sector to the next sector: the map of the
    /// next sector's coordinates `q_next` ([`crate::dynamics::cyclic`]); `None` inside a sector.
    pub neighbour_map: Option<DMatrix<f64>>,
}

/// Linear structure in generalised coordinates with nonlinear elements attached.
#[derive(Debug, Clone)]
pub struct Structure {
    /// Physical DOFs of a lumped model or modal coordinates.
    pub kind: CoordinateKind,
    /// One label per coordinate (`node.x` for lumped DOFs, `mode 3` for modal coordinates).
    pub labels: Vec<String>,
    /// Mass matrix `M` (kg; identity for mass-normalised modal coordinates).
    pub mass: DMatrix<f64>,
    /// Viscous damping matrix `C` (N·s/m; `2ζ_r·ω_r` on the diagonal for modal coordinates).
    pub damping: DMatrix<f64>,
    /// Stiffness matrix `K` (N/m; `ω_r²` on the diagonal for modal coordinates).
    pub stiffness: DMatrix<f64>,
    /// The nonlinear elements with their maps.
    pub elements: Vec<AttachedElement>,
    /// Cyclic symmetry when the structure is one sector of a cyclic structure
    /// ([`Structure::make_cyclic`]); `None` for a structure on its own.
    pub cyclic: Option<CyclicSymmetry>,
}

fn check_square(name: &str, a: &DMatrix<f64>, n: usize) -> Result<()> {
    if a.nrows() != n || a.ncols() != n {
        return Err(Error::param(
            name,
            format!("must be {n} × {n}, got {} × {}", a.nrows(), a.ncols()),
        ));
    }
    if let Some(v) = a.iter().find(|v| !v.is_finite()) {
        return Err(Error::param(name, format!("entry {v} is not finite")));
    }
    Ok(())
}

fn check_symmetric(name: &str, a: &DMatrix<f64>) -> Result<()> {
    let scale = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for r in 0..a.nrows() {
        for c in 0..r {
            if (a[(r, c)] - a[(c, r)]).abs() > 1e-9 * scale {
                return Err(Error::param(
                    name,
                    format!(
                        "must be symmetric: entry ({}, {}) = {} but ({}, {}) = {}",
                        r + 1,
                        c + 1,
                        a[(r, c)],
                        c + 1,
                        r + 1,
                        a[(c, r)]
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// Smallest eigenvalue of a symmetric matrix relative to its largest magnitude.
fn relative_min_eigenvalue(a: &DMatrix<f64>) -> f64 {
    let e = a.clone().symmetric_eigen().eigenvalues;
    let max = e.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let min = e.iter().fold(f64::INFINITY, |m, &v| m.min(v));
    if max == 0.0 {
        0.0
    } else {
        min / max
    }
}

impl Structure {
    /// Lumped model: symmetric positive definite `M` and `K`, symmetric positive semi-definite
    /// `C` (no negative damping), all `n × n` with `n = labels.len()`. Errors name `mass`,
    /// `stiffness` or `damping`.
    pub fn lumped(
        labels: Vec<String>,
        mass: DMatrix<f64>,
        damping: DMatrix<f64>,
        stiffness: DMatrix<f64>,
    ) -> Result<Self> {
        let n = labels.len();
        if n == 0 {
            return Err(Error::param("mass", "the model has no degree of freedom"));
        }
        for (name, a) in [
            ("mass", &mass),
            ("damping", &damping),
            ("stiffness", &stiffness),
        ] {
            check_square(name, a, n)?;
            check_symmetric(name, a)?;
        }
        for (name, a) in [("mass", &mass), ("stiffness", &stiffness)] {
            let r = relative_min_eigenvalue(a);
            if r <= 1e-12 {
                return Err(Error::param(
                    name,
                    format!(
                        "must be positive definite (non-singular); smallest eigenvalue / largest = {r:.3e}"
                    ),
                ));
            }
        }
        let r = relative_min_eigenvalue(&damping);
        if r < -1e-12 {
            return Err(Error::param(
                "damping",
                format!(
                    "negative damping: the matrix has a negative eigenvalue (relative {r:.3e})"
                ),
            ));
        }
        Ok(Self {
            kind: CoordinateKind::Physical,
            labels,
            mass,
            damping,
            stiffness,
            elements: Vec::new(),
            cyclic: None,
        })
    }

    /// Reduced modal model from natural frequencies (Hz, > 0) and modal damping ratios (≥ 0).
    /// Errors name `frequency_Hz` or `damping_ratio` with the mode number (1-based).
    pub fn modal(frequencies_hz: &[f64], damping_ratios: &[f64]) -> Result<Self> {
        let n = frequencies_hz.len();
        if n == 0 || damping_ratios.len() != n {
            return Err(Error::param(
                "damping_ratio",
                format!(
                    "{} frequencies and {} damping ratios (need one of each per mode, at least one mode)",
                    n,
                    damping_ratios.len()
                ),
            ));
        }
        for (r, (&f, &z)) in frequencies_hz.iter().zip(damping_ratios).enumerate() {
            if !(f.is_finite() && f > 0.0) {
                return Err(Error::param(
                    "frequency_Hz",
                    format!(
                        "mode {}: natural frequency must be finite and > 0, got {f}",
                        r + 1
                    ),
                ));
            }
            if !(z.is_finite() && z >= 0.0) {
                return Err(Error::param(
                    "damping_ratio",
                    format!("mode {}: negative or non-finite damping ratio {z}", r + 1),
                ));
            }
        }
        let w: Vec<f64> = frequencies_hz
            .iter()
            .map(|f| 2.0 * std::f64::consts::PI * f)
            .collect();
        Ok(Self {
            kind: CoordinateKind::Modal,
            labels: (1..=n).map(|r| format!("mode {r}")).collect(),
            mass: DMatrix::identity(n, n),
            damping: DMatrix::from_diagonal(&DVector::from_iterator(
                n,
                w.iter().zip(damping_ratios).map(|(w, z)| 2.0 * z * w),
            )),
            stiffness: DMatrix::from_diagonal(&DVector::from_iterator(n, w.iter().map(|w| w * w))),
            elements: Vec::new(),
            cyclic: None,
        })
    }

    /// A single mass-normalised mode (frequency in Hz, damping ratio): the 1-DOF modal model
    /// of a nonlinear mode. Attach a joint element on the modal coordinate with
    /// `attach(label, element, DMatrix::from_element(1, 1, φ))`, `φ` the mode shape's value
    /// across the joint (1 for an element acting directly on the modal coordinate).
    pub fn single_mode(frequency_hz: f64, damping_ratio: f64) -> Result<Self> {
        Self::modal(&[frequency_hz], &[damping_ratio])
    }

    /// Number of coordinates.
    pub fn n(&self) -> usize {
        self.labels.len()
    }

    /// Whether the modal matrices are diagonal (modal coordinates).
    pub fn is_modal(&self) -> bool {
        self.kind == CoordinateKind::Modal
    }

    /// Attach an element with its map `P_e` (`d × n`).
    pub fn attach(
        &mut self,
        label: impl Into<String>,
        element: Arc<dyn HystereticElement>,
        map: DMatrix<f64>,
    ) -> Result<()> {
        let label = label.into();
        if map.nrows() != element.dofs() || map.ncols() != self.n() {
            return Err(Error::param(
                "map",
                format!(
                    "element {label}: map must be {} × {}, got {} × {}",
                    element.dofs(),
                    self.n(),
                    map.nrows(),
                    map.ncols()
                ),
            ));
        }
        if map.iter().any(|v| !v.is_finite()) {
            return Err(Error::param("map", format!("element {label}: not finite")));
        }
        self.elements.push(AttachedElement {
            label,
            element,
            map,
            neighbour_map: None,
        });
        Ok(())
    }

    /// Declare the structure one sector of `sectors` identical sectors under an excitation of
    /// engine order `engine_order`, with the left boundary coordinates `left` paired with their
    /// images `right` in the next sector (indices into the coordinates;
    /// [`crate::dynamics::cyclic`]). Lumped models only: the boundary conditions act on
    /// physical DOFs. Errors name `cyclic.*`.
    pub fn make_cyclic(
        &mut self,
        sectors: usize,
        engine_order: usize,
        left: Vec<usize>,
        right: Vec<usize>,
    ) -> Result<()> {
        if self.is_modal() {
            return Err(Error::param(
                "cyclic",
                "cyclic symmetry needs the sector's physical DOFs (a lumped model): the \
                 boundary conditions pair DOFs of the left and right boundaries",
            ));
        }
        self.cyclic = Some(CyclicSymmetry::new(
            sectors,
            engine_order,
            left,
            right,
            self.n(),
        )?);
        Ok(())
    }

    /// Attach an element joining this cyclic sector to the next one: `u_e = P_e·q + P'_e·q_next`
    /// with `map = P_e` and `neighbour_map = P'_e` (each `d × n`, `q_next` the next sector's
    /// coordinates in this sector's numbering). The structure must be cyclic
    /// ([`Structure::make_cyclic`]).
    pub fn attach_across(
        &mut self,
        label: impl Into<String>,
        element: Arc<dyn HystereticElement>,
        map: DMatrix<f64>,
        neighbour_map: DMatrix<f64>,
    ) -> Result<()> {
        let label = label.into();
        if self.cyclic.is_none() {
            return Err(Error::param(
                "map",
                format!("element {label}: joins a next sector, but the structure is not cyclic"),
            ));
        }
        if neighbour_map.shape() != map.shape() || neighbour_map.iter().any(|v| !v.is_finite()) {
            return Err(Error::param(
                "map",
                format!(
                    "element {label}: the next sector's map must be finite and {} × {}",
                    map.nrows(),
                    map.ncols()
                ),
            ));
        }
        self.attach(label, element, map)?;
        self.elements
            .last_mut()
            .expect("just attached")
            .neighbour_map = Some(neighbour_map);
        Ok(())
    }

    /// Whether an element joins the sector to the next one.
    pub fn has_elements_across(&self) -> bool {
        self.elements.iter().any(|e| e.neighbour_map.is_some())
    }

    /// Total number of element displacement components (the size of the contact problem).
    pub fn contact_dofs(&self) -> usize {
        self.elements.iter().map(|e| e.element.dofs()).sum()
    }
}

/// Undamped modes of `K·φ = ω²·M·φ` for symmetric `K` (its symmetric part is used) and
/// symmetric positive-definite `M`: by the Cholesky factor `M = L·Lᵀ`, the symmetric standard
/// problem `L⁻¹·K·L⁻ᵀ·y = ω²·y`, `φ = L⁻ᵀ·y` (Bathe, *Finite Element Procedures*, §10.2.5).
/// Returns the eigenvalues `ω²` (rad²/s², ascending; a rigid-body or unstable mode gives
/// `ω² ≤ 0`) and the mass-normalised shapes `φᵀ·M·φ = 1` in the same order. Errors name `mass`.
pub fn undamped_modes(
    mass: &DMatrix<f64>,
    stiffness: &DMatrix<f64>,
) -> Result<(Vec<f64>, Vec<DVector<f64>>)> {
    let n = mass.nrows();
    let l = mass
        .clone()
        .cholesky()
        .ok_or_else(|| {
            Error::param(
                "mass",
                "must be positive definite (a mass at every coordinate)",
            )
        })?
        .l();
    let sym = |a: &DMatrix<f64>| (a + a.transpose()) * 0.5;
    let li_k = l
        .solve_lower_triangular(&sym(stiffness))
        .ok_or_else(|| Error::param("mass", "singular Cholesky factor"))?;
    let a = l
        .solve_lower_triangular(&li_k.transpose())
        .ok_or_else(|| Error::param("mass", "singular Cholesky factor"))?;
    let eig = sym(&a).symmetric_eigen();
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&x, &y| eig.eigenvalues[x].total_cmp(&eig.eigenvalues[y]));
    let lt = l.transpose();
    let mut shapes = Vec::with_capacity(n);
    for &i in &order {
        let y = eig.eigenvectors.column(i).into_owned();
        shapes.push(
            lt.solve_upper_triangular(&y)
                .ok_or_else(|| Error::param("mass", "singular Cholesky factor"))?,
        );
    }
    Ok((order.iter().map(|&i| eig.eigenvalues[i]).collect(), shapes))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn invalid_matrices_are_refused() {
        let l = vec!["a.x".to_string(), "b.x".to_string()];
        let m = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, 2.0]);
        let k = DMatrix::from_row_slice(2, 2, &[2.0, -1.0, -1.0, 1.0]);
        let c = DMatrix::zeros(2, 2);
        assert!(Structure::lumped(l.clone(), m.clone(), c.clone(), k.clone()).is_ok());
        let bad = DMatrix::from_row_slice(2, 2, &[2.0, -1.0, -0.5, 1.0]);
        let e = Structure::lumped(l.clone(), m.clone(), c.clone(), bad).unwrap_err();
        assert!(e.to_string().contains("stiffness") && e.to_string().contains("symmetric"));
        let sing = DMatrix::from_row_slice(2, 2, &[1.0, -1.0, -1.0, 1.0]);
        let e = Structure::lumped(l.clone(), m.clone(), c.clone(), sing).unwrap_err();
        assert!(e.to_string().contains("stiffness") && e.to_string().contains("singular"));
        let e =
            Structure::lumped(l.clone(), DMatrix::zeros(2, 2), c.clone(), k.clone()).unwrap_err();
        assert!(e.to_string().contains("mass"));
        let neg = DMatrix::from_row_slice(2, 2, &[-0.1, 0.0, 0.0, 0.1]);
        let e = Structure::lumped(l, m, neg, k).unwrap_err();
        assert!(e.to_string().contains("negative damping"), "{e}");
        assert!(Structure::modal(&[10.0], &[-0.01]).is_err());
        assert!(Structure::modal(&[0.0], &[0.01]).is_err());
    }
}
