//! Every Rust error becomes a Python exception here, in one place.
//!
//! Bad input (options, actions, seeds, buffers, snapshot bytes) is a `ValueError`; calling in the wrong
//! order (a step before reset, or after the episode ended) is a `RuntimeError`. Messages are the Rust ones:
//! they name the bad value and what is allowed.

use chopperscape::{ConfigError, Error, SnapshotError};
use chopperscape_vector::BatchError;
use pyo3::PyErr;
use pyo3::exceptions::{PyRuntimeError, PyValueError};

/// A core error as a Python exception.
pub(crate) fn env_error(e: Error) -> PyErr {
    match e {
        Error::NotReset | Error::EpisodeOver(_) => PyRuntimeError::new_err(e.to_string()),
        _ => PyValueError::new_err(e.to_string()),
    }
}

/// An invalid option as a `ValueError`.
pub(crate) fn config_error(e: ConfigError) -> PyErr {
    PyValueError::new_err(e.to_string())
}

/// Unreadable snapshot bytes as a `ValueError`.
pub(crate) fn snapshot_error(e: SnapshotError) -> PyErr {
    PyValueError::new_err(e.to_string())
}

/// A refused batch call as a Python exception.
pub(crate) fn batch_error(e: BatchError) -> PyErr {
    match e {
        BatchError::NotReset | BatchError::EnvState { .. } | BatchError::ThreadPool { .. } => {
            PyRuntimeError::new_err(e.to_string())
        }
        _ => PyValueError::new_err(e.to_string()),
    }
}

/// What a second thread gets while another one is inside a call on the same environment (instead of
/// PyO3's bare "Already borrowed").
pub(crate) fn in_use(_: impl std::fmt::Display) -> PyErr {
    PyRuntimeError::new_err(
        "this environment is in use by another thread: an env cannot be used from two threads at once \
         (give each thread its own env, or guard it with a lock)",
    )
}
