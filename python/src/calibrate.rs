//! The calibration table (kn, E0, k, μ, Et per unit area versus pressure): read, interpolate,
//! write; and its join with node preloads into one row per contact element.

use crate::arrays::borrow_f64;
use crate::errors::{to_python, IntoPy};
use asperity::calibrate::table::{self, RangeFlag};
use asperity::elements::{self, ElementRow};
use asperity::film::nodes::Preload;
use asperity::film::NodePixel;
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
    /// Returns a dict with `pressure_Pa`, `contact_area_ratio`, `kn_N_per_m3`, `E0_N_per_m3`,
    /// `k`, `mu`, `Et_N_per_m3` and `range` (−1 below, 0 within, +1 above the table), as numbers
    /// or arrays like the argument.
    fn interpolate<'py>(
        &self,
        py: Python<'py>,
        pressure_pa: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        if let Ok(p) = pressure_pa.extract::<f64>() {
            let v = self.inner.interpolate(p);
            d.set_item("pressure_Pa", v.pressure_pa)?;
            d.set_item("contact_area_ratio", v.contact_area_ratio)?;
            d.set_item("kn_N_per_m3", v.element.kn_n_per_m3)?;
            d.set_item("E0_N_per_m3", v.element.e0_n_per_m3)?;
            d.set_item("k", v.element.k)?;
            d.set_item("mu", v.element.mu)?;
            d.set_item("Et_N_per_m3", v.element.et_n_per_m3)?;
            d.set_item("range", range_code(v.range))?;
            return Ok(d);
        }
        let p = borrow_f64::<Ix1>(pressure_pa, "pressure_pa", "pressures (Pa)")?;
        let vals: Vec<_> = p
            .as_slice()
            .expect("contiguous")
            .iter()
            .map(|&p| self.inner.interpolate(p))
            .collect();
        let col = |f: fn(&table::Interpolated) -> f64| {
            PyArray1::from_vec(py, vals.iter().map(f).collect::<Vec<f64>>())
        };
        d.set_item("pressure_Pa", col(|v| v.pressure_pa))?;
        d.set_item("contact_area_ratio", col(|v| v.contact_area_ratio))?;
        d.set_item("kn_N_per_m3", col(|v| v.element.kn_n_per_m3))?;
        d.set_item("E0_N_per_m3", col(|v| v.element.e0_n_per_m3))?;
        d.set_item("k", col(|v| v.element.k))?;
        d.set_item("mu", col(|v| v.element.mu))?;
        d.set_item("Et_N_per_m3", col(|v| v.element.et_n_per_m3))?;
        d.set_item(
            "range",
            PyArray1::from_vec(
                py,
                vals.iter()
                    .map(|v| range_code(v.range))
                    .collect::<Vec<i8>>(),
            ),
        )?;
        Ok(d)
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
/// (open contact) left out and counted. Returns `(columns, summary)`; with
/// `out=path` the element CSV is written too (atomic).
#[pyfunction]
#[pyo3(signature = (preloads, table, out=None))]
pub fn join_elements<'py>(
    py: Python<'py>,
    preloads: &Bound<'py, PyDict>,
    table: &CalibrationTable,
    out: Option<PathBuf>,
) -> PyResult<(Bound<'py, PyDict>, Bound<'py, PyAny>)> {
    let pre = preloads_from_columns(preloads)?;
    let (rows, summary) = elements::join(&pre, &table.inner).py()?;
    if let Some(path) = out {
        elements::write_csv(&path, &rows).py()?;
    }
    Ok((element_columns(py, &rows)?, to_python(py, &summary)?))
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
    pub convergence: Py<PyAny>,
    /// Warnings of the run.
    pub warnings: Vec<String>,
    /// Files written into `out_dir` (empty without one).
    pub written: Vec<String>,
    /// Wall time of each stage (s).
    pub times: Py<PyAny>,
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
    use asperity::calibrate::pipeline::{self, SurfaceSource};
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
        convergence: to_python(py, &run.convergence)?.unbind(),
        warnings: run.warnings.clone(),
        written: written.iter().map(|p| p.display().to_string()).collect(),
        times: to_python(py, &run.times)?.unbind(),
    })
}
