//! Smooth fit of a pressure map: a 2-D polynomial of total degree `order` by linear least squares.
//!
//! `σ(x, y) ≈ Σ_{a+b ≤ order} c_ab · u^a · v^b`, with scaled coordinates
//! `u = (x − x_c)/h_x`, `v = (y − y_c)/h_y` mapping the fitted region's bounding box onto
//! `[−1, 1]²` (or a frame given by the caller). Scaling keeps the monomial basis well conditioned
//! (condition number of order 10² for order 4 instead of ~10²⁰ in metres); the least-squares
//! problem is solved by Householder QR of the design matrix (Golub & Van Loan, *Matrix
//! Computations*, §5.3), never by forming the normal equations. Coefficients are reported in
//! this scaled basis, in Pa, with the frame.
//!
//! Goodness of fit: `R² = 1 − SS_res / SS_tot` (coefficient of determination) over the fitted
//! points; the reference study reports R² = 0.935 for its order-4 fit.

use crate::core::error::{Error, Result};

/// The affine map from film coordinates (m) to the scaled fit coordinates.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct FitFrame {
    /// Centre x of the fitted points' bounding box, film frame (m).
    pub x_centre_m: f64,
    /// Centre y of the bounding box (m).
    pub y_centre_m: f64,
    /// Half width of the bounding box in x (m): scaled `x' = (x − x_centre)/x_half_width`.
    pub x_half_width_m: f64,
    /// Half width of the bounding box in y (m).
    pub y_half_width_m: f64,
}

impl FitFrame {
    /// The frame mapping the bounding box of `points` onto `[−1, 1]²`.
    pub fn bounding(points: &[(f64, f64)]) -> Result<Self> {
        let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for &(x, y) in points {
            x0 = x0.min(x);
            x1 = x1.max(x);
            y0 = y0.min(y);
            y1 = y1.max(y);
        }
        if points.is_empty() || x1 <= x0 || y1 <= y0 {
            return Err(Error::Data(
                "polynomial fit needs points spread in both x and y".into(),
            ));
        }
        Ok(Self {
            x_centre_m: 0.5 * (x0 + x1),
            y_centre_m: 0.5 * (y0 + y1),
            x_half_width_m: 0.5 * (x1 - x0),
            y_half_width_m: 0.5 * (y1 - y0),
        })
    }

    /// Scaled coordinates `(u, v)` of a film point.
    pub fn scaled(&self, x: f64, y: f64) -> (f64, f64) {
        (
            (x - self.x_centre_m) / self.x_half_width_m,
            (y - self.y_centre_m) / self.y_half_width_m,
        )
    }
}

/// Exponents `(a, b)` of the monomials `u^a v^b` of total degree ≤ `order`, ordered by total
/// degree, then by decreasing `a`: 1, u, v, u², uv, v², …
pub fn exponents(order: usize) -> Vec<(usize, usize)> {
    let mut e = Vec::new();
    for d in 0..=order {
        for b in 0..=d {
            e.push((d - b, b));
        }
    }
    e
}

/// A fitted polynomial pressure field.
#[derive(Debug, Clone, serde::Serialize)]
pub struct PolyFit2 {
    /// Total degree of the polynomial (`a + b ≤ order`).
    pub order: usize,
    /// The map from film coordinates to the scaled basis `[−1, 1]²`.
    pub frame: FitFrame,
    /// Exponents `(a, b)` of each coefficient (see [`exponents`]).
    pub exponents: Vec<(usize, usize)>,
    /// Coefficients `c_ab` in Pa, in the scaled basis.
    pub coefficients_pa: Vec<f64>,
    /// Coefficient of determination over the fitted points; NaN (undefined) when every point
    /// has the same pressure ([`PolyFit2::r_squared_text`] writes it as an empty field).
    pub r_squared: f64,
    /// Root-mean-square residual (Pa).
    pub rms_residual_pa: f64,
    /// Number of points fitted.
    pub n_points: usize,
}

impl PolyFit2 {
    /// R² with `digits` decimals for tables, or an empty field when it is undefined (uniform
    /// points): a reader of the table sees "no value", never `NaN` in a number column.
    pub fn r_squared_text(&self, digits: usize) -> String {
        if self.r_squared.is_finite() {
            format!("{:.*}", digits, self.r_squared)
        } else {
            String::new()
        }
    }

    /// Evaluate the fitted pressure (Pa) at a film point (m).
    pub fn eval(&self, x: f64, y: f64) -> f64 {
        let (u, v) = self.frame.scaled(x, y);
        self.exponents
            .iter()
            .zip(&self.coefficients_pa)
            .map(|(&(a, b), c)| c * u.powi(a as i32) * v.powi(b as i32))
            .sum()
    }
}

