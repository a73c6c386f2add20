//! Model-free check of the levels not used in the fit: the single-nonlinear-mode response built
//! from the fit levels' own backbone, without any joint model or effect.
//!
//! The pointwise backbone of the fit levels ([`backbone::from_data`] on those levels alone:
//! natural frequency and damping ratio of every half-power row against its drive-point
//! displacement amplitude, modal constant `R = 1/m` of their lowest level) is interpolated in
//! the amplitude by smooth laws, and every level's response follows from the forced response of
//! one nonlinear mode (Krack, Panning-von Scheidt & Wallaschek 2013, *J. Sound Vib.*
//! 332:6798, the single-nonlinear-mode synthesis):
//!
//! ```text
//!   R·F = a·|D(a, ω)|,   X = R / D(a, ω),   D(a, ω) = ω_n(a)² − ω² + 2i·ζ(a)·ω_n(a)·ω
//! ```
//!
//! solved for the drive-point amplitude `a` of every row at the row's measured force, along the
//! sweep (the root nearest the previous row's, as a stepped sine stays on its branch).
//!
//! Six laws are tried: `ω_n` linear or quadratic in `a`; `ζ` linear, quadratic, or
//! `ζ0 + c·(a/a_ref)^p` (`p` in 0.25–4), each held at its end values outside the amplitudes the
//! points span. The spread of their errors on a level is what the fit levels' data alone
//! predict for it. The verdict on a level not used ([`Comparison`]) compares the RMS complex
//! error in the half-power band (where the synthesis holds): only laws that reproduce the fit
//! levels within [`REPRODUCTION_FACTOR`] of the model may judge (otherwise *inconclusive*); one
//! below [`BETTER_FACTOR`] of the model's error says the fit levels carry an amplitude
//! dependence the model lacks; none says the fit levels show no trend the model misses there.
//!
//! Units: SI (m, Hz, rad/s, N, kg).

use super::backbone::{self, BackbonePoint};
use super::fit::LevelData;
use super::measured::Sweep;
use super::report::{level_role, LevelErrors};
use super::stationarity;
use crate::core::error::{Error, Result};
use argmin::core::{CostFunction, Executor};
use argmin::solver::brent::{BrentOpt, BrentRoot};
use nalgebra::{DMatrix, DVector};
use realfft::num_complex::Complex64;
use serde::Serialize;
use std::f64::consts::TAU;

/// Range of the damping law's exponent.
const EXPONENT_RANGE: (f64, f64) = (0.25, 4.0);

/// A polynomial in `a/a_ref`: `Σ c_k·(a/a_ref)^k`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Polynomial {
    /// Coefficients `c_k`, constant term first (unit of the interpolated value).
    pub coefficients: Vec<f64>,
    /// Amplitude scale (m).
    pub a_ref_m: f64,
}

impl Polynomial {
    /// Value at drive-point amplitude `a` (m), by Horner's scheme.
    pub fn at(&self, a: f64) -> f64 {
        let s = a / self.a_ref_m;
        self.coefficients
            .iter()
            .rev()
            .fold(0.0, |acc, c| acc * s + c)
    }

    /// Weighted least-squares fit of degree `degree` to `(a_i, y_i)` with weights `w_i`
    /// (minimises `Σ w_i²·(P(a_i) − y_i)²`); `None` with fewer points than coefficients or a
    /// rank-deficient design (every point at one amplitude).
    fn fit(a: &[f64], y: &[f64], w: &[f64], degree: usize, a_ref_m: f64) -> Option<Self> {
        let n = degree + 1;
        if a.len() < n {
            return None;
        }
        let m = DMatrix::from_fn(a.len(), n, |i, k| w[i] * (a[i] / a_ref_m).powi(k as i32));
        let b = DVector::from_fn(a.len(), |i, _| w[i] * y[i]);
        let svd = m.svd(true, true);
        let s_max = svd.singular_values.max();
        if svd.singular_values.min() <= 1e-10 * s_max {
            return None;
        }
        let c = svd.solve(&b, 0.0).ok()?;
        Some(Self {
            coefficients: c.iter().copied().collect(),
            a_ref_m,
        })
    }
}

/// Damping ratio against the drive-point amplitude.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "law", rename_all = "snake_case")]
pub enum DampingLaw {
    /// `Σ c_k·(a/a_ref)^k` (linear or quadratic).
    Polynomial(Polynomial),
    /// `ζ0 + c·(a/a_ref)^p`.
    PowerLaw {
        /// Damping ratio at zero amplitude (dimensionless).
        zeta0: f64,
        /// Amplitude-dependent damping ratio at `a = a_ref` (dimensionless).
        c: f64,
        /// Exponent, in `EXPONENT_RANGE`.
        p: f64,
        /// Amplitude scale (m).
        a_ref_m: f64,
    },
}

