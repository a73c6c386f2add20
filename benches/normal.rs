//! Benchmark of the normal contact solver (Polonsky–Keer) against tamaas 2.9.
//!
//!     benches/peers/setup.sh                      # throwaway venv with tamaas (once)
//!     cargo bench --bench normal                  # comparison + timings, markdown tables
//!     cargo bench --bench normal -- --size 4096   # one 4096² solve (run under /usr/bin/time -v)
//!     cargo bench --bench normal -- --reference   # reference sweep and kn ∝ p^β fit
//!
//! Surfaces: the reference Gaussian surface (Rq 0.177 µm, cl 6.6 µm, 250 µm) generated at the
//! grid size of each case (same seed), exported to .npy for tamaas. Steel on steel
//! (E = 210 GPa, ν = 0.3 both bodies). Times are per cold solve (uniform initial pressure),
//! best of `REPEATS`, excluding the one-off FFT planning and kernel transform of both codes.
//! Threads: asperity runs in rayon pools of 1 and 2 threads; tamaas with OMP_NUM_THREADS=1, 2.
//! Units: SI.

use asperity::contact::normal::{NormalOptions, NormalProblem, NormalSolver};
use asperity::contact::sweep;
use asperity::surface::combine::{composite_modulus, Material};
use asperity::surface::generate::{generate, GaussianSurfaceSpec};
use asperity::Grid2;
use std::path::{Path, PathBuf};
use std::time::Instant;

const REPEATS: usize = 3;
const TOLERANCE: f64 = NormalOptions::DEFAULT_TOLERANCE;
const COMPARE_PRESSURES_PA: [f64; 3] = [0.2e6, 2e6, 10e6];

fn venv_python() -> Option<PathBuf> {
    let dir = std::env::var("ASPERITY_PEERS_VENV").unwrap_or("/tmp/asperity-peers-venv".into());
    let py = Path::new(&dir).join("bin/python");
    py.exists().then_some(py)
}

fn surface(n: usize) -> Grid2 {
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

fn e_star() -> f64 {
    composite_modulus(Material::STEEL, Material::STEEL).unwrap()
}

struct Ours {
    area: f64,
    mean_gap: f64,
    iterations: usize,
    time_s: f64,
    cpu_s: f64,
}

/// CPU time of the calling thread (s), from /proc/thread-self/schedstat (ns on CPU). With a
/// one-thread rayon pool every solve runs on that pool's thread, so this is the solve's CPU
/// time, robust to other processes sharing the machine.
fn thread_cpu_s() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<f64>().ok())
        .map_or(f64::NAN, |ns| ns * 1e-9)
}

fn run_ours(s: &Grid2, pressures: &[f64], threads: usize) -> Vec<Ours> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let mut solver = NormalSolver::new(
            &NormalProblem {
                surface: s,
                e_star_pa: e_star(),
            },
            NormalOptions {
                tolerance: TOLERANCE,
                ..NormalOptions::default()
            },
        )
        .unwrap();
        pressures
            .iter()
            .map(|&p| {
                let mut best = f64::INFINITY;
                let mut best_cpu = f64::INFINITY;
                let mut last = None;
                for _ in 0..REPEATS {
                    let c0 = thread_cpu_s();
                    let t0 = Instant::now();
                    let sol = solver.solve_load(p, None).unwrap();
                    best = best.min(t0.elapsed().as_secs_f64());
                    best_cpu = best_cpu.min(thread_cpu_s() - c0);
                    last = Some(sol);
                }
                let sol = last.unwrap();
                Ours {
                    area: sol.contact_area_ratio,
                    mean_gap: sol.mean_gap_m,
                    iterations: sol.iterations,
                    time_s: best,
                    cpu_s: best_cpu,
                }
            })
            .collect()
    })
}

struct Peer {
    area: f64,
    mean_gap: f64,
    time_s: f64,
    cpu_s: f64,
}

fn run_tamaas(
    py: &Path,
    s: &Grid2,
    pressures: &[f64],
    threads: usize,
    dir: &Path,
) -> Option<Vec<Peer>> {
    let npy = dir.join(format!("surface_{}.npy", s.nx()));
    if !npy.exists() {
        ndarray_npy::write_npy(&npy, &s.heights).unwrap();
    }
    let case = serde_json::json!({
        "surface_npy": npy,
        "lx_m": s.lx(),
        "ly_m": s.ly(),
        "e_star_pa": e_star(),
        "tolerance": TOLERANCE,
        "pressures_pa": pressures,
        "repeats": REPEATS,
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
                time_s: r["time_s"].as_f64().unwrap(),
                cpu_s: r["cpu_s"].as_f64().unwrap(),
            })
            .collect(),
    )
}

