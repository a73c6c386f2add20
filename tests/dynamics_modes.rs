//! Nonlinear modes by the extended periodic motion concept (src/dynamics/nonlinear_modes.rs)
//! against closed forms: the Duffing oscillator's backbone (first-harmonic and exact, by the
//! Jacobi elliptic solution) and the Jenkins oscillator's describing function (Caughey 1960).

use asperity::dynamics::aft::Harmonics;
use asperity::dynamics::continuation::{sweep_partial, ContinuationSettings};
use asperity::dynamics::hbm::{Excitation, FormulationChoice, HbmSystem};
use asperity::dynamics::model::Structure;
use asperity::dynamics::modes::synthesise;
use asperity::dynamics::nonlinear_modes::{log_spaced, nonlinear_mode, ModeSettings};
use asperity::dynamics::report;
use asperity::element::{CubicSpring, HystereticElement, Jenkins};
use nalgebra::{DMatrix, DVector};
use std::f64::consts::PI;
use std::sync::Arc;

/// One mass `m` on a spring `k` and a dashpot `c` to ground, with `element` in parallel.
fn oscillator(m: f64, c: f64, k: f64, element: Arc<dyn HystereticElement>) -> Structure {
    let one = |v: f64| DMatrix::from_element(1, 1, v);
    let mut s = Structure::lumped(vec!["mass.x".into()], one(m), one(c), one(k)).unwrap();
    s.attach("element", element, one(1.0)).unwrap();
    s
}

fn system(s: &Structure, harmonics: Harmonics) -> HbmSystem<'_> {
    HbmSystem::new(
        s,
        harmonics,
        Excitation {
            force: DVector::zeros(s.n()),
            harmonic: 1,
            force_sin: None,
        },
        FormulationChoice::Coordinates,
    )
    .unwrap()
}

/// Complete elliptic integral of the first kind `K(m) = π / (2·AGM(1, √(1 − m)))` (parameter
/// `m = k²`; Abramowitz & Stegun 17.6).
fn elliptic_k(m: f64) -> f64 {
    let (mut a, mut b) = (1.0f64, (1.0 - m).sqrt());
    // Quadratic convergence: a handful of iterations reach rounding (a fixed count, since the
    // last bit of a and b may alternate forever).
    for _ in 0..40 {
        (a, b) = (0.5 * (a + b), (a * b).sqrt());
    }
    PI / (2.0 * a)
}

/// The conservative Duffing oscillator `ẍ + ω0²x + εx³ = 0` of peak displacement `X`:
/// `x = X·cn(Ωt, μ)`, `Ω² = ω0² + εX²`, `μ = εX²/(2Ω²)`, so its angular frequency is
/// `πΩ/(2K(μ))`; the Fourier series of cn (A&S 16.23.2) gives the amplitude of harmonic
/// `2j+1`: `X·(2π/(√μ·K))·q^{j+½}/(1 + q^{2j+1})`, nome `q = exp(−πK(1−μ)/K(μ))`.
/// Returns `(ω, [A1, A3, A5])`.
fn duffing_exact(omega0: f64, eps: f64, x: f64) -> (f64, [f64; 3]) {
    let big = (omega0 * omega0 + eps * x * x).sqrt();
    let mu = eps * x * x / (2.0 * big * big);
    let k = elliptic_k(mu);
    let q = (-PI * elliptic_k(1.0 - mu) / k).exp();
    let coefficient = |j: i32| {
        let p = j as f64 + 0.5;
        x * 2.0 * PI / (mu.sqrt() * k) * q.powf(p) / (1.0 + q.powf(2.0 * p))
    };
    (
        PI * big / (2.0 * k),
        [coefficient(0), coefficient(1), coefficient(2)],
    )
}

