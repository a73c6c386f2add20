//! Hysteresis loops at several amplitudes on one pressure field, from one loading history.
//!
//! Units: SI, per unit nominal area (displacements in m, shear stresses in Pa, energies in J/m²).
//!
//! # Why one history serves all amplitudes (Masing)
//! Under a constant normal load, with the normal and tangential problems decoupled
//! (quasi-identical bodies, [`crate::contact::tangential::QUASI_IDENTICAL_ASSUMPTION`]) and the
//! slip along the loading direction, Coulomb partial slip obeys Masing's rules (Mindlin &
//! Deresiewicz 1953; Jäger's and Ciavarella's superposition, see Barber, *Contact Mechanics*,
//! 2018, §12.7): after a reversal the branch is the virgin curve scaled by two, the loop closes
//! after the first reversal, and loading past the previous extreme continues on the virgin curve
//! as if the smaller cycles had not happened. Two consequences are used here:
//!
//! 1. One history of increasing amplitudes replaces separate runs from the virgin state: virgin
//!    quarter cycle to `+a₁`, half cycle to `−a₁`, continued on to `−a₂`, half cycle to `+a₂`,
//!    on to `+a₃`, ... Every half cycle starts where the separate virgin run at that amplitude
//!    would have its steady cycle start.
//! 2. The steady loop is symmetric: the second half cycle is the point reflection of the first
//!    (the Coulomb problem is odd in the load), so only one half cycle per amplitude is computed.
//!
//! Both rest on the loop closing, i.e. on the traction after the half cycle being the negative of
//! the traction before it. The Cerruti cross terms turn the slip slightly out of the loading
//! direction, so the rules are close to, not exactly, true. Each loop therefore reports its
//! **closure error** `max_i |q_i(end) + q_i(start)| / max_i μ p_i`; the test
//! `history_loops_equal_separate_virgin_runs` below compares the loops with separate virgin runs
//! of full cycles on a rough patch (≤ 8e-5 μp), and `tests/tangential_contact.rs` the energy per
//! cycle of a Hertzian asperity with Mindlin–Deresiewicz (within 1 % from 0.2 to 1.5 δ_gs).
//!
//! # Samples
//! `steps_per_cycle = n` (a multiple of 4): the virgin quarter has `n/4` steps
//! `δ = a₁ sin(2πk/n)`, each half cycle `n/2` steps `δ = ±a cos(2πk/n)`, each continuation from
//! `a_j` to `a_{j+1}` the steps of the quarter sine of amplitude `a_{j+1}` from `a_j` on (at least
//! one). The loop of each amplitude is reported over one full steady cycle from `+a` through `−a`
//! back to `+a` (`n + 1` samples, the half not computed by its point reflection).
//!
//! # Energy per cycle
//! Two measures, which agree to the quadrature error of the samples: the loop area `∮τ dδ`
//! (trapezoidal rule on the `n + 1` samples, the quadrature the element fit uses, so that BEM and
//! element are compared alike) and the frictional dissipation `Σ ΔA q·Δg` of the computed half
//! cycle, doubled (the dissipation of the incremental Coulomb problem, without quadrature error).

use crate::contact::tangential::{Control, TangentialSolver};
use crate::core::error::{Error, Result};
use crate::element::dissipated_energy;
use ndarray::Array2;
use std::f64::consts::PI;
use std::time::Instant;

/// The steady loop at one amplitude.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct AmplitudeLoop {
    /// Amplitude as a multiple of the gross-slip displacement (-).
    pub amplitude_factor: f64,
    /// Displacement amplitude `a` (m).
    pub amplitude_m: f64,
    /// Steady cycle from `+a` through `−a` back to `+a`: displacement (m), `n + 1` samples.
    pub displacement_m: Vec<f64>,
    /// Mean shear stress at the samples (Pa).
    pub shear_stress_pa: Vec<f64>,
    /// True when the BEM computed the descending half (`+a → −a`); the other half is its point
    /// reflection.
    pub computed_descending: bool,
    /// Loop area `∮τ dδ` by the trapezoidal rule on the samples (J/m²).
    pub loop_area_j_per_m2: f64,
    /// The loop area's numerical floor (J/m², [`energy_floor`]): a loop area of smaller
    /// magnitude is not resolved by the solve, and a negative one beyond it is an artefact.
    pub energy_floor_j_per_m2: f64,
    /// Frictional dissipation of the computed half cycle, doubled (J/m²).
    pub dissipation_j_per_m2: f64,
    /// `max_i |q_i(end) + q_i(start)| / max_i μ p_i` over the computed half cycle (-): zero for
    /// an exactly closed (Masing) loop.
    pub closure_error: f64,
}

