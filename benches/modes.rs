//! Benchmark: the EPMC backbone (nonlinear mode) at underplatform-damper size.
//!
//!     cargo bench --bench modes                 # 100 amplitudes
//!     cargo bench --bench modes -- --quick      # 10 amplitudes
//!
//! Case: the synthetic reduced modal model of `benches/response.rs` (30 modes, 0.6–8 kHz, 0.3 %
//! modal damping, seeded; tests/support/upd_model.rs), 146 Valanis microslip contact elements
//! (438 contact DOFs), harmonics 0..7 with 128 samples per period, coordinates formulation (30 ×
//! 15 = 450 harmonic unknowns + ω + ξ). The mode continued is the one the benchmark's excitation
//! drives most in the response bench's span (550–1100 Hz) with the elements stuck; the amplitudes
//! are log-spaced from 1/100 of its linear resonance amplitude at 0.05 N to that at 8 N (the
//! response bench's levels), the default range of `asperity modes`. Prints the wall and CPU time
//! (all threads), the Newton iterations, retries and the backbone's ends. Goal: under 60 s wall
//! on 2 cores for 100 amplitudes. Units: SI, times in seconds.

use asperity::dynamics::aft::Harmonics;
use asperity::dynamics::hbm::{Excitation, FormulationChoice, HbmSystem};
use asperity::dynamics::nonlinear_modes::{linear_mode, log_spaced, Epmc, ModeSettings};
use nalgebra::DVector;
use std::time::Instant;

#[path = "../tests/support/upd_model.rs"]
#[allow(dead_code)]
mod upd_model;
use upd_model::{model, MODES};

fn cpu_time() -> f64 {
    cpu_time::ProcessTime::now().as_duration().as_secs_f64()
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let (s, force, _) = model();
    let sys = HbmSystem::new(
        &s,
        Harmonics::new(7, false, Some(128)).unwrap(),
        Excitation {
            force: DVector::zeros(MODES),
            harmonic: 1,
            force_sin: None,
        },
        FormulationChoice::Coordinates,
    )
    .unwrap();
    let first = linear_mode(&sys, 1).unwrap();
    // The mode in 550–1100 Hz that the excitation drives most.
    let (index, lin) = (1..=MODES)
        .filter(|&i| (550.0..1100.0).contains(&first.frequencies_hz[i - 1]))
        .map(|i| (i, linear_mode(&sys, i).unwrap()))
        .max_by(|a, b| {
            a.1.shape
                .dot(&force)
                .abs()
                .total_cmp(&b.1.shape.dot(&force).abs())
        })
        .expect("a mode in the span");
    let a_lin = |level: f64| {
        lin.shape.dot(&force).abs() * level / (2.0 * lin.damping_ratio() * lin.omega.powi(2))
    };
    let n = if quick { 10 } else { 100 };
    let amplitudes = log_spaced(a_lin(0.05) / 100.0, a_lin(8.0), n).unwrap();
    println!(
        "## EPMC backbone, underplatform-damper size: {MODES} modes, {} elements ({} contact DOFs), harmonics 0..7, {} samples/period, {} unknowns + 2",
        s.elements.len(),
        s.contact_dofs(),
        sys.harmonics.n_time(),
        sys.unknowns()
    );
    println!(
        "mode {index}: {:.3} Hz stuck, damping ratio {:.4e}; {n} amplitudes {:.3e}–{:.3e} m·kg^½; rayon threads {}; load average {}",
        lin.frequency_hz(),
        lin.damping_ratio(),
        amplitudes[0],
        amplitudes[n - 1],
        rayon::current_num_threads(),
        std::fs::read_to_string("/proc/loadavg").unwrap_or_default().trim()
    );
    let epmc = Epmc::new(&sys, ModeSettings::new(index, amplitudes)).unwrap();
    let (t0, c0) = (Instant::now(), cpu_time());
    let mode = epmc.backbone(&mut |_| {}).unwrap();
    let (wall, cpu) = (t0.elapsed().as_secs_f64(), cpu_time() - c0);
    let (p0, p1) = (&mode.points[0], mode.points.last().unwrap());
    println!(
        "{} of {n} points{}; Newton iterations {} (final solves), retries {}, subdivisions {}; {:.3} Hz → {:.3} Hz, damping ratio {:.4e} → {:.4e} (largest {:.4e}); largest energy-balance error {:.2e}",
        mode.points.len(),
        mode.stopped.as_ref().map(|w| format!(" (stopped {w})")).unwrap_or_default(),
        mode.points.iter().map(|p| p.iterations).sum::<usize>(),
        mode.retries,
        mode.subdivisions,
        p0.frequency_hz(),
        p1.frequency_hz(),
        p0.damping_ratio(),
        p1.damping_ratio(),
        mode.points.iter().map(|p| p.damping_ratio()).fold(0.0, f64::max),
        mode.points.iter().map(|p| p.energy_balance_error()).fold(0.0, f64::max),
    );
    // Harmonic content of the last points, ‖Q₃‖/‖Q₁‖ over the coordinates (an internal
    // resonance of the third harmonic with a higher mode shows as its growth), and the
    // stuck structure's modes near three times the last frequency.
    let len = sys.harmonics.len();
    let norm_of = |z: &DVector<f64>, k: usize| {
        let (ci, si) = sys.harmonics.index_of(k).unwrap();
        (0..MODES)
            .map(|r| z[r * len + ci].powi(2) + z[r * len + si].powi(2))
            .sum::<f64>()
            .sqrt()
    };
    for p in mode.points.iter().rev().take(6).rev() {
        println!(
            "a {:.4e} m·kg^½: {:.3} Hz, ζ {:.4e}, ‖Q3‖/‖Q1‖ {:.3e}, ‖Q5‖/‖Q1‖ {:.3e}, element-averaged slip {:.3}, separation {:.3}",
            p.amplitude,
            p.frequency_hz(),
            p.damping_ratio(),
            norm_of(&p.z, 3) / norm_of(&p.z, 1),
            norm_of(&p.z, 5) / norm_of(&p.z, 1),
            p.elements.iter().map(|c| c.slip_fraction).sum::<f64>() / p.elements.len() as f64,
            p.elements.iter().map(|c| c.separation_fraction).sum::<f64>() / p.elements.len() as f64
        );
    }
    let f3 = 3.0 * p1.frequency_hz();
    println!(
        "stuck modes within 25 % of 3 × {:.1} Hz: {:?} Hz",
        p1.frequency_hz(),
        lin.frequencies_hz
            .iter()
            .filter(|f| (**f / f3 - 1.0).abs() < 0.25)
            .map(|f| (f * 10.0).round() / 10.0)
            .collect::<Vec<f64>>()
    );
    println!(
        "wall {wall:.2} s, CPU {cpu:.2} s (all threads); load average at the end {}",
        std::fs::read_to_string("/proc/loadavg")
            .unwrap_or_default()
            .trim()
    );
}
