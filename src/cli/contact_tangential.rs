//! `asperity contact tangential`: hysteresis loops of the rough contact under an oscillating
//! tangential displacement δ(t) = δa·sin(ωt) along x, one loop per nominal pressure.
//!
//! Writes `tangential_loops.csv` (every step, SI units in the column names),
//! `tangential_energy.csv` (energy per cycle, J/m²), `tangential_timings.csv` (wall times, s,
//! kept apart so that the other files are reproducible), `tangential_loops.png` (mean shear stress vs
//! displacement, all pressures) and `tangential_loops_normalised.png` (τ/(μ p̄), so that the
//! low-pressure loops are visible too).
//!
//! With `--normal-amplitude-ratio r` the normal load oscillates with the displacement,
//! p̄(t) = p̄·(1 + r·sin(ωt + φ)) (`--normal-phase-deg φ`): the loops, energies and plots are then
//! those of the varying load, `tangential_loops.csv` gains the normal pressure and the element's
//! shear stress of each step, and the Valanis element of the table (λ ∝ 1/Fz, E0 and k fitted to
//! the constant-load loop at p̄) is run on the same history: `tangential_element.csv` (energies
//! per cycle and the element's error), `tangential_element_loops.png`,
//! `tangential_element_energy.png`.

use asperity::calibrate::varying_load::{
    check_element, constant_load_loop, varying_load_loop, ElementCheck,
};
use asperity::contact::normal::{NormalOptions, NormalProblem, NormalSolver};
use asperity::contact::sweep::{checked_pressures, REFERENCE_PRESSURES_PA};
use asperity::contact::tangential::varying_load::{
    oscillate_with_normal_load, NormalLoadOscillation, TangentialSide, VaryingLoadHistory,
    VaryingLoadResult,
};
use asperity::contact::tangential::{
    oscillate, oscillate_elliptical, Control, EllipticalPath, Operator, Oscillation,
    OscillationResult, TangentialOptions, TangentialProblem, TangentialSolver,
};
use asperity::core::fft::Boundary;
use asperity::core::material::composite_modulus;
use asperity::core::plot::{line_plot, LinePlot, Scale, Series};
use asperity::surface::generate::{generate, GaussianSurfaceSpec};
use asperity::{Error, Result};
use std::fmt::Write as _;
use std::path::PathBuf;

/// Default amplitude as a multiple of the gross-slip displacement at the highest pressure.
pub const DEFAULT_AMPLITUDE_FACTOR: f64 = 1.5;

