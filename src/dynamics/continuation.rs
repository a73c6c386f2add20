//! Pseudo-arclength continuation of harmonic-balance solutions in frequency.
//!
//! The path `y(s) = (z(s), ω(s))` of solutions of `R(z, ω) = 0` is followed in scaled variables
//! `ŷ = (z/z_s, ω/ω_s)` (`ω_s` = the frequency span, `z_s` = the largest unknown seen so far)
//! with a predictor `ŷ_p = ŷ_i + Δs·t̂_i` and a bordered Newton corrector on
//! `[R(ŷ) = 0; t̂_iᵀ·(ŷ − ŷ_p) = 0]` (Keller 1977; Seydel, *Practical Bifurcation and Stability
//! Analysis*, 3rd ed., Springer 2010, §4.3–4.5). The bordered matrix stays regular at turning
//! points, so folds (Duffing) are followed. The direction `t̂` is the secant through the last
//! two points (unit length in the scaled variables; the first one solves
//! `[∂R/∂ŷ; eᵀ]·t̂ = [0; 1]`, `e` the unit frequency direction in the sweep's sense), and the
//! turning angle of the step control is measured between
//! successive secants.
//!
//! Step control: the step is rejected and halved when the corrector fails or when the path
//! turns by more than `max_angle_deg`; after an accepted step it is scaled by
//! `target_iterations / iterations` and by the turning angle (within ×0.5 … ×2). Its largest
//! value advances the frequency by at most `span/points` (so a sweep has about `points` points
//! where the response is smooth, and more where the path turns: at resonance peaks and folds)
//! and moves along the path by at most [`MAX_ARC_STEP`] (a tenth of the largest unknown, so a
//! peak gets some twenty points even where it is steep); its smallest is `10⁻⁴/points`.
//!
//! # Non-smooth transitions
//!
//! Where a contact starts or stops slipping (or separates) the branch is only piecewise smooth:
//! the describing function of a Jenkins slider, for one, has a slope discontinuity at the stick
//! limit `a = Fs/kt` (Caughey 1960), so the path has a kink whose angle does not shrink with the
//! step. Pseudo-arclength continuation assumes a smooth path and fails there in two ways
//! (on continuation through such points: Leine & Nijmeijer, *Dynamics and Bifurcations of
//! Non-Smooth Mechanical Systems*, Springer 2004; on the step control it builds on: Allgower &
//! Georg, *Introduction to Numerical Continuation Methods*, SIAM 2003, ch. 6):
//! the turning-angle test rejects every step across the kink, so the step collapses onto it; and
//! past the kink the corrector's hyperplane, normal to the secant, meets the continuation of the
//! old branch behind as well as the new one ahead, and Newton's method from the predictor may
//! end on either — a spurious fold that walks the sweep back. The step control here handles
//! both:
//!
//! * **Distance test**: a corrected point farther than `MAX_CORRECTION` steps from its
//!   predictor is on another branch (on a smooth path the distance is about the step times the
//!   turning angle); the step is halved and the next corrector starts from a fresh Jacobian at
//!   its predictor, so that Newton's method converges to the nearby branch.
//! * **Kink test**: when halving the step leaves the turning angle above the limit and no
//!   smaller than `KINK_ANGLE_RATIO` of its value (on a smooth path it shrinks with the step),
//!   the point is past a kink and is accepted, provided the turn is below `MAX_KINK_ANGLE` and
//!   the point lies within the reach of the new branch from the predictor (`1 + 1.2·tan(angle)`
//!   steps, the geometry of a hyperplane crossing a branch at that angle) and within
//!   `KINK_JUMP` of it; the secant through it then points along the new branch.
//!
//! Kinks passed are counted in [`Branch::kinks`]; turning points (sign changes of `dω/ds`) are
//! counted separately and are real folds. When the step still falls below its minimum, or the
//! point cap is reached, the sweep stops: [`sweep_partial`] keeps the points computed and says
//! why and what to change in [`Branch::stopped`]; [`sweep`] makes that an error.

