//! The underplatform-damper-size case shared by `benches/response.rs` and
//! `tests/dynamics_upd_accuracy.rs`: a synthetic reduced modal model of two blades and an
//! underplatform damper (seeded), 146 Valanis microslip contact elements, and the parabolic
//! refinement of a sampled peak. Units: SI (m, N, kg, Hz).

use asperity::dynamics::model::Structure;
use asperity::element::MicroslipContact;
use asperity::element::ValanisParams;
use nalgebra::{DMatrix, DVector};
use rand::{Rng, SeedableRng};
use std::sync::Arc;

/// Modes of the reduced model.
pub const MODES: usize = 30;

/// Rigid-body kinematics of a contact point at `r` (m) of a body moving by translation `t` and
/// small rotation `th`: `t + th × r`.
fn point(t: [f64; 3], th: [f64; 3], r: [f64; 3]) -> [f64; 3] {
    [
        t[0] + th[1] * r[2] - th[2] * r[1],
        t[1] + th[2] * r[0] - th[0] * r[2],
        t[2] + th[0] * r[1] - th[1] * r[0],
    ]
}

/// Two blades and a damper: every mode moves each body's platform region as a rigid body plus a
/// smooth elastic bending over the contact face; shapes mass-normalised (modal masses 0.05–0.5 kg).
pub fn model() -> (Structure, DVector<f64>, DVector<f64>) {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let freqs: Vec<f64> = (0..MODES)
        .map(|r| 600.0 * (8000.0f64 / 600.0).powf(r as f64 / (MODES - 1) as f64))
        .collect();
    let mut s = Structure::modal(&freqs, &vec![0.003; MODES]).unwrap();
    // Per mode and body: translation (m per √kg) and rotation (rad per √kg) amplitudes.
    let mut body = vec![[[0.0; 3]; 6]; MODES];
    for b in body.iter_mut() {
        let scale = 1.0 / rng.random_range(0.05f64..0.5).sqrt();
        for (k, v) in b.iter_mut().enumerate() {
            for x in v.iter_mut() {
                // Bodies 0..2 translations, 3..5 rotations (×1/lever 10 mm).
                *x = scale * rng.random_range(-1.0..1.0) * if k < 3 { 1.0 } else { 50.0 };
            }
        }
    }
    let v = ValanisParams::new(2.6e13 * 1.0e-7, 0.316, 0.0, 0.6).unwrap();
    let (kn, n0) = (2.6e13 * 1.0e-7, 2.0e6 * 1.0e-7 * 5.0);
    for iface in 0..2 {
        // Contact face 10 mm × 6 mm, normal tilted ±45° in the x–z plane (wedge damper).
        let sgn = if iface == 0 { 1.0 } else { -1.0 };
        let normal = [
            sgn * std::f64::consts::FRAC_1_SQRT_2,
            0.0,
            std::f64::consts::FRAC_1_SQRT_2,
        ];
        let t1 = [-normal[2], 0.0, normal[0]];
        let t2 = [0.0, 1.0, 0.0];
        for e in 0..73 {
            let (i, j) = (e % 11, e / 11);
            let r = [
                sgn * 0.01 + 0.0006 * i as f64 * t1[0],
                -0.003 + 0.001 * j as f64,
                0.0006 * i as f64 * t1[2],
            ];
            let mut map = DMatrix::zeros(3, MODES);
            for (m, b) in body.iter().enumerate() {
                // Damper (body 2, translation index 2 and rotation index 5) against blade `iface`.
                let pd = point(b[2], b[5], r);
                let pb = point(b[iface], b[3 + iface], r);
                let rel = [pd[0] - pb[0], pd[1] - pb[1], pd[2] - pb[2]];
                for (c, axis) in [t1, t2, normal].iter().enumerate() {
                    map[(c, m)] = axis.iter().zip(&rel).map(|(a, b)| a * b).sum::<f64>();
                }
            }
            let el = MicroslipContact::new(v, kn, n0).unwrap();
            s.attach(format!("{iface}-{e}"), Arc::new(el), map).unwrap();
        }
    }
    // Excitation and response at a blade-1 tip point (modal participation from body 0).
    let force = DVector::from_iterator(MODES, body.iter().map(|b| b[0][0]));
    let response = force.clone();
    (s, force, response)
}

/// Peak of sampled (frequency, amplitude) points refined by a parabola through the largest
/// sample and its neighbours.
pub fn refined_peak(f: &[f64], a: &[f64]) -> (f64, f64) {
    let i = (0..a.len())
        .max_by(|&i, &j| a[i].partial_cmp(&a[j]).unwrap())
        .unwrap();
    if i == 0 || i + 1 == a.len() {
        return (f[i], a[i]);
    }
    // Lagrange parabola through three (possibly unequally spaced) points.
    let (x0, x1, x2) = (f[i - 1], f[i], f[i + 1]);
    let (y0, y1, y2) = (a[i - 1], a[i], a[i + 1]);
    let d = (x0 - x1) * (x0 - x2) * (x1 - x2);
    let aa = (x2 * (y1 - y0) + x1 * (y0 - y2) + x0 * (y2 - y1)) / d;
    let bb = (x2 * x2 * (y0 - y1) + x1 * x1 * (y2 - y0) + x0 * x0 * (y1 - y2)) / d;
    let cc = (x1 * x2 * (x1 - x2) * y0 + x2 * x0 * (x2 - x0) * y1 + x0 * x1 * (x0 - x1) * y2) / d;
    if aa >= 0.0 {
        return (f[i], a[i]);
    }
    let xv = -bb / (2.0 * aa);
    (xv, aa * xv * xv + bb * xv + cc)
}
