//! Normal contact solver (Polonsky–Keer) against closed-form solutions.
//! References: /work/shared/data/contact/REFERENCES.md (Hertz; Westergaard wavy surface).
//! Units: SI (m, Pa, N).

use asperity::contact::analytic::Hertz;
use asperity::contact::normal::{NormalOptions, NormalProblem, NormalSolver};
use asperity::Grid2;
use ndarray::Array2;
use std::f64::consts::PI;

fn solver(surface: &Grid2, e_star: f64) -> NormalSolver {
    NormalSolver::new(
        &NormalProblem {
            surface,
            e_star_pa: e_star,
        },
        NormalOptions::default(),
    )
    .unwrap()
}

/// Hertz sphere on a flat, zero-padded (DC-FFT) mode, ~84 points across the contact diameter.
///
/// Approach: the sphere is sampled with its apex on a grid point, so the rigid approach measured
/// from first contact of the highest grid point is the approach of the continuous sphere,
/// δ = a²/R.
#[test]
fn hertz_sphere_on_flat() {
    let (radius, e_star, force) = (0.01, 1.0e11, 10.0);
    let hz = Hertz::new(radius, force, e_star);
    let n = 101;
    let dx = 2.4 * hz.radius / n as f64;
    let c = (n / 2) as f64;
    let heights = Array2::from_shape_fn((n, n), |(i, j)| {
        let (x, y) = ((i as f64 - c) * dx, (j as f64 - c) * dx);
        -(x * x + y * y) / (2.0 * radius)
    });
    let surface = Grid2::new(heights, dx, dx, false).unwrap();
    assert!(2.0 * hz.radius / dx >= 40.0);
    let mut s = solver(&surface, e_star);
    let sol = s.solve_load(force / surface.area(), None).unwrap();
    assert!(sol.converged && sol.residual <= NormalOptions::DEFAULT_TOLERANCE);

    let a_num = (sol.contact_points as f64 * dx * dx / PI).sqrt();
    let p_max = sol.pressure.iter().copied().fold(0.0, f64::max);
    let (mut num, mut den) = (0.0, 0.0);
    for ((i, j), p) in sol.pressure.indexed_iter() {
        let r = ((i as f64 - c).powi(2) + (j as f64 - c).powi(2)).sqrt() * dx;
        let want = hz.pressure(r);
        num += (p - want).powi(2);
        den += want * want;
    }
    let l2 = (num / den).sqrt();
    let err_a = a_num / hz.radius - 1.0;
    let err_p0 = p_max / hz.peak_pressure - 1.0;
    let err_d = sol.approach_m / hz.approach - 1.0;
    eprintln!(
        "Hertz: a {err_a:+.2e}, p0 {err_p0:+.2e}, δ {err_d:+.2e}, L2 {l2:.2e}, {} it",
        sol.iterations
    );
    assert!(err_a.abs() < 0.01, "contact radius error {err_a}");
    assert!(err_p0.abs() < 0.01, "peak pressure error {err_p0}");
    assert!(err_d.abs() < 0.01, "approach error {err_d}");
    assert!(l2 < 0.02, "pressure L2 error {l2}");
    assert_eq!(sol.contact_spots, 1);
    // Elastic energy of Hertz contact: W = (2/5)·P·δ (Johnson 1985 §4.2, ∫P dδ with P ∝ δ^{3/2}).
    let w = 0.4 * force * hz.approach;
    assert!((sol.elastic_energy_j / w - 1.0).abs() < 0.02);
}

/// One period λ of h(x) = g cos(2πx/λ) on an nx × ny periodic grid (uniform along y).
fn wavy(nx: usize, ny: usize, lambda: f64, g: f64) -> Grid2 {
    let dx = lambda / nx as f64;
    let h = Array2::from_shape_fn((nx, ny), |(i, _)| {
        g * (2.0 * PI * i as f64 / nx as f64).cos()
    });
    Grid2::new(h, dx, dx, true).unwrap()
}

