//! The overconstrained rover (seed 002): the switching kinematic model, the P1–P3 feedback
//! primitives and `models/rover.urdf` with five wheels in contact.
//!
//! The ideal run integrates the multiple-model system with a prescribed σ(t) (`[model.switching]`);
//! the physics run lets the contact solver decide which rear axle slips. The feedback policy
//! reads whichever state it is given, so both runs are closed loop. With
//! `open_loop_replay = true` the plan is instead the command sequence recorded from the ideal
//! closed-loop run, replayed without feedback (it still reaches the goal in the ideal run,
//! which is deterministic, but not on Rapier).

pub mod kinematics;
pub mod physics;
pub mod primitives;

use crate::engine::perturb::Exposure;
use crate::engine::PhysicsSettings;
use crate::engine::PhysicsSystem;
use crate::error::SetupError;
use crate::integrate::{simulate, Trajectory};
use crate::metric::{m, Direction::*, Family::*, Metric, Unit};
use crate::model::{Input, KinematicModel, State};
use crate::paper::{rows_from, same, PaperRow};
use crate::plan::{Command, ControlLaw, Controller, Limits, Plan, PolicyFactory};
use crate::planner::PlanError;
use crate::record::Comparison;
use crate::record::{Overlay, SimTrajectory};
use crate::robots::rover::kinematics::{RoverGeometry, SwitchingRover, SwitchingSignal};
use crate::robots::rover::physics::RoverPhysics;
use crate::robots::rover::primitives::{se2_distance, RoverPrimitiveParams, TurnDirection};
use crate::robots::System;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The rover's own metrics: the SE(2) error and the primitives' envelope.
pub const METRICS: &[Metric] = &[
    m(
        "{run}_goal_se2",
        Unit::Ratio,
        LowerIsBetter,
        EndOnly,
        "Final error in the seed's SE(2) metric √(Δx² + Δy² + Δθ²), m and rad alike.",
    ),
    m(
        "envelope_fraction",
        Unit::Fraction,
        HigherIsBetter,
        EndOnly,
        "Fraction of the physics run inside the primitives' envelope.",
    ),
    m(
        "envelope_outside_fraction",
        Unit::Fraction,
        LowerIsBetter,
        EndOnly,
        "Fraction of the physics run outside the envelope.",
    ),
    m(
        "envelope_distance_max",
        Unit::Meter,
        LowerIsBetter,
        RunningMax,
        "Largest distance outside the envelope.",
    ),
];

/// σ(t) of the ideal run.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum SwitchingConfig {
    /// σ ≡ a (middle axle holds).
    A,
    /// σ ≡ b (back axle holds).
    B,
    /// Random telegraph signal: fair initial coin, Poisson switches at `rate` per second.
    Telegraph {
        /// RNG seed.
        seed: u64,
        /// Mean switching rate, 1/s.
        #[schemars(range(min = 0))]
        rate: f64,
    },
}

impl Default for SwitchingConfig {
    fn default() -> Self {
        SwitchingConfig::Telegraph { seed: 1, rate: 0.5 }
    }
}

/// The overconstrained rover of seed 002: a steered, driven front wheel and
/// two passive rear axles, one of which must slip (σ(t) says which in the
/// ideal run; the contact solver decides on Rapier).
#[derive(Debug, Clone, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RoverConfig {
    /// URDF file, relative to the scenario file.
    pub urdf: PathBuf,
    /// Dimensions (must match the URDF); defaults: l = r = 0.25 m, wheel radius 0.065 m.
    #[serde(default)]
    pub geometry: RoverGeometry,
    /// σ(t) for the ideal run.
    #[serde(default)]
    pub switching: SwitchingConfig,
    /// Replay the ideal closed-loop run's commands open loop (no feedback).
    #[serde(default)]
    pub open_loop_replay: bool,
    /// A physics sample counts as inside the envelope when its distance to the allowed
    /// velocity set is at most this (m/s and rad/s alike).
    #[serde(default = "default_envelope_tolerance")]
    #[schemars(range(min = 0))]
    pub envelope_tolerance: f64,
}

fn default_envelope_tolerance() -> f64 {
    0.02
}

struct Rover {
    model: SwitchingRover,
    params: RoverPrimitiveParams,
    open_loop: bool,
    envelope_tol: f64,
}

