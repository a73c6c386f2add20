//! Pressure sweeps of the normal contact solver: real contact area, mean gap and the normal
//! contact stiffness per unit nominal area `kn = dp̄/dδ` (N/m³) versus nominal pressure.
//!
//! Units: pressures in Pa, gaps in m, kn in N/m³ (Pa/m).
//!
//! # How kn is obtained
//! `kn(p̄) = dp̄/dδ` is the slope of the load–approach curve (δ = rigid-body approach of the
//! surfaces; for a periodic patch `dδ = −dḡ`, ḡ the mean gap, so kn = −dp̄/dḡ). Differencing
//! across the coarse sweep (0.1 … 10 MPa, ratios up to 5) would blur it badly; each sweep point
//! instead solves the tangent problem on its contact set
//! ([`NormalSolver::contact_stiffness`], one linear solve: the exact derivative of the branch,
//! equal to the stiffness of a rigid punch of the contact area, Barber 2003). Earlier versions
//! used the central difference of two extra nonlinear solves at `p̄(1 ± 0.02)` on the mean gap,
//! which for a finite (zero-padded) window also counted the elastic sinking of the unloaded
//! surface inside the window ([`stiffness_central_difference`] remains for validation).
//!
//! # Resolution report
//! Each point reports how many grid points span the contact spots and the free regions
//! ([`ContactResolution`]); when the narrower of the two spans fewer than
//! [`crate::contact::resolution::RESOLVED_POINTS_ACROSS`] points, the grid does not resolve the
//! contact at that load and the area ratio (and, less so, kn) is grid dependent: refine the grid.
//! In a non-periodic window, contact points on the border rows/columns
//! ([`ContactResolution::reaches_window_edge`]) mean the contact is cut by the window: the result
//! depends on the window, not on the grid; enlarge the window.
//! The smallest and median spot sizes are reported too.

use super::normal::{NormalMethod, NormalSolution, NormalSolver};
use super::resolution::ContactResolution;
use crate::core::error::{num, require_positive, Error, Result};

/// The reference sweep of nominal pressures (Pa): 0.1, 0.2, 1, 2, 5, 10 MPa.
pub const REFERENCE_PRESSURES_PA: [f64; 6] = [0.1e6, 0.2e6, 1e6, 2e6, 5e6, 10e6];

/// Sweep settings.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SweepOptions {
    /// Keep every converged solution (pressure maps) in the result.
    pub keep_solutions: bool,
}

/// One nominal pressure of a sweep.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SweepPoint {
    /// Nominal (mean) pressure p̄ (Pa).
    pub pressure_pa: f64,
    /// Real contact area over nominal area (-).
    pub contact_area_ratio: f64,
    /// Mean gap ḡ (m).
    pub mean_gap_m: f64,
    /// Normal contact stiffness per unit nominal area kn = dp̄/dδ (N/m³). Hardness-limited
    /// contact: the unloading/reloading stiffness about the plastically deformed state (the
    /// one an element carries; the loading tangent is in [`SweepPoint::plastic`]).
    pub kn_n_per_m3: f64,
    /// Rigid approach from first contact (m).
    pub approach_m: f64,
    /// Number of contact spots.
    pub contact_spots: usize,
    /// Grid points of the smallest contact spot.
    pub smallest_spot_points: usize,
    /// Grid points of the median contact spot.
    pub median_spot_points: usize,
    /// Grid points across the contact spots and across the free regions.
    pub resolution: ContactResolution,
    /// The iteration used at p̄.
    pub method: NormalMethod,
    /// Iterations of the contact solve at p̄.
    pub iterations: usize,
    /// Iterations of the tangent solve for kn.
    pub stiffness_iterations: usize,
    /// Final relative gap error of the solve at p̄.
    pub residual: f64,
    /// Wall time of this point: contact solve and kn (s).
    pub wall_time_s: f64,
    /// The plastic part of a hardness-limited solve; `None` for elastic contact.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plastic: Option<PlasticPoint>,
}

