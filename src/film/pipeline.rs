//! `asperity film` as a library call: a film image in, the pressure map, its regions, their
//! polynomial fits, the node preloads and their reduction out ([`run`] takes a [`FilmConfig`]
//! and returns a [`FilmReport`]; [`FilmReport::write`] writes the files of the command).
//!
//! The steps, in order:
//!
//! 1. **Check the parameters** ([`FilmConfig::check`]): colour distance within the RGB cube
//!    (`0 < d ≤ 255·√3`), a positive target load and node scale, a finite rotation and offset.
//! 2. **Calibration**: a colour table (pressure → RGB, [`ColourTable`]; pixels farther
//!    than the colour distance from its curve are rejected) or a density calibration for raw
//!    scans ([`DensityCalibration`], density read in one channel,
//!    [`scan::Channel`]).
//! 3. **Image and pixel size**: the image is read (8 or 16 bit, EXIF orientation applied); the
//!    pixel size is the one given or the resolution the image declares ([`scan::resolution`]),
//!    checked for a film scan ([`crate::core::sanity::film_pixel_size`]); optional Gaussian
//!    smoothing against speckle ([`scan::smooth`]).
//! 4. **Paper level** (density mode): the density at or below which a pixel is unstained, given
//!    or estimated from the histogram's mode plus five times its robust noise
//!    ([`scan::paper_level`]), never above the first calibration point.
//! 5. **Pressure map** ([`FilmMap::from_image`]): per pixel a pressure (Pa) where in
//!    range, else its class (unstained, below range, above range, off-curve).
//! 6. **Regions**: the region of interest given (rectangle or polygon, mm), or the round patches
//!    detected automatically ([`detect_patches_with`]: pressure-bearing components at
//!    least the smallest diameter across, their below-range rim joined, holes filled, marks
//!    rejected by elongation and solidity). Stained components entirely below the range are
//!    reported, not fitted: no pressure is known there.
//! 7. **Fits**: per region an order-n 2-D polynomial least-squares fit of its in-range
//!    pressures ([`polyfit::fit`], R² reported); a region that cannot be fitted is skipped with a
//!    warning, and no region fitted is an error.
//! 8. **Node preloads** (with nodes): the nodes are placed on the film (offset, rotation, scale),
//!    read on their region's fitted field only where the film is stained or enclosed by stain
//!    ([`FittedRegion`]), `N0 = σ_fit(x, y)·A` with areas given or triangulated
//!    ([`preloads`]), rescaled to a total load if asked; the film's class under each node
//!    is reported (a fit read on saturated or below-range film is a bound at best, never clamped).
//! 9. **Reduction** (with a mesh size): the nodes are reduced on a coarse triangular mesh, area
//!    and load preserved ([`reduce`]).
//!
//! Every note and warning is passed to the caller's log as it arises (the command prints them to
//! stderr) and kept in [`FilmReport::messages`].
//!
//! Parameters carry the units of the command's flags (mm for lengths on the film, degrees for
//! the rotation), as the user measures them and as `film.json` records them; errors name the
//! flag of the parameter (`--pixel-size-mm`, …).

use super::colour::{ColourTable, ColourToPressure, DensityCalibration};
use super::nodes::{
    preloads, read_nodes_csv, write_preloads_csv, write_preloads_csv_with_classes, Placement,
    Preload, PreloadSummary,
};
use super::polyfit::{self, PolyFit2};
use super::reduce::reduce;
use super::regions::{
    detect_below_range, detect_patches_with, roi_region, summarise, write_region_pixels_csv,
    write_summary_csv, ClassCounts, FilmMap, PatchOptions, Region, RegionSummary, Roi,
};
use super::scan::{self, Channel, PaperLevel};
use super::{FittedRegion, NodePixel};
use crate::core::error::{Error, Result};
use crate::core::hash::{provenance_json, InputFile};
use crate::core::output::{write_string_atomic, OutputSet};
use crate::core::plot::{heatmap, HeatMap};
use ndarray::Array2;
use std::path::{Path, PathBuf};

/// Largest Euclidean distance between two colours of the 0–255 RGB cube, black to white
/// (255·√3): a larger colour distance would reject nothing, so pen marks, tape and dirt would
/// all be read as pressure.
pub const MAX_RGB_DISTANCE: f64 = 441.672_955_930_063_7;

