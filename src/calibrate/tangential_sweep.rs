//! `asperity contact tangential` as a library call: hysteresis loops of the rough contact under
//! an oscillating tangential displacement, one loop per nominal pressure ([`run`] takes a
//! [`TangentialSweepConfig`] and returns a [`TangentialSweep`]; [`TangentialSweep::write`] writes
//! the command's files into the output set that [`output_set`] declares).
//!
//! It lives in the calibration stage because, under a varying normal load, it checks the
//! calibration's element against the contact solver ([`super::varying_load`]); the solvers it
//! drives are those of [`crate::contact`].
//!
//! The steps, in order:
//!
//! 1. **Check the parameters**: step counts within the limits, at most
//!    [`crate::core::limits::MAX_PRESSURES`] pressures, a physical friction coefficient, a finite
//!    non-zero amplitude, at least one cycle of at least four steps, a normal-load amplitude
//!    ratio in [0, 1) with a finite phase, a finite direction and path ratio (an elliptical path
//!    only at constant normal load, at least two cycles with a varying one), the material, the
//!    pressures (positive, ascending after sorting,
//!    [`crate::contact::sweep::checked_pressures`]), a hardness above the highest normal load
//!    and the solver options ([`TangentialOptions::validated`]).
//! 2. **Surface**: the reference Gaussian surface, optionally on another grid
//!    ([`crate::contact::surface_sweep::reference_spec`]), or the equivalent surface `h1 − h2`
//!    of one or two measured files ([`crate::surface::io::read_equivalent_surface`], missing
//!    points filled if asked); grid
//!    size and surface checked, the pressures checked against `E*` and the surface, the
//!    amplitude against the patch size (a unit error beyond it).
//! 3. **Normal contact** at each pressure, ascending and warm-started ([`NormalSolver`], elastic
//!    or hardness-limited); warnings when the contact is cut by the edge of a non-periodic
//!    window or not resolved by the grid ([`crate::contact::resolution`]).
//! 4. **Amplitude**: given, or [`DEFAULT_AMPLITUDE_FACTOR`] × the gross-slip displacement along
//!    the loading direction at the highest pressure
//!    ([`TangentialSolver::gross_slip_displacement`]).
//! 5. **Loops**: at each pressure, Coulomb partial slip with history on the normal pressure field
//!    (Cattaneo–Mindlin on the rough contact; [`TangentialSolver`], quasi-identical bodies),
//!    `cycles × steps_per_cycle` displacement-controlled steps along the direction
//!    ([`oscillate`]) or round the elliptical path ([`oscillate_elliptical`]); the energy
//!    dissipated per cycle checked finite.
//! 6. **Varying normal load** (amplitude ratio > 0): at each pressure the same displacement
//!    history with the normal load oscillating about it
//!    ([`crate::contact::tangential::varying_load::oscillate_with_normal_load`]), and the
//!    Valanis element fitted to the constant-load loop of step 5 driven through it
//!    ([`super::varying_load::check_element`]). The loops reported are then those of the
//!    varying load.
//!
//! Notes and warnings go to the caller's log as they arise (the command prints them to stderr);
//! progress goes to a bar the caller makes for the number of solves.

use super::varying_load::{check_element, constant_load_loop, varying_load_loop, ElementCheck};
use crate::contact::normal::{NormalOptions, NormalProblem, NormalSolution, NormalSolver};
use crate::contact::sweep::{checked_pressures, REFERENCE_PRESSURES_PA};
use crate::contact::tangential::varying_load::{
    oscillate_with_normal_load, NormalLoadOscillation, TangentialSide, VaryingLoadHistory,
};
use crate::contact::tangential::{
    oscillate, oscillate_elliptical, Control, EllipticalPath, Oscillation, OscillationResult,
    TangentialOptions, TangentialProblem, TangentialSolver,
};
use crate::core::error::{Error, Result};
use crate::core::fft::Boundary;
use crate::core::grid::Grid2;
use crate::core::material::{composite_modulus, Hardness, Material};
use crate::core::output::OutputSet;
use crate::core::plot::{line_plot, LinePlot, Scale, Series};
use crate::surface::generate::generate;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Default amplitude as a multiple of the gross-slip displacement at the highest pressure.
pub const DEFAULT_AMPLITUDE_FACTOR: f64 = 1.5;

/// The files [`TangentialSweep::write`] writes at every run.
pub const OUTPUTS: [&str; 5] = [
    "tangential_loops.csv",
    "tangential_energy.csv",
    "tangential_timings.csv",
    "tangential_loops.png",
    "tangential_loops_normalised.png",
];

/// The files it writes in addition under a varying normal load.
pub const ELEMENT_OUTPUTS: [&str; 3] = [
    "tangential_element.csv",
    "tangential_element_loops.png",
    "tangential_element_energy.png",
];

