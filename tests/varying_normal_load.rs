//! Tangential loops under a varying normal load (`contact::tangential::varying_load`) on a single
//! Hertzian asperity, against Mindlin & Deresiewicz (J. Appl. Mech. 20 (1953) 327–344; Johnson,
//! *Contact Mechanics*, 1985, §7.5):
//!
//! - oblique loading at a constant ratio `dT/dP = k` from `(P0, 0)`: no slip at all for `k < μ`
//!   and `δ = (3k·s/16)(P/a − P0/a0)`; slip in an annulus for `k > μ`, `δ` and the stick radius
//!   of `q = μ(p_P − p_Pc)` ([`ObliqueLoading`]);
//! - whole cycles with the normal load oscillating in phase, out of phase and at 90°, against
//!   the method of dimensionality reduction, which reproduces Mindlin–Deresiewicz for any history
//!   of normal and tangential load on an axisymmetric profile (Popov & Heß, *Method of
//!   Dimensionality Reduction in Contact Mechanics and Friction*, Springer 2015, ch. 5; exact by
//!   Jäger's superposition, J. Tribol. 120 (1998) 677–684) — here on 40 000 springs, a converged
//!   peer independent of the BEM.
//!
//! The BEM runs on the sampled Hertz pressure of each load (scaled to the exact load), 44 points
//! across the smallest contact, as the Cattaneo–Mindlin tests of `tests/tangential_contact.rs`.
//! Units: SI (m, Pa, N, J). Both bodies G = 200 MPa, ν = 0.42, R = 50 mm, μ = 0.4.

use asperity::contact::analytic::{Hertz, ObliqueLoading};
use asperity::contact::tangential::varying_load::{
    oscillate_on_fields, NormalLoadOscillation, VaryingLoadHistory,
};
use asperity::contact::tangential::{
    Control, TangentialOptions, TangentialProblem, TangentialSolver,
};
use asperity::core::fft::Boundary;
use asperity::core::material::{composite_modulus, Material};
use ndarray::Array2;
use std::f64::consts::PI;

const G: f64 = 2e8;
const NU: f64 = 0.42;
const R: f64 = 0.05;
const MU: f64 = 0.4;
/// Reference normal force (N): a = 1 mm.
const P0: f64 = 9.1954;

fn material() -> Material {
    Material {
        youngs_modulus_pa: 2.0 * G * (1.0 + NU),
        poisson_ratio: NU,
    }
}

fn e_star() -> f64 {
    composite_modulus(material(), material()).unwrap()
}

/// `s = Σ (2 − ν)/G` of the two bodies (1/Pa).
fn compliance_sum() -> f64 {
    2.0 * (2.0 - NU) / G
}

/// Element-centre coordinate of index `i` on an `n`-point grid centred on the sphere.
fn centre(i: usize, n: usize, dx: f64) -> f64 {
    (i as f64 - 0.5 * (n as f64 - 1.0)) * dx
}

/// Hertz pressure of the load `p` at the element centres, scaled so that ΔA Σ p = P exactly.
fn hertz_field(n: usize, dx: f64, p: f64) -> Array2<f64> {
    let h = Hertz::new(R, p, e_star());
    let mut f = Array2::from_shape_fn((n, n), |(i, j)| {
        h.pressure(centre(i, n, dx).hypot(centre(j, n, dx)))
    });
    let s = f.sum() * dx * dx;
    f.mapv_inplace(|v| v * p / s);
    f
}

/// A solver on the contact of the largest load `p_max` (it holds every smaller one).
fn solver(n: usize, dx: f64, p_max: f64) -> TangentialSolver {
    TangentialSolver::new(
        &TangentialProblem {
            pressure: &hertz_field(n, dx, p_max),
            dx,
            dy: dx,
            boundary: Boundary::ZeroPadded,
            friction_coefficient: MU,
            body1: material(),
            body2: material(),
        },
        TangentialOptions {
            tolerance: 1e-8,
            ..TangentialOptions::default()
        },
    )
    .unwrap()
}

fn oblique(k: f64) -> ObliqueLoading {
    ObliqueLoading {
        sphere_radius: R,
        e_star: e_star(),
        friction_coefficient: MU,
        compliance_sum: compliance_sum(),
        initial_normal_force: P0,
        ratio: k,
    }
}

