//! Closed-form contact solutions used to validate the boundary-element solvers.
//!
//! Hertz (sphere on flat), Johnson, *Contact Mechanics*, 1985, §4.2; see also
//! `../shared/data/contact/REFERENCES.md`. SI units.

/// Hertz contact of a sphere (radius `r`, m) pressed with force `p` (N), composite modulus
/// `e_star` (Pa).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hertz {
    /// Contact radius a = (3PR / (4E*))^(1/3) (m).
    pub radius: f64,
    /// Peak pressure p0 = 3P / (2πa²) (Pa).
    pub peak_pressure: f64,
    /// Approach δ = a² / R (m).
    pub approach: f64,
}

impl Hertz {
    /// Closed-form Hertz solution.
    pub fn new(sphere_radius: f64, force: f64, e_star: f64) -> Self {
        let a = (3.0 * force * sphere_radius / (4.0 * e_star)).cbrt();
        Self {
            radius: a,
            peak_pressure: 3.0 * force / (2.0 * std::f64::consts::PI * a * a),
            approach: a * a / sphere_radius,
        }
    }

    /// Pressure at distance `r` from the centre: p0·sqrt(1 - r²/a²) inside, 0 outside (Pa).
    pub fn pressure(&self, r: f64) -> f64 {
        let s = 1.0 - (r / self.radius).powi(2);
        if s > 0.0 {
            self.peak_pressure * s.sqrt()
        } else {
            0.0
        }
    }
}

/// The load at which the Hertz peak pressure reaches the hardness `H` (N): with
/// `p0 = (6PE*²/(π³R²))^(1/3)` (Johnson 1985, §4.2), `p0 = H` at
///
/// `P_H = (πH)³ R² / (6 E*²)`.
///
/// Below it a hardness-limited (pressure-saturated) contact is exactly Hertzian; above it the
/// centre saturates at `H`. (This is the onset of saturation, not of yield inside the body,
/// which starts at `p0 ≈ 1.6 Y` below the surface; Johnson 1985, §6.1.)
pub fn hertz_saturation_load(sphere_radius: f64, hardness: f64, e_star: f64) -> f64 {
    (std::f64::consts::PI * hardness).powi(3) * sphere_radius.powi(2) / (6.0 * e_star.powi(2))
}

/// Normal stiffness `dP/dδ = 2E*a` of a rigid flat-ended circular punch of radius `a` on an
/// elastic half-space (N/m; Johnson 1985, §3.8; Sneddon, Int. J. Eng. Sci. 3 (1965) 47–57).
/// By Barber's theorem it is also the unloading stiffness of any frictionless contact whose
/// contact area is a disc of radius `a` (Pharr, Oliver & Brotzen, J. Mater. Res. 7 (1992)
/// 613–617).
pub fn flat_punch_stiffness(contact_radius: f64, e_star: f64) -> f64 {
    2.0 * e_star * contact_radius
}

/// Cattaneo–Mindlin partial slip of a Hertz contact under constant normal force `P` and a
/// tangential force `T` (Johnson, *Contact Mechanics*, 1985, §7.2; Mindlin & Deresiewicz 1953).
///
/// Valid for quasi-identical bodies (normal and tangential problems decouple). The tangential
/// compliance of the pair enters through `s = (2-ν1)/G1 + (2-ν2)/G2` (1/Pa); for identical
/// bodies `s = 2(2-ν)/G`. SI units: N, m, Pa.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CattaneoMindlin {
    /// Hertz contact radius a (m).
    pub contact_radius: f64,
    /// Normal force P (N).
    pub normal_force: f64,
    /// Friction coefficient μ (-).
    pub friction_coefficient: f64,
    /// Tangential compliance sum `s = Σ (2-ν_k)/G_k` (1/Pa).
    pub compliance_sum: f64,
}

impl CattaneoMindlin {
    /// The closed form for contact radius `a` (m), normal force `P` (N), friction coefficient μ
    /// and the two bodies' shear moduli (Pa) and Poisson ratios.
    pub fn new(a: f64, p: f64, mu: f64, g1: f64, nu1: f64, g2: f64, nu2: f64) -> Self {
        Self {
            contact_radius: a,
            normal_force: p,
            friction_coefficient: mu,
            compliance_sum: (2.0 - nu1) / g1 + (2.0 - nu2) / g2,
        }
    }

