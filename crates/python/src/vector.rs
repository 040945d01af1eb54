//! `chopperscape._core.VectorEnv`: a batch of environments stepped by one call with the GIL released,
//! written into numpy arrays. The Gymnasium class in `chopperscape/vector.py` wraps it.

use chopperscape::consts::{HEIGHT, WIDTH};
use chopperscape::{Dtype, ObsBufMut, Snapshot};
use chopperscape_vector::{AutoresetMode, BatchMut, VectorEnv};
use numpy::{PyArray1, PyArrayDyn, PyArrayMethods, PyReadonlyArray1, PyReadwriteArray1, PyReadwriteArrayDyn};
use pyo3::exceptions::{PyIndexError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyTuple};

use crate::errors::{batch_error, env_error, in_use};
use crate::obs::{BoundsArrays, ObsArray, bounds};
use crate::options::config_from;

/// The output arrays of a batch.
struct Arrays {
    obs: ObsPy,
    final_obs: Option<ObsPy>,
    /// `float64`, as Gymnasium's vector envs return rewards; the batch writes `float32` into `rewards32`.
    rewards: Py<PyArray1<f64>>,
    terminated: Py<PyArray1<bool>>,
    truncated: Py<PyArray1<bool>>,
    /// `int64`, as Gymnasium batches Python ints; the batch writes `uint32` into `fuel32`.
    fuel: Py<PyArray1<i64>>,
    /// `int64`; the batch writes `uint32` into `lives32`.
    lives: Py<PyArray1<i64>>,
    cause: Py<PyArray1<u8>>,
    /// With `copy=False`: read-only views of the arrays above, in the order `run` returns them, handed out
    /// instead of the arrays themselves (the batch keeps writing into them).
    views: Option<Vec<Py<PyAny>>>,
}

enum ObsPy {
    U8(Py<PyArrayDyn<u8>>),
    F32(Py<PyArrayDyn<f32>>),
}

/// Write borrows of an observation array.
enum ObsRw<'py> {
    U8(PyReadwriteArrayDyn<'py, u8>),
    F32(PyReadwriteArrayDyn<'py, f32>),
}

impl ObsPy {
    fn new(py: Python<'_>, shape: &[usize], dtype: Dtype) -> PyResult<ObsPy> {
        Ok(match ObsArray::zeros(py, shape, dtype)? {
            ObsArray::U8(a) => ObsPy::U8(a.unbind()),
            ObsArray::F32(a) => ObsPy::F32(a.unbind()),
        })
    }

    fn bind<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        match self {
            ObsPy::U8(a) => a.bind(py).clone().into_any(),
            ObsPy::F32(a) => a.bind(py).clone().into_any(),
        }
    }

    fn borrow<'py>(&self, py: Python<'py>) -> PyResult<ObsRw<'py>> {
        Ok(match self {
            ObsPy::U8(a) => ObsRw::U8(a.bind(py).try_readwrite().map_err(borrowed)?),
            ObsPy::F32(a) => ObsRw::F32(a.bind(py).try_readwrite().map_err(borrowed)?),
        })
    }
}

impl ObsRw<'_> {
    fn as_buf_mut(&mut self) -> ObsBufMut<'_> {
        match self {
            ObsRw::U8(a) => ObsBufMut::U8(a.as_slice_mut().expect("the binding's own arrays are contiguous")),
            ObsRw::F32(a) => ObsBufMut::F32(a.as_slice_mut().expect("the binding's own arrays are contiguous")),
        }
    }
}

/// Copies `from` into the wider numpy type Gymnasium's vector envs use.
fn widen<S: Copy, D: From<S>>(to: &mut [D], from: &[S]) {
    for (d, &s) in to.iter_mut().zip(from) {
        *d = D::from(s);
    }
}

fn borrowed(e: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(format!("the vector env's output arrays are in use elsewhere: {e}"))
}

fn rw<'py, T: numpy::Element>(a: &Py<PyArray1<T>>, py: Python<'py>) -> PyResult<PyReadwriteArray1<'py, T>> {
    a.bind(py).try_readwrite().map_err(borrowed)
}

/// `num_envs` environments stepped together over `num_threads` threads; environment `i` of a batch reset with
/// seed `s` is seeded `s + i`. With `copy`, each call returns fresh arrays; without, the same arrays every call.
/// `time_limit` truncates episodes as Gymnasium's `TimeLimit` does (see `VectorEnv::set_time_limit`).
#[pyclass(name = "VectorEnv", module = "chopperscape._core")]
pub(crate) struct PyVectorEnv {
    inner: VectorEnv,
    copy: bool,
    arrays: Option<Arrays>,
    rewards32: Vec<f32>,
    fuel32: Vec<u32>,
    lives32: Vec<u32>,
}

