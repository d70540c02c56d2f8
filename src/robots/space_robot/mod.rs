//! The free-floating planar space robot (seed 000 §4.1, seed 001 §5):
//! `models/space_robot.urdf`, planners `stokes_space` (seed 000 §4.1) and
//! `endogenous` (seed 001).
//!
//! Both planners drive the joints (θ1', θ2'); the vehicle angle θ0 moves only
//! by conservation of angular momentum. The ideal run integrates seed 000's
//! Eq. 13 ([`SpaceRobotModel`], state (θ0, θ1, θ2)) for both planners: the
//! endogenous planner plans on seed 001's Eq. 29 ([`SpaceManipulator`],
//! state (φ, θ1, θ2), p = 0), which is the same vector field (tested in
//! `model::space_manipulator`), so metric names are the same for every
//! space-robot scenario.
//!
//! Extra metrics (from the physics channels, maxima over the whole run):
//! `max_abs_angular_momentum` (|L_z| about the system CoM, kg m²/s),
//! `max_angular_momentum_out_of_plane`, `max_linear_momentum` (kg m/s),
//! `max_com_drift` (m), `max_out_of_plane` (m or rad), `max_contact_pairs`.
//! Endogenous plans with via points also report `ideal_via_error_deg` and
//! `sim_via_error_deg`: the largest coordinate error (deg, wrapped) at the
//! via times T, 2T, ….

pub mod kinematics;
pub mod manipulator;
pub mod physics;
pub mod stokes;

#[cfg(test)]
mod endogenous_tests;

use crate::compare::{coord_error, sample};
use crate::engine::perturb::Exposure;
use crate::engine::PhysicsSettings;
use crate::engine::PhysicsSystem;
use crate::error::SetupError;
use crate::integrate::Trajectory;
use crate::metric::{m, Direction::*, Family::*, Metric, Unit};
use crate::model::{KinematicModel, State};
use crate::paper::{rows_from, same, PaperRow};
use crate::plan::{Limits, Plan};
use crate::planner::endogenous::{self, EndogenousParams, EndogenousSystem, Fixed, Linearization};
use crate::planner::PlanError;
use crate::record::Comparison;
use crate::record::SimTrajectory;
use crate::robots::space_robot::kinematics::{SpaceRobot, SpaceRobotModel};
use crate::robots::space_robot::manipulator::SpaceManipulator;
use crate::robots::space_robot::physics::SpaceRobotPhysics;
use crate::robots::space_robot::stokes::{FixedSide, StokesSpaceParams};
use crate::robots::System;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// A free-floating planar space robot with a two-link arm (seeds 000 §4.1 and
/// 001): the vehicle turns through the arm's motion alone. The robot is seed
/// 000's table; the URDF must match it (the physics checks).
#[derive(Debug, Clone, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SpaceRobotConfig {
    /// URDF file, relative to the scenario file.
    pub urdf: PathBuf,
}

/// The space robot's planners, with their parameters.
#[derive(Debug, Clone)]
pub enum SpacePlanner {
    /// Seed 000 §4.1 Stokes planner.
    Stokes(StokesSpaceParams),
    /// Seed 001 endogenous-configuration-space planner.
    Endogenous(EndogenousParams),
}

use SpacePlanner as Planner;

