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

pub mod geometric;
pub mod kinematics;
pub mod physics;
#[cfg(test)]
mod test_support;
pub mod triangle;

use crate::compare::sample;
use crate::engine::perturb::Exposure;
use crate::engine::PhysicsSettings;
use crate::engine::PhysicsSystem;
use crate::error::SetupError;
use crate::integrate::Trajectory;
use crate::metric::{m, tracking, Direction::*, Family::*, Metric, Unit};
use crate::model::{KinematicModel, State};
use crate::paper::{detail, rows_from, same, PaperRow};
use crate::plan::{Limits, Plan};
use crate::planner::PlanError;
use crate::record::{Comparison, Overlay, SimTrajectory};
use crate::robots::rolling_sphere::geometric::{ArcDirection, SphereGeometricParams};
use crate::robots::rolling_sphere::kinematics::{
    euler_state_to_quat_state, geodesic_angle, quat_of_state, quat_state_to_euler_state,
    RollingSphere, RollingSphereQuat,
};
use crate::robots::rolling_sphere::physics::SpherePhysics;
use crate::robots::rolling_sphere::triangle::SphereTriangleParams;
use crate::robots::System;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// A sphere rolling without slipping on a plane (seed 003), its orientation
/// written as Euler angles in scenario files.
#[derive(Debug, Clone, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SphereConfig {
    /// Sphere radius, m (must match the URDF ball).
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub radius: f64,
    /// URDF file, relative to the scenario file.
    pub urdf: PathBuf,
}

/// The sphere's planners, with their parameters.
#[derive(Debug, Clone)]
pub enum SpherePlanner {
    /// Seed 003 §3 geometric (A)-(B)-(A) planner.
    Geometric(SphereGeometricParams),
    /// Seed 003 §4 spherical-triangle planner.
    Triangle(SphereTriangleParams),
}

use SpherePlanner as Planner;

/// The sphere's own metrics: orientation errors as one angle.
pub const METRICS: &[Metric] = &[
    m(
        "{run}_goal_orientation_deg",
        Unit::Degree,
        LowerIsBetter,
        EndOnly,
        "Angle between the ball's final orientation and the goal's.",
    ),
    tracking(
        "tracking_orientation_deg_max",
        Unit::Degree,
        RunningMax,
        "Largest angle between the two runs' orientations.",
    ),
    tracking(
        "tracking_orientation_deg_rms",
        Unit::Degree,
        EndOnly,
        "RMS angle between the two runs' orientations.",
    ),
    tracking(
        "tracking_orientation_deg_final",
        Unit::Degree,
        EndOnly,
        "Angle between the two runs' final orientations.",
    ),
];

struct Sphere {
    euler: RollingSphere,
    quat: RollingSphereQuat,
    planner: Planner,
}

