//! numpy arrays in and out.
//!
//! **In**: array arguments must be `numpy.ndarray`s of dtype float64, C-contiguous, with the
//! documented number of dimensions; they are borrowed read-only (no copy) and checked with
//! errors that name the argument: `asperity.ArrayTypeError` (a `TypeError`) for something that
//! is not an array or has another dtype, `asperity.ParameterError` (a `ValueError`) for the
//! wrong number of dimensions, a non-contiguous layout or a non-finite value. Nothing is
//! converted silently: pass `numpy.ascontiguousarray(x, dtype=numpy.float64)` when needed.
//!
//! **Out**: fields owned by a result object are handed out as read-only views of its memory
//! (no copy, kept alive by the object); freshly computed arrays are moved into numpy (no copy).

use crate::errors::{array_type, parameter};
use ndarray::{ArrayBase, Data, Dimension};
use numpy::{
    Element, PyArray, PyArrayDescrMethods, PyArrayMethods, PyReadonlyArray, PyUntypedArray,
    PyUntypedArrayMethods,
};
use pyo3::prelude::*;

/// Borrow `obj` as a read-only float64 array of `D::NDIM` dimensions; `what` describes the
/// expected content (e.g. "heights (m), shape (nx, ny)").
pub fn borrow_f64<'py, D: Dimension>(
    obj: &Bound<'py, PyAny>,
    name: &str,
    what: &str,
) -> PyResult<PyReadonlyArray<'py, f64, D>> {
    let py = obj.py();
    let ndim = D::NDIM.expect("fixed dimension");
    let Ok(arr) = obj.cast::<PyUntypedArray>() else {
        return Err(array_type(
            py,
            format!(
                "`{name}`: expected a numpy.ndarray of float64 ({what}), got {}",
                obj.get_type().name()?
            ),
        ));
    };
    if arr.ndim() != ndim {
        return Err(parameter(
            py,
            name,
            format!(
                "expected a {ndim}-D array ({what}), got a {}-D array of shape ({})",
                arr.ndim(),
                python_shape(arr.shape())
            ),
        ));
    }
    let dtype = arr.dtype();
    if !dtype.is_equiv_to(&numpy::dtype::<f64>(py)) {
        return Err(array_type(
            py,
            format!(
                "`{name}`: expected dtype float64 ({what}), got {}; convert with numpy.asarray({name}, dtype=numpy.float64)",
                dtype.str()?
            ),
        ));
    }
    if !arr.is_c_contiguous() {
        return Err(parameter(
            py,
            name,
            "array is not C-contiguous (a strided slice, a transpose or Fortran order); \
             pass numpy.ascontiguousarray(...)"
                .into(),
        ));
    }
    let typed = arr
        .cast::<PyArray<f64, D>>()
        .map_err(|e| array_type(py, format!("`{name}`: {e}")))?;
    typed
        .try_readonly()
        .map_err(|e| parameter(py, name, format!("array is being written elsewhere: {e}")))
}

/// A shape as Python prints it: `(4,)`, `(2, 3)`.
fn python_shape(shape: &[usize]) -> String {
    match shape {
        [n] => format!("{n},"),
        _ => shape
            .iter()
            .map(|n| n.to_string())
            .collect::<Vec<_>>()
            .join(", "),
    }
}

/// Check that every value is finite, naming the first offending index.
pub fn require_finite(py: Python<'_>, name: &str, values: &[f64]) -> PyResult<()> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(i) => Err(parameter(
            py,
            name,
            format!("non-finite value {} at index {i}", values[i]),
        )),
        None => Ok(()),
    }
}

/// A 1-D float64 array as a slice, checked finite.
pub fn finite_slice<'a>(
    py: Python<'_>,
    arr: &'a PyReadonlyArray<'_, f64, ndarray::Ix1>,
    name: &str,
) -> PyResult<&'a [f64]> {
    let s = arr.as_slice().expect("checked C-contiguous");
    require_finite(py, name, s)?;
    Ok(s)
}

/// A read-only numpy view of `array`, which `owner` (a frozen Python object) owns and never
/// changes: no copy; the view keeps `owner` alive.
pub fn view<'py, S: Data<Elem = T>, D: Dimension, T: Element>(
    array: &ArrayBase<S, D>,
    owner: Bound<'py, PyAny>,
) -> Bound<'py, PyArray<T, D>> {
    // SAFETY: `owner` is a frozen pyclass holding the memory of `array`: the memory is never reallocated or
    // written while the owner lives, and the view holds a reference to the owner.
    let a = unsafe { PyArray::borrow_from_array(array, owner) };
    drop(a.readwrite().make_nonwriteable());
    a
}
