//! The pipeline for one prepared scenario (see [`crate::validate`], which
//! already planned it): ideal run → physics replay → compare → thresholds →
//! logs (one unit, [`crate::log::unit`]).

use crate::cancel::Cancel;
use crate::compare::compare;
use crate::engine::{replay, ReplayError, ReplayObserver, ReplayOptions};
use crate::error::Error;
use crate::integrate::{simulate_until, IdealStop, Trajectory};
use crate::log::unit::LogUnit;
use crate::log::Keep;
use crate::model::{KinematicModel, State};
use crate::plan::{ControlLaw, Plan};
use crate::record::{RunRecord, Series, SimTrajectory};
use crate::robots::{EarlyAnalysis, SimFollower};
use crate::verdict::Verdict;
use serde::Serialize;
use serde_json::json;
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::Instant;

pub use crate::compare::metric_spec;
pub use crate::validate::Prepared;

/// Where logs go, whether to show progress, and how to stop a run.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// Root directory for `<scenario>/run.*`; `None` writes no logs.
    pub log_root: Option<PathBuf>,
    /// Where progress goes (nothing by default).
    pub progress: crate::progress::Progress,
    /// Link poses in the logs per second of simulated time (at least this
    /// many, see [`pose_stride`]); 0 logs them at every sample.
    pub pose_rate: f64,
    /// Set from another thread to stop the run (the ideal run and the
    /// replay check it every step; the run then fails with
    /// [`crate::cancel::CANCELLED`]). The CLI passes the default token.
    pub cancel: Cancel,
    /// Which files the log directory keeps.
    pub keep: Keep,
    /// Sweeps: step groups of variants together in shared engine worlds
    /// ([`crate::engine::batch`]; the same results); false runs each
    /// variant in a world of its own.
    pub batch: bool,
}

impl Default for RunOptions {
    /// No logs, no progress, the default pose rate, batched sweeps.
    fn default() -> Self {
        RunOptions {
            log_root: None,
            progress: Default::default(),
            pose_rate: DEFAULT_POSE_RATE,
            cancel: Cancel::default(),
            keep: Keep::All,
            batch: true,
        }
    }
}

/// Default of [`RunOptions::pose_rate`], Hz: more than a viewer plays back,
/// a fifth of the samples of a 2 ms run.
pub const DEFAULT_POSE_RATE: f64 = 100.0;

/// Physics samples per logged link-pose row for `rate` Hz at step `dt`: the
/// largest whole stride that still gives at least `rate` rows per second;
/// 1 (every sample) for rate 0 or a rate above the sample rate.
pub fn pose_stride(rate: f64, dt: f64) -> usize {
    if rate > 0.0 && dt > 0.0 {
        // The small epsilon keeps 1/(100·0.002) = 5 from rounding down to 4.
        ((1.0 / (rate * dt)) * (1.0 + 1e-9)).floor().max(1.0) as usize
    } else {
        1
    }
}

/// Wall time of each stage, s.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Timings {
    /// Planner.
    pub plan: f64,
    /// Ideal RK4 run, and the part of the analysis that needs it alone
    /// (computed beside the physics replay).
    pub ideal: f64,
    /// Physics replay.
    pub physics: f64,
    /// Comparison, metrics and the rest of the system's analysis (e.g. V
    /// along the physics run), once both runs exist.
    pub analysis: f64,
    /// Log writing.
    pub logs: f64,
    /// Everything.
    pub total: f64,
    /// CPU time of the physics replay (its thread's, so a loaded machine
    /// does not inflate it as it does the wall time), s; absent where the
    /// platform does not report it ([`thread_cpu_s`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub physics_cpu: Option<f64>,
}

/// CPU time the calling thread has used so far, s: `CLOCK_THREAD_CPUTIME_ID`
/// (what Python's `time.thread_time` reads); `None` where it is missing.
///
/// Not `/proc/thread-self/schedstat`: the kernel brings a running thread's
/// sum there up to date only at scheduler ticks, so a run of a few
/// milliseconds read 0 or a whole tick (the work-precision study measured a
/// 0.0 s replay).
#[cfg(unix)]
pub fn thread_cpu_s() -> Option<f64> {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid, writable timespec for the duration of the call.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    (rc == 0).then_some(ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9)
}

/// CPU time the calling thread has used so far: not measured off Unix.
#[cfg(not(unix))]
pub fn thread_cpu_s() -> Option<f64> {
    None
}

