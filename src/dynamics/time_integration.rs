//! Reference time integration to the periodic steady state (validation of the harmonic balance,
//! and available to users for any structure of [`crate::dynamics::model`]).
//!
//! Newmark's average-acceleration scheme (trapezoidal rule, β = ¼, γ = ½: unconditionally
//! stable, second order, no numerical damping; Newmark 1959, *J. Eng. Mech. Div.* 85:67) on
//! `M·q̈ + C·q̇ + K·q + Σ_e P_eᵀ·f_e(P_e·q) = level·F·cos(hωt)`. The elements are advanced with
//! the same time-discrete update as in the AFT (one increment per time step, from the state of
//! the previous step); each step is solved by Newton's method with the elements' tangents and a
//! backtracking line search (piecewise-linear stick/slip laws). A rate-dependent element
//! ([`crate::element::HystereticElement::rate_dependent`]) reads the step `Δt` and the
//! scheme's velocities at both ends of the step, `P·q̇_n` and `P·q̇_{n+1}` with
//! `q̇_{n+1} = q̇_n + (q̈_n + q̈_{n+1})·Δt/2` (its tangent gains `∂f/∂v1·2/Δt`, the derivative
//! of that velocity with respect to `q_{n+1}`), as the AFT gives it the harmonics' velocities.
//!
//! The run starts from given initial conditions (e.g. a harmonic-balance solution) with the
//! elements loaded from their virgin state at `q = 0` to the first position (the AFT's
//! convention), and stops when the harmonics of two successive periods agree within the
//! tolerance (relative to the largest coefficient).

use crate::core::error::{Error, Result};
use crate::dynamics::aft::Harmonics;
use crate::dynamics::model::Structure;
use crate::element::{Kinematics, RatePartials, StepPartials};
use nalgebra::{DMatrix, DVector};
use std::time::Instant;

/// Settings of a steady-state run.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct TimeIntegrationSettings {
    /// Time steps per excitation period.
    pub steps_per_period: usize,
    /// Periods integrated at most.
    pub max_periods: usize,
    /// Steady when the harmonics of successive periods differ by less than this (relative).
    pub tolerance: f64,
}

impl Default for TimeIntegrationSettings {
    fn default() -> Self {
        Self {
            steps_per_period: 2048,
            max_periods: 2000,
            tolerance: 1e-8,
        }
    }
}

/// Result of a steady-state run.
#[derive(Debug, Clone)]
pub struct SteadyState {
    /// Harmonics of the coordinates over the last period (`n × len`, coordinate-major, in the
    /// convention of [`Harmonics`]).
    pub harmonics: DVector<f64>,
    /// Periods integrated.
    pub periods: usize,
    /// Relative change of the harmonics over the last period.
    pub change: f64,
    /// The change met the tolerance within the period cap.
    pub converged: bool,
    /// Wall-clock time of the run (s).
    pub wall_time_s: f64,
}

