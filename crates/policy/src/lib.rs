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
pub use vet::{
    MAX_ATTRIBUTES, MAX_ELEMENTS, MAX_GROUP, MAX_INITIALIZERS, MAX_MULTIPLY_ADDS, MAX_NODE_INPUTS, MAX_NODE_OUTPUTS,
    MAX_NODES, MAX_RANK, MAX_WINDOW, OPERATORS,
};

/// The largest policy file read: 64 MiB (the recipe's MLP takes 0.1 MB, its CNN on 84 × 84 frames about 7 MB).
pub const MAX_POLICY_BYTES: u64 = 64 << 20;

/// The most elements one observation of a policy may have: 8 Mi (32 MiB of `f32`), checked on the metadata's
/// `obs_shape` and on the observation its env options give, before the env or any observation is made. The
/// recipe's pixel policy takes 84 × 84 × 4 = 28,224; the env's default `rgb` 600 × 800 stacked 4 deep takes
/// 5.76 Mi. (Without it, `rgb_float` 4096 × 4096 in the metadata allocated 2 GB before it was refused.)
pub const MAX_OBSERVATION_ELEMENTS: usize = 8 << 20;

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

/// `text` as one line of at most [`MAX_MESSAGE_CHARS`] characters: control characters (a newline in a node name
/// or a metadata value) escaped, the rest cut with `…`. Every message built from a file's contents goes
/// through here, so an error stays one line whatever the file holds.
pub(crate) fn one_line(text: &str) -> String {
    let mut out = String::new();
    for (n, c) in text.chars().enumerate() {
        if n == MAX_MESSAGE_CHARS {
            out.push('…');
            break;
        }
        if c.is_control() { out.extend(c.escape_default()) } else { out.push(c) }
    }
    out
}

/// The most characters of an error message taken from a file (a node name, a metadata value, tract's text): 400.
const MAX_MESSAGE_CHARS: usize = 400;

#[cfg(panic = "unwind")]
mod quiet {
    //! Silences the panic hook while tract runs on this thread, so that a panic inside tract (caught, and
    //! returned as an error) prints nothing. One hook is installed for the whole process, the first time it is
    //! needed; it forwards every panic to the hook it replaced, except on a thread that is inside [`quietly`].
    //! Other threads' panics print as before. A hook set later by the program replaces this one (tract's panics
    //! then print again, nothing else changes).
    use std::cell::Cell;
    use std::sync::Once;

    thread_local! {
        static QUIET: Cell<bool> = const { Cell::new(false) };
    }

    /// Runs `f` with this thread's panics silenced.
    pub fn quietly<T>(f: impl FnOnce() -> T) -> T {
        static INSTALL: Once = Once::new();
        INSTALL.call_once(|| {
            let previous = std::panic::take_hook();
            std::panic::set_hook(Box::new(move |info| {
                if !QUIET.try_with(Cell::get).unwrap_or(false) {
                    previous(info);
                }
            }));
        });
        /// Restores the flag even when `f` unwinds.
        struct Restore(bool);
        impl Drop for Restore {
            fn drop(&mut self) {
                QUIET.with(|q| q.set(self.0));
            }
        }
        let _restore = Restore(QUIET.with(|q| q.replace(true)));
        f()
    }
}

/// Runs `f`, turning a panic (inside tract) into [`PolicyError::Run`], with the panic hook silenced on this thread
/// (where panics unwind; where they abort, as in the browser, nothing can be caught).
fn guarded<T>(f: impl FnOnce() -> Result<T, PolicyError>) -> Result<T, PolicyError> {
    let run = || catch_unwind(AssertUnwindSafe(f));
    #[cfg(panic = "unwind")]
    let result = quiet::quietly(run);
    #[cfg(not(panic = "unwind"))]
    let result = run();
    result.unwrap_or_else(|panic| {
        let msg = panic
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "the inference engine panicked".into());
        Err(PolicyError::Run(one_line(&format!("the inference engine failed ({msg})"))))
    })
}

fn run_err(e: impl std::fmt::Display) -> PolicyError {
    PolicyError::Run(one_line(&format!("{e:#}")))
}

/// What a path that is not a regular file is, in words ("a folder", "a character device", ...).
#[cfg(unix)]
fn file_kind(kind: std::fs::FileType) -> &'static str {
    use std::os::unix::fs::FileTypeExt as _;
    match () {
        () if kind.is_dir() => "a folder",
        () if kind.is_char_device() => "a character device",
        () if kind.is_block_device() => "a block device",
        () if kind.is_fifo() => "a named pipe",
        () if kind.is_socket() => "a socket",
        () => "not a regular file",
    }
}

