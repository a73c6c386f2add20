//! `asperity film`: film image → pressure map, regions, polynomial fit, node preloads.

use asperity::core::output::write_string_atomic;
use asperity::core::plot::{heatmap, HeatMap};
use asperity::elements::{provenance_json, InputFile};
use asperity::film::colour::{
    ColourTable, ColourToPressure, DensityCalibration, DEFAULT_MAX_COLOUR_DISTANCE,
};
use asperity::film::nodes::{
    preloads, read_nodes_csv, write_preloads_csv, write_preloads_csv_with_classes, Placement,
    Preload,
};
use asperity::film::polyfit::{self, PolyFit2};
use asperity::film::reduce::reduce;
use asperity::film::regions::{
    detect_below_range, detect_patches_with, roi_region, summarise, write_region_pixels_csv,
    write_summary_csv, FilmMap, PatchOptions, Region, Roi, DEFAULT_MAX_ELONGATION,
    DEFAULT_MIN_SOLIDITY, DEFAULT_RIM_PIXELS,
};
use asperity::film::scan::{self, Channel};
use asperity::film::{FittedRegion, NodePixel};
use asperity::{Error, Result};
use ndarray::Array2;
use std::path::{Path, PathBuf};

/// Pressure-measurement film → pressure map (Pa), regions, order-n polynomial fit, preloads.
///
/// Film frame: x to the right, y upwards, metres, origin at the centre of the image's bottom-left
/// pixel. Without --roi-rect-mm / --roi-polygon-mm, round patches are detected automatically.
#[derive(clap::Args)]
pub struct FilmArgs {
    #[command(flatten)]
    opts: Box<FilmOptions>,
}

/// The flags of `asperity film` (boxed in [`FilmArgs`] to keep the CLI's command enum small).
#[derive(clap::Args)]
pub struct FilmOptions {
    /// Film image (PNG, JPEG or TIFF; 8 or 16 bit).
    #[arg(long)]
    image: PathBuf,
    /// Pixel size in mm (square pixels). Default: from the resolution the image declares
    /// (PNG pHYs, TIFF XResolution, JPEG JFIF dpi); an error when it declares none.
    #[arg(long, allow_hyphen_values = true)]
    pixel_size_mm: Option<f64>,
    /// Colour table CSV (pressure, R, G, B; vendor format in MPa).
    #[arg(
        long,
        conflicts_with = "density_calibration",
        required_unless_present = "density_calibration"
    )]
    colour_table: Option<PathBuf>,
    /// Off-curve rejection distance in RGB units (0–255, Euclidean).
    #[arg(long, default_value_t = DEFAULT_MAX_COLOUR_DISTANCE)]
    max_colour_distance: f64,
    /// Density calibration CSV (density,pressure_MPa) for raw scans, instead of a colour table.
    #[arg(long)]
    density_calibration: Option<PathBuf>,
    /// Channel the density is read in (density mode): luma, red, green, blue, or complement
    /// (the channel in which the stain, --stain-rgb, is darkest: green for a magenta-red stain).
    #[arg(long, default_value = "luma", requires = "density_calibration")]
    channel: String,
    /// Colour of the stain `R,G,B` (0–255) in density mode: selects --channel complement, and
    /// makes pixels of another hue (black or blue pen ink) off-curve instead of stain.
    #[arg(long, value_delimiter = ',', requires = "density_calibration")]
    stain_rgb: Option<Vec<f64>>,
    /// Density of unstained paper (density mode): at or below it a pixel is unstained, above it
    /// and below the first calibration point below range. Default: estimated from the scan
    /// (mode of the density histogram + 5 × its noise).
    #[arg(long, requires = "density_calibration", allow_hyphen_values = true)]
    unstained_density: Option<f64>,
    /// Gaussian smoothing of the image before it is read, standard deviation in mm (against
    /// scanner speckle). Default: none.
    #[arg(long, allow_hyphen_values = true)]
    smooth_mm: Option<f64>,
    /// Rectangular region of interest `x0,y0,x1,y1` in mm (film frame).
    #[arg(
        long,
        value_delimiter = ',',
        conflicts_with = "roi_polygon_mm",
        allow_hyphen_values = true
    )]
    roi_rect_mm: Option<Vec<f64>>,
    /// Polygonal region of interest `x,y;x,y;...` in mm (film frame, at least 3 vertices).
    #[arg(long, allow_hyphen_values = true)]
    roi_polygon_mm: Option<String>,
    /// Smallest equivalent diameter (mm) of an automatically detected patch.
    #[arg(long, default_value_t = 2.0)]
    min_patch_diameter_mm: f64,
    /// Width (pixels) of the stained below-range rim joined to a detected patch.
    #[arg(long, default_value_t = DEFAULT_RIM_PIXELS)]
    rim_pixels: usize,
    /// Largest elongation (ratio of principal axes) of a detected patch: longer shapes are
    /// rejected as pen strokes or tape edges.
    #[arg(long, default_value_t = DEFAULT_MAX_ELONGATION)]
    max_elongation: f64,
    /// Smallest solidity (stained pixels / convex hull area) of a detected patch: hollower
    /// shapes are rejected as handwriting and labels.
    #[arg(long, default_value_t = DEFAULT_MIN_SOLIDITY)]
    min_solidity: f64,
    /// Order of the 2-D polynomial fitted to each region's in-range pressures.
    #[arg(long, default_value_t = 4)]
    fit_order: usize,
    /// Contact nodes CSV (id,x_m,y_m[,area_m2]) to preload from the fitted pressure.
    #[arg(long)]
    nodes: Option<PathBuf>,
    /// Region whose fit preloads the nodes (required when several regions exist).
    #[arg(long)]
    nodes_region: Option<usize>,
    /// Node placement offset `x,y` in mm (mesh frame → film frame).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    node_offset_mm: Option<Vec<f64>>,
    /// Node placement rotation in degrees (counter-clockwise).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    node_rotation_deg: f64,
    /// Node placement scale (mesh length → film length).
    #[arg(long, default_value_t = 1.0)]
    node_scale: f64,
    /// Rescale preloads so that they sum to this total normal load (N).
    #[arg(long)]
    total_load_n: Option<f64>,
    /// Reduce the nodes on a coarse triangular mesh of this side (mm).
    #[arg(long)]
    reduce_mesh_size_mm: Option<f64>,
    /// Output directory.
    #[arg(long)]
    out_dir: PathBuf,
}

