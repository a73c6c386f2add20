//! Contact solvers on the elastic half-space: normal (projected CG) and tangential (Coulomb
//! partial slip with history), and pressure sweeps.
pub mod analytic;
pub mod normal;
pub mod resolution;
pub mod surface_sweep;
pub mod sweep;
pub mod tangential;
