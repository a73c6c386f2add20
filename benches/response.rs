//! Benchmark: harmonic balance at underplatform-damper size.
//!
//!     cargo bench --bench response                 # full case: 4 levels × 200 points
//!     cargo bench --bench response -- --quick      # one level, ≥ 10 points
//!     cargo bench --bench response -- --peer-only  # the Jenkins SDOF against pyHarm only
//!     cargo bench --bench response -- --costs      # costs of one evaluation only
//!     cargo bench --bench response -- --skip-peers --levels 0.05,0.5  # chosen levels only
//!     cargo bench --bench response -- --stability  # cost of Hill's stability per point
//!
//! The pyHarm comparison runs when the venv of benches/peers/setup_pyharm.sh exists. It is at
//! equal work: pyHarm runs first, and asperity's `points` is scaled until its branch has
//! pyHarm's number of points (within 3 %); both are timed in-process (pyHarm's second
//! `operate()`, after its JIT compilation; asperity's sweep, best of 3), models built beforehand.
//!
//! Case: a synthetic reduced modal model of two blades and an underplatform damper (30 modes,
//! 0.6–8 kHz, 0.3 % modal damping; seeded, see `model()`), 146 Valanis microslip contact
//! elements (73 per damper–platform interface, 3 DOF each: 438 contact DOFs) with per-element
//! parameters of the reference calibration table at 2 MPa, harmonics 0..7 (15 coefficients,
//! 128 samples per period). Prints the cost of one AFT evaluation (all elements, residual only)
//! and of one Jacobian, the formulation used, and the sweep times. Units: SI, times in seconds.

use asperity::dynamics::aft::{self, Harmonics};
use asperity::dynamics::continuation::{sweep, ContinuationSettings};
use asperity::dynamics::hbm::{Excitation, FormulationChoice, HbmSystem};
use asperity::dynamics::model::Structure;
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use std::sync::Arc;
use std::time::Instant;

#[path = "../tests/support/upd_model.rs"]
mod upd_model;
use upd_model::{model, refined_peak, MODES};

/// A friction case shared with pyHarm: masses on ground springs and dashpots, optionally a
/// coupling spring and dashpot between masses 1 and 2, a Jenkins element (to ground from mass 1,
/// or between masses 1 and 2), force on mass 1.
struct PeerCase {
    name: &'static str,
    m: Vec<f64>,
    k: Vec<f64>,
    c: Vec<f64>,
    k12: f64,
    c12: f64,
    kt: f64,
    fs: f64,
    force: f64,
    f0: f64,
    f1: f64,
}