#[test]
fn westergaard_full_contact_amplitude() {
    let (lambda, g, e_star) = (100e-6, 1e-6, 1e11);
    let p_star = PI * e_star * g / lambda;
    let (nx, ny) = (64, 4);
    let surface = wavy(nx, ny, lambda, g);
    let mut s = solver(&surface, e_star);
    for ratio in [1.2, 3.0] {
        let sol = s.solve_load(ratio * p_star, None).unwrap();
        assert_eq!(sol.contact_points, nx * ny);
        // First cosine harmonic of the pressure: p = p̄ + p* cos(2πx/λ).
        let amp = 2.0 / (nx * ny) as f64
            * sol
                .pressure
                .indexed_iter()
                .map(|((i, _), p)| p * (2.0 * PI * i as f64 / nx as f64).cos())
                .sum::<f64>();
        eprintln!(
            "Westergaard full: amplitude/p* - 1 = {:+.2e}",
            amp / p_star - 1.0
        );
        assert!((amp / p_star - 1.0).abs() < 0.005, "{amp} vs {p_star}");
        // Full contact: the mean gap is zero.
        assert!(sol.mean_gap_m.abs() < 1e-6 * g);
    }
}

#[test]
fn westergaard_partial_contact_half_width() {
    let (lambda, g, e_star) = (100e-6, 1e-6, 1e11);
    let p_star = PI * e_star * g / lambda;
    let (nx, ny) = (512, 2);
    let dx = lambda / nx as f64;
    let surface = wavy(nx, ny, lambda, g);
    let mut s = solver(&surface, e_star);
    let mut warm = None;
    for ratio in [0.05, 0.2, 0.5, 0.8] {
        let sol = s.solve_load(ratio * p_star, warm.as_ref()).unwrap();
        let a_want = lambda / PI * f64::sqrt(ratio).asin();
        let a_num = 0.5 * (sol.contact_points / ny) as f64 * dx;
        eprintln!(
            "Westergaard p̄/p* = {ratio}: a = {a_num:.4e}, closed form {a_want:.4e}, dx {dx:.2e}, {} it",
            sol.iterations
        );
        assert!((a_num - a_want).abs() <= dx, "{a_num} vs {a_want}");
        assert_eq!(sol.contact_spots, 1);
        warm = Some(sol);
    }
}

/// Reference statistics (Rq 0.177 µm, cl 6.6 µm, 250 µm, steel/steel) on a coarser 256² grid:
/// kn = −dp̄/dḡ rises monotonically over the reference sweep 0.1–10 MPa, the contact area grows
/// and the mean gap closes. (The 1024² reference case runs in `cargo bench --bench normal --
/// --reference` and `asperity contact normal`.)
#[test]
fn reference_statistics_kn_monotone() {
    use asperity::contact::sweep;
    use asperity::surface::combine::{composite_modulus, Material};
    use asperity::surface::generate::{generate, GaussianSurfaceSpec};
    let spec = GaussianSurfaceSpec {
        nx: 256,
        ny: 256,
        ..GaussianSurfaceSpec::reference()
    };
    let surface = generate(&spec).unwrap();
    let e_star = composite_modulus(Material::STEEL, Material::STEEL).unwrap();
    let mut s = solver(&surface, e_star);
    let sw = sweep::run(
        &mut s,
        &sweep::REFERENCE_PRESSURES_PA,
        sweep::SweepOptions::default(),
        |_| {},
    )
    .unwrap();
    assert_eq!(sw.points.len(), 6);
    for w in sw.points.windows(2) {
        assert!(w[1].kn_n_per_m3 > w[0].kn_n_per_m3, "{w:?}");
        assert!(w[1].contact_area_ratio >= w[0].contact_area_ratio);
        assert!(w[1].mean_gap_m < w[0].mean_gap_m);
    }
    let (beta, _) = sweep::power_law_fit(&sw.points).unwrap();
    eprintln!("256² reference statistics: β = {beta:.3}");
    assert!(beta > 0.0 && beta < 1.5, "β = {beta}");
}
