//! Physical sanity of inputs (before a solve) and of results (after it).
//!
//! A solver given an input outside the range its model covers does not fail: it returns a
//! number (a flat surface gives kn = −∞, a tolerance of 1 stops at iteration 0, a pressure of
//! 1e-300 Pa leaves the gap unchanged to round-off). These checks turn every such case into an
//! error naming the flag, key or file, with the bound and why it holds.
//!
//! | check | bound | why |
//! |---|---|---|
//! | [`tolerance`] | `0 < tol < 1` | a relative residual of 1 or more is met by the initial guess |
//! | [`contact_surface`] | spacing in [[`MIN_SPACING_M`], [`MAX_SPACING_M`]], `max |h|` ≤ [`MAX_HEIGHT_M`], not flat | outside these the heights are in the wrong unit or the products overflow; a flat surface is in full contact at any load |
//! | [`crate::surface::stats::contact_surface_tilt`] (warning) | plane's rise across a non-periodic window ≤ the Rq left without it | the solvers take heights as given: a tilt loads one side of the window |
//! | [`contact_file_grid`] | ≥ [`MIN_CONTACT_FILE_POINTS`] points per side | a profile or a stub read from a file is not an area whose contact the solvers resolve |
//! | [`contact_pressures`] | `p ≤ MAX_STRAIN · E*` (10 %, also in `NormalSolver::solve_load`) and `p·L/E* ≥ RESOLVABLE_FRACTION · (h_max − h_min)` | small-strain linear elasticity; an elastic displacement below the round-off of the heights cannot be resolved |
//! | [`finite_result`] / [`positive_result`] | finite (and > 0) | a non-finite or non-positive stiffness, gap or error is never reported as a result |
//! | [`magnitudes`] | `|v| ≤ max` | measured values beyond any instrument's range are a unit or format error |
//! | [`grid_spacing`] (every topography read, `surface::io::read`) | [[`MIN_SPACING_M`], [`MAX_SPACING_M`]] | the same spacings for statistics, conversion and contact: outside them the unit is wrong and slopes or lengths overflow |
//! | [`film_pixel_size`] | [[`MIN_FILM_PIXEL_M`], [`MAX_FILM_PIXEL_M`]] | a pixel outside any scan's range gives infinite areas or no patch at all |
//!
//! New commands adopt them with one call per input (`sanity::tolerance("--tolerance", t)?`,
//! `sanity::contact_surface(&grid, &source)?`, `sanity::contact_pressures("--pressures-pa",
//! &p, e_star, &grid)?`) and one per reported number (`sanity::finite_result(what, v)?`).

use crate::core::error::{num, Error, Result};
use crate::core::grid::Grid2;

/// Smallest grid spacing of a contact surface (1 pm: below atomic distances).
pub const MIN_SPACING_M: f64 = 1e-12;
/// Largest grid spacing of a contact surface (1 m).
pub const MAX_SPACING_M: f64 = 1.0;
/// Largest |height| of a contact surface (1 m): roughness heights are µm; metres mean a unit error.
pub const MAX_HEIGHT_M: f64 = 1.0;
/// Largest nominal strain `p̄/E*` of the linear-elastic half-space model (10 %), the one limit
/// of every door (CLI, configuration, library solver, Python).
///
/// Why here: the model is infinitesimal-strain linear elasticity on a half-space, whose error
/// grows like the strain (and, for the half-space, like the square of the surface slopes); at
/// 10 % the correction is no longer small. A rough surface the half-space model admits has rms
/// gradients h' of at most about 0.1–0.2, and its contact is then essentially complete
/// (A/A₀ → 1 as p̄ approaches E*·h', Persson's theory), so higher nominal pressures carry no
/// rough-contact information either. Benchmarks of the self-affine surface (h' = 0.1) at
/// p̄/(E*h') = 0.53, i.e. p̄ = 0.053·E* (contact fraction 0.76), lie within it.
pub const MAX_STRAIN: f64 = 0.1;
/// Smallest elastic displacement scale `p·L/E*` relative to the height range that double
/// precision resolves in the gap `h0 − δ + u` (10⁻¹² ≫ the 2.2 × 10⁻¹⁶ round-off).
pub const RESOLVABLE_FRACTION: f64 = 1e-12;

/// Smallest pixel of a pressure-film scan (0.1 µm, about 250 000 dpi): finer than any scanner
/// or microscope image of a film whose microcapsules are several µm across.
pub const MIN_FILM_PIXEL_M: f64 = 1e-7;
/// Largest pixel of a pressure-film scan (10 mm, 2.5 dpi): a coarser image does not resolve a
/// contact patch.
pub const MAX_FILM_PIXEL_M: f64 = 1e-2;

