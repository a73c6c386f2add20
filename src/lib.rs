//! # asperity
//!
//! Contact parameters for microslip elements, computed from the rough surface.
//!
//! The data flows one way and the modules follow it:
//!
//! ```text
//! surface  ──►  halfspace (Boussinesq, Cerruti, FFT convolution)
//!          ──►  contact::normal (projected CG) ──► contact::tangential (partial slip loops)
//!          ──►  element (Valanis, Jenkins) + calibrate (kn, E0, k vs pressure)
//!          ──►  film (preload map) ──► elements (one row per contact element)
//!          ◄──  diagnose (measured loops: residual, missing effect, error before/after)
//! ```
//!
//! Units: SI throughout (m, Pa, N). File headers, CSV columns and CLI flags name their units.
//! Grids follow the [`grid::Grid2`] convention: shape `(nx, ny)`, `[[i, j]]` at `(i·dx, j·dy)`.

pub mod build_info;
pub mod calibrate;
pub mod contact;
pub mod core;
pub mod diagnose;
pub mod dynamics;
pub mod element;
pub mod elements;
pub mod error;
pub mod film;
pub mod grid;
pub mod halfspace;
pub mod identify;
pub mod input;
pub mod limits;
pub mod output;
pub mod plot;
pub mod sanity;
pub mod shard;
pub mod surface;
pub mod testdata;

pub use error::{Error, Result};
pub use grid::Grid2;
