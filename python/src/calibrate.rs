//! The calibration table (kn, E0, k, μ, Et per unit area versus pressure): read, interpolate,
//! write; and its join with node preloads into one row per contact element.

use crate::arrays::borrow_f64;
use crate::errors::IntoPy;
use asperity::calibrate::convergence::Check;
use asperity::calibrate::pipeline;
use asperity::calibrate::table::{self, RangeFlag};
use asperity::elements::{self, ElementRow};
use asperity::film::nodes::Preload;
use asperity::film::NodePixel;
use asperity::surface::generate::GaussianSurfaceSpec;
use ndarray::Ix1;
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

/// Calibration table: rows of pressure (Pa), contact area ratio, kn, E0, Et (N/m³), k, μ, fit R²
/// and energy per cycle (J/m²), strictly increasing in pressure.
#[pyclass(frozen, module = "asperity")]
pub struct CalibrationTable {
    pub inner: table::CalibrationTable,
}

fn range_code(r: RangeFlag) -> i8 {
    match r {
        RangeFlag::Below => -1,
        RangeFlag::Within => 0,
        RangeFlag::Above => 1,
    }
}

#[pymethods]
impl CalibrationTable {
    /// Read `calibration_table.csv` (as written by `asperity calibrate`); errors name the file
    /// and line.
    #[staticmethod]
    fn read_csv(path: PathBuf) -> PyResult<Self> {
        Ok(Self {
            inner: table::CalibrationTable::read_csv(&path).py()?,
        })
    }

    /// Write the table (atomic).
    fn write_csv(&self, path: PathBuf) -> PyResult<()> {
        self.inner.write_csv(&path).py()
    }

    /// The columns as numpy arrays, named as in the CSV header.
    fn columns<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        let rows = &self.inner.rows;
        let fields: [fn(&table::CalibrationRow) -> f64; 9] = [
            |r| r.pressure_pa,
            |r| r.contact_area_ratio,
            |r| r.element.kn_n_per_m3,
            |r| r.element.e0_n_per_m3,
            |r| r.element.k,
            |r| r.element.mu,
            |r| r.element.et_n_per_m3,
            |r| r.fit_r2,
            |r| r.energy_per_cycle_j_per_m2,
        ];
        for (name, f) in table::COLUMNS.iter().zip(fields) {
            d.set_item(*name, PyArray1::from_vec(py, rows.iter().map(f).collect()))?;
        }
        // A table over several realisations: the realisation count and the 95 % interval
        // half-widths of the means.
        if let Some(iv) = &self.inner.intervals {
            let fields: [fn(&table::RowInterval) -> f64; 7] = [
                |r| r.realisations as f64,
                |r| r.contact_area_ratio,
                |r| r.kn_n_per_m3,
                |r| r.e0_n_per_m3,
                |r| r.k,
                |r| r.et_n_per_m3,
                |r| r.energy_per_cycle_j_per_m2,
            ];
            for (name, f) in table::INTERVAL_COLUMNS.iter().zip(fields) {
                d.set_item(*name, PyArray1::from_vec(py, iv.iter().map(f).collect()))?;
            }
        }
        // A table written by `asperity calibrate`: each row's convergence verdict (strings).
        if let Some(c) = &self.inner.convergence {
            let names: Vec<&str> = c.iter().map(|v| v.name()).collect();
            d.set_item(table::CONVERGENCE_COLUMN, names)?;
        }
        Ok(d)
    }

    /// (lowest, highest) tabulated pressure (Pa).
    #[getter]
    fn pressure_range(&self) -> (f64, f64) {
        self.inner.pressure_range()
    }

    /// Element parameters at `pressure_pa` (Pa; a number or a float64 array): monotone cubic
    /// (Fritsch–Carlson) in ln p inside the table; outside it kn, E0 and the contact area ratio
    /// follow the end pair's power law (Et keeps Et/E0, k and μ the end row's values).
    /// Returns a `TableValues` for a number, a `TableColumns` (arrays) for an array; `range` is
    /// −1 below, 0 within, +1 above the table.
    fn interpolate<'py>(
        &self,
        py: Python<'py>,
        pressure_pa: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        if let Ok(p) = pressure_pa.extract::<f64>() {
            let v = self.inner.interpolate(p);
            let values = TableValues {
                pressure_pa: v.pressure_pa,
                contact_area_ratio: v.contact_area_ratio,
                kn_n_per_m3: v.element.kn_n_per_m3,
                e0_n_per_m3: v.element.e0_n_per_m3,
                k: v.element.k,
                mu: v.element.mu,
                et_n_per_m3: v.element.et_n_per_m3,
                range: range_code(v.range),
            };
            return Ok(Bound::new(py, values)?.into_any());
        }
        let p = borrow_f64::<Ix1>(pressure_pa, "pressure_pa", "pressures (Pa)")?;
        let vals: Vec<_> = p
            .as_slice()
            .expect("contiguous")
            .iter()
            .map(|&p| self.inner.interpolate(p))
            .collect();
        let col = |f: fn(&table::Interpolated) -> f64| {
            PyArray1::from_vec(py, vals.iter().map(f).collect::<Vec<f64>>()).unbind()
        };
        let columns = TableColumns {
            pressure_pa: col(|v| v.pressure_pa),
            contact_area_ratio: col(|v| v.contact_area_ratio),
            kn_n_per_m3: col(|v| v.element.kn_n_per_m3),
            e0_n_per_m3: col(|v| v.element.e0_n_per_m3),
            k: col(|v| v.element.k),
            mu: col(|v| v.element.mu),
            et_n_per_m3: col(|v| v.element.et_n_per_m3),
            range: PyArray1::from_vec(py, vals.iter().map(|v| range_code(v.range)).collect())
                .unbind(),
        };
        Ok(Bound::new(py, columns)?.into_any())
    }

    fn __len__(&self) -> usize {
        self.inner.rows.len()
    }

    fn __repr__(&self) -> String {
        let (lo, hi) = self.inner.pressure_range();
        format!(
            "CalibrationTable({} rows, {lo:e}–{hi:e} Pa)",
            self.inner.rows.len()
        )
    }
}

