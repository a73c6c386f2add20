//! The model under test: a Valanis microslip element (the baseline) extended by candidate
//! effects, each with few parameters and a physical meaning.
//!
//! The element is driven by the measured displacement `x(t)` through an optional link, and its
//! friction capacity (the normal load `Fz` of the Valanis law, `crate::element::valanis`) is
//! modulated by the capacity effects:
//!
//! ```text
//! Fz(t)   = N̄ · c_v(t) · c_d(t) · c_N(t) · c_s(t)          capacity effects
//! F_v     = Valanis(y(t), Fz(t))  with  F_v(y) = L(x − y)   link: series spring and clearance
//! F(t)    = F_v + c·ẋ                                        viscous damping
//! ```
//!
//! | effect | law | parameters |
//! |---|---|---|
//! | macroslip slope (hardening / wear) | Valanis `Et` (force asymptote `Et·q ± μFz`) | `Et` (N/m) |
//! | velocity-dependent friction | `c_v = 1 + a·exp(−|ẋ|/v_s)` (static → dynamic decay, Stribeck-type; Armstrong-Hélouvry 1994) | `a`, `v_s` (m/s) |
//! | viscous damping | `F += c·ẋ` | `c` (N·s/m) |
//! | clearance / backlash at reversal | link `L(u) = k_link·(u − g·sign u)` for `|u| > g`, else 0, with a rigid link (`k_link = 10³·E0`) | `g` (m) |
//! | series compliance (rig flexibility) | link `L(u) = k_s·u` | `k_s` (N/m) |
//! | normal load varying over the cycle | `c_N = N(t)/N̄` measured, or `1 + a₁cos θ + b₁ sin θ`, θ = 2π t/T | none, or `a₁`, `b₁` |
//! | direction-dependent friction | `c_d = 1 + d·sign(ẋ)` | `d` |
//! | static friction peak (breakaway) | `c_s = 1 + a·exp(−s/s₀)`, `s` = element travel since its last reversal (a slip-distance decay from static to dynamic friction, as in rate-and-state friction's characteristic slip distance; Dieterich 1979) | `a`, `s₀` (m) |
//!
//! # Physical bounds
//!
//! Every parameter is fitted inside bounds (see [`ParamSpec`]) scaled by the record: `F̂` the
//! force amplitude (N), `Â` the displacement amplitude (m), `v̂` the drive speed (99th
//! percentile, m/s). The lower bound of a scale parameter is where the effect is negligible
//! (it switches the effect off); the upper bound is the largest value that still describes the
//! physical effect and not another one. A candidate whose fitted parameter sits on a bound
//! (within 0.2 % of its interval) is reported as such and is not accepted: the data then ask
//! for something the effect cannot physically be.
//!
//! | parameter | lower | upper | why the upper bound |
//! |---|---|---|---|
//! | `Et` (N/m) | `10⁻⁴ F̂/Â` | `F̂/Â` | hardening larger than the loop's secant stiffness would double the force over the stroke: not a slope of macroslip |
//! | `a` (velocity) | `10⁻³` | `2` | static friction up to 3× dynamic (the range reported for metal pairs, Armstrong-Hélouvry 1994) |
//! | `v_s` (m/s) | `10⁻³ v̂` | `v̂` | a decay velocity above the largest drive speed is a constant factor, i.e. the slip force |
//! | `c` (N·s/m) | `10⁻⁴ F̂/v̂` | `F̂/v̂` | a viscous force larger than the force amplitude is not a friction damper's loop |
//! | `g` (m) | `10⁻⁴ Â` | `Â/2` | a free play of the whole stroke would leave no contact |
//! | `k_s` (N/m) | `F̂/Â` | `10⁴ F̂/Â` | (lower) a spring softer than the loop's secant would prevent slip within the stroke; (upper) indistinguishable from rigid: the effect is off |
//! | `a₁`, `b₁` | `−0.5` | `0.5` | a normal load varying by more than ±50 % (together clamped at ≥ 5 % of N̄) is loss of contact, not a variation |
//! | `d` | `−0.5` | `0.5` | friction differing by more than 3:1 between directions is a different mechanism per direction |
//! | `a` (static peak) | `10⁻³` | `2` | as for `a` (velocity) |
//! | `s₀` (m) | `10⁻³ Â` | `Â` | a decay distance beyond the stroke never reaches dynamic friction: the slip force |
//!
//! The fitted baseline (`select`) is bounded likewise: `E0 ∈ [F̂/(2Â), 10⁴ F̂/Â]` (log),
//! `k ∈ [0, 0.98]`, slip force `∈ [0.2 F̂, 5 F̂]` (log).
//!
//! The link equation `F_v(y) − L(x − y) = 0` is solved per time step for the element
//! displacement `y` by a bracketed Illinois (regula falsi) iteration; both sides are monotone in
//! `y`, so the root is unique.
//!
//! **Time integration.** The element is advanced by the exact branch solution at the step's
//! capacity ([`crate::element::valanis::frozen_load_step`]), not by implicit Euler. A measured
//! force is the response of a continuous system; implicit Euler at the analysed sampling (a few
//! hundred samples per cycle, so a drive increment of a fair fraction of the stick range
//! `μN/E0`) lags the exact loop by O(Δx). That lag is systematic, odd in the direction of motion
//! and concentrated after reversals, and a selection then "explains" it with viscous damping or
//! a static friction peak: with an exactly calibrated baseline and no effect in the data it gave
//! false positives (ΔBIC −11 to −18 at 400 and 1024 samples per cycle; −82 on an earlier record).
//! With the exact step the calibrated baseline's residual is at the noise (tested in
//! `tests/diagnose_independent.rs`).

