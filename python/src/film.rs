//! Pressure-measurement film → pressure map (Pa), regions, polynomial fit, preloads per node
//! (N), node reduction: `film()` runs the library's pipeline of `asperity film`
//! (`asperity::film::pipeline`, the function the CLI calls); the building blocks are bound too,
//! for composing other pipelines. Film frame: x right, y up, metres, origin at the centre of the image's
//! bottom-left pixel; arrays are indexed `[i, j]` at `(i·s, j·s)` for pixel size `s`.

use crate::arrays::{borrow_f64, view};
use crate::calibrate::{preload_columns, preloads_from_columns};
use crate::errors::IntoPy;
use asperity::film::colour::{
    ColourTable, ColourToPressure, DensityCalibration, PixelClass, DEFAULT_MAX_COLOUR_DISTANCE,
};
use asperity::film::nodes::{self, Node, Placement};
use asperity::film::polyfit::{self, PolyFit2};
use asperity::film::reduce;
use asperity::film::regions::{self, Roi, DEFAULT_RIM_PIXELS};
use ndarray::Ix1;
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

/// Pixel class codes of `FilmMap.pixel_class`, in order.
const CLASSES: [PixelClass; 5] = [
    PixelClass::InRange,
    PixelClass::Unstained,
    PixelClass::BelowRange,
    PixelClass::AboveRange,
    PixelClass::OffCurve,
];

fn class_code(c: PixelClass) -> u8 {
    CLASSES
        .iter()
        .position(|k| *k == c)
        .expect("every class listed") as u8
}

/// Pixel counts per class of a film map or region.
#[pyclass(frozen, get_all, skip_from_py_object, module = "asperity")]
#[derive(Clone)]
pub struct ClassCounts {
    /// Pixels inside the calibrated pressure range.
    pub in_range: usize,
    /// Unstained pixels.
    pub unstained: usize,
    /// Stained pixels below the film's range.
    pub below_range: usize,
    /// Pixels at or above the upper end of the range (saturated).
    pub above_range: usize,
    /// Pixels far from the colour curve (rejected).
    pub off_curve: usize,
}

impl From<&regions::ClassCounts> for ClassCounts {
    fn from(c: &regions::ClassCounts) -> Self {
        Self {
            in_range: c.in_range,
            unstained: c.unstained,
            below_range: c.below_range,
            above_range: c.above_range,
            off_curve: c.off_curve,
        }
    }
}

/// Summary of a region of a film map (film frame, m; pressures in Pa).
#[pyclass(frozen, get_all, module = "asperity")]
pub struct RegionSummary {
    /// Region id.
    pub id: usize,
    /// Centroid x of the region's pixels (m).
    pub centre_x_m: f64,
    /// Centroid y (m).
    pub centre_y_m: f64,
    /// Pixel count × pixel area (m²).
    pub area_m2: f64,
    /// Diameter of the circle of that area (m).
    pub equivalent_diameter_m: f64,
    /// Mean in-range pressure (Pa; NaN when none is in range).
    pub mean_pressure_pa: f64,
    /// Largest in-range pressure (Pa).
    pub max_pressure_pa: f64,
    /// Load carried by the in-range pixels (N): a lower bound of the region's load.
    pub in_range_load_n: f64,
    /// Pixels of each class in the region.
    pub counts: ClassCounts,
    /// Saturated pixels over the pressure-bearing ones (NaN when there are none).
    pub saturated_fraction: f64,
}

impl From<&regions::RegionSummary> for RegionSummary {
    fn from(r: &regions::RegionSummary) -> Self {
        Self {
            id: r.id,
            centre_x_m: r.centre_x_m,
            centre_y_m: r.centre_y_m,
            area_m2: r.area_m2,
            equivalent_diameter_m: r.equivalent_diameter_m,
            mean_pressure_pa: r.mean_pressure_pa,
            max_pressure_pa: r.max_pressure_pa,
            in_range_load_n: r.in_range_load_n,
            counts: ClassCounts::from(&r.counts),
            saturated_fraction: r.saturated_fraction,
        }
    }
}

/// A film image read into pressure: per-pixel class and pressure (Pa, NaN unless in range).
#[pyclass(frozen, module = "asperity")]
pub struct FilmMap {
    inner: regions::FilmMap,
}

/// A set of pixels of a film map, with an id.
#[pyclass(frozen, module = "asperity")]
pub struct Region {
    inner: regions::Region,
}

/// A 2-D polynomial least-squares fit of a region's in-range pressures (Pa) in coordinates
/// scaled to the region's bounding box.
#[pyclass(frozen, module = "asperity")]
pub struct PolyFit {
    inner: PolyFit2,
}

