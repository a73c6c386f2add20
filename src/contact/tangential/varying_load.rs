//! Tangential loops under a normal load that oscillates with the tangential one.
//!
//! Units: SI (m, Pa, N, J); the normal load is given as the nominal (mean) pressure `p̄` (Pa),
//! the normal force `P = p̄ · nominal area` is reported alongside.
//!
//! # Loading
//! Over a cycle `θ = 2πk/n` (`k = 1 … cycles·n`, `n` steps per cycle):
//!
//! - normal: `p̄(θ) = p̄₀ (1 + r sin(θ + φ))`, amplitude ratio `0 ≤ r < 1`, phase `φ` (0: in
//!   phase with the tangential load, π: out of phase);
//! - tangential: `δ(θ) = δa sin θ` (displacement control) or `T(θ) = Ta sin θ` (load control).
//!
//! The history starts from the virgin state under the normal load of `θ = 0` (the normal load is
//! applied first, without shear).
//!
//! # Method
//! Quasi-identical bodies: the normal problem does not depend on the shear
//! ([`super::QUASI_IDENTICAL_ASSUMPTION`]), so the pressure field of each step is the normal
//! solution at that step's load. The `n` fields of a cycle are solved once (warm-started from
//! each other). The tangential solver is built on a field whose contact set holds all of them
//! (their point-wise maximum) and each step replaces its pressure
//! ([`TangentialSolver::set_pressure`]) before solving the step with history: Coulomb's bound
//! `μ p_i(t)` follows the pressure, points leaving contact lose their traction, points entering
//! start to stick from where they are (Kalker 1990, *Three-dimensional elastic bodies in rolling
//! contact*, §2.3). This is Mindlin & Deresiewicz's problem (J. Appl. Mech. 20 (1953) 327–344;
//! Johnson, *Contact Mechanics*, 1985, §7.5) on any surface.
//!
//! **Hardness-limited contact** (`hardness_pa`): the surface is first loaded to the largest
//! normal load of the cycle with the pressure bounded by `H`; every load of the cycle is then
//! solved elastically on the residual (plastically deformed) surface, which is exact in the
//! pressure-saturation model (unloading and reloading up to the largest load are elastic on it;
//! [`crate::contact::normal`]). The loops are those of the shaken-down state, after the first
//! excursion to the largest load.
//!
//! **Energy.** The normal work over a closed cycle vanishes (elastic, path independent normal
//! problem), so the energy dissipated per cycle is the tangential loop area `∮ T·dδ`, and it
//! equals the frictional work `Σ ΔA q·Δg` summed over the steps (up to the time discretisation);
//! both are reported ([`CycleEnergy`]).

use super::{
    cycle_energies, Control, CycleEnergy, TangentialMetadata, TangentialOptions, TangentialProblem,
    TangentialSolver, TangentialStep,
};
use crate::contact::normal::{NormalOptions, NormalProblem, NormalSolver};
use crate::core::error::{Error, Result};
use crate::core::material::Material;
use ndarray::Array2;
use std::f64::consts::PI;
use std::time::Instant;

/// A normal load oscillating about its mean: `p̄(θ) = p̄₀ (1 + r sin(θ + φ))`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct NormalLoadOscillation {
    /// Mean nominal pressure p̄₀ (Pa), > 0.
    pub mean_pressure_pa: f64,
    /// Amplitude ratio r = Δp̄/p̄₀ (-), in [0, 1): the contact stays closed.
    pub amplitude_ratio: f64,
    /// Phase φ of the normal load ahead of the tangential one (rad): 0 in phase, π out of phase.
    pub phase_rad: f64,
}

impl NormalLoadOscillation {
    /// Checked: p̄₀ finite and > 0, 0 ≤ r < 1, φ finite.
    pub fn validated(self) -> Result<Self> {
        crate::core::error::require_positive("mean_pressure_pa", self.mean_pressure_pa)?;
        let r = self.amplitude_ratio;
        if !(r.is_finite() && (0.0..1.0).contains(&r)) {
            return Err(Error::param(
                "amplitude_ratio",
                format!(
                    "the normal load amplitude over its mean must lie in [0, 1) (the contact \
                     stays closed), got {r}"
                ),
            ));
        }
        if !self.phase_rad.is_finite() {
            return Err(Error::param(
                "phase",
                format!("must be finite, got {}", self.phase_rad),
            ));
        }
        Ok(self)
    }

    /// `p̄(θ)` (Pa).
    pub fn pressure_at(&self, theta: f64) -> f64 {
        self.mean_pressure_pa * (1.0 + self.amplitude_ratio * (theta + self.phase_rad).sin())
    }

    /// The largest normal load of the cycle, `p̄₀ (1 + r)` (Pa).
    pub fn max_pressure(&self) -> f64 {
        self.mean_pressure_pa * (1.0 + self.amplitude_ratio)
    }
}