/// Least-squares fit of `(x, y, pressure)` points (m, m, Pa) with a polynomial of total degree
/// `order`, in `frame` (default: the points' bounding box).
pub fn fit(points: &[(f64, f64, f64)], order: usize, frame: Option<FitFrame>) -> Result<PolyFit2> {
    if order > 10 {
        return Err(Error::param(
            "fit_order",
            format!("must be 0–10, got {order}"),
        ));
    }
    let exps = exponents(order);
    let m = exps.len();
    if points.len() < m {
        return Err(Error::Data(format!(
            "polynomial fit of order {order} needs at least {m} points with a pressure, got {}",
            points.len()
        )));
    }
    if points
        .iter()
        .any(|p| !(p.0.is_finite() && p.1.is_finite() && p.2.is_finite()))
    {
        return Err(Error::Data("polynomial fit: non-finite point".into()));
    }
    let frame = match frame {
        Some(f) => f,
        None => FitFrame::bounding(&points.iter().map(|p| (p.0, p.1)).collect::<Vec<_>>())?,
    };
    let n = points.len();
    // Column-major design matrix.
    let mut a = vec![0.0; n * m];
    let mut rhs: Vec<f64> = points.iter().map(|p| p.2).collect();
    for (r, p) in points.iter().enumerate() {
        let (u, v) = frame.scaled(p.0, p.1);
        for (c, &(ea, eb)) in exps.iter().enumerate() {
            a[c * n + r] = u.powi(ea as i32) * v.powi(eb as i32);
        }
    }
    let coef = householder_least_squares(&mut a, n, m, &mut rhs)?;
    let mean = points.iter().map(|p| p.2).sum::<f64>() / n as f64;
    let mut ss_tot = 0.0;
    let mut ss_res = 0.0;
    let mut result = PolyFit2 {
        order,
        frame,
        exponents: exps,
        coefficients_pa: coef,
        r_squared: f64::NAN,
        rms_residual_pa: f64::NAN,
        n_points: n,
    };
    for p in points {
        let e = p.2 - result.eval(p.0, p.1);
        ss_res += e * e;
        ss_tot += (p.2 - mean).powi(2);
    }
    // Uniform points (one flat colour, e.g. a grey disc read with order 0) are fitted exactly
    // by the constant, but leave no variance to explain: R² = 0/0 is undefined, not a number
    // to report (rounding can leave a tiny SS_tot, so spread is tested, not SS_tot > 0).
    let (lo, hi) = points
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p.2), b.max(p.2))
        });
    let uniform = hi - lo <= 1e-12 * hi.abs().max(lo.abs());
    result.r_squared = if uniform {
        f64::NAN
    } else {
        1.0 - ss_res / ss_tot
    };
    result.rms_residual_pa = (ss_res / n as f64).sqrt();
    Ok(result)
}

/// Solve `min ‖A c − y‖₂` for column-major `A` (n × m, n ≥ m) by Householder QR; `a` and `y`
/// are overwritten. Errors when `A` is rank deficient (a column's norm collapses).
fn householder_least_squares(a: &mut [f64], n: usize, m: usize, y: &mut [f64]) -> Result<Vec<f64>> {
    let col_scale: Vec<f64> = (0..m)
        .map(|c| {
            a[c * n..(c + 1) * n]
                .iter()
                .map(|v| v * v)
                .sum::<f64>()
                .sqrt()
        })
        .collect();
    let mut diag = vec![0.0; m];
    for k in 0..m {
        let (before, rest) = a.split_at_mut((k + 1) * n);
        let col = &mut before[k * n..];
        let norm = col[k..].iter().map(|v| v * v).sum::<f64>().sqrt();
        if norm <= 1e-12 * col_scale[k].max(f64::MIN_POSITIVE) {
            return Err(Error::Data(format!(
                "polynomial fit is rank deficient (monomial {k} is not determined by the points): use a lower order or a larger region"
            )));
        }
        let alpha = if col[k] > 0.0 { -norm } else { norm };
        col[k] -= alpha;
        let vnorm2 = col[k..].iter().map(|v| v * v).sum::<f64>();
        diag[k] = alpha;
        // Apply H = I − 2 v vᵀ / (vᵀv) to the remaining columns and to y.
        for c in 0..(m - k - 1) {
            let other = &mut rest[c * n..(c + 1) * n];
            let dot: f64 = col[k..].iter().zip(&other[k..]).map(|(p, q)| p * q).sum();
            let f = 2.0 * dot / vnorm2;
            for (o, v) in other[k..].iter_mut().zip(&col[k..]) {
                *o -= f * v;
            }
        }
        let dot: f64 = col[k..].iter().zip(&y[k..]).map(|(p, q)| p * q).sum();
        let f = 2.0 * dot / vnorm2;
        for (o, v) in y[k..].iter_mut().zip(&col[k..]) {
            *o -= f * v;
        }
    }
    // Back substitution with R (diagonal in `diag`, strict upper part in `a`).
    let mut c = vec![0.0; m];
    for k in (0..m).rev() {
        let mut s = y[k];
        for j in k + 1..m {
            s -= a[j * n + k] * c[j];
        }
        c[k] = s / diag[k];
    }
    Ok(c)
}

