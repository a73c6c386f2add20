//! Benchmark: Valanis element integrators, the Valanis fit, and the calibration chain on coarse
//! grids (the full 1024² reference run is timed through the CLI; see BENCHMARKS.md).
//!
//!     cargo bench --bench calibrate
//!
//! Units: times in seconds (or µs per step), per unit nominal area quantities inside.

use asperity::calibrate::config::CalibrationConfig;
use asperity::calibrate::fit::{fit_valanis, FitOptions, LoopData};
use asperity::calibrate::pipeline;
use asperity::element::sine_history;
use asperity::element::valanis::{integrate, Integrator, ValanisParams};
use std::time::Instant;

fn best_of<T>(reps: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut best = f64::INFINITY;
    let mut out = None;
    for _ in 0..reps {
        let t = Instant::now();
        let r = f();
        best = best.min(t.elapsed().as_secs_f64());
        out = Some(r);
    }
    (best, out.expect("reps > 0"))
}

fn main() {
    println!("## Valanis element integrators (one element, 10 cycles × 1000 steps)");
    let p = ValanisParams::new(5e13, 0.5, 0.0, 0.6).unwrap();
    let fz0 = 5e6;
    let q = sine_history(2.0 * p.mu * fz0 / p.e0, 10, 1000);
    let constant = vec![fz0; q.len()];
    let varying: Vec<f64> = (0..q.len())
        .map(|i| fz0 * (1.0 + 0.3 * (i as f64 * 0.0047).sin()))
        .collect();
    for (name, fz) in [("constant Fz", &constant), ("varying Fz", &varying)] {
        for method in [Integrator::ImplicitEuler, Integrator::Reference] {
            let (t, f) = best_of(5, || integrate(&p, &q, fz, method).unwrap());
            println!(
                "{name:12} {method:?}: {:.3} µs/step (final force {:.4e} Pa)",
                t / (q.len() - 1) as f64 * 1e6,
                f[f.len() - 1]
            );
        }
    }

    println!("\n## Valanis fit (E0, k; μ fixed)");
    for per in [40usize, 400] {
        let qh = sine_history(1.5 * p.mu * fz0 / p.e0, 2, per);
        let fh = integrate(&p, &qh, &vec![fz0; qh.len()], Integrator::Reference).unwrap();
        let n = qh.len();
        let data = LoopData::constant_load(qh, fh, fz0, n - per - 1..n);
        let (t, fit) = best_of(3, || fit_valanis(&data, &FitOptions::default()).unwrap());
        println!(
            "{per:4} samples/cycle: {:.3} s per fit ({} Nelder–Mead iterations, R² {:.6})",
            t, fit.iterations, fit.r2
        );
    }

    println!("\n## Calibration chain on coarse grids (library call, reference statistics)");
    for n in [256usize, 512] {
        let mut cfg = CalibrationConfig::reference();
        cfg.surface.nx = n;
        cfg.surface.ny = n;
        let (t, run) = best_of(1, || {
            pipeline::run(&cfg, &indicatif::ProgressBar::hidden()).unwrap()
        });
        let s = run.times;
        println!(
            "{n}²: total {t:.2} s (surface {:.2}, normal sweep {:.2}, loops {:.2}, fits {:.2}); min R² {:.5}",
            s.surface_s,
            s.normal_sweep_s,
            s.tangential_loops_s,
            s.fits_s,
            run.table
                .rows
                .iter()
                .map(|r| r.fit_r2)
                .fold(f64::INFINITY, f64::min)
        );
    }
}
