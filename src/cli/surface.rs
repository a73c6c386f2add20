//! `asperity surface …`: generate, analyse, convert and combine rough surfaces.

use asperity::core::output::OutputSet;
use asperity::core::plot::{line_plot, LinePlot, Scale, Series};
use asperity::surface::missing::{fill_topography, Fill, FillReport};
use asperity::surface::stats::Psd;
use asperity::surface::{self, Detrend, GaussianSurfaceSpec, SurfaceStats, Topography};
use asperity::{Error, Result};
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(clap::Subcommand)]
pub enum SurfaceCommand {
    /// Gaussian-correlated periodic rough patch from profilometer statistics
    /// (defaults: the reference case Rq 0.177 µm, cl 6.6 µm, 250 µm, 1024², seed 1).
    Generate(Box<GenerateArgs>),
    /// Statistics of a measured or generated topography (Ra, Rq, Rsk, Rku, rms slope/gradient,
    /// correlation lengths) and its power spectral density (CSV + PNG).
    Stats(StatsArgs),
    /// Two rough bodies reduced to one: equivalent surface (h1 - h2 on a common grid), equivalent
    /// statistics (Rq = √(Rq1² + Rq2²)) and composite modulus 1/E* = (1-ν1²)/E1 + (1-ν2²)/E2.
    Combine(CombineArgs),
    /// Convert a height map between formats (.npy, .x3p, .csv/.txt/.asc matrix, .png image).
    Convert(ConvertArgs),
    /// Self-affine (fractal) periodic rough patch: power-law PSD C(q) ∝ q^(−2(1+H)) between a
    /// roll-off and a cut-off wavelength, scaled to an rms gradient (defaults: the benchmark
    /// surface of the normal contact solver, H 0.8, rms gradient 0.1, 1 mm, 512², seed 1).
    SelfAffine(SelfAffineArgs),
}

#[derive(clap::Args)]
pub struct SelfAffineArgs {
    /// Hurst exponent H (0 < H < 1).
    #[arg(long, default_value_t = 0.8)]
    hurst: f64,
    /// RMS gradient [⟨|∇h|²⟩]^½ (-), from first differences as `surface stats` computes it.
    #[arg(long, default_value_t = 0.1)]
    rms_gradient: f64,
    /// Square patch side (m).
    #[arg(long, default_value_t = 1e-3)]
    size_m: f64,
    /// Grid points per side.
    #[arg(long, default_value_t = 512)]
    n: usize,
    /// Roll-off wavelength (m); default a quarter of the patch.
    #[arg(long)]
    rolloff_wavelength_m: Option<f64>,
    /// Short-wavelength cut-off (m); default 16 grid spacings, or half the roll-off where that
    /// is not shorter than the roll-off (coarse grids: n ≤ 64 at the default roll-off).
    #[arg(long)]
    cutoff_wavelength_m: Option<f64>,
    /// Random seed (same seed ⇒ same surface, bit for bit).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Output files; the format follows the extension (.npy, .x3p, .csv, .png). Repeatable.
    #[arg(long = "out", short = 'o', default_values = ["self_affine.npy", "self_affine.png"])]
    out: Vec<PathBuf>,
}

#[derive(clap::Args)]
pub struct ConvertArgs {
    /// Input height map (any readable area format).
    input: PathBuf,
    /// Output file(s); the format follows the extension. Repeatable. All are written, or none.
    /// Missing points are kept (NaN; x3p validity mask) unless --fill is given.
    #[arg(long = "out", short = 'o', required = true)]
    out: Vec<PathBuf>,
    /// Fill missing points before writing: `harmonic` (Laplace interpolation) or `nearest`.
    #[arg(long)]
    fill: Option<Fill>,
    /// Remove the mean height (`mean`) or the least-squares plane (`plane`, fitted to the
    /// measured points, after --fill) before writing; without it the heights are written as
    /// read. A plane removed from one period of a periodic surface leaves a seam: the output is
    /// then non-periodic.
    #[arg(long)]
    detrend: Option<String>,
}