    fn mu_p(&self) -> f64 {
        self.friction_coefficient * self.normal_force
    }

    /// Stick radius `c = a (1 − T/(μP))^(1/3)` (m), for `0 ≤ T ≤ μP`.
    pub fn stick_radius(&self, t: f64) -> f64 {
        self.contact_radius * (1.0 - t.abs() / self.mu_p()).max(0.0).cbrt()
    }

    /// Tangential displacement of the bodies under monotonic loading from zero to `T` (m):
    /// `δ = 3μP·s/(16a) · [1 − (1 − T/(μP))^(2/3)]` (for identical bodies
    /// `3μP(2−ν)/(8Ga)·[…]`, Johnson eq. 7.42). Odd in `T`.
    pub fn displacement(&self, t: f64) -> f64 {
        let x = (t.abs() / self.mu_p()).min(1.0);
        let d = 3.0 * self.mu_p() * self.compliance_sum / (16.0 * self.contact_radius)
            * (1.0 - (1.0 - x).powf(2.0 / 3.0));
        d.copysign(t)
    }

    /// Initial tangential stiffness `dT/dδ` at `T = 0`: `8a/s` (N/m); identical bodies
    /// `4Ga/(2−ν)` (Mindlin 1949).
    pub fn initial_stiffness(&self) -> f64 {
        8.0 * self.contact_radius / self.compliance_sum
    }

    /// Displacement on the unloading branch from `T*` down to `T` (Masing rule,
    /// Mindlin & Deresiewicz 1953): `δ(T) = δ(T*) − 2 δ((T* − T)/2)`. The reloading branch from
    /// `−T*` is its mirror image.
    pub fn unloading_displacement(&self, t_star: f64, t: f64) -> f64 {
        self.displacement(t_star) - 2.0 * self.displacement(0.5 * (t_star - t))
    }

    /// Energy dissipated per cycle of `T` oscillating between `±T*` (J):
    /// `W = 9μ²P²·s/(10a) · {1 − (1−x)^(5/3) − (5x/6)[1 + (1−x)^(2/3)]}`, `x = T*/(μP)`
    /// (identical bodies: `9μ²P²(2−ν)/(5Ga)·{…}`, Johnson 1985 eq. 7.59).
    pub fn energy_per_cycle(&self, t_star: f64) -> f64 {
        let x = (t_star.abs() / self.mu_p()).min(1.0);
        let m = self.mu_p();
        9.0 * m * m * self.compliance_sum / (10.0 * self.contact_radius)
            * (1.0 - (1.0 - x).powf(5.0 / 3.0) - 5.0 * x / 6.0 * (1.0 + (1.0 - x).powf(2.0 / 3.0)))
    }
}

