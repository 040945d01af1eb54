//! numpy arrays for observations, allocated by the binding and written by the core.

use chopperscape::{BoxSpace, Dtype, ObsBufMut};
use numpy::{IxDyn, PyArrayDyn, PyArrayMethods};
use pyo3::prelude::*;

/// A numpy observation array of the space's element type.
pub(crate) enum ObsArray<'py> {
    /// `uint8`.
    U8(Bound<'py, PyArrayDyn<u8>>),
    /// `float32`.
    F32(Bound<'py, PyArrayDyn<f32>>),
}

impl<'py> ObsArray<'py> {
    /// A zeroed array of this shape and element type.
    pub(crate) fn zeros(py: Python<'py>, shape: &[usize], dtype: Dtype) -> ObsArray<'py> {
        match dtype {
            Dtype::U8 => ObsArray::U8(PyArrayDyn::zeros(py, IxDyn(shape), false)),
            Dtype::F32 => ObsArray::F32(PyArrayDyn::zeros(py, IxDyn(shape), false)),
        }
    }

    /// A zeroed array for one observation of `space`.
    pub(crate) fn for_space(py: Python<'py>, space: &BoxSpace) -> ObsArray<'py> {
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
