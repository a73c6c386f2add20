//! Hunt–Crossley normal contact with separation and impact: a nonlinear spring with damping
//! proportional to the indentation (Hunt & Crossley 1975, *J. Appl. Mech.* 42:440),
//!
//! ```text
//! F = max(0, k·δⁿ·(1 + χ·δ̇))   for δ = u − g0 > 0,   F = 0 for δ ≤ 0 (separated)
//! ```
//!
//! with `u` the approach along the joint direction (m, `u > 0` closing), `g0 ≥ 0` the initial gap
//! (m), `k` the contact stiffness (N/mⁿ), `n ≥ 1` the exponent (3/2 for Hertz) and `χ` the damping
//! factor (s/m; Hunt & Crossley write it `(3/2)·α`). Because the damping force vanishes with
//! the indentation, the force is continuous at impact and at separation, and the `max(0, ·)`
//! keeps the contact from pulling when it opens faster than `1/χ`.
//!
//! # Damping factor from the coefficient of restitution
//!
//! For a single impact of a mass `m` arriving at `δ̇ = v_in` (free flight before and after,
//! `m·δ̈ = −F`), dividing the equation of motion by `δ̇` separates it:
//! `m·v/(1 + χv)·dv = −k·δⁿ·dδ`. The right side integrates to zero over the impact (from `δ = 0`
//! down to the largest indentation and back), so the exit velocity `v_out = −e·v_in` satisfies
//! `∫_{v_in}^{v_out} v/(1 + χv) dv = 0`, i.e. with `x = χ·v_in`
//!
//! ```text
//! ln((1 − e·x)/(1 + x)) + (1 + e)·x = 0            (exact, any k, n and m)
//! ```
//!
//! (Gonthier, McPhee, Lange & Piedbœuf 2004, *Multibody Syst. Dyn.* 11:209, eq. 22; the same
//! integral as Hunt & Crossley's energy balance, without its small-damping expansion). It has one
//! root `x ∈ (0, 1/e)` for every `0 < e < 1`: [`damping_factor`] solves it, and
//! [`restitution`] evaluates `e` from `χ·v_in`. The classical explicit approximations, valid for
//! `e` near 1, are Hunt & Crossley's `χ = 3(1 − e)/(2·v_in)` ([`damping_factor_hunt_crossley`])
//! and Lankarani & Nikravesh's `χ = 3(1 − e²)/(4·v_in)` (1990, *J. Mech. Des.* 112:369;
//! [`damping_factor_lankarani_nikravesh`]). The coefficient of restitution depends on the impact
//! velocity: `χ` is a material constant only for the velocity it was fitted at.
//!
//! Units: `u`, `g0` in m, `δ̇` in m/s, `F` in N, `k` in N/mⁿ, `χ` in s/m.

use crate::core::error::{Error, Result};
use crate::element::hysteretic::{
    ContactStatus, HystereticElement, Kinematics, RatePartials, StepPartials,
};

/// Hunt–Crossley contact parameters (module documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HuntCrossleyParams {
    /// Contact stiffness `k` (N/mⁿ), > 0.
    pub stiffness: f64,
    /// Exponent `n` (–), ≥ 1 (1: linear spring, 3/2: Hertz).
    pub exponent: f64,
    /// Damping factor `χ` (s/m), ≥ 0.
    pub damping_factor: f64,
    /// Initial gap `g0` (m), ≥ 0: the contact closes at `u = g0`.
    pub gap: f64,
}

impl HuntCrossleyParams {
    /// Validate: `k > 0`, `n ≥ 1`, `χ ≥ 0`, `g0 ≥ 0`, all finite.
    pub fn validate(&self) -> Result<()> {
        crate::core::error::require_positive("stiffness", self.stiffness)?;
        if !(self.exponent.is_finite() && self.exponent >= 1.0) {
            return Err(Error::param(
                "exponent",
                format!(
                    "must be ≥ 1 (the tangent stiffness is infinite at touch-down below), got {}",
                    self.exponent
                ),
            ));
        }
        for (name, v) in [("damping_factor", self.damping_factor), ("gap", self.gap)] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::param(
                    name,
                    format!("must be finite and ≥ 0, got {v}"),
                ));
            }
        }
        Ok(())
    }

    /// Force `F` at approach `u` and approach rate `v`, with `∂F/∂u` and `∂F/∂v`.
    pub fn force_and_partials(&self, u: f64, v: f64) -> (f64, f64, f64) {
        let delta = u - self.gap;
        let factor = 1.0 + self.damping_factor * v;
        if delta <= 0.0 || factor <= 0.0 {
            return (0.0, 0.0, 0.0);
        }
        let dn1 = delta.powf(self.exponent - 1.0);
        let kdn = self.stiffness * dn1 * delta;
        (
            kdn * factor,
            self.exponent * self.stiffness * dn1 * factor,
            kdn * self.damping_factor,
        )
    }
}