/// asperity and the peer on the same case in the same run.
fn peer(case: &PeerCase) {
    let (hmax, nt) = (7, 256);
    let n = case.m.len();
    let mut kk = DMatrix::from_diagonal(&DVector::from_vec(case.k.clone()));
    let mut cc = DMatrix::from_diagonal(&DVector::from_vec(case.c.clone()));
    let jmap = if n == 2 {
        for (mat, v) in [(&mut kk, case.k12), (&mut cc, case.c12)] {
            mat[(0, 0)] += v;
            mat[(1, 1)] += v;
            mat[(0, 1)] -= v;
            mat[(1, 0)] -= v;
        }
        DMatrix::from_row_slice(1, 2, &[1.0, -1.0])
    } else {
        DMatrix::from_element(1, 1, 1.0)
    };
    let mut st = Structure::lumped(
        (0..n).map(|i| format!("m{}.x", i + 1)).collect(),
        DMatrix::from_diagonal(&DVector::from_vec(case.m.clone())),
        cc,
        kk,
    )
    .unwrap();
    st.attach(
        "jenkins",
        Arc::new(asperity::element::Jenkins::new(case.kt, case.fs).unwrap()),
        jmap,
    )
    .unwrap();
    let h = Harmonics::new(hmax, false, Some(nt)).unwrap();
    let mut f = DVector::zeros(n);
    f[0] = 1.0;
    let sys = HbmSystem::new(
        &st,
        h,
        Excitation {
            force: f,
            harmonic: 1,
            force_sin: None,
        },
        FormulationChoice::Coordinates,
    )
    .unwrap();
    // pyHarm first (when its venv exists): its point count sets asperity's, so that both codes
    // are timed at equal work — the same number of converged points over the same span, both
    // in-process (pyHarm: its second `operate()`, after JIT compilation; asperity: the sweep,
    // best of 3), with the model built beforehand in both.
    let pyharm = run_pyharm(case, hmax, nt);
    let target_points = pyharm.as_ref().map(|p| p.frequencies.len());
    let mut settings = ContinuationSettings::new(case.f0, case.f1);
    settings.points = 100;
    let mut b = sweep(&sys, case.force, &settings, &mut |_| {}).unwrap();
    if let Some(target) = target_points {
        // The step control puts more points at the peak than `points`: scale `points` until
        // the branch has pyHarm's number of points (within 3 %, at most 6 tries).
        for _ in 0..6 {
            let got = b.points.len();
            if (got as f64 / target as f64 - 1.0).abs() <= 0.03 {
                break;
            }
            let next = ((settings.points as f64) * target as f64 / got as f64).round() as usize;
            settings.points = next.max(2);
            b = sweep(&sys, case.force, &settings, &mut |_| {}).unwrap();
        }
    }
    let mut best = f64::INFINITY;
    let mut best_cpu = f64::INFINITY;
    for _ in 0..3 {
        let c0 = cpu_time();
        let t = Instant::now();
        b = sweep(&sys, case.force, &settings, &mut |_| {}).unwrap();
        best = best.min(t.elapsed().as_secs_f64());
        best_cpu = best_cpu.min(cpu_time() - c0);
    }
    let (ci, si) = sys.harmonics.index_of(1).unwrap();
    let fr: Vec<f64> = b
        .points
        .iter()
        .map(|p| p.omega / (2.0 * std::f64::consts::PI))
        .collect();
    let am: Vec<f64> = b.points.iter().map(|p| p.z[ci].hypot(p.z[si])).collect();
    let (fpk, apk) = refined_peak(&fr, &am);
    println!(
        "## {} vs pyHarm (masses {:?} kg, ground springs {:?} N/m, dashpots {:?} N·s/m, coupling {} N/m / {} N·s/m, Jenkins kt {} N/m, slip force {} N, F {} N on mass 1, harmonics 0..7, 256 samples, {}–{} Hz)",
        case.name, case.m, case.k, case.c, case.k12, case.c12, case.kt, case.fs, case.force, case.f0, case.f1
    );
    println!("asperity: {} points (sweep.points = {}), peak {apk:.6e} m at {fpk:.4} Hz (mass 1); sweep wall {best:.4} s, CPU {best_cpu:.4} s (best of 3, in-process)", b.points.len(), settings.points);
    let Some(r) = pyharm else {
        println!("pyHarm venv not found (run benches/peers/setup_pyharm.sh) or pyHarm failed: peer skipped");
        return;
    };
    let (pfpk, papk) = refined_peak(&r.frequencies, &r.amplitudes);
    println!("pyHarm:   {} points, peak {papk:.6e} m at {pfpk:.4} Hz; analysis wall {:.4} s, CPU {:.4} s (second run, after JIT, in-process)", r.frequencies.len(), r.wall, r.cpu);
    let (np, na) = (r.frequencies.len() as f64, b.points.len() as f64);
    println!(
        "peak amplitude {:+.3} %, peak frequency {:+.3} %; points {} vs {}; time ratio pyHarm/asperity: wall {:.1}×, CPU {:.1}×; per point: wall {:.1}×, CPU {:.1}×\n",
        (apk / papk - 1.0) * 100.0,
        (fpk / pfpk - 1.0) * 100.0,
        r.frequencies.len(),
        b.points.len(),
        r.wall / best,
        r.cpu / best_cpu.max(1e-9),
        (r.wall / np) / (best / na),
        (r.cpu / np) / (best_cpu.max(1e-9) / na),
    );
}