/// A film pixel size (m) within [[`MIN_FILM_PIXEL_M`], [`MAX_FILM_PIXEL_M`]]; the message
/// otherwise (areas and pressures derived from a pixel outside it overflow, or no patch is
/// large enough to be found).
pub fn film_pixel_size(pixel_m: f64) -> std::result::Result<(), String> {
    if (MIN_FILM_PIXEL_M..=MAX_FILM_PIXEL_M).contains(&pixel_m) {
        Ok(())
    } else {
        Err(format!(
            "a pixel of {} mm lies outside the {}–{} mm a film scan can have (wrong unit? \
             300 dpi is 0.0847 mm)",
            num(pixel_m * 1e3),
            num(MIN_FILM_PIXEL_M * 1e3),
            num(MAX_FILM_PIXEL_M * 1e3)
        ))
    }
}

/// Largest displacement amplitude a measured vibration row may imply (m): no vibration test of
/// a structure reaches a metre at its resonance; more is a unit error.
pub const MAX_VIBRATION_AMPLITUDE_M: f64 = 1.0;

/// Largest harmonic force amplitude (N) of a measured row or a model's excitation level: beyond
/// any shaker or hammer.
pub const MAX_FORCE_AMPLITUDE_N: f64 = 1e6;

/// Fewest grid points per side of a contact surface read from a file: the contact commands'
/// `--grid` floor (tangential: 8). Fewer points are a profile or a stub, not an area whose
/// contact the half-space solvers can resolve (a 4 × 1 matrix gives kn ≈ 1e16 N/m³).
pub const MIN_CONTACT_FILE_POINTS: usize = 8;

/// A contact surface read from `source` (a file, named in the message) has at least
/// [`MIN_CONTACT_FILE_POINTS`] points along x and along y.
pub fn contact_file_grid(source: &str, nx: usize, ny: usize) -> Result<()> {
    if nx < MIN_CONTACT_FILE_POINTS || ny < MIN_CONTACT_FILE_POINTS {
        return Err(Error::Data(format!(
            "{source}: {nx} x {ny} points (x by y); a contact surface needs at least \
             {MIN_CONTACT_FILE_POINTS} points along each side (a profile or a few points do not \
             resolve an area's contact)"
        )));
    }
    Ok(())
}

/// Largest Coulomb friction coefficient accepted. Dry metal pairs measure 0.1–1.5 in air and
/// clean surfaces in vacuum a few; a value of ten or more is a typing or unit error.
pub const MAX_FRICTION_COEFFICIENT: f64 = 10.0;

/// A Coulomb friction coefficient: `0 < μ ≤` [`MAX_FRICTION_COEFFICIENT`].
pub fn friction_coefficient(name: &str, mu: f64) -> Result<f64> {
    if mu.is_finite() && mu > 0.0 && mu <= MAX_FRICTION_COEFFICIENT {
        Ok(mu)
    } else {
        Err(Error::param(
            name,
            format!(
                "a friction coefficient must satisfy 0 < μ ≤ {} (dry metal pairs: 0.1–1.5), got {}",
                num(MAX_FRICTION_COEFFICIENT),
                num(mu)
            ),
        ))
    }
}

/// A relative solver tolerance: `0 < value < 1`.
pub fn tolerance(name: &str, value: f64) -> Result<f64> {
    if value.is_finite() && value > 0.0 && value < 1.0 {
        Ok(value)
    } else {
        Err(Error::param(
            name,
            format!(
                "a relative tolerance must satisfy 0 < tolerance < 1, got {} (a residual \
                 tolerance of 1 or more is met by the initial guess)",
                num(value)
            ),
        ))
    }
}

/// A result that must be finite; the error names what it is.
pub fn finite_result(what: &str, value: f64) -> Result<f64> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(Error::Data(format!(
            "{what} is {} (not a finite number): the input is outside the range the model \
             covers; nothing is written",
            num(value)
        )))
    }
}

/// A result that must be finite and strictly positive (a stiffness, a contact area).
pub fn positive_result(what: &str, value: f64) -> Result<f64> {
    finite_result(what, value)?;
    if value > 0.0 {
        Ok(value)
    } else {
        Err(Error::Data(format!(
            "{what} is {} (must be > 0): the input is outside the range the model covers; \
             nothing is written",
            num(value)
        )))
    }
}

