//! Normal contact stiffness `kn = dp̄/dδ` of a converged solution from the tangent problem on its
//! contact set.
//!
//! Units: pressures in Pa, displacements in m, kn in N/m³ (Pa/m).
//!
//! # Why the tangent problem
//! For frictionless contact of elastic bodies the incremental stiffness `dP/dδ` equals the
//! stiffness of a rigid flat punch whose footprint is the current contact area (Barber, *Proc.
//! R. Soc. Lond. A* 459 (2003) 53–66; Pharr, Oliver & Brotzen, *J. Mater. Res.* 7 (1992)
//! 613–617): the pressure vanishes at the contact edges, so the growth of the contact area does
//! not contribute at first order. On the grid, with the contact set `S` of the solution fixed, a
//! rigid-body approach `dδ` gives the pressure increment `dp` supported on `S` with
//!
//! `K⊛dp = dδ` on `S`,
//!
//! i.e. the minimiser of `½ dp·K⊛dp` under the load `Σ_S dp = N·dp̄`, whose Lagrange multiplier is
//! `dδ`. It is solved for `dp̄ = 1 Pa` by conjugate gradients projected onto `Σ_S dp = const` and
//! preconditioned by `E*|q|/2` (the same operators as the contact solve); then
//! `kn = dp̄/dδ = 1 Pa / dδ`. One linear solve replaces the two nonlinear solves of a central
//! difference, and gives the derivative of the discrete branch exactly (the central difference
//! converges to it as O(ε²), `tests/normal_contact.rs` compares both).
//!
//! `δ` is the rigid-body approach of the surfaces, so `kn·A` is the stiffness of the window
//! whatever its size: for a finite (zero-padded) window this is the physical contact stiffness
//! (Hertz: `kn·A = 2E*a`), whereas the slope of the mean gap would include the elastic sinking of
//! the unloaded surface inside the window. For a periodic patch `−dp̄/dḡ = dp̄/dδ` (the periodic
//! displacement has zero mean), so both definitions agree. A periodic patch in full contact
//! cannot approach further: kn is infinite.
//!
//! # Hardness-limited contact: unloading and loading stiffness
//! With a hardness H (see [`crate::contact::normal`]) two stiffnesses differ:
//!
//! - **unloading/reloading** ([`NormalSolver::contact_stiffness`]): on unloading every contact
//!   point, plastic ones included, responds elastically — the state is the elastic state of
//!   the residual surface `h_res` at the same load — so `dp̄/dδ` is the tangent problem above on
//!   the whole contact set `p > 0`: the stiffness of a rigid punch of the contact area (Barber's
//!   theorem again). This is the stiffness of the joint under the small oscillations about a
//!   preload that the dynamics see, and the one a contact element (and a calibration table)
//!   carries: a flat punch gives `2E*a` whatever the plastic ring at its edge, as unloading
//!   curves of indentation do (Pharr, Oliver & Brotzen 1992).
//! - **loading tangent** ([`NormalSolver::loading_stiffness`]): under more load the plastic
//!   points hold `p = H` (`dp = 0`) and penetrate further, so the tangent problem is solved on
//!   the free set `0 < p < H` only: smaller, and zero in the fully plastic limit.

use super::projected_cg::{row, rows_sum, Ptr};
use super::{NormalSolution, NormalSolver};
use crate::core::error::{Error, Result};
use crate::core::fft::Boundary;
use std::time::Instant;

/// Tolerance of the tangent solve on the rms gap residual over the contact set, relative to the
/// approach increment: kn, a Rayleigh-quotient-like quantity, is then exact to ~1e-12.
pub const STIFFNESS_TOLERANCE: f64 = 1e-8;

/// Iteration cap of the tangent solve.
const MAX_ITERATIONS: usize = 1000;

/// Normal contact stiffness of one solution (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ContactStiffness {
    /// kn = dp̄/dδ (N/m³); infinite for a periodic patch in full contact.
    pub kn_n_per_m3: f64,
    /// Conjugate-gradient iterations of the tangent solve.
    pub iterations: usize,
    /// Final rms gap residual over the contact set relative to the approach increment.
    pub residual: f64,
    /// Always true for a returned value (non-convergence is an error).
    pub converged: bool,
    /// Wall time (s).
    pub wall_time_s: f64,
}

impl NormalSolver {
    /// The normal contact stiffness `kn = dp̄/dδ` (N/m³) of `solution` (a converged solution of
    /// this solver's surface), from the tangent problem on its contact set `p > 0` (see
    /// [`crate::contact::normal::stiffness`]). Uses the solver's work arrays.
    ///
    /// For a hardness-limited solution this is the **unloading/reloading** stiffness: the
    /// elastic stiffness about the plastically deformed state, whose every contact point
    /// (plastic ones included) responds elastically to unloading. It is the stiffness a contact
    /// element carries; [`NormalSolver::loading_stiffness`] is the tangent of continued loading.
    pub fn contact_stiffness(&mut self, solution: &NormalSolution) -> Result<ContactStiffness> {
        let mask: Vec<bool> = solution.pressure.iter().map(|&p| p > 0.0).collect();
        self.stiffness_on_set(
            solution,
            mask,
            "no contact point: the contact stiffness is zero",
        )
    }