/// The parameters of `asperity contact tangential`, one per flag (SI units; errors name the
/// flags).
#[derive(Debug, Clone, PartialEq)]
pub struct TangentialSweepConfig {
    /// Nominal pressures (Pa); `None`: [`REFERENCE_PRESSURES_PA`].
    pub pressures_pa: Option<Vec<f64>>,
    /// Coulomb friction coefficient μ (-).
    pub friction_coefficient: f64,
    /// Displacement amplitude δa (m); `None`: [`DEFAULT_AMPLITUDE_FACTOR`] × the gross-slip
    /// displacement of the highest pressure.
    pub amplitude_m: Option<f64>,
    /// Number of cycles.
    pub cycles: usize,
    /// Load steps per cycle.
    pub steps_per_cycle: usize,
    /// Grid points per side of the reference surface (`None`: its own, 1024).
    pub grid: Option<usize>,
    /// Measured surfaces (one, or two bodies) instead of the reference generated one.
    pub surface: Vec<PathBuf>,
    /// Fill missing points of the measured surfaces first.
    pub fill: Option<crate::surface::missing::Fill>,
    /// Young's modulus of both bodies (Pa).
    pub youngs_modulus_pa: f64,
    /// Poisson's ratio of both bodies (-).
    pub poisson_ratio: f64,
    /// Hardness H bounding the contact pressure; `None`: elastic contact.
    pub hardness: Option<Hardness>,
    /// Normal load p̄(t) = p̄·(1 + r·sin(ωt + φ)) about each pressure: r in [0, 1) (0: constant).
    pub normal_amplitude_ratio: f64,
    /// Phase φ of the normal load ahead of the displacement (degrees).
    pub normal_phase_deg: f64,
    /// In-plane direction of the displacement, angle from x towards y (degrees).
    pub direction_deg: f64,
    /// Second semi-axis of an elliptical path over the amplitude (0: straight to-and-fro).
    pub path_minor_ratio: f64,
    /// Options of the tangential solver (tolerance, iteration cap, compliance operator).
    pub options: TangentialOptions,
}

impl TangentialSweepConfig {
    /// Whether the normal load varies (amplitude ratio > 0): the element is then checked.
    pub fn varying(&self) -> bool {
        self.normal_amplitude_ratio > 0.0
    }

    /// Whether the path leaves the x axis (a direction or an ellipse): the loops then carry the
    /// y components too.
    pub fn in_plane(&self) -> bool {
        self.direction_deg != 0.0 || self.path_minor_ratio != 0.0
    }

    /// Unit vectors along the direction and turned +90°; exactly (1, 0), (0, 1) at 0°.
    pub fn directions(&self) -> ([f64; 2], [f64; 2]) {
        if self.direction_deg == 0.0 {
            ([1.0, 0.0], [0.0, 1.0])
        } else {
            let theta = self.direction_deg.to_radians();
            ([theta.cos(), theta.sin()], [-theta.sin(), theta.cos()])
        }
    }
}

/// The output set of a run into `out_dir` (`flag` names it in errors), declared before any work:
/// the files of [`OUTPUTS`] (and [`ELEMENT_OUTPUTS`] under a varying normal load); the surface
/// files (and their sidecars) are inputs that no output may be.
pub fn output_set(config: &TangentialSweepConfig, out_dir: &Path, flag: &str) -> Result<OutputSet> {
    let mut out = OutputSet::in_dir(out_dir, flag)?;
    out.writes(&OUTPUTS)?;
    if config.varying() {
        out.writes(&ELEMENT_OUTPUTS)?;
    }
    crate::surface::io::declare_inputs(&mut out, &config.surface, "--surface")?;
    Ok(out)
}

/// The element against the contact solver under the varying normal load at one pressure.
#[derive(Debug, Clone, PartialEq)]
pub struct VaryingLoadCheck {
    /// The element fitted at constant load, run on the varying history, and its refit.
    pub check: ElementCheck,
    /// Mean normal pressure of each step (Pa).
    pub normal_pressure_pa: Vec<f64>,
}

/// What `asperity contact tangential` computed: the loops at each pressure with what they were
/// computed from.
#[derive(Debug, Clone)]
pub struct TangentialSweep {
    /// The parameters of the run.
    pub config: TangentialSweepConfig,
    /// The surface (heights, m).
    pub surface: Grid2,
    /// The surface's description (the generated one's statistics, or the files).
    pub source: String,
    /// The material of both bodies.
    pub material: Material,
    /// Composite modulus `E*` (Pa).
    pub e_star_pa: f64,
    /// Coulomb friction coefficient μ (-).
    pub friction_coefficient: f64,
    /// Hardness H (Pa) bounding the pressure, if any.
    pub hardness_pa: Option<f64>,
    /// The nominal pressures (Pa), ascending.
    pub pressures_pa: Vec<f64>,
    /// Contact area ratio of the normal contact at each pressure.
    pub contact_area_ratios: Vec<f64>,
    /// Plastic area ratio of the normal contact at each pressure.
    pub plastic_area_ratios: Vec<f64>,
    /// Displacement amplitude (m).
    pub amplitude_m: f64,
    /// Where the amplitude came from.
    pub amplitude_note: String,
    /// One loop history per pressure (under the varying normal load when there is one).
    pub results: Vec<OscillationResult>,
    /// Under a varying normal load, the element's check at each pressure; empty otherwise.
    pub element: Vec<VaryingLoadCheck>,
    /// Warning: contact cut by the edge of a non-periodic window.
    pub edge_warning: Option<String>,
    /// Warning: contact not resolved by the grid.
    pub resolution_warning: Option<String>,
}

