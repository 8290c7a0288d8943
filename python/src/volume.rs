//! Volumes between numpy and the library: an array indexed `[i, j, k]` (grid point
//! `(x, y, z)`, as a `.npy` input) to a [`ScalarGrid`] and back.
//!
//! The grid holds its samples x fastest in their own type. A Fortran-ordered (x fastest),
//! aligned array of a type the grid stores (`uint8`, `int16`, `uint16`, `float32`,
//! `float64`, native byte order) is read in place: the grid shares the array's memory
//! ([`InPlace`]) while the caller's call runs, and holds numpy's read-only borrow of it. Any
//! other array is copied once into the grid: a transposing copy for another order, and the
//! readers' conversions for the other types (`int8` widened to `int16`; 32- and 64-bit
//! integers to `float64`).

use std::slice;

use numpy::ndarray::ArrayView3;
use numpy::npyffi::NPY_ORDER;
use numpy::{
    Element, PyArray1, PyArray3, PyArrayDescrMethods, PyArrayMethods, PyReadonlyArray3,
    PyUntypedArray, PyUntypedArrayMethods,
};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use tptd::nalgebra::{Affine3, Matrix4};
use tptd::{Buffer, Samples, ScalarGrid};

/// The samples of a Fortran-ordered numpy array, read in place by a grid.
///
/// Holds a reference to the array, which keeps its memory alive as long as the grid does;
/// the reference is given back with the thread attached to Python, wherever the grid is
/// dropped.
struct InPlace<T> {
    /// The array (taken when dropped).
    array: Option<Py<PyAny>>,
    /// Its first sample: non-null and aligned for `T`.
    data: *const T,
    /// Its number of samples, contiguous from `data`.
    len: usize,
}

// SAFETY: the samples are only read (through `&[T]`, `T: Sync`), never written from Rust
// while the call that made this holds numpy's read-only borrow of the array, and the caller
// is told not to write them from Python meanwhile; `Py<PyAny>` is `Send + Sync`.
unsafe impl<T: Sync> Send for InPlace<T> {}
// SAFETY: as for `Send`: shared access only reads.
unsafe impl<T: Sync> Sync for InPlace<T> {}

impl<T> AsRef<[T]> for InPlace<T> {
    #[inline]
    fn as_ref(&self) -> &[T] {
        // SAFETY: `data` and `len` are those of a non-empty, aligned, contiguous array of `T`
        // (checked by `PyReadonlyArray::as_slice` in `in_place`), whose memory the held
        // reference keeps alive.
        unsafe { slice::from_raw_parts(self.data, self.len) }
    }
}

impl<T> Drop for InPlace<T> {
    fn drop(&mut self) {
        if let Some(array) = self.array.take() {
            // attached (at once when already so), so that the reference is given back now
            // rather than when some later call attaches
            Python::attach(move |_| drop(array));
        }
    }
}

/// A buffer reading `array` in place when its memory is the grid's order (Fortran, x
/// fastest), aligned, in native byte order and not empty; `None` otherwise.
fn in_place<T: Element + Sync + 'static>(array: &PyReadonlyArray3<'_, T>) -> Option<Buffer<T>> {
    let native = array.dtype().is_native_byteorder() != Some(false);
    if !array.is_fortran_contiguous() || !native {
        return None;
    }
    let s = array.as_slice().ok().filter(|s| !s.is_empty())?;
    let shared = InPlace {
        array: Some(array.as_any().clone().unbind()),
        data: s.as_ptr(),
        len: s.len(),
    };
    Some(Buffer::shared(shared))
}

/// The array's samples x fastest, in their type: one copy, gathered in that order from any
/// layout (no intermediate array).
fn x_fastest<T: Copy>(a: ArrayView3<'_, T>) -> Vec<T> {
    let t = a.reversed_axes();
    match t.as_slice() {
        Some(s) => s.to_vec(),
        None => t.iter().copied().collect(),
    }
}

/// The read-only borrows of the arrays a grid reads in place, held until the call that
/// meshes it ends (other Rust code cannot write the arrays meanwhile).
pub(crate) struct Lent<'py>(Vec<Box<dyn Held + 'py>>);

/// Anything held for its lifetime only (a borrow guard).
trait Held {}
impl<T> Held for T {}

/// `volume` borrowed read-only as an array of `T`, if that is its type.
fn of_type<'py, T: Element>(
    volume: &Bound<'py, PyUntypedArray>,
) -> PyResult<Option<PyReadonlyArray3<'py, T>>> {
    if !volume.dtype().is_equiv_to(&numpy::dtype::<T>(volume.py())) {
        return Ok(None);
    }
    Ok(Some(volume.cast::<PyArray3<T>>()?.try_readonly()?))
}