/// The columns of a preload table (`id`, `x_m`, `y_m`, `area_m2`, `pressure_Pa`, `N0_N`) as
/// numpy arrays.
pub fn preload_columns<'py>(py: Python<'py>, rows: &[Preload]) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let col =
        |f: fn(&Preload) -> f64| PyArray1::from_vec(py, rows.iter().map(f).collect::<Vec<f64>>());
    d.set_item(
        "id",
        PyArray1::from_vec(py, rows.iter().map(|r| r.id).collect::<Vec<u64>>()),
    )?;
    d.set_item("x_m", col(|r| r.x_m))?;
    d.set_item("y_m", col(|r| r.y_m))?;
    d.set_item("area_m2", col(|r| r.area_m2))?;
    d.set_item("pressure_Pa", col(|r| r.pressure_pa))?;
    d.set_item("N0_N", col(|r| r.n0_n))?;
    Ok(d)
}

/// Preloads from a dict of columns (`id` integer array, the others float64 arrays).
pub fn preloads_from_columns(columns: &Bound<'_, PyDict>) -> PyResult<Vec<Preload>> {
    let py = columns.py();
    let get = |name: &str| -> PyResult<Bound<'_, PyAny>> {
        columns.get_item(name)?.ok_or_else(|| {
            crate::errors::parameter(
                py,
                "preloads",
                format!("missing column `{name}` (need id, x_m, y_m, area_m2, pressure_Pa, N0_N)"),
            )
        })
    };
    let ids: Vec<u64> = get("id")?.extract()?;
    let mut cols = Vec::new();
    for name in ["x_m", "y_m", "area_m2", "pressure_Pa", "N0_N"] {
        let obj = get(name)?;
        let a = borrow_f64::<Ix1>(&obj, name, "preload column")?;
        let v = crate::arrays::finite_slice(py, &a, name)?.to_vec();
        if v.len() != ids.len() {
            return Err(crate::errors::parameter(
                py,
                name,
                format!("{} values for {} ids", v.len(), ids.len()),
            ));
        }
        cols.push(v);
    }
    Ok((0..ids.len())
        .map(|i| Preload {
            id: ids[i],
            x_m: cols[0][i],
            y_m: cols[1][i],
            area_m2: cols[2][i],
            pressure_pa: cols[3][i],
            n0_n: cols[4][i],
        })
        .collect())
}