/// Peak displacement `X` whose first harmonic is `a1` (bisection; `A1(X)` increases with `X`).
fn duffing_peak_for_first_harmonic(omega0: f64, eps: f64, a1: f64) -> f64 {
    let (mut lo, mut hi) = (a1, 1.5 * a1);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if duffing_exact(omega0, eps, mid).1[0] < a1 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Duffing oscillator `mẍ + cẋ + kx + k3x³ = 0`: at the first harmonic the EPMC backbone is
/// `ω² = k/m + (3/4)(k3/m)X²` exactly (X = a/√m the physical amplitude of the mass-normalised
/// modal amplitude a); at harmonics 0..7 the frequency and the first, third and fifth harmonics
/// are those of the exact periodic orbit (elliptic functions) within 1e-6 (measured: 6e-11 in
/// frequency and 8e-10 of A1 in the fifth harmonic at ω/ω0 = 1.6; the truncation of the cn series
/// after the seventh harmonic is of order q⁴ ≈ 1e-8 there); and, the nonlinearity
/// being conservative, the self-excitation is the linear `ξ = c/m` at every amplitude (so the
/// modal damping ratio is `ζ = c/(2mω)`, equal to the linear `c/(2√(km))` at the linear
/// frequency). Amplitudes up to a frequency ratio ω/ω0 ≈ 1.6.
#[test]
fn duffing_backbone_matches_the_closed_forms() {
    let (m, c, k, k3): (f64, f64, f64, f64) = (2.0, 3.0, 8.0e4, 4.0e10);
    let omega0 = (k / m).sqrt();
    let eps = k3 / m;
    let s = oscillator(m, c, k, Arc::new(CubicSpring { k3 }));
    // εX² from 2e-4·ω0² to 2·ω0²: X from 2e-5 m to 2.2e-3 m.
    let amplitudes = log_spaced(2e-5 * m.sqrt(), 2e-3 * m.sqrt(), 12).unwrap();

    // A conservative nonlinearity is smooth: Newton converges quadratically, to a tolerance
    // well below the default's.
    let settings = ModeSettings {
        tolerance: 1e-11,
        ..ModeSettings::new(1, amplitudes.clone())
    };
    let h1 = system(&s, Harmonics::new(1, true, Some(32)).unwrap());
    let mode = nonlinear_mode(&h1, settings.clone(), &mut |_| {}).unwrap();
    assert!(mode.stopped.is_none(), "{:?}", mode.stopped);
    assert_eq!(mode.points.len(), amplitudes.len());
    assert!((mode.linear.omega / omega0 - 1.0).abs() < 1e-12);
    assert!((mode.linear.damping_ratio() - c / (2.0 * (k * m).sqrt())).abs() < 1e-12);
    for p in &mode.points {
        let x = p.amplitude / m.sqrt();
        let exact = (omega0 * omega0 + 0.75 * eps * x * x).sqrt();
        assert!(
            (p.omega / exact - 1.0).abs() < 1e-8,
            "H1, X = {x:e} m: ω = {} rad/s, first-harmonic backbone {exact}",
            p.omega
        );
        assert!(
            (p.xi / (c / m) - 1.0).abs() < 1e-8,
            "H1, X = {x:e} m: ξ = {} 1/s, c/m = {}",
            p.xi,
            c / m
        );
        assert!((p.damping_ratio() - c / (2.0 * m * p.omega)).abs() < 1e-8 * p.damping_ratio());
        // A cubic spring dissipates nothing.
        assert!(p.element_energy_j().abs() < 1e-9 * p.self_excitation_energy_j);
    }
    let last = mode.points.last().unwrap();
    assert!(
        last.omega / omega0 > 1.5,
        "the amplitudes reach the strongly nonlinear range (ω/ω0 = {})",
        last.omega / omega0
    );

    let h7 = system(&s, Harmonics::new(7, false, Some(64)).unwrap());
    let mode = nonlinear_mode(&h7, settings, &mut |_| {}).unwrap();
    assert!(mode.stopped.is_none(), "{:?}", mode.stopped);
    let len = h7.harmonics.len();
    for p in &mode.points {
        let a1 = p.amplitude / m.sqrt();
        let x = duffing_peak_for_first_harmonic(omega0, eps, a1);
        let (exact, harmonics) = duffing_exact(omega0, eps, x);
        assert!(
            (p.omega / exact - 1.0).abs() < 1e-6,
            "H7, A1 = {a1:e} m: ω = {} rad/s, exact {exact}",
            p.omega
        );
        assert!(
            (p.xi / (c / m) - 1.0).abs() < 1e-8,
            "H7, A1 = {a1:e} m: ξ = {} 1/s, c/m = {}",
            p.xi,
            c / m
        );
        // Harmonics of the mode shape: cosine terms of the odd harmonics (phase normalisation:
        // no first-harmonic sine term), nothing else.
        for (j, &order) in [1usize, 3, 5].iter().enumerate() {
            let (ci, si) = h7.harmonics.index_of(order).unwrap();
            assert!(
                (p.z[ci] - harmonics[j]).abs() < 1e-6 * a1,
                "H7, A1 = {a1:e} m: harmonic {order} cosine {} m, exact {} m",
                p.z[ci],
                harmonics[j]
            );
            assert!(p.z[si].abs() < 1e-8 * a1);
        }
        // The mean (first coefficient) and the even harmonics vanish by symmetry.
        assert!(p.z[0].abs() < 1e-8 * a1, "mean {} m", p.z[0]);
        for order in [2usize, 4, 6] {
            let (ci, si) = h7.harmonics.index_of(order).unwrap();
            assert!(p.z[ci].abs() < 1e-8 * a1 && p.z[si].abs() < 1e-8 * a1);
        }
        assert_eq!(p.z.len(), len);
    }
}

/// Jenkins oscillator: mass `m`, dashpot `c`, spring `k` and a Jenkins element (stiffness `kt`,
/// slip force `Fs`) to ground. At the first harmonic, for a displacement `X·cos θ` with
/// `X > Fs/kt`, the element's force has the describing-function coefficients (Caughey,
/// *J. Appl. Mech.* 27 (1960) 640; the hysteresis loop of the bilinear element):
///
/// * in phase: `K_eq = (kt/π)(β − sin 2β / 2)`, `cos β = 1 − 2Fs/(kt X)` (β: the phase from a
///   reversal to the slip onset),
/// * in quadrature: `h = W/(πX²) = (4Fs/(πX))(1 − Fs/(kt X))`, `W = 4Fs(X − Fs/kt)` the loop
///   area,
///
/// so that the EPMC balance `(k + K_eq − mω²)X = 0`, `((c − ξm)ω + h)X = 0` gives
/// `ω² = (k + K_eq)/m`, `ξ = (c + h/ω)/m`, `ζ = ξ/(2ω)`; in stick `K_eq = kt`, `h = 0`.
/// Checked within 1e-5 (frequency and damping ratio; measured ≤ 1.2e-6, the AFT's sampling of
/// the loop's corners) from stick through microslip to gross slip, with 2048 AFT samples; the
/// element energy against `W` and the energy balance `Σ W_e = W_ξ − W_C` within 1e-5.
#[test]
fn jenkins_backbone_matches_the_describing_function() {
    let (m, c, k): (f64, f64, f64) = (0.5, 2.0, 2.0e5);
    let (kt, fs) = (3.0e5, 3.0);
    let x_slip = fs / kt; // 1e-5 m
    let s = oscillator(m, c, k, Arc::new(Jenkins::new(kt, fs).unwrap()));
    let sys = system(&s, Harmonics::new(1, true, Some(2048)).unwrap());
    // Physical amplitudes from 0.3 to 300 times the slip onset.
    let amplitudes = log_spaced(0.3 * x_slip * m.sqrt(), 300.0 * x_slip * m.sqrt(), 16).unwrap();
    let mode = nonlinear_mode(&sys, ModeSettings::new(1, amplitudes.clone()), &mut |_| {}).unwrap();
    assert!(mode.stopped.is_none(), "{:?}", mode.stopped);
    assert_eq!(mode.points.len(), amplitudes.len());
    assert!((mode.linear.omega / ((k + kt) / m).sqrt() - 1.0).abs() < 1e-10);
    let mut slipping = 0;
    for p in &mode.points {
        let x = p.amplitude / m.sqrt();
        let (k_eq, h) = if x <= x_slip {
            (kt, 0.0)
        } else {
            slipping += 1;
            let beta = (1.0 - 2.0 * fs / (kt * x)).acos();
            (
                kt / PI * (beta - (2.0 * beta).sin() / 2.0),
                4.0 * fs / (PI * x) * (1.0 - fs / (kt * x)),
            )
        };
        let omega = ((k + k_eq) / m).sqrt();
        let zeta = (c + h / omega) / m / (2.0 * omega);
        assert!(
            (p.omega / omega - 1.0).abs() < 1e-5,
            "X = {x:e} m: {} Hz, describing function {} Hz",
            p.frequency_hz(),
            omega / (2.0 * PI)
        );
        assert!(
            (p.damping_ratio() / zeta - 1.0).abs() < 1e-5,
            "X = {x:e} m: ζ = {}, describing function {zeta}",
            p.damping_ratio()
        );
        let w = if x <= x_slip {
            0.0
        } else {
            4.0 * fs * (x - x_slip)
        };
        let e = p.element_energy_j();
        assert!(
            (e - w).abs() <= 1e-5 * w.max(1e-3 * fs * x_slip),
            "X = {x:e} m: element energy {e:e} J, loop area {w:e} J"
        );
        assert!(
            p.energy_balance_error() < 1e-5,
            "X = {x:e} m: energy balance error {}",
            p.energy_balance_error()
        );
    }
    assert!(slipping >= 12, "most amplitudes are beyond the slip onset");
    // Friction softens and damps: frequency falls towards √(k/m) and the damping ratio peaks.
    let first = &mode.points[0];
    let last = mode.points.last().unwrap();
    assert!(last.omega < 0.85 * first.omega);
    let peak_zeta = mode
        .points
        .iter()
        .map(|p| p.damping_ratio())
        .fold(0.0, f64::max);
    assert!(peak_zeta > 5.0 * first.damping_ratio());
}

/// Single-nonlinear-mode synthesis against the full harmonic balance: a two-DOF chain (ground –
/// k1 – m1 – k2 – m2, a Jenkins element from m1 to ground, stiffness-proportional damping,
/// the force on m2), forced at a level whose linear resonance would reach 8 times the slip
/// onset at m1. The peak of the forced response synthesised from the EPMC backbone of mode 1
/// (`(ω² − Ω² + 2iζωΩ)a = φᴴF`, Krack 2015) against the peak of the full first-harmonic
/// balance of both DOFs, swept by continuation: the synthesis neglects the second mode's
/// off-resonant response, of relative size about `2ζ(a)·ω1²/(ω2² − ω1²)·|φ2ᵀF·φ2| / |φ1ᵀF·φ1|`
/// at the peak (≈ 1 % here with ζ ≈ 5 %), hence tolerances of 2 % on the amplitude and 0.5 % on the
/// frequency; a linear tolerance check (the same model without the joint slipping, Fs → ∞)
/// would not distinguish friction damping, so the peak must also lie well below the linear one.
/// Measured: +0.12 % in frequency, −0.3 % in amplitude, the peak at 16 % of the linear one.
#[test]
fn single_mode_synthesis_matches_the_full_forced_response() {
    let (m1, m2, k1, k2): (f64, f64, f64, f64) = (1.0, 0.5, 1.0e5, 5.0e4);
    let (kt, fs) = (5.0e4, 0.5);
    let x_slip = fs / kt;
    let beta = 4e-5;
    let mass = DMatrix::from_row_slice(2, 2, &[m1, 0.0, 0.0, m2]);
    let stiffness = DMatrix::from_row_slice(2, 2, &[k1 + k2, -k2, -k2, k2]);
    let mut s = Structure::lumped(
        vec!["m1.x".into(), "m2.x".into()],
        mass,
        &stiffness * beta,
        stiffness,
    )
    .unwrap();
    s.attach(
        "joint",
        Arc::new(Jenkins::new(kt, fs).unwrap()),
        DMatrix::from_row_slice(1, 2, &[1.0, 0.0]),
    )
    .unwrap();
    let force = DVector::from_vec(vec![0.0, 1.0]);
    let harmonics = Harmonics::new(1, true, Some(1024)).unwrap();
    let modal = system(&s, harmonics.clone());
    let linear = asperity::dynamics::nonlinear_modes::linear_mode(&modal, 1).unwrap();
    // Level of a linear resonance at 8 slip onsets at m1.
    let a_lin = 8.0 * x_slip / linear.shape[0].abs();
    let level = a_lin * 2.0 * linear.damping_ratio() * linear.omega.powi(2)
        / linear.shape.dot(&force).abs();
    let amplitudes = log_spaced(0.05 * a_lin, a_lin, 60).unwrap();
    let mode = nonlinear_mode(&modal, ModeSettings::new(1, amplitudes), &mut |_| {}).unwrap();
    assert!(mode.stopped.is_none(), "{:?}", mode.stopped);
    let (curve, peak) = synthesise(&mode, &harmonics, &force, level);
    let peak = peak.expect("the backbone reaches the synthesised peak");
    assert!(!curve.is_empty());
    let row2 = DVector::from_vec(vec![0.0, 1.0]);
    let synth_amplitude = peak.response_amplitude(&mode, &harmonics, &row2);

    let forced = HbmSystem::new(
        &s,
        harmonics,
        Excitation {
            force,
            harmonic: 1,
            force_sin: None,
        },
        FormulationChoice::Coordinates,
    )
    .unwrap();
    let f0 = linear.frequency_hz();
    let mut settings = ContinuationSettings::new(0.85 * f0, 1.05 * f0);
    settings.points = 60;
    let branch = sweep_partial(&forced, level, &settings, &mut |_| {}).unwrap();
    assert!(branch.stopped.is_none(), "{:?}", branch.stopped);
    let full = report::summarise(&forced, level, branch, &row2).interpolated_peak;
    assert!(!full.at_sweep_end);
    let linear_peak_m2 = a_lin * linear.shape[1].abs();
    assert!(
        full.amplitude_m < 0.7 * linear_peak_m2,
        "friction damps the peak: {} m against the linear {linear_peak_m2} m",
        full.amplitude_m
    );
    let (df, da) = (
        peak.omega / (2.0 * PI) / full.frequency_hz - 1.0,
        synth_amplitude / full.amplitude_m - 1.0,
    );
    eprintln!(
        "synthesis against the full balance: frequency {df:+.2e}, amplitude {da:+.2e} (peak {} m, linear {linear_peak_m2} m)",
        full.amplitude_m
    );
    assert!(
        df.abs() < 5e-3 && da.abs() < 2e-2,
        "synthesis {} Hz, {synth_amplitude:e} m; full harmonic balance {} Hz, {:e} m",
        peak.omega / (2.0 * PI),
        full.frequency_hz,
        full.amplitude_m
    );
}

/// Bad settings are refused with the parameter named.
#[test]
fn bad_settings_name_the_parameter() {
    let s = oscillator(1.0, 1.0, 1e4, Arc::new(CubicSpring { k3: 1e8 }));
    let sys = system(&s, Harmonics::new(3, true, Some(32)).unwrap());
    for (settings, name) in [
        (ModeSettings::new(2, vec![1e-3]), "mode"),
        (ModeSettings::new(0, vec![1e-3]), "mode"),
        (ModeSettings::new(1, vec![]), "amplitudes"),
        (ModeSettings::new(1, vec![1e-3, -1.0]), "amplitudes"),
        (ModeSettings::new(1, vec![2e-3, 1e-3]), "amplitudes"),
    ] {
        let e = nonlinear_mode(&sys, settings, &mut |_| {}).unwrap_err();
        assert!(e.to_string().contains(name), "{e}");
    }
    assert!(log_spaced(1e-3, 1e-4, 10)
        .unwrap_err()
        .to_string()
        .contains("amplitude_max"));
}
