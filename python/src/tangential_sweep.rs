//! The tangential sweep, `asperity contact tangential` as one call: the library's
//! `calibrate::tangential_sweep::run` (normal contact at each pressure, then the sinusoidal
//! partial-slip history; optionally hardness-limited, under a varying normal load, along any
//! in-plane direction or an elliptical path).
//! Pressures and moduli in Pa, lengths in m, energies in J/m².

use crate::contact::{oscillation_result, OscillationResult};
use crate::element::ValanisParams;
use crate::errors::IntoPy;
use asperity::calibrate::tangential_sweep::{self as pipeline, TangentialSweepConfig};
use asperity::contact::tangential::TangentialOptions;
use asperity::core::material::Hardness;
use numpy::PyArray1;
use pyo3::prelude::*;
use std::path::PathBuf;

/// The table's element against the contact solver under the varying normal load at one
/// pressure (`tangential_element.csv` of the command).
#[pyclass(frozen, get_all, module = "asperity")]
pub struct VaryingLoadCheck {
    /// The element fitted at constant normal load (the calibration table's element).
    pub table_params: ValanisParams,
    /// R² of that fit on the constant-load loop.
    pub table_fit_r2: f64,
    /// Energy per cycle of the contact solver at constant load (J/m²).
    pub bem_constant_energy_j_per_m2: f64,
    /// Energy per cycle of the contact solver under the varying load (J/m²).
    pub bem_energy_j_per_m2: f64,
    /// Energy per cycle of the table's element under the varying load (J/m²).
    pub element_energy_j_per_m2: f64,
    /// `(element − BEM)/BEM` of the energy per cycle under the varying load.
    pub energy_rel_error: f64,
    /// R² of the table's element's shear stress against the solver's, last cycle.
    pub r2: f64,
    /// The table's element's shear stress over the whole varying history (Pa).
    pub element_shear_pa: Py<PyArray1<f64>>,
    /// Mean normal pressure of each step (Pa).
    pub normal_pressure_pa: Py<PyArray1<f64>>,
    /// The element refitted to the varying loop.
    pub refit_params: ValanisParams,
    /// R² of the refitted element on the varying loop.
    pub refit_r2: f64,
    /// `(element − BEM)/BEM` of the energy per cycle of the refitted element.
    pub refit_energy_rel_error: f64,
    /// The constant loads at which the load-following element was fitted (Pa), ascending.
    pub load_following_loads_pa: Vec<f64>,
    /// The load-following element's parameters at each of those loads.
    pub load_following_params: Vec<ValanisParams>,
    /// Energy per cycle of the load-following element under the varying load (J/m²).
    pub load_following_energy_j_per_m2: f64,
    /// `(load-following element − BEM)/BEM` of the energy per cycle.
    pub load_following_energy_rel_error: f64,
    /// R² of the load-following element's shear stress against the solver's, last cycle.
    pub load_following_r2: f64,
}

/// The result of a tangential sweep: one loop history per nominal pressure.
#[pyclass(frozen, get_all, module = "asperity")]
pub struct TangentialSweepResult {
    /// The surface's description (the generated one's statistics, or the files).
    pub source: String,
    /// Composite modulus E* (Pa).
    pub e_star_pa: f64,
    /// Coulomb friction coefficient μ (-).
    pub friction_coefficient: f64,
    /// Hardness H (Pa) bounding the contact pressure, or None (elastic contact).
    pub hardness_pa: Option<f64>,
    /// Nominal pressures (Pa), ascending.
    pub pressures_pa: Vec<f64>,
    /// Real contact area ratio at each pressure.
    pub contact_area_ratios: Vec<f64>,
    /// Plastic area ratio at each pressure (0 for elastic contact).
    pub plastic_area_ratios: Vec<f64>,
    /// Displacement amplitude (m).
    pub amplitude_m: f64,
    /// Where the amplitude came from.
    pub amplitude_note: String,
    /// One history per pressure, in the order of `pressures_pa`.
    pub results: Vec<Py<OscillationResult>>,
    /// Under a varying normal load, the element's check at each pressure; empty otherwise.
    pub element_checks: Vec<Py<VaryingLoadCheck>>,
    /// Warning: contact cut by the edge of a non-periodic window.
    pub edge_warning: Option<String>,
    /// Files written into `out_dir` (empty without one).
    pub written: Vec<String>,
}

