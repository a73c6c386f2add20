//! Closing the loop: compare a model with a measured hysteresis record, find what it misses,
//! add it and show the gain — and say so when the model cannot explain the record.
//!
//! ```text
//! record (CSV)  ──► cycles (reversals, complete cycles, phases)
//!               ──► noise floor from the data alone (cycle-to-cycle repeatability)
//!               ──► baseline Valanis element (fitted, or from a calibration table)
//!               ──► candidate effects, each refitted on training cycles, scored on held-out
//!                   cycles against the noise floor ──► verdict: effect(s) found / model
//!                   adequate / model inadequate (where, ringing, drift)
//!               ──► stationarity (baseline per cycle, trend test)
//!               ──► report (text, JSON, CSV, PNG)
//! ```

pub mod acceleration;
pub mod cycles;
pub mod effects;
pub mod noise;
pub mod record;
pub mod report;
pub mod residual;
pub mod select;
pub mod stationarity;

pub use effects::{Baseline, Bound, Effect, Model};
pub use record::{Columns, Record};
pub use select::{diagnose, BaselineSource, Diagnosis, Options, Verdict};