/// Integrate `structure` under `level·force·cos(harmonic·ω·t)` from `q0`, `v0` until the
/// response is periodic; the harmonics of the last period are returned in the basis `basis`
/// (its `n_time` is ignored: the period is sampled at the time steps).
#[allow(clippy::too_many_arguments)]
pub fn steady_state(
    structure: &Structure,
    force: &DVector<f64>,
    harmonic: usize,
    level: f64,
    omega: f64,
    basis: &Harmonics,
    q0: &DVector<f64>,
    v0: &DVector<f64>,
    settings: &TimeIntegrationSettings,
) -> Result<SteadyState> {
    let t_start = Instant::now();
    let n = structure.n();
    if structure.cyclic.is_some() {
        return Err(Error::param(
            "cyclic",
            "time integration of a cyclic sector is not implemented (integrate the full structure)",
        ));
    }
    if force.len() != n || q0.len() != n || v0.len() != n {
        return Err(Error::param(
            "q0",
            "initial conditions or force of the wrong length",
        ));
    }
    crate::core::error::require_positive("omega", omega)?;
    if settings.steps_per_period < 8 {
        return Err(Error::param("steps_per_period", "at least 8"));
    }
    let sampled = Harmonics::new(basis.h_max(), false, Some(settings.steps_per_period))?;
    let len = basis.len();
    let dt = 2.0 * std::f64::consts::PI / omega / settings.steps_per_period as f64;
    let mut newmark = Newmark::new(structure, q0, v0, &(force * level), dt)?;
    let fvec: Vec<f64> = force.iter().copied().collect();
    let mut prev: Option<DVector<f64>> = None;
    let mut samples = vec![vec![0.0; settings.steps_per_period]; n];
    let mut step_count: usize = 0;
    for period in 1..=settings.max_periods {
        for i in 0..settings.steps_per_period {
            step_count += 1;
            let t1 = step_count as f64 * dt;
            let cos = (harmonic as f64 * omega * t1).cos();
            let f1: Vec<f64> = fvec.iter().map(|f| f * level * cos).collect();
            newmark.step(&f1, t1)?;
            let idx = (i + 1) % settings.steps_per_period;
            for (r, &qr) in newmark.q().iter().enumerate() {
                samples[r][idx] = qr;
            }
        }
        // Harmonics of this period (samples at t_i = i·T/N of the period).
        let mut h = DVector::zeros(n * len);
        let mut full = vec![0.0; sampled.len()];
        for r in 0..n {
            let mut s = samples[r].clone();
            sampled.to_harmonics(&mut s, &mut full);
            for &order in basis.orders() {
                if order == 0 {
                    h[r * len] = full[0];
                } else {
                    let (ci, si) = basis.index_of(order).expect("retained");
                    let (cs, ss) = sampled.index_of(order).expect("retained");
                    h[r * len + ci] = full[cs];
                    h[r * len + si] = full[ss];
                }
            }
        }
        if let Some(p) = &prev {
            let change = (&h - p).amax() / h.amax().max(f64::MIN_POSITIVE);
            if change <= settings.tolerance {
                return Ok(SteadyState {
                    harmonics: h,
                    periods: period,
                    change,
                    converged: true,
                    wall_time_s: t_start.elapsed().as_secs_f64(),
                });
            }
            if period == settings.max_periods {
                return Ok(SteadyState {
                    harmonics: h,
                    periods: period,
                    change,
                    converged: false,
                    wall_time_s: t_start.elapsed().as_secs_f64(),
                });
            }
        }
        prev = Some(h);
    }
    Err(Error::param("max_periods", "at least 2"))
}

/// Newmark's average-acceleration scheme on a structure with its elements (see the module
/// documentation), one time step at a time: the state (`q`, `q̇`, `q̈` and the elements'
/// history) advances by [`Newmark::step`] under the external force at the end of the step.
/// [`steady_state`] and the free decay of [`crate::dynamics::transient`] both run on it.
pub struct Newmark<'a> {
    els: &'a [crate::dynamics::model::AttachedElement],
    n: usize,
    dt: f64,
    mr: Vec<f64>,
    cr: Vec<f64>,
    kr: Vec<f64>,
    klin: Vec<f64>,
    maps: Vec<Vec<f64>>,
    states: Vec<Vec<f64>>,
    new_states: Vec<Vec<f64>>,
    u_prev: Vec<Vec<f64>>,
    partials: Vec<StepPartials>,
    q: Vec<f64>,
    v: Vec<f64>,
    a: Vec<f64>,
    base_a: Vec<f64>,
    q1: Vec<f64>,
    trial: Vec<f64>,
    r: Vec<f64>,
    rt: Vec<f64>,
    kt: Vec<f64>,
    dq: Vec<f64>,
    u1: Vec<f64>,
    fe: Vec<f64>,
    rates: RateScratch,
}

/// What the rate-dependent elements of a Newmark step read: each element's velocity at the
/// start of the step, its rate partials, and scratch for the velocities at the end.
struct RateScratch {
    /// Element velocities at the start of the step (`P·q̇_n`, per element).
    v_prev: Vec<Vec<f64>>,
    /// Rate partials per element.
    partials: Vec<RatePartials>,
    /// Coordinate velocities at the end of the step (`n`).
    vq1: Vec<f64>,
    /// One element's velocities at the end of the step (largest `d`).
    ve1: Vec<f64>,
}