/// pyHarm's branch and timings on a case.
struct PyHarmRun {
    frequencies: Vec<f64>,
    amplitudes: Vec<f64>,
    wall: f64,
    cpu: f64,
}

/// Run pyHarm on `case` (benches/peers/pyharm_jenkins.py in the venv of
/// benches/peers/setup_pyharm.sh); `None` when the venv is missing or the run fails.
fn run_pyharm(case: &PeerCase, hmax: usize, nt: usize) -> Option<PyHarmRun> {
    let python = std::path::Path::new("/tmp/asperity-pyharm-venv/bin/python");
    if !python.exists() {
        return None;
    }
    let dir = tempfile::tempdir().unwrap();
    let case_json = dir.path().join("case.json");
    let out = dir.path().join("out.json");
    std::fs::write(
        &case_json,
        serde_json::json!({"m_kg": case.m, "k_N_per_m": case.k, "c_N_s_per_m": case.c,
            "k12_N_per_m": case.k12, "c12_N_s_per_m": case.c12, "kt_N_per_m": case.kt,
            "slip_force_N": case.fs, "force_N": case.force, "f_start_Hz": case.f0,
            "f_end_Hz": case.f1, "h_max": hmax, "n_time": nt, "ds_max": 0.5})
        .to_string(),
    )
    .unwrap();
    let script =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/peers/pyharm_jenkins.py");
    let o = std::process::Command::new(python)
        .arg(&script)
        .arg(&case_json)
        .arg(&out)
        .output()
        .ok()?;
    if !o.status.success() {
        println!("pyHarm failed: {}", String::from_utf8_lossy(&o.stderr));
        return None;
    }
    let r: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&out).ok()?).ok()?;
    let column = |name: &str| -> Vec<f64> {
        r[name]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect()
    };
    Some(PyHarmRun {
        frequencies: column("frequency_Hz"),
        amplitudes: column("amplitude_m"),
        wall: r["wall_s"].as_f64()?,
        cpu: r["cpu_s"].as_f64()?,
    })
}

/// CPU time of this process (s; `CLOCK_PROCESS_CPUTIME_ID`: all its threads, rayon workers
/// included).
fn cpu_time() -> f64 {
    cpu_time::ProcessTime::now().as_duration().as_secs_f64()
}

/// Wall and CPU time (s) of one call of `f`, averaged over `reps` calls.
fn timed(reps: usize, mut f: impl FnMut()) -> (f64, f64) {
    let (c0, t0) = (cpu_time(), Instant::now());
    for _ in 0..reps {
        f();
    }
    (
        t0.elapsed().as_secs_f64() / reps as f64,
        (cpu_time() - c0) / reps as f64,
    )
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let only_costs = std::env::args().any(|a| a == "--costs");
    if std::env::args().any(|a| a == "--stability") {
        stability_costs(quick);
        return;
    }
    if !only_costs && !std::env::args().any(|a| a == "--skip-peers") {
        peers();
    }
    if std::env::args().any(|a| a == "--peer-only") {
        return;
    }
    upd_size(quick);
}

/// The two friction cases shared with pyHarm.
fn peers() {
    peer(&PeerCase {
        name: "Jenkins SDOF",
        m: vec![1.0],
        k: vec![4.0e4],
        c: vec![2.0],
        k12: 0.0,
        c12: 0.0,
        kt: 3.0e4,
        fs: 1.0,
        force: 2.0,
        f0: 28.0,
        f1: 44.0,
    });
    peer(&PeerCase {
        name: "2-DOF friction (Jenkins between the masses)",
        m: vec![1.0, 0.5],
        k: vec![1.0e5, 0.0],
        c: vec![3.0, 0.0],
        k12: 1.0e4,
        c12: 0.5,
        kt: 4.0e4,
        fs: 3.0,
        force: 20.0,
        f0: 30.0,
        f1: 70.0,
    });
}

