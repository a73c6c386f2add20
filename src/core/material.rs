//! Isotropic linear-elastic materials: the constants every elastic stage reads (Young's
//! modulus, Poisson's ratio, shear modulus).

use crate::core::error::{require_positive, Error, Result};

/// Isotropic linear-elastic material.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Material {
    /// Young's modulus E (Pa).
    pub youngs_modulus_pa: f64,
    /// Poisson's ratio ν (-).
    pub poisson_ratio: f64,
}

impl Material {
    /// Structural steel as in the reference case: E = 210 GPa, ν = 0.3.
    pub const STEEL: Material = Material {
        youngs_modulus_pa: 210e9,
        poisson_ratio: 0.3,
    };

    /// Check E > 0 and -1 < ν ≤ 0.5 (0.5: incompressible, e.g. an elastomer; nothing here
    /// divides by `1 − 2ν`).
    pub fn validated(self, name: &str) -> Result<Self> {
        require_positive(&format!("{name}.youngs_modulus_pa"), self.youngs_modulus_pa)?;
        let nu = self.poisson_ratio;
        if !(nu.is_finite() && nu > -1.0 && nu <= 0.5) {
            return Err(Error::param(
                format!("{name}.poisson_ratio"),
                format!("must lie in (-1, 0.5], got {nu}"),
            ));
        }
        Ok(self)
    }

    /// Shear modulus G = E / (2(1+ν)) (Pa).
    pub fn shear_modulus_pa(&self) -> f64 {
        self.youngs_modulus_pa / (2.0 * (1.0 + self.poisson_ratio))
    }
}

/// Composite (contact) modulus of two elastic bodies (Johnson, *Contact Mechanics*, 1985, eq. 4.22):
///
/// `1/E* = (1-ν1²)/E1 + (1-ν2²)/E2`  (Pa).
pub fn composite_modulus(body1: Material, body2: Material) -> Result<f64> {
    let b1 = body1.validated("body1")?;
    let b2 = body2.validated("body2")?;
    let c = (1.0 - b1.poisson_ratio.powi(2)) / b1.youngs_modulus_pa
        + (1.0 - b2.poisson_ratio.powi(2)) / b2.youngs_modulus_pa;
    Ok(1.0 / c)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An incompressible body (ν = 0.5) is accepted: E* = E/(1 − ν²) = 4E/3 for one rigid
    /// counterface; ν beyond 0.5 is refused by name.
    #[test]
    fn incompressible_body_is_accepted() {
        let rubber = Material {
            youngs_modulus_pa: 3e6,
            poisson_ratio: 0.5,
        };
        let rigid = Material {
            youngs_modulus_pa: f64::MAX,
            poisson_ratio: 0.0,
        };
        let e = composite_modulus(rubber, rigid).unwrap();
        assert!((e / 4e6 - 1.0).abs() < 1e-12, "{e}");
        let e = composite_modulus(
            Material {
                poisson_ratio: 0.51,
                ..rubber
            },
            rigid,
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("body1.poisson_ratio") && e.contains("(-1, 0.5]"),
            "{e}"
        );
    }

    #[test]
    fn steel_on_steel() {
        // E* = E / (2(1-ν²)) for identical bodies.
        let e = composite_modulus(Material::STEEL, Material::STEEL).unwrap();
        assert!((e - 210e9 / (2.0 * (1.0 - 0.09))).abs() < 1e-3);
    }

    #[test]
    fn rigid_limit_and_bad_input() {
        let rigid = Material {
            youngs_modulus_pa: 1e30,
            poisson_ratio: 0.0,
        };
        let e = composite_modulus(Material::STEEL, rigid).unwrap();
        assert!((e / (210e9 / 0.91) - 1.0).abs() < 1e-12);
        let bad = Material {
            youngs_modulus_pa: -1.0,
            poisson_ratio: 0.3,
        };
        let msg = composite_modulus(bad, rigid).unwrap_err().to_string();
        assert!(msg.contains("body1.youngs_modulus_pa"), "{msg}");
    }
}
