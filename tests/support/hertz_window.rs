//! A sphere's height matrix in a non-periodic window, shared by the contact CLI tests
//! (`tests/contact_normal_cli.rs`, `tests/tangential_contact.rs`).

use std::path::Path;

/// Write the heights `−(x² + y²)/(2R)` of a sphere of radius 10 mm, centred, on an `n × n`
/// grid over a square window of side `l_m` (m), as an asperity height matrix (`periodic: false`).
pub fn write_hertz_window(path: &Path, n: usize, l_m: f64) {
    let (r, dx) = (0.01, l_m / n as f64);
    let c = (n / 2) as f64;
    let mut text = format!(
        "# asperity height matrix\n# unit: m, dx_m: {dx:e}, dy_m: {dx:e}, periodic: false\n"
    );
    for j in 0..n {
        let row: Vec<String> = (0..n)
            .map(|i| {
                let (x, y) = ((i as f64 - c) * dx, (j as f64 - c) * dx);
                format!("{:e}", -(x * x + y * y) / (2.0 * r))
            })
            .collect();
        text.push_str(&row.join(","));
        text.push('\n');
    }
    std::fs::write(path, text).unwrap();
}
