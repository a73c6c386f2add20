//! The iterations of the load-controlled normal contact solve: projected conjugate gradients on
//! the contact set, plain (Polonsky & Keer 1999) or preconditioned with the inverse of the
//! half-space compliance (after Vollebregt 2014). Both share one loop; Polonsky–Keer is the case
//! of the identity preconditioner.
//!
//! Units: pressures in Pa, gaps and displacements in m.
//!
//! # One iteration
//! With the contact set `Ic = {p > 0}`, the centred gap `g = K⊛p + h0 − δ` (`δ = mean_Ic(K⊛p + h0)`,
//! the Lagrange multiplier of the imposed load) and the projector `P` onto fields on `Ic` with zero
//! sum there (`Px = 1_Ic (x − mean_Ic x)`):
//!
//! 1. `z = P M⁻¹ P g`, the preconditioned residual: `M = I` (Polonsky–Keer) or
//!    `M⁻¹ = F⁻¹ (E*|q|/2) F`, the inverse of the periodic Boussinesq operator `2/(E*|q|)`
//!    ([`precond_spectrum`]), applied in single precision (everything else is double);
//! 2. `t = z + β t_old` on `Ic`, shifted so that `Σ t = 0` (the step keeps the load).
//!    Polonsky–Keer: Fletcher–Reeves `β = G/G_old`, `G = Σ_Ic g²`, reset after points entered.
//!    Preconditioned: Polak–Ribière+ `β = max(0, g·(z − z_old)/(g·z)_old)` (robust to the changes
//!    of the contact set; Nocedal & Wright, *Numerical Optimization*, 2006, §5.2), reset when the
//!    old direction would cancel most of the descent; the penetrating points (`p = 0`, `g < 0`)
//!    join the direction with `t = diag(M⁻¹)·g`, so that their entry is part of the line search;
//! 3. `r = K⊛t`, step `τ = Σ g·t / Σ r·t` (the exact line minimum of the elastic energy);
//! 4. `p ← max(p − τ t, 0)`; Polonsky–Keer lets penetrating points enter with `p = −τ g`;
//! 5. if no point left or entered, `g ← g − τ r` and re-centring (linearity), otherwise the
//!    displacement is recomputed, `K⊛p`, after rescaling `p` to the load.
//!
//! The displacement is also recomputed every [`REFRESH_INTERVAL`] directions against round-off
//! drift, and always before convergence is accepted.
//!
//! # Passes over the grid
//! The passes around the transforms are fused into them ([`FftPlan::convolve_fused`]), so that an
//! iteration reads and writes each field about once:
//! - the gap is stored uncentred, `g_s = g + c` with the scalar `c = mean_Ic g_s` known from the
//!   sums of the pass that wrote it, so no pass is needed to centre it;
//! - the step length comes from the energy `t·K⊛t` summed in Fourier space (Parseval), known
//!   before the inverse transform ends, so that steps 4–5 happen in the output pass of `K⊛t`:
//!   the displacement `r` is never stored;
//! - the residual, the masking and the direction update are the input passes of the
//!   transforms (preconditioner, or `K⊛t` for Polonsky–Keer), whose sums decide whether the
//!   transforms run at all (converged, or a recomputation is due).
//!
//! All sums are added in row order, so results do not depend on the number of threads.

use super::{NormalMethod, NormalSolver, REFRESH_INTERVAL};
use crate::core::error::{Error, Result};
use crate::core::fft::{FftPlan, FftReal, KernelSpectrum, SharedMut};
use ndarray::Array2;
use rayon::prelude::*;
use rustfft::num_complex::Complex64;

/// Raw pointer for disjoint per-row writes to the work arrays from parallel closures.
pub(super) type Ptr = SharedMut<f64>;

/// Row `i` of a standard-layout array.
pub(super) fn row(a: &Array2<f64>, i: usize) -> &[f64] {
    let ny = a.ncols();
    &a.as_slice().expect("standard layout")[i * ny..(i + 1) * ny]
}

/// Per-row sums over `0..nx` in parallel, added in row order.
pub(super) fn rows_sum<const K: usize>(
    nx: usize,
    f: impl Fn(usize) -> [f64; K] + Sync,
) -> [f64; K] {
    let parts: Vec<[f64; K]> = (0..nx).into_par_iter().map(&f).collect();
    let mut total = [0.0; K];
    for p in parts {
        for k in 0..K {
            total[k] += p[k];
        }
    }
    total
}

