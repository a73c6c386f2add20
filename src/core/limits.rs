//! Resource limits, checked **before** anything large is allocated.
//!
//! A request that cannot be met is refused with [`Error::Limit`] naming the flag, key or file
//! and the limit, instead of ending in an out-of-memory abort (exit 134) half-way through.
//!
//! | what | limit | checked by |
//! |---|---|---|
//! | points of one grid (surface, film map) | [`MAX_GRID_POINTS`] = 2²⁶ ≈ 67 M (8192 × 8192) | [`check_grid`] |
//! | working memory of a command | its estimate ≤ 90 % of the memory available now (`MemAvailable`) | [`check_grid`], [`check_memory`] |
//! | text input file (topography, CSV, TOML) | [`MAX_TEXT_FILE_BYTES`] = 1 GiB | [`check_file_size`] |
//! | film image | [`MAX_IMAGE_PIXELS`] = 2²⁸ pixels | `film::regions::FilmMap::read_image` |
//! | load steps of one loading history | [`MAX_STEPS`] = 100 000 in all, [`MAX_STEPS_PER_CYCLE`] = 10 000 per cycle, [`MAX_CYCLES`] = 1000 | [`check_steps`] |
//! | nominal pressures of a sweep | [`MAX_PRESSURES`] = 1000 | [`check_count`] |
//! | harmonics and time samples of a harmonic-balance model | [`MAX_HARMONICS`] = 256, [`MAX_TIME_SAMPLES`] = 65 536 | `dynamics::aft::Harmonics::new`, model-file validation |
//! | unknowns of a harmonic-balance Jacobian | its dense matrices within the available memory | `dynamics::hbm::HbmSystem::new` ([`check_memory`]) |
//! | identification search: starts, particles, swarm iterations, local iterations, chain steps | [`MAX_FIT_STARTS`], [`MAX_PARTICLES`], [`MAX_SWARM_ITERATIONS`], [`MAX_LOCAL_ITERATIONS`], [`MAX_CHAIN_STEPS`] | `asperity identify` ([`check_count`]) |
//! | rows of a measured frequency-response file | [`MAX_SWEEP_ROWS`] = 20 000 | `identify::measured::Sweep::read_csv` |
//! | points of a response sweep (`sweep.points`) | [`MAX_SWEEP_POINTS`] = 5000; accepted points at most 4 × that | response-model validation |
//!
//! Binary files are checked against their own headers first: a `.npy` whose header promises
//! more values than the file holds, or an x3p whose `main.xml` declares more points than its
//! data entry carries, is reported as truncated before its data are read.
//!
//! The working-memory estimates are per grid point ([`STATS_BYTES_PER_POINT`],
//! [`CONTACT_BYTES_PER_POINT`], ...): the solvers' FFT buffers (zero-padded to 2n × 2n for
//! finite windows) dominate; they were measured as peak resident memory on 256² and 512²
//! grids and rounded up.
//!
//! Commands adopt the limits with one call each: `check_grid(flag, nx, ny, bytes_per_point)` for
//! every grid they are about to build, `check_steps(flag, cycles, steps_per_cycle)` for every
//! loading history, `check_count(flag, n, MAX_PRESSURES)` for lists.

use crate::core::error::{Error, Result};
use std::path::Path;

/// Largest number of points of one grid (2²⁶ ≈ 67 million, e.g. 8192 × 8192): one field of
/// f64 is then 512 MiB, and the solvers hold several.
pub const MAX_GRID_POINTS: usize = 1 << 26;

/// Largest text input file read into memory (1 GiB).
pub const MAX_TEXT_FILE_BYTES: u64 = 1 << 30;

/// Largest film image (2²⁸ ≈ 268 million pixels, e.g. a 16 000 × 16 000 scan).
pub const MAX_IMAGE_PIXELS: u64 = 1 << 28;

/// Largest number of load steps of one loading history (all cycles).
pub const MAX_STEPS: usize = 100_000;

/// Largest number of load steps per cycle.
pub const MAX_STEPS_PER_CYCLE: usize = 10_000;

/// Largest number of cycles of one loading history.
pub const MAX_CYCLES: usize = 1_000;

/// Largest number of nominal pressures of one sweep.
pub const MAX_PRESSURES: usize = 1_000;

/// Highest harmonic of a harmonic-balance model. Microslip joints are resolved with a few tens
/// (the underplatform-damper and bolted-joint studies use 5–15); the dense synthesis and analysis
/// matrices and the Jacobian grow with the square of the unknowns.
pub const MAX_HARMONICS: usize = 256;

/// Most time samples per period of the alternating frequency–time method (2¹⁶ ≥ 256 samples per
/// retained harmonic at [`MAX_HARMONICS`]).
pub const MAX_TIME_SAMPLES: usize = 1 << 16;

/// Most particle-swarm starts of one identification fit.
pub const MAX_FIT_STARTS: usize = 100;

/// Most particles of one swarm.
pub const MAX_PARTICLES: usize = 10_000;

/// Most swarm iterations per start.
pub const MAX_SWARM_ITERATIONS: u64 = 100_000;

/// Most Nelder–Mead iterations per local run.
pub const MAX_LOCAL_ITERATIONS: u64 = 10_000_000;

/// Most steps of one Metropolis chain of the prediction bands (each step's model is kept in
/// memory for the chain's diagnostics).
pub const MAX_CHAIN_STEPS: usize = 1_000_000;

/// Most data rows of one measured frequency-response file (`identify`, `predict`): every model
/// evaluation of an identification visits each row, so the work grows with the rows.
pub const MAX_SWEEP_ROWS: usize = 20_000;

/// Most points of `sweep.points` of a response model (the span's smooth part; peaks get more,
/// up to four times as many accepted points, [`crate::dynamics::continuation`]).
pub const MAX_SWEEP_POINTS: usize = 5_000;

