//! The validation pass: every scenario of a call (`run`, `check`, `plan`,
//! `list`) is read and checked before the first run starts or the first log
//! is written; any failure is bad input (exit 2) and nothing is written.
//!
//! For each file: kind and size ([`crate::input`]), TOML, model/planner
//! match and ranges ([`Scenario::parse`]), the URDF ([`urdf`]), thresholds
//! and sweep metric names, names usable as directories and not shared by two
//! scenarios of the call. Then what can only be checked by building the
//! system: the **plan** is made (unreachable goals, bad planner parameters)
//! and the **physics is built at the start pose** (URDF against the model,
//! and whatever a system refuses there, e.g. a start inside an obstacle).
//!
//! Planning up front costs little: at most tens of milliseconds per shipped
//! scenario (the endogenous planner; `wall_time_s.plan` in summary.json). The plan is
//! kept in [`Prepared::planned`] and the run replays it, so nothing is
//! planned twice. The physics probe is dropped (a Rapier world is cheap to
//! build and not `Sync`); the run builds its own.

pub mod reference;
pub mod urdf;
pub mod wheels;
pub mod xacro;

use crate::compare::metric_spec;
use crate::engine::reading::UrdfReading;
use crate::engine::PhysicsSystem;
use crate::error::Error;
use crate::model::{KinematicModel, State};
use crate::plan::{Limits, Plan};
use crate::planner::PlanError;
use crate::robots::System;
use crate::scenario::{build_system, collect, Scenario, Variant, DEFAULT_TIME_METRIC};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Default step budget: the most RK4 (and physics) steps one run may take,
/// plan plus settle, at `sim.dt`. The longest shipped scenario takes 150 000
/// (a 300 s rover horizon at 2 ms); each step keeps a few hundred bytes of
/// samples, so 2 000 000 stays around a gigabyte. `--max-steps` raises it.
pub const DEFAULT_MAX_STEPS: u64 = 2_000_000;

/// A scenario that passed validation: system built, URDF loaded, planned.
pub struct Prepared {
    /// The scenario.
    pub scenario: Scenario,
    /// Model, planner and physics counterpart.
    pub system: Box<dyn System>,
    /// Parsed, validated URDF.
    pub robot: urdf_rs::Robot,
    /// The plan made during validation; runs replay it (planners are deterministic).
    pub planned: Plan,
    /// Wall time of that planning, s.
    pub plan_wall_s: f64,
    /// Step budget the scenario was validated against (sweep variants too).
    pub max_steps: u64,
    /// What the physics read from the URDF: bodies, wheels, drives,
    /// geometry, and the warnings (defaults filled in, meshes left out).
    pub reading: UrdfReading,
    /// The warnings of loading the URDF alone (sweep variants reuse them).
    urdf_warnings: Vec<String>,
    /// `[compare] reference`: the recording, lined up with the plan.
    pub reference: Option<std::sync::Arc<crate::record::Track>>,
}

impl Prepared {
    /// Validate a loaded scenario: URDF, system, thresholds, sweep metrics,
    /// plan, physics at the start pose. Every failure is a user input error.
    pub fn new(scenario: Scenario) -> Result<Prepared, Error> {
        Prepared::with_budget(scenario, DEFAULT_MAX_STEPS)
    }

    /// Like [`Prepared::new`] with a step budget other than [`DEFAULT_MAX_STEPS`].
    pub fn with_budget(scenario: Scenario, max_steps: u64) -> Result<Prepared, Error> {
        let loaded =
            urdf::load_from(&scenario.urdf, &scenario.urdf_source).map_err(Error::several)?;
        let mut prep = Prepared::with_robot(scenario, loaded.robot, loaded.warnings, max_steps)?;
        prep.reading.notes = loaded.notes;
        Ok(prep)
    }

