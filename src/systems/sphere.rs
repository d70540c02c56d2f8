//! The rolling sphere (ball-plate problem): seed 003 §3 geometric and §4 spherical-triangle
//! planners, `models/sphere.urdf`.
//!
//! Charts. Scenario files write `start`/`goal` in the paper's coordinates
//! (x, y, α, θ, φ) (z-y-z Euler angles, degrees): [`System::file_model`] is the Euler model
//! [`RollingSphere`]. That chart is singular at θ = 0, exactly where the paper's goal (P
//! upright) sits, so the harness integrates, replays and compares the singularity-free
//! quaternion model [`RollingSphereQuat`], state (x, y, qw, qx, qy, qz):
//! [`System::state_from_file`] converts once at load time, and the planners (which work in
//! the Euler chart) get the states converted back (at θ = 0 only α + φ is defined; the
//! planners only use that sum there).
//!
//! Metrics. Per-coordinate errors of quaternion components are not angles, so the system adds
//! the geodesic orientation error on SO(3): `ideal_goal_orientation_deg`,
//! `sim_goal_orientation_deg` and `tracking_orientation_deg_{rms,max,final}` (ideal vs
//! simulated orientation on the common dt grid). Position metrics come from (x, y).

use super::{mismatch, System};
use crate::compare::sample;
use crate::integrate::Trajectory;
use crate::model::rolling_sphere::{
    euler_state_to_quat_state, geodesic_angle, quat_of_state, quat_state_to_euler_state,
    RollingSphere, RollingSphereQuat,
};
use crate::model::{KinematicModel, State};
use crate::physics::sphere::SpherePhysics;
use crate::physics::PhysicsSettings;
use crate::physics::PhysicsSystem;
use crate::plan::{Limits, Plan};
use crate::planner::sphere_geometric::{self, SphereGeometricParams};
use crate::planner::sphere_triangle::{self, SphereTriangleParams};
use crate::planner::PlanError;
use crate::record::{Comparison, Overlay, SimTrajectory};
use crate::scenario::PlannerConfig;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// `[model] kind = "rolling_sphere"`.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SphereConfig {
    /// Sphere radius, m (must match the URDF ball).
    pub radius: f64,
    /// URDF file, relative to the scenario file.
    pub urdf: PathBuf,
}

enum Planner {
    Geometric(SphereGeometricParams),
    Triangle(SphereTriangleParams),
}

struct Sphere {
    euler: RollingSphere,
    quat: RollingSphereQuat,
    planner: Planner,
}

/// Build the sphere system.
pub fn build(cfg: &SphereConfig, planner: &PlannerConfig) -> Result<Box<dyn System>, String> {
    if !(cfg.radius > 0.0 && cfg.radius.is_finite()) {
        return Err("key `model.radius`: must be > 0".into());
    }
    let planner = match planner {
        PlannerConfig::SphereGeometric(p) => Planner::Geometric(p.clone()),
        PlannerConfig::SphereTriangle(p) => Planner::Triangle(p.clone()),
        other => {
            return Err(mismatch(
                "rolling_sphere",
                other,
                &["sphere_geometric", "sphere_triangle"],
            ))
        }
    };
    Ok(Box::new(Sphere {
        euler: RollingSphere { a: cfg.radius },
        quat: RollingSphereQuat::new(cfg.radius),
        planner,
    }))
}

/// Metric names added by the sphere system.
pub const EXTRA_METRICS: [&str; 5] = [
    "ideal_goal_orientation_deg",
    "sim_goal_orientation_deg",
    "tracking_orientation_deg_rms",
    "tracking_orientation_deg_max",
    "tracking_orientation_deg_final",
];

/// Geodesic orientation error (rad) between two quaternion trajectories on
/// the comparison's time grid (each run held at its end).
pub fn orientation_tracking(ideal: &Trajectory, sim: &Trajectory, grid: &[f64]) -> Vec<f64> {
    grid.iter()
        .map(|&t| {
            geodesic_angle(
                &quat_of_state(&sample(ideal, t)),
                &quat_of_state(&sample(sim, t)),
            )
        })
        .collect()
}