/// The parameters that need no surface, checked.
struct Checked {
    /// μ (-).
    mu: f64,
    /// Both bodies.
    material: Material,
    /// `E*` (Pa).
    e_star: f64,
    /// Ascending (Pa).
    pressures: Vec<f64>,
    /// H (Pa).
    hardness_pa: Option<f64>,
    /// Of the tangential solver.
    options: TangentialOptions,
}

/// Check the parameters that need no surface, under the flags' names (step 1 of the
/// [module documentation](self)).
fn checked(args: &TangentialSweepConfig) -> Result<Checked> {
    crate::core::limits::check_steps(
        "--cycles",
        args.cycles,
        "--steps-per-cycle",
        args.steps_per_cycle,
    )?;
    if let Some(p) = &args.pressures_pa {
        crate::core::limits::check_count(
            "--pressures-pa",
            p.len(),
            crate::core::limits::MAX_PRESSURES,
        )?;
    }
    let mu = crate::core::sanity::friction_coefficient(
        "--friction-coefficient",
        args.friction_coefficient,
    )?;
    if let Some(a) = args.amplitude_m {
        if !(a.is_finite() && a != 0.0) {
            return Err(Error::param(
                "--amplitude-m",
                format!("must be finite and non-zero, got {a}"),
            ));
        }
    }
    if args.cycles == 0 {
        return Err(Error::param("--cycles", "must be at least 1"));
    }
    if args.steps_per_cycle < 4 {
        return Err(Error::param("--steps-per-cycle", "must be at least 4"));
    }
    let ratio = args.normal_amplitude_ratio;
    if !(ratio.is_finite() && (0.0..1.0).contains(&ratio)) {
        return Err(Error::param(
            "--normal-amplitude-ratio",
            format!(
                "the normal load amplitude over its mean must lie in [0, 1) (the contact stays \
                 closed), got {ratio}"
            ),
        ));
    }
    if !args.normal_phase_deg.is_finite() {
        return Err(Error::param(
            "--normal-phase-deg",
            format!("must be finite, got {}", args.normal_phase_deg),
        ));
    }
    let varying = args.varying();
    for (flag, v) in [
        ("--direction-deg", args.direction_deg),
        ("--path-minor-ratio", args.path_minor_ratio),
    ] {
        if !v.is_finite() {
            return Err(Error::param(flag, format!("must be finite, got {v}")));
        }
    }
    if varying && args.path_minor_ratio != 0.0 {
        return Err(Error::param(
            "--path-minor-ratio",
            "an elliptical path is not combined with a varying normal load (use a straight \
             path, --path-minor-ratio 0)",
        ));
    }
    if varying && args.cycles < 2 {
        return Err(Error::param(
            "--cycles",
            "with a varying normal load give at least 2 (the element is compared on the last, \
             steady cycle)",
        ));
    }
    let material = crate::core::material::from_flags(args.youngs_modulus_pa, args.poisson_ratio)?;
    let e_star = composite_modulus(material, material)?;
    let pressures = checked_pressures(
        args.pressures_pa
            .as_deref()
            .unwrap_or(&REFERENCE_PRESSURES_PA),
    )
    .map_err(|e| e.renamed_param("--pressures-pa"))?;
    let hardness_pa = args
        .hardness
        .as_ref()
        .map(|h| h.pa("--hardness-pa"))
        .transpose()?;
    if let (Some(h), Some(&p)) = (hardness_pa, pressures.last()) {
        let p = p * (1.0 + ratio);
        if p >= h {
            return Err(Error::param(
                "--hardness-pa",
                format!(
                    "H = {h:e} Pa must exceed the highest nominal pressure {p:e} Pa (a contact \
                     at p̄ ≥ H is plastic over the whole patch)"
                ),
            ));
        }
    }
    // Checked now, under the flags' names, not after the normal solves.
    let options = args.options.validated().map_err(|e| match e {
        Error::InvalidParameter { name, message } => {
            Error::param(format!("--{}", name.replace('_', "-")), message)
        }
        other => other,
    })?;
    Ok(Checked {
        mu,
        material,
        e_star,
        pressures,
        hardness_pa,
        options,
    })
}

/// The surface of the run and its description: the reference generated one (on `--grid` if
/// given) or the equivalent surface of the files, checked (step 2).
fn surface_of(args: &TangentialSweepConfig) -> Result<(Grid2, String)> {
    let (surface, source) = if args.surface.is_empty() {
        if let Some(n) = args.grid.filter(|&n| n < 8) {
            return Err(Error::param(
                "--grid",
                format!("must be at least 8, got {n}"),
            ));
        }
        let spec = crate::contact::surface_sweep::reference_spec(args.grid)?;
        (
            generate(&spec)?,
            format!(
                "reference generated surface (Rq {} m, correlation length {} m, {} m, {}², seed {})",
                spec.rq_m, spec.clx_m, spec.lx_m, spec.nx, spec.seed
            ),
        )
    } else {
        if args.grid.is_some() {
            return Err(Error::param(
                "--grid",
                "applies to the generated surface, not to a --surface file",
            ));
        }
        crate::surface::io::read_equivalent_surface(&args.surface, args.fill)
            .map_err(|e| e.renamed_param("--surface"))?
    };
    crate::core::limits::check_grid(
        &source,
        surface.nx(),
        surface.ny(),
        crate::core::limits::CONTACT_BYTES_PER_POINT,
    )?;
    crate::core::sanity::contact_surface(&surface, &source)?;
    Ok((surface, source))
}

