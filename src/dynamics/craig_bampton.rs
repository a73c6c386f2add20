//! Craig–Bampton reduction of a finite-element model: interface (boundary) DOFs kept, interior
//! described by static constraint modes and fixed-interface normal modes.
//!
//! Craig, R. R. & Bampton, M. C. C. (1968), "Coupling of substructures for dynamic analyses",
//! AIAA Journal 6(7):1313–1319. With the DOFs split into boundary `B` (kept: contact nodes,
//! excitation and response points) and interior `I`, the interior displacement is
//!
//! ```text
//! u_I = Ψ·u_B + Φ·q,   Ψ = −K_II⁻¹·K_IB          (static constraint modes)
//!                      K_II·φ_j = λ_j·M_II·φ_j    (fixed-interface normal modes, lowest m,
//!                                                  mass-normalised: Φᵀ·M_II·Φ = I)
//! ```
//!
//! and the reduced matrices on the coordinates `[u_B; q]` are `K_r = Tᵀ·K·T`, `M_r = Tᵀ·M·T`
//! with `T = [I 0; Ψ Φ]`:
//!
//! ```text
//! K_r = [K_BB + K_BI·Ψ   0 ]      M_r = [M_BB + M_BI·Ψ + Ψᵀ·M_IB + Ψᵀ·M_II·Ψ   (M_BI + Ψᵀ·M_II)·Φ]
//!       [0               Λ ]            [sym.                                  Φᵀ·M_II·Φ = I    ]
//! ```
//!
//! (the stiffness coupling `K_BI·Φ + Ψᵀ·K_II·Φ` vanishes identically by the definition of Ψ).
//! With every interior mode kept the reduction is exact: `T` is then a change of basis.
//!
//! **Sparse algebra** (`faer`): `K_II` is factorised once by a sparse Cholesky factorisation
//! (`LLᵀ` with a fill-reducing ordering); it gives the constraint modes (one solve per boundary
//! DOF) and the normal modes. The normal modes are found by **shift-invert subspace iteration
//! with Rayleigh–Ritz projection** (Bathe, *Finite Element Procedures*, 2nd ed. 2014, §11.6):
//! `Y = (K_II − σ·M_II)⁻¹·M_II·X`, then the projected problem `(Yᵀ·K_II·Y)·Q = (Yᵀ·M_II·Y)·Q·Λ̂`
//! solved densely and `X ← Y·Q`, with `p = max(2m, m + 8)` vectors (capped at the interior
//! size; when that is the whole interior, the dense problem is solved instead). The shift is `σ = 0`: the lowest modes are the ones wanted, and `K_II` must be
//! factorised for Ψ anyway (it is positive definite whenever the boundary DOFs hold the
//! structure, the premise of the method). Each mode's convergence is measured by its relative
//! eigen-residual `‖K_II·φ − λ·M_II·φ‖ / ‖K_II·φ‖`, reported in the result.

use crate::core::error::{Error, Result};
use crate::dynamics::fe_matrices::SparseMatrix;
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::matmul::sparse_dense_matmul;
use faer::sparse::{SparseColMat, Triplet};
use faer::{Accum, Mat, Par, Side};
use nalgebra::DMatrix;
use rand::{Rng, SeedableRng};

/// Settings of the reduction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReductionSettings {
    /// Fixed-interface normal modes kept (`m`; at most the number of interior DOFs).
    pub modes: usize,
    /// Largest relative eigen-residual accepted for every kept mode (default 1e-8: the rounding
    /// floor of `‖K·φ − λ·M·φ‖ / ‖K·φ‖` for a solid FE model is near 1e-9; the eigenvalue's
    /// error is of the order of the residual squared).
    pub tolerance: f64,
    /// Cap on the subspace iterations.
    pub max_iterations: usize,
}

impl Default for ReductionSettings {
    fn default() -> Self {
        Self {
            modes: 20,
            tolerance: 1e-8,
            max_iterations: 500,
        }
    }
}