/// Result of one scenario run.
#[derive(Debug, Clone, Serialize)]
pub struct RunOutcome {
    /// Scenario name.
    pub name: String,
    /// Planner kind.
    pub planner: String,
    /// All thresholds met.
    pub passed: bool,
    /// PASS, FAIL, XFAIL or XPASS: `passed` against the scenario's `expect`.
    pub verdict: Verdict,
    /// `expect = "fails"`: the scenario's reason.
    pub expect_reason: Option<String>,
    /// Whether the `tracking_*` metrics mean anything (see [`tracking_meaningful`]).
    pub tracking_meaningful: bool,
    /// Broken thresholds, human-readable.
    pub failures: Vec<String>,
    /// Metric name → value.
    pub metrics: Vec<(String, f64)>,
    /// Physics steps.
    pub steps: usize,
    /// Stage timings.
    pub timings: Timings,
    /// Log directory, when logs were written.
    pub log_dir: Option<PathBuf>,
    /// What the result column adds to the verdict: each `[margins]` gate
    /// that held (`command_latency holds at 0.02 s`).
    pub notes: Vec<String>,
    /// What the planner says about its plan when it matters to the
    /// verdict (the plan's `details.note`: e.g. that no sequence
    /// converged, and what each candidate did), shown after the verdict.
    pub plan_note: Option<String>,
}

impl RunOutcome {
    /// A metric by name.
    pub fn metric(&self, name: &str) -> Option<f64> {
        crate::metric::find(&self.metrics, name)
    }

    /// Whether metric `name` means anything for this run: the results table
    /// shows n/a, and baselines neither write nor compare, the ones that do not.
    pub fn meaningful(&self, name: &str) -> bool {
        self.tracking_meaningful || !crate::robots::compares_runs(name)
    }
}

/// Why the `tracking_*` metrics of a run mean nothing, when they do not.
pub const TRACKING_NOT_MEANINGFUL: &str = "not meaningful: a feedback policy closes the loop on each run's own state, so the runs reach the goal at different times and differ sample by sample whatever the physics";

/// Whether the `tracking_*` metrics (simulated − ideal at equal times) mean
/// anything: only when both runs execute the same commands, i.e. the system
/// says its plan's commands depend on time alone ([`crate::robots::System::same_commands`]).
pub fn tracking_meaningful(prep: &Prepared) -> bool {
    prep.system.same_commands(&prep.planned)
}

/// State in display units (angles in degrees) as a JSON object.
fn display_state(model: &dyn KinematicModel, q: &State) -> serde_json::Value {
    let ang = model.angular_states();
    let mut m = serde_json::Map::new();
    for (i, name) in model.state_names().iter().enumerate() {
        if ang.contains(&i) {
            m.insert(format!("{name}_deg"), json!(q[i].to_degrees()));
        } else {
            m.insert(name.to_string(), json!(q[i]));
        }
    }
    serde_json::Value::Object(m)
}

/// Everything one run produced, for library callers (the Python package):
/// the outcome, both runs, the system's series and the `summary.json` object.
#[derive(Debug, Clone)]
pub struct Finished {
    /// Metrics, thresholds, timings, log directory.
    pub outcome: RunOutcome,
    /// The ideal kinematic run.
    pub ideal: Trajectory,
    /// The physics replay (with its channels).
    pub sim: SimTrajectory,
    /// Series the system computed from both runs (e.g. `V/ideal`).
    pub series: Vec<Series>,
    /// The same object as `summary.json` (also when no logs were written).
    pub summary: serde_json::Value,
    /// The plan's label names (with those a feedback law named while running).
    pub labels: Vec<String>,
}

/// Run one scenario end to end.
pub fn run(prep: &Prepared, opts: &RunOptions) -> Result<RunOutcome, Error> {
    // Planned by the validation pass.
    run_plan(prep, &prep.planned, prep.plan_wall_s, opts, false).map(|d| d.outcome)
}

/// [`run`], keeping the trajectories, series and summary.
pub fn run_detailed(prep: &Prepared, opts: &RunOptions) -> Result<Finished, Error> {
    run_plan(prep, &prep.planned, prep.plan_wall_s, opts, true)
}

