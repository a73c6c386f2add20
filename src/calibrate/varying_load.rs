//! The element's normal-load law against the contact solver: the Valanis element of the
//! calibration table, whose slip limit follows the normal load (`λ = E0/(μ·Fz(t)·(1 − k·Et/E0))`,
//! [`crate::element::valanis`]; the 3-D contact element of the dynamics uses the same law), driven
//! through a BEM history in which the normal load oscillates with the tangential displacement
//! ([`crate::contact::tangential::varying_load`]).
//!
//! Units: per unit nominal area, as in the calibration table: displacement in m, shear stress
//! and normal pressure in Pa, E0 and Et in N/m³, energies in J/m².
//!
//! # What is compared
//! 1. The **table's element**: E0 and k fitted (μ fixed, Et = 0 unless asked) to the BEM loop at
//!    *constant* normal load `p̄₀` and the same displacement amplitude, as the calibration does.
//! 2. That element driven by the varying history `(δ(t), p̄(t))` of the BEM (accurate reference
//!    integrator), against the BEM's own loop under the same history: the energy per cycle
//!    (`∮τ dδ` on the last cycle, same samples and quadrature) and `R²` of the shear stress.
//!    The relative energy error is the element's error on that history.
//! 3. The **best the law can do**: E0 and k refitted to the varying loop itself. If the refit is
//!    good where the table's element is not, the law's form holds but its parameters should
//!    depend on the instantaneous load; if the refit is poor too, the form itself fails.
//! 4. The **load-following element** ([`LoadDependentValanis`]): E0 and k fitted at constant
//!    loads spanning the cycle's load range (the lowest and highest load of the varying history
//!    besides the mean), interpolated at the instantaneous load inside the element. Nothing is
//!    fitted to the varying loop: it is what a table with rows at those loads predicts.
//!
//! Quasi-identical bodies (the BEM's assumption) and the steady cycle (the last one) throughout.

use crate::calibrate::fit::{fit_valanis, goodness_of_fit, FitOptions, LoopData};
use crate::contact::tangential::varying_load::VaryingLoadResult;
use crate::contact::tangential::OscillationResult;
use crate::core::error::{Error, Result};
use crate::element::dissipated_energy;
use crate::element::valanis::{
    integrate_load_dependent, integrate_reference, LoadDependentValanis, ValanisParams,
};

/// The BEM loop of a constant normal load `pressure_pa` (Pa) as fit data: shear stress and
/// displacement along the unit vector `direction` (the loading direction) over the whole
/// history, the last of its cycles of `steps_per_cycle` steps as the steady one.
pub fn constant_load_loop(
    result: &OscillationResult,
    pressure_pa: f64,
    steps_per_cycle: usize,
    direction: [f64; 2],
) -> Result<LoopData> {
    let along = |v: [f64; 2]| v[0] * direction[0] + v[1] * direction[1];
    let q: Vec<f64> = result.steps.iter().map(|s| along(s.shift_m)).collect();
    let force: Vec<f64> = result
        .steps
        .iter()
        .map(|s| along(s.mean_shear_pa))
        .collect();
    let steady = last_cycle(q.len(), steps_per_cycle)?;
    Ok(LoopData::constant_load(q, force, pressure_pa, steady))
}

/// The BEM loop of a varying-load history as fit data (along the unit vector `direction`;
/// normal load: the mean pressure of each step), the last cycle as the steady one.
pub fn varying_load_loop(
    result: &VaryingLoadResult,
    steps_per_cycle: usize,
    direction: [f64; 2],
) -> Result<LoopData> {
    let along = |v: [f64; 2]| v[0] * direction[0] + v[1] * direction[1];
    let q: Vec<f64> = result
        .steps
        .iter()
        .map(|s| along(s.tangential.shift_m))
        .collect();
    let steady = last_cycle(q.len(), steps_per_cycle)?;
    Ok(LoopData {
        q,
        force: result
            .steps
            .iter()
            .map(|s| along(s.tangential.mean_shear_pa))
            .collect(),
        normal_load: result.steps.iter().map(|s| s.mean_pressure_pa).collect(),
        steady,
    })
}

/// The last cycle of a history of `samples` samples (`cycles·n + 1`).
fn last_cycle(samples: usize, n: usize) -> Result<std::ops::Range<usize>> {
    if n == 0 || samples < n + 1 || !(samples - 1).is_multiple_of(n) {
        return Err(Error::param(
            "steps_per_cycle",
            format!("{samples} samples are not whole cycles of {n} steps plus the start"),
        ));
    }
    Ok(samples - 1 - n..samples)
}