impl<'a> Newmark<'a> {
    /// Start at displacement `q0` and velocity `v0` under the external force `f0` (the
    /// acceleration follows from the equation of motion), time step `dt` (s). The elements are
    /// loaded from their virgin state at `q = 0` to `q0`.
    pub fn new(
        structure: &'a Structure,
        q0: &DVector<f64>,
        v0: &DVector<f64>,
        f0: &DVector<f64>,
        dt: f64,
    ) -> Result<Self> {
        let n = structure.n();
        if structure.cyclic.is_some() {
            return Err(Error::param(
            "cyclic",
            "time integration of a cyclic sector is not implemented (integrate the full structure)",
        ));
        }
        if f0.len() != n || q0.len() != n || v0.len() != n {
            return Err(Error::param(
                "q0",
                "initial conditions or force of the wrong length",
            ));
        }
        crate::core::error::require_positive("dt", dt)?;
        let (m, c, k) = (&structure.mass, &structure.damping, &structure.stiffness);
        let els = &structure.elements;
        // Element states, displacements and forces.
        let mut states: Vec<Vec<f64>> = Vec::with_capacity(els.len());
        let mut u_prev: Vec<Vec<f64>> = Vec::with_capacity(els.len());
        let partials: Vec<StepPartials> = els
            .iter()
            .map(|e| StepPartials::new(e.element.state_len(), e.element.dofs()))
            .collect();
        let mut fnl = DVector::zeros(n);
        for e in els {
            let (mm, d) = (e.element.state_len(), e.element.dofs());
            let mut virgin = vec![0.0; mm];
            e.element.virgin_state(&mut virgin);
            let u0: Vec<f64> = (&e.map * q0).iter().copied().collect();
            let mut s = vec![0.0; mm];
            let mut f = vec![0.0; d];
            e.element
                .step(&virgin, &vec![0.0; d], &u0, &mut s, &mut f, None);
            fnl += e.map.transpose() * DVector::from_vec(f);
            states.push(s);
            u_prev.push(u0);
        }
        // Plain row-major buffers: the step loop allocates nothing.
        let row_major = |a: &DMatrix<f64>| -> Vec<f64> {
            let mut v = vec![0.0; a.nrows() * a.ncols()];
            for r in 0..a.nrows() {
                for c in 0..a.ncols() {
                    v[r * a.ncols() + c] = a[(r, c)];
                }
            }
            v
        };
        let (mr, cr, kr) = (row_major(m), row_major(c), row_major(k));
        let maps: Vec<Vec<f64>> = els.iter().map(|e| row_major(&e.map)).collect();
        // Initial acceleration from the equation of motion.
        let rhs0: DVector<f64> = f0 - c * v0 - k * q0 - &fnl;
        let a: Vec<f64> = m
            .clone()
            .lu()
            .solve(&rhs0)
            .ok_or_else(|| Error::param("mass", "singular"))?
            .iter()
            .copied()
            .collect();
        let mut klin = vec![0.0; n * n];
        for i in 0..n * n {
            klin[i] = kr[i] + cr[i] * (2.0 / dt) + mr[i] * (4.0 / (dt * dt));
        }
        let dmax = els.iter().map(|e| e.element.dofs()).max().unwrap_or(0);
        let rates = RateScratch {
            v_prev: els
                .iter()
                .map(|e| (&e.map * v0).iter().copied().collect())
                .collect(),
            partials: els
                .iter()
                .map(|e| RatePartials::new(e.element.state_len(), e.element.dofs()))
                .collect(),
            vq1: vec![0.0; n],
            ve1: vec![0.0; dmax],
        };
        Ok(Self {
            rates,
            els,
            n,
            dt,
            mr,
            cr,
            kr,
            klin,
            maps,
            new_states: states.clone(),
            states,
            u_prev,
            partials,
            q: q0.iter().copied().collect(),
            v: v0.iter().copied().collect(),
            a,
            base_a: vec![0.0; n],
            q1: vec![0.0; n],
            trial: vec![0.0; n],
            r: vec![0.0; n],
            rt: vec![0.0; n],
            kt: vec![0.0; n * n],
            dq: vec![0.0; n],
            u1: vec![0.0; dmax],
            fe: vec![0.0; dmax],
        })
    }

    /// Displacements at the current time (m).
    pub fn q(&self) -> &[f64] {
        &self.q
    }

    /// Velocities at the current time (m/s).
    pub fn v(&self) -> &[f64] {
        &self.v
    }