    /// Like [`Prepared::with_budget`] with the URDF already loaded, and the
    /// warnings of its loading.
    fn with_robot(
        mut scenario: Scenario,
        robot: urdf_rs::Robot,
        load_warnings: Vec<String>,
        max_steps: u64,
    ) -> Result<Prepared, Error> {
        let system = build_system(&scenario.model, &scenario.planner)
            .map_err(|e| scenario.setup_error(&e))?;
        let mut known = metric_names(system.as_ref());
        known.extend(reference::metric_names(&scenario, system.as_ref()));
        let gates = scenario.thresholds.keys().map(|k| ("thresholds", k));
        for (table, k) in gates.chain(scenario.minimums.keys().map(|k| ("minimums", k))) {
            if !known.contains(k) {
                return Err(scenario.error_at(
                    &format!("{table}.{k}"),
                    unknown_metric(k, system.as_ref(), &[]).to_string(),
                ));
            }
        }
        let written = |k: &str| scenario.has_key(k);
        let (success_written, time_written) = (
            written("sweep.success_metric"),
            written("sweep.time_metric"),
        );
        if let Some(sw) = &mut scenario.sweep {
            // The default time metric only where the model reports one.
            if sw.time_metric.is_none() && known.iter().any(|k| k == DEFAULT_TIME_METRIC) {
                sw.time_metric = Some(DEFAULT_TIME_METRIC.into());
            }
        }
        if let Some(sw) = &scenario.sweep {
            let metrics = [
                ("success_metric", Some(&sw.success_metric), success_written),
                ("time_metric", sw.time_metric.as_ref(), time_written),
            ];
            for (key, m, is_written) in metrics {
                let Some(m) = m.filter(|m| !known.contains(m)) else {
                    continue;
                };
                let default = if is_written {
                    String::new()
                } else {
                    format!("the default `{m}` does not fit this model: name a metric; ")
                };
                return Err(scenario.error_at(
                    &format!("sweep.{key}"),
                    format!("{default}{}", unknown_metric(m, system.as_ref(), &[])),
                ));
            }
        }
        let mut regressable = known.clone();
        let sweep_metrics = match scenario.sweep {
            Some(_) => crate::scenario::sweep_metric_names(),
            None => Vec::new(),
        };
        regressable.extend(sweep_metrics.iter().cloned());
        let margin_metrics: Vec<String> = scenario
            .margins
            .gates()
            .into_iter()
            .map(|(d, _)| crate::scenario::MarginsConfig::metric(d))
            .collect();
        regressable.extend(margin_metrics);
        if let Some(k) = scenario.regression.unknown_metrics(&regressable).next() {
            return Err(scenario.error_at(
                &format!("regression.metrics.{k}"),
                unknown_metric(k, system.as_ref(), &sweep_metrics).to_string(),
            ));
        }
        // The physics first: a URDF that disagrees with the model explains a
        // planner refusal better than the refusal does.
        let probe = build_physics(&scenario, system.as_ref(), &robot)?;
        let mut reading = probe.reading();
        drop(probe);
        reading.bodies = bodies(&robot, system.as_ref());
        reading.settle_default_limits(scenario.has_key("sim.motor_max_torque"));
        if let Some(w) = wheels::undriven(&robot, &reading, &system.urdf_names()) {
            reading.warnings.push(w);
        }
        reading.warnings.splice(0..0, load_warnings.iter().cloned());
        // The step budget, before anything integrates: what settling alone
        // and the planner's own integration imply, then the whole run.
        let budget = Budget {
            sc: &scenario,
            max_steps,
        };
        budget.check(scenario.sim.settle, "sim.settle", "settling")?;
        if let Some((horizon, key)) = system.planning_horizon() {
            budget.check(horizon, key, "the planner's recorded run")?;
        }
        let t0 = Instant::now();
        let planned = make_plan(&scenario, system.as_ref())?;
        let plan_wall_s = t0.elapsed().as_secs_f64();
        budget.check(
            planned.duration + scenario.sim.settle,
            "sim.dt",
            "the plan and settling",
        )?;
        if !system.same_commands(&planned) {
            // The runs follow their own feedback: comparing them at equal
            // times measures the time shift, not the physics.
            let gates = scenario.thresholds.keys().map(|k| ("thresholds", k));
            for (table, k) in gates.chain(scenario.minimums.keys().map(|k| ("minimums", k))) {
                if crate::robots::compares_runs(k) {
                    return Err(scenario.error_at(&format!("{table}.{k}"), "tracking errors mean nothing for this plan (a feedback policy: each run closes the loop on its own state and reaches the goal at its own time); gate on `sim_goal_*` instead"));
                }
            }
        }
        check_perturbable(&scenario, system.as_ref(), &planned)?;
        let recorded = reference::load(&scenario, system.as_ref(), &planned)?;
        check_perturbation_times(&scenario, &planned, &budget)?;
        let prep = Prepared {
            scenario,
            system,
            robot,
            planned,
            plan_wall_s,
            max_steps,
            reading,
            urdf_warnings: load_warnings,
            reference: recorded,
        };
        if let Some(sw) = &prep.scenario.sweep {
            // Variants differ only in friction, masses and σ: when variant 0
            // cannot even be set up (e.g. a mass scale the model refuses),
            // none can, and that is bad input.
            let v = sw.variant(0);
            if let Err(e) = prep.variant(&v) {
                let params: Vec<String> = v
                    .params
                    .iter()
                    .map(|(k, x)| format!("{k} = {x:.4}"))
                    .collect();
                return Err(prep.scenario.error_at(
                    "sweep",
                    format!(
                        "variant 0 ({}mass scale {:.4}) cannot run: {e}",
                        params.iter().map(|p| format!("{p}, ")).collect::<String>(),
                        v.mass_scale
                    ),
                ));
            }
        }
        Ok(prep)
    }

