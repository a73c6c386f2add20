//! `asperity modes` as a library call: the nonlinear mode (EPMC,
//! [`crate::dynamics::nonlinear_modes`]) of a model file of `asperity response`, and its files.
//!
//! The steps, in order:
//!
//! 1. **System**: the model file's structure, elements and harmonic basis (`[sweep]`'s
//!    `harmonics`, `odd_only`, `time_samples`) in the coordinates formulation (the amplitude
//!    condition needs every coordinate's harmonics; the frequency span, points and
//!    `formulation` of `[sweep]` are not used).
//! 2. **Amplitudes**: log-spaced modal amplitudes between the given ends, by default
//!    ([`default_amplitude_range`]) from 1/100 of the linear resonance amplitude of the mode at
//!    the model's lowest excitation level to that at its highest.
//! 3. **Backbone** ([`crate::dynamics::nonlinear_modes::Epmc::backbone`]).
//! 4. **Synthesis**: the forced response of each excitation level predicted from the backbone
//!    as a single nonlinear mode ([`synthesise`]).
//! 5. **Files** ([`ModesRun::write`]): `modes.csv` (per amplitude: frequency, damping ratio,
//!    ξ, energies, the harmonics of every response DOF), `modes_shapes.csv` (the harmonics of
//!    every coordinate), `modes_elements.csv` (energy and contact states per element and
//!    amplitude), `modes_synthesis.csv` (the synthesised forced response per level),
//!    `modes.png` (frequency and damping ratio against amplitude) and `modes.json`
//!    (provenance, settings, summary).

use crate::core::error::{Error, Result};
use crate::core::output::{write_atomic, write_string_atomic, OutputSet};
use crate::core::plot::{stacked_line_plots, LinePlot, Scale, Series};
use crate::dynamics::aft::Harmonics;
use crate::dynamics::hbm::{Excitation, FormulationChoice, HbmSystem};
use crate::dynamics::model_file::{self, LoadedModel};
use crate::dynamics::nonlinear_modes::{self, Epmc, ModeSettings, NonlinearMode};
use crate::elements::{provenance_json, InputFile};
use nalgebra::DVector;
use std::path::Path;

const TWO_PI: f64 = 2.0 * std::f64::consts::PI;

/// The files of `asperity modes`.
pub const FILES: [&str; 6] = [
    "modes.csv",
    "modes_shapes.csv",
    "modes_elements.csv",
    "modes_synthesis.csv",
    "modes.png",
    "modes.json",
];

/// The output set of a run of the model file `model` into `out_dir` (`flag` names it in
/// errors), declared before any work; the model file and every file it names are inputs.
pub fn output_set(model: &Path, out_dir: &Path, flag: &str) -> Result<OutputSet> {
    let mut out = OutputSet::in_dir(out_dir, flag)?;
    out.writes(&FILES)?;
    model_file::declare_inputs(&mut out, model)?;
    Ok(out)
}

/// What to compute: the linear mode to continue and the amplitudes (`None`: the default
/// range); `points` amplitudes, log-spaced.
#[derive(Debug, Clone, PartialEq)]
pub struct ModesRequest {
    /// 1-based index of the underlying linear mode.
    pub mode: usize,
    /// Smallest modal amplitude (m·kg^½).
    pub amplitude_min: Option<f64>,
    /// Largest modal amplitude (m·kg^½).
    pub amplitude_max: Option<f64>,
    /// Amplitudes on the backbone.
    pub points: usize,
}

/// The harmonic-balance system of the model file for the EPMC: its harmonic basis, the
/// coordinates formulation, no excitation.
pub fn system(model: &LoadedModel) -> Result<HbmSystem<'_>> {
    model.refuse_static("asperity modes")?;
    if model.structure.cyclic.is_some() {
        return Err(Error::parse(
            &model.path,
            0,
            "[cyclic]: nonlinear modes of a cyclic sector are not implemented (asperity response \
             solves its forced response)",
        ));
    }
    let sw = &model.file.sweep;
    let harmonics = Harmonics::new(sw.harmonics, sw.odd_only, sw.time_samples)
        .map_err(|e| e.renamed_param("sweep.harmonics / sweep.time_samples"))?;
    HbmSystem::new(
        &model.structure,
        harmonics,
        Excitation {
            force: DVector::zeros(model.structure.n()),
            harmonic: 1,
            force_sin: None,
        },
        FormulationChoice::Coordinates,
    )
}

