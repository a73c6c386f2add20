//! `asperity surface …`: generate, analyse, convert and combine rough surfaces.

use asperity::surface::{self, GaussianSurfaceSpec};
use asperity::{Error, Result};
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(clap::Subcommand)]
pub enum SurfaceCommand {
    /// Gaussian-correlated periodic rough patch from profilometer statistics
    /// (defaults: the reference case Rq 0.177 µm, cl 6.6 µm, 250 µm, 1024², seed 1).
    Generate(Box<GenerateArgs>),
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
        s.validate()?;
        Ok(s)
    }
}

/// Read a surface spec from TOML (all fields required).
fn read_spec(path: &Path) -> Result<GaussianSurfaceSpec> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    toml::from_str(&text).map_err(|e| {
        let line = e
            .span()
            .map(|r| text[..r.start].matches('\n').count() + 1)
            .unwrap_or(0);
        Error::parse(path, line, e.message().to_string())
    })
}

pub fn run(cmd: SurfaceCommand) -> Result<()> {
    match cmd {
        SurfaceCommand::Generate(a) => generate(*a),
    }
}

fn generate(a: GenerateArgs) -> Result<()> {
    let spec = a.spec()?;
    for p in &a.out {
        surface::io::check_writable_format(p)?;
    }
    let t0 = Instant::now();
    let grid = surface::generate(&spec)?;
    let t_gen = t0.elapsed().as_secs_f64();
    for p in &a.out {
        surface::io::write(p, &grid)?;
    }
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
    for p in &a.out {
        println!("wrote {}", p.display());
    }
    Ok(())
}