use crate::element::valanis::{frozen_load_step, ValanisParams, ValanisState};
use serde::Serialize;

/// Stiffness of a "rigid" clearance link relative to the element's `E0`.
pub const RIGID_LINK_FACTOR: f64 = 1e3;

/// Candidate effects (model extensions beyond the baseline element).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Effect {
    /// Valanis residual stiffness `Et` (N/m): a slope of macroslip (hardening or wear).
    MacroslipSlope,
    /// Capacity factor `1 + a·exp(−|ẋ|/v_s)` (Armstrong-Hélouvry 1994); parameters `a`, `v_s` (m/s).
    VelocityDependentFriction,
    /// Viscous force `c·ẋ` added; parameter `c` (N·s/m).
    ViscousDamping,
    /// Rigid link with a clearance `g` (m) at reversal.
    Backlash,
    /// Series spring `k_s` (N/m) between drive and element (rig flexibility).
    SeriesCompliance,
    /// Normal load varying over the cycle: measured `N(t)/N̄`, or `1 + a₁cos θ + b₁ sin θ`.
    NormalLoadVariation,
    /// Capacity factor `1 + d·sign(ẋ)`; parameter `d`.
    DirectionalFriction,
    /// Capacity factor `1 + a·exp(−s/s₀)` over the travel `s` since the last reversal (Dieterich
    /// 1979); parameters `a`, `s₀` (m).
    StaticFrictionPeak,
}

impl Effect {
    /// Every candidate, in the order they are tested.
    pub const ALL: [Effect; 8] = [
        Effect::MacroslipSlope,
        Effect::VelocityDependentFriction,
        Effect::ViscousDamping,
        Effect::Backlash,
        Effect::SeriesCompliance,
        Effect::NormalLoadVariation,
        Effect::DirectionalFriction,
        Effect::StaticFrictionPeak,
    ];