/// The preconditioner `M⁻¹ = E*|q|/2` on a plan (zero at `q = 0`): the exact inverse of the
/// periodic Boussinesq compliance `2/(E*|q|)` on its range. Returns the spectrum and the
/// diagonal of the circulant operator, `mean_q(E*|q|/2)` (Pa/m).
pub(super) fn precond_spectrum<T: FftReal>(
    plan: &FftPlan<T>,
    dx: f64,
    dy: f64,
    e_star: f64,
) -> (KernelSpectrum<T>, f64) {
    let spec = plan.spectrum_from_wavenumbers(dx, dy, |qx, qy| {
        Complex64::new(0.5 * e_star * qx.hypot(qy), 0.0)
    });
    // Diagonal: (1/N) Σ_q over the full (two-sided) spectrum; the stored half spectrum holds
    // y-frequencies 0..=nfy/2, the others are their mirror images.
    let (nfx, nfy) = plan.fft_shape();
    let (qx, qy) = plan.wavenumbers(dx, dy);
    let mut total = 0.0;
    for (m, &y) in qy.iter().enumerate() {
        let weight = if m == 0 || (nfy % 2 == 0 && m == nfy / 2) {
            1.0
        } else {
            2.0
        };
        total += weight * qx.iter().map(|&x| x.hypot(y)).sum::<f64>();
    }
    let diag = 0.5 * e_star * total / (nfx * nfy) as f64;
    (spec, diag)
}

/// Sums of the state `(p, g_s)` written by a step or a recomputation, over the new contact set.
#[derive(Debug, Clone, Copy, Default)]
struct StateSums {
    /// Σ p.
    p: f64,
    /// Contact points.
    n_c: f64,
    /// Σ_Ic g_s.
    g: f64,
    /// Σ_Ic g_s².
    g2: f64,
    /// Σ_Ic t (the direction of the step).
    t: f64,
    /// Σ_Ic g_s t.
    gt: f64,
    /// Points that left the contact set.
    clipped: f64,
    /// Points that entered it.
    entered: f64,
    /// Plastic points (`p = H`).
    n_pl: f64,
}

impl StateSums {
    const N: usize = 9;
    fn from(a: [f64; Self::N]) -> Self {
        Self {
            p: a[0],
            n_c: a[1],
            g: a[2],
            g2: a[3],
            t: a[4],
            gt: a[5],
            clipped: a[6],
            entered: a[7],
            n_pl: a[8],
        }
    }

    /// Accumulate one point of the new state: the sums over the free set `0 < p < H` (the
    /// contact set without hardness) and over the plastic set `p = H`.
    #[inline(always)]
    fn add(s: &mut [f64; Self::N], p: f64, g: f64, t: f64, h: f64) {
        s[0] += p;
        if p > 0.0 {
            if p < h {
                s[1] += 1.0;
                s[2] += g;
                s[3] += g * g;
                s[4] += t;
                s[5] += g * t;
            } else {
                s[8] += 1.0;
            }
        }
    }

    fn set_changed(&self) -> bool {
        self.clipped > 0.0 || self.entered > 0.0
    }
}

// Sums of the pass that reads the current state (the residual, the penetrating points and the
// plastic points whose gap opened).
const R_COMPL: usize = 0; // Σ_F p |g| + Σ_Pl p max(g, 0)
const R_PEN: usize = 1; // Σ_{p=0} max(−g, 0)
const R_REL: usize = 2; // Σ_Pl max(g, 0)
const R_N: usize = 3;

/// Residual terms of one point of the centred gap `g` (hardness `h`, infinite without).
#[inline(always)]
fn residual_terms(s: &mut [f64], p: f64, g: f64, h: f64) {
    if p > 0.0 {
        if p < h {
            s[R_COMPL] += p * g.abs();
        } else if g > 0.0 {
            // A plastic point whose gap opened: its pressure must drop below H.
            s[R_COMPL] += p * g;
            s[R_REL] += g;
        }
    } else if g < 0.0 {
        s[R_PEN] -= g;
    }
}

