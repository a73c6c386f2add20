//! The iterations of the load-controlled normal contact solve: projected conjugate gradients on
//! the contact set, plain (Polonsky & Keer 1999) or preconditioned with the inverse of the
//! half-space compliance (Vollebregt 2014). Both share one loop; Polonsky–Keer is the special case
//! of the identity preconditioner.
//!
//! Units: pressures in Pa, gaps and displacements in m.
//!
//! # One iteration
//! With the contact set `Ic = {p > 0}`, the centred gap `g = K⊛p + h0 − δ` (`δ = mean_Ic(K⊛p + h0)`,
//! the Lagrange multiplier of the imposed load) and the projector `P` onto fields on `Ic` with zero
//! sum there (`Px = 1_Ic (x − mean_Ic x)`):
//!
//! 1. `z = P M⁻¹ P g` — the preconditioned residual; `M = I` (Polonsky–Keer) or
//!    `M⁻¹ = F⁻¹ (E*|q|/2) F`, the inverse of the periodic Boussinesq operator `2/(E*|q|)`
//!    ([`precond_spectrum`]);
//! 2. `t = z + β t_old` on `Ic`, `β = (g·z)/(g·z)_old`, reset to `β = 0` after points entered;
//! 3. `r = K⊛t`, step `τ = Σ_Ic g·t / Σ_Ic (r − r̄) t` (exact line minimum of the energy);
//! 4. `p ← max(p − τ t, 0)`; non-contact points that penetrate (`p = 0`, `g < 0`) enter with
//!    `p = −c g`, `c = τ·diag(M⁻¹)` (Polonsky–Keer: `c = τ`);
//! 5. if no point left or entered, `g ← g − τ (r − r̄)` exactly (linearity; `δ ← δ − τ r̄`), otherwise
//!    the displacement is recomputed, `K⊛p`, after rescaling `p` to the load.
//!
//! The displacement is also recomputed every [`REFRESH_INTERVAL`] directions against round-off
//! drift, and always before convergence is accepted.
//!
//! # Passes over the grid
//! The passes around the transforms are fused into them ([`FftPlan::convolve_fused`]): the
//! update of step 4–5 and the masking of `g` are the load of the preconditioner transform (whose
//! output pass masks `z` and sums `Σz`, `Σg·z`); the direction update of step 2 is the load of the
//! `K⊛t` transform (whose output pass sums `Σr`, `Σr·t`). Polonsky–Keer, which has no
//! preconditioner transform, makes the update its own pass. All sums are added in row order, so
//! results do not depend on the number of threads.

use super::{NormalMethod, NormalSolver, REFRESH_INTERVAL};
use crate::error::{Error, Result};
use crate::halfspace::convolution::{FftPlan, KernelSpectrum};
use ndarray::Array2;
use rayon::prelude::*;
use rustfft::num_complex::Complex64;

/// How the pass after a direction step finds the new gap.
#[derive(Debug, Clone, Copy)]
enum Update {
    /// The gap was just recomputed by convolution (`g = K⊛p + h0`): centre it by `δ`.
    Centre { approach: f64 },
    /// Step `τ` along the direction: `p ← p − τ t` (projected, penetrating points enter with
    /// `p = −c g`), `g ← g − τ (r − r̄)`.
    Step { tau: f64, r_mean: f64, entry: f64 },
}

// Sums of the update pass.
const SUM_P: usize = 0;
const SUM_G2: usize = 1; // Σ_Ic g²
const SUM_COMPL: usize = 2; // Σ_Ic p |g|
const SUM_PEN: usize = 3; // Σ_{p=0} max(−g, 0)
const SUM_NC: usize = 4; // contact points
const SUM_G: usize = 5; // Σ_Ic g
const SUM_CLIPPED: usize = 6;
const SUM_ENTERED: usize = 7;
const SUM_T: usize = 8; // Σ_Ic t_old (to project the old direction onto zero load change)
const UPDATE_SUMS: usize = 9;