/// Run a prepared scenario with a plan the caller supplies instead of the
/// one its planner made: the same ideal run, physics replay, comparison,
/// thresholds and logs as [`run`].
///
/// This is how a feedback law from outside the scenario file runs (the
/// Python package's `run(scenario, law=callable, period=...)`): wrap it in a
/// [`crate::plan::PolicyFactory`] whose controllers answer
/// [`crate::plan::Controller::command`] (and report failures through
/// [`crate::plan::Controller::fault`], which ends the run with
/// [`Error::Law`], exit 3), then
///
/// ```ignore
/// let plan = Plan::feedback(Vec::new(), factory, period, horizon, json!({}));
/// let outcome = runner::run_with_plan(&prep, &plan, &opts)?;
/// ```
///
/// The law is sampled exactly as an external law of `[planner] kind =
/// "external"` is: at t = j · period on the `sim.dt` grid (the first at 0),
/// held in between, one controller per run (ideal first, then physics), the
/// run ending at `horizon` or `settle` seconds after a command with `done`.
/// The controller sees the same `t` and state values an external process is
/// sent (the JSON numbers round-trip exactly), so a deterministic law gives
/// bit-identical results in process and through the protocol; wrap it in
/// [`crate::plan::OncePerSample`] as the external law is, so that it is
/// asked once per sample (the runs ask twice at t = 0) like the process. A factory
/// that names labels while running returns them from
/// [`crate::plan::PolicyFactory::labels`] (see [`crate::plan::LabelTable`]).
///
/// Bad plans are bad input (exit 2) naming the scenario: a hold period that
/// is not a positive number, a non-finite or negative duration, or one over
/// the scenario's step budget.
pub fn run_with_plan(prep: &Prepared, plan: &Plan, opts: &RunOptions) -> Result<RunOutcome, Error> {
    check_plan(prep, plan)?;
    run_plan(prep, plan, 0.0, opts, false).map(|d| d.outcome)
}

/// [`run_with_plan`], keeping the trajectories, series and summary.
pub fn run_with_plan_detailed(
    prep: &Prepared,
    plan: &Plan,
    opts: &RunOptions,
) -> Result<Finished, Error> {
    check_plan(prep, plan)?;
    run_plan(prep, plan, 0.0, opts, true)
}

/// A caller's plan against the scenario: what [`run_with_plan`] refuses.
fn check_plan(prep: &Prepared, plan: &Plan) -> Result<(), Error> {
    let sc = &prep.scenario;
    if let ControlLaw::Feedback { period, .. } = &plan.law {
        if !(period.is_finite() && *period > 0.0) {
            return Err(Error::input(
                &sc.path,
                format!("feedback law: period must be a number > 0 s, got {period}"),
            ));
        }
    }
    if !(plan.duration.is_finite() && plan.duration >= 0.0) {
        return Err(Error::input(
            &sc.path,
            format!(
                "plan: duration must be a number >= 0 s, got {}",
                plan.duration
            ),
        ));
    }
    let steps = crate::integrate::step_count(plan.duration + sc.sim.settle, sc.sim.dt) as u64;
    if steps > prep.max_steps {
        return Err(Error::input(
            &sc.path,
            format!(
                "plan: {} s and settling at sim.dt = {} s is {steps} steps, over the budget of {} steps",
                plan.duration, sc.sim.dt, prep.max_steps
            ),
        ));
    }
    Ok(())
}