/// Every value of a measured column within `|v| ≤ max` (`unit` names the unit of `max`).
/// Returns the index of the first offending value in the error message.
pub fn magnitudes(name: &str, values: &[f64], max: f64, unit: &str) -> Result<()> {
    if let Some((i, v)) = values.iter().enumerate().find(|(_, v)| v.abs() > max) {
        return Err(Error::Data(format!(
            "{name}: value {} at sample {i} exceeds {} {unit} in magnitude: a unit or format \
             error",
            num(*v),
            num(max)
        )));
    }
    Ok(())
}

/// Height range `(min, max)` of a grid.
fn height_range(g: &Grid2) -> (f64, f64) {
    g.heights
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &h| {
            (a.min(h), b.max(h))
        })
}

/// A grid spacing `d` (m) a rough contact patch can have, in [[`MIN_SPACING_M`],
/// [`MAX_SPACING_M`]]; the message (without the axis or source) otherwise.
pub fn grid_spacing(d: f64) -> std::result::Result<(), String> {
    if (MIN_SPACING_M..=MAX_SPACING_M).contains(&d) {
        Ok(())
    } else {
        Err(format!(
            "grid spacing {} m lies outside [{}, {}] m that a measured or generated rough \
             surface can have (wrong unit?)",
            num(d),
            num(MIN_SPACING_M),
            num(MAX_SPACING_M)
        ))
    }
}

/// A surface that a contact solver can use: spacings in [[`MIN_SPACING_M`],
/// [`MAX_SPACING_M`]], heights within ±[`MAX_HEIGHT_M`], and not flat (a flat surface touches
/// everywhere at the first load: the contact is complete and kn undefined). `source` names the
/// file or the generated surface.
pub fn contact_surface(g: &Grid2, source: &str) -> Result<()> {
    for (axis, d) in [("x", g.dx), ("y", g.dy)] {
        grid_spacing(d).map_err(|m| Error::Data(format!("{source}: along {axis}, {m}")))?;
    }
    let (lo, hi) = height_range(g);
    let big = lo.abs().max(hi.abs());
    if big > MAX_HEIGHT_M {
        return Err(Error::Data(format!(
            "{source}: heights reach {} m, beyond the ±{} m a rough surface can have (wrong \
             unit?)",
            num(if hi.abs() >= lo.abs() { hi } else { lo }),
            num(MAX_HEIGHT_M)
        )));
    }
    if hi - lo <= 64.0 * f64::EPSILON * big {
        return Err(Error::Data(format!(
            "{source}: the surface is flat (all heights {} m): it is in full contact at any \
             load, so there is no rough contact to solve and kn is undefined",
            num(hi)
        )));
    }
    Ok(())
}

/// Nominal pressures that the half-space model can resolve on `surface` with composite
/// modulus `e_star_pa`: `p ≤ MAX_STRAIN · E*` (small strain) and `p·L/E* ≥ RESOLVABLE_FRACTION
/// × (h_max − h_min)` with `L` the larger side of the patch (the elastic displacement must be
/// visible above the round-off of the heights). `name` is the flag or key.
pub fn contact_pressures(
    name: &str,
    pressures_pa: &[f64],
    e_star_pa: f64,
    surface: &Grid2,
) -> Result<()> {
    let (lo, hi) = height_range(surface);
    contact_pressures_for(
        name,
        pressures_pa,
        e_star_pa,
        surface.lx().max(surface.ly()),
        hi - lo,
    )
}

/// Below this composite modulus (Pa) a solid's modulus was most likely given in the wrong unit
/// (GPa or MPa read as Pa): the softest elastomers have E ≈ 1 MPa.
pub const IMPLAUSIBLE_E_STAR_PA: f64 = 1e5;

/// The likely cause of a pressure above the small-strain bound: the units. Names the modulus
/// flag when `name` is a flag, and says so outright when E* itself is implausibly small.
fn units_hint(name: &str, e_star_pa: f64) -> String {
    let modulus = if name.starts_with("--") {
        format!("--youngs-modulus-pa is in Pa (steel: 2.1e11), {name} in Pa")
    } else {
        format!("`youngs_modulus_pa` is in Pa (steel: 2.1e11), `{name}` in Pa")
    };
    if e_star_pa < IMPLAUSIBLE_E_STAR_PA {
        format!(
            " — check the units: E* = {} Pa is far below any solid's (a modulus in GPa or \
             MPa given as Pa?); {modulus}",
            num(e_star_pa)
        )
    } else {
        format!(" (check the units: {modulus})")
    }
}