use crate::core::error::{Error, Result};
use crate::dynamics::hbm::{HbmPoint, HbmSystem};
use nalgebra::{DMatrix, DVector};
use std::rc::Rc;
use std::time::Instant;

const TWO_PI: f64 = 2.0 * std::f64::consts::PI;

/// A step is rejected when the corrector ends farther than this many steps from its predictor
/// (on a smooth path the distance is of the order of the step times the turning angle): the
/// corrector's hyperplane crosses another branch, e.g. the continuation of the branch before a
/// kink.
const MAX_CORRECTION: f64 = 1.0;

/// Halving the step shrinks the angle between successive secants on a smooth path; at a kink it
/// does not. A turn above the angle limit that shrank by less than this factor when the step was
/// halved is taken as a kink and passed.
const KINK_ANGLE_RATIO: f64 = 0.9;

/// The largest turn passed as a kink (degrees): beyond, the hyperplane of the corrector meets
/// the branch behind as readily as the one ahead.
const MAX_KINK_ANGLE: f64 = 80.0;

/// Farthest a point past a kink may lie from the predictor, in the scaled variables: a farther
/// one makes a long secant along the new branch, which may curve away (the Nyquist circle of a
/// linear branch); the step is halved instead.
const KINK_JUMP: f64 = 0.02;

/// Largest step along the path in the scaled variables (unknowns relative to the largest seen,
/// frequency relative to the span).
pub const MAX_ARC_STEP: f64 = 0.1;

/// A chord corrector refreshes its Jacobian when, at the contraction seen, the tolerance is
/// more than this many steps away (a fresh Jacobian costs several residual evaluations).
const CHORD_STEPS_BEFORE_REFRESH: f64 = 6.0;

/// Settings of a frequency sweep.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ContinuationSettings {
    /// Start of the sweep (Hz); the sweep runs downwards when the end is below it.
    pub frequency_start_hz: f64,
    /// End of the sweep (Hz).
    pub frequency_end_hz: f64,
    /// Number of points along the frequency span where the response is smooth (sets the
    /// largest frequency step); resonance peaks and folds get more.
    pub points: usize,
    /// Corrector iterations aimed at.
    pub target_iterations: usize,
    /// Corrector iteration cap.
    pub max_corrector_iterations: usize,
    /// Largest angle between successive tangents (degrees) before a step is rejected.
    pub max_angle_deg: f64,
    /// Cap on the number of accepted points.
    pub max_points: usize,
}

impl ContinuationSettings {
    /// A sweep from `start_hz` to `end_hz` with the default controls (200 points).
    pub fn new(start_hz: f64, end_hz: f64) -> Self {
        Self {
            frequency_start_hz: start_hz,
            frequency_end_hz: end_hz,
            points: 200,
            target_iterations: 4,
            max_corrector_iterations: 12,
            max_angle_deg: 20.0,
            max_points: 4 * crate::core::limits::MAX_SWEEP_POINTS,
        }
    }

    fn validate(&self) -> Result<()> {
        crate::core::error::require_positive("frequency_start_Hz", self.frequency_start_hz)?;
        crate::core::error::require_positive("frequency_end_Hz", self.frequency_end_hz)?;
        if self.frequency_start_hz == self.frequency_end_hz {
            return Err(Error::param(
                "frequency_end_Hz",
                "must differ from the start frequency",
            ));
        }
        if self.points < 2 {
            return Err(Error::param("points", "at least 2"));
        }
        if !(self.max_angle_deg > 0.0 && self.max_angle_deg < 90.0) {
            return Err(Error::param("max_angle_deg", "must lie in (0, 90)"));
        }
        Ok(())
    }
}

