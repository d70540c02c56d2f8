//! `anholonomy.Scenario`: a scenario that passed the CLI's validation pass
//! (TOML, ranges, URDF, plan, physics at the start pose), ready to run.

use crate::convert::{json_to_py, py_to_toml, toml_text};
use crate::errors::{input_error, to_py};
use anholonomy::validate::Prepared;
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;
use std::sync::Arc;

/// A validated scenario: parsed and checked like the CLI does before it
/// runs anything (keys, ranges, URDF, the plan, the physics at the start
/// pose). Make one with `anholonomy.load`; `replace` gives variants.
#[pyclass(frozen, module = "anholonomy")]
pub struct Scenario {
    pub prep: Arc<Prepared>,
}

/// Validate a parsed scenario (planning and the physics probe run without
/// the GIL).
pub fn prepare(
    py: Python<'_>,
    sc: anholonomy::scenario::Scenario,
    max_steps: u64,
) -> PyResult<Scenario> {
    let prep = py
        .detach(|| Prepared::with_budget(sc, max_steps))
        .map_err(|e| to_py(py, &e))?;
    Ok(Scenario {
        prep: Arc::new(prep),
    })
}

fn parsed(
    py: Python<'_>,
    res: Result<anholonomy::scenario::Scenario, anholonomy::Error>,
    max_steps: u64,
) -> PyResult<Scenario> {
    prepare(py, res.map_err(|e| to_py(py, &e))?, max_steps)
}

/// A scenario file.
#[pyfunction]
pub fn load_file(py: Python<'_>, path: PathBuf, max_steps: u64) -> PyResult<Scenario> {
    parsed(py, anholonomy::scenario::Scenario::load(&path), max_steps)
}

/// Scenario text, read as if from the file `path` (relative paths inside
/// resolve against its directory; the name defaults to its stem).
#[pyfunction]
pub fn load_text(py: Python<'_>, text: &str, path: PathBuf, max_steps: u64) -> PyResult<Scenario> {
    parsed(
        py,
        anholonomy::scenario::Scenario::parse(&path, text),
        max_steps,
    )
}

/// A scenario as nested dicts, written as TOML and read as if from `path`.
#[pyfunction]
pub fn load_table(
    py: Python<'_>,
    table: &Bound<'_, PyDict>,
    path: PathBuf,
    max_steps: u64,
) -> PyResult<Scenario> {
    let value = py_to_toml(table.as_any(), "")?;
    let text = toml::to_string(&value).map_err(|e| {
        input_error(
            py,
            format!("{}: {e}", path.display()),
            Some(&path),
            None,
            None,
        )
    })?;
    load_text(py, &text, path, max_steps)
}

#[pymethods]
impl Scenario {
    /// A variant: values written over this scenario's keys, given by the
    /// dotted key paths sweeps use (`"sim.friction"`, `"goal"`,
    /// `"start[2]"`, `"planner.k1"`), then validated like a file. Angles in
    /// `start`/`goal` are in degrees, as in the file. Raises `InputError`
    /// (with the key and the line where the file writes it).
    fn replace(&self, py: Python<'_>, changes: &Bound<'_, PyDict>) -> PyResult<Scenario> {
        let mut edits = Vec::with_capacity(changes.len());
        for (k, v) in changes.iter() {
            let key: String = k.extract()?;
            let value = py_to_toml(&v, &key)?;
            edits.push((key, toml_text(&value)));
        }
        let sc = self
            .prep
            .scenario
            .replace(&edits)
            .map_err(|e| to_py(py, &e))?;
        prepare(py, sc, self.prep.max_steps)
    }

    /// The scenario's name (its log directory).
    #[getter]
    fn name(&self) -> &str {
        &self.prep.scenario.name
    }

    /// The file it was read from (for text and dicts: the path it was read as).
    #[getter]
    fn file(&self) -> PathBuf {
        self.prep.scenario.path.clone()
    }

    /// The `description` key.
    #[getter]
    fn description(&self) -> &str {
        &self.prep.scenario.description
    }

    /// The model kind (`model.kind`).
    #[getter]
    fn model(&self) -> &str {
        self.prep.scenario.model.kind()
    }

    /// The planner kind (`planner.kind`).
    #[getter]
    fn planner(&self) -> &str {
        self.prep.scenario.planner.kind()
    }

    /// Names of the state coordinates (columns of `Result.ideal.q`).
    #[getter]
    fn state_names(&self) -> Vec<&'static str> {
        self.prep.model().state_names().to_vec()
    }

    /// Names of the inputs (what a feedback law returns, in this order).
    #[getter]
    fn input_names(&self) -> Vec<&'static str> {
        self.prep.model().input_names().to_vec()
    }

    /// Start state in model coordinates, SI units (angles in radians).
    #[getter]
    fn start<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.prep.scenario.start)
    }

    /// Goal state in model coordinates, SI units (angles in radians).
    #[getter]
    fn goal<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.prep.scenario.goal)
    }

    /// Physics and integration step `sim.dt`, s.
    #[getter]
    fn dt(&self) -> f64 {
        self.prep.scenario.sim.dt
    }

    /// Duration of the validated plan, s (a feedback law's horizon).
    #[getter]
    fn duration(&self) -> f64 {
        self.prep.planned.duration
    }

    /// The scenario's TOML text as read (without `replace`'s changes).
    #[getter]
    fn text(&self) -> &str {
        self.prep.scenario.text()
    }

    /// Whether the scenario has a `[sweep]` table (`run` then runs its variants).
    #[getter]
    fn is_sweep(&self) -> bool {
        self.prep.scenario.sweep.is_some()
    }

    /// The resolved scenario (defaults filled in, SI units) as a dict.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let v = serde_json::to_value(&self.prep.scenario)
            .map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))?;
        json_to_py(py, &v)
    }

    fn __repr__(&self) -> String {
        let sc = &self.prep.scenario;
        format!(
            "Scenario({:?}, model={:?}, planner={:?}, file={:?})",
            sc.name,
            sc.model.kind(),
            sc.planner.kind(),
            sc.path.display().to_string()
        )
    }
}
