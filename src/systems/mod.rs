//! Systems: each pairs a kinematic model with its planners and its Rapier
//! counterpart. One module per system; [`build`] picks it from the scenario.
//!
//! Adding a system: a `ModelConfig` variant (scenario.rs), planner variants
//! in `PlannerConfig`, a module here implementing [`System`], one arm in
//! [`build`].

pub mod disk;
pub mod rover;
pub mod space_robot;
pub mod sphere;

use crate::integrate::Trajectory;
use crate::model::{KinematicModel, State};
use crate::physics::PhysicsSettings;
use crate::physics::PhysicsSystem;
use crate::plan::{Limits, Plan};
use crate::planner::PlanError;
use crate::record::{Comparison, Overlay, SimTrajectory};
use crate::scenario::{ModelConfig, PlannerConfig};
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
    /// Extra polylines for the 3D views (e.g. a target line).
    fn overlays(&self, _start: &State, _goal: &State) -> Vec<Overlay> {
        Vec::new()
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
}

/// The system for a scenario's model and planner; mismatches are user errors.
pub fn build(model: &ModelConfig, planner: &PlannerConfig) -> Result<Box<dyn System>, String> {
    match model {
        ModelConfig::RollingDisk(m) => disk::build(m, planner),
        ModelConfig::SpaceRobot(m) => space_robot::build(m, planner),
        ModelConfig::Rover(m) => rover::build(m, planner),
        ModelConfig::RollingSphere(m) => sphere::build(m, planner),
    }
}

/// The error for a planner that does not fit the model.
pub fn mismatch(model: &str, planner: &PlannerConfig, expected: &[&str]) -> String {
    format!(
        "key `planner.kind`: `{}` does not plan for model `{model}` (use {})",
        planner.kind(),
        expected.join(" or ")
    )
}