/// A computed branch of the frequency response at one excitation level.
#[derive(Debug, Clone)]
pub struct Branch {
    /// Excitation level (multiplies [`Excitation::force`](crate::dynamics::hbm::Excitation::force)).
    pub level: f64,
    /// The accepted points, in path order.
    pub points: Vec<HbmPoint>,
    /// Steps rejected (corrector failure or turning angle) and retried with half the step.
    pub rejected_steps: usize,
    /// Turning points passed (sign changes of dω/ds).
    pub turning_points: usize,
    /// Kinks passed: points where the path turned by more than the angle limit whatever the
    /// step (non-smooth transitions, e.g. where a contact starts to slip).
    pub kinks: usize,
    /// Jacobian evaluations (each with one AFT Jacobian per element).
    pub jacobians: usize,
    /// Wall-clock time of the sweep (s).
    pub wall_time_s: f64,
    /// Why the sweep stopped before the end of its span, with what to change (`None`: it
    /// reached the end). The points computed up to there are kept.
    pub stopped: Option<String>,
}

impl Branch {
    /// `Ok` when the sweep reached the end of its span; otherwise the error of a sweep that
    /// stopped, naming the level and why.
    pub fn check_complete(&self) -> Result<()> {
        match &self.stopped {
            None => Ok(()),
            Some(why) => Err(Error::Data(format!(
                "continuation at level {:.4e}: {why}",
                self.level
            ))),
        }
    }

    /// Points at which some element's AFT state did not become periodic within the period cap
    /// (periodicity error above `tolerance`, the [`crate::dynamics::aft::AftSettings`]
    /// tolerance): their element forces are those of the last period integrated, not of the
    /// steady state.
    pub fn non_periodic_points(&self, tolerance: f64) -> usize {
        self.points
            .iter()
            .filter(|p| p.periodicity_error > tolerance || p.periodicity_error.is_nan())
            .count()
    }
}

/// Outcome of one corrector run.
struct Corrected {
    z: DVector<f64>,
    omega: f64,
    iterations: usize,
    /// Iterations after the last fresh Jacobian (`None`: the previous point's Jacobian served
    /// throughout).
    newton_iterations: Option<usize>,
    jacobians: usize,
    residual: f64,
    periodicity: f64,
    /// The factorisation the corrector ended with (for the next corrector).
    factorised: Option<Rc<Bordered>>,
    /// Start states of the elements' periodic cycles (warm start of the next AFT).
    states: Vec<crate::dynamics::aft::WarmStart>,
}

/// LU factorisation of the bordered matrix `A = [J·z_s, (∂R/∂ω)·ω_s; bᵀ]` at the point where the
/// Jacobian was last computed. Later corrector steps (chord iterations, also at later points)
/// reuse it with another border row `t` and unknowns' scale `z_s'` through the
/// Sherman–Morrison formula: with `D = diag(z_s'/z_s, …, 1)`, the matrix wanted is
/// `(A + e_n·vᵀ)·D`, `v = D⁻¹t − b`, and `(A + e_n·vᵀ)⁻¹·r = y − w·(vᵀy)/(1 + vᵀw)` with
/// `y = A⁻¹r`, `w = A⁻¹e_n` (Golub & Van Loan, *Matrix Computations*, 4th ed., §2.1.4).
struct Bordered {
    lu: nalgebra::LU<f64, nalgebra::Dyn, nalgebra::Dyn>,
    /// `A⁻¹·e_n`.
    w: DVector<f64>,
    border: DVector<f64>,
    zs: f64,
}

impl Bordered {
    /// Factorise `[jz·zs, jw·ws; borderᵀ]`; `None` when it is singular.
    fn new(
        jz: &DMatrix<f64>,
        jw: &DVector<f64>,
        border: &DVector<f64>,
        zs: f64,
        ws: f64,
    ) -> Option<Self> {
        let n = jz.nrows();
        let mut a = DMatrix::zeros(n + 1, n + 1);
        a.view_mut((0, 0), (n, n)).copy_from(jz);
        a.view_mut((0, 0), (n, n)).scale_mut(zs);
        a.view_mut((0, n), (n, 1)).copy_from(&(jw * ws));
        for c in 0..=n {
            a[(n, c)] = border[c];
        }
        let lu = a.lu();
        let mut e = DVector::zeros(n + 1);
        e[n] = 1.0;
        let w = lu.solve(&e)?;
        w.iter().all(|v| v.is_finite()).then(|| Self {
            lu,
            w,
            border: border.clone(),
            zs,
        })
    }

