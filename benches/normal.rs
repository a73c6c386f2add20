//! Benchmark of the normal contact solver against tamaas 2.9, in the same run.
//!
//!     benches/peers/setup.sh                        # throwaway venv with tamaas (once)
//!     cargo bench --bench normal                    # sections A–C below (about 1 h, 2 idle cores)
//!     cargo bench --bench normal -- --quick         # sections A–C on 512² only
//!     cargo bench --bench normal -- --sizes 512,1024 # A–C on the grids given (B: ≤ 1024² only)
//!     cargo bench --bench normal -- --gaussian      # section B only (512², 1024²; or --sizes)
//!     cargo bench --bench normal -- --warm-start    # section D: warm against nested start (1024²)
//!     ASPERITY_BENCH_METHOD=preconditioned cargo bench --bench normal -- --gaussian   # method forced
//!     cargo bench --bench normal -- --resolution    # R: grid-refinement study of the resolution
//!     cargo bench --bench normal -- --size 4096     # one 4096² solve (run under /usr/bin/time -v)
//!     cargo bench --bench normal -- --reference     # reference sweep (1024²) and kn ∝ p^β
//!     cargo bench --bench normal -- --plastic       # P: hardness-limited solve (1024²; or --sizes)
//!
//! A. Self-affine surfaces (H = 0.8, rms gradient 0.1, periodic, roll-off L/4, cut-off 16 grid
//!    spacings; `SelfAffineSpec::benchmark`, seed 1) on 512², 1024², 2048² at p̄/(E*h'rms) =
//!    0.005, 0.05, 0.21, 0.53 (about 1, 10, 40 and 76 % contact), E* = 1e11 Pa on 1 mm.
//! B. The reference Gaussian surface (Rq 0.177 µm, cl 6.6 µm, 250 µm, seed 1, mean removed),
//!    steel on steel, the reference sweep 0.1–10 MPa, on 512² and 1024² (`--gaussian --sizes`:
//!    on the grids given, the same 250 µm patch).
//! C. Warm-started sweeps and kn: the six reference pressures and the four self-affine loads on
//!    1024², cold solves against a warm-started sweep; kn from the tangent problem against two
//!    warm-started solves of a central difference.
//!
//! P. Hardness-limited (elastic–perfectly plastic) contact on the self-affine surface of A
//!    (seed 1), H = 0.3·E*·h'rms = 3 GPa (the ratio H/E* of steel, 0.029, at h'rms = 0.1), at
//!    p̄/H = 0.01, 0.1, 0.3, 0.45 (1–55 % contact): the plastic solve against the elastic solve
//!    of the same surface and load (cold, 1 thread, CPU time), the unloading and loading
//!    stiffnesses, and tamaas 2.9's `KatoSaturated` (`benches/peers/tamaas_saturated.py`, one
//!    thread, tolerance 1e-10): contact and plastic sets point for point, load, CPU-time ratio.
//!    tamaas's saturated solver needs about 6 000 iterations at 256² and 12 500 at 512² (30 s and
//!    4 min of CPU per load): with tamaas installed, `--plastic --sizes 256,512` answers in about
//!    20 minutes, the default 1024² in over an hour.
//!
//! Every asperity solve of A and B is cold (uniform pressure, or the nested coarse-to-fine start
//! of the preconditioned method) with the default method choice (`auto`), timed on rayon pools
//! of 1 and 2 threads; Polonsky–Keer (the former method) runs on 1 thread for reference. tamaas
//! runs its PolonskyKeerRey solver with OMP_NUM_THREADS=1 (and =2 on 512² to show that its wheel
//! does not use the second thread). Same surface (.npy), E*, grid and tolerance (1e-10) in both
//! codes. Single-thread ratios use CPU time (asperity: its rayon worker thread's
//! `CLOCK_THREAD_CPUTIME_ID`; tamaas: time.process_time), two-thread ratios wall time. Time per
//! iteration is given in units of one convolution (one forward and one inverse real transform
//! of the grid: `FftPlan::convolve_into`, 1 thread, CPU time) and includes the coarse levels.
//! Units: SI.

use asperity::contact::normal::{
    NormalMethod, NormalOptions, NormalProblem, NormalSolution, NormalSolver,
};
use asperity::contact::resolution::ContactResolution;
use asperity::contact::sweep::{self, stiffness_central_difference};
use asperity::core::fft::{Boundary, FftPlan};
use asperity::core::material::{composite_modulus, Material};
use asperity::halfspace::influence::boussinesq_spectrum;
use asperity::surface::generate::{generate, GaussianSurfaceSpec};
use asperity::surface::self_affine::{generate_self_affine, SelfAffineSpec};
use asperity::Grid2;
use std::path::{Path, PathBuf};
use std::time::Instant;