impl PyVectorEnv {
    fn new_arrays(&self, py: Python<'_>) -> PyResult<Arrays> {
        let n = self.inner.num_envs();
        let space = self.inner.single_observation_space();
        let mut shape = vec![n];
        shape.extend_from_slice(&space.shape);
        let same_step = self.inner.autoreset_mode() == AutoresetMode::SameStep;
        let mut arrays = Arrays {
            obs: ObsPy::new(py, &shape, space.dtype)?,
            final_obs: same_step.then(|| ObsPy::new(py, &shape, space.dtype)).transpose()?,
            rewards: PyArray1::zeros(py, n, false).unbind(),
            terminated: PyArray1::zeros(py, n, false).unbind(),
            truncated: PyArray1::zeros(py, n, false).unbind(),
            fuel: PyArray1::zeros(py, n, false).unbind(),
            lives: PyArray1::zeros(py, n, false).unbind(),
            cause: PyArray1::zeros(py, n, false).unbind(),
            views: None,
        };
        if !self.copy {
            let read_only = |a: Bound<'_, PyAny>| -> PyResult<Py<PyAny>> {
                if a.is_none() {
                    return Ok(a.unbind());
                }
                let view = a.call_method0("view")?;
                view.getattr("flags")?.setattr("writeable", false)?;
                Ok(view.unbind())
            };
            arrays.views = Some(arrays.all(py).into_iter().map(read_only).collect::<PyResult<_>>()?);
        }
        Ok(arrays)
    }

    /// Runs `f` on the output arrays (fresh ones with `copy`) with the GIL released; returns the arrays as
    /// `(obs, rewards, terminated, truncated, fuel, lives, cause, final_obs | None)`, read-only views of them
    /// without `copy`.
    fn run<'py>(
        slf: &Bound<'py, Self>,
        f: impl FnOnce(&mut VectorEnv, BatchMut<'_>) -> PyResult<()> + Send,
    ) -> PyResult<Bound<'py, PyTuple>> {
        let py = slf.py();
        let mut this = slf.try_borrow_mut().map_err(in_use)?;
        let this = &mut *this;
        if this.copy || this.arrays.is_none() {
            this.arrays = Some(this.new_arrays(py)?);
        }
        let a = this.arrays.as_ref().expect("arrays were just made");
        let mut obs = a.obs.borrow(py)?;
        let mut final_obs = a.final_obs.as_ref().map(|f| f.borrow(py)).transpose()?;
        let (mut rewards, mut terminated, mut truncated) =
            (rw(&a.rewards, py)?, rw(&a.terminated, py)?, rw(&a.truncated, py)?);
        let (mut fuel, mut lives, mut cause) = (rw(&a.fuel, py)?, rw(&a.lives, py)?, rw(&a.cause, py)?);
        let (rewards32, fuel32, lives32) = (&mut this.rewards32, &mut this.fuel32, &mut this.lives32);
        let contiguous = "the binding's own arrays are contiguous";
        let batch = BatchMut {
            observations: obs.as_buf_mut(),
            rewards: rewards32,
            terminated: terminated.as_slice_mut().expect(contiguous),
            truncated: truncated.as_slice_mut().expect(contiguous),
            fuel: fuel32,
            lives: lives32,
            cause: cause.as_slice_mut().expect(contiguous),
            final_observations: final_obs.as_mut().map(ObsRw::as_buf_mut),
        };
        let inner = &mut this.inner;
        py.detach(|| f(inner, batch))?;
        widen(rewards.as_slice_mut().expect(contiguous), &this.rewards32);
        widen(fuel.as_slice_mut().expect(contiguous), &this.fuel32);
        widen(lives.as_slice_mut().expect(contiguous), &this.lives32);
        drop((obs, final_obs, rewards, terminated, truncated, fuel, lives, cause));
        match &a.views {
            Some(views) => PyTuple::new(py, views.iter().map(|v| v.bind(py))),
            None => PyTuple::new(py, a.all(py)),
        }
    }
}

impl Arrays {
    /// Every output, in the order `run` returns them (`None` for the final observations without `SAME_STEP`).
    fn all<'py>(&self, py: Python<'py>) -> [Bound<'py, PyAny>; 8] {
        [
            self.obs.bind(py),
            self.rewards.bind(py).clone().into_any(),
            self.terminated.bind(py).clone().into_any(),
            self.truncated.bind(py).clone().into_any(),
            self.fuel.bind(py).clone().into_any(),
            self.lives.bind(py).clone().into_any(),
            self.cause.bind(py).clone().into_any(),
            self.final_obs.as_ref().map_or_else(|| py.None().into_bound(py), |f| f.bind(py)),
        ]
    }
}

