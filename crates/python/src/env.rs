//! `chopperscape._core.Env`: one environment. The Gymnasium class in `chopperscape/env.py` wraps it.

use chopperscape::consts::{HEIGHT, WIDTH};
use chopperscape::{ChopperScape, Env, Info, Snapshot};
use numpy::{PyArrayDyn, PyArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyTuple};
use pyo3::{IntoPyObjectExt, intern};

use crate::errors::{env_error, in_use, snapshot_error};
use crate::obs::{BoundsArrays, ObsArray, bounds};
use crate::options::config_from;

/// One ChopperScape environment, as the core runs it. `options` are the keyword options of SPEC.md
/// (plus `max_episode_steps`); every method returns fresh numpy arrays.
#[pyclass(name = "Env", module = "chopperscape._core")]
pub(crate) struct PyEnv {
    env: ChopperScape,
    /// Pixel observations are drawn with the GIL released; a features step is cheaper than releasing it.
    pixels: bool,
}

/// The info dict: `{"fuel": int, "lives": int}`, plus `"cause"` on the terminating step.
pub(crate) fn info_dict<'py>(py: Python<'py>, info: &Info) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item(intern!(py, "fuel"), info.fuel)?;
    d.set_item(intern!(py, "lives"), info.lives)?;
    if let Some(cause) = info.cause {
        d.set_item(intern!(py, "cause"), cause.as_str())?;
    }
    Ok(d)
}

/// An action as `i64`, or a `ValueError` saying what actions are.
pub(crate) fn extract_action(action: &Bound<'_, PyAny>) -> PyResult<i64> {
    action.extract::<i64>().map_err(|_| {
        PyValueError::new_err(format!(
            "invalid action {}: allowed actions are the integers 0..=4 (0 Right, 1 Left, 2 Down, 3 Up, 4 Do Nothing)",
            action.repr().map_or_else(|_| "?".to_string(), |r| r.to_string())
        ))
    })
}

#[pymethods]
impl PyEnv {
    #[new]
    #[pyo3(signature = (options = None))]
    fn new(options: Option<&Bound<'_, PyDict>>) -> PyResult<PyEnv> {
        let config = config_from(options)?;
        let pixels = config.obs_type.is_pixels();
        let env = ChopperScape::new(config).map_err(|e| PyValueError::new_err(e.to_string()))?;
        Ok(PyEnv { env, pixels })
    }

