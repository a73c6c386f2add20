//! Stationarity of a record: does the loop change from cycle to cycle?
//!
//! Only the complete cycles at the steady amplitude (peak-to-peak stroke within 3 % of the
//! largest) are compared: a drive whose amplitude ramps up or down changes the loop for a reason
//! that is not drift. The baseline element is fitted to each of them on its own (slip force and `E0`, with
//! the shape parameter `k` of the whole-record fit; see [`super::select`]) and the dissipated
//! energy `∮F dx` of each cycle is measured directly. Three descriptors per cycle:
//! slip force (N), stiffness (reload slope `2E0/(1+k)`, N/m) and loop area (J).
//!
//! **Trend test.** For each descriptor `y_c` over cycles `c = 0 … n−1`: the ordinary
//! least-squares slope `b`, its standard error `s_b = √(Σr²/(n−2) / Σ(c − c̄)²)` and
//! `t = b/s_b`. A drift is reported when **both**
//! - the slope is significant: `|t| > t_{0.995, n−2}` (two-sided 1 % level of Student's t;
//!   4.60 for 6 cycles), and
//! - it matters: the change over the record `|b|·(n−1)` is at least [`MIN_RELATIVE_CHANGE`]
//!   (5 %) of the trend line's value at the first cycle.
//!
//! A perfectly linear series (`s_b = 0`) with a relevant change counts as significant.
//!
//! **Power.** The test has `n − 2` degrees of freedom. Below [`MIN_DEGREES_OF_FREEDOM`] (3, i.e.
//! fewer than 5 cycles) it has no useful power: Student's t then has no finite variance and its
//! 1 % critical value is 63.7 (1 degree of freedom, 3 cycles) or 9.9 (2), so a 5 % drift goes
//! undetected unless the cycles scatter by well under 1 %. A trend found there is still
//! reported, but the absence of one is "drift not testable", never "no drift".

use serde::Serialize;
use statrs::distribution::{ContinuousCDF, StudentsT};

/// Two-sided significance level of the trend test.
pub const SIGNIFICANCE: f64 = 0.01;
/// Smallest change over the record, relative to its start, reported as drift.
pub const MIN_RELATIVE_CHANGE: f64 = 0.05;
/// Fewest degrees of freedom (`cycles − 2`) for the absence of a trend to mean "no drift"
/// (module documentation).
pub const MIN_DEGREES_OF_FREEDOM: usize = 3;

/// Trend of one descriptor over the cycles.
#[derive(Debug, Clone, Serialize)]
pub struct Trend {
    /// Descriptor name with unit, e.g. `"slip force (N)"`.
    pub name: String,
    /// Value per complete cycle.
    pub per_cycle: Vec<f64>,
    /// Least-squares slope per cycle (descriptor unit per cycle).
    pub slope_per_cycle: f64,
    /// Change over the record `b·(n−1)` relative to the trend line's value at the first cycle.
    pub relative_change: f64,
    /// `t = b/s_b` (infinite for an exactly linear series with a change).
    pub t: f64,
    /// Critical `|t|` at the 1 % level with `n − 2` degrees of freedom (`None` below 3 cycles).
    pub t_critical: Option<f64>,
    /// Significant and relevant (module documentation).
    pub drift: bool,
}

/// Student-t trend test of `y` against its index (module documentation).
pub fn trend(name: &str, y: &[f64]) -> Trend {
    let n = y.len();
    let nf = n as f64;
    let mean = y.iter().sum::<f64>() / nf.max(1.0);
    let cbar = (nf - 1.0) / 2.0;
    let sxx: f64 = (0..n).map(|c| (c as f64 - cbar).powi(2)).sum();
    let b = if sxx > 0.0 {
        (0..n)
            .map(|c| (c as f64 - cbar) * (y[c] - mean))
            .sum::<f64>()
            / sxx
    } else {
        0.0
    };
    // Relative to the trend line's value at the first cycle (the mean if that is not > 0).
    let start = mean - b * cbar;
    let reference = if start > 0.0 { start } else { mean.abs() };
    let relative_change = if reference > 0.0 {
        b * (nf - 1.0) / reference
    } else {
        0.0
    };
    if n < 3 {
        return Trend {
            name: name.into(),
            per_cycle: y.to_vec(),
            slope_per_cycle: b,
            relative_change,
            t: f64::NAN,
            t_critical: None,
            drift: false,
        };
    }
    let rss: f64 = (0..n)
        .map(|c| (y[c] - mean - b * (c as f64 - cbar)).powi(2))
        .sum();
    let sb = (rss / (nf - 2.0) / sxx).sqrt();
    // An exactly linear series: any non-zero slope is infinitely significant.
    let t = if sb > 1e-12 * b.abs() {
        b / sb
    } else if b != 0.0 {
        f64::INFINITY * b.signum()
    } else {
        0.0
    };
    let t_crit = StudentsT::new(0.0, 1.0, nf - 2.0)
        .map(|d| d.inverse_cdf(1.0 - SIGNIFICANCE / 2.0))
        .unwrap_or(f64::INFINITY);
    Trend {
        name: name.into(),
        per_cycle: y.to_vec(),
        slope_per_cycle: b,
        relative_change,
        t,
        t_critical: Some(t_crit),
        drift: t.abs() > t_crit && relative_change.abs() >= MIN_RELATIVE_CHANGE,
    }
}