/// What the loop does with the current state.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Verdict {
    /// Converged on a freshly convolved displacement.
    Converged,
    /// Converged on an updated displacement, or recomputation due: recompute and check again.
    Refresh,
    /// Keep iterating with a new direction.
    Continue,
}

struct Judge {
    total_load: f64,
    p_mean: f64,
    h_scale: f64,
    tol: f64,
}

impl Judge {
    fn residual(&self, compl: f64, pen: f64) -> f64 {
        (compl + self.p_mean * pen) / (self.total_load * self.h_scale)
    }

    fn verdict(&self, residual: f64, exact: bool, refresh_due: bool) -> Verdict {
        if residual <= self.tol {
            if exact {
                Verdict::Converged
            } else {
                Verdict::Refresh
            }
        } else if refresh_due && !exact {
            Verdict::Refresh
        } else {
            Verdict::Continue
        }
    }
}

/// The step of the output pass of `K⊛t`: `τ = gt / energy` (0 when the direction vanished);
/// Polonsky–Keer lets penetrating points enter with `p = −entry·g` (`entry = τ`, or `1/K(0)`
/// when the direction vanished); the preconditioned method has them in `t`.
#[derive(Debug, Clone, Copy)]
struct Step {
    gt: f64,
    /// Offset of the stored gap: the centred gap is `g_s − c`.
    c: f64,
    /// Polonsky–Keer entry rule with this stiffness (Pa/m), or `None` (entry through `t`).
    pk_entry: Option<EntryRule>,
}

#[derive(Debug, Clone, Copy)]
enum EntryRule {
    /// `p = −τ g`.
    Step,
    /// The direction vanished: `τ = 0`, `p = −g / K(0)`.
    SelfCompliance(f64),
}

impl Step {
    fn tau(&self, energy: f64) -> f64 {
        match self.pk_entry {
            Some(EntryRule::SelfCompliance(_)) => 0.0,
            _ if energy > 0.0 && energy.is_finite() => self.gt / energy,
            _ => 0.0,
        }
    }
}

