//! What characterises a residual (measured − model force, N), against the noise floor:
//! where in the loop it sits, whether it is a ringing at a frequency, and the clearance
//! plateaus of the measured force.
//!
//! **Where.** Samples are classified by phase: reversal, stick, microslip, macroslip from the
//! model force (`super::cycles::classify_phases`), and clearance / closing from the measured
//! force ([`clearance_regions`]). Per phase, over the held-out cycles: RMS residual in N and as
//! a multiple of the noise floor σ, and the phase's share of the *excess* residual energy
//! `Σ max(r² − σ², 0)`. The
//! residual is "concentrated at" the phases whose RMS exceeds 2σ and that carry at least 20 %
//! of the excess, in decreasing share.
//!
//! **Ringing** ([`ringing`]). A lightly damped mode in the load path rings after each sudden
//! change of the contact force. Its signature in the residual is a local maximum of the
//! spectrum well above the drive's low harmonics, and an autocorrelation that oscillates and
//! decays. (1) Periodogram of the Hann-windowed residual over the complete cycles, smoothed
//! over two harmonic spacings of the drive; between 5× the drive frequency and 0.8× Nyquist,
//! the largest ratio of the spectrum to its local background (the median within a factor 1.4
//! in frequency) must be ≥ 8, and the top of its hill (the largest value within a factor 1.4)
//! a true peak (half-power points on both sides within a factor 1.4). (2) The residual is high-passed by subtracting its moving
//! average over one period of the peak frequency (which removes slow misfit and leaves that
//! frequency untouched); its autocorrelation, whose envelope decays as `exp(−ζωτ)` for a
//! lightly damped mode under impulsive or broadband excitation (the basis of the Natural
//! Excitation Technique; James, Carne & Lauffer 1993), gives the frequency from the spacing of
//! its peaks (up to 0.4 of the drive period: a ringing restarted at every reversal makes the
//! autocorrelation rise again towards half the period). The damping ratio comes from the free
//! decays in time, the logarithmic decrement of successive peak amplitudes
//! (`free_decay_damping`): an autocorrelation envelope mixes the decay with the interference
//! of successive restarts and was 10× off on a synthetic record. (3) A ringing is reported
//! when the first autocorrelation peak is
//! ≥ 0.3 and the high-passed residual's RMS is ≥ 1.5σ_hp (the high-pass noise estimate).

use super::cycles::{classify_phases, Cycles, Phase};
use realfft::RealFftPlanner;
use serde::Serialize;

/// Residual statistics of one phase.
#[derive(Debug, Clone, Serialize)]
pub struct PhaseStats {
    /// The phase the statistics are over.
    pub phase: Phase,
    /// Held-out samples in the phase.
    pub samples: usize,
    /// Mean residual signed with the direction of motion (N); `None` without samples.
    pub mean_residual_n: Option<f64>,
    /// RMS residual (N).
    pub rms_residual_n: Option<f64>,
    /// RMS residual / noise floor.
    pub rms_over_noise: Option<f64>,
    /// Share of the excess residual energy (0 … 1).
    pub excess_share: f64,
}

/// Smallest share of the zero-crossing band (`|F| < 0.15·F̂`) that a clearance's plateau
/// (`|F| < 0.05·F̂`) spans.
pub const CLEARANCE_DWELL: f64 = 0.5;

/// A zero-force plateau of the measured force after a reversal: the drive crosses a clearance.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct ClearanceRegion {
    /// Half-cycle index.
    pub half_cycle: usize,
    /// First sample of the plateau (samples `start..=end`).
    pub start: usize,
    /// Last sample of the plateau.
    pub end: usize,
    /// Last sample of the closing (5 % of the stroke after the plateau).
    pub closing_end: usize,
    /// Displacement span of the plateau (m): the free play, `2g` of the backlash link.
    pub span_m: f64,
}