#[pymethods]
impl FilmMap {
    /// Read a PNG, JPEG or TIFF film image (8 or 16 bit) with square pixels of `pixel_size_m`
    /// (m), through a colour table (`colour_table`: pressure in MPa, R, G, B; or a
    /// `pressure_Pa,R,G,B` header) or a density calibration (`density_calibration`:
    /// `density,pressure_MPa` for raw scans). Pixels farther than `max_colour_distance` (RGB
    /// units) from the colour curve are rejected (off-curve).
    #[staticmethod]
    #[pyo3(signature = (image, pixel_size_m, *, colour_table=None, density_calibration=None, max_colour_distance=DEFAULT_MAX_COLOUR_DISTANCE))]
    fn read(
        py: Python<'_>,
        image: PathBuf,
        pixel_size_m: f64,
        colour_table: Option<PathBuf>,
        density_calibration: Option<PathBuf>,
        max_colour_distance: f64,
    ) -> PyResult<Self> {
        let inner = py
            .detach(|| {
                let reader = match (&colour_table, &density_calibration) {
                    (Some(t), None) => {
                        ColourToPressure::Table(ColourTable::read_csv(t, max_colour_distance)?)
                    }
                    (None, Some(d)) => ColourToPressure::Density(DensityCalibration::read_csv(d)?),
                    _ => {
                        return Err(asperity::Error::param(
                            "colour_table / density_calibration",
                            "give exactly one",
                        ))
                    }
                };
                regions::FilmMap::read_image(&image, &reader, pixel_size_m)
            })
            .py()?;
        Ok(Self { inner })
    }

    /// Pressure (Pa), shape (nx, ny), NaN unless the pixel is in range: a read-only view.
    #[getter]
    fn pressure_pa(slf: Bound<'_, Self>) -> Bound<'_, PyArray2<f64>> {
        let owner = slf.clone().into_any();
        view(&slf.get().inner.pressure_pa, owner)
    }

    /// Pixel classes as codes (uint8, shape (nx, ny)); `class_names[code]` names them.
    #[getter]
    fn pixel_class<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<u8>> {
        PyArray2::from_owned_array(py, self.inner.class.mapv(class_code))
    }

    /// Names of the pixel class codes: in_range, unstained, below_range, above_range, off_curve.
    #[classattr]
    fn class_names() -> Vec<&'static str> {
        CLASSES.iter().map(|c| c.name()).collect()
    }

    /// Pixel counts per class.
    #[getter]
    fn class_counts(&self) -> ClassCounts {
        ClassCounts::from(&self.inner.class_counts())
    }

    /// Pixel size (m).
    #[getter]
    fn pixel_size_m(&self) -> f64 {
        self.inner.pixel_size_m
    }

    /// (nx, ny) pixels.
    #[getter]
    fn shape(&self) -> (usize, usize) {
        self.inner.dim()
    }

    /// Automatic patches: 8-connected components of pressure-bearing pixels whose core is at
    /// least `min_diameter_m` (m) across, plus up to `rim_pixels` of the stained below-range rim,
    /// holes filled. Returns `(regions, discarded_small_components)`.
    #[pyo3(signature = (min_diameter_m=2e-3, rim_pixels=DEFAULT_RIM_PIXELS))]
    fn detect_patches(
        &self,
        py: Python<'_>,
        min_diameter_m: f64,
        rim_pixels: usize,
    ) -> PyResult<(Vec<Region>, usize)> {
        let map = &self.inner;
        let d = py
            .detach(|| regions::detect_patches(map, min_diameter_m, rim_pixels))
            .py()?;
        Ok((
            d.patches
                .into_iter()
                .map(|inner| Region { inner })
                .collect(),
            d.discarded_small,
        ))
    }

    /// The pixels whose centres lie in the rectangle [x0_m, x1_m] × [y0_m, y1_m] (m).
    #[pyo3(signature = (x0_m, y0_m, x1_m, y1_m, id=1))]
    fn roi_rectangle(
        &self,
        x0_m: f64,
        y0_m: f64,
        x1_m: f64,
        y1_m: f64,
        id: usize,
    ) -> PyResult<Region> {
        let roi = Roi::Rectangle {
            x0: x0_m,
            y0: y0_m,
            x1: x1_m,
            y1: y1_m,
        };
        Ok(Region {
            inner: regions::roi_region(&self.inner, &roi, id).py()?,
        })
    }