/// A Craig–Bampton reduced model and how it was obtained.
#[derive(Debug, Clone)]
pub struct CraigBampton {
    /// Rows of the full model kept as boundary DOFs, in the order of the reduced coordinates.
    pub boundary: Vec<usize>,
    /// Reduced stiffness (units of the full model, N/m in SI), `(n_B + m)²`: the boundary DOFs
    /// first (in the order of `boundary`), then the modal coordinates.
    pub stiffness: DMatrix<f64>,
    /// Reduced mass (kg in SI), same coordinates.
    pub mass: DMatrix<f64>,
    /// Fixed-interface natural frequencies (Hz), ascending, one per modal coordinate.
    pub fixed_interface_frequencies_hz: Vec<f64>,
    /// Relative eigen-residual `‖K_II·φ − λ·M_II·φ‖ / ‖K_II·φ‖` of every kept mode.
    pub residuals: Vec<f64>,
    /// Subspace iterations run.
    pub iterations: usize,
}

/// Where a row of the full model goes.
#[derive(Clone, Copy)]
enum Part {
    Boundary(usize),
    Interior(usize),
}

/// Blocks of a full-storage symmetric matrix split into boundary and interior DOFs.
struct Blocks {
    ii: SparseColMat<usize, f64>,
    /// `A_IB`, dense (`n_I × n_B`).
    ib: Mat<f64>,
    bb: DMatrix<f64>,
}

fn split(a: &SparseMatrix, parts: &[Part], nb: usize, ni: usize, name: &str) -> Result<Blocks> {
    let mut ii = Vec::with_capacity(a.entries.len());
    let mut ib = Mat::<f64>::zeros(ni, nb);
    let mut bb = DMatrix::zeros(nb, nb);
    for &(r, c, v) in &a.entries {
        match (parts[r], parts[c]) {
            (Part::Interior(i), Part::Interior(j)) => ii.push(Triplet::new(i, j, v)),
            (Part::Interior(i), Part::Boundary(b)) => ib[(i, b)] += v,
            (Part::Boundary(b), Part::Boundary(d)) => bb[(b, d)] += v,
            (Part::Boundary(_), Part::Interior(_)) => {}
        }
    }
    let ii = SparseColMat::try_new_from_triplets(ni, ni, &ii)
        .map_err(|e| Error::Data(format!("{name}: sparse assembly failed: {e:?}")))?;
    Ok(Blocks { ii, ib, bb })
}

fn overflow() -> Error {
    Error::Data(
        "Craig–Bampton: the matrices overflow (non-finite values in the reduction): check the \
         units and magnitudes of K and M"
            .into(),
    )
}

/// `A·X` for sparse `A` and dense `X`.
fn sp_mul(a: &SparseColMat<usize, f64>, x: &Mat<f64>) -> Mat<f64> {
    let mut y = Mat::<f64>::zeros(a.nrows(), x.ncols());
    sparse_dense_matmul(
        y.as_mut(),
        Accum::Replace,
        a.as_ref(),
        x.as_ref(),
        1.0,
        Par::Seq,
    );
    y
}

/// `Aᵀ·B` of two dense matrices as a nalgebra matrix.
fn at_b(a: &Mat<f64>, b: &Mat<f64>) -> DMatrix<f64> {
    let p = a.as_ref().transpose() * b.as_ref();
    DMatrix::from_fn(p.nrows(), p.ncols(), |i, j| p[(i, j)])
}

fn symmetric_part(a: &DMatrix<f64>) -> DMatrix<f64> {
    (a + a.transpose()) * 0.5
}

/// Eigenvalues λ (ascending), mass-normalised shapes Φ (columns), relative eigen-residuals and
/// iterations of a fixed-interface eigen-solve.
type Modes = (Vec<f64>, Mat<f64>, Vec<f64>, usize);