/// The underplatform-damper-size case: 4 levels × 200 points (`quick`: one level, 10 points).
fn upd_size(quick: bool) {
    let (s, force, response) = model();
    let h = Harmonics::new(7, false, Some(128)).unwrap();
    let sys = HbmSystem::new(
        &s,
        h,
        Excitation {
            force,
            harmonic: 1,
            force_sin: None,
        },
        FormulationChoice::Auto,
    )
    .unwrap();
    println!(
        "## Harmonic balance, underplatform-damper size: {} modes, {} elements ({} contact DOFs), harmonics 0..7, {} samples/period",
        MODES,
        s.elements.len(),
        s.contact_dofs(),
        sys.harmonics.n_time()
    );
    println!(
        "formulation chosen: {:?}, {} unknowns (receptance would need {}); rayon threads {}; load average {}",
        sys.formulation(),
        sys.unknowns(),
        s.contact_dofs() * sys.harmonics.len(),
        rayon::current_num_threads(),
        std::fs::read_to_string("/proc/loadavg").unwrap_or_default().trim()
    );
    if std::env::args().any(|a| a == "--costs") {
        // Costs only, at two states near the first resonance: microslip and slip.
        for level in [0.05, 0.5] {
            let p = sys
                .solve(2.0 * std::f64::consts::PI * 876.0, level, None)
                .unwrap();
            costs(&sys, &s, &p);
        }
        return;
    }
    // `--levels 0.05,0.5`: a subset of the levels (N).
    let args: Vec<String> = std::env::args().collect();
    let levels: Vec<f64> = match args.iter().position(|a| a == "--levels") {
        Some(i) => args[i + 1]
            .split(',')
            .map(|v| v.parse().expect("--levels: comma-separated forces in N"))
            .collect(),
        None if quick => vec![0.05],
        None => vec![0.05, 0.5, 2.0, 8.0],
    };
    let mut settings = ContinuationSettings::new(550.0, 1100.0);
    settings.points = if quick { 10 } else { 200 };
    let t_all = Instant::now();
    let c_all = cpu_time();
    let mut peak_point = None;
    let len = sys.harmonics.len();
    // The levels run concurrently, as `asperity response` runs them (rayon tasks; the element
    // loops inside are parallel too). Per-level times are the wall time of each sweep, which
    // overlap; the total wall and CPU time of all levels follow the table.
    let branches: Vec<_> = levels
        .par_iter()
        .map(|&level| (level, sweep(&sys, level, &settings, &mut |_| {}).unwrap()))
        .collect();
    let (wall_all, cpu_all) = (t_all.elapsed().as_secs_f64(), cpu_time() - c_all);
    println!("\n| level (N) | points | corrector iterations | Jacobians | rejected steps | peak (m) | peak (Hz) | sweep wall (s) |\n|---|---|---|---|---|---|---|---|");
    for (level, b) in branches {
        let (ci, si) = sys.harmonics.index_of(1).unwrap();
        let (mut amax, mut fpk) = (0.0, 0.0);
        for p in &b.points {
            let a: f64 = (0..MODES)
                .map(|r| response[r] * p.z[r * len + ci])
                .sum::<f64>()
                .hypot(
                    (0..MODES)
                        .map(|r| response[r] * p.z[r * len + si])
                        .sum::<f64>(),
                );
            if a > amax {
                amax = a;
                fpk = p.omega / (2.0 * std::f64::consts::PI);
                peak_point = Some(p.clone());
            }
        }
        println!(
            "| {level} | {} | {} | {} | {} | {amax:.4e} | {fpk:.2} | {:.2} |",
            b.points.len(),
            b.points.iter().map(|p| p.iterations).sum::<usize>(),
            b.jacobians,
            b.rejected_steps,
            b.wall_time_s,
        );
    }
    println!(
        "\nall levels: wall {wall_all:.2} s, CPU {cpu_all:.2} s (all threads); load average at the end {}",
        std::fs::read_to_string("/proc/loadavg").unwrap_or_default().trim()
    );
    // Cost of one evaluation at a representative state: the peak of the last sweep.
    costs(&sys, &s, &peak_point.expect("a sweep ran"));
}