    /// The time step (s).
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// One time step to `t1` (used in messages only) under the external force `f1` at its end:
    /// Newton's method with the elements' tangents and a backtracking line search.
    pub fn step(&mut self, f1: &[f64], t1: f64) -> Result<()> {
        let (n, dt) = (self.n, self.dt);
        let norm = |x: &[f64]| x.iter().map(|v| v * v).sum::<f64>().sqrt();
        let Self {
            els,
            mr,
            cr,
            kr,
            klin,
            maps,
            states,
            new_states,
            u_prev,
            partials,
            q,
            v,
            a,
            base_a,
            q1,
            trial,
            r,
            rt,
            kt,
            dq,
            u1,
            fe,
            rates,
            ..
        } = self;
        for j in 0..n {
            base_a[j] = -(q[j] * (4.0 / (dt * dt))) - v[j] * (4.0 / dt) - a[j];
            q1[j] = q[j] + v[j] * dt + a[j] * (0.25 * dt * dt);
        }
        let ctx = StepContext {
            dt,
            m: mr,
            c: cr,
            k: kr,
            klin,
            base_a,
            v,
            a,
            f1,
            els,
            maps,
        };
        let kq: f64 = norm(
            &(0..n)
                .map(|r| (0..n).map(|j| kr[r * n + j] * q[j]).sum::<f64>())
                .collect::<Vec<f64>>(),
        );
        // Residual scale: the largest term of the step equation (the inertia term
        // 4/dt²·M·q1 dominates round-off).
        let mq: f64 = norm(
            &(0..n)
                .map(|r| (0..n).map(|j| mr[r * n + j] * q1[j]).sum::<f64>())
                .collect::<Vec<f64>>(),
        ) * 4.0
            / (dt * dt);
        let scale = norm(f1) + kq + mq + f64::MIN_POSITIVE;
        let mut converged = false;
        for _ in 0..60 {
            residual(
                q1,
                r,
                Some(kt),
                &ctx,
                states,
                u_prev,
                new_states,
                partials,
                u1,
                fe,
                rates,
            );
            let r0 = norm(r);
            if r0 <= 1e-12 * scale {
                converged = true;
                break;
            }
            for j in 0..n {
                dq[j] = -r[j];
            }
            if !gauss_solve(kt, dq, n) {
                return Err(Error::Data("singular time-step matrix".into()));
            }
            if norm(dq) <= 1e-14 * (norm(q1) + f64::MIN_POSITIVE) {
                converged = true;
                break;
            }
            let mut lambda = 1.0;
            let mut accepted = false;
            for _ in 0..12 {
                for j in 0..n {
                    trial[j] = q1[j] + lambda * dq[j];
                }
                residual(
                    trial, rt, None, &ctx, states, u_prev, new_states, partials, u1, fe, rates,
                );
                if norm(rt) < r0 {
                    q1.copy_from_slice(trial);
                    accepted = true;
                    break;
                }
                lambda *= 0.5;
            }
            if !accepted {
                for j in 0..n {
                    q1[j] += dq[j];
                }
            }
        }
        residual(
            q1, r, None, &ctx, states, u_prev, new_states, partials, u1, fe, rates,
        );
        if !converged && norm(r) > 1e-8 * scale {
            return Err(Error::NonConvergence {
                solver: format!("Newmark time step at t = {t1:.6e} s"),
                iterations: 60,
                residual: norm(r) / scale,
                tolerance: 1e-8,
            });
        }
        for j in 0..n {
            let a1 = q1[j] * (4.0 / (dt * dt)) + base_a[j];
            v[j] += (a[j] + a1) * (0.5 * dt);
            a[j] = a1;
            q[j] = q1[j];
        }
        std::mem::swap(states, new_states);
        for (ie, e) in els.iter().enumerate() {
            let d = e.element.dofs();
            for c in 0..d {
                u_prev[ie][c] = (0..n).map(|j| maps[ie][c * n + j] * q[j]).sum();
                rates.v_prev[ie][c] = (0..n).map(|j| maps[ie][c * n + j] * v[j]).sum();
            }
        }
        Ok(())
    }
}