/// Fixed-interface modes: the lowest `m` eigenpairs of `K·φ = λ·M·φ` by subspace iteration
/// with the factorisation `llt` of `K` (shift σ = 0). Returns `(λ, Φ mass-normalised,
/// residuals, iterations)`.
fn lowest_modes(
    k: &SparseColMat<usize, f64>,
    m: &SparseColMat<usize, f64>,
    llt: &faer::sparse::linalg::solvers::Llt<usize, f64>,
    settings: &ReductionSettings,
) -> Result<Modes> {
    let n = k.nrows();
    let want = settings.modes;
    let p = (2 * want).max(want + 8).min(n);
    if p == n {
        return all_modes_dense(k, m, want);
    }
    // Seeded start vectors: the same reduction on every run.
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(0x00c0_ffee);
    let x = Mat::<f64>::from_fn(n, p, |_, _| rng.random_range(-1.0..1.0));
    // Only M·X is needed, carried from one iteration to the next (X ← Y·Q: M·X ← (M·Y)·Q).
    let mut m_x = sp_mul(m, &x);
    let mut worst = f64::INFINITY;
    for it in 1..=settings.max_iterations {
        // Inverse (shift-invert) step Y = K⁻¹·M·X; then K·Y = M·X needs no product.
        let mut y = m_x.clone();
        llt.solve_in_place(y.as_mut());
        let mut ky = m_x;
        // Unit columns: Y's columns shrink like 1/λ, and the test of independence below must
        // see directions, not magnitudes.
        for j in 0..p {
            let norm = y.col(j).norm_l2();
            if norm > 0.0 {
                for i in 0..n {
                    y[(i, j)] /= norm;
                    ky[(i, j)] /= norm;
                }
            }
        }
        // Rayleigh–Ritz on span(Y): an M-orthonormal basis W of it (dropping directions the
        // iteration has made dependent), then the symmetric projected problem.
        let my = sp_mul(m, &y);
        let kh = symmetric_part(&at_b(&y, &ky));
        let mh = symmetric_part(&at_b(&y, &my));
        if !kh.iter().chain(mh.iter()).all(|v| v.is_finite()) {
            return Err(overflow());
        }
        let em = mh.symmetric_eigen();
        let dmax = em.eigenvalues.iter().fold(0.0f64, |a, &b| a.max(b));
        let keep: Vec<usize> = (0..em.eigenvalues.len())
            .filter(|&i| em.eigenvalues[i] > 1e-13 * dmax)
            .collect();
        if keep.len() < want {
            return Err(Error::Data(format!(
                "fixed-interface modes: the iteration subspace collapsed to {} independent vectors, \
                 fewer than the {want} modes asked",
                keep.len()
            )));
        }
        let w = DMatrix::from_fn(p, keep.len(), |i, j| {
            em.eigenvectors[(i, keep[j])] / em.eigenvalues[keep[j]].sqrt()
        });
        let kt = symmetric_part(&(w.transpose() * &kh * &w));
        let ek = kt.symmetric_eigen();
        let mut order: Vec<usize> = (0..keep.len()).collect();
        order.sort_by(|&a, &b| ek.eigenvalues[a].total_cmp(&ek.eigenvalues[b]));
        let q_n = &w
            * DMatrix::from_fn(keep.len(), keep.len(), |i, j| {
                ek.eigenvectors[(i, order[j])]
            });
        let lambda: Vec<f64> = order.iter().map(|&i| ek.eigenvalues[i]).collect();
        let q = Mat::<f64>::from_fn(p, keep.len(), |i, j| q_n[(i, j)]);
        let xn = &y * &q;
        let kx = &ky * &q;
        let mx = &my * &q;
        let residual = |kx: &Mat<f64>, j: usize| {
            let mut r2 = 0.0;
            let mut k2 = 0.0;
            for i in 0..n {
                let d = kx[(i, j)] - lambda[j] * mx[(i, j)];
                r2 += d * d;
                k2 += kx[(i, j)] * kx[(i, j)];
            }
            (r2 / k2).sqrt()
        };
        worst = (0..want).map(|j| residual(&kx, j)).fold(0.0f64, f64::max);
        if worst <= settings.tolerance {
            // Confirm with K·φ itself (the iteration's K·Y relies on the solve's accuracy).
            let phi = Mat::<f64>::from_fn(n, want, |i, j| xn[(i, j)]);
            let k_phi = sp_mul(k, &phi);
            let residuals: Vec<f64> = (0..want).map(|j| residual(&k_phi, j)).collect();
            worst = residuals.iter().fold(0.0f64, |a, &b| a.max(b));
            if worst <= settings.tolerance {
                if lambda[0] <= 0.0 {
                    return Err(Error::Data(
                        "fixed-interface modes: a non-positive eigenvalue (K_II is not positive \
                         definite)"
                            .into(),
                    ));
                }
                return Ok((lambda[..want].to_vec(), phi, residuals, it));
            }
        }
        if xn.ncols() == p {
            m_x = mx;
        } else {
            // Keep the subspace size: refill dropped directions with fresh random vectors.
            let x = Mat::<f64>::from_fn(n, p, |i, j| {
                if j < xn.ncols() {
                    xn[(i, j)]
                } else {
                    rng.random_range(-1.0..1.0)
                }
            });
            m_x = sp_mul(m, &x);
        }
    }
    Err(Error::NonConvergence {
        solver: format!("Craig–Bampton fixed-interface modes (subspace iteration, {p} vectors)"),
        iterations: settings.max_iterations,
        residual: worst,
        tolerance: settings.tolerance,
    })
}