#[derive(clap::Args)]
pub struct CombineArgs {
    /// Height map of body 1 (any readable area format).
    #[arg(requires_all = ["surface2", "out"])]
    surface1: Option<PathBuf>,
    /// Height map of body 2 in the same frame (z from body 1 towards body 2), same grid.
    surface2: Option<PathBuf>,
    /// Output file(s) for the equivalent surface (.npy, .x3p, .csv, .png). Repeatable.
    #[arg(long = "out", short = 'o')]
    out: Vec<PathBuf>,
    /// RMS height of body 1 (m), for the equivalent statistics.
    #[arg(long, allow_hyphen_values = true, requires = "rq2_m")]
    rq1_m: Option<f64>,
    /// RMS height of body 2 (m).
    #[arg(long, allow_hyphen_values = true, requires = "rq1_m")]
    rq2_m: Option<f64>,
    /// RMS slope of body 1.
    #[arg(long, allow_hyphen_values = true, requires = "slope2")]
    slope1: Option<f64>,
    /// RMS slope of body 2.
    #[arg(long, allow_hyphen_values = true, requires = "slope1")]
    slope2: Option<f64>,
    /// Young's modulus of body 1 (Pa).
    #[arg(long, allow_hyphen_values = true, requires_all = ["nu1", "e2_pa", "nu2"])]
    e1_pa: Option<f64>,
    /// Poisson's ratio of body 1.
    #[arg(long, allow_hyphen_values = true, requires = "e1_pa")]
    nu1: Option<f64>,
    /// Young's modulus of body 2 (Pa).
    #[arg(long, allow_hyphen_values = true, requires = "e1_pa")]
    e2_pa: Option<f64>,
    /// Poisson's ratio of body 2.
    #[arg(long, allow_hyphen_values = true, requires = "e1_pa")]
    nu2: Option<f64>,
    /// Fill missing points of the surfaces first: `harmonic` or `nearest`.
    #[arg(long)]
    fill: Option<Fill>,
}

#[derive(clap::Args)]
pub struct StatsArgs {
    /// Topography file: .npy, .x3p, Dektak CSV export, height-matrix or profile text.
    file: PathBuf,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    json: bool,
    /// What to remove first: `mean` (default) or `plane` (least-squares plane / line).
    #[arg(long, default_value = "mean")]
    detrend: String,
    /// Also write the power spectral density: this CSV table and a log-log plot beside it
    /// (same name, extension .png). Without it no file is written.
    #[arg(long)]
    psd_out: Option<PathBuf>,
    /// Fill missing points first (`harmonic` or `nearest`); without it the statistics are
    /// computed over the measured points only (and no PSD can be written).
    #[arg(long)]
    fill: Option<Fill>,
}

#[derive(clap::Args)]
pub struct GenerateArgs {
    /// TOML file with the fields of the surface spec (rq_m, clx_m, cly_m, lx_m, ly_m, nx, ny,
    /// seed); flags given on the command line override it.
    #[arg(long)]
    config: Option<PathBuf>,
    /// RMS height Rq (m).
    #[arg(long, allow_hyphen_values = true)]
    rq_m: Option<f64>,
    /// Isotropic 1/e correlation length (m); sets both --clx-m and --cly-m.
    #[arg(long, allow_hyphen_values = true, conflicts_with_all = ["clx_m", "cly_m"])]
    cl_m: Option<f64>,
    /// 1/e correlation length along x (m).
    #[arg(long, allow_hyphen_values = true)]
    clx_m: Option<f64>,
    /// 1/e correlation length along y (m).
    #[arg(long, allow_hyphen_values = true)]
    cly_m: Option<f64>,
    /// Square patch side (m); sets both --lx-m and --ly-m.
    #[arg(long, allow_hyphen_values = true, conflicts_with_all = ["lx_m", "ly_m"])]
    size_m: Option<f64>,
    /// Patch size along x (m).
    #[arg(long, allow_hyphen_values = true)]
    lx_m: Option<f64>,
    /// Patch size along y (m).
    #[arg(long, allow_hyphen_values = true)]
    ly_m: Option<f64>,
    /// Grid points per side (square grid); sets both --nx and --ny.
    #[arg(long, conflicts_with_all = ["nx", "ny"])]
    n: Option<usize>,
    /// Grid points along x.
    #[arg(long)]
    nx: Option<usize>,
    /// Grid points along y.
    #[arg(long)]
    ny: Option<usize>,
    /// Random seed (same seed ⇒ same surface, bit for bit).
    #[arg(long)]
    seed: Option<u64>,
    /// Output files; the format follows the extension (.npy, .x3p, .csv, .png). Repeatable.
    /// All are written, or none.
    #[arg(long = "out", short = 'o', default_values = ["surface.npy", "surface.png"])]
    out: Vec<PathBuf>,
}