const TOLERANCE: f64 = NormalOptions::DEFAULT_TOLERANCE;
/// p̄ / (E* h'rms) of the self-affine cases (about 1, 10, 40, 76 % contact).
const SELF_AFFINE_LOADS: [f64; 4] = [0.005, 0.05, 0.21, 0.53];
const SELF_AFFINE_E_STAR: f64 = 1e11;
const SELF_AFFINE_SIDE_M: f64 = 1e-3;

fn repeats(n: usize) -> usize {
    match n {
        0..=512 => 3,
        513..=1024 => 2,
        _ => 1,
    }
}

fn venv_python() -> Option<PathBuf> {
    let dir = std::env::var("ASPERITY_PEERS_VENV").unwrap_or("/tmp/asperity-peers-venv".into());
    let py = Path::new(&dir).join("bin/python");
    py.exists().then_some(py)
}

fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|_| "?".into())
}

/// CPU time of the calling thread (s; `CLOCK_THREAD_CPUTIME_ID`, exact to the nanosecond
/// where /proc/thread-self/schedstat moves in scheduler ticks of several ms). With a one-thread
/// rayon pool every solve runs on that pool's thread, so this is the solve's CPU time, robust
/// to other processes sharing the machine.
fn thread_cpu_s() -> f64 {
    cpu_time::ThreadTime::now().as_duration().as_secs_f64()
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
}

fn gaussian_reference(n: usize) -> Grid2 {
    let spec = GaussianSurfaceSpec {
        nx: n,
        ny: n,
        ..GaussianSurfaceSpec::reference()
    };
    let mut g = generate(&spec).expect("reference surface");
    let mean = g.heights.mean().unwrap();
    g.heights.mapv_inplace(|h| h - mean);
    g
}

fn steel() -> f64 {
    composite_modulus(Material::STEEL, Material::STEEL).unwrap()
}

fn self_affine(n: usize) -> Grid2 {
    generate_self_affine(&SelfAffineSpec::benchmark(n, SELF_AFFINE_SIDE_M, 1)).unwrap()
}

/// CPU time of one periodic convolution of the grid on one thread (s): best of 5 batches.
fn convolution_cpu_s(s: &Grid2, e_star: f64) -> f64 {
    pool(1).install(|| {
        let (nx, ny) = s.heights.dim();
        let plan = FftPlan::new(nx, ny, Boundary::Periodic);
        let kernel = boussinesq_spectrum(&plan, s.dx, s.dy, e_star);
        let mut ws = plan.workspace();
        let mut out = ndarray::Array2::zeros((nx, ny));
        let batch = (4_194_304 / (nx * ny)).clamp(2, 50);
        let mut best = f64::INFINITY;
        for _ in 0..5 {
            let c0 = thread_cpu_s();
            for _ in 0..batch {
                plan.convolve_into(&kernel, &s.heights, &mut out, &mut ws);
            }
            best = best.min((thread_cpu_s() - c0) / batch as f64);
        }
        best
    })
}

#[derive(Clone)]
struct Ours {
    area: f64,
    mean_gap: f64,
    method: NormalMethod,
    iterations: usize,
    coarse_iterations: usize,
    transforms: usize,
    time_s: f64,
    cpu_s: f64,
}

/// The method of the compared asperity solves: `auto` unless `ASPERITY_BENCH_METHOD` is
/// `preconditioned` or `polonsky-keer` (to measure the choice `auto` makes).
fn method_choice() -> NormalMethod {
    match std::env::var("ASPERITY_BENCH_METHOD").as_deref() {
        Ok("preconditioned") => NormalMethod::Preconditioned,
        Ok("polonsky-keer") => NormalMethod::PolonskyKeer,
        _ => NormalMethod::Auto,
    }
}

fn solver(s: &Grid2, e_star: f64, method: NormalMethod) -> NormalSolver {
    NormalSolver::new(
        &NormalProblem {
            surface: s,
            e_star_pa: e_star,
            hardness_pa: None,
        },
        NormalOptions {
            tolerance: TOLERANCE,
            method,
            ..NormalOptions::default()
        },
    )
    .unwrap()
}