/// A history of tangential and normal loads oscillating together (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VaryingLoadHistory {
    /// Tangential amplitude: displacement δa (m) or force Ta (N), with its direction.
    pub tangential_amplitude: Control,
    /// The normal load.
    pub normal: NormalLoadOscillation,
    /// Number of cycles (≥ 1).
    pub cycles: usize,
    /// Steps per cycle (≥ 4).
    pub steps_per_cycle: usize,
}

impl VaryingLoadHistory {
    fn validated(self) -> Result<Self> {
        let a = self.tangential_amplitude.vector();
        if !(a[0].is_finite() && a[1].is_finite() && a[0].hypot(a[1]) > 0.0) {
            return Err(Error::param(
                "amplitude",
                format!("tangential amplitude must be finite and non-zero, got {a:?}"),
            ));
        }
        if self.cycles == 0 {
            return Err(Error::param("cycles", "must be at least 1"));
        }
        if self.steps_per_cycle < 4 {
            return Err(Error::param(
                "steps_per_cycle",
                format!("must be at least 4, got {}", self.steps_per_cycle),
            ));
        }
        self.normal.validated()?;
        Ok(self)
    }

    /// `sin θ_k` of step `k`, exactly zero at multiples of π (closed cycles).
    fn sine(&self, k: usize) -> f64 {
        let n = self.steps_per_cycle;
        if (2 * k).is_multiple_of(n) {
            0.0
        } else {
            (2.0 * PI * k as f64 / n as f64).sin()
        }
    }

    /// Phase angle θ_k = 2πk/n (rad).
    fn theta(&self, k: usize) -> f64 {
        2.0 * PI * (k % self.steps_per_cycle) as f64 / self.steps_per_cycle as f64
    }
}

/// One step: the normal state and the tangential step.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct VaryingLoadStep {
    /// Nominal pressure p̄ of the step (Pa).
    pub mean_pressure_pa: f64,
    /// Normal force P = ΔA Σ p (N).
    pub normal_force_n: f64,
    /// Grid points in contact.
    pub contact_points: usize,
    /// The tangential step (force, shift, stick fraction, work, ...).
    pub tangential: TangentialStep,
}

/// Facts about the normal solves of a cycle.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct NormalCycleFacts {
    /// Hardness H (Pa), or `None` for elastic contact.
    pub hardness_pa: Option<f64>,
    /// Hardness-limited: plastic area ratio at the largest load (the shaken-down state's).
    pub plastic_area_ratio: Option<f64>,
    /// Hardness-limited: plastically displaced volume at the largest load (m³).
    pub plastic_volume_m3: Option<f64>,
    /// Smallest and largest contact area ratio over the cycle (-).
    pub contact_area_ratio_range: (f64, f64),
    /// Normal solver iterations, summed over the cycle's loads.
    pub iterations: usize,
    /// Wall time of the normal solves (s).
    pub wall_time_s: f64,
}

/// Result of a varying-load history.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct VaryingLoadResult {
    /// Every step, starting with the initial state (step 0: normal load of θ = 0, no shear).
    pub steps: Vec<VaryingLoadStep>,
    /// One entry per cycle (cycle 1 includes the initial loading from the virgin state).
    pub cycles: Vec<CycleEnergy>,
    /// Set-up facts of the tangential solver (on the envelope of the cycle's contact sets).
    pub metadata: TangentialMetadata,
    /// Facts about the normal solves.
    pub normal: NormalCycleFacts,
    /// Total wall time (s).
    pub wall_time_s: f64,
}

/// Run a history on a solver built on the envelope of the pressure fields, the field of phase
/// index `k` (`θ = 2πk/n`, `k < n`) given by `field(k)`. The solver is reset first.
/// `progress(k, total)` after each step.
///
/// Errors: an invalid history, a field the solver does not cover, any step's errors (in load
/// control `|T| ≥ μP(t)`, gross slip, has no static solution).
pub fn oscillate_on_fields(
    solver: &mut TangentialSolver,
    history: &VaryingLoadHistory,
    mut field: impl FnMut(usize) -> Result<Array2<f64>>,
    mut progress: impl FnMut(usize, usize),
) -> Result<(Vec<VaryingLoadStep>, Vec<CycleEnergy>)> {
    let history = history.validated()?;
    let n = history.steps_per_cycle;
    let total = history.cycles * n;
    solver.reset();
    let area = solver.metadata().nominal_area_m2;
    let record = |solver: &TangentialSolver, tangential: TangentialStep| {
        let force = solver.metadata().normal_force_n;
        VaryingLoadStep {
            mean_pressure_pa: force / area,
            normal_force_n: force,
            contact_points: solver.points_in_contact(),
            tangential,
        }
    };
    solver.set_pressure(&field(0)?)?;
    let mut steps = Vec::with_capacity(total + 1);
    steps.push(record(solver, TangentialStep::INITIAL));
    for k in 1..=total {
        solver.set_pressure(&field(k % n)?)?;
        let st = solver.step(history.tangential_amplitude.scaled(history.sine(k)))?;
        steps.push(record(solver, st));
        progress(k, total);
    }
    let tangential: Vec<TangentialStep> = steps.iter().map(|s| s.tangential).collect();
    let cycles = cycle_energies(&tangential, history.cycles, n, area);
    Ok((steps, cycles))
}