    /// A sweep variant of this scenario, validated and planned like the scenario.
    pub fn variant(&self, v: &Variant) -> Result<Prepared, Error> {
        let sc = self.scenario.variant(v)?;
        let mut prep = Prepared::with_robot(
            sc,
            self.robot.clone(),
            self.urdf_warnings.clone(),
            self.max_steps,
        )?;
        prep.reading.notes = self.reading.notes.clone();
        Ok(prep)
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

    /// Every metric a run of this scenario reports.
    pub fn metric_names(&self) -> Vec<String> {
        let mut names = metric_names(self.system.as_ref());
        names.extend(reference::metric_names(
            &self.scenario,
            self.system.as_ref(),
        ));
        names
    }

    /// Run the planner again (validation already planned: see
    /// [`Prepared::planned`]; this is for benchmarks and tests).
    pub fn plan(&self) -> Result<Plan, Error> {
        make_plan(&self.scenario, self.system.as_ref())
    }

    /// Build the physics counterpart at the start state.
    pub fn physics(&self) -> Result<Box<dyn PhysicsSystem>, Error> {
        build_physics(&self.scenario, self.system.as_ref(), &self.robot)
    }

    /// The physics counterpart under other settings (a margin level's
    /// perturbed world: [`crate::scenario::SimConfig::physics`]).
    pub fn physics_with(
        &self,
        settings: &crate::engine::PhysicsSettings,
    ) -> Result<Box<dyn PhysicsSystem>, Error> {
        let sc = &self.scenario;
        let dir = sc.urdf.parent().unwrap_or(Path::new("."));
        self.system
            .physics(&self.robot, dir, &sc.start, settings)
            .map_err(|e| physics_error(sc, &e))
    }
}

/// Every perturbation set in `[sim.perturb]` and every margin gated in
/// `[margins]` must reach the system under its plan
/// ([`System::perturbable`]).
fn check_perturbable(sc: &Scenario, system: &dyn System, plan: &Plan) -> Result<(), Error> {
    let applies = system.perturbable(plan);
    let set = sc
        .sim
        .perturb
        .active()
        .into_iter()
        .map(|d| ("sim.perturb", d));
    let gated = sc.margins.gates().into_iter().map(|(d, _)| ("margins", d));
    for (table, d) in set.chain(gated) {
        if !applies.contains(&d) {
            return Err(sc.error_at(&format!("{table}.{d}"), not_applicable(d, sc, &applies)));
        }
    }
    Ok(())
}

/// The dimensions measured in seconds: each must fit in the run (a command
/// or a state older than the whole run, or a lag slower than it, leaves the
/// run without its plan), and the latency's extra steps in the step budget.
/// Refused before anything runs: a latency of 1e300 s overflowed the delay
/// line, one of 1e6 s allocated gigabytes.
fn check_perturbation_times(sc: &Scenario, plan: &Plan, budget: &Budget<'_>) -> Result<(), Error> {
    use crate::engine::perturb::Dimension as D;
    use crate::numfmt::readable;
    let run = plan.duration;
    let what = match plan.law {
        crate::plan::ControlLaw::Feedback { .. } => "the run (planner.horizon)",
        _ => "the plan",
    };
    let set = [D::CommandLatency, D::StateLatency, D::ActuatorTau]
        .into_iter()
        .map(|d| ("sim.perturb", d, d.value(&sc.sim.perturb)));
    let gated = sc
        .margins
        .gates()
        .into_iter()
        .filter(|(d, _)| d.unit() == "s")
        .map(|(d, g)| (format!("margins.{d}"), d, g));
    let set = set.map(|(table, d, v)| (format!("{table}.{d}"), d, v));
    // A sweep varying one: the values validation probes (a range's ends).
    let varied = sc.sweep.iter().flat_map(|sw| {
        sw.vary.iter().filter_map(|(path, dist)| {
            let d = D::parse(path.strip_prefix("sim.perturb.")?)?;
            let top = dist.probes().into_iter().fold(f64::NEG_INFINITY, f64::max);
            (d.unit() == "s").then(|| (crate::scenario::vary_key(path), d, top))
        })
    });
    for (key, d, v) in set.chain(gated).chain(varied) {
        if v > run {
            return Err(sc.error_at(
                &key.to_string(),
                format!(
                    "{} s is longer than {what}, {} s: {}; at most {} s",
                    readable(v),
                    readable(run),
                    match d {
                        D::CommandLatency => "no command would reach the drives before it ends",
                        D::StateLatency => "the law would see nothing but the start state",
                        _ => "the drives would not follow a single command",
                    },
                    readable(run)
                ),
            ));
        }
    }
    let latency = sc.sim.perturb.command_latency;
    if latency > 0.0 {
        budget.check(
            run + sc.sim.settle + latency,
            "sim.perturb.command_latency",
            "the plan, settling and the command latency",
        )?;
    }
    Ok(())
}

/// Why dimension `d` does not reach this scenario's system, and which do.
pub fn not_applicable(
    d: crate::engine::perturb::Dimension,
    sc: &Scenario,
    applies: &[crate::engine::perturb::Dimension],
) -> String {
    use crate::engine::perturb::Dimension as D;
    let (model, planner) = (sc.model.kind(), sc.planner.kind());
    let why = match d {
        d if d.observes() => format!(
            "it perturbs the state a feedback law sees, and the plan of `{planner}` here reads no state (open loop)"
        ),
        D::WheelRadiusScale => format!("model `{model}` has no wheels"),
        D::FrictionScale => format!("nothing in the world of model `{model}` touches anything"),
        _ => format!("model `{model}` does not take it"),
    };
    let names: Vec<&str> = applies.iter().map(|d| d.name()).collect();
    format!(
        "`{d}` does not apply: {why} (applies here: {})",
        names.join(", ")
    )
}

/// The step budget of one scenario: simulated time at `sim.dt` must not
/// imply more than `max_steps` steps.
struct Budget<'a> {
    sc: &'a Scenario,
    max_steps: u64,
}