impl GenerateArgs {
    /// Reference case, then the config file, then the flags.
    fn spec(&self) -> Result<GaussianSurfaceSpec> {
        let mut s = match &self.config {
            Some(p) => read_spec(p)?,
            None => GaussianSurfaceSpec::reference(),
        };
        let set = |dst: &mut f64, v: Option<f64>| {
            if let Some(v) = v {
                *dst = v;
            }
        };
        set(&mut s.rq_m, self.rq_m);
        set(&mut s.clx_m, self.cl_m.or(self.clx_m));
        set(&mut s.cly_m, self.cl_m.or(self.cly_m));
        set(&mut s.lx_m, self.size_m.or(self.lx_m));
        set(&mut s.ly_m, self.size_m.or(self.ly_m));
        if let Some(n) = self.n.or(self.nx) {
            s.nx = n;
        }
        if let Some(n) = self.n.or(self.ny) {
            s.ny = n;
        }
        if let Some(seed) = self.seed {
            s.seed = seed;
        }
        s.validate().map_err(|e| self.name_source(e))?;
        // Refused before the noise and its transforms are allocated.
        let grid_flag = if self.n.is_some() {
            "--n".to_string()
        } else if self.nx.is_some() || self.ny.is_some() {
            "--nx × --ny".to_string()
        } else if let Some(c) = &self.config {
            format!("{} (nx × ny)", c.display())
        } else {
            "--n".to_string()
        };
        asperity::core::limits::check_grid(
            &grid_flag,
            s.nx,
            s.ny,
            asperity::core::limits::GENERATE_BYTES_PER_POINT,
        )?;
        Ok(s)
    }

    /// Name the flag (or the config file) of a parameter error of the spec.
    fn name_source(&self, e: Error) -> Error {
        let Error::InvalidParameter { name, message } = e else {
            return e;
        };
        let own = format!("--{}", name.replace('_', "-"));
        let (flag, given) = match name.as_str() {
            "rq_m" => (own, self.rq_m.is_some()),
            "clx_m" | "cly_m" if self.cl_m.is_some() => ("--cl-m".to_string(), true),
            "clx_m" => (own, self.clx_m.is_some()),
            "cly_m" => (own, self.cly_m.is_some()),
            "lx_m" | "ly_m" if self.size_m.is_some() => ("--size-m".to_string(), true),
            "lx_m" => (own, self.lx_m.is_some()),
            "ly_m" => (own, self.ly_m.is_some()),
            "nx" | "ny" if self.n.is_some() => ("--n".to_string(), true),
            "nx" => (own, self.nx.is_some()),
            "ny" => (own, self.ny.is_some()),
            _ => (own, false),
        };
        match (&self.config, given) {
            (Some(c), false) => Error::parse(c, 0, format!("invalid `{name}`: {message}")),
            _ => Error::param(flag, message),
        }
    }
}

/// Read a surface spec from TOML (all fields required).
fn read_spec(path: &Path) -> Result<GaussianSurfaceSpec> {
    asperity::core::limits::check_file_size(path, asperity::core::limits::MAX_TEXT_FILE_BYTES)?;
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    toml::from_str(&text).map_err(|e| {
        let line = e
            .span()
            .map(|r| text[..r.start].matches('\n').count() + 1)
            .unwrap_or(0);
        Error::parse(path, line, e.message().to_string())
    })
}

use super::spinner;

