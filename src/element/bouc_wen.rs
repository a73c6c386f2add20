//! Bouc–Wen hysteretic element.
//!
//! # Constitutive model
//! (Bouc 1967; Wen 1976, *J. Eng. Mech. Div. ASCE* 102:249; the form of Ismail, Ikhouane &
//! Rodellar 2009, *Arch. Comput. Methods Eng.* 16:161):
//!
//! ```text
//! F  = α·k·u + (1 − α)·k·z
//! ż  = A·u̇ − β·|u̇|·|z|^{n−1}·z − γ·u̇·|z|^n
//! ```
//!
//! The model is rate-independent, so `z` follows `dz/du = A − |z|^n·(β·sign(u̇·z) + γ)`.
//! Under sustained motion `z` tends to `z_u = (A/(β + γ))^{1/n}` (the ultimate hysteretic
//! displacement); the hysteretic force saturates at `(1 − α)·k·z_u`. The exponent `n` sets
//! the sharpness of the elastic–plastic transition; `γ` the shape of unloading: for
//! `β = γ` unloading (`u̇·z < 0`) is linear with slope `k·A` until `z` changes sign.
//! For `n = 1`, `γ = 0`, `α = 0` the law is `dF/du = kA − β·sign(u̇)·F`: the Valanis element
//! with `k = 0`, `Et = 0`, `E0 = kA`, slip force `kA/β` (checked in the tests).
//!
//! # Time-discrete update
//! From `(u0, z0)` to `u1`: classical fourth-order Runge–Kutta on `dz/du` (the direction of
//! motion is that of the increment, fixed within it), with sub-steps no longer than
//! [`SUBSTEP_FRACTION`] of `z_u/A` (the elastic range); `z` is clamped to `|z| ≤ z_u`, which the
//! exact solution never leaves. Units: `u`, `z` in m, `k` in N/m, `F` in N, `A` and `α`
//! dimensionless, `β`, `γ` in 1/m^n.

use crate::core::error::{require_positive, Error, Result};
use crate::element::hysteretic::{ContactStatus, HystereticElement, StepPartials};
use serde::{Deserialize, Serialize};

/// Largest Runge–Kutta sub-step as a fraction of the elastic range `z_u/A`.
pub const SUBSTEP_FRACTION: f64 = 0.01;

/// Bouc–Wen parameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BoucWenParams {
    /// Initial stiffness scale `k` (N/m).
    pub k: f64,
    /// Post-yield stiffness ratio `0 ≤ α < 1`.
    pub alpha: f64,
    /// `A > 0`.
    pub a: f64,
    /// `β` (1/m^n), with `β + γ > 0` and `β − γ ≥ 0` (a stable, dissipative loop).
    pub beta: f64,
    /// `γ` (1/m^n).
    pub gamma: f64,
    /// Exponent `n ≥ 1`.
    pub n: f64,
}

impl BoucWenParams {
    /// Build and validate.
    pub fn new(k: f64, alpha: f64, a: f64, beta: f64, gamma: f64, n: f64) -> Result<Self> {
        require_positive("k", k)?;
        require_positive("a", a)?;
        if !(alpha.is_finite() && (0.0..1.0).contains(&alpha)) {
            return Err(Error::param(
                "alpha",
                format!("must satisfy 0 <= α < 1, got {alpha}"),
            ));
        }
        if !(beta.is_finite() && gamma.is_finite() && beta + gamma > 0.0 && beta >= gamma.abs()) {
            return Err(Error::param(
                "beta",
                format!(
                    "need β + γ > 0 and β ≥ |γ| (dissipative loop), got β = {beta}, γ = {gamma}"
                ),
            ));
        }
        if !(n.is_finite() && n >= 1.0) {
            return Err(Error::param("n", format!("must be >= 1, got {n}")));
        }
        Ok(Self {
            k,
            alpha,
            a,
            beta,
            gamma,
            n,
        })
    }

    /// Ultimate hysteretic displacement `z_u = (A/(β + γ))^{1/n}` (m).
    pub fn z_ultimate(&self) -> f64 {
        (self.a / (self.beta + self.gamma)).powf(1.0 / self.n)
    }

