//! The model file of `asperity response` (TOML) and the files it names.
//!
//! ```toml
//! [linear]                      # either a lumped model ...
//! mass = "mass.csv"             # CSV matrices: `# unit: kg` | `# unit: N/m` | `# unit: N*s/m`
//! damping = "damping.csv"       #   line, a header row of DOF labels `node.x|y|z|rx|ry|rz`
//! stiffness = "stiffness.csv"   #   (rotations in rad), n rows
//! # modes = "modes.csv"         # ... or a reduced modal model: mode,frequency_Hz,damping_ratio
//! # shapes = "shapes.csv"       #   node,direction,mode_1_per_sqrt_kg,… (mass-normalised)
//! # calculix = "fe/beam"        # ... or an FE model, Craig–Bampton reduced on load: a CalculiX
//! #                             #   export fe/beam.sti, .mas, .dof (or fe_stiffness, fe_mass:
//! #                             #   Matrix Market, with fe_dofs: node.direction per row)
//! # interface_nodes = [5, 6]    #   FE nodes kept (all their DOFs), named n5, n6 below
//! # fixed_interface_modes = 20  #   fixed-interface normal modes kept
//! # rayleigh_alpha_per_s = 0.0  #   damping C = α·M + β·K (defaults 0)
//! # rayleigh_beta_s = 1.0e-6
//!
//! # [nodes]                     # optional: positions (m) of rotating nodes that carry
//! # damper = [0.0, 0.0, 0.01]   #   contact elements at offset points (`film_origin_m`)
//!
//! # [cyclic]                    # optional: the model is one sector of a cyclic structure
//! # sectors = 24                #   (lumped models); N identical sectors
//! # engine_order = 3            #   EO of the excitation: inter-sector phase 2π·EO/N
//! # left = ["disk_l.x", "disk_l.y"]   # left boundary DOFs, paired in order with
//! # right = ["disk_r.x", "disk_r.y"]  #   their images on the right boundary
//!
//! [[contact]]                   # one or more element tables
//! elements = "elements.csv"     # written by `asperity elements`
//! law = "valanis"               # valanis (3-D microslip) | jenkins (2-D circular + normal)
//! node_a = "damper"             # one node pair for every row ...
//! node_b = "blade1"             #   (`ground` for a fixed side; `next:<node>` for a node of
//!                               #   the next sector of a [cyclic] model)
//! # pairs = "pairs.csv"         # ... or element_id,node_a,node_b
//! normal = [0.0, 0.0, 1.0]      # from node_a towards node_b
//! tangent = [1.0, 0.0, 0.0]
//! # film_origin_m = [0.0, 0.0, -0.01]   # elements at their x_m, y_m (film frame: tangent,
//! #                             #   normal × tangent), moved by their nodes' rotations
//! # load_following = "calibration_table.csv"   # valanis: kn(N), E0(N) follow the load
//!
//! [[joint]]                     # zero or more joints on one direction each
//! law = "bilinear"              # bilinear normal contact (element::bilinear)
//! node_a = "tip"                # `ground` for a fixed side
//! node_b = "ground"
//! direction = [0.0, 0.0, 1.0]   # u = direction·(x_a − x_b), u > 0 closing
//! k1_n_per_m = 2.0e6            # stiffness up to the threshold indentation
//! k2_n_per_m = 8.0e6            # stiffness beyond it
//! threshold_m = 1.0e-5          # indentation where the stiffness changes (> 0)
//! static_indentation_m = -2.0e-6   # indentation at the static equilibrium (< 0: an open gap)
//! # law = "thin-layer"          # elastic–plastic virtual layer (element::thin_layer) with
//! # elastic_modulus_pa, plastic_modulus_pa, yield_stress_pa, transition_exponent, area_m2,
//! # thickness_m
//! # law = "hunt-crossley"       # impact k·δⁿ·(1 + χ·δ̇) (element::hunt_crossley) with
//! # k_n_per_m_pow_n, exponent, static_indentation_m (≤ 0: the gap), and either
//! # damping_factor_s_per_m or restitution with impact_velocity_m_per_s
//! # law = "lugre"               # LuGre friction along `direction` (element::lugre) with
//! # sigma0_n_per_m, sigma1_n_s_per_m, sigma2_n_s_per_m, coulomb_force_n, static_force_n,
//! # stribeck_velocity_m_per_s
//!
//! # [static]                    # optional preload, the same at every level (needs
//! # dofs = ["damper.z"]         #   odd_only = false: balanced by the response's mean)
//! # forces_n = [-120.0]
//!
//! [excitation]
//! dofs = ["blade1.x", "blade2.x"]  # force F(t) = level·Σ w_i·e_i·cos(harmonic·ω·t + θ_i)
//! weights = [1.0, -1.0]         # optional (default 1 each): out-of-phase forcing
//! # phases_deg = [0.0, 90.0]    # optional phase θ_i of each DOF's force (default 0)
//! harmonic = 1
//! levels_n = [0.5, 2.0, 8.0]    # force amplitudes (N)
//!
//! [response]
//! dofs = ["blade1.x", "blade2.x"]
//!
//! [sweep]
//! frequency_start_hz = 100.0
//! frequency_end_hz = 300.0
//! points = 200                  # points over the span where the response is smooth (more at peaks)
//! harmonics = 7                 # highest harmonic
//! odd_only = false
//! time_samples = 128            # optional (default: power of two ≥ 16·harmonics)
//! formulation = "auto"          # auto | coordinates | receptance
//! # max_points = 20000          # optional cap on one level's points (default max(20000, 20·points))
//! ```
//!
//! Paths are relative to the model file. Every error names the file, line and key or column.
//!
//! **Cyclic symmetry** (`[cyclic]`; [`crate::dynamics::cyclic`]): the lumped matrices are one
//! sector of `sectors` identical ones, whose right boundary DOFs `right[i]` are the next sector's
//! left boundary DOFs `left[i]` (the sector's matrices hold both boundaries, as an FE sector
//! mesh does; assembling the sectors merges them). The excitation is the travelling wave of
//! engine order `engine_order`: the `[excitation]` force acts on this sector, and sector `j`
//! receives it delayed by `j·2π·EO/(N·ω)`. Harmonic `h` of the response has the inter-sector
//! phase `h·2π·EO/N` (its harmonic index is reported in `response.json`). A contact node
//! `next:<node>` is `<node>` of the next sector (e.g. a damper between adjacent blades:
//! `node_a = "damper"`, `node_b = "next:platform_left"`); it moves like `<node>` of this sector
//! advanced by the inter-sector phase. The sector is solved in the coordinates formulation;
//! the stability of its points is not assessed.

use crate::core::error::{Error, Result};
use crate::dynamics::contact::ContactLaw;
use crate::dynamics::contact::{self, contact_frame, TableElement};
use crate::dynamics::hbm::FormulationChoice;
use crate::dynamics::model::Structure;
use nalgebra::{DMatrix, DVector};
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

/// `[linear]`: the linear structure, either lumped matrices (`mass`, `damping`, `stiffness`) or a
/// reduced modal model (`modes`, `shapes`). Paths relative to the model file.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinearSection {
    /// Mass matrix CSV (`# unit: kg`, header of DOF labels `node.x|y|z`).
    pub mass: Option<PathBuf>,
    /// Viscous damping matrix CSV (`# unit: N*s/m`), same DOFs as `mass`.
    pub damping: Option<PathBuf>,
    /// Stiffness matrix CSV (`# unit: N/m`), same DOFs as `mass`.
    pub stiffness: Option<PathBuf>,
    /// Modal model CSV: `mode,frequency_Hz,damping_ratio` (instead of the matrices).
    pub modes: Option<PathBuf>,
    /// Mass-normalised mode shapes CSV: `node,direction,mode_1_per_sqrt_kg,…` (with `modes`).
    pub shapes: Option<PathBuf>,
    /// FE model from a CalculiX matrix export: the job's path without extension (`<job>.sti`,
    /// `<job>.mas`, `<job>.dof`), reduced by Craig–Bampton.
    pub calculix: Option<PathBuf>,
    /// FE model in Matrix Market files: stiffness (N/m), with `fe_mass` and `fe_dofs`.
    pub fe_stiffness: Option<PathBuf>,
    /// FE mass matrix, Matrix Market (kg).
    pub fe_mass: Option<PathBuf>,
    /// DOF map of the Matrix Market matrices: one `node.direction` line per row.
    pub fe_dofs: Option<PathBuf>,
    /// FE nodes kept by the reduction (all their DOFs): the nodes of contacts, excitation and
    /// response, named `n<node>` in the rest of the model file.
    pub interface_nodes: Option<Vec<u64>>,
    /// Fixed-interface normal modes kept by the reduction.
    pub fixed_interface_modes: Option<usize>,
    /// Rayleigh damping of the FE model `C = α·M + β·K`: α (1/s; default 0).
    pub rayleigh_alpha_per_s: Option<f64>,
    /// Rayleigh damping β (s; default 0).
    pub rayleigh_beta_s: Option<f64>,
}

impl LinearSection {
    /// Is the structure an FE model to be reduced (`calculix` or Matrix Market files)?
    pub fn is_fe(&self) -> bool {
        self.calculix.is_some()
            || self.fe_stiffness.is_some()
            || self.fe_mass.is_some()
            || self.fe_dofs.is_some()
    }
}