/// `|φ_cᴴ·F|`: the modal force per newton of excitation, `φ_c = (Q₁ᶜ − i·Q₁ˢ)/a` the complex
/// first-harmonic shape of a backbone point (or of the linear mode), `F` the excitation vector.
fn modal_force(
    z: &DVector<f64>,
    amplitude: f64,
    force: &DVector<f64>,
    len: usize,
    ci: usize,
    si: usize,
) -> f64 {
    let n = force.len();
    let re: f64 = (0..n).map(|r| z[r * len + ci] * force[r]).sum();
    let im: f64 = (0..n).map(|r| z[r * len + si] * force[r]).sum();
    re.hypot(im) / amplitude
}

/// Default amplitude range: from 1/100 of the modal amplitude of the linear mode's resonance
/// at the lowest excitation level, `|φᵀF|·F_min/(2ζω²)`, to that at the highest level (an upper
/// bound of the forced response's when the elements add damping). Errors name `--mode` when
/// the excitation does not drive the mode, `--amplitude-min-m-sqrt-kg` when it is undamped.
pub fn default_amplitude_range(
    model: &LoadedModel,
    linear: &nonlinear_modes::LinearMode,
) -> Result<(f64, f64)> {
    let phi_f: f64 = linear.shape.dot(&model.force).abs();
    let zeta = linear.damping_ratio();
    let levels = &model.file.excitation.levels_n;
    let (lo, hi) = levels
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), &v| (a.min(v), b.max(v)));
    let resonance = |level: f64| phi_f * level / (2.0 * zeta * linear.omega * linear.omega);
    let frequencies: Vec<String> = linear
        .frequencies_hz
        .iter()
        .map(|f| format!("{f:.6}"))
        .collect();
    // The excitation drives the mode when its modal force is more than rounding of φ·F.
    let driven = phi_f > 1e-9 * linear.shape.norm() * model.force.norm();
    if !driven {
        return Err(Error::param(
            "--mode",
            format!(
                "the model's excitation does not drive linear mode {} ({:.6} Hz; modal force {phi_f:.3e} N per N): choose the mode it drives (linear frequencies with the elements stuck: {} Hz) or give --amplitude-min-m-sqrt-kg and --amplitude-max-m-sqrt-kg",
                linear.index,
                linear.frequency_hz(),
                frequencies.join(", ")
            ),
        ));
    }
    if !(zeta > 0.0 && resonance(hi).is_finite()) {
        return Err(Error::param(
            "--amplitude-min-m-sqrt-kg",
            format!(
                "no default amplitude range: linear mode {} is undamped (damping ratio {zeta:.3e}); give --amplitude-min-m-sqrt-kg and --amplitude-max-m-sqrt-kg",
                linear.index
            ),
        ));
    }
    Ok((resonance(lo) / 100.0, resonance(hi)))
}

/// The single-nonlinear-mode synthesis of the forced response at one excitation level: for a
/// backbone point `(a, ω(a), ζ(a), φ(a))` the modal equation
/// `(ω² − Ω² + 2iζωΩ)·a = φ_cᴴF̂` (Krack, *Comput. Struct.* 154 (2015) 59, §5; Szemplińska-
/// Stupnicka's single-mode approximation) has the excitation frequencies
/// `Ω² = ω²(1 − 2ζ²) ± √(r² − 4ζ²ω⁴(1 − ζ²))`, `r = |φ_cᴴF̂|/a`, where the radicand is not
/// negative: two points of the response curve (below and above the backbone) per amplitude up to
/// the peak, which is where the radicand vanishes. One point: `(Ω (rad/s), a, side)`,
/// side −1 below, +1 above the backbone.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SynthesisPoint {
    /// Excitation frequency (rad/s).
    pub omega: f64,
    /// Modal amplitude (m·kg^½).
    pub amplitude: f64,
    /// Index of the backbone point.
    pub point: usize,
    /// −1: below the backbone frequency; +1: above.
    pub side: i8,
}