impl DampingLaw {
    /// Damping ratio at drive-point amplitude `a` (m).
    pub fn at(&self, a: f64) -> f64 {
        match self {
            DampingLaw::Polynomial(p) => p.at(a),
            DampingLaw::PowerLaw {
                zeta0,
                c,
                p,
                a_ref_m,
            } => zeta0 + c * (a / a_ref_m).powf(*p),
        }
    }

    /// `ζ0` and `c` of the power law at exponent `p` by least squares on the relative error
    /// (weights `1/ζ_i`), and its sum of squared relative residuals.
    fn power_law_at(points: &[BackbonePoint], p: f64, a_ref_m: f64) -> Option<(Self, f64)> {
        let a: Vec<f64> = points.iter().map(|q| q.amplitude_m).collect();
        let z: Vec<f64> = points.iter().map(|q| q.damping_ratio).collect();
        let w: Vec<f64> = z.iter().map(|z| 1.0 / z.abs()).collect();
        let s: Vec<f64> = a.iter().map(|a| (a / a_ref_m).powf(p)).collect();
        // The power law is linear in (ζ0, c) at fixed p: a polynomial of degree 1 in s.
        let lin = Polynomial::fit(&s, &z, &w, 1, 1.0)?;
        let law = DampingLaw::PowerLaw {
            zeta0: lin.coefficients[0],
            c: lin.coefficients[1],
            p,
            a_ref_m,
        };
        let ss = a
            .iter()
            .zip(&z)
            .map(|(&a, &z)| (law.at(a) / z - 1.0).powi(2))
            .sum();
        Some((law, ss))
    }

    /// The power law of least squared relative error over the exponent range: a scan in steps
    /// of 0.05, then Brent's minimisation within a step either side of the best.
    fn fit_power_law(points: &[BackbonePoint], a_ref_m: f64) -> Option<Self> {
        if points.len() < 3 {
            return None;
        }
        let (lo, hi) = EXPONENT_RANGE;
        let steps = ((hi - lo) / 0.05).round() as usize;
        let best = (0..=steps)
            .map(|k| lo + (hi - lo) * k as f64 / steps as f64)
            .filter_map(|p| Self::power_law_at(points, p, a_ref_m).map(|(_, ss)| (p, ss)))
            .min_by(|x, y| x.1.total_cmp(&y.1))?
            .0;
        struct Profile<'a>(&'a [BackbonePoint], f64);
        impl CostFunction for Profile<'_> {
            type Param = f64;
            type Output = f64;
            fn cost(&self, p: &f64) -> std::result::Result<f64, argmin::core::Error> {
                Ok(DampingLaw::power_law_at(self.0, *p, self.1).map_or(f64::INFINITY, |x| x.1))
            }
        }
        let (a, b) = ((best - 0.05).max(lo), (best + 0.05).min(hi));
        let p = Executor::new(Profile(points, a_ref_m), BrentOpt::new(a, b))
            .configure(|s| s.param(best).max_iters(100))
            .run()
            .ok()
            .and_then(|r| r.state.best_param)
            .unwrap_or(best);
        Self::power_law_at(points, p, a_ref_m).map(|x| x.0)
    }
}

/// One smooth interpolation of the fit levels' backbone.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BackboneLaw {
    /// E.g. "ω_n quadratic, ζ power law".
    pub name: String,
    /// The same as a file-safe id, e.g. "wn-quadratic-zeta-power-law".
    pub id: String,
    /// Natural frequency (Hz) against the amplitude.
    pub frequency_hz: Polynomial,
    /// Damping ratio against the amplitude.
    pub damping: DampingLaw,
    /// Amplitudes the points span (m): outside them the law is held at its value at the nearer
    /// end (the data say nothing there, and a polynomial's extrapolation to the small
    /// amplitudes of the rows far from resonance would be arbitrary).
    pub amplitude_range_m: (f64, f64),
}

impl BackboneLaw {
    /// `D(a, ω) = ω_n(a)² − ω² + 2i·ζ(a)·ω_n(a)·ω` (rad²/s²), `a` held inside the points'
    /// range; `None` where the law leaves the physical range (`ω_n ≤ 0` or `ζ ≤ 0`).
    pub fn dynamic_stiffness_per_mass(&self, a: f64, omega: f64) -> Option<Complex64> {
        let a = a.clamp(self.amplitude_range_m.0, self.amplitude_range_m.1);
        let wn = TAU * self.frequency_hz.at(a);
        let zeta = self.damping.at(a);
        (wn > 0.0 && zeta > 0.0 && wn.is_finite() && zeta.is_finite())
            .then(|| Complex64::new(wn * wn - omega * omega, 2.0 * zeta * wn * omega))
    }

