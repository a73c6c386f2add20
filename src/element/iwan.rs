//! Iwan element with a power-law distribution of slip strengths: Segalman's four-parameter
//! model of a lap joint.
//!
//! # Constitutive model
//! A continuum of Jenkins elements in parallel (Iwan 1966, *J. Appl. Mech.* 33:893), each a
//! spring in series with a slider; the element with slip displacement `φ` (its slider opens
//! when its spring is stretched by `φ`) has stiffness density `ρ(φ)`:
//!
//! ```text
//! ρ(φ) = R·φ^χ·[H(φ) − H(φ − φ_max)] + S·δ(φ − φ_max),        −1 < χ ≤ 0
//! ```
//!
//! (Segalman 2005, "A four-parameter Iwan model for lap-type joints", *J. Appl. Mech.*
//! 72:752–760). The power law reproduces the measured dissipation `D ∝ A^{χ+3}` of joints in
//! microslip; the delta `S` at `φ_max` makes the transition to macroslip abrupt. The four
//! parameters are the slip force `F_S`, the stiffness `K_T`, the exponent `χ` and
//! `β = S/(R·φ_max^{χ+1}/(χ+1))` (the share of stiffness in the delta relative to the
//! distributed part), with (Segalman 2005, eqs. 18–20), `θ = β + (χ+1)/(χ+2)`:
//!
//! ```text
//! φ_max = F_S·(1 + β)/(K_T·θ),   R = F_S·(χ+1)/(φ_max^{χ+2}·θ),   S = (F_S/φ_max)·β/θ
//! ```
//!
//! Closed forms (used to validate the discretisation, never by it):
//! - virgin loading ("backbone"), `0 ≤ u ≤ φ_max`: `F(u) = K_T·u − R·u^{χ+2}/((χ+1)(χ+2))`,
//!   and `F = F_S` beyond ([`IwanParams::backbone`]);
//! - after a reversal at `(u_r, F_r)`, Masing's rule (exact for any parallel Jenkins
//!   assembly): `F = F_r + s·2F_b(|u − u_r|/2)` with `s` the direction of motion
//!   ([`IwanParams::masing_branch`]);
//! - dissipation per cycle at amplitude `A ≤ φ_max`: `D = 4R·A^{χ+3}/((χ+2)(χ+3))`
//!   ([`IwanParams::dissipation_per_cycle`]).
//!
//! # Discretisation ([`IwanElement`])
//! The distributed part is split at `φ_j = φ_max·(j/N)^{1/(χ+1)}` into `N` intervals of equal
//! stiffness; each interval becomes one Jenkins element with the interval's stiffness
//! `k_j = ∫ρ dφ` and slip displacement `φ̄_j = ∫φρ dφ / ∫ρ dφ`, so that its slip force
//! `k_j·φ̄_j` equals the interval's; the delta is one more Jenkins element (`S`, `φ_max`).
//! Total stiffness and slip force are exact, and the backbone is exact at every node `φ_j`
//! (all elements below it slip, all above stick), piecewise linear between.
//!
//! # Time-discrete update
//! From a state (the slider positions) and a new displacement `u`, each Jenkins element is
//! updated by its return map: spring stretch `u − x_j` clamped to `±φ̄_j`. This is exact for
//! any displacement path (the update depends only on the end point of the increment, as for
//! any rate-independent assembly of ideal sliders). The tangent stiffness is the stiffness of
//! the elements that stick ([`IwanElement::tangent`]).
//!
//! Units: displacement m, force N, stiffness N/m (per element); `χ`, `β` dimensionless.

use crate::core::error::{require_positive, Error, Result};
use crate::element::hysteretic::{ContactStatus, HystereticElement, StepPartials};
use serde::{Deserialize, Serialize};

/// Segalman's four parameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct IwanParams {
    /// Slip force `F_S` (N): the force in macroslip.
    pub slip_force: f64,
    /// Stiffness `K_T` (N/m): the initial slope.
    pub stiffness: f64,
    /// Exponent `χ` of the slip-strength density, `−1 < χ ≤ 0`.
    pub chi: f64,
    /// `β ≥ 0`: stiffness in the delta at `φ_max` relative to the distributed part.
    pub beta: f64,
}

