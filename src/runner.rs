//! The pipeline for one scenario: validate → plan → ideal run → physics
//! replay → compare → thresholds → logs.

use crate::compare::{compare, MetricSpec};
use crate::error::Error;
use crate::integrate::{simulate, Trajectory};
use crate::model::{KinematicModel, State};
use crate::physics::{replay_with, urdf, PhysicsSystem, ReplayOptions};
use crate::plan::{Limits, Plan};
use crate::record::{RunRecord, SimTrajectory};
use crate::scenario::Scenario;
use crate::systems::{self, System};
use serde::Serialize;
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// A scenario with its model and URDF loaded and its thresholds checked.
pub struct Prepared {
    /// The scenario.
    pub scenario: Scenario,
    /// Model, planner and physics counterpart.
    pub system: Box<dyn System>,
    /// Parsed, validated URDF.
    pub robot: urdf_rs::Robot,
}

impl Prepared {
    /// Load everything a run needs; every failure here is a user input error.
    pub fn new(scenario: Scenario) -> Result<Prepared, Error> {
        let robot = urdf::read(&scenario.urdf).map_err(|m| Error::input(&scenario.urdf, m))?;
        let system = systems::build(&scenario.model, &scenario.planner)
            .map_err(|m| Error::input(&scenario.path, m))?;
        let mut known = metric_spec(system.model()).names();
        known.extend(system.extra_metric_names());
        for k in scenario.thresholds.keys() {
            if !known.contains(k) {
                return Err(Error::input(
                    &scenario.path,
                    format!(
                        "key `thresholds.{k}`: unknown metric; known: {}",
                        known.join(", ")
                    ),
                ));
            }
        }
        Ok(Prepared {
            scenario,
            system,
            robot,
        })
    }

    /// The kinematic model.
    pub fn model(&self) -> &dyn KinematicModel {
        self.system.model()
    }

    /// Start and goal as model states.
    pub fn start_goal(&self) -> (State, State) {
        (
            State::from_vec(self.scenario.start.clone()),
            State::from_vec(self.scenario.goal.clone()),
        )
    }

    /// Run the planner.
    pub fn plan(&self) -> Result<Plan, Error> {
        let sc = &self.scenario;
        let (start, goal) = self.start_goal();
        let limits = Limits {
            max_rate: sc.max_rate.clone(),
            ramp: sc.ramp,
            step: sc.sim.dt,
        };
        let plan = self
            .system
            .plan(&start, &goal, &limits)
            .map_err(|source| Error::Plan {
                path: sc.path.clone(),
                source,
            })?;
        if !plan.duration.is_finite() || plan.duration > 1e6 {
            return Err(Error::Plan {
                path: sc.path.clone(),
                source: crate::planner::PlanError::Unreachable(format!(
                    "plan duration {} s is not usable",
                    plan.duration
                )),
            });
        }
        Ok(plan)
    }

    /// Build the physics counterpart at the start state.
    pub fn physics(&self) -> Result<Box<dyn PhysicsSystem>, Error> {
        let sc = &self.scenario;
        let dir = sc.urdf.parent().unwrap_or(Path::new("."));
        self.system
            .physics(&self.robot, dir, &sc.start, &sc.sim.physics())
            .map_err(|m| Error::input(&sc.path, m))
    }
}

/// The metric names and units of a model.
pub fn metric_spec(model: &dyn KinematicModel) -> MetricSpec<'_> {
    MetricSpec {
        names: model.state_names(),
        angular: model.angular_states(),
        position: model.position_states(),
    }
}