/// `[[contact]]`: one element table and how its elements attach to the structure.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactSection {
    /// Element table written by `asperity elements`.
    pub elements: PathBuf,
    /// Element law: `valanis` (3-D microslip) or `jenkins` (2-D circular slider with normal contact).
    pub law: ContactLaw,
    /// Node on the first side of every element (`ground` for a fixed side); with `node_b`, instead
    /// of `pairs`.
    pub node_a: Option<String>,
    /// Node on the second side of every element (`ground` for a fixed side).
    pub node_b: Option<String>,
    /// CSV `element_id,node_a,node_b`: a node pair per element (instead of `node_a`/`node_b`).
    pub pairs: Option<PathBuf>,
    /// Contact normal in the structure's axes, from `node_a` towards `node_b` (normalised on load).
    pub normal: [f64; 3],
    /// First tangential direction in the structure's axes (orthogonalised against `normal`).
    pub tangent: [f64; 3],
    /// Position (m, structure axes) of the origin of the element table's `x_m`, `y_m` (the film
    /// frame), whose axes are `tangent` and `normal × tangent`: every element then acts at its
    /// own point, moved by the rotations of its nodes (positions in `[nodes]`); without it every
    /// element acts at its nodes.
    pub film_origin_m: Option<[f64; 3]>,
    /// Calibration table the elements were interpolated from: with it, every element's `kn` and
    /// `E0` follow its instantaneous normal load (`kn ∝ N^b`, `E0 ∝ N^a`, the table's local
    /// exponents at the element's pressure; `valanis` law only).
    pub load_following: Option<PathBuf>,
}

/// Constitutive law of a `[[joint]]`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum JointLaw {
    /// [`crate::element::BilinearContact`]: `k1_n_per_m`, `k2_n_per_m`, `threshold_m`,
    /// `static_indentation_m`.
    Bilinear,
    /// [`crate::element::ThinLayer`]: `elastic_modulus_pa`, `plastic_modulus_pa`,
    /// `yield_stress_pa`, `transition_exponent`, `area_m2`, `thickness_m`.
    ThinLayer,
    /// [`crate::element::HuntCrossley`]: `k_n_per_m_pow_n` (N/mⁿ), `exponent`,
    /// `static_indentation_m` (≤ 0: the contact is open at the static equilibrium by the gap
    /// `−static_indentation_m`), and the damping as either `damping_factor_s_per_m` (χ) or
    /// `restitution` with `impact_velocity_m_per_s` (χ from the exact relation of
    /// [`crate::element::hunt_crossley::damping_factor`]).
    HuntCrossley,
    /// [`crate::element::LuGre`]: `sigma0_n_per_m`, `sigma1_n_s_per_m`, `sigma2_n_s_per_m`,
    /// `coulomb_force_n`, `static_force_n`, `stribeck_velocity_m_per_s`.
    #[serde(rename = "lugre")]
    LuGre,
}

impl JointLaw {
    /// The law's name in the model file.
    pub fn name(self) -> &'static str {
        match self {
            JointLaw::Bilinear => "bilinear",
            JointLaw::ThinLayer => "thin-layer",
            JointLaw::HuntCrossley => "hunt-crossley",
            JointLaw::LuGre => "lugre",
        }
    }

    /// Groups of keys of which the law needs exactly one, whole (besides [`Self::keys`]).
    fn alternatives(self) -> &'static [&'static [&'static str]] {
        match self {
            JointLaw::HuntCrossley => &[
                &["damping_factor_s_per_m"],
                &["restitution", "impact_velocity_m_per_s"],
            ],
            _ => &[],
        }
    }

    /// The parameter keys the law needs (every other parameter key, but those of
    /// [`Self::alternatives`], is refused).
    fn keys(self) -> &'static [&'static str] {
        match self {
            JointLaw::Bilinear => &[
                "k1_n_per_m",
                "k2_n_per_m",
                "threshold_m",
                "static_indentation_m",
            ],
            JointLaw::ThinLayer => &[
                "elastic_modulus_pa",
                "plastic_modulus_pa",
                "yield_stress_pa",
                "transition_exponent",
                "area_m2",
                "thickness_m",
            ],
            JointLaw::HuntCrossley => &["k_n_per_m_pow_n", "exponent", "static_indentation_m"],
            JointLaw::LuGre => &[
                "sigma0_n_per_m",
                "sigma1_n_s_per_m",
                "sigma2_n_s_per_m",
                "coulomb_force_n",
                "static_force_n",
                "stribeck_velocity_m_per_s",
            ],
        }
    }
}

/// `[[joint]]`: one joint law between two nodes (or a node and ground) along one direction,
/// acting on the approach `u = direction·(x_a − x_b)` (`u > 0` closing) with the force `f`
/// applied as `−f·direction` on `node_a` and `+f·direction` on `node_b`.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointSection {
    /// The joint's law.
    pub law: JointLaw,
    /// First node (`ground` for a fixed side).
    pub node_a: String,
    /// Second node (`ground` for a fixed side).
    pub node_b: String,
    /// Direction of the joint in the structure's axes, from `node_a` towards `node_b`
    /// (normalised on load).
    pub direction: [f64; 3],
    /// Bilinear: stiffness up to the threshold indentation (N/m).
    pub k1_n_per_m: Option<f64>,
    /// Bilinear: stiffness beyond the threshold indentation (N/m).
    pub k2_n_per_m: Option<f64>,
    /// Bilinear: indentation where the stiffness changes (m).
    pub threshold_m: Option<f64>,
    /// Bilinear: indentation at the static equilibrium (m; negative: an open gap).
    pub static_indentation_m: Option<f64>,
    /// Thin layer: elastic modulus of the virtual material (Pa).
    pub elastic_modulus_pa: Option<f64>,
    /// Thin layer: plastic (hardening) modulus (Pa), below the elastic one.
    pub plastic_modulus_pa: Option<f64>,
    /// Thin layer: yield stress (Pa).
    pub yield_stress_pa: Option<f64>,
    /// Thin layer: exponent of the smooth elastic–plastic transition (–; larger: sharper).
    pub transition_exponent: Option<f64>,
    /// Thin layer: area of the layer (m²).
    pub area_m2: Option<f64>,
    /// Thin layer: thickness of the layer (m); its strain is the approach over it.
    pub thickness_m: Option<f64>,
    /// Hunt–Crossley: contact stiffness `k` (N/mⁿ).
    pub k_n_per_m_pow_n: Option<f64>,
    /// Hunt–Crossley: exponent `n` (–; 1.5 for Hertz).
    pub exponent: Option<f64>,
    /// Hunt–Crossley: damping factor `χ` (s/m).
    pub damping_factor_s_per_m: Option<f64>,
    /// Hunt–Crossley: coefficient of restitution `e` (–, in (0, 1]) at `impact_velocity_m_per_s`.
    pub restitution: Option<f64>,
    /// Hunt–Crossley: impact velocity the coefficient of restitution holds at (m/s).
    pub impact_velocity_m_per_s: Option<f64>,
    /// LuGre: bristle stiffness `σ0` (N/m).
    pub sigma0_n_per_m: Option<f64>,
    /// LuGre: bristle damping `σ1` (N·s/m).
    pub sigma1_n_s_per_m: Option<f64>,
    /// LuGre: viscous friction `σ2` (N·s/m).
    pub sigma2_n_s_per_m: Option<f64>,
    /// LuGre: Coulomb friction force `Fc` (N).
    pub coulomb_force_n: Option<f64>,
    /// LuGre: static (stiction) friction force `Fs ≥ Fc` (N).
    pub static_force_n: Option<f64>,
    /// LuGre: Stribeck velocity `vs` (m/s).
    pub stribeck_velocity_m_per_s: Option<f64>,
}

