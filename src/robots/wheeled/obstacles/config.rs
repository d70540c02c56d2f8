//! What the wheeled systems (differential drive, car) share besides slip:
//! fixed obstacles from `[[model.obstacles]]` (boxes and vertical
//! cylinders, the keys of the mobile manipulator's table: `name`, `center`,
//! `semi_axes`, `rpy_deg`), their clearance and contact metrics, and the
//! time to goal.

use crate::engine::{PhysicsSettings, PhysicsSystem};
use crate::error::SetupError;
use crate::integrate::Trajectory;
use crate::model::State;
use crate::record::{Overlay, SimTrajectory};
use crate::robots::wheeled::obstacles::{Obstacle, Solid, WithObstacles};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// The solid of a `[[model.obstacles]]` entry.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum SolidKind {
    /// A box of half extents `semi_axes`.
    #[default]
    Box,
    /// A cylinder about its z axis: radius `semi_axes[0]` (= `semi_axes[1]`),
    /// half height `semi_axes[2]`.
    Cylinder,
}

/// One fixed obstacle as written in the scenario.
#[derive(Debug, Clone, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SolidObstacleConfig {
    /// Name (unique; used in messages and logs).
    pub name: String,
    /// `box` or `cylinder` (about its own z axis).
    #[serde(default)]
    pub shape: SolidKind,
    /// Centre, m (a box or cylinder standing on the ground has z = its half height).
    pub center: [f64; 3],
    /// Half extents along the obstacle's x, y, z, m (> 0); a cylinder's radius is x = y.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub semi_axes: [f64; 3],
    /// Orientation, URDF roll-pitch-yaw in degrees.
    #[serde(default)]
    pub rpy_deg: [f64; 3],
}

/// Default of `goal_tolerance`: 2 cm and 2 degrees.
pub(crate) fn default_goal_tolerance() -> [f64; 2] {
    [0.02, 2.0]
}

/// Clearance and contacts against obstacles, time to goal.
const OBSTACLE_METRICS: [&str; 2] = ["sim_min_clearance", "sim_obstacle_contacts"];
const TIME_METRICS: [&str; 2] = ["ideal_time_to_goal", "sim_time_to_goal"];

/// The obstacles and goal tolerance of a wheeled system.
#[derive(Debug, Clone, Default)]
pub struct World {
    obstacles: Vec<Obstacle>,
    /// Position, m, and heading, rad.
    tolerance: [f64; 2],
}

impl World {
    /// Validate the `[model]` keys.
    pub fn new(cfgs: &[SolidObstacleConfig], goal_tolerance: [f64; 2]) -> Result<Self, SetupError> {
        if !goal_tolerance.iter().all(|t| t.is_finite() && *t > 0.0) {
            return Err(SetupError::key(
                "model.goal_tolerance",
                "must be [metres, degrees], both > 0",
            ));
        }
        let mut obstacles = Vec::new();
        for (i, o) in cfgs.iter().enumerate() {
            let key = |field: &str| format!("model.obstacles[{i}].{field}");
            if o.name.is_empty() || cfgs[..i].iter().any(|p| p.name == o.name) {
                return Err(SetupError::key(
                    key("name"),
                    format!("`{}` is empty or not unique", o.name),
                ));
            }
            if !o.semi_axes.iter().all(|a| a.is_finite() && *a > 0.0) {
                return Err(SetupError::key(
                    key("semi_axes"),
                    "every half extent must be > 0",
                ));
            }
            if !o.center.iter().chain(&o.rpy_deg).all(|v| v.is_finite()) {
                return Err(SetupError::key(key("center"), "must be finite"));
            }
            let [a, b, c] = o.semi_axes;
            let solid = match o.shape {
                SolidKind::Box => Solid::Box { half: o.semi_axes },
                SolidKind::Cylinder if (a - b).abs() > 1e-12 * a.max(b) => {
                    return Err(SetupError::key(
                        key("semi_axes"),
                        format!("a cylinder is round: x and y (its radius) must be equal, not {a} and {b}"),
                    ))
                }
                SolidKind::Cylinder => Solid::Cylinder {
                    radius: a,
                    half_height: c,
                },
            };
            obstacles.push(Obstacle {
                name: o.name.clone(),
                center: o.center,
                rpy: o.rpy_deg.map(f64::to_radians),
                solid,
            });
        }
        Ok(World {
            obstacles,
            tolerance: [goal_tolerance[0], goal_tolerance[1].to_radians()],
        })
    }

