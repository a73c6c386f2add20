//! Stability of forced-response points by Hill's method (`asperity::dynamics::stability`)
//! against independent references:
//!
//! 1. the Duffing oscillator at one harmonic: the branch between the two folds is unstable and
//!    the rest stable, point by point against the sign of the first-harmonic closed form's
//!    `∂G/∂A²`, and the folds' frequencies against the zeros of the discriminant of its cubic
//!    in `A²`;
//! 2. Hill against Floquet: the monodromy matrix of the Duffing oscillator's variational
//!    equation, integrated over one period by RK4 about the harmonic-balance solution, has the
//!    multipliers `e^{T·s}` of Hill's exponents; and the receptance formulation gives the same
//!    exponents as the coordinates one;
//! 3. a Jenkins friction oscillator swept from stick to gross slip through `asperity response`
//!    is stable everywhere with no bifurcation (its describing function has no fold at these
//!    levels), and the CSV and JSON carry the verdict.

use asperity::dynamics::aft::Harmonics;
use asperity::dynamics::continuation::{sweep, ContinuationSettings};
use asperity::dynamics::hbm::{Excitation, FormulationChoice, HbmPoint, HbmSystem};
use asperity::dynamics::model::Structure;
use asperity::dynamics::report::{plot_frf_family, summarise};
use asperity::dynamics::stability::{branch_stability, BifurcationKind, HillAnalysis};
use asperity::element::cubic::CubicSpring;
use nalgebra::{Complex, DMatrix, DVector, Matrix2};
use std::f64::consts::PI;
use std::path::Path;
use std::process::Command;
use std::sync::Arc;

const TWO_PI: f64 = 2.0 * PI;

/// The Duffing oscillator `m·ẍ + c·ẋ + k·x + k3·x³ = F·cos ωt` of the harmonic-balance
/// validation (10 Hz, ζ = 1 %, hardening, F = 0.79 N: a fold of about 12 % in frequency).
struct Duffing {
    m: f64,
    c: f64,
    k: f64,
    k3: f64,
    force: f64,
}

const DUFFING: Duffing = Duffing {
    m: 1.0,
    c: 2.0 * 0.01 * TWO_PI * 10.0,
    k: (TWO_PI * 10.0) * (TWO_PI * 10.0),
    k3: 1.05e7,
    force: 0.79,
};

impl Duffing {
    fn structure(&self) -> Structure {
        let mut s = Structure::lumped(
            vec!["x".into()],
            DMatrix::from_element(1, 1, self.m),
            DMatrix::from_element(1, 1, self.c),
            DMatrix::from_element(1, 1, self.k),
        )
        .unwrap();
        s.attach(
            "duffing",
            Arc::new(CubicSpring { k3: self.k3 }),
            DMatrix::from_element(1, 1, 1.0),
        )
        .unwrap();
        s
    }

    /// Coefficients of the first-harmonic closed form `G(u, ω) = u·[(κ + ¾k3·u)² + (cω)²] − F²`,
    /// `u = A²`, `κ = k − mω²` (Nayfeh & Mook, *Nonlinear Oscillations*, 1979, §4.1), as the
    /// cubic `c3·u³ + c2·u² + c1·u + c0`.
    fn cubic(&self, w: f64) -> [f64; 4] {
        let kappa = self.k - self.m * w * w;
        let g = self.c * w;
        [
            9.0 / 16.0 * self.k3 * self.k3,
            1.5 * self.k3 * kappa,
            kappa * kappa + g * g,
            -self.force * self.force,
        ]
    }

    /// `∂G/∂u = (κ + ¾k3·u)(κ + 9/4·k3·u) + (cω)²`: the determinant of the slow flow's
    /// Jacobian up to a positive factor; negative on the unstable middle branch.
    fn dg_du(&self, u: f64, w: f64) -> f64 {
        let kappa = self.k - self.m * w * w;
        (kappa + 0.75 * self.k3 * u) * (kappa + 2.25 * self.k3 * u) + (self.c * w).powi(2)
    }

    /// The two fold frequencies (rad/s) of the first-harmonic response: where the cubic in
    /// `u` has a double root, i.e. its discriminant vanishes (bisection from a scan).
    fn folds(&self, lo: f64, hi: f64) -> Vec<f64> {
        let disc = |w: f64| {
            let [a, b, c, d] = self.cubic(w);
            18.0 * a * b * c * d - 4.0 * b.powi(3) * d + b * b * c * c
                - 4.0 * a * c.powi(3)
                - 27.0 * a * a * d * d
        };
        let n = 4000;
        let x = |i: usize| lo + (hi - lo) * i as f64 / n as f64;
        let mut out = Vec::new();
        for i in 0..n {
            let (a, b) = (x(i), x(i + 1));
            if disc(a) * disc(b) < 0.0 {
                let (mut l, mut h) = (a, b);
                for _ in 0..200 {
                    let mid = 0.5 * (l + h);
                    if disc(l) * disc(mid) <= 0.0 {
                        h = mid;
                    } else {
                        l = mid;
                    }
                }
                out.push(0.5 * (l + h));
            }
        }
        out
    }
}

