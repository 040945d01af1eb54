//! `chopperscape._core.Policy` and `chopperscape._core.VectorPolicy`: the built-in policies of
//! [`chopperscape::policy`], reading the world of an env of this module (never a Python-side copy of it).
//!
//! A policy is made by name; the heuristic plans for the options of the env it plays (its `frame_skip` and
//! `sticky_prob`), so it is built for an env's options the first time it sees that env, and rebuilt when it
//! sees an env with other options. `random` draws from its own generator, seeded as the CLI's `demo` seeds it.

use chopperscape::limits::{check_budget, probe};
use chopperscape::policy::{self, Policy};
use chopperscape::{Action, Config};
use chopperscape_vector::MAX_BATCH_BYTES;
use numpy::PyArray1;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::env::PyEnv;
use crate::errors::{config_error, in_use};
use crate::vector::PyVectorEnv;

/// Heap bytes one policy may take beside its [`Built`]: its boxed policy (the largest, `random`'s generator,
/// is 40 bytes), its name, and the options it plans for (kept inline). Generous, so the budget is an upper bound.
const POLICY_HEAP_BYTES: u64 = 128;

/// The memory `num_envs` policies take: what a `VectorPolicy` is checked against before anything is allocated.
fn policies_bytes(num_envs: usize) -> u64 {
    (std::mem::size_of::<Built>() as u64 + POLICY_HEAP_BYTES).saturating_mul(num_envs as u64)
}

/// One built-in policy by name, and the options it was built for.
struct Built {
    name: String,
    seed: u64,
    policy: Box<dyn Policy + Send + Sync>,
    /// The options the policy plans for (`None`: not built for an env yet).
    config: Option<Config>,
}

impl Built {
    fn new(name: &str, seed: u64) -> PyResult<Built> {
        let policy = policy::by_name(name, seed, &Config::default()).map_err(PyValueError::new_err)?;
        Ok(Built { name: name.to_string(), seed, policy, config: None })
    }

    /// Makes the policy plan for `config`. `random` ignores the options, so its generator is never restarted.
    fn fit(&mut self, config: &Config) {
        if self.name != "random" && self.config.as_ref() != Some(config) {
            self.policy = policy::by_name(&self.name, self.seed, config).expect("the name was checked");
            self.config = Some(config.clone());
        }
    }

    fn reseed(&mut self, seed: u64) {
        self.seed = seed;
        self.policy = policy::by_name(&self.name, seed, self.config.as_ref().unwrap_or(&Config::default()))
            .expect("the name was checked");
    }
}

/// A built-in policy for one `chopperscape._core.Env`: `random` (seeded), `heuristic`, or a fixed action
/// (`right`, `left`, `down`, `up`, `noop`).
#[pyclass(name = "Policy", module = "chopperscape._core")]
pub(crate) struct PyPolicy {
    inner: Built,
}

#[pymethods]
impl PyPolicy {
    #[new]
    #[pyo3(signature = (name, seed = 0))]
    fn new(name: &str, seed: u64) -> PyResult<PyPolicy> {
        Ok(PyPolicy { inner: Built::new(name, seed)? })
    }

    /// The action (0..=4) for the env's current state. While another thread is inside a call on the env, the
    /// package's two-threads `RuntimeError`.
    fn act(&mut self, env: &Bound<'_, PyEnv>) -> PyResult<u8> {
        let env = env.try_borrow().map_err(in_use)?;
        let env = env.core();
        self.inner.fit(env.config());
        Ok(self.inner.policy.act(env.world()) as u8)
    }

    /// Starts over as if new with `seed` (`None`: the seed it has): `random` restarts its generator.
    #[pyo3(signature = (seed = None))]
    fn reset(&mut self, seed: Option<u64>) {
        self.inner.reseed(seed.unwrap_or(self.inner.seed));
    }

    /// The policy's name.
    #[getter]
    fn name(&self) -> &str {
        &self.inner.name
    }

    /// The seed of its generator (used by `random` only).
    #[getter]
    fn seed(&self) -> u64 {
        self.inner.seed
    }
}

/// One built-in policy per environment of a `chopperscape._core.VectorEnv`; policy `i` is seeded `seed + i`, as the
/// environment `i` of a batch reset with `seed`. `act` computes the whole batch's actions with the GIL released.
#[pyclass(name = "VectorPolicy", module = "chopperscape._core")]
pub(crate) struct PyVectorPolicy {
    policies: Vec<Built>,
    seed: u64,
}

#[pymethods]
impl PyVectorPolicy {
    #[new]
    #[pyo3(signature = (name, num_envs, seed = 0))]
    fn new(name: &str, num_envs: usize, seed: u64) -> PyResult<PyVectorPolicy> {
        if num_envs == 0 {
            return Err(PyValueError::new_err("invalid value 0 for option `num_envs`: allowed an integer >= 1"));
        }
        let first = Built::new(name, seed)?;
        // The batch's memory budget, checked (and asked of the system) before anything is allocated.
        let what = format!("{num_envs} policies");
        let needed = policies_bytes(num_envs);
        check_budget(what.clone(), needed, MAX_BATCH_BYTES, "play fewer environments").map_err(config_error)?;
        probe(needed, &what).map_err(config_error)?;
        let mut policies = Vec::new();
        policies
            .try_reserve_exact(num_envs)
            .map_err(|_| config_error(chopperscape::ConfigError::OutOfMemory { what: what.clone(), needed }))?;
        policies.push(first);
        for i in 1..num_envs as u64 {
            policies.push(Built::new(name, seed.wrapping_add(i))?);
        }
        Ok(PyVectorPolicy { policies, seed })
    }

    /// The `num_envs` actions (`int64`) for the batch's current states. An environment whose next step is an
    /// autoreset (its action is ignored) gets 4 (Do Nothing), and its policy draws nothing for it.
    fn act<'py>(&mut self, py: Python<'py>, envs: &Bound<'py, PyVectorEnv>) -> PyResult<Bound<'py, PyArray1<i64>>> {
        let envs = envs.try_borrow().map_err(in_use)?;
        let inner = envs.core();
        if inner.num_envs() != self.policies.len() {
            return Err(PyValueError::new_err(format!(
                "the vector env has {} environments but this policy plays {}: make the policy with num_envs={}",
                inner.num_envs(),
                self.policies.len(),
                inner.num_envs()
            )));
        }
        let policies = &mut self.policies;
        let actions: Vec<i64> = py.detach(|| {
            policies
                .iter_mut()
                .enumerate()
                .map(|(i, policy)| {
                    if inner.pending_reset(i) {
                        return Action::Noop as i64;
                    }
                    let env = inner.env(i);
                    policy.fit(env.config());
                    policy.policy.act(env.world()) as i64
                })
                .collect()
        });
        Ok(PyArray1::from_vec(py, actions))
    }

    /// Starts over as if new with `seed` (`None`: the seed it has): policy `i` is seeded `seed + i`.
    #[pyo3(signature = (seed = None))]
    fn reset(&mut self, seed: Option<u64>) {
        self.seed = seed.unwrap_or(self.seed);
        for (i, p) in self.policies.iter_mut().enumerate() {
            p.reseed(self.seed.wrapping_add(i as u64));
        }
    }

    /// The policies' name.
    #[getter]
    fn name(&self) -> &str {
        &self.policies[0].name
    }

    /// Number of environments it plays.
    #[getter]
    fn num_envs(&self) -> usize {
        self.policies.len()
    }

    /// The seed of policy 0 (policy `i` has `seed + i`).
    #[getter]
    fn seed(&self) -> u64 {
        self.seed
    }
}