    /// The loading tangent `dp̄/dδ` (N/m³) of a hardness-limited `solution`: the tangent
    /// problem on its elastic (free) points `0 < p < H`, the plastic points holding `p = H`
    /// while they penetrate further. Equal to [`NormalSolver::contact_stiffness`] without
    /// plastic points; smaller with them. Zero when every contact point is plastic (the load
    /// then grows only by new points entering the contact, which a tangent on the current set
    /// does not see).
    pub fn loading_stiffness(&mut self, solution: &NormalSolution) -> Result<ContactStiffness> {
        let h = solution.hardness_pa.unwrap_or(f64::INFINITY);
        let mask: Vec<bool> = solution
            .pressure
            .iter()
            .map(|&p| p > 0.0 && p < h)
            .collect();
        if solution.contact_points > 0 && !mask.iter().any(|m| *m) {
            return Ok(ContactStiffness {
                kn_n_per_m3: 0.0,
                iterations: 0,
                residual: 0.0,
                converged: true,
                wall_time_s: 0.0,
            });
        }
        self.stiffness_on_set(
            solution,
            mask,
            "no contact point: the contact stiffness is zero",
        )
    }

    /// `dp̄/dδ` from the tangent problem on the points of `mask`.
    fn stiffness_on_set(
        &mut self,
        solution: &NormalSolution,
        mask: Vec<bool>,
        empty: &str,
    ) -> Result<ContactStiffness> {
        let start = Instant::now();
        self.check_shape("solution", solution.pressure.dim())?;
        self.ensure_preconditioner();
        let (nx, ny) = (self.nx, self.ny);
        let n = (nx * ny) as f64;
        let n_c = mask.iter().filter(|m| **m).count() as f64;
        if n_c == 0.0 {
            return Err(Error::param("solution", empty));
        }
        let done = |kn: f64, iterations, residual| ContactStiffness {
            kn_n_per_m3: kn,
            iterations,
            residual,
            converged: true,
            wall_time_s: start.elapsed().as_secs_f64(),
        };
        if self.boundary == Boundary::Periodic && n_c == n {
            return Ok(done(f64::INFINITY, 0, 0.0));
        }
        let mask = &mask[..];
        let at = |i: usize, k: usize| mask[i * ny + k];
        // x = uniform unit mean-pressure increment on S, res = K⊛x.
        let x0 = n / n_c;
        self.p
            .iter_mut()
            .zip(mask.iter())
            .for_each(|(x, m)| *x = if *m { x0 } else { 0.0 });
        self.t.fill(0.0);
        let mut approach = self.tangent_refresh(mask)?;
        let mut sum_r2 = self.centre_on_set(mask, approach);
        let mut rho_old = 1.0;
        let mut residual = f64::INFINITY;
        for it in 0..=MAX_ITERATIONS {
            if approach.is_nan() || approach <= 0.0 {
                return Err(Error::Data(format!(
                    "contact stiffness: non-positive approach increment {approach:e} m/Pa"
                )));
            }
            residual = (sum_r2 / n_c).sqrt() / approach;
            if residual <= STIFFNESS_TOLERANCE {
                return Ok(done(1.0 / approach, it, residual));
            }
            if it == MAX_ITERATIONS {
                break;
            }
            // z = P M⁻¹ P res.
            let g = &self.g;
            let zp = Ptr::of(&mut self.z);
            let m = self.precond.as_mut().expect("preconditioner built");
            let (_, z_sums) = m.plan.convolve_fused::<0, 2, ()>(
                &m.spectrum,
                &mut m.ws,
                |i, buf| {
                    for (b, &v) in buf.iter_mut().zip(row(g, i)) {
                        *b = v as f32;
                    }
                    []
                },
                |_| Some(()),
                |_, _, i, res| {
                    // SAFETY: row i of z is touched by this call only.
                    let z = unsafe { zp.row(i, ny) };
                    let g = row(g, i);
                    let mut s = [0.0; 2];
                    for k in 0..ny {
                        if at(i, k) {
                            let zk = f64::from(res[k]);
                            z[k] = zk;
                            s[0] += zk;
                            s[1] += g[k] * zk;
                        } else {
                            z[k] = 0.0;
                        }
                    }
                    s
                },
            );
            let (_, [sum_z, sum_gz]) = z_sums.expect("proceeds");
            let z_mean = sum_z / n_c;
            let rho = sum_gz; // Σ_S res = 0, so Σ res·(z − z̄) = Σ res·z.
            let beta = if it == 0 { 0.0 } else { rho / rho_old };
            rho_old = rho;
            // t = (z − z̄) + β t (Σ_S t = 0 kept), r = K⊛t.
            let tp = Ptr::of(&mut self.t);
            let rp = Ptr::of(&mut self.r);
            let (z, g) = (&self.z, &self.g);
            let (load, store) = self.plan.convolve_fused::<1, 2, ()>(
                &self.kernel,
                &mut self.ws,
                |i, buf| {
                    // SAFETY: row i of t is touched by this call only.
                    let t = unsafe { tp.row(i, ny) };
                    let (z, g) = (row(z, i), row(g, i));
                    let mut s = [0.0];
                    for k in 0..ny {
                        let v = if at(i, k) {
                            z[k] - z_mean + beta * t[k]
                        } else {
                            0.0
                        };
                        t[k] = v;
                        buf[k] = v;
                        s[0] += g[k] * v;
                    }
                    s
                },
                |_| Some(()),
                |_, _, i, res| {
                    // SAFETY: the load phase is over; row i of r is written by this call only.
                    let (t, r) = unsafe { (tp.row(i, ny), rp.row(i, ny)) };
                    let mut s = [0.0; 2];
                    for k in 0..ny {
                        r[k] = res[k];
                        if at(i, k) {
                            s[0] += res[k];
                            s[1] += res[k] * t[k];
                        }
                    }
                    s
                },
            );
            let (_, [sum_r, sum_rt]) = store.expect("proceeds");
            if sum_rt.is_nan() || sum_rt <= 0.0 {
                return Err(Error::NonConvergence {
                    solver: "normal contact stiffness (tangent CG)".into(),
                    iterations: it,
                    residual,
                    tolerance: STIFFNESS_TOLERANCE,
                });
            }
            let tau = load[0] / sum_rt;
            let r_mean = sum_r / n_c;
            // x ← x − τ t, res ← res − τ (r − r̄) on S, dδ ← dδ − τ r̄.
            let xp = Ptr::of(&mut self.p);
            let gp = Ptr::of(&mut self.g);
            let (t, r) = (&self.t, &self.r);
            [sum_r2] = rows_sum(nx, |i| {
                // SAFETY: rows are disjoint.
                let (x, g) = unsafe { (xp.row(i, ny), gp.row(i, ny)) };
                let (t, r) = (row(t, i), row(r, i));
                let mut s = [0.0];
                for k in 0..ny {
                    if at(i, k) {
                        x[k] -= tau * t[k];
                        g[k] -= tau * (r[k] - r_mean);
                        s[0] += g[k] * g[k];
                    }
                }
                s
            });
            approach -= tau * r_mean;
            // Against round-off drift: recompute K⊛x every few iterations.
            if (it + 1) % super::REFRESH_INTERVAL == 0 {
                approach = self.tangent_refresh(mask)?;
                sum_r2 = self.centre_on_set(mask, approach);
            }
        }
        Err(Error::NonConvergence {
            solver: "normal contact stiffness (tangent CG)".into(),
            iterations: MAX_ITERATIONS,
            residual,
            tolerance: STIFFNESS_TOLERANCE,
        })
    }