    /// Solve `[J·zs, (∂R/∂ω)·ω_s; tᵀ]·x = r`; `None` when the updated matrix is singular.
    fn solve(&self, t: &DVector<f64>, zs: f64, r: &DVector<f64>) -> Option<DVector<f64>> {
        let n = t.len() - 1;
        let ratio = zs / self.zs;
        let mut v = t - &self.border;
        if ratio != 1.0 {
            for k in 0..n {
                v[k] = t[k] / ratio - self.border[k];
            }
        }
        let mut y = self.lu.solve(r)?;
        let den = 1.0 + v.dot(&self.w);
        if den.abs() < 1e-12 * (1.0 + v.norm() * self.w.norm()) {
            return None;
        }
        y.axpy(-v.dot(&y) / den, &self.w, 1.0);
        if ratio != 1.0 {
            y.rows_mut(0, n).unscale_mut(ratio);
        }
        y.iter().all(|x| x.is_finite()).then_some(y)
    }
}

/// Follow the frequency response of `system` at excitation `level` over the settings' span.
/// `progress(fraction)` is called after each accepted point with the fraction of the span
/// covered. A sweep that stops before the end of its span is an error naming the level, the
/// frequency and what to change ([`sweep_partial`] keeps the points computed).
pub fn sweep(
    system: &HbmSystem<'_>,
    level: f64,
    settings: &ContinuationSettings,
    progress: &mut dyn FnMut(f64),
) -> Result<Branch> {
    let branch = sweep_partial(system, level, settings, progress)?;
    branch.check_complete()?;
    Ok(branch)
}