/// Mindlin–Deresiewicz oblique loading of a Hertz contact: from the normal force `P0` without
/// shear, the normal force `P` and the tangential force `T` increase together with a constant
/// ratio `dT/dP = k` (Mindlin & Deresiewicz, J. Appl. Mech. 20 (1953) 327–344; Johnson,
/// *Contact Mechanics*, 1985, §7.5). Quasi-identical bodies, SI units (N, m, Pa).
///
/// The shear traction is a superposition of Hertz distributions of the same sphere
/// (`p_P(r)`, the Hertz pressure of the load `P`, radius `a(P)`). Inside its own contact `p_P`
/// as a shear traction displaces the surface by `3P·s/(16a)` plus a quadratic term in `r` whose
/// coefficient `∝ p0/a = 2E*/(πR)` is the same for every load, so a combination whose weights
/// sum to zero displaces the region where all its terms act rigidly (Mindlin 1949; Jäger, J.
/// Tribol. 120 (1998) 677–684):
///
/// - `k ≤ μ`: **no slip**. Every increment `dq = k·dp` is of that kind and `|dq| ≤ μ dp`, so
///   `q = k (p_P − p_P0)` with no slip anywhere, and `δ = (3k·s/16)(P/a − P0/a0)`
///   (`∫ dT / (8a/s)` with the contact radius growing, `∫ dP/a = (3/2) P/a`).
/// - `k > μ`: **slip in an annulus** `c < r < a`: `q = μ (p_P − p_Pc)` with `P_c` from
///   `μ (P − P_c) = T = k (P − P0)`, i.e. `P_c = P − (k/μ)(P − P0)`, the stick radius
///   `c = a(P_c)` shrinking as `P` grows, and `δ = (3μ·s/16)(P/a − P_c/c)` (at `P0 = P`, constant
///   normal load, Cattaneo–Mindlin's [`CattaneoMindlin::displacement`]). Gross slip when
///   `P_c ≤ 0`, i.e. `T ≥ μP`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObliqueLoading {
    /// Sphere radius R (m).
    pub sphere_radius: f64,
    /// Composite modulus E* (Pa).
    pub e_star: f64,
    /// Friction coefficient μ (-).
    pub friction_coefficient: f64,
    /// Tangential compliance sum `s = Σ (2-ν_k)/G_k` (1/Pa).
    pub compliance_sum: f64,
    /// Normal force at the start, without shear, P0 (N).
    pub initial_normal_force: f64,
    /// Ratio of the increments dT/dP = k (-), ≥ 0.
    pub ratio: f64,
}

impl ObliqueLoading {
    /// Tangential force at normal force `P ≥ P0`: `T = k (P − P0)` (N).
    pub fn tangential_force(&self, p: f64) -> f64 {
        self.ratio * (p - self.initial_normal_force)
    }

    fn radius(&self, p: f64) -> f64 {
        Hertz::new(self.sphere_radius, p, self.e_star).radius
    }

    /// The normal force `P_c` whose Hertz contact is the stick zone (N): `P` when `k ≤ μ` (no
    /// slip), `P − (k/μ)(P − P0)` otherwise; ≤ 0 is gross slip.
    pub fn stick_load(&self, p: f64) -> f64 {
        let (k, mu) = (self.ratio, self.friction_coefficient);
        if k <= mu {
            p
        } else {
            p - k / mu * (p - self.initial_normal_force)
        }
    }

    /// Stick radius at normal force `P` (m): `a(P)` when `k ≤ μ`, `a(P_c)` otherwise, 0 at gross
    /// slip.
    pub fn stick_radius(&self, p: f64) -> f64 {
        let pc = self.stick_load(p);
        if pc > 0.0 {
            self.radius(pc)
        } else {
            0.0
        }
    }