fn element_columns<'py>(py: Python<'py>, rows: &[ElementRow]) -> PyResult<Bound<'py, PyDict>> {
    let nodes: Vec<Preload> = rows
        .iter()
        .map(|r| Preload {
            id: r.id,
            x_m: r.x_m,
            y_m: r.y_m,
            area_m2: r.area_m2,
            pressure_pa: r.pressure_pa,
            n0_n: r.n0_n,
        })
        .collect();
    let d = preload_columns(py, &nodes)?;
    let col = |f: fn(&ElementRow) -> f64| {
        PyArray1::from_vec(py, rows.iter().map(f).collect::<Vec<f64>>())
    };
    d.set_item("kn_N_per_m", col(|r| r.element.kn_n_per_m))?;
    d.set_item("E0_N_per_m", col(|r| r.element.e0_n_per_m))?;
    d.set_item("k", col(|r| r.element.k))?;
    d.set_item("mu", col(|r| r.element.mu))?;
    d.set_item("Et_N_per_m", col(|r| r.element.et_n_per_m))?;
    d.set_item(
        "out_of_range",
        PyArray1::from_vec(py, rows.iter().map(|r| r.out_of_range).collect::<Vec<i8>>()),
    )?;
    Ok(d)
}

/// One row per contact element (`asperity elements`): each preloaded node (a dict of preload
/// columns, as `film_preloads` or `read_preloads` return) joined with the table at its
/// pressure; kn, E0, Et scaled by the node's area (N/m), k and μ as tabulated, out-of-range
/// pressures flagged (−1/+1) and continued by the end pair's power law, nodes of zero pressure
/// (open contact) left out and counted. Returns `(columns, ElementSummary)`; with
/// `out=path` the element CSV is written too (atomic).
#[pyfunction]
#[pyo3(signature = (preloads, table, out=None))]
pub fn join_elements<'py>(
    py: Python<'py>,
    preloads: &Bound<'py, PyDict>,
    table: &CalibrationTable,
    out: Option<PathBuf>,
) -> PyResult<(Bound<'py, PyDict>, ElementSummary)> {
    let pre = preloads_from_columns(preloads)?;
    let (rows, summary) = elements::join(&pre, &table.inner).py()?;
    if let Some(path) = out {
        elements::write_csv(&path, &rows).py()?;
    }
    Ok((element_columns(py, &rows)?, ElementSummary::from(&summary)))
}

