//! # asperity
//!
//! Contact parameters for microslip elements, computed from the rough surface.
//!
//! The data flows one way and the modules follow it; each stage uses only the stages above it
//! and [`core`] (checked by `tests/module_layers.rs`):
//!
//! ```text
//! core        FFT plans, materials, grids, statistics, hashing, inputs, limits, output sets
//! surface     generate · stats · io · combine                 rough patches, measured files
//! halfspace   influence (Boussinesq, Cerruti)                 elastic half-space kernels
//! contact     normal (projected CG) · tangential (partial slip) · sweeps
//! element     one file per law: Valanis, Jenkins, Iwan, …     force update with exact partials
//! calibrate   loops → Valanis fits → kn, E0, k versus pressure (calib/*.csv)
//! film        pressure film → preload map → N0 per node
//! elements    preloads + table → one row per contact element
//! dynamics    harmonic balance (AFT, continuation) of structures with those elements
//! identify    measured frequency responses → joint model → levels not used
//! diagnose    measured loops → residual → missing effect → error before/after
//! ```
//!
//! Units: SI throughout (m, Pa, N). File headers, CSV columns and CLI flags name their units.
//! Grids follow the [`Grid2`] convention: shape `(nx, ny)`, `[[i, j]]` at `(i·dx, j·dy)`.

// Every public item carries a doc comment (CI: clippy -D warnings and `cargo doc` with
// RUSTDOCFLAGS=-D warnings). Set here rather than in the workspace [lints] table, which would
// also ask for docs in the binary, the tests, the benches and the Python crate.
#![warn(missing_docs)]

pub mod calibrate;
pub mod contact;
pub mod core;
pub mod diagnose;
pub mod dynamics;
pub mod element;
pub mod elements;
pub mod film;
pub mod halfspace;
pub mod identify;
pub mod surface;

pub use crate::core::error::{Error, Result};
pub use crate::core::grid::Grid2;
