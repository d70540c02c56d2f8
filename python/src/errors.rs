//! The harness's errors as the package's exceptions (defined in Python, in
//! `anholonomy/_errors.py`, so they carry docstrings and pickle):
//! bad input → `InputError` (file, line, key, the CLI's one-line message),
//! runtime failures → `RuntimeFailure`.

use anholonomy::Error;
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::PyType;
use std::path::Path;

static INPUT_ERROR: PyOnceLock<Py<PyType>> = PyOnceLock::new();
static RUNTIME_FAILURE: PyOnceLock<Py<PyType>> = PyOnceLock::new();

fn raise<'py>(
    py: Python<'py>,
    cell: &PyOnceLock<Py<PyType>>,
    name: &str,
    args: impl pyo3::call::PyCallArgs<'py>,
) -> PyErr {
    let made = cell
        .import(py, "anholonomy._errors", name)
        .and_then(|cls| cls.call1(args));
    match made {
        Ok(exc) => PyErr::from_value(exc),
        Err(e) => e,
    }
}

/// `InputError(text, file, line, key)`.
pub fn input_error(
    py: Python<'_>,
    text: String,
    file: Option<&Path>,
    line: Option<usize>,
    key: Option<String>,
) -> PyErr {
    let file = file.map(|p| p.display().to_string());
    raise(py, &INPUT_ERROR, "InputError", (text, file, line, key))
}

/// `RuntimeFailure(text)`.
pub fn runtime_failure(py: Python<'_>, text: String) -> PyErr {
    raise(py, &RUNTIME_FAILURE, "RuntimeFailure", (text,))
}

/// The exception for a harness error: its text is the CLI's line without
/// the `error: ` prefix.
pub fn to_py(py: Python<'_>, e: &Error) -> PyErr {
    // The CLI's line exactly, numbers included (1e300, not 301 digits).
    let text = anholonomy::numfmt::shorten_long_numbers(&e.to_string());
    match e {
        Error::Input {
            path, line, key, ..
        } => input_error(py, text, Some(path), *line, key.clone()),
        // The planner ran and did not converge: exit 3 in the CLI.
        Error::Plan {
            source: anholonomy::planner::PlanError::NoConvergence(_),
            ..
        } => runtime_failure(py, text),
        Error::Plan {
            path, line, key, ..
        } => input_error(py, text, Some(path), *line, Some(key.clone())),
        _ => runtime_failure(py, text),
    }
}