/// The peak of a synthesised forced response: where `r(a) = 2ζω²√(1 − ζ²)`, interpolated
/// between the backbone points `lower` and `lower + 1` at `fraction` of the step in `ln a`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SynthesisPeak {
    /// Excitation frequency of the peak, `ω√(1 − 2ζ²)` (rad/s).
    pub omega: f64,
    /// Modal amplitude at the peak (m·kg^½).
    pub amplitude: f64,
    /// The backbone point below the peak.
    pub lower: usize,
    /// Position between `lower` and `lower + 1` in `ln a` (0..1).
    pub fraction: f64,
}

impl SynthesisPeak {
    /// First-harmonic amplitude of `row·q` at the peak (m for a physical DOF): the peak's modal
    /// amplitude times the backbone's `|row·Q₁|/a`, interpolated like the peak.
    pub fn response_amplitude(
        &self,
        mode: &NonlinearMode,
        harmonics: &Harmonics,
        row: &DVector<f64>,
    ) -> f64 {
        let len = harmonics.len();
        let (ci, si) = harmonics.index_of(1).expect("first harmonic retained");
        let ratio = |i: usize| {
            let p = &mode.points[i];
            crate::dynamics::hbm::amplitude(&p.z, row, len, ci, si) / p.amplitude
        };
        let (r0, r1) = (ratio(self.lower), ratio(self.lower + 1));
        self.amplitude * (r0 + self.fraction * (r1 - r0))
    }
}

/// The synthesised forced response at excitation level `level` (N) of the force vector `force`
/// (per newton, on the coordinates), one backbone point at a time ([`SynthesisPoint`]), and its
/// peak ([`SynthesisPeak`], where `r(a) − 2ζω²√(1 − ζ²)` changes sign between two backbone
/// points; `None` when the backbone does not reach it).
pub fn synthesise(
    mode: &NonlinearMode,
    harmonics: &Harmonics,
    force: &DVector<f64>,
    level: f64,
) -> (Vec<SynthesisPoint>, Option<SynthesisPeak>) {
    let len = harmonics.len();
    let (ci, si) = harmonics.index_of(1).expect("first harmonic retained");
    let mut below = Vec::new();
    let mut above = Vec::new();
    let mut margins = Vec::new();
    for (i, p) in mode.points.iter().enumerate() {
        let r = level * modal_force(&p.z, p.amplitude, force, len, ci, si) / p.amplitude;
        let (w, z) = (p.omega, p.damping_ratio());
        let peak_r = 2.0 * z * w * w * (1.0 - z * z).max(0.0).sqrt();
        margins.push(r - peak_r);
        let disc = r * r - peak_r * peak_r;
        if disc < 0.0 {
            continue;
        }
        let centre = w * w * (1.0 - 2.0 * z * z);
        for (side, y) in [(-1i8, centre - disc.sqrt()), (1i8, centre + disc.sqrt())] {
            if y > 0.0 {
                let sp = SynthesisPoint {
                    omega: y.sqrt(),
                    amplitude: p.amplitude,
                    point: i,
                    side,
                };
                if side < 0 {
                    below.push(sp);
                } else {
                    above.push(sp);
                }
            }
        }
    }
    // The curve: up the low-frequency side, down the high-frequency side.
    above.reverse();
    let mut curve = below;
    curve.extend(above);
    // The peak: the margin changes sign between consecutive points (linear in ln a).
    let peak = margins.windows(2).enumerate().find_map(|(i, m)| {
        (m[0] >= 0.0 && m[1] < 0.0).then(|| {
            let t = m[0] / (m[0] - m[1]);
            let (p0, p1) = (&mode.points[i], &mode.points[i + 1]);
            let a = (p0.amplitude.ln() + t * (p1.amplitude / p0.amplitude).ln()).exp();
            let lerp = |x0: f64, x1: f64| x0 + t * (x1 - x0);
            let (w, z) = (
                lerp(p0.omega, p1.omega),
                lerp(p0.damping_ratio(), p1.damping_ratio()),
            );
            SynthesisPeak {
                omega: (w * w * (1.0 - 2.0 * z * z)).max(0.0).sqrt(),
                amplitude: a,
                lower: i,
                fraction: t,
            }
        })
    });
    (curve, peak)
}

