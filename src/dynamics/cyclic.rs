//! Cyclic symmetry: one sector of a structure of `N` identical sectors (a bladed disk) under a
//! travelling-wave (engine-order) excitation, solved on the sector alone.
//!
//! A force of engine order `EO` reaches sector `j` delayed by `j·φ/ω`, with the inter-sector
//! phase `φ = 2π·EO/N`. The steady state of a cyclically symmetric structure is then the same
//! travelling wave: sector `j + 1` moves like sector `j` advanced in time by `φ/ω`,
//! `q_{j+1}(t) = q_j(t + φ/ω)`. Harmonic `h` of the response therefore sees the inter-sector
//! phase `h·φ` (complex amplitudes: `Q_{j+1,h} = Q_{j,h}·e^{i·h·φ}`), and belongs to the
//! harmonic index (nodal diameter) `k_h = min(h·EO mod N, N − h·EO mod N)`
//! ([`CyclicSymmetry::harmonic_index`]). In the real basis `a·cos hωt + b·sin hωt` of the harmonic
//! balance the phase is a rotation of the coefficient pair ([`shift_operator`]):
//!
//! ```text
//! (a, b) ↦ (a·cos hφ + b·sin hφ,  b·cos hφ − a·sin hφ)      (the mean, h = 0, is unchanged)
//! ```
//!
//! **Sector boundary condition.** The sector's DOFs are split into its left boundary `L`, its
//! right boundary `R` (paired one to one with `L`: `R` of sector `j` is `L` of sector `j + 1`)
//! and the rest `I`. Per harmonic, `Q_R = S(hφ)·Q_L`, so the independent unknowns are `Q_I` and
//! `Q_L` and the sector's harmonics are `Q = T·z` with the real expansion `T`
//! ([`CyclicSymmetry::expansion`]). The balance is projected with `Tᵀ` (virtual work over the
//! cyclic displacements): the interface forces the neighbours exert on `L` and `R` cancel in
//! `Tᵀ·(…)` because `S` is orthogonal, so `Tᵀ·R(T·z) = 0` is exactly the full assembly's balance
//! restricted to travelling waves. `φ = 0` (`EO = 0`) and `φ = π` (`EO = N/2`) are the real
//! standing cases (`Q_R = ±Q_L` on odd harmonics); they need no special treatment.
//!
//! **Elements between neighbouring sectors.** An element joining this sector to the next one
//! (e.g. a damper between adjacent blades) acts on `u = P·q + P'·q_next`, and `q_next` is `q`
//! shifted in time by `φ/ω`: its harmonics are `S(hφ)·Q`, so the AFT sees
//! `U = P·Q + P'·S·Q`, an operator linear in `Q`. The element's force reaches this sector through
//! `P` and, from the element of the previous sector (the same force delayed by `φ/ω`), through
//! `P'`: `Pᵀ·F̂ + P'ᵀ·Sᵀ·F̂`, the transpose of the displacement operator. The harmonic-balance
//! Jacobian is that operator's `Aᵀ·J_e·A` and stays exact ([`crate::dynamics::hbm`]).
//!
//! References: Thomas, D. L. (1979) Dynamics of rotationally periodic structures, *Int. J. Numer.
//! Meth. Eng.* 14:81–102 (the sector condition per harmonic index); Petrov, E. P. (2004) A method
//! for use of cyclic symmetry properties in analysis of nonlinear multiharmonic vibrations of
//! bladed disks, *J. Turbomach.* 126:175–183 (harmonic `h` of an engine-order travelling wave
//! belongs to harmonic index `h·EO`; friction dampers between neighbouring blades by the phase
//! shift in time).

use crate::core::error::{Error, Result};
use crate::dynamics::aft::Harmonics;
use nalgebra::DMatrix;

/// Cyclic symmetry of a sector: the number of sectors, the engine order of the excitation and
/// the paired left and right boundary coordinates.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct CyclicSymmetry {
    /// Number of sectors `N` of the full structure (≥ 2).
    pub sectors: usize,
    /// Engine order `EO` of the excitation (≥ 0): inter-sector phase `φ = 2π·EO/N`.
    pub engine_order: usize,
    /// Coordinates of the left boundary (indices into the sector's coordinates).
    pub left: Vec<usize>,
    /// Coordinates of the right boundary, `right[i]` the image of `left[i]` in the next sector.
    pub right: Vec<usize>,
}

impl CyclicSymmetry {
    /// Check the definition against a sector of `n` coordinates: `sectors ≥ 2`, as many right as
    /// left boundary coordinates, each coordinate on one boundary at most and within the sector.
    /// Errors name `cyclic.sectors`, `cyclic.left` or `cyclic.right`.
    pub fn new(
        sectors: usize,
        engine_order: usize,
        left: Vec<usize>,
        right: Vec<usize>,
        n: usize,
    ) -> Result<Self> {
        if sectors < 2 {
            return Err(Error::param(
                "cyclic.sectors",
                format!("a cyclic structure has at least 2 sectors, got {sectors}"),
            ));
        }
        if left.len() != right.len() {
            return Err(Error::param(
                "cyclic.right",
                format!(
                    "{} right boundary DOFs for {} left ones (pair each left DOF with its image \
                     on the right)",
                    right.len(),
                    left.len()
                ),
            ));
        }
        let mut seen = vec![false; n];
        for (key, list) in [("cyclic.left", &left), ("cyclic.right", &right)] {
            for &i in list {
                if i >= n {
                    return Err(Error::param(
                        key,
                        format!("coordinate {} of a sector with {n}", i + 1),
                    ));
                }
                if std::mem::replace(&mut seen[i], true) {
                    return Err(Error::param(
                        key,
                        format!(
                            "coordinate {} is listed twice (a DOF is on one boundary, once)",
                            i + 1
                        ),
                    ));
                }
            }
        }
        Ok(Self {
            sectors,
            engine_order,
            left,
            right,
        })
    }

