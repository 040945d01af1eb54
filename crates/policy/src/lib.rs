//! Trained ChopperScape policies in pure Rust: an ONNX file from `python -m chopperscape.learn.export`, run by
//! [tract](https://github.com/sonos/tract), acting greedily from the env's own observation.
//!
//! # How the types relate
//! - [`Policy`] is one loaded policy: its [`Metadata`] (the observation it takes, the env options it was
//!   trained with, the layout versions it learned) and the graph, which maps one raw observation (the env's
//!   `Observation`, normalisation included in the graph) to the logits of the five actions.
//! - [`Policy::config`] gives the env options it was trained with; [`Policy::check`] refuses an env `Config`
//!   whose observation is not what the policy takes, before anything is played; [`Policy::act`] is the greedy
//!   action (the first of the highest logits, as `torch.argmax`).
//! - Every failure is a [`PolicyError`]. A policy file may come from anyone, so it is checked before tract
//!   builds anything from it (see [`MAX_POLICY_BYTES`] and the operator list [`OPERATORS`]), and a panic inside
//!   tract is caught and returned as an error.
//!
//! # Examples
//! ```no_run
//! use chopperscape::{ChopperScape, Env};
//! use chopperscape_policy::Policy;
//!
//! let mut policy = Policy::load("models/ppo-features.onnx")?;
//! let config = policy.config()?;
//! policy.check(&config)?;
//! let mut env = ChopperScape::new(config).unwrap();
//! let (mut obs, _) = env.reset(Some(7));
//! loop {
//!     let step = env.step(policy.act(&obs)? as i64).unwrap();
//!     obs = step.observation;
//!     if step.terminated || step.truncated {
//!         break;
//!     }
//! }
//! # Ok::<(), chopperscape_policy::PolicyError>(())
//! ```

mod error;
mod metadata;
mod vet;

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;

use chopperscape::{Action, ChopperScape, Config, Dtype, Env, N_ACTIONS, ObsData, ObsType, Observation};
use tract_onnx::prelude::*;

pub use error::PolicyError;
pub use metadata::{FORMAT, Metadata, keys};
pub use vet::{MAX_ELEMENTS, OPERATORS};

/// The largest policy file read: 64 MiB (the recipe's MLP takes 0.1 MB, its CNN on 84 × 84 frames about 7 MB).
pub const MAX_POLICY_BYTES: u64 = 64 << 20;

/// A loaded policy, ready to act. Not `Sync`: it keeps tract's run state between steps.
pub struct Policy {
    meta: Metadata,
    state: TypedSimpleState,
    dtype: Dtype,
    input_shape: Vec<usize>,
}

impl std::fmt::Debug for Policy {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Policy").field("meta", &self.meta).finish_non_exhaustive()
    }
}

/// The element type of an observation type.
fn dtype_of(obs_type: ObsType) -> Dtype {
    match obs_type {
        ObsType::Rgb | ObsType::Grayscale => Dtype::U8,
        ObsType::RgbFloat | ObsType::Features => Dtype::F32,
    }
}

fn describe(dtype: Dtype, shape: &[usize]) -> String {
    format!("{} {shape:?}", dtype.as_str())
}

/// Runs `f`, turning a panic (inside tract) into [`PolicyError::Run`].
fn guarded<T>(f: impl FnOnce() -> Result<T, PolicyError>) -> Result<T, PolicyError> {
    catch_unwind(AssertUnwindSafe(f)).unwrap_or_else(|panic| {
        let msg = panic
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "the inference engine panicked".into());
        Err(PolicyError::Run(msg))
    })
}

fn run_err(e: impl std::fmt::Display) -> PolicyError {
    PolicyError::Run(format!("{e:#}"))
}

