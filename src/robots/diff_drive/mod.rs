//! The differential drive: unicycle kinematics on a two-wheel-plus-caster
//! URDF (`models/diff_drive.urdf` or the user's own).
//!
//! No built-in planner: plans come from a plan file or an external feedback
//! law (`[planner] kind = "file"` or `"external"`), which wrap this system.
//! The wheel radius, track and reference point are read from the URDF (the
//! unicycle itself has no parameters); the names of the parts the physics
//! looks up are `[model]` keys with the defaults of `models/diff_drive.urdf`.

pub mod kinematics;
pub mod physics;

use crate::engine::perturb::Exposure;
use crate::engine::required::Named;
use crate::engine::{PhysicsSettings, PhysicsSystem};
use crate::error::SetupError;
use crate::integrate::Trajectory;
use crate::model::{KinematicModel, State};
use crate::plan::{Limits, Plan};
use crate::planner::PlanError;
use crate::record::{Comparison, SimTrajectory};
use crate::robots::diff_drive::kinematics::Unicycle;
use crate::robots::diff_drive::physics::{
    self as phys, DiffDriveNames, DiffDrivePhysics, REQUIRED,
};
use crate::robots::wheeled::obstacles::config::{
    default_goal_tolerance, SolidObstacleConfig, World,
};
use crate::robots::wheeled::slip::{slip_metrics, SLIP_METRICS};
use crate::robots::{check_names, no_planner, System};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// A differential drive (unicycle: x, y, θ; inputs v, ω) on two driven
/// wheels and a caster; wheel radius, track and reference point are read
/// from the URDF. No built-in planner: plans come from a file or an
/// external law.
#[derive(Debug, Clone, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DiffDriveConfig {
    /// URDF file, relative to the scenario file.
    pub urdf: PathBuf,
    /// The body link; its +x axis is the heading.
    #[serde(default = "default_base")]
    pub base_link: String,
    /// The left wheel's continuous joint (its child is the wheel).
    #[serde(default = "default_left")]
    pub left_wheel_joint: String,
    /// The right wheel's continuous joint.
    #[serde(default = "default_right")]
    pub right_wheel_joint: String,
    /// Several driven wheels on the left (a skid steer: every wheel of a
    /// side gets the same ground speed), instead of `left_wheel_joint`.
    #[serde(default)]
    pub left_wheel_joints: Vec<String>,
    /// Several driven wheels on the right, instead of `right_wheel_joint`.
    #[serde(default)]
    pub right_wheel_joints: Vec<String>,
    /// Caster links (made frictionless); may be empty.
    #[serde(default = "default_casters")]
    pub caster_links: Vec<String>,
    /// Fixed obstacles (boxes, vertical cylinders): `[[model.obstacles]]`.
    #[serde(default)]
    pub obstacles: Vec<SolidObstacleConfig>,
    /// Within this distance (m) and heading difference (degrees) of the goal
    /// the robot has reached it (`ideal_time_to_goal`, `sim_time_to_goal`:
    /// the first such time).
    #[serde(default = "default_goal_tolerance")]
    pub goal_tolerance: [f64; 2],
}

fn default_base() -> String {
    phys::BASE.into()
}
fn default_left() -> String {
    phys::LEFT_JOINT.into()
}
fn default_right() -> String {
    phys::RIGHT_JOINT.into()
}
fn default_casters() -> Vec<String> {
    vec![phys::CASTER.into()]
}

struct DiffDrive {
    names: DiffDriveNames,
    world: World,
}

/// One side's wheel joints: the list key, or the single-joint key.
fn side(
    one: &str,
    many: &[String],
    default: &str,
    (one_key, many_key): (&'static str, &'static str),
) -> Result<(Vec<String>, &'static str), SetupError> {
    if many.is_empty() {
        return Ok((vec![one.to_string()], one_key));
    }
    if one != default {
        return Err(SetupError::key(
            format!("model.{many_key}"),
            format!("give either `{one_key}` or `{many_key}`, not both"),
        ));
    }
    Ok((many.to_vec(), many_key))
}

