//! Seed 004: mobile manipulators navigated by a dipolar inverse Lyapunov
//! function (`dilf` planner), `models/mobile_manipulator.urdf`.
//!
//! The plan is the feedback law of Eq. 18, evaluated every `period` on the
//! ideal state and, in physics, on the simulated state. Obstacles are
//! generalized ellipsoids written in the scenario (`[[model.obstacles]]`);
//! the planner avoids them as ellipsoids, the physics meets them as convex
//! colliders (their inscribed hulls).
//!
//! Extra metrics: `ideal_time_to_goal`, `sim_time_to_goal` (first time within
//! the planner's tolerance; NaN if never), `ideal_min_clearance` (least
//! distance between the URDF collision shapes placed by forward kinematics
//! and the obstacle colliders along the ideal run; the same parry queries as
//! the physics channel), `sim_min_clearance`, `sim_obstacle_contacts` (most
//! robot–obstacle contact pairs at any step; must be 0),
//! `ideal_min_obstacle_function` / `sim_min_obstacle_function` (least β of the
//! ellipsoid model, > 0 free), `ideal_vdot_violations` / `sim_vdot_violations`
//! (policy samples with V̇ < 0 under the applied input: the paper's V̇ ≥ 0
//! claim, Appendix G), `ideal_min_manipulability` / `sim_min_manipulability`
//! (least √det(JᵀJ) = |det J| of any arm at the policy samples, m³: the
//! singularity-avoidance claim), `slip_lateral_max`, `joint_rate_error_max`, `sim_max_tilt_deg` (largest
//! platform tilt, deg; `sim_max_tilt_2_deg` for robot 2), `ideal_stall_time` /
//! `sim_stall_time` (when the law declared a stall, s: no progress in V for
//! `planner.stall.time`, [`crate::robots::mobile_manipulator::dilf::stall`]; NaN if it never
//! did; informational: the verdict shows in the time to goal).

pub mod beam;
pub mod dilf;
pub mod ellipsoid;
pub mod kinematics;
pub mod physics;
pub mod puma560;

mod config;
mod grasp;
mod overlay;

pub use config::{
    ArmServoConfig, BeamConfig, BoundKind, MobileManipulatorConfig, ObstacleConfig, WristConfig,
    DEFAULT_MAX_FORCE, DEFAULT_MAX_MOMENT,
};

use crate::engine::perturb::Exposure;
use crate::engine::PhysicsSettings;
use crate::engine::PhysicsSystem;
use crate::error::SetupError;
use crate::integrate::Trajectory;
use crate::metric::{m, Direction::*, Family::*, Metric, Unit};
use crate::model::{KinematicModel, State};
use crate::plan::{Limits, Plan};
use crate::planner::PlanError;
use crate::record::{Comparison, LinkVisual, Overlay, Series, SimTrajectory};
use crate::robots::mobile_manipulator::beam::physics::BeamOptions;
use crate::robots::mobile_manipulator::dilf::control::{self, vdot_scaled, Gains};
use crate::robots::mobile_manipulator::dilf::object::Carried;
use crate::robots::mobile_manipulator::dilf::potential::{Obstacle, Scene, Warm};
use crate::robots::mobile_manipulator::dilf::DilfParams;
use crate::robots::mobile_manipulator::ellipsoid::Superellipsoid;
use crate::robots::mobile_manipulator::kinematics::{self as mm, MobileManipulator, Wrist};
use crate::robots::mobile_manipulator::physics::{
    link_visuals, robot_link_name, ArmServo, CarriedBeam, MobileManipulatorPhysics, ObstacleShape,
    Setup,
};
use crate::robots::{EarlyAnalysis, SimFollower, System};
use overlay::{wireframe, ClearanceProbe};
use std::path::Path;
use std::sync::Arc;