pub fn run(cmd: SurfaceCommand) -> Result<()> {
    match cmd {
        SurfaceCommand::Generate(a) => generate(*a),
        SurfaceCommand::Stats(a) => stats(a),
        SurfaceCommand::Combine(a) => combine(a),
        SurfaceCommand::Convert(a) => convert(a),
        SurfaceCommand::SelfAffine(a) => self_affine(a),
    }
}

fn self_affine(a: SelfAffineArgs) -> Result<()> {
    let benchmark = surface::SelfAffineSpec::benchmark(a.n.max(1), a.size_m, a.seed);
    let rolloff = a
        .rolloff_wavelength_m
        .unwrap_or(benchmark.rolloff_wavelength_m);
    // The benchmark's cut-off (16 spacings) where it lies below the roll-off; on coarser grids
    // half the roll-off, so that the defaults give a spectrum on every grid that can hold one.
    let default_cutoff = if benchmark.cutoff_wavelength_m < rolloff {
        benchmark.cutoff_wavelength_m
    } else {
        0.5 * rolloff
    };
    let spec = surface::SelfAffineSpec {
        hurst: a.hurst,
        rms_gradient: a.rms_gradient,
        rolloff_wavelength_m: rolloff,
        cutoff_wavelength_m: a.cutoff_wavelength_m.unwrap_or(default_cutoff),
        ..benchmark
    };
    let spec = surface::SelfAffineSpec {
        nx: a.n,
        ny: a.n,
        ..spec
    };
    spec.validate().map_err(|e| {
        let flag = flag_of(&e);
        // A wavelength the user did not give is a default that the grid cannot hold: the
        // grid (--n, --size-m) is what to change, or the wavelength to give.
        let given = match flag.as_str() {
            "--rolloff-wavelength-m" => a.rolloff_wavelength_m.is_some(),
            "--cutoff-wavelength-m" => a.cutoff_wavelength_m.is_some(),
            _ => true,
        };
        match e {
            Error::InvalidParameter { message, .. } if !given => Error::param(
                "--n",
                format!(
                    "{} points over {:e} m are too few for the default spectrum (roll-off a \
                     quarter of the patch, cut-off 16 spacings or half the roll-off): the \
                     default {} {message}; give more points, or {flag}",
                    a.n,
                    a.size_m,
                    if flag.starts_with("--rolloff") {
                        "roll-off wavelength"
                    } else {
                        "cut-off wavelength"
                    }
                ),
            ),
            e => super::rename_param(e, &flag),
        }
    })?;
    for p in &a.out {
        surface::io::check_writable_format(p)?;
    }
    let t0 = Instant::now();
    let grid = surface::generate_self_affine(&spec)?;
    let t_gen = t0.elapsed().as_secs_f64();
    let title = format!(
        "self-affine: H {}, rms gradient {}, seed {}",
        spec.hurst, spec.rms_gradient, spec.seed
    );
    for p in &a.out {
        if p.extension().is_some_and(|e| e.eq_ignore_ascii_case("png")) {
            surface::io::png::write(p, &grid, &title)?;
        } else {
            surface::io::write(p, &grid)?;
        }
    }
    println!(
        "generated {n}×{n} self-affine patch {:.4e} m (dx {:.4e} m), H {}, rms gradient {}, \
         roll-off {:.4e} m, cut-off {:.4e} m, seed {}, periodic, in {t_gen:.3} s",
        spec.lx_m,
        spec.dx(),
        spec.hurst,
        spec.rms_gradient,
        spec.rolloff_wavelength_m,
        spec.cutoff_wavelength_m,
        spec.seed,
        n = spec.nx
    );
    for p in &a.out {
        println!("wrote {}", p.display());
    }
    Ok(())
}

/// The command-line flag of a [`surface::SelfAffineSpec`] field named in an error.
fn flag_of(e: &Error) -> String {
    match e {
        Error::InvalidParameter { name, .. } => match name.as_str() {
            "lx_m" | "ly_m" => "--size-m".into(),
            "nx" | "ny" => "--n".into(),
            other => format!("--{}", other.replace('_', "-")),
        },
        _ => String::new(),
    }
}

