//! numpy arrays for observations, allocated by the binding and written by the core.

use chopperscape::{Bounds, BoxSpace, Dtype, ObsBufMut};
use numpy::npyffi::PY_ARRAY_API;
use numpy::{Element, PyArray1, PyArrayDescrMethods, PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;

/// A zeroed C-contiguous array of `shape`, or Python's `MemoryError` when numpy cannot allocate it (where
/// `PyArrayDyn::zeros` would panic).
pub(crate) fn zeros<'py, T: Element>(py: Python<'py>, shape: &[usize]) -> PyResult<Bound<'py, PyArrayDyn<T>>> {
    let mut dims: Vec<numpy::npyffi::npy_intp> = shape.iter().map(|&d| d as numpy::npyffi::npy_intp).collect();
    // SAFETY: `dims` holds `shape.len()` dimensions and outlives the call; `PyArray_Zeros` steals the dtype
    // reference `into_dtype_ptr` gives it, and returns a new reference or NULL with an exception set.
    let array = unsafe {
        let ptr = PY_ARRAY_API.PyArray_Zeros(
            py,
            dims.len() as std::os::raw::c_int,
            dims.as_mut_ptr(),
            T::get_dtype(py).into_dtype_ptr(),
            0,
        );
        Bound::from_owned_ptr_or_err(py, ptr)?
    };
    let array = array.cast_into::<PyArrayDyn<T>>().map_err(PyErr::from)?;
    debug_assert!(array.is_c_contiguous() && array.dtype().is_equiv_to(&T::get_dtype(py)));
    Ok(array)
}

/// `(low, high)` arrays of an observation space's bounds.
pub(crate) type BoundsArrays<'py> = (Bound<'py, PyArray1<f32>>, Bound<'py, PyArray1<f32>>);

/// One period of the space's bounds as two `float32` arrays (one value each when the bounds are uniform):
/// element `i` of an observation has the bounds `low[i % len]`, `high[i % len]`.
pub(crate) fn bounds<'py>(py: Python<'py>, space: &BoxSpace) -> BoundsArrays<'py> {
    match &space.bounds {
        Bounds::Uniform { low, high } => (PyArray1::from_slice(py, &[*low]), PyArray1::from_slice(py, &[*high])),
        Bounds::Repeated { low, high } => (PyArray1::from_slice(py, low), PyArray1::from_slice(py, high)),
    }
}

/// A numpy observation array of the space's element type.
pub(crate) enum ObsArray<'py> {
    /// `uint8`.
    U8(Bound<'py, PyArrayDyn<u8>>),
    /// `float32`.
    F32(Bound<'py, PyArrayDyn<f32>>),
}

impl<'py> ObsArray<'py> {
    /// A zeroed array of this shape and element type.
    ///
    /// # Errors
    /// `MemoryError` when numpy cannot allocate it.
    pub(crate) fn zeros(py: Python<'py>, shape: &[usize], dtype: Dtype) -> PyResult<ObsArray<'py>> {
        Ok(match dtype {
            Dtype::U8 => ObsArray::U8(zeros(py, shape)?),
            Dtype::F32 => ObsArray::F32(zeros(py, shape)?),
        })
    }

    /// A zeroed array for one observation of `space`.
    ///
    /// # Errors
    /// `MemoryError` when numpy cannot allocate it.
    pub(crate) fn for_space(py: Python<'py>, space: &BoxSpace) -> PyResult<ObsArray<'py>> {
        ObsArray::zeros(py, &space.shape, space.dtype)
    }

    /// Its elements, to write into.
    ///
    /// # Safety
    /// No other reference to the array's memory may be in use while the view lives: call it only on an array
    /// this binding has just created and not yet handed to Python.
    pub(crate) unsafe fn as_buf_mut(&self) -> ObsBufMut<'_> {
        // SAFETY: fresh arrays from `zeros` are C-contiguous, aligned and unshared (the caller's contract).
        unsafe {
            match self {
                ObsArray::U8(a) => ObsBufMut::U8(a.as_slice_mut().expect("a fresh array is contiguous")),
                ObsArray::F32(a) => ObsBufMut::F32(a.as_slice_mut().expect("a fresh array is contiguous")),
            }
        }
    }

    /// The array as a Python object.
    pub(crate) fn into_any(self) -> Bound<'py, PyAny> {
        match self {
            ObsArray::U8(a) => a.into_any(),
            ObsArray::F32(a) => a.into_any(),
        }
    }
}