/// Build the rover system.
pub fn build(
    cfg: &RoverConfig,
    params: &RoverPrimitiveParams,
) -> Result<Box<dyn System>, SetupError> {
    cfg.geometry
        .validate()
        .map_err(|e| SetupError::key("model.geometry", e))?;
    if !(cfg.envelope_tolerance.is_finite() && cfg.envelope_tolerance >= 0.0) {
        return Err(SetupError::key(
            "model.envelope_tolerance",
            "must be finite and ≥ 0",
        ));
    }
    let params = params.clone();
    let horizon = if params.horizon.is_finite() {
        params.horizon.max(0.0)
    } else {
        0.0
    };
    let signal = match cfg.switching {
        SwitchingConfig::A => SwitchingSignal::FixedA,
        SwitchingConfig::B => SwitchingSignal::FixedB,
        SwitchingConfig::Telegraph { seed, rate } => {
            SwitchingSignal::telegraph(seed, rate, horizon)
                .map_err(|e| SetupError::key("model.switching", e))?
        }
    };
    Ok(Box::new(Rover {
        model: SwitchingRover::new(cfg.geometry, signal),
        params,
        open_loop: cfg.open_loop_replay,
        envelope_tol: cfg.envelope_tolerance,
    }))
}

/// Replays recorded commands on the policy's sample grid, ignoring the state.
struct Recorded {
    t: Vec<f64>,
    u: Vec<Input>,
    label: Vec<usize>,
}

struct RecordedController(Arc<Recorded>);

impl Controller for RecordedController {
    fn command(&mut self, t: f64, _q: &State) -> Command {
        let r = &self.0;
        let k = r.t.partition_point(|&s| s <= t + 1e-9).saturating_sub(1);
        Command {
            u: r.u[k].clone(),
            label: r.label[k],
            done: false,
        }
    }
}

struct RecordedFactory(Arc<Recorded>);

impl PolicyFactory for RecordedFactory {
    fn start(&self) -> Box<dyn Controller> {
        Box::new(RecordedController(self.0.clone()))
    }
}

/// First time the run is within `eps` of the goal in the seed's SE(2) metric (NaN if never).
pub fn time_to_goal(tr: &Trajectory, goal: &State, eps: f64) -> f64 {
    tr.q.iter()
        .zip(&tr.t)
        .find(|(q, _)| se2_distance(q, goal) <= eps)
        .map(|(_, t)| *t)
        .unwrap_or(f64::NAN)
}

