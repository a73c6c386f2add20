//! Transient response: the free decay of a structure with its contact elements, and the
//! amplitude-dependent frequency and damping read from it — how joints are tested (ring-down)
//! and what the single-nonlinear-mode picture of a jointed structure is compared with.
//!
//! # Run
//!
//! Newmark's average-acceleration scheme with the elements' exact time-discrete update
//! ([`crate::dynamics::time_integration::Newmark`]), no external force, from rest in the shape
//! of a linearised mode: the mode `φ` of `K_stick·φ = ω0²·M·φ`, where `K_stick` adds to `K` the
//! elements' tangent at their virgin state (their stick stiffness), scaled so that the observed
//! response starts at the amplitude asked for. The elements start virgin at `q = 0` and are
//! loaded to the initial position. The time step is `T0/steps_per_period` with `T0 = 2π/ω0`.
//!
//! # Instantaneous frequency and damping (peak picking)
//!
//! The extrema `e_j` of the response (each refined by the parabola through the extreme sample
//! and its neighbours) give half peak-to-peak amplitudes `A_j = |e_{j+1} − e_j|/2` at the
//! mid-times `t_j = (τ_j + τ_{j+1})/2` (the peak-to-peak form is immune to the static offset a
//! stuck slider leaves). Over one period, `A_j → A_{j+2}` (one estimate per half period, each
//! spanning a whole period):
//!
//! ```text
//! f = 1/(t_{j+2} − t_j),   δ = ln(A_j/A_{j+2}),   ζ = δ/√(4π² + δ²),   a = √(A_j·A_{j+2})
//! ```
//!
//! (the logarithmic decrement of a viscously damped oscillator, exact for constant `ζ`; for an
//! amplitude-dependent damping it is the period's average, assigned to the geometric mean
//! amplitude). For light damping the envelope then follows the first-order averaging equation
//! `da/dt = −ζ(a)·ω(a)·a` (Krylov–Bogoliubov), which is how it is compared with a describing
//! function or a nonlinear mode's backbone.

use crate::core::error::{Error, Result};
use crate::core::output::OutputSet;
use crate::core::plot::{line_plot, LinePlot, Scale, Series};
use crate::dynamics::model::{undamped_modes, Structure};
use crate::dynamics::model_file;
use crate::dynamics::time_integration::Newmark;
use crate::element::StepPartials;
use nalgebra::{DMatrix, DVector};
use std::time::Instant;

/// Settings of a free-decay run.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct DecaySettings {
    /// Which linearised mode the structure starts in (1 = the lowest).
    pub mode: usize,
    /// Initial amplitude of the observed response (m).
    pub amplitude_m: f64,
    /// Periods of the linearised mode integrated.
    pub periods: usize,
    /// Time steps per period of the linearised mode.
    pub steps_per_period: usize,
}

impl Default for DecaySettings {
    fn default() -> Self {
        Self {
            mode: 1,
            amplitude_m: 1e-5,
            periods: 100,
            steps_per_period: 256,
        }
    }
}

/// One period of the decay, from peak picking (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct DecayCycle {
    /// Mid-time of the period (s).
    pub time_s: f64,
    /// Amplitude: geometric mean of the half peak-to-peak amplitudes at its ends (m).
    pub amplitude_m: f64,
    /// Frequency: the inverse of the period (Hz).
    pub frequency_hz: f64,
    /// Damping ratio from the logarithmic decrement over the period.
    pub damping_ratio: f64,
}

/// A free decay: the observed response at every time step and its cycles.
#[derive(Debug, Clone, serde::Serialize)]
pub struct DecayResult {
    /// The settings it ran with.
    pub settings: DecaySettings,
    /// Natural frequency of the linearised (stuck) mode it started in (Hz).
    pub linear_frequency_hz: f64,
    /// The linearised mode shape, scaled to the initial displacement (m).
    pub initial_displacement_m: Vec<f64>,
    /// Time of every sample (s).
    pub time_s: Vec<f64>,
    /// The observed response at every sample (m).
    pub response_m: Vec<f64>,
    /// Frequency and damping per period, in time order.
    pub cycles: Vec<DecayCycle>,
    /// Wall-clock time of the integration (s).
    pub wall_time_s: f64,
}

