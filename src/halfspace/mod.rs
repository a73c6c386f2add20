//! The elastic half-space: influence coefficients (Boussinesq, Cerruti) and their FFT
//! convolution with surface tractions (periodic or zero-padded).

pub mod convolution;
pub mod influence;

pub use convolution::{Boundary, ConvolutionWorkspace, FftPlan, KernelSpectrum, PairWorkspace};