/// Read a preload CSV (`id,x_m,y_m,area_m2,pressure_Pa,N0_N`) as a dict of columns.
#[pyfunction]
pub fn read_preloads(py: Python<'_>, path: PathBuf) -> PyResult<Bound<'_, PyDict>> {
    let rows = asperity::film::nodes::read_preloads_csv(&path).py()?;
    preload_columns(py, &rows)
}

/// Write preloads (a dict of columns) as the CSV `asperity film` writes, `comment` lines first.
#[pyfunction]
#[pyo3(signature = (path, preloads, comment=""))]
pub fn write_preloads(path: PathBuf, preloads: &Bound<'_, PyDict>, comment: &str) -> PyResult<()> {
    let rows = preloads_from_columns(preloads)?;
    // A `pixel_class` column (from `film_preloads`) is written as the CLI writes it.
    match preloads.get_item("pixel_class")? {
        Some(obj) => {
            let names: Vec<String> = obj.extract()?;
            let classes = names
                .iter()
                .map(|n| {
                    NodePixel::from_name(n).ok_or_else(|| {
                        crate::errors::parameter(
                            preloads.py(),
                            "pixel_class",
                            format!(
                                "unknown class `{n}` (in_range, above_range, below_range or hole)"
                            ),
                        )
                    })
                })
                .collect::<PyResult<Vec<_>>>()?;
            asperity::film::nodes::write_preloads_csv_with_classes(&path, &rows, &classes, comment)
                .py()
        }
        None => asperity::film::nodes::write_preloads_csv(&path, &rows, comment).py(),
    }
}

/// What `calibrate()` produced (the results of `asperity calibrate`).
#[pyclass(frozen, get_all, module = "asperity")]
pub struct CalibrationRun {
    /// The table of the means over the realisations.
    pub table: Py<CalibrationTable>,
    /// Columns per realisation × pressure: realisation, seed (−1 for a given surface),
    /// pressure_Pa, contact_area_ratio, kn_N_per_m3, mean_gap_m, gross_slip_displacement_m,
    /// E0_N_per_m3, k, Et_N_per_m3, fit_R2, contact_spots, median_spot_points.
    pub realisations: Py<PyDict>,
    /// The grid and patch checks per pressure, as calibration.json records them.
    pub convergence: Py<CalibrationConvergence>,
    /// Warnings of the run.
    pub warnings: Vec<String>,
    /// Files written into `out_dir` (empty without one).
    pub written: Vec<String>,
    /// Wall and CPU time of each stage (s).
    pub times: Py<StageTimes>,
}

#[pymethods]
impl CalibrationRun {
    fn __repr__(&self) -> String {
        format!(
            "CalibrationRun({} warnings, {} files written)",
            self.warnings.len(),
            self.written.len()
        )
    }
}

/// The calibration chain of `asperity calibrate` (surfaces → normal sweep → tangential loops at
/// several amplitudes → Valanis fits → table with 95 % intervals, grid and patch checks).
///
/// `config`: a calibration TOML file (None: the built-in reference case); `grid` and
/// `realisations` override it as the CLI's `--grid`/`--realisations` do; `surface`: a
/// `Surface` (heights in m) to calibrate on instead of generated ones (one realisation, no
/// checks). With `out_dir`, writes the files of `asperity calibrate --out-dir` (identical to
/// the CLI's on the same inputs, `calibration_timings.csv` excepted).
///
/// Returns a `CalibrationRun`.
#[pyfunction]
#[pyo3(signature = (config=None, *, grid=None, realisations=None, surface=None, out_dir=None))]
pub fn calibrate<'py>(
    py: Python<'py>,
    config: Option<PathBuf>,
    grid: Option<usize>,
    realisations: Option<usize>,
    surface: Option<&crate::surface::Surface>,
    out_dir: Option<PathBuf>,
) -> PyResult<CalibrationRun> {
    use asperity::calibrate::config::CalibrationConfig;
    use asperity::calibrate::output::{self, ConfigSource};
    use asperity::calibrate::pipeline::SurfaceSource;
    let (mut cfg, source) = match &config {
        Some(path) => {
            let bytes = std::fs::read(path)
                .map_err(|e| asperity::Error::io(path, e))
                .py()?;
            (
                CalibrationConfig::read(path).py()?,
                ConfigSource::file(path, &bytes),
            )
        }
        None => (CalibrationConfig::reference(), ConfigSource::BuiltIn),
    };
    let rename = |e: asperity::Error, name: &str| match e {
        asperity::Error::InvalidParameter { message, .. } => asperity::Error::param(name, message),
        other => other,
    };
    if let Some(n) = grid {
        if surface.is_some() {
            return Err(crate::errors::parameter(
                py,
                "grid",
                "applies to the generated surfaces, not to a given surface".into(),
            ));
        }
        cfg.surface.nx = n;
        cfg.surface.ny = n;
        cfg.validate().map_err(|e| rename(e, "grid")).py()?;
    }
    if let Some(n) = realisations {
        if surface.is_some() && n != 1 {
            return Err(crate::errors::parameter(
                py,
                "realisations",
                "a given surface is one realisation".into(),
            ));
        }
        cfg.realisations.count = n;
        cfg.validate().map_err(|e| rename(e, "realisations")).py()?;
    }
    let surfaces = match surface {
        None => SurfaceSource::Generated,
        Some(s) => {
            cfg.realisations.count = 1;
            SurfaceSource::Given {
                surface: s.grid().clone(),
                description: "a Surface given from Python".to_string(),
            }
        }
    };
    let (run, written) = py
        .detach(|| {
            let run = pipeline::run(&cfg, &surfaces, &indicatif::ProgressBar::hidden())?;
            let written = match &out_dir {
                Some(dir) => output::write_outputs(&run, &source, dir)?.0,
                None => Vec::new(),
            };
            Ok::<_, asperity::Error>((run, written))
        })
        .py()?;
    let rows: Vec<(
        usize,
        &pipeline::Realisation,
        &pipeline::PressureCalibration,
    )> = run
        .realisations
        .iter()
        .enumerate()
        .flat_map(|(i, r)| r.pressures.iter().map(move |pc| (i + 1, r, pc)))
        .collect();
    let cols = PyDict::new(py);
    cols.set_item(
        "realisation",
        PyArray1::from_vec(py, rows.iter().map(|r| r.0 as i64).collect::<Vec<_>>()),
    )?;
    cols.set_item(
        "seed",
        PyArray1::from_vec(
            py,
            rows.iter()
                .map(|r| r.1.seed.map_or(-1, |s| s as i64))
                .collect::<Vec<_>>(),
        ),
    )?;
    type Get = fn(&pipeline::PressureCalibration) -> f64;
    let fields: [(&str, Get); 11] = [
        ("pressure_Pa", |pc| pc.sweep.pressure_pa),
        ("contact_area_ratio", |pc| pc.sweep.contact_area_ratio),
        ("kn_N_per_m3", |pc| pc.sweep.kn_n_per_m3),
        ("mean_gap_m", |pc| pc.sweep.mean_gap_m),
        ("gross_slip_displacement_m", |pc| {
            pc.amplitudes.gross_slip_displacement_m
        }),
        ("E0_N_per_m3", |pc| pc.fit.params.e0),
        ("k", |pc| pc.fit.params.k),
        ("Et_N_per_m3", |pc| pc.fit.params.et),
        ("fit_R2", |pc| pc.fit.r2),
        ("contact_spots", |pc| pc.sweep.contact_spots as f64),
        ("median_spot_points", |pc| {
            pc.sweep.median_spot_points as f64
        }),
    ];
    for (name, f) in fields {
        cols.set_item(
            name,
            PyArray1::from_vec(py, rows.iter().map(|r| f(r.2)).collect::<Vec<_>>()),
        )?;
    }
    Ok(CalibrationRun {
        table: Py::new(
            py,
            CalibrationTable {
                inner: run.table.clone(),
            },
        )?,
        realisations: cols.unbind(),
        convergence: Py::new(py, convergence(py, &run.convergence)?)?,
        warnings: run.warnings.clone(),
        written: written.iter().map(|p| p.display().to_string()).collect(),
        times: Py::new(py, StageTimes::from(&run.times))?,
    })
}