impl Policy {
    /// Reads a policy file ([`MAX_POLICY_BYTES`] at most).
    ///
    /// # Errors
    /// A file that cannot be read or is too large, and everything [`Policy::from_bytes`] refuses.
    pub fn load(path: impl AsRef<Path>) -> Result<Policy, PolicyError> {
        use std::io::Read;
        let path = path.as_ref();
        let read_err = |source| PolicyError::Read { path: path.display().to_string(), source };
        let file = std::fs::File::open(path).map_err(read_err)?;
        let mut bytes = Vec::new();
        // One byte past the limit tells a file at the limit from a larger one, without reading the rest.
        file.take(MAX_POLICY_BYTES + 1).read_to_end(&mut bytes).map_err(read_err)?;
        if bytes.len() as u64 > MAX_POLICY_BYTES {
            let len = std::fs::metadata(path).map(|m| m.len()).unwrap_or(bytes.len() as u64);
            return Err(PolicyError::TooLarge { bytes: len, max: MAX_POLICY_BYTES });
        }
        Policy::from_bytes(&bytes)
    }

    /// A policy from the bytes of an exported ONNX file: its metadata read and checked (format, layout versions,
    /// env options), the graph checked (see [`OPERATORS`]), built for one observation of the metadata's shape and
    /// type, and run once on zeros to check it gives five logits.
    ///
    /// # Errors
    /// [`PolicyError::TooLarge`], [`PolicyError::NotPolicy`] (not ONNX, or a graph no export makes),
    /// [`PolicyError::Metadata`], or [`PolicyError::Run`] when tract refuses the graph.
    pub fn from_bytes(bytes: &[u8]) -> Result<Policy, PolicyError> {
        if bytes.len() as u64 > MAX_POLICY_BYTES {
            return Err(PolicyError::TooLarge { bytes: bytes.len() as u64, max: MAX_POLICY_BYTES });
        }
        guarded(|| {
            let onnx = tract_onnx::onnx();
            let proto = onnx
                .proto_model_for_read(&mut &bytes[..])
                .map_err(|e| PolicyError::NotPolicy(format!("it is not an ONNX model ({e})")))?;
            vet::model(&proto, bytes.len())?;
            let meta = Metadata::from_props(proto.metadata_props.iter().map(|e| (e.key.as_str(), e.value.as_str())))?;
            meta.check_versions()?;
            // The env options must make the observation the graph takes.
            let config = meta.config()?;
            let (env_dtype, env_shape) = observation_of(&config)?;
            let dtype = dtype_of(meta.obs_type);
            if env_shape != meta.obs_shape || env_dtype != dtype {
                return Err(PolicyError::Metadata {
                    key: keys::OBS_SHAPE,
                    problem: format!(
                        "is {}, but its env options give {} observations",
                        describe(dtype, &meta.obs_shape),
                        describe(env_dtype, &env_shape)
                    ),
                });
            }
            let mut input_shape = vec![1];
            input_shape.extend_from_slice(&meta.obs_shape);
            let datum = match dtype {
                Dtype::U8 => u8::datum_type(),
                Dtype::F32 => f32::datum_type(),
            };
            let model = onnx.model_for_proto_model(&proto).map_err(run_err)?;
            let model = model
                .with_input_fact(0, InferenceFact::dt_shape(datum, input_shape.clone()))
                .and_then(|m| m.into_typed())
                .map_err(run_err)?;
            bounded(&model)?;
            let plan = model.into_optimized().and_then(|m| m.into_runnable()).map_err(run_err)?;
            let state = plan.spawn().map_err(run_err)?;
            let mut policy = Policy { meta, state, dtype, input_shape };
            policy.logits(&Observation::zeros(policy.meta.obs_shape.clone(), dtype))?;
            Ok(policy)
        })
    }

    /// The policy's metadata.
    pub fn metadata(&self) -> &Metadata {
        &self.meta
    }

    /// The env options the policy was trained with (the v0 rules where it says nothing).
    ///
    /// # Errors
    /// None in practice: the options were checked when the policy was loaded.
    pub fn config(&self) -> Result<Config, PolicyError> {
        self.meta.config()
    }

    /// Checks that an env with `config` gives the observation this policy takes (type and shape).
    ///
    /// # Errors
    /// [`PolicyError::Mismatch`] naming both.
    pub fn check(&self, config: &Config) -> Result<(), PolicyError> {
        let (dtype, shape) = observation_of(config)?;
        if shape != self.meta.obs_shape || dtype != self.dtype || config.obs_type != self.meta.obs_type {
            return Err(PolicyError::Mismatch {
                model: format!("{} {}", self.meta.obs_type.as_str(), describe(self.dtype, &self.meta.obs_shape)),
                env: format!(
                    "{} {} (obs_size {}x{}, frame_stack {})",
                    config.obs_type.as_str(),
                    describe(dtype, &shape),
                    config.obs_size.0,
                    config.obs_size.1,
                    config.frame_stack
                ),
            });
        }
        Ok(())
    }