/// `K` plus the elements' tangents at their virgin state (one-sided, at a displacement of
/// `probe` m in every direction): the stiffness of the stuck structure.
pub fn stick_stiffness(structure: &Structure, probe: f64) -> DMatrix<f64> {
    let mut k = structure.stiffness.clone();
    for e in &structure.elements {
        let (m, d) = (e.element.state_len(), e.element.dofs());
        let mut virgin = vec![0.0; m];
        e.element.virgin_state(&mut virgin);
        let mut state = vec![0.0; m];
        let mut force = vec![0.0; d];
        let mut partials = StepPartials::new(m, d);
        e.element.step(
            &virgin,
            &vec![0.0; d],
            &vec![probe; d],
            &mut state,
            &mut force,
            Some(&mut partials),
        );
        let ke = DMatrix::from_row_slice(d, d, &partials.df_du1);
        k += e.map.transpose() * ke * &e.map;
    }
    k
}

/// Mode `index` (1-based, ascending frequency) of `K·φ = ω²·M·φ` for symmetric `K` (its
/// symmetric part is used) and symmetric positive-definite `M`: `(ω, φ)` with `φᵀMφ = 1`.
pub fn linear_mode(
    mass: &DMatrix<f64>,
    stiffness: &DMatrix<f64>,
    index: usize,
) -> Result<(f64, DVector<f64>)> {
    let n = mass.nrows();
    if index == 0 || index > n {
        return Err(Error::param(
            "--mode",
            format!("{index}: the structure has modes 1 to {n}"),
        ));
    }
    let (eigenvalues, mut shapes) = undamped_modes(mass, stiffness)?;
    let lambda = eigenvalues[index - 1];
    if lambda <= 0.0 {
        return Err(Error::param(
            "--mode",
            format!("mode {index} has ω² = {lambda:e} ≤ 0: the stuck structure is not stable"),
        ));
    }
    Ok((lambda.sqrt(), shapes.swap_remove(index - 1)))
}

/// Free decay of `structure` from the linearised mode `settings.mode`, scaled so that the
/// observation `response·q` starts at `settings.amplitude_m` (see the module documentation).
///
/// Errors: bad settings (named), a mass that is not positive definite, a mode the response does
/// not see, a time step that does not converge.
pub fn free_decay(
    structure: &Structure,
    response: &DVector<f64>,
    settings: &DecaySettings,
    progress: &mut dyn FnMut(f64),
) -> Result<DecayResult> {
    let t0 = Instant::now();
    let n = structure.n();
    if structure.cyclic.is_some() {
        return Err(Error::param(
            "cyclic",
            "time integration of a cyclic sector is not implemented (integrate the full structure)",
        ));
    }
    crate::core::error::require_positive("--amplitude-m", settings.amplitude_m)?;
    if settings.steps_per_period < 16 {
        return Err(Error::param(
            "--steps-per-period",
            format!(
                "{}: at least 16 steps per period are needed to follow the decay",
                settings.steps_per_period
            ),
        ));
    }
    if settings.periods < 3 {
        return Err(Error::param(
            "--periods",
            format!(
                "{}: at least 3 periods give a frequency and a damping",
                settings.periods
            ),
        ));
    }
    if response.len() != n {
        return Err(Error::param("response", "row of the wrong length"));
    }
    let k_stick = stick_stiffness(structure, 1e-12 * settings.amplitude_m);
    let (omega0, phi) = linear_mode(&structure.mass, &k_stick, settings.mode)?;
    let seen = response.dot(&phi);
    if seen.abs() <= 1e-9 * response.norm() * phi.amax() {
        return Err(Error::param(
            "--mode",
            format!(
                "the response does not see mode {} (its displacement there is zero)",
                settings.mode
            ),
        ));
    }
    let q0 = phi * (settings.amplitude_m / seen);
    let dt = 2.0 * std::f64::consts::PI / omega0 / settings.steps_per_period as f64;
    let zero = DVector::zeros(n);
    let mut newmark = Newmark::new(structure, &q0, &zero, &zero, dt)?;
    let steps = settings.periods * settings.steps_per_period;
    let f1 = vec![0.0; n];
    let mut time_s = Vec::with_capacity(steps + 1);
    let mut response_m = Vec::with_capacity(steps + 1);
    let observe = |q: &[f64]| {
        q.iter()
            .zip(response.iter())
            .map(|(a, b)| a * b)
            .sum::<f64>()
    };
    time_s.push(0.0);
    response_m.push(observe(newmark.q()));
    for i in 1..=steps {
        let t = i as f64 * dt;
        newmark.step(&f1, t)?;
        time_s.push(t);
        response_m.push(observe(newmark.q()));
        if i % settings.steps_per_period == 0 {
            progress(i as f64 / steps as f64);
        }
    }
    let cycles = decay_cycles(&time_s, &response_m);
    Ok(DecayResult {
        settings: *settings,
        linear_frequency_hz: omega0 / (2.0 * std::f64::consts::PI),
        initial_displacement_m: q0.iter().copied().collect(),
        time_s,
        response_m,
        cycles,
        wall_time_s: t0.elapsed().as_secs_f64(),
    })
}