    /// The law sampled at `n` amplitudes spaced logarithmically over the points' range.
    pub fn curve(&self, n: usize) -> Vec<BackbonePoint> {
        let (lo, hi) = self.amplitude_range_m;
        (0..n)
            .map(|k| {
                let a = lo * (hi / lo).powf(k as f64 / (n - 1).max(1) as f64);
                BackbonePoint {
                    amplitude_m: a,
                    frequency_hz: self.frequency_hz.at(a),
                    damping_ratio: self.damping.at(a),
                }
            })
            .collect()
    }

    /// The six laws fitted to `points`; a law the points cannot determine is left out.
    fn all(points: &[BackbonePoint]) -> Vec<Self> {
        let a_ref = points.iter().map(|p| p.amplitude_m).fold(0.0, f64::max);
        let a_min = points
            .iter()
            .map(|p| p.amplitude_m)
            .fold(f64::INFINITY, f64::min);
        let a: Vec<f64> = points.iter().map(|p| p.amplitude_m).collect();
        let f: Vec<f64> = points.iter().map(|p| p.frequency_hz).collect();
        let z: Vec<f64> = points.iter().map(|p| p.damping_ratio).collect();
        let ones = vec![1.0; a.len()];
        let rel: Vec<f64> = z.iter().map(|z| 1.0 / z.abs()).collect();
        let mut laws = Vec::new();
        for (fname, fdeg) in [("linear", 1), ("quadratic", 2)] {
            let Some(freq) = Polynomial::fit(&a, &f, &ones, fdeg, a_ref) else {
                continue;
            };
            let damping = [
                (
                    "linear",
                    Polynomial::fit(&a, &z, &rel, 1, a_ref).map(DampingLaw::Polynomial),
                ),
                (
                    "quadratic",
                    Polynomial::fit(&a, &z, &rel, 2, a_ref).map(DampingLaw::Polynomial),
                ),
                ("power law", DampingLaw::fit_power_law(points, a_ref)),
            ];
            for (zname, law) in damping {
                if let Some(damping) = law {
                    laws.push(BackboneLaw {
                        name: format!("ω_n {fname}, ζ {zname}"),
                        id: format!("wn-{fname}-zeta-{}", zname.replace(' ', "-")),
                        frequency_hz: freq.clone(),
                        damping,
                        amplitude_range_m: (a_min, a_ref),
                    });
                }
            }
        }
        laws
    }

    /// Drive-point receptance (m/N, `e^{iωt}`) of every drive `(ω, F)` along a sweep, from
    /// `R·F = a·|D(a, ω)|` (see the module documentation): the roots are bracketed on a
    /// logarithmic grid of amplitudes up to `a_max` and refined by Brent's method; NaN where no
    /// root lies in the physical range of the law.
    pub fn receptance(&self, r: f64, drives: &[(f64, f64)], a_max: f64) -> Vec<Complex64> {
        let grid: Vec<f64> = (0..=800)
            .map(|k| a_max * 1e-5f64.powf(1.0 - k as f64 / 800.0))
            .collect();
        let mut previous: Option<f64> = None;
        drives
            .iter()
            .map(|&(omega, force)| {
                let g = |a: f64| {
                    self.dynamic_stiffness_per_mass(a, omega)
                        .map(|d| a * d.norm() - r * force)
                };
                let values: Vec<Option<f64>> = grid.iter().map(|&a| g(a)).collect();
                let roots: Vec<f64> = (0..grid.len() - 1)
                    .filter_map(|k| match (values[k], values[k + 1]) {
                        (Some(u), Some(v)) if u <= 0.0 && v > 0.0 => {
                            refine_root(&g, grid[k], grid[k + 1])
                        }
                        _ => None,
                    })
                    .collect();
                let chosen = match previous {
                    None => roots.first().copied(),
                    Some(p) => roots
                        .iter()
                        .copied()
                        .min_by(|x, y| (x - p).abs().total_cmp(&(y - p).abs())),
                };
                previous = chosen.or(previous);
                chosen
                    .and_then(|a| self.dynamic_stiffness_per_mass(a, omega))
                    .map_or(Complex64::new(f64::NAN, f64::NAN), |d| r / d)
            })
            .collect()
    }
}

