//! Benchmark: tangential partial-slip loops on the reference rough patch.
//!
//! For each grid size (default 256, 512, 1024; `ASPERITY_BENCH_GRIDS=256,512,1024,2048`), the
//! reference surface statistics on the same 250 µm patch, the normal contact at
//! `ASPERITY_BENCH_PRESSURE_PA` (default 10 MPa, the highest pressure of the sweep: the largest
//! contact set), then one cycle of `ASPERITY_BENCH_STEPS` (default 40) displacement steps at
//! 1.5 × the gross-slip displacement, with each compliance operator (dense restricted matrix and
//! FFT; `ASPERITY_BENCH_OPERATORS=dense,fft`). Prints one line per run: grid, contact points,
//! operator, set-up time, cycle time, iterations, and the process CPU time and minor page faults
//! of the cycle (Linux; the library path: this bench does not set the binary's allocator options,
//! `keep_freed_memory` in src/main.rs). Units: s, m, Pa.
//!
//! Run: `cargo bench --bench tangential` (2 cores: `RAYON_NUM_THREADS=2`).

use asperity::contact::normal::{NormalOptions, NormalProblem, NormalSolver};
use asperity::contact::tangential::{
    oscillate, Control, Operator, Oscillation, TangentialOptions, TangentialProblem,
    TangentialSolver,
};
use asperity::core::fft::Boundary;
use asperity::core::material::{composite_modulus, Material};
use asperity::surface::generate::{generate, GaussianSurfaceSpec};
use std::time::Instant;

/// Minor page faults of the process so far (Linux; 0 elsewhere).
fn minor_faults() -> i64 {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        // SAFETY: getrusage writes into the zeroed struct passed to it.
        let mut ru: libc::rusage = unsafe { std::mem::zeroed() };
        if unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut ru) } == 0 {
            return ru.ru_minflt;
        }
    }
    0
}

/// Process CPU time (s, all threads).
fn cpu_seconds() -> f64 {
    cpu_time::ProcessTime::now().as_duration().as_secs_f64()
}

fn env_list<T: std::str::FromStr>(name: &str, default: &str) -> Vec<T> {
    std::env::var(name)
        .unwrap_or_else(|_| default.to_string())
        .split(',')
        .filter_map(|s| s.trim().parse().ok())
        .collect()
}

fn main() {
    let grids: Vec<usize> = env_list("ASPERITY_BENCH_GRIDS", "256,512,1024");
    let pressure: f64 = env_list("ASPERITY_BENCH_PRESSURE_PA", "1e7")[0];
    let steps: usize = env_list("ASPERITY_BENCH_STEPS", "40")[0];
    let operators: Vec<String> = env_list("ASPERITY_BENCH_OPERATORS", "dense,fft");
    let tolerance = env_list::<f64>("ASPERITY_BENCH_TOLERANCE", "0")
        .first()
        .copied()
        .filter(|&t| t > 0.0)
        .unwrap_or(TangentialOptions::default().tolerance);
    let mu = 0.6;
    let m = Material::STEEL;
    let e_star = composite_modulus(m, m).unwrap();
    println!(
        "threads {} | pressure {pressure:e} Pa | μ {mu} | one cycle of {steps} steps",
        rayon::current_num_threads()
    );
    println!("grid  contact_points  operator  setup_s  cycle_s  per_step_s  mean_iterations  energy_J_per_m2  tolerance  cycle_cpu_s  cycle_minor_faults");
    for &n in &grids {
        let mut spec = GaussianSurfaceSpec::reference();
        spec.nx = n;
        spec.ny = n;
        let surface = generate(&spec).unwrap();
        let mut normal = NormalSolver::new(
            &NormalProblem {
                surface: &surface,
                e_star_pa: e_star,
                hardness_pa: None,
            },
            NormalOptions::default(),
        )
        .unwrap();
        let sol = normal.solve_load(pressure, None).unwrap();
        let mut amplitude = None;
        for op in &operators {
            let operator = match op.as_str() {
                "dense" => Operator::Dense,
                "fft" => Operator::Fft,
                _ => Operator::Auto,
            };
            let t0 = Instant::now();
            let built = TangentialSolver::new(
                &TangentialProblem {
                    pressure: &sol.pressure,
                    dx: surface.dx,
                    dy: surface.dy,
                    boundary: Boundary::Periodic,
                    friction_coefficient: mu,
                    body1: m,
                    body2: m,
                },
                TangentialOptions {
                    operator,
                    tolerance,
                    ..TangentialOptions::default()
                },
            );
            let mut s = match built {
                Ok(s) => s,
                Err(e) => {
                    println!("{n:>5}  {op}: {e}");
                    continue;
                }
            };
            let setup = t0.elapsed().as_secs_f64();
            let a = *amplitude
                .get_or_insert_with(|| 1.5 * s.gross_slip_displacement([1.0, 0.0]).unwrap());
            let (t1, cpu1, faults1) = (Instant::now(), cpu_seconds(), minor_faults());
            let r = oscillate(
                &mut s,
                &Oscillation {
                    amplitude: Control::Displacement([a, 0.0]),
                    cycles: 1,
                    steps_per_cycle: steps,
                },
                |_, _| {},
            )
            .unwrap();
            let cycle = t1.elapsed().as_secs_f64();
            let (cpu, faults) = (cpu_seconds() - cpu1, minor_faults() - faults1);
            let its: usize = r.steps.iter().map(|s| s.iterations).sum();
            println!(
                "{n:>5}  {:>14}  {:>8}  {setup:>7.2}  {cycle:>7.2}  {:>10.4}  {:>15.1}  {:>15.9}  {:e}  {cpu:>11.2}  {faults:>18}",
                s.metadata().contact_points,
                op,
                cycle / steps as f64,
                its as f64 / steps as f64,
                r.cycles[0].dissipated_j_per_m2,
                tolerance
            );
        }
    }
}
