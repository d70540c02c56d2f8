//! A feedback law written in Python, u = law(t, q), as a [`PolicyFactory`]
//! run by [`anholonomy::runner::run_with_plan_detailed`]: sampled every
//! `period` seconds on the ideal and on the simulated state, exactly where
//! the harness sends an external law (`[planner] kind = "external"`) its
//! JSON line, and held in between.
//!
//! The runs happen without the GIL; each sample attaches to the
//! interpreter, calls the law with `t` (float) and `q` (a fresh numpy
//! array, so a law may keep it) and reads the answer: u as a sequence or
//! array, or a dict like the external protocol's answer (`{"u": [...],
//! "label": "...", "done": false}`). When the law raises or answers
//! something that is not an input, the controller faults (the run ends at
//! that sample, the command unused) and the caller raises the exception.

use crate::errors::runtime_failure;
use anholonomy::cancel::Cancel;
use anholonomy::model::{Input, State};
use anholonomy::plan::{Command, Controller, LabelTable, OncePerSample, PolicyFactory};
use anholonomy::sources::external::protocol::MAX_LABELS;
use numpy::{AllowTypeChange, PyArray1, PyArrayLike1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

/// Label of commands whose answer names none.
pub const DEFAULT_LABEL: &str = "python";

/// What the runs of one call share with the caller.
pub struct Shared {
    /// The first exception a law raised (or a bad answer's error).
    pub error: Mutex<Option<PyErr>>,
    /// Cancelled on Ctrl-C (checked by the runs at every step, and before
    /// each call of the law).
    pub cancel: Cancel,
    /// Law calls, both runs.
    pub calls: AtomicU64,
    /// Wall time of those calls, ns: attaching to the interpreter, the
    /// array, the call and reading the answer (the per-sample overhead).
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

    fn keep(&self, e: PyErr) {
        let mut slot = self.error.lock().unwrap_or_else(|p| p.into_inner());
        slot.get_or_insert(e);
    }

    /// The law's exception, if it failed.
    pub fn take_error(&self) -> Option<PyErr> {
        self.error.lock().unwrap_or_else(|p| p.into_inner()).take()
    }
}

/// The factory: one controller per run (ideal, physics), all calling the
/// same Python object and naming labels in one table.
pub struct PyLaw {
    law: Arc<Py<PyAny>>,
    inputs: &'static [&'static str],
    shared: Arc<Shared>,
    labels: Arc<LabelTable>,
}

impl PyLaw {
    pub fn new(law: Py<PyAny>, inputs: &'static [&'static str], shared: Arc<Shared>) -> PyLaw {
        PyLaw {
            law: Arc::new(law),
            inputs,
            shared,
            labels: Arc::new(LabelTable::default()),
        }
    }
}

impl PolicyFactory for PyLaw {
    /// A Python callable may keep state across runs: they take turns.
    fn concurrent(&self) -> bool {
        false
    }

    fn start(&self) -> Box<dyn Controller> {
        // Asked once per sample, as an external law is (the runs ask twice
        // at t = 0): a law that counts its calls or keeps state sees the
        // same sequence both ways.
        Box::new(OncePerSample::new(PyController {
            law: self.law.clone(),
            inputs: self.inputs,
            shared: self.shared.clone(),
            labels: self.labels.clone(),
            fault: None,
        }))
    }

    fn labels(&self) -> Option<Vec<String>> {
        Some(self.labels.names())
    }
}

struct PyController {
    law: Arc<Py<PyAny>>,
    inputs: &'static [&'static str],
    shared: Arc<Shared>,
    labels: Arc<LabelTable>,
    fault: Option<String>,
}

/// A law's answer.
struct Answer {
    u: Input,
    label: Option<String>,
    done: bool,
}