/// The mobile manipulators' own metrics: obstacles, the law's claims, the arms, the carried beam.
pub const METRICS: &[Metric] = &[
    m(
        "{run}_min_obstacle_function",
        Unit::Ratio,
        HigherIsBetter,
        RunningMin,
        "Least obstacle function β of the ellipsoid model (> 0: free).",
    ),
    m(
        "{run}_vdot_violations",
        Unit::Count,
        LowerIsBetter,
        RunningMax,
        "Policy samples with V̇ < 0 under the applied input (the paper claims none).",
    ),
    m(
        "{run}_min_manipulability",
        Unit::Ratio,
        HigherIsBetter,
        RunningMin,
        "Least manipulability |det J| of any arm at the policy samples, m³.",
    ),
    m(
        "{run}_stall_time",
        Unit::Second,
        Informational,
        EndOnly,
        "When the law declared a stall (NaN: never); the verdict shows in the time to goal.",
    ),
    m(
        "joint_rate_error_max",
        Unit::RadianPerSecond,
        LowerIsBetter,
        RunningMax,
        "Largest difference between a commanded and a simulated joint rate.",
    ),
    m(
        "sim_max_tilt_deg",
        Unit::Degree,
        LowerIsBetter,
        RunningMax,
        "Largest platform tilt in physics.",
    ),
    m(
        "sim_max_tilt_{n}_deg",
        Unit::Degree,
        LowerIsBetter,
        RunningMax,
        "Largest platform tilt of robot n in physics.",
    ),
    m(
        "sim_robot_clearance",
        Unit::Meter,
        HigherIsBetter,
        RunningMin,
        "Least distance between the two robots in physics.",
    ),
    m(
        "sim_body_contacts",
        Unit::Count,
        LowerIsBetter,
        RunningMax,
        "Most contacts between the robots' own bodies at any step.",
    ),
    m(
        "{run}_grasp_wrench_ratio",
        Unit::Ratio,
        LowerIsBetter,
        EndOnly,
        "Largest grasp wrench over its bound, |F|/F_max or |M|/M_max (below 1: kept).",
    ),
    m(
        "sim_grasp_force_max",
        Unit::Newton,
        LowerIsBetter,
        RunningMax,
        "Largest grasp force at any physics step.",
    ),
    m(
        "sim_grasp_torque_max",
        Unit::NewtonMeter,
        LowerIsBetter,
        RunningMax,
        "Largest grasp moment at any physics step.",
    ),
    m(
        "sim_wrist_travel_used",
        Unit::Fraction,
        LowerIsBetter,
        EndOnly,
        "Largest compliant-wrist deflection over its travel (1: at the stop).",
    ),
    m(
        "{run}_max_deformation",
        Unit::Meter,
        LowerIsBetter,
        RunningMax,
        "Largest deformation of the carried beam.",
    ),
    m(
        "sim_beam_max_deformation",
        Unit::Meter,
        LowerIsBetter,
        RunningMax,
        "Largest deformation of the physics beam.",
    ),
    m(
        "sim_beam_fe_gap",
        Unit::Meter,
        LowerIsBetter,
        EndOnly,
        "Largest gap between the physics beam and the finite-element model.",
    ),
];

struct Dilf {
    model: MobileManipulator,
    arm: ArmServo,
    arm_max_torque: Option<[f64; 6]>,
    arm_armature: [f64; 6],
    wrist: Wrist,
    beam: Option<BeamConfig>,
    params: DilfParams,
    obstacles: Vec<(String, Superellipsoid)>,
    probe: ClearanceProbe,
}

/// Build the mobile-manipulator system.
pub fn build(
    cfg: &MobileManipulatorConfig,
    params: &DilfParams,
) -> Result<Box<dyn System>, SetupError> {
    Ok(Box::new(dilf(cfg, params)?))
}

/// The potential's scene of a task (obstacles, goal, the beam grasped at
/// `start`), as the planner sees it: for benchmarks and tools.
pub fn task_scene(
    cfg: &MobileManipulatorConfig,
    params: &DilfParams,
    start: &[f64],
    goal: &State,
) -> Result<Scene, SetupError> {
    dilf(cfg, params)?.scene(start, goal)
}