    /// Identifier used in reports and JSON.
    pub fn id(self) -> &'static str {
        match self {
            Effect::MacroslipSlope => "macroslip_slope",
            Effect::VelocityDependentFriction => "velocity_dependent_friction",
            Effect::ViscousDamping => "viscous_damping",
            Effect::Backlash => "backlash",
            Effect::SeriesCompliance => "series_compliance",
            Effect::NormalLoadVariation => "normal_load_variation",
            Effect::DirectionalFriction => "directional_friction",
            Effect::StaticFrictionPeak => "static_friction_peak",
        }
    }

    /// One-line physical meaning.
    pub fn meaning(self) -> &'static str {
        match self {
            Effect::MacroslipSlope => {
                "force keeps rising in macroslip (hardening, fretting wear): Valanis Et"
            }
            Effect::VelocityDependentFriction => {
                "friction decays from static to dynamic with slip velocity"
            }
            Effect::ViscousDamping => "force proportional to velocity (viscous damping)",
            Effect::Backlash => {
                "clearance in the load path: force drops to zero over a gap at each reversal"
            }
            Effect::SeriesCompliance => {
                "a spring in series (rig flexibility) lowers the apparent stick stiffness"
            }
            Effect::NormalLoadVariation => "the normal load varies over the cycle",
            Effect::DirectionalFriction => "friction differs between the two sliding directions",
            Effect::StaticFrictionPeak => {
                "friction peaks at breakaway after each stick and decays to dynamic over a slip distance"
            }
        }
    }

    /// Parameters of the effect for a given drive, each with its physical bounds (see the
    /// module table; normal-load variation has none when the normal force is measured).
    ///
    /// Scales: `F̂` the force amplitude (N), `Â` the displacement amplitude (m), `v̂` the 99th
    /// percentile of the drive speed (m/s), so `F̂/Â` is the secant stiffness of the loop.
    pub fn params(self, drive: &Drive) -> Vec<ParamSpec> {
        let (f, a, v) = (drive.force_scale_n, drive.amplitude_m, drive.velocity_scale);
        let stiff = f / a;
        match self {
            Effect::MacroslipSlope => {
                vec![log_param("et", "N/m", 1e-4 * stiff, stiff, 0.05 * stiff)]
            }
            Effect::VelocityDependentFriction => vec![
                log_param("static_excess", "-", 1e-3, 2.0, 0.1),
                log_param("decay_velocity", "m/s", 1e-3 * v, v, 0.2 * v),
            ],
            Effect::ViscousDamping => vec![log_param(
                "damping",
                "N*s/m",
                1e-4 * f / v,
                f / v,
                0.02 * f / v,
            )],
            Effect::Backlash => vec![log_param("gap", "m", 1e-4 * a, 0.5 * a, 0.005 * a)],
            Effect::SeriesCompliance => {
                vec![log_param(
                    "series_stiffness",
                    "N/m",
                    stiff,
                    1e4 * stiff,
                    200.0 * stiff,
                )]
            }
            Effect::NormalLoadVariation => {
                if drive.normal_ratio.is_some() {
                    vec![]
                } else {
                    vec![
                        linear_param("normal_cos_amplitude", "-", -0.5, 0.5, 0.0),
                        linear_param("normal_sin_amplitude", "-", -0.5, 0.5, 0.0),
                    ]
                }
            }
            Effect::StaticFrictionPeak => vec![
                log_param("static_excess", "-", 1e-3, 2.0, 0.1),
                log_param("decay_slip_distance", "m", 1e-3 * a, a, 0.05 * a),
            ],
            Effect::DirectionalFriction => {
                vec![linear_param("direction_asymmetry", "-", -0.5, 0.5, 0.0)]
            }
        }
    }
}

pub use crate::core::fit::{Bound, ParamSpec};

/// A parameter within this fraction of its (linear or logarithmic) interval from a bound is
/// reported as sitting on that bound.
pub const AT_BOUND_FRACTION: f64 = 2e-3;