/// Root of `g` in `[lo, hi]` (a sign change) by Brent's method, relative tolerance 1e-12.
fn refine_root(g: &dyn Fn(f64) -> Option<f64>, lo: f64, hi: f64) -> Option<f64> {
    struct Residual<'a>(&'a dyn Fn(f64) -> Option<f64>);
    impl CostFunction for Residual<'_> {
        type Param = f64;
        type Output = f64;
        fn cost(&self, a: &f64) -> std::result::Result<f64, argmin::core::Error> {
            (self.0)(*a).ok_or_else(|| argmin::core::Error::msg("outside the law's range"))
        }
    }
    Executor::new(Residual(g), BrentRoot::new(lo, hi, 1e-12))
        .configure(|s| s.param(0.5 * (lo + hi)).max_iters(200))
        .run()
        .ok()
        .and_then(|r| r.state.best_param)
}

/// One law's errors on every level.
#[derive(Debug, Clone, Serialize)]
pub struct LawPrediction {
    /// The interpolation law.
    pub law: BackboneLaw,
    /// Per level (all levels, by increasing mean force).
    pub errors: Vec<LevelErrors>,
}

/// The spread of the laws' errors on one level.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Spread {
    /// Smallest value over the laws (NaN when no law gave a finite value).
    pub min: f64,
    /// Largest value over the laws.
    pub max: f64,
    /// Smallest magnitude over the laws.
    pub best_abs: f64,
}

impl Spread {
    fn of(values: impl Iterator<Item = f64>) -> Self {
        let v: Vec<f64> = values.filter(|x| x.is_finite()).collect();
        Self {
            min: v.iter().copied().fold(f64::NAN, f64::min),
            max: v.iter().copied().fold(f64::NAN, f64::max),
            best_abs: v.iter().map(|x| x.abs()).fold(f64::NAN, f64::min),
        }
    }
}

/// Per level: the laws' spread of the goal errors.
#[derive(Debug, Clone, Serialize)]
pub struct LevelSpread {
    /// File name of the level's sweep.
    pub file: String,
    /// "fit" or "predicted".
    pub role: String,
    /// Relative peak error `peak_law/peak_measured − 1` (fraction).
    pub peak_error: Spread,
    /// Resonance-frequency error, law minus measured (Hz).
    pub resonance_error_hz: Spread,
    /// Phase-resonance error, law minus measured (Hz).
    pub phase_resonance_error_hz: Spread,
    /// RMS complex error over all rows (fraction of the level's peak).
    pub rms_complex: Spread,
    /// RMS complex error of the rows in the half-power band, where the pointwise backbone
    /// comes from and the single-mode synthesis holds (far from resonance out-of-band modes and
    /// the backbone's extrapolation to small amplitudes dominate it).
    pub rms_at_resonance: Spread,
}

/// The model-free check.
#[derive(Debug, Clone, Serialize)]
pub struct ModelFreeCheck {
    /// `1/R` of the fit levels' lowest level (kg).
    pub modal_mass_kg: f64,
    /// The pointwise backbone points the laws are fitted to.
    pub points: Vec<BackbonePoint>,
    /// Fit levels whose earlier side was left out as not stationary (the settled variant,
    /// [`Rows::Settled`]); empty when every point was used.
    pub earlier_side_left_out: Vec<String>,
    /// Every law that could be fitted, with its errors on every level.
    pub laws: Vec<LawPrediction>,
    /// Per level (by increasing mean force): the spread of the laws' errors.
    pub levels: Vec<LevelSpread>,
    /// The comparison with the model on every level not used.
    pub comparisons: Vec<LevelComparison>,
}

/// The comparison on one level not used.
#[derive(Debug, Clone, Serialize)]
pub struct LevelComparison {
    /// 1-based level (by increasing mean force).
    pub level: usize,
    /// File name of the level's sweep.
    pub file: String,
    /// The verdict on the level.
    pub comparison: Comparison,
}

/// Which of the fit levels' pointwise points the laws are fitted to.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Rows<'a> {
    /// Every point in the half-power bands.
    All,
    /// Given the fit levels' side comparisons (in `fit_levels` order, as the caller judged
    /// them): on a level whose two sides differ, only the resonance row and the rows after it
    /// ([`stationarity::settled_points`]).
    Settled(&'a [Option<stationarity::SideComparison>]),
}