/// The command `asperity contact tangential`, whose flags the keywords follow (errors name the
/// flag): at each nominal pressure `pressures_pa` (default the reference 0.1–10 MPa) the
/// normal contact of the reference surface on `grid`² points (or of the measured `surface`
/// files, one or two bodies), then `cycles` cycles of a sinusoidal tangential displacement of
/// amplitude `amplitude_m` (default a factor of the gross-slip displacement), `steps_per_cycle`
/// steps each. `hardness_pa`: a value in Pa or a material name (`steel-42crmo4`,
/// `inconel-718`); `normal_amplitude_ratio`/`normal_phase_deg`: the normal load
/// `p̄·(1 + r·sin(ωt + φ))`; `direction_deg`, `path_minor_ratio`: the in-plane path;
/// `operator`: "auto", "dense" or "fft". With `out_dir` the command's files are written there
/// (all or none; an input is never overwritten). Runs without the GIL.
#[pyfunction]
#[pyo3(signature = (*, pressures_pa=None, friction_coefficient=0.6, amplitude_m=None, cycles=3, steps_per_cycle=40, grid=None, surface=None, youngs_modulus_pa=210e9, poisson_ratio=0.3, hardness_pa=None, normal_amplitude_ratio=0.0, normal_phase_deg=0.0, direction_deg=0.0, path_minor_ratio=0.0, tolerance=None, max_iterations=None, operator="auto", out_dir=None))]
#[allow(clippy::too_many_arguments)]
pub fn tangential_sweep(
    py: Python<'_>,
    pressures_pa: Option<Vec<f64>>,
    friction_coefficient: f64,
    amplitude_m: Option<f64>,
    cycles: usize,
    steps_per_cycle: usize,
    grid: Option<usize>,
    surface: Option<Vec<PathBuf>>,
    youngs_modulus_pa: f64,
    poisson_ratio: f64,
    hardness_pa: Option<String>,
    normal_amplitude_ratio: f64,
    normal_phase_deg: f64,
    direction_deg: f64,
    path_minor_ratio: f64,
    tolerance: Option<f64>,
    max_iterations: Option<usize>,
    operator: &str,
    out_dir: Option<PathBuf>,
) -> PyResult<TangentialSweepResult> {
    let defaults = TangentialOptions::default();
    let config = TangentialSweepConfig {
        pressures_pa,
        friction_coefficient,
        amplitude_m,
        cycles,
        steps_per_cycle,
        grid,
        surface: surface.unwrap_or_default(),
        fill: None,
        youngs_modulus_pa,
        poisson_ratio,
        hardness: hardness_pa.as_deref().map(Hardness::parse),
        normal_amplitude_ratio,
        normal_phase_deg,
        direction_deg,
        path_minor_ratio,
        options: TangentialOptions {
            tolerance: tolerance.unwrap_or(defaults.tolerance),
            max_iterations: max_iterations.unwrap_or(defaults.max_iterations),
            operator: operator
                .parse()
                .map_err(|e: asperity::Error| e.renamed_param("operator"))
                .py()?,
        },
    };
    let (sweep, written) = py
        .detach(|| -> asperity::Result<_> {
            // The output set is declared (and every path checked) before any work.
            let out = out_dir
                .as_deref()
                .map(|d| pipeline::output_set(&config, d, "out_dir"))
                .transpose()?;
            let sweep = pipeline::run(&config, &|_| indicatif::ProgressBar::hidden(), &mut |_| {})?;
            let written = match out {
                Some(mut o) => {
                    sweep.write(&mut o)?;
                    o.commit()?
                }
                None => Vec::new(),
            };
            Ok((sweep, written))
        })
        .py()?;
    Ok(TangentialSweepResult {
        source: sweep.source.clone(),
        e_star_pa: sweep.e_star_pa,
        friction_coefficient: sweep.friction_coefficient,
        hardness_pa: sweep.hardness_pa,
        pressures_pa: sweep.pressures_pa.clone(),
        contact_area_ratios: sweep.contact_area_ratios.clone(),
        plastic_area_ratios: sweep.plastic_area_ratios.clone(),
        amplitude_m: sweep.amplitude_m,
        amplitude_note: sweep.amplitude_note.clone(),
        results: sweep
            .results
            .iter()
            .map(|r| Py::new(py, oscillation_result(py, r)?))
            .collect::<PyResult<_>>()?,
        element_checks: sweep
            .element
            .iter()
            .map(|v| {
                let c = &v.check;
                Py::new(
                    py,
                    VaryingLoadCheck {
                        table_params: ValanisParams {
                            inner: c.table_params,
                        },
                        table_fit_r2: c.table_fit_r2,
                        bem_constant_energy_j_per_m2: c.bem_constant_energy_j_per_m2,
                        bem_energy_j_per_m2: c.bem_energy_j_per_m2,
                        element_energy_j_per_m2: c.element_energy_j_per_m2,
                        energy_rel_error: c.energy_rel_error,
                        r2: c.r2,
                        element_shear_pa: PyArray1::from_slice(py, &c.element_shear_pa).unbind(),
                        normal_pressure_pa: PyArray1::from_slice(py, &v.normal_pressure_pa)
                            .unbind(),
                        refit_params: ValanisParams {
                            inner: c.refit_params,
                        },
                        refit_r2: c.refit_r2,
                        refit_energy_rel_error: c.refit_energy_rel_error,
                        load_following_loads_pa: c.load_following.loads.clone(),
                        load_following_params: c
                            .load_following
                            .params
                            .iter()
                            .map(|&inner| ValanisParams { inner })
                            .collect(),
                        load_following_energy_j_per_m2: c.load_following_energy_j_per_m2,
                        load_following_energy_rel_error: c.load_following_energy_rel_error,
                        load_following_r2: c.load_following_r2,
                    },
                )
            })
            .collect::<PyResult<_>>()?,
        edge_warning: sweep.edge_warning.clone(),
        written: written.iter().map(|p| p.display().to_string()).collect(),
    })
}
