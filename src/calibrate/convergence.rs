//! Is a calibrated value converged in grid resolution and in patch size? Verdicts per pressure.
//!
//! Units: as the compared quantities (kn, E0 in N/m³; k dimensionless); tolerances relative for
//! kn and E0, absolute for k ([`crate::calibrate::config::ConvergenceConfig`]).
//!
//! - **Grid**: the same surfaces on the grid with half as many points per side (the generator
//!   gives the same surface low-passed, [`crate::surface::generate`](mod@crate::surface::generate)), so the paired difference
//!   of each realisation's value is the effect of resolution alone. If refining from `n/2` to
//!   `n` changes the value by less than the tolerance, the `n` result (whose error is smaller
//!   still for a converging discretisation) is called converged.
//! - **Patch**: independent surfaces on a patch of half the side at the same spacing (same
//!   spectrum, a quarter of the area); the difference of the realisation means (Welch) is the
//!   effect of patch size plus sampling noise.
//!
//! A verdict uses the 95 % interval of the change `Δ ± h` ([`crate::calibrate::statistics`]):
//! converged when the whole interval lies within `±tolerance` (`|Δ| + h ≤ tol`), not converged
//! when it lies wholly outside (`|Δ| − h > tol`), undetermined otherwise (more realisations
//! would tell).

use crate::calibrate::statistics::Difference;

/// Outcome of one convergence check.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Verdict {
    /// The 95 % interval of the change lies within the tolerance.
    Converged,
    /// The interval straddles the tolerance: more realisations are needed to tell.
    Undetermined,
    /// The interval lies beyond the tolerance.
    NotConverged,
    /// The check could not be run (e.g. the coarser grid does not resolve the correlation length,
    /// or a measured surface).
    NotChecked,
}

impl Verdict {
    /// The verdict of a change `d` against `tolerance` (see the module documentation). A
    /// difference without an interval (one realisation) is undetermined: its value alone mixes
    /// the effect with the surface's sampling noise — one realisation at 256² called the same
    /// 5 MPa grid check converged or not converged depending on the seed (with two
    /// realisations it read undetermined).
    pub fn of(d: Difference, tolerance: f64) -> Self {
        if !d.mean.is_finite() {
            return Verdict::NotChecked;
        }
        if !d.ci95.is_finite() {
            return Verdict::Undetermined;
        }
        let h = d.ci95;
        if d.mean.abs() + h <= tolerance {
            Verdict::Converged
        } else if d.mean.abs() - h > tolerance {
            Verdict::NotConverged
        } else {
            Verdict::Undetermined
        }
    }

    /// The least favourable of several verdicts (not converged, then undetermined, then not
    /// checked, then converged).
    pub fn worst(verdicts: impl IntoIterator<Item = Verdict>) -> Self {
        let rank = |v: &Verdict| match v {
            Verdict::NotConverged => 3,
            Verdict::Undetermined => 2,
            Verdict::NotChecked => 1,
            Verdict::Converged => 0,
        };
        verdicts
            .into_iter()
            .max_by_key(rank)
            .unwrap_or(Verdict::NotChecked)
    }

    /// The name in files (`converged`, `undetermined`, `not-converged`, `not-checked`: the
    /// serialised form).
    pub fn name(&self) -> &'static str {
        match self {
            Verdict::Converged => "converged",
            Verdict::Undetermined => "undetermined",
            Verdict::NotConverged => "not-converged",
            Verdict::NotChecked => "not-checked",
        }
    }

    /// The verdict of a [`Verdict::name`].
    pub fn parse(name: &str) -> Option<Self> {
        [
            Verdict::Converged,
            Verdict::Undetermined,
            Verdict::NotConverged,
            Verdict::NotChecked,
        ]
        .into_iter()
        .find(|v| v.name() == name)
    }

    /// Short text for tables and messages.
    pub fn as_str(&self) -> &'static str {
        match self {
            Verdict::Converged => "converged",
            Verdict::Undetermined => "undetermined",
            Verdict::NotConverged => "NOT converged",
            Verdict::NotChecked => "not checked",
        }
    }
}

/// One check of one quantity at one pressure.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Check {
    /// Change of the value (finer or larger minus coarser or smaller) with its 95 % interval.
    pub change: Difference,
    /// Allowed change (same unit as the value).
    pub tolerance: f64,
    /// The verdict.
    pub verdict: Verdict,
}

impl Check {
    /// Judge `change` against `tolerance`.
    pub fn new(change: Difference, tolerance: f64) -> Self {
        Self {
            change,
            tolerance,
            verdict: Verdict::of(change, tolerance),
        }
    }

    /// A check that could not be run.
    pub fn not_checked() -> Self {
        Self {
            change: Difference {
                mean: f64::NAN,
                ci95: f64::NAN,
            },
            tolerance: f64::NAN,
            verdict: Verdict::NotChecked,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn d(mean: f64, ci95: f64) -> Difference {
        Difference { mean, ci95 }
    }

    #[test]
    fn verdicts_from_the_interval_of_the_change() {
        assert_eq!(Verdict::of(d(0.01, 0.02), 0.05), Verdict::Converged);
        assert_eq!(Verdict::of(d(-0.04, 0.02), 0.05), Verdict::Undetermined);
        assert_eq!(Verdict::of(d(0.10, 0.02), 0.05), Verdict::NotConverged);
        // One realisation: no interval, no verdict either way.
        assert_eq!(Verdict::of(d(0.01, f64::NAN), 0.05), Verdict::Undetermined);
        assert_eq!(Verdict::of(d(0.50, f64::NAN), 0.05), Verdict::Undetermined);
        assert_eq!(Verdict::of(d(f64::NAN, 0.0), 0.05), Verdict::NotChecked);
        assert_eq!(
            Verdict::worst([
                Verdict::Converged,
                Verdict::Undetermined,
                Verdict::NotChecked
            ]),
            Verdict::Undetermined
        );
        assert_eq!(Verdict::worst([]), Verdict::NotChecked);
    }

    /// The table's names are the report's (serde) names, and read back.
    #[test]
    fn names_are_the_serialised_ones_and_parse_back() {
        for v in [
            Verdict::Converged,
            Verdict::Undetermined,
            Verdict::NotConverged,
            Verdict::NotChecked,
        ] {
            assert_eq!(serde_json::to_value(v).unwrap(), v.name());
            assert_eq!(Verdict::parse(v.name()), Some(v));
        }
        assert_eq!(Verdict::parse("NOT converged"), None);
    }
}
