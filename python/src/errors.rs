//! Python exceptions for `asperity::Error`: every error carries the Rust message as its text and
//! the fields of the variant as attributes. The classes live in `asperity/errors.py`:
//!
//! | Rust variant | Python class | also a |
//! |---|---|---|
//! | `Io` | `asperity.FileError` (`.filename`, `.errno`) | `OSError` |
//! | `Parse` | `asperity.ParseError` (`.path`, `.line`) | `ValueError` |
//! | `InvalidParameter` | `asperity.ParameterError` (`.name`) | `ValueError` |
//! | `NonConvergence` | `asperity.ConvergenceError` (`.solver`, `.iterations`, `.residual`, `.tolerance`) | `RuntimeError` |
//! | `Data` | `asperity.DataError` | `ValueError` |
//! | `Limit` | `asperity.ResourceLimitError` (`.name`) | `MemoryError` |
//!
//! and, for arrays of the wrong type or dtype, `asperity.ArrayTypeError` (a `TypeError`). All
//! derive from `asperity.Error`.

use pyo3::prelude::*;
use pyo3::types::PyDict;

/// An instance of `asperity.errors.<class>(message)` with the attributes `set` puts into the
/// dict, as a `PyErr`.
pub fn exception(
    py: Python<'_>,
    class: &str,
    message: String,
    set: impl FnOnce(&Bound<'_, PyDict>) -> PyResult<()>,
) -> PyErr {
    let make = || -> PyResult<PyErr> {
        let attrs = PyDict::new(py);
        set(&attrs)?;
        let exc = py
            .import("asperity.errors")?
            .getattr(class)?
            .call1((message,))?;
        for (k, v) in attrs.iter() {
            exc.setattr(k.cast_into::<pyo3::types::PyString>()?, v)?;
        }
        Ok(PyErr::from_value(exc))
    };
    make().unwrap_or_else(|e| e)
}

/// `asperity.ParameterError` (a `ValueError`) for a check made on the Python side (array shape,
/// layout, values).
pub fn parameter(py: Python<'_>, name: &str, message: String) -> PyErr {
    exception(
        py,
        "ParameterError",
        format!("invalid parameter `{name}`: {message}"),
        |d| d.set_item("name", name),
    )
}

/// `asperity.ArrayTypeError` (a `TypeError`): an argument is not an array of the right type.
pub fn array_type(py: Python<'_>, message: String) -> PyErr {
    exception(py, "ArrayTypeError", message, |_| Ok(()))
}

/// The Python exception of a library error (see the module documentation).
pub fn to_py(e: asperity::Error) -> PyErr {
    Python::attach(|py| {
        let message = e.to_string();
        match e {
            asperity::Error::Io { path, source } => exception(py, "FileError", message, |d| {
                d.set_item("filename", path.display().to_string())?;
                d.set_item("errno", source.raw_os_error())?;
                d.set_item("strerror", source.to_string())
            }),
            asperity::Error::Parse { path, line, .. } => {
                exception(py, "ParseError", message, |d| {
                    d.set_item("path", path.display().to_string())?;
                    d.set_item("line", line)
                })
            }
            asperity::Error::InvalidParameter { name, .. } => {
                exception(py, "ParameterError", message, |d| d.set_item("name", name))
            }
            asperity::Error::NonConvergence {
                solver,
                iterations,
                residual,
                tolerance,
            } => exception(py, "ConvergenceError", message, |d| {
                d.set_item("solver", solver)?;
                d.set_item("iterations", iterations)?;
                d.set_item("residual", residual)?;
                d.set_item("tolerance", tolerance)
            }),
            asperity::Error::Data(_) => exception(py, "DataError", message, |_| Ok(())),
            asperity::Error::Limit { name, .. } => {
                exception(py, "ResourceLimitError", message, |d| {
                    d.set_item("name", name)
                })
            }
        }
    })
}

/// `asperity::Result` → `PyResult`.
pub trait IntoPy<T> {
    fn py(self) -> PyResult<T>;
}

impl<T> IntoPy<T> for asperity::Result<T> {
    fn py(self) -> PyResult<T> {
        self.map_err(to_py)
    }
}