/// The space robot's own metrics: momentum conservation, planarity, via points.
pub const METRICS: &[Metric] = &[
    m(
        "{run}_via_error_deg",
        Unit::Degree,
        LowerIsBetter,
        EndOnly,
        "Largest error at a via point (seed 001), deg.",
    ),
    m(
        "max_abs_angular_momentum",
        Unit::AngularMomentum,
        LowerIsBetter,
        RunningMax,
        "Largest |angular momentum| of the free-floating system in physics (0 in the model).",
    ),
    m(
        "max_angular_momentum_out_of_plane",
        Unit::AngularMomentum,
        LowerIsBetter,
        RunningMax,
        "Largest out-of-plane angular momentum in physics.",
    ),
    m(
        "max_linear_momentum",
        Unit::LinearMomentum,
        LowerIsBetter,
        RunningMax,
        "Largest |linear momentum| in physics (0 in the model).",
    ),
    m(
        "max_com_drift",
        Unit::Meter,
        LowerIsBetter,
        RunningMax,
        "Largest drift of the centre of mass in physics.",
    ),
    m(
        "max_out_of_plane",
        Unit::Meter,
        LowerIsBetter,
        RunningMax,
        "Largest motion out of the plane in physics.",
    ),
    m(
        "max_contact_pairs",
        Unit::Count,
        LowerIsBetter,
        RunningMax,
        "Most contact pairs at any step (the links must not touch).",
    ),
];

struct Space {
    model: SpaceRobotModel,
    planner: Planner,
}

/// Channel name → metric name (maximum of |value| over the run).
const CHANNEL_METRICS: [(&str, &str); 6] = [
    ("angular_momentum_z", "max_abs_angular_momentum"),
    (
        "angular_momentum_out_of_plane",
        "max_angular_momentum_out_of_plane",
    ),
    ("linear_momentum_norm", "max_linear_momentum"),
    ("com_drift", "max_com_drift"),
    ("out_of_plane", "max_out_of_plane"),
    ("contact_pairs", "max_contact_pairs"),
];

/// Build the space-robot system.
pub fn build(
    _cfg: &SpaceRobotConfig,
    planner: SpacePlanner,
) -> Result<Box<dyn System>, SetupError> {
    if let Planner::Endogenous(p) = &planner {
        if p.via_deg
            .iter()
            .any(|v| v.len() != 3 || v.iter().any(|x| !x.is_finite()))
        {
            return Err(SetupError::key(
                "planner.via_deg",
                "each via point needs 3 finite angles (θ0, θ1, θ2) in degrees",
            ));
        }
        if !(p.segment_time.is_finite() && p.segment_time > 0.0) {
            return Err(SetupError::key("planner.segment_time", "must be > 0"));
        }
    }
    Ok(Box::new(Space {
        model: SpaceRobotModel::default(),
        planner,
    }))
}

impl Space {
    fn via(&self) -> Vec<(f64, State)> {
        match &self.planner {
            Planner::Endogenous(p) => p
                .via_deg
                .iter()
                .enumerate()
                .map(|(k, v)| {
                    (
                        (k + 1) as f64 * p.segment_time,
                        State::from_iterator(3, v.iter().map(|x| x.to_radians())),
                    )
                })
                .collect(),
            Planner::Stokes(_) => Vec::new(),
        }
    }
}

/// Seed 001's Eq. 29 for the endogenous planner: its analytic
/// linearisation (one cos/sin per call).
impl EndogenousSystem for SpaceManipulator {
    type Dims = Fixed<3, 2>;
    fn dims(&self) -> Fixed<3, 2> {
        Fixed
    }
    #[inline]
    fn linearize(&self, q: &[f64], u: &[f64], out: &mut Linearization) {
        let l = SpaceManipulator::linearize(
            self,
            &nalgebra::Vector3::new(q[0], q[1], q[2]),
            &nalgebra::Vector2::new(u[0], u[1]),
        );
        let (qdot, a, b) = (&mut out.qdot[..3], &mut out.a[..9], &mut out.b[..6]);
        for r in 0..3 {
            qdot[r] = l.qdot[r];
            for c in 0..3 {
                a[r * 3 + c] = l.a[(r, c)];
            }
            for c in 0..2 {
                b[r * 2 + c] = l.g[(r, c)];
            }
        }
    }
    fn error_unit(&self) -> &'static str {
        " rad"
    }
}