/// A scale parameter bounded in `[lower, upper]` (both > 0), spanned logarithmically, on the
/// MINUIT coordinate: the optimiser works on an unconstrained `z` and the fraction of the
/// interval is `u = (sin z + 1)/2` (James & Roos 1975), so every trial value is inside the bounds
/// and the sensitivity does not vanish near them as with logistic maps
/// ([`crate::core::fit::Coordinate::Sine`]).
pub fn log_param(
    name: &'static str,
    unit: &'static str,
    lower: f64,
    upper: f64,
    start: f64,
) -> ParamSpec {
    ParamSpec::log(name, unit, lower, upper, start).on_sine()
}

/// A parameter bounded in `[lower, upper]`, spanned linearly, on the MINUIT coordinate.
pub fn linear_param(
    name: &'static str,
    unit: &'static str,
    lower: f64,
    upper: f64,
    start: f64,
) -> ParamSpec {
    ParamSpec::linear(name, unit, lower, upper, start).on_sine()
}

/// The bound a value of `p` sits on (within [`AT_BOUND_FRACTION`] of the interval), if any.
pub fn at_bound(p: &ParamSpec, value: f64) -> Option<Bound> {
    p.bound_at(value, AT_BOUND_FRACTION)
}

/// The inputs of a simulation, derived once from a record.
#[derive(Debug, Clone)]
pub struct Drive {
    /// Sample times (s).
    pub time_s: Vec<f64>,
    /// Drive displacement relative to the centre of its range (m).
    pub q_m: Vec<f64>,
    /// Smoothed drive velocity (m/s).
    pub velocity_m_per_s: Vec<f64>,
    /// Measured normal force over its mean, when measured.
    pub normal_ratio: Option<Vec<f64>>,
    /// Drive phase θ = 2π t / T (rad).
    pub phase_rad: Vec<f64>,
    /// Measured force at the first sample (N): the element's initial state.
    pub initial_force_n: f64,
    /// Force amplitude `F̂` (N), half the 0.5–99.5 % range of the measured force: with
    /// `amplitude_m` and `velocity_scale`, the scales that make parameters dimensionless.
    pub force_scale_n: f64,
    /// Displacement amplitude `Â` (m).
    pub amplitude_m: f64,
    /// Drive speed scale `v̂`, the 99th percentile of `|ẋ|` (m/s).
    pub velocity_scale: f64,
}

/// Parameters of the baseline Valanis element, in per-element units (N/m, N).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Baseline {
    /// Valanis parameters: `e0`, `et` in N/m, `k` and `mu` dimensionless.
    pub valanis: ValanisParams,
    /// Mean normal load `N̄` (N); the slip force is `μ·N̄`.
    pub normal_n: f64,
}

impl Baseline {
    /// Slip force `μ·N̄` (N).
    pub fn slip_force_n(&self) -> f64 {
        self.valanis.mu * self.normal_n
    }
}

/// A baseline plus a set of effects with their physical parameter values.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Model {
    /// The baseline Valanis element.
    pub baseline: Baseline,
    /// Effects added, each with its parameter values in physical units (order and units of
    /// [`Effect::params`]).
    pub effects: Vec<(Effect, Vec<f64>)>,
}

impl Model {
    fn effect(&self, e: Effect) -> Option<&[f64]> {
        self.effects
            .iter()
            .find(|(k, _)| *k == e)
            .map(|(_, v)| v.as_slice())
    }

    /// Capacity factor `c_v·c_d·c_N` at sample `i`.
    fn capacity(&self, drive: &Drive, i: usize) -> f64 {
        let v = drive.velocity_m_per_s[i];
        let mut c = 1.0;
        if let Some(p) = self.effect(Effect::VelocityDependentFriction) {
            c *= 1.0 + p[0] * (-v.abs() / p[1]).exp();
        }
        if let Some(p) = self.effect(Effect::DirectionalFriction) {
            c *= 1.0 + p[0] * v.signum() * f64::from(u8::from(v != 0.0));
        }
        if let Some(p) = self.effect(Effect::NormalLoadVariation) {
            c *= match (&drive.normal_ratio, p) {
                (Some(r), _) => r[i],
                (None, [a, b]) => {
                    let th = drive.phase_rad[i];
                    (1.0 + a * th.cos() + b * th.sin()).max(0.05)
                }
                _ => 1.0,
            };
        }
        c
    }