/// Zero-force plateaus of the (smoothed) measured force `y` (N) against displacement `x` (m).
///
/// In each half-cycle, the band `|F| < 0.15·F̂` where the force crosses zero towards the
/// direction of motion is found; the plateau runs from the first to the last sample of the
/// band within `0.05·F̂` of zero. It is a clearance when it spans at least [`CLEARANCE_DWELL`]
/// (half) of the band's displacement and at least 1 % of the stroke: a contact without play
/// crosses the band at a finite, nearly constant slope and spends about a third of it within
/// `±0.05·F̂` (Valanis, Jenkins, Iwan, rough-patch loops alike), whereas behind a free play the
/// force dwells at zero while the drive crosses it. Displacement spans rather than local
/// slopes: at a few hundred samples per cycle a plateau may hold only a handful of samples.
pub fn clearance_regions(
    x: &[f64],
    y: &[f64],
    cycles: &Cycles,
    force_scale: f64,
) -> Vec<ClearanceRegion> {
    let mut out = Vec::new();
    for (k, h) in cycles.half_cycles.iter().enumerate() {
        let (a, b) = (h.start, h.end);
        let d = f64::from(h.direction);
        let stroke = (x[b] - x[a]).abs();
        if stroke <= 0.0 || d * y[a] >= 0.0 {
            continue;
        }
        // The band |F| < 0.15 F̂ where the force crosses zero towards the direction of motion.
        let Some(s0) = (a..=b).find(|&i| d * y[i] > -0.15 * force_scale) else {
            continue;
        };
        let e0 = (s0..=b)
            .find(|&i| d * y[i] > 0.15 * force_scale)
            .unwrap_or(b);
        // The plateau: from the first to the last sample of the band within 5 % of F̂ of zero.
        let near: Vec<usize> = (s0..=e0)
            .filter(|&i| y[i].abs() < 0.05 * force_scale)
            .collect();
        let (Some(&s), Some(&e)) = (near.first(), near.last()) else {
            continue;
        };
        // The force dwells at zero over most of the crossing: a contact without play crosses
        // the band at a finite slope and spends about a third of it within ±0.05·F̂.
        let band = (x[e0] - x[s0]).abs();
        if band <= 0.0 || (x[e] - x[s]).abs() < CLEARANCE_DWELL * band {
            continue;
        }
        let span = (x[e] - x[s]).abs();
        if span < 0.01 * stroke {
            continue;
        }
        let closing_end = (e..=b)
            .find(|&i| (x[i] - x[e]) * d >= 0.05 * stroke)
            .unwrap_or(b);
        out.push(ClearanceRegion {
            half_cycle: k,
            start: s,
            end: e,
            closing_end,
            span_m: span,
        });
    }
    out
}

/// Phases of every sample: from the model force `f`, with the clearance plateaus and closings
/// of the measured force laid over them when they are found in at least half of the
/// half-cycles (a systematic feature, not a stray sample).
pub fn phases(
    x: &[f64],
    f: &[f64],
    cycles: &Cycles,
    clearances: &[ClearanceRegion],
) -> Vec<Option<Phase>> {
    let mut p = classify_phases(x, f, cycles);
    if 2 * clearances.len() >= cycles.half_cycles.len() {
        for c in clearances {
            p[c.start..=c.end]
                .iter_mut()
                .for_each(|v| *v = Some(Phase::Clearance));
            p[c.end + 1..c.closing_end.max(c.end + 1)]
                .iter_mut()
                .for_each(|v| *v = Some(Phase::Closing));
        }
    }
    p
}