/// Fit the laws to the pointwise backbone of the levels `fit_levels` (0-based into `sweeps`,
/// `frfs` their responses per unit force in the crate's convention, `levels` the same sweeps as
/// fit data), compute every level's response from each law, and compare the laws with the
/// model's errors `model` (every level) on the levels not used.
pub fn check(
    sweeps: &[Sweep],
    frfs: &[Vec<Complex64>],
    levels: &[LevelData],
    fit_levels: &[usize],
    model: &[LevelErrors],
) -> Result<ModelFreeCheck> {
    check_rows(sweeps, frfs, levels, fit_levels, model, Rows::All)
}

/// The check on the settled rows ([`Rows::Settled`]) when a fit level's two sides differ
/// (`stationarity`: every level's side comparison, `None` where not compared), or `None` when
/// every fit level is stationary or unchecked; an error as its reason.
pub fn check_settled(
    sweeps: &[Sweep],
    frfs: &[Vec<Complex64>],
    levels: &[LevelData],
    fit_levels: &[usize],
    model: &[LevelErrors],
    stationarity: &[Option<stationarity::SideComparison>],
) -> Option<std::result::Result<ModelFreeCheck, String>> {
    let fit_sides: Vec<Option<stationarity::SideComparison>> = fit_levels
        .iter()
        .map(|&i| stationarity[i].clone())
        .collect();
    fit_sides
        .iter()
        .any(|c| c.as_ref().is_some_and(|c| !c.stationary))
        .then(|| {
            check_rows(
                sweeps,
                frfs,
                levels,
                fit_levels,
                model,
                Rows::Settled(&fit_sides),
            )
            .map_err(|e| e.to_string())
        })
}

/// [`check`] on the fit levels' points chosen by `rows`.
pub fn check_rows(
    sweeps: &[Sweep],
    frfs: &[Vec<Complex64>],
    levels: &[LevelData],
    fit_levels: &[usize],
    model: &[LevelErrors],
    rows: Rows<'_>,
) -> Result<ModelFreeCheck> {
    let fit_sweeps: Vec<Sweep> = fit_levels.iter().map(|&i| sweeps[i].clone()).collect();
    let fit_frfs: Vec<Vec<Complex64>> = fit_levels.iter().map(|&i| frfs[i].clone()).collect();
    let backbones = backbone::from_data(&fit_sweeps, &fit_frfs)?;
    let lowest = backbones
        .iter()
        .min_by(|a, b| a.mean_force_n.total_cmp(&b.mean_force_n))
        .ok_or_else(|| Error::Data("model-free check: no fit level".into()))?;
    let modal_mass_kg = lowest.pointwise_modal_mass_kg;
    let mut earlier_side_left_out = Vec::new();
    let mut points: Vec<BackbonePoint> = Vec::new();
    for (j, b) in backbones.iter().enumerate() {
        match rows {
            Rows::All => points.extend(&b.points),
            Rows::Settled(sides) => {
                let sides = sides[j].as_ref();
                if sides.is_some_and(|c| !c.stationary) {
                    earlier_side_left_out.push(b.file.clone());
                }
                points.extend(stationarity::settled_points(b, sides));
            }
        }
    }
    let laws = BackboneLaw::all(&points);
    if laws.is_empty() {
        return Err(Error::Data(format!(
            "model-free check: {} pointwise backbone points in the fit levels' half-power bands \
             determine no law of the amplitude (at least 2 at two amplitudes are needed)",
            points.len()
        )));
    }
    // Amplitudes searched: up to 20 times the largest the data reach (any level's peak).
    let a_max = 20.0
        * sweeps
            .iter()
            .zip(frfs)
            .flat_map(|(s, y)| {
                s.rows
                    .iter()
                    .zip(y)
                    .map(|(r, y)| (y / s.quantity.from_displacement(r.omega())).norm() * r.force_n)
            })
            .fold(0.0, f64::max);
    let r = 1.0 / modal_mass_kg;
    let laws: Vec<LawPrediction> = laws
        .into_iter()
        .map(|law| {
            let errors = levels
                .iter()
                .enumerate()
                .map(|(i, l)| {
                    let drives: Vec<(f64, f64)> =
                        l.drives.iter().map(|d| (d.omega, d.force_n)).collect();
                    let x = law.receptance(r, &drives, a_max);
                    let failed = x.iter().filter(|v| !v.re.is_finite()).count();
                    LevelErrors::new(l, &l.from_receptance(&x), level_role(i, fit_levels), failed)
                })
                .collect();
            LawPrediction { law, errors }
        })
        .collect();
    let levels = (0..levels.len())
        .map(|i| {
            let e = || laws.iter().map(move |l| &l.errors[i]);
            LevelSpread {
                file: levels[i].name.clone(),
                role: level_role(i, fit_levels).to_string(),
                peak_error: Spread::of(e().map(|e| e.peak_error)),
                resonance_error_hz: Spread::of(e().map(|e| e.resonance_error_hz)),
                phase_resonance_error_hz: Spread::of(e().map(|e| e.phase_resonance_error_hz)),
                rms_complex: Spread::of(e().map(|e| e.rms_complex)),
                rms_at_resonance: Spread::of(e().map(rms_at_resonance)),
            }
        })
        .collect();
    let mut c = ModelFreeCheck {
        modal_mass_kg,
        points,
        earlier_side_left_out,
        laws,
        levels,
        comparisons: Vec::new(),
    };
    c.comparisons = (0..c.levels.len())
        .filter(|k| !fit_levels.contains(k))
        .map(|k| LevelComparison {
            level: k + 1,
            file: c.levels[k].file.clone(),
            comparison: c.compare(k, model),
        })
        .collect();
    Ok(c)
}