/// The element against the BEM on one varying-load history (see the module documentation).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ElementCheck {
    /// E0, k (Et) fitted at constant normal load: the table's element.
    pub table_params: ValanisParams,
    /// R² of that fit on the constant-load loop.
    pub table_fit_r2: f64,
    /// Energy per cycle of the BEM at constant load (J/m²).
    pub bem_constant_energy_j_per_m2: f64,
    /// Energy per cycle of the BEM under the varying load (J/m²).
    pub bem_energy_j_per_m2: f64,
    /// Energy per cycle of the table's element under the varying load (J/m²).
    pub element_energy_j_per_m2: f64,
    /// `(element − BEM)/BEM` of the energy per cycle under the varying load.
    pub energy_rel_error: f64,
    /// R² of the table's element's shear stress against the BEM's, last cycle.
    pub r2: f64,
    /// The table's element's shear stress over the whole varying history (Pa).
    pub element_shear_pa: Vec<f64>,
    /// E0, k (Et) refitted to the varying loop.
    pub refit_params: ValanisParams,
    /// R² of the refitted element on the varying loop.
    pub refit_r2: f64,
    /// `(element − BEM)/BEM` of the energy per cycle of the refitted element.
    pub refit_energy_rel_error: f64,
    /// The load-following element: E0 and k fitted at each constant load given (the mean and
    /// the spanning loads), interpolated at the instantaneous load.
    pub load_following: LoadDependentValanis,
    /// Energy per cycle of the load-following element under the varying load (J/m²).
    pub load_following_energy_j_per_m2: f64,
    /// `(load-following element − BEM)/BEM` of the energy per cycle.
    pub load_following_energy_rel_error: f64,
    /// R² of the load-following element's shear stress against the BEM's, last cycle.
    pub load_following_r2: f64,
}

/// Fit the table's element on `constant` (the loop at the mean load), drive it through
/// `varying`, refit on `varying`; fit the element at every load of `spanning` too (constant-load
/// loops at other loads, same amplitude) and drive the load-following element built from all of
/// them through `varying` (with `spanning` empty it is the table's element).
///
/// Errors: inconsistent loops, a fit that fails, an element that cannot be integrated.
pub fn check_element(
    constant: &LoopData,
    spanning: &[LoopData],
    varying: &LoopData,
    options: &FitOptions,
) -> Result<ElementCheck> {
    let table = fit_valanis(constant, options)?;
    let load_following = load_following_element(constant, &table.params, spanning, options)?;
    let following_shear =
        integrate_load_dependent(&load_following, &varying.q, &varying.normal_load)?;
    let element_shear_pa = integrate_reference(&table.params, &varying.q, &varying.normal_load)?;
    let r = varying.steady.clone();
    let bem = dissipated_energy(&varying.q[r.clone()], &varying.force[r.clone()]);
    let element = dissipated_energy(&varying.q[r.clone()], &element_shear_pa[r.clone()]);
    let (r2, _) = goodness_of_fit(&varying.force[r.clone()], &element_shear_pa[r.clone()]);
    let following = dissipated_energy(&varying.q[r.clone()], &following_shear[r.clone()]);
    let (following_r2, _) = goodness_of_fit(&varying.force[r.clone()], &following_shear[r.clone()]);
    let rc = constant.steady.clone();
    let bem_constant = dissipated_energy(&constant.q[rc.clone()], &constant.force[rc]);
    let refit = fit_valanis(varying, options)?;
    let refit_loop = refit
        .loops
        .first()
        .ok_or_else(|| Error::Data("refit returned no loop".into()))?;
    Ok(ElementCheck {
        table_params: table.params,
        table_fit_r2: table.r2,
        bem_constant_energy_j_per_m2: bem_constant,
        bem_energy_j_per_m2: bem,
        element_energy_j_per_m2: element,
        energy_rel_error: (element - bem) / bem,
        r2,
        element_shear_pa,
        refit_params: refit.params,
        refit_r2: refit.r2,
        refit_energy_rel_error: refit_loop.energy_rel_error,
        load_following,
        load_following_energy_j_per_m2: following,
        load_following_energy_rel_error: (following - bem) / bem,
        load_following_r2: following_r2,
    })
}

/// The constant normal load of a constant-load loop (its first sample; Pa).
fn constant_load_of(l: &LoopData) -> Result<f64> {
    let first = *l
        .normal_load
        .first()
        .ok_or_else(|| Error::Data("a constant-load loop has no samples".into()))?;
    if l.normal_load.iter().any(|&v| v != first) {
        return Err(Error::Data(
            "a loop given as constant-load has a varying normal load".into(),
        ));
    }
    Ok(first)
}

/// The load-following element from the mean loop's fit and fits at the `spanning` loads.
fn load_following_element(
    mean: &LoopData,
    mean_params: &ValanisParams,
    spanning: &[LoopData],
    options: &FitOptions,
) -> Result<LoadDependentValanis> {
    let mut rows = vec![(constant_load_of(mean)?, *mean_params)];
    for l in spanning {
        rows.push((constant_load_of(l)?, fit_valanis(l, options)?.params));
    }
    rows.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (loads, params) = rows.into_iter().unzip();
    LoadDependentValanis::new(loads, params)
}
