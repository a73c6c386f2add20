//! Thin-layer interface law: the joint's interface as a thin layer of a virtual elastic–plastic
//! material (thickness `t`, area `A`) with elastic modulus `Ee`, plastic (hardening) modulus
//! `Ep`, yield stress `Sy` and a smooth elastic–plastic transition of exponent `n`. The layer's
//! strain is `ε = u/t` for the relative displacement `u` across it, and the element force is
//! `F = A·σ(ε)`.
//!
//! The smooth transition with kinematic hardening and memory of the last reversal is the
//! Menegotto–Pinto law (Menegotto & Pinto 1973, IABSE Symposium, Lisbon; in the form of
//! Filippou, Popov & Bertero 1983, EERC report 83/19, eq. 2.1):
//!
//! ```text
//! σ* = b·ε* + (1 − b)·ε*/(1 + |ε*|ⁿ)^{1/n},      b = Ep/Ee,
//! ε* = (ε − εr)/(ε0 − εr),  σ* = (σ − σr)/(σ0 − σr)
//! ```
//!
//! with `(εr, σr)` the last reversal point (the origin for the virgin layer) and `(ε0, σ0)` the
//! intersection of the elastic line through it (slope `Ee`) with the hardening asymptote of the
//! current loading direction `d = ±1`, `σ = d·Sy·(1 − b) + Ep·ε` (kinematic hardening: the two
//! asymptotes are the lines through `(±εy, ±Sy)`, `εy = Sy/Ee`, with slope `Ep`). The virgin curve is
//! `σ/Sy = b·x + (1 − b)·x/(1 + |x|ⁿ)^{1/n}`, `x = ε/εy`; `n → ∞` gives the bilinear
//! elastic–plastic layer.
//!
//! State: `(εr, σr, d)` (`d = 0` for the virgin layer). A step from `u0` to `u1` that moves
//! against `d` reverses at `u0` (the AFT steps to located reversals, so every step is
//! monotone). The partial derivatives are exact (`σ = σr + Ee·Δε0·σ*(ξ)`, `ξ = (ε − εr)/Δε0`,
//! `Δε0 = ε0 − εr`; see [`ThinLayer::stress`]).
//!
//! Units: `Ee`, `Ep`, `Sy` in Pa, `A` in m², `t` in m, `u` in m, `F` in N.

use crate::core::error::{require_positive, Error, Result};
use crate::element::hysteretic::{ContactStatus, HystereticElement, StepPartials};

/// Thin-layer parameters (module documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThinLayer {
    /// Elastic modulus `Ee` (Pa), > 0.
    pub elastic_modulus: f64,
    /// Plastic (hardening) modulus `Ep` (Pa), `0 ≤ Ep < Ee`.
    pub plastic_modulus: f64,
    /// Yield stress `Sy` (Pa), > 0.
    pub yield_stress: f64,
    /// Transition exponent `n` (–), > 0 (larger: sharper yield).
    pub exponent: f64,
    /// Layer area `A` (m²), > 0.
    pub area: f64,
    /// Layer thickness `t` (m), > 0.
    pub thickness: f64,
}

/// Stress at a strain for a given reversal state, with its derivatives.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LayerStress {
    /// `σ` (Pa).
    pub stress: f64,
    /// `∂σ/∂ε` (Pa): the tangent modulus.
    pub d_strain: f64,
    /// `∂σ/∂εr` (Pa).
    pub d_eps_r: f64,
    /// `∂σ/∂σr` (–).
    pub d_sig_r: f64,
}

impl ThinLayer {
    /// Build and validate.
    pub fn new(
        elastic_modulus: f64,
        plastic_modulus: f64,
        yield_stress: f64,
        exponent: f64,
        area: f64,
        thickness: f64,
    ) -> Result<Self> {
        require_positive("elastic_modulus", elastic_modulus)?;
        require_positive("yield_stress", yield_stress)?;
        require_positive("exponent", exponent)?;
        require_positive("area", area)?;
        require_positive("thickness", thickness)?;
        if !(plastic_modulus.is_finite()
            && plastic_modulus >= 0.0
            && plastic_modulus < elastic_modulus)
        {
            return Err(Error::param(
                "plastic_modulus",
                format!(
                    "must be ≥ 0 and below the elastic modulus {elastic_modulus}, got {plastic_modulus}"
                ),
            ));
        }
        Ok(Self {
            elastic_modulus,
            plastic_modulus,
            yield_stress,
            exponent,
            area,
            thickness,
        })
    }

