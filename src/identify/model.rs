//! The single-nonlinear-mode model of a jointed structure and its evaluation by harmonic
//! balance at measured frequencies and forces.
//!
//! # Equation
//!
//! One mass-normalised mode `q` (shape `φ` at the drive point, `m = 1/φ²` the modal mass seen at
//! the drive point), a joint element acting on the modal coordinate, and the candidate effects
//! of [`super::effects`]:
//!
//! ```text
//! q̈ + 2ζ0·ω_s·q̇ + ω0²·q + φ·f_joint(φq) + φ·f_effects(φq, φq̇) = φ·F·cos ωt,      u = φ·q
//! ω_s² = ω0² + k_t/m          (the small-amplitude, stuck-joint natural frequency)
//! ```
//!
//! Multiplied by `1/φ²` this is the drive-point form `m·ü + c·u̇ + k·u + f_joint(u) = F cos ωt`
//! with `k = m·ω0²`, `c = 2ζ0·m·ω_s`, which is how the parameters are stated (SI, N and m):
//!
//! | parameter | meaning | unit |
//! |---|---|---|
//! | `frequency_Hz` | `f_s = ω_s/2π`, natural frequency with the joint stuck (amplitude → 0) | Hz |
//! | `damping_ratio` | `ζ0`, linear modal damping (material, boundary, air) | – |
//! | `modal_mass_kg` | `m = 1/φ²`, modal mass at the drive point | kg |
//! | `joint_stiffness_share` | `κ = k_t/(m·ω_s²)`: share of the modal stiffness carried by the joint's stick stiffness (`f` falls to `f_s·√(1−κ)` in gross slip) | – |
//! | `slip_displacement_m` | `δ = F_s/k_t`: joint displacement at which it slips (Jenkins) or its microslip scale (`σ0/E0`, Valanis; `F_S/K_T`, Iwan) | m |
//!
//! plus the family's shape parameters and those of the effects ([`ModelSpec::params`]).
//!
//! # Evaluation
//!
//! [`crate::dynamics`]: `Structure::single_mode(f0, ζ')` with `f0 = f_s·√(1−κ)`,
//! `ζ' = ζ0·ω_s/ω0`, the joint attached with map `φ`, excitation `φ` per newton, harmonics
//! 1, 3 (odd orders: the joint laws are odd and the forcing is a pure cosine, so the steady state
//! has half-wave symmetry), Newton at each measured frequency with the measured force of the row,
//! warm-started from the previous row of the sweep (the rows are in sweep order). The model's
//! fundamental is compared with the measured fundamental. A row where Newton fails from the warm
//! start is retried from the linear stuck-joint and slipped-joint responses and by a ramp of the
//! force; a row that still fails is an error naming the frequency.

use super::effects::Effect;
use crate::core::error::{Error, Result};
use crate::dynamics::aft::{self, AftSettings, Harmonics};
use crate::dynamics::hbm::{Excitation, FormulationChoice, HbmPoint, HbmSystem};
use crate::dynamics::model::Structure;
use crate::element::power_law_damper::sine_power_cycle_integral;
use crate::element::{
    CubicSpring, GaulLenz, GaulLenzParams, HystereticElement, IwanElement, IwanParams, Jenkins,
    PowerLawDamper, QuadraticSpring,
};
use nalgebra::{DMatrix, DVector};
use realfft::num_complex::Complex64;
use serde::{Deserialize, Serialize};
use std::f64::consts::{PI, TAU};
use std::sync::Arc;

/// Constitutive law of the joint element.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Family {
    /// Spring `k_t` in series with a Coulomb slider `F_s` (macroslip).
    Jenkins,
    /// Valanis element, Gaul–Lenz form (`E0 = k_t`, `σ0 = F_s`, `Et = 0`, shape `k`).
    Valanis,
    /// Iwan element with Segalman's power-law density (`K_T = k_t`, `F_S = F_s`, exponent `χ`,
    /// strength ratio `β`), discretised into [`IWAN_SLIDERS`] Jenkins sliders.
    Iwan,
}

/// Jenkins sliders of the Iwan joint's distributed part. The backbone is exact at the slider
/// nodes; the cycle's dissipation is within 4 % of Segalman's closed form from 0.1 to 0.9 `φ_max`
/// for `χ = −0.5`, and within 4 % from 0.2 `φ_max` for `χ = 0` (the equal-stiffness split puts
/// few sliders at small slip displacements; 24 sliders halve these errors at 2× the cost of an
/// AFT evaluation, which grows as the square of the state size).
pub const IWAN_SLIDERS: usize = 16;

/// Reference scales taken from the data, used to state bounds and the dimensionless effect
/// parameters (saved with the model so that the parameters keep their meaning).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scales {
    /// Reference frequency (Hz): the median measured resonance frequency of the fit levels.
    pub frequency_hz: f64,
    /// Reference modal mass (kg): the equivalent linear fit of the lowest fit level.
    pub modal_mass_kg: f64,
    /// Largest peak drive-point displacement amplitude of the fit levels (m).
    pub amplitude_max_m: f64,
    /// Smallest peak drive-point displacement amplitude of the fit levels (m).
    pub amplitude_min_m: f64,
    /// Largest mean force of the fit levels (N).
    pub force_n: f64,
}

impl Scales {
    /// Scales read from a file are finite and > 0 (the error names the field).
    pub fn check(&self) -> std::result::Result<(), String> {
        for (name, v) in [
            ("frequency_hz", self.frequency_hz),
            ("modal_mass_kg", self.modal_mass_kg),
            ("amplitude_max_m", self.amplitude_max_m),
            ("amplitude_min_m", self.amplitude_min_m),
            ("force_n", self.force_n),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("{name} = {v}: must be finite and > 0"));
            }
        }
        Ok(())
    }
}

/// A bounded physical parameter ([`crate::core::fit::ParamSpec`]: searched on the unit box,
/// linearly or in `ln` between its bounds; its start is the value of "effect absent", or a
/// central start, used as the first local start).
pub use crate::core::fit::ParamSpec;

/// A parameter within this fraction of its box of a bound is reported as sitting on it (a
/// parameter on a bound is not identified by the data).
pub const AT_BOUND_MARGIN: f64 = 0.005;

