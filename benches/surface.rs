//! Benchmark: `surface generate` and `surface stats` on reference-like patches of 1024² and
//! 4096² points (Rq 0.177 µm, cl 6.6 µm, spacing 250 µm / 1024), and the same statistics with
//! SurfaceTopography when its throwaway virtualenv exists (benches/peers/setup_surfacetopography.sh).
//!
//! Run: `cargo bench --bench surface` (release build). Prints a Markdown table for BENCHMARKS.md.
//! Times are the best of several runs (wall clock); threads = rayon's pool size.

use asperity::surface::{self, Detrend, GaussianSurfaceSpec, Topography};
use std::path::Path;
use std::process::Command;
use std::time::Instant;

const PEER_PYTHON: &str = "/tmp/asperity-surface-peers-venv/bin/python";

fn best_of<T>(runs: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut best = f64::INFINITY;
    let mut out = None;
    for _ in 0..runs {
        let t0 = Instant::now();
        let v = f();
        best = best.min(t0.elapsed().as_secs_f64());
        out = Some(v);
    }
    (best, out.expect("at least one run"))
}

/// SurfaceTopography's time and values on the same file, or None when the venv is absent.
fn peer(npy: &Path) -> Option<serde_json::Value> {
    if !Path::new(PEER_PYTHON).exists() {
        return None;
    }
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/peers/surface_stats.py");
    let o = Command::new(PEER_PYTHON)
        .arg(script)
        .arg(npy)
        .output()
        .ok()?;
    if !o.status.success() {
        eprintln!("peer failed: {}", String::from_utf8_lossy(&o.stderr));
        return None;
    }
    serde_json::from_slice(&o.stdout).ok()
}

fn main() {
    let dir = tempfile::tempdir().expect("temp dir");
    let reference = GaussianSurfaceSpec::reference();
    let threads = rayon::current_num_threads();
    println!("| grid | generate (s) | stats + PSD (s) | SurfaceTopography stats + PSD (s) | ratio ST/asperity | Rq (m) | rms gradient asperity / ST |");
    println!("|---|---|---|---|---|---|---|");
    for (n, runs) in [(1024usize, 5usize), (4096, 2)] {
        let spec = GaussianSurfaceSpec {
            nx: n,
            ny: n,
            lx_m: reference.dx() * n as f64,
            ly_m: reference.dy() * n as f64,
            ..reference
        };
        let (t_gen, grid) = best_of(runs, || surface::generate(&spec).expect("generate"));
        let topo = Topography::Area(grid.clone());
        let (t_stats, st) = best_of(runs, || {
            let s = surface::stats(&topo, Detrend::Mean).expect("stats");
            let p = surface::stats::power_spectrum(&topo, Detrend::Mean).expect("psd");
            (s, p.q.len())
        });
        let npy = dir.path().join(format!("bench{n}.npy"));
        surface::io::write(&npy, &grid).expect("write npy");
        let (peer_t, ratio, peer_grad) = match peer(&npy) {
            Some(v) => {
                let t = v["stats_time_s"].as_f64().unwrap_or(f64::NAN);
                (
                    format!("{t:.3} (v{})", v["version"].as_str().unwrap_or("?")),
                    format!("{:.1}", t / t_stats),
                    format!("{:.10e}", v["rms_gradient"].as_f64().unwrap_or(f64::NAN)),
                )
            }
            None => ("not run".into(), "—".into(), "—".into()),
        };
        println!(
            "| {n}² | {t_gen:.3} | {t_stats:.3} | {peer_t} | {ratio} | {:.6e} | {:.10e} / {peer_grad} |",
            st.0.rq_m,
            st.0.rms_gradient.unwrap_or(f64::NAN),
        );
    }
    println!("\nthreads: {threads}");
}
