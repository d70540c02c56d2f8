//! `run` and `run_many`: the CLI's pipeline on validated scenarios, without
//! the GIL, on a worker thread while the calling thread waits and checks
//! for signals (Ctrl-C cancels the run at its next step and raises
//! `KeyboardInterrupt`). Results come back as dicts of numpy arrays; the
//! Python layer wraps them (`anholonomy.Result`).

use crate::convert::json_to_py;
use crate::errors::{input_error, to_py};
use crate::law::{PyLaw, Shared};
use crate::scenario::Scenario;
use anholonomy::cancel::Cancel;
use anholonomy::integrate::Trajectory;
use anholonomy::plan::Plan;
use anholonomy::runner::{run_detailed, run_with_plan_detailed, Finished, RunOptions, RunOutcome};
use anholonomy::scenario::PlannerConfig;
use anholonomy::validate::Prepared;
use anholonomy::Error;
use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::mpsc::{self, RecvTimeoutError};
use std::sync::Arc;
use std::time::Duration;

/// How often the waiting thread looks for a signal.
const SIGNAL_POLL: Duration = Duration::from_millis(50);

/// Run `work` on a worker thread without the GIL; the calling thread checks
/// for signals meanwhile. On a signal (Ctrl-C) the token is cancelled, the
/// worker's result is dropped once it stops, and the signal's exception
/// (`KeyboardInterrupt`) is returned.
fn interruptible<T: Send>(
    py: Python<'_>,
    cancel: &Cancel,
    work: impl FnOnce() -> T + Send,
) -> PyResult<T> {
    let (tx, rx) = mpsc::channel();
    let (out, signal) = std::thread::scope(|s| {
        // The main thread's stack size: runs on the CLI's main thread get as much.
        let spawned = std::thread::Builder::new()
            .name("anholonomy-run".into())
            .stack_size(8 << 20)
            .spawn_scoped(s, move || {
                // A thread state for the worker's lifetime: a law's per-sample
                // attach then only takes the GIL, without creating and
                // destroying a thread state each time.
                let v = Python::attach(|py| py.detach(work));
                let _ = tx.send(v);
            });
        if let Err(e) = spawned {
            return Err(pyo3::exceptions::PyRuntimeError::new_err(format!(
                "cannot start the run's thread: {e}"
            )));
        }
        Ok(py.detach(move || {
            let mut signal: Option<PyErr> = None;
            loop {
                match rx.recv_timeout(SIGNAL_POLL) {
                    Ok(v) => return (Some(v), signal),
                    // The worker panicked: the scope re-raises the panic.
                    Err(RecvTimeoutError::Disconnected) => return (None, signal),
                    Err(RecvTimeoutError::Timeout) => {
                        if signal.is_none() {
                            if let Err(e) = Python::attach(|py| py.check_signals()) {
                                signal = Some(e);
                                cancel.cancel();
                            }
                        }
                    }
                }
            }
        }))
    })?;
    match (signal, out) {
        (Some(e), _) => Err(e),
        (None, Some(v)) => Ok(v),
        (None, None) => Err(pyo3::exceptions::PyRuntimeError::new_err(
            "the run's thread stopped without a result",
        )),
    }
}

/// Log root checks the CLI's validation pass makes.
fn check_logs(py: Python<'_>, logs: Option<&Path>, names: &[&str]) -> PyResult<()> {
    let Some(root) = logs else { return Ok(()) };
    if root.exists() && !root.is_dir() {
        return Err(input_error(
            py,
            format!("{}: logs: exists and is not a directory", root.display()),
            Some(root),
            None,
            None,
        ));
    }
    for n in names {
        let dir = root.join(n);
        if dir.exists() && !dir.is_dir() {
            return Err(input_error(
                py,
                format!(
                    "{}: log directory exists and is not a directory",
                    dir.display()
                ),
                Some(&dir),
                None,
                None,
            ));
        }
    }
    Ok(())
}

fn check_pose_rate(py: Python<'_>, rate: f64) -> PyResult<()> {
    if rate.is_finite() && rate >= 0.0 {
        return Ok(());
    }
    Err(input_error(
        py,
        format!("pose_rate: {} is not a rate: give link poses per second of simulated time (0 = every sample)", anholonomy::numfmt::readable(rate)),
        None,
        None,
        Some("pose_rate".into()),
    ))
}