/// Where logs go, and whether to show progress.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// Root directory for `<scenario>/run.*`; `None` writes no logs.
    pub log_root: Option<PathBuf>,
    /// Show a progress bar when a run takes longer than a second.
    pub progress: bool,
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
    /// Comparison and log writing.
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

    let t0 = Instant::now();
    let plan = prep.plan()?;
    timings.plan = t0.elapsed().as_secs_f64();

    let t0 = Instant::now();
    let ideal = simulate(model, &plan, &start, sc.sim.dt);
    timings.ideal = t0.elapsed().as_secs_f64();

    let t0 = Instant::now();
    let mut sys = prep.physics()?;
    let bar = crate::progress::Delayed::new(&sc.name, opts.progress);
    let replay_opts = ReplayOptions {
        dt: sc.sim.dt,
        settle: sc.sim.settle,
        // Only the 3D logs read link poses.
        link_poses: opts.log_root.is_some(),
    };
    let sim =
        replay_with(sys.as_mut(), &plan, &replay_opts, &mut |f| bar.set(f)).map_err(|message| {
            Error::Physics {
                path: sc.path.clone(),
                message,
            }
        })?;
    bar.finish();
    timings.physics = t0.elapsed().as_secs_f64();

    let t0 = Instant::now();
    let spec = metric_spec(model);
    let cmp = compare(&ideal, &sim.traj, sc.sim.dt, spec.angular, spec.position);
    let mut metrics = spec.compute(&goal, ideal.last(), sim.traj.last(), &cmp);
    metrics.extend(prep.system.extra_metrics(&goal, &ideal, &sim, &cmp));
    let mut failures = Vec::new();
    for (k, limit) in &sc.thresholds {
        let v = metrics
            .iter()
            .find(|(n, _)| n == k)
            .map(|(_, v)| *v)
            .unwrap_or(f64::NAN);
        if v.is_nan() || v > *limit {
            failures.push(format!("{k} = {v:.6} > {limit}"));
        }
    }
    let mut outcome = RunOutcome {
        name: sc.name.clone(),
        planner: sc.planner.kind().into(),
        passed: failures.is_empty(),
        failures,
        metrics,
        steps: sim.steps,
        timings,
        log_dir: None,
    };
    if let Some(root) = &opts.log_root {
        let dir = root.join(&sc.name);
        write_logs(prep, &plan, &ideal, &sim, &cmp, &mut outcome, &dir, &goal).map_err(
            |message| Error::Log {
                path: sc.path.clone(),
                message,
            },
        )?;
        outcome.log_dir = Some(dir);
    }
    outcome.timings.logs = t0.elapsed().as_secs_f64();
    outcome.timings.total = t_all.elapsed().as_secs_f64();
    if let Some(dir) = &outcome.log_dir {
        // The summary carries the final timings, so it is written last.
        let summary = summary_json(prep, &plan, &ideal, &sim, &outcome);
        write_atomic(&dir.join("summary.json"), |w| {
            serde_json::to_writer_pretty(w, &summary).map_err(std::io::Error::other)
        })
        .map_err(|message| Error::Log {
            path: sc.path.clone(),
            message,
        })?;
    }
    Ok(outcome)
}

#[allow(clippy::too_many_arguments)]
fn write_logs(
    prep: &Prepared,
    plan: &Plan,
    ideal: &Trajectory,
    sim: &SimTrajectory,
    cmp: &crate::record::Comparison,
    outcome: &mut RunOutcome,
    dir: &Path,
    goal: &State,
) -> Result<(), String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let model = prep.model();
    let links = urdf::visuals(&prep.robot);
    let goal_v: Vec<f64> = goal.iter().copied().collect();
    let (start, _) = prep.start_goal();
    let overlays = prep.system.overlays(&start, goal);
    let rec = RunRecord {
        scenario: &prep.scenario.name,
        state_names: model.state_names(),
        input_names: model.input_names(),
        angular: model.angular_states(),
        position: model.position_states(),
        goal: &goal_v,
        goal_heading: prep.system.goal_heading(goal),
        overlays: &overlays,
        labels: &plan.labels,
        ideal,
        sim,
        comparison: cmp,
        links: &links,
        metrics: &outcome.metrics,
    };
    crate::log::mcap::write_mcap(&dir.join("run.mcap"), &rec).map_err(|e| e.to_string())?;
    crate::log::rerun::write_rrd(&dir.join("run.rrd"), &rec).map_err(|e| e.to_string())
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
    json!({
        "scenario": sc.name,
        "file": sc.path,
        "description": sc.description,
        "passed": o.passed,
        "failures": o.failures,
        "thresholds": sc.thresholds,
        "model": sc.model,
        "planner": sc.planner,
        "plan": {
            "duration_s": plan.duration,
            "labels": plan.labels,
            "segments": plan.segments,
            "details": plan.details,
        },
        "sim_settings": sc.sim,
        "goal": display_state(model, &State::from_vec(sc.goal.clone())),
        "ideal": {
            "final_state": display_state(model, ideal.last()),
            "goal_error_position": metric("ideal_goal_position"),
        },
        "sim": {
            "final_state": display_state(model, sim.traj.last()),
            "goal_error_position": metric("sim_goal_position"),
        },
        "metrics": o.metrics.iter().cloned().collect::<std::collections::BTreeMap<_, _>>(),
        "sim_steps": o.steps,
        "sim_steps_per_second": o.steps as f64 / o.timings.physics.max(1e-9),
        "wall_time_s": o.timings,
    })
}

/// Write a file via a temporary name in the same directory, renamed on success.
pub fn write_atomic(
    path: &Path,
    write: impl FnOnce(&mut std::io::BufWriter<std::fs::File>) -> std::io::Result<()>,
) -> Result<(), String> {
    let tmp = path.with_extension("tmp");
    let res = (|| {
        let mut w = std::io::BufWriter::new(std::fs::File::create(&tmp)?);
        write(&mut w)?;
        std::io::Write::flush(&mut w)?;
        std::fs::rename(&tmp, path)
    })();
    res.map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        format!("{}: {e}", path.display())
    })
}