impl JointSection {
    /// Every parameter key with its value, if given.
    fn parameters(&self) -> [(&'static str, Option<f64>); 21] {
        [
            ("k1_n_per_m", self.k1_n_per_m),
            ("k2_n_per_m", self.k2_n_per_m),
            ("threshold_m", self.threshold_m),
            ("static_indentation_m", self.static_indentation_m),
            ("elastic_modulus_pa", self.elastic_modulus_pa),
            ("plastic_modulus_pa", self.plastic_modulus_pa),
            ("yield_stress_pa", self.yield_stress_pa),
            ("transition_exponent", self.transition_exponent),
            ("area_m2", self.area_m2),
            ("thickness_m", self.thickness_m),
            ("k_n_per_m_pow_n", self.k_n_per_m_pow_n),
            ("exponent", self.exponent),
            ("damping_factor_s_per_m", self.damping_factor_s_per_m),
            ("restitution", self.restitution),
            ("impact_velocity_m_per_s", self.impact_velocity_m_per_s),
            ("sigma0_n_per_m", self.sigma0_n_per_m),
            ("sigma1_n_s_per_m", self.sigma1_n_s_per_m),
            ("sigma2_n_s_per_m", self.sigma2_n_s_per_m),
            ("coulomb_force_n", self.coulomb_force_n),
            ("static_force_n", self.static_force_n),
            ("stribeck_velocity_m_per_s", self.stribeck_velocity_m_per_s),
        ]
    }

    /// The joint's element. Errors name the key (`joint.<key>`).
    pub fn element(&self) -> Result<std::sync::Arc<dyn crate::element::HystereticElement>> {
        let needed = self.law.keys();
        let law = self.law.name();
        let alternatives = self.law.alternatives();
        let given = |key: &str| {
            self.parameters()
                .iter()
                .any(|(k, v)| *k == key && v.is_some())
        };
        if !alternatives.is_empty() {
            let describe = |g: &[&str]| g.join(" with ");
            let options = alternatives
                .iter()
                .map(|g| format!("`{}`", describe(g)))
                .collect::<Vec<_>>()
                .join(" or ");
            let touched: Vec<&[&str]> = alternatives
                .iter()
                .copied()
                .filter(|g| g.iter().any(|k| given(k)))
                .collect();
            match touched.as_slice() {
                [] => {
                    return Err(Error::param(
                        format!("joint.{}", alternatives[0][0]),
                        format!("the `{law}` law needs {options}"),
                    ))
                }
                [g] => {
                    if let Some(missing) = g.iter().find(|k| !given(k)) {
                        return Err(Error::param(
                            format!("joint.{missing}"),
                            format!("the `{law}` law needs `{}`", describe(g)),
                        ));
                    }
                }
                [_, g, ..] => {
                    let key = g.iter().find(|k| given(k)).expect("touched");
                    return Err(Error::param(
                        format!("joint.{key}"),
                        format!("the `{law}` law takes {options}, not both"),
                    ));
                }
            }
        }
        for (key, value) in self.parameters() {
            if alternatives.iter().any(|g| g.contains(&key)) {
                continue;
            }
            match (needed.contains(&key), value) {
                (true, None) => {
                    return Err(Error::param(
                        format!("joint.{key}"),
                        format!("the `{law}` law needs `{key}`"),
                    ))
                }
                (false, Some(_)) => {
                    return Err(Error::param(
                        format!("joint.{key}"),
                        format!(
                            "is not a parameter of the `{law}` law (it takes {})",
                            needed.join(", ")
                        ),
                    ))
                }
                _ => {}
            }
        }
        let rename = |e: Error, keys: &[(&str, &str)]| match e {
            Error::InvalidParameter { name, message } => {
                let key = keys
                    .iter()
                    .find(|(n, _)| *n == name)
                    .map(|(_, k)| *k)
                    .unwrap_or("law");
                Error::param(format!("joint.{key}"), message)
            }
            o => o,
        };
        Ok(match self.law {
            JointLaw::Bilinear => std::sync::Arc::new(
                crate::element::BilinearContact::new(
                    self.k1_n_per_m.expect("checked"),
                    self.k2_n_per_m.expect("checked"),
                    self.threshold_m.expect("checked"),
                    self.static_indentation_m.expect("checked"),
                )
                .map_err(|e| {
                    rename(
                        e,
                        &[
                            ("k1", "k1_n_per_m"),
                            ("k2", "k2_n_per_m"),
                            ("threshold", "threshold_m"),
                            ("static_indentation", "static_indentation_m"),
                        ],
                    )
                })?,
            ),
            JointLaw::ThinLayer => std::sync::Arc::new(
                crate::element::ThinLayer::new(
                    self.elastic_modulus_pa.expect("checked"),
                    self.plastic_modulus_pa.expect("checked"),
                    self.yield_stress_pa.expect("checked"),
                    self.transition_exponent.expect("checked"),
                    self.area_m2.expect("checked"),
                    self.thickness_m.expect("checked"),
                )
                .map_err(|e| {
                    rename(
                        e,
                        &[
                            ("elastic_modulus", "elastic_modulus_pa"),
                            ("plastic_modulus", "plastic_modulus_pa"),
                            ("yield_stress", "yield_stress_pa"),
                            ("exponent", "transition_exponent"),
                            ("area", "area_m2"),
                            ("thickness", "thickness_m"),
                        ],
                    )
                })?,
            ),
            JointLaw::HuntCrossley => {
                let static_indentation = self.static_indentation_m.expect("checked");
                if !(static_indentation.is_finite() && static_indentation <= 0.0) {
                    return Err(Error::param(
                        "joint.static_indentation_m",
                        format!(
                            "a Hunt–Crossley contact is open or just touching at the static \
                             equilibrium (≤ 0, minus the gap; a preloaded contact is the \
                             `bilinear` law's), got {static_indentation}"
                        ),
                    ));
                }
                let damping_factor = match self.damping_factor_s_per_m {
                    Some(chi) => chi,
                    None => crate::element::hunt_crossley::damping_factor(
                        self.restitution.expect("checked"),
                        self.impact_velocity_m_per_s.expect("checked"),
                    )
                    .map_err(|e| {
                        rename(
                            e,
                            &[
                                ("restitution", "restitution"),
                                ("impact_velocity", "impact_velocity_m_per_s"),
                            ],
                        )
                    })?,
                };
                let params = crate::element::HuntCrossleyParams {
                    stiffness: self.k_n_per_m_pow_n.expect("checked"),
                    exponent: self.exponent.expect("checked"),
                    damping_factor,
                    gap: -static_indentation,
                };
                params.validate().map_err(|e| {
                    rename(
                        e,
                        &[
                            ("stiffness", "k_n_per_m_pow_n"),
                            ("exponent", "exponent"),
                            ("damping_factor", "damping_factor_s_per_m"),
                            ("gap", "static_indentation_m"),
                        ],
                    )
                })?;
                std::sync::Arc::new(crate::element::HuntCrossley { params })
            }
            JointLaw::LuGre => {
                let params = crate::element::LuGreParams {
                    sigma0: self.sigma0_n_per_m.expect("checked"),
                    sigma1: self.sigma1_n_s_per_m.expect("checked"),
                    sigma2: self.sigma2_n_s_per_m.expect("checked"),
                    coulomb: self.coulomb_force_n.expect("checked"),
                    stiction: self.static_force_n.expect("checked"),
                    stribeck_velocity: self.stribeck_velocity_m_per_s.expect("checked"),
                };
                params.validate().map_err(|e| {
                    rename(
                        e,
                        &[
                            ("sigma0", "sigma0_n_per_m"),
                            ("sigma1", "sigma1_n_s_per_m"),
                            ("sigma2", "sigma2_n_s_per_m"),
                            ("coulomb", "coulomb_force_n"),
                            ("stiction", "static_force_n"),
                            ("stribeck_velocity", "stribeck_velocity_m_per_s"),
                        ],
                    )
                })?;
                std::sync::Arc::new(crate::element::LuGre { params })
            }
        })
    }
}

/// `[cyclic]`: the lumped model is one sector of a cyclic structure under an engine-order
/// excitation ([`crate::dynamics::cyclic`]).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CyclicSection {
    /// Number of identical sectors `N` of the full structure (≥ 2).
    pub sectors: usize,
    /// Engine order `EO` of the excitation (≥ 0): inter-sector phase `2π·EO/N`.
    pub engine_order: usize,
    /// DOF labels of the sector's left boundary.
    pub left: Vec<String>,
    /// DOF labels of the right boundary, `right[i]` the image of `left[i]` (the next sector's
    /// `left[i]`).
    pub right: Vec<String>,
}

/// `[static]`: constant forces `F0 = Σ f_i·e_i` (N) on top of the harmonic excitation, the same
/// at every level (a preload, e.g. a centrifugal load), balanced by the response's mean
/// (harmonic 0: `odd_only = false`; coordinates formulation).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StaticSection {
    /// DOFs loaded (`node.x|y|z`).
    pub dofs: Vec<String>,
    /// Force on each DOF (N).
    pub forces_n: Vec<f64>,
}

/// Prefix of a contact node of the next sector in a `[cyclic]` model (`next:<node>`).
pub const NEXT_SECTOR: &str = "next:";

/// `[excitation]`: the harmonic force `F(t) = level·Σ w_i·e_i·cos(harmonic·ω·t + θ_i)`.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExcitationSection {
    /// DOFs loaded by the force, each with a weight (default 1): `F = level·Σ w_i·e_i`.
    pub dofs: Vec<String>,
    /// Weight `w_i` of each DOF (dimensionless; default 1 each, e.g. `[1, -1]` for out-of-phase
    /// forcing).
    pub weights: Option<Vec<f64>>,
    /// Phase `θ_i` of each DOF's force (degrees; default 0 each): the force leads
    /// `cos(harmonic·ω·t)` by `θ_i`, the convention of the response's `phase_rad`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub phases_deg: Option<Vec<f64>>,
    /// Harmonic of the sweep frequency the force acts at (default 1).
    #[serde(default = "one")]
    pub harmonic: usize,
    /// Force amplitudes `level` (N), one frequency sweep each.
    pub levels_n: Vec<f64>,
}

fn one() -> usize {
    1
}

/// `[response]`: the DOFs whose response is reported.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ResponseSection {
    /// DOF labels `node.x|y|z`.
    pub dofs: Vec<String>,
}