/// Oblique loading from `(P0, 0)` to `P = 1.5 P0` in 10 load-controlled steps, the pressure
/// following the load. `k = 0.5 μ`: no slip, and `δ` follows the closed form within 0.5 %;
/// `k = 2μ`: `δ` within 0.5 % (`T/μP` reaches 0.67) and the stick radius within one spacing.
/// Measured: within 0.29 %. The Cattaneo–Mindlin test at 44 points across is within 0.25 %
/// (`tests/tangential_contact.rs`); 0.5 % allows for the contact edge moving within the steps.
/// For `k < μ` the only slipping points are in the outermost ring of the contact (at most 2 %
/// of the points).
#[test]
fn oblique_loading_at_a_constant_ratio_follows_mindlin_deresiewicz() {
    let a0 = Hertz::new(R, P0, e_star()).radius;
    let dx = 2.0 * a0 / 44.0;
    let p_max = 1.5 * P0;
    let n = 2 * (Hertz::new(R, p_max, e_star()).radius / dx).ceil() as usize + 6;
    for k in [0.5 * MU, 2.0 * MU] {
        let closed = oblique(k);
        let mut s = solver(n, dx, p_max);
        s.set_pressure(&hertz_field(n, dx, P0)).unwrap();
        let mut worst: f64 = 0.0;
        for step in 1..=10 {
            let p = P0 * (1.0 + 0.05 * step as f64);
            let field = hertz_field(n, dx, p);
            s.set_pressure(&field).unwrap();
            let t = closed.tangential_force(p);
            let st = s.step(Control::Force([t, 0.0])).unwrap();
            let want = closed.displacement(p).unwrap();
            let err = st.shift_m[0] / want - 1.0;
            worst = worst.max(err.abs());
            let stick_points = s.stick_mask().iter().filter(|b| **b).count();
            let c_num = (stick_points as f64 * dx * dx / PI).sqrt();
            let c = closed.stick_radius(p);
            eprintln!(
                "k/μ = {}: P/P0 = {:.2}, T/μP = {:.3}: δ = {:.5e} m, closed form {want:.5e} m \
                 ({:+.3} %), stick fraction {:.4}, stick radius {c_num:.4e} vs {c:.4e} m",
                k / MU,
                p / P0,
                t / (MU * p),
                st.shift_m[0],
                100.0 * err,
                st.stick_fraction,
            );
            assert!(
                err.abs() < 0.005,
                "k/μ = {}, P/P0 = {}: {err}",
                k / MU,
                p / P0
            );
            if k < MU {
                // No slip but for a few points of the outermost ring, whose sampled pressure
                // jumps from zero within one step (the grid's edge, not the mechanics).
                let a = Hertz::new(R, p, e_star()).radius;
                let stick = s.stick_mask();
                let slipping: Vec<f64> = field
                    .indexed_iter()
                    .filter(|((i, j), v)| **v > 0.0 && !stick[[*i, *j]])
                    .map(|((i, j), _)| centre(i, n, dx).hypot(centre(j, n, dx)))
                    .collect();
                assert!(st.stick_fraction > 0.98, "k < μ: {}", st.stick_fraction);
                assert!(
                    slipping.iter().all(|&r| r > a - 1.5 * dx),
                    "k < μ: slip inside the edge ring: {slipping:?}, a = {a:e}"
                );
            } else {
                assert!((c_num - c).abs() <= dx, "stick radius {c_num} vs {c}");
            }
        }
        eprintln!("k/μ = {}: worst {worst:.4}", k / MU);
    }
}

/// The method of dimensionality reduction for a sphere (Popov & Heß 2015, ch. 3 and 5): a row
/// of independent springs at spacing `dx` on the profile `g(x) = x²/R`, normal stiffness
/// `E*·dx`, tangential stiffness `(4/s)·dx`; a spring in contact sticks until its force reaches
/// μ times its normal force, then slides; a spring out of contact carries nothing and comes
/// back into contact unstretched.
struct Mdr {
    x: Vec<f64>,
    dx: f64,
    u: Vec<f64>,
    shift: f64,
}

