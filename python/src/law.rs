//! A feedback law written in Python, u = law(t, q), as a [`PolicyFactory`]:
//! sampled every `period` seconds on the ideal and on the simulated state,
//! exactly where the harness samples any feedback law (and where it sends
//! an external law its JSON line), and held in between.
//!
//! The runs happen without the GIL; each sample attaches to the
//! interpreter, calls the law with `t` (float) and `q` (a fresh numpy
//! array, so a law may keep it) and reads u back. When the law raises, or
//! returns something that is not u, the exception is kept, the run is
//! stopped (its token cancelled) and the caller raises that exception.

use crate::errors::runtime_failure;
use anholonomy::cancel::Cancel;
use anholonomy::model::{Input, State};
use anholonomy::plan::{Command, Controller, PolicyFactory};
use numpy::{AllowTypeChange, PyArray1, PyArrayLike1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyFloat, PyInt, PyList, PyTuple};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

/// What the runs of one call share with the caller.
pub struct Shared {
    /// The first exception a law raised (or a bad return value's error).
    pub error: Mutex<Option<PyErr>>,
    /// Cancelled when the law fails, or on Ctrl-C.
    pub cancel: Cancel,
    /// Law calls, both runs.
    pub calls: AtomicU64,
    /// Wall time of those calls, ns: attaching to the interpreter, the
    /// array, the call and reading u back (the per-sample overhead).
    pub nanos: AtomicU64,
}

impl Shared {
    pub fn new(cancel: Cancel) -> Shared {
        Shared {
            error: Mutex::new(None),
            cancel,
            calls: AtomicU64::new(0),
            nanos: AtomicU64::new(0),
        }
    }

    fn fail(&self, e: PyErr) {
        let mut slot = self.error.lock().unwrap_or_else(|p| p.into_inner());
        slot.get_or_insert(e);
        self.cancel.cancel();
    }

    /// The law's exception, if it failed.
    pub fn take_error(&self) -> Option<PyErr> {
        self.error.lock().unwrap_or_else(|p| p.into_inner()).take()
    }
}

/// The factory: one controller per run (ideal, physics), all calling the
/// same Python object.
pub struct PyLaw {
    law: Arc<Py<PyAny>>,
    inputs: &'static [&'static str],
    shared: Arc<Shared>,
}

impl PyLaw {
    pub fn new(law: Py<PyAny>, inputs: &'static [&'static str], shared: Arc<Shared>) -> PyLaw {
        PyLaw {
            law: Arc::new(law),
            inputs,
            shared,
        }
    }
}

impl PolicyFactory for PyLaw {
    fn start(&self) -> Box<dyn Controller> {
        Box::new(PyController {
            law: self.law.clone(),
            inputs: self.inputs,
            shared: self.shared.clone(),
            failed: false,
        })
    }
}

struct PyController {
    law: Arc<Py<PyAny>>,
    inputs: &'static [&'static str],
    shared: Arc<Shared>,
    failed: bool,
}

impl Controller for PyController {
    fn command(&mut self, t: f64, q: &State) -> Command {
        let stop = Command {
            u: Input::zeros(self.inputs.len()),
            label: 0,
            done: true,
        };
        if self.failed || self.shared.cancel.is_cancelled() {
            return stop;
        }
        let t0 = Instant::now();
        let res = Python::attach(|py| call(py, &self.law, self.inputs, t, q));
        let ns = t0.elapsed().as_nanos() as u64;
        self.shared.calls.fetch_add(1, Ordering::Relaxed);
        self.shared.nanos.fetch_add(ns, Ordering::Relaxed);
        match res {
            Ok(u) => Command {
                u,
                label: 0,
                done: false,
            },
            Err(e) => {
                self.failed = true;
                self.shared.fail(e);
                stop
            }
        }
    }
}

/// One sample: u = law(t, q), checked.
fn call(
    py: Python<'_>,
    law: &Py<PyAny>,
    inputs: &[&str],
    t: f64,
    q: &State,
) -> PyResult<Input> {
    let arr = PyArray1::from_slice(py, q.as_slice());
    let r = law.bind(py).call1((t, arr))?;
    let u = extract_u(&r).map_err(|what| {
        runtime_failure(
            py,
            format!(
                "feedback law: law(t, q) returned {what} at t = {t} s; expected a sequence of {} numbers ({})",
                inputs.len(),
                inputs.join(", ")
            ),
        )
    })?;
    if u.len() != inputs.len() {
        return Err(runtime_failure(
            py,
            format!(
                "feedback law: law(t, q) returned {} values at t = {t} s; the model takes {} ({})",
                u.len(),
                inputs.len(),
                inputs.join(", ")
            ),
        ));
    }
    if let Some(i) = u.iter().position(|x| !x.is_finite()) {
        return Err(runtime_failure(
            py,
            format!(
                "feedback law: law(t, q) returned {} = {} at t = {t} s (not a finite number)",
                inputs[i], u[i]
            ),
        ));
    }
    Ok(Input::from_vec(u))
}

/// The numbers of a law's return value: a float64 numpy array and lists or
/// tuples of numbers directly, anything else numpy converts to a 1-D float
/// array; else what it was, for the message.
fn extract_u(r: &Bound<'_, PyAny>) -> Result<Vec<f64>, String> {
    if let Ok(a) = r.cast::<PyArray1<f64>>() {
        if let Ok(s) = a.readonly().as_slice() {
            return Ok(s.to_vec());
        }
    }
    if r.is_instance_of::<PyList>() || r.is_instance_of::<PyTuple>() {
        if let Ok(v) = r.extract::<Vec<f64>>() {
            return Ok(v);
        }
    }
    let type_name = || {
        r.get_type()
            .name()
            .map(|n| n.to_string())
            .unwrap_or_else(|_| "?".into())
    };
    if r.is_instance_of::<PyFloat>() || r.is_instance_of::<PyInt>() || r.is_none() {
        return Err(format!("a single {}", type_name()));
    }
    match r.extract::<PyArrayLike1<'_, f64, AllowTypeChange>>() {
        Ok(a) => Ok(a.as_array().to_vec()),
        Err(_) => {
            let shape = r
                .getattr("shape")
                .ok()
                .map(|s| format!(" of shape {s}"))
                .unwrap_or_default();
            Err(format!("a {}{shape}", type_name()))
        }
    }
}