fn dilf(cfg: &MobileManipulatorConfig, params: &DilfParams) -> Result<Dilf, SetupError> {
    match (cfg.robots, &cfg.beam) {
        (1, None) | (2, Some(_)) => {}
        (1, Some(_)) => {
            return Err(SetupError::key(
                "model.beam",
                "one robot cannot carry a beam (robots = 2)",
            ))
        }
        (2, None) => {
            return Err(SetupError::key(
                "model.robots",
                "two robots carry a beam: add [model.beam]",
            ))
        }
        (n, _) => {
            return Err(SetupError::key(
                "model.robots",
                format!("{n} robots (1 or 2)"),
            ))
        }
    }
    if let Some(b) = &cfg.beam {
        b.beam()?;
    }
    let arm = cfg.arm_servo.servo()?;
    let wrist = cfg.wrist.wrist()?;
    if cfg.robots == 1 && wrist != Wrist::Rigid {
        return Err(SetupError::key(
            "model.wrist",
            "a compliant wrist holds the carried beam (robots = 2)",
        ));
    }
    let mut obstacles = Vec::new();
    for (i, o) in cfg.obstacles.iter().enumerate() {
        let shape = o.shape();
        shape.validate().map_err(|e| {
            use crate::robots::mobile_manipulator::ellipsoid::ShapeError;
            let field = match &e {
                ShapeError::SemiAxes(_) => "semi_axes",
                ShapeError::ExponentLow(_) | ShapeError::ExponentHigh(_) => "exponent",
                ShapeError::NotFinite => "rpy_deg",
            };
            SetupError::key(format!("model.obstacles[{i}].{field}"), e)
        })?;
        if o.name.is_empty() || cfg.obstacles[..i].iter().any(|p| p.name == o.name) {
            return Err(SetupError::key(
                format!("model.obstacles[{i}].name"),
                format!("`{}` is empty or not unique", o.name),
            ));
        }
        obstacles.push((o.name.clone(), shape));
    }
    if let Err(crate::planner::PlanError::InvalidParameter { name, reason }) = params.validate() {
        return Err(SetupError::key(
            format!("planner.{name}"),
            reason.to_string(),
        ));
    }
    let params = params.clone();
    Ok(Dilf {
        model: MobileManipulator { robots: cfg.robots },
        arm,
        arm_max_torque: cfg.arm_servo.max_torque(),
        arm_armature: cfg.arm_servo.armature(),
        wrist,
        beam: cfg.beam.clone(),
        params,
        probe: ClearanceProbe::new(&obstacles),
        obstacles,
    })
}

impl Dilf {
    /// The scene for a task; `start` fixes the beam's grasps (it is straight there).
    fn scene(&self, start: &[f64], goal: &State) -> Result<Scene, SetupError> {
        let scene = self.scene_without_beam(goal)?;
        let Some(b) = &self.beam else {
            return Ok(scene);
        };
        let carried =
            Carried::at_rest(&b.beam()?, b.length, start, b.q_max(), b.segments, b.radius)
                .map_err(|e| {
                    let key = if b.length.is_some() {
                        "model.beam.length"
                    } else {
                        "start"
                    };
                    SetupError::key(key, e)
                })?
                .with_grasps(b.bound(), self.wrist)
                .map_err(|e| SetupError::key("model.beam", e))?;
        Ok(scene.with_object(carried.with_max_stretch(b.max_stretch)))
    }

    fn scene_without_beam(&self, goal: &State) -> Result<Scene, SetupError> {
        let p = &self.params;
        Scene::new(
            self.model.robots,
            mm::default_parts(),
            self.obstacles
                .iter()
                .map(|(name, s)| Obstacle {
                    name: name.clone(),
                    shape: s.at_rest(),
                })
                .collect(),
            goal.iter().copied().collect(),
            p.potential(),
        )
        .map_err(|e| SetupError::other(e.to_string()))
    }

    /// The beam as the physics holds it: the scene's grasps and FE beam.
    fn carried_beam(&self, scene: &Scene) -> Option<CarriedBeam> {
        let (c, cfg) = (scene.object.as_ref()?, self.beam.as_ref()?);
        Some(CarriedBeam {
            beam: *c.fe.beam(),
            grasp: c.grasp,
            options: BeamOptions {
                segments: cfg.physics_segments,
                ..BeamOptions::default()
            },
        })
    }