/// Coefficient of restitution `e` of one impact for `x = χ·v_in` (the root in `(0, 1]` of
/// `ln((1 − e·x)/(1 + x)) + (1 + e)·x = 0`, module documentation): 1 without damping,
/// decreasing with `x`.
pub fn restitution(chi_v_in: f64) -> f64 {
    let x = chi_v_in;
    if x <= 0.0 {
        return 1.0;
    }
    // g(e) = ln(1 − e·x) − ln(1 + x) + (1 + e)·x; g(0) = x − ln(1 + x) > 0, g decreases towards
    // −∞ at e = 1/x, and the nontrivial root is the one below min(1, 1/x).
    let g = |e: f64| (-e * x).ln_1p() - x.ln_1p() + (1.0 + e) * x;
    let hi = if x > 1.0 { 1.0 / x } else { 1.0 };
    if g(hi) >= 0.0 {
        return hi;
    }
    bisect(g, 0.0, hi)
}

/// Damping factor `χ` (s/m) that gives the coefficient of restitution `e` at impact velocity
/// `v_in` (m/s), exactly (the root `x = χ·v_in ∈ (0, 1/e)` of the relation in the module
/// documentation). `0 < e ≤ 1`, `v_in > 0`.
pub fn damping_factor(e: f64, v_in: f64) -> Result<f64> {
    check_restitution(e, v_in)?;
    if e == 1.0 {
        return Ok(0.0);
    }
    // f(x) = ln(1 − e·x) − ln(1 + x) + (1 + e)·x: f ~ (1 − e²)x²/2 > 0 near 0, → −∞ at 1/e.
    let f = |x: f64| (-e * x).ln_1p() - x.ln_1p() + (1.0 + e) * x;
    let hi = 1.0 / e;
    // The positive lobe starts at 0 with f = 0: bracket from a point where f > 0.
    let mut lo = 1e-6 * hi;
    while f(lo) <= 0.0 && lo > 1e-300 {
        lo *= 0.5;
    }
    Ok(bisect(f, lo, hi * (1.0 - 1e-15)) / v_in)
}

/// Hunt & Crossley's damping factor `χ = 3(1 − e)/(2·v_in)` (s/m), accurate for `e` near 1.
pub fn damping_factor_hunt_crossley(e: f64, v_in: f64) -> Result<f64> {
    check_restitution(e, v_in)?;
    Ok(1.5 * (1.0 - e) / v_in)
}

/// Lankarani & Nikravesh's damping factor `χ = 3(1 − e²)/(4·v_in)` (s/m), accurate for `e`
/// near 1.
pub fn damping_factor_lankarani_nikravesh(e: f64, v_in: f64) -> Result<f64> {
    check_restitution(e, v_in)?;
    Ok(0.75 * (1.0 - e * e) / v_in)
}

fn check_restitution(e: f64, v_in: f64) -> Result<()> {
    if !(e > 0.0 && e <= 1.0) {
        return Err(Error::param(
            "restitution",
            format!("must be in (0, 1], got {e}"),
        ));
    }
    crate::core::error::require_positive("impact_velocity", v_in)?;
    Ok(())
}