fn generate(a: GenerateArgs) -> Result<()> {
    let spec = a.spec()?;
    for p in &a.out {
        surface::io::check_writable_format(p).map_err(|e| super::rename_param(e, "--out"))?;
    }
    let mut out = OutputSet::for_files(&a.out, "--out")?;
    out.inputs(&a.config, "--config")?;
    let pb = spinner(&format!("generating {}×{} patch", spec.nx, spec.ny));
    let t0 = Instant::now();
    let grid = surface::generate(&spec)?;
    let t_gen = t0.elapsed().as_secs_f64();
    let swapped = surface::generate::GaussianSurfaceSpec {
        clx_m: spec.cly_m,
        cly_m: spec.clx_m,
        lx_m: spec.ly_m,
        ly_m: spec.lx_m,
        nx: spec.ny,
        ny: spec.nx,
        ..spec
    };
    for (axis, s, cl) in [("x", &spec, spec.clx_m), ("y", &swapped, spec.cly_m)] {
        let expected = surface::generate::expected_correlation_length_x(s);
        if expected.is_none_or(|e| e < 0.98 * cl) {
            eprintln!(
                "note: the patch holds few correlation lengths along {axis}: the generated \
                 surface's expected 1/e correlation length there is {} of the requested {cl:.4e} m \
                 (the mean wave is removed and periodic images add); enlarge the patch for the \
                 requested autocorrelation",
                expected.map_or("beyond half the patch".to_string(), |e| format!(
                    "{:.3e} m, {:.1} %",
                    e,
                    100.0 * e / cl
                ))
            );
        }
    }
    pb.set_message("writing");
    let title = format!(
        "generated: Rq {:.3} µm, cl {:.2} × {:.2} µm, seed {}",
        spec.rq_m * 1e6,
        spec.clx_m * 1e6,
        spec.cly_m * 1e6,
        spec.seed
    );
    for p in &a.out {
        let staged = out.file(p, "--out")?;
        if p.extension().is_some_and(|e| e.eq_ignore_ascii_case("png")) {
            surface::io::png::write(&staged, &grid, &title)?;
        } else {
            surface::io::write(&staged, &grid)?;
        }
    }
    let written = out.commit()?;
    pb.finish_and_clear();
    println!(
        "generated {}×{} patch {:.4e} m × {:.4e} m (dx {:.4e} m, dy {:.4e} m), Rq {:.6e} m, \
         clx {:.4e} m, cly {:.4e} m, seed {}, periodic, in {:.3} s",
        spec.nx,
        spec.ny,
        spec.lx_m,
        spec.ly_m,
        spec.dx(),
        spec.dy(),
        spec.rq_m,
        spec.clx_m,
        spec.cly_m,
        spec.seed,
        t_gen
    );
    for p in written {
        println!("wrote {}", p.display());
    }
    Ok(())
}

/// Read a topography and fill its missing points when asked; errors name the file.
fn read_filled(file: &Path, fill: Option<Fill>) -> Result<(Topography, Option<FillReport>)> {
    let topo = surface::io::read(file)?;
    match fill {
        Some(f) => fill_topography(topo, f).map_err(|e| e.in_file(file)),
        None => Ok((topo, None)),
    }
}