    /// The pixels whose centres lie in the polygon of `vertices_m` [(x, y), ...] (m, ≥ 3).
    #[pyo3(signature = (vertices_m, id=1))]
    fn roi_polygon(&self, vertices_m: Vec<(f64, f64)>, id: usize) -> PyResult<Region> {
        Ok(Region {
            inner: regions::roi_region(&self.inner, &Roi::Polygon(vertices_m), id).py()?,
        })
    }

    /// Summary of a region: centre, area, equivalent diameter (m, m²), mean/max pressure (Pa),
    /// in-range load (N), pixel counts by class.
    fn summarise(&self, region: &Region) -> PyResult<RegionSummary> {
        let s = regions::summarise(&self.inner, &region.inner).py()?;
        Ok(RegionSummary::from(&s))
    }

    /// Order-`order` polynomial fit of the region's in-range pressures (Householder QR).
    #[pyo3(signature = (region, order=4))]
    fn fit(&self, py: Python<'_>, region: &Region, order: usize) -> PyResult<PolyFit> {
        let pts = self.inner.pressure_points(&region.inner.pixels);
        if pts.is_empty() {
            return Err(asperity::Error::Data(format!(
                "region {} holds no in-range pixel: nothing to fit",
                region.inner.id
            )))
            .py();
        }
        let inner = py.detach(|| polyfit::fit(&pts, order, None)).py()?;
        Ok(PolyFit { inner })
    }
}

#[pymethods]
impl Region {
    #[getter]
    fn id(&self) -> usize {
        self.inner.id
    }

    /// Pixel indices (i, j), shape (n, 2), uint64.
    #[getter]
    fn pixels<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<u64>> {
        let n = self.inner.pixels.len();
        let flat: Vec<u64> = self
            .inner
            .pixels
            .iter()
            .flat_map(|&(i, j)| [i as u64, j as u64])
            .collect();
        PyArray2::from_owned_array(
            py,
            ndarray::Array2::from_shape_vec((n, 2), flat).expect("n × 2"),
        )
    }

    /// Bounding box [x0, x1, y0, y1] (m) on `film_map`, pixel edges included.
    fn bounds_m(&self, film_map: &FilmMap) -> [f64; 4] {
        self.inner.bounds_m(&film_map.inner)
    }

    fn __len__(&self) -> usize {
        self.inner.pixels.len()
    }

    fn __repr__(&self) -> String {
        format!(
            "Region(id={}, {} pixels)",
            self.inner.id,
            self.inner.pixels.len()
        )
    }
}

#[pymethods]
impl PolyFit {
    #[getter]
    fn order(&self) -> usize {
        self.inner.order
    }

    /// Coefficients (Pa) of the monomials `exponents`.
    #[getter]
    fn coefficients_pa<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.inner.coefficients_pa)
    }

    /// Exponents (a, b) of each monomial ξ^a η^b in scaled coordinates.
    #[getter]
    fn exponents(&self) -> Vec<(usize, usize)> {
        self.inner.exponents.clone()
    }

    #[getter]
    fn r_squared(&self) -> f64 {
        self.inner.r_squared
    }

    /// RMS residual (Pa).
    #[getter]
    fn rms_residual_pa(&self) -> f64 {
        self.inner.rms_residual_pa
    }

    #[getter]
    fn n_points(&self) -> usize {
        self.inner.n_points
    }

    /// Fitted pressure (Pa) at film points `x_m`, `y_m` (m; numbers or float64 arrays).
    fn __call__<'py>(
        &self,
        py: Python<'py>,
        x_m: &Bound<'py, PyAny>,
        y_m: &Bound<'py, PyAny>,
    ) -> PyResult<Py<PyAny>> {
        if let (Ok(x), Ok(y)) = (x_m.extract::<f64>(), y_m.extract::<f64>()) {
            return Ok(self.inner.eval(x, y).into_pyobject(py)?.into_any().unbind());
        }
        let xa = borrow_f64::<Ix1>(x_m, "x_m", "film x (m)")?;
        let ya = borrow_f64::<Ix1>(y_m, "y_m", "film y (m)")?;
        let (xs, ys) = (
            xa.as_slice().expect("contiguous"),
            ya.as_slice().expect("contiguous"),
        );
        if xs.len() != ys.len() {
            return Err(asperity::Error::param(
                "y_m",
                format!("{} y values for {} x values", ys.len(), xs.len()),
            ))
            .py();
        }
        let v: Vec<f64> = xs
            .iter()
            .zip(ys)
            .map(|(&x, &y)| self.inner.eval(x, y))
            .collect();
        Ok(PyArray1::from_vec(py, v).into_any().unbind())
    }

    fn __repr__(&self) -> String {
        format!(
            "PolyFit(order={}, r_squared={:.6}, n_points={})",
            self.inner.order, self.inner.r_squared, self.inner.n_points
        )
    }
}