/// The lowest `want` modes when the iteration subspace would be the whole interior: the dense
/// generalized eigenproblem ([`crate::dynamics::model::undamped_modes`]); a subspace iteration
/// over every direction loses the highest ones to rounding.
fn all_modes_dense(
    k: &SparseColMat<usize, f64>,
    m: &SparseColMat<usize, f64>,
    want: usize,
) -> Result<Modes> {
    let n = k.nrows();
    let dense = |a: &SparseColMat<usize, f64>| {
        let d = a.to_dense();
        DMatrix::from_fn(n, n, |i, j| d[(i, j)])
    };
    let (kd, md) = (dense(k), dense(m));
    if !kd.iter().chain(md.iter()).all(|v| v.is_finite()) {
        return Err(overflow());
    }
    let (lambda, shapes) = crate::dynamics::model::undamped_modes(&md, &kd)
        .map_err(|e| Error::Data(format!("fixed-interface modes (dense): {e}")))?;
    if lambda[0] <= 0.0 {
        return Err(Error::Data(
            "fixed-interface modes: a non-positive eigenvalue (K_II is not positive definite)"
                .into(),
        ));
    }
    let phi = Mat::<f64>::from_fn(n, want, |i, j| shapes[j][i]);
    let residuals = (0..want)
        .map(|j| {
            let kx = &kd * &shapes[j];
            (&kx - &md * &shapes[j] * lambda[j]).norm() / kx.norm()
        })
        .collect();
    Ok((lambda[..want].to_vec(), phi, residuals, 1))
}

