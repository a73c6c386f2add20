//! Receptance-based condensation of the linear structure onto the element displacements.
//!
//! Per harmonic order `k` the linear structure answers a force `F̂_k` with
//! `X_k = H(kω)·F̂_k`, `H(Ω) = (K − Ω²M + iΩC)⁻¹` (complex amplitudes `X = a − i·b` of
//! `a·cos + b·sin`). With the element forces acting through `P` (all element maps stacked,
//! `n_c × n`), the element displacements satisfy
//!
//! ```text
//! U_k = level·P·H(kω)·F̂_k − G_k·f̂_k(U),   G_k = P·H(kω)·Pᵀ   (n_c × n_c)
//! ```
//!
//! so that the harmonic-balance unknowns are the `n_c` contact displacements only, whatever the
//! size of the model (Petrov & Ewins, *J. Turbomach.* 125 (2003) 364; Sanliturk, Ewins &
//! Stanbridge, *J. Eng. Gas Turbines Power* 123 (2001) 919). For a modal model
//! `H(Ω) = Σ_r φ_r φ_rᵀ / (ω_r² − Ω² + 2iζ_r ω_r Ω)` (the modes given, no residual
//! flexibility); for a lumped model `H` comes from a complex LU of the `n × n` dynamic stiffness.
//! `∂H/∂Ω = −H·(−2ΩM + iC)·H` gives the frequency derivative the continuation needs.

use crate::dynamics::hbm::{Evaluation, HbmSystem};
use nalgebra::{Complex, DMatrix, DVector};

type C64 = Complex<f64>;

/// Per retained order `k`: `(k, G_k, ∂G_k/∂ω, H(kω))`.
type OrderBlock = (usize, DMatrix<C64>, DMatrix<C64>, DMatrix<C64>);

/// The condensed linear structure at one frequency, for every retained harmonic.
pub struct Receptance {
    omega: f64,
    blocks: Vec<OrderBlock>,
}

fn complex(a: &DMatrix<f64>) -> DMatrix<C64> {
    a.map(|v| C64::new(v, 0.0))
}

impl Receptance {
    /// Receptances of `system`'s structure at fundamental frequency `omega` (rad/s).
    pub fn new(system: &HbmSystem<'_>, omega: f64) -> Self {
        let s = system.structure;
        let n = s.n();
        let p = complex(&stacked(system));
        let pt = p.transpose();
        let blocks = system
            .harmonics
            .orders()
            .iter()
            .map(|&k| {
                let w = k as f64 * omega;
                let (h, dz) = if s.is_modal() {
                    let mut h = DMatrix::zeros(n, n);
                    let mut dz = DMatrix::zeros(n, n);
                    for r in 0..n {
                        h[(r, r)] = C64::new(1.0, 0.0)
                            / C64::new(s.stiffness[(r, r)] - w * w, w * s.damping[(r, r)]);
                        dz[(r, r)] = C64::new(-2.0 * w, s.damping[(r, r)]);
                    }
                    (h, dz)
                } else {
                    let z = DMatrix::from_fn(n, n, |r, c| {
                        C64::new(
                            s.stiffness[(r, c)] - w * w * s.mass[(r, c)],
                            w * s.damping[(r, c)],
                        )
                    });
                    let h = z
                        .lu()
                        .try_inverse()
                        .unwrap_or_else(|| DMatrix::from_element(n, n, C64::new(f64::NAN, 0.0)));
                    let dz = DMatrix::from_fn(n, n, |r, c| {
                        C64::new(-2.0 * w * s.mass[(r, c)], s.damping[(r, c)])
                    });
                    (h, dz)
                };
                // dH/dω = k·dH/dΩ = −k·H·(dZ/dΩ)·H.
                let dh = -(&h * &dz * &h) * C64::new(k as f64, 0.0);
                let g = &p * &h * &pt;
                let dg = &p * dh * &pt;
                (k, g, dg, h)
            })
            .collect();
        Self { omega, blocks }
    }