/// Costs at one solution point: one AFT evaluation of all elements (residual only), one with
/// the Jacobian (AFT Jacobians and their assembly), the LU solve of the Newton system, and one
/// element alone. Wall and CPU time (all threads).
fn costs(sys: &HbmSystem<'_>, s: &Structure, p: &asperity::dynamics::hbm::HbmPoint) {
    let (w, lv) = (p.omega, p.level);
    let len = sys.harmonics.len();
    let (res_w, res_c) = timed(10, || {
        std::hint::black_box(sys.evaluate(&p.z, w, lv, false));
    });
    let (jac_w, jac_c) = timed(5, || {
        std::hint::black_box(sys.evaluate(&p.z, w, lv, true));
    });
    let ev = sys.evaluate(&p.z, w, lv, true);
    let (lu_w, lu_c) = timed(5, || {
        std::hint::black_box(
            asperity::dynamics::hbm::solve_linear(&ev.jacobian, &ev.residual, w).unwrap(),
        );
    });
    let element_u = |e: &asperity::dynamics::model::AttachedElement| -> Vec<f64> {
        let um = &e.map * DMatrix::from_row_slice(MODES, len, p.z.as_slice());
        (0..3)
            .flat_map(|c| (0..len).map(move |hh| (c, hh)))
            .map(|(c, hh)| um[(c, hh)])
            .collect()
    };
    let e = &s.elements[0];
    let u = element_u(e);
    let settings = sys.aft;
    let (el_w, _) = timed(200, || {
        std::hint::black_box(aft::evaluate(
            e.element.as_ref(),
            &sys.harmonics,
            &u,
            w,
            false,
            &settings,
        ));
    });
    let (elj_w, _) = timed(200, || {
        std::hint::black_box(aft::evaluate(
            e.element.as_ref(),
            &sys.harmonics,
            &u,
            w,
            true,
            &settings,
        ));
    });
    let periods: Vec<usize> = s
        .elements
        .iter()
        .map(|e| {
            aft::evaluate(
                e.element.as_ref(),
                &sys.harmonics,
                &element_u(e),
                w,
                false,
                &settings,
            )
            .periods
        })
        .collect();
    println!(
        "costs at {:.2} Hz, level {lv} N (load average {}):",
        w / (2.0 * std::f64::consts::PI),
        std::fs::read_to_string("/proc/loadavg")
            .unwrap_or_default()
            .trim()
    );
    println!(
        "  AFT periods per element: mean {:.2}, max {}",
        periods.iter().sum::<usize>() as f64 / periods.len() as f64,
        periods.iter().max().unwrap()
    );
    println!(
        "  one element: AFT {:.1} µs, AFT + Jacobian {:.1} µs (wall, one thread)",
        el_w * 1e6,
        elj_w * 1e6
    );
    println!(
        "  all elements, residual only (one AFT evaluation): wall {:.2} ms, CPU {:.2} ms",
        res_w * 1e3,
        res_c * 1e3
    );
    println!(
        "  residual + Jacobian (AFT Jacobians + assembly): wall {:.2} ms, CPU {:.2} ms",
        jac_w * 1e3,
        jac_c * 1e3
    );
    println!(
        "  LU solve of the {0}×{0} Newton system: wall {1:.2} ms, CPU {2:.2} ms",
        sys.unknowns(),
        lu_w * 1e3,
        lu_c * 1e3
    );
}

