//! Systems: each pairs a kinematic model with its planners and its Rapier
//! counterpart. One module per system, implementing [`System`].
//!
//! # Adding a system
//!
//! Configuration flows one way, from the scenario layer down: a system never
//! imports `crate::scenario` (a test, `tests/it/layering.rs`, fails if it does).
//!
//! 1. In `src/systems/<name>.rs`, define the system's own plain `[model]`
//!    parameter struct (`#[derive(Deserialize, Serialize)]`,
//!    `#[serde(deny_unknown_fields)]`, without `kind`: the scenario layer
//!    strips it), e.g. [`rolling_disk::DiskModelConfig`]. Planner parameters are
//!    the planner's own structs (`crate::planner::*::*Params`); a system
//!    with several planners defines an enum of them (e.g.
//!    [`space_robot::SpacePlanner`]).
//! 2. Write `pub fn build(cfg: &Config, planner: ...) -> Result<Box<dyn
//!    System>, SetupError>`: check the parameters that need no file; a
//!    refusal says what it is about ([`crate::error::SetupError::key`] for
//!    a `[model]` or `[planner]` key, `urdf_at` for a URDF element), so the
//!    scenario layer points at the line.
//! 3. Declare the URDF links and joints the physics looks up by name
//!    (`REQUIRED` in the physics module, a [`crate::engine::required::Required`]
//!    table; a `[model]` key may rename them) and return them, as named by
//!    the scenario, from [`System::urdf_names`].
//! 4. Add one row to the `registry!` table in `src/scenario/config.rs`: the
//!    `kind`, the config type, the `REQUIRED` table and the build function
//!    per planner (or `outside:` for a model planned only from outside).
//!    The enums, kind lists, schemas, reference pages and model/planner
//!    pairs are generated from it.
//! 5. Everything else is checked by the validation pass before anything runs
//!    (`crate::validate`): it builds the system, calls [`System::plan`] and
//!    [`System::physics`] at the start pose, and reports their errors as bad
//!    input (exit 2). So a task that cannot work (URDF that disagrees with
//!    the model, unreachable goal, a start inside an obstacle) should be
//!    refused by `plan` or `physics`, with a message that names the scenario
//!    key (`model.radius`, `goal`, ...) or, for URDF problems, starts with
//!    `URDF` and names the link or joint (`` link `wheel` ``).

pub mod car;
pub mod declared;
pub mod diff_drive;
pub mod mobile_manipulator;
pub mod rolling_disk;
pub mod rolling_sphere;
pub mod rover;
pub mod space_robot;
pub mod wheeled;

use crate::engine::perturb::{Dimension, Exposure};
use crate::engine::required::Named;
use crate::engine::PhysicsSettings;
use crate::engine::PhysicsSystem;
use crate::error::SetupError;
use crate::integrate::Trajectory;
use crate::metric::Metric;
use crate::model::{KinematicModel, State};
use crate::paper::PaperRow;
use crate::plan::{Limits, Plan};
use crate::planner::PlanError;
use crate::record::{Comparison, LinkVisual, Overlay, Series, SimTrajectory};
use std::path::Path;

/// What a system's analysis computed beside the physics replay, on the core
/// the replay leaves idle: from the ideal run alone
/// ([`System::analysis_of_ideal`]) and by following the replay
/// ([`SimFollower`]). Named metrics and series, which the system's
/// [`System::analysis_with`] places among the rest.
#[derive(Debug, Clone, Default)]
pub struct EarlyAnalysis {
    /// Metrics by name.
    pub metrics: Vec<(String, f64)>,
    /// Series (each named).
    pub series: Vec<Series>,
}

impl EarlyAnalysis {
    /// The metric `name`, if computed.
    pub fn get(&self, name: &str) -> Option<f64> {
        crate::metric::find(&self.metrics, name)
    }
    /// The metric `name` (NaN when absent: the gate then reports it).
    pub fn metric(&self, name: &str) -> f64 {
        self.get(name).unwrap_or(f64::NAN)
    }
    /// The series `name`, taken out (empty when absent).
    pub fn take_series(&mut self, name: &str) -> Series {
        match self.series.iter().position(|s| s.name == name) {
            Some(i) => self.series.remove(i),
            None => Series::new(name.into()),
        }
    }
    /// Both parts together.
    pub fn and(mut self, other: EarlyAnalysis) -> EarlyAnalysis {
        self.metrics.extend(other.metrics);
        self.series.extend(other.series);
        self
    }
}

/// Part of a system's analysis that follows the physics replay sample by
/// sample while it runs ([`System::sim_follower`]).
pub trait SimFollower: Send {
    /// Physics sample `k` at time `t`, state `q`; every sample, in order.
    fn sample(&mut self, k: usize, t: f64, q: &[f64]);
    /// What it computed.
    fn finish(self: Box<Self>) -> EarlyAnalysis;
}