    /// Simulated tangential force (N) for the drive. A model with a non-finite or invalid
    /// parameter (an optimiser's trial point) returns NaN forces.
    pub fn simulate(&self, drive: &Drive) -> Vec<f64> {
        let n = drive.q_m.len();
        let finite = self
            .effects
            .iter()
            .all(|(_, v)| v.iter().all(|x| x.is_finite()))
            && self.baseline.valanis.validate().is_ok()
            && self.baseline.normal_n > 0.0;
        if !finite {
            return vec![f64::NAN; n];
        }
        let mut p = self.baseline.valanis;
        if let Some(s) = self.effect(Effect::MacroslipSlope) {
            p.et = (p.et + s[0]).min(0.9 * p.e0);
        }
        let gap = self.effect(Effect::Backlash).map_or(0.0, |g| g[0]);
        let link_k = match self.effect(Effect::SeriesCompliance) {
            Some(k) => Some(k[0]),
            None if gap > 0.0 => Some(RIGID_LINK_FACTOR * p.e0),
            None => None,
        };
        let damping = self.effect(Effect::ViscousDamping).map_or(0.0, |c| c[0]);
        // Static friction peak: capacity × (1 + a·exp(−s/s₀)), s = element travel since its
        // last reversal of motion (evaluated at the start of each step).
        let peak = self
            .effect(Effect::StaticFrictionPeak)
            .map(|v| (v[0], v[1]));
        let breakaway = |s: f64| peak.map_or(1.0, |(a, s0)| 1.0 + a * (-s / s0).exp());
        let fz0 = self.baseline.normal_n * self.capacity(drive, 0) * breakaway(0.0);
        let limit0 = p.slip_limit(fz0);
        let mut state = ValanisState {
            force: drive.initial_force_n.clamp(-limit0, limit0),
            q: drive.q_m[0],
            fz: fz0,
            q_ref: 0.0,
        };
        if let Some(k) = link_k {
            // Start with the link carrying the element force.
            state.q = drive.q_m[0] - inverse_link(state.force, k, gap);
        }
        let mut out = Vec::with_capacity(n);
        out.push(state.force + damping * drive.velocity_m_per_s[0]);
        let (mut y_rev, mut dir) = (state.q, 0.0_f64);
        for i in 1..n {
            let fz = self.baseline.normal_n
                * self.capacity(drive, i)
                * breakaway((state.q - y_rev).abs());
            let q = drive.q_m[i];
            let y_prev = state.q;
            state = match link_k {
                None => frozen_load_step(&p, &state, q, fz),
                Some(k) => link_step(&p, &state, q, fz, k, gap),
            };
            let dy = state.q - y_prev;
            if dy != 0.0 && dy.signum() != dir {
                y_rev = y_prev;
                dir = dy.signum();
            }
            out.push(state.force + damping * drive.velocity_m_per_s[i]);
        }
        out
    }
}

/// Link force `L(u) = k·(u − g·sign u)` for `|u| > g`, else 0.
pub fn link_force(u: f64, k: f64, gap: f64) -> f64 {
    if u > gap {
        k * (u - gap)
    } else if u < -gap {
        k * (u + gap)
    } else {
        0.0
    }
}

/// Link elongation carrying force `f` (the contact side chosen by the sign of `f`).
fn inverse_link(f: f64, k: f64, gap: f64) -> f64 {
    f / k + gap * f.signum()
}