impl IwanParams {
    /// Build and validate (`F_S > 0`, `K_T > 0`, `−1 < χ ≤ 0`, `β ≥ 0`, all finite).
    pub fn new(slip_force: f64, stiffness: f64, chi: f64, beta: f64) -> Result<Self> {
        require_positive("slip_force", slip_force)?;
        require_positive("stiffness", stiffness)?;
        if !(chi.is_finite() && chi > -1.0 && chi <= 0.0) {
            return Err(Error::param(
                "chi",
                format!("must satisfy -1 < χ <= 0, got {chi}"),
            ));
        }
        if !(beta.is_finite() && beta >= 0.0) {
            return Err(Error::param(
                "beta",
                format!("must be finite and >= 0, got {beta}"),
            ));
        }
        Ok(Self {
            slip_force,
            stiffness,
            chi,
            beta,
        })
    }

    fn theta(&self) -> f64 {
        self.beta + (self.chi + 1.0) / (self.chi + 2.0)
    }

    /// Largest slip displacement of the distribution, `φ_max` (m): macroslip beyond.
    pub fn phi_max(&self) -> f64 {
        self.slip_force * (1.0 + self.beta) / (self.stiffness * self.theta())
    }

    /// Coefficient `R` of the density `R·φ^χ` (N/m^{χ+2}).
    pub fn density_coefficient(&self) -> f64 {
        self.slip_force * (self.chi + 1.0) / (self.phi_max().powf(self.chi + 2.0) * self.theta())
    }

    /// Stiffness `S` of the delta at `φ_max` (N/m).
    pub fn delta_stiffness(&self) -> f64 {
        self.slip_force / self.phi_max() * self.beta / self.theta()
    }

    /// Virgin loading curve `F(u)` (N), odd in `u`.
    pub fn backbone(&self, u: f64) -> f64 {
        let a = u.abs();
        let f = if a >= self.phi_max() {
            self.slip_force
        } else {
            let c = self.chi;
            self.stiffness * a
                - self.density_coefficient() * a.powf(c + 2.0) / ((c + 1.0) * (c + 2.0))
        };
        f * u.signum()
    }

    /// Force at `u` on the branch after a reversal at `(u_r, F_r)` (Masing's rule).
    pub fn masing_branch(&self, u_r: f64, f_r: f64, u: f64) -> f64 {
        f_r + 2.0 * self.backbone(0.5 * (u - u_r))
    }

    /// Energy dissipated per cycle of amplitude `A ≤ φ_max` (J), after the first loading.
    pub fn dissipation_per_cycle(&self, amplitude: f64) -> f64 {
        let (a, c) = (amplitude.abs().min(self.phi_max()), self.chi);
        4.0 * self.density_coefficient() * a.powf(c + 3.0) / ((c + 2.0) * (c + 3.0))
    }
}

/// One Jenkins element of the discretisation: stiffness (N/m) and slip displacement (m).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Slider {
    /// Spring stiffness of the slider (N/m).
    pub stiffness: f64,
    /// Spring stretch at which the slider slips, `φ̄` (m); its slip force is `stiffness·φ̄`.
    pub slip_displacement: f64,
}

impl Slider {
    /// Return map at displacement `u` of the slider at position `x`: the spring stretch
    /// `clamp(u − x, ±φ̄)` (the new position is `u − stretch`), and whether it sticks
    /// (`|u − x| < φ̄`).
    pub fn stretch(&self, u: f64, x: f64) -> (f64, bool) {
        let trial = u - x;
        (
            trial.clamp(-self.slip_displacement, self.slip_displacement),
            trial.abs() < self.slip_displacement,
        )
    }
}