/// Read a nodes CSV (`id,x_m,y_m[,area_m2]`, mesh frame) as columns; `area_m2` is NaN where the
/// file gives none.
#[pyfunction]
pub fn read_nodes(py: Python<'_>, path: PathBuf) -> PyResult<Bound<'_, PyDict>> {
    let n = nodes::read_nodes_csv(&path).py()?;
    let d = PyDict::new(py);
    d.set_item(
        "id",
        PyArray1::from_vec(py, n.iter().map(|n| n.id).collect::<Vec<u64>>()),
    )?;
    d.set_item(
        "x_m",
        PyArray1::from_vec(py, n.iter().map(|n| n.x_m).collect::<Vec<f64>>()),
    )?;
    d.set_item(
        "y_m",
        PyArray1::from_vec(py, n.iter().map(|n| n.y_m).collect::<Vec<f64>>()),
    )?;
    d.set_item(
        "area_m2",
        PyArray1::from_vec(
            py,
            n.iter()
                .map(|n| n.area_m2.unwrap_or(f64::NAN))
                .collect::<Vec<f64>>(),
        ),
    )?;
    Ok(d)
}

fn nodes_from_columns(columns: &Bound<'_, PyDict>) -> PyResult<Vec<Node>> {
    let py = columns.py();
    let get = |name: &str| -> PyResult<Bound<'_, PyAny>> {
        columns.get_item(name)?.ok_or_else(|| {
            crate::errors::parameter(
                py,
                "nodes",
                format!("missing column `{name}` (need id, x_m, y_m[, area_m2])"),
            )
        })
    };
    let ids: Vec<u64> = get("id")?.extract()?;
    let xa = get("x_m")?;
    let ya = get("y_m")?;
    let x = borrow_f64::<Ix1>(&xa, "x_m", "node x (m)")?;
    let y = borrow_f64::<Ix1>(&ya, "y_m", "node y (m)")?;
    let x = crate::arrays::finite_slice(py, &x, "x_m")?;
    let y = crate::arrays::finite_slice(py, &y, "y_m")?;
    let area: Option<Vec<f64>> = match columns.get_item("area_m2")? {
        Some(a) => Some(
            borrow_f64::<Ix1>(&a, "area_m2", "node area (m²), NaN where absent")?
                .as_slice()
                .expect("contiguous")
                .to_vec(),
        ),
        None => None,
    };
    if x.len() != ids.len()
        || y.len() != ids.len()
        || area.as_ref().is_some_and(|a| a.len() != ids.len())
    {
        return Err(crate::errors::parameter(
            py,
            "nodes",
            "columns of different lengths".into(),
        ));
    }
    Ok((0..ids.len())
        .map(|i| Node {
            id: ids[i],
            x_m: x[i],
            y_m: y[i],
            area_m2: area.as_ref().map(|a| a[i]).filter(|a| !a.is_nan()),
            // Arrays from Python have no file lines: messages name the node id alone.
            line: 0,
        })
        .collect())
}

/// Preload of each node, `N0 = σ_fit(x, y)·A` (N): the nodes (columns as `read_nodes` returns;
/// mesh frame) are placed on the film by `offset_m` (m), `rotation_rad` (counter-clockwise) and
/// `scale`; areas come from the nodes or, when absent, from a Delaunay triangulation; the
/// pressure is the region's fit. With `total_load_n` (N) every preload is rescaled to that
/// total. Nodes outside the map or the region raise `asperity.DataError`.
/// Returns `(preloads, PreloadSummary)`, the preloads as columns `id, x_m, y_m, area_m2, pressure_Pa,
/// N0_N` (film frame) and `pixel_class` (what the film says under each node: `in_range`,
/// `above_range`, `below_range`, `hole`; as `preload.csv` of `asperity film`).
#[pyfunction]
#[pyo3(signature = (film_map, region, fit, nodes, *, offset_m=(0.0, 0.0), rotation_rad=0.0, scale=1.0, total_load_n=None))]
#[allow(clippy::too_many_arguments)]
pub fn film_preloads<'py>(
    py: Python<'py>,
    film_map: &FilmMap,
    region: &Region,
    fit: &PolyFit,
    nodes: &Bound<'py, PyDict>,
    offset_m: (f64, f64),
    rotation_rad: f64,
    scale: f64,
    total_load_n: Option<f64>,
) -> PyResult<(Bound<'py, PyDict>, PreloadSummary)> {
    let nodes = nodes_from_columns(nodes)?;
    let placement = Placement {
        offset_x_m: offset_m.0,
        offset_y_m: offset_m.1,
        rotation_rad,
        scale,
    };
    let field = asperity::film::FittedRegion::new(&film_map.inner, &region.inner, &fit.inner);
    let pressure_at = |x: f64, y: f64| field.pressure_at(x, y);
    let (pre, summary) = nodes::preloads(&nodes, &placement, pressure_at, total_load_n).py()?;
    // What the film says under each node, as `asperity film` writes it (`pixel_class`).
    let classes: Vec<&str> = pre
        .iter()
        .map(|p| field.pixel_at(p.x_m, p.y_m).map(|c| c.name()))
        .collect::<asperity::Result<_>>()
        .py()?;
    let columns = preload_columns(py, &pre)?;
    columns.set_item("pixel_class", classes)?;
    Ok((columns, PreloadSummary::from(&summary)))
}