/// Serialise parameters as reports state them: name, unit, bounds `lo`, `hi`, whether searched
/// in `ln` (`log`) and the start (`neutral`).
pub fn serialize_params<S: serde::Serializer>(
    params: &[ParamSpec],
    serializer: S,
) -> std::result::Result<S::Ok, S::Error> {
    #[derive(Serialize)]
    struct Stated<'a> {
        name: &'a str,
        unit: &'a str,
        lo: f64,
        hi: f64,
        log: bool,
        neutral: f64,
    }
    serializer.collect_seq(params.iter().map(|p| Stated {
        name: p.name,
        unit: p.unit,
        lo: p.lo,
        hi: p.hi,
        log: p.transform == crate::core::fit::Transform::Log,
        neutral: p.start,
    }))
}

/// Whether `v` lies within [`AT_BOUND_MARGIN`] of the box width of a bound of `p`.
pub fn at_bound(p: &ParamSpec, v: f64) -> bool {
    p.bound_at(v, AT_BOUND_MARGIN).is_some()
}

/// Structure of a model: the joint family, the effects added and the scales.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelSpec {
    /// Family of the baseline joint (a family effect replaces it).
    pub family: Family,
    /// Effects added to the baseline, in the order they were accepted.
    pub effects: Vec<Effect>,
    /// Reference scales of the dimensionless parameters (from the fit levels' data).
    pub scales: Scales,
}

/// Number of parameters of the baseline mode (frequency, damping, mass, joint share, slip).
pub const BASE_PARAMS: usize = 5;

impl ModelSpec {
    /// The baseline model of a family.
    pub fn baseline(family: Family, scales: Scales) -> Self {
        Self {
            family,
            effects: Vec::new(),
            scales,
        }
    }

    /// This spec with one more effect.
    pub fn with(&self, e: Effect) -> Self {
        let mut s = self.clone();
        s.effects.push(e);
        s
    }

    /// The joint family in force (a family effect overrides the baseline's).
    pub fn joint_family(&self) -> Family {
        if self.effects.contains(&Effect::ValanisJoint) {
            Family::Valanis
        } else if self.effects.contains(&Effect::IwanJoint) {
            Family::Iwan
        } else {
            self.family
        }
    }

    /// Highest harmonic of the balance (odd harmonics only).
    pub fn harmonics(&self) -> usize {
        if self.effects.contains(&Effect::HigherHarmonics) {
            9
        } else {
            3
        }
    }

    /// Whether `e` may be added: not already present, a family change only from Jenkins, and
    /// one amplitude-dependent damping law at most (they nest).
    pub fn admits(&self, e: Effect) -> bool {
        let family_change_allowed = !e.is_family() || self.joint_family() == Family::Jenkins;
        let damping_law_free =
            !e.is_damping_law() || !self.effects.iter().any(|x| x.is_damping_law());
        !self.effects.contains(&e) && family_change_allowed && damping_law_free
    }

    /// The spec with the accepted effect that `e` nests replaced by `e`, and `values` (a model
    /// of this spec) mapped onto it so that it is the same model
    /// ([`Effect::nested_values`] inserted after the nested effect's own values); `None` when
    /// `e` nests no effect of this spec. This is how the search generalises an accepted effect
    /// (the quadratic damper to the power law) on held-out evidence for the extra parameter.
    pub fn generalised(&self, e: Effect, values: &[f64]) -> Option<(Self, Vec<f64>)> {
        let nested = e.nests()?;
        let at = self.effects.iter().position(|&x| x == nested)?;
        let mut spec = self.clone();
        spec.effects[at] = e;
        let before = ModelSpec {
            effects: self.effects[..at].to_vec(),
            ..self.clone()
        }
        .params()
        .len();
        let end = before + effect_params(nested, &self.scales).len();
        let mut v = values[..end].to_vec();
        v.extend(e.nested_values());
        v.extend(&values[end..]);
        Some((spec, v))
    }

    /// Parameters, in order: the mode, the family's shape, then each effect's.
    pub fn params(&self) -> Vec<ParamSpec> {
        let s = &self.scales;
        let mut p = vec![
            ParamSpec::linear(
                "frequency_Hz",
                "Hz",
                0.97 * s.frequency_hz,
                1.03 * s.frequency_hz,
                s.frequency_hz,
            ),
            ParamSpec::log("damping_ratio", "-", 1e-5, 0.05, 1e-3),
            ParamSpec::log(
                "modal_mass_kg",
                "kg",
                0.2 * s.modal_mass_kg,
                5.0 * s.modal_mass_kg,
                s.modal_mass_kg,
            ),
            ParamSpec::log("joint_stiffness_share", "-", 1e-4, 0.5, 0.01),
            ParamSpec::log(
                "slip_displacement_m",
                "m",
                0.01 * s.amplitude_min_m,
                10.0 * s.amplitude_max_m,
                s.amplitude_min_m,
            ),
        ];
        match self.family {
            Family::Jenkins => {}
            Family::Valanis => p.push(valanis_shape()),
            Family::Iwan => p.extend(iwan_shape()),
        }
        for e in &self.effects {
            p.extend(effect_params(*e, s));
        }
        p
    }
}

fn iwan_shape() -> [ParamSpec; 2] {
    [
        ParamSpec::linear("iwan_exponent_chi", "-", -0.9, 0.0, -0.5),
        ParamSpec::linear("iwan_strength_ratio_beta", "-", 0.0, 4.0, 0.5),
    ]
}

fn valanis_shape() -> ParamSpec {
    ParamSpec::linear("valanis_shape_k", "-", 0.0, 0.95, 0.5)
}