impl NormalSolver {
    /// Projected CG iterations from the current `self.p` (mean `p_mean`, not necessarily exact).
    /// Returns (iterations, residual, approach).
    pub(super) fn iterate(
        &mut self,
        p_mean: f64,
        method: NormalMethod,
    ) -> Result<(usize, f64, f64)> {
        let preconditioned = method == NormalMethod::Preconditioned;
        if preconditioned {
            self.ensure_preconditioner();
        }
        let n = self.nx * self.ny;
        let judge = Judge {
            total_load: p_mean * n as f64,
            p_mean,
            h_scale: self.height_scale,
            tol: self.options.tolerance,
        };
        let solver_name = if preconditioned {
            "normal contact (preconditioned projected CG)"
        } else {
            "normal contact (Polonsky–Keer)"
        };
        let non_convergence = |iterations, residual| Error::NonConvergence {
            solver: solver_name.into(),
            iterations,
            residual,
            tolerance: judge.tol,
        };
        self.counts = (0, 0);
        self.t.fill(0.0);
        let gamma = self.precond_diagonal;
        let mut approach = 0.0;
        let mut sum_p = self.p.sum();
        check_load(sum_p, 0)?;
        let mut state = if self.hardness.is_finite() {
            let h = self.hardness;
            let [n_f, n_pl] = rows_sum(self.nx, |i| {
                row(&self.p, i).iter().fold([0.0; 2], |[f, pl], &p| {
                    if p >= h {
                        [f, pl + 1.0]
                    } else if p > 0.0 {
                        [f + 1.0, pl]
                    } else {
                        [f, pl]
                    }
                })
            });
            self.restore_load(judge.total_load, sum_p, n_f, n_pl, approach)?
        } else {
            self.refresh(judge.total_load / sum_p, approach)?.0
        };
        let mut exact = true;
        let mut since_refresh = 0usize;
        let mut conjugate = false;
        let mut rho_old = 0.0;
        let mut iterations = 0usize;
        let mut residual = f64::INFINITY;
        loop {
            if state.set_changed() {
                // Polonsky–Keer restarts after points entered; the preconditioned method keeps
                // its direction (Polak–Ribière+ and the restart test decide).
                conjugate = state.entered == 0.0 || preconditioned;
                check_load(state.p, iterations)?;
                sum_p = state.p;
                state =
                    self.restore_load(judge.total_load, sum_p, state.n_c, state.n_pl, approach)?;
                exact = true;
                since_refresh = 0;
            }
            // n_c: the free set 0 < p < H (the contact set without hardness).
            let n_c = state.n_c;
            if n_c == 0.0 && state.n_pl == 0.0 {
                return Err(Error::Data(
                    "normal contact: the pressure vanished everywhere (no contact set)".into(),
                ));
            }
            sum_p = state.p;
            check_load(sum_p, iterations)?;
            // δ is the mean over the free set. With every contact point plastic (the load is a
            // whole number of points at H) the free set does not fix it: see
            // `degenerate_centre`.
            let c = if n_c > 0.0 {
                state.g / n_c
            } else {
                self.degenerate_centre()
            };
            approach += c;
            // Σ_F g² and Σ_F g·t_old of the centred gap g = g_s − c.
            let g2 = (state.g2 - n_c * c * c).max(0.0);
            let gt_old = state.gt - c * state.t;
            let t_mean = if n_c > 0.0 { state.t / n_c } else { 0.0 };
            let refresh_due = since_refresh >= REFRESH_INTERVAL;
            let at_cap = iterations >= self.options.max_iterations;
            let mut verdict = Verdict::Continue;
            let stepped = if preconditioned {
                // z = P M⁻¹ P g, with the residual of the current state in its input pass.
                let (r, z_sums) = self.precondition(c, |r| {
                    residual = judge.residual(r[R_COMPL], r[R_PEN]);
                    verdict = judge.verdict(residual, exact, refresh_due);
                    verdict == Verdict::Continue && !at_cap
                });
                z_sums.map(|[sum_z, sum_gz, sum_gz_old]| {
                    let z_mean = sum_z / n_c;
                    // With Σ_Ic g = 0: g·(z − z̄) = g·z, and likewise for z_old and t_old.
                    let (rho, rho_cross) = (sum_gz, sum_gz_old);
                    let mut beta = if conjugate && rho_old > 0.0 {
                        ((rho - rho_cross) / rho_old).max(0.0)
                    } else {
                        0.0
                    };
                    // Restart when the old direction would cancel most of the descent of the
                    // new one: g·t = ρ + β g·t_old on the contact set.
                    if rho + beta * gt_old < 0.2 * rho {
                        beta = 0.0;
                    }
                    rho_old = rho;
                    // Σ_E t = γ Σ_E g = γ(rel − pen) over the entering points E (penetrating,
                    // and plastic points whose gap opened): the free part is shifted to keep
                    // Σ t = 0.
                    let offset = if n_c > 0.0 {
                        z_mean + beta * t_mean - gamma * (r[R_PEN] - r[R_REL]) / n_c
                    } else {
                        0.0
                    };
                    self.step_preconditioned(c, beta, offset, gamma)
                })
            } else {
                let beta = if conjugate && rho_old > 0.0 {
                    g2 / rho_old
                } else {
                    0.0
                };
                let vanished = g2 == 0.0 && self.self_compliance > 0.0;
                let self_compliance = self.self_compliance;
                let stepped = self.step_polonsky_keer(c, beta, beta * t_mean, |r, gt| {
                    residual = judge.residual(r[R_COMPL], r[R_PEN]);
                    verdict = judge.verdict(residual, exact, refresh_due);
                    if verdict != Verdict::Continue || at_cap {
                        return None;
                    }
                    Some(Step {
                        gt,
                        c,
                        pk_entry: Some(if vanished && r[R_PEN] > 0.0 {
                            // The contact set carries no gap gradient (e.g. a single point)
                            // while other points penetrate: no conjugate step exists, so let
                            // them enter with the pressure that closes their own gap.
                            EntryRule::SelfCompliance(1.0 / self_compliance)
                        } else {
                            EntryRule::Step
                        }),
                    })
                });
                if stepped.is_some() {
                    rho_old = g2;
                }
                stepped
            };
            if verdict == Verdict::Continue && at_cap {
                return Err(non_convergence(iterations, residual));
            }
            let Some((energy, sums)) = stepped else {
                if verdict == Verdict::Converged {
                    return Ok((iterations, residual, approach));
                }
                state =
                    self.restore_load(judge.total_load, sum_p, state.n_c, state.n_pl, approach)?;
                exact = true;
                since_refresh = 0;
                continue;
            };
            if energy.is_nan() || energy < 0.0 {
                // K is positive definite on zero-sum fields: a negative curvature means the
                // data are broken (the step was not taken).
                return Err(non_convergence(iterations, residual));
            }
            if energy == 0.0 && !sums.set_changed() {
                // The direction vanished and no point enters: nothing can improve the state.
                return Err(non_convergence(iterations, residual));
            }
            // The stored gap is g − τ r with the old centring: the loop top re-centres it.
            state = sums;
            iterations += 1;
            since_refresh += 1;
            exact = false;
            conjugate = true;
        }
    }