/// The samples of `volume` if its type is `T`, a type the grid stores: read in place when the
/// array allows it (its borrow pushed to `lent`), else copied x fastest.
fn stored<'py, T>(
    volume: &Bound<'py, PyUntypedArray>,
    lent: &mut Lent<'py>,
) -> PyResult<Option<Samples>>
where
    T: Element + Copy + Sync + 'static,
    Samples: From<Vec<T>> + From<Buffer<T>>,
{
    let Some(array) = of_type::<T>(volume)? else {
        return Ok(None);
    };
    if let Some(buffer) = in_place(&array) {
        lent.0.push(Box::new(array));
        return Ok(Some(Samples::from(buffer)));
    }
    Ok(Some(Samples::from(x_fastest(array.as_array()))))
}

/// The samples of `volume` if its type is `T`, copied x fastest and converted by `into`.
fn converted<T: Element + Copy>(
    volume: &Bound<'_, PyUntypedArray>,
    into: impl Fn(Vec<T>) -> Samples,
) -> PyResult<Option<Samples>> {
    Ok(of_type::<T>(volume)?.map(|a| into(x_fastest(a.as_array()))))
}

/// The samples of a 3-D array of one of the readers' types, x fastest (borrows of arrays
/// read in place pushed to `lent`).
fn samples<'py>(volume: &Bound<'py, PyUntypedArray>, lent: &mut Lent<'py>) -> PyResult<Samples> {
    fn wide<T: Into<f64>>(v: Vec<T>) -> Samples {
        Samples::from(v.into_iter().map(Into::into).collect::<Vec<f64>>())
    }
    fn wide64<T: Copy>(v: Vec<T>, f: fn(T) -> f64) -> Samples {
        Samples::from(v.into_iter().map(f).collect::<Vec<f64>>())
    }
    let found = stored::<u8>(volume, lent)?
        .or(stored::<i16>(volume, lent)?)
        .or(stored::<u16>(volume, lent)?)
        .or(stored::<f32>(volume, lent)?)
        .or(stored::<f64>(volume, lent)?)
        .or(converted::<i8>(volume, Samples::from)?)
        .or(converted::<u32>(volume, wide)?)
        .or(converted::<i32>(volume, wide)?)
        .or(converted::<u64>(volume, |v| wide64(v, |x| x as f64))?)
        .or(converted::<i64>(volume, |v| wide64(v, |x| x as f64))?);
    found.ok_or_else(|| {
        PyValueError::new_err(format!(
            "volume: unsupported dtype {}; use an integer or floating-point type (uint8, \
             int16, uint16, float32, float64; other integers are widened)",
            volume.dtype()
        ))
    })
}

/// The grid of `volume` (a 3-D array indexed `[i, j, k]`) at `origin` with unit spacing, or
/// placed by the 4×4 `affine` from index to physical coordinates, and the borrows to hold
/// while it is used. The grid may read the array in place: drop it before the borrows, and
/// while attached.
///
/// # Errors
/// `ValueError`: not 3-D, an unsupported type, or a grid the library refuses (`volume: …`).
pub(crate) fn grid_of<'py>(
    volume: &Bound<'py, PyUntypedArray>,
    origin: [f64; 3],
    affine: Option<[[f64; 4]; 4]>,
) -> PyResult<(ScalarGrid, Lent<'py>)> {
    if volume.ndim() != 3 {
        return Err(PyValueError::new_err(format!(
            "volume: expected a 3-D array indexed [i, j, k], got shape {:?}",
            volume.shape()
        )));
    }
    let dims = [volume.shape()[0], volume.shape()[1], volume.shape()[2]];
    let mut lent = Lent(Vec::new());
    let values = samples(volume, &mut lent)?;
    let refused = |e: tptd::grid::GridError| PyValueError::new_err(format!("volume: {e}"));
    let grid = match affine {
        Some(a) => {
            let m = Matrix4::from_fn(|r, c| a[r][c]);
            ScalarGrid::with_affine(dims, &Affine3::from_matrix_unchecked(m), values)
                .map_err(refused)?
        }
        None => {
            let grid = ScalarGrid::new(dims, values).map_err(refused)?;
            let direction = grid.direction;
            ScalarGrid::with_geometry(dims, [1.0; 3], origin, direction, grid.values)
                .map_err(refused)?
        }
    };
    Ok((grid, lent))
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
/// affine from index to physical coordinates. The array takes the grid's vector (a read
/// grid owns its samples: no copy).
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
        Samples::U8(v) => fortran(py, v.into_vec(), dims)?,
        Samples::I16(v) => fortran(py, v.into_vec(), dims)?,
        Samples::U16(v) => fortran(py, v.into_vec(), dims)?,
        Samples::F32(v) => fortran(py, v.into_vec(), dims)?,
        Samples::F64(v) => fortran(py, v.into_vec(), dims)?,
    };
    let rows: Vec<Vec<f64>> = affine.iter().map(|r| r.to_vec()).collect();
    let affine = PyArray1::from_vec(py, rows.concat()).reshape([4, 4])?;
    Ok((array.unbind(), affine.into_any().unbind()))
}
