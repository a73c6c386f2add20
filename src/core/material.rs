//! Isotropic linear-elastic materials: the constants every elastic stage reads (Young's
//! modulus, Poisson's ratio, shear modulus), and named material grades with the indentation
//! hardness that bounds the contact pressure of the hardness-limited normal contact.

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

/// Pascals per Vickers hardness number: HV is a load in kgf over the indent's surface area in
/// mm², so `H = HV · 9.80665 N/kgf · 10⁶ mm²/m²`.
pub const PA_PER_HV: f64 = 9.80665e6;

/// The material of both bodies of a contact command from its `--youngs-modulus-pa` and
/// `--poisson-ratio`, validated, with errors naming the flag.
pub fn from_flags(youngs_modulus_pa: f64, poisson_ratio: f64) -> Result<Material> {
    Material {
        youngs_modulus_pa,
        poisson_ratio,
    }
    .validated("material")
    .map_err(|e| match e {
        Error::InvalidParameter { ref name, .. } if name.ends_with("poisson_ratio") => {
            e.renamed_param("--poisson-ratio")
        }
        e => e.renamed_param("--youngs-modulus-pa"),
    })
}

/// A named material with its indentation hardness: the elastic constants and the default
/// hardness H (Pa) of the hardness-limited normal contact ([`crate::contact::normal`]), with
/// their sources.
///
/// H is the Vickers hardness in Pa (load over the indent's *surface* area, [`PA_PER_HV`]); the
/// mean pressure over the *projected* area of a Vickers indent (Meyer hardness) is 7.9 % higher
/// (`2 / (2 sin 68°)`), and both are ≈ 3Y for metals that do not harden much (Tabor, *The
/// Hardness of Metals*, 1951). A measured hardness of the actual parts replaces these defaults
/// (`--hardness-pa <Pa>`); work hardening, temperature and surface treatments move it by tens
/// of per cent.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MaterialGrade {
    /// Name used on the command line (`--hardness-pa <name>`).
    pub name: &'static str,
    /// Elastic constants.
    pub elastic: Material,
    /// Vickers hardness number (kgf/mm²).
    pub vickers_hv: f64,
    /// Where the numbers come from.
    pub source: &'static str,
}

impl MaterialGrade {
    /// Hardness H = HV · [`PA_PER_HV`] (Pa).
    pub fn hardness_pa(&self) -> f64 {
        self.vickers_hv * PA_PER_HV
    }
}

/// The materials with a documented default hardness.
pub const MATERIAL_GRADES: [MaterialGrade; 2] = [
    MaterialGrade {
        name: "steel-42crmo4",
        // The reference case's steel constants.
        elastic: Material::STEEL,
        vickers_hv: 340.0,
        source: "42CrMo4 (AISI 4140) quenched and tempered, 25–40 mm: 300–350 HBW \
                 (EN 10083-3:2006, mechanical properties in the quenched and tempered condition, \
                 hardness informative); 325 HBW ≈ 340 HV (ISO 18265:2013, Annex A, low-alloy \
                 steels); E = 210 GPa, ν = 0.3",
    },
    MaterialGrade {
        name: "inconel-718",
        elastic: Material {
            youngs_modulus_pa: 200e9,
            poisson_ratio: 0.29,
        },
        vickers_hv: 450.0,
        source: "Inconel 718 solution treated and aged: 450 HV after ageing at 680 °C (Slama & \
                 Abdellaoui, J. Alloys Compd. 306 (2000) 277–284); E = 29.0·10³ ksi = 200 GPa, \
                 ν = 0.29 at room temperature (Special Metals, INCONEL alloy 718, publication \
                 SMC-045, Table 3)",
    },
];

/// The grade named `name` (see [`MATERIAL_GRADES`]); the error lists the names.
pub fn material_grade(name: &str) -> Result<&'static MaterialGrade> {
    MATERIAL_GRADES
        .iter()
        .find(|g| g.name == name)
        .ok_or_else(|| {
            let names: Vec<&str> = MATERIAL_GRADES.iter().map(|g| g.name).collect();
            Error::param(
                "hardness_pa",
                format!(
                    "`{name}` is neither a hardness in Pa nor a material ({})",
                    names.join(", ")
                ),
            )
        })
}

/// A hardness as given by a user: a value in Pa, or the name of a material grade whose
/// documented hardness to use ([`MATERIAL_GRADES`]). In TOML a number or a string
/// (`hardness_pa = 3.3e9` or `hardness_pa = "steel-42crmo4"`).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(untagged)]
pub enum Hardness {
    /// Hardness H (Pa).
    Pa(f64),
    /// A grade of [`MATERIAL_GRADES`], by name.
    Grade(String),
}

impl Hardness {
    /// A number (Pa) or a grade name, as typed on a command line.
    pub fn parse(text: &str) -> Self {
        match text.trim().parse::<f64>() {
            Ok(h) => Hardness::Pa(h),
            Err(_) => Hardness::Grade(text.trim().to_string()),
        }
    }

    /// H (Pa), checked (finite, > 0; a known grade); errors carry `name`.
    pub fn pa(&self, name: &str) -> Result<f64> {
        match self {
            Hardness::Pa(h) => require_positive(name, *h),
            Hardness::Grade(g) => material_grade(g)
                .map(|g| g.hardness_pa())
                .map_err(|e| match e {
                    Error::InvalidParameter { message, .. } => Error::param(name, message),
                    other => other,
                }),
        }
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

    /// The grades' hardness in Pa from HV, and their names resolve; an unknown name lists them.
    #[test]
    fn grades_have_hardness_and_names() {
        let steel = material_grade("steel-42crmo4").unwrap();
        assert!((steel.hardness_pa() / 3.334261e9 - 1.0).abs() < 1e-6);
        let inconel = material_grade("inconel-718").unwrap();
        assert!((inconel.hardness_pa() / 4.4129925e9 - 1.0).abs() < 1e-7);
        for g in MATERIAL_GRADES {
            g.elastic.validated(g.name).unwrap();
            assert!(!g.source.is_empty());
        }
        let e = material_grade("brass").unwrap_err().to_string();
        assert!(
            e.contains("steel-42crmo4") && e.contains("inconel-718"),
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