impl ModelFreeCheck {
    /// Report section: per level the laws' spread beside the model's errors, and per level not
    /// used what the comparison says.
    pub fn text(&self, model: &[LevelErrors]) -> String {
        let rows = if self.earlier_side_left_out.is_empty() {
            String::new()
        } else {
            format!(
                "; settled rows only: the rows before the resonance of {} left out as not \
                 stationary",
                self.earlier_side_left_out.join(", ")
            )
        };
        let mut s = format!(
            "\nmodel-free check{}: the fit levels' own backbone ({} pointwise points{rows}, modal mass \
             {:.4} kg) interpolated by {} smooth laws in the amplitude, each in a \
             single-nonlinear-mode response at the measured forces (no joint model, no effect):\n",
            if self.earlier_side_left_out.is_empty() { "" } else { " (settled rows)" },
            self.points.len(),
            self.modal_mass_kg,
            self.laws.len()
        );
        s += "  level  role        peak error: laws [min, max] / model   amplitude-peak Δf (Hz): laws / model   RMS at resonance: best law / model\n";
        let pct = |x: f64| format!("{:+.1}%", 100.0 * x);
        for (k, (l, m)) in self.levels.iter().zip(model).enumerate() {
            s += &format!(
                "  {:<5}  {:<10}  [{}, {}] / {:<24}  [{:+.3}, {:+.3}] / {:<+10.3}   {:.3} / {:.3}\n",
                k + 1,
                l.role,
                pct(l.peak_error.min),
                pct(l.peak_error.max),
                pct(m.peak_error),
                l.resonance_error_hz.min,
                l.resonance_error_hz.max,
                m.resonance_error_hz,
                l.rms_at_resonance.best_abs,
                rms_at_resonance(m),
            );
        }
        for c in &self.comparisons {
            s += &format!("  level {}: {}\n", c.level, c.comparison.describe());
        }
        s
    }
}

/// Every law's backbone over the points' amplitudes (40 points each), labelled by its id, for
/// the backbone figure and CSV; none when the check is not available.
pub fn law_curves(
    check: &std::result::Result<ModelFreeCheck, String>,
) -> Vec<(String, Vec<BackbonePoint>)> {
    check.as_ref().map_or(Vec::new(), |c| {
        c.laws
            .iter()
            .map(|l| (format!("model-free-{}", l.law.id), l.law.curve(40)))
            .collect()
    })
}

/// The report section of a check, or the reason it is not available.
pub fn section(
    check: &std::result::Result<ModelFreeCheck, String>,
    model: &[LevelErrors],
) -> String {
    match check {
        Ok(c) => c.text(model),
        Err(e) => format!("\nmodel-free check not available: {e}\n"),
    }
}

/// RMS complex error of the rows in the half-power band ("at resonance" region).
fn rms_at_resonance(e: &LevelErrors) -> f64 {
    e.regions
        .iter()
        .find(|r| r.region == "at resonance")
        .map_or(f64::NAN, |r| r.rms_complex)
}

/// A law counts as reproducing the fit levels when its RMS complex error in the half-power band
/// is at most this many times the model's on every fit level.
pub const REPRODUCTION_FACTOR: f64 = 2.0;
/// A law predicts a level not used better than the model when its error there is below this
/// fraction of the model's.
pub const BETTER_FACTOR: f64 = 0.8;