/// Parameters of one effect (see [`super::effects`] for the laws).
pub fn effect_params(e: Effect, s: &Scales) -> Vec<ParamSpec> {
    match e {
        Effect::ValanisJoint => vec![valanis_shape()],
        Effect::IwanJoint => iwan_shape().to_vec(),
        Effect::AmplitudeStiffness => vec![ParamSpec::linear(
            "stiffness_change_at_ref_amplitude",
            "-",
            -0.05,
            0.05,
            0.0,
        )],
        Effect::QuadraticStiffness => vec![ParamSpec::linear(
            "proportional_stiffness_change_at_ref_amplitude",
            "-",
            -0.05,
            0.05,
            0.0,
        )],
        Effect::QuadraticDamping => vec![ParamSpec::log(
            "quadratic_damping_ratio_at_ref_amplitude",
            "-",
            1e-6,
            0.05,
            1e-6,
        )],
        Effect::PowerLawDamping => vec![
            ParamSpec::log(
                "power_law_damping_ratio_at_ref_amplitude",
                "-",
                1e-6,
                0.05,
                1e-6,
            ),
            ParamSpec::linear(
                "power_law_damping_exponent",
                "-",
                POWER_LAW_EXPONENT_MIN,
                POWER_LAW_EXPONENT_MAX,
                1.0,
            ),
        ],
        Effect::PreloadLoss => vec![ParamSpec::linear(
            "preload_loss_per_ref_force",
            "-",
            0.0,
            0.9,
            0.0,
        )],
        Effect::HigherHarmonics => vec![],
        Effect::OutOfBandModes => vec![ParamSpec::linear(
            "residual_flexibility_ratio",
            "-",
            -3.0,
            3.0,
            0.0,
        )],
        Effect::ShakerInteraction => {
            let t = 1.0 / (20.0 * s.frequency_hz);
            vec![ParamSpec::linear("force_delay_s", "s", -t, t, 0.0)]
        }
    }
}

/// Factor on a joint's slip force and stiffness after a preload loss `λ` per reference force:
/// `1 − λ·F̄/F_ref` at a level of mean force `F̄`, at least 0.05 (a joint never loses all
/// its preload within a test series).
pub fn preload_factor_law(lambda: f64, mean_force_n: f64, force_ref_n: f64) -> f64 {
    (1.0 - lambda * mean_force_n / force_ref_n).max(0.05)
}

/// Cubic stiffness `k3` (N/m³) whose describing-function stiffness `(3/4)·k3·A²` is `ε·k` at
/// the reference amplitude `A_ref`: `k3 = 4ε·k/(3·A_ref²)`.
pub fn cubic_stiffness_law(eps: f64, k: f64, a_ref: f64) -> f64 {
    4.0 * eps * k / (3.0 * a_ref * a_ref)
}

/// Quadratic stiffness `k2` (N/m²) of `k2·|u|·u` whose describing-function stiffness
/// `(8/3π)·k2·A` is `ε1·k` at the reference amplitude `A_ref`: `k2 = 3π·ε1·k/(8·A_ref)`.
pub fn quadratic_stiffness_law(eps: f64, k: f64, a_ref: f64) -> f64 {
    3.0 * PI * eps * k / (8.0 * a_ref)
}

/// A model with parameter values (physical units, in the order of [`ModelSpec::params`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Model {
    /// Structure of the model: family, effects and scales.
    pub spec: ModelSpec,
    /// Parameter values in physical units, in the order and units of [`ModelSpec::params`].
    pub values: Vec<f64>,
}

/// Drive-point quantities of a model.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Physical {
    /// Stuck-joint angular frequency ω_s (rad/s).
    pub omega_s: f64,
    /// Modal mass m (kg).
    pub mass_kg: f64,
    /// Linear stiffness without the joint, k = m·ω0² (N/m).
    pub k_linear: f64,
    /// Viscous coefficient c = 2ζ0·m·ω_s (N·s/m).
    pub c_linear: f64,
    /// Joint stick stiffness `k_t` (N/m).
    pub k_joint: f64,
    /// Joint slip force `F_s` (N).
    pub slip_force_n: f64,
}

/// Range of the power-law damping exponent `p` (`p = 0` would be the linear `ζ0`, `p = 1` the
/// quadratic damper; above 3 the damping would grow faster than any measured joint law).
pub const POWER_LAW_EXPONENT_MIN: f64 = 0.25;
/// Largest power-law damping exponent `p`.
pub const POWER_LAW_EXPONENT_MAX: f64 = 3.0;

/// One point to evaluate: angular frequency and force amplitude.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Drive {
    /// Excitation angular frequency (rad/s).
    pub omega: f64,
    /// Drive force amplitude (N).
    pub force_n: f64,
}

/// What a failed row was.
#[derive(Debug, Clone)]
pub struct RowFailure {
    /// Index of the row in the list evaluated.
    pub index: usize,
    /// The solver's error message.
    pub error: String,
}

/// Solve a sweep row by row in its order, each row warm-started from the previous row's
/// unknowns scaled by the force ratio. `solve(drive, warm)` gives the row's receptance (m/N) and
/// unknowns. With `tolerant`, a row that fails is recorded (its value NaN) and the next row
/// starts cold; otherwise the first failure ends the sweep.
pub fn solve_sweep(
    drives: &[Drive],
    tolerant: bool,
    mut solve: impl FnMut(&Drive, Option<&DVector<f64>>) -> Result<(Complex64, DVector<f64>)>,
) -> Result<(Vec<Complex64>, Vec<RowFailure>)> {
    let mut out = Vec::with_capacity(drives.len());
    let mut failures = Vec::new();
    let mut guess: Option<(DVector<f64>, f64)> = None;
    for (i, d) in drives.iter().enumerate() {
        let warm = guess.as_ref().map(|(z, f)| z * (d.force_n / f));
        match solve(d, warm.as_ref()) {
            Ok((x, z)) => {
                out.push(x);
                guess = Some((z, d.force_n));
            }
            Err(e) => {
                if !tolerant {
                    return Err(e);
                }
                failures.push(RowFailure {
                    index: i,
                    error: e.to_string(),
                });
                out.push(Complex64::new(f64::NAN, f64::NAN));
                guess = None;
            }
        }
    }
    Ok((out, failures))
}

impl Model {
    /// Build and check the value count and bounds (values outside the bounds are refused:
    /// a saved model must describe the physics it was fitted with).
    pub fn new(spec: ModelSpec, values: Vec<f64>) -> Result<Self> {
        check_values(&spec.params(), &values)?;
        Ok(Self { spec, values })
    }

