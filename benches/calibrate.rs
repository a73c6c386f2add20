//! Benchmark: Valanis element integrators, the Valanis fit, how the calibration's chains share
//! the cores, and the full reference calibration with its time split by stage.
//!
//!     cargo bench --bench calibrate                                  # all but the reference run
//!     ASPERITY_BENCH_REFERENCE=1 cargo bench --bench calibrate       # + the built-in reference case
//!     ASPERITY_BENCH_PARALLEL_GRID=512 ASPERITY_BENCH_PARALLEL_REALISATIONS=4 cargo bench --bench calibrate
//!
//! Units: times in seconds (or µs per step), per unit nominal area quantities inside.

use asperity::calibrate::config::CalibrationConfig;
use asperity::calibrate::fit::{fit_valanis, FitOptions, LoopData};
use asperity::calibrate::pipeline::{self, Parallelism, StageTimes, SurfaceSource};
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

    println!("\n## Chains sharing the cores: concurrently single-threaded vs one at a time");
    let grid = env_usize("ASPERITY_BENCH_PARALLEL_GRID", 512);
    let count = env_usize("ASPERITY_BENCH_PARALLEL_REALISATIONS", 4);
    let mut cfg = CalibrationConfig::reference();
    cfg.surface.nx = grid;
    cfg.surface.ny = grid;
    cfg.realisations.count = count;
    let mut tables = Vec::new();
    for mode in [
        Parallelism::ChainsConcurrently,
        Parallelism::OneChainAtATime,
    ] {
        let load = load_average();
        let (t, run) = best_of(1, || {
            pipeline::run_with(
                &cfg,
                &SurfaceSource::Generated,
                &indicatif::ProgressBar::hidden(),
                mode,
            )
            .unwrap()
        });
        println!(
            "{grid}², {count} realisations + checks, {} threads, {mode:?}: wall {t:.1} s (load average before: {load})",
            rayon::current_num_threads()
        );
        tables.push(run.table);
    }
    println!(
        "tables identical: {}",
        tables.windows(2).all(|w| w[0] == w[1])
    );

    if std::env::var("ASPERITY_BENCH_REFERENCE").is_ok() {
        println!("\n## Reference case (built-in default of `asperity calibrate`)");
        let cfg = CalibrationConfig::reference();
        let load = load_average();
        let dir = tempfile::tempdir().unwrap();
        let t = Instant::now();
        let run = pipeline::run(
            &cfg,
            &SurfaceSource::Generated,
            &indicatif::ProgressBar::hidden(),
        )
        .unwrap();
        let (_, output_s) = asperity::calibrate::write_outputs(
            &run,
            &asperity::calibrate::ConfigSource::BuiltIn,
            dir.path(),
        )
        .unwrap();
        let wall = t.elapsed().as_secs_f64();
        let s: StageTimes = run.times;
        println!(
            "{} realisations × {} pressures × {} amplitudes at {}², {} threads: wall {wall:.1} s (chains {:.1} s, output {output_s:.1} s); load average before: {load}, after: {}",
            cfg.realisations.count,
            cfg.loading.pressures_pa.len(),
            cfg.loading.amplitude_factors.len(),
            cfg.surface.nx,
            rayon::current_num_threads(),
            s.total_s,
            load_average()
        );
        println!("| stage | CPU, all chains (s) | CPU, main chains (s) | CPU, check chains (s) |");
        println!("|---|---|---|---|");
        let sum = |rs: &[pipeline::Realisation], f: fn(&StageTimes) -> f64| -> f64 {
            rs.iter().map(|r| f(&r.times)).sum()
        };
        let checks: Vec<pipeline::Realisation> = run
            .grid_check
            .iter()
            .chain(&run.patch_check)
            .cloned()
            .collect();
        type Stage = (&'static str, fn(&StageTimes) -> f64);
        let stages: [Stage; 4] = [
            ("surface", |t| t.surface_cpu_s),
            ("normal", |t| t.normal_cpu_s),
            ("tangential", |t| t.tangential_cpu_s),
            ("fit", |t| t.fit_cpu_s),
        ];
        for (name, f) in stages {
            println!(
                "| {name} | {:.1} | {:.1} | {:.1} |",
                f(&s),
                sum(&run.realisations, f),
                sum(&checks, f)
            );
        }
        println!("| output (wall) | {output_s:.1} | | |");
        for (i, r) in run.table.rows.iter().enumerate() {
            let iv = run.table.intervals.as_ref().map(|v| v[i]);
            let c = &run.convergence.pressures[i];
            println!(
                "{} MPa: kn {:.3e} ± {:.1e}, E0 {:.3e} ± {:.1e}, k {:.3} ± {:.3}; spots {:.1}, median points/spot {}; grid {}, patch {}",
                r.pressure_pa / 1e6,
                r.element.kn_n_per_m3,
                iv.map_or(f64::NAN, |v| v.kn_n_per_m3),
                r.element.e0_n_per_m3,
                iv.map_or(f64::NAN, |v| v.e0_n_per_m3),
                r.element.k,
                iv.map_or(f64::NAN, |v| v.k),
                c.contact_spots.mean,
                c.median_spot_points,
                c.grid_verdict.as_str(),
                c.patch_verdict.as_str()
            );
        }
    }
}

fn env_usize(name: &str, default: usize) -> usize {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// The 1-, 5- and 15-minute load averages (the machine may be shared).
fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|_| "unknown".into())
}