/// Element parameters the table gives at one pressure (`CalibrationTable.interpolate` of a
/// number).
#[pyclass(frozen, get_all, module = "asperity")]
pub struct TableValues {
    /// The pressure asked for (Pa).
    pub pressure_pa: f64,
    /// Real over nominal contact area.
    pub contact_area_ratio: f64,
    /// Normal stiffness per unit area (N/m³).
    pub kn_n_per_m3: f64,
    /// Valanis initial tangential stiffness per unit area (N/m³).
    pub e0_n_per_m3: f64,
    /// Valanis shape parameter k.
    pub k: f64,
    /// Friction coefficient μ.
    pub mu: f64,
    /// Valanis tangent stiffness after macroslip per unit area (N/m³).
    pub et_n_per_m3: f64,
    /// −1 below, 0 within, +1 above the table's pressures.
    pub range: i8,
}

#[pymethods]
impl TableValues {
    fn __repr__(&self) -> String {
        format!(
            "TableValues(pressure_pa={:e}, kn_n_per_m3={:e}, e0_n_per_m3={:e}, k={}, mu={}, \
             et_n_per_m3={:e}, range={})",
            self.pressure_pa,
            self.kn_n_per_m3,
            self.e0_n_per_m3,
            self.k,
            self.mu,
            self.et_n_per_m3,
            self.range
        )
    }
}

/// Element parameters the table gives at each of several pressures
/// (`CalibrationTable.interpolate` of an array): one float64 array per quantity, `range` int8.
#[pyclass(frozen, get_all, module = "asperity")]
pub struct TableColumns {
    /// The pressures asked for (Pa).
    pub pressure_pa: Py<PyArray1<f64>>,
    /// Real over nominal contact area.
    pub contact_area_ratio: Py<PyArray1<f64>>,
    /// Normal stiffness per unit area (N/m³).
    pub kn_n_per_m3: Py<PyArray1<f64>>,
    /// Valanis initial tangential stiffness per unit area (N/m³).
    pub e0_n_per_m3: Py<PyArray1<f64>>,
    /// Valanis shape parameter k.
    pub k: Py<PyArray1<f64>>,
    /// Friction coefficient μ.
    pub mu: Py<PyArray1<f64>>,
    /// Valanis tangent stiffness after macroslip per unit area (N/m³).
    pub et_n_per_m3: Py<PyArray1<f64>>,
    /// −1 below, 0 within, +1 above the table's pressures.
    pub range: Py<PyArray1<i8>>,
}

