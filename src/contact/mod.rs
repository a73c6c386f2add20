//! Contact solvers on the elastic half-space: normal (projected CG) and tangential (Coulomb
//! partial slip with history), and pressure sweeps; [`normal_sweep`] is `asperity contact normal`
//! as a library call (`asperity contact tangential` is
//! [`crate::calibrate::tangential_sweep`], which also checks the calibration's element).
pub mod analytic;
pub mod normal;
pub mod normal_sweep;
pub mod resolution;
pub mod surface_sweep;
pub mod sweep;
pub mod tangential;
