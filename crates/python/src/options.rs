//! Keyword options (a Python dict) to a [`Config`], through [`Config::set`] so the rules for every value
//! live in the core.

use chopperscape::{Config, ConfigError, OptionKind, OptionValue, option_info};
use pyo3::IntoPyObjectExt;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyList, PyString};

use crate::errors::config_error;

/// The v0 config with each option of `options` applied in turn. Values may be Python values
/// (`obs_size=(84, 84)` or any sequence of two ints, `hud=False` (bools only, numpy's included), `lives=3`,
/// `alien_prob=0.02`, `max_episode_steps=None`) or the textual forms [`Config::set`] reads (not for `hud`).
///
/// `mode` (a name of [`chopperscape::MODES`], or `None` for none) is applied first, whatever its place in the dict;
/// the other options go on top, and one that contradicts the mode's fixed rules is refused, naming the mode (the
/// core's [`chopperscape::configure`], as the command line and the page build theirs).
///
/// # Errors
/// `ValueError` naming the first unknown option or value out of range, or the options that contradict the mode.
pub(crate) fn config_from(options: Option<&Bound<'_, PyDict>>) -> PyResult<Config> {
    let Some(options) = options else { return Ok(Config::default()) };
    let mode = match options.get_item("mode")? {
        Some(value) if !value.is_none() => Some(mode_of(&value)?),
        _ => None,
    };
    let set = |config: &mut Config| -> Result<(), OptionError> {
        for (name, value) in options.iter() {
            let name: String = name
                .extract()
                .map_err(|_| PyValueError::new_err(format!("option names must be strings, got {name:?}")))?;
            if name == "mode" {
                continue;
            }
            let kind = option_info(&name).map(|o| o.kind);
            if kind == Some(OptionKind::Size) && !value.is_instance_of::<PyString>() {
                set_size(config, &name, &value)?;
                continue;
            }
            let text = option_text(&name, kind, &value)?;
            config.set(&name, &text)?;
        }
        Ok(())
    };
    chopperscape::configure(Config::default(), mode, set).map_err(|OptionError(e)| e)
}

/// A Python exception on its way out of [`chopperscape::configure`], which raises the core's errors through `From`.
struct OptionError(PyErr);

impl From<PyErr> for OptionError {
    fn from(e: PyErr) -> Self {
        OptionError(e)
    }
}

impl From<ConfigError> for OptionError {
    fn from(e: ConfigError) -> Self {
        OptionError(config_error(e))
    }
}