/// What a path that is not a regular file is, in words.
#[cfg(not(unix))]
fn file_kind(kind: std::fs::FileType) -> &'static str {
    if kind.is_dir() { "a folder" } else { "not a regular file" }
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
        // Only a regular file is a policy: a device (`/dev/zero`) would read as an endless or empty file, a FIFO
        // would block the open, a folder fails later with a vaguer message. Said before anything is read.
        let kind = std::fs::metadata(path).map_err(read_err)?.file_type();
        if !kind.is_file() {
            let what = file_kind(kind);
            let source = std::io::Error::other(format!("it is {what}, not a policy file (an exported .onnx)"));
            return Err(read_err(source));
        }
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
            let elements = config.observation_bytes()
                / match dtype_of(config.obs_type) {
                    Dtype::U8 => 1,
                    Dtype::F32 => 4,
                };
            if elements > MAX_OBSERVATION_ELEMENTS as u64 {
                return Err(PolicyError::Metadata {
                    key: keys::ENV_OPTIONS,
                    problem: format!(
                        "give {} observations of {elements} elements, more than the {MAX_OBSERVATION_ELEMENTS} a \
                         policy may take",
                        config.obs_type.as_str()
                    ),
                });
            }
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

/// Refuses a typed graph whose values are not all of known size, have more than [`MAX_RANK`] axes, or hold more
/// than [`MAX_ELEMENTS`] together (each `Conv`'s unfolded patches counted as values), or that costs more than
/// [`MAX_MULTIPLY_ADDS`] per observation. Checked before tract optimises or runs the graph.
fn bounded(model: &TypedModel) -> Result<(), PolicyError> {
    use tract_onnx::tract_core::ops::cnn::Conv;
    use tract_onnx::tract_core::ops::einsum::EinSum;
    let too_many = |node: &TypedNode, what: &str| {
        PolicyError::NotPolicy(one_line(&format!("{what} for one observation (at {:?})", node.name)))
    };
    let shape_of = |node: &TypedNode, fact: &TypedFact| -> Result<Vec<u64>, PolicyError> {
        let shape = fact.shape.as_concrete().ok_or_else(|| {
            PolicyError::NotPolicy(one_line(&format!(
                "the size of {:?} does not follow from the observation's",
                node.name
            )))
        })?;
        if shape.len() > MAX_RANK {
            return Err(too_many(node, &format!("its values have more than {MAX_RANK} axes")));
        }
        Ok(shape.iter().map(|&d| d as u64).collect())
    };
    // u128 products of at most MAX_RANK sizes below 2^64 each cannot overflow once each factor is checked;
    // saturating keeps that true for any input.
    let product = |shape: &[u64]| shape.iter().fold(1u128, |n, &d| n.saturating_mul(u128::from(d)));
    let mut total = 0u128;
    let mut multiply_adds = 0u128;
    for node in model.nodes() {
        for output in &node.outputs {
            total = total.saturating_add(product(&shape_of(node, &output.fact)?));
        }
        let input_shapes: Vec<Vec<u64>> = node
            .inputs
            .iter()
            .map(|i| shape_of(node, model.outlet_fact(*i).map_err(run_err)?))
            .collect::<Result<_, _>>()?;
        if let Some(conv) = node.op_as::<Conv>() {
            let out = product(&shape_of(node, &node.outputs[0].fact)?);
            let kernel = product(&conv.pool_spec.kernel_shape.iter().map(|&k| k as u64).collect::<Vec<_>>());
            let (cin, cout, group) =
                (conv.input_channels() as u128, conv.output_channels().max(1) as u128, conv.group.max(1) as u128);
            multiply_adds = multiply_adds.saturating_add(out.saturating_mul(cin / group).saturating_mul(kernel));
            total = total.saturating_add((out / cout).saturating_mul(cin).saturating_mul(kernel));
        } else if let Some(einsum) = node.op_as::<EinSum>() {
            let input_shapes = &input_shapes;
            // Every axis of the expression, at its size: the output's elements times the summed axes'.
            let mut n = 1u128;
            for axis in einsum.axes.iter_all_axes() {
                let size = axis
                    .inputs
                    .iter()
                    .enumerate()
                    .flat_map(|(ix, positions)| {
                        positions.iter().filter_map(move |&p| input_shapes.get(ix).and_then(|s| s.get(p)))
                    })
                    .copied()
                    .max()
                    .unwrap_or(1);
                n = n.saturating_mul(u128::from(size));
            }
            multiply_adds = multiply_adds.saturating_add(n);
        }
        if total > MAX_ELEMENTS as u128 {
            return Err(too_many(node, &format!("its values hold more than {MAX_ELEMENTS} elements")));
        }
        if multiply_adds > u128::from(MAX_MULTIPLY_ADDS) {
            return Err(too_many(node, &format!("it costs more than {MAX_MULTIPLY_ADDS} multiply-adds")));
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