    /// Hardening ratio `b = Ep/Ee`.
    pub fn hardening_ratio(&self) -> f64 {
        self.plastic_modulus / self.elastic_modulus
    }

    /// Yield strain `εy = Sy/Ee`.
    pub fn yield_strain(&self) -> f64 {
        self.yield_stress / self.elastic_modulus
    }

    /// Stress of the branch from the reversal `(εr, σr)` in direction `d = ±1` at strain `ε`,
    /// with `∂σ/∂ε = Ee·σ*'(ξ)`,
    /// `∂σ/∂εr = Ee·(b/(1 − b)·σ* − (1 + ξ·b/(1 − b))·σ*')` and
    /// `∂σ/∂σr = 1 + (ξ·σ*' − σ*)/(1 − b)`, where `σ*' = b + (1 − b)·(1 + |ξ|ⁿ)^{−1/n − 1}`
    /// (from `∂Δε0/∂εr = b/(1 − b)` and `∂Δε0/∂σr = −1/(Ee·(1 − b))`).
    pub fn stress(&self, eps: f64, eps_r: f64, sig_r: f64, d: f64) -> LayerStress {
        let (ee, b, n) = (self.elastic_modulus, self.hardening_ratio(), self.exponent);
        let eps0 = (d * self.yield_stress * (1.0 - b) - sig_r + ee * eps_r) / (ee * (1.0 - b));
        let de0 = eps0 - eps_r;
        let xi = (eps - eps_r) / de0;
        let w = 1.0 + xi.abs().powf(n);
        let root = w.powf(-1.0 / n);
        let s_star = b * xi + (1.0 - b) * xi * root;
        let ds_star = b + (1.0 - b) * root / w;
        let c = b / (1.0 - b);
        LayerStress {
            stress: sig_r + ee * de0 * s_star,
            d_strain: ee * ds_star,
            d_eps_r: ee * (c * s_star - (1.0 + xi * c) * ds_star),
            d_sig_r: 1.0 + (xi * ds_star - s_star) / (1.0 - b),
        }
    }
}