fn ours_of(sol: &NormalSolution, time_s: f64, cpu_s: f64) -> Ours {
    Ours {
        area: sol.contact_area_ratio,
        mean_gap: sol.mean_gap_m,
        method: sol.method,
        iterations: sol.iterations,
        coarse_iterations: sol.coarse_iterations,
        transforms: sol.convolutions + sol.preconditioner_applications,
        time_s,
        cpu_s,
    }
}

/// Cold solves at each pressure, best of `repeats(n)`, on a pool of `threads`.
fn run_ours(
    s: &Grid2,
    e_star: f64,
    pressures: &[f64],
    threads: usize,
    method: NormalMethod,
    reps: usize,
) -> Vec<Ours> {
    pool(threads).install(|| {
        let mut solver = solver(s, e_star, method);
        pressures
            .iter()
            .map(|&p| {
                let (mut best, mut best_cpu, mut last) = (f64::INFINITY, f64::INFINITY, None);
                for _ in 0..reps {
                    let c0 = thread_cpu_s();
                    let t0 = Instant::now();
                    let sol = solver.solve_load(p, None).unwrap();
                    best = best.min(t0.elapsed().as_secs_f64());
                    best_cpu = best_cpu.min(thread_cpu_s() - c0);
                    last = Some(sol);
                }
                ours_of(&last.unwrap(), best, best_cpu)
            })
            .collect()
    })
}

struct Peer {
    area: f64,
    mean_gap: f64,
    iterations: Option<u64>,
    time_s: f64,
    cpu_s: f64,
}

fn run_tamaas(
    py: &Path,
    s: &Grid2,
    e_star: f64,
    pressures: &[f64],
    threads: usize,
    reps: usize,
    dir: &Path,
) -> Option<Vec<Peer>> {
    let npy = dir.join(format!(
        "surface_{}_{:x}.npy",
        s.nx(),
        s.heights.sum().to_bits()
    ));
    if !npy.exists() {
        ndarray_npy::write_npy(&npy, &s.heights).unwrap();
    }
    let case = serde_json::json!({
        "surface_npy": npy,
        "lx_m": s.lx(),
        "ly_m": s.ly(),
        "e_star_pa": e_star,
        "tolerance": TOLERANCE,
        "pressures_pa": pressures,
        "repeats": reps,
    });
    let case_path = dir.join("case.json");
    let out_path = dir.join("tamaas.json");
    std::fs::write(&case_path, case.to_string()).unwrap();
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/peers/tamaas_compare.py");
    let status = std::process::Command::new(py)
        .arg(script)
        .arg(&case_path)
        .arg(&out_path)
        .env("OMP_NUM_THREADS", threads.to_string())
        .status()
        .ok()?;
    if !status.success() {
        eprintln!("tamaas run failed ({status})");
        return None;
    }
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out_path).ok()?).ok()?;
    Some(
        v["results"]
            .as_array()?
            .iter()
            .map(|r| Peer {
                area: r["contact_area_ratio"].as_f64().unwrap(),
                mean_gap: r["mean_gap_m"].as_f64().unwrap(),
                iterations: r["iterations"].as_u64(),
                time_s: r["time_s"].as_f64().unwrap(),
                cpu_s: r["cpu_s"].as_f64().unwrap(),
            })
            .collect(),
    )
}

fn method_tag(o: &Ours) -> &'static str {
    match o.method {
        NormalMethod::Preconditioned => "P",
        NormalMethod::PolonskyKeer => "PK",
        NormalMethod::Auto => "?",
    }
}