/// The tangential side of a varying-load problem: friction and the two bodies.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TangentialSide {
    /// Coulomb friction coefficient μ (-).
    pub friction_coefficient: f64,
    /// Body 1 (the rough surface's material).
    pub body1: Material,
    /// Body 2 (the counter-face).
    pub body2: Material,
    /// Tangential solver settings.
    pub options: TangentialOptions,
}

/// A point set with values: the contact part of a pressure field (flat index, Pa).
type SparseField = Vec<(usize, f64)>;

/// Solve the normal contact at every load of the cycle (hardness-limited: on the residual
/// surface of the largest load, see the module documentation), then run the history.
///
/// Errors: an invalid history or problem, a normal solve that fails, any tangential step's.
pub fn oscillate_with_normal_load(
    normal: &NormalProblem<'_>,
    normal_options: NormalOptions,
    tangential: &TangentialSide,
    history: &VaryingLoadHistory,
    mut progress: impl FnMut(usize, usize),
) -> Result<VaryingLoadResult> {
    let start = Instant::now();
    let history = history.validated()?;
    let n = history.steps_per_cycle;
    let surface = normal.surface;
    // The plastic state of the largest load, and the elastic problem of the cycle.
    let residual;
    let mut facts = NormalCycleFacts {
        hardness_pa: normal.hardness_pa,
        plastic_area_ratio: None,
        plastic_volume_m3: None,
        contact_area_ratio_range: (f64::INFINITY, 0.0),
        iterations: 0,
        wall_time_s: 0.0,
    };
    let elastic_surface = match normal.hardness_pa {
        Some(_) => {
            let mut plastic = NormalSolver::new(normal, normal_options)?;
            let top = plastic.solve_load(history.normal.max_pressure(), None)?;
            facts.iterations += top.iterations;
            facts.plastic_area_ratio = Some(top.plastic_area_ratio);
            facts.plastic_volume_m3 = Some(top.plastic_volume_m3);
            residual = top.residual_surface(surface)?;
            &residual
        }
        None => surface,
    };
    let mut solver = NormalSolver::new(
        &NormalProblem {
            surface: elastic_surface,
            e_star_pa: normal.e_star_pa,
            hardness_pa: None,
        },
        normal_options,
    )?;
    let (nx, ny) = solver.grid_shape();
    let mut fields: Vec<SparseField> = Vec::with_capacity(n);
    let mut envelope = Array2::<f64>::zeros((nx, ny));
    let mut previous = None;
    for k in 0..n {
        let p = history.normal.pressure_at(history.theta(k));
        let sol = solver.solve_load(p, previous.as_ref())?;
        facts.iterations += sol.iterations;
        let (lo, hi) = facts.contact_area_ratio_range;
        facts.contact_area_ratio_range = (
            lo.min(sol.contact_area_ratio),
            hi.max(sol.contact_area_ratio),
        );
        let sparse: SparseField = sol
            .pressure
            .iter()
            .enumerate()
            .filter(|(_, &v)| v > 0.0)
            .map(|(i, &v)| (i, v))
            .collect();
        for (e, &v) in envelope.iter_mut().zip(sol.pressure.iter()) {
            *e = e.max(v);
        }
        fields.push(sparse);
        previous = Some(sol);
    }
    drop(previous);
    facts.wall_time_s = start.elapsed().as_secs_f64();
    let (dx, dy) = solver.spacing();
    let boundary = solver.boundary();
    drop(solver);
    let mut tangential_solver = TangentialSolver::new(
        &TangentialProblem {
            pressure: &envelope,
            dx,
            dy,
            boundary,
            friction_coefficient: tangential.friction_coefficient,
            body1: tangential.body1,
            body2: tangential.body2,
        },
        tangential.options,
    )?;
    drop(envelope);
    let (steps, cycles) = oscillate_on_fields(
        &mut tangential_solver,
        &history,
        |k| {
            let mut p = Array2::<f64>::zeros((nx, ny));
            let flat = p
                .as_slice_mut()
                .ok_or_else(|| Error::Data("pressure field is not contiguous".into()))?;
            for &(i, v) in &fields[k] {
                flat[i] = v;
            }
            Ok(p)
        },
        &mut progress,
    )?;
    let metadata = tangential_solver.metadata().clone();
    Ok(VaryingLoadResult {
        steps,
        cycles,
        metadata,
        normal: facts,
        wall_time_s: start.elapsed().as_secs_f64(),
    })
}