    /// The centring `c` of the stored gap when every contact point is plastic (no free point
    /// fixes δ): the root of `φ(c) = Σ_{p=0, g_s<c} (g_s − c) + Σ_{p=H, g_s>c} (g_s − c)`,
    /// decreasing in `c`, so that the direction of the entering points (penetrating, and
    /// plastic points whose gap opened), `t = γ (g_s − c)`, has zero sum and exchanges load
    /// between them. When the largest plastic gap is below the smallest open one, every `c`
    /// between them is a root and the state is a solution (residual 0): the largest plastic gap
    /// is returned. Otherwise bisection on `[min open gap, max plastic gap]`. Rare: only when
    /// the load is a whole number of points at H.
    fn degenerate_centre(&self) -> f64 {
        let h = self.hardness;
        let extremes = |i: usize| {
            let mut e = [f64::INFINITY, f64::NEG_INFINITY];
            for (&p, &g) in row(&self.p, i).iter().zip(row(&self.g, i)) {
                if p >= h {
                    e[1] = e[1].max(g);
                } else if p <= 0.0 {
                    e[0] = e[0].min(g);
                }
            }
            e
        };
        let [min_open, max_plastic] = (0..self.nx).into_par_iter().map(extremes).reduce(
            || [f64::INFINITY, f64::NEG_INFINITY],
            |a, b| [a[0].min(b[0]), a[1].max(b[1])],
        );
        if max_plastic <= min_open {
            return max_plastic;
        }
        let phi = |c: f64| {
            let [v] = rows_sum(self.nx, |i| {
                let mut s = 0.0;
                for (&p, &g) in row(&self.p, i).iter().zip(row(&self.g, i)) {
                    if (p <= 0.0 && g < c) || (p >= h && g > c) {
                        s += g - c;
                    }
                }
                [s]
            });
            v
        };
        let (mut lo, mut hi) = (min_open, max_plastic);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            if phi(mid) > 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    }

    /// Build the preconditioner on first use.
    pub(super) fn ensure_preconditioner(&mut self) {
        if self.precond.is_none() {
            self.precond = Some(super::Preconditioner::new(
                self.nx,
                self.ny,
                self.dx,
                self.dy,
                self.e_star,
            ));
            self.precond_diagonal = self.precond.as_ref().map_or(1.0, |m| m.diagonal);
        }
        if self.z.dim() != (self.nx, self.ny) {
            self.z = Array2::zeros((self.nx, self.ny));
        }
    }

    /// The load restored and the displacement recomputed. Without hardness `p ← s p` with
    /// `s = L / Σp`. With hardness H the free points are scaled, `p ← s p` on `0 < p < H` with
    /// `s = (L − H·n_pl) / Σ_F p` (the plastic points carry `H` each); when that pushes a free
    /// point above H (or no free load is left) the load is restored exactly by
    /// [`NormalSolver::project_load`] instead. Returns the sums of the new state.
    fn restore_load(
        &mut self,
        total_load: f64,
        sum_p: f64,
        n_free: f64,
        n_plastic: f64,
        approach: f64,
    ) -> Result<StateSums> {
        let h = self.hardness;
        if !h.is_finite() {
            return Ok(self.refresh(total_load / sum_p, approach)?.0);
        }
        let free_load = sum_p - h * n_plastic;
        let free_target = total_load - h * n_plastic;
        if n_free > 0.0 && free_load > 0.0 && free_target > 0.0 {
            let (state, saturated) = self.refresh(free_target / free_load, approach)?;
            if saturated == 0.0 {
                return Ok(state);
            }
        }
        self.project_load(total_load);
        Ok(self.refresh(1.0, approach)?.0)
    }

