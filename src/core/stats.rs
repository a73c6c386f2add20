//! Order statistics and Student-t quantiles shared by every stage.
//!
//! Each function states its convention: the nearest-rank percentile of a sample, the Hazen
//! quantile of sorted values (type 5 of Hyndman & Fan, *Am. Stat.* 50 (1996) 361–365), the
//! median with the mean of the two middle values for an even count, and Student's t quantile
//! from `statrs`.

use statrs::distribution::{ContinuousCDF, StudentsT};

/// Median of a non-empty `v` (the mean of the two middle values for an even count; sorted by
/// `total_cmp`, so a NaN-free input is assumed).
pub fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(|a, b| a.total_cmp(b));
    let n = s.len();
    if n % 2 == 1 {
        s[n / 2]
    } else {
        0.5 * (s[n / 2 - 1] + s[n / 2])
    }
}

/// Nearest-rank percentile of a non-empty sample: the sorted value at index
/// `round((n − 1)·q)`, `0 ≤ q ≤ 1` (no interpolation, so the result is one of the samples).
pub fn percentile_nearest(x: &[f64], q: f64) -> f64 {
    let mut v = x.to_vec();
    v.sort_by(|a, b| a.total_cmp(b));
    v[((v.len() - 1) as f64 * q).round() as usize]
}

/// Quantile `q` of non-empty sorted values, the k-th of n at `(k + ½)/n` and linear between
/// (Hazen; type 5 of Hyndman & Fan 1996); clamped to the extremes outside `[½/n, 1 − ½/n]`.
pub fn quantile_hazen(sorted: &[f64], q: f64) -> f64 {
    let n = sorted.len();
    let x = q * n as f64 - 0.5;
    if x <= 0.0 {
        return sorted[0];
    }
    let (i, t) = (x.floor() as usize, x.fract());
    if i + 1 >= n {
        return sorted[n - 1];
    }
    sorted[i] * (1.0 - t) + sorted[i + 1] * t
}

/// Quantile `t_p,ν` of Student's t with `ν > 0` degrees of freedom, `0 < p < 1` (NaN for an
/// invalid `ν` or `p`).
pub fn student_t_quantile(p: f64, dof: f64) -> f64 {
    if !(dof > 0.0 && dof.is_finite() && p > 0.0 && p < 1.0) {
        return f64::NAN;
    }
    match StudentsT::new(0.0, 1.0, dof) {
        Ok(t) => t.inverse_cdf(p),
        Err(_) => f64::NAN,
    }
}

/// Two-sided 95 % quantile `t₀.₉₇₅,ν` of Student's t with `ν > 0` degrees of freedom (NaN
/// otherwise).
pub fn student_t_975(dof: f64) -> f64 {
    student_t_quantile(0.975, dof)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_of_odd_and_even_counts() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 3.0, 2.0]), 2.5);
    }

    #[test]
    fn nearest_rank_percentile_is_a_sample() {
        let x = [5.0, 1.0, 4.0, 2.0, 3.0];
        assert_eq!(percentile_nearest(&x, 0.0), 1.0);
        assert_eq!(percentile_nearest(&x, 0.5), 3.0);
        assert_eq!(percentile_nearest(&x, 1.0), 5.0);
        // (n − 1)·0.6 = 2.4 → index 2.
        assert_eq!(percentile_nearest(&x, 0.6), 3.0);
    }

    #[test]
    fn hazen_quantile_interpolates_between_plotting_positions() {
        let s = [1.0, 2.0, 3.0, 4.0];
        // Plotting positions (k + ½)/n = 0.125, 0.375, 0.625, 0.875.
        assert_eq!(quantile_hazen(&s, 0.125), 1.0);
        assert_eq!(quantile_hazen(&s, 0.5), 2.5);
        assert_eq!(quantile_hazen(&s, 0.05), 1.0);
        assert_eq!(quantile_hazen(&s, 0.99), 4.0);
    }

    /// Student's t quantiles against the printed table (Abramowitz & Stegun, Table 26.10):
    /// t₀.₉₇₅ = 12.706 (ν 1), 2.571 (ν 5), 2.228 (ν 10), 1.960 (ν → ∞, here 10⁶).
    #[test]
    fn student_t_matches_the_table() {
        assert!((student_t_975(1.0) - 12.706).abs() < 1e-3);
        assert!((student_t_975(5.0) - 2.571).abs() < 1e-3);
        assert!((student_t_975(10.0) - 2.228).abs() < 1e-3);
        assert!((student_t_975(1e6) - 1.960).abs() < 1e-3);
        assert!(student_t_975(0.0).is_nan());
        assert!(student_t_quantile(1.0, 3.0).is_nan());
    }
}
