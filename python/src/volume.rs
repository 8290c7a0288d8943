//! Volumes between numpy and the library: an array indexed `[i, j, k]` (grid point
//! `(x, y, z)`, as a `.npy` input) to a [`ScalarGrid`] and back.
//!
//! The grid holds its samples x fastest in their own type, so the array is copied once into
//! it: a straight copy for a Fortran-ordered array, a transposing one otherwise. The types
//! are the readers': `uint8`, `int16`, `uint16`, `float32`, `float64` as they are; `int8`
//! widened to `int16`; 32- and 64-bit integers to `float64`.

use numpy::ndarray::ArrayView3;
use numpy::npyffi::NPY_ORDER;
use numpy::{
    Element, PyArray1, PyArray3, PyArrayDescrMethods, PyArrayMethods, PyUntypedArray,
    PyUntypedArrayMethods,
};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use tptd::nalgebra::{Affine3, Matrix4};
use tptd::{Samples, ScalarGrid};

/// The array's samples x fastest, in their type.
fn x_fastest<T: Copy>(a: ArrayView3<'_, T>) -> Vec<T> {
    let t = a.reversed_axes();
    match t.as_slice() {
        Some(s) => s.to_vec(),
        None => t.as_standard_layout().iter().copied().collect(),
    }
}

/// The samples of `volume` if its type is `T`, converted by `into`.
fn typed<T: Element + Copy>(
    volume: &Bound<'_, PyUntypedArray>,
    into: impl Fn(Vec<T>) -> Samples,
) -> PyResult<Option<Samples>> {
    let py = volume.py();
    if !volume.dtype().is_equiv_to(&numpy::dtype::<T>(py)) {
        return Ok(None);
    }
    let array = volume.cast::<PyArray3<T>>()?.try_readonly()?;
    Ok(Some(into(x_fastest(array.as_array()))))
}

/// The samples of a 3-D array of one of the readers' types, x fastest.
fn samples(volume: &Bound<'_, PyUntypedArray>) -> PyResult<Samples> {
    fn wide<T: Into<f64>>(v: Vec<T>) -> Samples {
        Samples::from(v.into_iter().map(Into::into).collect::<Vec<f64>>())
    }
    fn wide64<T: Copy>(v: Vec<T>, f: fn(T) -> f64) -> Samples {
        Samples::from(v.into_iter().map(f).collect::<Vec<f64>>())
    }
    let found = typed::<u8>(volume, Samples::from)?
        .or(typed::<i16>(volume, Samples::from)?)
        .or(typed::<u16>(volume, Samples::from)?)
        .or(typed::<f32>(volume, Samples::from)?)
        .or(typed::<f64>(volume, Samples::from)?)
        .or(typed::<i8>(volume, Samples::from)?)
        .or(typed::<u32>(volume, wide)?)
        .or(typed::<i32>(volume, wide)?)
        .or(typed::<u64>(volume, |v| wide64(v, |x| x as f64))?)
        .or(typed::<i64>(volume, |v| wide64(v, |x| x as f64))?);
    found.ok_or_else(|| {
        PyValueError::new_err(format!(
            "volume: unsupported dtype {}; use an integer or floating-point type (uint8, \
             int16, uint16, float32, float64; other integers are widened)",
            volume.dtype()
        ))
    })
}

/// The grid of `volume` (a 3-D array indexed `[i, j, k]`) at `origin` with unit spacing, or
/// placed by the 4×4 `affine` from index to physical coordinates.
///
/// # Errors
/// `ValueError`: not 3-D, an unsupported type, or a grid the library refuses (`volume: …`).
pub(crate) fn grid_of(
    volume: &Bound<'_, PyUntypedArray>,
    origin: [f64; 3],
    affine: Option<[[f64; 4]; 4]>,
) -> PyResult<ScalarGrid> {
    if volume.ndim() != 3 {
        return Err(PyValueError::new_err(format!(
            "volume: expected a 3-D array indexed [i, j, k], got shape {:?}",
            volume.shape()
        )));
    }
    let dims = [volume.shape()[0], volume.shape()[1], volume.shape()[2]];
    let values = samples(volume)?;
    let refused = |e: tptd::grid::GridError| PyValueError::new_err(format!("volume: {e}"));
    match affine {
        Some(a) => {
            let m = Matrix4::from_fn(|r, c| a[r][c]);
            ScalarGrid::with_affine(dims, &Affine3::from_matrix_unchecked(m), values)
                .map_err(refused)
        }
        None => {
            let grid = ScalarGrid::new(dims, values).map_err(refused)?;
            let direction = grid.direction;
            ScalarGrid::with_geometry(dims, [1.0; 3], origin, direction, grid.values)
                .map_err(refused)
        }
    }
}

/// A 1-D array of `v` (no copy) reshaped to `dims` in Fortran order (x fastest).
fn fortran<'py, T: Element>(
    py: Python<'py>,
    v: Vec<T>,
    dims: [usize; 3],
) -> PyResult<Bound<'py, PyAny>> {
    let flat = PyArray1::from_vec(py, v);
    Ok(flat
        .reshape_with_order(dims, NPY_ORDER::NPY_FORTRANORDER)?
        .into_any())
}

/// `(array, affine)` of a grid: the samples in their type, indexed `[i, j, k]`, and the 4×4
/// affine from index to physical coordinates.
pub(crate) fn to_numpy(py: Python<'_>, grid: ScalarGrid) -> PyResult<(Py<PyAny>, Py<PyAny>)> {
    let zero = grid.to_physical([0.0; 3]);
    let mut affine = [[0.0; 4]; 4];
    for c in 0..3 {
        let mut e = [0.0; 3];
        e[c] = 1.0;
        let p = grid.to_physical(e);
        for r in 0..3 {
            affine[r][c] = p[r] - zero[r];
        }
    }
    for r in 0..3 {
        affine[r][3] = zero[r];
    }
    affine[3][3] = 1.0;
    let dims = grid.dims;
    let array = match grid.values {
        Samples::U8(v) => fortran(py, v, dims)?,
        Samples::I16(v) => fortran(py, v, dims)?,
        Samples::U16(v) => fortran(py, v, dims)?,
        Samples::F32(v) => fortran(py, v, dims)?,
        Samples::F64(v) => fortran(py, v, dims)?,
    };
    let rows: Vec<Vec<f64>> = affine.iter().map(|r| r.to_vec()).collect();
    let affine = PyArray1::from_vec(py, rows.concat()).reshape([4, 4])?;
    Ok((array.unbind(), affine.into_any().unbind()))
}