/// Write fitted coefficients of several regions as CSV
/// (`region_id,order,x_centre_m,y_centre_m,x_half_width_m,y_half_width_m,a,b,coefficient_Pa`).
pub fn write_coefficients_csv(path: &std::path::Path, fits: &[(usize, &PolyFit2)]) -> Result<()> {
    crate::core::output::write_atomic(path, |w| {
        let io = |e: std::io::Error| Error::io(path, e);
        writeln!(w, "# sigma(x, y) = sum coefficient_Pa * u^a * v^b, u = (x - x_centre_m)/x_half_width_m, v = (y - y_centre_m)/y_half_width_m (film frame, m)").map_err(io)?;
        writeln!(w, "region_id,order,x_centre_m,y_centre_m,x_half_width_m,y_half_width_m,a,b,coefficient_Pa").map_err(io)?;
        for (id, f) in fits {
            for (&(a, b), c) in f.exponents.iter().zip(&f.coefficients_pa) {
                writeln!(
                    w,
                    "{id},{},{:.12e},{:.12e},{:.12e},{:.12e},{a},{b},{c:.12e}",
                    f.order,
                    f.frame.x_centre_m,
                    f.frame.y_centre_m,
                    f.frame.x_half_width_m,
                    f.frame.y_half_width_m
                )
                .map_err(io)?;
            }
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_polynomial_is_recovered() {
        let truth =
            |u: f64, v: f64| 3.0 + 0.5 * u - 0.2 * v + 0.7 * u * u * v * v - 0.1 * v.powi(4);
        let mut pts = Vec::new();
        for i in 0..30 {
            for j in 0..20 {
                let (x, y) = (0.01 + i as f64 * 1e-4, 0.02 + j as f64 * 2e-4);
                pts.push((x, y, 0.0));
            }
        }
        let frame =
            FitFrame::bounding(&pts.iter().map(|p| (p.0, p.1)).collect::<Vec<_>>()).unwrap();
        for p in pts.iter_mut() {
            let (u, v) = frame.scaled(p.0, p.1);
            p.2 = truth(u, v);
        }
        let f = fit(&pts, 4, None).unwrap();
        assert!((f.r_squared - 1.0).abs() < 1e-12);
        let e = exponents(4);
        let want = |a, b| match (a, b) {
            (0, 0) => 3.0,
            (1, 0) => 0.5,
            (0, 1) => -0.2,
            (2, 2) => 0.7,
            (0, 4) => -0.1,
            _ => 0.0,
        };
        for (k, &(a, b)) in e.iter().enumerate() {
            assert!((f.coefficients_pa[k] - want(a, b)).abs() < 1e-10, "{a},{b}");
        }
    }

    /// Uniform points are fitted exactly by the constant; their R² is undefined and written
    /// as an empty field, never as `NaN`.
    #[test]
    fn uniform_pressure_has_no_r_squared() {
        let mut pts = Vec::new();
        for i in 0..10 {
            for j in 0..10 {
                pts.push((i as f64 * 1e-4, j as f64 * 1e-4, 5.78e6));
            }
        }
        let f = fit(&pts, 4, None).unwrap();
        assert!((f.eval(3e-4, 4e-4) - 5.78e6).abs() < 1e-3);
        assert_eq!(f.r_squared_text(9), "");
        pts[0].2 = 5.7e6;
        let f = fit(&pts, 4, None).unwrap();
        assert!(f.r_squared.is_finite());
        assert!(!f.r_squared_text(9).is_empty());
    }

    #[test]
    fn too_few_points_or_collinear_points_are_errors() {
        let pts: Vec<_> = (0..5).map(|i| (i as f64, 0.0, 1.0)).collect();
        assert!(fit(&pts, 4, None).is_err());
        let pts: Vec<_> = (0..50).map(|i| (i as f64, 0.0, 1.0)).collect();
        assert!(fit(&pts, 1, None).is_err());
    }
}