/// Residual of the step equation at `q1` (and the tangent when `tangent` is set).
#[allow(clippy::too_many_arguments)]
fn residual(
    q1: &[f64],
    out: &mut [f64],
    tangent: Option<&mut [f64]>,
    ctx: &StepContext<'_>,
    states: &[Vec<f64>],
    u_prev: &[Vec<f64>],
    new_states: &mut [Vec<f64>],
    partials: &mut [StepPartials],
    u1: &mut [f64],
    fe: &mut [f64],
    rates: &mut RateScratch,
) {
    let n = q1.len();
    let dt = ctx.dt;
    let mut want = tangent;
    if let Some(t) = want.as_deref_mut() {
        t.copy_from_slice(ctx.klin);
    }
    for i in 0..n {
        let mut s = -ctx.f1[i];
        for j in 0..n {
            let a1 = q1[j] * (4.0 / (dt * dt)) + ctx.base_a[j];
            let v1 = ctx.v[j] + (ctx.a[j] + a1) * (0.5 * dt);
            s += ctx.m[i * n + j] * a1 + ctx.c[i * n + j] * v1 + ctx.k[i * n + j] * q1[j];
        }
        out[i] = s;
    }
    if ctx.els.iter().any(|e| e.element.rate_dependent()) {
        for j in 0..n {
            let a1 = q1[j] * (4.0 / (dt * dt)) + ctx.base_a[j];
            rates.vq1[j] = ctx.v[j] + (ctx.a[j] + a1) * (0.5 * dt);
        }
    }
    for (ie, e) in ctx.els.iter().enumerate() {
        let d = e.element.dofs();
        let p = &ctx.maps[ie];
        for c in 0..d {
            u1[c] = (0..n).map(|j| p[c * n + j] * q1[j]).sum();
        }
        if e.element.rate_dependent() {
            let ve1 = &mut rates.ve1[..d];
            for (c, v) in ve1.iter_mut().enumerate() {
                *v = (0..n).map(|j| p[c * n + j] * rates.vq1[j]).sum();
            }
            let kin = Kinematics {
                dt,
                v0: &rates.v_prev[ie],
                v1: ve1,
            };
            let part = if want.is_some() {
                partials[ie].clear();
                rates.partials[ie].clear();
                Some((&mut partials[ie], &mut rates.partials[ie]))
            } else {
                None
            };
            e.element.step_at_rate(
                &states[ie],
                &u_prev[ie],
                &u1[..d],
                kin,
                &mut new_states[ie],
                &mut fe[..d],
                part,
            );
            if want.is_some() {
                // ∂v1/∂q1 = (2/Δt)·P: the tangent damping enters the step's stiffness.
                let (kd, cd) = (&mut partials[ie].df_du1, &rates.partials[ie].df_dv1);
                for (k, c) in kd.iter_mut().zip(cd) {
                    *k += c * (2.0 / dt);
                }
            }
        } else {
            let part = if want.is_some() {
                partials[ie].clear();
                Some(&mut partials[ie])
            } else {
                None
            };
            e.element.step(
                &states[ie],
                &u_prev[ie],
                &u1[..d],
                &mut new_states[ie],
                &mut fe[..d],
                part,
            );
        }
        for c in 0..d {
            for i in 0..n {
                out[i] += p[c * n + i] * fe[c];
            }
        }
        if let Some(t) = want.as_deref_mut() {
            let kd = &partials[ie].df_du1;
            for c in 0..d {
                for c2 in 0..d {
                    let kv = kd[c * d + c2];
                    if kv == 0.0 {
                        continue;
                    }
                    for i in 0..n {
                        let pi = p[c * n + i] * kv;
                        if pi == 0.0 {
                            continue;
                        }
                        for j in 0..n {
                            t[i * n + j] += pi * p[c2 * n + j];
                        }
                    }
                }
            }
        }
    }
}

/// What the step residual needs besides the unknowns.
struct StepContext<'a> {
    dt: f64,
    m: &'a [f64],
    c: &'a [f64],
    k: &'a [f64],
    klin: &'a [f64],
    base_a: &'a [f64],
    v: &'a [f64],
    a: &'a [f64],
    f1: &'a [f64],
    els: &'a [crate::dynamics::model::AttachedElement],
    maps: &'a [Vec<f64>],
}

/// Solve `a·x = b` in place (Gaussian elimination with partial pivoting, `a` row-major `n × n`,
/// destroyed); false if singular.
fn gauss_solve(a: &mut [f64], b: &mut [f64], n: usize) -> bool {
    for col in 0..n {
        let piv = (col..n)
            .max_by(|&i, &j| {
                a[i * n + col]
                    .abs()
                    .partial_cmp(&a[j * n + col].abs())
                    .unwrap()
            })
            .expect("non-empty");
        if a[piv * n + col] == 0.0 || !a[piv * n + col].is_finite() {
            return false;
        }
        if piv != col {
            for j in 0..n {
                a.swap(piv * n + j, col * n + j);
            }
            b.swap(piv, col);
        }
        let d = a[col * n + col];
        for i in col + 1..n {
            let f = a[i * n + col] / d;
            if f != 0.0 {
                for j in col..n {
                    a[i * n + j] -= f * a[col * n + j];
                }
                b[i] -= f * b[col];
            }
        }
    }
    for col in (0..n).rev() {
        let mut s = b[col];
        for j in col + 1..n {
            s -= a[col * n + j] * b[j];
        }
        b[col] = s / a[col * n + col];
    }
    true
}

/// Initial displacement and velocity at `t = 0` of a harmonic solution `x` (`n × len`).
pub fn initial_conditions(
    x: &DVector<f64>,
    basis: &Harmonics,
    n: usize,
    omega: f64,
) -> (DVector<f64>, DVector<f64>) {
    let len = basis.len();
    let mut q0 = DVector::zeros(n);
    let mut v0 = DVector::zeros(n);
    for r in 0..n {
        for &order in basis.orders() {
            if order == 0 {
                q0[r] += x[r * len];
            } else {
                let (ci, si) = basis.index_of(order).expect("retained");
                q0[r] += x[r * len + ci];
                v0[r] += order as f64 * omega * x[r * len + si];
            }
        }
    }
    (q0, v0)
}