    /// When the law declared a stall along a trajectory (NaN if never).
    fn stall_time(&self, tr: &Trajectory) -> f64 {
        let stalled = dilf::label_index(self.model.robots, "stalled");
        tr.label
            .iter()
            .zip(&tr.t)
            .find(|(l, _)| Some(**l) == stalled)
            .map(|(_, t)| *t)
            .unwrap_or(f64::NAN)
    }

    /// The first time a trajectory is within the planner's tolerance (NaN if never).
    fn time_to_goal(&self, tr: &Trajectory, goal: &State) -> f64 {
        let g = goal.as_slice();
        tr.q.iter()
            .zip(&tr.t)
            .find(|(q, _)| self.params.tolerance.reached(q.as_slice(), g))
            .map(|(_, t)| *t)
            .unwrap_or(f64::NAN)
    }

    /// Indices of a trajectory's policy samples (every `period`).
    fn policy_samples(&self, tr: &Trajectory) -> Vec<usize> {
        let dt = if tr.t.len() > 1 {
            tr.t[1] - tr.t[0]
        } else {
            1.0
        };
        (0..tr.t.len()).step_by(self.steps_per_period(dt)).collect()
    }

    /// Steps of `dt` per policy period (at least 1).
    fn steps_per_period(&self, dt: f64) -> usize {
        ((self.params.period / dt).round() as usize).max(1)
    }
}

/// Metrics of two robots carrying the beam: ‖q_f‖∞ of the FE model at the
/// ideal and at the simulated grasps (policy samples), of the physics beam
/// (every step), the largest gap between the physics beam's and the FE
/// model's ‖q_f‖∞ at the same step, the least robot–robot distance, the
/// most non-obstacle collision pairs (robot–robot, beam–platform/ground),
/// the largest grasp force and torque, robot 2's largest lateral slip and
/// tilt.
const PAIR_METRICS: [&str; 10] = [
    "ideal_max_deformation",
    "sim_max_deformation",
    "sim_beam_max_deformation",
    "sim_beam_fe_gap",
    "sim_robot_clearance",
    "sim_body_contacts",
    "sim_grasp_force_max",
    "sim_grasp_torque_max",
    "slip_lateral_2_max",
    "sim_max_tilt_2_deg",
];

/// √det(JᵀJ) of a PUMA 560 at joint angles `q` (6): |det J| = |a2 f_shoulder
/// f_elbow f_wrist| for the square geometric Jacobian, m³.
fn manipulability(q: &[f64]) -> f64 {
    let [s, e, w] = crate::robots::mobile_manipulator::puma560::singularity_factors::<f64>(q);
    (crate::robots::mobile_manipulator::puma560::DH[1].a * s * e * w).abs()
}

/// Metrics of the V̇ ≥ 0 claim and the ellipsoid model along one run.
struct Along {
    /// `ideal` or `sim`: the metrics' prefix and the series' suffix.
    run: &'static str,
    min_beta: f64,
    /// Least √det(JᵀJ) = |det J| of any arm, m³ (zero at a singularity).
    min_manipulability: f64,
    max_deformation: f64,
    vdot_violations: usize,
    v: Series,
    beta: Series,
}

impl Along {
    fn new(run: &'static str) -> Along {
        Along {
            run,
            min_beta: f64::INFINITY,
            min_manipulability: f64::INFINITY,
            max_deformation: 0.0,
            vdot_violations: 0,
            v: Series::new(format!("V/{run}")),
            beta: Series::new(format!("min_obstacle_function/{run}")),
        }
    }

    /// The law's V and field at one policy sample (in order: `warm` carries
    /// the inner solves' warm starts from one sample to the next).
    fn sample(&mut self, scene: &Scene, gains: &Gains, warm: &mut Warm, t: f64, q: &[f64]) {
        for arm in q.chunks(mm::DOF) {
            self.min_manipulability = self.min_manipulability.min(manipulability(&arm[3..]));
        }
        let Ok((e, f)) = scene.field(q, warm) else {
            self.vdot_violations += 1;
            return;
        };
        self.min_beta = self.min_beta.min(e.min_beta);
        self.max_deformation = self.max_deformation.max(e.max_deformation);
        // The law's input at this very state (the recorded one may have
        // been computed a step earlier when sample times round).
        let (u, branches) = control::control(q, &f, &scene.goal, gains);
        // The final alignment is ours, not Eq. 18: not counted.
        if !branches.contains(&control::Branch::Align) {
            let u = u.as_slice();
            let vd = vdot_scaled(q, &f, u);
            let size = f.iter().map(|x| x * x).sum::<f64>().sqrt()
                * u.iter().map(|x| x * x).sum::<f64>().sqrt();
            if vd < -1e-9 * size {
                self.vdot_violations += 1;
            }
        }
        self.v.push(t, e.v);
        self.beta.push(t, e.min_beta);
    }

