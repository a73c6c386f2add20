//! Measured hysteresis record → Valanis baseline → missing effect (selected on held-out cycles)
//! → errors before and after: `asperity diagnose` from numpy arrays. Time in s, displacement in
//! m, forces in N, stiffnesses in N/m.

use crate::arrays::{borrow_f64, finite_slice};
use crate::element::ValanisParams;
use crate::errors::{to_python, IntoPy};
use asperity::diagnose::report::{InputInfo, Report};
use asperity::diagnose::{Baseline, BaselineSource, Columns, Options, Record};
use ndarray::Ix1;
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

/// Read the chosen columns of a record CSV: `{"time_s", "displacement_m", "force_N"[,
/// "normal_force_N"]}` as float64 arrays.
#[pyfunction]
#[pyo3(signature = (path, *, time_column="time_s", displacement_column="displacement_m", force_column="friction_force_N", normal_force_column=None))]
pub fn read_record<'py>(
    py: Python<'py>,
    path: PathBuf,
    time_column: &str,
    displacement_column: &str,
    force_column: &str,
    normal_force_column: Option<String>,
) -> PyResult<Bound<'py, PyDict>> {
    let columns = Columns {
        time: time_column.into(),
        displacement: displacement_column.into(),
        force: force_column.into(),
        normal_force: normal_force_column,
    };
    let r = Record::read_csv(&path, &columns).py()?;
    let d = PyDict::new(py);
    d.set_item("time_s", PyArray1::from_vec(py, r.time_s))?;
    d.set_item("displacement_m", PyArray1::from_vec(py, r.displacement_m))?;
    d.set_item("force_N", PyArray1::from_vec(py, r.force_n))?;
    if let Some(nf) = r.normal_force_n {
        d.set_item("normal_force_N", PyArray1::from_vec(py, nf))?;
    }
    Ok(d)
}

fn column(obj: &Bound<'_, PyAny>, name: &str, what: &str) -> PyResult<Vec<f64>> {
    let a = borrow_f64::<Ix1>(obj, name, what)?;
    Ok(finite_slice(obj.py(), &a, name)?.to_vec())
}

/// Diagnose a record: fit (or take) a Valanis baseline, estimate the noise floor from the
/// record's cycle-to-cycle repeatability, search the candidate effects by their held-out
/// evidence against that floor, give one of three verdicts (effect(s) found, model adequate,
/// model inadequate with where the residual sits) and the errors before and after. The baseline is fitted to
/// the training cycles, or given as `baseline` (a `ValanisParams` in N/m) with the mean normal
/// load `normal_n` (N). Returns the report of `diagnose.json` (dict) with, under `"series"`,
/// the analysed samples and both models' forces as arrays. Runs without the GIL.
#[pyfunction]
#[pyo3(signature = (time_s, displacement_m, force_n, normal_force_n=None, *, baseline=None, normal_n=None, max_effects=2, source="numpy arrays"))]
#[allow(clippy::too_many_arguments)]
pub fn diagnose<'py>(
    py: Python<'py>,
    time_s: &Bound<'py, PyAny>,
    displacement_m: &Bound<'py, PyAny>,
    force_n: &Bound<'py, PyAny>,
    normal_force_n: Option<&Bound<'py, PyAny>>,
    baseline: Option<&ValanisParams>,
    normal_n: Option<f64>,
    max_effects: usize,
    source: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let record = Record::new(
        column(time_s, "time_s", "sample times (s)")?,
        column(
            displacement_m,
            "displacement_m",
            "tangential displacement (m)",
        )?,
        column(force_n, "force_n", "tangential force (N)")?,
        normal_force_n
            .map(|n| column(n, "normal_force_n", "normal force (N)"))
            .transpose()?,
    )
    .py()?;
    let (baseline, baseline_source) = match (baseline, normal_n) {
        (Some(p), Some(n)) => (
            BaselineSource::Given(Baseline {
                valanis: p.inner,
                normal_n: asperity::core::error::require_positive("normal_n", n).py()?,
            }),
            "given".to_string(),
        ),
        (None, None) => (
            BaselineSource::Fitted,
            "fitted to the training cycles".to_string(),
        ),
        _ => {
            return Err(asperity::Error::param(
                "baseline / normal_n",
                "give both (a given baseline) or neither (a fitted one)",
            ))
            .py()
        }
    };
    let options = Options {
        baseline,
        max_effects,
        ..Options::default()
    };
    let d = py
        .detach(|| asperity::diagnose::diagnose(&record, &options))
        .py()?;
    let mut columns = vec!["time_s".into(), "displacement_m".into(), "force_N".into()];
    if record.normal_force_n.is_some() {
        columns.push("normal_force_N".into());
    }
    let report = Report::new(
        &d,
        InputInfo {
            file: source.to_string(),
            columns,
            baseline_source,
        },
    );
    let out = to_python(py, &report)?.cast_into::<PyDict>()?;
    let p = &d.prepared.record;
    let series = PyDict::new(py);
    series.set_item("time_s", PyArray1::from_slice(py, &p.time_s))?;
    series.set_item(
        "displacement_m",
        PyArray1::from_slice(py, &p.displacement_m),
    )?;
    series.set_item("force_N", PyArray1::from_slice(py, &p.force_n))?;
    series.set_item("baseline_force_N", PyArray1::from_vec(py, d.baseline_force))?;
    series.set_item("final_force_N", PyArray1::from_vec(py, d.final_force))?;
    out.set_item("series", series)?;
    out.set_item("text", report.text())?;
    Ok(out)
}