/// `[sweep]`: the frequency band and the harmonic-balance settings.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SweepSection {
    /// First frequency of the sweep (Hz).
    pub frequency_start_hz: f64,
    /// Last frequency of the sweep (Hz).
    pub frequency_end_hz: f64,
    /// Points over the span where the response is smooth; continuation adds more at peaks
    /// (default 200).
    #[serde(default = "default_points")]
    pub points: usize,
    /// Highest harmonic of the balance.
    pub harmonics: usize,
    /// Odd harmonics only (no static term or even harmonics; default `false`).
    #[serde(default)]
    pub odd_only: bool,
    /// Time samples per period of the AFT (default: the power of two ≥ 16·harmonics).
    pub time_samples: Option<usize>,
    /// Unknowns of the balance: `auto` (the fewer), `coordinates` or `receptance`.
    #[serde(default = "default_formulation")]
    pub formulation: FormulationChoice,
    /// Cap on the points of one level's branch (default: the larger of 20 000 and 20 × points).
    pub max_points: Option<usize>,
}

fn default_points() -> usize {
    200
}

fn default_formulation() -> FormulationChoice {
    FormulationChoice::Auto
}

/// The whole model file.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelFile {
    /// The linear structure.
    pub linear: LinearSection,
    /// Cyclic symmetry of a sector model (none: the structure on its own).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cyclic: Option<CyclicSection>,
    /// The element tables (none: a linear response).
    #[serde(default)]
    pub contact: Vec<ContactSection>,
    /// The joints (none: no joint law).
    #[serde(default)]
    pub joint: Vec<JointSection>,
    /// Node positions (m, structure axes): needed for the nodes with rotational DOFs on which a
    /// contact acts at offset points (`film_origin_m`).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub nodes: BTreeMap<String, [f64; 3]>,
    /// A static force (a preload that does not scale with the excitation level; none: none).
    #[serde(default, rename = "static", skip_serializing_if = "Option::is_none")]
    pub static_load: Option<StaticSection>,
    /// The forcing.
    pub excitation: ExcitationSection,
    /// The reported DOFs.
    pub response: ResponseSection,
    /// The frequency band and solver settings.
    pub sweep: SweepSection,
}

/// A model ready to solve: the structure, the excitation and observation vectors, and every
/// file that was read (for the provenance record).
#[derive(Debug)]
pub struct LoadedModel {
    /// The model file as parsed.
    pub file: ModelFile,
    /// Path of the model file.
    pub path: PathBuf,
    /// The structure with its elements attached.
    pub structure: Structure,
    /// Force on the coordinates per newton of excitation, in phase with `cos(harmonic·ω·t)`.
    pub force: DVector<f64>,
    /// Quadrature part (on `sin(harmonic·ω·t)`) when `[excitation]` gives phases.
    pub force_sin: Option<DVector<f64>>,
    /// The `[static]` force on the coordinates (N), the same at every level.
    pub static_force: Option<DVector<f64>>,
    /// One observation row per response DOF (label, row).
    pub responses: Vec<(String, DVector<f64>)>,
    /// `(role, path)` of every input file.
    pub inputs: Vec<(String, PathBuf)>,
    /// Element ids per contact section, and how many were out of the calibration range.
    pub out_of_range: usize,
    /// The law and table row of every attached element, in the order of
    /// `structure.elements` (to rebuild them with updated parameters).
    pub element_rows: Vec<(ContactLaw, TableElement)>,
}

impl LoadedModel {
    /// Refuse a `[static]` force for `command`, which does not solve the static equilibrium
    /// (only `asperity response` balances it).
    pub fn refuse_static(&self, command: &str) -> Result<()> {
        if self.static_force.is_some() {
            return Err(Error::parse(
                &self.path,
                0,
                format!(
                    "[static]: {command} does not solve a static preload (asperity response \
                     balances it with the response's mean); remove the section for {command}"
                ),
            ));
        }
        Ok(())
    }
}

/// Attach `element` (label `label`, map `map` on this sector's coordinates) to `structure`;
/// with `next`, its map on the next sector's coordinates, across the boundary of a cyclic sector
/// — refused with `needs_cyclic()` when the structure is not cyclic.
fn attach_pair(
    structure: &mut Structure,
    label: String,
    element: std::sync::Arc<dyn crate::element::HystereticElement>,
    map: DMatrix<f64>,
    next: Option<DMatrix<f64>>,
    needs_cyclic: impl FnOnce() -> Error,
) -> Result<()> {
    match next {
        Some(next) if structure.cyclic.is_some() => {
            structure.attach_across(label, element, map, next)
        }
        Some(_) => Err(needs_cyclic()),
        None => structure.attach(label, element, map),
    }
}

/// 1-based line of `key = …` in TOML text (first occurrence), or 0.
fn key_line(text: &str, key: &str) -> usize {
    text.lines()
        .position(|l| {
            l.split('#')
                .next()
                .and_then(|s| s.split_once('='))
                .is_some_and(|(k, _)| k.trim() == key)
        })
        .map(|i| i + 1)
        .unwrap_or(0)
}

impl ModelFile {
    /// Parse and validate TOML text (`path` names it in errors).
    pub fn parse(text: &str, path: &Path) -> Result<Self> {
        let f: Self =
            toml::from_str(text).map_err(|e| crate::core::input::toml_error(path, text, e))?;
        f.validate().map_err(|e| match e {
            Error::InvalidParameter { name, message } => {
                let key = name.rsplit('.').next().unwrap_or(&name).to_string();
                Error::parse(
                    path,
                    key_line(text, &key),
                    format!("invalid `{name}`: {message}"),
                )
            }
            other => other,
        })?;
        Ok(f)
    }