fn system<'a>(s: &'a Structure, harmonics: usize, samples: usize) -> HbmSystem<'a> {
    let mut sys = HbmSystem::new(
        s,
        Harmonics::new(harmonics, true, Some(samples)).unwrap(),
        Excitation {
            force: DVector::from_fn(s.n(), |r, _| if r == 0 { 1.0 } else { 0.0 }),
            harmonic: 1,
            force_sin: None,
        },
        FormulationChoice::Auto,
    )
    .unwrap();
    sys.newton.tolerance = 1e-12;
    sys
}

/// (1) One harmonic: every point's verdict equals the closed form's (unstable exactly where
/// `∂G/∂A² < 0`, points within 1e-3 of its scale of a fold left out), there are exactly two
/// bifurcations, both folds with an exponent crossing, at the closed form's fold frequencies
/// within 1e-4 (measured: 1e-11 where the crossing is located on the branch, 5.6e-5 where the
/// located solves do not converge and the turning point's parabola through three points
/// stands).
#[test]
fn duffing_branch_between_the_folds_is_unstable() {
    let d = DUFFING;
    let s = d.structure();
    let sys = system(&s, 1, 16);
    let mut settings = ContinuationSettings::new(8.0, 14.0);
    settings.points = 100;
    let b = sweep(&sys, d.force, &settings, &mut |_| {}).unwrap();
    assert_eq!(b.turning_points, 2);
    let st = branch_stability(&sys, &b).unwrap();
    let (mut unstable, mut checked) = (0, 0);
    for (p, v) in b.points.iter().zip(&st.points) {
        let u = p.z[0].powi(2) + p.z[1].powi(2);
        let g = d.dg_du(u, p.omega);
        let scale = (d.c * p.omega).powi(2) + (d.k - d.m * p.omega.powi(2)).powi(2);
        assert!(v.schur_residual < 1e-12, "{}", v.schur_residual);
        if g.abs() < 1e-3 * scale {
            continue;
        }
        checked += 1;
        assert_eq!(
            v.stable,
            g > 0.0,
            "{:.5} Hz, A = {:.4e}: Hill {:?}, ∂G/∂u = {g:e}",
            p.omega / TWO_PI,
            u.sqrt(),
            v.exponents
        );
        unstable += usize::from(!v.stable);
    }
    eprintln!(
        "{} points, {checked} checked against the closed form, {unstable} unstable",
        b.points.len()
    );
    assert!(unstable >= 5, "{unstable} unstable points");
    // The FRF plot draws the unstable piece dashed (its drawing must not fail).
    let row = DVector::from_element(1, 1.0);
    let mut level = summarise(&sys, d.force, b.clone(), &row);
    level.stability = Some(st.clone());
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("frf.png");
    plot_frf_family(&png, &sys, "x", &row, &[level], true).unwrap();
    assert!(std::fs::metadata(&png).unwrap().len() > 1000);
    let folds = d.folds(TWO_PI * 8.0, TWO_PI * 14.0);
    assert_eq!(folds.len(), 2, "{folds:?}");
    assert_eq!(st.bifurcations.len(), 2, "{:?}", st.bifurcations);
    for bif in &st.bifurcations {
        assert_eq!(bif.kind, BifurcationKind::Fold);
        assert!(bif.exponent_crossing);
        let f = bif.frequency_hz;
        let exact = folds
            .iter()
            .map(|w| w / TWO_PI)
            .min_by(|a, b| (a - f).abs().total_cmp(&(b - f).abs()))
            .unwrap();
        eprintln!(
            "fold at {f:.6} Hz, closed form {exact:.6} Hz: {:+.2e}",
            f / exact - 1.0
        );
        assert!((f / exact - 1.0).abs() < 1e-4, "{f} vs {exact}");
    }
}

/// The periodic solution's displacement at time `t` from its odd harmonics.
fn displacement(p: &HbmPoint, orders: &[usize], t: f64) -> f64 {
    orders
        .iter()
        .enumerate()
        .map(|(i, &k)| {
            let (sn, cs) = (k as f64 * p.omega * t).sin_cos();
            p.z[2 * i] * cs + p.z[2 * i + 1] * sn
        })
        .sum()
}