    /// The model's physics, with the obstacles in its world when there are any.
    pub fn physics(
        &self,
        inner: Box<dyn PhysicsSystem>,
        sim: &PhysicsSettings,
    ) -> Result<Box<dyn PhysicsSystem>, SetupError> {
        if self.obstacles.is_empty() {
            return Ok(inner);
        }
        Ok(Box::new(WithObstacles::new(
            inner,
            &self.obstacles,
            sim.friction,
        )?))
    }

    /// Obstacle wireframes for the logs.
    pub fn overlays(&self) -> Vec<Overlay> {
        self.obstacles
            .iter()
            .flat_map(|o| o.wireframe([0.85, 0.2, 0.2, 1.0]))
            .collect()
    }

    /// Names of [`World::metrics`].
    pub fn metric_names(&self) -> Vec<String> {
        let mut out: Vec<String> = TIME_METRICS.map(String::from).to_vec();
        if !self.obstacles.is_empty() {
            out.extend(OBSTACLE_METRICS.map(String::from));
        }
        out
    }

    /// Time to goal of both runs (first time within `goal_tolerance`, s;
    /// NaN if never), and with obstacles the least clearance (m) and the
    /// most robot–obstacle contact pairs at any physics step.
    pub fn metrics(
        &self,
        goal: &State,
        ideal: &Trajectory,
        sim: &SimTrajectory,
    ) -> Vec<(String, f64)> {
        let mut out = vec![
            (TIME_METRICS[0].into(), self.time_to_goal(ideal, goal)),
            (TIME_METRICS[1].into(), self.time_to_goal(&sim.traj, goal)),
        ];
        if !self.obstacles.is_empty() {
            let ch = |n: &str| sim.channel(n).unwrap_or(&[]).to_vec();
            let clearance = ch("obstacle_clearance")
                .into_iter()
                .fold(f64::INFINITY, f64::min);
            let contacts = ch("obstacle_contacts").into_iter().fold(0.0, f64::max);
            out.push((OBSTACLE_METRICS[0].into(), clearance));
            out.push((OBSTACLE_METRICS[1].into(), contacts));
        }
        out
    }

    /// First time the pose (x, y, θ) is within the tolerance of the goal's.
    fn time_to_goal(&self, tr: &Trajectory, goal: &State) -> f64 {
        let [dp, dth] = self.tolerance;
        tr.q.iter()
            .zip(&tr.t)
            .find(|(q, _)| {
                let d = (q[0] - goal[0]).hypot(q[1] - goal[1]);
                let e = (q[2] - goal[2] + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                    - std::f64::consts::PI;
                d <= dp && e.abs() <= dth
            })
            .map(|(_, t)| *t)
            .unwrap_or(f64::NAN)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cfg(shape: SolidKind, semi_axes: [f64; 3]) -> SolidObstacleConfig {
        SolidObstacleConfig {
            name: "a".into(),
            shape,
            center: [0.0, 0.0, 0.1],
            semi_axes,
            rpy_deg: [0.0; 3],
        }
    }

    #[test]
    fn bad_obstacles_name_their_key() {
        let err =
            |c: Vec<SolidObstacleConfig>| World::new(&c, [0.02, 2.0]).unwrap_err().to_string();
        assert!(err(vec![cfg(SolidKind::Box, [0.1, 0.0, 0.1])]).contains("obstacles[0].semi_axes"));
        assert!(err(vec![cfg(SolidKind::Cylinder, [0.1, 0.2, 0.1])]).contains("round"));
        let twice = vec![cfg(SolidKind::Box, [0.1; 3]), cfg(SolidKind::Box, [0.1; 3])];
        assert!(err(twice).contains("obstacles[1].name"));
        assert!(World::new(&[], [0.0, 2.0])
            .unwrap_err()
            .to_string()
            .contains("goal_tolerance"));
    }

    #[test]
    fn time_to_goal_is_the_first_passage() {
        let w = World::new(&[], [0.02, 2.0]).unwrap();
        let tr = Trajectory {
            t: vec![0.0, 1.0, 2.0, 3.0],
            q: [
                [1.0, 0.0, 0.0],
                [0.01, 0.0, 0.1],
                [0.01, 0.0, 0.0],
                [0.5, 0.0, 0.0],
            ]
            .iter()
            .map(|q| State::from_vec(q.to_vec()))
            .collect(),
            ..Default::default()
        };
        let goal = State::from_vec(vec![0.0, 0.0, 0.0]);
        // 0.1 rad is 5.7 deg: not yet at t = 1.
        assert_eq!(w.time_to_goal(&tr, &goal), 2.0);
        let far = State::from_vec(vec![5.0, 0.0, 0.0]);
        assert!(w.time_to_goal(&tr, &far).is_nan());
    }
}