fn options(logs: Option<PathBuf>, pose_rate: f64, cancel: &Cancel) -> RunOptions {
    RunOptions {
        log_root: logs,
        progress: Default::default(),
        pose_rate,
        cancel: cancel.clone(),
        keep: anholonomy::log::Keep::All,
        batch: true,
    }
}

/// What one scenario gave.
enum Ran {
    Run(Box<Finished>),
    Sweep(Box<RunOutcome>, String),
}

fn run_one(prep: &Prepared, opts: &RunOptions) -> Result<Ran, Error> {
    if prep.scenario.sweep.is_some() {
        let (o, table) = anholonomy::sweep::run_sweep_report(prep, opts, None, None)?;
        Ok(Ran::Sweep(Box::new(o), table))
    } else {
        run_detailed(prep, opts).map(|f| Ran::Run(Box::new(f)))
    }
}

/// The plan of a Python law: `law` sampled every `period` s for at most
/// `horizon` s (defaults: an external law's `planner.period` and
/// `planner.horizon`, else the scenario's plan duration).
fn law_plan(
    py: Python<'_>,
    prep: &Prepared,
    law: Py<PyAny>,
    period: Option<f64>,
    horizon: Option<f64>,
    shared: Arc<Shared>,
) -> PyResult<Plan> {
    let sc = &prep.scenario;
    let bad =
        |key: &str, m: String| input_error(py, format!("{key}: {m}"), None, None, Some(key.into()));
    if sc.sweep.is_some() {
        return Err(bad(
            "law",
            "the scenario has a [sweep] table, whose variants run its planner: run the law on variants made with `replace`".into(),
        ));
    }
    let external = match &sc.planner {
        PlannerConfig::External(p) => Some(p),
        _ => None,
    };
    let Some(period) = period.or(external.map(|p| p.period)) else {
        return Err(bad(
            "period",
            "a feedback law needs its sample period, s".into(),
        ));
    };
    let horizon = horizon
        .or(external.map(|p| p.horizon))
        .unwrap_or(prep.planned.duration);
    // Numbers as the CLI prints them: `1e300`, not 301 digits.
    use anholonomy::numfmt::readable;
    if !(period.is_finite() && period > 0.0) {
        return Err(bad(
            "period",
            format!("{} s: must be a finite time > 0", readable(period)),
        ));
    }
    if !(horizon.is_finite() && horizon > 0.0) {
        return Err(bad(
            "horizon",
            format!("{} s: must be a finite time > 0", readable(horizon)),
        ));
    }
    let steps = ((horizon + sc.sim.settle) / sc.sim.dt).ceil();
    if steps > prep.max_steps as f64 {
        return Err(bad(
            "horizon",
            format!(
                "{} s plus sim.settle at sim.dt = {} s is {} steps, over the budget of {} steps",
                readable(horizon),
                readable(sc.sim.dt),
                readable(steps),
                readable(prep.max_steps as f64)
            ),
        ));
    }
    let inputs = prep.model().input_names();
    let details = serde_json::json!({ "law": "python", "period_s": period });
    Ok(Plan::feedback(
        Vec::new(),
        Arc::new(PyLaw::new(law, inputs, shared)),
        period,
        horizon,
        details,
    ))
}