/// The pipeline; the summary is built when logs are written or `summarize`.
fn run_plan(
    prep: &Prepared,
    plan: &Plan,
    plan_wall_s: f64,
    opts: &RunOptions,
    summarize: bool,
) -> Result<Finished, Error> {
    let started = Instant::now();
    let sc = &prep.scenario;
    let mut timings = Timings {
        plan: plan_wall_s,
        ..Default::default()
    };
    let (start, goal) = prep.start_goal();
    let ideal_part = || {
        let t0 = Instant::now();
        let tr = ideal_run(prep, plan, &opts.cancel)?;
        let of_ideal = prep.system.analysis_of_ideal(&goal, &tr);
        Ok::<_, Error>((tr, of_ideal, t0.elapsed().as_secs_f64()))
    };
    // `feed`: where every recorded physics sample goes, for a follower.
    let physics_part = |feed: Option<mpsc::Sender<(usize, f64, Vec<f64>)>>| {
        let t0 = Instant::now();
        let cpu0 = thread_cpu_s();
        let mut sys = prep.physics()?;
        let mut bar = crate::progress::RunMeter::start(&*opts.progress, &sc.name);
        let mut fed = 0;
        let mut send = |traj: &Trajectory| {
            if let Some(tx) = &feed {
                for k in fed..traj.t.len() {
                    // A follower that stopped needs nothing more.
                    let _ = tx.send((k, traj.t[k], traj.q[k].as_slice().to_vec()));
                }
                fed = traj.t.len();
            }
        };
        // The observer borrows `send` and the bar for the replay only.
        let sim = {
            let mut observer = Observer {
                after_step: |out: &SimTrajectory| send(&out.traj),
                bar: &mut bar,
                cancel: &opts.cancel,
            };
            replay(
                sys.as_mut(),
                plan,
                &replay_options(prep, opts),
                &mut observer,
            )
        };
        drop(bar);
        let sim = sim.map_err(|e| replay_error(prep, e))?;
        send(&sim.traj);
        let cpu = thread_cpu_s().zip(cpu0).map(|(b, a)| b - a);
        Ok::<_, Error>((sim, t0.elapsed().as_secs_f64(), cpu))
    };
    // The two runs are independent (a feedback law starts a controller of
    // its own in each), so a law of the harness runs them side by side,
    // the ideal run then following the physics replay for the analysis. A
    // law outside it (a process, a Python callable) runs them one after the
    // other, as its author may expect: it may share state between its
    // controllers, and it names labels in the order the runs meet them.
    let concurrent = match &plan.law {
        ControlLaw::Feedback { factory, .. } => factory.concurrent(),
        _ => true,
    };
    let ((ideal, early, ideal_s), (sim, physics_s, physics_cpu)) = if concurrent {
        let follower = prep.system.sim_follower(&start, &goal, sc.sim.dt);
        let following = follower.is_some();
        let (tx, rx) = mpsc::channel();
        // A thread of its own, not a rayon job: the follower waits for the
        // physics, which a busy pool might otherwise run after it.
        let (ideal, physics) = std::thread::scope(|s| {
            let beside = s.spawn(|| {
                let ideal = ideal_part();
                (ideal, follower.map(|f| follow(f, rx)))
            });
            let physics = physics_part(following.then_some(tx));
            let (ideal, followed) = beside
                .join()
                .unwrap_or_else(|p| std::panic::resume_unwind(p));
            let ideal = ideal.map(|(tr, early, s)| match followed {
                Some(f) => (tr, early.and(f), s),
                None => (tr, early, s),
            });
            (ideal, physics)
        });
        (ideal?, physics?)
    } else {
        let ideal = ideal_part()?;
        (ideal, physics_part(None)?)
    };
    timings.ideal = ideal_s;
    timings.physics = physics_s;
    timings.physics_cpu = physics_cpu;
    let runs = Runs {
        ideal,
        early: Some(early),
        sim,
        timings,
        started,
    };
    finish(prep, plan, opts, summarize, runs)
}

/// A follower fed every physics sample until the replay ends (and drops
/// its sender).
fn follow(
    mut f: Box<dyn SimFollower>,
    rx: mpsc::Receiver<(usize, f64, Vec<f64>)>,
) -> EarlyAnalysis {
    for (k, t, q) in rx {
        f.sample(k, t, &q);
    }
    f.finish()
}

/// The ideal kinematic run of `plan` (stopped by `cancel`).
pub fn ideal_run(prep: &Prepared, plan: &Plan, cancel: &Cancel) -> Result<Trajectory, Error> {
    let sc = &prep.scenario;
    let (start, _) = prep.start_goal();
    simulate_until(prep.model(), plan, &start, sc.sim.dt, cancel).map_err(|e| match e {
        IdealStop::Fault(message) => Error::Law {
            path: sc.path.clone(),
            run: "ideal",
            message,
        },
        IdealStop::Cancelled => cancelled(prep),
        IdealStop::NonFinite(message) => Error::Physics {
            path: sc.path.clone(),
            message,
        },
    })
}

/// The runner's view of a replay: its progress, the follower fed each
/// new sample, and the run's cancel token.
struct Observer<'a, 'b, F: FnMut(&SimTrajectory)> {
    after_step: F,
    bar: &'a mut crate::progress::RunMeter<'b>,
    cancel: &'a Cancel,
}