    /// Starts an episode: `seed` reseeds the generator, `None` continues its stream. Returns `(obs, info)`.
    #[pyo3(signature = (seed = None))]
    fn reset<'py>(slf: &Bound<'py, Self>, seed: Option<u64>) -> PyResult<Bound<'py, PyTuple>> {
        let py = slf.py();
        let mut this = slf.try_borrow_mut().map_err(in_use)?;
        let this = &mut *this;
        let obs = ObsArray::for_space(py, this.env.observation_space())?;
        // SAFETY: `obs` was just created and is not shared yet.
        let buf = unsafe { obs.as_buf_mut() };
        let env = &mut this.env;
        let info = if this.pixels { py.detach(|| env.reset_into(seed, buf)) } else { env.reset_into(seed, buf) }
            .map_err(env_error)?;
        PyTuple::new(py, [obs.into_any(), info_dict(py, &info)?.into_any()])
    }

    /// Advances one step. Returns `(obs, reward: float, terminated: bool, truncated: bool, info)`.
    fn step<'py>(slf: &Bound<'py, Self>, action: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyTuple>> {
        let py = slf.py();
        let action = extract_action(action)?;
        let mut this = slf.try_borrow_mut().map_err(in_use)?;
        let this = &mut *this;
        let obs = ObsArray::for_space(py, this.env.observation_space())?;
        // SAFETY: `obs` was just created and is not shared yet.
        let buf = unsafe { obs.as_buf_mut() };
        let env = &mut this.env;
        let t = if this.pixels { py.detach(|| env.step_into(action, buf)) } else { env.step_into(action, buf) }
            .map_err(env_error)?;
        PyTuple::new(
            py,
            [
                obs.into_any(),
                f64::from(t.reward).into_bound_py_any(py)?,
                t.terminated.into_bound_py_any(py)?,
                t.truncated.into_bound_py_any(py)?,
                info_dict(py, &t.info)?.into_any(),
            ],
        )
    }

    /// The full 600 × 800 × 3 `uint8` frame of the current state, HUD included whatever the observation (the text
    /// line, or the fuel and lives bars with `hud_style="gauge"`).
    fn render<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyArrayDyn<u8>>> {
        let py = slf.py();
        let this = slf.try_borrow().map_err(in_use)?;
        let frame = crate::obs::zeros::<u8>(py, &[HEIGHT as usize, WIDTH as usize, 3])?;
        // SAFETY: `frame` was just created and is not shared yet.
        let rgb = unsafe { frame.as_slice_mut() }.expect("a fresh array is contiguous");
        let env = &this.env;
        py.detach(|| env.render_into(rgb)).map_err(env_error)?;
        Ok(frame)
    }

    /// The info of the current state.
    fn info<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyDict>> {
        info_dict(slf.py(), &slf.try_borrow().map_err(in_use)?.env.info())
    }

    /// Steps taken in the current episode (what a `TimeLimit` wrapper counts).
    #[getter]
    fn elapsed_steps(slf: &Bound<'_, Self>) -> PyResult<u32> {
        Ok(slf.try_borrow().map_err(in_use)?.env.world().steps)
    }

    /// Shape of one observation.
    #[getter]
    fn obs_shape(slf: &Bound<'_, Self>) -> PyResult<Vec<usize>> {
        Ok(slf.try_borrow().map_err(in_use)?.env.observation_space().shape.clone())
    }

    /// numpy name of the observation's element type: `"uint8"` or `"float32"`.
    #[getter]
    fn obs_dtype(slf: &Bound<'_, Self>) -> PyResult<&'static str> {
        Ok(slf.try_borrow().map_err(in_use)?.env.observation_space().dtype.as_str())
    }

    /// One period of the observation's bounds, `(low, high)`, as `float32` arrays: one value each when every
    /// element shares them (pixels), else the per-element bounds of one features vector, repeated over the
    /// frame stack. Nothing is stored per element.
    #[getter]
    fn obs_bounds<'py>(slf: &Bound<'py, Self>) -> PyResult<BoundsArrays<'py>> {
        Ok(bounds(slf.py(), slf.try_borrow().map_err(in_use)?.env.observation_space()))
    }

    /// The whole state (options included) as versioned bytes.
    fn snapshot<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyBytes>> {
        Ok(PyBytes::new(slf.py(), &slf.try_borrow().map_err(in_use)?.env.snapshot().to_bytes()))
    }

    /// Restores a state from [`PyEnv::snapshot`] bytes taken with the same options.
    fn restore(slf: &Bound<'_, Self>, data: &[u8]) -> PyResult<()> {
        let snapshot = Snapshot::from_bytes(data).map_err(snapshot_error)?;
        slf.try_borrow_mut().map_err(in_use)?.env.restore(&snapshot).map_err(env_error)
    }

    /// An environment rebuilt from snapshot bytes alone (what unpickling does).
    #[staticmethod]
    fn from_snapshot(data: &[u8]) -> PyResult<PyEnv> {
        let snapshot = Snapshot::from_bytes(data).map_err(snapshot_error)?;
        let env = ChopperScape::from_snapshot(&snapshot).map_err(env_error)?;
        Ok(PyEnv { pixels: env.config().obs_type.is_pixels(), env })
    }

    /// Pickles as its snapshot bytes.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, PyBytes>,))> {
        let ctor = slf.py().get_type::<PyEnv>().getattr(intern!(slf.py(), "from_snapshot"))?;
        Ok((ctor, (PyEnv::snapshot(slf)?,)))
    }
}

impl PyEnv {
    /// The core env (for the built-in policies, which read its world).
    pub(crate) fn core(&self) -> &ChopperScape {
        &self.env
    }
}