/// Run one scenario (a sweep runs its variants), optionally with a Python
/// feedback law in place of its planner. Returns the raw result dict.
#[pyfunction]
#[pyo3(signature = (scenario, logs=None, law=None, period=None, horizon=None, pose_rate=100.0))]
pub fn run<'py>(
    py: Python<'py>,
    scenario: &Scenario,
    logs: Option<PathBuf>,
    law: Option<Py<PyAny>>,
    period: Option<f64>,
    horizon: Option<f64>,
    pose_rate: f64,
) -> PyResult<Bound<'py, PyAny>> {
    check_pose_rate(py, pose_rate)?;
    check_logs(py, logs.as_deref(), &[&scenario.prep.scenario.name])?;
    let cancel = Cancel::new();
    let shared = Arc::new(Shared::new(cancel.clone()));
    let plan = match law {
        Some(law) => Some(law_plan(
            py,
            &scenario.prep,
            law,
            period,
            horizon,
            shared.clone(),
        )?),
        None => {
            if period.is_some() || horizon.is_some() {
                return Err(input_error(
                    py,
                    "period/horizon: only a run with `law=` takes them".into(),
                    None,
                    None,
                    Some(
                        if period.is_some() {
                            "period"
                        } else {
                            "horizon"
                        }
                        .into(),
                    ),
                ));
            }
            None
        }
    };
    let prep = &scenario.prep;
    let opts = options(logs, pose_rate, &cancel);
    let res = interruptible(py, &cancel, || match &plan {
        Some(plan) => run_with_plan_detailed(prep, plan, &opts).map(|f| Ran::Run(Box::new(f))),
        None => run_one(prep, &opts),
    })?;
    if let Some(e) = shared.take_error() {
        return Err(e);
    }
    let ran = res.map_err(|e| to_py(py, &e))?;
    let d = ran_dict(py, prep, plan.as_ref().unwrap_or(&prep.planned), &ran)?;
    if plan.is_some() {
        use std::sync::atomic::Ordering::Relaxed;
        d.set_item("planner", "python")?;
        d.set_item("law_calls", shared.calls.load(Relaxed))?;
        let timings = d.get_item("timings")?;
        if let Some(t) = timings {
            t.set_item("law", shared.nanos.load(Relaxed) as f64 * 1e-9)?;
        }
    }
    Ok(d.into_any())
}

/// Run several scenarios in parallel like the CLI (longest first on rayon's
/// pool; each run is single-threaded and deterministic), results in input
/// order. A failed scenario gives its exception in its place when
/// `return_exceptions`, else the first failure is raised after all ran.
#[pyfunction]
#[pyo3(signature = (scenarios, logs=None, pose_rate=100.0, return_exceptions=false))]
pub fn run_many<'py>(
    py: Python<'py>,
    scenarios: Vec<PyRef<'py, Scenario>>,
    logs: Option<PathBuf>,
    pose_rate: f64,
    return_exceptions: bool,
) -> PyResult<Bound<'py, PyList>> {
    check_pose_rate(py, pose_rate)?;
    let preps: Vec<Arc<Prepared>> = scenarios.iter().map(|s| s.prep.clone()).collect();
    let names: Vec<&str> = preps.iter().map(|p| p.scenario.name.as_str()).collect();
    if logs.is_some() {
        // Two scenarios of one call must not share a log directory.
        let mut seen = std::collections::HashMap::new();
        for p in &preps {
            let sc = &p.scenario;
            if let Some(other) = seen.insert(sc.name.to_lowercase(), sc.path.clone()) {
                let e = sc.error_at(
                    "name",
                    format!(
                        "`{}` is also the name of {}: both would write the same log directory",
                        sc.name,
                        other.display()
                    ),
                );
                return Err(to_py(py, &e));
            }
        }
    }
    check_logs(py, logs.as_deref(), &names)?;
    let cancel = Cancel::new();
    let opts = options(logs, pose_rate, &cancel);
    let ran = interruptible(py, &cancel, || {
        let mut order: Vec<usize> = (0..preps.len()).collect();
        order.sort_by_key(|&i| std::cmp::Reverse(anholonomy::suite::cost(&preps[i])));
        let mut done: Vec<(usize, Result<Ran, Error>)> = order
            .par_iter()
            .with_max_len(1)
            .map(|&i| (i, run_one(&preps[i], &opts)))
            .collect();
        done.sort_by_key(|(i, _)| *i);
        done
    })?;
    let out = PyList::empty(py);
    let mut first_err: Option<PyErr> = None;
    for (i, r) in ran {
        match r {
            Ok(r) => out.append(ran_dict(py, &preps[i], &preps[i].planned, &r)?)?,
            Err(e) => {
                let err = to_py(py, &e);
                if return_exceptions {
                    out.append(err.value(py))?;
                } else if first_err.is_none() {
                    first_err = Some(err);
                }
            }
        }
    }
    match first_err {
        Some(e) => Err(e),
        None => Ok(out),
    }
}