impl Mdr {
    fn new(half_width: f64, springs: usize) -> Self {
        let dx = 2.0 * half_width / springs as f64;
        Self {
            x: (0..springs)
                .map(|i| (i as f64 + 0.5) * dx - half_width)
                .collect(),
            dx,
            u: vec![0.0; springs],
            shift: 0.0,
        }
    }

    /// Indentation `d` at normal force `P`: `P = (4/3) E* √R d^{3/2}`.
    fn indentation(p: f64) -> f64 {
        (3.0 * p / (4.0 * e_star() * R.sqrt())).powf(2.0 / 3.0)
    }

    /// Spring elongations after moving to `shift` under normal force `p` (not stored), and the
    /// tangential force.
    fn trial(&self, p: f64, shift: f64, out: &mut [f64]) -> f64 {
        let d = Self::indentation(p);
        let kx = 4.0 / compliance_sum() * self.dx;
        let kz = e_star() * self.dx;
        let mut t = 0.0;
        for ((o, &x), &u) in out.iter_mut().zip(&self.x).zip(&self.u) {
            let fz = kz * (d - x * x / R);
            *o = if fz > 0.0 {
                let lim = MU * fz / kx;
                (u + shift - self.shift).clamp(-lim, lim)
            } else {
                0.0
            };
            t += kx * *o;
        }
        t
    }

    /// Load-controlled step to tangential force `t` under normal force `p`: the shift by
    /// bisection (the force is non-decreasing in it). Returns the shift.
    fn step(&mut self, p: f64, t: f64) -> f64 {
        let mut out = vec![0.0; self.u.len()];
        let scale = MU * p * compliance_sum() / Hertz::new(R, p, e_star()).radius;
        let (mut lo, mut hi) = (self.shift - 4.0 * scale, self.shift + 4.0 * scale);
        assert!(self.trial(p, lo, &mut out) < t && self.trial(p, hi, &mut out) > t);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if self.trial(p, mid, &mut out) < t {
                lo = mid;
            } else {
                hi = mid;
            }
            if hi - lo <= 1e-14 * scale {
                break;
            }
        }
        let shift = 0.5 * (lo + hi);
        self.trial(p, shift, &mut out);
        self.u = out;
        self.shift = shift;
        shift
    }
}

/// `∮ T dδ` by the trapezoidal rule over `(δ, T)` pairs.
fn loop_area(points: &[(f64, f64)]) -> f64 {
    points
        .windows(2)
        .map(|w| 0.5 * (w[0].1 + w[1].1) * (w[1].0 - w[0].0))
        .sum()
}

/// One history on the BEM and on the peer: `(W_bem, W_mdr, worst shift difference relative to
/// T*·s/(8a_min), frictional work of the BEM's last cycle)`.
fn cycle_against_mdr(
    ratio: f64,
    t_amp: f64,
    phase_deg: f64,
    points_across: f64,
) -> (f64, f64, f64, f64) {
    let a_min = Hertz::new(R, P0 * (1.0 - ratio), e_star()).radius;
    let a_max = Hertz::new(R, P0 * (1.0 + ratio), e_star()).radius;
    let dx = 2.0 * a_min / points_across;
    let n = 2 * (a_max / dx).ceil() as usize + 6;
    let steps_per_cycle = 40;
    let normal = NormalLoadOscillation {
        mean_pressure_pa: P0 / (n as f64 * dx).powi(2),
        amplitude_ratio: ratio,
        phase_rad: phase_deg * PI / 180.0,
    };
    let history = VaryingLoadHistory {
        tangential_amplitude: Control::Force([t_amp, 0.0]),
        normal,
        cycles: 2,
        steps_per_cycle,
    };
    let load = |k: usize| {
        P0 * normal.pressure_at(2.0 * PI * k as f64 / steps_per_cycle as f64)
            / normal.mean_pressure_pa
    };
    let mut s = solver(n, dx, P0 * (1.0 + ratio));
    let (steps, cycles) = oscillate_on_fields(
        &mut s,
        &history,
        |k| Ok(hertz_field(n, dx, load(k))),
        |_, _| {},
    )
    .unwrap();
    let mut mdr = Mdr::new(1.2 * a_max, 40_000);
    let mut peer = vec![(0.0, 0.0)];
    let mut worst_shift: f64 = 0.0;
    let shift_scale = t_amp * compliance_sum() / (8.0 * a_min);
    for (k, st) in steps.iter().enumerate().skip(1) {
        let p = load(k % steps_per_cycle);
        assert!((st.normal_force_n / p - 1.0).abs() < 1e-9);
        let t = st.tangential.force_n[0];
        let d = mdr.step(p, t);
        peer.push((d, t));
        worst_shift = worst_shift.max((st.tangential.shift_m[0] - d).abs() / shift_scale);
    }
    (
        cycles[1].dissipated_j,
        loop_area(&peer[steps_per_cycle..]),
        worst_shift,
        cycles[1].frictional_work_j,
    )
}

