//! The Iwan element ([`crate::element::iwan`], Segalman's four-parameter power-law model,
//! discretised into parallel Jenkins sliders) as a [`HystereticElement`] for harmonic balance.
//!
//! State: the slider positions `x_j` (m). One increment to `u1` is the return map of every
//! slider, `stretch_j = clamp(u1 − x_j, ±φ̄_j)`, `x_j ← u1 − stretch_j`,
//! `F = Σ k_j·stretch_j` (exact for any displacement path, see the element's module). Its exact
//! derivatives: a stuck slider (`|u1 − x_j| < φ̄_j`) has `∂x_j/∂x_j0 = 1` and contributes
//! `k_j` to `∂F/∂u1` and `−k_j` to `∂F/∂x_j0`; a slipping one has `∂x_j/∂u1 = 1` and no force
//! derivative (its force is `±k_j·φ̄_j`).

use crate::core::error::Result;
use crate::dynamics::nonlinear::{ContactStatus, HystereticElement, StepPartials};
use crate::element::iwan::{IwanElement, IwanParams};

/// An Iwan joint on one displacement component.
#[derive(Debug, Clone, PartialEq)]
pub struct Iwan {
    pub element: IwanElement,
}

impl Iwan {
    /// Discretise Segalman's element with `sliders` Jenkins sliders for the distributed part
    /// (plus one for the delta when `β > 0`).
    pub fn new(params: IwanParams, sliders: usize) -> Result<Self> {
        Ok(Self {
            element: IwanElement::new(params, sliders)?,
        })
    }
}

impl HystereticElement for Iwan {
    fn name(&self) -> &'static str {
        "iwan"
    }
    fn dofs(&self) -> usize {
        1
    }
    fn state_len(&self) -> usize {
        self.element.sliders.len()
    }
    fn virgin_state(&self, s: &mut [f64]) {
        s.fill(0.0);
    }
    fn state_scales(&self, scales: &mut [f64]) {
        for (s, j) in scales.iter_mut().zip(&self.element.sliders) {
            *s = j.slip_displacement;
        }
    }
    fn force_scale(&self) -> f64 {
        self.element.params.slip_force
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
        let m = self.element.sliders.len();
        let mut f = 0.0;
        for (j, sl) in self.element.sliders.iter().enumerate() {
            let trial = u - s0[j];
            let stuck = trial.abs() < sl.slip_displacement;
            let stretch = trial.clamp(-sl.slip_displacement, sl.slip_displacement);
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
            .element
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
    use crate::dynamics::aft::{self, AftSettings, Harmonics};
    use crate::dynamics::nonlinear::check_partials;

    /// Step derivatives against finite differences, with sliders stuck and slipping.
    #[test]
    fn partials_match_finite_differences() {
        let el = Iwan::new(IwanParams::new(2.0, 1e5, -0.4, 0.3).unwrap(), 8).unwrap();
        let m = el.state_len();
        let s0: Vec<f64> = (0..m).map(|j| 1e-6 * (j as f64 - 3.0)).collect();
        let scales = vec![1e-9; m];
        let w = check_partials(&el, &s0, &[0.0], &[7e-6], 1e-10, &scales).unwrap();
        assert!(w < 1e-6, "{w}");
    }

    /// The AFT cycle dissipates Segalman's closed form `D = 4R·A^{χ+3}/((χ+2)(χ+3))` within the
    /// discretisation error (40 sliders: 2 %), and its fundamental in-phase stiffness lies
    /// between the secant of the backbone and the stick stiffness.
    #[test]
    fn aft_cycle_dissipates_segalmans_energy() {
        let p = IwanParams::new(2.0, 1e5, -0.3, 0.5).unwrap();
        let el = Iwan::new(p, 40).unwrap();
        let h = Harmonics::new(3, true, Some(2048)).unwrap();
        for frac in [0.2, 0.5, 0.9] {
            let a = frac * p.phi_max();
            let c = aft::cycle_summary(&el, &h, &[a, 0.0, 0.0, 0.0], &AftSettings::default());
            let exact = p.dissipation_per_cycle(a);
            assert!(
                (c.dissipated_energy_j / exact - 1.0).abs() < 0.02,
                "A = {frac} φmax: {} vs {exact}",
                c.dissipated_energy_j
            );
            let r = aft::evaluate(&el, &h, &[a, 0.0, 0.0, 0.0], false, &AftSettings::default());
            let keq = r.forces[0] / a;
            assert!(keq < p.stiffness && keq > p.backbone(a) / a * 0.9, "{keq}");
        }
    }
}