/// Refuse a nominal pressure `p_pa` above [`MAX_STRAIN`] × `e_star_pa` (the message without
/// the name of the flag or key).
pub fn nominal_strain(p_pa: f64, e_star_pa: f64) -> std::result::Result<(), String> {
    if p_pa > MAX_STRAIN * e_star_pa {
        Err(strain_message(p_pa, e_star_pa))
    } else {
        Ok(())
    }
}

fn strain_message(p_pa: f64, e_star_pa: f64) -> String {
    format!(
        "{} Pa exceeds {} × E* = {:.4e} Pa: nominal strains above {} % are outside the \
         linear-elastic half-space model (and a rough surface it admits is in full contact \
         there)",
        num(p_pa),
        num(MAX_STRAIN),
        MAX_STRAIN * e_star_pa,
        num(100.0 * MAX_STRAIN)
    )
}

/// [`contact_pressures`] for a surface known by its size `size_m` (larger side) and height
/// range `height_range_m` (for a generated Gaussian surface, about 8 Rq), before it exists.
pub fn contact_pressures_for(
    name: &str,
    pressures_pa: &[f64],
    e_star_pa: f64,
    size_m: f64,
    height_range_m: f64,
) -> Result<()> {
    let (lo, hi, size) = (0.0, height_range_m, size_m);
    for &p in pressures_pa {
        if nominal_strain(p, e_star_pa).is_err() {
            return Err(Error::param(
                name,
                format!(
                    "{}{}",
                    strain_message(p, e_star_pa),
                    units_hint(name, e_star_pa)
                ),
            ));
        }
        let u = p * size / e_star_pa;
        if u < RESOLVABLE_FRACTION * (hi - lo) {
            return Err(Error::param(
                name,
                format!(
                    "{} Pa is too small to resolve: its elastic displacement p·L/E* ≈ {} m is \
                     below the round-off of the surface heights (range {} m)",
                    num(p),
                    num(u),
                    num(hi - lo)
                ),
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use ndarray::Array2;

    fn rough(scale: f64, dx: f64) -> Grid2 {
        let h = Array2::from_shape_fn((8, 8), |(i, j)| scale * ((i * 7 + j * 3) % 5) as f64);
        Grid2::new(h, dx, dx, true).unwrap()
    }

    #[test]
    fn tolerance_must_lie_in_the_unit_interval() {
        assert!(tolerance("--tolerance", 1e-8).is_ok());
        for t in [0.0, 1.0, 5.0, -1e-3, f64::NAN] {
            let e = tolerance("--tolerance", t).unwrap_err().to_string();
            assert!(e.contains("--tolerance"), "{e}");
        }
    }

    #[test]
    fn unusable_surfaces_and_pressures_are_named() {
        let g = rough(1e-7, 1e-6);
        assert!(contact_surface(&g, "s").is_ok());
        let flat = Grid2::new(Array2::from_elem((8, 8), 3e-6), 1e-6, 1e-6, true).unwrap();
        assert!(contact_surface(&flat, "flat.npy")
            .unwrap_err()
            .to_string()
            .contains("flat.npy: the surface is flat"));
        assert!(contact_surface(&rough(1e292, 1e-6), "big")
            .unwrap_err()
            .to_string()
            .contains("wrong unit"));
        assert!(contact_surface(&rough(1e-7, 1e-300), "tiny").is_err());
        assert!(contact_surface(&rough(1e-7, 1e300), "huge").is_err());
        assert!(contact_pressures("--p", &[1e6], 1.15e11, &g).is_ok());
        let e = contact_pressures("--p", &[1e-300], 1.15e11, &g)
            .unwrap_err()
            .to_string();
        assert!(e.contains("--p") && e.contains("too small"), "{e}");
        // One small-strain limit, 10 % of E*: BENCHMARKS' self-affine cases at 0.053·E* run.
        assert!(contact_pressures("--p", &[2e10], 1.15e11, &g).is_err());
        assert!(nominal_strain(0.053 * 1.15e11, 1.15e11).is_ok());
        assert!(nominal_strain(0.1001 * 1.15e11, 1.15e11).is_err());
        assert!(finite_result("kn", f64::NEG_INFINITY).is_err());
        assert!(positive_result("kn", -1.0).is_err());
        assert!(magnitudes("force", &[1.0, 1e304], 1e12, "N")
            .unwrap_err()
            .to_string()
            .contains("sample 1"));
    }
}