    /// `g ← g − δ` on the set, 0 elsewhere; returns `Σ_S g²`.
    fn centre_on_set(&mut self, mask: &[bool], approach: f64) -> f64 {
        let ny = self.ny;
        let gp = Ptr::of(&mut self.g);
        let [sum_r2] = rows_sum(self.nx, |i| {
            // SAFETY: row i is touched by this call only.
            let g = unsafe { gp.row(i, ny) };
            let mut s = [0.0];
            for (k, v) in g.iter_mut().enumerate() {
                if mask[i * ny + k] {
                    *v -= approach;
                    s[0] += *v * *v;
                } else {
                    *v = 0.0;
                }
            }
            s
        });
        sum_r2
    }

    /// `g = K⊛x` (x in `self.p`); returns `mean_S g`.
    fn tangent_refresh(&mut self, mask: &[bool]) -> Result<f64> {
        let ny = self.ny;
        let x = &self.p;
        let gp = Ptr::of(&mut self.g);
        let (_, sums) = self.plan.convolve_fused::<0, 2, ()>(
            &self.kernel,
            &mut self.ws,
            |i, buf| {
                buf.copy_from_slice(row(x, i));
                []
            },
            |_| Some(()),
            |_, _, i, res| {
                // SAFETY: row i of g is written by this call only.
                let g = unsafe { gp.row(i, ny) };
                let mut s = [0.0; 2];
                for k in 0..ny {
                    g[k] = res[k];
                    if mask[i * ny + k] {
                        s[0] += res[k];
                        s[1] += 1.0;
                    }
                }
                s
            },
        );
        let (_, [sum, count]) = sums.expect("proceeds");
        Ok(sum / count)
    }
}