    /// The model at the neutral values of every parameter.
    pub fn neutral(spec: ModelSpec) -> Self {
        let values = spec.params().iter().map(|p| p.start).collect();
        Self { spec, values }
    }

    /// Value of a parameter by name.
    pub fn get(&self, name: &str) -> Option<f64> {
        self.spec
            .params()
            .iter()
            .position(|p| p.name == name)
            .map(|i| self.values[i])
    }

    fn value(&self, name: &str) -> f64 {
        self.get(name)
            .unwrap_or_else(|| panic!("parameter {name} of the spec"))
    }

    /// The drive-point quantities.
    pub fn physical(&self) -> Physical {
        let omega_s = TAU * self.values[0];
        let zeta = self.values[1];
        let m = self.values[2];
        let kappa = self.values[3];
        let delta = self.values[4];
        let ks = m * omega_s * omega_s;
        let kt = kappa * ks;
        Physical {
            omega_s,
            mass_kg: m,
            k_linear: ks - kt,
            c_linear: 2.0 * zeta * m * omega_s,
            k_joint: kt,
            slip_force_n: kt * delta,
        }
    }

    /// Factor on the joint's slip force and stiffness at a level of mean force `mean_force_n`
    /// (preload loss; 1 without it).
    pub fn preload_factor(&self, mean_force_n: f64) -> f64 {
        self.get("preload_loss_per_ref_force").map_or(1.0, |l| {
            preload_factor_law(l, mean_force_n, self.spec.scales.force_n)
        })
    }

    /// The joint element at a preload factor.
    pub fn joint(&self, preload: f64) -> Result<Arc<dyn HystereticElement>> {
        let ph = self.physical();
        let (kt, fs) = (ph.k_joint * preload, ph.slip_force_n * preload);
        Ok(match self.spec.joint_family() {
            Family::Jenkins => Arc::new(Jenkins::new(kt, fs)?),
            Family::Valanis => Arc::new(GaulLenz::new(&GaulLenzParams {
                e0: kt,
                k: self.value("valanis_shape_k"),
                et: 0.0,
                sigma0: fs,
            })?),
            Family::Iwan => Arc::new(IwanElement::new(
                IwanParams::new(
                    fs,
                    kt,
                    self.value("iwan_exponent_chi"),
                    self.value("iwan_strength_ratio_beta"),
                )?,
                IWAN_SLIDERS,
            )?),
        })
    }

    /// Cubic stiffness `k3` (N/m³) of the amplitude-dependent stiffness effect.
    pub fn cubic_stiffness(&self) -> Option<f64> {
        self.get("stiffness_change_at_ref_amplitude").map(|eps| {
            let ph = self.physical();
            cubic_stiffness_law(
                eps,
                ph.mass_kg * ph.omega_s * ph.omega_s,
                self.spec.scales.amplitude_max_m,
            )
        })
    }

    /// Quadratic stiffness `k2` (N/m²) of the amplitude-proportional stiffness effect: its
    /// describing-function stiffness `(8/3π)·k2·A_ref` is `ε1·m·ω_s²` at the reference amplitude.
    pub fn quadratic_stiffness(&self) -> Option<f64> {
        self.get("proportional_stiffness_change_at_ref_amplitude")
            .map(|eps| {
                let ph = self.physical();
                quadratic_stiffness_law(
                    eps,
                    ph.mass_kg * ph.omega_s * ph.omega_s,
                    self.spec.scales.amplitude_max_m,
                )
            })
    }

    /// The amplitude-dependent damper `(c, p)` of `f = c·|u̇|^p·u̇`, if any: the quadratic
    /// damper (`p = 1`, `c2 = 3π·m·ζ_q/(4·A_ref)`) or the power law, whose equivalent damping
    /// ratio at the reference amplitude `A_ref` and the stuck-joint frequency `ω_s` is the
    /// parameter: `c = 2π·m·ζ_p/(A_ref^p·ω_s^{p−1}·I(p+2))`.
    pub fn damper(&self) -> Option<(f64, f64)> {
        let m = self.physical().mass_kg;
        let a_ref = self.spec.scales.amplitude_max_m;
        if let Some(z) = self.get("quadratic_damping_ratio_at_ref_amplitude") {
            return Some((3.0 * PI * m * z / (4.0 * a_ref), 1.0));
        }
        let z = self.get("power_law_damping_ratio_at_ref_amplitude")?;
        let p = self.value("power_law_damping_exponent");
        let ws = self.physical().omega_s;
        let c = 2.0 * PI * m * z
            / (a_ref.powf(p) * ws.powf(p - 1.0) * sine_power_cycle_integral(p + 2.0));
        Some((c, p))
    }

    /// Residual receptance `r` (m/N) of the out-of-band modes.
    pub fn residual_receptance(&self) -> f64 {
        self.get("residual_flexibility_ratio").map_or(0.0, |rho| {
            let ph = self.physical();
            rho / (ph.mass_kg * ph.omega_s * ph.omega_s)
        })
    }

    /// Delay `τ` (s) between measured force and force into the structure.
    pub fn force_delay(&self) -> f64 {
        self.get("force_delay_s").unwrap_or(0.0)
    }

    /// The structure at a preload factor and (for the velocity-dependent effect) frequency.
    fn structure(&self, preload: f64, omega: f64, n_time: usize) -> Result<(Structure, f64)> {
        let ph = self.physical();
        let omega0 = (ph.k_linear / ph.mass_kg).sqrt();
        let zeta_prime = ph.c_linear / (2.0 * ph.mass_kg * omega0);
        let mut s = Structure::single_mode(omega0 / TAU, zeta_prime)?;
        let phi = 1.0 / ph.mass_kg.sqrt();
        let map = DMatrix::from_element(1, 1, phi);
        s.attach("joint", self.joint(preload)?, map.clone())?;
        if let Some(k3) = self.cubic_stiffness() {
            if k3 != 0.0 {
                s.attach("cubic spring", Arc::new(CubicSpring { k3 }), map.clone())?;
            }
        }
        if let Some(k2) = self.quadratic_stiffness() {
            if k2 != 0.0 {
                s.attach(
                    "quadratic spring",
                    Arc::new(QuadraticSpring { k2 }),
                    map.clone(),
                )?;
            }
        }
        if let Some((c, exponent)) = self.damper() {
            s.attach(
                "power-law damper",
                Arc::new(PowerLawDamper {
                    c,
                    exponent,
                    sample_rate: omega * n_time as f64 / TAU,
                }),
                map,
            )?;
        }
        Ok((s, phi))
    }