    fn validate(&self) -> Result<()> {
        let l = &self.linear;
        let lumped = l.mass.is_some() || l.damping.is_some() || l.stiffness.is_some();
        let modal = l.modes.is_some() || l.shapes.is_some();
        let fe = l.is_fe();
        if usize::from(lumped) + usize::from(modal) + usize::from(fe) != 1
            || (lumped && (l.mass.is_none() || l.damping.is_none() || l.stiffness.is_none()))
            || (modal && (l.modes.is_none() || l.shapes.is_none()))
        {
            return Err(Error::param(
                "linear.mass",
                "give either mass, damping and stiffness (lumped), modes and shapes (modal), or \
                 an FE model (calculix, or fe_stiffness, fe_mass and fe_dofs)",
            ));
        }
        if fe {
            let mm = l.fe_stiffness.is_some() || l.fe_mass.is_some() || l.fe_dofs.is_some();
            if l.calculix.is_some() == mm
                || (mm && (l.fe_stiffness.is_none() || l.fe_mass.is_none() || l.fe_dofs.is_none()))
            {
                return Err(Error::param(
                    "linear.calculix",
                    "give either calculix (a CalculiX job) or fe_stiffness, fe_mass and fe_dofs \
                     (Matrix Market)",
                ));
            }
            if l.interface_nodes.as_ref().is_none_or(|v| v.is_empty()) {
                return Err(Error::param(
                    "linear.interface_nodes",
                    "an FE model needs the interface nodes kept by the reduction",
                ));
            }
            if l.fixed_interface_modes.is_none() {
                return Err(Error::param(
                    "linear.fixed_interface_modes",
                    "an FE model needs the number of fixed-interface modes kept",
                ));
            }
            for (key, v) in [
                ("rayleigh_alpha_per_s", l.rayleigh_alpha_per_s),
                ("rayleigh_beta_s", l.rayleigh_beta_s),
            ] {
                if v.is_some_and(|v| !(v >= 0.0 && v.is_finite())) {
                    return Err(Error::param(
                        format!("linear.{key}"),
                        "must be finite and ≥ 0",
                    ));
                }
            }
        } else if l.interface_nodes.is_some()
            || l.fixed_interface_modes.is_some()
            || l.rayleigh_alpha_per_s.is_some()
            || l.rayleigh_beta_s.is_some()
        {
            return Err(Error::param(
                "linear.interface_nodes",
                "interface_nodes, fixed_interface_modes and rayleigh_* belong to an FE model \
                 (calculix or fe_stiffness)",
            ));
        }
        if let Some(c) = &self.cyclic {
            if !lumped {
                return Err(Error::param(
                    "cyclic.sectors",
                    "cyclic symmetry needs a lumped model (mass, damping, stiffness): the \
                     boundary conditions pair physical DOFs",
                ));
            }
            if c.sectors < 2 {
                return Err(Error::param(
                    "cyclic.sectors",
                    format!(
                        "a cyclic structure has at least 2 sectors, got {}",
                        c.sectors
                    ),
                ));
            }
            if c.left.len() != c.right.len() {
                return Err(Error::param(
                    "cyclic.right",
                    format!(
                        "{} right boundary DOFs for {} left ones (pair each left DOF with its \
                         image on the right, in order)",
                        c.right.len(),
                        c.left.len()
                    ),
                ));
            }
            if self.sweep.formulation == FormulationChoice::Receptance {
                return Err(Error::param(
                    "sweep.formulation",
                    "a [cyclic] sector is solved in the coordinates formulation (auto or \
                     coordinates)",
                ));
            }
        }
        for (node, x) in &self.nodes {
            if x.iter().any(|v| !v.is_finite()) {
                return Err(Error::param(
                    format!("nodes.{node}"),
                    "the position must be three finite numbers (m)",
                ));
            }
        }
        for (i, c) in self.contact.iter().enumerate() {
            if c.film_origin_m
                .is_some_and(|o| o.iter().any(|v| !v.is_finite()))
            {
                return Err(Error::param(
                    "contact.film_origin_m",
                    format!("contact {}: must be three finite numbers (m)", i + 1),
                ));
            }
            if self.cyclic.is_none() {
                for (key, node) in [("contact.node_a", &c.node_a), ("contact.node_b", &c.node_b)] {
                    if node.as_deref().is_some_and(|n| n.starts_with(NEXT_SECTOR)) {
                        return Err(Error::param(
                            key,
                            format!(
                                "contact {}: `{}` names a node of the next sector, but the model \
                                 has no [cyclic] section",
                                i + 1,
                                node.as_deref().unwrap_or("")
                            ),
                        ));
                    }
                }
            }
            let pair = c.node_a.is_some() && c.node_b.is_some();
            if pair == c.pairs.is_some() || (c.node_a.is_some() != c.node_b.is_some()) {
                return Err(Error::param(
                    "contact.node_a",
                    format!("contact {}: give node_a and node_b, or pairs", i + 1),
                ));
            }
            contact_frame(c.normal, c.tangent).map_err(|e| match e {
                Error::InvalidParameter { name, message } => {
                    Error::param(format!("contact.{name}"), message)
                }
                o => o,
            })?;
        }
        for (i, j) in self.joint.iter().enumerate() {
            let n = j.direction.iter().map(|v| v * v).sum::<f64>().sqrt();
            if !(n.is_finite() && n > 0.0) {
                return Err(Error::param(
                    "joint.direction",
                    format!("joint {}: must be a non-zero finite vector", i + 1),
                ));
            }
            if j.node_a == j.node_b {
                return Err(Error::param(
                    "joint.node_b",
                    format!(
                        "joint {}: node_a and node_b are the same node `{}` (a joint needs two \
                         nodes, or `ground` for one side)",
                        i + 1,
                        j.node_a
                    ),
                ));
            }
            j.element().map_err(|e| match e {
                Error::InvalidParameter { name, message } => {
                    Error::param(name, format!("joint {}: {message}", i + 1))
                }
                o => o,
            })?;
        }
        let e = &self.excitation;
        if e.levels_n.is_empty() {
            return Err(Error::param(
                "excitation.levels_n",
                "give at least one level",
            ));
        }
        if let Some(v) = e.levels_n.iter().find(|v| !(v.is_finite() && **v > 0.0)) {
            return Err(Error::param(
                "excitation.levels_n",
                format!("levels must be finite and > 0, got {v}"),
            ));
        }
        let max = crate::core::sanity::MAX_FORCE_AMPLITUDE_N;
        if let Some(v) = e.levels_n.iter().find(|v| **v > max) {
            return Err(Error::param(
                "excitation.levels_n",
                format!("{v} N is more than {max:e} N, beyond any exciter (a unit error?)"),
            ));
        }
        if e.dofs.is_empty() {
            return Err(Error::param("excitation.dofs", "give at least one DOF"));
        }
        if let Some(d) = e
            .dofs
            .iter()
            .enumerate()
            .find_map(|(i, d)| e.dofs[..i].contains(d).then_some(d))
        {
            return Err(Error::param(
                "excitation.dofs",
                format!("`{d}` is listed twice (give each DOF once, with its weight)"),
            ));
        }
        if let Some(w) = &e.weights {
            if w.len() != e.dofs.len() || w.iter().any(|v| !v.is_finite()) {
                return Err(Error::param(
                    "excitation.weights",
                    "one finite weight per excitation DOF",
                ));
            }
        }
        if let Some(p) = &e.phases_deg {
            if p.len() != e.dofs.len() || p.iter().any(|v| !v.is_finite()) {
                return Err(Error::param(
                    "excitation.phases_deg",
                    "one finite phase (degrees) per excitation DOF",
                ));
            }
        }
        if e.harmonic == 0 {
            return Err(Error::param("excitation.harmonic", "must be ≥ 1"));
        }
        if self.response.dofs.is_empty() {
            return Err(Error::param("response.dofs", "give at least one DOF"));
        }
        let s = &self.sweep;
        for (k, v) in [
            ("sweep.frequency_start_hz", s.frequency_start_hz),
            ("sweep.frequency_end_hz", s.frequency_end_hz),
        ] {
            crate::core::error::require_positive(k, v)?;
        }
        if s.frequency_start_hz == s.frequency_end_hz {
            return Err(Error::param(
                "sweep.frequency_end_hz",
                "must differ from the start",
            ));
        }
        if s.harmonics == 0 {
            return Err(Error::param("sweep.harmonics", "must be ≥ 1"));
        }
        if s.harmonics > crate::core::limits::MAX_HARMONICS {
            return Err(Error::param(
                "sweep.harmonics",
                format!(
                    "{} is more than the limit of {}",
                    s.harmonics,
                    crate::core::limits::MAX_HARMONICS
                ),
            ));
        }
        if let Some(n) = s
            .time_samples
            .filter(|&n| n > crate::core::limits::MAX_TIME_SAMPLES)
        {
            return Err(Error::param(
                "sweep.time_samples",
                format!(
                    "{n} is more than the limit of {}",
                    crate::core::limits::MAX_TIME_SAMPLES
                ),
            ));
        }
        if s.max_points.is_some_and(|m| m < s.points) {
            return Err(Error::param(
                "sweep.max_points",
                "must be at least sweep.points",
            ));
        }
        if s.points < 2 {
            return Err(Error::param("sweep.points", "must be ≥ 2"));
        }
        if s.points > crate::core::limits::MAX_SWEEP_POINTS {
            return Err(Error::param(
                "sweep.points",
                format!(
                    "{} is more than the limit of {} (resource limit: each point is a Newton \
                     solve of every level's harmonic balance; a resonance gets more points than \
                     this by itself)",
                    s.points,
                    crate::core::limits::MAX_SWEEP_POINTS
                ),
            ));
        }
        if e.harmonic > s.harmonics || (s.odd_only && e.harmonic.is_multiple_of(2)) {
            return Err(Error::param(
                "excitation.harmonic",
                "must be one of the retained harmonics",
            ));
        }
        Ok(())
    }
}

/// Split `node.x` into `(node, axis)`.
fn split_dof(label: &str) -> Option<(&str, usize)> {
    let (node, dir) = label.rsplit_once('.')?;
    let axis = AXES.iter().position(|a| *a == dir)?;
    (!node.is_empty()).then_some((node, axis))
}

/// The directions of a node's DOFs: translations x, y, z (m) and rotations rx, ry, rz (rad)
/// about the structure's axes.
const AXES: [&str; 6] = ["x", "y", "z", "rx", "ry", "rz"];

/// Unit of a DOF's displacement by its label: `rad` for a rotation `node.rx|ry|rz`, `m`
/// otherwise (a translation, or a modal coordinate's label).
pub fn dof_unit(label: &str) -> &'static str {
    match split_dof(label) {
        Some((_, axis)) if axis >= 3 => "rad",
        _ => "m",
    }
}

/// A reduced FE model: the structure, its node kinematics and the files read (role, path).
type ReducedFe = (Structure, Kinematics, Vec<(String, PathBuf)>);

/// The FE model of `[linear]` read, Craig–Bampton reduced on its interface nodes
/// ([`crate::dynamics::craig_bampton`]) and damped by `C = α·M_r + β·K_r` (Rayleigh damping
/// is preserved by the reduction: `Tᵀ·(α·M + β·K)·T`). The reduced coordinates are labelled
/// `n<node>.x|y|z` (`.rx|ry|rz` for rotations) and `cb_mode_<j>`.
fn reduce_fe_model(l: &LinearSection, base: &Path) -> Result<ReducedFe> {
    use crate::dynamics::craig_bampton::{reduce, ReductionSettings};
    use crate::dynamics::fe_matrices::{calculix_paths, read_calculix, read_matrix_market_pair};
    let (fe, files, origin) = if let Some(job) = &l.calculix {
        let job = base.join(job);
        let [sti, mas, dof] = calculix_paths(&job);
        let files = vec![
            ("CalculiX stiffness".to_string(), sti),
            ("CalculiX mass".to_string(), mas),
            ("CalculiX DOF map".to_string(), dof.clone()),
        ];
        (read_calculix(&job)?, files, dof)
    } else {
        let (k, m, d) = (
            base.join(l.fe_stiffness.as_ref().expect("validated")),
            base.join(l.fe_mass.as_ref().expect("validated")),
            base.join(l.fe_dofs.as_ref().expect("validated")),
        );
        let fe = read_matrix_market_pair(&k, &m, &d)?;
        let files = vec![
            ("FE stiffness".to_string(), k),
            ("FE mass".to_string(), m),
            ("FE DOF map".to_string(), d.clone()),
        ];
        (fe, files, d)
    };
    let nodes = l.interface_nodes.as_deref().expect("validated");
    let boundary = fe
        .rows_of_nodes(nodes)
        .map_err(|e| Error::parse(&origin, 0, format!("`linear.interface_nodes`: {e}")))?;
    let settings = ReductionSettings {
        modes: l.fixed_interface_modes.expect("validated"),
        ..Default::default()
    };
    let r = reduce(&fe.stiffness, &fe.mass, &boundary, &settings).map_err(|e| match e {
        Error::InvalidParameter { name, message } => Error::param(
            if name == "modes" {
                "linear.fixed_interface_modes".to_string()
            } else {
                format!("linear.{name}")
            },
            message,
        ),
        o => o,
    })?;
    let nb = boundary.len();
    let n = r.stiffness.nrows();
    let mut labels = Vec::with_capacity(n);
    let mut kin_nodes: HashMap<String, [Option<Vec<f64>>; 6]> = HashMap::new();
    for (i, &row) in boundary.iter().enumerate() {
        let d = fe.dofs[row];
        let node = format!("n{}", d.node);
        let axis = usize::from(d.direction) - 1;
        labels.push(format!("{node}.{}", AXES[axis]));
        let mut unit = vec![0.0; n];
        unit[i] = 1.0;
        kin_nodes.entry(node).or_default()[axis] = Some(unit);
    }
    labels.extend((1..=n - nb).map(|j| format!("cb_mode_{j}")));
    let damping = &r.mass * l.rayleigh_alpha_per_s.unwrap_or(0.0)
        + &r.stiffness * l.rayleigh_beta_s.unwrap_or(0.0);
    let s = Structure::lumped(labels, r.mass, damping, r.stiffness)
        .map_err(|e| Error::parse(&origin, 0, format!("the reduced model: {e}")))?;
    Ok((
        s,
        Kinematics {
            n,
            nodes: kin_nodes,
        },
        files,
    ))
}