    /// The logits of the five actions for one observation.
    ///
    /// # Errors
    /// An observation of another shape or type ([`PolicyError::Mismatch`]), or a failure inside tract.
    pub fn logits(&mut self, obs: &Observation) -> Result<[f32; N_ACTIONS], PolicyError> {
        let obs_dtype = match obs.data {
            ObsData::U8(_) => Dtype::U8,
            ObsData::F32(_) => Dtype::F32,
        };
        if obs.shape != self.meta.obs_shape || obs_dtype != self.dtype {
            return Err(PolicyError::Mismatch {
                model: describe(self.dtype, &self.meta.obs_shape),
                env: describe(obs_dtype, &obs.shape),
            });
        }
        let input = match &obs.data {
            ObsData::U8(v) => Tensor::from_shape(&self.input_shape, v),
            ObsData::F32(v) => Tensor::from_shape(&self.input_shape, v),
        }
        .map_err(run_err)?;
        let state = &mut self.state;
        guarded(|| {
            let out = state.run(tvec!(input.into_tvalue())).map_err(run_err)?;
            let logits = out.first().ok_or_else(|| PolicyError::Run("the graph gave no output".into()))?;
            let values = logits.try_as_plain_ram().and_then(|v| v.as_slice::<f32>()).map_err(run_err)?;
            <[f32; N_ACTIONS]>::try_from(values).map_err(|_| {
                PolicyError::Run(format!(
                    "the graph gives {} values of shape {:?}, not 5 logits",
                    values.len(),
                    logits.shape()
                ))
            })
        })
    }

    /// The greedy action for one observation: the first of the highest logits (a NaN counts as highest, as in
    /// `torch.argmax`).
    ///
    /// # Errors
    /// As [`Policy::logits`].
    pub fn act(&mut self, obs: &Observation) -> Result<Action, PolicyError> {
        Ok(Action::ALL[argmax(&self.logits(obs)?)])
    }
}

/// The index of the first highest value; NaN is above every number (`torch.argmax`).
pub fn argmax(values: &[f32]) -> usize {
    let mut best = 0;
    for (i, &v) in values.iter().enumerate().skip(1) {
        let b = values[best];
        if !b.is_nan() && (v.is_nan() || v > b) {
            best = i;
        }
    }
    best
}

/// The element type and shape of the observation of an env with `config`.
fn observation_of(config: &Config) -> Result<(Dtype, Vec<usize>), PolicyError> {
    let env = ChopperScape::new(config.clone())
        .map_err(|e| PolicyError::Metadata { key: keys::ENV_OPTIONS, problem: format!("make no env: {e}") })?;
    let space = env.observation_space();
    Ok((space.dtype, space.shape.clone()))
}

/// Refuses a typed graph whose values are not all of known size, or hold more than [`MAX_ELEMENTS`] together.
fn bounded(model: &TypedModel) -> Result<(), PolicyError> {
    let mut total = 0usize;
    for node in model.nodes() {
        for output in &node.outputs {
            let shape = output.fact.shape.as_concrete().ok_or_else(|| {
                PolicyError::NotPolicy(format!("the size of {:?} does not follow from the observation's", node.name))
            })?;
            let n = shape.iter().try_fold(1usize, |n, &d| n.checked_mul(d));
            total = n.and_then(|n| total.checked_add(n)).filter(|&t| t <= MAX_ELEMENTS).ok_or_else(|| {
                PolicyError::NotPolicy(format!(
                    "its values hold more than {MAX_ELEMENTS} elements for one observation (at {:?}, shape {shape:?})",
                    node.name
                ))
            })?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn argmax_takes_the_first_highest_and_nan_as_highest() {
        assert_eq!(argmax(&[1.0, 3.0, 3.0, 2.0, 0.0]), 1);
        assert_eq!(argmax(&[1.0, 3.0, f32::NAN, 2.0, f32::NAN]), 2);
        assert_eq!(argmax(&[f32::NAN, 3.0, 0.0, 0.0, 0.0]), 0);
    }
}