#[pymethods]
impl TableColumns {
    fn __len__(&self, py: Python<'_>) -> usize {
        numpy::PyUntypedArrayMethods::len(self.pressure_pa.bind(py))
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        format!(
            "TableColumns({} pressures)",
            numpy::PyUntypedArrayMethods::len(self.pressure_pa.bind(py))
        )
    }
}

/// Counts and totals of `join_elements` (as the summary of `asperity elements`).
#[pyclass(frozen, get_all, module = "asperity")]
pub struct ElementSummary {
    /// Elements (nodes of non-zero pressure).
    pub n_elements: usize,
    /// Nodes of zero pressure (open contact), left out.
    pub n_open: usize,
    /// Ids of the open nodes.
    pub open_ids: Vec<u64>,
    /// Total tributary area of the open nodes (m²).
    pub open_area_m2: f64,
    /// Elements below the table's first pressure.
    pub n_below_range: usize,
    /// Elements above the table's last pressure (at most 10× it).
    pub n_above_range: usize,
    /// Ids of the elements below the table's range.
    pub below_range_ids: Vec<u64>,
    /// Ids of the elements above the table's range.
    pub above_range_ids: Vec<u64>,
    /// Elements taking their values from rows judged not converged in grid or patch size.
    pub not_converged_row_ids: Vec<u64>,
    /// Elements taking their values from rows whose convergence could not be judged.
    pub undetermined_row_ids: Vec<u64>,
    /// Total tributary area of the elements (m²).
    pub total_area_m2: f64,
    /// Total normal preload ΣN0 of the elements (N).
    pub total_load_n: f64,
    /// Smallest pressure of the table (Pa).
    pub table_pressure_min_pa: f64,
    /// Largest pressure of the table (Pa).
    pub table_pressure_max_pa: f64,
    /// Smallest element pressure (Pa).
    pub element_pressure_min_pa: f64,
    /// Largest element pressure (Pa).
    pub element_pressure_max_pa: f64,
}

impl From<&elements::ElementSummary> for ElementSummary {
    fn from(s: &elements::ElementSummary) -> Self {
        Self {
            n_elements: s.n_elements,
            n_open: s.n_open,
            open_ids: s.open_ids.clone(),
            open_area_m2: s.open_area_m2,
            n_below_range: s.n_below_range,
            n_above_range: s.n_above_range,
            below_range_ids: s.below_range_ids.clone(),
            above_range_ids: s.above_range_ids.clone(),
            not_converged_row_ids: s.not_converged_row_ids.clone(),
            undetermined_row_ids: s.undetermined_row_ids.clone(),
            total_area_m2: s.total_area_m2,
            total_load_n: s.total_load_n,
            table_pressure_min_pa: s.table_pressure_min_pa,
            table_pressure_max_pa: s.table_pressure_max_pa,
            element_pressure_min_pa: s.element_pressure_min_pa,
            element_pressure_max_pa: s.element_pressure_max_pa,
        }
    }
}

#[pymethods]
impl ElementSummary {
    fn __repr__(&self) -> String {
        format!(
            "ElementSummary({} elements, {} open, {} below / {} above the table)",
            self.n_elements, self.n_open, self.n_below_range, self.n_above_range
        )
    }
}

/// Wall and CPU time of each stage of `calibrate()` (s), summed over the chains.
#[pyclass(frozen, get_all, module = "asperity")]
pub struct StageTimes {
    /// Wall time generating (or hashing) the surfaces (s).
    pub surface_s: f64,
    /// Wall time of the normal-contact sweeps (s).
    pub normal_s: f64,
    /// Wall time of the tangential loops (s).
    pub tangential_s: f64,
    /// Wall time of the Valanis fits (s).
    pub fit_s: f64,
    /// CPU time of the surface stage (s).
    pub surface_cpu_s: f64,
    /// CPU time of the normal sweeps (s).
    pub normal_cpu_s: f64,
    /// CPU time of the tangential loops (s).
    pub tangential_cpu_s: f64,
    /// CPU time of the fits (s).
    pub fit_cpu_s: f64,
    /// Wall time of the whole run (s).
    pub total_s: f64,
}