/// A trajectory's arrays: t (N,), q (N, n), u (N, m), label (N,).
fn traj_dict<'py>(
    py: Python<'py>,
    tr: &Trajectory,
    n: usize,
    m: usize,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let rows = tr.t.len();
    let flat = |v: &[anholonomy::model::State], w: usize| {
        let mut out = Vec::with_capacity(rows * w);
        for x in v {
            out.extend(x.iter().copied());
        }
        PyArray1::from_vec(py, out).reshape([v.len(), w])
    };
    d.set_item("t", PyArray1::from_slice(py, &tr.t))?;
    d.set_item("q", flat(&tr.q, n)?)?;
    d.set_item("u", flat(&tr.u, m)?)?;
    let labels: Vec<i64> = tr.label.iter().map(|&l| l as i64).collect();
    d.set_item("label", PyArray1::from_vec(py, labels))?;
    Ok(d)
}

fn outcome_items(d: &Bound<'_, PyDict>, o: &RunOutcome) -> PyResult<()> {
    let py = d.py();
    d.set_item("name", &o.name)?;
    d.set_item("planner", &o.planner)?;
    d.set_item("passed", o.passed)?;
    d.set_item("verdict", o.verdict.as_str())?;
    d.set_item("failures", &o.failures)?;
    let metrics = PyDict::new(py);
    for (k, v) in &o.metrics {
        metrics.set_item(k, *v)?;
    }
    d.set_item("metrics", metrics)?;
    d.set_item("steps", o.steps)?;
    let timings = serde_json::to_value(&o.timings).unwrap_or_default();
    d.set_item("timings", json_to_py(py, &timings)?)?;
    d.set_item(
        "log_dir",
        o.log_dir.as_ref().map(|p| p.display().to_string()),
    )?;
    Ok(())
}

fn ran_dict<'py>(
    py: Python<'py>,
    prep: &Prepared,
    plan: &Plan,
    ran: &Ran,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let model = prep.model();
    d.set_item("state_names", model.state_names().to_vec())?;
    d.set_item("input_names", model.input_names().to_vec())?;
    match ran {
        Ran::Sweep(o, table) => {
            d.set_item("kind", "sweep")?;
            outcome_items(&d, o)?;
            d.set_item("table", table)?;
            let summary = o
                .log_dir
                .as_ref()
                .and_then(|dir| std::fs::read_to_string(dir.join("sweep.json")).ok())
                .and_then(|s| serde_json::from_str::<serde_json::Value>(&s).ok());
            match summary {
                Some(v) => d.set_item("summary", json_to_py(py, &v)?)?,
                None => d.set_item("summary", py.None())?,
            }
        }
        Ran::Run(f) => {
            let (n, m) = (model.state_names().len(), model.input_names().len());
            d.set_item("kind", "run")?;
            outcome_items(&d, &f.outcome)?;
            d.set_item("summary", json_to_py(py, &f.summary)?)?;
            d.set_item("labels", &f.labels)?;
            d.set_item("ideal", traj_dict(py, &f.ideal, n, m)?)?;
            d.set_item("sim", traj_dict(py, &f.sim.traj, n, m)?)?;
            let channels = PyDict::new(py);
            for (name, v) in &f.sim.channels {
                channels.set_item(name, PyArray1::from_slice(py, v))?;
            }
            d.set_item("channels", channels)?;
            let series = PyDict::new(py);
            for s in &f.series {
                series.set_item(
                    &s.name,
                    (
                        PyArray1::from_slice(py, &s.t),
                        PyArray1::from_slice(py, &s.values),
                    ),
                )?;
            }
            d.set_item("series", series)?;
            let p = PyDict::new(py);
            p.set_item("duration", plan.duration)?;
            p.set_item("hold_period", plan.hold_period())?;
            let segs: Vec<(String, f64, f64)> = plan
                .segments
                .iter()
                .map(|s| (plan.label_name(s.label).to_string(), s.start, s.end))
                .collect();
            p.set_item("segments", segs)?;
            p.set_item("details", json_to_py(py, &plan.details)?)?;
            d.set_item("plan", p)?;
        }
    }
    Ok(d)
}