fn stats(a: StatsArgs) -> Result<()> {
    let detrend: Detrend = a
        .detrend
        .parse()
        .map_err(|e| super::rename_param(e, "--detrend"))?;
    let psd_paths = match &a.psd_out {
        Some(csv) => {
            if csv.extension().is_none_or(|e| e != "csv") {
                return Err(Error::param(
                    "--psd-out",
                    format!("must end in .csv, got {}", csv.display()),
                ));
            }
            Some((csv.clone(), csv.with_extension("png")))
        }
        None => None,
    };
    let mut out = match &psd_paths {
        Some((csv, png)) => {
            let mut set = OutputSet::for_files(&[csv.clone(), png.clone()], "--psd-out")?;
            super::surface_inputs(&mut set, std::slice::from_ref(&a.file), "the topography")?;
            Some(set)
        }
        None => None,
    };
    let pb = spinner(&format!("reading {}", a.file.display()));
    let t0 = Instant::now();
    let (topo, fill) = read_filled(&a.file, a.fill)?;
    let t_read = t0.elapsed().as_secs_f64();
    if let Some(r) = &fill {
        eprintln!("{}: {}", a.file.display(), r.describe());
    }
    pb.set_message("statistics and PSD");
    let t1 = Instant::now();
    let s = surface::stats(&topo, detrend).map_err(|e| e.in_file(&a.file))?;
    let psd = match &psd_paths {
        Some(_) if topo.missing() > 0 => {
            return Err(Error::param(
                "--psd-out",
                format!(
                    "{} has {} missing points and the power spectrum needs every point: add \
                     --fill harmonic or --fill nearest",
                    a.file.display(),
                    topo.missing()
                ),
            ))
        }
        Some(_) => {
            Some(surface::stats::power_spectrum(&topo, detrend).map_err(|e| e.in_file(&a.file))?)
        }
        None => None,
    };
    let t_stats = t1.elapsed().as_secs_f64();
    if let (Some((csv, png)), Some(psd), Some(set)) = (&psd_paths, &psd, out.as_mut()) {
        let (c, p) = (set.file(csv, "--psd-out")?, set.file(png, "--psd-out")?);
        write_psd(&c, &p, &a.file, psd, detrend)?;
    }
    if let Some(set) = out {
        set.commit()?;
    }
    pb.finish_and_clear();
    if a.json {
        let mut v = serde_json::to_value(&s).map_err(|e| Error::Data(e.to_string()))?;
        if let Some(o) = v.as_object_mut() {
            o.insert("file".into(), a.file.display().to_string().into());
            if let Some((csv, png)) = &psd_paths {
                o.insert("psd_csv".into(), csv.display().to_string().into());
                o.insert("psd_png".into(), png.display().to_string().into());
            }
            if let Some(r) = &fill {
                o.insert(
                    "fill".into(),
                    serde_json::to_value(r).map_err(|e| Error::Data(e.to_string()))?,
                );
            }
            o.insert("read_time_s".into(), t_read.into());
            o.insert("stats_time_s".into(), t_stats.into());
        }
        println!(
            "{}",
            serde_json::to_string_pretty(&v).map_err(|e| Error::Data(e.to_string()))?
        );
    } else {
        print_stats_table(&a.file, &s);
        if let Some((csv, png)) = &psd_paths {
            println!("PSD: {} and {}", csv.display(), png.display());
        }
        println!("read {t_read:.3} s, statistics {t_stats:.3} s");
    }
    Ok(())
}

fn opt(v: Option<f64>, unit: &str) -> String {
    v.map(|x| format!("{x:.6e}{unit}"))
        .unwrap_or_else(|| "—".into())
}

fn print_stats_table(file: &Path, s: &SurfaceStats) {
    let shape = if s.kind == "area" {
        format!(
            "{} × {} points, {:.4e} m × {:.4e} m",
            s.nx,
            s.ny,
            s.lx_m,
            s.ly_m.unwrap_or(0.0)
        )
    } else {
        format!(
            "{} points over {:.4e} m ({})",
            s.nx,
            s.lx_m,
            if s.uniform { "uniform" } else { "nonuniform" }
        )
    };
    println!(
        "{}: {} {shape}, periodic {}, detrend {}",
        file.display(),
        s.kind,
        s.periodic,
        match s.detrend {
            Detrend::Mean => "mean",
            Detrend::Plane => "plane",
        }
    );
    if s.missing_points > 0 {
        println!(
            "  missing points         {} of {} (statistics over the measured points)",
            s.missing_points,
            s.nx * s.ny
        );
    }
    println!("  Ra                     {:.6e} m", s.ra_m);
    println!("  Rq (rms height)        {:.6e} m", s.rq_m);
    println!("  Rsk                    {:.6}", s.rsk);
    println!("  Rku                    {:.6}", s.rku);
    println!("  rms slope (x)          {:.6e}", s.rms_slope);
    if s.kind == "area" {
        println!("  rms slope (y)          {}", opt(s.rms_slope_y, ""));
        println!("  rms gradient           {}", opt(s.rms_gradient, ""));
    }
    println!(
        "  correlation length 1/e {}",
        opt(s.correlation_length_1_over_e_m, " m")
    );
    println!(
        "  correlation length 0.2 {}",
        opt(s.correlation_length_0_2_m, " m")
    );
    if s.kind == "area" {
        println!(
            "  corr. length 1/e along x {}",
            opt(s.correlation_length_x_1_over_e_m, " m")
        );
        println!(
            "  corr. length 1/e along y {}",
            opt(s.correlation_length_y_1_over_e_m, " m")
        );
    }
}