/// A count option (`num_envs`, `num_threads`) as `usize`, or a `ValueError` naming it.
fn count(name: &str, value: &Bound<'_, PyAny>) -> PyResult<usize> {
    match value.extract::<usize>() {
        Ok(n) if !value.is_instance_of::<pyo3::types::PyBool>() => Ok(n),
        _ => Err(PyValueError::new_err(format!(
            "invalid value {} for option `{name}`: allowed an integer >= 1 (that fits the memory budget)",
            value.repr().map_or_else(|_| "?".to_string(), |r| r.to_string())
        ))),
    }
}

/// The `time_limit` (Python's `max_episode_steps`): `None` or an integer in `1..=u32::MAX`.
fn time_limit(value: Option<&Bound<'_, PyAny>>) -> PyResult<Option<u32>> {
    let Some(value) = value.filter(|v| !v.is_none()) else { return Ok(None) };
    match value.extract::<u32>() {
        Ok(n) if n >= 1 && !value.is_instance_of::<pyo3::types::PyBool>() => Ok(Some(n)),
        _ => Err(PyValueError::new_err(format!(
            "invalid value {} for option `max_episode_steps`: allowed an integer in 1..=4294967295, or None to never \
             truncate",
            value.repr().map_or_else(|_| "?".to_string(), |r| r.to_string())
        ))),
    }
}