/// State of an Iwan element: displacement, slider positions and force.
#[derive(Debug, Clone, PartialEq)]
pub struct IwanState {
    /// Element displacement `u` (m).
    pub displacement: f64,
    /// Position `x_j` of each slider (m); spring stretch `u − x_j`.
    pub slider_positions: Vec<f64>,
    /// Force (N).
    pub force: f64,
}

/// A discretised Iwan element (module documentation).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct IwanElement {
    /// The four Iwan parameters.
    pub params: IwanParams,
    /// The Jenkins sliders of the discretisation; the delta's (when `β > 0`) last.
    pub sliders: Vec<Slider>,
}

impl IwanElement {
    /// Discretise with `n` Jenkins elements for the distributed part (plus one for the delta
    /// when `β > 0`). Errors: `n = 0`, invalid parameters.
    pub fn new(params: IwanParams, n: usize) -> Result<Self> {
        let p = IwanParams::new(params.slip_force, params.stiffness, params.chi, params.beta)?;
        if n == 0 {
            return Err(Error::param("n", "at least one slider is needed"));
        }
        let (c, r, pm) = (p.chi, p.density_coefficient(), p.phi_max());
        let node = |j: usize| pm * (j as f64 / n as f64).powf(1.0 / (c + 1.0));
        let mut sliders: Vec<Slider> = (1..=n)
            .map(|j| {
                let (a, b) = (node(j - 1), node(j));
                let k = r * (b.powf(c + 1.0) - a.powf(c + 1.0)) / (c + 1.0);
                let m = r * (b.powf(c + 2.0) - a.powf(c + 2.0)) / (c + 2.0);
                Slider {
                    stiffness: k,
                    slip_displacement: m / k,
                }
            })
            .collect();
        if p.beta > 0.0 {
            sliders.push(Slider {
                stiffness: p.delta_stiffness(),
                slip_displacement: pm,
            });
        }
        Ok(Self { params: p, sliders })
    }

    /// The unloaded state at displacement `u0`.
    pub fn virgin_state(&self, u0: f64) -> IwanState {
        IwanState {
            displacement: u0,
            slider_positions: vec![u0; self.sliders.len()],
            force: 0.0,
        }
    }

    /// Advance `state` to displacement `u` (return map of every Jenkins element).
    pub fn step(&self, state: &mut IwanState, u: f64) {
        let mut f = 0.0;
        for (x, s) in state.slider_positions.iter_mut().zip(&self.sliders) {
            let (stretch, _) = s.stretch(u, *x);
            *x = u - stretch;
            f += s.stiffness * stretch;
        }
        state.displacement = u;
        state.force = f;
    }

    /// Tangent stiffness (N/m) for a further move in direction `direction` (±1): the
    /// stiffness of the elements that do not slip in that direction.
    pub fn tangent(&self, state: &IwanState, direction: f64) -> f64 {
        state
            .slider_positions
            .iter()
            .zip(&self.sliders)
            .filter(|(x, s)| {
                let stretch = state.displacement - **x;
                stretch * direction.signum() < s.slip_displacement * (1.0 - 1e-12)
            })
            .map(|(_, s)| s.stiffness)
            .sum()
    }

    /// Force history of a virgin element driven by the displacements `u` (N).
    pub fn integrate(&self, u: &[f64]) -> Result<Vec<f64>> {
        if let Some(i) = u.iter().position(|v| !v.is_finite()) {
            return Err(Error::param("u", format!("sample {i} is not finite")));
        }
        let Some(&u0) = u.first() else {
            return Ok(vec![]);
        };
        let mut st = self.virgin_state(u0);
        Ok(u.iter()
            .map(|&ui| {
                self.step(&mut st, ui);
                st.force
            })
            .collect())
    }
}