/// Whole cycles, `P = P0 (1 + r sin(θ + φ))`, `T = T* sin θ` (load control, below the friction
/// limit at every phase), 40 steps per cycle, the second cycle's energy:
///
/// - `r = 0.3`, `T* = 0.25 μP0`: `|ΔT/ΔP| = 0.83 μ < μ`. In phase and out of phase the force
///   moves to and fro along a line inside the friction cone and Mindlin & Deresiewicz's steady
///   cycle **dissipates nothing** (every increment has `|dq| ≤ μ|dp|` once the first excursion
///   has set the traction; the peer gives 1e-19 J): the BEM's loop area within 0.1 % of the
///   constant-load energy at the same `T*`. At 90° the path is an ellipse and it dissipates.
/// - `r = 0.2`, `T* = 0.5 μP0`: `|ΔT/ΔP| = 2.5 μ > μ`: slip in every phase; in phase and out of
///   phase the same energy (the two steady cycles are mirror images, `T → −T`), 16 % less than
///   at constant load, at 90° 31 % more.
/// - `r = 0`: constant load, against the peer and the closed form (Johnson 1985, eq. 7.59).
///
/// Energies against the peer within 1.5 % (measured −0.9 % … +1.0 %) and the shift at every step
/// within 1 % of `T*·s/(8a_min)` (measured ≤ 0.33 %), at 44 points across the smallest contact.
/// The energy error is the grid's microslip at the contact edge, largest at small amplitude:
/// at constant load it is −0.6 % at `T* = 0.5 μP0` and between −1.7 % and +2.0 % at
/// `0.25 μP0` depending on how the grid samples the edge, the size of the Cattaneo–Mindlin
/// error of `tests/tangential_contact.rs`; the 1 % of the issue holds for the dissipative
/// cases at `T* = 0.5 μP0`. The phase changes the energy by far more than the tolerance.
#[test]
fn cycles_with_an_oscillating_normal_load_match_mindlin_deresiewicz() {
    let across = 44.0;
    let cm = |t: f64| {
        asperity::contact::analytic::CattaneoMindlin::new(
            Hertz::new(R, P0, e_star()).radius,
            P0,
            MU,
            G,
            NU,
            G,
            NU,
        )
        .energy_per_cycle(t)
    };
    let mut results = Vec::new();
    for (ratio, t_frac, phase) in [
        (0.0, 0.5, 0.0),
        (0.3, 0.25, 0.0),
        (0.3, 0.25, 180.0),
        (0.3, 0.25, 90.0),
        (0.2, 0.5, 0.0),
        (0.2, 0.5, 90.0),
        (0.2, 0.5, 180.0),
    ] {
        let t_amp = t_frac * MU * P0;
        let (w, w_peer, shift, work) = cycle_against_mdr(ratio, t_amp, phase, across);
        let w_const = cm(t_amp);
        eprintln!(
            "r = {ratio}, T*/μP0 = {t_frac}, phase {phase}°: W = {w:.5e} J, peer {w_peer:.5e} J \
             ({:+.3} %), constant-load closed form {w_const:.5e} J, W/W_const = {:.4}, \
             frictional work {work:.5e} J, worst shift difference {shift:.4}",
            100.0 * (w / w_peer - 1.0),
            w / w_const
        );
        results.push((ratio, t_frac, phase, w, w_peer, shift, w_const));
    }
    for &(ratio, t_frac, phase, w, w_peer, shift, w_const) in &results {
        let case = format!("r = {ratio}, T*/μP0 = {t_frac}, phase {phase}°");
        assert!(shift < 0.01, "{case}: shift {shift}");
        if ratio > 0.0 && t_frac / ratio < 1.0 && phase != 90.0 {
            assert!(w_peer.abs() < 1e-9 * w_const, "{case}: peer {w_peer:e}");
            assert!(w.abs() < 1e-3 * w_const, "{case}: {w:e} vs {w_const:e}");
        } else {
            assert!(
                (w / w_peer - 1.0).abs() < 0.015,
                "{case}: {w:e} vs {w_peer:e}"
            );
        }
        if ratio == 0.0 {
            assert!(
                (w / w_const - 1.0).abs() < 0.015,
                "{case}: {w:e} vs {w_const:e}"
            );
        }
    }
    // r = 0.2: in and out of phase alike, below the constant-load energy; 90° above it.
    let w = |phase: f64| {
        results
            .iter()
            .find(|r| r.0 == 0.2 && r.2 == phase)
            .map(|r| (r.3, r.6))
            .unwrap()
    };
    let ((w0, w_const), (w90, _), (w180, _)) = (w(0.0), w(90.0), w(180.0));
    assert!((w0 / w180 - 1.0).abs() < 0.005, "{w0:e} {w180:e}");
    assert!(
        w0 < 0.9 * w_const && w90 > 1.2 * w_const,
        "{w0:e} {w90:e} {w_const:e}"
    );
}