#[pymethods]
impl PyVectorEnv {
    #[new]
    #[pyo3(signature = (num_envs, num_threads = None, options = None, same_step = false, copy = true, time_limit = None))]
    fn new(
        num_envs: &Bound<'_, PyAny>,
        num_threads: Option<&Bound<'_, PyAny>>,
        options: Option<&Bound<'_, PyDict>>,
        same_step: bool,
        copy: bool,
        time_limit: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<PyVectorEnv> {
        let num_envs = count("num_envs", num_envs)?;
        let num_threads = num_threads.map_or(Ok(1), |n| count("num_threads", n))?;
        let time_limit = self::time_limit(time_limit)?;
        let config = config_from(options)?;
        let mode = if same_step { AutoresetMode::SameStep } else { AutoresetMode::NextStep };
        let mut inner = VectorEnv::with_mode(config, num_envs, num_threads, mode).map_err(env_error)?;
        inner.set_time_limit(time_limit).map_err(env_error)?;
        // copy=False hands out the same arrays every call, to be read and not written: pixels can be drawn
        // incrementally onto them.
        inner.set_persistent_observations(!copy);
        let (rewards32, fuel32, lives32) = (vec![0.0; num_envs], vec![0; num_envs], vec![0; num_envs]);
        Ok(PyVectorEnv { inner, copy, arrays: None, rewards32, fuel32, lives32 })
    }

    /// Resets every environment: `seed` gives environment `i` the seed `seed + i`; `None` continues each
    /// stream. Returns the output arrays (see the class).
    #[pyo3(signature = (seed = None))]
    fn reset<'py>(slf: &Bound<'py, Self>, seed: Option<u64>) -> PyResult<Bound<'py, PyTuple>> {
        PyVectorEnv::run(slf, |v, out| v.reset_into(seed, out).map_err(batch_error))
    }

    /// Resets every environment, environment `i` with `seeds[i]` (`None` continues its stream).
    fn reset_seeds<'py>(slf: &Bound<'py, Self>, seeds: Vec<Option<u64>>) -> PyResult<Bound<'py, PyTuple>> {
        PyVectorEnv::run(slf, move |v, out| v.reset_seeds_into(&seeds, out).map_err(batch_error))
    }

    /// Steps every environment; `actions` is a contiguous `int64` array of `num_envs` actions.
    fn step<'py>(slf: &Bound<'py, Self>, actions: PyReadonlyArray1<'py, i64>) -> PyResult<Bound<'py, PyTuple>> {
        let actions = actions.as_slice().map_err(|e| PyValueError::new_err(format!("actions: {e}")))?;
        PyVectorEnv::run(slf, |v, out| v.step_into(actions, out).map_err(batch_error))
    }

    /// The full 600 × 800 × 3 frame of environment `i`.
    fn render<'py>(slf: &Bound<'py, Self>, i: usize) -> PyResult<Bound<'py, PyArrayDyn<u8>>> {
        let py = slf.py();
        let this = slf.try_borrow().map_err(in_use)?;
        let env = this.env(i)?;
        let frame = crate::obs::zeros::<u8>(py, &[HEIGHT as usize, WIDTH as usize, 3])?;
        // SAFETY: `frame` was just created and is not shared yet.
        let rgb = unsafe { frame.as_slice_mut() }.expect("a fresh array is contiguous");
        py.detach(|| env.render_into(rgb)).map_err(env_error)?;
        Ok(frame)
    }

    /// Snapshot bytes of environment `i` (what `chopperscape._core.Env.from_snapshot` reads).
    fn snapshot<'py>(slf: &Bound<'py, Self>, i: usize) -> PyResult<Bound<'py, PyBytes>> {
        Ok(PyBytes::new(slf.py(), &Snapshot::to_bytes(&slf.try_borrow().map_err(in_use)?.env(i)?.snapshot())))
    }

    /// The batch's state: `(started, [(snapshot bytes, pending reset, elapsed steps)] per environment)`.
    #[allow(clippy::type_complexity)]
    fn state<'py>(slf: &Bound<'py, Self>) -> PyResult<(bool, Vec<(Bound<'py, PyBytes>, bool, u32)>)> {
        let this = slf.try_borrow().map_err(in_use)?;
        let envs = (0..this.inner.num_envs())
            .map(|i| {
                let bytes = PyBytes::new(slf.py(), &this.inner.env(i).snapshot().to_bytes());
                (bytes, this.inner.pending_reset(i), this.inner.elapsed(i))
            })
            .collect();
        Ok((this.inner.is_started(), envs))
    }

    /// Restores [`PyVectorEnv::state`] (taken from a batch with the same options and size). Refuses, changing
    /// nothing, a state the batch cannot be in (see `VectorEnv::restore_env`).
    fn set_state(slf: &Bound<'_, Self>, started: bool, envs: Vec<(Vec<u8>, bool, u32)>) -> PyResult<()> {
        let mut this = slf.try_borrow_mut().map_err(in_use)?;
        this.set_state_of(started, envs)
    }

    /// Number of environments.
    #[getter]
    fn num_envs(&self) -> usize {
        self.inner.num_envs()
    }

    /// Worker threads a batch is split over.
    #[getter]
    fn num_threads(&self) -> usize {
        self.inner.num_threads()
    }

    /// Shape of one environment's observation.
    #[getter]
    fn obs_shape(&self) -> Vec<usize> {
        self.inner.single_observation_space().shape.clone()
    }

    /// numpy name of the observation's element type.
    #[getter]
    fn obs_dtype(&self) -> &'static str {
        self.inner.single_observation_space().dtype.as_str()
    }

    /// One period of the bounds of one observation, `(low, high)` (see `chopperscape._core.Env.obs_bounds`).
    #[getter]
    fn obs_bounds<'py>(&self, py: Python<'py>) -> BoundsArrays<'py> {
        bounds(py, self.inner.single_observation_space())
    }

    /// Fuel at reset (the `max_fuel` option).
    #[getter]
    fn max_fuel(&self) -> u32 {
        self.inner.config().max_fuel
    }

    /// Lives at reset (the `lives` option).
    #[getter]
    fn lives(&self) -> u32 {
        self.inner.config().lives
    }
}

impl PyVectorEnv {
    fn set_state_of(&mut self, started: bool, envs: Vec<(Vec<u8>, bool, u32)>) -> PyResult<()> {
        if envs.len() != self.inner.num_envs() {
            return Err(PyValueError::new_err(format!(
                "state holds {} environments: this batch has {}",
                envs.len(),
                self.inner.num_envs()
            )));
        }
        let snapshots = envs
            .iter()
            .map(|(bytes, _, _)| Snapshot::from_bytes(bytes).map_err(crate::errors::snapshot_error))
            .collect::<PyResult<Vec<_>>>()?;
        if started {
            // Restore into a copy, so that a snapshot of other options leaves this batch as it was.
            let mut next = self.inner.clone();
            for (i, (snapshot, (_, pending, elapsed))) in snapshots.iter().zip(&envs).enumerate() {
                next.restore_env(i, snapshot, *pending, *elapsed).map_err(env_error)?;
            }
            self.inner = next;
        }
        Ok(())
    }

    fn env(&self, i: usize) -> PyResult<&chopperscape::ChopperScape> {
        if i >= self.inner.num_envs() {
            return Err(PyIndexError::new_err(format!(
                "environment {i} does not exist: num_envs is {}",
                self.inner.num_envs()
            )));
        }
        Ok(self.inner.env(i))
    }
}

impl PyVectorEnv {
    /// The core batch (for the pilots, which read each env's world).
    pub(crate) fn core(&self) -> &VectorEnv {
        &self.inner
    }
}