    /// The load `Σp = L` restored exactly within `0 ≤ p ≤ H`, keeping the shape of the pressure:
    /// `p ← min(s p, H)` with the `s` that carries `L` (`Σ min(s p_i, H)` is increasing and
    /// piecewise linear in `s`: the points are sorted once), or, when the contact points at H
    /// cannot carry `L`, all of them at H and the rest on the non-contact points of smallest gap,
    /// H each (one partly). Needs `L < N·H` (checked by the caller of the solve).
    fn project_load(&mut self, total_load: f64) {
        let h = self.hardness;
        let p = self.p.as_slice_mut().expect("standard layout");
        let mut contact: Vec<f64> = p.iter().copied().filter(|&v| v > 0.0).collect();
        let capacity = h * contact.len() as f64;
        if capacity > total_load {
            contact.sort_unstable_by(|a, b| b.total_cmp(a));
            // With the k largest saturated: s_k = (L − kH) / Σ_{i ≥ k} p_(i), valid when
            // s_k p_(k) ≤ H.
            let mut rest: f64 = contact.iter().sum();
            let mut s = total_load / rest;
            for (k, &pk) in contact.iter().enumerate() {
                s = (total_load - h * k as f64) / rest;
                if s * pk <= h {
                    break;
                }
                rest -= pk;
            }
            for v in p.iter_mut().filter(|v| **v > 0.0) {
                *v = (s * *v).min(h);
            }
        } else {
            for v in p.iter_mut().filter(|v| **v > 0.0) {
                *v = h;
            }
            let g = self.g.as_slice().expect("standard layout");
            let mut order: Vec<usize> = (0..p.len()).filter(|&i| p[i] == 0.0).collect();
            order.sort_unstable_by(|&a, &b| g[a].total_cmp(&g[b]));
            let mut remaining = total_load - capacity;
            for i in order {
                if remaining <= 0.0 {
                    break;
                }
                p[i] = remaining.min(h);
                remaining -= p[i];
            }
        }
    }

    /// `p ← s p` on the points below the hardness (all points without hardness), clamped at H;
    /// `g_s = K⊛p + h0 − δ` with the current approach estimate `δ`. Returns the sums of the new
    /// state (its mean over the free set is the correction of `δ`) and the number of points the
    /// scaling pushed to H.
    fn refresh(&mut self, scale: f64, approach: f64) -> Result<(StateSums, f64)> {
        self.counts.0 += 1;
        let ny = self.ny;
        let h = self.hardness;
        let pp = Ptr::of(&mut self.p);
        let gp = Ptr::of(&mut self.g);
        let (h0, t) = (&self.separation, &self.t);
        let ([saturated], rest) = self.plan.convolve_fused::<1, { StateSums::N }, ()>(
            &self.kernel,
            &mut self.ws,
            |i, buf| {
                // SAFETY: row i is written by this call only.
                let p = unsafe { pp.row(i, ny) };
                let mut saturated = 0.0;
                for (b, v) in buf.iter_mut().zip(p.iter_mut()) {
                    if *v < h {
                        *v *= scale;
                        if *v > h {
                            *v = h;
                            saturated += 1.0;
                        }
                    }
                    *b = *v;
                }
                [saturated]
            },
            |_| Some(()),
            |_, _, i, res| {
                // SAFETY: the load phase is over; row i is touched by this call only.
                let (p, g) = unsafe { (pp.row(i, ny), gp.row(i, ny)) };
                let (h0, t) = (row(h0, i), row(t, i));
                let mut s = [0.0; StateSums::N];
                for k in 0..ny {
                    let v = res[k] + h0[k] - approach;
                    g[k] = v;
                    StateSums::add(&mut s, p[k], v, t[k], h);
                }
                s
            },
        );
        let (_, sums) = rest.expect("the recomputation always proceeds");
        Ok((StateSums::from(sums), saturated))
    }

