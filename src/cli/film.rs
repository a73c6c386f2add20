//! `asperity film`: film image → pressure map, regions, polynomial fit, node preloads. The
//! pipeline is [`asperity::film::pipeline`]; this module parses the flags, declares the output
//! set, prints the notes and the region table.

use asperity::film::colour::DEFAULT_MAX_COLOUR_DISTANCE;
use asperity::film::pipeline::{self, FilmConfig, FilmReport};
use asperity::film::regions::{DEFAULT_MAX_ELONGATION, DEFAULT_MIN_SOLIDITY, DEFAULT_RIM_PIXELS};
use asperity::Result;
use std::path::PathBuf;

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

impl FilmOptions {
    /// The pipeline's parameters, one per flag.
    fn config(&self) -> FilmConfig {
        FilmConfig {
            image: self.image.clone(),
            pixel_size_mm: self.pixel_size_mm,
            colour_table: self.colour_table.clone(),
            max_colour_distance: self.max_colour_distance,
            density_calibration: self.density_calibration.clone(),
            channel: self.channel.clone(),
            stain_rgb: self.stain_rgb.clone(),
            unstained_density: self.unstained_density,
            smooth_mm: self.smooth_mm,
            roi_rect_mm: self.roi_rect_mm.clone(),
            roi_polygon_mm: self.roi_polygon_mm.clone(),
            min_patch_diameter_mm: self.min_patch_diameter_mm,
            rim_pixels: self.rim_pixels,
            max_elongation: self.max_elongation,
            min_solidity: self.min_solidity,
            fit_order: self.fit_order,
            nodes: self.nodes.clone(),
            nodes_region: self.nodes_region,
            node_offset_mm: self.node_offset_mm.clone(),
            node_rotation_deg: self.node_rotation_deg,
            node_scale: self.node_scale,
            total_load_n: self.total_load_n,
            reduce_mesh_size_mm: self.reduce_mesh_size_mm,
        }
    }
}

/// The region table printed on stdout (one row per region, MPa and mm).
fn print_regions(report: &FilmReport) {
    println!("id,centre_x_mm,centre_y_mm,diameter_mm,area_mm2,mean_pressure_MPa,n_in_range,n_unstained,n_below_range,n_above_range,n_off_curve,fit_R2,saturated_fraction");
    for (s, f) in report.regions_with_fits() {
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
}

pub fn run(args: FilmArgs) -> Result<()> {
    let args = *args.opts;
    let config = args.config();
    config.check()?;
    // Refused now, before any work: an --out-dir that is a file or not writable, an output that
    // is one of the inputs.
    let mut out = pipeline::output_set(&config, &args.out_dir, "--out-dir")?;
    let report = pipeline::run(&config, &mut |m| eprintln!("{m}"))?;
    // Every input is checked: stage the outputs (they appear together at the end).
    let staged = out.staging_dir()?;
    report.write(&staged)?;
    print_regions(&report);
    out.commit()?;
    Ok(())
}