fn contact_tangential(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args(["contact", "tangential"])
        .args(args)
        .output()
        .unwrap()
}

/// Data rows of a CSV with `#` comments, split.
fn rows(path: &std::path::Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header = lines.next().unwrap().split(',').map(String::from).collect();
    (
        header,
        lines
            .map(|l| l.split(',').map(String::from).collect())
            .collect(),
    )
}

fn column(header: &[String], name: &str) -> usize {
    header
        .iter()
        .position(|c| c == name)
        .unwrap_or_else(|| panic!("no column {name} in {header:?}"))
}

/// `contact tangential --normal-amplitude-ratio --normal-phase-deg` on the generated surface:
/// the normal pressure of every step is `p̄(1 + r sin(2πk/n + φ))` (to the normal solver's
/// tolerance); the element file's BEM energies are those of the varying run's last cycle and of
/// the constant-load run at the same amplitude; the element's error is the relative difference
/// of its energy; the plots exist. Bad values are refused by flag, without output.
#[test]
fn cli_varying_normal_load_writes_loops_element_check_and_plots() {
    let dir = tempfile::tempdir().unwrap();
    let base = |out: &std::path::Path| -> Vec<String> {
        [
            "--grid",
            "128",
            "--pressures-pa",
            "1e6,1e7",
            "--cycles",
            "2",
            "--steps-per-cycle",
            "12",
            "--amplitude-m",
            "5e-8",
            "--out-dir",
            out.to_str().unwrap(),
        ]
        .iter()
        .map(|s| s.to_string())
        .collect()
    };
    let run = |name: &str, extra: &[&str]| {
        let out = dir.path().join(name);
        let mut args = base(&out);
        args.extend(extra.iter().map(|s| s.to_string()));
        let a: Vec<&str> = args.iter().map(String::as_str).collect();
        let o = contact_tangential(&a);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        out
    };
    let constant = run("constant", &[]);
    assert!(!constant.join("tangential_element.csv").exists());
    let (ratio, phase) = (0.4, 60.0);
    let out = run(
        "varying",
        &[
            "--normal-amplitude-ratio",
            "0.4",
            "--normal-phase-deg",
            "60",
        ],
    );
    for f in [
        "tangential_element_loops.png",
        "tangential_element_energy.png",
        "tangential_loops.png",
    ] {
        assert!(image::open(out.join(f)).is_ok(), "{f}");
    }
    let (h, loops) = rows(&out.join("tangential_loops.csv"));
    let (cp, cs, cn) = (
        column(&h, "pressure_Pa"),
        column(&h, "step"),
        column(&h, "normal_pressure_Pa"),
    );
    column(&h, "element_mean_shear_stress_Pa");
    assert_eq!(loops.len(), 2 * (2 * 12 + 1));
    for r in &loops {
        let p: f64 = r[cp].parse().unwrap();
        let k: f64 = r[cs].parse().unwrap();
        let pn: f64 = r[cn].parse().unwrap();
        let want = p * (1.0 + ratio * (2.0 * PI * k / 12.0 + phase * PI / 180.0).sin());
        assert!((pn / want - 1.0).abs() < 1e-6, "step {k}: {pn} vs {want}");
    }
    let last_cycle_energy = |dir: &std::path::Path| -> Vec<f64> {
        let (h, e) = rows(&dir.join("tangential_energy.csv"));
        let (c, w) = (column(&h, "cycle"), column(&h, "dissipated_J_per_m2"));
        e.iter()
            .filter(|r| r[c] == "2")
            .map(|r| r[w].parse().unwrap())
            .collect()
    };
    let (h, el) = rows(&out.join("tangential_element.csv"));
    assert_eq!(el.len(), 2);
    let get = |r: &Vec<String>, name: &str| -> f64 { r[column(&h, name)].parse().unwrap() };
    let (w_var, w_const) = (last_cycle_energy(&out), last_cycle_energy(&constant));
    for (i, r) in el.iter().enumerate() {
        let bem = get(r, "bem_J_per_m2");
        assert!((bem / w_var[i] - 1.0).abs() < 1e-4, "{bem} vs {}", w_var[i]);
        let bem_c = get(r, "bem_constant_load_J_per_m2");
        assert!(
            (bem_c / w_const[i] - 1.0).abs() < 1e-4,
            "{bem_c} vs {}",
            w_const[i]
        );
        let e = get(r, "element_J_per_m2");
        assert!((get(r, "element_energy_error") - (e / bem - 1.0)).abs() < 1e-5);
        assert!(get(r, "constant_load_fit_R2") > 0.95);
        // The varying load changes the loop by more than the comparison's noise.
        assert!((bem / bem_c - 1.0).abs() > 1e-3, "{bem} {bem_c}");
        // The load-following element: fitted at the cycle's lowest and highest loads (besides
        // the mean), its error the relative difference of its energy; a rough contact stiffens
        // with the load, so E0 grows from the lowest to the highest load.
        let p = get(r, "pressure_Pa");
        assert!((get(r, "load_low_Pa") / (p * (1.0 - ratio)) - 1.0).abs() < 1e-12);
        assert!((get(r, "load_high_Pa") / (p * (1.0 + ratio)) - 1.0).abs() < 1e-12);
        let (e_low, e_mid, e_high) = (
            get(r, "E0_low_N_per_m3"),
            get(r, "E0_N_per_m3"),
            get(r, "E0_high_N_per_m3"),
        );
        assert!(e_low < e_mid && e_mid < e_high, "{e_low} {e_mid} {e_high}");
        let lf = get(r, "load_following_J_per_m2");
        assert!((get(r, "load_following_energy_error") - (lf / bem - 1.0)).abs() < 1e-5);
        assert!(get(r, "load_following_R2") > 0.9);
    }
    for (flags, name) in [
        (
            vec!["--normal-amplitude-ratio", "1.0"],
            "--normal-amplitude-ratio",
        ),
        (
            vec!["--normal-amplitude-ratio", "-0.1"],
            "--normal-amplitude-ratio",
        ),
        (
            vec![
                "--normal-amplitude-ratio",
                "0.3",
                "--normal-phase-deg",
                "nan",
            ],
            "--normal-phase-deg",
        ),
        (
            vec!["--normal-amplitude-ratio", "0.3", "--cycles", "1"],
            "--cycles",
        ),
    ] {
        let bad = dir.path().join("bad");
        let mut args = vec![
            "--grid",
            "128",
            "--pressures-pa",
            "1e6",
            "--out-dir",
            bad.to_str().unwrap(),
        ];
        args.extend(flags.iter().copied());
        let o = contact_tangential(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success() && err.contains(name),
            "{flags:?}: {err}"
        );
        assert!(!bad.join("tangential_loops.csv").exists());
    }
}

