//! Two rough elastic bodies reduced to one: equivalent surface and equivalent statistics (the
//! composite modulus is [`crate::core::material::composite_modulus`]).
//!
//! The contact of two rough elastic half-spaces is equivalent to that of one rigid rough
//! surface, whose height is the sum of the two bodies' deviations towards each other, on an
//! elastic half-space of composite modulus `E*` (Johnson, *Contact Mechanics*, 1985, §13.1;
//! Greenwood & Tripp, 1970). With both height maps expressed in one frame, `z` pointing from body 1
//! towards body 2, body 2's surface seen from body 1, the gap is `g = h2 - h1` and the equivalent
//! rough surface is the height difference `h = h1 - h2`. (A profilometer measures body 2 from its
//! own side: its heights in the common frame are the measured ones negated, with one lateral axis
//! mirrored.) For statistically independent surfaces the variances add: `Rq² = Rq1² + Rq2²`, and
//! likewise the mean-square slopes.

use crate::core::error::{Error, Result};
use crate::core::grid::Grid2;

/// Relative tolerance for two grid spacings to count as equal.
const SPACING_TOLERANCE: f64 = 1e-9;

/// Equivalent rough surface `h = h1 - h2` of two height maps on a common grid (same shape and
/// spacings to 1e-9); periodic only when both are.
pub fn equivalent_surface(body1: &Grid2, body2: &Grid2) -> Result<Grid2> {
    if body1.heights.dim() != body2.heights.dim() {
        return Err(Error::Data(format!(
            "the two surfaces are on different grids: {} × {} and {} × {} points; resample one \
             onto the other's grid first",
            body1.nx(),
            body1.ny(),
            body2.nx(),
            body2.ny()
        )));
    }
    for (name, a, b) in [("dx", body1.dx, body2.dx), ("dy", body1.dy, body2.dy)] {
        if ((a - b) / a).abs() > SPACING_TOLERANCE {
            return Err(Error::Data(format!(
                "the two surfaces have different spacings: {name} = {a:e} m and {b:e} m"
            )));
        }
    }
    if body1.heights == body2.heights {
        // The same surface twice (often the same file): h1 − h2 is zero everywhere, a flat
        // surface in full contact at any load — say what happened, not "flat".
        return Err(Error::Data(
            "identical bodies: the two surfaces have the same heights at every point, so h1 − h2 \
             is zero everywhere (the same file twice?); give body 2's own measurement"
                .into(),
        ));
    }
    Grid2::new(
        &body1.heights - &body2.heights,
        body1.dx,
        body1.dy,
        body1.periodic && body2.periodic,
    )
}

/// Equivalent rms height of two independent rough surfaces, `Rq = √(Rq1² + Rq2²)` (m).
pub fn equivalent_rq(rq1_m: f64, rq2_m: f64) -> Result<f64> {
    let a = require_nonnegative("rq1_m", rq1_m)?;
    let b = require_nonnegative("rq2_m", rq2_m)?;
    Ok(a.hypot(b))
}

/// Equivalent rms slope of two independent rough surfaces, `√(m1² + m2²)`.
pub fn equivalent_rms_slope(slope1: f64, slope2: f64) -> Result<f64> {
    let a = require_nonnegative("slope1", slope1)?;
    let b = require_nonnegative("slope2", slope2)?;
    Ok(a.hypot(b))
}

fn require_nonnegative(name: &str, v: f64) -> Result<f64> {
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(Error::param(
            name,
            format!("must be finite and ≥ 0, got {v}"),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ndarray::Array2;

    #[test]
    fn equivalent_surface_is_the_difference_and_rq_adds_for_independent_surfaces() {
        use crate::surface::generate::{generate, GaussianSurfaceSpec};
        let spec = GaussianSurfaceSpec {
            rq_m: 3e-7,
            clx_m: 4e-6,
            cly_m: 4e-6,
            lx_m: 128e-6,
            ly_m: 128e-6,
            nx: 128,
            ny: 128,
            seed: 1,
        };
        let a = generate(&spec).unwrap();
        let b = generate(&GaussianSurfaceSpec {
            rq_m: 4e-7,
            seed: 2,
            ..spec
        })
        .unwrap();
        let h = equivalent_surface(&a, &b).unwrap();
        assert!(h.periodic);
        assert_eq!(h.heights[[3, 5]], a.heights[[3, 5]] - b.heights[[3, 5]]);
        let n = h.heights.len() as f64;
        let rq = (h.heights.iter().map(|v| v * v).sum::<f64>() / n).sqrt();
        // Independent seeds: Rq close to 5e-7 (sampling noise of the cross term, ~1/√N_eff).
        assert!(
            (rq / equivalent_rq(3e-7, 4e-7).unwrap() - 1.0).abs() < 0.05,
            "{rq}"
        );
        assert!((equivalent_rq(3e-7, 4e-7).unwrap() / 5e-7 - 1.0).abs() < 1e-15);
        assert!((equivalent_rms_slope(0.3, 0.4).unwrap() / 0.5 - 1.0).abs() < 1e-15);
        assert!(equivalent_rq(-1.0, 1.0)
            .unwrap_err()
            .to_string()
            .contains("rq1_m"));
    }

    #[test]
    fn different_grids_are_refused() {
        let a = Grid2::new(Array2::zeros((4, 4)), 1e-6, 1e-6, true).unwrap();
        let b = Grid2::new(Array2::zeros((4, 5)), 1e-6, 1e-6, true).unwrap();
        let c = Grid2::new(Array2::zeros((4, 4)), 1.1e-6, 1e-6, true).unwrap();
        assert!(equivalent_surface(&a, &b)
            .unwrap_err()
            .to_string()
            .contains("different grids"));
        assert!(equivalent_surface(&a, &c)
            .unwrap_err()
            .to_string()
            .contains("dx"));
    }
}