impl System for Sphere {
    fn model(&self) -> &dyn KinematicModel {
        &self.quat
    }
    fn file_model(&self) -> &dyn KinematicModel {
        &self.euler
    }
    /// The spherical triangles the contact point traces on the ball (body
    /// frame, drawn just outside the shell so they move with the ball).
    fn overlays(&self, start: &State, goal: &State) -> Vec<Overlay> {
        let Planner::Triangle(p) = &self.planner else {
            return Vec::new();
        };
        let (s, g) = (
            quat_state_to_euler_state(start),
            quat_state_to_euler_state(goal),
        );
        let traces =
            sphere_triangle::triangle_traces(&self.euler, &s, &g, p, 24).unwrap_or_default();
        let scale = 1.01 * self.euler.a;
        traces
            .into_iter()
            .enumerate()
            .map(|(k, tri)| Overlay {
                name: format!("triangle_{}", k + 1),
                points: tri.iter().map(|v| v.map(|c| c * scale)).collect(),
                link: Some(crate::physics::sphere::BALL.to_string()),
                rgba: [0.95, 0.3, 0.6, 1.0],
            })
            .collect()
    }
    fn state_from_file(&self, q: Vec<f64>) -> Vec<f64> {
        if q.len() != 5 {
            return q; // length errors are reported by the scenario parser
        }
        euler_state_to_quat_state(&State::from_vec(q))
            .iter()
            .copied()
            .collect()
    }
    fn default_max_rate(&self) -> Vec<f64> {
        vec![1.0, 1.0]
    }
    fn plan(&self, start: &State, goal: &State, limits: &Limits) -> Result<Plan, PlanError> {
        let bad = |name: &str, q: &State| {
            if q.len() == 6 && q.iter().all(|v| v.is_finite()) && q.rows(2, 4).norm() > 0.5 {
                Ok(quat_state_to_euler_state(q))
            } else {
                Err(PlanError::InvalidParameter {
                    name: name.into(),
                    reason: "need (x, y, qw, qx, qy, qz) with a non-zero quaternion".into(),
                })
            }
        };
        let (s, g) = (bad("start", start)?, bad("goal", goal)?);
        match &self.planner {
            Planner::Geometric(p) => sphere_geometric::plan(&self.euler, &s, &g, p, limits),
            Planner::Triangle(p) => sphere_triangle::plan(&self.euler, &s, &g, p, limits),
        }
    }
    fn physics(
        &self,
        robot: &urdf_rs::Robot,
        urdf_dir: &Path,
        start: &[f64],
        sim: &PhysicsSettings,
    ) -> Result<Box<dyn PhysicsSystem>, String> {
        Ok(Box::new(SpherePhysics::new(
            robot,
            urdf_dir,
            self.euler.a,
            start,
            sim,
        )?))
    }
    fn extra_metric_names(&self) -> Vec<String> {
        EXTRA_METRICS.iter().map(|s| s.to_string()).collect()
    }
    fn extra_metrics(
        &self,
        goal: &State,
        ideal: &Trajectory,
        sim: &SimTrajectory,
        cmp: &Comparison,
    ) -> Vec<(String, f64)> {
        let g = quat_of_state(goal);
        let ideal_goal = geodesic_angle(&g, &quat_of_state(ideal.last()));
        let sim_goal = geodesic_angle(&g, &quat_of_state(sim.traj.last()));
        let (rms, max, fin) =
            crate::compare::stats(&orientation_tracking(ideal, &sim.traj, &cmp.t));
        [ideal_goal, sim_goal, rms, max, fin]
            .iter()
            .zip(EXTRA_METRICS)
            .map(|(v, n)| (n.to_string(), v.to_degrees()))
            .collect()
    }
}