/// Reduce preloaded nodes on a triangular mesh of side `mesh_size_m` (m): in each triangle the
/// node nearest its centroid is kept with the summed area and load (pressure = ΣN0/ΣA), so the
/// total area and load are preserved.
#[pyfunction]
pub fn reduce_preloads<'py>(
    py: Python<'py>,
    preloads: &Bound<'py, PyDict>,
    mesh_size_m: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let fine = preloads_from_columns(preloads)?;
    let r = reduce::reduce(&fine, mesh_size_m).py()?;
    preload_columns(py, &r.nodes)
}

/// The parameter named by a library error of the film pipeline, as the keyword argument of
/// `film()` (`--pixel-size-mm` → `pixel_size_mm`).
fn keyword_error(e: asperity::Error) -> asperity::Error {
    match e {
        asperity::Error::InvalidParameter { name, message } if name.starts_with("--") => {
            let keyword = name
                .trim_start_matches("--")
                .replace(" / --", " / ")
                .replace('-', "_");
            asperity::Error::param(keyword, message)
        }
        other => other,
    }
}

/// The whole film pipeline of `asperity film` (module `asperity::film::pipeline`): image →
/// pressure map → regions → polynomial fits → node preloads → reduction, with the same
/// parameters (lengths on the film in mm, as the CLI's flags) and the same checks.
#[pyclass(frozen, module = "asperity")]
pub struct FilmResult {
    inner: asperity::film::pipeline::FilmReport,
    written: Vec<PathBuf>,
}

#[pymethods]
impl FilmResult {
    /// The pressure map (a copy).
    #[getter]
    fn film_map(&self) -> FilmMap {
        FilmMap {
            inner: self.inner.map.clone(),
        }
    }

    /// The regions (automatic patches, or the region of interest).
    #[getter]
    fn regions(&self) -> Vec<Region> {
        self.inner
            .regions
            .iter()
            .map(|r| Region { inner: r.clone() })
            .collect()
    }

    /// The fit of each region, `None` where the region could not be fitted.
    #[getter]
    fn fits(&self) -> Vec<Option<PolyFit>> {
        self.inner
            .fits
            .iter()
            .map(|f| f.clone().map(|inner| PolyFit { inner }))
            .collect()
    }

    /// Summary of each region (as `FilmMap.summarise`).
    #[getter]
    fn summaries(&self) -> Vec<RegionSummary> {
        self.inner
            .summaries
            .iter()
            .map(RegionSummary::from)
            .collect()
    }

    /// Pixel size (m) and where it came from.
    #[getter]
    fn pixel_size_m(&self) -> f64 {
        self.inner.pixel_size_m
    }

    #[getter]
    fn pixel_size_source(&self) -> &str {
        &self.inner.pixel_size_source
    }

    /// Calibrated range (Pa), bottom and top.
    #[getter]
    fn range_pa(&self) -> (f64, f64) {
        self.inner.range_pa
    }