/// Cost of Hill's stability assessment per point relative to the sweep that computed the points,
/// levels one after the other (so that neither overlaps another level), wall and CPU time:
/// the shipped blade–damper example (`calib/response/model.toml`, its four levels) and the
/// underplatform-damper-size model (one level, 0.5 N, over 850–900 Hz: `quick` 10 points).
fn stability_costs(quick: bool) {
    use asperity::dynamics::response::ResponseSettings;
    use asperity::dynamics::stability::branch_stability;
    let run = |name: &str, sys: &HbmSystem<'_>, levels: &[f64], settings: &ContinuationSettings| {
        let n = sys.structure.n();
        println!(
            "## {name}: {} coordinates, harmonics {:?}, {} samples, {:?} formulation ({} unknowns); Hill companion matrix {} × {}; rayon threads {}; load average {}",
            n,
            sys.harmonics.orders(),
            sys.harmonics.n_time(),
            sys.formulation(),
            sys.unknowns(),
            2 * n * sys.harmonics.len(),
            2 * n * sys.harmonics.len(),
            rayon::current_num_threads(),
            std::fs::read_to_string("/proc/loadavg").unwrap_or_default().trim()
        );
        println!("| level (N) | points | sweep wall (s) | sweep CPU (s) | stability wall (s) | stability CPU (s) | stability/sweep wall | stability/sweep CPU | unstable points | bifurcations |\n|---|---|---|---|---|---|---|---|---|---|");
        let (mut sw, mut sc, mut tw, mut tc) = (0.0, 0.0, 0.0, 0.0);
        for &level in levels {
            let (c0, t0) = (cpu_time(), Instant::now());
            let b =
                asperity::dynamics::continuation::sweep_partial(sys, level, settings, &mut |_| {})
                    .unwrap();
            let (w1, c1) = (t0.elapsed().as_secs_f64(), cpu_time() - c0);
            let (c0, t0) = (cpu_time(), Instant::now());
            let st = branch_stability(sys, &b).unwrap();
            let (w2, c2) = (t0.elapsed().as_secs_f64(), cpu_time() - c0);
            println!(
                "| {level} | {} | {w1:.2} | {c1:.2} | {w2:.2} | {c2:.2} | {:.2} | {:.2} | {} | {} |",
                b.points.len(),
                w2 / w1,
                c2 / c1,
                st.unstable_points(),
                st.bifurcations.len()
            );
            (sw, sc, tw, tc) = (sw + w1, sc + c1, tw + w2, tc + c2);
        }
        println!(
            "all levels: stability/sweep wall {:.2}, CPU {:.2}\n",
            tw / sw,
            tc / sc
        );
    };
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("calib/response/model.toml");
    let m = asperity::dynamics::model_file::load(&path).unwrap();
    let rs = ResponseSettings::of_model_file(&m.file.sweep).unwrap();
    let sys = HbmSystem::new(
        &m.structure,
        rs.harmonics.clone(),
        Excitation {
            force: m.force.clone(),
            harmonic: m.file.excitation.harmonic,
            force_sin: m.force_sin.clone(),
        },
        rs.formulation,
    )
    .unwrap();
    run(
        "blade–damper example (calib/response/model.toml)",
        &sys,
        &m.file.excitation.levels_n,
        &rs.continuation,
    );
    let (s, force, _) = model();
    let h = Harmonics::new(7, false, Some(128)).unwrap();
    let sys = HbmSystem::new(
        &s,
        h,
        Excitation {
            force,
            harmonic: 1,
            force_sin: None,
        },
        FormulationChoice::Auto,
    )
    .unwrap();
    let mut settings = ContinuationSettings::new(850.0, 900.0);
    settings.points = if quick { 10 } else { 40 };
    run(
        "underplatform-damper size (30 modes, 146 Valanis elements)",
        &sys,
        &[0.5],
        &settings,
    );
}