fn compare(sizes: &[usize]) {
    let py = venv_python();
    if py.is_none() {
        eprintln!("tamaas venv not found: run benches/peers/setup.sh (timings of asperity only)");
    }
    let dir = tempfile::tempdir().unwrap();
    println!(
        "E* = {:.6e} Pa (steel/steel), tolerance {TOLERANCE:e}, best of {REPEATS} cold solves\n",
        e_star()
    );
    println!("| grid | p̄ (MPa) | area ratio asperity | area ratio tamaas | Δ area | mean gap asperity (µm) | mean gap tamaas (µm) | Δ gap | iterations |");
    println!("|---|---|---|---|---|---|---|---|---|");
    let mut timing_rows = Vec::new();
    for &n in sizes {
        let s = surface(n);
        let mut per_thread = Vec::new();
        for threads in [1, 2] {
            let ours = run_ours(&s, &COMPARE_PRESSURES_PA, threads);
            let peer = py
                .as_ref()
                .and_then(|py| run_tamaas(py, &s, &COMPARE_PRESSURES_PA, threads, dir.path()));
            per_thread.push((threads, ours, peer));
        }
        let (_, ours, peer) = &per_thread[0];
        for (k, p) in COMPARE_PRESSURES_PA.iter().enumerate() {
            let o = &ours[k];
            let (ta, tg, da, dg) = match peer {
                Some(t) => (
                    format!("{:.5}", t[k].area),
                    format!("{:.6}", t[k].mean_gap * 1e6),
                    format!("{:+.3}%", 100.0 * (o.area / t[k].area - 1.0)),
                    format!("{:+.3}%", 100.0 * (o.mean_gap / t[k].mean_gap - 1.0)),
                ),
                None => ("-".into(), "-".into(), "-".into(), "-".into()),
            };
            println!(
                "| {n}² | {} | {:.5} | {ta} | {da} | {:.6} | {tg} | {dg} | {} |",
                p / 1e6,
                o.area,
                o.mean_gap * 1e6,
                o.iterations
            );
        }
        for (threads, ours, peer) in per_thread {
            for (k, p) in COMPARE_PRESSURES_PA.iter().enumerate() {
                timing_rows.push((
                    n,
                    threads,
                    *p,
                    (ours[k].time_s, ours[k].cpu_s),
                    peer.as_ref().map(|t| (t[k].time_s, t[k].cpu_s)),
                ));
            }
        }
    }
    println!("\nWall time (s) and, single-threaded, CPU time (s) per cold solve; speed-up = tamaas/asperity");
    println!("(CPU time for 1 thread, wall time for 2 threads).\n");
    println!("| grid | threads | p̄ (MPa) | asperity wall | asperity CPU | tamaas wall | tamaas CPU | speed-up |");
    println!("|---|---|---|---|---|---|---|---|");
    for (n, th, p, ours, peer) in timing_rows {
        let (tw, tc, r) = match peer {
            Some((w, c)) => (
                format!("{w:.3}"),
                format!("{c:.3}"),
                if th == 1 {
                    format!("{:.2}×", c / ours.1)
                } else {
                    format!("{:.2}×", w / ours.0)
                },
            ),
            None => ("-".into(), "-".into(), "-".into()),
        };
        let oc = if th == 1 {
            format!("{:.3}", ours.1)
        } else {
            "-".into()
        };
        println!(
            "| {n}² | {th} | {} | {:.3} | {oc} | {tw} | {tc} | {r} |",
            p / 1e6,
            ours.0
        );
    }
}

/// One solve on an n² reference surface (memory measurement under /usr/bin/time -v).
fn single(n: usize) {
    let t0 = Instant::now();
    let s = surface(n);
    let mut solver = NormalSolver::new(
        &NormalProblem {
            surface: &s,
            e_star_pa: e_star(),
        },
        NormalOptions::default(),
    )
    .unwrap();
    let sol = solver.solve_load(2e6, None).unwrap();
    println!(
        "{n}²: p̄ = 2 MPa, area ratio {:.5}, mean gap {:.5} µm, {} iterations, solve {:.2} s, total {:.2} s, {} threads",
        sol.contact_area_ratio,
        sol.mean_gap_m * 1e6,
        sol.iterations,
        sol.wall_time_s,
        t0.elapsed().as_secs_f64(),
        rayon::current_num_threads()
    );
}

/// The reference sweep (1024²) and the power-law exponent of kn.
fn reference() {
    let s = surface(1024);
    let mut solver = NormalSolver::new(
        &NormalProblem {
            surface: &s,
            e_star_pa: e_star(),
        },
        NormalOptions::default(),
    )
    .unwrap();
    let t0 = Instant::now();
    let sw = sweep::run(
        &mut solver,
        &sweep::REFERENCE_PRESSURES_PA,
        sweep::SweepOptions::default(),
        |_| {},
    )
    .unwrap();
    println!("| p̄ (MPa) | area ratio | mean gap (µm) | kn (N/m³) | spots | smallest spot (points) | median spot (points) |");
    println!("|---|---|---|---|---|---|---|");
    for p in &sw.points {
        println!(
            "| {} | {:.5} | {:.5} | {:.4e} | {} | {} | {} |",
            p.pressure_pa / 1e6,
            p.contact_area_ratio,
            p.mean_gap_m * 1e6,
            p.kn_n_per_m3,
            p.contact_spots,
            p.smallest_spot_points,
            p.median_spot_points
        );
    }
    let (beta, c) = sweep::power_law_fit(&sw.points).unwrap();
    println!(
        "\nkn ∝ p^β over 0.1–10 MPa: β = {beta:.4} (C = {c:.4e}); sweep {:.1} s on {} threads",
        t0.elapsed().as_secs_f64(),
        rayon::current_num_threads()
    );
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if let Some(i) = args.iter().position(|a| a == "--size") {
        let n = args[i + 1].parse().expect("--size N");
        single(n);
    } else if args.iter().any(|a| a == "--reference") {
        reference();
    } else if args.iter().any(|a| a == "--quick") {
        compare(&[256]);
    } else {
        compare(&[512, 1024]);
    }
}
