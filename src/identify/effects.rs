//! Candidate structure-level effects beyond the baseline single-nonlinear-mode model, each with
//! one or two parameters and a physical meaning. A multi-DOF reduced model takes those that act
//! on its response coordinate, the level or the measurement chain
//! ([`super::reduced::REDUCED_EFFECTS`], laws in [`super::reduced`]).
//!
//! | effect | law | parameters |
//! |---|---|---|
//! | Valanis joint (microslip family) | the joint is a Valanis element (Gaul–Lenz form, `E0 = k_t`, `σ0 = F_s`, `Et = 0`) instead of a Jenkins slider: gradual microslip instead of an abrupt stick–slip transition | shape `k` |
//! | Iwan joint (power-law microslip) | the joint is a four-parameter Iwan element (Segalman 2005, power-law slip-strength density, `crate::element::iwan`) instead of a Jenkins slider: dissipation `∝ A^{3+χ}` at small amplitude, `K_T = k_t`, `F_S = F_s` | exponent `χ ∈ [−0.9, 0]`, strength ratio `β ∈ [0, 4]` |
//! | amplitude-dependent stiffness | cubic spring `k3·u³` on the drive-point coordinate (geometric or contact stiffening, or softening) | `ε = 3k3·A_ref²/(4k_s)`: relative change of `ω²` at the reference amplitude |
//! | amplitude-proportional stiffness | quadratic spring `k2·|u|·u` on the drive-point coordinate: a stiffness that changes in proportion to the amplitude (`(8/3π)·k2·A`; softening for `k2 < 0`: the contact stiffness a joint loses to microslip, here without the dissipation a Masing element ties to it; hardening: a contact area growing with load). With the cubic spring it gives a backbone that first softens and then stiffens | `ε1 = 8k2·A_ref/(3π·k_s)`: relative change of `ω²` at the reference amplitude |
//! | quadratic (amplitude-dependent viscous) damping | `c2·|u̇|·u̇` (air drag, acoustic radiation): a damping ratio growing `∝ A` with no loss of stiffness | `ζ_q`: equivalent damping ratio added at the reference amplitude, `c2 = 3π·m·ζ_q/(4·A_ref)` |
//! | power-law damping | `c_p·|u̇|^p·u̇`: a damping ratio growing `∝ A^p` with no loss of stiffness (the empirical law of amplitude-dependent joint and material damping, `ζ = ζ0 + c·A^p`; nests the quadratic damper at `p = 1`) | `ζ_p` at the reference amplitude and `p ∈ [0.25, 3]`, `c_p = 2π·m·ζ_p/(A_ref^p·ω_s^{p−1}·I(p+2))`, `I(n) = ∫₀^{2π}|sin θ|ⁿdθ` |
//! | joint preload loss | the joint's slip force and stiffness fall with the excitation level the joint has seen (bolt relaxation from test to test; levels run from low to high): `F_s, k_t × (1 − λ·F̄/F_ref)` | `λ` |
//! | higher harmonics | harmonics 1, 3, …, 9 instead of 1, 3 in the balance | none |
//! | out-of-band modes | a constant residual receptance `r = ρ/k_s` (m/N) added at the drive point (the other modes' flexibility, rigid-body mass line of a free structure) | `ρ` |
//! | shaker–structure interaction | the force transducer sits on the shaker side of the stinger: the stinger's transmission and the channels' skew appear as a delay `τ` between the measured force and the force entering the structure, `Y → Y·e^{−iωτ}` | `τ` (s) |
//!
//! Linear viscous damping and linear hysteretic (loss-factor) damping are not candidates: over a
//! sweep band of a few per cent about one resonance the two differ only by the factor `ω/ω_n`
//! (±1 %), and both are the baseline's `ζ0`. Their amplitude-dependent forms are the candidates
//! (quadratic damping; the joint families). A drive-point mass loading (stinger and transducer
//! mass below the gauge) is not a candidate either: on a single mode it rescales `m` and `ω`
//! exactly and cannot be told from them.

use serde::{Deserialize, Serialize};