    /// Harmonic basis of the balance.
    pub fn harmonic_basis(&self) -> Result<Harmonics> {
        Harmonics::new(self.spec.harmonics(), true, None)
    }

    /// Complex fundamental drive-point displacement per unit force (m/N, `e^{iωt}` convention)
    /// at every drive, in order, warm-started along the list (the sweep order). `mean_force_n`
    /// is the level's mean force (for the preload-loss effect). The out-of-band and delay
    /// effects are applied to the result.
    pub fn receptance(&self, drives: &[Drive], mean_force_n: f64) -> Result<Vec<Complex64>> {
        self.receptance_tolerant(drives, mean_force_n, false)
            .map(|(r, _)| r)
    }

    /// As [`Self::receptance`]; with `tolerant`, a row that fails is recorded (its value NaN)
    /// instead of ending the evaluation.
    pub fn receptance_tolerant(
        &self,
        drives: &[Drive],
        mean_force_n: f64,
        tolerant: bool,
    ) -> Result<(Vec<Complex64>, Vec<RowFailure>)> {
        let h = self.harmonic_basis()?;
        let (ci, si) = h.index_of(1).expect("fundamental retained");
        let preload = self.preload_factor(mean_force_n);
        let rres = self.residual_receptance();
        let tau = self.force_delay();
        let velocity_dependent = self.damper().is_some();
        let mut built: Option<(Structure, f64)> = None;
        solve_sweep(drives, tolerant, |d, warm| {
            if built.is_none() || velocity_dependent {
                built = Some(self.structure(preload, d.omega, h.n_time())?);
            }
            let (s, phi) = built.as_ref().expect("built above");
            let sys = HbmSystem::new(
                s,
                h.clone(),
                Excitation {
                    force: DVector::from_element(1, *phi),
                    harmonic: 1,
                    force_sin: None,
                },
                FormulationChoice::Coordinates,
            )?;
            let sys = tuned(sys);
            let p = solve_robust(&sys, d, warm, self)?;
            let (a, b) = (phi * p.z[ci], phi * p.z[si]);
            let x = Complex64::new(a, -b) / d.force_n + rres;
            Ok((x * Complex64::from_polar(1.0, -d.omega * tau), p.z))
        })
    }

    /// Response-controlled evaluation: at each frequency, the force that holds the amplitude of
    /// the fundamental drive-point displacement at `target_m[i]` (m), and the complex receptance
    /// there. Returns `(force amplitudes (N), receptances (m/N))`. With out-of-band flexibility
    /// the total drive-point amplitude (mode + residual) is held by a fixed-point correction of
    /// the modal target. Warm-started along the sweep; a point whose Newton iteration fails is
    /// solved again with the AFT's time sampling doubled, then quadrupled: with the amplitude
    /// held within a few samples' resolution of a joint's slip onset, the sampled slip can
    /// leave the bordered system without a root at the default sampling (measured on the
    /// Brake–Reuss beam: 64 samples fail, 96–256 converge within 1 % of each other).
    pub fn response_controlled(
        &self,
        omegas: &[f64],
        target_m: &[f64],
        mean_force_n: f64,
    ) -> Result<(Vec<f64>, Vec<Complex64>)> {
        let h = self.harmonic_basis()?;
        let preload = self.preload_factor(mean_force_n);
        let tau = self.force_delay();
        let mut forces = Vec::with_capacity(omegas.len());
        let mut recs = Vec::with_capacity(omegas.len());
        let mut guess: Option<(DVector<f64>, f64)> = None;
        for (&w, &target) in omegas.iter().zip(target_m) {
            let mut point = self.response_controlled_point(&h, preload, w, target, guess.as_ref());
            for factor in [2, 4] {
                if point.is_ok() {
                    break;
                }
                let fine = Harmonics::new(h.h_max(), true, Some(factor * h.n_time()))?;
                if let Ok(p) =
                    self.response_controlled_point(&fine, preload, w, target, guess.as_ref())
                {
                    point = Ok(p);
                }
            }
            let (f, x, z) = point?;
            guess = Some((z, f));
            forces.push(f);
            recs.push(x * Complex64::from_polar(1.0, -w * tau));
        }
        Ok((forces, recs))
    }

    /// One point of [`Model::response_controlled`] on harmonics `h`: `(force (N), receptance
    /// (m/N), modal harmonics)`.
    fn response_controlled_point(
        &self,
        h: &Harmonics,
        preload: f64,
        w: f64,
        target: f64,
        guess: Option<&(DVector<f64>, f64)>,
    ) -> Result<(f64, Complex64, DVector<f64>)> {
        let (ci, si) = h.index_of(1).expect("fundamental retained");
        let rres = self.residual_receptance();
        let (s, phi) = self.structure(preload, w, h.n_time())?;
        let sys = HbmSystem::new(
            &s,
            h.clone(),
            Excitation {
                force: DVector::from_element(1, phi),
                harmonic: 1,
                force_sin: None,
            },
            FormulationChoice::Coordinates,
        )?;
        let sys = tuned(sys);
        let obs = DVector::from_element(1, phi);
        let mut modal_target = target;
        let mut guess = guess.map(|(z, l)| (z.clone(), *l));
        let mut result = None;
        for _ in 0..8 {
            let p = sys.solve_response_controlled(
                w,
                modal_target,
                &obs,
                guess.as_ref().map(|(z, l)| (z, *l)),
            )?;
            let x = Complex64::new(phi * p.z[ci], -phi * p.z[si]) / p.level + rres;
            let total = x.norm() * p.level;
            result = Some((p.level, x, p.z.clone()));
            guess = Some((p.z, p.level));
            if rres == 0.0 || (total - target).abs() <= 1e-9 * target {
                break;
            }
            modal_target *= target / total;
        }
        Ok(result.expect("at least one solve"))
    }