/// The driver with the normal solver (`oscillate_with_normal_load`) on a sphere surface: the
/// normal solves replace the sampled Hertz pressure, and the energy of `r = 0.2`,
/// `T* = 0.5 μP0`, 90°, is the peer's within 1.5 %, as the sampled-pressure run's (measured
/// −0.65 %). A hardness no pressure reaches gives
/// the elastic result bit for bit; one that binds flattens the sphere at the largest load
/// (plastic area > 0) and changes the energy.
#[test]
fn normal_solver_driver_on_a_sphere() {
    use asperity::contact::normal::{NormalOptions, NormalProblem};
    use asperity::contact::tangential::varying_load::{oscillate_with_normal_load, TangentialSide};
    let (ratio, t_amp, phase) = (0.2, 0.5 * MU * P0, 90.0);
    let a_min = Hertz::new(R, P0 * (1.0 - ratio), e_star()).radius;
    let dx = 2.0 * a_min / 44.0;
    let n = 128;
    let c = (n / 2) as f64;
    let heights = Array2::from_shape_fn((n, n), |(i, j)| {
        let (x, y) = ((i as f64 - c) * dx, (j as f64 - c) * dx);
        -(x * x + y * y) / (2.0 * R)
    });
    let surface = asperity::Grid2::new(heights, dx, dx, false).unwrap();
    let area = surface.area();
    let history = VaryingLoadHistory {
        tangential_amplitude: Control::Force([t_amp, 0.0]),
        normal: NormalLoadOscillation {
            mean_pressure_pa: P0 / area,
            amplitude_ratio: ratio,
            phase_rad: phase * PI / 180.0,
        },
        cycles: 2,
        steps_per_cycle: 40,
    };
    let run = |hardness: Option<f64>| {
        oscillate_with_normal_load(
            &NormalProblem {
                surface: &surface,
                e_star_pa: e_star(),
                hardness_pa: hardness,
            },
            NormalOptions::default(),
            &TangentialSide {
                friction_coefficient: MU,
                body1: material(),
                body2: material(),
                options: TangentialOptions {
                    tolerance: 1e-8,
                    ..TangentialOptions::default()
                },
            },
            &history,
            |_, _| {},
        )
        .unwrap()
    };
    let elastic = run(None);
    let w_peer = {
        let a_max = Hertz::new(R, P0 * (1.0 + ratio), e_star()).radius;
        let mut mdr = Mdr::new(1.2 * a_max, 40_000);
        let mut peer = vec![(0.0, 0.0)];
        for k in 1..=80 {
            let theta = 2.0 * PI * k as f64 / 40.0;
            let p = P0 * (1.0 + ratio * (theta + phase * PI / 180.0).sin());
            let t = if k % 20 == 0 {
                0.0
            } else {
                t_amp * theta.sin()
            };
            peer.push((mdr.step(p, t), t));
        }
        loop_area(&peer[40..])
    };
    let w = elastic.cycles[1].dissipated_j;
    eprintln!(
        "normal solver: W = {w:.5e} J, peer {w_peer:.5e} J ({:+.3} %)",
        100.0 * (w / w_peer - 1.0)
    );
    assert!((w / w_peer - 1.0).abs() < 0.015);
    for (k, st) in elastic.steps.iter().enumerate() {
        let want = P0 * history.normal.pressure_at(2.0 * PI * k as f64 / 40.0)
            / history.normal.mean_pressure_pa;
        assert!((st.normal_force_n / want - 1.0).abs() < 1e-6);
    }
    let unreached = run(Some(1e12));
    assert_eq!(unreached.cycles, elastic.cycles);
    assert_eq!(unreached.normal.plastic_area_ratio, Some(0.0));
    // H at 70 % of the Hertz peak pressure of the largest load.
    let h = 0.7 * Hertz::new(R, P0 * (1.0 + ratio), e_star()).peak_pressure;
    let plastic = run(Some(h));
    assert!(plastic.normal.plastic_area_ratio.unwrap() > 0.0);
    assert!(plastic.normal.plastic_volume_m3.unwrap() > 0.0);
    let wp = plastic.cycles[1].dissipated_j;
    eprintln!("H = 0.7 p0: W = {wp:.5e} J");
    assert!((wp / w - 1.0).abs() > 0.01);
}