/// Build the differential-drive system.
pub fn build(cfg: &DiffDriveConfig) -> Result<Box<dyn System>, SetupError> {
    let (left, lk) = side(
        &cfg.left_wheel_joint,
        &cfg.left_wheel_joints,
        phys::LEFT_JOINT,
        ("left_wheel_joint", "left_wheel_joints"),
    )?;
    let (right, rk) = side(
        &cfg.right_wheel_joint,
        &cfg.right_wheel_joints,
        phys::RIGHT_JOINT,
        ("right_wheel_joint", "right_wheel_joints"),
    )?;
    let mut names = vec![("base_link", cfg.base_link.as_str())];
    names.extend(left.iter().map(|j| (lk, j.as_str())));
    names.extend(right.iter().map(|j| (rk, j.as_str())));
    names.extend(
        cfg.caster_links
            .iter()
            .map(|c| ("caster_links", c.as_str())),
    );
    check_names(&names)?;
    Ok(Box::new(DiffDrive {
        names: DiffDriveNames {
            base: cfg.base_link.clone(),
            left,
            right,
            casters: cfg.caster_links.clone(),
        },
        world: World::new(&cfg.obstacles, cfg.goal_tolerance)?,
    }))
}

impl System for DiffDrive {
    fn model(&self) -> &dyn KinematicModel {
        &Unicycle
    }
    /// v in m/s, ω in rad/s (for built-in open-loop planners; plan files
    /// and external laws set their own).
    fn default_max_rate(&self) -> Vec<f64> {
        vec![0.5, 2.0]
    }
    fn plan(&self, _start: &State, _goal: &State, _limits: &Limits) -> Result<Plan, PlanError> {
        Err(no_planner("diff_drive"))
    }
    fn goal_heading(&self, goal: &State) -> Option<f64> {
        Some(goal[2])
    }
    fn urdf_names(&self) -> Vec<Named> {
        let n = &self.names;
        let mut out = vec![Named {
            required: &REQUIRED[0],
            name: n.base.clone(),
        }];
        for (req, joints) in [(&REQUIRED[1], &n.left), (&REQUIRED[2], &n.right)] {
            out.extend(joints.iter().map(|j| Named {
                required: req,
                name: j.clone(),
            }));
        }
        out.extend(n.casters.iter().map(|c| Named {
            required: &REQUIRED[3],
            name: c.clone(),
        }));
        out
    }
    fn physics(
        &self,
        robot: &urdf_rs::Robot,
        urdf_dir: &Path,
        start: &[f64],
        sim: &PhysicsSettings,
    ) -> Result<Box<dyn PhysicsSystem>, SetupError> {
        let inner = DiffDrivePhysics::new(robot, urdf_dir, &self.names, start, sim)?;
        self.world.physics(Box::new(inner), sim)
    }
    /// Its wheels can wear or differ from the URDF (`wheel_radius_scale`).
    fn exposure(&self, plan: &Plan) -> Exposure {
        Exposure {
            wheels: true,
            ..Exposure::of(plan)
        }
    }
    fn overlays(&self, _start: &State, _goal: &State) -> Vec<crate::record::Overlay> {
        self.world.overlays()
    }
    fn extra_metric_names(&self) -> Vec<String> {
        let mut out: Vec<String> = SLIP_METRICS.map(String::from).to_vec();
        out.extend(self.world.metric_names());
        out
    }
    /// Slip maxima, time to goal, and with obstacles clearance and contacts.
    fn extra_metrics(
        &self,
        goal: &State,
        ideal: &Trajectory,
        sim: &SimTrajectory,
        _cmp: &Comparison,
    ) -> Vec<(String, f64)> {
        let mut out = slip_metrics(sim);
        out.extend(self.world.metrics(goal, ideal, sim));
        out
    }
}