/// Build the sphere system.
pub fn build(cfg: &SphereConfig, planner: SpherePlanner) -> Result<Box<dyn System>, SetupError> {
    if !(cfg.radius > 0.0 && cfg.radius.is_finite()) {
        return Err(SetupError::key("model.radius", "must be > 0"));
    }
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
pub(crate) fn orientation_tracking(ideal: &Trajectory, sim: &Trajectory, grid: &[f64]) -> Vec<f64> {
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
    /// The ball is the wheel: its rolling radius can differ (`wheel_radius_scale`).
    fn exposure(&self, plan: &Plan) -> Exposure {
        Exposure {
            wheels: true,
            ..Exposure::of(plan)
        }
    }
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
        let traces = triangle::triangle_traces(&self.euler, &s, &g, p, 24).unwrap_or_default();
        let scale = 1.01 * self.euler.a;
        traces
            .into_iter()
            .enumerate()
            .map(|(k, tri)| Overlay {
                name: format!("triangle_{}", k + 1),
                points: tri.iter().map(|v| v.map(|c| c * scale)).collect(),
                link: Some(crate::robots::rolling_sphere::physics::BALL.to_string()),
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
            Planner::Geometric(p) => geometric::plan(&self.euler, &s, &g, p, limits),
            Planner::Triangle(p) => triangle::plan(&self.euler, &s, &g, p, limits),
        }
    }
    fn urdf_names(&self) -> Vec<crate::engine::required::Named> {
        crate::engine::required::defaults(&crate::robots::rolling_sphere::physics::REQUIRED)
    }
    fn physics(
        &self,
        robot: &urdf_rs::Robot,
        urdf_dir: &Path,
        start: &[f64],
        sim: &PhysicsSettings,
    ) -> Result<Box<dyn PhysicsSystem>, SetupError> {
        Ok(Box::new(SpherePhysics::new(
            robot,
            urdf_dir,
            self.euler.a,
            start,
            sim,
        )?))
    }
    /// Seed 003 §5.1 (geometric, (5, 5, −60°, 45°, −30°) → origin upright, ccw) and §5.2
    /// (one spherical triangle, d = 1.8, φ = 56.31°, α = −90°, ψ = φ + 10°).
    fn paper(&self, start: &State, goal: &State, plan: &Plan) -> Vec<PaperRow> {
        const DEG: f64 = 180.0 / std::f64::consts::PI;
        let d = &plan.details;
        if (self.euler.a - 1.0).abs() > 1e-12 {
            return Vec::new();
        }
        match &self.planner {
            Planner::Geometric(p) => {
                let s = quat_state_to_euler_state(start);
                let e: Vec<f64> = (2..5).map(|i| s[i] * DEG).collect();
                let at_origin_upright = goal[0].abs() < 1e-9
                    && goal[1].abs() < 1e-9
                    && geodesic_angle(
                        &quat_of_state(goal),
                        &quat_of_state(&State::from_vec(vec![0.0, 0.0, 1.0, 0.0, 0.0, 0.0])),
                    ) < 1e-9;
                let task = same(&[s[0], s[1]], &[5.0, 5.0], 1e-9)
                    && same(&e, &[-60.0, 45.0, -30.0], 1e-6)
                    && at_origin_upright
                    && p.direction == ArcDirection::Ccw;
                if !task {
                    return Vec::new();
                }
                const TRUNC: &str = "truncated";
                rows_from(
                    d,
                    &[
                        ("x_i (Eq. 24)", "4.61", "/x_i", 1.0, "m", ""),
                        ("y_i (Eq. 24)", "5.68", "/y_i", 1.0, "m", ""),
                        ("β_i (Eq. 25)", "−90", "/beta_i_deg", 1.0, "deg", ""),
                        ("r (Eq. 26)", "7.07", "/r", 1.0, "m", "7.07 = √50 is the distance from (x0, y0); Eq. 13 gives 7.31, the only value that reproduces the printed Δα, θ', C"),
                        ("Δβ", "−630", "/delta_beta_deg", 1.0, "deg", "−3.5π: the direct π/2 and π/2 − 2π have no ccw solution"),
                        ("Δα (Eq. 27)", "2.56", "/delta_alpha_deg", 1.0 / DEG, "rad", ""),
                        ("Δα (Eq. 27)", "146.7", "/delta_alpha_deg", 1.0, "deg", TRUNC),
                        ("θ' (Eq. 27)", "1.38", "/theta_prime_deg", 1.0 / DEG, "rad", ""),
                        ("θ' (Eq. 27)", "79.1", "/theta_prime_deg", 1.0, "deg", ""),
                        ("C x (Eq. 28)", "3.15", "/center/0", 1.0, "m", ""),
                        ("C y (Eq. 28)", "2.15", "/center/1", 1.0, "m", ""),
                        ("α_i (Eq. 15)", "67.5", "/alpha_i_deg", 1.0, "deg", TRUNC),
                    ],
                )
            }
            Planner::Triangle(p) => {
                let near = |ptr: &str, v: f64, tol: f64| {
                    detail(d, ptr).is_some_and(|x| (x - v).abs() <= tol)
                };
                let one = d["triangles"].as_array().is_some_and(|t| t.len() == 1);
                let task = p.psi_offset_deg.is_some_and(|o| (o - 10.0).abs() < 1e-9)
                    && one
                    && near("/d", 1.8, 1e-3)
                    && near("/phi_deg", 56.31, 5e-3)
                    && near("/alpha_deg", -90.0, 1e-6);
                if !task {
                    return Vec::new();
                }
                const INCONSISTENT: &str = "the printed triangle is not self-consistent (Napier on the printed a, b, C gives B = 70.76°, area 89.98° instead of 90°)";
                rows_from(
                    d,
                    &[
                        (
                            "ψ = φ + 10° (Eq. 30)",
                            "66.31",
                            "/triangles/0/psi_deg",
                            1.0,
                            "deg",
                            "",
                        ),
                        ("side a", "1.862", "/triangles/0/a", 1.0, "rad", ""),
                        ("side b", "1.198", "/triangles/0/b", 1.0, "rad", ""),
                        ("side c", "1.760", "/triangles/0/c", 1.0, "rad", ""),
                        (
                            "angle A",
                            "103.81",
                            "/triangles/0/A_deg",
                            1.0,
                            "deg",
                            INCONSISTENT,
                        ),
                        ("angle B", "70.78", "/triangles/0/B_deg", 1.0, "deg", ""),
                        (
                            "angle C",
                            "95.41",
                            "/triangles/0/C_deg",
                            1.0,
                            "deg",
                            INCONSISTENT,
                        ),
                    ],
                )
            }
        }
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