    /// As named metrics and series.
    fn into_early(self) -> EarlyAnalysis {
        let run = self.run;
        EarlyAnalysis {
            metrics: vec![
                (format!("{run}_min_obstacle_function"), self.min_beta),
                (
                    format!("{run}_vdot_violations"),
                    self.vdot_violations as f64,
                ),
                (format!("{run}_min_manipulability"), self.min_manipulability),
                (format!("{run}_max_deformation"), self.max_deformation),
            ],
            series: vec![self.v, self.beta],
        }
    }
}

fn along(
    scene: &Scene,
    gains: &Gains,
    tr: &Trajectory,
    samples: &[usize],
    run: &'static str,
) -> Along {
    let mut warm = scene.warm();
    let mut out = Along::new(run);
    for &k in samples {
        out.sample(scene, gains, &mut warm, tr.t[k], tr.q[k].as_slice());
    }
    out
}

/// [`Along`] of the physics run, sample by sample while the replay runs.
struct FollowSim {
    scene: Scene,
    gains: Gains,
    warm: Warm,
    /// Physics samples per policy sample.
    every: usize,
    along: Along,
}

impl SimFollower for FollowSim {
    fn sample(&mut self, k: usize, t: f64, q: &[f64]) {
        if k.is_multiple_of(self.every) {
            self.along
                .sample(&self.scene, &self.gains, &mut self.warm, t, q);
        }
    }
    fn finish(self: Box<Self>) -> EarlyAnalysis {
        self.along.into_early()
    }
}

impl System for Dilf {
    /// A differential drive: its wheels (and casters) can wear (`wheel_radius_scale`).
    fn exposure(&self, plan: &Plan) -> Exposure {
        Exposure {
            wheels: true,
            ..Exposure::of(plan)
        }
    }

    fn paper(&self, start: &State, goal: &State, _plan: &Plan) -> Vec<crate::paper::PaperRow> {
        if self.beam.is_none() {
            return Vec::new();
        }
        grasp::table_i_rows(start.as_slice(), goal.as_slice())
    }