fn parse_polygon(s: &str) -> Result<Vec<(f64, f64)>> {
    s.split(';')
        .filter(|v| !v.trim().is_empty())
        .map(|v| {
            let xy: Vec<&str> = v.split(',').map(str::trim).collect();
            let num = |t: &str| {
                t.parse::<f64>()
                    .map_err(|_| Error::param("--roi-polygon-mm", format!("`{t}` is not a number")))
            };
            if xy.len() != 2 {
                return Err(Error::param(
                    "--roi-polygon-mm",
                    format!("vertex `{v}` is not `x,y`"),
                ));
            }
            Ok((num(xy[0])? * 1e-3, num(xy[1])? * 1e-3))
        })
        .collect()
}

fn plot_region(
    path: &Path,
    map: &FilmMap,
    region: &Region,
    value: impl Fn(usize, usize) -> f64,
    title: &str,
    label: &str,
) -> Result<()> {
    let i0 = region.pixels.iter().map(|p| p.0).min().unwrap_or(0);
    let i1 = region.pixels.iter().map(|p| p.0).max().unwrap_or(0);
    let j0 = region.pixels.iter().map(|p| p.1).min().unwrap_or(0);
    let j1 = region.pixels.iter().map(|p| p.1).max().unwrap_or(0);
    let mut f = Array2::from_elem((i1 - i0 + 1, j1 - j0 + 1), f64::NAN);
    for &(i, j) in &region.pixels {
        f[[i - i0, j - j0]] = value(i, j);
    }
    let s = map.pixel_size_m;
    heatmap(
        path,
        &f,
        s,
        s,
        &HeatMap {
            title,
            value_label: label,
            value_scale: 1e-6,
            length_scale: 1e3,
            length_unit: "mm (from region corner)",
        },
    )
}

/// A region-of-interest error named by its flag.
fn roi_error(e: Error, flag: &str) -> Error {
    match e {
        Error::InvalidParameter { message, .. } | Error::Data(message) => {
            Error::param(flag, message)
        }
        other => other,
    }
}

/// The channel of `--channel` (with `--stain-rgb` for `complement`).
fn channel_from_flags(name: &str, stain: Option<&[f64]>) -> Result<Channel> {
    Ok(match name {
        "luma" => Channel::Luma,
        "red" => Channel::Red,
        "green" => Channel::Green,
        "blue" => Channel::Blue,
        "complement" => {
            let s = stain.ok_or_else(|| {
                Error::param(
                    "--channel",
                    "`complement` needs the stain's colour: give --stain-rgb R,G,B",
                )
            })?;
            if s.len() != 3
                || s.iter()
                    .any(|v| !(v.is_finite() && (0.0..=255.0).contains(v)))
            {
                return Err(Error::param(
                    "--stain-rgb",
                    "needs three values R,G,B in 0–255",
                ));
            }
            Channel::complement_of([s[0], s[1], s[2]])
        }
        other => {
            return Err(Error::param(
                "--channel",
                format!("expected luma, red, green, blue or complement, got `{other}`"),
            ))
        }
    })
}

/// Largest Euclidean distance between two colours of the 0–255 RGB cube, black to white
/// (255·√3): a larger --max-colour-distance would reject nothing, so pen marks, tape and dirt
/// would all be read as pressure.
const MAX_RGB_DISTANCE: f64 = 441.672_955_930_063_7;

