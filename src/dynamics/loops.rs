//! Per-element hysteresis loops of a solution point: every element's force against its relative
//! displacement and against its relative acceleration over one period, the loops the lap-joint
//! study plots (force–acceleration loops are what an accelerometer-instrumented joint shows).
//!
//! The displacement and force samples are the AFT's own (the periodic cycle at the solution's
//! harmonics, [`crate::dynamics::aft::cycle_samples`]); the acceleration is the second derivative
//! of the displacement's harmonics, `−(kω)²·(c_k, s_k)`, at the same instants `t_i = i·T/N`.
//! Components are in the element's order (3-D contact elements: tangential 1, tangential 2,
//! normal approach).

use crate::core::error::{Error, Result};
use crate::core::plot::{line_plot, LinePlot, Scale, Series};
use crate::dynamics::hbm::{HbmPoint, HbmSystem};
use std::path::Path;

/// One element's loop at a solution point.
#[derive(Debug, Clone, PartialEq)]
pub struct ElementLoop {
    /// The element's label.
    pub label: String,
    /// Its law.
    pub law: &'static str,
    /// Components of the element.
    pub dofs: usize,
    /// Relative displacement, `dofs × N` component-major (m).
    pub displacement_m: Vec<f64>,
    /// Relative acceleration, `dofs × N` (m/s²).
    pub acceleration_m_per_s2: Vec<f64>,
    /// Element force, `dofs × N` (N).
    pub force_n: Vec<f64>,
    /// Energy dissipated per cycle, `∮f·du` over the samples (J).
    pub dissipated_energy_j: f64,
}

/// The loops of every element at `point`.
pub fn element_loops(system: &HbmSystem<'_>, point: &HbmPoint) -> Vec<ElementLoop> {
    let h = &system.harmonics;
    let (n, len) = (h.n_time(), h.len());
    let samples = system.element_samples(point);
    let us = system.element_displacement_harmonics(point);
    system
        .structure
        .elements
        .iter()
        .zip(samples)
        .zip(us)
        .map(|((e, s), u)| {
            let d = e.element.dofs();
            let mut acc = vec![0.0; d * n];
            let mut coeffs = vec![0.0; len];
            for c in 0..d {
                let mut i = 0;
                for &k in h.orders() {
                    let w2 = (k as f64 * point.omega).powi(2);
                    if k == 0 {
                        coeffs[i] = 0.0;
                        i += 1;
                    } else {
                        coeffs[i] = -w2 * u[c * len + i];
                        coeffs[i + 1] = -w2 * u[c * len + i + 1];
                        i += 2;
                    }
                }
                h.to_time(&coeffs, &mut acc[c * n..(c + 1) * n]);
            }
            let mut energy = 0.0;
            for c in 0..d {
                let (uc, fc) = (&s.u[c * n..(c + 1) * n], &s.f[c * n..(c + 1) * n]);
                for i in 0..n {
                    let i1 = (i + 1) % n;
                    energy += 0.5 * (fc[i] + fc[i1]) * (uc[i1] - uc[i]);
                }
            }
            ElementLoop {
                label: e.label.clone(),
                law: e.element.name(),
                dofs: d,
                displacement_m: s.u,
                acceleration_m_per_s2: acc,
                force_n: s.f,
                dissipated_energy_j: energy,
            }
        })
        .collect()
}

/// Write the loops as CSV: one row per element (its index in the model, as labels may repeat
/// across contact sections), component and sample.
pub fn write_loops_csv(
    path: &Path,
    loops: &[ElementLoop],
    point: &HbmPoint,
    header: &str,
) -> Result<()> {
    let period = std::f64::consts::TAU / point.omega;
    crate::core::output::write_atomic(path, |w| {
        let io = |e: std::io::Error| Error::io(path, e);
        writeln!(
            w,
            "# {header}\n# loops of every element over one period at {:.6} Hz; components in the element's order (3-D contact: tangential 1, tangential 2, normal approach); acceleration = second derivative of the displacement harmonics",
            point.omega / std::f64::consts::TAU
        )
        .map_err(io)?;
        writeln!(
            w,
            "index,element,law,component,sample,time_s,displacement_m,acceleration_m_per_s2,force_N"
        )
        .map_err(io)?;
        for (index, l) in loops.iter().enumerate() {
            let n = l.force_n.len() / l.dofs;
            for c in 0..l.dofs {
                for i in 0..n {
                    let j = c * n + i;
                    writeln!(
                        w,
                        "{index},{},{},{c},{i},{:e},{:e},{:e},{:e}",
                        l.label,
                        l.law,
                        period * i as f64 / n as f64,
                        l.displacement_m[j],
                        l.acceleration_m_per_s2[j],
                        l.force_n[j]
                    )
                    .map_err(io)?;
                }
            }
        }
        Ok(())
    })
}

/// Two plots of the first component of the `top` elements that dissipate most: force against
/// relative displacement (µm) and force against relative acceleration.
pub fn plot_loops(
    displacement_png: &Path,
    acceleration_png: &Path,
    loops: &[ElementLoop],
    top: usize,
    title: &str,
) -> Result<()> {
    let mut order: Vec<usize> = (0..loops.len()).collect();
    order.sort_by(|&a, &b| {
        loops[b]
            .dissipated_energy_j
            .total_cmp(&loops[a].dissipated_energy_j)
    });
    let chosen = &order[..top.min(order.len())];
    let closed = |x: &[f64], y: &[f64], sx: f64| -> Vec<(f64, f64)> {
        let mut v: Vec<(f64, f64)> = x.iter().zip(y).map(|(&a, &b)| (a * sx, b)).collect();
        if let Some(&first) = v.first() {
            v.push(first);
        }
        v
    };
    let series = |acc: bool| -> Vec<Series> {
        chosen
            .iter()
            .enumerate()
            .map(|(i, &k)| {
                let l = &loops[k];
                let n = l.force_n.len() / l.dofs;
                let f = &l.force_n[..n];
                let pts = if acc {
                    closed(&l.acceleration_m_per_s2[..n], f, 1.0)
                } else {
                    closed(&l.displacement_m[..n], f, 1e6)
                };
                Series::line(
                    format!("{} ({:.2e} J)", l.label, l.dissipated_energy_j),
                    pts,
                )
                .with_colour(i)
            })
            .collect()
    };
    line_plot(
        displacement_png,
        &LinePlot {
            title,
            x_label: "relative displacement, component 1 (µm)",
            y_label: "element force, component 1 (N)",
            x_scale: Scale::Linear,
            y_scale: Scale::Linear,
        },
        &series(false),
    )?;
    line_plot(
        acceleration_png,
        &LinePlot {
            title,
            x_label: "relative acceleration, component 1 (m/s²)",
            y_label: "element force, component 1 (N)",
            x_scale: Scale::Linear,
            y_scale: Scale::Linear,
        },
        &series(true),
    )
}