/// PSD as CSV (with a header naming source, detrending and units) and a log-log PNG.
fn write_psd(csv: &Path, png: &Path, source: &Path, psd: &Psd, detrend: Detrend) -> Result<()> {
    use std::fmt::Write as _;
    let (col, unit) = if psd.dim == 1 {
        ("psd_m3", "m³")
    } else {
        ("psd_m4", "m⁴")
    };
    let mut text = String::new();
    let _ = writeln!(
        text,
        "# power spectral density of {} ({}, detrend {}); q angular wavenumber",
        source.display(),
        if psd.dim == 1 {
            "1-D profile"
        } else {
            "2-D, radially averaged"
        },
        match detrend {
            Detrend::Mean => "mean",
            Detrend::Plane => "plane",
        }
    );
    let _ = writeln!(text, "q_rad_per_m,{col},count");
    for ((q, c), n) in psd.q.iter().zip(&psd.c).zip(&psd.count) {
        let _ = writeln!(text, "{q:e},{c:e},{n}");
    }
    asperity::core::output::write_string_atomic(csv, &text)?;
    // The plot shows 12 decades below the peak; lower values are FFT round-off.
    let c_max = psd.c.iter().cloned().fold(0.0, f64::max);
    let points: Vec<(f64, f64)> = psd
        .q
        .iter()
        .zip(&psd.c)
        .filter(|(q, c)| **q > 0.0 && **c > 1e-12 * c_max)
        .map(|(q, c)| (q.log10(), c.log10()))
        .collect();
    let title = format!(
        "PSD of {}",
        source
            .file_name()
            .map(|f| f.to_string_lossy())
            .unwrap_or_default()
    );
    // Decimal logarithms on linear axes: readable labels over the many decades a PSD spans.
    let y_label = format!("log10 C(q) ({unit})");
    line_plot(
        png,
        &LinePlot {
            title: &title,
            x_label: "log10 q (rad/m)",
            y_label: &y_label,
            x_scale: Scale::Linear,
            y_scale: Scale::Linear,
        },
        &[Series::line("PSD", points)],
    )
}

