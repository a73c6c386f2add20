//! Rough surfaces: generation from profilometer statistics, statistics of measured or generated
//! topographies, file readers and writers, and the reduction of two rough bodies to one.
pub mod combine;
pub mod generate;
pub mod io;
pub mod missing;
pub mod self_affine;
pub mod stats;
pub mod topography;

pub use generate::{generate, GaussianSurfaceSpec};
pub use missing::{Fill, MaskedGrid};
pub use self_affine::{generate_self_affine, SelfAffineSpec};
pub use stats::{stats, Detrend, SurfaceStats};
pub use topography::{Profile, Topography};