/// Monodromy matrix of the variational equation `δẍ + (c/m)·δẋ + (k + 3k3·x(t)²)/m·δx = 0`
/// about the periodic solution, by the classical fourth-order Runge–Kutta method with `steps`
/// steps over one period.
fn monodromy(d: &Duffing, p: &HbmPoint, orders: &[usize], steps: usize) -> Matrix2<f64> {
    let period = TWO_PI / p.omega;
    let h = period / steps as f64;
    let a = |t: f64| {
        let x = displacement(p, orders, t);
        Matrix2::new(0.0, 1.0, -(d.k + 3.0 * d.k3 * x * x) / d.m, -d.c / d.m)
    };
    let mut phi = Matrix2::identity();
    for i in 0..steps {
        let t = i as f64 * h;
        let k1 = a(t) * phi;
        let k2 = a(t + 0.5 * h) * (phi + k1 * (0.5 * h));
        let k3 = a(t + 0.5 * h) * (phi + k2 * (0.5 * h));
        let k4 = a(t + h) * (phi + k3 * h);
        phi += (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (h / 6.0);
    }
    phi
}

/// (2) Seven odd harmonics: at every fifth point of the branch (stable and unstable) the Floquet
/// multipliers of the RK4 monodromy matrix (4000 steps per period) and `e^{T·s}` of Hill's two
/// exponents agree within 1e-8 of the larger multiplier's magnitude (measured 2.1e-12), and
/// the points Floquet calls unstable (`|μ| > 1`) are the ones Hill calls unstable.
#[test]
fn hill_exponents_agree_with_floquet_multipliers_of_the_monodromy_matrix() {
    let d = DUFFING;
    let s = d.structure();
    let sys = system(&s, 7, 64);
    let orders = sys.harmonics.orders().to_vec();
    let mut settings = ContinuationSettings::new(8.0, 14.0);
    settings.points = 60;
    let b = sweep(&sys, d.force, &settings, &mut |_| {}).unwrap();
    let hill = HillAnalysis::new(&sys).unwrap();
    let (mut worst, mut unstable, mut compared) = (0.0f64, 0, 0);
    for p in b.points.iter().step_by(5) {
        let st = hill.point(p).unwrap();
        let phi = monodromy(&d, p, &orders, 4000);
        let mut floquet: Vec<Complex<f64>> = phi.complex_eigenvalues().iter().copied().collect();
        let mut from_hill = st.multipliers();
        assert_eq!(from_hill.len(), 2);
        let key = |a: &Complex<f64>, b: &Complex<f64>| {
            b.norm().total_cmp(&a.norm()).then(b.im.total_cmp(&a.im))
        };
        floquet.sort_by(key);
        from_hill.sort_by(key);
        let scale = floquet[0].norm();
        let err = floquet
            .iter()
            .zip(&from_hill)
            .map(|(a, b)| (a - b).norm() / scale)
            .fold(0.0, f64::max);
        worst = worst.max(err);
        compared += 1;
        let floquet_unstable = floquet[0].norm() > 1.0 + 1e-9;
        assert_eq!(
            floquet_unstable,
            !st.stable,
            "{:.5} Hz: Floquet {floquet:?}, Hill {from_hill:?}",
            p.omega / TWO_PI
        );
        unstable += usize::from(floquet_unstable);
        assert!(
            err < 1e-8,
            "{:.5} Hz: Floquet {floquet:?}, Hill {from_hill:?}",
            p.omega / TWO_PI
        );
    }
    eprintln!("{compared} points ({unstable} unstable): largest multiplier difference {worst:.2e}");
    assert!(unstable >= 1 && unstable < compared);
}

/// (2) The receptance formulation's points are assessed on the full model: a two-mass chain
/// with the cubic spring on the first mass (one contact DOF, so `Auto` condenses onto it) gives
/// the exponents of the coordinates formulation at the same frequency and level to 1e-8.
#[test]
fn receptance_and_coordinates_formulations_give_the_same_exponents() {
    let d = DUFFING;
    let mut s = Structure::lumped(
        vec!["a".into(), "b".into()],
        DMatrix::from_diagonal(&DVector::from_vec(vec![1.0, 0.3])),
        DMatrix::from_row_slice(2, 2, &[1.5, -0.2, -0.2, 0.4]),
        DMatrix::from_row_slice(2, 2, &[d.k + 2e3, -2e3, -2e3, 2e3]),
    )
    .unwrap();
    s.attach(
        "duffing",
        Arc::new(CubicSpring { k3: d.k3 }),
        DMatrix::from_row_slice(1, 2, &[1.0, 0.0]),
    )
    .unwrap();
    let condensed = system(&s, 5, 64);
    assert_eq!(
        condensed.formulation(),
        asperity::dynamics::hbm::Formulation::Receptance
    );
    let mut full = HbmSystem::new(
        &s,
        condensed.harmonics.clone(),
        condensed.excitation.clone(),
        FormulationChoice::Coordinates,
    )
    .unwrap();
    full.newton.tolerance = 1e-12;
    for f in [9.0, 11.0, 12.5] {
        let w = TWO_PI * f;
        let pc = condensed.solve(w, d.force, None).unwrap();
        let pf = full.solve(w, d.force, None).unwrap();
        let a = HillAnalysis::new(&condensed).unwrap().point(&pc).unwrap();
        let b = HillAnalysis::new(&full).unwrap().point(&pf).unwrap();
        assert_eq!(a.exponents.len(), 4);
        let scale = b.exponents.iter().map(|e| e.norm()).fold(0.0, f64::max);
        for (x, y) in a.exponents.iter().zip(&b.exponents) {
            assert!((x - y).norm() < 1e-8 * scale, "{f} Hz: {x} vs {y}");
        }
    }
}

fn write(dir: &Path, name: &str, text: &str) {
    std::fs::write(dir.join(name), text).unwrap();
}

/// (3) The Jenkins oscillator of `tests/response_nonsmooth.rs` (`m = 1 kg, c = 1 N·s/m,
/// k = 1e4 N/m`, Jenkins to ground `kt = 1e4 N/m`, slip force 1 N) at 0.01 N (stuck), 0.05 and
/// 0.2 N (partial slip) and 2 N (gross slip), three harmonics: friction only adds dissipation and
/// the describing function has no fold here, so every point is stable, no bifurcation is named,
/// and the CSV's `stable` column is 1 throughout with a negative largest real part.
#[test]
fn jenkins_oscillator_is_stable_everywhere() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(d, "mass.csv", "# unit: kg\nm.x\n1.0\n");
    write(d, "stiffness.csv", "# unit: N/m\nm.x\n1e4\n");
    write(d, "damping.csv", "# unit: N*s/m\nm.x\n1.0\n");
    write(
        d,
        "elements.csv",
        "# units: N0_N in N; kn, E0, Et in N/m\n\
         id,x_m,y_m,area_m2,pressure_Pa,N0_N,kn_N_per_m,E0_N_per_m,k,mu,Et_N_per_m,out_of_range\n\
         1,0,0,1e-6,1e6,1.0,1e6,1e4,0,1.0,0,0\n",
    );
    write(d, "pairs.csv", "element_id,node_a,node_b\n1,m,ground\n");
    write(
        d,
        "model.toml",
        "[linear]\nmass = \"mass.csv\"\ndamping = \"damping.csv\"\nstiffness = \"stiffness.csv\"\n\n\
         [[contact]]\nelements = \"elements.csv\"\nlaw = \"jenkins\"\npairs = \"pairs.csv\"\n\
         normal = [0.0, 0.0, 1.0]\ntangent = [1.0, 0.0, 0.0]\n\n\
         [excitation]\ndofs = [\"m.x\"]\nlevels_n = [0.01, 0.05, 0.2, 2.0]\n\n\
         [response]\ndofs = [\"m.x\"]\n\n\
         [sweep]\nfrequency_start_hz = 10\nfrequency_end_hz = 30\nharmonics = 3\n",
    );
    let out = d.join("out");
    let o = Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args([
            "response",
            d.join("model.toml").to_str().unwrap(),
            "--out-dir",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("response.json")).unwrap()).unwrap();
    for (i, l) in json["summary"]["levels"]
        .as_array()
        .unwrap()
        .iter()
        .enumerate()
    {
        let st = &l["stability"];
        assert_eq!(st["unstable_points"], 0, "level {}: {st}", i + 1);
        assert_eq!(st["bifurcations"].as_array().unwrap().len(), 0, "{st}");
        let csv =
            std::fs::read_to_string(out.join(format!("response_level_{}.csv", i + 1))).unwrap();
        let mut lines = csv.lines().filter(|l| !l.starts_with('#'));
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
        let (cs, cr) = (col("stable"), col("floquet_max_real_part_per_s"));
        let mut rows = 0;
        for line in lines {
            let v: Vec<&str> = line.split(',').collect();
            assert_eq!(v[cs], "1", "level {}: {line}", i + 1);
            let re: f64 = v[cr].parse().unwrap();
            assert!(re < 0.0, "level {}: {line}", i + 1);
            rows += 1;
        }
        assert!(rows > 50, "{rows} rows");
    }
}