impl Controller for PyController {
    fn command(&mut self, t: f64, q: &State) -> Command {
        let stop = Command {
            u: Input::zeros(self.inputs.len()),
            label: 0,
            done: true,
        };
        if self.fault.is_some() {
            return stop;
        }
        if self.shared.cancel.is_cancelled() {
            self.fault = Some(anholonomy::cancel::CANCELLED.into());
            return stop;
        }
        let t0 = Instant::now();
        let res = Python::attach(|py| {
            call(py, &self.law, self.inputs, t, q).and_then(|a| {
                let name = a.label.as_deref().unwrap_or(DEFAULT_LABEL);
                let label = self.labels.intern(name, MAX_LABELS).ok_or_else(|| {
                    runtime_failure(
                        py,
                        format!("feedback law: more than {MAX_LABELS} distinct labels (`{name}` is one too many)"),
                    )
                })?;
                Ok(Command {
                    u: a.u,
                    label,
                    done: a.done,
                })
            })
            .map_err(|e| {
                let text = e.to_string();
                (e, text)
            })
        });
        self.shared.calls.fetch_add(1, Ordering::Relaxed);
        let ns = t0.elapsed().as_nanos() as u64;
        self.shared.nanos.fetch_add(ns, Ordering::Relaxed);
        match res {
            Ok(c) => c,
            Err((e, text)) => {
                self.shared.keep(e);
                self.fault = Some(text);
                stop
            }
        }
    }

    fn fault(&self) -> Option<String> {
        self.fault.clone()
    }
}

use anholonomy::numfmt::readable;

/// One sample: the law's answer, checked.
fn call(py: Python<'_>, law: &Py<PyAny>, inputs: &[&str], t: f64, q: &State) -> PyResult<Answer> {
    let arr = PyArray1::from_slice(py, q.as_slice());
    let r = law.bind(py).call1((t, arr))?;
    let bad = |what: String| {
        runtime_failure(
            py,
            format!(
                "feedback law: law(t, q) returned {what} at t = {} s; expected {} numbers ({}), or a dict {{\"u\": [...], \"label\": str, \"done\": bool}}",
                readable(t),
                inputs.len(),
                inputs.join(", ")
            ),
        )
    };
    let (u, label, done) = match r.cast::<PyDict>() {
        Ok(d) => {
            for k in d.keys() {
                let known = k
                    .extract::<String>()
                    .is_ok_and(|k| matches!(k.as_str(), "u" | "label" | "done"));
                if !known {
                    return Err(bad(format!("a dict with the key {}", k.repr()?)));
                }
            }
            let u = d
                .get_item("u")?
                .ok_or_else(|| bad("a dict without the key 'u'".into()))?;
            let label = match d.get_item("label")? {
                None => None,
                Some(l) if l.is_none() => None,
                Some(l) if l.is_instance_of::<PyString>() => Some(l.extract::<String>()?),
                Some(l) => return Err(bad(format!("a label that is a {}", type_name(&l)))),
            };
            let done = match d.get_item("done")? {
                None => false,
                Some(x) => x
                    .extract::<bool>()
                    .map_err(|_| bad(format!("`done` that is a {}", type_name(&x))))?,
            };
            (extract_u(&u).map_err(&bad)?, label, done)
        }
        Err(_) => (extract_u(&r).map_err(&bad)?, None, false),
    };
    if u.len() != inputs.len() {
        return Err(runtime_failure(
            py,
            format!(
                "feedback law: law(t, q) returned {} values at t = {} s; the model takes {} ({})",
                u.len(),
                readable(t),
                inputs.len(),
                inputs.join(", ")
            ),
        ));
    }
    if let Some(i) = u.iter().position(|x| !x.is_finite()) {
        return Err(runtime_failure(
            py,
            format!(
                "feedback law: law(t, q) returned {} = {} at t = {} s (not a finite number)",
                inputs[i],
                u[i],
                readable(t)
            ),
        ));
    }
    Ok(Answer {
        u: Input::from_vec(u),
        label,
        done,
    })
}

fn type_name(r: &Bound<'_, PyAny>) -> String {
    r.get_type()
        .name()
        .map(|n| n.to_string())
        .unwrap_or_else(|_| "?".into())
}

/// The numbers of u: a float64 numpy array and lists or tuples of numbers
/// directly, anything else numpy converts to a 1-D float array; else what
/// it was, for the message.
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
    if r.is_instance_of::<PyFloat>() || r.is_instance_of::<PyInt>() || r.is_none() {
        return Err(format!("a single {}", type_name(r)));
    }
    if r.is_instance_of::<PyString>() {
        return Err("a str".into());
    }
    match r.extract::<PyArrayLike1<'_, f64, AllowTypeChange>>() {
        Ok(a) => Ok(a.as_array().to_vec()),
        Err(_) => {
            let shape = r
                .getattr("shape")
                .ok()
                .map(|s| format!(" of shape {s}"))
                .unwrap_or_default();
            Err(format!("a {}{shape}", type_name(r)))
        }
    }
}