/// [`sweep`] that keeps the points computed when the sweep stops before the end of its span
/// ([`Branch::stopped`] says why and what to change). `Err` only when not even the first point
/// was solved or the settings are invalid.
pub fn sweep_partial(
    system: &HbmSystem<'_>,
    level: f64,
    settings: &ContinuationSettings,
    progress: &mut dyn FnMut(f64),
) -> Result<Branch> {
    settings.validate()?;
    let t0 = Instant::now();
    let w0 = TWO_PI * settings.frequency_start_hz;
    let w1 = TWO_PI * settings.frequency_end_hz;
    let dir = (w1 - w0).signum();
    let ws = (w1 - w0).abs();
    let frequency_step = 1.0 / settings.points as f64;
    let min_step = frequency_step * 1e-4;
    // Largest step along direction t: frequency advance ≤ span/points, path step ≤ MAX_ARC_STEP.
    let max_step =
        |t: &DVector<f64>| (frequency_step / t[t.len() - 1].abs()).clamp(min_step, MAX_ARC_STEP);
    let tol = system.newton.tolerance;
    let n = system.unknowns();
    let singular = |omega: f64| {
        Error::Data(format!(
            "singular bordered harmonic-balance Jacobian at {:.6} Hz (level {level:.4e})",
            omega / TWO_PI
        ))
    };

    let first = system.solve(w0, level, None)?;
    let mut jacobians = first.iterations + 1;
    let mut zs = first.z.amax().max(f64::MIN_POSITIVE);
    let ev = system.evaluate(&first.z, w0, level, true);
    jacobians += 1;
    let mut states = ev.element_states;
    // Initial tangent along +ω in the sweep direction: [J·zs, jw·ws; eᵀ]·t = [0; 1].
    let mut e = DVector::zeros(n + 1);
    e[n] = dir;
    let mut factorised = Bordered::new(&ev.jacobian, &ev.d_omega, &e, zs, ws).map(Rc::new);
    let mut t = factorised.as_ref().ok_or_else(|| singular(w0))?.w.clone();
    t /= t.norm();
    let mut points = vec![first];
    let mut step = max_step(&t);
    let mut rejected = 0;
    let mut turning = 0;
    progress(0.0);
    let max_angle = settings.max_angle_deg.to_radians();
    let mut stopped = None;
    let mut kinks = 0;
    let scaled = |p: &HbmPoint, zs: f64| {
        let mut y = DVector::zeros(n + 1);
        y.rows_mut(0, n).copy_from(&(&p.z / zs));
        y[n] = p.omega / ws;
        y
    };
    loop {
        let last = points.last().expect("at least the first point");
        let y_hat = scaled(last, zs);
        // Predictor + corrector, halving the step on failure.
        let mut halvings = 0;
        let mut last_failure = String::new();
        let mut previous_angle: Option<f64> = None;
        let step_tried = step;
        let accepted = loop {
            let yp = &y_hat + &t * step;
            match correct(
                system,
                level,
                &yp,
                &t,
                zs,
                ws,
                settings,
                tol,
                factorised.clone(),
                &states,
            ) {
                Ok(c) => {
                    jacobians += c.jacobians;
                    // Next predictor direction: the secant through the last two points.
                    let mut tn = DVector::zeros(n + 1);
                    tn.rows_mut(0, n).copy_from(&((&c.z - &last.z) / zs));
                    tn[n] = (c.omega - last.omega) / ws;
                    let norm = tn.norm();
                    if norm > 0.0 {
                        tn /= norm;
                    } else {
                        tn.copy_from(&t);
                    }
                    let angle = t.dot(&tn).clamp(-1.0, 1.0).acos();
                    // Distance of the corrected point from the predictor, in steps.
                    let mut yc = DVector::zeros(n + 1);
                    yc.rows_mut(0, n).copy_from(&(&c.z / zs));
                    yc[n] = c.omega / ws;
                    let moved = (&yc - &yp).norm() / step;
                    // A kink: halving the step did not shrink the turn (on a smooth path the
                    // angle between secants shrinks with the step).
                    let kink = previous_angle.is_some_and(|a| angle > KINK_ANGLE_RATIO * a);
                    previous_angle = Some(angle);
                    // Past a kink by a fraction of the step, the corrector's hyperplane meets
                    // the new branch `tan(angle)` steps from the predictor at most.
                    let reach = if angle < MAX_KINK_ANGLE.to_radians() {
                        MAX_CORRECTION + 1.2 * angle.tan()
                    } else {
                        0.0
                    };
                    let smooth = angle <= max_angle && moved <= MAX_CORRECTION;
                    let passes_kink = (kink || step <= 2.0 * min_step)
                        && moved <= reach
                        && moved * step <= KINK_JUMP;
                    factorised = c.factorised.clone();
                    if smooth || passes_kink {
                        if !smooth {
                            kinks += 1;
                        }
                        break Some((c, tn, angle));
                    }
                    last_failure = if moved > MAX_CORRECTION.max(reach) {
                        // Another branch crossing the corrector's hyperplane: retry closer,
                        // from a Jacobian at the new predictor.
                        factorised = None;
                        format!(
                            "the corrector moved {moved:.1} steps from the predictor (to another \
                             branch)"
                        )
                    } else {
                        format!("path turned by {:.1}°", angle.to_degrees())
                    };
                }
                Err(msg) => {
                    jacobians += settings.max_corrector_iterations;
                    factorised = None;
                    last_failure = msg;
                }
            }
            rejected += 1;
            halvings += 1;
            step *= 0.5;
            if step < min_step {
                break None;
            }
        };
        let Some((corr, tn, angle)) = accepted else {
            stopped = Some(format!(
                "continuation stopped after {:.6} Hz ({} points): step halved {halvings} times from \
                 {step_tried:.3e} to below {min_step:.3e}; last attempt: {last_failure}. \
                 More time_samples or harmonics resolve a non-smooth response better; a sweep \
                 started just beyond {:.6} Hz continues from there",
                last.omega / TWO_PI,
                points.len(),
                last.omega / TWO_PI
            ));
            break;
        };
        if tn[n].signum() != t[n].signum() && tn[n] != 0.0 && t[n] != 0.0 {
            turning += 1;
        }
        // Step adaptation on the corrector's iterations with a fresh Jacobian (chord iterations
        // on an older one say more about the Jacobian's age than about the step: such a step is
        // kept or grown) and on the turning angle.
        let iterations = corr
            .newton_iterations
            .unwrap_or(settings.target_iterations.min(corr.iterations));
        let mut factor = settings.target_iterations as f64 / iterations.max(1) as f64;
        if angle > 0.0 {
            factor = factor.min(0.5 * max_angle / angle);
        }
        // Rescale the direction if the unknowns' scale grows.
        let new_zs = zs.max(corr.z.amax());
        t = tn;
        if new_zs > zs {
            for v in t.rows_mut(0, n).iter_mut() {
                *v *= zs / new_zs;
            }
            t /= t.norm();
            zs = new_zs;
        }
        step = (step * factor.clamp(0.5, 2.0)).clamp(min_step, max_step(&t));
        states = corr.states;
        let past_end = (corr.omega - w1) * dir >= 0.0;
        let before_start = (corr.omega - w0) * dir < -0.05 * ws;
        let point = HbmPoint {
            omega: corr.omega,
            level,
            z: corr.z,
            iterations: corr.iterations,
            residual: corr.residual,
            converged: true,
            periodicity_error: corr.periodicity,
            wall_time_s: t0.elapsed().as_secs_f64(),
        };
        if past_end {
            // Land exactly on the end frequency from the interpolated state.
            let prev = points.last().expect("non-empty");
            let a = (w1 - prev.omega) / (point.omega - prev.omega);
            let guess = &prev.z + (&point.z - &prev.z) * a;
            match system.solve(w1, level, Some(&guess)) {
                Ok(end) => {
                    jacobians += end.iterations + 1;
                    points.push(end);
                    progress(1.0);
                }
                Err(e) => {
                    stopped = Some(format!(
                        "the end frequency was not solved from the branch's last points: {e}"
                    ))
                }
            }
            break;
        }
        if before_start {
            stopped = Some(format!(
                "the branch turned back below the start frequency ({:.6} Hz) after {} points: a \
                 fold whose other side lies before the span; start the sweep lower",
                point.omega / TWO_PI,
                points.len()
            ));
            break;
        }
        points.push(point);
        progress(((corr.omega - w0) / (w1 - w0)).clamp(0.0, 1.0));
        if points.len() >= settings.max_points {
            stopped = Some(format!(
                "reached its cap of {} accepted points (`sweep.max_points`; by default the \
                 larger of 20 000 and 20 × `sweep.points`) at {:.6} Hz: the branch folds or \
                 refines more than a response sweep should; raise `sweep.max_points` or narrow \
                 the frequency span",
                settings.max_points,
                corr.omega / TWO_PI,
            ));
            break;
        }
    }
    Ok(Branch {
        level,
        points,
        rejected_steps: rejected,
        turning_points: turning,
        kinks,
        jacobians,
        wall_time_s: t0.elapsed().as_secs_f64(),
        stopped,
    })
}

