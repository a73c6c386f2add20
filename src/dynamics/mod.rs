//! Nonlinear forced response of structures with contact elements: multi-harmonic balance (HBM)
//! with the alternating frequency–time method (AFT) and pseudo-arclength continuation.
//!
//! Data flow, one module per concept:
//!
//! ```text
//! fe_matrices (K, M exported by an FE code) ──► craig_bampton (interface DOFs + modes)
//!   ──► model (linear part: lumped M, C, K or a reduced modal model; elements on node pairs)
//!   ──► cyclic (one sector of a cyclic structure: travelling-wave boundary conditions)
//!   ──► crate::element (the laws, as time-discrete hysteretic elements)
//!   ──► aft (harmonics ⇄ time, periodic state)
//!   ──► hbm (residual, Jacobian, Newton; coordinates or receptance-condensed contact DOFs)
//!   ──► continuation (pseudo-arclength in frequency, turning points)
//!   ──► nonlinear_modes (EPMC: backbone and modal damping against modal amplitude)
//!   ──► stability (Hill's method at every point, bifurcations named)
//! time_integration: reference steady state by Newmark time stepping (validation)
//! transient: free decay by the same time stepping, frequency and damping per period
//! ```

// Index loops over DOFs, harmonics and samples read like the equations they implement.
#![allow(clippy::needless_range_loop)]

pub mod aft;
pub mod condensation;
pub mod contact;
pub mod continuation;
pub mod craig_bampton;
pub mod cyclic;
pub mod fe_matrices;
pub mod hbm;
pub mod loops;
pub mod model;
pub mod model_file;
pub mod modes;
pub mod nonlinear_modes;
pub mod report;
pub mod response;
pub mod stability;
pub mod time_integration;
pub mod transient;