/// Root of `f` in `[lo, hi]` with `f(lo) > 0 ≥ f(hi)`, by bisection to the last bit.
fn bisect(f: impl Fn(f64) -> f64, mut lo: f64, mut hi: f64) -> f64 {
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if f(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// A Hunt–Crossley contact on one displacement component as a rate-dependent
/// [`HystereticElement`] without state: the force at the end of an increment is
/// [`HuntCrossleyParams::force_and_partials`] at the end displacement and the end velocity the
/// caller gives it (the harmonics' exact velocity in the AFT, the integrator's in a time
/// integration). Its plain `step` is the quasi-static limit (zero approach rate: the elastic
/// law `k·δⁿ`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HuntCrossley {
    /// The law's parameters.
    pub params: HuntCrossleyParams,
}

impl HystereticElement for HuntCrossley {
    fn name(&self) -> &'static str {
        "hunt-crossley"
    }
    fn dofs(&self) -> usize {
        1
    }
    fn state_len(&self) -> usize {
        0
    }
    fn rate_dependent(&self) -> bool {
        true
    }
    fn virgin_state(&self, _s: &mut [f64]) {}
    fn state_scales(&self, _scales: &mut [f64]) {}
    fn force_scale(&self) -> f64 {
        self.params.stiffness
    }
    fn step(
        &self,
        _s0: &[f64],
        _u0: &[f64],
        u1: &[f64],
        _s1: &mut [f64],
        f1: &mut [f64],
        partials: Option<&mut StepPartials>,
    ) {
        let (f, df_du, _) = self.params.force_and_partials(u1[0], 0.0);
        f1[0] = f;
        if let Some(p) = partials {
            p.df_du1[0] = df_du;
        }
    }
    fn step_at_rate(
        &self,
        _s0: &[f64],
        _u0: &[f64],
        u1: &[f64],
        kin: Kinematics<'_>,
        _s1: &mut [f64],
        f1: &mut [f64],
        partials: Option<(&mut StepPartials, &mut RatePartials)>,
    ) {
        let (f, df_du, df_dv) = self.params.force_and_partials(u1[0], kin.v1[0]);
        f1[0] = f;
        if let Some((p, rp)) = partials {
            p.df_du1[0] = df_du;
            rp.df_dv1[0] = df_dv;
        }
    }
    fn status(&self, _s: &[f64], u: &[f64], f: &[f64]) -> ContactStatus {
        if u[0] <= self.params.gap || f[0] <= 0.0 {
            ContactStatus::Separated
        } else {
            ContactStatus::Stick
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::hysteretic::{check_partials, check_rate_partials};

    fn law(n: f64, chi: f64, gap: f64) -> HuntCrossleyParams {
        HuntCrossleyParams {
            stiffness: 2e7,
            exponent: n,
            damping_factor: chi,
            gap,
        }
    }

    #[test]
    fn partials_match_finite_differences_in_contact() {
        for n in [1.0, 1.5, 2.2] {
            let e = HuntCrossley {
                params: law(n, 0.3, 1e-5),
            };
            // Closing, opening (damping reduces the force), both in contact.
            for (u0, u1, v1) in [(3e-5, 3.4e-5, 0.4), (4e-5, 3.7e-5, -0.3)] {
                let kin = Kinematics {
                    dt: 1e-4,
                    v0: &[0.1],
                    v1: &[v1],
                };
                let w = check_rate_partials(&e, &[], &[u0], &[u1], kin, (1e-10, 1e-6, 1e-9), &[])
                    .unwrap();
                assert!(w < 1e-6, "n = {n}, {u0} → {u1}: {w}");
                let w = check_partials(&e, &[], &[u0], &[u1], 1e-10, &[]).unwrap();
                assert!(w < 1e-6, "quasi-static n = {n}, {u0} → {u1}: {w}");
            }
        }
    }

    #[test]
    fn separated_and_pulling_states_carry_no_force() {
        let p = law(1.5, 0.3, 1e-5);
        assert_eq!(p.force_and_partials(0.5e-5, 1.0), (0.0, 0.0, 0.0));
        // Opening faster than 1/χ: the contact does not pull.
        assert_eq!(p.force_and_partials(3e-5, -4.0), (0.0, 0.0, 0.0));
        let (f, _, _) = p.force_and_partials(3e-5, 0.0);
        assert!((f - 2e7 * (2e-5f64).powf(1.5)).abs() < 1e-12 * f);
        assert!(law(0.5, 0.3, 0.0).validate().is_err());
        assert!(law(1.5, -0.3, 0.0).validate().is_err());
        assert!(law(1.5, 0.3, -1.0).validate().is_err());
    }

    #[test]
    fn restitution_and_damping_factor_are_inverse() {
        for e in [0.05, 0.3, 0.7, 0.95, 0.999] {
            for v in [0.01, 1.0, 30.0] {
                let chi = damping_factor(e, v).unwrap();
                let back = restitution(chi * v);
                // The relation cancels to O(x²) from terms of O(x): e to about ε/x.
                assert!((back - e).abs() < 1e-10, "e = {e}, v = {v}: {back}");
            }
        }
        assert_eq!(damping_factor(1.0, 2.0).unwrap(), 0.0);
        assert!(damping_factor(0.0, 1.0).is_err());
        assert!(damping_factor(0.5, 0.0).is_err());
    }

    /// Both explicit formulas are the small-damping limit of the exact relation, whose expansion
    /// gives `x = 3(1 − e²)/(2(1 + e³)) + O(x²)` → `3(1 − e)/2` as `e → 1`.
    #[test]
    fn explicit_formulas_approach_the_exact_relation_near_elastic_impact() {
        let e = 0.999;
        let exact = damping_factor(e, 1.0).unwrap();
        for approx in [
            damping_factor_hunt_crossley(e, 1.0).unwrap(),
            damping_factor_lankarani_nikravesh(e, 1.0).unwrap(),
        ] {
            assert!((approx - exact).abs() < 5e-3 * exact, "{approx} vs {exact}");
        }
    }
}