    /// Residual `U − level·U_lin + G·f̂(U)` and its derivatives.
    pub fn evaluate(
        &self,
        system: &HbmSystem<'_>,
        z: &DVector<f64>,
        level: f64,
        jacobian: bool,
        warm: Option<&[crate::dynamics::aft::WarmStart]>,
    ) -> Evaluation {
        let len = system.harmonics.len();
        let p = stacked(system);
        let nc = p.nrows();
        let u = DMatrix::from_row_slice(nc, len, z.as_slice());
        let forces = system.element_forces(&u, self.omega, warm, jacobian);
        let fe = system.stacked_forces(&forces);
        // ∂f̂/∂ω of rate-dependent elements (zero for the others).
        let fe_rate = system.stacked_force_rates(&forces);
        let fex = system.excitation_harmonics();
        let fexm = DMatrix::from_row_slice(system.structure.n(), len, fex.as_slice());
        let mut ulin = DMatrix::zeros(nc, len);
        let mut dulin = DMatrix::zeros(nc, len);
        let mut gf = DMatrix::zeros(nc, len);
        let mut dgf = DMatrix::zeros(nc, len);
        let mut col = 0;
        for (k, g, dg, h) in &self.blocks {
            let cols = if *k == 0 { 1 } else { 2 };
            let to_c = |m: &DMatrix<f64>| -> DVector<C64> {
                DVector::from_iterator(
                    m.nrows(),
                    (0..m.nrows()).map(|r| {
                        if cols == 1 {
                            C64::new(m[(r, col)], 0.0)
                        } else {
                            C64::new(m[(r, col)], -m[(r, col + 1)])
                        }
                    }),
                )
            };
            let put = |out: &mut DMatrix<f64>, v: &DVector<C64>| {
                for r in 0..v.len() {
                    out[(r, col)] = v[r].re;
                    if cols == 2 {
                        out[(r, col + 1)] = -v[r].im;
                    }
                }
            };
            let fk = to_c(&fexm);
            let pc = complex(&p);
            let hf = h * &fk;
            put(&mut ulin, &(&pc * &hf));
            let dh_f = {
                // dU_lin/dω = P·dH·F̂ with P·dH·Pᵀ = dG; compute P·dH·F̂ directly.
                let w = *k as f64 * self.omega;
                let s = system.structure;
                let n = s.n();
                let dz = DMatrix::from_fn(n, n, |r, c| {
                    C64::new(-2.0 * w * s.mass[(r, c)], s.damping[(r, c)])
                });
                -(h * (dz * &hf)) * C64::new(*k as f64, 0.0)
            };
            put(&mut dulin, &(&pc * dh_f));
            let fc = to_c(&fe);
            put(&mut gf, &(g * &fc));
            let mut dgfk = dg * &fc;
            if let Some(fr) = &fe_rate {
                dgfk += g * to_c(fr);
            }
            put(&mut dgf, &dgfk);
            col += cols;
        }
        let flat = |m: &DMatrix<f64>| DVector::from_row_slice(m.transpose().as_slice());
        let residual = z - flat(&ulin) * level + flat(&gf);
        let scale = (flat(&ulin) * level).norm() + flat(&gf).norm();
        let d_omega = -flat(&dulin) * level + flat(&dgf);
        let d_level = -flat(&ulin);
        let jac = if jacobian {
            self.jacobian(system, &forces, nc, len)
        } else {
            DMatrix::zeros(0, 0)
        };
        Evaluation {
            residual,
            jacobian: jac,
            d_omega,
            d_level,
            scale,
            periodicity_error: crate::dynamics::aft::worst_periodicity_error(
                forces.iter().map(|f| f.periodicity_error),
            ),
            non_periodic: forces.iter().filter(|f| !f.periodic).count(),
            element_states: crate::dynamics::hbm::element_states(&forces),
        }
    }