/// The endogenous planner on the space manipulator: start → via points
/// (`params.via_deg`, degrees) → goal, one segment of `segment_time` each.
/// States are (φ, θ1, θ2) in rad.
pub fn plan_endogenous(
    model: &SpaceManipulator,
    start: &State,
    goal: &State,
    params: &EndogenousParams,
    limits: &Limits,
) -> Result<Plan, PlanError> {
    let invalid = |name: &str, reason: &str| PlanError::InvalidParameter {
        name: name.into(),
        reason: reason.into(),
    };
    model
        .validate()
        .map_err(|r| invalid("model", &r.to_string()))?;
    let three = |name: &str, v: &State| -> Result<Vec<f64>, PlanError> {
        if v.len() != 3 || v.iter().any(|x| !x.is_finite()) {
            return Err(invalid(
                name,
                "needs 3 finite coordinates (phi, theta1, theta2)",
            ));
        }
        Ok(v.as_slice().to_vec())
    };
    let q0 = three("start", start)?;
    let mut targets: Vec<Vec<f64>> = Vec::new();
    for v in &params.via_deg {
        if v.len() != 3 || v.iter().any(|x| !x.is_finite()) {
            return Err(invalid("via_deg", "each via point needs 3 finite angles"));
        }
        targets.push(v.iter().map(|x| x.to_radians()).collect());
    }
    targets.push(three("goal", goal)?);
    if !limits.max_rate.is_empty() && limits.max_rate.len() != 2 {
        return Err(invalid("limits.max_rate", "needs one entry per input (2)"));
    }
    let sol = endogenous::solve(model, &q0, &targets, params)?;
    endogenous::check_rate_limits(&sol, params, limits, &["u1", "u2"], " rad/s")?;
    Ok(endogenous::into_plan(
        sol,
        params,
        2,
        serde_json::json!({ "model": model.name() }),
    ))
}

fn manipulator(r: &SpaceRobot) -> SpaceManipulator {
    use crate::robots::space_robot::manipulator::SpaceManipulatorParams;
    SpaceManipulator::new(SpaceManipulatorParams {
        m0: r.m0,
        i0: r.i0,
        m1: r.m1,
        i1: r.i1,
        l1: r.l1,
        d1: 0.5 * r.l1,
        m2: r.m2,
        i2: r.i2,
        l2: r.l2,
        d2: 0.5 * r.l2,
        p: 0.0,
    })
}