/// The warning for pressures whose normal contact the grid does not resolve (as `contact
/// normal` reports it): the loops then come from a contact of a few points.
fn resolution_warning(pressures: &[f64], normals: &[NormalSolution]) -> Option<String> {
    let coarse: Vec<String> = pressures
        .iter()
        .zip(normals)
        .filter(|(_, n)| !n.resolution.resolved())
        .map(|(p, n)| {
            format!(
                "{p:e} Pa ({:.1} points across the {}, {} contact points)",
                n.resolution.points_across(),
                if n.resolution.contact_is_narrower() {
                    "contact spots"
                } else {
                    "free islands"
                },
                n.resolution.contact_points
            )
        })
        .collect();
    (!coarse.is_empty()).then(|| {
        format!(
            "the grid does not resolve the normal contact (fewer than {} points across the narrower of contact spots and free islands) at {}: the loops come from an under-resolved contact; refine the grid",
            crate::contact::resolution::RESOLVED_POINTS_ACROSS,
            coarse.join(", ")
        )
    })
}

/// Run the tangential sweep (steps in the [module documentation](self)). `progress` makes the
/// progress bar for a number of solves (once the checks have passed); `log` takes every note
/// and warning as it arises.
pub fn run(
    config: &TangentialSweepConfig,
    progress: &dyn Fn(u64) -> indicatif::ProgressBar,
    log: &mut dyn FnMut(&str),
) -> Result<TangentialSweep> {
    let args = config;
    let Checked {
        mu,
        material,
        e_star,
        pressures,
        hardness_pa,
        options,
    } = checked(args)?;
    let (ratio, varying) = (args.normal_amplitude_ratio, args.varying());
    let (e1, e2) = args.directions();
    let (surface, source) = surface_of(args)?;
    crate::core::sanity::contact_pressures("--pressures-pa", &pressures, e_star, &surface)?;
    if let Some(a) = args.amplitude_m {
        // Gross slip sets in at displacements of the order of μ·p/E*·(patch size); an amplitude
        // beyond the patch itself is a unit error (µm written as m).
        let l = surface.lx().max(surface.ly());
        if a.abs() > l {
            return Err(Error::param(
                "--amplitude-m",
                format!("{a} m is larger than the patch ({l:e} m): µm written as m?"),
            ));
        }
    }
    let boundary = if surface.periodic {
        Boundary::Periodic
    } else {
        Boundary::ZeroPadded
    };
    log(&format!(
        "surface: {source}; {}; E* = {e_star:.4e} Pa, μ = {mu}",
        crate::core::grid::describe(&surface)
    ));

    let steps_per_pressure = (args.cycles * args.steps_per_cycle) as u64;
    // Per pressure: the normal solve and the constant-load loop; under a varying normal load also
    // the varying loop and the constant-load loops (with their normal solves) at the lowest and
    // highest load of the cycle, for the load-following element.
    let bar = progress(
        pressures.len() as u64
            * (1 + steps_per_pressure + u64::from(varying) * (2 + 3 * steps_per_pressure)),
    );

    // Normal contact at each pressure (ascending, warm-started).
    let normal_problem = NormalProblem {
        surface: &surface,
        e_star_pa: e_star,
        hardness_pa,
    };
    let mut normal = NormalSolver::new(&normal_problem, NormalOptions::default())?;
    let mut normals = Vec::with_capacity(pressures.len());
    for &p in &pressures {
        bar.set_message(format!("normal {:.2} MPa", p / 1e6));
        let sol = normal.solve_load(p, normals.last())?;
        bar.inc(1);
        normals.push(sol);
    }
    // A contact cut by the edge of a non-periodic window depends on the window (not the grid).
    let edge_warning = crate::contact::resolution::ContactResolution::window_edge_warning(
        pressures
            .iter()
            .copied()
            .zip(normals.iter().map(|n| &n.resolution)),
    );
    if let Some(w) = &edge_warning {
        bar.suspend(|| log(&format!("warning: {w}")));
    }
    let resolution_warning = resolution_warning(&pressures, &normals);
    if let Some(w) = &resolution_warning {
        bar.suspend(|| log(&format!("warning: {w}")));
    }
    let build = |pressure: &ndarray::Array2<f64>| {
        TangentialSolver::new(
            &TangentialProblem {
                pressure,
                dx: surface.dx,
                dy: surface.dy,
                boundary,
                friction_coefficient: mu,
                body1: material,
                body2: material,
            },
            options,
        )
    };

    // Amplitude: given, or 1.5 × the gross-slip displacement at the highest pressure.
    let mut solvers: Vec<Option<TangentialSolver>> = (0..pressures.len()).map(|_| None).collect();
    let (amplitude, amplitude_note) = match args.amplitude_m {
        Some(a) => (a, "given by --amplitude-m".to_string()),
        None => {
            let last = pressures.len() - 1;
            let s = build(&normals[last].pressure)?;
            let d = s.gross_slip_displacement(e1)?;
            solvers[last] = Some(s);
            (
                DEFAULT_AMPLITUDE_FACTOR * d,
                format!(
                    "default: {DEFAULT_AMPLITUDE_FACTOR} x gross-slip displacement {d:.4e} m at {:e} Pa",
                    pressures[last]
                ),
            )
        }
    };
    log(&format!(
        "amplitude δa = {amplitude:.4e} m ({amplitude_note})"
    ));

    let mut results: Vec<OscillationResult> = Vec::with_capacity(pressures.len());
    for (k, &p) in pressures.iter().enumerate() {
        bar.set_message(format!("{:.2} MPa", p / 1e6));
        let mut s = match solvers[k].take() {
            Some(s) => s,
            None => build(&normals[k].pressure)?,
        };
        let done = bar.position();
        let major = Control::Displacement([amplitude * e1[0], amplitude * e1[1]]);
        let r = if args.path_minor_ratio == 0.0 {
            oscillate(
                &mut s,
                &Oscillation {
                    amplitude: major,
                    cycles: args.cycles,
                    steps_per_cycle: args.steps_per_cycle,
                },
                |i, _| bar.set_position(done + i as u64),
            )?
        } else {
            let b = args.path_minor_ratio * amplitude;
            oscillate_elliptical(
                &mut s,
                &EllipticalPath {
                    major,
                    minor: [b * e2[0], b * e2[1]],
                    cycles: args.cycles,
                    steps_per_cycle: args.steps_per_cycle,
                },
                |i, _| bar.set_position(done + i as u64),
            )?
        };
        for c in &r.cycles {
            crate::core::sanity::finite_result(
                &format!(
                    "the energy of cycle {} at {} Pa",
                    c.cycle,
                    crate::core::error::num(p)
                ),
                c.dissipated_j_per_m2,
            )?;
        }
        results.push(r);
    }
    // Varying normal load: the same amplitude with the normal load oscillating about each
    // pressure; the element fitted to the constant-load loop above is run on the same history.
    let n = args.steps_per_cycle;
    let mut element: Vec<VaryingLoadCheck> = Vec::new();
    if varying {
        let mut varying_results = Vec::with_capacity(pressures.len());
        for (k, &p) in pressures.iter().enumerate() {
            bar.set_message(format!("{:.2} MPa, varying normal load", p / 1e6));
            let done = bar.position();
            let r = oscillate_with_normal_load(
                &normal_problem,
                NormalOptions::default(),
                &TangentialSide {
                    friction_coefficient: mu,
                    body1: material,
                    body2: material,
                    options,
                },
                &VaryingLoadHistory {
                    tangential_amplitude: Control::Displacement([
                        amplitude * e1[0],
                        amplitude * e1[1],
                    ]),
                    normal: NormalLoadOscillation {
                        mean_pressure_pa: p,
                        amplitude_ratio: ratio,
                        phase_rad: args.normal_phase_deg.to_radians(),
                    },
                    cycles: args.cycles,
                    steps_per_cycle: n,
                },
                |i, _| bar.set_position(done + i as u64),
            )?;
            let mut spanning = Vec::with_capacity(2);
            for load in [p * (1.0 - ratio), p * (1.0 + ratio)] {
                bar.set_message(format!(
                    "{:.2} MPa, constant load {:.3} MPa for the load-following element",
                    p / 1e6,
                    load / 1e6
                ));
                let sol = normal.solve_load(load, Some(&normals[k]))?;
                bar.inc(1);
                let mut s = build(&sol.pressure)?;
                let done = bar.position();
                let r = oscillate(
                    &mut s,
                    &Oscillation {
                        amplitude: Control::Displacement([amplitude * e1[0], amplitude * e1[1]]),
                        cycles: args.cycles,
                        steps_per_cycle: n,
                    },
                    |i, _| bar.set_position(done + i as u64),
                )?;
                spanning.push(constant_load_loop(&r, load, n, e1)?);
            }
            let check = check_element(
                &constant_load_loop(&results[k], p, n, e1)?,
                &spanning,
                &varying_load_loop(&r, n, e1)?,
                &super::FitOptions {
                    mu,
                    ..super::FitOptions::default()
                },
            )
            .map_err(|e| Error::Data(format!("element check at {p:e} Pa: {e}")))?;
            element.push(VaryingLoadCheck {
                check,
                normal_pressure_pa: r.steps.iter().map(|s| s.mean_pressure_pa).collect(),
            });
            varying_results.push(OscillationResult {
                steps: r.steps.iter().map(|s| s.tangential).collect(),
                cycles: r.cycles.clone(),
                metadata: r.metadata.clone(),
                wall_time_s: r.wall_time_s,
            });
        }
        // From here on the loops, energies and plots are those of the varying load.
        results = varying_results;
    }
    bar.finish_and_clear();

    Ok(TangentialSweep {
        config: config.clone(),
        surface,
        source,
        material,
        e_star_pa: e_star,
        friction_coefficient: mu,
        hardness_pa,
        pressures_pa: pressures,
        contact_area_ratios: normals.iter().map(|n| n.contact_area_ratio).collect(),
        plastic_area_ratios: normals.iter().map(|n| n.plastic_area_ratio).collect(),
        amplitude_m: amplitude,
        amplitude_note,
        results,
        element,
        edge_warning,
        resolution_warning,
    })
}

