//! `asperity._native`: the Python bindings of the `asperity` library (PyO3, numpy).
//!
//! A thin layer: every function calls the library and converts arguments and results. Arrays
//! come in as borrowed read-only float64 views and go out without a second copy (see
//! [`arrays`]); library errors become Python exceptions carrying the Rust message (see
//! [`errors`]). Long computations release the GIL. The Python package `asperity`
//! (python/asperity/) re-exports everything with type stubs.

mod arrays;
mod calibrate;
mod contact;
mod diagnose;
mod dynamics;
mod element;
mod errors;
mod film;
mod identify;
mod surface;
mod tangential_sweep;

use pyo3::prelude::*;

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<surface::Surface>()?;
    m.add_class::<surface::Profile>()?;
    m.add_class::<surface::SurfaceStats>()?;
    m.add_class::<surface::PowerSpectrum>()?;
    m.add_function(wrap_pyfunction!(surface::read_topography, m)?)?;
    m.add_function(wrap_pyfunction!(surface::composite_modulus, m)?)?;
    m.add_function(wrap_pyfunction!(surface::equivalent_surface, m)?)?;
    m.add_class::<contact::NormalSolver>()?;
    m.add_class::<contact::NormalSolution>()?;
    m.add_class::<contact::Convergence>()?;
    m.add_function(wrap_pyfunction!(contact::normal_sweep, m)?)?;
    m.add_class::<tangential_sweep::VaryingLoadCheck>()?;
    m.add_class::<tangential_sweep::TangentialSweepResult>()?;
    m.add_function(wrap_pyfunction!(tangential_sweep::tangential_sweep, m)?)?;
    m.add_class::<contact::TangentialSolver>()?;
    m.add_class::<contact::TangentialStep>()?;
    m.add_class::<contact::CycleEnergy>()?;
    m.add_class::<contact::TangentialMetadata>()?;
    m.add_class::<contact::OscillationResult>()?;
    m.add_class::<contact::AmplitudeLoop>()?;
    m.add_class::<contact::AmplitudeHistory>()?;
    m.add_class::<element::ValanisParams>()?;
    m.add_class::<element::ValanisFit>()?;
    m.add_class::<element::LoopFit>()?;
    m.add_function(wrap_pyfunction!(element::valanis_integrate, m)?)?;
    m.add_function(wrap_pyfunction!(element::normal_load_history, m)?)?;
    m.add_function(wrap_pyfunction!(element::dissipated_energy, m)?)?;
    m.add_function(wrap_pyfunction!(element::sine_history, m)?)?;
    m.add_function(wrap_pyfunction!(element::fit_valanis, m)?)?;
    m.add_function(wrap_pyfunction!(element::fit_valanis_loops, m)?)?;
    m.add_function(wrap_pyfunction!(element::student_t_975, m)?)?;
    m.add_class::<calibrate::CalibrationTable>()?;
    m.add_class::<calibrate::CalibrationRun>()?;
    m.add_class::<calibrate::TableValues>()?;
    m.add_class::<calibrate::TableColumns>()?;
    m.add_class::<calibrate::ElementSummary>()?;
    m.add_class::<calibrate::StageTimes>()?;
    m.add_class::<calibrate::SurfaceSpec>()?;
    m.add_class::<calibrate::SampleSummary>()?;
    m.add_class::<calibrate::ConvergenceCheck>()?;
    m.add_class::<calibrate::PressureConvergence>()?;
    m.add_class::<calibrate::CalibrationConvergence>()?;
    m.add_function(wrap_pyfunction!(calibrate::join_elements, m)?)?;
    m.add_function(wrap_pyfunction!(calibrate::calibrate, m)?)?;
    m.add_class::<dynamics::ResponseModel>()?;
    m.add_class::<dynamics::SweepResult>()?;
    m.add_class::<dynamics::DecayResult>()?;
    m.add_class::<dynamics::NonlinearModeResult>()?;
    m.add_function(wrap_pyfunction!(calibrate::read_preloads, m)?)?;
    m.add_function(wrap_pyfunction!(calibrate::write_preloads, m)?)?;
    m.add_class::<film::FilmMap>()?;
    m.add_class::<film::ClassCounts>()?;
    m.add_class::<film::RegionSummary>()?;
    m.add_class::<film::Region>()?;
    m.add_class::<film::PolyFit>()?;
    m.add_function(wrap_pyfunction!(film::read_nodes, m)?)?;
    m.add_function(wrap_pyfunction!(film::film_preloads, m)?)?;
    m.add_function(wrap_pyfunction!(film::reduce_preloads, m)?)?;
    m.add_class::<film::FilmResult>()?;
    m.add_class::<film::FilmSummary>()?;
    m.add_class::<film::PreloadSummary>()?;
    m.add_class::<film::BelowRangePatch>()?;
    m.add_class::<film::NotFitted>()?;
    m.add_class::<film::NodePlacement>()?;
    m.add_class::<film::NodeClassReading>()?;
    m.add_class::<film::ReductionSummary>()?;
    m.add_class::<film::NodeSummary>()?;
    m.add_function(wrap_pyfunction!(film::film, m)?)?;
    m.add_class::<diagnose::Record>()?;
    m.add_class::<diagnose::DiagnoseErrors>()?;
    m.add_class::<diagnose::DiagnoseReport>()?;
    m.add_function(wrap_pyfunction!(diagnose::read_record, m)?)?;
    m.add_function(wrap_pyfunction!(diagnose::diagnose, m)?)?;
    m.add_class::<identify::ParameterEstimate>()?;
    m.add_class::<identify::LevelError>()?;
    m.add_class::<identify::IdentifyReport>()?;
    m.add_class::<identify::FilePrediction>()?;
    m.add_class::<identify::PredictReport>()?;
    m.add_function(wrap_pyfunction!(identify::identify, m)?)?;
    m.add_function(wrap_pyfunction!(identify::predict, m)?)?;
    Ok(())
}
