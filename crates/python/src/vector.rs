//! `chopperscape._core.VectorEnv`: a batch of environments stepped by one call with the GIL released,
//! written into numpy arrays. The Gymnasium class in `chopperscape/vector.py` wraps it.

use chopperscape::Snapshot;
use chopperscape::consts::{HEIGHT, WIDTH};
use chopperscape_vector::{AutoresetMode, BatchMut, VectorEnv};
use numpy::{PyArrayDyn, PyArrayMethods, PyReadonlyArray1};
use pyo3::exceptions::{PyIndexError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyTuple};

use crate::arrays::{ObsOut, Out};
use crate::errors::{batch_error, env_error, in_use};
use crate::obs::{BoundsArrays, bounds};
use crate::options::config_from;

/// The output arrays of a batch.
struct Arrays {
    obs: ObsOut,
    final_obs: Option<ObsOut>,
    /// `float64`, as Gymnasium's vector envs return rewards; the batch writes `float32` into `rewards32`.
    rewards: Out<f64>,
    terminated: Out<bool>,
    truncated: Out<bool>,
    /// `int64`, as Gymnasium batches Python ints; the batch writes `uint32` into `fuel32`.
    fuel: Out<i64>,
    /// `int64`; the batch writes `uint32` into `lives32`.
    lives: Out<i64>,
    cause: Out<u8>,
}

/// Copies `from` into the wider numpy type Gymnasium's vector envs use.
fn widen<S: Copy, D: From<S>>(to: &mut [D], from: &[S]) {
    for (d, &s) in to.iter_mut().zip(from) {
        *d = D::from(s);
    }
}

/// `num_envs` environments stepped together over `num_threads` threads; environment `i` of a batch reset with
/// seed `s` is seeded `s + i`. With `copy`, each call returns fresh arrays; without, the same sealed arrays every
/// call (read-only for good: see `arrays.rs`). `time_limit` truncates episodes as Gymnasium's `TimeLimit` does
/// (see `VectorEnv::set_time_limit`).
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
        let sealed = !self.copy;
        Ok(Arrays {
            obs: ObsOut::new(py, &shape, space.dtype, sealed)?,
            final_obs: same_step.then(|| ObsOut::new(py, &shape, space.dtype, sealed)).transpose()?,
            rewards: Out::new(py, &[n], sealed)?,
            terminated: Out::new(py, &[n], sealed)?,
            truncated: Out::new(py, &[n], sealed)?,
            fuel: Out::new(py, &[n], sealed)?,
            lives: Out::new(py, &[n], sealed)?,
            cause: Out::new(py, &[n], sealed)?,
        })
    }

    /// Runs `f` on the output arrays (fresh ones with `copy`) with the GIL released; returns the arrays as
    /// `(obs, rewards, terminated, truncated, fuel, lives, cause, final_obs | None)`.
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
        // SAFETY: the arrays are this binding's own, written only here under the exclusive borrow of `this`, and
        // no input of `f` is one of them (`step` copies the actions first); see `Out::slice_mut`.
        let (rewards, fuel, lives) = unsafe { (a.rewards.slice_mut(py), a.fuel.slice_mut(py), a.lives.slice_mut(py)) };
        let (rewards32, fuel32, lives32) = (&mut this.rewards32, &mut this.fuel32, &mut this.lives32);
        // SAFETY: as above.
        let batch = unsafe {
            BatchMut {
                observations: a.obs.buf_mut(py),
                rewards: rewards32,
                terminated: a.terminated.slice_mut(py),
                truncated: a.truncated.slice_mut(py),
                fuel: fuel32,
                lives: lives32,
                cause: a.cause.slice_mut(py),
                final_observations: a.final_obs.as_ref().map(|f| f.buf_mut(py)),
            }
        };
        let inner = &mut this.inner;
        py.detach(|| f(inner, batch))?;
        widen(rewards, &this.rewards32);
        widen(fuel, &this.fuel32);
        widen(lives, &this.lives32);
        PyTuple::new(py, a.all(py))
    }
}

impl Arrays {
    /// Every output, in the order `run` returns them (`None` for the final observations without `SAME_STEP`).
    fn all<'py>(&self, py: Python<'py>) -> [Bound<'py, PyAny>; 8] {
        [
            self.obs.bind(py),
            self.rewards.bind(py),
            self.terminated.bind(py),
            self.truncated.bind(py),
            self.fuel.bind(py),
            self.lives.bind(py),
            self.cause.bind(py),
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

    /// Steps every environment; `actions` is a contiguous `int64` array of `num_envs` actions. They are copied
    /// first (a few bytes an env), so that no output array the batch writes can be the input it reads.
    fn step<'py>(slf: &Bound<'py, Self>, actions: PyReadonlyArray1<'py, i64>) -> PyResult<Bound<'py, PyTuple>> {
        let actions = actions.as_slice().map_err(|e| PyValueError::new_err(format!("actions: {e}")))?.to_vec();
        PyVectorEnv::run(slf, move |v, out| v.step_into(&actions, out).map_err(batch_error))
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
    /// The core batch (for the built-in policies, which read each env's world).
    pub(crate) fn core(&self) -> &VectorEnv {
        &self.inner
    }
}
