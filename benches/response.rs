//! Benchmark: harmonic balance at underplatform-damper size.
//!
//!     cargo bench --bench response                 # full case: 4 levels × 200 points
//!     cargo bench --bench response -- --quick      # one level, 40 points
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

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
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
