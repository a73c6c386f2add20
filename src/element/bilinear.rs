//! Bilinear normal contact: a unilateral contact whose stiffness changes from `k1` to `k2` at an
//! indentation threshold `δt` (a stiffening contact as more of the interface closes, or a
//! softening one), without memory, the piecewise-linear model of vibro-impact studies (e.g.
//! Shaw & Holmes 1983, *J. Sound Vib.* 90:129, for the impacting oscillator with `k1 = k2`):
//!
//! ```text
//! N(δ) = 0                         δ ≤ 0        (separated: the contact never pulls)
//!      = k1·δ                      0 < δ ≤ δt
//!      = k1·δt + k2·(δ − δt)       δ > δt       (max(0, ·) when k2 < 0 would make it pull)
//! ```
//!
//! The indentation at the static equilibrium `u = 0` is `δ0` (negative: an open gap of `−δ0`),
//! so `δ = δ0 + u` with `u` the approach along the joint direction (`u > 0` closing), and the
//! element returns the change from the static preload, `f = N(δ0 + u) − N(δ0)` (the preload is
//! balanced by the static loads that produced it, [`crate::element::hysteretic`]).
//!
//! Units: `u`, `δ0`, `δt` in m, `N` in N, `k1`, `k2` in N/m.

use crate::core::error::{Error, Result};
use crate::element::hysteretic::{ContactStatus, HystereticElement, StepPartials};

/// Contact force `N(δ)` and its slope `dN/dδ` at indentation `δ` (module documentation; the
/// slope at a kink is the one of the side towards larger `δ`).
pub fn contact_force(k1: f64, k2: f64, threshold: f64, delta: f64) -> (f64, f64) {
    if delta <= 0.0 {
        (0.0, 0.0)
    } else if delta <= threshold {
        (k1 * delta, k1)
    } else {
        let n = k1 * threshold + k2 * (delta - threshold);
        if n > 0.0 {
            (n, k2)
        } else {
            (0.0, 0.0)
        }
    }
}

/// Bilinear normal contact on one displacement component (module documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BilinearContact {
    /// Stiffness `k1` below the threshold (N/m), > 0.
    pub k1: f64,
    /// Stiffness `k2` beyond the threshold (N/m), finite (may be below `k1`, or negative).
    pub k2: f64,
    /// Indentation `δt` where the stiffness changes (m), > 0.
    pub threshold: f64,
    /// Indentation at the static equilibrium `δ0` (m); negative: an open gap of `−δ0`.
    pub static_indentation: f64,
}

impl BilinearContact {
    /// Build and validate: `k1 > 0`, `k2` finite, `δt > 0`, `δ0` finite and, when the contact is
    /// closed at equilibrium, with a positive preload `N(δ0) > 0`.
    pub fn new(k1: f64, k2: f64, threshold: f64, static_indentation: f64) -> Result<Self> {
        crate::core::error::require_positive("k1", k1)?;
        crate::core::error::require_finite("k2", k2)?;
        crate::core::error::require_positive("threshold", threshold)?;
        crate::core::error::require_finite("static_indentation", static_indentation)?;
        if static_indentation > 0.0 && contact_force(k1, k2, threshold, static_indentation).0 <= 0.0
        {
            return Err(Error::param(
                "static_indentation",
                format!(
                    "{static_indentation} m is beyond the indentation where the contact force \
                     returns to zero (k2 < 0): no static preload there"
                ),
            ));
        }
        Ok(Self {
            k1,
            k2,
            threshold,
            static_indentation,
        })
    }

    /// The static preload `N(δ0)` (N).
    pub fn preload(&self) -> f64 {
        contact_force(self.k1, self.k2, self.threshold, self.static_indentation).0
    }
}

impl BilinearContact {
    /// Force change `N(δ0 + u) − N(δ0)` and tangent `dN/dδ` at the approach `u`.
    pub fn force_and_stiffness(&self, u: f64) -> (f64, f64) {
        let (n, k) = contact_force(
            self.k1,
            self.k2,
            self.threshold,
            self.static_indentation + u,
        );
        (n - self.preload(), k)
    }
}

impl HystereticElement for BilinearContact {
    fn name(&self) -> &'static str {
        "bilinear"
    }
    fn dofs(&self) -> usize {
        1
    }
    fn state_len(&self) -> usize {
        0
    }
    fn virgin_state(&self, _s: &mut [f64]) {}
    fn state_scales(&self, _scales: &mut [f64]) {}
    fn force_scale(&self) -> f64 {
        self.k1 * self.threshold
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
        let (f, k) = self.force_and_stiffness(u1[0]);
        f1[0] = f;
        if let Some(p) = partials {
            p.df_du1[0] = k;
        }
    }
    /// [`ContactStatus::Separated`] where the contact is open, [`ContactStatus::Stick`] (closed)
    /// otherwise.
    fn status(&self, _s: &[f64], u: &[f64], _f: &[f64]) -> ContactStatus {
        if contact_force(
            self.k1,
            self.k2,
            self.threshold,
            self.static_indentation + u[0],
        )
        .0 > 0.0
        {
            ContactStatus::Stick
        } else {
            ContactStatus::Separated
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::hysteretic::check_partials;

    #[test]
    fn branches_preload_and_separation() {
        let b = BilinearContact::new(2.0, 5.0, 1.0, 0.5).unwrap();
        assert_eq!(b.preload(), 1.0);
        assert_eq!(b.force_and_stiffness(0.0), (0.0, 2.0));
        // Beyond the threshold: 2·1 + 5·0.5 − 1.
        assert_eq!(b.force_and_stiffness(1.0), (3.5, 5.0));
        // Separated: the preload is lost, nothing pulls.
        assert_eq!(b.force_and_stiffness(-2.0), (-1.0, 0.0));
        // A gap: no force until it closes.
        let g = BilinearContact::new(2.0, 5.0, 1.0, -0.25).unwrap();
        assert_eq!(g.force_and_stiffness(0.2), (0.0, 0.0));
        assert_eq!(g.force_and_stiffness(0.75), (1.0, 2.0));
        assert_eq!(g.status(&[], &[0.2], &[0.0]), ContactStatus::Separated);
        assert_eq!(g.status(&[], &[0.75], &[1.0]), ContactStatus::Stick);
        // A softening branch that would pull is cut.
        assert_eq!(contact_force(2.0, -1.0, 1.0, 4.0), (0.0, 0.0));
        assert!(BilinearContact::new(2.0, -1.0, 1.0, 4.0).is_err());
        assert!(BilinearContact::new(0.0, 1.0, 1.0, 0.0).is_err());
        assert!(BilinearContact::new(1.0, 1.0, 0.0, 0.0).is_err());
    }

    #[test]
    fn partials_match_finite_differences_on_every_branch() {
        let b = BilinearContact::new(2e6, 7e6, 1e-5, 3e-6).unwrap();
        for u in [-1e-5, 1e-6, 2e-5] {
            let w = check_partials(&b, &[], &[0.0], &[u], 1e-10, &[]).unwrap();
            assert!(w < 1e-8, "u = {u}: {w}");
        }
    }
}