/// What the check says of one level not used (errors: RMS complex error in the half-power band,
/// fraction of the level's peak).
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "verdict", rename_all = "snake_case")]
pub enum Comparison {
    /// No law reproduces the fit levels within [`REPRODUCTION_FACTOR`] of the model: the
    /// synthesis does not represent these data well enough to judge (not one isolated mode with
    /// a smooth backbone in the band, or pointwise estimates too noisy).
    Inconclusive {
        /// The smallest, over the laws, of the worst ratio over the fit levels of the law's
        /// RMS complex error in the half-power band to the model's.
        best_fit_ratio: f64,
    },
    /// A law that reproduces the fit levels predicts this level clearly better than the model:
    /// the fit levels carry an amplitude dependence the model lacks.
    InterpolationBetter {
        /// Name of the law with the smallest error on this level.
        law: String,
        /// Its RMS complex error in the half-power band (fraction of the peak).
        law_error: f64,
        /// The model's RMS complex error in the half-power band (fraction of the peak).
        model_error: f64,
    },
    /// The laws that reproduce the fit levels do no better than the model here (the best of
    /// them picked on this level itself, which favours the laws): the fit levels show no
    /// amplitude trend the model misses on this level.
    NoBetter {
        /// Laws that reproduce the fit levels.
        laws: usize,
        /// Smallest RMS complex error in the half-power band among them (fraction of the peak).
        best_law_error: f64,
        /// The model's RMS complex error in the half-power band (fraction of the peak).
        model_error: f64,
        /// Smallest relative peak error among those laws (fraction).
        peak_error_min: f64,
        /// Largest relative peak error among those laws (fraction).
        peak_error_max: f64,
        /// The model's relative peak error (fraction).
        model_peak_error: f64,
    },
}

impl Comparison {
    /// One sentence for the report: the verdict, its numbers and what it means.
    pub fn describe(&self) -> String {
        match self {
            Comparison::Inconclusive { best_fit_ratio } => format!(
                "inconclusive — no law reproduces the fit levels within {REPRODUCTION_FACTOR}× \
                 the model's error at resonance (best {best_fit_ratio:.1}×): these data are not \
                 one nonlinear mode with a smooth backbone here, or its pointwise estimates are \
                 too noisy"
            ),
            Comparison::InterpolationBetter {
                law,
                law_error,
                model_error,
            } => format!(
                "interpolating the fit levels' backbone ({law}) predicts it better (RMS at \
                 resonance {law_error:.3} against the model's {model_error:.3}): the fit levels \
                 carry an amplitude dependence the model lacks"
            ),
            Comparison::NoBetter {
                laws,
                best_law_error,
                model_error,
                peak_error_min,
                peak_error_max,
                model_peak_error,
            } => format!(
                "the {laws} laws that reproduce the fit levels do no better than the model (RMS at \
                 resonance: best law {best_law_error:.3}, model {model_error:.3}; peak error laws \
                 {:+.1}…{:+.1} %, model {:+.1} %): the fit levels show no amplitude trend the \
                 model misses here — what remains on this level is not carried by them",
                100.0 * peak_error_min,
                100.0 * peak_error_max,
                100.0 * model_peak_error
            ),
        }
    }
}