    /// Inter-sector phase of the fundamental, `φ = 2π·EO/N` (rad).
    pub fn phase(&self) -> f64 {
        std::f64::consts::TAU * (self.engine_order % self.sectors) as f64 / self.sectors as f64
    }

    /// Harmonic index (nodal diameter) of harmonic `h`: `min(h·EO mod N, N − h·EO mod N)`.
    pub fn harmonic_index(&self, h: usize) -> usize {
        let r = (h * self.engine_order) % self.sectors;
        r.min(self.sectors - r)
    }

    /// Sector coordinates kept as unknowns (all but the right boundary), in order.
    pub fn kept(&self, n: usize) -> Vec<usize> {
        (0..n).filter(|i| !self.right.contains(i)).collect()
    }

    /// `T` (`n·len × m·len`, coordinate-major, `m = n − |R|`): the sector's harmonics from the
    /// kept coordinates' harmonics `z`, `Q_R = S(hφ)·Q_L` (see the [module documentation](self)).
    pub fn expansion(&self, n: usize, harmonics: &Harmonics) -> DMatrix<f64> {
        let len = harmonics.len();
        let kept = self.kept(n);
        let mut column_of = vec![usize::MAX; n];
        for (j, &i) in kept.iter().enumerate() {
            column_of[i] = j;
        }
        let s = shift_operator(harmonics, self.phase());
        let mut t = DMatrix::zeros(n * len, kept.len() * len);
        for (j, &i) in kept.iter().enumerate() {
            for h in 0..len {
                t[(i * len + h, j * len + h)] = 1.0;
            }
        }
        for (&l, &r) in self.left.iter().zip(&self.right) {
            let j = column_of[l];
            t.view_mut((r * len, j * len), (len, len)).copy_from(&s);
        }
        t
    }
}

/// `S(θ)` (`len × len`): the harmonics of `x(t + θ/ω)` from those of `x(t)`; order `k` turns its
/// pair `(a, b)` of `a·cos kωt + b·sin kωt` by `kθ`: `(a cos kθ + b sin kθ, b cos kθ − a sin kθ)`.
pub fn shift_operator(harmonics: &Harmonics, theta: f64) -> DMatrix<f64> {
    let len = harmonics.len();
    let mut s = DMatrix::zeros(len, len);
    let mut c = 0;
    for &k in harmonics.orders() {
        if k == 0 {
            s[(c, c)] = 1.0;
            c += 1;
            continue;
        }
        let (sn, cs) = (k as f64 * theta).sin_cos();
        s[(c, c)] = cs;
        s[(c, c + 1)] = sn;
        s[(c + 1, c)] = -sn;
        s[(c + 1, c + 1)] = cs;
        c += 2;
    }
    s
}

/// `I_n ⊗ S`: [`shift_operator`] applied to every one of `n` coordinates (coordinate-major).
pub fn shift_all(n: usize, s: &DMatrix<f64>) -> DMatrix<f64> {
    let len = s.nrows();
    let mut out = DMatrix::zeros(n * len, n * len);
    for r in 0..n {
        out.view_mut((r * len, r * len), (len, len)).copy_from(s);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::TAU;

    /// `S(θ)` is the time shift: the synthesis of `S·x` at `t` equals that of `x` at `t + θ/ω`.
    #[test]
    fn shift_operator_is_a_time_shift() {
        let h = Harmonics::new(3, false, Some(16)).unwrap();
        let x: Vec<f64> = (0..h.len()).map(|i| 0.3 + i as f64 * 0.7).collect();
        let theta = 0.83;
        let s = shift_operator(&h, theta);
        let y = &s * nalgebra::DVector::from_vec(x.clone());
        let value = |c: &[f64], wt: f64| {
            let mut v = 0.0;
            let mut i = 0;
            for &k in h.orders() {
                if k == 0 {
                    v += c[i];
                    i += 1;
                } else {
                    let a = k as f64 * wt;
                    v += c[i] * a.cos() + c[i + 1] * a.sin();
                    i += 2;
                }
            }
            v
        };
        for wt in [0.0, 0.4, 2.5, 5.9] {
            let (a, b) = (value(y.as_slice(), wt), value(&x, wt + theta));
            assert!((a - b).abs() < 1e-12, "ωt = {wt}: {a} vs {b}");
        }
    }

    #[test]
    fn harmonic_index_folds_to_the_nodal_diameter() {
        let c = CyclicSymmetry::new(7, 3, vec![0], vec![1], 3).unwrap();
        let k: Vec<usize> = (0..=4).map(|h| c.harmonic_index(h)).collect();
        // h·EO = 0, 3, 6, 9, 12 mod 7 = 0, 3, 6, 2, 5 → 0, 3, 1, 2, 2.
        assert_eq!(k, vec![0, 3, 1, 2, 2]);
        assert!((c.phase() - TAU * 3.0 / 7.0).abs() < 1e-15);
    }

    #[test]
    fn bad_definitions_are_refused() {
        assert!(CyclicSymmetry::new(1, 0, vec![0], vec![1], 2).is_err());
        let e = CyclicSymmetry::new(4, 1, vec![0, 1], vec![2], 3).unwrap_err();
        assert!(e.to_string().contains("cyclic.right"), "{e}");
        let e = CyclicSymmetry::new(4, 1, vec![0], vec![0], 3).unwrap_err();
        assert!(e.to_string().contains("twice"), "{e}");
        assert!(CyclicSymmetry::new(4, 1, vec![0], vec![5], 3).is_err());
    }
}