    /// The preconditioner transform, `z = P M⁻¹ P g` (`g = g_s − c`), with the residual of the
    /// current state in its input pass; `go(residual sums)` decides whether the transforms run.
    /// Returns the residual sums and `[Σ_Ic z, Σ_Ic g z, Σ_Ic g z_old]`.
    fn precondition(
        &mut self,
        c: f64,
        go: impl FnOnce(&[f64; R_N]) -> bool,
    ) -> ([f64; R_N], Option<[f64; 3]>) {
        let ny = self.ny;
        let h = self.hardness;
        let zp = Ptr::of(&mut self.z);
        let (p, g) = (&self.p, &self.g);
        let m = self.precond.as_mut().expect("preconditioner built");
        let (load, rest) = m.plan.convolve_fused::<R_N, 3, ()>(
            &m.spectrum,
            &mut m.ws,
            |i, buf| {
                let (p, g) = (row(p, i), row(g, i));
                let mut s = [0.0; R_N];
                for k in 0..ny {
                    let gk = g[k] - c;
                    residual_terms(&mut s, p[k], gk, h);
                    buf[k] = if p[k] > 0.0 && p[k] < h {
                        gk as f32
                    } else {
                        0.0
                    };
                }
                s
            },
            |s| go(s).then_some(()),
            |_, _, i, res| {
                // SAFETY: row i of z is touched by this call only.
                let z = unsafe { zp.row(i, ny) };
                let (p, g) = (row(p, i), row(g, i));
                let mut s = [0.0; 3];
                for k in 0..ny {
                    if p[k] > 0.0 && p[k] < h {
                        let gk = g[k] - c;
                        let zk = f64::from(res[k]);
                        s[2] += gk * z[k];
                        z[k] = zk;
                        s[0] += zk;
                        s[1] += gk * zk;
                    } else {
                        z[k] = 0.0;
                    }
                }
                s
            },
        );
        if rest.is_some() {
            self.counts.1 += 1;
        }
        (load, rest.map(|(_, s)| s))
    }

    /// Preconditioned direction and step: `t = z + β t − offset` on the free set, `t = γ g` on
    /// the penetrating points and on the plastic points whose gap opened, 0 on the other plastic
    /// points; `K⊛t` with the update `p ← min(max(p − τ t, 0), H)`, `g_s ← g − τ K⊛t` in its
    /// output pass. Returns the energy `t·K⊛t` and the sums of the new state.
    fn step_preconditioned(
        &mut self,
        c: f64,
        beta: f64,
        offset: f64,
        gamma: f64,
    ) -> (f64, StateSums) {
        self.counts.0 += 1;
        let ny = self.ny;
        let h = self.hardness;
        let tp = Ptr::of(&mut self.t);
        let pp = Ptr::of(&mut self.p);
        let gp = Ptr::of(&mut self.g);
        let z = &self.z;
        let (_, rest) = self.plan.convolve_fused::<1, { StateSums::N }, Step>(
            &self.kernel,
            &mut self.ws,
            |i, buf| {
                // SAFETY: rows of t are written by one call; p and g are only read here.
                let (t, p, g) = unsafe { (tp.row(i, ny), pp.row(i, ny), gp.row(i, ny)) };
                let z = row(z, i);
                let mut s = [0.0; 1];
                for k in 0..ny {
                    let gk = g[k] - c;
                    let v = if p[k] > 0.0 {
                        if p[k] < h {
                            z[k] + beta * t[k] - offset
                        } else if gk > 0.0 {
                            gamma * gk
                        } else {
                            0.0
                        }
                    } else if gk < 0.0 {
                        gamma * gk
                    } else {
                        0.0
                    };
                    t[k] = v;
                    buf[k] = v;
                    s[0] += gk * v;
                }
                s
            },
            |s| {
                Some(Step {
                    gt: s[0],
                    c,
                    pk_entry: None,
                })
            },
            |step, energy, i, r| {
                // SAFETY: the load phase is over; row i is touched by this call only.
                let (t, p, g) = unsafe { (tp.row(i, ny), pp.row(i, ny), gp.row(i, ny)) };
                update_row(step, step.tau(energy), h, p, g, t, r)
            },
        );
        let (energy, sums) = rest.expect("the step always proceeds");
        (energy, StateSums::from(sums))
    }