#[derive(clap::Args)]
pub struct TangentialArgs {
    /// Nominal pressures (Pa), comma separated. Default: the reference sweep
    /// 0.1, 0.2, 1, 2, 5, 10 MPa.
    /// One comma-separated list per flag; values starting with `-` are taken as values, so
    /// that a negative pressure reaches the flag's own check, which names it.
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    pressures_pa: Option<Vec<f64>>,
    /// Coulomb friction coefficient μ (-).
    #[arg(long, default_value_t = 0.6, allow_hyphen_values = true)]
    friction_coefficient: f64,
    /// Displacement amplitude δa (m). Default: 1.5 × the gross-slip displacement of the highest
    /// pressure, so that every loop at that pressure reaches gross slip.
    #[arg(long, allow_hyphen_values = true)]
    amplitude_m: Option<f64>,
    /// Number of cycles.
    #[arg(long, default_value_t = 3)]
    cycles: usize,
    /// Load steps per cycle.
    #[arg(long, default_value_t = 40)]
    steps_per_cycle: usize,
    /// Grid points per side of the reference surface (same 250 µm patch and statistics;
    /// default 1024). Smaller values give a quick, coarser look.
    #[arg(long)]
    grid: Option<usize>,
    /// A measured surface instead of the reference generated one (heights in m; every format
    /// `asperity surface stats` reads). Give it twice for two rough bodies: body 1, then body 2
    /// in the common frame (as `asperity surface combine`); their equivalent surface h1 − h2 is
    /// used. Non-periodic files use the zero-padded kernels (normal and tangential).
    #[arg(long, num_args = 1)]
    surface: Vec<PathBuf>,
    /// Fill missing points of the --surface files first: `harmonic` (Laplace interpolation) or
    /// `nearest`. Without it a surface with missing points is refused.
    #[arg(long, requires = "surface")]
    fill: Option<asperity::surface::missing::Fill>,
    /// Young's modulus of both bodies (Pa).
    #[arg(long, default_value_t = 210e9, allow_hyphen_values = true)]
    youngs_modulus_pa: f64,
    /// Poisson's ratio of both bodies (-).
    #[arg(long, default_value_t = 0.3, allow_hyphen_values = true)]
    poisson_ratio: f64,
    /// Hardness H bounding the contact pressure (elastic–perfectly plastic normal contact; the
    /// loops run on the bounded pressure): a value in Pa, or a material whose documented
    /// hardness to use: `steel-42crmo4` (340 HV, 3.334 GPa) or `inconel-718` (450 HV,
    /// 4.413 GPa); sources in docs/contact.md. Without it the contact is elastic.
    #[arg(long, allow_hyphen_values = true)]
    hardness_pa: Option<String>,
    /// Normal load oscillating with the tangential displacement: p̄(t) = p̄·(1 + r·sin(ωt + φ))
    /// about each pressure p̄, with this amplitude ratio r in [0, 1) (0: constant normal load).
    /// The Valanis element fitted at constant load is then run on the same history
    /// (`tangential_element.csv`).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    normal_amplitude_ratio: f64,
    /// Phase φ of the normal load ahead of the tangential displacement (degrees): 0 in phase,
    /// 180 out of phase, any value.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    normal_phase_deg: f64,
    /// In-plane direction of the displacement, angle from x towards y (degrees).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    direction_deg: f64,
    /// Elliptical path: the second semi-axis over the amplitude, perpendicular to the direction
    /// (turned +90°): δ(t) = δa·(e1·sin ωt + e·e2·(1 − cos ωt)), an ellipse through the origin;
    /// 1 a circle of radius δa, 0 (default) the straight to-and-fro. Not with a varying normal
    /// load.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    path_minor_ratio: f64,
    /// Compliance operator of the tangential solver: auto, dense or fft.
    #[arg(long, default_value = "auto")]
    operator: String,
    /// Tolerance of the tangential solver (relative natural residual).
    #[arg(long, default_value_t = TangentialOptions::default().tolerance)]
    tolerance: f64,
    /// Iteration cap per step (exceeding it is an error).
    #[arg(long, default_value_t = TangentialOptions::default().max_iterations)]
    max_iterations: usize,
    /// Output directory.
    #[arg(long, default_value = "out/contact-tangential")]
    out_dir: PathBuf,
}