/// The plastic part of a hardness-limited sweep point (see [`crate::contact::normal`]).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PlasticPoint {
    /// Hardness H (Pa).
    pub hardness_pa: f64,
    /// Loading tangent dp̄/dδ with the plastic points held at H (N/m³), ≤ the unloading kn.
    pub kn_loading_n_per_m3: f64,
    /// Elastic contact area (0 < p < H) over nominal area (-).
    pub elastic_area_ratio: f64,
    /// Plastic contact area (p = H) over nominal area (-).
    pub plastic_area_ratio: f64,
    /// Grid points in plastic contact.
    pub plastic_points: usize,
    /// Plastically displaced volume of the patch (m³), see
    /// [`NormalSolution::plastic_volume_m3`].
    pub plastic_volume_m3: f64,
    /// Iterations of the tangent solve of the loading tangent.
    pub loading_stiffness_iterations: usize,
}

impl PlasticPoint {
    /// The plastic part of a converged hardness-limited solution and its loading tangent;
    /// `None` for elastic contact.
    pub fn of(
        solver: &mut NormalSolver,
        solution: &NormalSolution,
    ) -> Result<Option<PlasticPoint>> {
        let Some(hardness_pa) = solution.hardness_pa else {
            return Ok(None);
        };
        let loading = solver.loading_stiffness(solution)?;
        Ok(Some(PlasticPoint {
            hardness_pa,
            kn_loading_n_per_m3: loading.kn_n_per_m3,
            elastic_area_ratio: solution.elastic_area_ratio,
            plastic_area_ratio: solution.plastic_area_ratio,
            plastic_points: solution.plastic_points,
            plastic_volume_m3: solution.plastic_volume_m3,
            loading_stiffness_iterations: loading.iterations,
        }))
    }
}

impl SweepPoint {
    /// The physical ranges of a solved pressure, as the solver guarantees them: `kn > 0`
    /// (pressing harder never loosens a contact, dp̄/dδ > 0), a contact area ratio in (0, 1]
    /// (a loaded contact touches somewhere, never over more than the nominal area), finite
    /// mean gap and approach. Used on results read back from files (shard merge), whose
    /// numbers no solver vouches for; the message names the field.
    pub fn check_physical(&self) -> std::result::Result<(), String> {
        if !(self.kn_n_per_m3.is_finite() && self.kn_n_per_m3 > 0.0) {
            return Err(format!(
                "`kn_n_per_m3` = {} must be finite and > 0 (a contact stiffens under load)",
                num(self.kn_n_per_m3)
            ));
        }
        if !(self.contact_area_ratio > 0.0 && self.contact_area_ratio <= 1.0) {
            return Err(format!(
                "`contact_area_ratio` = {} must lie in (0, 1] (real over nominal area)",
                num(self.contact_area_ratio)
            ));
        }
        for (name, v) in [
            ("mean_gap_m", self.mean_gap_m),
            ("approach_m", self.approach_m),
        ] {
            if !v.is_finite() {
                return Err(format!("`{name}` = {} is not finite", num(v)));
            }
        }
        if let Some(pl) = &self.plastic {
            if !(pl.kn_loading_n_per_m3 >= 0.0 && pl.kn_loading_n_per_m3 <= self.kn_n_per_m3) {
                return Err(format!(
                    "`kn_loading_n_per_m3` = {} must lie in [0, kn] (the plastic points only \
                     soften the loading tangent)",
                    num(pl.kn_loading_n_per_m3)
                ));
            }
            if !(pl.plastic_area_ratio >= 0.0
                && pl.plastic_area_ratio <= self.contact_area_ratio
                && pl.plastic_volume_m3 >= 0.0)
            {
                return Err(format!(
                    "`plastic_area_ratio` = {} must lie in [0, contact_area_ratio] and \
                     `plastic_volume_m3` = {} must be ≥ 0",
                    num(pl.plastic_area_ratio),
                    num(pl.plastic_volume_m3)
                ));
            }
        }
        Ok(())
    }
}

