//! `chopperscape._core.read_action_log`: the command line's own action-log reader (`chopperscape-actionlog`),
//! so that `chopperscape.integrations.datasets.from_action_logs` accepts and refuses exactly the logs `replay` does, with
//! the same 64 MiB cap.

use std::path::PathBuf;

use chopperscape_actionlog::{self as actionlog, rule_values};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};

/// Reads and checks the action log at `path` (at most `MAX_LOG_BYTES` are read). Returns `{"seed": int,
/// "options": {name: text} (the rules options but `max_episode_steps`), "max_episode_steps": int | None,
/// "actions": bytes (one 0..=4 per step), "steps": int, "return": int, "cause": str | None, "policy": str |
/// None}`; `ValueError` naming the file and what is wrong.
#[pyfunction]
pub(crate) fn read_action_log<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyDict>> {
    let log = py.detach(|| actionlog::read(&path)).map_err(|e| PyValueError::new_err(format!("{e:#}")))?;
    let d = PyDict::new(py);
    let mut options = rule_values(&log.config);
    options.remove("max_episode_steps");
    d.set_item("seed", log.seed)?;
    d.set_item("options", options)?;
    d.set_item("max_episode_steps", log.config.max_episode_steps)?;
    d.set_item("actions", PyBytes::new(py, &log.actions))?;
    d.set_item("steps", log.steps)?;
    d.set_item("return", log.ret)?;
    d.set_item("cause", log.cause)?;
    d.set_item("policy", log.policy)?;
    Ok(d)
}