/// Read a square matrix CSV: a `# unit: <unit>` line naming `unit`, a header of DOF labels,
/// and one row per DOF.
pub fn read_matrix(path: &Path, unit: &[&str]) -> Result<(Vec<String>, DMatrix<f64>)> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let mut found_unit = None;
    let mut labels: Option<Vec<String>> = None;
    let mut rows: Vec<Vec<f64>> = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let l = raw.trim();
        if l.is_empty() {
            continue;
        }
        if let Some(c) = l.strip_prefix('#') {
            if let Some(u) = c.trim().strip_prefix("unit:") {
                found_unit = Some((u.trim().to_string(), line));
            }
            continue;
        }
        let cells: Vec<&str> = l.split(',').map(|s| s.trim()).collect();
        match &labels {
            None => {
                for c in &cells {
                    if split_dof(c).is_none() {
                        return Err(Error::parse(
                            path,
                            line,
                            format!("header: `{c}` is not a DOF label `node.x|y|z|rx|ry|rz`"),
                        ));
                    }
                }
                labels = Some(cells.iter().map(|s| s.to_string()).collect());
            }
            Some(h) => {
                if cells.len() != h.len() {
                    return Err(Error::parse(
                        path,
                        line,
                        format!("expected {} values, found {}", h.len(), cells.len()),
                    ));
                }
                let mut row = Vec::with_capacity(cells.len());
                for c in cells {
                    let v: f64 = c
                        .parse()
                        .map_err(|_| Error::parse(path, line, format!("`{c}` is not a number")))?;
                    if !v.is_finite() {
                        return Err(Error::parse(path, line, format!("{v} is not finite")));
                    }
                    row.push(v);
                }
                rows.push(row);
            }
        }
    }
    match found_unit {
        Some((u, line)) if !unit.contains(&u.as_str()) => {
            return Err(Error::parse(
                path,
                line,
                format!("unit `{u}`, expected {}", unit.join(" or ")),
            ))
        }
        None => {
            return Err(Error::parse(
                path,
                0,
                format!("no `# unit: {}` line", unit[0]),
            ))
        }
        _ => {}
    }
    let labels = labels.ok_or_else(|| Error::parse(path, 0, "no header row"))?;
    let n = labels.len();
    if rows.len() != n {
        return Err(Error::parse(
            path,
            0,
            format!(
                "{} DOF labels but {} rows: the matrix must be square",
                n,
                rows.len()
            ),
        ));
    }
    let mut seen = HashMap::new();
    for l in &labels {
        if seen.insert(l.clone(), ()).is_some() {
            return Err(Error::parse(
                path,
                0,
                format!("DOF `{l}` appears twice in the header"),
            ));
        }
    }
    Ok((labels, DMatrix::from_fn(n, n, |r, c| rows[r][c])))
}

/// Modal data: frequencies (Hz), damping ratios, and shapes per (node, axis).
type Shapes = HashMap<(String, usize), Vec<f64>>;

fn read_modes(path: &Path) -> Result<(Vec<f64>, Vec<f64>)> {
    let mut rdr = crate::core::input::csv_reader(path)?;
    let h = rdr
        .headers()
        .map_err(|e| crate::core::input::csv_error(path, e))?
        .clone();
    if h.iter().ne(["mode", "frequency_Hz", "damping_ratio"]) {
        return Err(Error::parse(
            path,
            0,
            "expected the header `mode,frequency_Hz,damping_ratio`",
        ));
    }
    let (mut f, mut z) = (Vec::new(), Vec::new());
    for rec in rdr.records() {
        let (rec, line) = crate::core::input::csv_record(path, rec)?;
        let num = |i: usize, name: &str| -> Result<f64> {
            rec.get(i)
                .and_then(|s| s.parse::<f64>().ok())
                .filter(|v| v.is_finite())
                .ok_or_else(|| Error::parse(path, line, format!("`{name}` is not a finite number")))
        };
        let m = num(0, "mode")? as usize;
        if m != f.len() + 1 {
            return Err(Error::parse(
                path,
                line,
                format!("modes must be numbered 1, 2, … in order; got {m}"),
            ));
        }
        let (fr, zr) = (num(1, "frequency_Hz")?, num(2, "damping_ratio")?);
        if fr <= 0.0 {
            return Err(Error::parse(
                path,
                line,
                format!("`frequency_Hz` must be > 0, got {fr}"),
            ));
        }
        if zr < 0.0 {
            return Err(Error::parse(
                path,
                line,
                format!("negative damping: `damping_ratio` = {zr}"),
            ));
        }
        f.push(fr);
        z.push(zr);
    }
    if f.is_empty() {
        return Err(Error::parse(path, 0, "no modes"));
    }
    Ok((f, z))
}

fn read_shapes(path: &Path, n_modes: usize) -> Result<Shapes> {
    let mut rdr = crate::core::input::csv_reader(path)?;
    let h = rdr
        .headers()
        .map_err(|e| crate::core::input::csv_error(path, e))?
        .clone();
    let ok = h.len() == n_modes + 2
        && h.get(0) == Some("node")
        && h.get(1) == Some("direction")
        && (0..n_modes)
            .all(|r| h.get(r + 2) == Some(format!("mode_{}_per_sqrt_kg", r + 1).as_str()));
    if !ok {
        return Err(Error::parse(
            path,
            0,
            format!("expected the header `node,direction,mode_1_per_sqrt_kg,…,mode_{n_modes}_per_sqrt_kg` (mass-normalised shapes, one column per mode of the modes file)"),
        ));
    }
    let mut out = Shapes::new();
    for rec in rdr.records() {
        let (rec, line) = crate::core::input::csv_record(path, rec)?;
        let node = rec.get(0).unwrap_or("").to_string();
        let d = rec.get(1).unwrap_or("");
        let axis = AXES.iter().position(|a| *a == d).ok_or_else(|| {
            Error::parse(
                path,
                line,
                format!("direction `{d}`: expected x, y, z, rx, ry or rz"),
            )
        })?;
        let mut v = Vec::with_capacity(n_modes);
        for r in 0..n_modes {
            let s = rec.get(r + 2).unwrap_or("");
            let x: f64 = s
                .parse()
                .ok()
                .filter(|x: &f64| x.is_finite())
                .ok_or_else(|| {
                    Error::parse(
                        path,
                        line,
                        format!("mode {}: `{s}` is not a finite number", r + 1),
                    )
                })?;
            v.push(x);
        }
        if out.insert((node.clone(), axis), v).is_some() {
            return Err(Error::parse(
                path,
                line,
                format!("node {node} direction {} repeated", AXES[axis]),
            ));
        }
    }
    Ok(out)
}

/// How a node's displacement (x, y, z) and rotation (rx, ry, rz) depend on the coordinates: six
/// rows of length n.
struct Kinematics {
    n: usize,
    /// node → 6 rows (None for an axis without a DOF / shape: that component is zero).
    nodes: HashMap<String, [Option<Vec<f64>>; 6]>,
}

/// Where a contact element acts when it does not act at its nodes: its point in the
/// structure's axes (m) and the positions of the nodes whose rotations move it (`[nodes]`).
struct ContactPoint<'a> {
    point: [f64; 3],
    positions: &'a BTreeMap<String, [f64; 3]>,
}

/// Why a node pair could not be mapped.
enum PairError {
    /// The node is neither in the model nor `ground`.
    Unknown(String),
    /// The node rotates and the contact point is offset from it, but its position is not given.
    NoPosition(String),
    /// An offset contact point on a node of the next sector.
    OffsetAcrossSectors(String),
}