/// Everything computed at one pressure.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct AmplitudeSweep {
    /// Gross-slip displacement of monotonic loading `δ_gs` (m), the unit of the amplitudes.
    pub gross_slip_displacement_m: f64,
    /// The virgin (monotonic loading) curve from the history: displacement (m), increasing from 0.
    pub virgin_displacement_m: Vec<f64>,
    /// Mean shear stress on the virgin curve (Pa).
    pub virgin_shear_stress_pa: Vec<f64>,
    /// One loop per amplitude, amplitudes increasing.
    pub loops: Vec<AmplitudeLoop>,
    /// Load steps solved.
    pub steps: usize,
    /// Contact points carrying shear.
    pub contact_points: usize,
    /// Largest solver iteration count of a step.
    pub max_step_iterations: usize,
    /// Largest final residual of a step.
    pub max_step_residual: f64,
    /// Wall time of the history (s), solver set-up excluded.
    pub wall_time_s: f64,
}

impl AmplitudeSweep {
    /// Virgin curve at displacement `d` (linear interpolation, `0 ≤ d ≤` the largest amplitude).
    pub fn virgin_shear_at(&self, d: f64) -> f64 {
        interpolate(&self.virgin_displacement_m, &self.virgin_shear_stress_pa, d)
    }
}

/// `cos(2πk/n)` with exact 0 and ±1 at the quarter points (so that loops close exactly).
fn cos_exact(k: usize, n: usize) -> f64 {
    let k = k % n;
    if 4 * k == n || 4 * k == 3 * n {
        0.0
    } else if k == 0 {
        1.0
    } else if 2 * k == n {
        -1.0
    } else {
        (2.0 * PI * k as f64 / n as f64).cos()
    }
}

/// Linear interpolation of increasing `x` samples at `xq` (clamped to the ends).
fn interpolate(x: &[f64], y: &[f64], xq: f64) -> f64 {
    match x.iter().position(|&v| v >= xq) {
        None => *y.last().unwrap_or(&f64::NAN),
        Some(0) => y[0],
        Some(i) => {
            let t = (xq - x[i - 1]) / (x[i] - x[i - 1]);
            y[i - 1] + t * (y[i] - y[i - 1])
        }
    }
}

/// Check the amplitude factors: finite, positive, strictly increasing, at least one.
pub fn check_factors(factors: &[f64]) -> Result<()> {
    if factors.is_empty() {
        return Err(Error::param("amplitude_factors", "give at least one"));
    }
    for (i, &f) in factors.iter().enumerate() {
        if !(f.is_finite() && f > 0.0) {
            return Err(Error::param(
                "amplitude_factors",
                format!("entry {i} must be finite and > 0, got {f}"),
            ));
        }
        if i > 0 && f <= factors[i - 1] {
            return Err(Error::param(
                "amplitude_factors",
                format!(
                    "must be strictly increasing: entry {i} ({f}) follows {}",
                    factors[i - 1]
                ),
            ));
        }
    }
    Ok(())
}

/// Number of load steps [`run`] solves for `amplitude_factors.len()` amplitudes (continuations
/// counted for their ratio), for progress bars.
pub fn step_count(factors: &[f64], steps_per_cycle: usize) -> usize {
    let n = steps_per_cycle;
    let continuation: usize = factors
        .windows(2)
        .map(|w| continuation_angles(w[0] / w[1], n).len())
        .sum();
    n / 4 + factors.len() * (n / 2) + continuation
}

/// Phase angles θ of the continuation from `ratio·a` to `a` along `a sin θ`, at most `2π/n`
/// apart, the last exactly `π/2`.
fn continuation_angles(ratio: f64, n: usize) -> Vec<f64> {
    let theta0 = ratio.clamp(0.0, 1.0).asin();
    let span = 0.5 * PI - theta0;
    let m = ((span / (2.0 * PI / n as f64)).ceil() as usize).max(1);
    (1..=m)
        .map(|k| {
            if k == m {
                0.5 * PI
            } else {
                theta0 + span * k as f64 / m as f64
            }
        })
        .collect()
}

/// Numerical floor of a loop area `∮τ̄ dδ` (J/m²) at amplitude `a` (m).
///
/// A converged step's traction is within `ε·μp_max` of the exact one at every point (the
/// solver's relative natural residual `ε`, [`TangentialSolver::tolerance`]; a loop that does
/// not close adds its closure error, relative to the same bound), so the mean shear over the
/// nominal area is within `ε_τ = ε·μp_max·n_c/N` (`n_c` of the `N` grid points in contact, the
/// others carrying none). Along the loop's path of length `4a` the area is then uncertain by
/// `4a·ε_τ`: this floor. Smaller areas (near-stuck loops on coarse grids and loose tolerances)
/// are not results, and negative ones are numerical artefacts.
pub fn energy_floor(
    amplitude_m: f64,
    relative_error: f64,
    traction_bound_pa: f64,
    contact_fraction: f64,
) -> f64 {
    4.0 * amplitude_m * relative_error * traction_bound_pa * contact_fraction
}