/// The mode named by a Python value: a string of [`chopperscape::MODES`].
fn mode_of(value: &Bound<'_, PyAny>) -> PyResult<&'static chopperscape::Mode> {
    let name = value.cast::<PyString>().map(|s| s.to_string()).ok();
    name.as_deref().and_then(chopperscape::mode).ok_or_else(|| {
        let repr = value.repr().map_or_else(|_| "?".to_string(), |r| r.to_string());
        PyValueError::new_err(format!(
            "invalid value {repr} for option `mode`: allowed None or one of {}",
            chopperscape::mode_names()
        ))
    })
}

/// `_core.MODES`: the difficulty modes ([`chopperscape::MODES`]), easiest first, each a dict with `name`, `id`
/// (the Gymnasium id), `doc` and `options` (a dict of the rules options it sets, as text [`option_value`] reads).
pub(crate) fn mode_table(py: Python<'_>) -> PyResult<Bound<'_, PyList>> {
    let table = PyList::empty(py);
    for m in chopperscape::MODES {
        let row = PyDict::new(py);
        row.set_item("name", m.name)?;
        row.set_item("id", m.id)?;
        row.set_item("doc", m.doc)?;
        let options = PyDict::new(py);
        for (n, v) in m.options {
            options.set_item(n, v)?;
        }
        row.set_item("options", options)?;
        table.append(row)?;
    }
    Ok(table)
}

/// A size option (`obs_size`) from a Python value: a tuple, list or array of two ints.
fn set_size(config: &mut Config, name: &str, value: &Bound<'_, PyAny>) -> PyResult<()> {
    let refused = || {
        let repr = value.repr().map_or_else(|_| "?".to_string(), |r| r.to_string());
        PyValueError::new_err(format!(
            "invalid value {repr} for option `{name}`: allowed a tuple (height, width) of positive ints, each in \
             8..=4096, for example (84, 84)"
        ))
    };
    let items: Vec<Bound<'_, PyAny>> = value.extract().map_err(|_| refused())?;
    let [h, w] = items.as_slice() else { return Err(refused()) };
    let int = |v: &Bound<'_, PyAny>| if v.is_instance_of::<PyBool>() { None } else { v.extract::<u32>().ok() };
    let (Some(h), Some(w)) = (int(h), int(w)) else { return Err(refused()) };
    config.set(name, &format!("{h}x{w}")).map_err(|_| refused())
}

/// The textual form of one option's Python value (`kind`: the option's, `None` for an unknown name).
fn option_text(name: &str, kind: Option<OptionKind>, value: &Bound<'_, PyAny>) -> PyResult<String> {
    if kind == Some(OptionKind::Bool) {
        // A bool option takes bools only (numpy's too): "False" or 0 would silently mean something else.
        return match value.extract::<bool>() {
            Ok(b) => Ok(if b { "true" } else { "false" }.into()),
            Err(_) => Err(PyValueError::new_err(format!(
                "invalid value {} for option `{name}`: allowed True or False",
                value.repr().map_or_else(|_| "?".to_string(), |r| r.to_string())
            ))),
        };
    }
    if value.is_none() {
        return Ok("none".into());
    }
    if let Ok(s) = value.cast::<PyString>() {
        return Ok(s.to_string());
    }
    if value.is_instance_of::<PyBool>() {
        // A bool anywhere but a bool option is refused by the option's own parser, naming the option.
        return Ok(if value.is_truthy()? { "true" } else { "false" }.into());
    }
    Ok(value.str()?.to_string())
}

/// The value of option `name` written as text (as the command line's flags take it: `84x84`, `false`, `none`,
/// `0.02`, `features`), parsed by [`Config::set`] and returned as the Python value of the option's type: `int`,
/// `float`, `str`, `bool`, a `(height, width)` tuple, or `None` for `max_episode_steps=none`. The one place where
/// text from a command line becomes a typed option, so every tool reads `--option NAME=VALUE` alike.
///
/// # Errors
/// `ValueError` naming an unknown option, or the option and what it allows.
#[pyfunction]
pub(crate) fn option_value<'py>(py: Python<'py>, name: &str, text: &str) -> PyResult<Bound<'py, PyAny>> {
    // Features: no observation budget interferes with checking one option on its own.
    let mut c = Config::features();
    c.set(name, text).map_err(config_error)?;
    match c.value(name) {
        Some(OptionValue::Choice(v)) => v.into_bound_py_any(py),
        Some(OptionValue::Bool(v)) => v.into_bound_py_any(py),
        Some(OptionValue::Size(v)) => v.into_bound_py_any(py),
        Some(OptionValue::Integer(v)) => v.into_bound_py_any(py),
        Some(OptionValue::IntegerOrNone(v)) => v.into_bound_py_any(py),
        Some(OptionValue::Probability(v)) => v.into_bound_py_any(py),
        None => Err(PyValueError::new_err(format!("option `{name}` has no Python value type here"))),
    }
}

/// `_core.OPTIONS`: the core's description of every option ([`chopperscape::OPTIONS`]), in SPEC order, each a
/// dict with `name`, `default` (text, as [`option_value`] reads it), `allowed`, `doc` and `rule`.
pub(crate) fn option_table(py: Python<'_>) -> PyResult<Bound<'_, PyList>> {
    let table = PyList::empty(py);
    for o in chopperscape::OPTIONS {
        let row = PyDict::new(py);
        row.set_item("name", o.name)?;
        row.set_item("default", o.default)?;
        row.set_item("allowed", o.allowed)?;
        row.set_item("doc", o.doc)?;
        row.set_item("rule", o.rule)?;
        table.append(row)?;
    }
    Ok(table)
}