/// What `asperity modes` computed.
pub struct ModesRun<'a> {
    /// The model file, loaded.
    pub model: &'a LoadedModel,
    /// The EPMC's harmonic-balance system.
    pub system: HbmSystem<'a>,
    /// The settings used (mode, amplitudes, Newton).
    pub settings: ModeSettings,
    /// Whether the amplitudes are the default range.
    pub default_range: bool,
    /// The backbone.
    pub mode: NonlinearMode,
}

/// Compute the nonlinear mode of `model` (steps 1–3 of the [module documentation](self)).
/// `progress(len)` makes the progress bar for the amplitudes; `log` takes the description of
/// the system and of the linear mode.
pub fn run<'a>(
    model: &'a LoadedModel,
    request: &ModesRequest,
    progress: &dyn Fn(u64) -> indicatif::ProgressBar,
    log: &mut dyn FnMut(&str),
) -> Result<ModesRun<'a>> {
    let system = system(model)?;
    let linear = nonlinear_modes::linear_mode(&system, request.mode)
        .map_err(|e| e.renamed_param("--mode"))?;
    let default_range = request.amplitude_min.is_none() || request.amplitude_max.is_none();
    let (lo, hi) = match (request.amplitude_min, request.amplitude_max) {
        (Some(lo), Some(hi)) => (lo, hi),
        (lo, hi) => {
            let (dlo, dhi) = default_amplitude_range(model, &linear)?;
            (lo.unwrap_or(dlo), hi.unwrap_or(dhi))
        }
    };
    let amplitudes = nonlinear_modes::log_spaced(lo, hi, request.points).map_err(|e| match e {
        Error::InvalidParameter { name, message } => Error::param(
            match name.as_str() {
                "amplitude_min" => "--amplitude-min-m-sqrt-kg",
                "amplitude_max" => "--amplitude-max-m-sqrt-kg",
                _ => "--points",
            },
            message,
        ),
        other => other,
    })?;
    let n = model.structure.n();
    log(&format!(
        "{n} coordinates ({:?}), {} elements ({} contact DOFs); harmonics {:?}, {} samples per period; {} unknowns + frequency + self-excitation",
        model.structure.kind,
        model.structure.elements.len(),
        model.structure.contact_dofs(),
        system.harmonics.orders(),
        system.harmonics.n_time(),
        system.unknowns()
    ));
    let freqs: Vec<String> = linear
        .frequencies_hz
        .iter()
        .take(8)
        .map(|f| format!("{f:.4}"))
        .collect();
    log(&format!(
        "linear modes with the elements stuck (Hz): {}{}; mode {}: {:.6} Hz, damping ratio {:.4e}, reference coordinate {}",
        freqs.join(", "),
        if linear.frequencies_hz.len() > 8 { ", …" } else { "" },
        linear.index,
        linear.frequency_hz(),
        linear.damping_ratio(),
        model.structure.labels[linear.reference]
    ));
    log(&format!(
        "{} modal amplitudes from {lo:.4e} to {hi:.4e} m·kg^½{}",
        amplitudes.len(),
        if default_range {
            " (default range: from the linear resonance amplitudes at the model's excitation levels)"
        } else {
            ""
        }
    ));
    let settings = ModeSettings::new(request.mode, amplitudes);
    let epmc = Epmc::new(&system, settings.clone())?;
    let bar = progress(settings.amplitudes.len() as u64);
    bar.set_message(format!("mode {}", request.mode));
    let mode = epmc.backbone(&mut |done| bar.set_position(done as u64))?;
    bar.finish_and_clear();
    drop(epmc);
    Ok(ModesRun {
        model,
        system,
        settings,
        default_range,
        mode,
    })
}