impl<F: FnMut(&SimTrajectory)> ReplayObserver for Observer<'_, '_, F> {
    fn progress(&mut self, fraction: f64) {
        self.bar.set(fraction);
    }
    fn after_step(&mut self, so_far: &SimTrajectory) -> bool {
        (self.after_step)(so_far);
        false
    }
    fn cancelled(&self) -> bool {
        self.cancel.is_cancelled()
    }
}

/// How [`run`] replays the plan on the physics.
pub(crate) fn replay_options(prep: &Prepared, opts: &RunOptions) -> ReplayOptions {
    let sc = &prep.scenario;
    ReplayOptions {
        dt: sc.sim.dt,
        settle: sc.sim.settle,
        // Only the 3D logs read link poses, at their own rate.
        link_pose_every: (opts.log_root.is_some() && opts.keep == Keep::All)
            .then(|| pose_stride(opts.pose_rate, sc.sim.dt)),
        perturbation: sc.sim.perturb,
    }
}

/// A physics replay's failure as the run's error.
pub(crate) fn replay_error(prep: &Prepared, e: ReplayError) -> Error {
    let sc = &prep.scenario;
    match e {
        ReplayError::Law(message) => Error::Law {
            path: sc.path.clone(),
            run: "physics",
            message,
        },
        ReplayError::Diverged(message) => Error::Physics {
            path: sc.path.clone(),
            message,
        },
        ReplayError::Cancelled => cancelled(prep),
    }
}

fn cancelled(prep: &Prepared) -> Error {
    Error::Physics {
        path: prep.scenario.path.clone(),
        message: crate::cancel::CANCELLED.into(),
    }
}

/// Both runs of one scenario, before comparison: what [`finish`] needs.
pub struct Runs {
    /// The ideal kinematic run.
    pub ideal: Trajectory,
    /// What the system's analysis computed beside the physics replay
    /// ([`crate::robots::System::analysis_of_ideal`], a follower's result),
    /// when the runs were side by side (else `finish` computes the ideal
    /// part and the analysis the rest).
    pub early: Option<EarlyAnalysis>,
    /// The physics replay.
    pub sim: SimTrajectory,
    /// The plan, ideal and physics stages' timings.
    pub timings: Timings,
    /// When the run started (for [`Timings::total`]).
    pub started: Instant,
}

/// The rest of the pipeline once both runs exist (a batched sweep replays
/// its variants together, then finishes each): comparison, metrics,
/// thresholds and logs; the summary is built when logs are written or
/// `summarize`.
pub fn finish(
    prep: &Prepared,
    plan: &Plan,
    opts: &RunOptions,
    summarize: bool,
    runs: Runs,
) -> Result<Finished, Error> {
    let sc = &prep.scenario;
    let model = prep.model();
    let (_, goal) = prep.start_goal();
    let Runs {
        ideal,
        early,
        mut sim,
        mut timings,
        started: t_all,
    } = runs;
    let plan_wall_s = timings.plan;
    crate::engine::perturb::reality::add_drive_channels(&mut sim, model.input_names());
    // Labels an external law named while running, for the logs.
    let plan = &*plan.with_run_labels();

    let t0 = Instant::now();
    let spec = metric_spec(model);
    let cmp = compare(&ideal, &sim.traj, sc.sim.dt, spec.angular, &spec.positions);
    let mut metrics = spec.compute(&goal, ideal.last(), sim.traj.last(), &cmp);
    let early = early.unwrap_or_else(|| prep.system.analysis_of_ideal(&goal, &ideal));
    let (extra, series) = prep.system.analysis_with(&goal, &ideal, early, &sim, &cmp);
    metrics.extend(extra);
    if let (Some(track), Some(idx)) = (
        &prep.reference,
        crate::recording::align::PoseIndex::of(model),
    ) {
        metrics.extend(crate::recording::metrics::compute(
            track, &ideal, &sim.traj, &goal, &idx,
        ));
    }
    let failures = crate::gate::breaches(&sc.thresholds, &sc.minimums, &metrics)
        .iter()
        .map(ToString::to_string)
        .collect::<Vec<_>>();
    timings.analysis = t0.elapsed().as_secs_f64();
    let t0 = Instant::now();
    let mut outcome = RunOutcome {
        name: sc.name.clone(),
        planner: sc.planner.kind().into(),
        passed: failures.is_empty(),
        verdict: Verdict::of(failures.is_empty(), sc.expect_fails.is_some()),
        expect_reason: sc.expect_fails.clone(),
        // The plan run, which may be a caller's ([`run_with_plan`]).
        tracking_meaningful: prep.system.same_commands(plan),
        failures,
        metrics,
        steps: sim.steps,
        timings,
        log_dir: None,
        notes: Vec::new(),
        plan_note: plan.details["note"].as_str().map(String::from),
    };
    let log_error = |message: String| Error::Log {
        path: sc.path.clone(),
        message,
    };
    let unit = match &opts.log_root {
        Some(root) => {
            let unit = LogUnit::begin(root, &sc.name).map_err(|e| log_error(e.to_string()))?;
            let run = RunData {
                plan,
                ideal: &ideal,
                sim: &sim,
                cmp: &cmp,
                series: &series,
            };
            write_logs(prep, &run, &outcome, unit.dir(), &goal, opts.keep)
                .map_err(|e| log_error(e.to_string()))?;
            Some(unit)
        }
        None => None,
    };
    outcome.timings.logs = t0.elapsed().as_secs_f64();
    // Planning happened during validation: count it in.
    outcome.timings.total = t_all.elapsed().as_secs_f64() + plan_wall_s;
    let mut summary = if summarize || unit.is_some() {
        summary_json(prep, plan, &ideal, &sim, &outcome)
    } else {
        serde_json::Value::default()
    };
    if let Some(unit) = unit {
        // The summary carries the final timings, so it is written last; then
        // the three files replace the previous run's as one unit.
        summary["logs_kept"] = json!(opts.keep.as_str());
        crate::log::atomic::write_file(&unit.dir().join("summary.json"), |w| {
            serde_json::to_writer_pretty(w, &summary).map_err(std::io::Error::other)
        })
        .map_err(|e| log_error(e.to_string()))?;
        outcome.log_dir = Some(unit.commit().map_err(|e| log_error(e.to_string()))?);
    }
    Ok(Finished {
        outcome,
        ideal,
        sim,
        series,
        summary,
        labels: plan.labels.clone(),
    })
}

