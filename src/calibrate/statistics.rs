//! Statistics over realisations: means with 95 % confidence intervals, and differences of means.
//!
//! Results computed on random rough surfaces are random: each realisation (surface of the same
//! statistics, another seed) gives another value. Over `N` realisations the mean `x̄` is
//! reported with the half-width of its two-sided 95 % confidence interval from Student's t
//! distribution (the realisation values taken as independent draws of a normal variable):
//!
//! `x̄ ± t₀.₉₇₅,N−1 · s/√N`,  `s² = Σ (x_i − x̄)²/(N − 1)`,
//!
//! which narrows as `1/√N` once `t` has settled (`t₀.₉₇₅` = 12.7, 2.78, 2.36, 2.09, 1.96 for
//! `N` = 2, 5, 8, 20, ∞). The quantile comes from `statrs` (inverse CDF of Student's t).
//!
//! Differences of means, used by the convergence checks:
//! - **paired** (the same surfaces at two resolutions): the interval of the mean of the
//!   differences `d_i = x_i − y_i`, as above;
//! - **unpaired** (independent surfaces at two patch sizes): Welch's interval
//!   `x̄ − ȳ ± t₀.₉₇₅,ν · √(s_x²/N_x + s_y²/N_y)` with the Welch–Satterthwaite degrees of freedom
//!   `ν = (s_x²/N_x + s_y²/N_y)² / ((s_x²/N_x)²/(N_x − 1) + (s_y²/N_y)²/(N_y − 1))`.

use crate::core::stats::student_t_975;

/// Mean of a set of realisation values with its 95 % interval.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Summary {
    /// Number of values.
    pub n: usize,
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation (`N − 1` in the denominator); NaN for one value.
    pub sd: f64,
    /// Half-width of the 95 % confidence interval of the mean; NaN for one value.
    pub ci95: f64,
}

/// Mean, standard deviation and 95 % interval of `values` (see the module documentation).
pub fn summarise(values: &[f64]) -> Summary {
    let n = values.len();
    if n == 0 {
        return Summary {
            n,
            mean: f64::NAN,
            sd: f64::NAN,
            ci95: f64::NAN,
        };
    }
    let mean = values.iter().sum::<f64>() / n as f64;
    if n == 1 {
        return Summary {
            n,
            mean,
            sd: f64::NAN,
            ci95: f64::NAN,
        };
    }
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
    let sd = var.sqrt();
    Summary {
        n,
        mean,
        sd,
        ci95: student_t_975((n - 1) as f64) * sd / (n as f64).sqrt(),
    }
}

/// A difference of two means with the half-width of its 95 % interval.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Difference {
    /// `x̄ − ȳ`.
    pub mean: f64,
    /// Half-width of its 95 % confidence interval (NaN when it cannot be estimated).
    pub ci95: f64,
}

/// Paired difference of `x` and `y` (same realisations): the summary of `x_i − y_i`.
pub fn paired_difference(x: &[f64], y: &[f64]) -> Difference {
    let d: Vec<f64> = x.iter().zip(y).map(|(a, b)| a - b).collect();
    let s = summarise(&d);
    Difference {
        mean: s.mean,
        ci95: s.ci95,
    }
}

