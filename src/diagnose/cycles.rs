//! Cycle segmentation of a displacement history and the phases of a hysteresis loop.
//!
//! Reversals are found with a hysteresis (zig-zag) detector: after a running extremum, a reversal
//! is declared only once the displacement has moved back by more than a threshold (a fraction of
//! the robust total range, 1st to 99th percentile), so measurement noise smaller than that
//! threshold cannot create spurious reversals. The reversal is placed at the extremum of the
//! lightly smoothed displacement. A complete cycle is two consecutive half-cycles (reversal to
//! reversal to reversal).
//!
//! Phases of a half-cycle (after a reversal the contact first sticks, then slips partially, then
//! fully) are classified from a smooth model force: `Reversal` for the first 2 % of the stroke,
//! then by the tangent stiffness `k_t = dF/dx` relative to the half-cycle's initial stiffness:
//! `Stick` above 0.8, `Macroslip` below 0.1, `Microslip` between.

use crate::core::error::{Error, Result};
use crate::core::stats::percentile_nearest;
use serde::Serialize;

/// Reversal threshold as a fraction of the robust displacement range.
pub const REVERSAL_THRESHOLD: f64 = 0.05;
/// Minimum number of samples in a half-cycle; shorter oscillations are noise, not drive.
pub const MIN_HALF_CYCLE_SAMPLES: usize = 8;

/// A half-cycle: samples `start..=end` between two reversals, moving in `direction` (±1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct HalfCycle {
    /// First sample (a reversal).
    pub start: usize,
    /// Last sample (the next reversal).
    pub end: usize,
    /// Direction of motion: +1 for increasing displacement, −1 for decreasing.
    pub direction: i8,
}

/// Segmentation of a record into reversals and complete cycles.
#[derive(Debug, Clone, Serialize)]
pub struct Cycles {
    /// Sample indices of displacement reversals.
    pub reversals: Vec<usize>,
    /// Half-cycles between consecutive reversals.
    pub half_cycles: Vec<HalfCycle>,
    /// Complete cycles as sample ranges `[start, end)` (two half-cycles each).
    pub cycles: Vec<(usize, usize)>,
    /// Mean cycle period (s).
    pub period_s: f64,
    /// Mean displacement amplitude (m), half the mean peak-to-peak stroke.
    pub amplitude_m: f64,
}

/// Centred moving average of half-width `h` (shrinking at the ends).
fn moving_average(x: &[f64], h: usize) -> Vec<f64> {
    let n = x.len();
    let mut prefix = vec![0.0; n + 1];
    for i in 0..n {
        prefix[i + 1] = prefix[i] + x[i];
    }
    (0..n)
        .map(|i| {
            let (a, b) = (i.saturating_sub(h), (i + h + 1).min(n));
            (prefix[b] - prefix[a]) / (b - a) as f64
        })
        .collect()
}

/// Detect displacement reversals and segment the record into complete cycles.
///
/// Errors: constant displacement (no drive), oscillation only at the noise scale, or fewer than
/// three reversals (no complete cycle).
pub fn segment(time_s: &[f64], displacement_m: &[f64]) -> Result<Cycles> {
    let x = displacement_m;
    let n = x.len();
    let (lo, hi) = (percentile_nearest(x, 0.01), percentile_nearest(x, 0.99));
    let range = hi - lo;
    let scale = x.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    if range <= 1e-9 * scale || range == 0.0 || range.is_nan() {
        return Err(Error::Data(format!(
            "displacement is constant (range {range:.3e} m over {n} samples): no cycle to analyse"
        )));
    }
    let xs = moving_average(x, 2);
    let thr = REVERSAL_THRESHOLD * range;
    // Zig-zag: direction 0 until the first move larger than the threshold.
    let mut reversals = Vec::new();
    let (mut imax, mut imin) = (0usize, 0usize);
    let mut dir = 0i8;
    for i in 1..n {
        if xs[i] > xs[imax] {
            imax = i;
        }
        if xs[i] < xs[imin] {
            imin = i;
        }
        match dir {
            0 => {
                if xs[i] - xs[imin] > thr {
                    dir = 1;
                    imax = i;
                } else if xs[imax] - xs[i] > thr {
                    dir = -1;
                    imin = i;
                }
            }
            1 => {
                if xs[imax] - xs[i] > thr {
                    reversals.push(imax);
                    dir = -1;
                    imin = i;
                }
            }
            _ => {
                if xs[i] - xs[imin] > thr {
                    reversals.push(imin);
                    dir = 1;
                    imax = i;
                }
            }
        }
    }
    if reversals.len() >= 2 {
        let mut lens: Vec<usize> = reversals.windows(2).map(|w| w[1] - w[0]).collect();
        lens.sort_unstable();
        let median = lens[lens.len() / 2];
        if median < MIN_HALF_CYCLE_SAMPLES {
            return Err(Error::Data(format!(
                "displacement shows no drive: reversals every {median} samples (median), \
                 fewer than {MIN_HALF_CYCLE_SAMPLES}; the displacement is constant up to noise"
            )));
        }
    }
    if reversals.len() < 3 {
        return Err(Error::Data(format!(
            "no complete cycle in the record: {} displacement reversal(s) found, 3 needed \
             (threshold {:.3e} m, {:.0} % of the displacement range)",
            reversals.len(),
            thr,
            100.0 * REVERSAL_THRESHOLD
        )));
    }
    let half_cycles: Vec<HalfCycle> = reversals
        .windows(2)
        .map(|w| HalfCycle {
            start: w[0],
            end: w[1],
            direction: if x[w[1]] > x[w[0]] { 1 } else { -1 },
        })
        .collect();
    let cycles: Vec<(usize, usize)> = (0..reversals.len() - 2)
        .step_by(2)
        .map(|k| (reversals[k], reversals[k + 2]))
        .collect();
    let period_s = cycles
        .iter()
        .map(|&(a, b)| time_s[b] - time_s[a])
        .sum::<f64>()
        / cycles.len() as f64;
    let amplitude_m = half_cycles
        .iter()
        .map(|h| (x[h.end] - x[h.start]).abs())
        .sum::<f64>()
        / half_cycles.len() as f64
        / 2.0;
    Ok(Cycles {
        reversals,
        half_cycles,
        cycles,
        period_s,
        amplitude_m,
    })
}