impl Budget<'_> {
    /// Refuse `seconds` of simulated time (`what`, set by `key`) over the budget.
    fn check(&self, seconds: f64, key: &str, what: &str) -> Result<(), Error> {
        use crate::numfmt::readable;
        let dt = self.sc.sim.dt;
        let n = seconds / dt;
        // Whole steps, as the runs count them (a plan on the dt grid ends exactly).
        let steps = if (n - n.round()).abs() < 1e-6 {
            n.round()
        } else {
            n.ceil()
        };
        if steps.is_nan() || steps <= self.max_steps as f64 {
            return Ok(());
        }
        let span = if key == "sim.dt" {
            format!("{} s of {what}", readable(seconds))
        } else {
            format!("{what} of {} s", readable(seconds))
        };
        Err(self.sc.error_at(key, format!("{span} at sim.dt = {} s is {} steps, over the budget of {} steps (raise it with --max-steps)", readable(dt),
            readable(steps),
            readable(self.max_steps as f64))))
    }
}

/// "unknown metric `name`", the nearest known name if one is close, and the
/// known names with the per-coordinate families written once (a 2-robot
/// system has 130 names).
fn unknown_metric(name: &str, system: &dyn System, more: &[String]) -> String {
    let mut known = metric_names(system);
    known.extend(more.iter().cloned());
    let best = known
        .iter()
        .map(|k| (strsim::jaro_winkler(name, k), k))
        .max_by(|a, b| a.0.total_cmp(&b.0));
    let hint = match best {
        Some((score, k)) if score >= 0.85 => format!(" (did you mean `{k}`?)"),
        _ => String::new(),
    };
    let coords = metric_spec(system.model()).coords();
    let mut extra = system.extra_metric_names();
    extra.extend(more.iter().cloned());
    let extra = if extra.is_empty() {
        String::new()
    } else {
        format!("; {}", extra.join(", "))
    };
    format!(
        "unknown metric {}{hint}; known: ideal_goal_C, sim_goal_C, \
         tracking_C_rms, tracking_C_max, tracking_C_final for C in {}{extra}",
        crate::echo::code(name),
        coords.join(", ")
    )
}