/// Per-phase statistics of the residual `y − f` over the samples in `mask`.
pub fn phase_stats(
    y: &[f64],
    f: &[f64],
    velocity: &[f64],
    phases: &[Option<Phase>],
    mask: &[bool],
    sigma: f64,
) -> Vec<PhaseStats> {
    let idx_all: Vec<usize> = (0..y.len())
        .filter(|&i| mask[i] && phases[i].is_some())
        .collect();
    let excess = |i: usize| ((y[i] - f[i]).powi(2) - sigma * sigma).max(0.0);
    let total_excess: f64 = idx_all.iter().map(|&i| excess(i)).sum();
    Phase::ALL
        .iter()
        .map(|&ph| {
            let idx: Vec<usize> = idx_all
                .iter()
                .copied()
                .filter(|&i| phases[i] == Some(ph))
                .collect();
            let n = idx.len() as f64;
            let has = !idx.is_empty();
            let rms = (idx.iter().map(|&i| (y[i] - f[i]).powi(2)).sum::<f64>() / n).sqrt();
            PhaseStats {
                phase: ph,
                samples: idx.len(),
                mean_residual_n: has.then(|| {
                    idx.iter()
                        .map(|&i| (y[i] - f[i]) * velocity[i].signum())
                        .sum::<f64>()
                        / n
                }),
                rms_residual_n: has.then_some(rms),
                rms_over_noise: has.then_some(rms / sigma),
                excess_share: if total_excess > 0.0 {
                    idx.iter().map(|&i| excess(i)).sum::<f64>() / total_excess
                } else {
                    0.0
                },
            }
        })
        .collect()
}

/// Phases that carry the excess residual: RMS > 2σ and ≥ 20 % of the excess energy, largest
/// share first.
pub fn concentrated_at(stats: &[PhaseStats]) -> Vec<Phase> {
    let mut v: Vec<&PhaseStats> = stats
        .iter()
        .filter(|s| s.rms_over_noise.is_some_and(|r| r > 2.0) && s.excess_share >= 0.2)
        .collect();
    v.sort_by(|a, b| b.excess_share.total_cmp(&a.excess_share));
    v.iter().map(|s| s.phase).collect()
}

/// Smallest ratio of the spectral peak to its local background for a ringing.
pub const MIN_PROMINENCE: f64 = 8.0;

/// A ringing found in a residual.
#[derive(Debug, Clone, Serialize)]
pub struct Ringing {
    /// Frequency (Hz), from the autocorrelation peaks.
    pub frequency_hz: f64,
    /// Damping ratio ζ from the free decays (logarithmic decrement; `None` without a free
    /// decay of at least five half-periods above 3σ).
    pub damping_ratio: Option<f64>,
    /// RMS of the ringing above the noise, `√(RMS_hp² − σ²)` (N).
    pub rms_n: f64,
    /// Largest |high-passed residual| (N).
    pub peak_n: f64,
    /// Smoothed spectral peak over its local background.
    pub prominence: f64,
    /// First autocorrelation peak of the high-passed residual.
    pub first_correlation_peak: f64,
}

/// Damping ratio from the free decays of the high-passed residual `hp` (sampled at `dt`,
/// ringing period `period` samples, frequency `f` Hz): the largest |hp| in each half-period
/// window; runs of at least five successive falling peaks, all above `3σ`, are free decays
/// (logarithmic decrement): the slope of `ln peak` against time is `−ζ·2πf`. The median over
/// runs (a run cut short by the next excitation, whose ringing may cancel the last one, gives
/// a too steep decay; the median is robust to a few). `None` without such a run.
fn free_decay_damping(hp: &[f64], dt: f64, period: f64, f: f64, sigma: f64) -> Option<f64> {
    let half = 0.5 * period;
    let mut peaks: Vec<(f64, f64)> = Vec::new();
    let mut start = 0.0;
    while start + half < hp.len() as f64 {
        let (a, b) = (
            start as usize,
            ((start + half) as usize).max(start as usize + 1),
        );
        let (j, v) = (a..b.min(hp.len()))
            .map(|i| (i, hp[i].abs()))
            .max_by(|p, q| p.1.total_cmp(&q.1))?;
        peaks.push((j as f64 * dt, v));
        start += half;
    }
    let mut rates = Vec::new();
    let mut run: Vec<(f64, f64)> = Vec::new();
    let mut close = |run: &mut Vec<(f64, f64)>| {
        if run.len() >= 5 {
            let n = run.len() as f64;
            let (mt, ml) = (
                run.iter().map(|p| p.0).sum::<f64>() / n,
                run.iter().map(|p| p.1.ln()).sum::<f64>() / n,
            );
            let slope = run
                .iter()
                .map(|p| (p.0 - mt) * (p.1.ln() - ml))
                .sum::<f64>()
                / run.iter().map(|p| (p.0 - mt).powi(2)).sum::<f64>();
            rates.push(-slope / (std::f64::consts::TAU * f));
        }
        run.clear();
    };
    for p in peaks {
        if p.1 > 3.0 * sigma && run.last().is_some_and(|q| p.1 < q.1) {
            run.push(p);
        } else {
            close(&mut run);
            if p.1 > 3.0 * sigma {
                run.push(p);
            }
        }
    }
    close(&mut run);
    if rates.is_empty() {
        return None;
    }
    rates.sort_by(|a, b| a.total_cmp(b));
    Some(rates[rates.len() / 2])
}