/// A model, a configured planner and the physics counterpart.
pub trait System: Send + Sync {
    /// The kinematic model (state and input names, ideal dynamics).
    fn model(&self) -> &dyn KinematicModel;
    /// The chart `start`/`goal` are written in in scenario files (lengths, degrees), when it
    /// differs from the model state (e.g. Euler angles for a quaternion model). Default: the model.
    fn file_model(&self) -> &dyn KinematicModel {
        self.model()
    }
    /// A `start`/`goal` in [`System::file_model`] coordinates (SI) as a model state. Default: as is.
    fn state_from_file(&self, q: Vec<f64>) -> Vec<f64> {
        q
    }
    /// Default per-input rate limits for open-loop plans.
    fn default_max_rate(&self) -> Vec<f64>;
    /// Run the configured planner.
    fn plan(&self, start: &State, goal: &State, limits: &Limits) -> Result<Plan, PlanError>;
    /// The URDF links and joints the physics looks up, with the names this
    /// scenario gives them: the model's declaration (`REQUIRED` in its
    /// physics module). The validation pass checks them all before
    /// [`System::physics`] and names every missing one in one message.
    fn urdf_names(&self) -> Vec<Named>;
    /// Build the rigid-body counterpart at `start` (errors are user-facing, about the URDF).
    fn physics(
        &self,
        robot: &urdf_rs::Robot,
        urdf_dir: &Path,
        start: &[f64],
        sim: &PhysicsSettings,
    ) -> Result<Box<dyn PhysicsSystem>, SetupError>;
    /// Goal heading as a world yaw (rad) for the 3D views, if the model has one.
    fn goal_heading(&self, _goal: &State) -> Option<f64> {
        None
    }
    /// The links the logs draw, in the order of the physics' link poses:
    /// the URDF's own by default.
    fn links(&self, robot: &urdf_rs::Robot, _start: &State) -> Vec<LinkVisual> {
        crate::engine::urdf::visuals(robot)
    }
    /// Extra polylines for the 3D views (e.g. a target line).
    fn overlays(&self, _start: &State, _goal: &State) -> Vec<Overlay> {
        Vec::new()
    }
    /// Simulated time the planner itself integrates while planning, s, and the
    /// scenario key that sets it (e.g. a recorded closed-loop run), so the step
    /// budget can be checked before planning. `None`: planning integrates nothing.
    fn planning_horizon(&self) -> Option<(f64, &'static str)> {
        None
    }
    /// Names of system-specific metrics (so thresholds can be checked up front).
    fn extra_metric_names(&self) -> Vec<String> {
        Vec::new()
    }
    /// System-specific metrics from the two runs (e.g. momentum bounds,
    /// orientation error); `cmp` carries the common time grid.
    fn extra_metrics(
        &self,
        _goal: &State,
        _ideal: &Trajectory,
        _sim: &SimTrajectory,
        _cmp: &Comparison,
    ) -> Vec<(String, f64)> {
        Vec::new()
    }
    /// System metrics together with time series computed from the two runs
    /// (logged beside the state: MCAP `/analysis/<name>`, Rerun
    /// `analysis/<name>`): [`System::analysis_of_ideal`], then
    /// [`System::analysis_with`].
    fn analysis(
        &self,
        goal: &State,
        ideal: &Trajectory,
        sim: &SimTrajectory,
        cmp: &Comparison,
    ) -> (Vec<(String, f64)>, Vec<Series>) {
        let of_ideal = self.analysis_of_ideal(goal, ideal);
        self.analysis_with(goal, ideal, of_ideal, sim, cmp)
    }
    /// The part of [`System::analysis`] that needs the ideal run alone. The
    /// runner computes it beside the physics replay, on the core the replay
    /// leaves idle. Default: nothing.
    fn analysis_of_ideal(&self, _goal: &State, _ideal: &Trajectory) -> EarlyAnalysis {
        EarlyAnalysis::default()
    }
    /// A follower of the physics replay from `start`, started before it
    /// (the physics step is `dt`), whose result [`System::analysis_with`] then receives;
    /// `None` (the default): the analysis reads the finished run instead.
    fn sim_follower(
        &self,
        _start: &State,
        _goal: &State,
        _dt: f64,
    ) -> Option<Box<dyn SimFollower>> {
        None
    }
    /// [`System::analysis`] given `early`: this system's
    /// [`System::analysis_of_ideal`] of `ideal`, with its follower's result
    /// when the runner ran one. Systems whose series share work with their
    /// metrics override this; the default is [`System::extra_metrics`] and
    /// no series.
    fn analysis_with(
        &self,
        goal: &State,
        ideal: &Trajectory,
        _early: EarlyAnalysis,
        sim: &SimTrajectory,
        cmp: &Comparison,
    ) -> (Vec<(String, f64)>, Vec<Series>) {
        (self.extra_metrics(goal, ideal, sim, cmp), Vec::new())
    }
    /// Whether both runs execute the same commands, a function of time alone, so
    /// they can be compared sample by sample (the `tracking_*` metrics mean
    /// something only then). Default: open-loop plans (held plan files too) yes;
    /// feedback policies no (each run closes the loop on its own state and
    /// reaches the goal at its own time).
    fn same_commands(&self, plan: &Plan) -> bool {
        use crate::plan::ControlLaw;
        matches!(
            plan.law,
            ControlLaw::OpenLoop(_) | ControlLaw::Piecewise { .. }
        )
    }
    /// What of this system a perturbation can reach under `plan` (friction,
    /// wheels, a feedback law): each `[sim.perturb]` row says what it needs
    /// ([`crate::engine::perturb::Reaches`]). Default: [`Exposure::of`]
    /// (friction, no wheels, a feedback law when the plan is one).
    fn exposure(&self, plan: &Plan) -> Exposure {
        Exposure::of(plan)
    }
    /// The `[sim.perturb]` dimensions that reach this system under `plan`
    /// (those of its [`System::exposure`]): a value set away from nominal for
    /// any other dimension is bad input, and `anholonomy margin` searches these.
    fn perturbable(&self, plan: &Plan) -> Vec<Dimension> {
        Dimension::reaching(&self.exposure(plan))
    }
    /// The paper's printed numbers next to the values `plan` computes, when the scenario
    /// poses the paper's worked example (see [`crate::paper`]). Default: none.
    fn paper(&self, _start: &State, _goal: &State, _plan: &Plan) -> Vec<PaperRow> {
        Vec::new()
    }
}