fn metric_names(system: &dyn System) -> Vec<String> {
    let mut known = metric_spec(system.model()).names();
    known.extend(system.extra_metric_names());
    known
}

/// The key of the scenario a planner refusal is about.
fn plan_error_key(sc: &Scenario, e: &PlanError) -> String {
    match e {
        PlanError::InvalidParameter { name, .. } => {
            let nested = format!("planner.{name}");
            // Some planners check `start` or `goal` (top-level keys).
            if !sc.has_key(&nested) && sc.has_key(name) {
                name.clone()
            } else {
                nested
            }
        }
        PlanError::Unreachable(_) => "goal".into(),
        PlanError::Model { key, .. } => key.clone(),
        PlanError::NoConvergence(_) | PlanError::File(_) => "planner".into(),
    }
}

fn make_plan(sc: &Scenario, system: &dyn System) -> Result<Plan, Error> {
    let (start, goal) = (
        State::from_vec(sc.start.clone()),
        State::from_vec(sc.goal.clone()),
    );
    let limits = Limits {
        max_rate: sc.max_rate.clone(),
        ramp: sc.ramp,
        step: sc.sim.dt,
    };
    let plan_error = |source: PlanError| {
        // A bad plan file is reported at its own row, like a bad URDF.
        if let PlanError::File(f) = source {
            return Error::Input {
                key: None,
                path: f.path,
                line: f.line,
                message: f.message,
            };
        }
        let key = plan_error_key(sc, &source);
        Error::Plan {
            path: sc.path.clone(),
            line: sc.line_of(&key),
            key,
            source,
        }
    };
    let plan = system.plan(&start, &goal, &limits).map_err(plan_error)?;
    let max = crate::plan::MAX_DURATION;
    if !plan.duration.is_finite() || plan.duration > max {
        use crate::numfmt::readable;
        // A feedback law runs for its horizon: that key set the duration,
        // not the goal.
        let feedback = matches!(plan.law, crate::plan::ControlLaw::Feedback { .. });
        if feedback && sc.has_key("planner.horizon") {
            return Err(sc.error_at(
                "planner.horizon",
                format!(
                    "{} s is longer than any run may be (at most {} s)",
                    readable(plan.duration),
                    readable(max)
                ),
            ));
        }
        return Err(plan_error(PlanError::Unreachable(format!(
            "plan duration {} s is not usable (at most {} s)",
            readable(plan.duration),
            readable(max)
        ))));
    }
    Ok(plan)
}

/// The rigid bodies of `robot` as the system's physics loads them: fixed
/// joints lumped, except those the system names (it needs them as joints).
fn bodies(robot: &urdf_rs::Robot, system: &dyn System) -> Vec<crate::engine::reading::BodyReading> {
    use crate::engine::required::Element;
    let names = system.urdf_names();
    let keep: Vec<&str> = names
        .iter()
        .filter(|n| n.required.element == Element::Joint)
        .map(|n| n.name.as_str())
        .collect();
    match crate::engine::lump::lump(robot, &keep) {
        Ok(l) => UrdfReading::bodies_of(robot, &l),
        Err(_) => Vec::new(),
    }
}

