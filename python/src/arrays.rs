//! numpy arrays in: shape checks and borrowed slices. The Python layer
//! (`raykit/_arrays.py`) has already converted dtypes and made arrays
//! contiguous; these checks keep a direct caller of `_raykit` from
//! reaching a panic.

use crate::errors::value_error;
use numpy::ndarray::Dimension;
use numpy::{Element, PyReadonlyArray, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::PyResult;

/// The elements of an array in row-major (C) order as one slice. An array
/// in column-major (Fortran) order is contiguous too, but its slice would
/// read as the transpose: it is refused like any other layout.
pub fn c_order<'a, T: Element, D: Dimension>(
    a: &'a PyReadonlyArray<'_, T, D>,
    what: &str,
) -> PyResult<&'a [T]> {
    let refused = || value_error(format!("{what} must be C-contiguous"));
    if !a.is_c_contiguous() {
        return Err(refused());
    }
    a.as_slice().map_err(|_| refused())
}

/// The rows of an `(n, width)` array as one contiguous slice, and `n`.
pub fn rows<'a, T: Element>(
    a: &'a PyReadonlyArray2<'_, T>,
    width: usize,
    what: &str,
) -> PyResult<(&'a [T], usize)> {
    let shape = a.shape();
    if shape[1] != width {
        return Err(value_error(format!(
            "{what} must have shape (n, {width}), got ({}, {})",
            shape[0], shape[1]
        )));
    }
    Ok((c_order(a, what)?, shape[0]))
}

/// A one-dimensional array as a slice.
pub fn flat<'a, T: Element>(a: &'a PyReadonlyArray1<'_, T>, what: &str) -> PyResult<&'a [T]> {
    c_order(a, what)
}
