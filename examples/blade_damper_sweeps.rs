//! The synthetic measured sweeps of the full-size reduced-model update in docs/identify.md
//! ("Multi-DOF reduced models", `calib/identify-reduced/`): the blade–damper example of
//! `asperity response` (`calib/response/model.toml`, two tables of 110 Valanis elements) with
//! known updating factors, swept at three force levels and written as a displacement sensor at
//! the response DOF would record it (the mode is damped by 3–12 %: an accelerance's maximum would
//! sit well above the resonance) — seeded noise, so the report can be regenerated exactly
//! (`calib/identify-reduced/regenerate.sh`).
//!
//!     cargo run --release --example blade_damper_sweeps -- <out dir>
//!
//! Writes `level1.csv`, `level2.csv`, `level3.csv` (3, 10 and 30 N): `frequency_Hz,
//! force_amplitude_N, displacement_amplitude_m, phase_rad` (`e^{iωt}` convention), 36
//! rows per level across the level's resonance, the controller's force dipping by up to 10 % at
//! it, 0.5 % relative amplitude noise and 0.005 rad phase noise (normal, seeded per level).
//! Units: SI (Hz, N, m, rad).

#[path = "../tests/support/synthetic_sweep.rs"]
mod synthetic_sweep;

use asperity::core::output::OutputSet;
use asperity::identify::fit::Parametrised;
use asperity::identify::measured::Quantity;
use asperity::identify::model::Drive;
use asperity::identify::reduced::ReducedSpec;
use std::f64::consts::TAU;
use std::path::{Path, PathBuf};

/// The truth: `frequency_factor, damping_factor, contact_stiffness_factor, friction_factor`
/// applied to the model as computed from the surfaces and the film.
const TRUTH: [f64; 4] = [1.01, 1.3, 0.9, 1.2];

/// Per level: force (N), first and last frequency of the sweep (Hz), the truth's resonance
/// there (Hz, where the controller's force dips) and its half-power half-width (Hz). Each sweep
/// is centred on its level's resonance, as a test engineer sets one up.
const LEVELS: [(f64, f64, f64, f64, f64); 3] = [
    (3.0, 7300.0, 8700.0, 7990.0, 265.0),
    (10.0, 6900.0, 8650.0, 7780.0, 500.0),
    (30.0, 5800.0, 8300.0, 6950.0, 785.0),
];

/// Rows per level.
const ROWS: usize = 36;

/// Relative amplitude noise and phase noise (rad), standard deviations.
const NOISE: f64 = 0.005;

/// The rows of one level: `ROWS` frequencies from `f0` to `f1`, the force `force` dipping by
/// up to 10 % over the half-power band around `fr` (a controller that lags the resonance).
fn drives(force: f64, f0: f64, f1: f64, fr: f64, half_width: f64) -> Vec<Drive> {
    (0..ROWS)
        .map(|i| {
            let f = f0 + (f1 - f0) * i as f64 / (ROWS - 1) as f64;
            let dip = 0.1 / (1.0 + ((f - fr) / half_width).powi(2));
            Drive {
                omega: TAU * f,
                force_n: force * (1.0 - dip),
            }
        })
        .collect()
}

fn write_csv(path: &Path, rows: &[asperity::identify::measured::Row]) -> asperity::Result<()> {
    let mut t = format!(
        "# synthetic sweep of calib/response/model.toml with factors {TRUTH:?} \
         (examples/blade_damper_sweeps.rs); {NOISE} relative amplitude and {NOISE} rad phase noise\n\
         frequency_Hz,force_amplitude_N,displacement_amplitude_m,phase_rad\n"
    );
    for r in rows {
        t += &format!(
            "{:.3},{:.6},{:.6e},{:.6}\n",
            r.frequency_hz, r.force_n, r.response, r.phase_rad
        );
    }
    asperity::core::output::write_string_atomic(path, &t)
}

fn main() -> asperity::Result<()> {
    let out_dir = PathBuf::from(
        std::env::args()
            .nth(1)
            .ok_or_else(|| asperity::Error::param("out dir", "usage: <out dir>"))?,
    );
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR"));
    let spec = ReducedSpec::load(&manifest.join("calib/response/model.toml"))?;
    let truth = spec.model(TRUTH.to_vec());
    let mut out = OutputSet::in_dir(&out_dir, "out dir")?;
    for (k, &(force, f0, f1, fr, hw)) in LEVELS.iter().enumerate() {
        let d = drives(force, f0, f1, fr, hw);
        // Not tolerant: a row that fails to converge ends the run with its error.
        let (x, _) = truth.receptance_tolerant(&d, force, false)?;
        let name = format!("level{}.csv", k + 1);
        let sweep = synthetic_sweep::noisy_sweep_of(
            Quantity::Displacement,
            name.clone(),
            &d,
            &x,
            NOISE,
            k as u64 + 1,
        );
        write_csv(&out.path(&name)?, &sweep.rows)?;
        eprintln!("level {} ({force} N): {} rows", k + 1, sweep.rows.len());
    }
    out.commit()?;
    Ok(())
}