/// What one run produced, for the log writers.
struct RunData<'a> {
    plan: &'a Plan,
    ideal: &'a Trajectory,
    sim: &'a SimTrajectory,
    cmp: &'a crate::record::Comparison,
    series: &'a [Series],
}

fn write_logs(
    prep: &Prepared,
    run: &RunData<'_>,
    outcome: &RunOutcome,
    dir: &Path,
    goal: &State,
    keep: Keep,
) -> Result<(), crate::log::LogError> {
    if keep == Keep::Summary {
        return Ok(());
    }
    let RunData {
        plan,
        ideal,
        sim,
        cmp,
        series,
    } = *run;
    let model = prep.model();
    let goal_v: Vec<f64> = goal.iter().copied().collect();
    let (start, _) = prep.start_goal();
    let links = prep.system.links(&prep.robot, &start);
    let overlays = prep.system.overlays(&start, goal);
    let command = plan.command_info();
    let rec = RunRecord {
        scenario: &prep.scenario.name,
        state_names: model.state_names(),
        input_names: model.input_names(),
        angular: model.angular_states(),
        robot_positions: model.robot_positions(),
        goal: &goal_v,
        goal_heading: prep.system.goal_heading(goal),
        overlays: &overlays,
        series,
        labels: &plan.labels,
        ideal,
        sim,
        comparison: cmp,
        links: &links,
        metrics: &outcome.metrics,
        command: &command,
        tracking_meaningful: outcome.tracking_meaningful,
        real: prep.reference.as_deref(),
    };
    // The writers are independent (each file from the same record): on two
    // cores a single run's logs take the longer writer's time, not the sum.
    if keep == Keep::Report {
        return crate::log::series::write(&dir.join("series.json"), &rec);
    }
    let (mcap, rest) = rayon::join(
        || crate::log::mcap::write_mcap(&dir.join("run.mcap"), &rec),
        || {
            crate::log::series::write(&dir.join("series.json"), &rec)?;
            crate::log::rerun::write_rrd(&dir.join("run.rrd"), &rec)
        },
    );
    mcap.and(rest)
}

/// Segment (plan label) of a trajectory's last sample.
fn final_segment(plan: &Plan, tr: &Trajectory) -> Option<String> {
    tr.label
        .last()
        .map(|&l| crate::log::segment_name(&plan.labels, l).into_owned())
}

