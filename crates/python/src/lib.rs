//! The Python binding: the module `chopperscape._core`, thin newtypes over the core and vector crates.
//!
//! - `env::PyEnv` (`_core.Env`) wraps one [`chopperscape::ChopperScape`]; `vector::PyVectorEnv`
//!   (`_core.VectorEnv`) wraps a [`chopperscape_vector::VectorEnv`].
//! - Options arrive as a dict and go through [`chopperscape::Config::set`] (`options`); errors become Python
//!   exceptions in one place (`errors`).
//! - Observations are written straight into numpy arrays the binding allocates; pixel work and every batch
//!   run with the GIL released. A Rust panic surfaces as `pyo3_runtime.PanicException`, never an abort.
//!
//! The Gymnasium classes live in Python (`python/chopperscape/`), over this module.

mod actionlog;
mod arrays;
mod env;
mod errors;
mod obs;
mod options;
mod policies;
mod vector;

use pyo3::prelude::*;

/// The compiled core of the `chopperscape` package. Use `chopperscape.Env` / `chopperscape.VectorEnv`.
#[pymodule]
mod _core {
    use super::*;

    #[pymodule_export]
    use super::actionlog::read_action_log;
    #[pymodule_export]
    use super::env::PyEnv;
    #[pymodule_export]
    use super::options::option_value;
    #[pymodule_export]
    use super::policies::{PyPolicy, PyVectorPolicy};
    #[pymodule_export]
    use super::vector::PyVectorEnv;

    #[pymodule_init]
    fn init(m: &Bound<'_, PyModule>) -> PyResult<()> {
        m.add("ACTION_MEANINGS", chopperscape::ACTION_MEANINGS.to_vec())?;
        m.add("OPTION_NAMES", chopperscape::OPTION_NAMES.to_vec())?;
        m.add("OPTIONS", options::option_table(m.py())?)?;
        m.add("MODES", options::mode_table(m.py())?)?;
        m.add("CAUSE_NAMES", chopperscape_vector::CAUSE_NAMES.to_vec())?;
        m.add("SNAPSHOT_VERSION", chopperscape::SNAPSHOT_VERSION)?;
        m.add("FEATURES_VERSION", chopperscape::features::FEATURES_VERSION)?;
        m.add("PIXELS_VERSION", chopperscape::render::PIXELS_VERSION)?;
        let layouts = pyo3::types::PyDict::new(m.py());
        for version in 1..=chopperscape::render::PIXELS_VERSION {
            let options = chopperscape::render::layout_options(version).unwrap_or_default();
            layouts.set_item(version, pyo3::types::PyDict::from_sequence(&options.to_vec().into_pyobject(m.py())?)?)?;
        }
        m.add("PIXEL_LAYOUTS", layouts)?;
        m.add("RENDER_FPS", chopperscape::consts::RENDER_FPS)?;
        m.add("POLICY_NAMES", chopperscape::policy::NAMES.to_vec())?;
        m.add("MAX_ENV_BYTES", chopperscape::limits::MAX_ENV_BYTES)?;
        m.add("MAX_BATCH_BYTES", chopperscape_vector::MAX_BATCH_BYTES)?;
        m.add("MAX_THREADS", chopperscape_vector::MAX_THREADS)?;
        m.add("MAX_LOG_BYTES", chopperscape_actionlog::MAX_LOG_BYTES)?;
        m.add("__version__", env!("CARGO_PKG_VERSION"))?;
        Ok(())
    }

    /// Panics in Rust with `message`: lets the tests prove a panic reaches Python as an exception.
    #[pyfunction]
    fn _panic(message: &str) {
        panic!("{message}");
    }
}
