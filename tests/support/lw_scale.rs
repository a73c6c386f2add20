//! The Fujifilm Prescale LW colour scale of the reference colour table (graded rows
//! 2.5–9.06 MPa: red 255, green = blue falling linearly between rows), for tests that render
//! synthetic film images. Pressures in Pa.

/// Green (= blue) level of the LW colour at pressure `p` (Pa), linear between the graded rows;
/// `p` must lie within 2.5–9.06 MPa.
pub fn lw_green(p: f64) -> f64 {
    let rows = [
        (2.50e6, 227.0),
        (3.44e6, 198.0),
        (4.38e6, 170.0),
        (5.31e6, 142.0),
        (6.25e6, 113.0),
        (7.19e6, 85.0),
        (8.13e6, 57.0),
        (9.06e6, 28.0),
    ];
    assert!((2.5e6..=9.06e6).contains(&p), "{p} Pa outside the LW range");
    let k = rows.windows(2).position(|w| p <= w[1].0).unwrap();
    let (a, b) = (rows[k], rows[k + 1]);
    a.1 + (p - a.0) / (b.0 - a.0) * (b.1 - a.1)
}
