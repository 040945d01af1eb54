//! Keyword options (a Python dict) to a [`Config`], through [`Config::set`] so the rules for every value
//! live in the core.

use chopperscape::Config;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyString};

use crate::errors::config_error;

/// The v0 config with each option of `options` applied in turn. Values may be Python values
/// (`obs_size=(84, 84)` or any sequence of two ints, `hud=False` (bools only, numpy's included), `lives=3`,
/// `alien_prob=0.02`, `max_episode_steps=None`) or the textual forms [`Config::set`] reads (not for `hud`).
///
/// # Errors
/// `ValueError` naming the first unknown option or value out of range.
pub(crate) fn config_from(options: Option<&Bound<'_, PyDict>>) -> PyResult<Config> {
    let mut config = Config::default();
    let Some(options) = options else { return Ok(config) };
    for (name, value) in options.iter() {
        let name: String =
            name.extract().map_err(|_| PyValueError::new_err(format!("option names must be strings, got {name:?}")))?;
        if name == "obs_size" && !value.is_instance_of::<PyString>() {
            set_obs_size(&mut config, &value)?;
            continue;
        }
        let text = option_text(&name, &value)?;
        config.set(&name, &text).map_err(config_error)?;
    }
    Ok(config)
}

/// `obs_size` from a Python value: a tuple, list or array of two ints.
fn set_obs_size(config: &mut Config, value: &Bound<'_, PyAny>) -> PyResult<()> {
    let refused = || {
        let repr = value.repr().map_or_else(|_| "?".to_string(), |r| r.to_string());
        PyValueError::new_err(format!(
            "invalid value {repr} for option `obs_size`: allowed a tuple (height, width) of positive ints, each in \
             8..=4096, for example (84, 84)"
        ))
    };
    let items: Vec<Bound<'_, PyAny>> = value.extract().map_err(|_| refused())?;
    let [h, w] = items.as_slice() else { return Err(refused()) };
    let int = |v: &Bound<'_, PyAny>| if v.is_instance_of::<PyBool>() { None } else { v.extract::<u32>().ok() };
    let (Some(h), Some(w)) = (int(h), int(w)) else { return Err(refused()) };
    config.set("obs_size", &format!("{h}x{w}")).map_err(|_| refused())
}

/// The textual form of one option's Python value.
fn option_text(name: &str, value: &Bound<'_, PyAny>) -> PyResult<String> {
    if name == "hud" {
        // A bool option takes bools only (numpy's too): "False" or 0 would silently mean something else.
        return match value.extract::<bool>() {
            Ok(b) => Ok(if b { "true" } else { "false" }.into()),
            Err(_) => Err(PyValueError::new_err(format!(
                "invalid value {} for option `hud`: allowed True or False",
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
        // A bool anywhere but `hud` is refused by the option's own parser, naming the option.
        return Ok(if value.is_truthy()? { "true" } else { "false" }.into());
    }
    Ok(value.str()?.to_string())
}
