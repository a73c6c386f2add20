//! The parameter record of a contact element: normal contact stiffness `kn` and the Valanis
//! tangential parameters `E0, k, μ, Et` ([`crate::element::valanis`]), in the order of the
//! calibration table's and the element table's columns.
//!
//! Two types carry the units:
//!
//! | field | [`ContactParamsPerArea`] (calibration table) | [`ContactParams`] (element table, dynamics) |
//! |---|---|---|
//! | `kn` | N/m³ (Pa/m) | N/m |
//! | `E0` | N/m³ (Pa/m) | N/m |
//! | `k` | – | – |
//! | `μ` | – | – |
//! | `Et` | N/m³ (Pa/m) | N/m |
//!
//! and [`ContactParamsPerArea::over_area`] is the one place where a record per unit nominal
//! area becomes the record of an element of given area (stiffnesses × area, `k` and `μ` as they
//! are).

use crate::core::error::Result;
use crate::element::valanis::ValanisParams;

/// Contact-element parameters per unit nominal area (a row of the calibration table).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ContactParamsPerArea {
    /// Normal contact stiffness per unit area, `dp/dδ` (N/m³ = Pa/m).
    pub kn_n_per_m3: f64,
    /// Valanis initial-loading stiffness per unit area (N/m³).
    pub e0_n_per_m3: f64,
    /// Valanis shape parameter, `0 ≤ k < 1` (–).
    pub k: f64,
    /// Friction coefficient (–).
    pub mu: f64,
    /// Valanis residual stiffness per unit area (N/m³).
    pub et_n_per_m3: f64,
}

impl ContactParamsPerArea {
    /// The record of an element of nominal area `area_m2` (m²): `kn = kn″·A`, `E0 = E0″·A`,
    /// `Et = Et″·A` (N/m from N/m³ × m²); `k` and `μ` as they are.
    pub fn over_area(&self, area_m2: f64) -> ContactParams {
        ContactParams {
            kn_n_per_m: self.kn_n_per_m3 * area_m2,
            e0_n_per_m: self.e0_n_per_m3 * area_m2,
            k: self.k,
            mu: self.mu,
            et_n_per_m: self.et_n_per_m3 * area_m2,
        }
    }

    /// The Valanis parameters per unit area (stiffnesses in N/m³, forces in Pa), validated.
    pub fn valanis(&self) -> Result<ValanisParams> {
        ValanisParams::new(self.e0_n_per_m3, self.k, self.et_n_per_m3, self.mu)
    }
}

/// Contact-element parameters per element (a row of the element table).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ContactParams {
    /// Normal contact stiffness (N/m).
    pub kn_n_per_m: f64,
    /// Valanis initial-loading stiffness (N/m); the Jenkins contact's tangential stiffness.
    pub e0_n_per_m: f64,
    /// Valanis shape parameter, `0 ≤ k < 1` (–).
    pub k: f64,
    /// Friction coefficient (–).
    pub mu: f64,
    /// Valanis residual stiffness (N/m).
    pub et_n_per_m: f64,
}

impl ContactParams {
    /// The Valanis parameters of the element (stiffnesses in N/m, forces in N), validated.
    pub fn valanis(&self) -> Result<ValanisParams> {
        ValanisParams::new(self.e0_n_per_m, self.k, self.et_n_per_m, self.mu)
    }

    /// The record with its stiffnesses (`kn`, `E0`, `Et`) multiplied by `stiffness` and its
    /// friction coefficient by `friction` (a model update's factors).
    pub fn scaled(&self, stiffness: f64, friction: f64) -> Self {
        Self {
            kn_n_per_m: self.kn_n_per_m * stiffness,
            e0_n_per_m: self.e0_n_per_m * stiffness,
            k: self.k,
            mu: self.mu * friction,
            et_n_per_m: self.et_n_per_m * stiffness,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn per_area_record_scales_by_the_area() {
        let a = ContactParamsPerArea {
            kn_n_per_m3: 4e13,
            e0_n_per_m3: 2e13,
            k: 0.4,
            mu: 0.6,
            et_n_per_m3: 1e12,
        };
        // A power-of-two area: the products are exact.
        let e = a.over_area(0.25);
        assert_eq!(
            (e.kn_n_per_m, e.e0_n_per_m, e.k, e.mu, e.et_n_per_m),
            (1e13, 5e12, 0.4, 0.6, 2.5e11)
        );
        let v = e.valanis().unwrap();
        assert_eq!((v.e0, v.k, v.et, v.mu), (5e12, 0.4, 2.5e11, 0.6));
        let s = e.scaled(2.0, 0.5);
        assert_eq!(
            (s.kn_n_per_m, s.e0_n_per_m, s.mu, s.et_n_per_m),
            (2e13, 1e13, 0.3, 5e11)
        );
        assert!(ContactParams { k: 1.2, ..e }.valanis().is_err());
    }
}