impl System for Space {
    /// Free-floating: nothing touches anything, so friction does not apply.
    fn exposure(&self, plan: &Plan) -> Exposure {
        Exposure {
            friction: false,
            ..Exposure::of(plan)
        }
    }
    fn model(&self) -> &dyn KinematicModel {
        &self.model
    }
    fn default_max_rate(&self) -> Vec<f64> {
        vec![1.0, 1.0]
    }
    fn plan(&self, start: &State, goal: &State, limits: &Limits) -> Result<Plan, PlanError> {
        match &self.planner {
            Planner::Stokes(p) => stokes::plan(&self.model, start, goal, p, limits),
            Planner::Endogenous(p) => {
                plan_endogenous(&manipulator(&self.model.robot), start, goal, p, limits)
            }
        }
    }
    fn urdf_names(&self) -> Vec<crate::engine::required::Named> {
        crate::engine::required::defaults(&crate::robots::space_robot::physics::REQUIRED)
    }
    fn physics(
        &self,
        robot: &urdf_rs::Robot,
        urdf_dir: &Path,
        start: &[f64],
        sim: &PhysicsSettings,
    ) -> Result<Box<dyn PhysicsSystem>, SetupError> {
        let p = SpaceRobotPhysics::new(robot, urdf_dir, &self.model.robot, start, sim)?;
        Ok(Box::new(p))
    }
    /// Seed 000 §4.1's example ((0°, 15°, 15°) → (−20°, 45°, 0°)) with λ = 125° or
    /// γ = 75°. Seed 001 prints no numbers for its tasks (only qualitative claims).
    fn paper(&self, start: &State, goal: &State, plan: &Plan) -> Vec<PaperRow> {
        let Planner::Stokes(p) = &self.planner else {
            return Vec::new();
        };
        let deg = |v: &[f64]| v.iter().map(|x| x.to_radians()).collect::<Vec<_>>();
        if !(same(start.as_slice(), &deg(&[0.0, 15.0, 15.0]), 1e-9)
            && same(goal.as_slice(), &deg(&[-20.0, 45.0, 0.0]), 1e-9))
        {
            return Vec::new();
        }
        let mut spec = vec![
            ("A (Eq. 19)", "−89.848", "/A", 1.0, "", ""),
            ("B (Eq. 19)", "−13.92", "/B", 1.0, "", "truncated"),
            (
                "θ0 drift along OA, θ0d",
                "−12.87",
                "/theta0_d_deg",
                1.0,
                "deg",
                "",
            ),
            (
                "θ0 left for the cycles, θ̄0",
                "−7.13",
                "/theta0_bar_deg",
                1.0,
                "deg",
                "",
            ),
            ("k (Eq. 20)", "−7.696e-4", "/k", 1.0, "", ""),
        ];
        // The paper's rows for the rectangle the planner chose (auto included).
        let chose = |side: &str, v: f64| {
            let want = format!("{side} = {:.3}°", v);
            plan.details["choice"]
                .as_str()
                .is_some_and(|c| c.starts_with(&want))
        };
        let side = match p.fixed_side {
            FixedSide::Lambda => "λ",
            FixedSide::Gamma => "γ",
            FixedSide::Auto => "",
        };
        let fixed = p.fixed_deg().unwrap_or(f64::NAN);
        let lambda = (side == "λ" && (fixed - 125.0).abs() < 1e-9) || chose("λ", 125.0);
        let gamma = (side == "γ" && (fixed - 75.0).abs() < 1e-9) || chose("γ", 75.0);
        match (lambda, gamma) {
            (true, _) => spec.extend([
                (
                    "γ for λ = 125° (3 cycles)",
                    "53.36",
                    "/gamma_deg",
                    1.0,
                    "deg",
                    "truncated (53.3679°)",
                ),
                (
                    "γ for λ = 125° (3 cycles)",
                    "0.596",
                    "/gamma_deg",
                    1f64.to_radians(),
                    "rad",
                    "0.5967 is cos γ; γ = 0.931 rad",
                ),
            ]),
            (_, true) => spec.push((
                "λ for γ = 75° (4 cycles)",
                "76.084",
                "/lambda_deg",
                1.0,
                "deg",
                "follows from the rounded θ̄0 = −7.13°",
            )),
            _ => {}
        }
        rows_from(&plan.details, &spec)
    }
    fn extra_metric_names(&self) -> Vec<String> {
        let mut out: Vec<String> = CHANNEL_METRICS.iter().map(|(_, m)| m.to_string()).collect();
        if !self.via().is_empty() {
            out.push("ideal_via_error_deg".into());
            out.push("sim_via_error_deg".into());
        }
        out
    }
    fn extra_metrics(
        &self,
        _goal: &State,
        ideal: &Trajectory,
        sim: &SimTrajectory,
        _cmp: &Comparison,
    ) -> Vec<(String, f64)> {
        let mut out = Vec::new();
        for (channel, metric) in CHANNEL_METRICS {
            let v = sim
                .channel(channel)
                .map(|s| s.iter().fold(0.0_f64, |m, v| m.max(v.abs())))
                .unwrap_or(f64::NAN);
            out.push((metric.to_string(), v));
        }
        let via = self.via();
        if !via.is_empty() {
            let angular = self.model.angular_states();
            let err = |traj: &Trajectory| {
                via.iter()
                    .map(|(t, y)| {
                        coord_error(y, &sample(traj, *t), angular)
                            .iter()
                            .fold(0.0_f64, |m, e| m.max(e.abs()))
                    })
                    .fold(0.0_f64, f64::max)
                    .to_degrees()
            };
            out.push(("ideal_via_error_deg".into(), err(ideal)));
            out.push(("sim_via_error_deg".into(), err(&sim.traj)));
        }
        out
    }
}