/// A shear traction field `(q_x, q_y)` on the grid (Pa).
type Traction = (Array2<f64>, Array2<f64>);

/// Maximum over the grid of `|q(a) + q(b)|`, relative to `scale`.
fn closure(a: &Traction, b: &Traction, scale: f64) -> f64 {
    let mut worst: f64 = 0.0;
    for ((ax, ay), (bx, by)) in a.0.iter().zip(a.1.iter()).zip(b.0.iter().zip(b.1.iter())) {
        worst = worst.max((ax + bx).hypot(ay + by));
    }
    worst / scale
}

/// Run the history of increasing amplitudes `factors × δ_gs` along x on `solver` (reset to the
/// virgin state first) with `steps_per_cycle` steps per cycle (multiple of 4, ≥ 8). `progress`
/// is called after every step.
pub fn run(
    solver: &mut TangentialSolver,
    factors: &[f64],
    steps_per_cycle: usize,
    mut progress: impl FnMut(),
) -> Result<AmplitudeSweep> {
    check_factors(factors)?;
    let n = steps_per_cycle;
    if n < 8 || !n.is_multiple_of(4) {
        return Err(Error::param(
            "steps_per_cycle",
            format!("must be a multiple of 4 and at least 8, got {n}"),
        ));
    }
    let started = Instant::now();
    solver.reset();
    let gross_slip = solver.gross_slip_displacement([1.0, 0.0])?;
    let area = solver.metadata().nominal_area_m2;
    let bound = solver.traction_bound_pa();
    let tolerance = solver.tolerance();
    let contact_fraction = {
        let m = solver.metadata();
        m.contact_points as f64 / (m.grid.0 * m.grid.1) as f64
    };
    let amplitudes: Vec<f64> = factors.iter().map(|f| f * gross_slip).collect();
    let (mut steps, mut max_it, mut max_res) = (0usize, 0usize, 0.0f64);
    let mut virgin = (vec![0.0], vec![0.0]);
    let mut step = |solver: &mut TangentialSolver, d: f64| -> Result<(f64, f64, f64)> {
        let s = solver.step(Control::Displacement([d, 0.0]))?;
        steps += 1;
        max_it = max_it.max(s.iterations);
        max_res = max_res.max(s.residual);
        progress();
        Ok((s.shift_m[0], s.mean_shear_pa[0], s.frictional_work_j))
    };
    // Virgin quarter cycle to +a₁.
    for k in 1..=n / 4 {
        let (d, t, _) = step(solver, amplitudes[0] * cos_exact(n / 4 - k, n))?;
        virgin.0.push(d);
        virgin.1.push(t);
    }
    let mut loops = Vec::with_capacity(factors.len());
    let mut sign = 1.0; // the current extreme is sign·a_j
    for (j, &a) in amplitudes.iter().enumerate() {
        if j > 0 {
            // Continue past the previous extreme on the virgin curve to sign·a_j.
            for theta in continuation_angles(amplitudes[j - 1] / a, n) {
                let (d, t, _) = step(solver, sign * a * theta.sin())?;
                virgin.0.push(sign * d);
                virgin.1.push(sign * t);
            }
        }
        // Half cycle from sign·a to −sign·a.
        let start = solver.traction();
        let mut d_half = vec![sign * a];
        let mut t_half = vec![*virgin.1.last().expect("virgin curve") * sign];
        let mut work = 0.0;
        for k in 1..=n / 2 {
            let (d, t, w) = step(solver, sign * a * cos_exact(k, n))?;
            d_half.push(d);
            t_half.push(t);
            work += w;
        }
        let end = solver.traction();
        let closure_error = closure(&start, &end, bound);
        // The full cycle from +a: descending half, then ascending half (point reflections).
        let (desc_d, desc_t): (Vec<f64>, Vec<f64>) = if sign > 0.0 {
            (d_half.clone(), t_half.clone())
        } else {
            (
                d_half.iter().map(|v| -v).collect(),
                t_half.iter().map(|v| -v).collect(),
            )
        };
        let mut displacement = desc_d.clone();
        let mut shear = desc_t.clone();
        displacement.extend(desc_d[1..].iter().map(|v| -v));
        shear.extend(desc_t[1..].iter().map(|v| -v));
        loops.push(AmplitudeLoop {
            amplitude_factor: factors[j],
            amplitude_m: a,
            loop_area_j_per_m2: dissipated_energy(&displacement, &shear),
            energy_floor_j_per_m2: energy_floor(
                a,
                tolerance.max(closure_error),
                bound,
                contact_fraction,
            ),
            dissipation_j_per_m2: 2.0 * work / area,
            displacement_m: displacement,
            shear_stress_pa: shear,
            computed_descending: sign > 0.0,
            closure_error,
        });
        sign = -sign;
    }
    Ok(AmplitudeSweep {
        gross_slip_displacement_m: gross_slip,
        virgin_displacement_m: virgin.0,
        virgin_shear_stress_pa: virgin.1,
        loops,
        steps,
        contact_points: solver.contact_points().len(),
        max_step_iterations: max_it,
        max_step_residual: max_res,
        wall_time_s: started.elapsed().as_secs_f64(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::normal::{NormalOptions, NormalProblem, NormalSolver};
    use crate::contact::tangential::{
        oscillate, Oscillation, TangentialOptions, TangentialProblem,
    };
    use crate::core::fft::Boundary;
    use crate::core::material::{composite_modulus, Material};
    use crate::surface::generate::{generate, GaussianSurfaceSpec};

    fn rough_solver(pressure_pa: f64) -> TangentialSolver {
        let spec = GaussianSurfaceSpec {
            nx: 128,
            ny: 128,
            ..GaussianSurfaceSpec::reference()
        };
        let surface = generate(&spec).unwrap();
        let steel = Material::STEEL;
        let mut normal = NormalSolver::new(
            &NormalProblem {
                surface: &surface,
                e_star_pa: composite_modulus(steel, steel).unwrap(),
                hardness_pa: None,
            },
            NormalOptions::default(),
        )
        .unwrap();
        let sol = normal.solve_load(pressure_pa, None).unwrap();
        TangentialSolver::new(
            &TangentialProblem {
                pressure: &sol.pressure,
                dx: sol.dx,
                dy: sol.dy,
                boundary: Boundary::Periodic,
                friction_coefficient: 0.6,
                body1: steel,
                body2: steel,
            },
            TangentialOptions::default(),
        )
        .unwrap()
    }

    /// The claim the history rests on, checked on a rough patch (reference statistics, 128²,
    /// several contact spots): each loop of the one history of increasing amplitudes (half
    /// cycle + point reflection) equals the second full cycle of a separate run from the virgin
    /// state at that amplitude, sample by sample.
    #[test]
    fn history_loops_equal_separate_virgin_runs() {
        let n = 40;
        let factors = [0.2, 0.4, 0.7, 1.0, 1.5];
        for pressure in [2e6, 10e6] {
            let mut solver = rough_solver(pressure);
            let sweep = run(&mut solver, &factors, n, || {}).unwrap();
            assert_eq!(sweep.steps, step_count(&factors, n));
            let scale = 0.6 * pressure;
            for l in &sweep.loops {
                solver.reset();
                let r = oscillate(
                    &mut solver,
                    &Oscillation {
                        amplitude: Control::Displacement([l.amplitude_m, 0.0]),
                        cycles: 3,
                        steps_per_cycle: n,
                    },
                    |_, _| {},
                )
                .unwrap();
                // Separate run: steps[i] at a·sin(2πi/n); the steady cycle from the peak of
                // cycle 2 is steps[n + n/4 + k] at a·cos(2πk/n).
                let mut worst: f64 = 0.0;
                for k in 0..=n {
                    let s = &r.steps[n + n / 4 + k];
                    assert!((s.shift_m[0] - l.displacement_m[k]).abs() < 1e-12 * l.amplitude_m);
                    worst = worst.max((s.mean_shear_pa[0] - l.shear_stress_pa[k]).abs() / scale);
                }
                let w_sep = r.cycles[1].dissipated_j_per_m2;
                eprintln!(
                    "{} MPa, δa/δgs = {}: max |Δτ|/(μp) = {worst:.2e}, energy {:+.2e} relative, \
                     closure error {:.1e}",
                    pressure / 1e6,
                    l.amplitude_factor,
                    l.loop_area_j_per_m2 / w_sep - 1.0,
                    l.closure_error
                );
                // Measured: ≤ 7.7e-5 of μp and ≤ 1.6e-4 in energy (tolerance 1e-6 of the solver).
                assert!(worst < 5e-4, "{worst}");
                assert!((l.loop_area_j_per_m2 / w_sep - 1.0).abs() < 1e-3);
            }
        }
    }

    #[test]
    fn factors_and_samples() {
        assert!(check_factors(&[]).is_err());
        assert!(check_factors(&[0.5, 0.5]).is_err());
        assert!(check_factors(&[-0.1]).is_err());
        assert!(check_factors(&[0.2, 1.5]).is_ok());
        assert_eq!(cos_exact(10, 40), 0.0);
        assert_eq!(cos_exact(20, 40), -1.0);
        assert_eq!(cos_exact(40, 40), 1.0);
        let t = continuation_angles(0.5, 40);
        assert_eq!(*t.last().unwrap(), 0.5 * PI);
        assert!(t[0] > (0.5f64).asin());
        assert_eq!(t.len(), 7); // 60° in steps of at most 9°
    }
}
