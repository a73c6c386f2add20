//! Closing the loop: compare a model with a measured hysteresis record, find what it misses,
//! add it and show the gain.
//!
//! ```text
//! record (CSV)  ──► cycles (reversals, complete cycles, phases)
//!               ──► baseline Valanis element (fitted, or from a calibration table)
//!               ──► residual per phase ──► candidate effects, each refitted on training cycles
//!               ──► selection on held-out cycles (ΔBIC) ──► report (text, JSON, PNG)
//! ```

pub mod cycles;
pub mod effects;
pub mod record;
pub mod report;
pub mod select;

pub use effects::{Baseline, Effect, Model};
pub use record::{Columns, Record};
pub use select::{diagnose, BaselineSource, Diagnosis, Options};