/// The extrema of `x` sampled at `t` (uniform steps), each refined by the parabola through the
/// extreme sample and its neighbours: `(time, value)` alternating maxima and minima.
pub fn extrema(t: &[f64], x: &[f64]) -> Vec<(f64, f64)> {
    // (time, value, is a maximum)
    let mut out: Vec<(f64, f64, bool)> = Vec::new();
    for i in 1..x.len().saturating_sub(1) {
        let (a, b, c) = (x[i - 1], x[i], x[i + 1]);
        let is_max = b > a && b >= c;
        if !(is_max || (b < a && b <= c)) {
            continue;
        }
        // Vertex of the parabola through (−1, a), (0, b), (1, c).
        let curv = a - 2.0 * b + c;
        let (s, v) = if curv != 0.0 {
            let s = 0.5 * (a - c) / curv;
            (s, b - 0.25 * (a - c) * s)
        } else {
            (0.0, b)
        };
        let e = (t[i] + s * (t[i + 1] - t[i]), v, is_max);
        // Alternating: of two maxima (or minima) in a row, keep the larger (smaller).
        match out.last_mut() {
            Some(last) if last.2 == is_max => {
                if (is_max && e.1 > last.1) || (!is_max && e.1 < last.1) {
                    *last = e;
                }
            }
            _ => out.push(e),
        }
    }
    out.into_iter().map(|(t, v, _)| (t, v)).collect()
}

/// Frequency, damping ratio and amplitude per period from the extrema of the response (see the
/// module documentation); periods whose amplitude no longer falls (the decay has ended in
/// stick, or at the rounding level) are left out from the first such period on.
pub fn decay_cycles(t: &[f64], x: &[f64]) -> Vec<DecayCycle> {
    let e = extrema(t, x);
    let half: Vec<(f64, f64)> = e
        .windows(2)
        .map(|w| (0.5 * (w[0].0 + w[1].0), 0.5 * (w[1].1 - w[0].1).abs()))
        .collect();
    let mut out = Vec::new();
    for j in 0..half.len().saturating_sub(2) {
        let ((ta, aa), (tb, ab)) = (half[j], half[j + 2]);
        if !(ab > 0.0 && aa > ab) {
            break;
        }
        let delta = (aa / ab).ln();
        out.push(DecayCycle {
            time_s: 0.5 * (ta + tb),
            amplitude_m: (aa * ab).sqrt(),
            frequency_hz: 1.0 / (tb - ta),
            damping_ratio: delta / (4.0 * std::f64::consts::PI.powi(2) + delta * delta).sqrt(),
        });
    }
    out
}

/// The files of a decay run.
pub const OUTPUTS: [&str; 4] = [
    "decay.csv",
    "decay_cycles.csv",
    "decay.png",
    "decay_backbone.png",
];

/// The output set of a decay run of the model file `model` into `out_dir` (`flag` names it in
/// errors), declared before any work; the model file and every file it names are inputs.
pub fn output_set(
    model: &std::path::Path,
    out_dir: &std::path::Path,
    flag: &str,
) -> Result<OutputSet> {
    let mut out = OutputSet::in_dir(out_dir, flag)?;
    out.writes(&OUTPUTS)?;
    model_file::declare_inputs(&mut out, model)?;
    Ok(out)
}