impl TangentialSweep {
    /// The provenance header of the CSVs.
    fn csv_head(&self) -> String {
        let args = &self.config;
        let (material, mu, amplitude) =
            (self.material, self.friction_coefficient, self.amplitude_m);
        let mut head = String::new();
        let _ = writeln!(
            head,
            "# asperity contact tangential: Coulomb partial slip with history on the normal-contact pressure"
        );
        let _ = writeln!(
            head,
            "# assumption: {}",
            self.results[0].metadata.assumption
        );
        let _ = writeln!(head, "# surface: {}", self.source);
        let _ = writeln!(head, "{}", crate::core::grid::csv_header(&self.surface));
        for w in [&self.edge_warning, &self.resolution_warning]
            .into_iter()
            .flatten()
        {
            let _ = writeln!(head, "# warning: {w}");
        }
        let _ = writeln!(
            head,
            "# youngs_modulus_Pa = {:e}, poisson_ratio = {} (both bodies), friction_coefficient = {mu}",
            material.youngs_modulus_pa, material.poisson_ratio
        );
        let _ = match self.hardness_pa {
            Some(h) => writeln!(
                head,
                "# hardness_Pa = {h:e}: elastic-perfectly plastic normal contact (pressure <= H, monotonic loading to each pressure); Coulomb bound mu*p on that bounded pressure"
            ),
            None => writeln!(head, "# no hardness: elastic normal contact"),
        };
        let _ = writeln!(
            head,
            "# loading: {}, amplitude_m = {amplitude:e} ({}), cycles = {}, steps_per_cycle = {}",
            if !args.in_plane() {
                "displacement along x, delta(t) = amplitude_m * sin(2 pi step / steps_per_cycle)"
                    .to_string()
            } else if args.path_minor_ratio == 0.0 {
                format!("displacement along e1 = (cos, sin)({} deg), delta(t) = amplitude_m * e1 * sin(2 pi step / steps_per_cycle); displacement_m, mean_shear_stress_Pa, force_N are x components", args.direction_deg)
            } else {
                format!("elliptical path delta(t) = amplitude_m * (e1 sin(theta) + {} e2 (1 - cos(theta))), theta = 2 pi step / steps_per_cycle, e1 = (cos, sin)({} deg), e2 = e1 turned +90 deg; displacement_m, mean_shear_stress_Pa, force_N are x components; dissipated = loop integral of T . d(delta) over both components", args.path_minor_ratio, args.direction_deg)
            },
            self.amplitude_note,
            args.cycles,
            args.steps_per_cycle
        );
        if args.varying() {
            let _ = writeln!(
                head,
                "# normal load: p(t) = pressure_Pa * (1 + r sin(2 pi step / steps_per_cycle + phase)), r = {}, phase_deg = {}; applied first at step 0 (virgin state); {}",
                args.normal_amplitude_ratio,
                args.normal_phase_deg,
                if self.hardness_pa.is_some() {
                    "hardness: the plastic state of the largest load, every load elastic on its residual surface"
                } else {
                    "elastic"
                }
            );
        }
        let _ = writeln!(
            head,
            "# mean shear stress = tangential force / nominal area; accumulated slip = slip path length averaged over the contact area; tolerance = {:e}",
            args.options.tolerance
        );
        head
    }