/// Craig–Bampton reduction of the symmetric model `(K, M)` (full storage) keeping the rows
/// `boundary` and `settings.modes` fixed-interface normal modes.
///
/// Errors: a boundary row outside the model or given twice, no interior DOF, more modes than
/// interior DOFs, a `K_II` that is not positive definite (the boundary does not hold the
/// structure), or modes that do not converge.
pub fn reduce(
    stiffness: &SparseMatrix,
    mass: &SparseMatrix,
    boundary: &[usize],
    settings: &ReductionSettings,
) -> Result<CraigBampton> {
    let n = stiffness.nrows;
    if stiffness.ncols != n || mass.nrows != n || mass.ncols != n {
        return Err(Error::Data(format!(
            "Craig–Bampton: stiffness {}×{} and mass {}×{} must be square and of one size",
            stiffness.nrows, stiffness.ncols, mass.nrows, mass.ncols
        )));
    }
    if n > stiffness.entries.len() {
        // Refused before allocating per row: a positive definite K has every diagonal entry.
        return Err(Error::Data(format!(
            "Craig–Bampton: stiffness of {n} rows with {} entries: some rows are empty",
            stiffness.entries.len()
        )));
    }
    let mut parts: Vec<Option<Part>> = vec![None; n];
    for (b, &row) in boundary.iter().enumerate() {
        if row >= n {
            return Err(Error::param(
                "boundary",
                format!("row {row} outside the model's {n} DOFs"),
            ));
        }
        if parts[row].is_some() {
            return Err(Error::param("boundary", format!("row {row} given twice")));
        }
        parts[row] = Some(Part::Boundary(b));
    }
    let nb = boundary.len();
    let ni = n - nb;
    if ni == 0 {
        return Err(Error::param(
            "boundary",
            "every DOF is a boundary DOF: nothing to reduce",
        ));
    }
    if settings.modes > ni {
        return Err(Error::param(
            "modes",
            format!("{} modes asked, the interior has {ni} DOFs", settings.modes),
        ));
    }
    if settings.tolerance.is_nan() || settings.tolerance <= 0.0 || settings.max_iterations == 0 {
        return Err(Error::param(
            "tolerance",
            "tolerance must be > 0 and max_iterations ≥ 1",
        ));
    }
    let mut next = 0;
    let parts: Vec<Part> = parts
        .into_iter()
        .map(|p| {
            p.unwrap_or_else(|| {
                next += 1;
                Part::Interior(next - 1)
            })
        })
        .collect();
    let k = split(stiffness, &parts, nb, ni, "stiffness")?;
    let m = split(mass, &parts, nb, ni, "mass")?;
    let llt = k.ii.as_ref().sp_cholesky(Side::Lower).map_err(|e| {
        Error::Data(format!(
            "Craig–Bampton: the interior stiffness K_II is not positive definite ({e:?}): the \
             boundary DOFs must hold the structure (no rigid-body motion with them fixed)"
        ))
    })?;
    // Static constraint modes Ψ = −K_II⁻¹·K_IB.
    let mut psi = Mat::<f64>::from_fn(ni, nb, |i, j| -k.ib[(i, j)]);
    llt.solve_in_place(psi.as_mut());
    if !(0..nb).all(|j| psi.col(j).iter().all(|v| v.is_finite())) {
        return Err(overflow());
    }
    let (lambda, phi, residuals, iterations) = if settings.modes > 0 {
        lowest_modes(&k.ii, &m.ii, &llt, settings)?
    } else {
        (Vec::new(), Mat::<f64>::zeros(ni, 0), Vec::new(), 0)
    };
    let nm = lambda.len();
    // Reduced stiffness.
    let k_bb = symmetric_part(&(&k.bb + at_b(&k.ib, &psi)));
    let mut kr = DMatrix::zeros(nb + nm, nb + nm);
    kr.view_mut((0, 0), (nb, nb)).copy_from(&k_bb);
    for (j, &l) in lambda.iter().enumerate() {
        kr[(nb + j, nb + j)] = l;
    }
    // Reduced mass.
    let mii_psi = sp_mul(&m.ii, &psi);
    let m_ib_psi = at_b(&m.ib, &psi);
    let m_bb = symmetric_part(&(&m.bb + &m_ib_psi + m_ib_psi.transpose() + at_b(&psi, &mii_psi)));
    let m_bq = at_b(&m.ib, &phi) + at_b(&mii_psi, &phi);
    let m_qq = symmetric_part(&at_b(&phi, &sp_mul(&m.ii, &phi)));
    let mut mr = DMatrix::zeros(nb + nm, nb + nm);
    mr.view_mut((0, 0), (nb, nb)).copy_from(&m_bb);
    mr.view_mut((0, nb), (nb, nm)).copy_from(&m_bq);
    mr.view_mut((nb, 0), (nm, nb)).copy_from(&m_bq.transpose());
    mr.view_mut((nb, nb), (nm, nm)).copy_from(&m_qq);
    Ok(CraigBampton {
        boundary: boundary.to_vec(),
        stiffness: kr,
        mass: mr,
        fixed_interface_frequencies_hz: lambda
            .iter()
            .map(|l| l.sqrt() / (2.0 * std::f64::consts::PI))
            .collect(),
        residuals,
        iterations,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Fixed–free chain of `n` unit springs and masses.
    fn chain(n: usize) -> (SparseMatrix, SparseMatrix) {
        let mut k = Vec::new();
        let mut m = Vec::new();
        for i in 0..n {
            k.push((i, i, if i + 1 < n { 2.0 } else { 1.0 }));
            m.push((i, i, 1.0));
            if i + 1 < n {
                k.push((i, i + 1, -1.0));
                k.push((i + 1, i, -1.0));
            }
        }
        let s = |entries| SparseMatrix {
            nrows: n,
            ncols: n,
            entries,
        };
        (s(k), s(m))
    }

    #[test]
    fn fixed_interface_modes_of_a_chain_match_the_closed_form() {
        // Chain of 40 with the free end as boundary: the interior is the fixed–fixed chain of
        // 39 masses, λ_j = 4·sin²(jπ / (2·40)).
        let (k, m) = chain(40);
        let s = ReductionSettings {
            modes: 5,
            ..Default::default()
        };
        let r = reduce(&k, &m, &[39], &s).unwrap();
        for j in 0..5 {
            let exact = 4.0 * ((j + 1) as f64 * std::f64::consts::PI / 80.0).sin().powi(2);
            let f = exact.sqrt() / (2.0 * std::f64::consts::PI);
            let got = r.fixed_interface_frequencies_hz[j];
            assert!((got - f).abs() < 1e-10 * f, "mode {j}: {got} vs {f}");
            assert!(r.residuals[j] <= 1e-8);
        }
    }

    #[test]
    fn bad_boundaries_are_refused() {
        let (k, m) = chain(4);
        let s = ReductionSettings::default();
        assert!(reduce(&k, &m, &[4], &s).is_err());
        assert!(reduce(&k, &m, &[1, 1], &s).is_err());
        assert!(reduce(&k, &m, &[0, 1, 2, 3], &s).is_err());
        let e = reduce(&k, &m, &[3], &s).unwrap_err();
        assert!(e.to_string().contains("modes"), "{e}");
    }
}