    fn model(&self) -> &dyn KinematicModel {
        &self.model
    }
    fn default_max_rate(&self) -> Vec<f64> {
        vec![1.0; 8 * self.model.robots]
    }
    fn plan(&self, start: &State, goal: &State, limits: &Limits) -> Result<Plan, PlanError> {
        let scene =
            self.scene(start.as_slice(), goal)
                .map_err(|e| PlanError::InvalidParameter {
                    name: e.key_name().unwrap_or("planner").into(),
                    reason: e.reason().into(),
                })?;
        dilf::plan(Arc::new(scene), start, &self.params, limits.step)
    }
    fn urdf_names(&self) -> Vec<crate::engine::required::Named> {
        crate::engine::required::defaults(&crate::robots::mobile_manipulator::physics::REQUIRED)
    }
    fn physics(
        &self,
        robot: &urdf_rs::Robot,
        urdf_dir: &Path,
        start: &[f64],
        sim: &PhysicsSettings,
    ) -> Result<Box<dyn PhysicsSystem>, SetupError> {
        // The model's own check first, naming the key: a start inside an
        // obstacle is bad input, not a physics failure.
        let scene = self.scene(start, &State::from_vec(start.to_vec()))?;
        if let Err(crate::planner::PlanError::InvalidParameter { name, reason }) =
            dilf::check_configuration(&scene, start, "start")
        {
            return Err(SetupError::key(name.to_string(), reason.to_string()));
        }
        let obstacles: Vec<ObstacleShape> = self
            .obstacles
            .iter()
            .map(|(name, shape)| ObstacleShape {
                name: name.clone(),
                shape: *shape,
            })
            .collect();
        let beam = self.carried_beam(&scene);
        let setup = Setup {
            start,
            obstacles: &obstacles,
            beam: beam.as_ref(),
            arm: self.arm,
            arm_max_torque: self.arm_max_torque,
            arm_armature: self.arm_armature,
            wrist: self.wrist,
        };
        Ok(Box::new(MobileManipulatorPhysics::new(
            robot, urdf_dir, sim, &setup,
        )?))
    }
    fn links(&self, robot: &urdf_rs::Robot, start: &State) -> Vec<LinkVisual> {
        let beam = self
            .scene(start.as_slice(), start)
            .ok()
            .and_then(|s| self.carried_beam(&s));
        link_visuals(
            crate::engine::urdf::visuals(robot),
            self.model.robots,
            beam.as_ref(),
        )
    }
    fn goal_heading(&self, goal: &State) -> Option<f64> {
        Some(goal[2])
    }
    /// Wireframes of the obstacles (world) and of the robot's ellipsoid cover
    /// (attached to the links, so they move with the simulated robot).
    fn overlays(&self, _start: &State, _goal: &State) -> Vec<Overlay> {
        let mut out = Vec::new();
        for (name, s) in &self.obstacles {
            out.extend(wireframe(
                &format!("obstacle_{name}"),
                s,
                None,
                [0.85, 0.2, 0.2, 1.0],
            ));
        }
        for r in 1..=self.model.robots {
            for p in mm::default_parts() {
                out.extend(wireframe(
                    &format!("ellipsoid_{}", p.name),
                    &p.shape,
                    Some(&robot_link_name(r, p.link.urdf_name())),
                    [0.2, 0.75, 0.9, 1.0],
                ));
            }
        }
        out
    }
    fn extra_metric_names(&self) -> Vec<String> {
        let mut names: Vec<String> = [
            "ideal_time_to_goal",
            "sim_time_to_goal",
            "ideal_min_clearance",
            "sim_min_clearance",
            "sim_obstacle_contacts",
            "ideal_min_obstacle_function",
            "sim_min_obstacle_function",
            "ideal_vdot_violations",
            "sim_vdot_violations",
            "ideal_min_manipulability",
            "sim_min_manipulability",
            "slip_lateral_max",
            "joint_rate_error_max",
            "sim_max_tilt_deg",
            "ideal_stall_time",
            "sim_stall_time",
        ]
        .map(String::from)
        .to_vec();
        if let Some(b) = &self.beam {
            names.extend(PAIR_METRICS.map(String::from));
            names.extend(grasp::metric_names(
                b.bound == BoundKind::Wrench,
                self.wrist != Wrist::Rigid,
            ));
        }
        names
    }
    fn analysis_of_ideal(&self, goal: &State, ideal: &Trajectory) -> EarlyAnalysis {
        let Ok(scene) = self.scene(ideal.q[0].as_slice(), goal) else {
            return EarlyAnalysis::default();
        };
        let samples = self.policy_samples(ideal);
        let a = along(&scene, &self.params.gains(), ideal, &samples, "ideal");
        let mut clear = Series::new("clearance/ideal".into());
        for k in samples {
            clear.push(
                ideal.t[k],
                self.probe
                    .clearance(ideal.q[k].as_slice(), scene.object.as_ref()),
            );
        }
        let min_clear = clear.values.iter().copied().fold(f64::INFINITY, f64::min);
        a.into_early().and(EarlyAnalysis {
            metrics: vec![("ideal_min_clearance".into(), min_clear)],
            series: vec![clear],
        })
    }
    fn sim_follower(&self, start: &State, goal: &State, dt: f64) -> Option<Box<dyn SimFollower>> {
        let scene = self.scene(start.as_slice(), goal).ok()?;
        Some(Box::new(FollowSim {
            warm: scene.warm(),
            scene,
            gains: self.params.gains(),
            every: self.steps_per_period(dt),
            along: Along::new("sim"),
        }))
    }
    fn analysis_with(
        &self,
        goal: &State,
        ideal: &Trajectory,
        early: EarlyAnalysis,
        sim: &SimTrajectory,
        _cmp: &Comparison,
    ) -> (Vec<(String, f64)>, Vec<Series>) {
        let Ok(scene) = self.scene(ideal.q[0].as_slice(), goal) else {
            return (Vec::new(), Vec::new());
        };
        // The physics run's part, unless a follower computed it already.
        let mut early = if early.get("sim_min_obstacle_function").is_some() {
            early
        } else {
            let samples = self.policy_samples(&sim.traj);
            let a = along(&scene, &self.params.gains(), &sim.traj, &samples, "sim");
            early.and(a.into_early())
        };
        let metric = |name: &str| (name.to_string(), early.metric(name));
        let chan = |n: &str| sim.channel(n).unwrap_or(&[]);
        let min_of = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
        let max_abs = |v: &[f64]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let mut metrics = vec![
            ("ideal_time_to_goal".into(), self.time_to_goal(ideal, goal)),
            (
                "sim_time_to_goal".into(),
                self.time_to_goal(&sim.traj, goal),
            ),
            metric("ideal_min_clearance"),
            ("sim_min_clearance".into(), min_of(chan("min_clearance"))),
            (
                "sim_obstacle_contacts".into(),
                max_abs(chan("obstacle_contacts")),
            ),
            metric("ideal_min_obstacle_function"),
            metric("sim_min_obstacle_function"),
            metric("ideal_vdot_violations"),
            metric("sim_vdot_violations"),
            metric("ideal_min_manipulability"),
            metric("sim_min_manipulability"),
            ("slip_lateral_max".into(), max_abs(chan("slip_lateral"))),
            (
                "joint_rate_error_max".into(),
                max_abs(chan("joint_rate_error")),
            ),
            ("sim_max_tilt_deg".into(), max_abs(chan("tilt_deg"))),
            ("ideal_stall_time".into(), self.stall_time(ideal)),
            ("sim_stall_time".into(), self.stall_time(&sim.traj)),
        ];
        if self.beam.is_some() {
            // ‖q_f‖∞ of the FE model at the ideal and at the simulated grasps,
            // at every policy sample.
            metrics.push(metric("ideal_max_deformation"));
            metrics.push(metric("sim_max_deformation"));
            let max_of = |v: &[f64]| v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let gap = chan("beam_deformation")
                .iter()
                .zip(chan("fe_deformation"))
                .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
            metrics.extend([
                (
                    "sim_beam_max_deformation".into(),
                    max_of(chan("beam_deformation")),
                ),
                ("sim_beam_fe_gap".into(), gap),
                (
                    "sim_robot_clearance".into(),
                    min_of(chan("robot_clearance")),
                ),
                ("sim_body_contacts".into(), max_abs(chan("body_contacts"))),
                (
                    "sim_grasp_force_max".into(),
                    max_of(chan("grasp1_force")).max(max_of(chan("grasp2_force"))),
                ),
                (
                    "sim_grasp_torque_max".into(),
                    max_of(chan("grasp1_torque")).max(max_of(chan("grasp2_torque"))),
                ),
                ("slip_lateral_2_max".into(), max_abs(chan("slip_lateral_2"))),
                ("sim_max_tilt_2_deg".into(), max_abs(chan("tilt_2_deg"))),
            ]);
        }
        let mut series = [
            "V/ideal",
            "V/sim",
            "min_obstacle_function/ideal",
            "min_obstacle_function/sim",
            "clearance/ideal",
        ]
        .map(|name| early.take_series(name))
        .to_vec();
        if let Some(c) = &scene.object {
            let dt = match sim.traj.t.as_slice() {
                [a, b, ..] => b - a,
                _ => self.params.period,
            };
            let every = self.steps_per_period(dt);
            let samples = self.policy_samples(ideal);
            let compliant = self.wrist != Wrist::Rigid;
            let (m, s) = grasp::analysis(c, compliant, ideal, &samples, sim, every);
            metrics.extend(m);
            series.extend(s);
        }
        // The clearance of a scene without obstacles is infinite throughout:
        // nothing to plot, so no empty view in Rerun or the report.
        series.retain(|s| s.values.iter().any(|v| v.is_finite()));
        (metrics, series)
    }
}