    /// Write the command's files into the output set `out` (declared by [`output_set`]):
    /// `tangential_loops.csv` (every step, SI units in the column names),
    /// `tangential_energy.csv` (energy per cycle, J/m²), `tangential_timings.csv` (wall times,
    /// s, kept apart so that the other files are reproducible), `tangential_loops.png` (mean
    /// shear stress vs displacement along the loading direction, all pressures) and
    /// `tangential_loops_normalised.png` (τ/(μ p̄), so that the low-pressure loops are visible
    /// too); under a varying normal load also `tangential_element.csv` and its two plots.
    pub fn write(&self, out: &mut OutputSet) -> Result<()> {
        let args = &self.config;
        let (pressures, results) = (&self.pressures_pa, &self.results);
        let (mu, n, in_plane) = (
            self.friction_coefficient,
            args.steps_per_cycle,
            args.in_plane(),
        );
        let (e1, _) = args.directions();
        let head = self.csv_head();
        let mut loops = head.clone();
        let _ = writeln!(
            loops,
            "pressure_Pa,cycle,step,displacement_m,mean_shear_stress_Pa,mean_shear_stress_y_Pa,force_N,stick_fraction,accumulated_slip_m,iterations,residual{}{}",
            if in_plane { ",displacement_y_m,force_y_N" } else { "" },
            if args.varying() {
                ",normal_pressure_Pa,element_mean_shear_stress_Pa"
            } else {
                ""
            }
        );
        let mut energy = head.clone();
        let _ = writeln!(
            energy,
            "# cycle 1 starts from the virgin state (includes the initial loading branch); dissipated = loop area of mean shear stress vs displacement"
        );
        let _ = writeln!(
            energy,
            "pressure_Pa,cycle,dissipated_J_per_m2,dissipated_J,frictional_work_J,contact_area_ratio,plastic_area_ratio,contact_points,operator"
        );
        // Wall times in a file of their own, so that the loops and energies are reproducible
        // byte for byte (as `contact normal` keeps its timings apart).
        let mut timings =
            String::from("pressure_Pa,setup_time_s,oscillation_wall_time_s,step_wall_time_max_s\n");
        for (k, (&p, r)) in pressures.iter().zip(results).enumerate() {
            for (i, st) in r.steps.iter().enumerate() {
                let cycle = if i == 0 { 1 } else { (i - 1) / n + 1 };
                let in_plane_columns = if in_plane {
                    format!(",{:e},{:e}", st.shift_m[1], st.force_n[1])
                } else {
                    String::new()
                };
                let extra = match self.element.get(k) {
                    Some(v) => format!(
                        ",{:e},{:e}",
                        v.normal_pressure_pa[i], v.check.element_shear_pa[i]
                    ),
                    None => String::new(),
                };
                let _ = write!(
                    loops,
                    "{p:e},{cycle},{i},{:e},{:e},{:e},{:e},{:.6},{:e},{},{:e}",
                    st.shift_m[0],
                    st.mean_shear_pa[0],
                    st.mean_shear_pa[1],
                    st.force_n[0],
                    st.stick_fraction,
                    st.accumulated_slip_m,
                    st.iterations,
                    st.residual,
                );
                let _ = writeln!(loops, "{in_plane_columns}{extra}");
            }
            let _ = writeln!(
                timings,
                "{p:e},{:.3},{:.3},{:.4}",
                r.metadata.setup_time_s,
                r.wall_time_s,
                r.steps.iter().map(|s| s.wall_time_s).fold(0.0, f64::max)
            );
            for c in &r.cycles {
                let _ = writeln!(
                    energy,
                    "{p:e},{},{:e},{:e},{:e},{:e},{:e},{},{:?}",
                    c.cycle,
                    c.dissipated_j_per_m2,
                    c.dissipated_j,
                    c.frictional_work_j,
                    self.contact_area_ratios[k],
                    self.plastic_area_ratios[k],
                    r.metadata.contact_points,
                    r.metadata.operator,
                );
            }
        }
        crate::core::output::write_string_atomic(&out.path("tangential_loops.csv")?, &loops)?;
        crate::core::output::write_string_atomic(&out.path("tangential_energy.csv")?, &energy)?;
        crate::core::output::write_string_atomic(&out.path("tangential_timings.csv")?, &timings)?;
        if args.varying() {
            self.write_element_outputs(out, &head)?;
        }

        // Loops along the loading direction (x at 0°).
        let along = |v: [f64; 2]| v[0] * e1[0] + v[1] * e1[1];
        let series = |norm: bool| -> Vec<Series> {
            pressures
                .iter()
                .zip(results)
                .map(|(&p, r)| {
                    let f = if norm { 1.0 / (mu * p) } else { 1e-6 };
                    Series::line(
                        format!("{} MPa", p / 1e6),
                        r.steps
                            .iter()
                            .map(|s| (along(s.shift_m) * 1e6, along(s.mean_shear_pa) * f))
                            .collect(),
                    )
                })
                .collect()
        };
        line_plot(
            &out.path("tangential_loops.png")?,
            &LinePlot {
                title: "Tangential hysteresis loops (mean shear stress vs displacement)",
                x_label: "tangential displacement (µm)",
                y_label: "mean shear stress (MPa)",
                x_scale: Scale::Linear,
                y_scale: Scale::Linear,
            },
            &series(false),
        )?;
        line_plot(
            &out.path("tangential_loops_normalised.png")?,
            &LinePlot {
                title: "Tangential hysteresis loops, normalised by μ p",
                x_label: "tangential displacement (µm)",
                y_label: "mean shear stress / (μ p) (-)",
                x_scale: Scale::Linear,
                y_scale: Scale::Linear,
            },
            &series(true),
        )
    }

