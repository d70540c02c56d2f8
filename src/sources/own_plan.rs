//! Plans from outside the harness, for every model: a plan file
//! (`[planner] kind = "file"`) or an external feedback law (`kind =
//! "external"`). The model's own system does everything (model, physics,
//! metrics, logs); only the plan comes from elsewhere, so a model added
//! later gets both without code of its own.

use crate::engine::required::Named;
use crate::engine::{PhysicsSettings, PhysicsSystem};
use crate::error::SetupError;
use crate::integrate::Trajectory;
use crate::model::{KinematicModel, State};
use crate::plan::{Limits, Plan};
use crate::planner::PlanError;
use crate::record::{Comparison, LinkVisual, Overlay, Series, SimTrajectory};
use crate::robots::{EarlyAnalysis, SimFollower, System};
use crate::sources::external::{self, ExternalParams};
use crate::sources::file::{self, FilePlanParams};
use std::path::{Path, PathBuf};

/// Where the plan comes from.
#[derive(Debug, Clone)]
pub enum Source {
    /// A CSV, JSON or MCAP file.
    File(FilePlanParams),
    /// A feedback law in another process.
    External(ExternalParams),
}

/// `inner` (a model's system, built with any of its planners) with its plan
/// from `source`. Checks what needs no planning: the plan file exists, the
/// law's numbers are in range and its program is executable; errors name
/// the scenario key.
pub fn wrap(inner: Box<dyn System>, source: Source) -> Result<Box<dyn System>, SetupError> {
    let program = match &source {
        Source::File(p) => {
            p.check()?;
            None
        }
        Source::External(p) => Some(p.check()?),
    };
    Ok(Box::new(OwnPlan {
        inner,
        source,
        program,
    }))
}

struct OwnPlan {
    inner: Box<dyn System>,
    source: Source,
    /// The external law's resolved program.
    program: Option<PathBuf>,
}

impl System for OwnPlan {
    fn model(&self) -> &dyn KinematicModel {
        self.inner.model()
    }
    fn file_model(&self) -> &dyn KinematicModel {
        self.inner.file_model()
    }
    fn state_from_file(&self, q: Vec<f64>) -> Vec<f64> {
        self.inner.state_from_file(q)
    }
    fn default_max_rate(&self) -> Vec<f64> {
        self.inner.default_max_rate()
    }
    fn plan(&self, _start: &State, _goal: &State, _limits: &Limits) -> Result<Plan, PlanError> {
        let model = self.inner.model();
        match &self.source {
            Source::File(p) => file::plan(p, model.input_names()),
            Source::External(p) => {
                let program = match &self.program {
                    Some(prog) => prog.clone(),
                    None => p.check().map_err(|e| PlanError::InvalidParameter {
                        name: e
                            .key_name()
                            .and_then(|k| k.strip_prefix("planner."))
                            .unwrap_or("command")
                            .into(),
                        reason: e.reason().into(),
                    })?,
                };
                Ok(external::plan(
                    p,
                    program,
                    model.state_names(),
                    model.input_names(),
                ))
            }
        }
    }
    fn urdf_names(&self) -> Vec<Named> {
        self.inner.urdf_names()
    }
    // No `same_commands`: the default (open-loop and held plan files yes,
    // external feedback laws no), not the inner system's (about its own planner).
    fn physics(
        &self,
        robot: &urdf_rs::Robot,
        urdf_dir: &Path,
        start: &[f64],
        sim: &PhysicsSettings,
    ) -> Result<Box<dyn PhysicsSystem>, SetupError> {
        self.inner.physics(robot, urdf_dir, start, sim)
    }
    fn goal_heading(&self, goal: &State) -> Option<f64> {
        self.inner.goal_heading(goal)
    }
    fn links(&self, robot: &urdf_rs::Robot, start: &State) -> Vec<LinkVisual> {
        self.inner.links(robot, start)
    }
    fn overlays(&self, start: &State, goal: &State) -> Vec<Overlay> {
        self.inner.overlays(start, goal)
    }
    fn extra_metric_names(&self) -> Vec<String> {
        self.inner.extra_metric_names()
    }
    fn extra_metrics(
        &self,
        goal: &State,
        ideal: &Trajectory,
        sim: &SimTrajectory,
        cmp: &Comparison,
    ) -> Vec<(String, f64)> {
        self.inner.extra_metrics(goal, ideal, sim, cmp)
    }
    fn analysis_of_ideal(&self, goal: &State, ideal: &Trajectory) -> EarlyAnalysis {
        self.inner.analysis_of_ideal(goal, ideal)
    }
    fn sim_follower(&self, start: &State, goal: &State, dt: f64) -> Option<Box<dyn SimFollower>> {
        self.inner.sim_follower(start, goal, dt)
    }
    fn analysis_with(
        &self,
        goal: &State,
        ideal: &Trajectory,
        early: EarlyAnalysis,
        sim: &SimTrajectory,
        cmp: &Comparison,
    ) -> (Vec<(String, f64)>, Vec<Series>) {
        self.inner.analysis_with(goal, ideal, early, sim, cmp)
    }
    fn exposure(&self, plan: &Plan) -> crate::engine::perturb::Exposure {
        self.inner.exposure(plan)
    }
    // No `paper`: the seeds' printed numbers are about their planners' plans.
    // No `planning_horizon`: nothing is integrated while planning.
}