    /// With nodes: the preloads as columns `id, x_m, y_m, area_m2, pressure_Pa, N0_N` (film
    /// frame) and `pixel_class`, as `preload.csv`; else `None`.
    #[getter]
    fn preloads<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let Some(n) = &self.inner.nodes else {
            return Ok(None);
        };
        let columns = preload_columns(py, &n.preloads)?;
        let classes: Vec<&str> = n.pixel_classes.iter().map(|c| c.name()).collect();
        columns.set_item("pixel_class", classes)?;
        Ok(Some(columns))
    }

    /// With a reduction mesh: the reduced preloads as columns (as `preload_reduced.csv`).
    #[getter]
    fn reduced_preloads<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        match self.inner.nodes.as_ref().and_then(|n| n.reduced.as_ref()) {
            Some(r) => Ok(Some(preload_columns(py, &r.nodes)?)),
            None => Ok(None),
        }
    }

    /// The `summary` of `film.json` (pixel counts, regions, fits, regions not fitted,
    /// below-range patches, node preload summary and pixel classes, reduction).
    #[getter]
    fn summary(&self, py: Python<'_>) -> PyResult<FilmSummary> {
        film_summary(py, &self.inner)
    }

    /// The notes and warnings of the run, in order (the CLI prints them to stderr).
    #[getter]
    fn messages(&self) -> Vec<String> {
        self.inner.messages.clone()
    }

    /// The files written (with `out_dir`).
    #[getter]
    fn written(&self) -> Vec<PathBuf> {
        self.written.clone()
    }

    fn __repr__(&self) -> String {
        format!(
            "FilmResult({} regions, {} fitted, {})",
            self.inner.regions.len(),
            self.inner.fits.iter().filter(|f| f.is_some()).count(),
            match &self.inner.nodes {
                Some(n) => format!("{} nodes preloaded", n.preloads.len()),
                None => "no nodes".to_string(),
            }
        )
    }
}

/// `asperity film` from Python: the library's film pipeline with the command's parameters, as
/// keyword arguments named after its flags (lengths on the film in mm, rotation in degrees).
/// With `out_dir`, writes the command's files there (the same files, refused and committed the
/// same way). Returns a `FilmResult`; errors name the keyword argument.
#[pyfunction]
#[pyo3(signature = (image, *, pixel_size_mm=None, colour_table=None, density_calibration=None,
    max_colour_distance=DEFAULT_MAX_COLOUR_DISTANCE, channel="luma".to_string(), stain_rgb=None,
    unstained_density=None, smooth_mm=None, roi_rect_mm=None, roi_polygon_mm=None,
    min_patch_diameter_mm=2.0, rim_pixels=DEFAULT_RIM_PIXELS,
    max_elongation=regions::DEFAULT_MAX_ELONGATION, min_solidity=regions::DEFAULT_MIN_SOLIDITY,
    fit_order=4, nodes=None, nodes_region=None, node_offset_mm=None, node_rotation_deg=0.0,
    node_scale=1.0, total_load_n=None, reduce_mesh_size_mm=None, out_dir=None))]
#[allow(clippy::too_many_arguments)]
pub fn film(
    py: Python<'_>,
    image: PathBuf,
    pixel_size_mm: Option<f64>,
    colour_table: Option<PathBuf>,
    density_calibration: Option<PathBuf>,
    max_colour_distance: f64,
    channel: String,
    stain_rgb: Option<Vec<f64>>,
    unstained_density: Option<f64>,
    smooth_mm: Option<f64>,
    roi_rect_mm: Option<Vec<f64>>,
    roi_polygon_mm: Option<Vec<(f64, f64)>>,
    min_patch_diameter_mm: f64,
    rim_pixels: usize,
    max_elongation: f64,
    min_solidity: f64,
    fit_order: usize,
    nodes: Option<PathBuf>,
    nodes_region: Option<usize>,
    node_offset_mm: Option<(f64, f64)>,
    node_rotation_deg: f64,
    node_scale: f64,
    total_load_n: Option<f64>,
    reduce_mesh_size_mm: Option<f64>,
    out_dir: Option<PathBuf>,
) -> PyResult<FilmResult> {
    use asperity::film::pipeline::{self, FilmConfig};
    let config = FilmConfig {
        image,
        pixel_size_mm,
        colour_table,
        max_colour_distance,
        density_calibration,
        channel,
        stain_rgb,
        unstained_density,
        smooth_mm,
        roi_rect_mm,
        // The polygon's text form `x,y;x,y;...` (mm), as the CLI takes it and film.json
        // records it; `{}` prints each f64 so that it reads back exactly.
        roi_polygon_mm: roi_polygon_mm.map(|v| {
            v.iter()
                .map(|(x, y)| format!("{x},{y}"))
                .collect::<Vec<_>>()
                .join(";")
        }),
        min_patch_diameter_mm,
        rim_pixels,
        max_elongation,
        min_solidity,
        fit_order,
        nodes,
        nodes_region,
        node_offset_mm: node_offset_mm.map(|(x, y)| vec![x, y]),
        node_rotation_deg,
        node_scale,
        total_load_n,
        reduce_mesh_size_mm,
    };
    let (inner, written) = py
        .detach(|| {
            let out = match &out_dir {
                Some(dir) => Some(pipeline::output_set(&config, dir, "out_dir")?),
                None => None,
            };
            let report = pipeline::run(&config, &mut |_| {})?;
            let written = match out {
                Some(mut out) => {
                    let staged = out.staging_dir()?;
                    report.write(&staged)?;
                    out.commit()?
                }
                None => Vec::new(),
            };
            Ok::<_, asperity::Error>((report, written))
        })
        .map_err(keyword_error)
        .py()?;
    Ok(FilmResult { inner, written })
}