/// The solution on the branch between three consecutive points `points` at arclength `at`
/// (measured from the middle point, in the scaled variables of [`point_arclengths`]): the
/// parabola through the three points in arclength predicts it, and the bordered corrector finds
/// it on the hyperplane normal to the parabola's tangent there. `None` when the corrector fails.
pub fn point_between(
    system: &HbmSystem<'_>,
    level: f64,
    points: [&HbmPoint; 3],
    at: f64,
) -> Option<HbmPoint> {
    let n = system.unknowns();
    let (zs, ws, s) = point_arclengths(points);
    let y: Vec<DVector<f64>> = points
        .iter()
        .map(|p| {
            let mut v = DVector::zeros(n + 1);
            v.rows_mut(0, n).copy_from(&(&p.z / zs));
            v[n] = p.omega / ws;
            v
        })
        .collect();
    // Lagrange basis of the parabola through (s_k, y_k) and its derivative at `at`.
    let mut yp = DVector::zeros(n + 1);
    let mut t = DVector::zeros(n + 1);
    for k in 0..3 {
        let (a, b) = ((k + 1) % 3, (k + 2) % 3);
        let den = (s[k] - s[a]) * (s[k] - s[b]);
        let l = (at - s[a]) * (at - s[b]) / den;
        let dl = (2.0 * at - s[a] - s[b]) / den;
        yp.axpy(l, &y[k], 1.0);
        t.axpy(dl, &y[k], 1.0);
    }
    let norm = t.norm();
    if norm.is_nan() || norm <= 0.0 {
        return None;
    }
    t /= norm;
    let settings = ContinuationSettings::new(1.0, 2.0);
    let c = correct(
        system,
        level,
        &yp,
        &t,
        zs,
        ws,
        &settings,
        system.newton.tolerance,
        None,
        &[],
    )
    .ok()?;
    Some(HbmPoint {
        omega: c.omega,
        level,
        z: c.z,
        iterations: c.iterations,
        residual: c.residual,
        converged: true,
        periodicity_error: c.periodicity,
        wall_time_s: 0.0,
    })
}