/// A candidate effect (model extension beyond the baseline).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Effect {
    /// The joint is a Valanis element (Gaul–Lenz form) instead of a Jenkins slider; parameter: shape `k`.
    ValanisJoint,
    /// The joint is a four-parameter Iwan element (Segalman 2005); parameters: exponent `χ`,
    /// strength ratio `β`.
    IwanJoint,
    /// Cubic spring `k3·u³` at the drive point; parameter: relative change `ε` of `ω²` at `A_ref`.
    AmplitudeStiffness,
    /// Quadratic spring `k2·|u|·u` at the drive point; parameter: relative change `ε1` of `ω²` at
    /// `A_ref`.
    QuadraticStiffness,
    /// Quadratic damper `c2·|u̇|·u̇`; parameter: damping ratio `ζ_q` added at `A_ref`.
    QuadraticDamping,
    /// Power-law damper `c_p·|u̇|^p·u̇`; parameters: `ζ_p` at `A_ref` and exponent `p`.
    PowerLawDamping,
    /// Joint slip force and stiffness scaled by `1 − λ·F̄/F_ref`; parameter: `λ`.
    PreloadLoss,
    /// Harmonics 1, 3, …, 9 in the balance instead of 1, 3; no parameter.
    HigherHarmonics,
    /// Constant residual receptance `ρ/k_s` (m/N) at the drive point; parameter: `ρ`.
    OutOfBandModes,
    /// Delay between measured force and force into the structure, `Y → Y·e^{−iωτ}`; parameter: `τ` (s).
    ShakerInteraction,
}

impl Effect {
    /// Every candidate, in the order they are tested.
    pub const ALL: [Effect; 10] = [
        Effect::ValanisJoint,
        Effect::IwanJoint,
        Effect::AmplitudeStiffness,
        Effect::QuadraticStiffness,
        Effect::QuadraticDamping,
        Effect::PowerLawDamping,
        Effect::PreloadLoss,
        Effect::HigherHarmonics,
        Effect::OutOfBandModes,
        Effect::ShakerInteraction,
    ];

    /// Identifier used in reports, JSON and on the command line.
    pub fn id(self) -> &'static str {
        match self {
            Effect::ValanisJoint => "valanis_joint",
            Effect::IwanJoint => "iwan_joint",
            Effect::AmplitudeStiffness => "amplitude_stiffness",
            Effect::QuadraticStiffness => "quadratic_stiffness",
            Effect::QuadraticDamping => "quadratic_damping",
            Effect::PowerLawDamping => "power_law_damping",
            Effect::PreloadLoss => "preload_loss",
            Effect::HigherHarmonics => "higher_harmonics",
            Effect::OutOfBandModes => "out_of_band_modes",
            Effect::ShakerInteraction => "shaker_interaction",
        }
    }

    /// Parse an identifier.
    pub fn from_id(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|e| e.id() == s)
    }

    /// One-line physical meaning.
    pub fn meaning(self) -> &'static str {
        match self {
            Effect::ValanisJoint => {
                "gradual microslip in the joint (Valanis element) instead of abrupt stick-slip"
            }
            Effect::IwanJoint => {
                "power-law microslip in the joint (Iwan element): dissipation grows as A^(3+chi)"
            }
            Effect::AmplitudeStiffness => {
                "stiffness changes with amplitude (cubic spring: geometric or contact stiffening)"
            }
            Effect::QuadraticStiffness => {
                "stiffness changes in proportion to amplitude (quadratic spring: joint contact stiffness)"
            }
            Effect::QuadraticDamping => {
                "damping grows with velocity amplitude without stiffness loss (air drag, radiation)"
            }
            Effect::PowerLawDamping => {
                "damping grows as a power of the amplitude without stiffness loss (joint/material)"
            }
            Effect::PreloadLoss => {
                "joint slip force and stiffness fall with the excitation level seen (preload loss)"
            }
            Effect::HigherHarmonics => "harmonics up to 9 in the balance instead of 3",
            Effect::OutOfBandModes => {
                "residual flexibility of the other modes at the drive point (constant receptance)"
            }
            Effect::ShakerInteraction => {
                "delay between measured force and force into the structure (stinger, channels)"
            }
        }
    }

    /// Whether the effect replaces the joint element (the two families exclude each other).
    pub fn is_family(self) -> bool {
        matches!(self, Effect::ValanisJoint | Effect::IwanJoint)
    }

    /// The candidate this effect contains as a special case, if any: a start from that
    /// candidate's optimum (extended by [`Effect::nested_values`]) makes the larger fit at least
    /// as good as the nested one. The power law is the quadratic damper at `p = 1`.
    pub fn nests(self) -> Option<Effect> {
        match self {
            Effect::PowerLawDamping => Some(Effect::QuadraticDamping),
            _ => None,
        }
    }

    /// This effect's parameter values that reproduce the nested effect's: the nested effect's
    /// values followed by the extra ones (`ζ_p = ζ_q`, `p = 1` for the power law).
    pub fn nested_values(self) -> &'static [f64] {
        match self {
            Effect::PowerLawDamping => &[1.0],
            _ => &[],
        }
    }

    /// Whether the effect is an amplitude-dependent damping law (the quadratic damper is the
    /// power law at `p = 1`: at most one of them in a model).
    pub fn is_damping_law(self) -> bool {
        matches!(self, Effect::QuadraticDamping | Effect::PowerLawDamping)
    }
}
