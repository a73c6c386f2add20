//! Rough surfaces: generation from profilometer statistics, statistics of measured or generated
//! topographies, file readers and writers, and the reduction of two rough bodies to one.
pub mod combine;
pub mod generate;

pub use generate::{generate, GaussianSurfaceSpec};