impl HystereticElement for ThinLayer {
    fn name(&self) -> &'static str {
        "thin-layer"
    }
    fn dofs(&self) -> usize {
        1
    }
    fn state_len(&self) -> usize {
        3
    }
    fn virgin_state(&self, s: &mut [f64]) {
        s.fill(0.0);
    }
    fn state_scales(&self, scales: &mut [f64]) {
        scales.copy_from_slice(&[self.yield_strain(), self.yield_stress, 1.0]);
    }
    fn force_scale(&self) -> f64 {
        self.yield_stress * self.area
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
        let t = self.thickness;
        let (e0, e1) = (u0[0] / t, u1[0] / t);
        let step = e1 - e0;
        // ∂(εr1, σr1)/∂(εr0, σr0) and ∂(εr1, σr1)/∂u0.
        let mut jac_s = [[1.0, 0.0], [0.0, 1.0]];
        let mut jac_u0 = [0.0, 0.0];
        s1.copy_from_slice(s0);
        if s0[2] == 0.0 {
            if step != 0.0 {
                // Virgin layer: the first branch starts at the origin.
                s1.copy_from_slice(&[0.0, 0.0, step.signum()]);
                jac_s = [[0.0; 2]; 2];
            }
        } else if s0[2] * step < 0.0 {
            // Reversal at u0: the new branch starts where the old one is at ε0.
            let r = self.stress(e0, s0[0], s0[1], s0[2]);
            s1.copy_from_slice(&[e0, r.stress, -s0[2]]);
            jac_s = [[0.0, 0.0], [r.d_eps_r, r.d_sig_r]];
            jac_u0 = [1.0 / t, r.d_strain / t];
        }
        let (stress, d_e, d_er, d_sr) = if s1[2] == 0.0 {
            (self.elastic_modulus * e1, self.elastic_modulus, 0.0, 0.0)
        } else {
            let r = self.stress(e1, s1[0], s1[1], s1[2]);
            (r.stress, r.d_strain, r.d_eps_r, r.d_sig_r)
        };
        f1[0] = self.area * stress;
        if let Some(p) = partials {
            for (r, (row, du0)) in jac_s.iter().zip(jac_u0).enumerate() {
                p.ds_ds0[r * 3..r * 3 + 2].copy_from_slice(row);
                p.ds_du0[r] = du0;
            }
            // The direction is a discrete function of the path (∂d1/∂d0 = 0 almost everywhere):
            // as a neutral direction of the AFT's periodicity Newton it would keep the direction
            // of the initial loading even where the periodic cycle arrives the other way.
            let a = self.area;
            for (c, df) in p.df_ds0[..2].iter_mut().enumerate() {
                *df = a * (d_er * jac_s[0][c] + d_sr * jac_s[1][c]);
            }
            p.df_du0[0] = a * (d_er * jac_u0[0] + d_sr * jac_u0[1]);
            p.df_du1[0] = a * d_e / t;
        }
    }
    fn status(&self, s: &[f64], u: &[f64], _f: &[f64]) -> ContactStatus {
        // Yielding once the tangent has fallen half-way from Ee to Ep.
        if s[2] == 0.0 {
            return ContactStatus::Stick;
        }
        let r = self.stress(u[0] / self.thickness, s[0], s[1], s[2]);
        let mid = 0.5 * (self.elastic_modulus + self.plastic_modulus);
        if r.d_strain < mid {
            ContactStatus::Slip
        } else {
            ContactStatus::Stick
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::hysteretic::check_partials;

    fn layer(n: f64) -> ThinLayer {
        ThinLayer::new(2e11, 2e10, 3e8, n, 1e-4, 1e-4).unwrap()
    }

    #[test]
    fn partials_match_finite_differences() {
        for n in [1.0, 2.5, 8.0] {
            let l = layer(n);
            let ey = l.yield_strain() * l.thickness;
            let branch = |er: f64, sr: f64, d: f64| [er, sr, d];
            for (s0, u0, u1) in [
                // Virgin loading beyond yield.
                (branch(0.0, 0.0, 0.0), 0.0, 2.0 * ey),
                // Continuing a branch.
                (branch(-1e-3, -2e8, 1.0), 0.3 * ey, 1.7 * ey),
                // Reversal from a loading branch.
                (branch(-1e-3, -2e8, 1.0), 1.5 * ey, -0.8 * ey),
                (branch(2e-3, 3.1e8, -1.0), 0.4 * ey, 2.5 * ey),
            ] {
                // A zero step leaves out the discrete direction `d` (its quotient is 0/0).
                let w =
                    check_partials(&l, &s0, &[u0], &[u1], 1e-3 * ey, &[1e-9, 1e2, 0.0]).unwrap();
                assert!(w < 1e-6, "n = {n}, {s0:?}, {u0} → {u1}: {w}");
            }
        }
    }

    /// The virgin curve is `σ/Sy = b·x + (1 − b)·x/(1 + |x|ⁿ)^{1/n}` (`x = ε/εy`), the elastic
    /// slope `Ee` at the origin and `Ep` far beyond yield.
    #[test]
    fn virgin_curve_is_the_closed_form() {
        let l = layer(3.0);
        let (ey, b) = (l.yield_strain(), l.hardening_ratio());
        let mut s = [0.0; 3];
        let mut f = [0.0];
        let mut u = 0.0;
        for x in [0.1, 0.5, 1.0, 2.0, 10.0] {
            let u1 = x * ey * l.thickness;
            let mut s1 = [0.0; 3];
            l.step(&s, &[u], &[u1], &mut s1, &mut f, None);
            let exact = l.yield_stress
                * l.area
                * (b * x + (1.0 - b) * x / (1.0 + x.powf(3.0)).powf(1.0 / 3.0));
            assert!(
                (f[0] - exact).abs() < 1e-12 * exact,
                "x = {x}: {} vs {exact}",
                f[0]
            );
            s = s1;
            u = u1;
        }
        assert!(ThinLayer::new(2e11, 2e11, 3e8, 3.0, 1e-4, 1e-4).is_err());
        assert!(ThinLayer::new(2e11, 1e10, 3e8, 0.0, 1e-4, 1e-4).is_err());
    }
}
