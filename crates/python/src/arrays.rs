//! The output arrays of a batch: fresh numpy arrays each call (`copy=True`), or one set of *sealed* arrays
//! written again every call (`copy=False`).
//!
//! A sealed array is read-only to Python for good: its memory belongs to a Rust container object (its `base`),
//! which is neither an ndarray nor a writable buffer, so numpy refuses `flags.writeable = True` on it and on
//! every view of it. (A read-only *view* of a writable numpy array, which `copy=False` handed out before, can
//! be made writable again through its base, and an edit would then corrupt later incrementally drawn frames.)
//! Only this binding writes into the arrays, under the env's exclusive borrow.

use chopperscape::{Dtype, ObsBufMut};
use numpy::ndarray::{ArrayD, IxDyn};
use numpy::{Element, PyArrayDyn, PyArrayMethods};
use pyo3::exceptions::PyMemoryError;
use pyo3::prelude::*;

/// One output array.
pub(crate) struct Out<T: Element>(Py<PyArrayDyn<T>>);

impl<T: Element + Default + Clone> Out<T> {
    /// A zeroed array of `shape`: a fresh numpy array, or a sealed one (see the module docs).
    ///
    /// # Errors
    /// `MemoryError` when the memory is refused.
    pub(crate) fn new(py: Python<'_>, shape: &[usize], sealed: bool) -> PyResult<Out<T>> {
        if !sealed {
            return Ok(Out(crate::obs::zeros::<T>(py, shape)?.unbind()));
        }
        let len = shape.iter().try_fold(1usize, |n, &d| n.checked_mul(d));
        let refused = || PyMemoryError::new_err(format!("could not allocate an output array of shape {shape:?}"));
        let len = len.ok_or_else(refused)?;
        let mut data = Vec::new();
        data.try_reserve_exact(len).map_err(|_| refused())?;
        data.resize(len, T::default());
        let array = ArrayD::from_shape_vec(IxDyn(shape), data).expect("the length is the shape's product");
        let array = PyArrayDyn::from_owned_array(py, array);
        array.getattr("flags")?.setattr("writeable", false)?;
        Ok(Out(array.unbind()))
    }

    /// The array as Python sees it.
    pub(crate) fn bind<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        self.0.bind(py).clone().into_any()
    }

    /// Its elements, to write into.
    ///
    /// # Safety
    /// No other Rust reference to the array's memory may be alive while the slice lives. The arrays are this
    /// binding's own (fresh ones not yet handed out, or sealed ones, which Python cannot write), they are written
    /// only under the env's exclusive borrow, and no input of a call is one of them (actions are copied first).
    #[allow(clippy::mut_from_ref)]
    pub(crate) unsafe fn slice_mut<'a>(&'a self, py: Python<'a>) -> &'a mut [T] {
        // SAFETY: the caller's contract; the arrays are made C-contiguous and aligned above.
        unsafe { self.0.bind(py).as_slice_mut() }.expect("the binding's own arrays are contiguous")
    }
}

/// An observation output array of the space's element type.
pub(crate) enum ObsOut {
    /// `uint8`.
    U8(Out<u8>),
    /// `float32`.
    F32(Out<f32>),
}

impl ObsOut {
    /// A zeroed observation array (see [`Out::new`]).
    ///
    /// # Errors
    /// `MemoryError` when the memory is refused.
    pub(crate) fn new(py: Python<'_>, shape: &[usize], dtype: Dtype, sealed: bool) -> PyResult<ObsOut> {
        Ok(match dtype {
            Dtype::U8 => ObsOut::U8(Out::new(py, shape, sealed)?),
            Dtype::F32 => ObsOut::F32(Out::new(py, shape, sealed)?),
        })
    }

    /// The array as Python sees it.
    pub(crate) fn bind<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        match self {
            ObsOut::U8(a) => a.bind(py),
            ObsOut::F32(a) => a.bind(py),
        }
    }

    /// Its elements as the core's buffer type.
    ///
    /// # Safety
    /// As [`Out::slice_mut`].
    pub(crate) unsafe fn buf_mut<'a>(&'a self, py: Python<'a>) -> ObsBufMut<'a> {
        // SAFETY: the caller's contract.
        unsafe {
            match self {
                ObsOut::U8(a) => ObsBufMut::U8(a.slice_mut(py)),
                ObsOut::F32(a) => ObsBufMut::F32(a.slice_mut(py)),
            }
        }
    }
}
