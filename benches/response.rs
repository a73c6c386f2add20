//! Benchmark: harmonic balance at underplatform-damper size.
//!
//!     cargo bench --bench response                 # full case: 4 levels × 200 points
//!     cargo bench --bench response -- --quick      # one level, ≥ 10 points
//!     cargo bench --bench response -- --peer-only  # the Jenkins SDOF against pyHarm only
//!
//! The pyHarm comparison runs when the venv of benches/peers/setup_pyharm.sh exists.
//!
//! Case: a synthetic reduced modal model of two blades and an underplatform damper (30 modes,
//! 0.6–8 kHz, 0.3 % modal damping; seeded, see `model()`), 146 Valanis microslip contact
//! elements (73 per damper–platform interface, 3 DOF each: 438 contact DOFs) with per-element
//! parameters of the reference calibration table at 2 MPa, harmonics 0..7 (15 coefficients,
//! 128 samples per period). Prints the cost of one AFT evaluation (all elements, residual only)
//! and of one Jacobian, the formulation used, and the sweep times. Units: SI, times in seconds.

use asperity::dynamics::aft::{self, AftSettings, Harmonics};
use asperity::dynamics::continuation::{sweep, ContinuationSettings};
use asperity::dynamics::hbm::{Excitation, FormulationChoice, HbmSystem};
use asperity::dynamics::model::Structure;
use asperity::dynamics::nonlinear::MicroslipContact;
use asperity::element::ValanisParams;
use nalgebra::{DMatrix, DVector};
use rand::{Rng, SeedableRng};
use std::sync::Arc;
use std::time::Instant;

const MODES: usize = 30;

/// Rigid-body kinematics of a contact point at `r` (m) of a body moving by translation `t` and
/// small rotation `th`: `t + th × r`.
fn point(t: [f64; 3], th: [f64; 3], r: [f64; 3]) -> [f64; 3] {
    [
        t[0] + th[1] * r[2] - th[2] * r[1],
        t[1] + th[2] * r[0] - th[0] * r[2],
        t[2] + th[0] * r[1] - th[1] * r[0],
    ]
}

/// Two blades and a damper: every mode moves each body's platform region as a rigid body plus a
/// smooth elastic bending over the contact face; shapes mass-normalised (modal masses 0.05–0.5 kg).
fn model() -> (Structure, DVector<f64>, DVector<f64>) {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let freqs: Vec<f64> = (0..MODES)
        .map(|r| 600.0 * (8000.0f64 / 600.0).powf(r as f64 / (MODES - 1) as f64))
        .collect();
    let mut s = Structure::modal(&freqs, &vec![0.003; MODES]).unwrap();
    // Per mode and body: translation (m per √kg) and rotation (rad per √kg) amplitudes.
    let mut body = vec![[[0.0; 3]; 6]; MODES];
    for b in body.iter_mut() {
        let scale = 1.0 / rng.random_range(0.05f64..0.5).sqrt();
        for (k, v) in b.iter_mut().enumerate() {
            for x in v.iter_mut() {
                // Bodies 0..2 translations, 3..5 rotations (×1/lever 10 mm).
                *x = scale * rng.random_range(-1.0..1.0) * if k < 3 { 1.0 } else { 50.0 };
            }
        }
    }
    let v = ValanisParams::new(2.6e13 * 1.0e-7, 0.316, 0.0, 0.6).unwrap();
    let (kn, n0) = (2.6e13 * 1.0e-7, 2.0e6 * 1.0e-7 * 5.0);
    for iface in 0..2 {
        // Contact face 10 mm × 6 mm, normal tilted ±45° in the x–z plane (wedge damper).
        let sgn = if iface == 0 { 1.0 } else { -1.0 };
        let normal = [
            sgn * std::f64::consts::FRAC_1_SQRT_2,
            0.0,
            std::f64::consts::FRAC_1_SQRT_2,
        ];
        let t1 = [-normal[2], 0.0, normal[0]];
        let t2 = [0.0, 1.0, 0.0];
        for e in 0..73 {
            let (i, j) = (e % 11, e / 11);
            let r = [
                sgn * 0.01 + 0.0006 * i as f64 * t1[0],
                -0.003 + 0.001 * j as f64,
                0.0006 * i as f64 * t1[2],
            ];
            let mut map = DMatrix::zeros(3, MODES);
            for (m, b) in body.iter().enumerate() {
                // Damper (body 2, translation index 2 and rotation index 5) against blade `iface`.
                let pd = point(b[2], b[5], r);
                let pb = point(b[iface], b[3 + iface], r);
                let rel = [pd[0] - pb[0], pd[1] - pb[1], pd[2] - pb[2]];
                for (c, axis) in [t1, t2, normal].iter().enumerate() {
                    map[(c, m)] = axis.iter().zip(&rel).map(|(a, b)| a * b).sum::<f64>();
                }
            }
            let el = MicroslipContact::new(v, kn, n0).unwrap();
            s.attach(format!("{iface}-{e}"), Arc::new(el), map).unwrap();
        }
    }
    // Excitation and response at a blade-1 tip point (modal participation from body 0).
    let force = DVector::from_iterator(MODES, body.iter().map(|b| b[0][0]));
    let response = force.clone();
    (s, force, response)
}