/// Drive displacement at which the link carries the element's current force (the previous
/// step's drive position, to within its solver tolerance).
fn q_previous(state: &ValanisState, _fz: f64, k: f64, gap: f64) -> f64 {
    state.q + inverse_link(state.force, k, gap)
}

/// Advance the element behind a link to drive displacement `q`: find `y` with
/// `F_v(y) = L(q − y)` by bracketed Illinois iteration.
fn link_step(
    p: &ValanisParams,
    state: &ValanisState,
    q: f64,
    fz: f64,
    k: f64,
    gap: f64,
) -> ValanisState {
    let h = |y: f64| -> (f64, ValanisState) {
        let s = frozen_load_step(p, state, y, fz);
        (s.force - link_force(q - y, k, gap), s)
    };
    let bound = state.force.abs() + p.slip_limit(fz) + p.et * (state.q.abs() + q.abs() + gap);
    let width = gap + 1.1 * bound / k + 1e-15;
    // The previous step left F_v(y₀) = L(q₀ − y₀); for a drive increment Δq the root lies between
    // "the element stays" (y₀) and "the element follows the drive" (y₀ + Δq). Try that narrow
    // bracket (widened by a margin for the previous step's tolerance) before the wide one.
    let (y0, dq) = (state.q, q - q_previous(state, fz, k, gap));
    let margin = 1e-3 * dq.abs() + 1e-12 * width;
    let (mut a, mut b) = (y0.min(y0 + dq) - margin, y0.max(y0 + dq) + margin);
    let (mut ha, _) = h(a);
    let (mut hb, _) = h(b);
    if !(ha <= 0.0 && hb >= 0.0) {
        (a, b) = (q - width, q + width);
        ha = h(a).0;
        hb = h(b).0;
    }
    let mut grow = 0;
    while ha > 0.0 && grow < 60 {
        a -= 2.0 * (b - a);
        ha = h(a).0;
        grow += 1;
    }
    while hb < 0.0 && grow < 120 {
        b += 2.0 * (b - a);
        hb = h(b).0;
        grow += 1;
    }
    let tol = 1e-9 * (p.slip_limit(fz) + state.force.abs() + 1e-30);
    let mut side = 0i8;
    let mut best = h(0.5 * (a + b));
    for _ in 0..100 {
        let y = if hb != ha {
            (a * hb - b * ha) / (hb - ha)
        } else {
            0.5 * (a + b)
        };
        let y = if y > a && y < b { y } else { 0.5 * (a + b) };
        best = h(y);
        let hy = best.0;
        if hy.abs() <= tol || (b - a) <= 1e-14 * (q.abs() + width) {
            break;
        }
        if hy < 0.0 {
            a = y;
            ha = hy;
            if side == -1 {
                hb *= 0.5;
            }
            side = -1;
        } else {
            b = y;
            hb = hy;
            if side == 1 {
                ha *= 0.5;
            }
            side = 1;
        }
    }
    best.1
}

#[cfg(test)]
mod tests {
    use super::*;

    fn drive(n_cycles: f64, per_cycle: usize) -> Drive {
        let n = (n_cycles * per_cycle as f64) as usize;
        let t: Vec<f64> = (0..n).map(|i| i as f64 / per_cycle as f64).collect();
        let tau = std::f64::consts::TAU;
        let q: Vec<f64> = t.iter().map(|&t| 1e-3 * (tau * t).sin()).collect();
        let v: Vec<f64> = t.iter().map(|&t| 1e-3 * tau * (tau * t).cos()).collect();
        Drive {
            phase_rad: t.iter().map(|&t| tau * t).collect(),
            time_s: t,
            q_m: q,
            velocity_m_per_s: v,
            normal_ratio: None,
            initial_force_n: 0.0,
            force_scale_n: 100.0,
            amplitude_m: 1e-3,
            velocity_scale: 1e-3 * tau,
        }
    }