/// A fitted region more than this share of whose pressure-bearing pixels is above the film's
/// range (saturated) is named in a warning beside its R².
pub const SATURATED_WARNING_FRACTION: f64 = 0.01;

/// The files of fixed name [`FilmReport::write`] writes (some only with nodes or a reduction
/// mesh); besides them, [`REGION_PLOTS`].
pub const FIXED_OUTPUTS: [&str; 9] = [
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

/// The per-region plots [`FilmReport::write`] writes, as (prefix, suffix) around the region id:
/// `region_<id>_fitted.png`, `region_<id>_residual.png`.
pub const REGION_PLOTS: [(&str, &str); 2] =
    [("region_", "_fitted.png"), ("region_", "_residual.png")];

/// The parameters of `asperity film`, one per flag, in the flag's units.
#[derive(Debug, Clone, PartialEq)]
pub struct FilmConfig {
    /// Film image (PNG, JPEG or TIFF; 8 or 16 bit).
    pub image: PathBuf,
    /// Pixel size (mm, square pixels); `None`: the resolution the image declares.
    pub pixel_size_mm: Option<f64>,
    /// Colour table CSV (pressure, R, G, B); exactly one of this and `density_calibration`.
    pub colour_table: Option<PathBuf>,
    /// Off-curve rejection distance (RGB units, Euclidean).
    pub max_colour_distance: f64,
    /// Density calibration CSV (`density,pressure_MPa`) for raw scans.
    pub density_calibration: Option<PathBuf>,
    /// Density channel: `luma`, `red`, `green`, `blue` or `complement` (of `stain_rgb`).
    pub channel: String,
    /// Colour of the stain `[R, G, B]` (0–255), density mode.
    pub stain_rgb: Option<Vec<f64>>,
    /// Density of unstained paper (density mode); `None`: estimated from the scan.
    pub unstained_density: Option<f64>,
    /// Gaussian smoothing of the image, standard deviation (mm).
    pub smooth_mm: Option<f64>,
    /// Rectangular region of interest `[x0, y0, x1, y1]` (mm, film frame).
    pub roi_rect_mm: Option<Vec<f64>>,
    /// Polygonal region of interest `x,y;x,y;...` (mm, film frame, at least 3 vertices).
    pub roi_polygon_mm: Option<String>,
    /// Smallest equivalent diameter (mm) of an automatically detected patch.
    pub min_patch_diameter_mm: f64,
    /// Width (pixels) of the stained below-range rim joined to a detected patch.
    pub rim_pixels: usize,
    /// Largest elongation (ratio of principal axes) of a detected patch.
    pub max_elongation: f64,
    /// Smallest solidity (stained pixels / convex hull area) of a detected patch.
    pub min_solidity: f64,
    /// Order of the 2-D polynomial fitted to each region's in-range pressures.
    pub fit_order: usize,
    /// Contact nodes CSV (`id,x_m,y_m[,area_m2]`) to preload from the fitted pressure.
    pub nodes: Option<PathBuf>,
    /// Region whose fit preloads the nodes (required when several regions exist).
    pub nodes_region: Option<usize>,
    /// Node placement offset `[x, y]` (mm, mesh frame → film frame).
    pub node_offset_mm: Option<Vec<f64>>,
    /// Node placement rotation (degrees, counter-clockwise).
    pub node_rotation_deg: f64,
    /// Node placement scale (mesh length → film length).
    pub node_scale: f64,
    /// Rescale preloads so that they sum to this total normal load (N).
    pub total_load_n: Option<f64>,
    /// Reduce the nodes on a coarse triangular mesh of this side (mm).
    pub reduce_mesh_size_mm: Option<f64>,
}

impl FilmConfig {
    /// The command's defaults for an image read through a colour table.
    pub fn with_colour_table(image: PathBuf, colour_table: PathBuf) -> Self {
        Self {
            image,
            pixel_size_mm: None,
            colour_table: Some(colour_table),
            max_colour_distance: super::colour::DEFAULT_MAX_COLOUR_DISTANCE,
            density_calibration: None,
            channel: "luma".into(),
            stain_rgb: None,
            unstained_density: None,
            smooth_mm: None,
            roi_rect_mm: None,
            roi_polygon_mm: None,
            min_patch_diameter_mm: 2.0,
            rim_pixels: super::regions::DEFAULT_RIM_PIXELS,
            max_elongation: super::regions::DEFAULT_MAX_ELONGATION,
            min_solidity: super::regions::DEFAULT_MIN_SOLIDITY,
            fit_order: 4,
            nodes: None,
            nodes_region: None,
            node_offset_mm: None,
            node_rotation_deg: 0.0,
            node_scale: 1.0,
            total_load_n: None,
            reduce_mesh_size_mm: None,
        }
    }

    /// The command's defaults for a raw scan read through a density calibration.
    pub fn with_density_calibration(image: PathBuf, density_calibration: PathBuf) -> Self {
        Self {
            colour_table: None,
            density_calibration: Some(density_calibration),
            ..Self::with_colour_table(image, PathBuf::new())
        }
    }

    /// The numeric parameters, checked before any work so that errors name the flag (the
    /// library functions check them again under their own names).
    pub fn check(&self) -> Result<()> {
        use crate::core::error::{num, require_finite, require_positive};
        let d = self.max_colour_distance;
        if !(d.is_finite() && d > 0.0 && d <= MAX_RGB_DISTANCE) {
            return Err(Error::param(
                "--max-colour-distance",
                format!(
                    "must be > 0 and at most 255·√3 ≈ 441.7 RGB units (black to white), got {}",
                    num(d)
                ),
            ));
        }
        // A preload rescaled to a non-positive total would pull the joint apart.
        if let Some(f) = self.total_load_n {
            require_positive("--total-load-n", f)?;
        }
        // Mesh lengths map onto film lengths: a zero or negative scale mirrors or collapses the
        // mesh.
        require_positive("--node-scale", self.node_scale)?;
        require_finite("--node-rotation-deg", self.node_rotation_deg)?;
        if let Some(off) = &self.node_offset_mm {
            if off.len() != 2 {
                return Err(Error::param(
                    "--node-offset-mm",
                    format!("needs 2 values x,y, got {}", off.len()),
                ));
            }
            for v in off {
                require_finite("--node-offset-mm", *v)?;
            }
        }
        Ok(())
    }

    /// The parameters as `film.json` records them, with what the run derived from them.
    fn parameters_json(&self, report: &FilmReport) -> serde_json::Value {
        let (lo, hi) = report.range_pa;
        serde_json::json!({
            "pixel_size_m": report.pixel_size_m,
            "pixel_size_source": report.pixel_size_source,
            "density_channel": report.density_channel.map(|c| c.name()),
            "unstained_density": report.unstained_density,
            "paper_level_estimate": report.paper_level,
            "smooth_mm": self.smooth_mm,
            "max_elongation": self.max_elongation,
            "min_solidity": self.min_solidity,
            "max_colour_distance_rgb": self.max_colour_distance,
            "calibrated_range_pa": [lo, hi],
            "fit_order": self.fit_order,
            "roi_rect_mm": self.roi_rect_mm,
            "roi_polygon_mm": self.roi_polygon_mm,
            "min_patch_diameter_mm": self.min_patch_diameter_mm,
            "rim_pixels": self.rim_pixels,
            "total_load_n": self.total_load_n,
            "reduce_mesh_size_mm": self.reduce_mesh_size_mm,
        })
    }
}

/// The output set of a run into `out_dir` (`flag` names it in errors), declared before any work:
/// an `out_dir` that is a file or not writable is refused now; every file the command writes is
/// its own (one of an earlier run that this run does not write, such as a `preload_reduced.csv`
/// or the plots of a region that no longer exists, is removed at the commit, so that no reader
/// picks up a stale file); no output may be, or remove, one of the inputs.
pub fn output_set(config: &FilmConfig, out_dir: &Path, flag: &str) -> Result<OutputSet> {
    let mut out = OutputSet::in_dir(out_dir, flag)?;
    for name in FIXED_OUTPUTS {
        out.owns(name, "")?;
    }
    for (prefix, suffix) in REGION_PLOTS {
        out.owns(prefix, suffix)?;
    }
    out.input(&config.image, "--image")?;
    out.inputs(&config.colour_table, "--colour-table")?;
    out.inputs(&config.density_calibration, "--density-calibration")?;
    out.inputs(&config.nodes, "--nodes")?;
    Ok(out)
}

/// A region that could not be fitted, and why.
#[derive(Debug, Clone, serde::Serialize)]
pub struct NotFitted {
    /// Id of the region (1-based, as in the region table).
    pub region: usize,
    /// Why the fit was not possible (too few in-range pixels for the order, a singular system, …).
    pub reason: String,
}

/// A stained component entirely below the film's range (no pressure known there).
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct BelowRangePatch {
    /// Centroid x, film frame (m).
    pub centre_x_m: f64,
    /// Centroid y, film frame (m).
    pub centre_y_m: f64,
    /// Diameter of the disc of the same area (m).
    pub equivalent_diameter_m: f64,
}

/// The nodes on one film pixel class, and what the fit reads under them (Pa).
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct NodeClassReading {
    /// Number of nodes on pixels of this class.
    pub n_nodes: usize,
    /// Smallest fitted pressure (Pa) under these nodes; `None` without nodes.
    pub fitted_pressure_min_pa: Option<f64>,
    /// Largest fitted pressure (Pa) under these nodes; `None` without nodes.
    pub fitted_pressure_max_pa: Option<f64>,
}

/// The reduction of the preloaded nodes on a coarse mesh.
#[derive(Debug, Clone)]
pub struct ReducedPreloads {
    /// The kept nodes with summed areas and loads.
    pub nodes: Vec<Preload>,
    /// Number of fine nodes.
    pub n_fine: usize,
    /// Coarse triangle side (m).
    pub mesh_size_m: f64,
    /// Header comment of `preload_reduced.csv`.
    pub comment: String,
}

/// The node preloads of a run with nodes.
#[derive(Debug, Clone)]
pub struct NodePreloads {
    /// Id of the region whose fit preloads the nodes.
    pub region: usize,
    /// Mesh frame → film frame of the node coordinates (offset, rotation, scale).
    pub placement: Placement,
    /// One preload per node (film frame, N).
    pub preloads: Vec<Preload>,
    /// The film pixel class under each node.
    pub pixel_classes: Vec<NodePixel>,
    /// Counts and fitted readings per class, in [`NodePixel::ALL`] order.
    pub class_readings: Vec<(NodePixel, NodeClassReading)>,
    /// Totals of the node preloads: nodes, tributary area (m²), load before and after rescaling (N).
    pub summary: PreloadSummary,
    /// Header comment of `preload.csv`.
    pub comment: String,
    /// With a reduction mesh size.
    pub reduced: Option<ReducedPreloads>,
}

/// What `asperity film` found: the pressure map, its regions with summaries and fits, the node
/// preloads, and the messages of the run.
#[derive(Debug, Clone)]
pub struct FilmReport {
    /// The parameters of the run.
    pub config: FilmConfig,
    /// The pressure map (Pa where in range) and pixel classes.
    pub map: FilmMap,
    /// Pixel size (m).
    pub pixel_size_m: f64,
    /// Where the pixel size came from (the flag, or the image's resolution tag).
    pub pixel_size_source: String,
    /// The density channel (density mode).
    pub density_channel: Option<Channel>,
    /// The density at or below which a pixel is unstained (density mode).
    pub unstained_density: Option<f64>,
    /// The paper level estimated from the scan (density mode without a given level).
    pub paper_level: Option<PaperLevel>,
    /// The calibrated range (Pa), bottom and top.
    pub range_pa: (f64, f64),
    /// Pixel counts over the whole image.
    pub pixel_counts: ClassCounts,
    /// Automatic detection: components smaller than the smallest patch (0 with a region of
    /// interest).
    pub discarded_small_components: usize,
    /// Automatic detection: components rejected by their shape as marks (0 with a region of
    /// interest).
    pub rejected_marks: usize,
    /// Stained components entirely below the range (automatic detection only).
    pub below_range_patches: Vec<BelowRangePatch>,
    /// The regions (detected patches or the region of interest).
    pub regions: Vec<Region>,
    /// Per region: pixel counts, load and mean pressure of the in-range pixels.
    pub summaries: Vec<RegionSummary>,
    /// Per region: the 2-D polynomial fit of the pressure (`None`: not fitted, see `not_fitted`).
    pub fits: Vec<Option<PolyFit2>>,
    /// The regions that could not be fitted, and why.
    pub not_fitted: Vec<NotFitted>,
    /// With nodes.
    pub nodes: Option<NodePreloads>,
    /// The input files, with their SHA-256.
    pub inputs: Vec<InputFile>,
    /// Every note and warning, in order.
    pub messages: Vec<String>,
}

/// The messages of a run: each goes to the caller's log at once and is kept.
struct Log<'a> {
    sink: &'a mut dyn FnMut(&str),
    messages: Vec<String>,
}

