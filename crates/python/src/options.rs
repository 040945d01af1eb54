//! Keyword options (a Python dict) to a [`Config`], through [`Config::set`] so the rules for every value
//! live in the core.

use chopperscape::Config;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyString};

use crate::errors::config_error;

/// The v0 config with each option of `options` applied in turn. Values may be Python values
/// (`obs_size=(84, 84)`, `hud=False`, `lives=3`, `alien_prob=0.02`, `max_episode_steps=None`) or the
/// textual forms [`Config::set`] reads.
///
/// # Errors
/// `ValueError` naming the first unknown option or value out of range.
pub(crate) fn config_from(options: Option<&Bound<'_, PyDict>>) -> PyResult<Config> {
    let mut config = Config::default();
    let Some(options) = options else { return Ok(config) };
    for (name, value) in options.iter() {
        let name: String =
            name.extract().map_err(|_| PyValueError::new_err(format!("option names must be strings, got {name:?}")))?;
        let text = option_text(&name, &value)?;
        config.set(&name, &text).map_err(config_error)?;
    }
    Ok(config)
}

/// The textual form of one option's Python value.
fn option_text(name: &str, value: &Bound<'_, PyAny>) -> PyResult<String> {
    if value.is_none() {
        return Ok("none".into());
    }
    if let Ok(s) = value.cast::<PyString>() {
        return Ok(s.to_string());
    }
    if value.is_instance_of::<PyBool>() {
        // `hud=True` reads as "true"; a bool anywhere else is refused by the option's own parser.
        return Ok(if value.is_truthy()? { "true" } else { "false" }.into());
    }
    if name == "obs_size" {
        if let Ok((h, w)) = value.extract::<(Bound<'_, PyAny>, Bound<'_, PyAny>)>() {
            return Ok(format!("{}x{}", h.str()?, w.str()?));
        }
        // A list, as a JSON round trip (a Minari dataset's env spec) gives back.
        if let Ok([h, w]) = value.extract::<Vec<Bound<'_, PyAny>>>().as_deref() {
            return Ok(format!("{}x{}", h.str()?, w.str()?));
        }
    }
    Ok(value.str()?.to_string())
}