/// Largest `main.xml` of an x3p archive (16 MiB; real ones are a few kB).
pub const MAX_XML_BYTES: u64 = 16 << 20;

/// Working memory per grid point of reading a topography and computing its statistics
/// (heights, mask, zero-padded autocorrelation and PSD transforms).
pub const STATS_BYTES_PER_POINT: u64 = 256;

/// Working memory per grid point of a contact computation (normal solver with zero-padded
/// kernel, tangential solver, the pressure fields of every load kept for the loops).
pub const CONTACT_BYTES_PER_POINT: u64 = 1024;

/// Working memory per grid point of generating a surface (noise, filter and their transforms).
pub const GENERATE_BYTES_PER_POINT: u64 = 96;

/// Working memory per pixel of reading a film image (decoded RGB, channels, classes, pressure).
pub const FILM_BYTES_PER_PIXEL: u64 = 64;

/// Memory the operating system reports as available now (`MemAvailable` of `/proc/meminfo`),
/// or `None` where that is not known.
pub fn available_memory_bytes() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb.saturating_mul(1024))
}

fn human_bytes(b: u64) -> String {
    let b = b as f64;
    if b >= 1024.0 * 1024.0 * 1024.0 {
        format!("{:.1} GiB", b / (1024.0 * 1024.0 * 1024.0))
    } else if b >= 1024.0 * 1024.0 {
        format!("{:.1} MiB", b / (1024.0 * 1024.0))
    } else {
        format!("{b:.0} bytes")
    }
}

/// Refuse an estimated working memory of `bytes` that exceeds 90 % of the available memory.
pub fn check_memory(name: &str, bytes: u64, what: &str) -> Result<()> {
    if let Some(avail) = available_memory_bytes() {
        if bytes > avail / 10 * 9 {
            return Err(Error::limit(
                name,
                format!(
                    "{what} needs about {} of memory, {} is available",
                    human_bytes(bytes),
                    human_bytes(avail)
                ),
            ));
        }
    }
    Ok(())
}

/// Refuse a grid of `nx × ny` points above [`MAX_GRID_POINTS`], or whose working memory
/// (`bytes_per_point` per point) exceeds the available memory. `name` is the flag, key or file
/// that asked for it.
pub fn check_grid(name: &str, nx: usize, ny: usize, bytes_per_point: u64) -> Result<()> {
    let points = nx.checked_mul(ny).filter(|&n| n <= MAX_GRID_POINTS);
    let Some(points) = points else {
        return Err(Error::limit(
            name,
            format!(
                "a {nx} × {ny} grid has more than {MAX_GRID_POINTS} points (the documented \
                 limit, 8192 × 8192); use a coarser grid or a smaller window"
            ),
        ));
    };
    check_memory(
        name,
        (points as u64).saturating_mul(bytes_per_point),
        &format!("a {nx} × {ny} grid"),
    )
}

/// Refuse a count above `max`, naming the flag or key.
pub fn check_count(name: &str, value: usize, max: usize) -> Result<()> {
    if value > max {
        Err(Error::limit(
            name,
            format!("{value} is more than the limit of {max}"),
        ))
    } else {
        Ok(())
    }
}

/// Refuse a loading history of more than [`MAX_CYCLES`] cycles, [`MAX_STEPS_PER_CYCLE`] steps
/// per cycle or [`MAX_STEPS`] steps in all. `cycles_name` and `steps_name` are the flags or
/// keys.
pub fn check_steps(
    cycles_name: &str,
    cycles: usize,
    steps_name: &str,
    steps_per_cycle: usize,
) -> Result<()> {
    check_count(cycles_name, cycles, MAX_CYCLES)?;
    check_count(steps_name, steps_per_cycle, MAX_STEPS_PER_CYCLE)?;
    let total = cycles.saturating_mul(steps_per_cycle);
    if total > MAX_STEPS {
        return Err(Error::limit(
            format!("{cycles_name} × {steps_name}"),
            format!(
                "{cycles} cycles × {steps_per_cycle} steps = {total} load steps, more than the \
                 limit of {MAX_STEPS}"
            ),
        ));
    }
    Ok(())
}

/// Size of a file in bytes, refused above `max` (the error names the file).
pub fn check_file_size(path: &Path, max: u64) -> Result<u64> {
    let len = std::fs::metadata(path)
        .map_err(|e| Error::io(path, e))?
        .len();
    if len > max {
        return Err(Error::limit(
            path.display().to_string(),
            format!(
                "the file has {}, more than the {} this reader accepts",
                human_bytes(len),
                human_bytes(max)
            ),
        ));
    }
    Ok(len)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn oversized_requests_are_named_errors() {
        let e = check_grid("--n", 65536, 65536, 8).unwrap_err().to_string();
        assert!(e.contains("--n") && e.contains("resource limit"), "{e}");
        let e = check_grid("--nx", usize::MAX, 3, 8)
            .unwrap_err()
            .to_string();
        assert!(e.contains("--nx"), "{e}");
        assert!(check_grid("--n", 64, 64, 8).is_ok());
        let e = check_steps("--cycles", 1_000_000, "--steps-per-cycle", 40)
            .unwrap_err()
            .to_string();
        assert!(e.contains("--cycles"), "{e}");
        let e = check_steps("--cycles", 900, "--steps-per-cycle", 400)
            .unwrap_err()
            .to_string();
        assert!(e.contains("360000"), "{e}");
        assert!(check_steps("--cycles", 3, "--steps-per-cycle", 40).is_ok());
        // More memory than any machine has.
        if available_memory_bytes().is_some() {
            assert!(check_memory("x", u64::MAX / 2, "it").is_err());
        }
    }
}