fn combine(a: CombineArgs) -> Result<()> {
    use asperity::core::material::{composite_modulus, Material};
    use asperity::surface::combine::{equivalent_rms_slope, equivalent_rq, equivalent_surface};
    if a.surface1.is_none() && a.rq1_m.is_none() && a.slope1.is_none() && a.e1_pa.is_none() {
        return Err(Error::param(
            "combine",
            "give two surfaces (SURFACE1 SURFACE2 --out FILE), or --rq1-m/--rq2-m, \
             --slope1/--slope2, --e1-pa/--nu1/--e2-pa/--nu2",
        ));
    }
    // Everything is computed and checked before any file is written.
    let rq = match (a.rq1_m, a.rq2_m) {
        (Some(r1), Some(r2)) => Some(equivalent_rq(r1, r2)?),
        _ => None,
    };
    let slope = match (a.slope1, a.slope2) {
        (Some(m1), Some(m2)) => Some(equivalent_rms_slope(m1, m2)?),
        _ => None,
    };
    let e_star = match (a.e1_pa, a.nu1, a.e2_pa, a.nu2) {
        (Some(e1), Some(nu1), Some(e2), Some(nu2)) => Some(composite_modulus(
            Material {
                youngs_modulus_pa: e1,
                poisson_ratio: nu1,
            },
            Material {
                youngs_modulus_pa: e2,
                poisson_ratio: nu2,
            },
        )?),
        _ => None,
    };
    let mut out = None;
    let eq = match (&a.surface1, &a.surface2) {
        (Some(p1), Some(p2)) => {
            for p in &a.out {
                surface::io::check_writable_format(p)
                    .map_err(|e| super::rename_param(e, "--out"))?;
            }
            let mut set = OutputSet::for_files(&a.out, "--out")?;
            super::surface_inputs(&mut set, std::slice::from_ref(p1), "SURFACE1")?;
            super::surface_inputs(&mut set, std::slice::from_ref(p2), "SURFACE2")?;
            out = Some(set);
            let load = |p: &Path| -> Result<_> {
                let (g, r) = surface::missing::load_area(p, a.fill)?;
                if let Some(r) = r {
                    eprintln!("{}: {}", p.display(), r.describe());
                }
                Ok(g)
            };
            let g1 = load(p1)?;
            let g2 = load(p2)?;
            Some(equivalent_surface(&g1, &g2).map_err(|e| match e {
                Error::Data(m) => {
                    Error::Data(format!("{} and {}: {m}", p1.display(), p2.display()))
                }
                e => e,
            })?)
        }
        _ => None,
    };
    if let Some(v) = rq {
        println!("equivalent Rq          {v:.6e} m");
    }
    if let Some(v) = slope {
        println!("equivalent rms slope   {v:.6e}");
    }
    if let Some(v) = e_star {
        println!("composite modulus E*   {v:.6e} Pa");
    }
    if let (Some(g), Some(mut set)) = (eq, out) {
        let s = surface::stats(&surface::Topography::Area(g.clone()), Detrend::Mean)?;
        for p in &a.out {
            surface::io::write(&set.file(p, "--out")?, &g)?;
        }
        set.commit()?;
        println!(
            "equivalent surface {}×{}: Rq {:.6e} m, rms gradient {:.6e}",
            g.nx(),
            g.ny(),
            s.rq_m,
            s.rms_gradient.unwrap_or(f64::NAN)
        );
        for p in &a.out {
            println!("wrote {}", p.display());
        }
    }
    Ok(())
}

fn convert(a: ConvertArgs) -> Result<()> {
    for p in &a.out {
        surface::io::check_writable_format(p).map_err(|e| super::rename_param(e, "--out"))?;
    }
    let detrend: Option<Detrend> = a
        .detrend
        .as_deref()
        .map(str::parse)
        .transpose()
        .map_err(|e| super::rename_param(e, "--detrend"))?;
    let mut out = OutputSet::for_files(&a.out, "--out")?;
    super::surface_inputs(&mut out, std::slice::from_ref(&a.input), "the input")?;
    let (topo, fill) = read_filled(&a.input, a.fill)?;
    if let Topography::Profile(_) = topo {
        return Err(Error::Data(format!(
            "{}: a 1-D profile cannot be converted (the writers write height maps)",
            a.input.display()
        )));
    }
    let topo = match detrend {
        Some(d) => {
            let (levelled, removed) = surface::stats::detrend_topography(&topo, d);
            eprintln!("{}: {removed}", a.input.display());
            levelled
        }
        None => topo,
    };
    if let Some(r) = &fill {
        eprintln!("{}: {}", a.input.display(), r.describe());
    } else if topo.missing() > 0 {
        eprintln!(
            "{}: {} missing points kept (NaN; x3p validity mask; blank in PNG)",
            a.input.display(),
            topo.missing()
        );
    }
    let title = a
        .input
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    for p in &a.out {
        let staged = out.file(p, "--out")?;
        match (
            &topo,
            p.extension().is_some_and(|e| e.eq_ignore_ascii_case("png")),
        ) {
            (Topography::Area(g), true) => surface::io::png::write(&staged, g, &title)?,
            _ => surface::io::write_topography(&staged, &topo)?,
        }
    }
    for p in out.commit()? {
        println!("wrote {}", p.display());
    }
    Ok(())
}