/// Welch's difference of the means of independent samples `x` and `y`.
pub fn welch_difference(x: &[f64], y: &[f64]) -> Difference {
    let (sx, sy) = (summarise(x), summarise(y));
    let (vx, vy) = (sx.sd.powi(2) / sx.n as f64, sy.sd.powi(2) / sy.n as f64);
    let se2 = vx + vy;
    let dof = se2.powi(2) / (vx.powi(2) / (sx.n as f64 - 1.0) + vy.powi(2) / (sy.n as f64 - 1.0));
    let ci95 = if se2 > 0.0 {
        student_t_975(dof) * se2.sqrt()
    } else if se2 == 0.0 {
        0.0
    } else {
        f64::NAN
    };
    Difference {
        mean: sx.mean - sy.mean,
        ci95,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    #[test]
    fn student_t_quantiles_match_tables() {
        // Abramowitz & Stegun, Table 26.10 (two-sided 5 %).
        for (dof, t) in [
            (1.0, 12.706),
            (2.0, 4.303),
            (7.0, 2.365),
            (30.0, 2.042),
            (1e6, 1.960),
        ] {
            assert!((student_t_975(dof) - t).abs() < 1e-3, "ν = {dof}");
        }
        assert!(student_t_975(0.0).is_nan());
    }

    #[test]
    fn summary_of_known_values() {
        let s = summarise(&[1.0, 2.0, 3.0, 4.0]);
        assert_eq!(s.mean, 2.5);
        assert!((s.sd - (5.0f64 / 3.0).sqrt()).abs() < 1e-15);
        assert!((s.ci95 - 3.182446 * s.sd / 2.0).abs() < 1e-5);
        let one = summarise(&[7.0]);
        assert_eq!(one.mean, 7.0);
        assert!(one.ci95.is_nan());
    }

    /// Coverage: the 95 % interval contains the true mean in 95 % of normal samples (N = 5,
    /// 20 000 trials: binomial sd 0.15 %).
    #[test]
    fn interval_covers_the_mean_95_percent_of_the_time() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let normal = Normal::new(3.0, 2.0).unwrap();
        let trials = 20_000;
        let mut hits = 0;
        let mut welch_hits = 0;
        for _ in 0..trials {
            let x: Vec<f64> = (0..5).map(|_| normal.sample(&mut rng)).collect();
            let y: Vec<f64> = (0..8)
                .map(|_| normal.sample(&mut rng) * 0.5 + 1.5)
                .collect();
            let s = summarise(&x);
            if (s.mean - 3.0).abs() <= s.ci95 {
                hits += 1;
            }
            let d = welch_difference(&x, &y);
            if (d.mean - 0.0).abs() <= d.ci95 {
                welch_hits += 1;
            }
        }
        let cover = hits as f64 / trials as f64;
        let welch = welch_hits as f64 / trials as f64;
        assert!((cover - 0.95).abs() < 0.006, "coverage {cover}");
        // Welch's interval is approximate; its coverage stays close to nominal.
        assert!((welch - 0.95).abs() < 0.01, "Welch coverage {welch}");
    }

    /// The expected half-width is `t₀.₉₇₅,N−1 · c₄(N) σ/√N` with `c₄(N) = E[s]/σ =
    /// √(2/(N−1)) Γ(N/2)/Γ((N−1)/2)`: over 4000 normal samples each, N = 4, 16, 64 give it within
    /// 2 % (the interval narrows as 1/√N once t has settled).
    #[test]
    fn expected_half_width_narrows_as_one_over_root_n() {
        use statrs::function::gamma::ln_gamma;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let sigma = 2.0;
        let normal = Normal::new(0.0, sigma).unwrap();
        for n in [4usize, 16, 64] {
            let trials = 4000;
            let mean_hw = (0..trials)
                .map(|_| {
                    let x: Vec<f64> = (0..n).map(|_| normal.sample(&mut rng)).collect();
                    summarise(&x).ci95
                })
                .sum::<f64>()
                / trials as f64;
            let nf = n as f64;
            let c4 =
                (2.0 / (nf - 1.0)).sqrt() * (ln_gamma(nf / 2.0) - ln_gamma((nf - 1.0) / 2.0)).exp();
            let want = student_t_975(nf - 1.0) * c4 * sigma / nf.sqrt();
            assert!(
                (mean_hw / want - 1.0).abs() < 0.02,
                "N = {n}: {mean_hw} vs {want}"
            );
        }
    }

    #[test]
    fn paired_difference_removes_the_common_part() {
        let x = [10.0, 20.0, 30.0];
        let y = [9.0, 19.1, 28.9];
        let d = paired_difference(&x, &y);
        assert!((d.mean - 1.0).abs() < 1e-12);
        assert!(d.ci95 < 0.3);
        assert!(welch_difference(&x, &y).ci95 > 20.0);
    }
}
