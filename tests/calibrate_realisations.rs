//! Validation of the realisation statistics on a cheap configuration (reference
//! statistics on a 128² grid over a 125 µm patch, two pressures, two amplitudes): every
//! realisation is the same whatever the number of realisations run with it, and the 95 %
//! interval of the mean narrows as t₀.₉₇₅,N−1·s/√N (the expected half-width is checked exactly
//! on synthetic data in `calibrate::statistics`).
//!
//! Units: SI (kn, E0 in N/m³; k dimensionless).

use asperity::calibrate::config::CalibrationConfig;
use asperity::calibrate::pipeline::{self, CalibrationRun, SurfaceSource};
use asperity::core::stats::student_t_975;

fn cheap(count: usize) -> CalibrationConfig {
    let mut c = CalibrationConfig::reference();
    c.surface.nx = 128;
    c.surface.ny = 128;
    c.surface.lx_m = 125e-6;
    c.surface.ly_m = 125e-6;
    c.realisations.count = count;
    c.loading.pressures_pa = vec![2e6, 10e6];
    c.loading.amplitude_factors = vec![0.4, 1.5];
    c
}

fn run(count: usize) -> CalibrationRun {
    pipeline::run(
        &cheap(count),
        &SurfaceSource::Generated,
        &indicatif::ProgressBar::hidden(),
    )
    .unwrap()
}

#[test]
fn interval_narrows_as_one_over_root_n() {
    let (small, large) = (run(4), run(16));
    // The first four realisations are the same surfaces with the same results.
    for (a, b) in small.realisations.iter().zip(&large.realisations) {
        assert_eq!(a.seed, b.seed);
        assert_eq!(a.surface_sha256, b.surface_sha256);
        for (pa, pb) in a.pressures.iter().zip(&b.pressures) {
            assert_eq!(pa.sweep.kn_n_per_m3, pb.sweep.kn_n_per_m3);
            assert_eq!(pa.fit.params, pb.fit.params);
        }
    }
    let (is, il) = (
        small.table.intervals.as_ref().unwrap(),
        large.table.intervals.as_ref().unwrap(),
    );
    // hw = t·s/√N: the sample standard deviations s recovered from the two intervals estimate
    // the same spread (ratio within the 99 % range of s₄/s₁₆ for normal data, 0.2–2.2), and
    // the interval over 16 is narrower by t₃/t₁₅·√(16/4) ≈ 3.0 up to that ratio.
    let predicted = student_t_975(3.0) / student_t_975(15.0) * 2.0;
    for i in 0..2 {
        for (name, h4, h16) in [
            ("kn", is[i].kn_n_per_m3, il[i].kn_n_per_m3),
            ("E0", is[i].e0_n_per_m3, il[i].e0_n_per_m3),
            ("k", is[i].k, il[i].k),
        ] {
            let s4 = h4 * 2.0 / student_t_975(3.0);
            let s16 = h16 * 4.0 / student_t_975(15.0);
            eprintln!(
                "{} MPa {name}: half-width {h4:.3e} (N = 4) → {h16:.3e} (N = 16), ratio {:.2} \
                 (t·√N predicts {predicted:.2} × s₄/s₁₆ = {:.2})",
                small.table.rows[i].pressure_pa / 1e6,
                h4 / h16,
                s4 / s16
            );
            assert!(h16 < h4, "{name}: {h16} vs {h4}");
            assert!(
                (0.2..2.2).contains(&(s4 / s16)),
                "{name}: s4/s16 = {}",
                s4 / s16
            );
        }
    }
}