/// Scales and arclengths of three consecutive branch points: the unknowns' scale (their largest
/// magnitude), the frequency scale (the three points' frequency range, or the middle frequency
/// if they share it) and the signed distances of the points from the middle one in the scaled
/// variables.
pub fn point_arclengths(points: [&HbmPoint; 3]) -> (f64, f64, [f64; 3]) {
    let zs = points
        .iter()
        .map(|p| p.z.amax())
        .fold(f64::MIN_POSITIVE, f64::max);
    let (lo, hi) = points
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p.omega), hi.max(p.omega))
        });
    let ws = if hi > lo {
        hi - lo
    } else {
        points[1].omega.abs().max(1.0)
    };
    let d = |a: &HbmPoint, b: &HbmPoint| {
        (((&a.z - &b.z) / zs).norm_squared() + ((a.omega - b.omega) / ws).powi(2)).sqrt()
    };
    (
        zs,
        ws,
        [-d(points[0], points[1]), 0.0, d(points[1], points[2])],
    )
}

/// Bordered corrector from the predicted point `yp` on the hyperplane `tᵀ·(ŷ − ŷ_p) = 0`:
/// Newton's method with the Jacobian kept (chord iterations, residual-only AFT evaluations warm
/// started from the previous iterate's periodic states) while the residual falls at least by
/// half per iteration, refreshed otherwise. It starts from `factorised` (the last Jacobian of
/// the previous point) when given. `Err` carries what went wrong.
#[allow(clippy::too_many_arguments)]
fn correct(
    system: &HbmSystem<'_>,
    level: f64,
    yp: &DVector<f64>,
    t: &DVector<f64>,
    zs: f64,
    ws: f64,
    settings: &ContinuationSettings,
    tol: f64,
    factorised: Option<Rc<Bordered>>,
    states: &[crate::dynamics::aft::WarmStart],
) -> std::result::Result<Corrected, String> {
    let n = system.unknowns();
    let mut y = yp.clone();
    let mut first_residual = f64::NAN;
    let mut prev_residual = f64::INFINITY;
    let mut lu = factorised;
    let mut warm: Vec<crate::dynamics::aft::WarmStart> = states.to_vec();
    let mut jacobians = 0;
    let mut refreshed_at = None;
    for it in 0..=settings.max_corrector_iterations {
        let z = y.rows(0, n) * zs;
        let omega = y[n] * ws;
        if omega <= 0.0 {
            return Err("predicted frequency ≤ 0".into());
        }
        let refresh = lu.is_none();
        let mut ev = system.evaluate_from(&z, omega, level, refresh, Some(&warm));
        warm = std::mem::take(&mut ev.element_states);
        let rel = ev.relative_residual();
        if !rel.is_finite() {
            return Err("residual not finite".into());
        }
        if it == 0 {
            first_residual = rel;
        }
        if rel <= tol {
            if refresh {
                jacobians += 1;
                lu = Bordered::new(&ev.jacobian, &ev.d_omega, t, zs, ws).map(Rc::new);
            }
            return Ok(Corrected {
                z,
                omega,
                iterations: it,
                newton_iterations: refreshed_at.map(|k| it - k),
                jacobians,
                residual: rel,
                periodicity: ev.periodicity_error,
                factorised: lu,
                states: warm,
            });
        }
        if it == settings.max_corrector_iterations {
            return Err(format!(
                "corrector: {it} iterations at {:.6} Hz, relative residual {rel:.3e} (from {first_residual:.3e}) > {tol:.1e}",
                omega / TWO_PI
            ));
        }
        if it >= 3 && rel > first_residual * 10.0 {
            return Err(format!(
                "corrector diverging at {:.6} Hz: relative residual {rel:.3e} after {it} iterations",
                omega / TWO_PI
            ));
        }
        // Chord step while it contracts fast enough and the tolerance is a few steps away at
        // the contraction seen; fresh Jacobian otherwise.
        let ratio = rel / prev_residual;
        let slow = ratio > 0.5
            || (ratio > 0.0 && (tol / rel).ln() / ratio.ln() > CHORD_STEPS_BEFORE_REFRESH);
        let (ev, refreshed) = if !refresh && slow {
            let mut e = system.evaluate_from(&z, omega, level, true, Some(&warm));
            warm = std::mem::take(&mut e.element_states);
            (e, true)
        } else {
            (ev, refresh)
        };
        if refreshed {
            jacobians += 1;
            refreshed_at = Some(it);
            lu = Some(Rc::new(
                Bordered::new(&ev.jacobian, &ev.d_omega, t, zs, ws).ok_or_else(|| {
                    format!("singular bordered Jacobian at {:.6} Hz", omega / TWO_PI)
                })?,
            ));
        }
        prev_residual = rel;
        let g = t.dot(&(&y - yp));
        let mut b = DVector::zeros(n + 1);
        b.rows_mut(0, n).copy_from(&(-&ev.residual));
        b[n] = -g;
        let dy = match lu.as_ref().expect("factorised").solve(t, zs, &b) {
            Some(dy) => dy,
            None if !refreshed => {
                // The border update broke down: refresh at the next iteration.
                lu = None;
                prev_residual = f64::INFINITY;
                continue;
            }
            None => {
                return Err(format!(
                    "singular bordered Jacobian at {:.6} Hz",
                    omega / TWO_PI
                ))
            }
        };
        y += dy;
    }
    Err("corrector: no iteration".into())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(periodicity_error: f64) -> HbmPoint {
        HbmPoint {
            omega: 1.0,
            level: 1.0,
            z: DVector::zeros(1),
            iterations: 1,
            residual: 0.0,
            converged: true,
            periodicity_error,
            wall_time_s: 0.0,
        }
    }

    #[test]
    fn points_above_the_periodicity_tolerance_or_nan_are_counted() {
        let branch = Branch {
            level: 1.0,
            points: [0.0, 1e-13, 1e-12, 2e-12, 0.5, f64::NAN]
                .into_iter()
                .map(point)
                .collect(),
            rejected_steps: 0,
            turning_points: 0,
            kinks: 0,
            jacobians: 0,
            wall_time_s: 0.0,
            stopped: None,
        };
        assert_eq!(branch.non_periodic_points(1e-12), 3);
        assert_eq!(branch.non_periodic_points(1.0), 1);
    }
}
