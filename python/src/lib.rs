//! The native part of the `anholonomy` Python package (`anholonomy._native`):
//! scenarios validated and run by the harness's Rust core, results as numpy
//! arrays, feedback laws as Python callables. The public API, its types
//! and docs are in `anholonomy/__init__.py`; this module is its engine.

mod convert;
mod errors;
mod law;
mod run;
mod scenario;

use pyo3::prelude::*;

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<scenario::Scenario>()?;
    m.add_function(wrap_pyfunction!(scenario::load_file, m)?)?;
    m.add_function(wrap_pyfunction!(scenario::load_text, m)?)?;
    m.add_function(wrap_pyfunction!(scenario::load_table, m)?)?;
    m.add_function(wrap_pyfunction!(run::run, m)?)?;
    m.add_function(wrap_pyfunction!(run::run_many, m)?)?;
    m.add("DEFAULT_MAX_STEPS", anholonomy::validate::DEFAULT_MAX_STEPS)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