    /// Tangential displacement at normal force `P ≥ P0` (m); `None` at gross slip.
    pub fn displacement(&self, p: f64) -> Option<f64> {
        let (k, mu, s) = (self.ratio, self.friction_coefficient, self.compliance_sum);
        let p0 = self.initial_normal_force;
        let (a, a0) = (self.radius(p), self.radius(p0));
        if k <= mu {
            return Some(3.0 * k * s / 16.0 * (p / a - p0 / a0));
        }
        let pc = self.stick_load(p);
        (pc > 0.0).then(|| 3.0 * mu * s / 16.0 * (p / a - pc / self.radius(pc)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn contact_case_of_references_md() {
        // REFERENCES.md: G = 200 N/mm², ν = 0.42, R = 50 mm, Fn = 9.1954 N → a = 1 mm,
        // p0 = 4.390 N/mm², δ = 0.0200 mm. Work in mm and N/mm² (consistent units).
        let (g, nu) = (200.0, 0.42);
        let e = 2.0 * g * (1.0 + nu);
        let e_star = 1.0 / (2.0 * (1.0 - nu * nu) / e);
        let h = Hertz::new(50.0, 9.1954, e_star);
        assert!((h.radius - 1.0).abs() < 1e-3, "{}", h.radius);
        assert!(
            (h.peak_pressure - 4.390).abs() < 2e-3,
            "{}",
            h.peak_pressure
        );
        assert!((h.approach - 0.0200).abs() < 5e-5, "{}", h.approach);
    }

    /// The CONTACT `cattaneo` case of REFERENCES.md in mm and N/mm² (consistent units).
    fn contact_case() -> CattaneoMindlin {
        CattaneoMindlin::new(1.0, 9.1954, 0.4, 200.0, 0.42, 200.0, 0.42)
    }

    #[test]
    fn cattaneo_mindlin_reference_values() {
        let cm = contact_case();
        let t = 0.875 * 0.4 * 9.1954;
        // REFERENCES.md: c/a = 0.5 and δt = 8.17e-3 mm.
        assert!((cm.stick_radius(t) - 0.5).abs() < 1e-12);
        assert!(
            (cm.displacement(t) - 8.17e-3).abs() < 0.01e-3,
            "{}",
            cm.displacement(t)
        );
        // REFERENCES.md check value: W = 1.1022e-2 N·mm at x = 0.875.
        let w = cm.energy_per_cycle(t);
        assert!((w / 1.1022e-2 - 1.0).abs() < 1e-4, "{w}");
    }

    #[test]
    fn energy_equals_area_of_the_masing_loop() {
        // Integrate the loop built from δ(T) numerically: W = ∮ T dδ.
        let cm = contact_case();
        for x in [0.25, 0.5, 0.875] {
            let ts = x * 0.4 * 9.1954;
            let n = 20000;
            let mut w = 0.0;
            for k in 0..n {
                // Unloading branch T* → −T*; the reloading branch contributes the same by symmetry.
                let t0 = ts - 2.0 * ts * k as f64 / n as f64;
                let t1 = ts - 2.0 * ts * (k + 1) as f64 / n as f64;
                let d0 = cm.unloading_displacement(ts, t0);
                let d1 = cm.unloading_displacement(ts, t1);
                w += 0.5 * (t0 + t1) * (d1 - d0);
            }
            // The reloading branch is the point reflection of the unloading one and adds the
            // same ∫T dδ: ∮ T dδ = 2w.
            let w = 2.0 * w;
            let want = cm.energy_per_cycle(ts);
            assert!((w / want - 1.0).abs() < 1e-5, "x={x}: {w} vs {want}");
        }
        // Small-load limit of the compliance: δ ≈ T·s/(8a).
        let t = 1e-6;
        assert!((cm.displacement(t) * cm.initial_stiffness() / t - 1.0).abs() < 1e-5);
    }

    /// Oblique loading: the two regimes meet at `k = μ`; for `k > μ` the displacement is
    /// Cattaneo–Mindlin's at the same `T/(μP)` when `P0 → P` is written as the same stick load
    /// (`P_c/P = 1 − T/(μP)`), and gross slip comes at `T = μP`.
    #[test]
    fn oblique_loading_regimes() {
        let (r, e_star, mu, s) = (0.05, 1e9, 0.4, 1e-8);
        let ob = |k: f64| ObliqueLoading {
            sphere_radius: r,
            e_star,
            friction_coefficient: mu,
            compliance_sum: s,
            initial_normal_force: 5.0,
            ratio: k,
        };
        let p = 7.0;
        let below = ob(mu).displacement(p).unwrap();
        let above = ob(mu * (1.0 + 1e-9)).displacement(p).unwrap();
        assert!((below / above - 1.0).abs() < 1e-6, "{below} {above}");
        // k > μ: δ equals Cattaneo–Mindlin's at (P, T) (the stick zone is a Hertz contact of
        // P_c = P(1 − T/μP) in both).
        let o = ob(2.0 * mu);
        let t = o.tangential_force(p);
        let a = Hertz::new(r, p, e_star).radius;
        let cm = CattaneoMindlin {
            contact_radius: a,
            normal_force: p,
            friction_coefficient: mu,
            compliance_sum: s,
        };
        let d = o.displacement(p).unwrap();
        assert!((d / cm.displacement(t) - 1.0).abs() < 1e-12);
        assert!((o.stick_radius(p) - cm.stick_radius(t)).abs() < 1e-12 * a);
        // Gross slip: T = 2μ(P − 5) ≥ μP from P = 10.
        assert!(o.displacement(10.0 + 1e-9).is_none());
        // No slip below μ: the stick zone is the whole contact.
        assert_eq!(ob(0.5 * mu).stick_radius(p), a);
    }
}
