//! The pipeline for one prepared scenario (see [`crate::validate`], which
//! already planned it): ideal run → physics replay → compare → thresholds →
//! logs (one unit, [`crate::log::unit`]).

use crate::compare::compare;
use crate::error::Error;
use crate::integrate::{simulate, Trajectory};
use crate::log::unit::LogUnit;
use crate::log::Keep;
use crate::model::{KinematicModel, State};
use crate::physics::{replay_with, ReplayOptions};
use crate::plan::Plan;
use crate::record::{RunRecord, SimTrajectory};
use crate::verdict::Verdict;
use serde::Serialize;
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::Instant;

pub use crate::compare::metric_spec;
pub use crate::validate::Prepared;

/// Where logs go, and whether to show progress.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// Root directory for `<scenario>/run.*`; `None` writes no logs.
    pub log_root: Option<PathBuf>,
    /// Show a progress bar when a run takes longer than a second.
    pub progress: bool,
    /// Link poses in the logs per second of simulated time (at least this
    /// many, see [`pose_stride`]); 0 logs them at every sample.
    pub pose_rate: f64,
    /// Which files the log directory keeps.
    pub keep: Keep,
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
    /// Ideal RK4 run.
    pub ideal: f64,
    /// Physics replay.
    pub physics: f64,
    /// Comparison, metrics and the system's analysis (e.g. V along both runs).
    pub analysis: f64,
    /// Log writing.
    pub logs: f64,
    /// Everything.
    pub total: f64,
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
}

impl RunOutcome {
    /// A metric by name.
    pub fn metric(&self, name: &str) -> Option<f64> {
        self.metrics
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| *v)
    }
}

/// Why the `tracking_*` metrics of a run mean nothing, when they do not.
pub const TRACKING_NOT_MEANINGFUL: &str = "not meaningful: a feedback policy closes the loop on each run's own state, so the runs reach the goal at different times and differ sample by sample whatever the physics";

/// Whether the `tracking_*` metrics (simulated − ideal at equal times) mean
/// anything: only when both runs execute the same commands, i.e. the system
/// says its plan's commands depend on time alone ([`crate::systems::System::same_commands`]).
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