impl Kinematics {
    fn row(&self, label: &str) -> Option<Vec<f64>> {
        let (node, axis) = split_dof(label)?;
        self.nodes.get(node)?[axis].clone()
    }
    /// `R·(x_a − x_b)` at the contact point as a `3 × n` map of this sector's coordinates and,
    /// when a node is `next:<node>` (of the next sector), a `3 × n` map of the next sector's.
    /// A node's displacement at a point `p` offset from its position `c` is the rigid-body
    /// motion `u + θ × (p − c)` (its rotations enter only when the point is given).
    fn pair_map(
        &self,
        a: &str,
        b: &str,
        r: &[[f64; 3]; 3],
        point: Option<&ContactPoint<'_>>,
    ) -> std::result::Result<(DMatrix<f64>, Option<DMatrix<f64>>), PairError> {
        let mut p = DMatrix::zeros(3, self.n);
        let mut next: Option<DMatrix<f64>> = None;
        for (node, sign) in [(a, 1.0), (b, -1.0)] {
            if node == "ground" {
                continue;
            }
            let (target, name) = match node.strip_prefix(NEXT_SECTOR) {
                Some(name) => (next.get_or_insert_with(|| DMatrix::zeros(3, self.n)), name),
                None => (&mut p, node),
            };
            let rows = self
                .nodes
                .get(name)
                .ok_or_else(|| PairError::Unknown(node.to_string()))?;
            // Global displacement direction of each of the node's six rows at the point.
            let mut directions = [[0.0; 3]; 6];
            for (axis, d) in directions.iter_mut().enumerate().take(3) {
                d[axis] = 1.0;
            }
            let rotates = rows[3..].iter().any(Option::is_some);
            if let (Some(cp), true) = (point, rotates) {
                if node.starts_with(NEXT_SECTOR) {
                    return Err(PairError::OffsetAcrossSectors(node.to_string()));
                }
                let c = cp
                    .positions
                    .get(name)
                    .ok_or_else(|| PairError::NoPosition(node.to_string()))?;
                let arm = [cp.point[0] - c[0], cp.point[1] - c[1], cp.point[2] - c[2]];
                // e_j × arm for a unit rotation about axis j.
                directions[3] = [0.0, -arm[2], arm[1]];
                directions[4] = [arm[2], 0.0, -arm[0]];
                directions[5] = [-arm[1], arm[0], 0.0];
            }
            for (row, g) in rows.iter().zip(&directions) {
                if let Some(row) = row {
                    for c in 0..3 {
                        let w = sign * (r[c][0] * g[0] + r[c][1] * g[1] + r[c][2] * g[2]);
                        if w != 0.0 {
                            for j in 0..self.n {
                                target[(c, j)] += w * row[j];
                            }
                        }
                    }
                }
            }
        }
        Ok((p, next))
    }
}

/// Declare the model file's referenced files ([`referenced_files`]) as inputs of `out`: no
/// output of a command that reads the model may be one of them.
pub fn declare_inputs(out: &mut crate::core::output::OutputSet, model: &Path) -> Result<()> {
    for (role, p) in referenced_files(model)? {
        out.input(&p, &format!("{role} of {}", model.display()))?;
    }
    Ok(())
}

/// `(role, path)` of the model file and of every file it names (matrices or modes and shapes,
/// element tables, node pairs, load-following calibration tables), paths resolved against the model file's directory, without
/// reading those files: the inputs a command declares before it writes anything.
pub fn referenced_files(path: &Path) -> Result<Vec<(String, PathBuf)>> {
    crate::core::limits::check_file_size(path, crate::core::limits::MAX_TEXT_FILE_BYTES)?;
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let file = ModelFile::parse(&text, path)?;
    let base = path.parent().unwrap_or(Path::new("."));
    let mut files = vec![("model".to_string(), path.to_path_buf())];
    let l = &file.linear;
    for (role, p) in [
        ("mass", &l.mass),
        ("damping", &l.damping),
        ("stiffness", &l.stiffness),
        ("modes", &l.modes),
        ("shapes", &l.shapes),
    ] {
        if let Some(p) = p {
            files.push((format!("{role} matrix"), base.join(p)));
        }
    }
    if let Some(job) = &l.calculix {
        let [sti, mas, dof] = crate::dynamics::fe_matrices::calculix_paths(&base.join(job));
        files.push(("CalculiX stiffness".into(), sti));
        files.push(("CalculiX mass".into(), mas));
        files.push(("CalculiX DOF map".into(), dof));
    }
    for (role, p) in [
        ("FE stiffness", &l.fe_stiffness),
        ("FE mass", &l.fe_mass),
        ("FE DOF map", &l.fe_dofs),
    ] {
        if let Some(p) = p {
            files.push((role.to_string(), base.join(p)));
        }
    }
    for (ci, c) in file.contact.iter().enumerate() {
        files.push((
            format!("contact {} elements", ci + 1),
            base.join(&c.elements),
        ));
        if let Some(p) = &c.pairs {
            files.push((format!("contact {} pairs", ci + 1), base.join(p)));
        }
        if let Some(p) = &c.load_following {
            files.push((format!("contact {} load_following", ci + 1), base.join(p)));
        }
    }
    Ok(files)
}