/// The numeric flags, checked before any work so that errors name the flag (the library
/// functions check them again under their own names).
fn check_flags(a: &FilmOptions) -> Result<()> {
    let d = a.max_colour_distance;
    if !(d.is_finite() && d > 0.0 && d <= MAX_RGB_DISTANCE) {
        return Err(Error::param(
            "--max-colour-distance",
            format!(
                "must be > 0 and at most 255·√3 ≈ 441.7 RGB units (black to white), got {}",
                asperity::core::error::num(d)
            ),
        ));
    }
    // A preload rescaled to a non-positive total would pull the joint apart.
    if let Some(f) = a.total_load_n {
        asperity::core::error::require_positive("--total-load-n", f)?;
    }
    // Mesh lengths map onto film lengths: a zero or negative scale mirrors or collapses the mesh.
    asperity::core::error::require_positive("--node-scale", a.node_scale)?;
    asperity::core::error::require_finite("--node-rotation-deg", a.node_rotation_deg)?;
    if let Some(off) = &a.node_offset_mm {
        if off.len() != 2 {
            return Err(Error::param(
                "--node-offset-mm",
                format!("needs 2 values x,y, got {}", off.len()),
            ));
        }
        for v in off {
            asperity::core::error::require_finite("--node-offset-mm", *v)?;
        }
    }
    Ok(())
}

/// A fitted region more than this share of whose pressure-bearing pixels is above the film's
/// range (saturated) is named in a warning beside its R².
const SATURATED_WARNING_FRACTION: f64 = 0.01;

/// Count the nodes by the film pixel under them, warn about those on saturated or below-range
/// pixels (where the fit, made from in-range pixels, reads anything: a 6 MPa fit where the film
/// says ≥ 9.06 MPa) and on holes; the counts and the fit's readings per class for film.json.
fn node_pixel_report(
    pre: &[Preload],
    classes: &[NodePixel],
    fit: &PolyFit2,
    lo: f64,
    hi: f64,
) -> serde_json::Value {
    let fitted = |c: NodePixel| -> Vec<f64> {
        pre.iter()
            .zip(classes)
            .filter(|(_, k)| **k == c)
            .map(|(p, _)| fit.eval(p.x_m, p.y_m))
            .collect()
    };
    let span = |v: &[f64]| {
        v.iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            })
    };
    let mut json = serde_json::Map::new();
    for c in NodePixel::ALL {
        let v = fitted(c);
        let (a, b) = span(&v);
        json.insert(
            c.name().to_string(),
            serde_json::json!({
                "n_nodes": v.len(),
                "fitted_pressure_min_pa": (!v.is_empty()).then_some(a),
                "fitted_pressure_max_pa": (!v.is_empty()).then_some(b),
            }),
        );
        if v.is_empty() {
            continue;
        }
        match c {
            NodePixel::InRange => {}
            NodePixel::AboveRange => {
                let short = v.iter().filter(|&&p| p < hi).count();
                eprintln!(
                    "warning: {} nodes lie on pixels above the film's range (≥ {:.3} MPa), where \
                     the fit reads {:.2}–{:.2} MPa{}: the preload there is a lower bound at best; \
                     use a film of a higher range (pixel_class in preload.csv)",
                    v.len(),
                    hi / 1e6,
                    a / 1e6,
                    b / 1e6,
                    if short > 0 {
                        format!(
                            " ({short} of them below the range's top, by up to {:.2} MPa)",
                            (hi - a) / 1e6
                        )
                    } else {
                        String::new()
                    }
                );
            }
            NodePixel::BelowRange => {
                let over = v.iter().filter(|&&p| p >= lo).count();
                eprintln!(
                    "warning: {} nodes lie on stained pixels below the film's range (< {:.3} MPa), \
                     where the fit reads {:.2}–{:.2} MPa{}: the preload there is an upper bound at \
                     best; use a film of a lower range (pixel_class in preload.csv)",
                    v.len(),
                    lo / 1e6,
                    a / 1e6,
                    b / 1e6,
                    if over > 0 {
                        format!(
                            " ({over} of them at or above the range's bottom, by up to {:.2} MPa)",
                            (b - lo) / 1e6
                        )
                    } else {
                        String::new()
                    }
                );
            }
            NodePixel::Hole => {
                eprintln!(
                    "note: {} nodes lie on unstained or rejected pixels enclosed by the stain \
                     (holes: contact below the film's range, or ink), where the fit reads \
                     {:.2}–{:.2} MPa (pixel_class hole in preload.csv)",
                    v.len(),
                    a / 1e6,
                    b / 1e6
                );
            }
        }
    }
    serde_json::Value::Object(json)
}