/// Run one scenario end to end.
pub fn run(prep: &Prepared, opts: &RunOptions) -> Result<RunOutcome, Error> {
    let t_all = Instant::now();
    let sc = &prep.scenario;
    let model = prep.model();
    let (start, goal) = prep.start_goal();
    let mut timings = Timings::default();

    // Planned by the validation pass.
    let plan = &prep.planned;
    timings.plan = prep.plan_wall_s;

    let t0 = Instant::now();
    let ideal = simulate(model, plan, &start, sc.sim.dt);
    timings.ideal = t0.elapsed().as_secs_f64();

    let t0 = Instant::now();
    let mut sys = prep.physics()?;
    let bar = crate::progress::Delayed::new(&sc.name, opts.progress);
    let replay_opts = ReplayOptions {
        dt: sc.sim.dt,
        settle: sc.sim.settle,
        // Only the 3D logs read link poses, at their own rate.
        link_pose_every: (opts.log_root.is_some() && opts.keep == Keep::All)
            .then(|| pose_stride(opts.pose_rate, sc.sim.dt)),
    };
    let sim =
        replay_with(sys.as_mut(), plan, &replay_opts, &mut |f| bar.set(f)).map_err(|message| {
            Error::Physics {
                path: sc.path.clone(),
                message,
            }
        })?;
    bar.finish();
    timings.physics = t0.elapsed().as_secs_f64();

    let t0 = Instant::now();
    let spec = metric_spec(model);
    let cmp = compare(&ideal, &sim.traj, sc.sim.dt, spec.angular, &spec.positions);
    let mut metrics = spec.compute(&goal, ideal.last(), sim.traj.last(), &cmp);
    let (extra, series) = prep.system.analysis(&goal, &ideal, &sim, &cmp);
    metrics.extend(extra);
    let value = |k: &str| {
        metrics
            .iter()
            .find(|(n, _)| n == k)
            .map(|(_, v)| *v)
            .unwrap_or(f64::NAN)
    };
    let mut failures = Vec::new();
    for (k, limit) in &sc.thresholds {
        let v = value(k);
        if v.is_nan() || v > *limit {
            let (v, limit) = crate::numfmt::breach(v, *limit);
            failures.push(format!("{k} = {v} > {limit}"));
        }
    }
    for (k, floor) in &sc.minimums {
        let v = value(k);
        if v.is_nan() || v < *floor {
            let (v, floor) = crate::numfmt::breach(v, *floor);
            failures.push(format!("{k} = {v} < {floor}"));
        }
    }
    timings.analysis = t0.elapsed().as_secs_f64();
    let t0 = Instant::now();
    let mut outcome = RunOutcome {
        name: sc.name.clone(),
        planner: sc.planner.kind().into(),
        passed: failures.is_empty(),
        verdict: Verdict::of(failures.is_empty(), sc.expect_fails.is_some()),
        expect_reason: sc.expect_fails.clone(),
        tracking_meaningful: tracking_meaningful(prep),
        failures,
        metrics,
        steps: sim.steps,
        timings,
        log_dir: None,
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
            write_logs(prep, &run, &outcome, unit.dir(), &goal, opts.keep).map_err(log_error)?;
            Some(unit)
        }
        None => None,
    };
    outcome.timings.logs = t0.elapsed().as_secs_f64();
    // Planning happened during validation: count it in.
    outcome.timings.total = t_all.elapsed().as_secs_f64() + prep.plan_wall_s;
    if let Some(unit) = unit {
        // The summary carries the final timings, so it is written last; then
        // the three files replace the previous run's as one unit.
        let mut summary = summary_json(prep, plan, &ideal, &sim, &outcome);
        summary["logs_kept"] = json!(opts.keep.as_str());
        crate::log::atomic::write_atomic(&unit.dir().join("summary.json"), |w| {
            serde_json::to_writer_pretty(w, &summary).map_err(std::io::Error::other)
        })
        .map_err(log_error)?;
        outcome.log_dir = Some(unit.commit().map_err(|e| log_error(e.to_string()))?);
    }
    Ok(outcome)
}

/// What one run produced, for the log writers.
struct RunData<'a> {
    plan: &'a Plan,
    ideal: &'a Trajectory,
    sim: &'a SimTrajectory,
    cmp: &'a crate::record::Comparison,
    series: &'a [crate::record::Series],
}

fn write_logs(
    prep: &Prepared,
    run: &RunData<'_>,
    outcome: &RunOutcome,
    dir: &Path,
    goal: &State,
    keep: Keep,
) -> Result<(), String> {
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
        position: model.position_states(),
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
    };
    // The writers are independent (each file from the same record): on two
    // cores a single run's logs take the longer writer's time, not the sum.
    if keep == Keep::Report {
        return crate::report::data::write(&dir.join("series.json"), &rec);
    }
    let (mcap, rest) = rayon::join(
        || crate::log::mcap::write_mcap(&dir.join("run.mcap"), &rec).map_err(|e| e.to_string()),
        || {
            crate::report::data::write(&dir.join("series.json"), &rec)?;
            crate::log::rerun::write_rrd(&dir.join("run.rrd"), &rec).map_err(|e| e.to_string())
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
        "model": sc.model,
        "planner": sc.planner,
        "plan": {
            "duration_s": plan.duration,
            "labels": plan.labels,
            "segments": plan.segments,
            "details": plan.details,
        },
        "paper": prep.system.paper(&start, &goal, plan),
        "sim_settings": sc.sim,
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

/// The `wall_time_s` object: stage timings, s, and the physics step rate.
pub fn timing_json(o: &RunOutcome) -> serde_json::Value {
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