    /// Backbone of the model by the single-harmonic describing function of the joint and the
    /// effects at drive-point displacement amplitude `a` (m): natural frequency (Hz) and damping
    /// ratio of the equivalent linear mode,
    /// `ω_n² = (k + K_eq(a) + ¾k3·a² + (8/3π)·k2·a)/m`, `ζ = (c·ω_n + h(a) + c_eq(a, ω_n)·ω_n)/(2m·ω_n²)`, with
    /// `K_eq = a1/a` and `h = −b1/a` from the fundamental `a1·cos θ + b1·sin θ` of the joint force
    /// under `u = a·cos θ` (AFT, 1024 samples; `π·a²·h` is the energy the joint dissipates per
    /// cycle) and `c_eq` the damper's equivalent viscous coefficient
    /// ([`PowerLawDamper::equivalent_viscous`]; `(8/3π)·c2·ω_n·a` for the quadratic damper).
    pub fn backbone_point(&self, a: f64, mean_force_n: f64) -> Result<(f64, f64)> {
        let ph = self.physical();
        let h = Harmonics::new(1, true, Some(1024))?;
        let joint = self.joint(self.preload_factor(mean_force_n))?;
        // The joint laws of an identification are rate-independent: the frequency is not read.
        let r = aft::evaluate(
            joint.as_ref(),
            &h,
            &[a, 0.0],
            ph.omega_s,
            false,
            &AftSettings::default(),
        );
        let (keq, hl) = (r.forces[0] / a, -r.forces[1] / a);
        let k3 = self.cubic_stiffness().unwrap_or(0.0);
        let k2 = self.quadratic_stiffness().unwrap_or(0.0);
        let wn2 = (ph.k_linear
            + keq
            + 0.75 * k3 * a * a
            + crate::element::quadratic_spring::equivalent_stiffness(k2, a))
            / ph.mass_kg;
        if wn2 <= 0.0 {
            return Err(Error::Data(format!(
                "the model has no positive stiffness at amplitude {a:.3e} m"
            )));
        }
        let wn = wn2.sqrt();
        let c_eq = self.damper().map_or(0.0, |(c, p)| {
            PowerLawDamper::equivalent_viscous(c, p, a, wn)
        });
        let zeta = (ph.c_linear * wn + hl + c_eq * wn) / (2.0 * ph.mass_kg * wn2);
        Ok((wn / TAU, zeta))
    }
}

/// Relative residual tolerance of the harmonic balance in identification: `1e-8` (the solver's
/// default, [`crate::dynamics::hbm::NewtonSettings`], is `1e-7`); the responses are then exact to far below the measurement scatter
/// (≥ 1e-4 of the peak on the Brake–Reuss beam) and a warm-started row needs one Newton
/// iteration less.
pub const NEWTON_TOLERANCE: f64 = 1e-8;

/// Numerical floor of the objective's residuals (relative to a level's peak): the model's
/// responses are exact only to about the balance tolerance times the resonance's
/// amplification (`NEWTON_TOLERANCE·Q`, `Q = 1/2ζ`: 5e-6 at ζ = 0.1 %); `1e-6` is taken. A
/// misfit below it is solver noise, not evidence: the effect search and the posterior add its
/// square to the cost ([`NUMERICAL_COST_FLOOR`]), so noise-free (e.g. synthetic) data neither
/// accept an effect for fitting rounding nor give bands whose chains cannot move because ln J
/// jumps at the noise level.
pub const NUMERICAL_RESIDUAL_FLOOR: f64 = 1e-6;

/// The cost `J` (mean squared relative residual) of residuals at [`NUMERICAL_RESIDUAL_FLOOR`].
pub const NUMERICAL_COST_FLOOR: f64 = NUMERICAL_RESIDUAL_FLOOR * NUMERICAL_RESIDUAL_FLOOR;