/// The files of fixed name `asperity film` writes into --out-dir (some only with --nodes or
/// --reduce-mesh-size-mm); besides them, `region_<id>_fitted.png` and `region_<id>_residual.png`.
const FIXED_OUTPUTS: [&str; 9] = [
    "regions.csv",
    "pressure_map.csv",
    "pressure_map_Pa.npy",
    "pressure_map_Pa.npy.json",
    "pressure_map.png",
    "fit_coefficients.csv",
    "preload.csv",
    "preload_reduced.csv",
    "film.json",
];

pub fn run(args: FilmArgs) -> Result<()> {
    let args = *args.opts;
    check_flags(&args)?;
    // Refused now, before any work: an --out-dir that is a file or not writable.
    let mut out = asperity::core::output::OutputSet::in_dir(&args.out_dir, "--out-dir")?;
    // Every file film writes is its own: one of an earlier run into the same --out-dir that this
    // run does not write (a `preload_reduced.csv` of a run with --reduce-mesh-size-mm, the
    // plots of a region that no longer exists) is removed after the commit, so that no reader
    // (`asperity elements`) picks up a stale file.
    for name in FIXED_OUTPUTS {
        out.owns(name, "")?;
    }
    out.owns("region_", "_fitted.png")?;
    out.owns("region_", "_residual.png")?;
    // No output may be (or remove) one of the inputs.
    out.input(&args.image, "--image")?;
    out.inputs(&args.colour_table, "--colour-table")?;
    out.inputs(&args.density_calibration, "--density-calibration")?;
    out.inputs(&args.nodes, "--nodes")?;
    let (mut reader, table_path) = match (&args.colour_table, &args.density_calibration) {
        (Some(t), None) => (
            ColourToPressure::Table(ColourTable::read_csv(t, args.max_colour_distance)?),
            t.clone(),
        ),
        (None, Some(d)) => (
            ColourToPressure::Density(DensityCalibration::read_csv(d)?),
            d.clone(),
        ),
        _ => {
            return Err(Error::param(
                "--colour-table / --density-calibration",
                "give exactly one",
            ))
        }
    };
    let channel = channel_from_flags(&args.channel, args.stain_rgb.as_deref())?;
    let mut img = scan::read_rgb(&args.image)?;
    let (pixel_size_m, pixel_source) = match args.pixel_size_mm {
        Some(v) => (
            asperity::core::error::require_positive("--pixel-size-mm", v)? * 1e-3,
            "--pixel-size-mm".to_string(),
        ),
        None => match scan::resolution(&args.image)? {
            Some(r) => (
                r.pixel_size_m,
                format!(
                    "{} dpi declared by the image ({})",
                    asperity::core::error::num((r.dpi * 1e6).round() / 1e6),
                    r.source
                ),
            ),
            None => {
                return Err(Error::param(
                    "--pixel-size-mm",
                    format!(
                        "not given, and {} declares no resolution (dpi): give the pixel size",
                        args.image.display()
                    ),
                ))
            }
        },
    };
    asperity::core::sanity::film_pixel_size(pixel_size_m).map_err(|m| {
        if args.pixel_size_mm.is_some() {
            Error::param("--pixel-size-mm", m)
        } else {
            Error::param(
                "--pixel-size-mm",
                format!("not given, and the resolution {} declares ({pixel_source}) gives {m}: give the pixel size", args.image.display()),
            )
        }
    })?;
    let pixel_size_mm = pixel_size_m * 1e3;
    if let Some(s) = args.smooth_mm {
        asperity::core::error::require_positive("--smooth-mm", s)?;
        scan::smooth(&mut img, s / pixel_size_mm)
            .map_err(|e| super::rename_param(e, "--smooth-mm"))?;
    }
    // Density mode: the channel and the paper level.
    let mut paper = None;
    if let ColourToPressure::Density(d) = &mut reader {
        d.channel = channel;
        if let Some(st) = &args.stain_rgb {
            if st.len() != 3
                || st
                    .iter()
                    .any(|v| !(v.is_finite() && (0.0..=255.0).contains(v)))
            {
                return Err(Error::param(
                    "--stain-rgb",
                    "needs three values R,G,B in 0–255",
                ));
            }
            *d = d
                .clone()
                .with_stain([st[0], st[1], st[2]])
                .map_err(|e| super::rename_param(e, "--stain-rgb"))?;
        }
        let first = d.points[0].0;
        let level = match args.unstained_density {
            Some(u) => {
                asperity::core::error::require_finite("--unstained-density", u)?;
                if u > first {
                    return Err(Error::param(
                        "--unstained-density",
                        format!(
                            "{} exceeds the first calibration density {}: calibrated stain \
                             would read as paper",
                            asperity::core::error::num(u),
                            asperity::core::error::num(first)
                        ),
                    ));
                }
                u
            }
            None => {
                let (w, h) = img.dim();
                let p =
                    scan::paper_level((0..w * h).map(|k| channel.density(img.rgb(k % w, k / w))));
                paper = Some(p);
                p.stained_above.min(first)
            }
        };
        d.unstained_density = level;
        eprintln!(
            "density in the {} channel; unstained paper at or below density {:.4}{}",
            channel.name(),
            level,
            paper.map_or(String::new(), |p| format!(
                " (estimated: paper {:.4} ± {:.4})",
                p.density, p.noise
            ))
        );
    } else if args.channel != "luma" || args.unstained_density.is_some() {
        return Err(Error::param(
            "--channel",
            "a colour table reads the whole colour; --channel is for --density-calibration",
        ));
    }
    let map = FilmMap::from_image(&img, &reader, pixel_size_m)?;
    drop(img);
    let (nx, ny) = map.dim();
    let (lo, hi) = reader.range_pa();
    let all = map.class_counts();
    eprintln!(
        "{}: {nx} × {ny} px at {} mm ({pixel_source}); range {:.3}–{:.3} MPa; pixels in range {}, unstained {}, below range {}, above range {}, off-curve (rejected) {}",
        args.image.display(),
        asperity::core::error::num(pixel_size_mm),
        lo / 1e6,
        hi / 1e6,
        all.in_range,
        all.unstained,
        all.below_range,
        all.above_range,
        all.off_curve
    );
    if all.below_range > 0 {
        eprintln!(
            "note: {} pixels ({:.2} % of the image) are stained below the film's measuring range \
             (< {:.3} MPa): their pressure is unknown, they carry no pressure in the maps and fits",
            all.below_range,
            100.0 * all.below_range as f64 / all.total() as f64,
            lo / 1e6
        );
    }

    // Regions.
    let patch_options = PatchOptions {
        min_diameter_m: args.min_patch_diameter_mm * 1e-3,
        rim_pixels: args.rim_pixels,
        max_elongation: args.max_elongation,
        min_solidity: args.min_solidity,
    };
    let (regions, discarded, rejected_marks) = if let Some(r) = &args.roi_rect_mm {
        if r.len() != 4 {
            return Err(Error::param(
                "--roi-rect-mm",
                format!("needs 4 values x0,y0,x1,y1, got {}", r.len()),
            ));
        }
        let roi = Roi::Rectangle {
            x0: r[0] * 1e-3,
            y0: r[1] * 1e-3,
            x1: r[2] * 1e-3,
            y1: r[3] * 1e-3,
        };
        (
            vec![roi_region(&map, &roi, 1).map_err(|e| roi_error(e, "--roi-rect-mm"))?],
            0,
            0,
        )
    } else if let Some(p) = &args.roi_polygon_mm {
        (
            vec![roi_region(&map, &Roi::Polygon(parse_polygon(p)?), 1)
                .map_err(|e| roi_error(e, "--roi-polygon-mm"))?],
            0,
            0,
        )
    } else {
        let d = detect_patches_with(&map, &patch_options).map_err(|e| match e {
            Error::InvalidParameter { name, message } => Error::param(
                match name.as_str() {
                    "max_elongation" => "--max-elongation",
                    "min_solidity" => "--min-solidity",
                    _ => "--min-patch-diameter-mm",
                },
                message,
            ),
            other => other,
        })?;
        if d.rejected_marks > 0 {
            eprintln!(
                "{} components rejected by their shape as marks (elongation > {}, or solidity < {})",
                d.rejected_marks, args.max_elongation, args.min_solidity
            );
        }
        if d.patches.is_empty() {
            let below = detect_below_range(&map, &patch_options)?;
            if !below.patches.is_empty() {
                let diam: Vec<f64> = below
                    .patches
                    .iter()
                    .map(|r| {
                        (4.0 * r.pixels.len() as f64 / std::f64::consts::PI).sqrt() * pixel_size_mm
                    })
                    .collect();
                let (dmin, dmax) = diam
                    .iter()
                    .fold((f64::INFINITY, 0.0f64), |(a, b), &v| (a.min(v), b.max(v)));
                return Err(Error::Data(format!(
                    "{}: {} stained patches ({:.1}–{:.1} mm across) lie entirely below the film's \
                     measuring range (< {:.3} MPa): the contact pressure is below what this film \
                     measures; use a film grade with a lower range, or check the calibration",
                    args.image.display(),
                    below.patches.len(),
                    dmin,
                    dmax,
                    lo / 1e6
                )));
            }
            return Err(Error::Data(format!(
                "{}: no pressure patch of at least {} mm found ({} smaller components discarded, {} rejected as marks); check the colour table, --max-colour-distance or give a region of interest",
                args.image.display(),
                args.min_patch_diameter_mm,
                d.discarded_small,
                d.rejected_marks
            )));
        }
        (d.patches, d.discarded_small, d.rejected_marks)
    };
    // Stained patches entirely below the measuring range (not regions: no pressure is known).
    let mut below_range_patches = Vec::new();
    if args.roi_rect_mm.is_none() && args.roi_polygon_mm.is_none() {
        let taken: std::collections::HashSet<(usize, usize)> = regions
            .iter()
            .flat_map(|r| r.pixels.iter().copied())
            .collect();
        for r in detect_below_range(&map, &patch_options)?.patches {
            if r.pixels.iter().any(|p| taken.contains(p)) {
                continue;
            }
            let n = r.pixels.len() as f64;
            let (cx, cy) = r.pixels.iter().fold((0.0, 0.0), |(a, b), &(i, j)| {
                (a + i as f64 / n, b + j as f64 / n)
            });
            below_range_patches.push(serde_json::json!({
                "centre_x_m": cx * pixel_size_m,
                "centre_y_m": cy * pixel_size_m,
                "equivalent_diameter_m": (4.0 * n / std::f64::consts::PI).sqrt() * pixel_size_m,
            }));
        }
        if !below_range_patches.is_empty() {
            eprintln!(
                "note: {} stained components of at least {} mm lie entirely below the film's \
                 measuring range (< {:.3} MPa): patches loaded below the range, or tape and \
                 marks; no pressure is known there (centres and sizes in film.json, \
                 `below_range_patches`)",
                below_range_patches.len(),
                args.min_patch_diameter_mm,
                lo / 1e6
            );
        }
    }

    // Fits and summaries: a region that cannot be fitted is skipped with a warning, the others
    // are written.
    let mut fits: Vec<Option<PolyFit2>> = Vec::new();
    let mut summaries = Vec::new();
    let mut skipped: Vec<serde_json::Value> = Vec::new();
    for r in &regions {
        let s = summarise(&map, r)?;
        let pts = map.pressure_points(&r.pixels);
        let fit = if pts.is_empty() {
            Err(format!(
                "no in-range pixel (of {}: {} below range, {} above range, {} unstained, {} rejected colours)",
                r.pixels.len(),
                s.counts.below_range,
                s.counts.above_range,
                s.counts.unstained,
                s.counts.off_curve
            ))
        } else {
            polyfit::fit(&pts, args.fit_order, None).map_err(|e| e.to_string())
        };
        match fit {
            Ok(f) => {
                if !f.r_squared.is_finite() {
                    eprintln!(
                        "note: region {}: all {} in-range pixels read the same pressure ({:.4} MPa): \
                         fitted by that constant, R² undefined (empty in regions.csv); one flat \
                         colour is more often a mark or a saturated blot than a real contact",
                        r.id,
                        pts.len(),
                        pts[0].2 / 1e6
                    );
                }
                if s.saturated_fraction > SATURATED_WARNING_FRACTION {
                    eprintln!(
                        "warning: region {}: {:.1} % of its pressure-bearing pixels ({} of {}) are \
                         above the film's range (≥ {:.3} MPa, saturated); its fit (R² {}) is made \
                         from the in-range pixels only and does not know the pressure there, \
                         which is at least the range's top: use a film of a higher range",
                        r.id,
                        100.0 * s.saturated_fraction,
                        s.counts.above_range,
                        s.counts.in_range + s.counts.above_range,
                        hi / 1e6,
                        match f.r_squared_text(4).as_str() {
                            "" => "undefined".to_string(),
                            t => t.to_string(),
                        }
                    );
                }
                fits.push(Some(f))
            }
            Err(why) => {
                eprintln!("warning: region {} skipped, not fitted: {why}", r.id);
                skipped.push(serde_json::json!({ "region": r.id, "reason": why }));
                fits.push(None);
            }
        }
        summaries.push(s);
    }
    if fits.iter().all(Option::is_none) {
        return Err(Error::Data(format!(
            "{}: none of the {} regions could be fitted (see the warnings above)",
            args.image.display(),
            regions.len()
        )));
    }

    // Nodes.
    let mut inputs = vec![
        InputFile::new("image", &args.image)?,
        InputFile::new("colour_calibration", &table_path)?,
    ];
    let mut node_summary = serde_json::Value::Null;
    type NodeOutputs = (
        Vec<Preload>,
        Vec<NodePixel>,
        String,
        Option<(Vec<Preload>, String)>,
    );
    let mut node_outputs: Option<NodeOutputs> = None;
    if let Some(nodes_path) = &args.nodes {
        inputs.push(InputFile::new("nodes", nodes_path)?);
        let region_idx = match args.nodes_region {
            Some(id) => regions.iter().position(|r| r.id == id).ok_or_else(|| {
                Error::param(
                    "--nodes-region",
                    format!("no region {id} (found {})", regions.len()),
                )
            })?,
            None if regions.len() == 1 => 0,
            None => {
                return Err(Error::param(
                    "--nodes-region",
                    format!(
                        "{} regions were found: name the one the nodes sit on",
                        regions.len()
                    ),
                ))
            }
        };
        let region = &regions[region_idx];
        let fit = fits[region_idx].as_ref().ok_or_else(|| {
            Error::param(
                "--nodes-region",
                format!(
                    "region {} could not be fitted (see the warning above)",
                    region.id
                ),
            )
        })?;
        let nodes = read_nodes_csv(nodes_path)?;
        let off = args.node_offset_mm.clone().unwrap_or(vec![0.0, 0.0]);
        let placement = Placement {
            offset_x_m: off[0] * 1e-3,
            offset_y_m: off[1] * 1e-3,
            rotation_rad: args.node_rotation_deg.to_radians(),
            scale: args.node_scale,
        };
        let field = FittedRegion::new(&map, region, fit);
        let pressure_at = |x: f64, y: f64| field.pressure_at(x, y);
        // Errors about the nodes (their positions, their triangulation) name the nodes file.
        let (pre, psum) = preloads(&nodes, &placement, pressure_at, args.total_load_n)
            .map_err(|e| e.in_file(nodes_path))?;
        // What the film says under each node: the fit is made from in-range pixels, and reads
        // anything on saturated (above-range) or below-range pixels; say so, never clamp.
        let classes: Vec<NodePixel> = pre
            .iter()
            .map(|p| field.pixel_at(p.x_m, p.y_m))
            .collect::<Result<_>>()?;
        let pixel_classes = node_pixel_report(&pre, &classes, fit, lo, hi);
        let pre_comment = format!(
            "asperity {} node preloads N0 = sigma_fit(x, y) * area from {} (region {}, order-{} fit)",
            env!("CARGO_PKG_VERSION"),
            args.image.display(),
            region.id,
            fit.order
        );
        if psum.gap_triangles > 0 {
            eprintln!(
                "warning: {} triangles of the nodes' triangulation ({:.4} mm²) span gaps of the node set (holes, space between patches) and were left out of the areas; an element of the mesh more than {} times larger than those round it reads as a gap too: give area_m2 in {} if these are elements",
                psum.gap_triangles,
                psum.gap_area_m2 * 1e6,
                asperity::film::nodes::GAP_EDGE_FACTOR,
                nodes_path.display()
            );
        }
        let area_source = if psum.areas_from_triangulation {
            format!(
                "triangulated, {:.4} mm² of gaps left out",
                psum.gap_area_m2 * 1e6
            )
        } else {
            "given".to_string()
        };
        eprintln!(
            "{} nodes on region {}: total area {:.4} mm² ({area_source}), total load {:.6} N (scale {:.6}), {} negative fitted pressures set to 0",
            psum.n_nodes,
            region.id,
            psum.total_area_m2 * 1e6,
            psum.total_load_n,
            psum.load_scale,
            psum.clamped_negative
        );
        let mut reduced = serde_json::Value::Null;
        let mut reduced_rows = None;
        if let Some(h) = args.reduce_mesh_size_mm {
            let r = reduce(
                &pre,
                asperity::core::error::require_positive("--reduce-mesh-size-mm", h)? * 1e-3,
            )?;
            let red_comment = format!(
                "asperity {} reduced node preloads: {} of {} nodes kept on a {} mm triangular mesh; area and load are sums over each triangle",
                env!("CARGO_PKG_VERSION"),
                r.nodes.len(),
                r.n_fine,
                h
            );
            eprintln!(
                "reduced {} nodes to {} on a {h} mm mesh",
                r.n_fine,
                r.nodes.len()
            );
            reduced_rows = Some((r.nodes.clone(), red_comment));
            reduced = serde_json::json!({
                "mesh_size_m": r.mesh_size_m,
                "n_kept": r.nodes.len(),
                "total_area_m2": r.nodes.iter().map(|p| p.area_m2).sum::<f64>(),
                "total_load_n": r.nodes.iter().map(|p| p.n0_n).sum::<f64>(),
            });
        }
        node_outputs = Some((pre, classes, pre_comment, reduced_rows));
        node_summary = serde_json::json!({
            "region": region.id,
            "placement": placement,
            "preloads": psum,
            "pixel_classes": pixel_classes,
            "reduction": reduced,
        });
    }

    // Every input is checked: stage the outputs (they appear together at the end).
    let staged = out.staging_dir()?;
    let out_dir = &staged;
    let pairs: Vec<_> = summaries
        .iter()
        .cloned()
        .zip(fits.iter().map(|f| f.as_ref()))
        .collect();
    write_summary_csv(&out_dir.join("regions.csv"), &pairs)?;
    write_region_pixels_csv(&out_dir.join("pressure_map.csv"), &map, &regions)?;
    // With its sidecar (pixel size, unit Pa), so that it reads back with
    // asperity::surface::io::npy::read_field.
    asperity::surface::io::npy::write_field(
        &out_dir.join("pressure_map_Pa.npy"),
        &map.pressure_pa,
        pixel_size_m,
        pixel_size_m,
        false,
        "Pa",
        Some("film contact pressure (NaN where not in the measuring range); film frame x right, y up"),
    )?;
    heatmap(
        &out_dir.join("pressure_map.png"),
        &map.pressure_pa,
        pixel_size_m,
        pixel_size_m,
        &HeatMap {
            title: "film pressure (in-range pixels)",
            value_label: "pressure (MPa)",
            value_scale: 1e-6,
            length_scale: 1e3,
            length_unit: "mm",
        },
    )?;
    let fit_refs: Vec<(usize, &PolyFit2)> = regions
        .iter()
        .zip(&fits)
        .filter_map(|(r, f)| f.as_ref().map(|f| (r.id, f)))
        .collect();
    polyfit::write_coefficients_csv(&out_dir.join("fit_coefficients.csv"), &fit_refs)?;
    for (r, f) in regions.iter().zip(&fits) {
        let Some(f) = f else { continue };
        plot_region(
            &out_dir.join(format!("region_{}_fitted.png", r.id)),
            &map,
            r,
            |i, j| {
                let (x, y) = map.position(i, j);
                f.eval(x, y)
            },
            &format!(
                "region {}: order-{} fit, R² = {}",
                r.id,
                f.order,
                match f.r_squared_text(3).as_str() {
                    "" => "undefined (uniform)",
                    t => t,
                }
            ),
            "fitted pressure (MPa)",
        )?;
        plot_region(
            &out_dir.join(format!("region_{}_residual.png", r.id)),
            &map,
            r,
            |i, j| {
                let (x, y) = map.position(i, j);
                map.pressure_pa[[i, j]] - f.eval(x, y)
            },
            &format!("region {}: measured − fitted", r.id),
            "residual (MPa)",
        )?;
    }

    println!("id,centre_x_mm,centre_y_mm,diameter_mm,area_mm2,mean_pressure_MPa,n_in_range,n_unstained,n_below_range,n_above_range,n_off_curve,fit_R2,saturated_fraction");
    for (s, f) in &pairs {
        println!(
            "{},{:.3},{:.3},{:.3},{:.3},{:.4},{},{},{},{},{},{},{}",
            s.id,
            s.centre_x_m * 1e3,
            s.centre_y_m * 1e3,
            s.equivalent_diameter_m * 1e3,
            s.area_m2 * 1e6,
            s.mean_pressure_pa / 1e6,
            s.counts.in_range,
            s.counts.unstained,
            s.counts.below_range,
            s.counts.above_range,
            s.counts.off_curve,
            f.map(|f| f.r_squared_text(4)).unwrap_or_default(),
            if s.saturated_fraction.is_finite() {
                format!("{:.4}", s.saturated_fraction)
            } else {
                String::new()
            }
        );
    }

    if let Some((pre, classes, pre_comment, reduced_rows)) = &node_outputs {
        write_preloads_csv_with_classes(&out_dir.join("preload.csv"), pre, classes, pre_comment)?;
        if let Some((rows, comment)) = reduced_rows {
            write_preloads_csv(&out_dir.join("preload_reduced.csv"), rows, comment)?;
        }
    }

    let params = serde_json::json!({
        "pixel_size_m": pixel_size_m,
        "pixel_size_source": pixel_source,
        "density_channel": matches!(reader, ColourToPressure::Density(_)).then(|| channel.name()),
        "unstained_density": match &reader {
            ColourToPressure::Density(d) => Some(d.unstained_density),
            ColourToPressure::Table(_) => None,
        },
        "paper_level_estimate": paper,
        "smooth_mm": args.smooth_mm,
        "max_elongation": args.max_elongation,
        "min_solidity": args.min_solidity,
        "max_colour_distance_rgb": args.max_colour_distance,
        "calibrated_range_pa": [lo, hi],
        "fit_order": args.fit_order,
        "roi_rect_mm": args.roi_rect_mm,
        "roi_polygon_mm": args.roi_polygon_mm,
        "min_patch_diameter_mm": args.min_patch_diameter_mm,
        "rim_pixels": args.rim_pixels,
        "total_load_n": args.total_load_n,
        "reduce_mesh_size_mm": args.reduce_mesh_size_mm,
    });
    let summary = serde_json::json!({
        "image_pixels": all,
        "discarded_small_components": discarded,
        "rejected_marks": rejected_marks,
        "below_range_patches": below_range_patches,
        "regions_not_fitted": skipped,
        "regions": summaries,
        "fits": fits,
        "nodes": node_summary,
    });
    let json = provenance_json("film", &inputs, params, summary);
    write_string_atomic(
        &out_dir.join("film.json"),
        &serde_json::to_string_pretty(&json).map_err(|e| Error::Data(e.to_string()))?,
    )?;
    out.commit()?;
    Ok(())
}