    /// `dz/du` for motion in direction `s` (±1).
    pub fn dz_du(&self, z: f64, s: f64) -> f64 {
        self.a - z.abs().powf(self.n) * (self.beta * (s * z).signum() + self.gamma)
    }

    /// Force `αku + (1−α)kz` (N).
    pub fn force(&self, u: f64, z: f64) -> f64 {
        self.k * (self.alpha * u + (1.0 - self.alpha) * z)
    }
}

/// State: displacement `u` and hysteretic variable `z` (m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoucWenState {
    /// Displacement `u` (m).
    pub u: f64,
    /// Hysteretic displacement `z` (m).
    pub z: f64,
}

/// Advance the state to displacement `u1` (module documentation).
pub fn step(p: &BoucWenParams, state: &BoucWenState, u1: f64) -> BoucWenState {
    step_partials(p, state, u1).0
}

/// [`step`] with the exact derivatives of the discrete update, `(∂z1/∂z0, ∂z1/∂u0, ∂z1/∂u1)`:
/// forward-mode differentiation of the Runge–Kutta stages in the initial value and the sub-step
/// `h = Δu/m` (the sub-step count `m` is piecewise constant in `Δu`), with
/// `∂(dz/du)/∂z = −n·|z|^{n−1}·sign(z)·(β·sign(u̇·z) + γ)` and zero where `z` is clamped to
/// `±z_u`.
pub fn step_partials(p: &BoucWenParams, state: &BoucWenState, u1: f64) -> (BoucWenState, [f64; 3]) {
    let du = u1 - state.u;
    if du == 0.0 {
        // On the kink the one-sided derivative for u1 > u0.
        let dz = p.dz_du(state.z, 1.0);
        return (BoucWenState { u: u1, z: state.z }, [1.0, -dz, dz]);
    }
    let zu = p.z_ultimate();
    let s = du.signum();
    let h_max = SUBSTEP_FRACTION * zu / p.a;
    let m = (du.abs() / h_max).ceil().max(1.0) as usize;
    let h = du / m as f64;
    let g = |z: f64| p.dz_du(z.clamp(-zu, zu), s);
    // ∂g/∂z (zero outside the clamp; at z = 0, where it jumps for n = 1, the side z moves to).
    let dg = |z: f64| {
        if z.abs() > zu {
            return 0.0;
        }
        let side = if z == 0.0 { s } else { z.signum() };
        -p.n * z.abs().powf(p.n - 1.0) * side * (p.beta * (s * side).signum() + p.gamma)
    };
    let mut z = state.z;
    // Tangents of z along z0 and along h.
    let (mut a, mut b) = (1.0, 0.0);
    for _ in 0..m {
        let k1 = g(z);
        let (a1, b1) = (dg(z) * a, dg(z) * b);
        let z2 = z + 0.5 * h * k1;
        let k2 = g(z2);
        let (a2, b2) = (
            dg(z2) * (a + 0.5 * h * a1),
            dg(z2) * (b + 0.5 * k1 + 0.5 * h * b1),
        );
        let z3 = z + 0.5 * h * k2;
        let k3 = g(z3);
        let (a3, b3) = (
            dg(z3) * (a + 0.5 * h * a2),
            dg(z3) * (b + 0.5 * k2 + 0.5 * h * b2),
        );
        let z4 = z + h * k3;
        let k4 = g(z4);
        let (a4, b4) = (dg(z4) * (a + h * a3), dg(z4) * (b + k3 + h * b3));
        let sum = k1 + 2.0 * k2 + 2.0 * k3 + k4;
        let next = z + h / 6.0 * sum;
        if next.abs() > zu {
            (a, b) = (0.0, 0.0);
        } else {
            a += h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4);
            b += sum / 6.0 + h / 6.0 * (b1 + 2.0 * b2 + 2.0 * b3 + b4);
        }
        z = next.clamp(-zu, zu);
    }
    let dz_du1 = b / m as f64;
    (BoucWenState { u: u1, z }, [a, -dz_du1, dz_du1])
}