    /// Polonsky–Keer direction and step: `t = g + β t − offset` on `Ic` and `K⊛t` with the
    /// update in its output pass; the residual of the current state is summed in the input pass
    /// and `decide(residual sums, Σ g·t)` returns the step, or `None` to stop before the
    /// transforms. Returns the energy `t·K⊛t` and the sums of the new state.
    fn step_polonsky_keer(
        &mut self,
        c: f64,
        beta: f64,
        offset: f64,
        decide: impl FnOnce(&[f64; 2], f64) -> Option<Step>,
    ) -> Option<(f64, StateSums)> {
        let ny = self.ny;
        let h = self.hardness;
        let tp = Ptr::of(&mut self.t);
        let pp = Ptr::of(&mut self.p);
        let gp = Ptr::of(&mut self.g);
        let (_, rest) = self
            .plan
            .convolve_fused::<{ R_N + 1 }, { StateSums::N }, Step>(
                &self.kernel,
                &mut self.ws,
                |i, buf| {
                    // SAFETY: rows of t are written by one call; p and g are only read here.
                    let (t, p, g) = unsafe { (tp.row(i, ny), pp.row(i, ny), gp.row(i, ny)) };
                    let mut s = [0.0; R_N + 1];
                    for k in 0..ny {
                        let gk = g[k] - c;
                        residual_terms(&mut s, p[k], gk, h);
                        let v = if p[k] > 0.0 {
                            gk + beta * t[k] - offset
                        } else {
                            0.0
                        };
                        t[k] = v;
                        buf[k] = v;
                        s[R_N] += gk * v;
                    }
                    s
                },
                |s| decide(&[s[R_COMPL], s[R_PEN]], s[R_N]),
                |step, energy, i, r| {
                    // SAFETY: the load phase is over; row i is touched by this call only.
                    let (t, p, g) = unsafe { (tp.row(i, ny), pp.row(i, ny), gp.row(i, ny)) };
                    update_row(step, step.tau(energy), h, p, g, t, r)
                },
            );
        if rest.is_some() {
            self.counts.0 += 1;
        }
        rest.map(|(energy, sums)| (energy, StateSums::from(sums)))
    }
}

/// One row of the step: `p ← min(max(p − τ t, 0), H)` (Polonsky–Keer: penetrating points enter
/// with `p = −entry·g`), `g_s ← g − τ r` with `g = g_s − c`; returns the sums of the new state.
/// Points that reach 0 or H count as clipped, points that leave 0 or H as entered.
fn update_row(
    step: &Step,
    tau: f64,
    h: f64,
    p: &mut [f64],
    g: &mut [f64],
    t: &[f64],
    r: &[f64],
) -> [f64; StateSums::N] {
    let mut s = [0.0; StateSums::N];
    let entry = match step.pk_entry {
        Some(EntryRule::Step) => Some(tau),
        Some(EntryRule::SelfCompliance(k)) => Some(k),
        None => None,
    };
    for k in 0..p.len() {
        let g_old = g[k] - step.c;
        let was = p[k] > 0.0;
        let q = p[k] - tau * t[k];
        let new = if was && q > 0.0 {
            q
        } else if let Some(e) = entry {
            if g_old < 0.0 {
                -e * g_old
            } else {
                0.0
            }
        } else if !was && q > 0.0 {
            q
        } else {
            0.0
        };
        let bounded = new.min(h);
        if (was && q <= 0.0) || new > h {
            s[6] += 1.0;
        }
        if (new > 0.0 && !(was && q > 0.0)) || (p[k] >= h && bounded < h) {
            s[7] += 1.0;
        }
        p[k] = bounded;
        let gk = g_old - tau * r[k];
        g[k] = gk;
        StateSums::add(&mut s, bounded, gk, t[k], h);
    }
    s
}

fn check_load(sum_p: f64, iteration: usize) -> Result<()> {
    if !(sum_p > 0.0 && sum_p.is_finite()) {
        return Err(Error::Data(format!(
            "normal contact: pressure became {sum_p} at iteration {iteration}"
        )));
    }
    Ok(())
}
