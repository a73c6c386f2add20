//! Calibration of element parameters (kn, E0, k, Et versus pressure) from BEM hysteresis loops,
//! over several random surfaces and several amplitudes, with convergence checks.

pub mod amplitudes;
pub mod config;
pub mod convergence;
pub mod fit;
pub mod output;
pub mod pipeline;
pub mod statistics;
pub mod sweep;
pub mod table;
pub mod tangential_sweep;
pub mod varying_load;

pub use config::CalibrationConfig;
pub use fit::{fit_valanis, fit_valanis_loops, FitOptions, FitResult, LoopData};
pub use output::{write_outputs, ConfigSource};
pub use pipeline::{run, CalibrationRun, SurfaceSource};
pub use table::{CalibrationRow, CalibrationTable, Interpolated, RangeFlag, RowInterval};
