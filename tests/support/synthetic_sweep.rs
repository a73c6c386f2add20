//! Measured-format sweeps of a model's response, shared by the identification tests
//! (`tests/identify_synthetic.rs`, `tests/identify_reduced.rs`). Units: SI (m/N receptances,
//! m/s² accelerations, N, Hz, rad).

use asperity::identify::measured::{Quantity, Row, Sweep};
use asperity::identify::model::{Drive, Scales};
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use realfft::num_complex::Complex64;
use std::f64::consts::TAU;

/// The sweep an accelerometer would record of drive-point receptances `x` (m/N) at `drives`:
/// acceleration amplitude with relative noise and phase with noise (rad), both of standard
/// deviation `noise` (normal, seeded; drawn per row, amplitude then phase).
#[allow(dead_code)]
pub fn noisy_sweep(
    path: String,
    drives: &[Drive],
    x: &[Complex64],
    noise: f64,
    seed: u64,
) -> Sweep {
    noisy_sweep_of(Quantity::Acceleration, path, drives, x, noise, seed)
}

/// [`noisy_sweep`] as a sensor of `quantity` would record it (displacement, velocity or
/// acceleration amplitude and its phase).
pub fn noisy_sweep_of(
    quantity: Quantity,
    path: String,
    drives: &[Drive],
    x: &[Complex64],
    noise: f64,
    seed: u64,
) -> Sweep {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let n = Normal::new(0.0, noise).unwrap();
    let rows = drives
        .iter()
        .zip(x)
        .enumerate()
        .map(|(i, (d, xi))| {
            let y = xi * quantity.from_displacement(d.omega);
            Row {
                line: i + 2,
                frequency_hz: d.omega / TAU,
                force_n: d.force_n,
                response: y.norm() * d.force_n * (1.0 + n.sample(&mut rng)),
                phase_rad: y.arg() + n.sample(&mut rng),
            }
        })
        .collect();
    Sweep {
        path: path.into(),
        sha256: String::new(),
        quantity,
        rows,
        header_line: 1,
    }
}

/// Reference scales of the single-mode synthetic cases (80 Hz, 2 kg, 20–200 µm, 0.4 N): they only
/// state the truths' dimensionless effect parameters; an identification derives its own from the
/// data. Not every test binary that includes this file uses them.
#[allow(dead_code)]
pub const SCALES: Scales = Scales {
    frequency_hz: 80.0,
    modal_mass_kg: 2.0,
    amplitude_max_m: 2e-4,
    amplitude_min_m: 2e-5,
    force_n: 0.4,
};