impl SweepPoint {
    /// True when the grid does not resolve the narrower of contact spots and free regions
    /// (see [`ContactResolution::resolved`]).
    pub fn under_resolved(&self) -> bool {
        !self.resolution.resolved()
    }
}

/// Result of a sweep, points in increasing pressure.
#[derive(Debug, Clone)]
pub struct Sweep {
    /// One point per pressure, in increasing pressure.
    pub points: Vec<SweepPoint>,
    /// Solutions at the sweep pressures (only with [`SweepOptions::keep_solutions`]).
    pub solutions: Vec<NormalSolution>,
}

/// Check and sort sweep pressures: each finite and > 0, no duplicates.
pub fn checked_pressures(pressures_pa: &[f64]) -> Result<Vec<f64>> {
    if pressures_pa.is_empty() {
        return Err(Error::param("pressures_pa", "no pressure given"));
    }
    let mut p = Vec::with_capacity(pressures_pa.len());
    for &v in pressures_pa {
        p.push(require_positive("pressures_pa", v)?);
    }
    p.sort_by(f64::total_cmp);
    if let Some(w) = p.windows(2).find(|w| w[0] == w[1]) {
        return Err(Error::param(
            "pressures_pa",
            format!("pressure {} Pa given twice", w[0]),
        ));
    }
    Ok(p)
}

/// Run the sweep with warm starts (each pressure starts from the previous converged solution).
/// `progress(k)` is called after the k-th pressure (1-based) is done.
pub fn run(
    solver: &mut NormalSolver,
    pressures_pa: &[f64],
    options: SweepOptions,
    mut progress: impl FnMut(usize),
) -> Result<Sweep> {
    let pressures = checked_pressures(pressures_pa)?;
    let mut points = Vec::with_capacity(pressures.len());
    let mut solutions = Vec::new();
    let mut warm: Option<NormalSolution> = None;
    for (k, &p) in pressures.iter().enumerate() {
        let start = std::time::Instant::now();
        let sol = solver.solve_load(p, warm.as_ref())?;
        let kn = solver.contact_stiffness(&sol)?;
        let plastic = PlasticPoint::of(solver, &sol)?;
        points.push(SweepPoint {
            pressure_pa: p,
            contact_area_ratio: sol.contact_area_ratio,
            mean_gap_m: sol.mean_gap_m,
            kn_n_per_m3: kn.kn_n_per_m3,
            approach_m: sol.approach_m,
            contact_spots: sol.contact_spots,
            smallest_spot_points: sol.smallest_spot_points,
            median_spot_points: sol.median_spot_points,
            resolution: sol.resolution,
            method: sol.method,
            iterations: sol.iterations,
            stiffness_iterations: kn.iterations,
            residual: sol.residual,
            wall_time_s: start.elapsed().as_secs_f64(),
            plastic,
        });
        if options.keep_solutions {
            solutions.push(sol.clone());
        }
        warm = Some(sol);
        progress(k + 1);
    }
    Ok(Sweep { points, solutions })
}

/// `kn ≈ −2ε p̄ / (ḡ₊ − ḡ₋)` from the mean gaps (or, with the signs of the approaches,
/// `2ε p̄ / (δ₊ − δ₋)`) at `p̄(1−ε)` and `p̄(1+ε)` (N/m³): the central difference that validates
/// [`NormalSolver::contact_stiffness`].
pub fn stiffness_central_difference(
    pressure_pa: f64,
    eps: f64,
    gap_lo_m: f64,
    gap_hi_m: f64,
) -> f64 {
    -2.0 * eps * pressure_pa / (gap_hi_m - gap_lo_m)
}

