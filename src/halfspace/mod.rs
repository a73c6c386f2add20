//! The elastic half-space: influence coefficients (Boussinesq, Cerruti), convolved with surface
//! tractions by the FFT plans of [`crate::core::fft`] (periodic or zero-padded).

pub mod influence;