fn build_physics(
    sc: &Scenario,
    system: &dyn System,
    robot: &urdf_rs::Robot,
) -> Result<Box<dyn PhysicsSystem>, Error> {
    // Every name the model looks up, in one message, before the physics
    // stops at the first one it misses.
    crate::engine::required::check(robot, &system.urdf_names())
        .map_err(|e| physics_error(sc, &e))?;
    let dir = sc.urdf.parent().unwrap_or(Path::new("."));
    system
        .physics(robot, dir, &sc.start, &sc.sim.physics())
        .map_err(|e| physics_error(sc, &e))
}

/// A physics setup refusal at the file and line it is about: a scenario
/// key's, or a URDF element's.
fn physics_error(sc: &Scenario, e: &crate::error::SetupError) -> Error {
    match &e.about {
        crate::error::About::Urdf(_) => urdf::error_in(&sc.urdf, e),
        _ => sc.setup_error(e),
    }
}

/// What a call will do with its scenarios, as far as validation must know.
#[derive(Debug, Clone, Copy, Default)]
pub struct Call<'a> {
    /// Log root (`--logs`), when logs will be written.
    pub log_root: Option<&'a Path>,
    /// `--shard` was given: only sweep scenarios can be sharded.
    pub sharded: bool,
    /// Step budget (`--max-steps`); `None` is [`DEFAULT_MAX_STEPS`].
    pub max_steps: Option<u64>,
}

/// The validation pass over every scenario of a call: all errors, or every
/// scenario prepared (planned, physics probed), in the order given
/// (directories sorted).
pub fn prepare_all(paths: &[PathBuf], call: &Call<'_>) -> Result<Vec<Prepared>, Vec<Error>> {
    let (preps, errors) = prepare_each(paths, call);
    if errors.is_empty() {
        Ok(preps)
    } else {
        Err(errors)
    }
}

/// The validation pass, keeping what passed beside the errors (`list` shows
/// the scenarios that load and reports the others).
pub fn prepare_each(paths: &[PathBuf], call: &Call<'_>) -> (Vec<Prepared>, Vec<Error>) {
    let files = match collect(paths) {
        Ok(f) => f,
        Err(errors) => return (Vec::new(), errors),
    };
    let mut errors = Vec::new();
    if let Some(root) = call.log_root {
        if root.exists() && !root.is_dir() {
            errors.push(Error::input(root, "--logs: exists and is not a directory"));
        }
    }
    // Log directory names are compared case-insensitively (macOS, Windows).
    let mut names: HashMap<String, PathBuf> = HashMap::new();
    let mut preps = Vec::new();
    for f in files {
        let sc = match Scenario::load(&f) {
            Ok(sc) => sc,
            Err(e) => {
                errors.push(e);
                continue;
            }
        };
        if let Some(other) = names.insert(sc.name.to_lowercase(), f.clone()) {
            errors.push(sc.error_at(
                "name",
                format!(
                    "`{}` is also the name of {}: both would write the same log directory",
                    sc.name,
                    crate::echo::path(&other)
                ),
            ));
            continue;
        }
        if call.sharded && sc.sweep.is_none() {
            errors.push(Error::input(
                &f,
                "--shard: this scenario has no [sweep] table (only sweeps can be sharded; run it without --shard)",
            ));
            continue;
        }
        if let Some(root) = call.log_root {
            let dir = root.join(&sc.name);
            if dir.exists() && !dir.is_dir() {
                errors.push(Error::input(
                    &dir,
                    "log directory exists and is not a directory",
                ));
                continue;
            }
        }
        match Prepared::with_budget(sc, call.max_steps.unwrap_or(DEFAULT_MAX_STEPS)) {
            Ok(p) => preps.push(p),
            Err(e) => errors.extend(e.into_list()),
        }
    }
    (preps, errors)
}