/// Energy the loop dissipates, ∮F dx (J), averaged over the complete cycles (trapezoidal
/// rule). A friction contact dissipates, so a measured loop has ∮F dx > 0 when the force and
/// the displacement share the element's sign convention.
pub fn energy_per_cycle(x: &[f64], f: &[f64], cycles: &Cycles) -> f64 {
    let per: f64 = cycles
        .cycles
        .iter()
        .map(|&(a, b)| {
            (a..b)
                .map(|i| 0.5 * (f[i] + f[i + 1]) * (x[i + 1] - x[i]))
                .sum::<f64>()
        })
        .sum();
    per / cycles.cycles.len().max(1) as f64
}

/// Phase of the contact within a half-cycle.
///
/// The first four are classified from a model force ([`classify_phases`]); `Clearance` (the
/// force stays near zero while the drive crosses a free play) and `Closing` (the first 5 % of
/// the stroke after the play is taken up) are found in the measured force
/// (`super::residual::clearance_regions`), since a model without a clearance cannot show them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Phase {
    /// The first [`REVERSAL_FRACTION`] of the stroke after a reversal.
    Reversal,
    /// Tangent stiffness above 80 % of the half-cycle's initial stiffness.
    Stick,
    /// Tangent stiffness between 10 % and 80 % of the initial stiffness.
    Microslip,
    /// Tangent stiffness below 10 % of the initial stiffness.
    Macroslip,
    /// The measured force stays near zero while the drive crosses a free play.
    Clearance,
    /// The first 5 % of the stroke after a free play is taken up.
    Closing,
}

impl Phase {
    /// Every phase, in report order.
    pub const ALL: [Phase; 6] = [
        Phase::Reversal,
        Phase::Stick,
        Phase::Microslip,
        Phase::Macroslip,
        Phase::Clearance,
        Phase::Closing,
    ];

    /// Identifier of the phase in reports and JSON ("reversal", "stick", …).
    pub fn name(self) -> &'static str {
        match self {
            Phase::Reversal => "reversal",
            Phase::Stick => "stick",
            Phase::Microslip => "microslip",
            Phase::Macroslip => "macroslip",
            Phase::Clearance => "clearance",
            Phase::Closing => "closing",
        }
    }

    /// Words for a report ("at the closing of a clearance").
    pub fn description(self) -> &'static str {
        match self {
            Phase::Reversal => "at the reversals",
            Phase::Stick => "in stick",
            Phase::Microslip => "in microslip",
            Phase::Macroslip => "in macroslip",
            Phase::Clearance => "across the clearance (near-zero force plateau)",
            Phase::Closing => "at the closing of a clearance",
        }
    }
}

/// Fraction of the stroke after a reversal counted as the `Reversal` phase.
pub const REVERSAL_FRACTION: f64 = 0.02;