/// The Bouc–Wen element on one displacement component as a [`HystereticElement`]. State: the
/// hysteretic displacement `z` (m); force `α·k·u + (1 − α)·k·z`. Reported in slip when the
/// hysteretic force is within 1 % of its ultimate value (`|z| ≥ 0.99·z_u`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoucWen {
    /// The Bouc–Wen parameters.
    pub params: BoucWenParams,
}

impl BoucWen {
    /// Build and validate.
    pub fn new(params: BoucWenParams) -> Result<Self> {
        let p = params;
        BoucWenParams::new(p.k, p.alpha, p.a, p.beta, p.gamma, p.n)?;
        Ok(Self { params })
    }
}

impl HystereticElement for BoucWen {
    fn name(&self) -> &'static str {
        "bouc-wen"
    }
    fn dofs(&self) -> usize {
        1
    }
    fn state_len(&self) -> usize {
        1
    }
    fn virgin_state(&self, s: &mut [f64]) {
        s[0] = 0.0;
    }
    fn state_scales(&self, scales: &mut [f64]) {
        scales[0] = self.params.z_ultimate();
    }
    fn force_scale(&self) -> f64 {
        let p = &self.params;
        (1.0 - p.alpha) * p.k * p.z_ultimate()
    }
    fn step(
        &self,
        s0: &[f64],
        u0: &[f64],
        u1: &[f64],
        s1: &mut [f64],
        f1: &mut [f64],
        partials: Option<&mut StepPartials>,
    ) {
        let p = &self.params;
        let (st, [dz0, du0, du1]) = step_partials(p, &BoucWenState { u: u0[0], z: s0[0] }, u1[0]);
        s1[0] = st.z;
        f1[0] = p.force(u1[0], st.z);
        if let Some(d) = partials {
            let kz = p.k * (1.0 - p.alpha);
            d.ds_ds0[0] = dz0;
            d.ds_du0[0] = du0;
            d.ds_du1[0] = du1;
            d.df_ds0[0] = kz * dz0;
            d.df_du0[0] = kz * du0;
            d.df_du1[0] = p.k * p.alpha + kz * du1;
        }
    }
    fn status(&self, s: &[f64], _u: &[f64], _f: &[f64]) -> ContactStatus {
        ContactStatus::classify(
            1.0,
            s[0].abs(),
            crate::element::valanis::GROSS_SLIP_FRACTION * self.params.z_ultimate(),
        )
    }
}

/// Tangent stiffness `dF/du` (N/m) for motion in direction `s` at `state`.
pub fn tangent(p: &BoucWenParams, state: &BoucWenState, s: f64) -> f64 {
    p.k * (p.alpha + (1.0 - p.alpha) * p.dz_du(state.z, s))
}