/// Names given in `[model]`: none empty, none given twice.
pub(crate) fn check_names(names: &[(&str, &str)]) -> Result<(), SetupError> {
    for (i, (key, name)) in names.iter().enumerate() {
        if name.trim().is_empty() {
            return Err(SetupError::key(format!("model.{key}"), "must not be empty"));
        }
        if let Some((other, _)) = names[..i].iter().find(|(_, n)| n == name) {
            return Err(SetupError::key(
                format!("model.{key}"),
                format!("`{name}` is also `model.{other}` (each part needs its own name)"),
            ));
        }
    }
    Ok(())
}

/// The refusal of a model without a planner of its own (the plan-file and
/// external-law wrappers replace [`System::plan`]).
pub(crate) fn no_planner(model: &str) -> PlanError {
    PlanError::InvalidParameter {
        name: "kind".into(),
        reason: format!(
            "model `{model}` has no built-in planner: use kind = \"file\" or kind = \"external\""
        ),
    }
}

/// Every robot room's metric rows, then the harness's.
fn metric_rows() -> impl Iterator<Item = &'static Metric> {
    [
        space_robot::METRICS,
        rover::METRICS,
        rolling_sphere::METRICS,
        mobile_manipulator::METRICS,
        car::METRICS,
        crate::metric::HARNESS,
        crate::metric::REAL,
    ]
    .into_iter()
    .flatten()
}

/// The row of metric `name` (a robot's own before the harness's), if any.
pub fn metric(name: &str) -> Option<&'static Metric> {
    crate::metric::find_row(metric_rows(), name)
}

/// Whether metric `name` compares the two runs sample by sample (its row
/// is a tracking row): meaningless for a feedback policy.
pub(crate) fn compares_runs(name: &str) -> bool {
    metric(name).is_some_and(|r| r.compares_runs)
}

/// Whether metric `name` reads the ideal run alone (its row's `{run}` is
/// `ideal`): no perturbation of the physics changes it.
pub(crate) fn reads_ideal_run(name: &str) -> bool {
    metric(name).is_some_and(|r| r.run_of(name) == Some("ideal"))
}

/// The unit of metric `name` as written after its values (`m`, `°`, `s`;
/// empty when it has none or none is known), for a model whose coordinates
/// `spec` describes.
pub(crate) fn metric_unit(name: &str, spec: &crate::compare::MetricSpec<'_>) -> &'static str {
    let Some(row) = metric(name) else {
        return "";
    };
    if row.unit != crate::metric::Unit::Coordinate {
        return row.unit.symbol(name);
    }
    crate::metric::captures(row.name, name)
        .and_then(|c| c.into_iter().find(|(hole, _)| *hole == "coord"))
        .map_or("", |(_, coord)| spec.coord_unit(coord))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_say_which_metrics_compare_runs_and_which_read_the_ideal_run() {
        for name in [
            "tracking_position_max",
            "tracking_position_2_rms",
            "tracking_theta_deg_final",
            "tracking_orientation_deg_max",
        ] {
            assert!(compares_runs(name), "{name}");
        }
        for name in [
            "sim_goal_position",
            "ideal_goal_x",
            "slip_lateral_max",
            "real_sim_position_max",
            "not_a_metric",
        ] {
            assert!(!compares_runs(name), "{name}");
        }
        assert!(reads_ideal_run("ideal_goal_position"));
        assert!(reads_ideal_run("ideal_time_to_goal"));
        assert!(!reads_ideal_run("sim_goal_position"));
        assert!(!reads_ideal_run("real_ideal_position_max"));
        assert!(!reads_ideal_run("tracking_position_max"));
        // Every tracking row gets worse as it rises.
        for r in metric_rows().filter(|r| r.compares_runs) {
            assert_eq!(
                r.direction,
                crate::metric::Direction::LowerIsBetter,
                "{}",
                r.name
            );
        }
    }
}