impl From<&pipeline::StageTimes> for StageTimes {
    fn from(t: &pipeline::StageTimes) -> Self {
        Self {
            surface_s: t.surface_s,
            normal_s: t.normal_s,
            tangential_s: t.tangential_s,
            fit_s: t.fit_s,
            surface_cpu_s: t.surface_cpu_s,
            normal_cpu_s: t.normal_cpu_s,
            tangential_cpu_s: t.tangential_cpu_s,
            fit_cpu_s: t.fit_cpu_s,
            total_s: t.total_s,
        }
    }
}

#[pymethods]
impl StageTimes {
    fn __repr__(&self) -> String {
        format!("StageTimes(total_s={:.3})", self.total_s)
    }
}

/// A generated surface's statistics and grid (a convergence check's coarser configuration).
#[pyclass(frozen, get_all, module = "asperity")]
pub struct SurfaceSpec {
    /// Root-mean-square height Rq (m).
    pub rq_m: f64,
    /// 1/e correlation length along x (m).
    pub clx_m: f64,
    /// 1/e correlation length along y (m).
    pub cly_m: f64,
    /// Patch size along x (m).
    pub lx_m: f64,
    /// Patch size along y (m).
    pub ly_m: f64,
    /// Grid points along x.
    pub nx: usize,
    /// Grid points along y.
    pub ny: usize,
    /// Seed of the first surface.
    pub seed: u64,
}

impl From<&GaussianSurfaceSpec> for SurfaceSpec {
    fn from(s: &GaussianSurfaceSpec) -> Self {
        Self {
            rq_m: s.rq_m,
            clx_m: s.clx_m,
            cly_m: s.cly_m,
            lx_m: s.lx_m,
            ly_m: s.ly_m,
            nx: s.nx,
            ny: s.ny,
            seed: s.seed,
        }
    }
}

#[pymethods]
impl SurfaceSpec {
    fn __repr__(&self) -> String {
        format!(
            "SurfaceSpec({}×{} points, {:e}×{:e} m)",
            self.nx, self.ny, self.lx_m, self.ly_m
        )
    }
}

/// Mean, standard deviation and 95 % interval half-width of a quantity over the realisations.
#[pyclass(frozen, get_all, module = "asperity")]
pub struct SampleSummary {
    /// Number of values.
    pub n: usize,
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation (NaN with fewer than two values).
    pub sd: f64,
    /// Half-width of the 95 % confidence interval of the mean (Student t; NaN with fewer than
    /// two values).
    pub ci95: f64,
}

#[pymethods]
impl SampleSummary {
    fn __repr__(&self) -> String {
        format!(
            "SampleSummary(n={}, mean={}, ci95={})",
            self.n, self.mean, self.ci95
        )
    }
}

/// One grid or patch check of one quantity: the change from the coarser (or smaller) to the
/// main configuration with its 95 % interval, against the allowed change.
#[pyclass(frozen, get_all, module = "asperity")]
pub struct ConvergenceCheck {
    /// `kn`, `E0` or `k`.
    pub quantity: String,
    /// Change of the mean, main minus coarser (same unit as the quantity).
    pub change: f64,
    /// Half-width of the change's 95 % interval (NaN when it cannot be estimated).
    pub change_ci95: f64,
    /// Allowed change (same unit as the quantity).
    pub tolerance: f64,
    /// `converged`, `undetermined`, `not-converged` or `not-checked`.
    pub verdict: String,
}

#[pymethods]
impl ConvergenceCheck {
    fn __repr__(&self) -> String {
        format!(
            "ConvergenceCheck({}: {} ± {} against {}, {})",
            self.quantity, self.change, self.change_ci95, self.tolerance, self.verdict
        )
    }
}

/// Quantities of the checks, in the order of [`pipeline::PressureConvergence::grid`].
const CHECKED: [&str; 3] = ["kn", "E0", "k"];