/// Classify every sample inside a half-cycle by phase, from a smooth model force `f` (N).
/// Samples outside the half-cycles (initial loading, trailing part) are `None`.
pub fn classify_phases(x: &[f64], f: &[f64], cycles: &Cycles) -> Vec<Option<Phase>> {
    let mut phase = vec![None; x.len()];
    for h in &cycles.half_cycles {
        let stroke = (x[h.end] - x[h.start]).abs();
        let d = f64::from(h.direction);
        // Secant stiffness over a few samples, robust to tiny displacement steps.
        let tangent = |i: usize| -> Option<f64> {
            let (a, b) = (i.saturating_sub(2).max(h.start), (i + 2).min(h.end));
            let dx = (x[b] - x[a]) * d;
            (dx > 1e-6 * stroke).then(|| (f[b] - f[a]) * d / dx)
        };
        let k0 = (h.start..=h.end)
            .filter(|&i| (x[i] - x[h.start]).abs() <= 0.05 * stroke)
            .filter_map(tangent)
            .fold(0.0_f64, f64::max);
        for (i, p) in phase.iter_mut().enumerate().take(h.end).skip(h.start) {
            let travel = (x[i] - x[h.start]).abs();
            *p = Some(if travel <= REVERSAL_FRACTION * stroke {
                Phase::Reversal
            } else {
                match tangent(i) {
                    Some(k) if k0 > 0.0 && k > 0.8 * k0 => Phase::Stick,
                    Some(k) if k0 > 0.0 && k < 0.1 * k0 => Phase::Macroslip,
                    Some(_) => Phase::Microslip,
                    None => Phase::Reversal,
                }
            });
        }
    }
    phase
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    fn sine(n_cycles: f64, per_cycle: usize, noise: f64) -> (Vec<f64>, Vec<f64>) {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
        let g = Normal::new(0.0, noise).unwrap();
        let n = (n_cycles * per_cycle as f64) as usize;
        let t: Vec<f64> = (0..n).map(|i| i as f64 / per_cycle as f64).collect();
        let x = t
            .iter()
            .map(|&t| 1e-3 * (std::f64::consts::TAU * t).sin() + g.sample(&mut rng))
            .collect();
        (t, x)
    }

    #[test]
    fn noisy_sine_gives_exact_cycle_count() {
        // 4.5 cycles of sin: extrema at t = 0.25, 0.75, ... → 9 reversals, 4 complete cycles.
        let (t, x) = sine(4.5, 400, 2e-5);
        let c = segment(&t, &x).unwrap();
        assert_eq!(c.reversals.len(), 9);
        assert_eq!(c.cycles.len(), 4);
        assert!((c.period_s - 1.0).abs() < 0.01, "{}", c.period_s);
        assert!((c.amplitude_m - 1e-3).abs() < 5e-5, "{}", c.amplitude_m);
        for (k, &r) in c.reversals.iter().enumerate() {
            let expected = (0.25 + 0.5 * k as f64) * 400.0;
            assert!((r as f64 - expected).abs() < 15.0, "{r} vs {expected}");
        }
    }

    #[test]
    fn errors_for_constant_noise_and_incomplete() {
        let t: Vec<f64> = (0..500).map(f64::from).collect();
        let e = segment(&t, &vec![1e-3; 500]).unwrap_err().to_string();
        assert!(e.contains("constant"), "{e}");
        let (t2, x2) = sine(0.0, 400, 0.0);
        assert!(t2.is_empty() && x2.is_empty());
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let g = Normal::new(0.0, 1e-6).unwrap();
        let noise: Vec<f64> = (0..500).map(|_| 1e-3 + g.sample(&mut rng)).collect();
        let e = segment(&t, &noise).unwrap_err().to_string();
        assert!(e.contains("no drive") || e.contains("constant"), "{e}");
        let (t3, x3) = sine(0.9, 400, 0.0);
        let e = segment(&t3, &x3).unwrap_err().to_string();
        assert!(e.contains("no complete cycle"), "{e}");
    }

    #[test]
    fn phases_of_an_elastic_plastic_loop() {
        // Jenkins loop: stiffness 1 until |f| = 0.5, then flat.
        let (t, x) = sine(2.5, 400, 0.0);
        let x: Vec<f64> = x.iter().map(|v| v * 1e3).collect();
        let mut f = vec![0.0; x.len()];
        for i in 1..x.len() {
            f[i] = (f[i - 1] + x[i] - x[i - 1]).clamp(-0.5, 0.5);
        }
        let c = segment(&t, &x).unwrap();
        let p = classify_phases(&x, &f, &c);
        let count = |ph| p.iter().filter(|q| **q == Some(ph)).count();
        assert!(count(Phase::Stick) > 0 && count(Phase::Macroslip) > 0);
        assert!(count(Phase::Reversal) > 0);
        // A sample just before the next reversal is in macroslip.
        let h = c.half_cycles[1];
        assert_eq!(p[h.end - 5], Some(Phase::Macroslip));
    }
}