/// One surface against tamaas at `pressures`; prints the accuracy/iteration table and the time
/// table (markdown). `label(p)` names the load in the first column.
fn compare(
    name: &str,
    s: &Grid2,
    e_star: f64,
    pressures: &[f64],
    label: &dyn Fn(f64) -> String,
    tamaas_two_threads: bool,
    dir: &Path,
) {
    let n = s.nx();
    let reps = repeats(n);
    let py = venv_python();
    let conv = convolution_cpu_s(s, e_star);
    eprintln!(
        "{name} {n}²: convolution {:.2} ms CPU; load {}",
        conv * 1e3,
        load_average()
    );
    let method = method_choice();
    let one = run_ours(s, e_star, pressures, 1, method, reps);
    let two = run_ours(s, e_star, pressures, 2, method, reps);
    let pk = run_ours(s, e_star, pressures, 1, NormalMethod::PolonskyKeer, 1);
    let peer = py
        .as_ref()
        .and_then(|py| run_tamaas(py, s, e_star, pressures, 1, reps.min(2), dir));
    let peer2 = if tamaas_two_threads {
        py.as_ref()
            .and_then(|py| run_tamaas(py, s, e_star, pressures, 2, 1, dir))
    } else {
        None
    };
    println!(
        "\n#### {name}, {n}² (one convolution = {:.2} ms CPU; load average {})\n",
        conv * 1e3,
        load_average()
    );
    println!("| load | contact | Δ area vs tamaas | Δ mean gap vs tamaas | iterations asperity (method, +coarse) | Polonsky–Keer | tamaas | transforms / iteration | time / iteration (convolutions) | asperity CPU 1 thr (s) | Polonsky–Keer CPU 1 thr (s) | tamaas CPU (s) | ratio 1 thread (CPU) | asperity wall 2 thr (s) | tamaas wall (s) | ratio 2 cores (wall) |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for (k, &p) in pressures.iter().enumerate() {
        let (o, o2, r) = (&one[k], &two[k], &pk[k]);
        let (da, dg, tit, tcpu, twall, r1, r2) = match &peer {
            Some(t) => {
                let t = &t[k];
                (
                    format!("{:+.1e}", o.area / t.area - 1.0),
                    format!("{:+.1e}", o.mean_gap / t.mean_gap - 1.0),
                    t.iterations.map_or("-".into(), |i| i.to_string()),
                    format!("{:.3}", t.cpu_s),
                    format!("{:.3}", t.time_s),
                    format!("{:.1}×", t.cpu_s / o.cpu_s),
                    format!("{:.1}×", t.time_s / o2.time_s),
                )
            }
            None => Default::default(),
        };
        println!(
            "| {} | {:.4} | {da} | {dg} | {} ({}, +{}) | {} | {tit} | {:.2} | {:.2} | {:.3} | {:.3} | {tcpu} | {r1} | {:.3} | {twall} | {r2} |",
            label(p),
            o.area,
            o.iterations,
            method_tag(o),
            o.coarse_iterations,
            r.iterations,
            o.transforms as f64 / o.iterations.max(1) as f64,
            o.cpu_s / conv / o.iterations.max(1) as f64,
            o.cpu_s,
            r.cpu_s,
            o2.time_s,
        );
        // Same solution as Polonsky–Keer.
        assert!(
            (o.mean_gap / r.mean_gap - 1.0).abs() < 1e-9,
            "{name} {n}² {}: mean gap {} vs Polonsky–Keer {}",
            label(p),
            o.mean_gap,
            r.mean_gap
        );
    }
    if let (Some(t1), Some(t2)) = (&peer, &peer2) {
        let (c1, c2, w2): (f64, f64, f64) = t1.iter().zip(t2).fold((0.0, 0.0, 0.0), |a, (x, y)| {
            (a.0 + x.cpu_s, a.1 + y.cpu_s, a.2 + y.time_s)
        });
        println!(
            "\ntamaas with OMP_NUM_THREADS=2 on these loads: CPU {c2:.3} s, wall {w2:.3} s (OMP_NUM_THREADS=1: CPU {c1:.3} s): its solver runs on one thread."
        );
    }
}

/// C. Cold solves against a warm-started sweep, and kn: tangent problem against the central
/// difference of two warm-started solves (1 thread, CPU time).
fn warm_and_stiffness(name: &str, s: &Grid2, e_star: f64, pressures: &[f64]) {
    pool(1).install(|| {
        let mut solver = solver(s, e_star, NormalMethod::Auto);
        let (mut cold_cpu, mut cold_it) = (0.0, 0usize);
        for &p in pressures {
            let c0 = thread_cpu_s();
            let sol = solver.solve_load(p, None).unwrap();
            cold_cpu += thread_cpu_s() - c0;
            cold_it += sol.iterations;
        }
        let (mut warm_cpu, mut warm_it) = (0.0, 0usize);
        let (mut kn_cpu, mut cd_cpu, mut max_dev) = (0.0, 0.0, 0.0f64);
        let mut warm: Option<NormalSolution> = None;
        for &p in pressures {
            let c0 = thread_cpu_s();
            let sol = solver.solve_load(p, warm.as_ref()).unwrap();
            warm_cpu += thread_cpu_s() - c0;
            warm_it += sol.iterations;
            let c0 = thread_cpu_s();
            let kn = solver.contact_stiffness(&sol).unwrap().kn_n_per_m3;
            kn_cpu += thread_cpu_s() - c0;
            let c0 = thread_cpu_s();
            let eps = 0.02;
            let lo = solver.solve_load(p * (1.0 - eps), Some(&sol)).unwrap();
            let hi = solver.solve_load(p * (1.0 + eps), Some(&sol)).unwrap();
            cd_cpu += thread_cpu_s() - c0;
            let kd = stiffness_central_difference(p, eps, -lo.approach_m, -hi.approach_m);
            max_dev = max_dev.max((kn / kd - 1.0).abs());
            warm = Some(sol);
        }
        println!(
            "| {name} | {} | {cold_it} | {cold_cpu:.2} | {warm_it} | {warm_cpu:.2} | {:.2}× | {kn_cpu:.2} | {cd_cpu:.2} | {:.1}× | {:.1e} |",
            pressures.len(),
            cold_cpu / warm_cpu,
            cd_cpu / kn_cpu,
            max_dev
        );
    });
}