    /// `I + G·J_f` with `J_f` block-diagonal over the elements; `G` couples the cosine/sine pair
    /// of each order: `y_a = Gr·x_a + Gi·x_b`, `y_b = −Gi·x_a + Gr·x_b`.
    fn jacobian(
        &self,
        system: &HbmSystem<'_>,
        forces: &[crate::dynamics::aft::ElementHarmonics],
        nc: usize,
        len: usize,
    ) -> DMatrix<f64> {
        let nn = nc * len;
        let mut j = DMatrix::identity(nn, nn);
        // Real 2×2 (or 1×1) blocks of G per order: index of the first coefficient of each order.
        let mut order_of = vec![(0usize, 0usize); len];
        let mut col = 0;
        for (bi, (k, ..)) in self.blocks.iter().enumerate() {
            let cols = if *k == 0 { 1 } else { 2 };
            for t in 0..cols {
                order_of[col + t] = (bi, col);
            }
            col += cols;
        }
        // G real entry between (c, h) and (c', h') for h, h' of the same order.
        let g_real = |c: usize, h: usize, cp: usize, hp: usize| -> f64 {
            let (bi, start) = order_of[h];
            let g = self.blocks[bi].1[(c, cp)];
            if self.blocks[bi].0 == 0 {
                return g.re;
            }
            match (h - start, hp - start) {
                (0, 0) | (1, 1) => g.re,
                (0, 1) => g.im,
                _ => -g.im,
            }
        };
        let mut off = 0;
        for (e, fr) in system.structure.elements.iter().zip(forces) {
            let d = e.element.dofs();
            let dl = d * len;
            let je = &fr.jacobian;
            for c in 0..nc {
                for h in 0..len {
                    let (_, start) = order_of[h];
                    let width = if self.blocks[order_of[h].0].0 == 0 {
                        1
                    } else {
                        2
                    };
                    for cc in 0..dl {
                        let mut v = 0.0;
                        for cp in 0..d {
                            for hp in start..start + width {
                                v += g_real(c, h, off + cp, hp) * je[(cp * len + hp) * dl + cc];
                            }
                        }
                        let (c2, h2) = (cc / len, cc % len);
                        j[(c * len + h, (off + c2) * len + h2)] += v;
                    }
                }
            }
            off += d;
        }
        j
    }

    /// Harmonics of the structure's coordinates at a solution `z` (element displacements):
    /// `X_k = H(kω)·(level·F̂_k − Pᵀ·f̂_k)`.
    pub fn coordinates(
        &self,
        system: &HbmSystem<'_>,
        z: &DVector<f64>,
        level: f64,
    ) -> DVector<f64> {
        let len = system.harmonics.len();
        let p = stacked(system);
        let nc = p.nrows();
        let n = system.structure.n();
        let u = DMatrix::from_row_slice(nc, len, z.as_slice());
        let forces = system.element_forces(&u, self.omega, None, false);
        let fe = system.stacked_forces(&forces);
        let total = DMatrix::from_row_slice(n, len, system.excitation_harmonics().as_slice())
            * level
            - p.transpose() * fe;
        let mut x = DMatrix::zeros(n, len);
        let mut col = 0;
        for (k, _, _, h) in &self.blocks {
            let cols = if *k == 0 { 1 } else { 2 };
            let fk = DVector::from_iterator(
                n,
                (0..n).map(|r| {
                    if cols == 1 {
                        C64::new(total[(r, col)], 0.0)
                    } else {
                        C64::new(total[(r, col)], -total[(r, col + 1)])
                    }
                }),
            );
            let xk = h * fk;
            for r in 0..n {
                x[(r, col)] = xk[r].re;
                if cols == 2 {
                    x[(r, col + 1)] = -xk[r].im;
                }
            }
            col += cols;
        }
        DVector::from_row_slice(x.transpose().as_slice())
    }
}

fn stacked(system: &HbmSystem<'_>) -> DMatrix<f64> {
    let s = system.structure;
    let nc = s.contact_dofs();
    let mut p = DMatrix::zeros(nc, s.n());
    let mut row = 0;
    for e in &s.elements {
        p.rows_mut(row, e.element.dofs()).copy_from(&e.map);
        row += e.element.dofs();
    }
    p
}
