//! Calibration of element parameters (kn, E0, k, Et versus pressure) from BEM hysteresis loops.

pub mod amplitudes;
pub mod table;

pub use table::{CalibrationRow, CalibrationTable, Interpolated, RangeFlag};
pub mod fit;

pub use fit::{fit_valanis, FitOptions, FitResult, LoopData};
pub mod config;

pub use config::CalibrationConfig;
pub mod pipeline;

pub use pipeline::{run, write_outputs, CalibrationRun, ConfigSource};
