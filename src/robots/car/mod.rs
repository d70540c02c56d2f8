//! The car: kinematic bicycle (x, y, θ, φ; inputs v, φ') on a four-wheel
//! Ackermann URDF (`models/car.urdf` or the user's own); with `steering =
//! "angle"` the bicycle is steered by angle (x, y, θ; inputs v, φ).
//!
//! No built-in planner: plans come from a plan file or an external feedback
//! law (`[planner] kind = "file"` or `"external"`), which wrap this system.
//! The wheelbase and the steering limit are model keys (the bicycle needs
//! them before any URDF is read); the physics checks the URDF against both
//! and reads the rest (wheel radii, tracks, the reference point) from it.

pub mod kinematics;
pub mod physics;

use crate::engine::perturb::Exposure;
use crate::engine::required::Named;
use crate::engine::{PhysicsSettings, PhysicsSystem};
use crate::error::SetupError;
use crate::integrate::Trajectory;
use crate::metric::{m, Direction::*, Family::*, Metric, Unit};
use crate::model::{KinematicModel, State};
use crate::plan::{Limits, Plan};
use crate::planner::PlanError;
use crate::record::{Comparison, SimTrajectory};
use crate::robots::car::kinematics::{Bicycle, Steering};
use crate::robots::car::physics::{self as phys, CarNames, CarPhysics, REQUIRED};
use crate::robots::wheeled::obstacles::config::{
    default_goal_tolerance, SolidObstacleConfig, World,
};
use crate::robots::wheeled::slip::{slip_metrics, SLIP_METRICS};
use crate::robots::System;
use crate::robots::{check_names, no_planner};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The car's own metrics.
pub const METRICS: &[Metric] = &[m(
    "steer_clipped_fraction",
    Unit::Fraction,
    LowerIsBetter,
    EndOnly,
    "Fraction of the ideal run's samples whose steering exceeds the joints' limits.",
)];

/// A car (kinematic bicycle: x, y, θ, φ; inputs v, φ'; or steered by angle:
/// x, y, θ; inputs v, φ) on four wheels with Ackermann steering and
/// rear-wheel drive; wheel radii and tracks are read from the URDF. No
/// built-in planner: plans come from a file or an external law.
#[derive(Debug, Clone, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CarConfig {
    /// URDF file, relative to the scenario file.
    pub urdf: PathBuf,
    /// Wheelbase L, m: rear axle to the front steering pivots (the URDF's must match it within 0.1 mm).
    #[serde(default = "default_wheelbase")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub wheelbase: f64,
    /// Steering limit of the bicycle angle φ, degrees.
    #[serde(default = "default_max_steer")]
    #[schemars(extend("exclusiveMinimum" = 0, "exclusiveMaximum" = 90))]
    pub max_steer_deg: f64,
    /// The second input: `"rate"` (`steer_rate`, φ' in rad/s; φ is a state) or
    /// `"angle"` (`steer`, φ in rad, as Ackermann messages and most car planners
    /// give it; states x, y, θ; the steering joints are position-servoed to
    /// the commanded angle).
    #[serde(default)]
    pub steering: Steering,
    /// The body link; its +x axis is the heading.
    #[serde(default = "default_base")]
    pub base_link: String,
    /// Rear left wheel's continuous joint (driven).
    #[serde(default = "rear_left")]
    pub rear_left_wheel_joint: String,
    /// Rear right wheel's continuous joint (driven).
    #[serde(default = "rear_right")]
    pub rear_right_wheel_joint: String,
    /// Front left steering joint (revolute about the vertical).
    #[serde(default = "steer_left")]
    pub front_left_steer_joint: String,
    /// Front right steering joint.
    #[serde(default = "steer_right")]
    pub front_right_steer_joint: String,
    /// Front left wheel's continuous joint (passive).
    #[serde(default = "front_left")]
    pub front_left_wheel_joint: String,
    /// Front right wheel's continuous joint (passive).
    #[serde(default = "front_right")]
    pub front_right_wheel_joint: String,
    /// Fixed obstacles (boxes, vertical cylinders): `[[model.obstacles]]`.
    #[serde(default)]
    pub obstacles: Vec<SolidObstacleConfig>,
    /// Within this distance (m) and heading difference (degrees) of the goal
    /// the robot has reached it (`ideal_time_to_goal`, `sim_time_to_goal`:
    /// the first such time).
    #[serde(default = "default_goal_tolerance")]
    pub goal_tolerance: [f64; 2],
}

fn default_wheelbase() -> f64 {
    0.32
}
fn default_max_steer() -> f64 {
    25.0
}
fn default_base() -> String {
    phys::BASE.into()
}
fn rear_left() -> String {
    phys::REAR[0].into()
}
fn rear_right() -> String {
    phys::REAR[1].into()
}
fn steer_left() -> String {
    phys::STEER[0].into()
}
fn steer_right() -> String {
    phys::STEER[1].into()
}
fn front_left() -> String {
    phys::FRONT[0].into()
}
fn front_right() -> String {
    phys::FRONT[1].into()
}