/// What `film_preloads` did: counts, areas and totals of the node preloads (the `preloads` of
/// film.json's node summary).
#[pyclass(frozen, get_all, module = "asperity")]
pub struct PreloadSummary {
    /// Nodes with a preload.
    pub n_nodes: usize,
    /// Total tributary area (m²).
    pub total_area_m2: f64,
    /// ΣN0 before any rescaling (N).
    pub raw_total_load_n: f64,
    /// ΣN0 after rescaling to `total_load_n` (N).
    pub total_load_n: f64,
    /// Factor applied to every preload (1 without a target load).
    pub load_scale: f64,
    /// Nodes whose fitted pressure was negative (polynomial undershoot), set to zero.
    pub clamped_negative: usize,
    /// Whether the areas came from a Delaunay triangulation.
    pub areas_from_triangulation: bool,
    /// Area of the Delaunay triangles left out as gaps of the node set (m²; 0 with given areas).
    pub gap_area_m2: f64,
    /// Number of those triangles.
    pub gap_triangles: usize,
}

impl From<&nodes::PreloadSummary> for PreloadSummary {
    fn from(s: &nodes::PreloadSummary) -> Self {
        Self {
            n_nodes: s.n_nodes,
            total_area_m2: s.total_area_m2,
            raw_total_load_n: s.raw_total_load_n,
            total_load_n: s.total_load_n,
            load_scale: s.load_scale,
            clamped_negative: s.clamped_negative,
            areas_from_triangulation: s.areas_from_triangulation,
            gap_area_m2: s.gap_area_m2,
            gap_triangles: s.gap_triangles,
        }
    }
}

#[pymethods]
impl PreloadSummary {
    fn __repr__(&self) -> String {
        format!(
            "PreloadSummary({} nodes, {:e} m², {} N)",
            self.n_nodes, self.total_area_m2, self.total_load_n
        )
    }
}

/// A stained component entirely below the film's range (film frame, m).
#[pyclass(frozen, get_all, module = "asperity")]
pub struct BelowRangePatch {
    /// Centroid x (m).
    pub centre_x_m: f64,
    /// Centroid y (m).
    pub centre_y_m: f64,
    /// Diameter of the disc of the same area (m).
    pub equivalent_diameter_m: f64,
}

/// A region that could not be fitted, and why.
#[pyclass(frozen, get_all, module = "asperity")]
pub struct NotFitted {
    /// Region id (1-based).
    pub region: usize,
    /// Why the fit was not possible.
    pub reason: String,
}

/// Mesh frame → film frame of the node coordinates.
#[pyclass(frozen, get_all, module = "asperity")]
pub struct NodePlacement {
    /// Translation x of the mesh origin (m).
    pub offset_x_m: f64,
    /// Translation y of the mesh origin (m).
    pub offset_y_m: f64,
    /// Counter-clockwise rotation (rad).
    pub rotation_rad: f64,
    /// Uniform scale.
    pub scale: f64,
}

/// The nodes on one film pixel class and the fitted pressure under them (Pa).
#[pyclass(frozen, get_all, module = "asperity")]
pub struct NodeClassReading {
    /// `in_range`, `above_range`, `below_range` or `hole`.
    pub pixel_class: String,
    /// Nodes on pixels of this class.
    pub n_nodes: usize,
    /// Smallest fitted pressure under them (Pa; None without nodes).
    pub fitted_pressure_min_pa: Option<f64>,
    /// Largest fitted pressure under them (Pa; None without nodes).
    pub fitted_pressure_max_pa: Option<f64>,
}

/// The reduction of the preloaded nodes on a coarse triangular mesh.
#[pyclass(frozen, get_all, module = "asperity")]
pub struct ReductionSummary {
    /// Coarse triangle side (m).
    pub mesh_size_m: f64,
    /// Nodes kept.
    pub n_kept: usize,
    /// Total area of the kept nodes (m²).
    pub total_area_m2: f64,
    /// Total load of the kept nodes (N).
    pub total_load_n: f64,
}