/// Least-squares power law `kn = C·p̄^β` through the points, in log–log:
/// returns `(β, C)` (C in N/m³/Pa^β). Needs at least two points with positive kn.
pub fn power_law_fit(points: &[SweepPoint]) -> Result<(f64, f64)> {
    let xy: Vec<(f64, f64)> = points
        .iter()
        .filter(|p| p.kn_n_per_m3 > 0.0 && p.kn_n_per_m3.is_finite())
        .map(|p| (p.pressure_pa.ln(), p.kn_n_per_m3.ln()))
        .collect();
    if xy.len() < 2 {
        return Err(Error::Data(
            "power-law fit of kn needs at least two pressures with positive kn".into(),
        ));
    }
    let n = xy.len() as f64;
    let mx = xy.iter().map(|p| p.0).sum::<f64>() / n;
    let my = xy.iter().map(|p| p.1).sum::<f64>() / n;
    let sxy: f64 = xy.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = xy.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let beta = sxy / sxx;
    Ok((beta, (my - beta * mx).exp()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::normal::{NormalOptions, NormalProblem};
    use crate::Grid2;
    use ndarray::Array2;
    use std::f64::consts::PI;

    #[test]
    fn pressures_checked_and_sorted() {
        assert_eq!(checked_pressures(&[2.0, 1.0]).unwrap(), vec![1.0, 2.0]);
        assert!(checked_pressures(&[]).is_err());
        assert!(checked_pressures(&[1.0, 0.0]).is_err());
        assert!(checked_pressures(&[1.0, -3.0]).is_err());
        assert!(checked_pressures(&[1.0, f64::NAN]).is_err());
        let e = checked_pressures(&[1.0, 1.0]).unwrap_err().to_string();
        assert!(e.contains("twice"), "{e}");
    }

    #[test]
    fn power_law_recovers_exponent() {
        let pts: Vec<SweepPoint> = [1e5, 1e6, 1e7]
            .iter()
            .map(|&p| SweepPoint {
                pressure_pa: p,
                contact_area_ratio: 0.0,
                mean_gap_m: 0.0,
                kn_n_per_m3: 3.0 * f64::powf(p, 0.8),
                approach_m: 0.0,
                contact_spots: 0,
                smallest_spot_points: 0,
                median_spot_points: 0,
                resolution: ContactResolution::of(&Array2::from_elem((2, 2), true), true),
                method: NormalMethod::Auto,
                iterations: 0,
                stiffness_iterations: 0,
                residual: 0.0,
                wall_time_s: 0.0,
                plastic: None,
            })
            .collect();
        let (b, c) = power_law_fit(&pts).unwrap();
        assert!((b - 0.8).abs() < 1e-12 && (c / 3.0 - 1.0).abs() < 1e-10);
    }

    /// A 2D wavy surface in partial contact: kn positive and increasing with load, contact area
    /// increasing, mean gap decreasing.
    #[test]
    fn kn_increases_on_a_wavy_surface() {
        let (n, lambda, g, e_star) = (64, 100e-6, 1e-6, 1e11);
        let dx = lambda / n as f64;
        let h = Array2::from_shape_fn((n, n), |(i, j)| {
            g * ((2.0 * PI * i as f64 / n as f64).cos() + (2.0 * PI * j as f64 / n as f64).cos())
        });
        let s = Grid2::new(h, dx, dx, true).unwrap();
        let mut solver = NormalSolver::new(
            &NormalProblem {
                surface: &s,
                e_star_pa: e_star,
                hardness_pa: None,
            },
            NormalOptions::default(),
        )
        .unwrap();
        let p_star = PI * e_star * g / lambda;
        let ps: Vec<f64> = [0.01, 0.03, 0.1, 0.3].iter().map(|r| r * p_star).collect();
        let mut calls = 0;
        let sw = run(&mut solver, &ps, SweepOptions::default(), |_| calls += 1).unwrap();
        assert_eq!(calls, 4);
        for w in sw.points.windows(2) {
            assert!(w[1].kn_n_per_m3 > w[0].kn_n_per_m3);
            assert!(w[1].contact_area_ratio > w[0].contact_area_ratio);
            assert!(w[1].mean_gap_m < w[0].mean_gap_m);
        }
    }
}