impl ModesRun<'_> {
    /// Write the command's files into `out` (declared by [`output_set`]).
    pub fn write(&self, out: &mut OutputSet) -> Result<()> {
        let (model, system, mode) = (self.model, &self.system, &self.mode);
        let len = system.harmonics.len();
        let header = format!(
            "asperity {} modes: model {}; nonlinear mode {} by the extended periodic motion concept (Krack 2015); harmonics {:?}, {} samples per period; linear mode {:.9e} Hz, damping ratio {:.6e}",
            env!("CARGO_PKG_VERSION"),
            model.path.display(),
            mode.linear.index,
            system.harmonics.orders(),
            system.harmonics.n_time(),
            mode.linear.frequency_hz(),
            mode.linear.damping_ratio()
        );
        let stopped = mode
            .stopped
            .as_ref()
            .map(|w| format!("# INCOMPLETE: the continuation stopped {w}\n"))
            .unwrap_or_default();

        // modes.csv
        let path = out.path("modes.csv")?;
        write_atomic(&path, |w| {
            let io = |e: std::io::Error| Error::io(&path, e);
            writeln!(w, "# {header}").map_err(io)?;
            write!(w, "{stopped}").map_err(io)?;
            writeln!(w, "# units: modal_amplitude_m_sqrt_kg: √(Q1cᵀ·M·Q1c + Q1sᵀ·M·Q1s) of the first harmonic (m·kg^½; for mass-normalised modal coordinates their amplitude); frequency_Hz in Hz; damping_ratio = xi/(2ω); xi_per_s: self-excitation ξ (1/s);").map_err(io)?;
            writeln!(w, "#   energies in J per cycle: element_energy_J (Σ ∮f·du), viscous_energy_J (∮q̇ᵀCq̇), self_excitation_energy_J (ξ∮q̇ᵀMq̇); energy_balance_error = |element − (self_excitation − viscous)|/self_excitation;").map_err(io)?;
            writeln!(w, "#   per response DOF and harmonic k: <dof>_h<k>_amplitude_m (m) and <dof>_h<k>_phase_rad = arg(a − i·b) of a·cos(kωt) + b·sin(kωt) (h0: mean, m); slip/separation: element-averaged fractions of the period").map_err(io)?;
            let mut names = vec![
                "modal_amplitude_m_sqrt_kg".to_string(),
                "frequency_Hz".into(),
                "damping_ratio".into(),
                "xi_per_s".into(),
                "element_energy_J".into(),
                "viscous_energy_J".into(),
                "self_excitation_energy_J".into(),
                "energy_balance_error".into(),
                "slip_fraction".into(),
                "separation_fraction".into(),
            ];
            for (label, _) in &model.responses {
                for &k in system.harmonics.orders() {
                    if k == 0 {
                        names.push(format!("{label}_h0_mean_m"));
                    } else {
                        names.push(format!("{label}_h{k}_amplitude_m"));
                        names.push(format!("{label}_h{k}_phase_rad"));
                    }
                }
            }
            names.extend([
                "newton_iterations".into(),
                "relative_residual".into(),
                "aft_periodicity_error".into(),
            ]);
            writeln!(w, "{}", names.join(",")).map_err(io)?;
            let ne = system.structure.elements.len().max(1) as f64;
            for p in &mode.points {
                let mut v = vec![
                    format!("{:.9e}", p.amplitude),
                    format!("{:.9e}", p.frequency_hz()),
                    format!("{:.9e}", p.damping_ratio()),
                    format!("{:.9e}", p.xi),
                    format!("{:.6e}", p.element_energy_j()),
                    format!("{:.6e}", p.viscous_energy_j),
                    format!("{:.6e}", p.self_excitation_energy_j),
                    format!("{:.3e}", p.energy_balance_error()),
                    format!(
                        "{:.6}",
                        p.elements.iter().map(|c| c.slip_fraction).sum::<f64>() / ne
                    ),
                    format!(
                        "{:.6}",
                        p.elements
                            .iter()
                            .map(|c| c.separation_fraction)
                            .sum::<f64>()
                            / ne
                    ),
                ];
                for (_, row) in &model.responses {
                    for &k in system.harmonics.orders() {
                        let (amp, phase) =
                            crate::dynamics::report::harmonic_of(system, &p.z, row, k);
                        v.push(format!("{amp:.9e}"));
                        if k > 0 {
                            v.push(format!("{phase:.6}"));
                        }
                    }
                }
                v.push(p.iterations.to_string());
                v.push(format!("{:.3e}", p.residual));
                v.push(format!("{:.3e}", p.periodicity_error));
                writeln!(w, "{}", v.join(",")).map_err(io)?;
            }
            Ok(())
        })?;

        // modes_shapes.csv
        let path = out.path("modes_shapes.csv")?;
        write_atomic(&path, |w| {
            let io = |e: std::io::Error| Error::io(&path, e);
            writeln!(w, "# {header}").map_err(io)?;
            write!(w, "{stopped}").map_err(io)?;
            writeln!(w, "# the mode shape's harmonics per modal amplitude: q = Σ_k cos_k·cos(kωt) + sin_k·sin(kωt) (k = 0: the mean); units: m for physical DOFs, m·kg^½ for modal coordinates; the first-harmonic sine of the reference coordinate ({}) is zero (phase normalisation)", system.structure.labels[mode.linear.reference]).map_err(io)?;
            writeln!(w, "modal_amplitude_m_sqrt_kg,coordinate,harmonic,cos,sin").map_err(io)?;
            for p in &mode.points {
                for (r, label) in system.structure.labels.iter().enumerate() {
                    let mut c = 0;
                    for &k in system.harmonics.orders() {
                        let (a, b) = if k == 0 {
                            (p.z[r * len + c], 0.0)
                        } else {
                            (p.z[r * len + c], p.z[r * len + c + 1])
                        };
                        writeln!(w, "{:.9e},{label},{k},{a:.9e},{b:.9e}", p.amplitude)
                            .map_err(io)?;
                        c += if k == 0 { 1 } else { 2 };
                    }
                }
            }
            Ok(())
        })?;

        // modes_elements.csv
        let path = out.path("modes_elements.csv")?;
        write_atomic(&path, |w| {
            let io = |e: std::io::Error| Error::io(&path, e);
            writeln!(w, "# {header}").map_err(io)?;
            write!(w, "{stopped}").map_err(io)?;
            writeln!(w, "# units: dissipated_energy_J in J per cycle (∮f·du of the element); fractions of the period").map_err(io)?;
            writeln!(w, "modal_amplitude_m_sqrt_kg,element,law,dissipated_energy_J,stick_fraction,slip_fraction,separation_fraction").map_err(io)?;
            for p in &mode.points {
                for (e, c) in system.structure.elements.iter().zip(&p.elements) {
                    writeln!(
                        w,
                        "{:.9e},{},{},{:.6e},{:.6},{:.6},{:.6}",
                        p.amplitude,
                        e.label,
                        e.element.name(),
                        c.dissipated_energy_j,
                        c.stick_fraction,
                        c.slip_fraction,
                        c.separation_fraction
                    )
                    .map_err(io)?;
                }
            }
            Ok(())
        })?;

        // modes_synthesis.csv
        let levels = &model.file.excitation.levels_n;
        let syntheses: Vec<_> = levels
            .iter()
            .map(|&l| synthesise(mode, &system.harmonics, &model.force, l))
            .collect();
        let (resp_label, resp_row) = &model.responses[0];
        let path = out.path("modes_synthesis.csv")?;
        write_atomic(&path, |w| {
            let io = |e: std::io::Error| Error::io(&path, e);
            writeln!(w, "# {header}").map_err(io)?;
            write!(w, "{stopped}").map_err(io)?;
            writeln!(w, "# forced response of each excitation level of the model file predicted from the backbone as a single nonlinear mode: (ω(a)² − Ω² + 2iζ(a)ω(a)Ω)·a = φ(a)ᴴ·F (first harmonic; F the excitation vector times the level); side −1/+1: below/above the backbone frequency").map_err(io)?;
            for (l, (_, peak)) in levels.iter().zip(&syntheses) {
                match peak {
                    Some(pk) => writeln!(
                        w,
                        "# level {l} N: peak at {:.9e} Hz, modal amplitude {:.9e} m·kg^½, {resp_label} first harmonic {:.9e} m",
                        pk.omega / TWO_PI,
                        pk.amplitude,
                        pk.response_amplitude(mode, &system.harmonics, resp_row)
                    ),
                    None => writeln!(w, "# level {l} N: the backbone does not reach the peak (extend the amplitude range)"),
                }
                .map_err(io)?;
            }
            writeln!(
                w,
                "level_N,frequency_Hz,modal_amplitude_m_sqrt_kg,side,{resp_label}_h1_amplitude_m"
            )
            .map_err(io)?;
            for (l, (curve, _)) in levels.iter().zip(&syntheses) {
                for sp in curve {
                    let p = &mode.points[sp.point];
                    let (amp, _) = crate::dynamics::report::harmonic_of(system, &p.z, resp_row, 1);
                    writeln!(
                        w,
                        "{l},{:.9e},{:.9e},{},{amp:.9e}",
                        sp.omega / TWO_PI,
                        sp.amplitude,
                        sp.side
                    )
                    .map_err(io)?;
                }
            }
            Ok(())
        })?;

        // modes.png
        let png = out.path("modes.png")?;
        let freq: Vec<(f64, f64)> = mode
            .points
            .iter()
            .map(|p| (p.amplitude, p.frequency_hz()))
            .collect();
        let damp: Vec<(f64, f64)> = mode
            .points
            .iter()
            .map(|p| (p.amplitude, p.damping_ratio()))
            .collect();
        let positive_damping = damp.iter().all(|p| p.1 > 0.0);
        let title_f = format!("nonlinear mode {}: backbone", mode.linear.index);
        let title_d = format!("nonlinear mode {}: modal damping ratio", mode.linear.index);
        stacked_line_plots(
            &png,
            &[
                (
                    LinePlot {
                        title: &title_f,
                        x_label: "modal amplitude (m·kg^½)",
                        y_label: "frequency (Hz)",
                        x_scale: Scale::Log,
                        y_scale: Scale::Linear,
                    },
                    vec![Series::line("EPMC", freq)],
                ),
                (
                    LinePlot {
                        title: &title_d,
                        x_label: "modal amplitude (m·kg^½)",
                        y_label: "damping ratio ζ = ξ/(2ω) (-)",
                        x_scale: Scale::Log,
                        y_scale: if positive_damping {
                            Scale::Log
                        } else {
                            Scale::Linear
                        },
                    },
                    vec![Series::line("EPMC", damp)],
                ),
            ],
        )?;

        // modes.json
        let inputs: Vec<InputFile> = model
            .inputs
            .iter()
            .map(|(role, p)| InputFile::new(role, p))
            .collect::<Result<_>>()?;
        let json = provenance_json(
            "modes",
            &inputs,
            serde_json::json!({
                "model": serde_json::to_value(&model.file).map_err(|e| Error::Data(e.to_string()))?,
                "mode": self.settings.mode,
                "amplitudes_m_sqrt_kg": self.settings.amplitudes,
                "default_amplitude_range": self.default_range,
                "tolerance": self.settings.tolerance,
                "max_iterations": self.settings.max_iterations,
                "max_subdivisions": self.settings.max_subdivisions,
                "harmonics": system.harmonics.orders(),
                "time_samples": system.harmonics.n_time(),
                "formulation": system.formulation(),
                "aft": system.aft,
            }),
            serde_json::json!({
                "linear_frequency_Hz": mode.linear.frequency_hz(),
                "linear_damping_ratio": mode.linear.damping_ratio(),
                "linear_frequencies_Hz": mode.linear.frequencies_hz,
                "reference_coordinate": system.structure.labels[mode.linear.reference],
                "points": mode.points.len(),
                "complete": mode.stopped.is_none(),
                "stopped": mode.stopped,
                "retries": mode.retries,
                "subdivisions": mode.subdivisions,
                "frequency_range_Hz": [
                    mode.points.iter().map(|p| p.frequency_hz()).fold(f64::INFINITY, f64::min),
                    mode.points.iter().map(|p| p.frequency_hz()).fold(0.0, f64::max),
                ],
                "largest_damping_ratio": mode.points.iter().map(|p| p.damping_ratio()).fold(f64::NEG_INFINITY, f64::max),
                "max_relative_residual": mode.points.iter().map(|p| p.residual).fold(0.0, f64::max),
                "max_energy_balance_error": mode.points.iter().map(|p| p.energy_balance_error()).fold(0.0, f64::max),
                "synthesis_peaks": levels.iter().zip(&syntheses).map(|(l, (_, pk))| serde_json::json!({
                    "level_N": l,
                    "peak_frequency_Hz": pk.map(|p| p.omega / TWO_PI),
                    "peak_modal_amplitude_m_sqrt_kg": pk.map(|p| p.amplitude),
                    "peak_response_amplitude_m": pk.map(|p| p.response_amplitude(mode, &system.harmonics, &model.responses[0].1)),
                })).collect::<Vec<_>>(),
                "wall_time_s": mode.wall_time_s,
            }),
        );
        write_string_atomic(
            &out.path("modes.json")?,
            &serde_json::to_string_pretty(&json).map_err(|e| Error::Data(e.to_string()))?,
        )
    }
}