    /// `tangential_element.csv` and its two plots: the table's element (fitted at constant load)
    /// against the BEM under the varying normal load, per pressure.
    fn write_element_outputs(&self, out: &mut OutputSet, head: &str) -> Result<()> {
        let (pressures, results, element) = (&self.pressures_pa, &self.results, &self.element);
        let (mu, n) = (self.friction_coefficient, self.config.steps_per_cycle);
        let (e1, _) = self.config.directions();
        let along = |v: [f64; 2]| v[0] * e1[0] + v[1] * e1[1];
        let mut csv = head.to_string();
        let _ = writeln!(
            csv,
            "# element: Valanis, lambda = E0/(mu Fz (1 - k Et/E0)) with Fz = the normal pressure of the step (the 3-D element's law); E0 and k fitted to the constant-load BEM loop at pressure_Pa with the same displacement amplitude (mu fixed, Et = 0), then driven through the varying history; energies per cycle on the last (steady) cycle; element_energy_error = (element - BEM)/BEM; refit = E0 and k fitted to the varying loop itself (the best this law can do); load_following = E0(Fz) and k(Fz) fitted to constant-load BEM loops at the lowest and highest load of the cycle and at pressure_Pa (same amplitude), interpolated at the instantaneous load (power law in Fz for E0, linear in ln Fz for k), nothing fitted to the varying loop"
        );
        let _ = writeln!(
            csv,
            "pressure_Pa,bem_constant_load_J_per_m2,bem_J_per_m2,element_J_per_m2,element_energy_error,element_R2,E0_N_per_m3,k,constant_load_fit_R2,refit_E0_N_per_m3,refit_k,refit_R2,refit_energy_error,load_following_J_per_m2,load_following_energy_error,load_following_R2,load_low_Pa,E0_low_N_per_m3,k_low,load_high_Pa,E0_high_N_per_m3,k_high"
        );
        for (&p, v) in pressures.iter().zip(element) {
            let c = &v.check;
            let lf = &c.load_following;
            let _ = writeln!(
                csv,
                "{p:e},{:e},{:e},{:e},{:.6},{:.6},{:e},{:.6},{:.6},{:e},{:.6},{:.6},{:.6},{:e},{:.6},{:.6},{:e},{:e},{:.6},{:e},{:e},{:.6}",
                c.bem_constant_energy_j_per_m2,
                c.bem_energy_j_per_m2,
                c.element_energy_j_per_m2,
                c.energy_rel_error,
                c.r2,
                c.table_params.e0,
                c.table_params.k,
                c.table_fit_r2,
                c.refit_params.e0,
                c.refit_params.k,
                c.refit_r2,
                c.refit_energy_rel_error,
                c.load_following_energy_j_per_m2,
                c.load_following_energy_rel_error,
                c.load_following_r2,
                lf.loads[0],
                lf.params[0].e0,
                lf.params[0].k,
                lf.loads[lf.loads.len() - 1],
                lf.params[lf.params.len() - 1].e0,
                lf.params[lf.params.len() - 1].k,
            );
        }
        crate::core::output::write_string_atomic(&out.path("tangential_element.csv")?, &csv)?;
        // Loops of the last cycle, normalised by μ p̄: the BEM as lines, the element as markers
        // of the same colour.
        let mut loops = Vec::new();
        for (i, ((&p, r), v)) in pressures.iter().zip(results).zip(element).enumerate() {
            let last = r.steps.len() - 1 - n..r.steps.len();
            let f = 1.0 / (mu * p);
            loops.push(
                Series::line(
                    format!("BEM {} MPa", p / 1e6),
                    r.steps[last.clone()]
                        .iter()
                        .map(|s| (along(s.shift_m) * 1e6, along(s.mean_shear_pa) * f))
                        .collect(),
                )
                .with_colour(i),
            );
            loops.push(
                Series::markers(
                    format!("element {} MPa", p / 1e6),
                    last.map(|j| {
                        (
                            along(r.steps[j].shift_m) * 1e6,
                            v.check.element_shear_pa[j] * f,
                        )
                    })
                    .collect(),
                )
                .with_colour(i),
            );
        }
        line_plot(
            &out.path("tangential_element_loops.png")?,
            &LinePlot {
                title: "Varying normal load: BEM loops (lines) and the element's (markers)",
                x_label: "tangential displacement (µm)",
                y_label: "mean shear stress / (μ p̄) (-)",
                x_scale: Scale::Linear,
                y_scale: Scale::Linear,
            },
            &loops,
        )?;
        let energy = |label: &str, f: &dyn Fn(&ElementCheck) -> f64| {
            Series::markers(
                label.to_string(),
                pressures
                    .iter()
                    .zip(element)
                    .map(|(&p, v)| (p / 1e6, f(&v.check).abs().max(f64::MIN_POSITIVE)))
                    .collect(),
            )
        };
        line_plot(
            &out.path("tangential_element_energy.png")?,
            &LinePlot {
                title: "Energy per cycle: BEM at constant and varying normal load, element",
                x_label: "mean nominal pressure (MPa)",
                y_label: "energy per cycle (J/m²)",
                x_scale: Scale::Log,
                y_scale: Scale::Log,
            },
            &[
                energy("BEM, constant normal load", &|c| {
                    c.bem_constant_energy_j_per_m2
                }),
                energy("BEM, varying normal load", &|c| c.bem_energy_j_per_m2),
                energy("element (λ ∝ 1/Fz), varying", &|c| {
                    c.element_energy_j_per_m2
                }),
                energy("load-following element (E0, k of Fz), varying", &|c| {
                    c.load_following_energy_j_per_m2
                }),
            ],
        )?;
        Ok(())
    }
}