    fn baseline() -> Baseline {
        Baseline {
            valanis: ValanisParams::new(1e6, 0.3, 0.0, 1.0).unwrap(),
            normal_n: 100.0,
        }
    }

    #[test]
    fn baseline_saturates_at_the_slip_force() {
        let d = drive(2.0, 2000);
        let f = Model {
            baseline: baseline(),
            effects: vec![],
        }
        .simulate(&d);
        let max = f.iter().cloned().fold(f64::MIN, f64::max);
        assert!((max - 100.0).abs() < 1.0, "{max}");
    }

    #[test]
    fn series_spring_halves_the_stick_stiffness() {
        // Valanis E0 = 1e6 N/m in series with k_s = 1e6 N/m: initial slope 5e5 N/m.
        let d = drive(0.3, 4000);
        let m = Model {
            baseline: baseline(),
            effects: vec![(Effect::SeriesCompliance, vec![1e6])],
        };
        let f = m.simulate(&d);
        let i = 10;
        let slope = (f[i] - f[0]) / (d.q_m[i] - d.q_m[0]);
        assert!((slope / 5e5 - 1.0).abs() < 0.02, "{slope}");
    }

    #[test]
    fn backlash_holds_zero_force_across_the_gap() {
        let d = drive(1.5, 4000);
        let gap = 1e-4;
        let m = Model {
            baseline: baseline(),
            effects: vec![(Effect::Backlash, vec![gap])],
        };
        let f = m.simulate(&d);
        // After the first reversal (t = 0.25) the force falls to ~0 and stays there while the
        // drive travels about 2·gap back.
        let near_zero: Vec<f64> = (1000..3000)
            .filter(|&i| f[i].abs() < 1e-3 * 100.0)
            .map(|i| d.q_m[i])
            .collect();
        let span = near_zero.iter().cloned().fold(f64::MIN, f64::max)
            - near_zero.iter().cloned().fold(f64::MAX, f64::min);
        assert!((span / (2.0 * gap) - 1.0).abs() < 0.05, "{span}");
    }

    #[test]
    fn viscous_and_direction_effects_shift_the_force() {
        let d = drive(2.0, 2000);
        let plain = Model {
            baseline: baseline(),
            effects: vec![],
        }
        .simulate(&d);
        let dir = Model {
            baseline: baseline(),
            effects: vec![(Effect::DirectionalFriction, vec![0.2])],
        }
        .simulate(&d);
        let max = dir.iter().cloned().fold(f64::MIN, f64::max);
        let min = dir.iter().cloned().fold(f64::MAX, f64::min);
        assert!(
            (max - 120.0).abs() < 1.5 && (min + 80.0).abs() < 1.5,
            "{max} {min}"
        );
        let visc = Model {
            baseline: baseline(),
            effects: vec![(Effect::ViscousDamping, vec![1000.0])],
        }
        .simulate(&d);
        let i = 2000; // t = 1, velocity maximum
        assert!((visc[i] - plain[i] - 1000.0 * d.velocity_m_per_s[i]).abs() < 1e-9);
    }

    #[test]
    fn transforms_round_trip_and_stay_in_bounds() {
        for s in [
            log_param("a", "-", 1e-3, 2.0, 0.1),
            linear_param("b", "-", -0.5, 0.5, 0.0),
        ] {
            let z = 0.37;
            assert!((s.coordinate_of(s.value(z)) - z).abs() < 1e-9);
            assert!((s.value(s.start_coordinate()) - s.start).abs() < 1e-12);
            for z in [-40.0, -1.0, 0.0, 3.0, 1e3] {
                let v = s.value(z);
                assert!(v >= s.lo && v <= s.hi, "{v}");
            }
            assert_eq!(at_bound(&s, s.lo), Some(Bound::Lower));
            assert_eq!(at_bound(&s, s.hi), Some(Bound::Upper));
            assert_eq!(at_bound(&s, s.start), None);
        }
    }
}