impl Log<'_> {
    fn say(&mut self, message: String) {
        (self.sink)(&message);
        self.messages.push(message);
    }
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

/// The vertices (m) of a polygon `x,y;x,y;...` given in mm.
pub fn parse_polygon_mm(s: &str) -> Result<Vec<(f64, f64)>> {
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

/// The density channel named `name` (with the stain's colour for `complement`).
pub fn channel_named(name: &str, stain: Option<&[f64]>) -> Result<Channel> {
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

/// Count the nodes by the film pixel under them, warn about those on saturated or below-range
/// pixels (where the fit, made from in-range pixels, reads anything: a 6 MPa fit where the film
/// says ≥ 9.06 MPa) and on holes; the counts and the fit's readings per class.
fn node_class_readings(
    pre: &[Preload],
    classes: &[NodePixel],
    fit: &PolyFit2,
    (lo, hi): (f64, f64),
    log: &mut Log<'_>,
) -> Vec<(NodePixel, NodeClassReading)> {
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
    let mut readings = Vec::new();
    for c in NodePixel::ALL {
        let v = fitted(c);
        let (a, b) = span(&v);
        readings.push((
            c,
            NodeClassReading {
                n_nodes: v.len(),
                fitted_pressure_min_pa: (!v.is_empty()).then_some(a),
                fitted_pressure_max_pa: (!v.is_empty()).then_some(b),
            },
        ));
        if v.is_empty() {
            continue;
        }
        match c {
            NodePixel::InRange => {}
            NodePixel::AboveRange => {
                let short = v.iter().filter(|&&p| p < hi).count();
                log.say(format!(
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
                ));
            }
            NodePixel::BelowRange => {
                let over = v.iter().filter(|&&p| p >= lo).count();
                log.say(format!(
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
                ));
            }
            NodePixel::Hole => {
                log.say(format!(
                    "note: {} nodes lie on unstained or rejected pixels enclosed by the stain \
                     (holes: contact below the film's range, or ink), where the fit reads \
                     {:.2}–{:.2} MPa (pixel_class hole in preload.csv)",
                    v.len(),
                    a / 1e6,
                    b / 1e6
                ));
            }
        }
    }
    readings
}

/// The calibration of the run and the path it was read from.
fn read_calibration(config: &FilmConfig) -> Result<(ColourToPressure, PathBuf)> {
    match (&config.colour_table, &config.density_calibration) {
        (Some(t), None) => Ok((
            ColourToPressure::Table(ColourTable::read_csv(t, config.max_colour_distance)?),
            t.clone(),
        )),
        (None, Some(d)) => Ok((
            ColourToPressure::Density(DensityCalibration::read_csv(d)?),
            d.clone(),
        )),
        _ => Err(Error::param(
            "--colour-table / --density-calibration",
            "give exactly one",
        )),
    }
}

/// The pixel size (m) and where it came from: given, or the resolution the image declares;
/// checked for a film scan.
fn pixel_size(config: &FilmConfig) -> Result<(f64, String)> {
    let (pixel_size_m, source) = match config.pixel_size_mm {
        Some(v) => (
            crate::core::error::require_positive("--pixel-size-mm", v)? * 1e-3,
            "--pixel-size-mm".to_string(),
        ),
        None => match scan::resolution(&config.image)? {
            Some(r) => (
                r.pixel_size_m,
                format!(
                    "{} dpi declared by the image ({})",
                    crate::core::error::num((r.dpi * 1e6).round() / 1e6),
                    r.source
                ),
            ),
            None => {
                return Err(Error::param(
                    "--pixel-size-mm",
                    format!(
                        "not given, and {} declares no resolution (dpi): give the pixel size",
                        config.image.display()
                    ),
                ))
            }
        },
    };
    crate::core::sanity::film_pixel_size(pixel_size_m).map_err(|m| {
        if config.pixel_size_mm.is_some() {
            Error::param("--pixel-size-mm", m)
        } else {
            Error::param(
                "--pixel-size-mm",
                format!("not given, and the resolution {} declares ({source}) gives {m}: give the pixel size", config.image.display()),
            )
        }
    })?;
    Ok((pixel_size_m, source))
}

/// Run the film pipeline (steps in the [module documentation](self)); every note and warning
/// goes to `log` as it arises.
pub fn run(config: &FilmConfig, log: &mut dyn FnMut(&str)) -> Result<FilmReport> {
    let mut log = Log {
        sink: log,
        messages: Vec::new(),
    };
    let args = config;
    args.check()?;
    let (mut reader, table_path) = read_calibration(args)?;
    let channel = channel_named(&args.channel, args.stain_rgb.as_deref())?;
    let mut img = scan::read_rgb(&args.image)?;
    let (pixel_size_m, pixel_source) = pixel_size(args)?;
    let pixel_size_mm = pixel_size_m * 1e3;
    if let Some(s) = args.smooth_mm {
        crate::core::error::require_positive("--smooth-mm", s)?;
        scan::smooth(&mut img, s / pixel_size_mm).map_err(|e| e.renamed_param("--smooth-mm"))?;
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
                .map_err(|e| e.renamed_param("--stain-rgb"))?;
        }
        let first = d.points[0].0;
        let level = match args.unstained_density {
            Some(u) => {
                crate::core::error::require_finite("--unstained-density", u)?;
                if u > first {
                    return Err(Error::param(
                        "--unstained-density",
                        format!(
                            "{} exceeds the first calibration density {}: calibrated stain \
                             would read as paper",
                            crate::core::error::num(u),
                            crate::core::error::num(first)
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
        log.say(format!(
            "density in the {} channel; unstained paper at or below density {:.4}{}",
            channel.name(),
            level,
            paper.map_or(String::new(), |p| format!(
                " (estimated: paper {:.4} ± {:.4})",
                p.density, p.noise
            ))
        ));
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
    log.say(format!(
        "{}: {nx} × {ny} px at {} mm ({pixel_source}); range {:.3}–{:.3} MPa; pixels in range {}, unstained {}, below range {}, above range {}, off-curve (rejected) {}",
        args.image.display(),
        crate::core::error::num(pixel_size_mm),
        lo / 1e6,
        hi / 1e6,
        all.in_range,
        all.unstained,
        all.below_range,
        all.above_range,
        all.off_curve
    ));
    if all.below_range > 0 {
        log.say(format!(
            "note: {} pixels ({:.2} % of the image) are stained below the film's measuring range \
             (< {:.3} MPa): their pressure is unknown, they carry no pressure in the maps and fits",
            all.below_range,
            100.0 * all.below_range as f64 / all.total() as f64,
            lo / 1e6
        ));
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
            vec![roi_region(&map, &Roi::Polygon(parse_polygon_mm(p)?), 1)
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
            log.say(format!(
                "{} components rejected by their shape as marks (elongation > {}, or solidity < {})",
                d.rejected_marks, args.max_elongation, args.min_solidity
            ));
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
            below_range_patches.push(BelowRangePatch {
                centre_x_m: cx * pixel_size_m,
                centre_y_m: cy * pixel_size_m,
                equivalent_diameter_m: (4.0 * n / std::f64::consts::PI).sqrt() * pixel_size_m,
            });
        }
        if !below_range_patches.is_empty() {
            log.say(format!(
                "note: {} stained components of at least {} mm lie entirely below the film's \
                 measuring range (< {:.3} MPa): patches loaded below the range, or tape and \
                 marks; no pressure is known there (centres and sizes in film.json, \
                 `below_range_patches`)",
                below_range_patches.len(),
                args.min_patch_diameter_mm,
                lo / 1e6
            ));
        }
    }

    // Fits and summaries: a region that cannot be fitted is skipped with a warning, the others
    // are kept.
    let mut fits: Vec<Option<PolyFit2>> = Vec::new();
    let mut summaries = Vec::new();
    let mut skipped = Vec::new();
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
                    log.say(format!(
                        "note: region {}: all {} in-range pixels read the same pressure ({:.4} MPa): \
                         fitted by that constant, R² undefined (empty in regions.csv); one flat \
                         colour is more often a mark or a saturated blot than a real contact",
                        r.id,
                        pts.len(),
                        pts[0].2 / 1e6
                    ));
                }
                if s.saturated_fraction > SATURATED_WARNING_FRACTION {
                    log.say(format!(
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
                    ));
                }
                fits.push(Some(f))
            }
            Err(why) => {
                log.say(format!(
                    "warning: region {} skipped, not fitted: {why}",
                    r.id
                ));
                skipped.push(NotFitted {
                    region: r.id,
                    reason: why,
                });
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
    let mut node_preloads = None;
    if let Some(nodes_path) = &args.nodes {
        inputs.push(InputFile::new("nodes", nodes_path)?);
        node_preloads = Some(preload_nodes(
            args,
            nodes_path,
            &map,
            &regions,
            &fits,
            (lo, hi),
            &mut log,
        )?);
    }

    Ok(FilmReport {
        config: config.clone(),
        map,
        pixel_size_m,
        pixel_size_source: pixel_source,
        density_channel: matches!(reader, ColourToPressure::Density(_)).then_some(channel),
        unstained_density: match &reader {
            ColourToPressure::Density(d) => Some(d.unstained_density),
            ColourToPressure::Table(_) => None,
        },
        paper_level: paper,
        range_pa: (lo, hi),
        pixel_counts: all,
        discarded_small_components: discarded,
        rejected_marks,
        below_range_patches,
        regions,
        summaries,
        fits,
        not_fitted: skipped,
        nodes: node_preloads,
        inputs,
        messages: log.messages,
    })
}

/// Steps 8 and 9: the nodes of `nodes_path` placed on the film, preloaded from their region's
/// fit, classified by the film under them, and reduced when asked.
fn preload_nodes(
    args: &FilmConfig,
    nodes_path: &Path,
    map: &FilmMap,
    regions: &[Region],
    fits: &[Option<PolyFit2>],
    (lo, hi): (f64, f64),
    log: &mut Log<'_>,
) -> Result<NodePreloads> {
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
    let field = FittedRegion::new(map, region, fit);
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
    let class_readings = node_class_readings(&pre, &classes, fit, (lo, hi), log);
    let comment = format!(
        "asperity {} node preloads N0 = sigma_fit(x, y) * area from {} (region {}, order-{} fit)",
        env!("CARGO_PKG_VERSION"),
        args.image.display(),
        region.id,
        fit.order
    );
    if psum.gap_triangles > 0 {
        log.say(format!(
            "warning: {} triangles of the nodes' triangulation ({:.4} mm²) span gaps of the node set (holes, space between patches) and were left out of the areas; an element of the mesh more than {} times larger than those round it reads as a gap too: give area_m2 in {} if these are elements",
            psum.gap_triangles,
            psum.gap_area_m2 * 1e6,
            super::nodes::GAP_EDGE_FACTOR,
            nodes_path.display()
        ));
    }
    let area_source = if psum.areas_from_triangulation {
        format!(
            "triangulated, {:.4} mm² of gaps left out",
            psum.gap_area_m2 * 1e6
        )
    } else {
        "given".to_string()
    };
    log.say(format!(
        "{} nodes on region {}: total area {:.4} mm² ({area_source}), total load {:.6} N (scale {:.6}), {} negative fitted pressures set to 0",
        psum.n_nodes,
        region.id,
        psum.total_area_m2 * 1e6,
        psum.total_load_n,
        psum.load_scale,
        psum.clamped_negative
    ));
    let mut reduced = None;
    if let Some(h) = args.reduce_mesh_size_mm {
        let r = reduce(
            &pre,
            crate::core::error::require_positive("--reduce-mesh-size-mm", h)? * 1e-3,
        )?;
        let comment = format!(
            "asperity {} reduced node preloads: {} of {} nodes kept on a {} mm triangular mesh; area and load are sums over each triangle",
            env!("CARGO_PKG_VERSION"),
            r.nodes.len(),
            r.n_fine,
            h
        );
        log.say(format!(
            "reduced {} nodes to {} on a {h} mm mesh",
            r.n_fine,
            r.nodes.len()
        ));
        reduced = Some(ReducedPreloads {
            nodes: r.nodes,
            n_fine: r.n_fine,
            mesh_size_m: r.mesh_size_m,
            comment,
        });
    }
    Ok(NodePreloads {
        region: region.id,
        placement,
        preloads: pre,
        pixel_classes: classes,
        class_readings,
        summary: psum,
        comment,
        reduced,
    })
}

/// A heat map of `value` over a region's pixels, in the region's bounding box.
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

impl FilmReport {
    /// Each region's summary with its fit (`None`: not fitted).
    pub fn regions_with_fits(&self) -> impl Iterator<Item = (&RegionSummary, Option<&PolyFit2>)> {
        self.summaries
            .iter()
            .zip(self.fits.iter().map(|f| f.as_ref()))
    }

    /// The `summary` of `film.json`.
    pub fn summary_json(&self) -> serde_json::Value {
        let nodes = match &self.nodes {
            None => serde_json::Value::Null,
            Some(n) => {
                let pixel_classes: serde_json::Map<String, serde_json::Value> = n
                    .class_readings
                    .iter()
                    .map(|(c, r)| {
                        (
                            c.name().to_string(),
                            serde_json::to_value(r).unwrap_or_default(),
                        )
                    })
                    .collect();
                let reduction = match &n.reduced {
                    None => serde_json::Value::Null,
                    Some(r) => serde_json::json!({
                        "mesh_size_m": r.mesh_size_m,
                        "n_kept": r.nodes.len(),
                        "total_area_m2": r.nodes.iter().map(|p| p.area_m2).sum::<f64>(),
                        "total_load_n": r.nodes.iter().map(|p| p.n0_n).sum::<f64>(),
                    }),
                };
                serde_json::json!({
                    "region": n.region,
                    "placement": n.placement,
                    "preloads": n.summary,
                    "pixel_classes": pixel_classes,
                    "reduction": reduction,
                })
            }
        };
        serde_json::json!({
            "image_pixels": self.pixel_counts,
            "discarded_small_components": self.discarded_small_components,
            "rejected_marks": self.rejected_marks,
            "below_range_patches": self.below_range_patches,
            "regions_not_fitted": self.not_fitted,
            "regions": self.summaries,
            "fits": self.fits,
            "nodes": nodes,
        })
    }

    /// The provenance record `film.json`: inputs with their SHA-256, parameters, summary.
    pub fn film_json(&self) -> serde_json::Value {
        provenance_json(
            "film",
            &self.inputs,
            self.config.parameters_json(self),
            self.summary_json(),
        )
    }

    /// Write the files of `asperity film` into `dir` (a staging directory of an output set: the
    /// files are written one by one): `regions.csv`, `pressure_map.csv`, `pressure_map_Pa.npy`
    /// (with its sidecar), `pressure_map.png`, `fit_coefficients.csv`, per fitted region
    /// `region_<id>_fitted.png` and `region_<id>_residual.png`; with nodes `preload.csv`, with a
    /// reduction `preload_reduced.csv`; `film.json`.
    pub fn write(&self, dir: &Path) -> Result<()> {
        let map = &self.map;
        let pixel_size_m = self.pixel_size_m;
        let pairs: Vec<_> = self
            .summaries
            .iter()
            .cloned()
            .zip(self.fits.iter().map(|f| f.as_ref()))
            .collect();
        write_summary_csv(&dir.join("regions.csv"), &pairs)?;
        write_region_pixels_csv(&dir.join("pressure_map.csv"), map, &self.regions)?;
        // With its sidecar (pixel size, unit Pa), so that it reads back with
        // crate::surface::io::npy::read_field.
        crate::surface::io::npy::write_field(
            &dir.join("pressure_map_Pa.npy"),
            &map.pressure_pa,
            pixel_size_m,
            pixel_size_m,
            false,
            "Pa",
            Some("film contact pressure (NaN where not in the measuring range); film frame x right, y up"),
        )?;
        heatmap(
            &dir.join("pressure_map.png"),
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
        let fit_refs: Vec<(usize, &PolyFit2)> = self
            .regions
            .iter()
            .zip(&self.fits)
            .filter_map(|(r, f)| f.as_ref().map(|f| (r.id, f)))
            .collect();
        polyfit::write_coefficients_csv(&dir.join("fit_coefficients.csv"), &fit_refs)?;
        for (r, f) in self.regions.iter().zip(&self.fits) {
            let Some(f) = f else { continue };
            plot_region(
                &dir.join(format!("region_{}_fitted.png", r.id)),
                map,
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
                &dir.join(format!("region_{}_residual.png", r.id)),
                map,
                r,
                |i, j| {
                    let (x, y) = map.position(i, j);
                    map.pressure_pa[[i, j]] - f.eval(x, y)
                },
                &format!("region {}: measured − fitted", r.id),
                "residual (MPa)",
            )?;
        }
        if let Some(n) = &self.nodes {
            write_preloads_csv_with_classes(
                &dir.join("preload.csv"),
                &n.preloads,
                &n.pixel_classes,
                &n.comment,
            )?;
            if let Some(r) = &n.reduced {
                write_preloads_csv(&dir.join("preload_reduced.csv"), &r.nodes, &r.comment)?;
            }
        }
        write_string_atomic(
            &dir.join("film.json"),
            &serde_json::to_string_pretty(&self.film_json())
                .map_err(|e| Error::Data(e.to_string()))?,
        )
    }
}
