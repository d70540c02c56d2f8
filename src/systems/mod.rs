//! Systems: each pairs a kinematic model with its planners and its Rapier
//! counterpart. One module per system, implementing [`System`].
//!
//! # Adding a system
//!
//! Configuration flows one way, from the scenario layer down: a system never
//! imports `crate::scenario` (a test, `tests/layering.rs`, fails if it does).
//!
//! 1. In `src/systems/<name>.rs`, define the system's own plain `[model]`
//!    parameter struct (`#[derive(Deserialize, Serialize)]`,
//!    `#[serde(deny_unknown_fields)]`, without `kind`: the scenario layer
//!    strips it), e.g. [`disk::DiskModelConfig`]. Planner parameters are
//!    the planner's own structs (`crate::planner::*::*Params`); a system
//!    with several planners defines an enum of them (e.g.
//!    [`space_robot::SpacePlanner`]).
//! 2. Write `pub fn build(cfg: &Config, planner: ...) -> Result<Box<dyn
//!    System>, String>`: check the parameters that need no file (errors
//!    start with `` key `model.<key>`: `` or `` key `planner.<key>`: ``, so
//!    the scenario layer can add the line).
//! 3. In `src/scenario/config.rs`: a variant of `ModelConfig` (and of
//!    `PlannerConfig` for a new planner), its `kind` string in `KINDS` and
//!    `parse`, its row in `PAIRS`, and the arm(s) of `build_system` that hand
//!    the typed configs to `build`.
//! 4. Declare the URDF links and joints the physics looks up by name
//!    (`REQUIRED` in the physics module, a [`crate::physics::required::Required`]
//!    table; a `[model]` key may rename them) and return them, as named by
//!    the scenario, from [`System::urdf_names`]; add the table to
//!    `ModelConfig::required_urdf` in `src/scenario/config.rs`.
//! 5. Everything else is checked by the validation pass before anything runs
//!    (`crate::validate`): it builds the system, calls [`System::plan`] and
//!    [`System::physics`] at the start pose, and reports their errors as bad
//!    input (exit 2). So a task that cannot work (URDF that disagrees with
//!    the model, unreachable goal, a start inside an obstacle) should be
//!    refused by `plan` or `physics`, with a message that names the scenario
//!    key (`model.radius`, `goal`, ...) or, for URDF problems, starts with
//!    `URDF` and names the link or joint (`` link `wheel` ``).

pub mod dilf;
pub mod disk;
pub mod rover;
pub mod space_robot;
pub mod sphere;

use crate::integrate::Trajectory;
use crate::metric::Direction;
use crate::model::{KinematicModel, State};
use crate::paper::PaperRow;
use crate::physics::required::Named;
use crate::physics::PhysicsSettings;
use crate::physics::PhysicsSystem;
use crate::plan::{Limits, Plan};
use crate::planner::PlanError;
use crate::record::{Comparison, LinkVisual, Overlay, Series, SimTrajectory};
use std::path::Path;

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
    ) -> Result<Box<dyn PhysicsSystem>, String>;
    /// Goal heading as a world yaw (rad) for the 3D views, if the model has one.
    fn goal_heading(&self, _goal: &State) -> Option<f64> {
        None
    }
    /// The links the logs draw, in the order of the physics' link poses:
    /// the URDF's own by default.
    fn links(&self, robot: &urdf_rs::Robot, _start: &State) -> Vec<LinkVisual> {
        crate::physics::urdf::visuals(robot)
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
    /// `analysis/<name>`). Systems whose series share work with their metrics
    /// override this; the default is [`System::extra_metrics`] and no series.
    fn analysis(
        &self,
        goal: &State,
        ideal: &Trajectory,
        sim: &SimTrajectory,
        cmp: &Comparison,
    ) -> (Vec<(String, f64)>, Vec<Series>) {
        (self.extra_metrics(goal, ideal, sim, cmp), Vec::new())
    }
    /// Whether both runs execute the same commands, a function of time alone, so
    /// they can be compared sample by sample (the `tracking_*` metrics mean
    /// something only then). Default: open-loop plans yes; feedback policies no
    /// (each run closes the loop on its own state and reaches the goal at its own time).
    fn same_commands(&self, plan: &Plan) -> bool {
        matches!(plan.law, crate::plan::ControlLaw::OpenLoop(_))
    }
    /// Which way one of this system's metrics regresses, when the harness convention
    /// ([`Direction::conventional`]: `min`/`clearance`/`margin` tokens and success rates are
    /// higher-is-better, the rest lower-is-better) does not fit. Default: no declaration.
    fn metric_direction(&self, _name: &str) -> Option<Direction> {
        None
    }
    /// The paper's printed numbers next to the values `plan` computes, when the scenario
    /// poses the paper's worked example (see [`crate::paper`]). Default: none.
    fn paper(&self, _start: &State, _goal: &State, _plan: &Plan) -> Vec<PaperRow> {
        Vec::new()
    }
}