/// Section D: where a warm start beats the nested coarse-to-fine start. For each base load the
/// solution at that load warm-starts the solves at `ratio × base` (a solver whose
/// `warm_start_load_ratio` is infinite, so that it always takes the warm start), against the
/// nested start (no warm start) at the same loads; 1 thread, CPU time.
fn warm_start_study(n: usize) {
    const RATIOS: [f64; 7] = [0.5, 0.8, 0.98, 1.02, 1.1, 1.25, 2.0];
    println!(
        "\n### D. Warm start against the nested start ({n}², 1 thread, CPU time; load average {})\n",
        load_average()
    );
    println!(
        "Fine iterations and CPU time (s) of the solve at ratio × base load: nested start \
         (iterations +coarse), and warm-started from the solution at the base load."
    );
    println!("\n| surface | base load | ratio | nested: iterations (+coarse) | nested CPU (s) | warm: iterations | warm CPU (s) | warm / nested time |");
    println!("|---|---|---|---|---|---|---|---|");
    // (surface name, surface, E* (Pa), base loads (label, p̄ in Pa)).
    type Case = (&'static str, Grid2, f64, Vec<(String, f64)>);
    let cases: [Case; 2] = [
        (
            "reference Gaussian",
            gaussian_reference(n),
            steel(),
            vec![("0.2 MPa".into(), 2e5), ("2 MPa".into(), 2e6)],
        ),
        (
            "self-affine",
            self_affine(n),
            SELF_AFFINE_E_STAR,
            [0.005, 0.05, 0.21]
                .iter()
                .map(|l| (format!("p̄/E*h' = {l}"), l * SELF_AFFINE_E_STAR * 0.1))
                .collect(),
        ),
    ];
    pool(1).install(|| {
        for (name, s, e_star, loads) in &cases {
            let mut solver = solver(s, *e_star, NormalMethod::Auto);
            let mut always_warm = NormalSolver::new(
                &NormalProblem {
                    surface: s,
                    e_star_pa: *e_star,
                    hardness_pa: None,
                },
                NormalOptions {
                    tolerance: TOLERANCE,
                    warm_start_load_ratio: f64::INFINITY,
                    ..NormalOptions::default()
                },
            )
            .unwrap();
            for (label, p) in loads {
                let base = solver.solve_load(*p, None).unwrap();
                for r in RATIOS {
                    let c0 = thread_cpu_s();
                    let nested = solver.solve_load(p * r, None).unwrap();
                    let t_nested = thread_cpu_s() - c0;
                    let c0 = thread_cpu_s();
                    let warm = always_warm.solve_load(p * r, Some(&base)).unwrap();
                    let t_warm = thread_cpu_s() - c0;
                    println!(
                        "| {name} | {label} | {r} | {} (+{}) | {t_nested:.3} | {} | {t_warm:.3} | {:.2} |",
                        nested.iterations,
                        nested.coarse_iterations,
                        warm.iterations,
                        t_warm / t_nested
                    );
                }
            }
        }
    });
}

/// Section B: the reference Gaussian surface's sweep on the given sizes (those up to 1024² in a
/// full run, any with `--gaussian --sizes`).
fn gaussian_section(sizes: &[usize], dir: &Path) {
    println!("\n### B. Reference Gaussian surface, reference sweep 0.1–10 MPa (steel/steel)");
    for &n in sizes {
        compare(
            "reference Gaussian",
            &gaussian_reference(n),
            steel(),
            &sweep::REFERENCE_PRESSURES_PA,
            &|p| format!("{} MPa", p / 1e6),
            false,
            dir,
        );
    }
}

fn run_all(sizes: &[usize]) {
    let dir = tempfile::tempdir().unwrap();
    if venv_python().is_none() {
        eprintln!("tamaas venv not found: run benches/peers/setup.sh (asperity only)");
    }
    println!(
        "load average at start: {}; rayon pools of 1 and 2 threads; tolerance {TOLERANCE:e}",
        load_average()
    );
    println!("\n### A. Self-affine surfaces (H 0.8, rms gradient 0.1, periodic, seed 1)");
    for &n in sizes {
        let s = self_affine(n);
        let pressures: Vec<f64> = SELF_AFFINE_LOADS
            .iter()
            .map(|l| l * SELF_AFFINE_E_STAR * 0.1)
            .collect();
        compare(
            "self-affine",
            &s,
            SELF_AFFINE_E_STAR,
            &pressures,
            &|p| format!("p̄/E*h' = {}", p / (SELF_AFFINE_E_STAR * 0.1)),
            n == 512,
            dir.path(),
        );
    }
    // Sections B and C run on the grids up to 1024² (C on the largest of them).
    let small: Vec<usize> = sizes.iter().copied().filter(|&n| n <= 1024).collect();
    gaussian_section(&small, dir.path());
    let n = small.iter().copied().max().unwrap_or(512);
    println!("\n### C. Warm-started sweeps and kn ({n}², 1 thread, CPU time)\n");
    println!("| surface | loads | iterations cold | CPU cold (s) | iterations warm | CPU warm (s) | warm speed-up | kn tangent CPU (s) | kn central difference CPU (s) | kn speed-up | max |kn/kn_cd − 1| |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    warm_and_stiffness(
        "reference Gaussian",
        &gaussian_reference(n),
        steel(),
        &sweep::REFERENCE_PRESSURES_PA,
    );
    let pressures: Vec<f64> = SELF_AFFINE_LOADS
        .iter()
        .map(|l| l * SELF_AFFINE_E_STAR * 0.1)
        .collect();
    warm_and_stiffness(
        "self-affine",
        &self_affine(n),
        SELF_AFFINE_E_STAR,
        &pressures,
    );
    println!("\nload average at end: {}", load_average());
}

/// R. Grid-refinement study of the resolution criterion: self-affine surfaces generated on 512²
/// with the cut-off at L/32, sampled on 256² … 32²; area ratio, free area and kn against 512².
fn resolution_study() {
    let e_star = SELF_AFFINE_E_STAR;
    println!("| seed | p̄/E*h' | grid | contact | points across contact | points across free | min | median spot | Δ contact area | Δ free area | Δ kn | resolved |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|");
    for seed in 1..=3 {
        let spec = SelfAffineSpec {
            cutoff_wavelength_m: SELF_AFFINE_SIDE_M / 32.0,
            ..SelfAffineSpec::benchmark(512, SELF_AFFINE_SIDE_M, seed)
        };
        let fine = generate_self_affine(&spec).unwrap();
        for load in [0.002, 0.005, 0.05, 0.25, 0.5, 0.8] {
            let mut reference: Option<(f64, f64)> = None;
            for k in [1, 2, 4, 8, 16] {
                let n = 512 / k;
                let h =
                    ndarray::Array2::from_shape_fn((n, n), |(i, j)| fine.heights[[i * k, j * k]]);
                let s = Grid2::new(h, fine.dx * k as f64, fine.dy * k as f64, true).unwrap();
                let mut solver = solver(&s, e_star, NormalMethod::Auto);
                let sol = solver.solve_load(load * e_star * 0.1, None).unwrap();
                let kn = solver.contact_stiffness(&sol).unwrap().kn_n_per_m3;
                let r: ContactResolution = sol.resolution;
                let (a0, k0) = *reference.get_or_insert((sol.contact_area_ratio, kn));
                println!(
                    "| {seed} | {load} | {n}² | {:.4} | {:.2} | {:.2} | {:.2} | {} | {:+.1}% | {:+.1}% | {:+.1}% | {} |",
                    sol.contact_area_ratio,
                    r.points_across_contact(),
                    r.points_across_free(),
                    r.points_across(),
                    sol.median_spot_points,
                    100.0 * (sol.contact_area_ratio / a0 - 1.0),
                    100.0 * ((1.0 - sol.contact_area_ratio) / (1.0 - a0) - 1.0),
                    100.0 * (kn / k0 - 1.0),
                    if r.resolved() { "yes" } else { "no" }
                );
            }
        }
    }
}

/// One solve on an n² reference surface (memory measurement under /usr/bin/time -v).
fn single(n: usize) {
    let t0 = Instant::now();
    let s = gaussian_reference(n);
    let mut solver = solver(&s, steel(), NormalMethod::Auto);
    let sol = solver.solve_load(2e6, None).unwrap();
    println!(
        "{n}²: p̄ = 2 MPa, area ratio {:.5}, mean gap {:.5} µm, {} iterations ({:?}), solve {:.2} s, total {:.2} s, {} threads",
        sol.contact_area_ratio,
        sol.mean_gap_m * 1e6,
        sol.iterations,
        sol.method,
        sol.wall_time_s,
        t0.elapsed().as_secs_f64(),
        rayon::current_num_threads()
    );
}

/// The reference sweep (1024²) and the power-law exponent of kn.
fn reference() {
    let s = gaussian_reference(1024);
    let mut solver = solver(&s, steel(), NormalMethod::Auto);
    let t0 = Instant::now();
    let sw = sweep::run(
        &mut solver,
        &sweep::REFERENCE_PRESSURES_PA,
        sweep::SweepOptions::default(),
        |_| {},
    )
    .unwrap();
    println!("| p̄ (MPa) | area ratio | mean gap (µm) | kn (N/m³) | spots | points across contact | points across free | method | iterations |");
    println!("|---|---|---|---|---|---|---|---|---|");
    for p in &sw.points {
        println!(
            "| {} | {:.5} | {:.5} | {:.4e} | {} | {:.1} | {:.1} | {} | {} |",
            p.pressure_pa / 1e6,
            p.contact_area_ratio,
            p.mean_gap_m * 1e6,
            p.kn_n_per_m3,
            p.contact_spots,
            p.resolution.points_across_contact(),
            p.resolution.points_across_free(),
            p.method.name(),
            p.iterations
        );
    }
    let (beta, c) = sweep::power_law_fit(&sw.points).unwrap();
    println!(
        "\nkn ∝ p^β over 0.1–10 MPa: β = {beta:.4} (C = {c:.4e}); sweep {:.1} s on {} threads",
        t0.elapsed().as_secs_f64(),
        rayon::current_num_threads()
    );
}

/// The grid sizes of `--sizes N,N,…`, if given.
fn sizes_arg(args: &[String]) -> Option<Vec<usize>> {
    let i = args.iter().position(|a| a == "--sizes")?;
    Some(
        args.get(i + 1)
            .expect("--sizes N,N,…")
            .split(',')
            .map(|v| v.parse().expect("--sizes: grid sizes such as 512,1024"))
            .collect(),
    )
}

/// p̄/H of section P.
const PLASTIC_LOADS: [f64; 4] = [0.01, 0.1, 0.3, 0.45];

/// Section P: the hardness-limited solve against the elastic one and against tamaas'
/// `KatoSaturated` (see the module documentation).
fn plastic_section(n: usize, dir: &Path) {
    let s = self_affine(n);
    let e_star = SELF_AFFINE_E_STAR;
    let hardness = 0.3 * e_star * 0.1;
    let pressures: Vec<f64> = PLASTIC_LOADS.iter().map(|r| r * hardness).collect();
    let reps = repeats(n);
    let make = |h: Option<f64>| {
        NormalSolver::new(
            &NormalProblem {
                surface: &s,
                e_star_pa: e_star,
                hardness_pa: h,
            },
            NormalOptions {
                tolerance: TOLERANCE,
                ..NormalOptions::default()
            },
        )
        .unwrap()
    };
    // (solution, best CPU time) of cold solves on one thread.
    let timed = |solver: &mut NormalSolver, p: f64| {
        let mut best = f64::INFINITY;
        let mut last = None;
        for _ in 0..reps {
            let c0 = thread_cpu_s();
            let sol = solver.solve_load(p, None).unwrap();
            best = best.min(thread_cpu_s() - c0);
            last = Some(sol);
        }
        (last.unwrap(), best)
    };
    let load0 = load_average();
    let (elastic, plastic): (Vec<_>, Vec<_>) = pool(1).install(|| {
        let mut el = make(None);
        let mut pl = make(Some(hardness));
        pressures
            .iter()
            .map(|&p| {
                let e = timed(&mut el, p);
                let q = timed(&mut pl, p);
                let c0 = thread_cpu_s();
                let ku = pl.contact_stiffness(&q.0).unwrap();
                let kl = pl.loading_stiffness(&q.0).unwrap();
                let kcpu = thread_cpu_s() - c0;
                (e, (q, ku, kl, kcpu))
            })
            .unzip()
    });
    let peer = venv_python().and_then(|py| {
        let npy = dir.join(format!("plastic_surface_{n}.npy"));
        ndarray_npy::write_npy(&npy, &s.heights).unwrap();
        let case = serde_json::json!({
            "surface_npy": npy,
            "lx_m": s.lx(),
            "ly_m": s.ly(),
            "e_star_pa": e_star,
            "hardness_pa": hardness,
            "tolerance": TOLERANCE,
            "pressures_pa": pressures,
            "repeats": 1,
            "write_fields": true,
        });
        let case_path = dir.join("plastic_case.json");
        let out_path = dir.join("plastic_tamaas.json");
        std::fs::write(&case_path, case.to_string()).unwrap();
        let script =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/peers/tamaas_saturated.py");
        let status = std::process::Command::new(py)
            .arg(script)
            .arg(&case_path)
            .arg(&out_path)
            .env("OMP_NUM_THREADS", "1")
            .status()
            .ok()?;
        if !status.success() {
            eprintln!("tamaas run failed ({status})");
            return None;
        }
        serde_json::from_str::<serde_json::Value>(&std::fs::read_to_string(&out_path).ok()?).ok()
    });
    println!(
        "\n#### P. Hardness-limited contact, self-affine seed 1, {n}², H = {hardness:e} Pa (load average {load0} → {}){}\n",
        load_average(),
        peer.as_ref()
            .map(|v| format!(", tamaas {} {}", v["tamaas_version"], v["solver"]))
            .unwrap_or_else(|| ", no tamaas (run benches/peers/setup.sh)".into())
    );
    println!("| p̄/H | contact | plastic | iterations elastic / plastic (+coarse) | CPU elastic (s) | CPU plastic (s) | plastic / elastic | kn unloading (N/m³) | kn loading (N/m³) | kn CPU (s) | tamaas iterations | tamaas CPU (s) | tamaas / plastic | contact set diff | plastic set diff | load diff |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for (k, &ratio) in PLASTIC_LOADS.iter().enumerate() {
        let (e, ecpu) = &elastic[k];
        let ((q, pcpu), ku, kl, kcpu) = &plastic[k];
        let peer_cells = match &peer {
            Some(v) => {
                let r = &v["results"][k];
                let field: ndarray::Array2<f64> =
                    ndarray_npy::read_npy(r["pressure_npy"].as_str().unwrap()).unwrap();
                let diff = |f: &dyn Fn(f64) -> bool| {
                    q.pressure
                        .iter()
                        .zip(field.iter())
                        .filter(|(a, b)| f(**a) != f(**b))
                        .count()
                };
                let tcpu = r["cpu_s"].as_f64().unwrap();
                format!(
                    "{} | {tcpu:.2} | **{:.1}×** | {} | {} | {:.1e}",
                    r["iterations"],
                    tcpu / pcpu,
                    diff(&|p| p > 0.0),
                    diff(&|p| p >= hardness),
                    (q.pressure.mean().unwrap() - field.mean().unwrap()).abs() / pressures[k]
                )
            }
            None => "– | – | – | – | – | –".into(),
        };
        println!(
            "| {ratio} | {:.4} | {:.4} | {} / {} (+{}) | {ecpu:.3} | {pcpu:.3} | **{:.2}** | {:.4e} | {:.4e} | {kcpu:.3} | {peer_cells} |",
            q.contact_area_ratio,
            q.plastic_area_ratio,
            e.iterations,
            q.iterations,
            q.coarse_iterations,
            pcpu / ecpu,
            ku.kn_n_per_m3,
            kl.kn_n_per_m3,
        );
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if let Some(i) = args.iter().position(|a| a == "--size") {
        let n = args[i + 1].parse().expect("--size N");
        single(n);
    } else if args.iter().any(|a| a == "--reference") {
        reference();
    } else if args.iter().any(|a| a == "--resolution") {
        resolution_study();
    } else if args.iter().any(|a| a == "--gaussian") {
        let dir = tempfile::tempdir().unwrap();
        println!(
            "load average at start: {}; rayon pools of 1 and 2 threads; tolerance {TOLERANCE:e}",
            load_average()
        );
        gaussian_section(&sizes_arg(&args).unwrap_or(vec![512, 1024]), dir.path());
        println!("\nload average at end: {}", load_average());
    } else if args.iter().any(|a| a == "--plastic") {
        let dir = tempfile::tempdir().unwrap();
        for n in sizes_arg(&args).unwrap_or(vec![1024]) {
            plastic_section(n, dir.path());
        }
    } else if args.iter().any(|a| a == "--warm-start") {
        warm_start_study(1024);
    } else if args.iter().any(|a| a == "--quick") {
        run_all(&[512]);
    } else if let Some(sizes) = sizes_arg(&args) {
        run_all(&sizes);
    } else {
        run_all(&[512, 1024, 2048]);
    }
}