impl System for Rover {
    /// Wheeled; the open-loop replay reads no state (its plan is a held
    /// sequence of recorded commands), so state noise and latency do not apply.
    fn exposure(&self, plan: &Plan) -> Exposure {
        let e = Exposure::of(plan);
        Exposure {
            wheels: true,
            // The recorded commands are replayed: no law sees the state.
            feedback: e.feedback && !self.open_loop,
            ..e
        }
    }
    fn model(&self) -> &dyn KinematicModel {
        &self.model
    }
    /// The open-loop replay sends the recorded commands to both runs.
    fn same_commands(&self, _plan: &Plan) -> bool {
        self.open_loop
    }
    fn goal_heading(&self, goal: &State) -> Option<f64> {
        Some(goal[2])
    }
    /// The line N through the goal at the goal heading, which P2 stabilises to.
    fn overlays(&self, start: &State, goal: &State) -> Vec<Overlay> {
        let (c, s) = (goal[2].cos(), goal[2].sin());
        let reach = 2.0 + (start[0] - goal[0]).hypot(start[1] - goal[1]);
        let at = |d: f64| [goal[0] + d * c, goal[1] + d * s, 0.0];
        vec![Overlay {
            name: "line_N".into(),
            points: vec![at(-reach), at(reach)],
            link: None,
            rgba: [0.55, 0.35, 0.85, 1.0],
        }]
    }
    fn default_max_rate(&self) -> Vec<f64> {
        vec![1.0, 2.0]
    }
    fn planning_horizon(&self) -> Option<(f64, &'static str)> {
        // The open-loop replay records an ideal closed-loop run while planning.
        self.open_loop
            .then_some((self.params.horizon, "planner.horizon"))
    }
    fn plan(&self, start: &State, goal: &State, limits: &Limits) -> Result<Plan, PlanError> {
        let plan = primitives::plan(&self.model, start, goal, &self.params, limits)?;
        if !self.open_loop {
            return Ok(plan);
        }
        // Record the ideal closed-loop run and hand out its commands as an open-loop plan
        // (sampled and held on the same control grid, so the ideal replay is exact).
        let ideal = simulate(&self.model, &plan, start, limits.step);
        let n = ideal.t.len().saturating_sub(1).max(1);
        let duration = ideal.t.last().copied().unwrap_or(0.0);
        let rec = Recorded {
            t: ideal.t[..n].to_vec(),
            u: ideal.u[..n].to_vec(),
            label: ideal.label[..n].to_vec(),
        };
        let mut details = plan.details.clone();
        details["open_loop_replay"] = serde_json::json!({
            "recorded_duration_s": duration,
            "ideal_closed_loop_goal_se2": se2_distance(ideal.last(), goal),
        });
        Ok(Plan {
            labels: plan.labels,
            segments: Vec::new(),
            duration,
            law: ControlLaw::Feedback {
                factory: Arc::new(RecordedFactory(Arc::new(rec))),
                period: self.params.period,
            },
            details,
        })
    }
    fn urdf_names(&self) -> Vec<crate::engine::required::Named> {
        crate::engine::required::defaults(&crate::robots::rover::physics::REQUIRED)
    }
    fn physics(
        &self,
        robot: &urdf_rs::Robot,
        urdf_dir: &Path,
        start: &[f64],
        sim: &PhysicsSettings,
    ) -> Result<Box<dyn PhysicsSystem>, SetupError> {
        Ok(Box::new(RoverPhysics::new(
            robot,
            urdf_dir,
            self.model.geometry,
            start,
            sim,
        )?))
    }
    /// Seed 002 Fig. 2: from (0, 0, 90°) to (8, 2, 90°) the paper's run turns 330° left in P1.
    fn paper(&self, start: &State, goal: &State, plan: &Plan) -> Vec<PaperRow> {
        use std::f64::consts::FRAC_PI_2;
        let task = same(start.as_slice(), &[0.0, 0.0, FRAC_PI_2, 0.0], 1e-9)
            && same(goal.as_slice(), &[8.0, 2.0, FRAC_PI_2, 0.0], 1e-9)
            && self.params.turn == TurnDirection::Left;
        if !task {
            return Vec::new();
        }
        rows_from(
            &plan.details,
            &[(
                "P1 turn (left), Fig. 2",
                "330",
                "/p1_turn_rad",
                180.0 / std::f64::consts::PI,
                "deg",
                "",
            )],
        )
    }
    fn extra_metric_names(&self) -> Vec<String> {
        [
            "ideal_goal_se2",
            "sim_goal_se2",
            "ideal_time_to_goal",
            "sim_time_to_goal",
            "envelope_fraction",
            "envelope_outside_fraction",
            "envelope_distance_max",
            "slip_lateral_max",
            "slip_longitudinal_max",
        ]
        .map(String::from)
        .to_vec()
    }
    fn extra_metrics(
        &self,
        goal: &State,
        ideal: &Trajectory,
        sim: &SimTrajectory,
        _cmp: &Comparison,
    ) -> Vec<(String, f64)> {
        let eps = self.params.epsilon;
        let mut out = vec![
            (
                "ideal_goal_se2".to_string(),
                se2_distance(ideal.last(), goal),
            ),
            (
                "sim_goal_se2".to_string(),
                se2_distance(sim.traj.last(), goal),
            ),
            (
                "ideal_time_to_goal".to_string(),
                time_to_goal(ideal, goal, eps),
            ),
            (
                "sim_time_to_goal".to_string(),
                time_to_goal(&sim.traj, goal, eps),
            ),
        ];
        let env = sim.channel("envelope_distance").unwrap_or(&[]);
        let finite: Vec<f64> = env.iter().copied().filter(|v| v.is_finite()).collect();
        let inside = finite.iter().filter(|&&d| d <= self.envelope_tol).count();
        let frac = if finite.is_empty() {
            f64::NAN
        } else {
            inside as f64 / finite.len() as f64
        };
        out.push(("envelope_fraction".into(), frac));
        out.push(("envelope_outside_fraction".into(), 1.0 - frac));
        out.push((
            "envelope_distance_max".into(),
            finite.iter().fold(0.0, |m: f64, v| m.max(*v)),
        ));
        out.extend(crate::robots::wheeled::slip::slip_metrics(sim));
        out
    }
}