/// The discretised Iwan element on one displacement component as a [`HystereticElement`]. State:
/// the slider positions `x_j` (m). One increment to `u1` is the return map of every slider
/// ([`Slider::stretch`], exact for any displacement path), `F = Σ k_j·stretch_j`. Its exact
/// derivatives: a stuck slider (`|u1 − x_j| < φ̄_j`) has `∂x_j/∂x_j0 = 1` and contributes `k_j`
/// to `∂F/∂u1` and `−k_j` to `∂F/∂x_j0`; a slipping one has `∂x_j/∂u1 = 1` and no force
/// derivative (its force is `±k_j·φ̄_j`).
impl HystereticElement for IwanElement {
    fn name(&self) -> &'static str {
        "iwan"
    }
    fn dofs(&self) -> usize {
        1
    }
    fn state_len(&self) -> usize {
        self.sliders.len()
    }
    fn virgin_state(&self, s: &mut [f64]) {
        s.fill(0.0);
    }
    fn state_scales(&self, scales: &mut [f64]) {
        for (s, j) in scales.iter_mut().zip(&self.sliders) {
            *s = j.slip_displacement;
        }
    }
    fn force_scale(&self) -> f64 {
        self.params.slip_force
    }
    fn step(
        &self,
        s0: &[f64],
        _u0: &[f64],
        u1: &[f64],
        s1: &mut [f64],
        f1: &mut [f64],
        mut partials: Option<&mut StepPartials>,
    ) {
        let u = u1[0];
        let m = self.sliders.len();
        let mut f = 0.0;
        for (j, sl) in self.sliders.iter().enumerate() {
            let (stretch, stuck) = sl.stretch(u, s0[j]);
            s1[j] = u - stretch;
            f += sl.stiffness * stretch;
            if let Some(p) = partials.as_deref_mut() {
                if stuck {
                    p.ds_ds0[j * m + j] = 1.0;
                    p.df_ds0[j] = -sl.stiffness;
                    p.df_du1[0] += sl.stiffness;
                } else {
                    p.ds_du1[j] = 1.0;
                }
            }
        }
        f1[0] = f;
    }
    /// Gross slip when every slider slips, otherwise stick (including microslip).
    fn status(&self, s: &[f64], u: &[f64], _f: &[f64]) -> ContactStatus {
        let all_slip = self
            .sliders
            .iter()
            .zip(s)
            .all(|(sl, x)| (u[0] - x).abs() >= sl.slip_displacement * (1.0 - 1e-12));
        if all_slip {
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
    use crate::element::{dissipated_energy, sine_history};

    fn params() -> IwanParams {
        IwanParams::new(100.0, 2e6, -0.5, 0.3).unwrap()
    }

    #[test]
    fn segalman_parameters_are_consistent() {
        let p = params();
        let (c, r, s, pm) = (
            p.chi,
            p.density_coefficient(),
            p.delta_stiffness(),
            p.phi_max(),
        );
        // K_T = ∫ρ, F_S = ∫φρ, β = S/(R φ_max^{χ+1}/(χ+1)).
        let kd = r * pm.powf(c + 1.0) / (c + 1.0);
        assert!(((kd + s) / p.stiffness - 1.0).abs() < 1e-12);
        assert!(((r * pm.powf(c + 2.0) / (c + 2.0) + s * pm) / p.slip_force - 1.0).abs() < 1e-12);
        assert!((s / kd - p.beta).abs() < 1e-12);
        assert!((p.backbone(pm) - p.slip_force).abs() < 1e-9 * p.slip_force);
        assert!(IwanParams::new(100.0, 2e6, -1.0, 0.3).is_err());
        assert!(IwanParams::new(100.0, 2e6, 0.1, 0.3).is_err());
        assert!(IwanParams::new(100.0, -2e6, -0.5, 0.3).is_err());
        assert!(IwanElement::new(params(), 0).is_err());
    }

    /// Monotonic loading and a Masing branch against the closed forms: within 0.5 % of F_S
    /// with 200 sliders (exact at the nodes, piecewise linear between).
    #[test]
    fn backbone_and_masing_branch_match_closed_forms() {
        let p = params();
        let el = IwanElement::new(p, 200).unwrap();
        let pm = p.phi_max();
        let up: Vec<f64> = (0..=400).map(|i| 1.5 * pm * i as f64 / 400.0).collect();
        let f = el.integrate(&up).unwrap();
        let worst = up
            .iter()
            .zip(&f)
            .map(|(&u, &fi)| (fi - p.backbone(u)).abs())
            .fold(0.0, f64::max);
        assert!(worst < 5e-3 * p.slip_force, "backbone error {worst}");
        // Load to 0.6 φ_max (microslip), reverse to −0.6 φ_max.
        let ur = 0.6 * pm;
        let mut path: Vec<f64> = (0..=200).map(|i| ur * i as f64 / 200.0).collect();
        path.extend((1..=400).map(|i| ur - 2.0 * ur * i as f64 / 400.0));
        let f = el.integrate(&path).unwrap();
        let fr = f[200];
        let worst = (201..path.len())
            .map(|i| (f[i] - p.masing_branch(ur, fr, path[i])).abs())
            .fold(0.0, f64::max);
        assert!(worst < 5e-3 * p.slip_force, "Masing error {worst}");
        // Reversal tip: the unloaded loop closes on the virgin curve's mirror.
        assert!((f[600] + p.backbone(ur)).abs() < 5e-3 * p.slip_force);
    }

    /// Dissipation per cycle within 2 % of 4R A^{χ+3}/((χ+2)(χ+3)), and its log-log slope
    /// χ + 3 in microslip (the joint signature the power law is chosen for).
    #[test]
    fn dissipation_follows_the_power_law() {
        let p = params();
        let el = IwanElement::new(p, 400).unwrap();
        let per = 2000;
        let energy = |a: f64| {
            let q = sine_history(a, 2, per);
            let f = el.integrate(&q).unwrap();
            let n = q.len();
            dissipated_energy(&q[n - per - 1..], &f[n - per - 1..])
        };
        let pm = p.phi_max();
        for a in [0.2 * pm, 0.5 * pm, 0.9 * pm] {
            let (d, exact) = (energy(a), p.dissipation_per_cycle(a));
            assert!((d / exact - 1.0).abs() < 0.02, "A = {a}: {d} vs {exact}");
        }
        let slope = (energy(0.4 * pm) / energy(0.2 * pm)).ln() / 2f64.ln();
        assert!((slope - (p.chi + 3.0)).abs() < 0.05, "slope {slope}");
        // Macroslip: Jenkins-like loop energy 4 F_S (A − ...) grows linearly in A.
        let (d2, d3) = (energy(2.0 * pm), energy(3.0 * pm));
        assert!(((d3 - d2) / (pm * 4.0 * p.slip_force) - 1.0).abs() < 0.01);
    }

    #[test]
    fn tangent_matches_a_finite_difference() {
        let el = IwanElement::new(params(), 100).unwrap();
        let pm = el.params.phi_max();
        let mut st = el.virgin_state(0.0);
        for u in [0.3 * pm, 0.1 * pm] {
            el.step(&mut st, u);
        }
        for dir in [1.0, -1.0] {
            let h = 1e-9 * pm * dir;
            let mut probe = st.clone();
            el.step(&mut probe, st.displacement + h);
            let fd = (probe.force - st.force) / h;
            let k = el.tangent(&st, dir);
            assert!(
                (fd - k).abs() <= 1e-6 * el.params.stiffness,
                "{dir}: {fd} vs {k}"
            );
        }
        // Initially every slider sticks: K_T.
        let v = el.virgin_state(0.0);
        assert!((el.tangent(&v, 1.0) / el.params.stiffness - 1.0).abs() < 1e-12);
    }

    /// Step derivatives against finite differences, with sliders stuck and slipping.
    #[test]
    fn partials_match_finite_differences() {
        let el = IwanElement::new(IwanParams::new(2.0, 1e5, -0.4, 0.3).unwrap(), 8).unwrap();
        let m = el.state_len();
        let s0: Vec<f64> = (0..m).map(|j| 1e-6 * (j as f64 - 3.0)).collect();
        let scales = vec![1e-9; m];
        let w = check_partials(&el, &s0, &[0.0], &[7e-6], 1e-10, &scales).unwrap();
        assert!(w < 1e-6, "{w}");
    }
}