fn summary_json(
    prep: &Prepared,
    plan: &Plan,
    ideal: &Trajectory,
    sim: &SimTrajectory,
    o: &RunOutcome,
) -> serde_json::Value {
    let sc = &prep.scenario;
    let model = prep.model();
    let metric = |n: &str| o.metric(n);
    let (start, goal) = prep.start_goal();
    json!({
        "scenario": sc.name,
        "file": sc.path,
        "description": sc.description,
        "passed": o.passed,
        "verdict": o.verdict,
        "expect": {
            "fails": sc.expect_fails.is_some(),
            "reason": sc.expect_fails,
        },
        "failures": o.failures,
        "thresholds": sc.thresholds,
        "minimums": sc.minimums,
        "model": model_json(prep),
        "planner": sc.planner,
        "plan": {
            "duration_s": plan.duration,
            "labels": plan.labels,
            "segments": plan.segments,
            "details": plan.details,
        },
        "paper": prep.system.paper(&start, &goal, plan),
        "sim_settings": sc.sim,
        // What reality added to the physics replay (empty: nothing).
        "perturbation": sc.sim.perturb.active_json(),
        "goal": display_state(model, &State::from_vec(sc.goal.clone())),
        "ideal": {
            "final_state": display_state(model, ideal.last()),
            "goal_error_position": metric("ideal_goal_position"),
            "end_time_s": ideal.t.last(),
            "final_segment": final_segment(plan, ideal),
        },
        "sim": {
            "final_state": display_state(model, sim.traj.last()),
            "goal_error_position": metric("sim_goal_position"),
            "end_time_s": sim.traj.t.last(),
            // Why a run ended early shows here: a feedback law's stop label
            // (e.g. `collision`, `overstrained`) is the last sample's segment.
            "final_segment": final_segment(plan, &sim.traj),
        },
        "metrics": o.metrics.iter().cloned().collect::<std::collections::BTreeMap<_, _>>(),
        // Each metric's unit (empty: none), from its row.
        "units": o
            .metrics
            .iter()
            .map(|(n, _)| (n.clone(), crate::robots::metric_unit(n, &crate::compare::metric_spec(model))))
            .collect::<std::collections::BTreeMap<_, _>>(),
        // Metric families whose numbers mean nothing for this run, and why.
        "not_meaningful": if o.tracking_meaningful {
            json!({})
        } else {
            json!({ "tracking": TRACKING_NOT_MEANINGFUL })
        },
        "sim_steps": o.steps,
        // Everything that depends on the clock, and only that, sits here: the
        // rest of the summary is identical across runs.
        "wall_time_s": timing_json(o),
    })
}

/// The `model` object: the scenario's `[model]` table and what the physics
/// read from the URDF (`read_from_urdf`).
fn model_json(prep: &Prepared) -> serde_json::Value {
    let mut m = serde_json::to_value(&prep.scenario.model).unwrap_or_default();
    if let Some(o) = m.as_object_mut() {
        o.insert(
            "read_from_urdf".into(),
            serde_json::to_value(&prep.reading).unwrap_or_default(),
        );
    }
    m
}

/// The `wall_time_s` object: stage timings, s, and the physics step rate.
pub(crate) fn timing_json(o: &RunOutcome) -> serde_json::Value {
    let mut t = serde_json::to_value(&o.timings).unwrap_or_default();
    t["sim_steps_per_second"] = json!(o.steps as f64 / o.timings.physics.max(1e-9));
    t
}

#[cfg(test)]
mod pose_stride_tests {
    use super::pose_stride;

    #[test]
    fn stride_gives_at_least_the_rate() {
        assert_eq!(pose_stride(100.0, 0.002), 5);
        assert_eq!(pose_stride(100.0, 0.001), 10);
        // 2.5 samples per pose: every 2nd (125 Hz), never every 3rd (83 Hz).
        assert_eq!(pose_stride(100.0, 0.004), 2);
        assert_eq!(pose_stride(100.0, 0.02), 1);
        assert_eq!(pose_stride(0.0, 0.002), 1);
        for (rate, dt) in [(100.0, 3e-3), (60.0, 1e-3), (7.0, 0.013), (1e3, 1e-4)] {
            let k = pose_stride(rate, dt) as f64;
            assert!(1.0 / (k * dt) >= rate && 1.0 / ((k + 1.0) * dt) < rate);
        }
    }
}