fn checks(c: &[Check; 3]) -> Vec<ConvergenceCheck> {
    CHECKED
        .iter()
        .zip(c)
        .map(|(q, c)| ConvergenceCheck {
            quantity: q.to_string(),
            change: c.change.mean,
            change_ci95: c.change.ci95,
            tolerance: c.tolerance,
            verdict: c.verdict.name().to_string(),
        })
        .collect()
}

/// Convergence facts and verdicts at one pressure.
#[pyclass(frozen, get_all, module = "asperity")]
pub struct PressureConvergence {
    /// Nominal pressure (Pa).
    pub pressure_pa: f64,
    /// Contact spots on the patch over the realisations.
    pub contact_spots: Py<SampleSummary>,
    /// Median over the realisations of the median spot size (grid points).
    pub median_spot_points: f64,
    /// Smallest median spot size of a realisation (grid points).
    pub min_median_spot_points: usize,
    /// Realisations whose grid does not resolve the narrower of contact spots and free regions.
    pub under_resolved_realisations: usize,
    /// Fewest grid points across the narrower phase over the realisations.
    pub min_points_across: f64,
    /// Whether that narrowest phase is the contact spots (else the free regions).
    pub narrowest_is_contact: bool,
    /// Grid checks of kn, E0, k (n against n/2 points per side, same surfaces).
    pub grid: Vec<Py<ConvergenceCheck>>,
    /// Patch checks of kn, E0, k (L against L/2, independent surfaces).
    pub patch: Vec<Py<ConvergenceCheck>>,
    /// Worst grid verdict.
    pub grid_verdict: String,
    /// Worst patch verdict.
    pub patch_verdict: String,
}

#[pymethods]
impl PressureConvergence {
    fn __repr__(&self) -> String {
        format!(
            "PressureConvergence({:e} Pa: grid {}, patch {})",
            self.pressure_pa, self.grid_verdict, self.patch_verdict
        )
    }
}

/// The grid and patch checks of `calibrate()` (as `convergence` in calibration.json).
#[pyclass(frozen, get_all, module = "asperity")]
pub struct CalibrationConvergence {
    /// The grid check's surfaces: half the points per side (None: not run).
    pub grid_spec: Option<Py<SurfaceSpec>>,
    /// The patch check's surfaces: half the patch side at the same spacing (None: not run).
    pub patch_spec: Option<Py<SurfaceSpec>>,
    /// Why a check was not run.
    pub notes: Vec<String>,
    /// Verdicts per pressure.
    pub pressures: Vec<Py<PressureConvergence>>,
}

#[pymethods]
impl CalibrationConvergence {
    fn __repr__(&self) -> String {
        format!("CalibrationConvergence({} pressures)", self.pressures.len())
    }
}

fn convergence(py: Python<'_>, c: &pipeline::ConvergenceStudy) -> PyResult<CalibrationConvergence> {
    let spec = |s: &Option<GaussianSurfaceSpec>| {
        s.as_ref()
            .map(|s| Py::new(py, SurfaceSpec::from(s)))
            .transpose()
    };
    let list = |c: &[Check; 3]| {
        checks(c)
            .into_iter()
            .map(|c| Py::new(py, c))
            .collect::<PyResult<Vec<_>>>()
    };
    let pressures = c
        .pressures
        .iter()
        .map(|p| {
            Py::new(
                py,
                PressureConvergence {
                    pressure_pa: p.pressure_pa,
                    contact_spots: Py::new(
                        py,
                        SampleSummary {
                            n: p.contact_spots.n,
                            mean: p.contact_spots.mean,
                            sd: p.contact_spots.sd,
                            ci95: p.contact_spots.ci95,
                        },
                    )?,
                    median_spot_points: p.median_spot_points,
                    min_median_spot_points: p.min_median_spot_points,
                    under_resolved_realisations: p.under_resolved_realisations,
                    min_points_across: p.min_points_across,
                    narrowest_is_contact: p.narrowest_is_contact,
                    grid: list(&p.grid)?,
                    patch: list(&p.patch)?,
                    grid_verdict: p.grid_verdict.name().to_string(),
                    patch_verdict: p.patch_verdict.name().to_string(),
                },
            )
        })
        .collect::<PyResult<Vec<_>>>()?;
    Ok(CalibrationConvergence {
        grid_spec: spec(&c.grid_spec)?,
        patch_spec: spec(&c.patch_spec)?,
        notes: c.notes.clone(),
        pressures,
    })
}