fn tuned(mut sys: HbmSystem<'_>) -> HbmSystem<'_> {
    sys.newton.tolerance = NEWTON_TOLERANCE;
    sys
}

/// Newton from the warm start; on failure from the linear stuck-joint and free-joint responses,
/// then by a force ramp in four steps from the linear stuck response.
fn solve_robust(
    sys: &HbmSystem<'_>,
    d: &Drive,
    warm: Option<&DVector<f64>>,
    model: &Model,
) -> Result<HbmPoint> {
    let first = match sys.solve(d.omega, d.force_n, warm) {
        Ok(p) => return Ok(p),
        Err(e) => e,
    };
    let ph = model.physical();
    let h = &sys.harmonics;
    let (ci, si) = h.index_of(1).expect("fundamental");
    let phi = 1.0 / ph.mass_kg.sqrt();
    for k in [ph.k_linear + ph.k_joint, ph.k_linear] {
        // Linear modal response: q = φF/(k/m − ω² + iωc/m) in the e^{iωt} convention.
        let den = Complex64::new(
            k / ph.mass_kg - d.omega * d.omega,
            d.omega * ph.c_linear / ph.mass_kg,
        );
        let q = phi * d.force_n / den;
        let mut z = DVector::zeros(h.len());
        z[ci] = q.re;
        z[si] = -q.im;
        if let Ok(p) = sys.solve(d.omega, d.force_n, Some(&z)) {
            return Ok(p);
        }
    }
    let den = Complex64::new(
        (ph.k_linear + ph.k_joint) / ph.mass_kg - d.omega * d.omega,
        d.omega * ph.c_linear / ph.mass_kg,
    );
    let q = phi * d.force_n * 0.25 / den;
    let mut z = DVector::zeros(h.len());
    z[ci] = q.re;
    z[si] = -q.im;
    for step in 1..=4 {
        match sys.solve(d.omega, d.force_n * step as f64 / 4.0, Some(&z)) {
            Ok(p) => {
                if step == 4 {
                    return Ok(p);
                }
                z = p.z * ((step + 1) as f64 / step as f64);
            }
            Err(_) => break,
        }
    }
    Err(first)
}

/// Check a set of physical values against the parameters: one per parameter, finite and inside
/// its bounds (to 1e-9 of the box); the error names the parameter.
pub use crate::core::fit::check_values;

#[cfg(test)]
mod tests {
    use super::*;

    fn scales() -> Scales {
        Scales {
            frequency_hz: 80.0,
            modal_mass_kg: 1.0,
            amplitude_max_m: 3e-4,
            amplitude_min_m: 1e-4,
            force_n: 1.0,
        }
    }

    /// A joint far beyond its slip displacement leaves the linear mode: the receptance equals
    /// the closed form `1/(k − mω² + iωc)` with the slipped-joint stiffness to first order in
    /// `F_s`, and with a stuck joint (tiny amplitude) exactly the stuck-joint closed form.
    #[test]
    fn stuck_joint_gives_the_linear_frf() {
        let spec = ModelSpec::baseline(Family::Jenkins, scales());
        let m = Model::new(spec, vec![80.0, 2e-3, 1.2, 0.05, 1e-3]).unwrap();
        let ph = m.physical();
        let drives: Vec<Drive> = (0..9)
            .map(|i| Drive {
                omega: TAU * (79.0 + 0.25 * i as f64),
                force_n: 1e-3,
            })
            .collect();
        let x = m.receptance(&drives, 1e-3).unwrap();
        for (d, xi) in drives.iter().zip(&x) {
            let exact = 1.0
                / Complex64::new(
                    ph.k_linear + ph.k_joint - ph.mass_kg * d.omega * d.omega,
                    d.omega * ph.c_linear,
                );
            assert!((xi - exact).norm() < 1e-8 * exact.norm(), "{xi} vs {exact}");
        }
    }

    /// The Jenkins backbone matches Caughey's describing function:
    /// `K_eq = (k_t/π)(β − sin 2β/2)`, `h = (4F_s/(πa))(1 − F_s/(k_t a))`,
    /// `cos β = 1 − 2F_s/(k_t a)` (Caughey 1960, *J. Appl. Mech.* 27:640).
    #[test]
    fn jenkins_backbone_matches_caughey() {
        let spec = ModelSpec::baseline(Family::Jenkins, scales());
        let m = Model::new(spec, vec![80.0, 1e-3, 2.0, 0.1, 1e-4]).unwrap();
        let ph = m.physical();
        for a in [2e-4, 5e-4, 2e-3] {
            let (f, z) = m.backbone_point(a, 1.0).unwrap();
            let (kt, fs) = (ph.k_joint, ph.slip_force_n);
            let beta = (1.0 - 2.0 * fs / (kt * a)).acos();
            let keq = kt / PI * (beta - (2.0 * beta).sin() / 2.0);
            let h = 4.0 * fs / (PI * a) * (1.0 - fs / (kt * a));
            let wn = ((ph.k_linear + keq) / ph.mass_kg).sqrt();
            let zeta = (ph.c_linear * wn + h) / (2.0 * ph.mass_kg * wn * wn);
            assert!((f - wn / TAU).abs() < 1e-5 * f, "{f} vs {}", wn / TAU);
            assert!((z - zeta).abs() < 2e-3 * zeta, "{z} vs {zeta}");
        }
    }

    /// The power-law damper's equivalent damping at the reference amplitude is its parameter:
    /// the cycle energy of `c·|u̇|^p·u̇` under `u = A_ref·cos ω_s t`, by quadrature, equals
    /// `2π·ζ_p·m·ω_s²·A_ref²` (the linear damper of ratio `ζ_p`), and `p = 1` is the quadratic
    /// damper of the same ratio.
    #[test]
    fn power_law_damping_ratio_is_the_equivalent_ratio_at_the_reference_amplitude() {
        let base = vec![80.0, 1e-3, 2.0, 0.01, 1e-4];
        let sc = scales();
        let zeta_p = 3e-3;
        for p in [0.5, 1.0, 1.7, 2.5] {
            let spec = ModelSpec::baseline(Family::Jenkins, sc).with(Effect::PowerLawDamping);
            let mut v = base.clone();
            v.extend([zeta_p, p]);
            let m = Model::new(spec, v).unwrap();
            let (c, exponent) = m.damper().unwrap();
            assert_eq!(exponent, p);
            let ph = m.physical();
            let (a, w) = (sc.amplitude_max_m, ph.omega_s);
            let n = 100_000;
            let energy: f64 = (0..n)
                .map(|k| {
                    let th = TAU * (k as f64 + 0.5) / n as f64;
                    let v = -a * w * th.sin();
                    c * v.abs().powf(p) * v * v / w
                })
                .sum::<f64>()
                * TAU
                / n as f64;
            let linear = 2.0 * PI * zeta_p * ph.mass_kg * w * w * a * a;
            assert!(
                (energy - linear).abs() < 1e-6 * linear,
                "p = {p}: {energy} vs {linear}"
            );
            if p == 1.0 {
                let spec_q =
                    ModelSpec::baseline(Family::Jenkins, sc).with(Effect::QuadraticDamping);
                let mut vq = base.clone();
                vq.push(zeta_p);
                let q = Model::new(spec_q, vq).unwrap().damper().unwrap();
                assert!((q.0 - c).abs() < 1e-12 * c && q.1 == 1.0, "{q:?} vs {c}");
            }
        }
    }

    /// Response control with the amplitude held at a Jenkins joint's slip onset (`a/δ =
    /// 1.0005`), the Brake–Reuss beam's baseline as identified on all four levels: the bordered
    /// Newton iteration finds no root at the default 64 samples (it stalls at a relative
    /// residual of 2e-4) and the point is solved on the finer sampling. The force agrees with
    /// Caughey's first-harmonic describing function at that amplitude within 2 % (the sampled
    /// slip onset and the third harmonic make the difference).
    #[test]
    fn response_control_at_the_slip_onset_converges() {
        let spec = ModelSpec::baseline(
            Family::Jenkins,
            Scales {
                frequency_hz: 80.28631286698563,
                modal_mass_kg: 2.5412688533198775,
                amplitude_max_m: 2.7297542606293017e-4,
                amplitude_min_m: 7.823650326237084e-5,
                force_n: 1.4601442665853661,
            },
        );
        let values = vec![
            80.23920768861885,
            3.0604005943531266e-3,
            1.9721846834394934,
            0.5,
            2.3006232397997626e-4,
        ];
        let m = Model::new(spec, values).unwrap();
        let w = TAU * 79.925;
        let a = 58.0483 / (w * w);
        let ph = m.physical();
        let (kt, fs) = (ph.k_joint, ph.slip_force_n);
        assert!((kt * a / fs - 1.0).abs() < 1e-3, "a/δ = {}", kt * a / fs);
        let (f, x) = m.response_controlled(&[w], &[a], 1.46).unwrap();
        assert!((x[0].norm() * f[0] / a - 1.0).abs() < 1e-8);
        let beta = (1.0 - 2.0 * fs / (kt * a)).max(-1.0).acos();
        let k_eq = kt / PI * (beta - (2.0 * beta).sin() / 2.0);
        let h = 4.0 * fs / (PI * a) * (1.0 - fs / (kt * a)).max(0.0);
        let exact = a * (ph.k_linear + k_eq - ph.mass_kg * w * w).hypot(ph.c_linear * w + h);
        assert!((f[0] / exact - 1.0).abs() < 0.02, "{} vs {exact}", f[0]);
    }

    /// Generalising the quadratic damper of a two-effect model gives the power law at `p = 1`
    /// in the same place, with every other value kept: the same receptance to round-off.
    #[test]
    fn generalised_quadratic_damper_is_the_same_model() {
        let spec = ModelSpec::baseline(Family::Valanis, scales())
            .with(Effect::QuadraticDamping)
            .with(Effect::AmplitudeStiffness);
        let values = vec![80.0, 1e-3, 2.0, 0.05, 1e-4, 0.4, 2e-3, 0.004];
        let (g, gv) = spec.generalised(Effect::PowerLawDamping, &values).unwrap();
        assert_eq!(
            g.effects,
            [Effect::PowerLawDamping, Effect::AmplitudeStiffness]
        );
        assert_eq!(gv, [80.0, 1e-3, 2.0, 0.05, 1e-4, 0.4, 2e-3, 1.0, 0.004]);
        let (q, p) = (
            Model::new(spec.clone(), values).unwrap(),
            Model::new(g, gv).unwrap(),
        );
        let drives: Vec<Drive> = (0..5)
            .map(|i| Drive {
                omega: TAU * (79.5 + 0.25 * i as f64),
                force_n: 0.5,
            })
            .collect();
        let (xq, xp) = (
            q.receptance(&drives, 0.5).unwrap(),
            p.receptance(&drives, 0.5).unwrap(),
        );
        for (a, b) in xq.iter().zip(&xp) {
            assert!((a - b).norm() < 1e-9 * a.norm(), "{a} vs {b}");
        }
        assert!(spec.generalised(Effect::IwanJoint, &[0.0; 8]).is_none());
        let plain = ModelSpec::baseline(Family::Jenkins, scales());
        assert!(plain
            .generalised(Effect::PowerLawDamping, &[0.0; 5])
            .is_none());
    }

    /// A quadratic spring on a stuck-joint mode: the balanced first harmonic equals the
    /// single-harmonic closed form `A·|k_s + (8/3π)·k2·A − mω² + iωc| = F` (the third harmonic
    /// of `|u|·u` is 1/5 of its first, and is filtered by a dynamic stiffness eight times the
    /// resonant one: a 2e-4 relative effect at ε1 = 3 %), and at the reference amplitude the
    /// backbone's `ω²` is `ω_s²·(1 + ε1)`.
    #[test]
    fn quadratic_spring_matches_its_describing_function() {
        let eps = -0.03;
        let spec = ModelSpec::baseline(Family::Jenkins, scales()).with(Effect::QuadraticStiffness);
        let m = Model::new(spec, vec![80.0, 2e-3, 1.2, 0.05, 1e-3, eps]).unwrap();
        let ph = m.physical();
        let k2 = m.quadratic_stiffness().unwrap();
        let ks = ph.mass_kg * ph.omega_s * ph.omega_s;
        let a_ref = scales().amplitude_max_m;
        assert!(
            (crate::element::quadratic_spring::equivalent_stiffness(k2, a_ref) - eps * ks).abs()
                < 1e-12 * ks
        );
        let (f, _) = m.backbone_point(a_ref, 1.0).unwrap();
        let want = ph.omega_s * (1.0 + eps).sqrt() / TAU;
        assert!((f - want).abs() < 1e-9 * want, "{f} vs {want}");
        // Force-controlled points 4 % below and above the resonance, amplitude about A_ref/3
        // (the joint stays stuck: A < δ; single-valued, away from the softened resonance).
        for ratio in [0.96, 1.04] {
            let omega = ratio * ph.omega_s;
            let force = 2.0;
            let x = m
                .receptance(
                    &[Drive {
                        omega,
                        force_n: force,
                    }],
                    force,
                )
                .unwrap()[0];
            let dyn_stiffness = |a: f64| {
                Complex64::new(
                    ks + crate::element::quadratic_spring::equivalent_stiffness(k2, a)
                        - ph.mass_kg * omega * omega,
                    omega * ph.c_linear,
                )
                .norm()
            };
            // Fixed point A = F/|D(A)| (a contraction: the spring's share of D is a few per cent).
            let mut a = 1e-4;
            for _ in 0..200 {
                a = force / dyn_stiffness(a);
            }
            let got = x.norm() * force;
            assert!(got > 5e-5 && got < 2e-4, "amplitude {got}");
            assert!(
                (got - a).abs() < 5e-4 * a,
                "ω/ω_s = {ratio}: {got:.6e} vs {a:.6e}"
            );
        }
    }

    #[test]
    fn one_damping_law_at_most() {
        let spec = ModelSpec::baseline(Family::Jenkins, scales()).with(Effect::QuadraticDamping);
        assert!(!spec.admits(Effect::PowerLawDamping));
        assert!(spec.admits(Effect::AmplitudeStiffness));
    }

    #[test]
    fn out_of_bounds_values_are_refused() {
        let spec = ModelSpec::baseline(Family::Jenkins, scales());
        let e = Model::new(spec.clone(), vec![80.0, 2e-3, 1.2, 0.9, 1e-3]).unwrap_err();
        assert!(e.to_string().contains("joint_stiffness_share"), "{e}");
        assert!(Model::new(spec, vec![80.0]).is_err());
    }
}