/// Read the model file and everything it names; build the structure with its elements.
pub fn load(path: &Path) -> Result<LoadedModel> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let file = ModelFile::parse(&text, path)?;
    let base = path.parent().unwrap_or(Path::new("."));
    let resolve = |p: &Path| base.join(p);
    let mut inputs = vec![("model".to_string(), path.to_path_buf())];
    let l = &file.linear;
    let (mut structure, kin) =
        if let (Some(m), Some(c), Some(k)) = (&l.mass, &l.damping, &l.stiffness) {
            let (mp, cp, kp) = (resolve(m), resolve(c), resolve(k));
            let (lm, mm) = read_matrix(&mp, &["kg"])?;
            let (lc, cm) = read_matrix(&cp, &["N*s/m", "N·s/m", "Ns/m"])?;
            let (lk, km) = read_matrix(&kp, &["N/m"])?;
            for (p, lab) in [(&cp, &lc), (&kp, &lk)] {
                if lab != &lm {
                    return Err(Error::parse(
                        p,
                        0,
                        format!("DOF labels differ from those of {}", mp.display()),
                    ));
                }
            }
            let n = lm.len();
            let mut nodes: HashMap<String, [Option<Vec<f64>>; 6]> = HashMap::new();
            for (i, label) in lm.iter().enumerate() {
                let (node, axis) = split_dof(label).expect("checked by read_matrix");
                let mut row = vec![0.0; n];
                row[i] = 1.0;
                nodes.entry(node.to_string()).or_default()[axis] = Some(row);
            }
            let s = Structure::lumped(lm, mm, cm, km).map_err(|e| match e {
                Error::InvalidParameter { name, message } => {
                    let p = match name.as_str() {
                        "mass" => &mp,
                        "damping" => &cp,
                        _ => &kp,
                    };
                    Error::parse(p, 0, message)
                }
                o => o,
            })?;
            inputs.push(("mass".into(), mp));
            inputs.push(("damping".into(), cp));
            inputs.push(("stiffness".into(), kp));
            (s, Kinematics { n, nodes })
        } else if l.is_fe() {
            let (s, kin, files) = reduce_fe_model(l, base)?;
            inputs.extend(files);
            (s, kin)
        } else {
            let (mp, sp) = (
                resolve(l.modes.as_ref().expect("validated")),
                resolve(l.shapes.as_ref().expect("validated")),
            );
            let (f, z) = read_modes(&mp)?;
            let shapes = read_shapes(&sp, f.len())?;
            let mut nodes: HashMap<String, [Option<Vec<f64>>; 6]> = HashMap::new();
            for ((node, axis), v) in shapes {
                nodes.entry(node).or_default()[axis] = Some(v);
            }
            let s = Structure::modal(&f, &z).map_err(|e| Error::parse(&mp, 0, e.to_string()))?;
            inputs.push(("modes".into(), mp));
            inputs.push(("shapes".into(), sp));
            let n = f.len();
            (s, Kinematics { n, nodes })
        };
    if let Some(c) = &file.cyclic {
        let index = |key: &str, label: &str| {
            structure
                .labels
                .iter()
                .position(|l| l == label)
                .ok_or_else(|| {
                    Error::parse(
                        path,
                        key_line(&text, key),
                        format!(
                            "`cyclic.{key}`: unknown DOF `{label}` (expected node.x|y|z of the \
                             sector's matrices)"
                        ),
                    )
                })
        };
        let left = c
            .left
            .iter()
            .map(|l| index("left", l))
            .collect::<Result<Vec<_>>>()?;
        let right = c
            .right
            .iter()
            .map(|l| index("right", l))
            .collect::<Result<Vec<_>>>()?;
        structure
            .make_cyclic(c.sectors, c.engine_order, left, right)
            .map_err(|e| match e {
                Error::InvalidParameter { name, message } => {
                    let key = name.rsplit('.').next().unwrap_or(&name).to_string();
                    Error::parse(
                        path,
                        key_line(&text, &key),
                        format!("invalid `{name}`: {message}"),
                    )
                }
                o => o,
            })?;
    }
    let mut out_of_range = 0;
    let mut element_rows = Vec::new();
    for (ci, c) in file.contact.iter().enumerate() {
        let ep = resolve(&c.elements);
        let mut table: Vec<TableElement> = contact::read_element_table(&ep)?;
        if let Some(lf) = &c.load_following {
            if c.law != ContactLaw::Valanis {
                return Err(Error::parse(
                    path,
                    key_line(&text, "load_following"),
                    "`load_following` (kn(N), E0(N)) is a property of the `valanis` law",
                ));
            }
            let lf = resolve(lf);
            let calibration = crate::calibrate::table::CalibrationTable::read_csv(&lf)?;
            contact::set_load_exponents(&mut table, &ep, &calibration)?;
            inputs.push((format!("contact {} load_following", ci + 1), lf));
        }
        out_of_range += table.iter().filter(|e| e.out_of_range != 0).count();
        let frame = contact_frame(c.normal, c.tangent)?;
        let pairs = match &c.pairs {
            Some(pp) => {
                let pp = resolve(pp);
                let pairs = contact::read_pairs(&pp)?;
                inputs.push((format!("contact {} pairs", ci + 1), pp.clone()));
                Some((pp, pairs))
            }
            None => None,
        };
        for e in &table {
            let (a, b, where_, frame) = match &pairs {
                Some((pp, map)) => {
                    let row = map.get(&e.id).ok_or_else(|| {
                        Error::parse(
                            &ep,
                            e.line,
                            format!("element {} has no row in {}", e.id, pp.display()),
                        )
                    })?;
                    (
                        row.node_a.clone(),
                        row.node_b.clone(),
                        Error::parse(pp, row.line, ""),
                        row.frame.unwrap_or(frame),
                    )
                }
                None => (
                    c.node_a.clone().expect("validated"),
                    c.node_b.clone().expect("validated"),
                    Error::parse(&ep, e.line, ""),
                    frame,
                ),
            };
            if a == b {
                // The element acts on the relative displacement of its two nodes: with one node
                // it never moves and the contact does nothing.
                return Err(match &where_ {
                    Error::Parse { path, line, .. } => Error::parse(
                        path,
                        *line,
                        format!(
                            "element {}: node_a and node_b are the same node `{a}` (a contact \
                             needs two nodes, or `ground` for one side)",
                            e.id
                        ),
                    ),
                    _ => unreachable!(),
                });
            }
            let point = match c.film_origin_m {
                Some(o) => {
                    let (x, y) = e.position_m.ok_or_else(|| {
                        Error::parse(
                            &ep,
                            e.line,
                            "`film_origin_m` places every element at its `x_m`, `y_m`: the \
                             element table needs both columns (the table of `asperity elements`)",
                        )
                    })?;
                    let [t1, t2, _] = frame;
                    Some(ContactPoint {
                        point: std::array::from_fn(|i| o[i] + x * t1[i] + y * t2[i]),
                        positions: &file.nodes,
                    })
                }
                None => None,
            };
            let (map, next) = kin
                .pair_map(&a, &b, &frame, point.as_ref())
                .map_err(|err| {
                    let message = match err {
                        PairError::Unknown(node) => format!(
                            "contact node `{node}` {}",
                            if structure.is_modal() {
                                "has no mode shape"
                            } else {
                                "is not a node of the lumped model"
                            }
                        ),
                        PairError::NoPosition(node) => format!(
                            "contact node `{node}` rotates and the element acts at its own point \
                             (`film_origin_m`): give the node's position in [nodes]"
                        ),
                        PairError::OffsetAcrossSectors(node) => format!(
                            "contact node `{node}`: an element offset from a rotating node of \
                             the next sector is not supported (leave out `film_origin_m`)"
                        ),
                    };
                    match &where_ {
                        Error::Parse { path, line, .. } => {
                            Error::parse(path, *line, format!("element {}: {message}", e.id))
                        }
                        _ => unreachable!(),
                    }
                })?;
            let el = contact::element_for(c.law, e)
                .map_err(|err| Error::parse(&ep, e.line, err.to_string()))?;
            attach_pair(
                &mut structure,
                format!("{}", e.id),
                el,
                map,
                next,
                || match &where_ {
                    Error::Parse { path, line, .. } => Error::parse(
                        path,
                        *line,
                        format!(
                            "element {}: a node of the next sector (`{NEXT_SECTOR}…`) needs a \
                             [cyclic] section in the model file",
                            e.id
                        ),
                    ),
                    _ => unreachable!(),
                },
            )?;
            element_rows.push((c.law, e.clone()));
        }
        inputs.push((format!("contact {} elements", ci + 1), ep));
    }
    for (ji, j) in file.joint.iter().enumerate() {
        let norm = j.direction.iter().map(|v| v * v).sum::<f64>().sqrt();
        let d = j.direction.map(|v| v / norm);
        let frame = [d, [0.0; 3], [0.0; 3]];
        let (map, next) = kin
            .pair_map(&j.node_a, &j.node_b, &frame, None)
            .map_err(|err| {
                let (PairError::Unknown(node)
                | PairError::NoPosition(node)
                | PairError::OffsetAcrossSectors(node)) = err;
                let what = if structure.is_modal() {
                    "has no mode shape"
                } else {
                    "is not a node of the lumped model"
                };
                Error::parse(
                    path,
                    key_line(&text, if node == j.node_a { "node_a" } else { "node_b" }),
                    format!("joint {}: node `{node}` {what}", ji + 1),
                )
            })?;
        let el = j.element().expect("validated by parse");
        let label = format!("joint {}", ji + 1);
        let first_row = |m: DMatrix<f64>| m.rows(0, 1).into_owned();
        attach_pair(
            &mut structure,
            label,
            el,
            first_row(map),
            next.map(first_row),
            || {
                Error::parse(
                    path,
                    key_line(&text, "node_a"),
                    format!(
                        "joint {}: a node of the next sector (`{NEXT_SECTOR}…`) needs a [cyclic] \
                     section in the model file",
                        ji + 1
                    ),
                )
            },
        )?;
    }
    let dof_err = |key: &str, label: &str| {
        Error::parse(
            path,
            key_line(&text, key),
            format!("`{key}`: unknown DOF `{label}` (expected node.x|y|z of the model)"),
        )
    };
    let mut force = DVector::zeros(structure.n());
    let phases = file.excitation.phases_deg.as_ref();
    let mut force_sin = phases.map(|_| DVector::zeros(structure.n()));
    for (i, d) in file.excitation.dofs.iter().enumerate() {
        let w = file
            .excitation
            .weights
            .as_ref()
            .map(|w| w[i])
            .unwrap_or(1.0);
        let row = DVector::from_vec(kin.row(d).ok_or_else(|| dof_err("dofs", d))?);
        // w·cos(eωt + θ) = w·cos θ·cos eωt − w·sin θ·sin eωt.
        let (s, c) = phases.map_or(0.0, |p| p[i].to_radians()).sin_cos();
        force += &row * (w * c);
        if let Some(fs) = force_sin.as_mut() {
            *fs -= &row * (w * s);
        }
    }
    if force.amax() == 0.0 && force_sin.as_ref().is_none_or(|f| f.amax() == 0.0) {
        // Weights that cancel, or mode shapes that vanish at every excitation DOF: the
        // structure would not be excited and every response would be zero.
        return Err(Error::parse(
            path,
            key_line(&text, "dofs"),
            "`excitation.dofs`: the excitation force on the structure is zero (weights that \
             cancel, or mode shapes that are zero at every excitation DOF)",
        ));
    }
    let static_force = match &file.static_load {
        None => None,
        Some(st) => {
            if st.dofs.len() != st.forces_n.len() || st.dofs.is_empty() {
                return Err(Error::parse(
                    path,
                    key_line(&text, "forces_n"),
                    format!(
                        "`static`: {} DOFs and {} forces_n (one force per DOF, at least one)",
                        st.dofs.len(),
                        st.forces_n.len()
                    ),
                ));
            }
            if let Some(f) = st.forces_n.iter().find(|f| !f.is_finite()) {
                return Err(Error::parse(
                    path,
                    key_line(&text, "forces_n"),
                    format!("`static.forces_n`: {f} is not finite"),
                ));
            }
            if !file.sweep.odd_only {
                let mut f0 = DVector::zeros(structure.n());
                for (d, &f) in st.dofs.iter().zip(&st.forces_n) {
                    let row = DVector::from_vec(kin.row(d).ok_or_else(|| dof_err("dofs", d))?);
                    f0 += &row * f;
                }
                Some(f0)
            } else {
                return Err(Error::parse(
                    path,
                    key_line(&text, "odd_only"),
                    "`[static]` needs the mean (harmonic 0) in the balance: set `sweep.odd_only = \
                     false`",
                ));
            }
        }
    };
    let mut responses = Vec::new();
    for d in &file.response.dofs {
        let row = kin.row(d).ok_or_else(|| dof_err("dofs", d))?;
        responses.push((d.clone(), DVector::from_vec(row)));
    }
    Ok(LoadedModel {
        file,
        path: path.to_path_buf(),
        structure,
        force,
        force_sin,
        static_force,
        responses,
        inputs,
        out_of_range,
        element_rows,
    })
}
