//! Every way loading or running a policy file can fail, as one typed error whose message says what to do.

/// An error from [`crate::Policy`]: the file, its metadata, its graph, or a mismatch with an env.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PolicyError {
    /// The file could not be read.
    #[error("cannot read {path}: {source}")]
    Read {
        /// The file.
        path: String,
        /// Why.
        source: std::io::Error,
    },
    /// The file is larger than any policy this crate loads.
    #[error("the policy file is {bytes} bytes, more than the {max} bytes a policy may take")]
    TooLarge {
        /// Its size.
        bytes: u64,
        /// [`crate::MAX_POLICY_BYTES`].
        max: u64,
    },
    /// The bytes are not an ONNX model, or one this crate does not run (a graph it does not accept).
    #[error("not a ChopperScape policy (export one with `python -m chopperscape.learn.export`): {0}")]
    NotPolicy(String),
    /// A metadata entry is missing or malformed.
    #[error("the policy's metadata `{key}` {problem} (export it again with `python -m chopperscape.learn.export`)")]
    Metadata {
        /// The `metadata_props` key.
        key: &'static str,
        /// What is wrong with it.
        problem: String,
    },
    /// The policy observes something else than the env gives.
    #[error(
        "the policy takes {model} observations, but the env gives {env}: play it with the options it was trained with"
    )]
    Mismatch {
        /// What the model takes (type and shape).
        model: String,
        /// What the env gives (type and shape, and the options behind them).
        env: String,
    },
    /// The inference engine refused the graph or failed while running it.
    #[error("the policy's graph cannot be run: {0}")]
    Run(String),
}