/// Peak of sampled (frequency, amplitude) points refined by a parabola through the largest
/// sample and its neighbours.
fn refined_peak(f: &[f64], a: &[f64]) -> (f64, f64) {
    let i = (0..a.len())
        .max_by(|&i, &j| a[i].partial_cmp(&a[j]).unwrap())
        .unwrap();
    if i == 0 || i + 1 == a.len() {
        return (f[i], a[i]);
    }
    // Lagrange parabola through three (possibly unequally spaced) points.
    let (x0, x1, x2) = (f[i - 1], f[i], f[i + 1]);
    let (y0, y1, y2) = (a[i - 1], a[i], a[i + 1]);
    let d = (x0 - x1) * (x0 - x2) * (x1 - x2);
    let aa = (x2 * (y1 - y0) + x1 * (y0 - y2) + x0 * (y2 - y1)) / d;
    let bb = (x2 * x2 * (y0 - y1) + x1 * x1 * (y2 - y0) + x0 * x0 * (y1 - y2)) / d;
    let cc = (x1 * x2 * (x1 - x2) * y0 + x2 * x0 * (x2 - x0) * y1 + x0 * x1 * (x0 - x1) * y2) / d;
    if aa >= 0.0 {
        return (f[i], a[i]);
    }
    let xv = -bb / (2.0 * aa);
    (xv, aa * xv * xv + bb * xv + cc)
}

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
        Arc::new(asperity::dynamics::nonlinear::Jenkins::new(case.kt, case.fs).unwrap()),
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
        },
        FormulationChoice::Coordinates,
    )
    .unwrap();
    let mut settings = ContinuationSettings::new(case.f0, case.f1);
    settings.points = 100;
    let mut best = f64::INFINITY;
    let mut best_cpu = f64::INFINITY;
    let mut branch = None;
    for _ in 0..3 {
        let c0 = cpu_time();
        let t = Instant::now();
        let b = sweep(&sys, case.force, &settings, &mut |_| {}).unwrap();
        best = best.min(t.elapsed().as_secs_f64());
        best_cpu = best_cpu.min(cpu_time() - c0);
        branch = Some(b);
    }
    let b = branch.unwrap();
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
    println!("asperity: {} points, peak {apk:.6e} m at {fpk:.4} Hz (mass 1); sweep wall {best:.4} s, CPU {best_cpu:.4} s (best of 3)", b.points.len());
    let python = std::path::Path::new("/tmp/asperity-pyharm-venv/bin/python");
    if !python.exists() {
        println!("pyHarm venv not found (run benches/peers/setup_pyharm.sh): peer skipped");
        return;
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
        .unwrap();
    if !o.status.success() {
        println!("pyHarm failed: {}", String::from_utf8_lossy(&o.stderr));
        return;
    }
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    let pf: Vec<f64> = r["frequency_Hz"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let pa: Vec<f64> = r["amplitude_m"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let (pfpk, papk) = refined_peak(&pf, &pa);
    let (pw, pc) = (r["wall_s"].as_f64().unwrap(), r["cpu_s"].as_f64().unwrap());
    println!("pyHarm:   {} points, peak {papk:.6e} m at {pfpk:.4} Hz; analysis wall {pw:.4} s, CPU {pc:.4} s (second run, after JIT)", pf.len());
    println!(
        "peak amplitude {:+.3} %, peak frequency {:+.3} %; time ratio pyHarm/asperity: wall {:.1}×, CPU {:.1}×, per point (wall) {:.1}×\n",
        (apk / papk - 1.0) * 100.0,
        (fpk / pfpk - 1.0) * 100.0,
        pw / best,
        pc / best_cpu.max(1e-9),
        (pw / pf.len() as f64) / (best / b.points.len() as f64)
    );
}

/// CPU time of this process (s).
fn cpu_time() -> f64 {
    let s = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let f: Vec<&str> = s
        .rsplit(')')
        .next()
        .unwrap_or("")
        .split_whitespace()
        .collect();
    let tick = 100.0;
    (f.get(11).and_then(|v| v.parse::<f64>().ok()).unwrap_or(0.0)
        + f.get(12).and_then(|v| v.parse::<f64>().ok()).unwrap_or(0.0))
        / tick
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
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
    if std::env::args().any(|a| a == "--peer-only") {
        return;
    }
    let (s, force, response) = model();
    let h = Harmonics::new(7, false, Some(128)).unwrap();
    let sys = HbmSystem::new(
        &s,
        h,
        Excitation { force, harmonic: 1 },
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
    let levels: Vec<f64> = if quick {
        vec![0.05]
    } else {
        vec![0.05, 0.5, 2.0, 8.0]
    };
    let mut settings = ContinuationSettings::new(550.0, 1100.0);
    settings.points = if quick { 10 } else { 200 };
    let t_all = Instant::now();
    let mut peak_point = None;
    let len = sys.harmonics.len();
    println!("\n| level (N) | points | Jacobians | rejected steps | peak (m) | peak (Hz) | time (s) |\n|---|---|---|---|---|---|---|");
    for level in levels {
        let b = sweep(&sys, level, &settings, &mut |_| {}).unwrap();
        let (ci, si) = sys.harmonics.index_of(1).unwrap();
        let (mut amax, mut fpk) = (0.0, 0.0);
        for p in &b.points {
            let _ = &p;
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
            "| {level} | {} | {} | {} | {amax:.4e} | {fpk:.2} | {:.2} |",
            b.points.len(),
            b.jacobians,
            b.rejected_steps,
            b.wall_time_s
        );
    }
    println!("\ntotal sweep time {:.2} s", t_all.elapsed().as_secs_f64());
    // Cost of one evaluation at a representative state: the peak of the last sweep.
    let p = peak_point.expect("a sweep ran");
    let (w, lv) = (p.omega, p.level);
    let reps = 5;
    let t = Instant::now();
    for _ in 0..reps {
        std::hint::black_box(sys.evaluate(&p.z, w, lv, false));
    }
    let t_res = t.elapsed().as_secs_f64() / reps as f64;
    let t = Instant::now();
    for _ in 0..reps {
        std::hint::black_box(sys.evaluate(&p.z, w, lv, true));
    }
    let t_jac = t.elapsed().as_secs_f64() / reps as f64;
    // One element alone.
    let e = &s.elements[0];
    let len = sys.harmonics.len();
    let u: Vec<f64> = {
        let um = &e.map * DMatrix::from_row_slice(MODES, len, p.z.as_slice());
        (0..3)
            .flat_map(|c| (0..len).map(move |hh| (c, hh)))
            .map(|(c, hh)| um[(c, hh)])
            .collect()
    };
    let n1 = 200;
    let t = Instant::now();
    for _ in 0..n1 {
        std::hint::black_box(aft::evaluate(
            e.element.as_ref(),
            &sys.harmonics,
            &u,
            false,
            &AftSettings::default(),
        ));
    }
    let t_el = t.elapsed().as_secs_f64() / n1 as f64;
    let t = Instant::now();
    for _ in 0..n1 {
        std::hint::black_box(aft::evaluate(
            e.element.as_ref(),
            &sys.harmonics,
            &u,
            true,
            &AftSettings::default(),
        ));
    }
    let t_elj = t.elapsed().as_secs_f64() / n1 as f64;
    let one = aft::evaluate(
        e.element.as_ref(),
        &sys.harmonics,
        &u,
        false,
        &AftSettings::default(),
    );
    println!(
        "periods integrated by the AFT of element 0 at the peak: {} (periodicity error {:.1e})",
        one.periods, one.periodicity_error
    );
    let periods: Vec<usize> = s
        .elements
        .iter()
        .map(|e| {
            let um = &e.map * DMatrix::from_row_slice(MODES, len, p.z.as_slice());
            let u: Vec<f64> = (0..3)
                .flat_map(|c| (0..len).map(move |hh| (c, hh)))
                .map(|(c, hh)| um[(c, hh)])
                .collect();
            aft::evaluate(
                e.element.as_ref(),
                &sys.harmonics,
                &u,
                false,
                &AftSettings::default(),
            )
            .periods
        })
        .collect();
    println!(
        "periods over all elements: mean {:.2}, max {}",
        periods.iter().sum::<usize>() as f64 / periods.len() as f64,
        periods.iter().max().unwrap()
    );
    println!(
        "one element: AFT {:.1} µs, AFT + Jacobian {:.1} µs; whole system: residual {:.2} ms, residual + Jacobian (AFT Jacobians + assembly) {:.2} ms",
        t_el * 1e6,
        t_elj * 1e6,
        t_res * 1e3,
        t_jac * 1e3
    );
}