impl DecayResult {
    /// Write [`OUTPUTS`]: the response at every step, the frequency and damping per period, the
    /// time history and the backbone (frequency and damping ratio against amplitude). `header`
    /// (one line, without `#`) names the model and the response.
    pub fn write(&self, out: &mut OutputSet, header: &str) -> Result<()> {
        use std::fmt::Write as _;
        let s = &self.settings;
        let head = format!(
            "# {header}\n# free decay from rest in linearised mode {} ({:.6} Hz, elements stuck), initial response amplitude {:e} m; Newmark average acceleration, {} steps per period, {} periods\n",
            s.mode, self.linear_frequency_hz, s.amplitude_m, s.steps_per_period, s.periods
        );
        let mut csv = head.clone();
        csv.push_str("time_s,response_m\n");
        for (t, x) in self.time_s.iter().zip(&self.response_m) {
            let _ = writeln!(csv, "{t:e},{x:e}");
        }
        crate::core::output::write_string_atomic(&out.path("decay.csv")?, &csv)?;
        let mut cyc = head;
        cyc.push_str("# per period from peak picking: amplitude = geometric mean of the half peak-to-peak amplitudes at its ends; frequency = 1/period; damping ratio from the logarithmic decrement, delta/sqrt(4 pi^2 + delta^2)\n");
        cyc.push_str("time_s,amplitude_m,frequency_Hz,damping_ratio\n");
        for c in &self.cycles {
            let _ = writeln!(
                cyc,
                "{:e},{:e},{:.9e},{:.6e}",
                c.time_s, c.amplitude_m, c.frequency_hz, c.damping_ratio
            );
        }
        crate::core::output::write_string_atomic(&out.path("decay_cycles.csv")?, &cyc)?;
        let step = (self.time_s.len() / 20_000).max(1);
        line_plot(
            &out.path("decay.png")?,
            &LinePlot {
                title: "Free decay",
                x_label: "time (s)",
                y_label: "response (m)",
                x_scale: Scale::Linear,
                y_scale: Scale::Linear,
            },
            &[Series::line(
                "response",
                self.time_s
                    .iter()
                    .zip(&self.response_m)
                    .step_by(step)
                    .map(|(&t, &x)| (t, x))
                    .collect(),
            )],
        )?;
        let f0 = self.linear_frequency_hz;
        line_plot(
            &out.path("decay_backbone.png")?,
            &LinePlot {
                title: "Backbone from the decay: frequency / stuck frequency, damping ratio (%)",
                x_label: "amplitude (m)",
                y_label: "frequency ratio (-), damping ratio (%)",
                x_scale: Scale::Log,
                y_scale: Scale::Linear,
            },
            &[
                Series::markers(
                    "frequency / stuck frequency",
                    self.cycles
                        .iter()
                        .map(|c| (c.amplitude_m, c.frequency_hz / f0))
                        .collect(),
                ),
                Series::markers(
                    "damping ratio (%)",
                    self.cycles
                        .iter()
                        .map(|c| (c.amplitude_m, 100.0 * c.damping_ratio))
                        .collect(),
                ),
            ],
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A viscously damped linear oscillator sampled coarsely: peak picking returns its damped
    /// frequency and its damping ratio (the logarithmic decrement is exact for it).
    #[test]
    fn peak_picking_recovers_a_linear_oscillator() {
        let (f0, zeta) = (12.0_f64, 0.02_f64);
        let w0 = 2.0 * std::f64::consts::PI * f0;
        let wd = w0 * (1.0 - zeta * zeta).sqrt();
        let dt = 1.0 / (f0 * 64.0);
        let t: Vec<f64> = (0..64 * 40).map(|i| i as f64 * dt).collect();
        let x: Vec<f64> = t
            .iter()
            .map(|&t| 3e-4 * (-zeta * w0 * t).exp() * (wd * t + 0.3).cos() + 1e-4)
            .collect();
        let cycles = decay_cycles(&t, &x);
        assert!(cycles.len() > 30, "{}", cycles.len());
        for c in &cycles {
            assert!(
                (c.frequency_hz / (wd / (2.0 * std::f64::consts::PI)) - 1.0).abs() < 2e-3,
                "{c:?}"
            );
            assert!((c.damping_ratio / zeta - 1.0).abs() < 2e-2, "{c:?}");
            let envelope = 3e-4 * (-zeta * w0 * c.time_s).exp();
            assert!((c.amplitude_m / envelope - 1.0).abs() < 2e-2, "{c:?}");
        }
    }
}