impl ModelFreeCheck {
    /// The comparison on level `level` (0-based) with the model's errors on every level.
    pub fn compare(&self, level: usize, model: &[LevelErrors]) -> Comparison {
        let fit: Vec<usize> = (0..self.levels.len())
            .filter(|&k| self.levels[k].role == "fit")
            .collect();
        // Worst ratio over the fit levels of each law's error to the model's.
        let ratio = |law: &LawPrediction| {
            fit.iter()
                .map(|&k| rms_at_resonance(&law.errors[k]) / rms_at_resonance(&model[k]))
                .fold(
                    0.0,
                    |a: f64, r| if r.is_nan() { f64::INFINITY } else { a.max(r) },
                )
        };
        let qualified: Vec<&LawPrediction> = self
            .laws
            .iter()
            .filter(|l| ratio(l) <= REPRODUCTION_FACTOR)
            .collect();
        let model_error = rms_at_resonance(&model[level]);
        let err = |l: &LawPrediction| rms_at_resonance(&l.errors[level]);
        let best = qualified
            .iter()
            .copied()
            .filter(|l| err(l).is_finite())
            .min_by(|a, b| err(a).total_cmp(&err(b)));
        match best {
            None => Comparison::Inconclusive {
                best_fit_ratio: self.laws.iter().map(ratio).fold(f64::INFINITY, f64::min),
            },
            Some(b) if err(b) < BETTER_FACTOR * model_error => Comparison::InterpolationBetter {
                law: b.law.name.clone(),
                law_error: err(b),
                model_error,
            },
            Some(b) => {
                let peaks = qualified.iter().map(|l| l.errors[level].peak_error);
                Comparison::NoBetter {
                    laws: qualified.len(),
                    best_law_error: err(b),
                    model_error,
                    peak_error_min: peaks.clone().fold(f64::INFINITY, f64::min),
                    peak_error_max: peaks.fold(f64::NEG_INFINITY, f64::max),
                    model_peak_error: model[level].peak_error,
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(a: f64, f: f64, z: f64) -> BackbonePoint {
        BackbonePoint {
            amplitude_m: a,
            frequency_hz: f,
            damping_ratio: z,
        }
    }

    #[test]
    fn power_law_is_recovered_from_exact_points() {
        let law = |a: f64| 1e-3 + 2e-3 * (a / 3e-4).powf(1.7);
        let pts: Vec<BackbonePoint> = [5e-5, 8e-5, 1e-4, 2e-4, 2.5e-4, 3e-4]
            .iter()
            .map(|&a| point(a, 80.0, law(a)))
            .collect();
        let DampingLaw::PowerLaw {
            zeta0,
            c,
            p,
            a_ref_m,
        } = DampingLaw::fit_power_law(&pts, 3e-4).unwrap()
        else {
            panic!("not a power law")
        };
        assert!((p - 1.7).abs() < 1e-5, "p = {p}");
        assert!((zeta0 / 1e-3 - 1.0).abs() < 1e-5 && (c / 2e-3 - 1.0).abs() < 1e-5);
        assert_eq!(a_ref_m, 3e-4);
    }

    /// A linear mode (no amplitude dependence): every law reduces to constants and the
    /// single-nonlinear-mode response is the closed-form `R/(ω_n² − ω² + 2iζω_nω)`.
    #[test]
    fn a_linear_mode_gives_its_closed_form_receptance() {
        let (fnat, zeta, m) = (80.0, 2e-3, 2.5);
        let pts: Vec<BackbonePoint> = [6e-5, 9e-5, 1.2e-4, 2e-4, 2.6e-4]
            .iter()
            .map(|&a| point(a, fnat, zeta))
            .collect();
        let laws = BackboneLaw::all(&pts);
        assert_eq!(laws.len(), 6);
        let drives: Vec<(f64, f64)> = (0..41)
            .map(|k| (TAU * (79.0 + 0.05 * k as f64), 0.3 + 0.01 * k as f64))
            .collect();
        let wn = TAU * fnat;
        for law in &laws {
            let x = law.receptance(1.0 / m, &drives, 1e-2);
            for (&(w, _), x) in drives.iter().zip(&x) {
                let exact = 1.0 / (m * Complex64::new(wn * wn - w * w, 2.0 * zeta * wn * w));
                assert!(
                    (x - exact).norm() < 1e-8 * exact.norm(),
                    "{}: {x} vs {exact}",
                    law.name
                );
            }
        }
    }

    /// Hardening backbone with a fold: along an upward sweep the response stays on the upper
    /// branch past the frequency where a lower one appears (the root nearest the previous row).
    #[test]
    fn the_sweep_stays_on_its_branch_through_a_fold() {
        let law = BackboneLaw {
            name: "test".into(),
            id: "test".into(),
            frequency_hz: Polynomial {
                coefficients: vec![80.0, 0.0, 0.5],
                a_ref_m: 1e-4,
            },
            damping: DampingLaw::Polynomial(Polynomial {
                coefficients: vec![5e-4],
                a_ref_m: 1e-4,
            }),
            amplitude_range_m: (0.0, f64::INFINITY),
        };
        let m = 1.0;
        let drives: Vec<(f64, f64)> = (0..200)
            .map(|k| (TAU * (79.5 + 0.02 * k as f64), 0.053))
            .collect();
        let x = law.receptance(1.0 / m, &drives, 1e-2);
        let a: Vec<f64> = x.iter().zip(&drives).map(|(x, d)| x.norm() * d.1).collect();
        // The amplitude grows monotonically up to the jump down, then stays low.
        let peak = (0..a.len()).max_by(|&i, &j| a[i].total_cmp(&a[j])).unwrap();
        assert!(a[..=peak].windows(2).all(|w| w[1] >= w[0]));
        assert!(a[peak + 1] < 0.5 * a[peak], "no jump down after the fold");
        // At the peak the drive frequency is on the backbone well above 80 Hz (upper branch).
        let f_peak = drives[peak].0 / TAU;
        assert!(
            (f_peak - law.frequency_hz.at(a[peak])).abs() < 0.05 && f_peak > 80.5,
            "peak at {f_peak} Hz, backbone {}",
            law.frequency_hz.at(a[peak])
        );
    }
}