/// Raw mutable pointer for disjoint per-row writes from parallel closures.
#[derive(Clone, Copy)]
pub(super) struct Ptr(*mut f64);
unsafe impl Send for Ptr {}
unsafe impl Sync for Ptr {}
impl Ptr {
    pub(super) fn of(a: &mut Array2<f64>) -> Self {
        Ptr(a
            .as_slice_mut()
            .expect("work arrays are in standard layout")
            .as_mut_ptr())
    }
    /// Row `i` (length `ny`). Safety: each row is accessed by one closure call at a time and
    /// not read elsewhere during that call.
    #[allow(clippy::mut_from_ref)]
    pub(super) unsafe fn row(&self, i: usize, ny: usize) -> &mut [f64] {
        std::slice::from_raw_parts_mut(self.0.add(i * ny), ny)
    }
}

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
pub(super) fn precond_spectrum(
    plan: &FftPlan,
    dx: f64,
    dy: f64,
    e_star: f64,
) -> (KernelSpectrum, f64) {
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

/// One row of the update pass (see [`Update`]): new `p` and `g`, and the sums of the new state.
fn update_row(
    update: Update,
    p: &mut [f64],
    g: &mut [f64],
    t: &[f64],
    r: &[f64],
) -> [f64; UPDATE_SUMS] {
    let mut s = [0.0; UPDATE_SUMS];
    match update {
        Update::Centre { approach } => {
            for k in 0..p.len() {
                g[k] -= approach;
                accumulate(&mut s, p[k], g[k], t[k]);
            }
        }
        Update::Step { tau, r_mean, entry } => {
            for k in 0..p.len() {
                let g_old = g[k];
                let mut pk = p[k];
                if pk > 0.0 {
                    pk -= tau * t[k];
                    if pk <= 0.0 {
                        pk = 0.0;
                        s[SUM_CLIPPED] += 1.0;
                    }
                }
                if pk == 0.0 && g_old < 0.0 {
                    pk = -entry * g_old;
                    s[SUM_ENTERED] += 1.0;
                }
                p[k] = pk;
                let gk = g_old - tau * (r[k] - r_mean);
                g[k] = gk;
                accumulate(&mut s, pk, gk, t[k]);
            }
        }
    }
    s
}

#[inline(always)]
fn accumulate(s: &mut [f64; UPDATE_SUMS], p: f64, g: f64, t: f64) {
    s[SUM_P] += p;
    if p > 0.0 {
        s[SUM_T] += t;
        s[SUM_G2] += g * g;
        s[SUM_COMPL] += p * g.abs();
        s[SUM_NC] += 1.0;
        s[SUM_G] += g;
    } else if g < 0.0 {
        s[SUM_PEN] -= g;
    }
}

/// What the loop learns from the sums of one update pass.
enum Verdict {
    /// Points left or entered the contact set: recompute the displacement.
    SetChanged { entered: bool },
    /// Converged on a freshly convolved displacement.
    Converged,
    /// Converged on an updated displacement, or refresh due: recompute and check again.
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
    fn residual(&self, s: &[f64; UPDATE_SUMS]) -> f64 {
        (s[SUM_COMPL] + self.p_mean * s[SUM_PEN]) / (self.total_load * self.h_scale)
    }

    fn verdict(&self, s: &[f64; UPDATE_SUMS], exact: bool, refresh_due: bool) -> Verdict {
        if s[SUM_CLIPPED] > 0.0 || s[SUM_ENTERED] > 0.0 {
            return Verdict::SetChanged {
                entered: s[SUM_ENTERED] > 0.0,
            };
        }
        if self.residual(s) <= self.tol {
            return if exact {
                Verdict::Converged
            } else {
                Verdict::Refresh
            };
        }
        if refresh_due && !exact {
            return Verdict::Refresh;
        }
        Verdict::Continue
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
        let (nx, ny) = (self.nx, self.ny);
        let n = nx * ny;
        let judge = Judge {
            total_load: p_mean * n as f64,
            p_mean,
            h_scale: self.height_scale,
            tol: self.options.tolerance,
        };
        let solver_name = match method {
            NormalMethod::Preconditioned => "normal contact (preconditioned projected CG)",
            _ => "normal contact (Polonsky–Keer)",
        };
        self.counts = (0, 0);
        let mut sum_p = self.p.sum();
        let mut update: Option<Update> = None; // None: recompute the displacement first
        let mut approach = 0.0;
        let mut since_refresh = 0usize;
        let mut conjugate = false;
        let mut rho_old = 1.0;
        let mut z_mean_old = 0.0;
        let mut iterations = 0usize;
        self.t.fill(0.0);
        loop {
            let exact = update.is_none();
            let step = match update {
                Some(u) => u,
                None => {
                    approach = self.refresh(judge.total_load / sum_p)?;
                    since_refresh = 0;
                    Update::Centre { approach }
                }
            };
            let refresh_due = since_refresh >= REFRESH_INTERVAL;
            // Update pass (fused into the preconditioner transform when there is one).
            let (s, precond) = if preconditioned {
                self.update_and_precondition(step, |s| {
                    matches!(judge.verdict(s, exact, refresh_due), Verdict::Continue)
                })
            } else {
                (self.update_pass(step), None)
            };
            if let Update::Step { tau, r_mean, .. } = step {
                approach -= tau * r_mean;
            }
            let last_residual = judge.residual(&s);

            match judge.verdict(&s, exact, refresh_due) {
                Verdict::SetChanged { entered } => {
                    // Polonsky–Keer restarts after points entered; the preconditioned method
                    // keeps its direction (Polak–Ribière+ restarts by itself when needed).
                    conjugate = !entered || preconditioned;
                    sum_p = s[SUM_P];
                    update = None;
                    check_load(sum_p, iterations)?;
                    continue;
                }
                Verdict::Converged => return Ok((iterations, last_residual, approach)),
                Verdict::Refresh => {
                    sum_p = s[SUM_P];
                    update = None;
                    continue;
                }
                Verdict::Continue => {}
            }
            let n_c = s[SUM_NC];
            if n_c == 0.0 {
                return Err(Error::Data(
                    "normal contact: the pressure vanished everywhere (no contact set)".into(),
                ));
            }
            sum_p = s[SUM_P];
            check_load(sum_p, iterations)?;
            if iterations >= self.options.max_iterations {
                return Err(Error::NonConvergence {
                    solver: solver_name.into(),
                    iterations,
                    residual: last_residual,
                    tolerance: judge.tol,
                });
            }
            // Preconditioned residual and its product with the gap.
            let (z_mean, rho, rho_cross) = match precond {
                Some([sum_z, sum_gz, sum_gz_old]) => {
                    let z_mean = sum_z / n_c;
                    (
                        z_mean,
                        sum_gz - z_mean * s[SUM_G],
                        sum_gz_old - z_mean_old * s[SUM_G],
                    )
                }
                None => (0.0, s[SUM_G2], 0.0),
            };
            z_mean_old = z_mean;
            let entry_scale = if preconditioned {
                self.precond_diagonal
            } else {
                1.0
            };
            iterations += 1;
            since_refresh += 1;
            if !preconditioned && rho == 0.0 && s[SUM_PEN] > 0.0 && self.self_compliance > 0.0 {
                // The contact set carries no gap gradient (e.g. a single point) while other
                // points penetrate: no conjugate step exists, so let the penetrating points
                // enter with the pressure that would close their own gap, p = −g / K(0).
                self.t.fill(0.0);
                update = Some(Update::Step {
                    tau: 0.0,
                    r_mean: 0.0,
                    entry: 1.0 / self.self_compliance,
                });
                conjugate = false;
                continue;
            }
            // Fletcher–Reeves (Polonsky–Keer) or Polak–Ribière+ (preconditioned: robust to the
            // changes of the contact set, whose gradients are not conjugate; Nocedal & Wright,
            // Numerical Optimization, 2006, §5.2).
            let beta = if !conjugate || rho_old == 0.0 {
                0.0
            } else if preconditioned {
                ((rho - rho_cross) / rho_old).max(0.0)
            } else {
                rho / rho_old
            };
            rho_old = rho;
            // Preconditioned: penetrating points join the direction with t = diag(M⁻¹)·g, and
            // the contact part is shifted so that the step keeps the load.
            let entering = if preconditioned { entry_scale } else { 0.0 };
            // Σ_E t = entering·Σ_E g = −entering·SUM_PEN.
            let offset = z_mean + beta * s[SUM_T] / n_c - entering * s[SUM_PEN] / n_c;
            let [sum_gt, sum_t, sum_r, sum_rt] =
                self.direction(preconditioned, beta, offset, entering);
            let r_mean = sum_r / n_c;
            let denom = sum_rt - r_mean * sum_t;
            if denom.is_nan() || denom <= 0.0 {
                // K is positive definite on zero-mean fields: a non-positive curvature means
                // the direction vanished (converged to round-off) or the data are broken.
                return Err(Error::NonConvergence {
                    solver: solver_name.into(),
                    iterations,
                    residual: last_residual,
                    tolerance: judge.tol,
                });
            }
            let tau = sum_gt / denom;
            conjugate = true;
            update = Some(Update::Step {
                tau,
                r_mean,
                entry: tau * entry_scale,
            });
        }
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

    /// `p ← s p` (exact load), `g ← K⊛p + h0`; returns the approach `δ = mean_Ic g`.
    fn refresh(&mut self, scale: f64) -> Result<f64> {
        self.counts.0 += 1;
        let ny = self.ny;
        let pp = Ptr::of(&mut self.p);
        let h0 = &self.separation;
        let p_ro = pp;
        let (_, sums) = self.plan.convolve_fused::<0, 2>(
            &self.kernel,
            &mut self.ws,
            &mut self.g,
            |i, buf| {
                // SAFETY: row i is written by this call only.
                let p = unsafe { pp.row(i, ny) };
                for (b, v) in buf.iter_mut().zip(p.iter_mut()) {
                    *v *= scale;
                    *b = *v;
                }
                []
            },
            |_| true,
            |i, res, g| {
                // SAFETY: the load phase is over; rows are only read here.
                let p = unsafe { p_ro.row(i, ny) };
                let h = row(h0, i);
                let mut s = [0.0; 2];
                for k in 0..ny {
                    let v = res[k] + h[k];
                    g[k] = v;
                    if p[k] > 0.0 {
                        s[0] += v;
                        s[1] += 1.0;
                    }
                }
                s
            },
        );
        let [sum_g, n_c] = sums.expect("the refresh always proceeds");
        if n_c == 0.0 {
            return Err(Error::Data(
                "normal contact: the pressure vanished everywhere (no contact set)".into(),
            ));
        }
        Ok(sum_g / n_c)
    }

    /// The update pass on its own (Polonsky–Keer).
    fn update_pass(&mut self, update: Update) -> [f64; UPDATE_SUMS] {
        let ny = self.ny;
        let pp = Ptr::of(&mut self.p);
        let gp = Ptr::of(&mut self.g);
        let (t, r) = (&self.t, &self.r);
        rows_sum(self.nx, |i| {
            // SAFETY: row i is touched by this call only.
            let (p, g) = unsafe { (pp.row(i, ny), gp.row(i, ny)) };
            update_row(update, p, g, row(t, i), row(r, i))
        })
    }

    /// The update pass as the load of the preconditioner transform: `z = P M⁻¹ P g` is computed
    /// only when `go(sums)` says the iteration continues. Returns the update sums and
    /// `[Σ_Ic z, Σ_Ic g z]` (before centring `z`).
    fn update_and_precondition(
        &mut self,
        update: Update,
        go: impl FnOnce(&[f64; UPDATE_SUMS]) -> bool,
    ) -> ([f64; UPDATE_SUMS], Option<[f64; 3]>) {
        let ny = self.ny;
        let pp = Ptr::of(&mut self.p);
        let gp = Ptr::of(&mut self.g);
        let (t, r) = (&self.t, &self.r);
        let m = self.precond.as_mut().expect("preconditioner built");
        let result = m.plan.convolve_fused(
            &m.spectrum,
            &mut m.ws,
            &mut self.z,
            |i, buf| {
                // SAFETY: row i is touched by this call only.
                let (p, g) = unsafe { (pp.row(i, ny), gp.row(i, ny)) };
                let s = update_row(update, p, g, row(t, i), row(r, i));
                for k in 0..ny {
                    buf[k] = if p[k] > 0.0 { g[k] } else { 0.0 };
                }
                s
            },
            go,
            |i, res, z| {
                // SAFETY: the load phase is over; rows are only read here.
                let (p, g) = unsafe { (pp.row(i, ny), gp.row(i, ny)) };
                let mut s = [0.0; 3];
                for k in 0..ny {
                    if p[k] > 0.0 {
                        s[2] += g[k] * z[k];
                        z[k] = res[k];
                        s[0] += res[k];
                        s[1] += g[k] * res[k];
                    } else {
                        z[k] = 0.0;
                    }
                }
                s
            },
        );
        if result.1.is_some() {
            self.counts.1 += 1;
        }
        result
    }

    /// The new direction and its displacement `r = K⊛t`:
    /// on `Ic`, `t ← z + β t − offset` (Polonsky–Keer: `z = g`), with `offset` making
    /// `Σ t = 0` (the step keeps the load); on the penetrating points (`p = 0`, `g < 0`),
    /// `t = entering·g` (0 for Polonsky–Keer, whose entering points are not part of the step).
    /// Returns `[Σ g t, Σ t, Σ_Ic r, Σ r t]`.
    fn direction(
        &mut self,
        preconditioned: bool,
        beta: f64,
        offset: f64,
        entering: f64,
    ) -> [f64; 4] {
        self.counts.0 += 1;
        let ny = self.ny;
        let tp = Ptr::of(&mut self.t);
        let (p, g) = (&self.p, &self.g);
        let src = if preconditioned { &self.z } else { &self.g };
        let (load, store) = self.plan.convolve_fused::<2, 2>(
            &self.kernel,
            &mut self.ws,
            &mut self.r,
            |i, buf| {
                // SAFETY: row i of t is touched by this call only.
                let t = unsafe { tp.row(i, ny) };
                let (p, g, z) = (row(p, i), row(g, i), row(src, i));
                let mut s = [0.0; 2];
                for k in 0..ny {
                    let v = if p[k] > 0.0 {
                        z[k] + beta * t[k] - offset
                    } else if g[k] < 0.0 {
                        entering * g[k]
                    } else {
                        0.0
                    };
                    t[k] = v;
                    buf[k] = v;
                    s[0] += g[k] * v;
                    s[1] += v;
                }
                s
            },
            |_| true,
            |i, res, r| {
                // SAFETY: the load phase is over; rows are only read here.
                let t = unsafe { tp.row(i, ny) };
                let p = row(p, i);
                let mut s = [0.0; 2];
                for k in 0..ny {
                    r[k] = res[k];
                    s[1] += res[k] * t[k];
                    if p[k] > 0.0 {
                        s[0] += res[k];
                    }
                }
                s
            },
        );
        let store = store.expect("the direction transform always proceeds");
        [load[0], load[1], store[0], store[1]]
    }
}

fn check_load(sum_p: f64, iteration: usize) -> Result<()> {
    if !(sum_p > 0.0 && sum_p.is_finite()) {
        return Err(Error::Data(format!(
            "normal contact: pressure became {sum_p} at iteration {iteration}"
        )));
    }
    Ok(())
}