struct Car {
    model: Bicycle,
    names: CarNames,
    world: World,
}

/// Build the car system.
pub fn build(cfg: &CarConfig) -> Result<Box<dyn System>, SetupError> {
    // Written to also reject NaN (the scenario parser already rejects it).
    if cfg.wheelbase.is_nan() || cfg.wheelbase <= 0.0 {
        return Err(SetupError::key("model.wheelbase", "must be > 0"));
    }
    if !(cfg.max_steer_deg > 0.0 && cfg.max_steer_deg < 90.0) {
        return Err(SetupError::key("model.max_steer_deg", "must be in (0, 90)"));
    }
    check_names(&[
        ("base_link", &cfg.base_link),
        ("rear_left_wheel_joint", &cfg.rear_left_wheel_joint),
        ("rear_right_wheel_joint", &cfg.rear_right_wheel_joint),
        ("front_left_steer_joint", &cfg.front_left_steer_joint),
        ("front_right_steer_joint", &cfg.front_right_steer_joint),
        ("front_left_wheel_joint", &cfg.front_left_wheel_joint),
        ("front_right_wheel_joint", &cfg.front_right_wheel_joint),
    ])?;
    Ok(Box::new(Car {
        model: Bicycle {
            wheelbase: cfg.wheelbase,
            max_steer: cfg.max_steer_deg.to_radians(),
            steering: cfg.steering,
        },
        names: CarNames {
            base: cfg.base_link.clone(),
            rear: [
                cfg.rear_left_wheel_joint.clone(),
                cfg.rear_right_wheel_joint.clone(),
            ],
            steer: [
                cfg.front_left_steer_joint.clone(),
                cfg.front_right_steer_joint.clone(),
            ],
            front: [
                cfg.front_left_wheel_joint.clone(),
                cfg.front_right_wheel_joint.clone(),
            ],
        },
        world: World::new(&cfg.obstacles, cfg.goal_tolerance)?,
    }))
}

impl System for Car {
    fn model(&self) -> &dyn KinematicModel {
        &self.model
    }
    /// v in m/s, φ' in rad/s or φ in rad (for built-in open-loop planners;
    /// plan files and external laws set their own).
    fn default_max_rate(&self) -> Vec<f64> {
        match self.model.steering {
            Steering::Rate => vec![0.5, 1.0],
            Steering::Angle => vec![0.5, self.model.max_steer],
        }
    }
    fn plan(&self, _start: &State, _goal: &State, _limits: &Limits) -> Result<Plan, PlanError> {
        Err(no_planner("car"))
    }
    fn goal_heading(&self, goal: &State) -> Option<f64> {
        Some(goal[2])
    }
    fn urdf_names(&self) -> Vec<Named> {
        let n = &self.names;
        let names = [
            &n.base,
            &n.rear[0],
            &n.rear[1],
            &n.steer[0],
            &n.steer[1],
            &n.front[0],
            &n.front[1],
        ];
        REQUIRED
            .iter()
            .zip(names)
            .map(|(required, name)| Named {
                required,
                name: name.clone(),
            })
            .collect()
    }
    fn physics(
        &self,
        robot: &urdf_rs::Robot,
        urdf_dir: &Path,
        start: &[f64],
        sim: &PhysicsSettings,
    ) -> Result<Box<dyn PhysicsSystem>, SetupError> {
        let inner = CarPhysics::new(robot, urdf_dir, &self.names, &self.model, start, sim)?;
        self.world.physics(Box::new(inner), sim)
    }
    /// Its wheels can wear or differ from the URDF (`wheel_radius_scale`).
    fn exposure(&self, plan: &Plan) -> Exposure {
        Exposure {
            wheels: true,
            ..Exposure::of(plan)
        }
    }
    fn extra_metric_names(&self) -> Vec<String> {
        let mut out: Vec<String> = SLIP_METRICS.map(String::from).to_vec();
        out.push("steer_clipped_fraction".into());
        out.extend(self.world.metric_names());
        out
    }
    fn overlays(&self, _start: &State, _goal: &State) -> Vec<crate::record::Overlay> {
        self.world.overlays()
    }
    /// Slip maxima, the fraction of the ideal run's samples at which the
    /// plan asked to steer past the limit (a rate pushing past it, which the
    /// model dropped, or an angle beyond it, which the model stopped at the
    /// limit), time to goal, and with obstacles clearance and contacts.
    fn extra_metrics(
        &self,
        goal: &State,
        ideal: &Trajectory,
        sim: &SimTrajectory,
        _cmp: &Comparison,
    ) -> Vec<(String, f64)> {
        let mut out = slip_metrics(sim);
        let n = ideal.q.len().saturating_sub(1);
        let clipped = (0..n)
            .filter(|&k| self.model.sample_clipped(&ideal.q[k], &ideal.u[k]))
            .count();
        let frac = if n == 0 {
            0.0
        } else {
            clipped as f64 / n as f64
        };
        out.push(("steer_clipped_fraction".into(), frac));
        out.extend(self.world.metrics(goal, ideal, sim));
        out
    }
}