/// The node part of a film run's summary.
#[pyclass(frozen, get_all, module = "asperity")]
pub struct NodeSummary {
    /// Id of the region whose fit preloads the nodes.
    pub region: usize,
    /// How the nodes were placed on the film.
    pub placement: Py<NodePlacement>,
    /// Totals of the preloads.
    pub preloads: Py<PreloadSummary>,
    /// Nodes and fitted pressures per film pixel class (in_range, above_range, below_range,
    /// hole).
    pub pixel_classes: Vec<Py<NodeClassReading>>,
    /// With a reduction mesh.
    pub reduction: Option<Py<ReductionSummary>>,
}

/// The `summary` of film.json: what `film()` found.
#[pyclass(frozen, get_all, module = "asperity")]
pub struct FilmSummary {
    /// Pixel counts over the whole image.
    pub image_pixels: Py<ClassCounts>,
    /// Automatic detection: components smaller than the smallest patch.
    pub discarded_small_components: usize,
    /// Automatic detection: components rejected by their shape as marks.
    pub rejected_marks: usize,
    /// Stained components entirely below the range.
    pub below_range_patches: Vec<Py<BelowRangePatch>>,
    /// Regions that could not be fitted, and why.
    pub regions_not_fitted: Vec<Py<NotFitted>>,
    /// Summary of each region.
    pub regions: Vec<Py<RegionSummary>>,
    /// Fit of each region (None: not fitted).
    pub fits: Vec<Option<Py<PolyFit>>>,
    /// With nodes: their placement, preloads and readings; else None.
    pub nodes: Option<Py<NodeSummary>>,
}

#[pymethods]
impl FilmSummary {
    fn __repr__(&self) -> String {
        format!(
            "FilmSummary({} regions, {} not fitted, {})",
            self.regions.len(),
            self.regions_not_fitted.len(),
            if self.nodes.is_some() {
                "nodes"
            } else {
                "no nodes"
            }
        )
    }
}

fn film_summary(py: Python<'_>, r: &asperity::film::pipeline::FilmReport) -> PyResult<FilmSummary> {
    let nodes = match &r.nodes {
        None => None,
        Some(n) => {
            let pixel_classes = n
                .class_readings
                .iter()
                .map(|(c, v)| {
                    Py::new(
                        py,
                        NodeClassReading {
                            pixel_class: c.name().to_string(),
                            n_nodes: v.n_nodes,
                            fitted_pressure_min_pa: v.fitted_pressure_min_pa,
                            fitted_pressure_max_pa: v.fitted_pressure_max_pa,
                        },
                    )
                })
                .collect::<PyResult<Vec<_>>>()?;
            let reduction = n
                .reduced
                .as_ref()
                .map(|red| {
                    Py::new(
                        py,
                        ReductionSummary {
                            mesh_size_m: red.mesh_size_m,
                            n_kept: red.nodes.len(),
                            total_area_m2: red.nodes.iter().map(|p| p.area_m2).sum(),
                            total_load_n: red.nodes.iter().map(|p| p.n0_n).sum(),
                        },
                    )
                })
                .transpose()?;
            let p = &n.placement;
            Some(Py::new(
                py,
                NodeSummary {
                    region: n.region,
                    placement: Py::new(
                        py,
                        NodePlacement {
                            offset_x_m: p.offset_x_m,
                            offset_y_m: p.offset_y_m,
                            rotation_rad: p.rotation_rad,
                            scale: p.scale,
                        },
                    )?,
                    preloads: Py::new(py, PreloadSummary::from(&n.summary))?,
                    pixel_classes,
                    reduction,
                },
            )?)
        }
    };
    Ok(FilmSummary {
        image_pixels: Py::new(py, ClassCounts::from(&r.pixel_counts))?,
        discarded_small_components: r.discarded_small_components,
        rejected_marks: r.rejected_marks,
        below_range_patches: r
            .below_range_patches
            .iter()
            .map(|b| {
                Py::new(
                    py,
                    BelowRangePatch {
                        centre_x_m: b.centre_x_m,
                        centre_y_m: b.centre_y_m,
                        equivalent_diameter_m: b.equivalent_diameter_m,
                    },
                )
            })
            .collect::<PyResult<_>>()?,
        regions_not_fitted: r
            .not_fitted
            .iter()
            .map(|f| {
                Py::new(
                    py,
                    NotFitted {
                        region: f.region,
                        reason: f.reason.clone(),
                    },
                )
            })
            .collect::<PyResult<_>>()?,
        regions: r
            .summaries
            .iter()
            .map(|s| Py::new(py, RegionSummary::from(s)))
            .collect::<PyResult<_>>()?,
        fits: r
            .fits
            .iter()
            .map(|f| {
                f.as_ref()
                    .map(|f| Py::new(py, PolyFit { inner: f.clone() }))
                    .transpose()
            })
            .collect::<PyResult<_>>()?,
        nodes,
    })
}
