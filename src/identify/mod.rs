//! Closing the loop on measured frequency responses: identify a jointed structure's
//! single-nonlinear-mode model from stepped-sine sweeps at several excitation levels, find the
//! effect the model lacks, and predict the levels and tests not used; or update a multi-DOF
//! reduced model (an `asperity response` model file) by four factors ([`reduced`]).
//!
//! ```text
//! measured (stepped-sine CSVs, phase convention) ──► backbone (equivalent linear per level)
//!   ──► model (mode + joint element + effects, evaluated by dynamics::hbm)
//!   ──► fit (particle swarm + Nelder–Mead, several starts) ──► select (held-out ΔBIC)
//!   ──► report (errors before/after, backbones, plots, model file) ──► predict (any file)
//! ```

pub mod backbone;
pub mod command;
pub mod effects;
pub mod fit;
pub mod measured;
pub mod model;
pub mod model_free;
pub mod pipeline;
pub mod predict;
pub mod reduced;
pub mod report;
pub mod select;
pub mod stationarity;
pub mod uncertainty;

pub use pipeline::{identify, read_sweeps, Identification, Options, SavedModel};
pub use predict::{predict, Control, Prediction};