/// Centred moving average over `len` samples (shrinking at the ends).
fn moving_average(x: &[f64], len: usize) -> Vec<f64> {
    let n = x.len();
    let h = len / 2;
    let mut prefix = vec![0.0; n + 1];
    for i in 0..n {
        prefix[i + 1] = prefix[i] + x[i];
    }
    (0..n)
        .map(|i| {
            let (a, b) = (i.saturating_sub(h), (i + len - h).min(n));
            (prefix[b] - prefix[a]) / (b - a) as f64
        })
        .collect()
}

/// Search the residual `r` (N, uniformly sampled at `dt` s, covering `cycles_in_window`
/// drive cycles) for a ringing (module documentation); `sigma` is the high-frequency noise
/// (the high-pass estimate of [`super::noise`], N): a ringing is fast, so it is weighed against
/// the fast part of the scatter, not against slow cycle-to-cycle variation.
pub fn ringing(r: &[f64], dt: f64, cycles_in_window: f64, sigma: f64) -> Option<Ringing> {
    let n = r.len();
    if n < 64 || dt.is_nan() || dt <= 0.0 {
        return None;
    }
    let mean = r.iter().sum::<f64>() / n as f64;
    let mut buf: Vec<f64> = r
        .iter()
        .enumerate()
        .map(|(i, v)| {
            let w = 0.5 - 0.5 * (std::f64::consts::TAU * i as f64 / (n - 1) as f64).cos();
            (v - mean) * w
        })
        .collect();
    let fft = RealFftPlanner::<f64>::new().plan_fft_forward(n);
    let mut spec = fft.make_output_vec();
    fft.process(&mut buf, &mut spec).ok()?;
    let power: Vec<f64> = spec.iter().map(|c| c.norm_sqr()).collect();
    // Bin k is at k/(n dt) Hz; drive harmonic m at m·cycles_in_window.
    // Two harmonic spacings of the drive (an odd number of bins).
    let width = ((cycles_in_window).round() as usize).max(1) * 2 + 1;
    let smooth = moving_average(&power, width);
    let k_lo = (5.0 * cycles_in_window).ceil() as usize;
    let k_hi = (0.8 * (power.len() - 1) as f64) as usize;
    if k_hi <= k_lo + 2 * width {
        return None;
    }
    // Prominence over the local background: the median of the smoothed spectrum within a
    // factor 1.4 in frequency (a broad misfit spectrum falls smoothly; a mode stands out).
    let background = |k: usize| -> f64 {
        let (a, b) = (
            ((k as f64 / 1.4) as usize).max(k_lo),
            ((k as f64 * 1.4) as usize).min(k_hi),
        );
        let mut w = smooth[a..=b].to_vec();
        w.sort_by(|p, q| p.total_cmp(q));
        w[w.len() / 2]
    };
    let (k, prominence) = (k_lo + width / 2..=k_hi - width / 2)
        .map(|k| (k, smooth[k] / background(k).max(f64::MIN_POSITIVE)))
        .max_by(|a, b| a.1.total_cmp(&b.1))?;
    // The top of the hill holding the most prominent bin: the largest value within a factor
    // 1.4 in frequency (the prominence is largest on the flank where the background falls).
    let (lo, hi) = (
        ((k as f64 / 1.4) as usize).max(k_lo),
        ((k as f64 * 1.4) as usize).min(k_hi),
    );
    let k = (lo..=hi).max_by(|&p, &q| smooth[p].total_cmp(&smooth[q]))?;
    let peak = smooth[k];
    let (a, b) = (
        ((k as f64 / 1.4) as usize).max(k_lo),
        ((k as f64 * 1.4) as usize).min(k_hi),
    );
    let half_left = smooth[a..k].iter().any(|&v| v < 0.5 * peak);
    let half_right = smooth[k + 1..=b].iter().any(|&v| v < 0.5 * peak);
    if prominence < MIN_PROMINENCE || !half_left || !half_right {
        return None;
    }
    let f_peak = k as f64 / (n as f64 * dt);
    let period = 1.0 / (f_peak * dt); // samples per ringing period
    let len = period.round() as usize;
    if len < 3 {
        return None;
    }
    let ma = moving_average(r, len);
    let hp: Vec<f64> = r.iter().zip(&ma).map(|(a, b)| a - b).collect();
    let var0 = hp.iter().map(|v| v * v).sum::<f64>() / n as f64;
    let rms_hp = var0.sqrt();
    // Lags up to 0.4 of the drive period: a ringing excited at every reversal restarts each
    // half-period, which the envelope model ([`envelope_decay_rate`]) describes up to there.
    let restart = (0.4 * n as f64 / cycles_in_window) as usize;
    let max_lag = ((25.0 * period) as usize).min(restart).min(n / 2);
    let acf: Vec<f64> = (0..=max_lag)
        .map(|l| (0..n - l).map(|i| hp[i] * hp[i + l]).sum::<f64>() / (n as f64 * var0))
        .collect();
    // Peaks near m·period.
    let mut peaks: Vec<(f64, f64)> = Vec::new();
    for m in 1..=20 {
        let centre = m as f64 * period;
        let (lo, hi) = (
            ((centre - 0.5 * period).round() as usize).max(1),
            ((centre + 0.5 * period).round() as usize).min(max_lag.saturating_sub(1)),
        );
        if hi <= lo {
            break;
        }
        let (i, &v) = acf[lo..=hi]
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))?;
        let i = lo + i;
        if v < 0.05 || i == lo || i == hi {
            break;
        }
        // Parabolic refinement of the peak position and value.
        let (a, b, c) = (acf[i - 1], acf[i], acf[i + 1]);
        let den = a - 2.0 * b + c;
        let delta = if den < 0.0 { 0.5 * (a - c) / den } else { 0.0 };
        peaks.push((i as f64 + delta, b - 0.25 * (a - c) * delta));
    }
    let first = peaks.first()?.1;
    if first < 0.3 || rms_hp < 1.5 * sigma {
        return None;
    }
    // τ_m = m·T: least squares through the origin.
    let (smt, smm) = peaks.iter().enumerate().fold((0.0, 0.0), |(a, b), (m, p)| {
        let m = (m + 1) as f64;
        (a + m * p.0, b + m * m)
    });
    let frequency = 1.0 / (smt / smm * dt);
    let damping_ratio = free_decay_damping(&hp, dt, 1.0 / (frequency * dt), frequency, sigma);
    Some(Ringing {
        frequency_hz: frequency,
        damping_ratio,
        rms_n: (var0 - sigma * sigma).max(0.0).sqrt(),
        peak_n: hp.iter().fold(0.0_f64, |m, v| m.max(v.abs())),
        prominence,
        first_correlation_peak: first,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnose::cycles::segment;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    /// A damped sinusoid of 40 Hz, ζ = 0.02, restarted at every reversal of a 1 Hz drive, on a
    /// slow misfit and white noise: frequency within 2 %, damping within 25 %.
    #[test]
    fn finds_frequency_and_damping_of_a_ringing() {
        let (fs, fr, zeta) = (1000.0, 40.0, 0.02);
        let n = 6000;
        let dt = 1.0 / fs;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let g = Normal::new(0.0, 1.0).unwrap();
        let w = std::f64::consts::TAU * fr;
        // Bursts of one sign, and alternating in sign (as after up- and down-reversals).
        for alternating in [false, true] {
            let r: Vec<f64> = (0..n)
                .map(|i| {
                    let t = i as f64 * dt;
                    let since = (t + 0.25) % 0.5;
                    let sign = if alternating && ((t + 0.25) / 0.5) as usize % 2 == 1 {
                        -1.0
                    } else {
                        1.0
                    };
                    let ring = sign * 20.0 * (-zeta * w * since).exp() * (w * since).sin();
                    ring + 15.0 * (std::f64::consts::TAU * t).sin() + g.sample(&mut rng)
                })
                .collect();
            let ri = ringing(&r, dt, 6.0, 1.0).expect("ringing found");
            assert!((ri.frequency_hz / fr - 1.0).abs() < 0.02, "{ri:?}");
            let z = ri.damping_ratio.unwrap();
            assert!(
                (z / zeta - 1.0).abs() < 0.25,
                "alternating {alternating}: {ri:?}"
            );
        }
        // Noise and a slow misfit alone: no ringing.
        let quiet: Vec<f64> = (0..n)
            .map(|i| {
                let t = i as f64 * dt;
                15.0 * (std::f64::consts::TAU * t).sin()
                    + 5.0 * (std::f64::consts::TAU * 3.0 * t).sin().powi(3)
                    + g.sample(&mut rng)
            })
            .collect();
        assert!(ringing(&quiet, dt, 6.0, 1.0).is_none());
    }

    /// A Jenkins loop behind a free play of ±g: the plateau spans 2g; a plain Jenkins loop has
    /// none.
    #[test]
    fn finds_the_free_play_of_a_clearance() {
        let per = 400;
        let n = 3 * per + per / 2;
        let tau = std::f64::consts::TAU;
        let t: Vec<f64> = (0..n).map(|i| i as f64 / per as f64).collect();
        let x: Vec<f64> = t.iter().map(|&t| 1e-3 * (tau * t).sin()).collect();
        let c = segment(&t, &x).unwrap();
        let loop_with_gap = |g: f64| {
            let (mut f, mut u) = (vec![0.0; n], 0.0_f64);
            for i in 1..n {
                // Link elongation follows the drive inside the play.
                let dx = x[i] - x[i - 1];
                let trial = u + dx;
                let fl = |u: f64| {
                    if u > g {
                        1e7 * (u - g)
                    } else if u < -g {
                        1e7 * (u + g)
                    } else {
                        0.0
                    }
                };
                // Element: rigid-plastic at ±100 N; the link carries the element force.
                let ft = fl(trial);
                if ft.abs() <= 100.0 {
                    u = trial;
                    f[i] = ft;
                } else {
                    f[i] = 100.0 * ft.signum();
                    u = if ft > 0.0 {
                        g + 100.0 / 1e7
                    } else {
                        -g - 100.0 / 1e7
                    };
                }
            }
            f
        };
        let g = 5e-5;
        let regions = clearance_regions(&x, &loop_with_gap(g), &c, 100.0);
        assert_eq!(regions.len(), c.half_cycles.len());
        for r in &regions {
            assert!((r.span_m / (2.0 * g) - 1.0).abs() < 0.1, "{r:?}");
        }
        assert!(clearance_regions(&x, &loop_with_gap(0.0), &c, 100.0).is_empty());
    }
}