/// Force history of an element starting at `z = 0`, driven by `u` (N).
pub fn integrate(p: &BoucWenParams, u: &[f64]) -> Result<Vec<f64>> {
    BoucWenParams::new(p.k, p.alpha, p.a, p.beta, p.gamma, p.n)?;
    if let Some(i) = u.iter().position(|v| !v.is_finite()) {
        return Err(Error::param("u", format!("sample {i} is not finite")));
    }
    let Some(&u0) = u.first() else {
        return Ok(vec![]);
    };
    let mut st = BoucWenState { u: u0, z: 0.0 };
    Ok(u.iter()
        .map(|&ui| {
            st = step(p, &st, ui);
            p.force(ui, st.z)
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::sine_history;
    use crate::element::valanis::{integrate_reference, ValanisParams};

    /// n = 1: on each monotonic branch `z` approaches its limit exponentially, with rate
    /// `β + γ` when `z·u̇ > 0` and `β − γ` when `z·u̇ < 0`: one large step against the
    /// closed form.
    #[test]
    fn n_equal_one_matches_the_exponential_branches() {
        let p = BoucWenParams::new(1e6, 0.0, 1.0, 2e4, 5e3, 1.0).unwrap();
        let z_of = |z0: f64, du: f64, c: f64| p.a / c + (z0 - p.a / c) * (-c * du).exp();
        // Loading from z = 0: branch c = β + γ.
        let s1 = step(&p, &BoucWenState { u: 0.0, z: 0.0 }, 2e-4);
        let e1 = z_of(0.0, 2e-4, p.beta + p.gamma);
        assert!(
            (s1.z - e1).abs() < 1e-9 * p.z_ultimate(),
            "{} vs {e1}",
            s1.z
        );
        // Unloading (du < 0) from z > 0: dz/du = A + (β − γ)·z, so in v = −u,
        // z(v) = −A/c + (z0 + A/c)·exp(−c·v) with c = β − γ (while z > 0).
        let s2 = step(&p, &s1, 2e-4 - 2e-5);
        let c = p.beta - p.gamma;
        let exact = -p.a / c + (s1.z + p.a / c) * (-c * 2e-5).exp();
        assert!(
            (s2.z - exact).abs() < 1e-9 * p.z_ultimate(),
            "{} vs {exact}",
            s2.z
        );
    }

    #[test]
    fn saturates_at_the_ultimate_force_and_tangent_is_consistent() {
        let p = BoucWenParams::new(1e6, 0.1, 1.0, 1e8, 1e8, 2.0).unwrap();
        let zu = p.z_ultimate();
        let f = integrate(&p, &[0.0, 50.0 * zu]).unwrap();
        assert!((f[1] - p.force(50.0 * zu, zu)).abs() < 1e-9 * p.force(0.0, zu));
        let st = step(&p, &BoucWenState { u: 0.0, z: 0.0 }, 0.4 * zu);
        for s in [1.0, -1.0] {
            let h = 1e-7 * zu * s;
            let fd = (p.force(st.u + h, step(&p, &st, st.u + h).z) - p.force(st.u, st.z)) / h;
            assert!((fd / tangent(&p, &st, s) - 1.0).abs() < 1e-5, "{fd}");
        }
        assert!(BoucWenParams::new(1e6, 0.0, 1.0, 1.0, 2.0, 1.0).is_err());
        assert!(BoucWenParams::new(1e6, 0.0, 1.0, 1.0, 0.0, 0.5).is_err());
    }

    /// n = 1, γ = 0, α = 0 is the Valanis element with k = 0: two independent codes agree.
    #[test]
    fn special_case_equals_the_valanis_element() {
        let (k, a, beta) = (2e6, 1.0, 2e4);
        let p = BoucWenParams::new(k, 0.0, a, beta, 0.0, 1.0).unwrap();
        let v = ValanisParams::new(k * a, 0.0, 0.0, k * a / beta / 1000.0).unwrap();
        let q = sine_history(3.0 / beta, 2, 400);
        let fb = integrate(&p, &q).unwrap();
        let fv = integrate_reference(&v, &q, &vec![1000.0; q.len()]).unwrap();
        let dev = fb
            .iter()
            .zip(&fv)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        assert!(dev < 1e-6 * k * a / beta, "{dev}");
    }

    /// The element's derivatives against finite differences: loading, unloading and near
    /// saturation, for `n = 1` and `n = 2.5`.
    #[test]
    fn element_partials_match_finite_differences() {
        for p in [
            BoucWenParams::new(1e6, 0.1, 1.0, 2e4, 5e3, 1.0).unwrap(),
            BoucWenParams::new(1e6, 0.0, 1.0, 3e10, 1e10, 2.5).unwrap(),
        ] {
            let el = BoucWen::new(p).unwrap();
            let zu = p.z_ultimate();
            // Increments of 0.237 z_u (24 sub-steps, away from a change of the count).
            for (z0, u0, u1) in [
                (1e-3 * zu, 0.0, 0.237 * zu),
                (0.6 * zu, 1.0 * zu, 0.763 * zu),
                (-0.9 * zu, 0.0, -0.237 * zu),
                (0.3 * zu, 0.0, -0.237 * zu),
            ] {
                let w = crate::element::hysteretic::check_partials(
                    &el,
                    &[z0],
                    &[u0],
                    &[u1],
                    1e-7 * zu,
                    &[1e-7 * zu],
                )
                .unwrap();
                assert!(w < 1e-6, "n = {}: z0 = {z0:e}, u1 = {u1:e}: {w}", p.n);
            }
        }
    }
}