pub fn run(args: TangentialArgs) -> Result<()> {
    // Every input is checked before any work or output; the files are staged and appear
    // together at the end (asperity::core::output::OutputSet).
    let mut out = asperity::core::output::OutputSet::in_dir(&args.out_dir, "--out-dir")?;
    out.writes(&[
        "tangential_loops.csv",
        "tangential_energy.csv",
        "tangential_timings.csv",
        "tangential_loops.png",
        "tangential_loops_normalised.png",
    ])?;
    if args.normal_amplitude_ratio > 0.0 {
        out.writes(&[
            "tangential_element.csv",
            "tangential_element_loops.png",
            "tangential_element_energy.png",
        ])?;
    }
    super::surface_inputs(&mut out, &args.surface, "--surface")?;
    asperity::core::limits::check_steps(
        "--cycles",
        args.cycles,
        "--steps-per-cycle",
        args.steps_per_cycle,
    )?;
    if let Some(p) = &args.pressures_pa {
        asperity::core::limits::check_count(
            "--pressures-pa",
            p.len(),
            asperity::core::limits::MAX_PRESSURES,
        )?;
    }
    let mu = asperity::core::sanity::friction_coefficient(
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
    let varying = ratio > 0.0;
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
    let theta = args.direction_deg.to_radians();
    // Unit vectors along the direction and turned +90°; exactly (1, 0), (0, 1) at 0°.
    let (e1, e2) = if args.direction_deg == 0.0 {
        ([1.0, 0.0], [0.0, 1.0])
    } else {
        ([theta.cos(), theta.sin()], [-theta.sin(), theta.cos()])
    };
    let in_plane = args.direction_deg != 0.0 || args.path_minor_ratio != 0.0;
    if varying && args.cycles < 2 {
        return Err(Error::param(
            "--cycles",
            "with a varying normal load give at least 2 (the element is compared on the last, \
             steady cycle)",
        ));
    }
    let material = super::material_from_flags(args.youngs_modulus_pa, args.poisson_ratio)?;
    let e_star = composite_modulus(material, material)?;
    let pressures = checked_pressures(
        args.pressures_pa
            .as_deref()
            .unwrap_or(&REFERENCE_PRESSURES_PA),
    )
    .map_err(|e| super::rename_param(e, "--pressures-pa"))?;
    let hardness_pa = args
        .hardness_pa
        .as_deref()
        .map(super::contact_normal::parse_hardness)
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
    let operator = match args.operator.as_str() {
        "auto" => Operator::Auto,
        "dense" => Operator::Dense,
        "fft" => Operator::Fft,
        o => {
            return Err(Error::param(
                "--operator",
                format!("expected auto, dense or fft, got `{o}`"),
            ))
        }
    };
    let options = TangentialOptions {
        tolerance: args.tolerance,
        max_iterations: args.max_iterations,
        operator,
    };
    // Checked now, under the flags' names, not after the normal solves.
    let options = options.validated().map_err(|e| match e {
        Error::InvalidParameter { name, message } => {
            Error::param(format!("--{}", name.replace('_', "-")), message)
        }
        other => other,
    })?;
    let started = std::time::Instant::now();
    let (surface, source) = if args.surface.is_empty() {
        let mut spec = GaussianSurfaceSpec::reference();
        if let Some(n) = args.grid {
            if n < 8 {
                return Err(Error::param(
                    "--grid",
                    format!("must be at least 8, got {n}"),
                ));
            }
            spec.nx = n;
            spec.ny = n;
        }
        spec.validate()
            .map_err(|e| super::rename_param(e, "--grid"))?;
        asperity::core::limits::check_grid(
            "--grid",
            spec.nx,
            spec.ny,
            asperity::core::limits::CONTACT_BYTES_PER_POINT,
        )?;
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
        asperity::surface::io::read_equivalent_surface(&args.surface, args.fill)
            .map_err(|e| super::rename_param(e, "--surface"))?
    };
    asperity::core::limits::check_grid(
        &source,
        surface.nx(),
        surface.ny(),
        asperity::core::limits::CONTACT_BYTES_PER_POINT,
    )?;
    asperity::core::sanity::contact_surface(&surface, &source)?;
    asperity::core::sanity::contact_pressures("--pressures-pa", &pressures, e_star, &surface)?;
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
    eprintln!(
        "surface: {source}; {}; E* = {e_star:.4e} Pa, μ = {mu}",
        super::surface_summary(&surface)
    );

    let steps_per_pressure = (args.cycles * args.steps_per_cycle) as u64;
    let bar = super::progress_bar(
        "tangential",
        pressures.len() as u64 * (1 + steps_per_pressure * (1 + u64::from(varying))),
    );

    // Normal contact at each pressure (ascending, warm-started).
    let mut normal = NormalSolver::new(
        &NormalProblem {
            surface: &surface,
            e_star_pa: e_star,
            hardness_pa,
        },
        NormalOptions::default(),
    )?;
    let mut normals = Vec::with_capacity(pressures.len());
    for &p in &pressures {
        bar.set_message(format!("normal {:.2} MPa", p / 1e6));
        let sol = normal.solve_load(p, normals.last())?;
        bar.inc(1);
        normals.push(sol);
    }
    // A contact cut by the edge of a non-periodic window depends on the window (not the grid).
    let edge_warning = asperity::contact::resolution::ContactResolution::window_edge_warning(
        pressures
            .iter()
            .copied()
            .zip(normals.iter().map(|n| &n.resolution)),
    );
    if let Some(w) = &edge_warning {
        bar.suspend(|| eprintln!("warning: {w}"));
    }
    // The loops come from the normal solve's contact: one that the grid does not resolve (as
    // `contact normal` reports it) gives loops of a few points.
    let coarse: Vec<String> = pressures
        .iter()
        .zip(&normals)
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
    let resolution_warning = (!coarse.is_empty()).then(|| {
        format!(
            "the grid does not resolve the normal contact (fewer than {} points across the narrower of contact spots and free islands) at {}: the loops come from an under-resolved contact; refine the grid",
            asperity::contact::resolution::RESOLVED_POINTS_ACROSS,
            coarse.join(", ")
        )
    });
    if let Some(w) = &resolution_warning {
        bar.suspend(|| eprintln!("warning: {w}"));
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
    eprintln!("amplitude δa = {amplitude:.4e} m ({amplitude_note})");

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
            asperity::core::sanity::finite_result(
                &format!(
                    "the energy of cycle {} at {} Pa",
                    c.cycle,
                    asperity::core::error::num(p)
                ),
                c.dissipated_j_per_m2,
            )?;
        }
        results.push(r);
    }
    // Varying normal load: the same amplitude with the normal load oscillating about each
    // pressure; the element fitted to the constant-load loop above is run on the same history.
    let n = args.steps_per_cycle;
    let mut element: Vec<(ElementCheck, Vec<f64>)> = Vec::new();
    if varying {
        let mut varying_results = Vec::with_capacity(pressures.len());
        for (k, &p) in pressures.iter().enumerate() {
            bar.set_message(format!("{:.2} MPa, varying normal load", p / 1e6));
            let done = bar.position();
            let r: VaryingLoadResult = oscillate_with_normal_load(
                &NormalProblem {
                    surface: &surface,
                    e_star_pa: e_star,
                    hardness_pa,
                },
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
            let check = check_element(
                &constant_load_loop(&results[k], p, n, e1)?,
                &varying_load_loop(&r, n, e1)?,
                &asperity::calibrate::FitOptions {
                    mu,
                    ..asperity::calibrate::FitOptions::default()
                },
            )
            .map_err(|e| Error::Data(format!("element check at {p:e} Pa: {e}")))?;
            let normal_pressure: Vec<f64> = r.steps.iter().map(|s| s.mean_pressure_pa).collect();
            element.push((check, normal_pressure));
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

    // CSVs with a provenance header.
    let mut head = String::new();
    let _ = writeln!(
        head,
        "# asperity contact tangential: Coulomb partial slip with history on the normal-contact pressure"
    );
    let _ = writeln!(head, "# assumption: {}", results[0].metadata.assumption);
    let _ = writeln!(head, "# surface: {source}");
    let _ = writeln!(head, "{}", super::grid_header(&surface));
    for w in [&edge_warning, &resolution_warning].into_iter().flatten() {
        let _ = writeln!(head, "# warning: {w}");
    }
    let _ = writeln!(
        head,
        "# youngs_modulus_Pa = {:e}, poisson_ratio = {} (both bodies), friction_coefficient = {mu}",
        material.youngs_modulus_pa, material.poisson_ratio
    );
    let _ = match hardness_pa {
        Some(h) => writeln!(
            head,
            "# hardness_Pa = {h:e}: elastic-perfectly plastic normal contact (pressure <= H, monotonic loading to each pressure); Coulomb bound mu*p on that bounded pressure"
        ),
        None => writeln!(head, "# no hardness: elastic normal contact"),
    };
    let _ = writeln!(
        head,
        "# loading: {}, amplitude_m = {amplitude:e} ({amplitude_note}), cycles = {}, steps_per_cycle = {}",
        if !in_plane {
            "displacement along x, delta(t) = amplitude_m * sin(2 pi step / steps_per_cycle)".to_string()
        } else if args.path_minor_ratio == 0.0 {
            format!("displacement along e1 = (cos, sin)({} deg), delta(t) = amplitude_m * e1 * sin(2 pi step / steps_per_cycle); displacement_m, mean_shear_stress_Pa, force_N are x components", args.direction_deg)
        } else {
            format!("elliptical path delta(t) = amplitude_m * (e1 sin(theta) + {} e2 (1 - cos(theta))), theta = 2 pi step / steps_per_cycle, e1 = (cos, sin)({} deg), e2 = e1 turned +90 deg; displacement_m, mean_shear_stress_Pa, force_N are x components; dissipated = loop integral of T . d(delta) over both components", args.path_minor_ratio, args.direction_deg)
        },
        args.cycles, args.steps_per_cycle
    );
    if varying {
        let _ = writeln!(
            head,
            "# normal load: p(t) = pressure_Pa * (1 + r sin(2 pi step / steps_per_cycle + phase)), r = {ratio}, phase_deg = {}; applied first at step 0 (virgin state); {}",
            args.normal_phase_deg,
            if hardness_pa.is_some() {
                "hardness: the plastic state of the largest load, every load elastic on its residual surface"
            } else {
                "elastic"
            }
        );
    }
    let _ = writeln!(
        head,
        "# mean shear stress = tangential force / nominal area; accumulated slip = slip path length averaged over the contact area; tolerance = {:e}",
        args.tolerance
    );
    let mut loops = head.clone();
    let _ = writeln!(
        loops,
        "pressure_Pa,cycle,step,displacement_m,mean_shear_stress_Pa,mean_shear_stress_y_Pa,force_N,stick_fraction,accumulated_slip_m,iterations,residual{}{}",
        if in_plane { ",displacement_y_m,force_y_N" } else { "" },
        if varying {
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
    // Wall times in a file of their own, so that the loops and energies are reproducible byte
    // for byte (as `contact normal` keeps its timings apart).
    let mut timings =
        String::from("pressure_Pa,setup_time_s,oscillation_wall_time_s,step_wall_time_max_s\n");
    for (k, ((&p, r), sol)) in pressures.iter().zip(&results).zip(&normals).enumerate() {
        for (i, st) in r.steps.iter().enumerate() {
            let cycle = if i == 0 { 1 } else { (i - 1) / n + 1 };
            let in_plane_columns = if in_plane {
                format!(",{:e},{:e}", st.shift_m[1], st.force_n[1])
            } else {
                String::new()
            };
            let extra = match element.get(k) {
                Some((check, normal_pressure)) => {
                    format!(",{:e},{:e}", normal_pressure[i], check.element_shear_pa[i])
                }
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
                sol.contact_area_ratio,
                sol.plastic_area_ratio,
                r.metadata.contact_points,
                r.metadata.operator,
            );
        }
    }
    asperity::core::output::write_string_atomic(&out.path("tangential_loops.csv")?, &loops)?;
    asperity::core::output::write_string_atomic(&out.path("tangential_energy.csv")?, &energy)?;
    asperity::core::output::write_string_atomic(&out.path("tangential_timings.csv")?, &timings)?;
    if varying {
        write_element_outputs(&mut out, &head, &pressures, &element, &results, (mu, n, e1))?;
    }

    // Loops along the loading direction (x at 0°).
    let along = |v: [f64; 2]| v[0] * e1[0] + v[1] * e1[1];
    let series = |norm: bool| -> Vec<Series> {
        pressures
            .iter()
            .zip(&results)
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
    )?;

    println!("pressure_MPa  contact_points  operator  W_last_cycle_J_per_m2  time_s");
    for (&p, r) in pressures.iter().zip(&results) {
        println!(
            "{:>12.3}  {:>14}  {:>8?}  {:>21.4e}  {:>6.2}",
            p / 1e6,
            r.metadata.contact_points,
            r.metadata.operator,
            r.cycles.last().map_or(0.0, |c| c.dissipated_j_per_m2),
            r.wall_time_s + r.metadata.setup_time_s
        );
    }
    let written = out.commit()?;
    println!(
        "wrote {} files in {} (total {:.1} s)",
        written.len(),
        args.out_dir.display(),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}

/// `tangential_element.csv` and its two plots: the table's element (fitted at constant load)
/// against the BEM under the varying normal load, per pressure. `(mu, steps_per_cycle)`.
fn write_element_outputs(
    out: &mut asperity::core::output::OutputSet,
    head: &str,
    pressures: &[f64],
    element: &[(ElementCheck, Vec<f64>)],
    results: &[OscillationResult],
    (mu, n, e1): (f64, usize, [f64; 2]),
) -> Result<()> {
    let along = |v: [f64; 2]| v[0] * e1[0] + v[1] * e1[1];
    let mut csv = head.to_string();
    let _ = writeln!(
        csv,
        "# element: Valanis, lambda = E0/(mu Fz (1 - k Et/E0)) with Fz = the normal pressure of the step (the 3-D element's law); E0 and k fitted to the constant-load BEM loop at pressure_Pa with the same displacement amplitude (mu fixed, Et = 0), then driven through the varying history; energies per cycle on the last (steady) cycle; element_energy_error = (element - BEM)/BEM; refit = E0 and k fitted to the varying loop itself (the best this law can do)"
    );
    let _ = writeln!(
        csv,
        "pressure_Pa,bem_constant_load_J_per_m2,bem_J_per_m2,element_J_per_m2,element_energy_error,element_R2,E0_N_per_m3,k,constant_load_fit_R2,refit_E0_N_per_m3,refit_k,refit_R2,refit_energy_error"
    );
    for (&p, (c, _)) in pressures.iter().zip(element) {
        let _ = writeln!(
            csv,
            "{p:e},{:e},{:e},{:e},{:.6},{:.6},{:e},{:.6},{:.6},{:e},{:.6},{:.6},{:.6}",
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
        );
    }
    asperity::core::output::write_string_atomic(&out.path("tangential_element.csv")?, &csv)?;
    // Loops of the last cycle, normalised by μ p̄: the BEM as lines, the element as markers of
    // the same colour.
    let mut loops = Vec::new();
    for (i, ((&p, r), (c, _))) in pressures.iter().zip(results).zip(element).enumerate() {
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
                last.map(|j| (along(r.steps[j].shift_m) * 1e6, c.element_shear_pa[j] * f))
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
                .map(|(&p, (c, _))| (p / 1e6, f(c).abs().max(f64::MIN_POSITIVE)))
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
        ],
    )?;
    Ok(())
}
