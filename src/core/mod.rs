//! The core layer: what every stage uses and what uses no stage.
//!
//! | module | holds |
//! |---|---|
//! | [`fft`] | FFT plans (periodic and zero-padded), kernel spectra, convolution workspaces |
//! | [`material`] | isotropic elastic materials, composite modulus |
//! | [`grid`] | [`grid::Grid2`], heights on a regular grid with their spacing |
//! | [`stats`] | median, percentiles, quantiles, Student-t quantiles |
//! | [`fit`] | the one fitting layer: bounded parameter specs and transforms, restarted Nelder–Mead (argmin), particle swarm, held-out helpers |
//! | [`hash`] | SHA-256 of files and bytes (provenance) |
//! | [`error`] | the crate's [`error::Error`] and [`error::Result`] |
//! | [`input`] | CSV/TOML readers that name the file and line of a bad value |
//! | [`limits`], [`sanity`] | bounds on sizes and on physical inputs and results |
//! | [`output`] | atomic output sets (staged, moved into place together) |
//! | [`plot`] | PNG line plots beside the CSV outputs |
//! | [`shard`], [`build_info`] | sharded sweeps and the build identity they record |
//! | [`testdata`] | where tests find the shared reference data |
//!
//! Stages (surface → halfspace → contact → element → calibrate → film → elements → dynamics
//! → identify, diagnose) may use any of these; none of these uses a stage
//! (`tests/module_layers.rs` checks it).

pub mod build_info;
pub mod error;
pub mod fft;
pub mod fit;
pub mod grid;
pub mod hash;
pub mod input;
pub mod limits;
pub mod material;
pub mod output;
pub mod plot;
pub mod sanity;
pub mod shard;
pub mod stats;
pub mod testdata;