/// Trends of slip force, stiffness and loop area, and the drift findings in words.
#[derive(Debug, Clone, Serialize)]
pub struct Stationarity {
    /// Complete cycles tested: those at the steady amplitude (peak-to-peak stroke within 3 %
    /// of the largest).
    pub cycles: Vec<usize>,
    /// Trend of the per-cycle fitted slip force (N).
    pub slip_force: Trend,
    /// Trend of the per-cycle reload stiffness `2E0/(1+k)` (N/m).
    pub stiffness: Trend,
    /// Trend of the per-cycle loop area `∮F dx`, the energy dissipated per cycle (J).
    pub loop_area: Trend,
    /// One sentence per drifting descriptor (empty: stationary, or not testable).
    pub findings: Vec<String>,
    /// Whether the test has power: at least [`MIN_DEGREES_OF_FREEDOM`] degrees of freedom
    /// (5 complete cycles at the steady amplitude).
    pub testable: bool,
}

impl Stationarity {
    /// Build the trends and their findings from per-cycle values.
    pub fn new(
        cycles: &[usize],
        slip_force_n: &[f64],
        stiffness_n_per_m: &[f64],
        loop_area_j: &[f64],
    ) -> Self {
        let slip_force = trend("slip force (N)", slip_force_n);
        let stiffness = trend("stiffness 2E0/(1+k) (N/m)", stiffness_n_per_m);
        let loop_area = trend("loop area (J)", loop_area_j);
        let n = slip_force_n.len();
        let mut findings = Vec::new();
        for (tr, what, up, down) in [
            (
                &slip_force,
                "slip force",
                "run-in or wear",
                "wear of a coating, or the normal load relaxes",
            ),
            (
                &stiffness,
                "stiffness",
                "the contact closes or flattens (run-in)",
                "the contact or the rig loosens",
            ),
            (
                &loop_area,
                "dissipated energy per cycle",
                "friction or slip grows",
                "friction or slip falls",
            ),
        ] {
            if tr.drift {
                let grows = tr.relative_change > 0.0;
                findings.push(format!(
                    "{what} {} {:.0} % over {n} cycles (trend t = {:.1}, threshold {:.2}): {}",
                    if grows { "grows" } else { "falls" },
                    100.0 * tr.relative_change.abs(),
                    tr.t,
                    tr.t_critical.unwrap_or(f64::NAN),
                    if grows { up } else { down }
                ));
            }
        }
        Self {
            cycles: cycles.to_vec(),
            slip_force,
            stiffness,
            loop_area,
            findings,
            testable: n >= MIN_DEGREES_OF_FREEDOM + 2,
        }
    }

    /// Degrees of freedom of the trend test (`cycles − 2`, 0 below 2 cycles).
    pub fn degrees_of_freedom(&self) -> usize {
        self.cycles.len().saturating_sub(2)
    }

    /// Whether any descriptor drifts.
    pub fn drifts(&self) -> bool {
        !self.findings.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn critical_value_and_linear_drift() {
        // t_{0.995, 4} = 4.604 (tables).
        let tr = trend("x", &[1.0, 1.06, 1.12, 1.18, 1.24, 1.30]);
        assert!((tr.t_critical.unwrap() - 4.604).abs() < 1e-3);
        assert!(tr.drift && (tr.relative_change - 0.3).abs() < 1e-9);
        assert!(tr.t.is_infinite());
    }

    #[test]
    fn scatter_without_trend_and_small_trends_are_not_drift() {
        let tr = trend("x", &[1.0, 1.02, 0.99, 1.01, 0.98, 1.0]);
        assert!(!tr.drift, "{tr:?}");
        // Significant but below 5 %: not reported.
        let tr = trend("x", &[1.0, 1.005, 1.01, 1.015, 1.02, 1.0251]);
        assert!(tr.t.abs() > tr.t_critical.unwrap() && !tr.drift);
        let two = trend("x", &[1.0, 2.0]);
        assert!(!two.drift && two.t_critical.is_none());
    }

    #[test]
    fn finding_names_the_descriptor_and_direction() {
        let s = Stationarity::new(
            &[0, 1, 2, 3, 4, 5],
            &[100.0, 106.0, 112.0, 118.0, 124.0, 130.0],
            &[1e6; 6],
            &[1.0, 0.99, 1.01, 1.0, 1.0, 0.99],
        );
        assert_eq!(s.findings.len(), 1);
        assert!(
            s.findings[0].starts_with("slip force grows 30 % over 6 cycles"),
            "{:?}",
            s.findings
        );
    }

    /// Three cycles whose slip force truly grows 8 % (1.00, 1.05, 1.08: a drift with 1 %
    /// scatter) pass the trend test unnoticed: with 1 degree of freedom the 1 % critical value
    /// is 63.657 (tables). Such a record is "not testable", not "stationary"; from 5 cycles
    /// (3 degrees of freedom, critical value 5.841) the test counts.
    #[test]
    fn drift_is_testable_only_with_three_degrees_of_freedom() {
        let three = Stationarity::new(&[0, 1, 2], &[100.0, 105.0, 108.0], &[1e6; 3], &[1.0; 3]);
        assert!((three.slip_force.t_critical.unwrap() - 63.657).abs() < 1e-3);
        assert!(!three.drifts(), "{:?}", three.findings);
        assert!(!three.testable && three.degrees_of_freedom() == 1);
        let four = Stationarity::new(&[0, 1, 2, 3], &[1.0; 4], &[1.0; 4], &[1.0; 4]);
        assert!((four.slip_force.t_critical.unwrap() - 9.925).abs() < 1e-3);
        assert!(!four.testable);
        let five = Stationarity::new(&[0, 1, 2, 3, 4], &[1.0; 5], &[1.0; 5], &[1.0; 5]);
        assert!((five.slip_force.t_critical.unwrap() - 5.841).abs() < 1e-3);
        assert!(five.testable && five.degrees_of_freedom() == 3);
    }
}
