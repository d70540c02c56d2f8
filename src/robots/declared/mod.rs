//! A kinematic model declared in the scenario (`[model] kind =
//! "declared"`): its states, inputs, parameters and equations q' = f(q, u),
//! with the URDF joints that drive it and the links it is read back from.
//! Any nonholonomic robot, without writing Rust: a tractor with trailers, a
//! skid steer, a differential drive whose reference point is ahead of the
//! axle. Plans come from outside (files, external laws, Python callables)
//! or from seed 001's endogenous planner ([`crate::robots::declared::plan`]).

pub mod expr;
pub mod kinematics;
pub mod physics;
pub mod plan;
pub mod rates;

use crate::echo::code;
use crate::engine::perturb::Exposure;
use crate::engine::required::Named;
use crate::engine::{PhysicsSettings, PhysicsSystem};
use crate::error::SetupError;
use crate::model::{KinematicModel, State};
use crate::plan::{Limits, Plan};
use crate::planner::endogenous::EndogenousParams;
use crate::planner::PlanError;
use crate::robots::declared::kinematics::{Declared, Expr};
use crate::robots::declared::physics::{DeclaredPhysics, Read, Rig};
use crate::robots::no_planner;
use crate::robots::System;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A kinematic model q' = f(q, u) written in the scenario, and how its URDF
/// is driven and read back. Plans come from a file, an external law, a
/// Python callable or seed 001's endogenous planner (`kind = "endogenous"`).
#[derive(Debug, Clone, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DeclaredConfig {
    /// URDF file, relative to the scenario file.
    pub urdf: PathBuf,
    /// The state's names, in order: `start` and `goal` list their values.
    pub states: Vec<String>,
    /// The states that are angles: degrees in `start` and `goal`, radians
    /// in expressions; their errors wrap, their read-back unwraps.
    #[serde(default)]
    pub angles: Vec<String>,
    /// The input's names, in order: a plan file's columns, a law's `u`.
    pub inputs: Vec<String>,
    /// Links whose collisions carry no friction (ideal casters).
    #[serde(default)]
    pub frictionless: Vec<String>,
    /// The wheels that wear with `[sim.perturb] wheel_radius_scale`, as
    /// `[model.drive]` joints (default: the driven joints whose child link
    /// has a round collision on the ground at the start).
    #[serde(default)]
    pub wheels: Option<Vec<String>>,
    /// Named numbers the expressions may use (a sweep may vary them:
    /// `model.params.NAME`).
    #[serde(default)]
    pub params: BTreeMap<String, f64>,
    /// One expression per state: its time derivative, over the states, the
    /// inputs and the parameters.
    pub kinematics: BTreeMap<String, String>,
    /// Joint velocity targets (rad/s, or m/s for a prismatic joint), one
    /// expression per driven joint, over states, inputs and parameters.
    #[serde(default)]
    pub drive: BTreeMap<String, String>,
    /// Joint position targets (rad, or m), one expression per joint (steering).
    #[serde(default)]
    pub drive_position: BTreeMap<String, String>,
    /// Where each state is read in the simulation: `LINK.x`, `.y`, `.z`,
    /// `.roll`, `.pitch`, `.yaw` (world frame), `LINK.vx`, `.vy`, `.vz`
    /// (m/s), `.wx`, `.wy`, `.wz` (rad/s; the link frame's velocity in its
    /// own axes), `JOINT.position` or `JOINT.velocity`.
    pub read: BTreeMap<String, String>,
    /// Per-input bound on |u| for built-in leg planners (default 1 each).
    #[serde(default)]
    pub limits: BTreeMap<String, f64>,
}

/// The declared system.
pub struct DeclaredSystem {
    pub(super) model: Declared,
    /// `[planner] kind = "endogenous"`, when it plans for itself.
    pub(super) planner: Option<EndogenousParams>,
    rig: Rig,
    max_rate: Vec<f64>,
    /// The state read as the root's yaw, for the 3D goal arrow.
    heading: Option<usize>,
}

fn is_name(s: &str) -> bool {
    let mut c = s.chars();
    c.next()
        .is_some_and(|f| f.is_ascii_alphabetic() || f == '_')
        && c.all(|x| x.is_ascii_alphanumeric() || x == '_')
}

/// Build the declared system for plans from outside: every name and
/// expression checked, each error naming its `[model]` key.
pub fn build(cfg: &DeclaredConfig) -> Result<Box<dyn System>, SetupError> {
    build_planned(cfg, None)
}

/// [`build`], planning with seed 001's endogenous planner when `planner`
/// is given.
pub(crate) fn build_planned(
    cfg: &DeclaredConfig,
    planner: Option<EndogenousParams>,
) -> Result<Box<dyn System>, SetupError> {
    let params: Vec<String> = cfg.params.keys().cloned().collect();
    let mut seen: BTreeMap<&str, &str> = BTreeMap::new();
    for (key, list) in [
        ("states", &cfg.states),
        ("inputs", &cfg.inputs),
        ("params", &params),
    ] {
        if key != "params" && list.is_empty() {
            return Err(SetupError::key(format!("model.{key}"), "at least one name"));
        }
        for n in list {
            if !is_name(n) {
                return Err(SetupError::key(
                    format!("model.{key}"),
                    format!(
                        "{} is not a name (letters, digits and _, not starting with a digit)",
                        code(n)
                    ),
                ));
            }
            if crate::robots::declared::kinematics::reserved(n) {
                return Err(SetupError::key(
                    format!("model.{key}"),
                    format!("{} is a function of the expression language", code(n)),
                ));
            }
            if let Some(other) = seen.insert(n, key) {
                return Err(SetupError::key(
                    format!("model.{key}"),
                    format!("{} is also one of `model.{other}`", code(n)),
                ));
            }
        }
    }
    for (k, v) in &cfg.params {
        if !v.is_finite() {
            return Err(SetupError::key(
                format!("model.params.{k}"),
                format!("must be a finite number, got {v}"),
            ));
        }
    }
    let mut angles = Vec::new();
    for a in &cfg.angles {
        match cfg.states.iter().position(|s| s == a) {
            Some(i) => angles.push(i),
            None => {
                return Err(SetupError::key(
                    "model.angles",
                    format!(
                        "{} is not a state (states: {})",
                        code(a),
                        cfg.states.join(", ")
                    ),
                ))
            }
        }
    }
    // One equation and one read-back per state, and nothing else.
    for (table, map) in [("kinematics", &cfg.kinematics), ("read", &cfg.read)] {
        if let Some(s) = cfg.states.iter().find(|s| !map.contains_key(*s)) {
            return Err(SetupError::key(
                format!("model.{table}"),
                format!("state `{s}` has no entry"),
            ));
        }
        if let Some(k) = map.keys().find(|k| !cfg.states.contains(k)) {
            return Err(SetupError::key(
                format!("model.{table}.{k}"),
                format!(
                    "{} is not a state (states: {})",
                    code(k),
                    cfg.states.join(", ")
                ),
            ));
        }
    }
    for k in cfg.limits.keys() {
        if !cfg.inputs.contains(k) {
            return Err(SetupError::key(
                format!("model.limits.{k}"),
                format!("{} is not an input", code(k)),
            ));
        }
    }
    if let Some((k, v)) = cfg
        .limits
        .iter()
        .find(|(_, v)| !(**v > 0.0 && v.is_finite()))
    {
        return Err(SetupError::key(
            format!("model.limits.{k}"),
            format!("must be > 0, got {v}"),
        ));
    }
    if let Some(w) = cfg
        .wheels
        .iter()
        .flatten()
        .find(|w| !cfg.drive.contains_key(*w))
    {
        return Err(SetupError::key(
            "model.wheels",
            format!(
                "{} is not a driven joint: a wheel is a `[model.drive]` joint ({})",
                code(w),
                if cfg.drive.is_empty() {
                    "there are none".to_string()
                } else {
                    cfg.drive.keys().cloned().collect::<Vec<_>>().join(", ")
                }
            ),
        ));
    }
    let names = Declared::slot_names(&cfg.states, &cfg.inputs, &params);
    let expr = |table: &str, key: &str, text: &str| {
        Expr::parse(text, &names).map_err(|e| SetupError::key(format!("model.{table}.{key}"), e))
    };
    let f = cfg
        .states
        .iter()
        .map(|s| expr("kinematics", s, &cfg.kinematics[s]))
        .collect::<Result<Vec<_>, _>>()?;
    let drives = |table: &str, map: &BTreeMap<String, String>| {
        map.iter()
            .map(|(j, t)| Ok((j.clone(), expr(table, j, t)?)))
            .collect::<Result<Vec<_>, SetupError>>()
    };
    let reads = cfg
        .states
        .iter()
        .map(|s| {
            Read::parse(&cfg.read[s]).map_err(|e| SetupError::key(format!("model.read.{s}"), e))
        })
        .collect::<Result<Vec<_>, _>>()?;
    // The goal arrow: a yaw read of the first link that is read.
    let heading = reads.iter().position(
        |r| matches!(r, Read::Link(_, c) if *c == crate::robots::declared::physics::LinkCoord::Yaw),
    );
    let model = Declared::new(
        &cfg.states,
        &cfg.inputs,
        &angles,
        cfg.params.values().copied().collect(),
        f,
    );
    Ok(Box::new(DeclaredSystem {
        rig: Rig {
            states: cfg.states.clone(),
            reads,
            drives: drives("drive", &cfg.drive)?,
            positions: drives("drive_position", &cfg.drive_position)?,
            frictionless: cfg.frictionless.clone(),
            wheels: cfg.wheels.clone(),
        },
        max_rate: cfg
            .inputs
            .iter()
            .map(|i| cfg.limits.get(i).copied().unwrap_or(1.0))
            .collect(),
        heading,
        model,
        planner,
    }))
}

impl System for DeclaredSystem {
    fn model(&self) -> &dyn KinematicModel {
        &self.model
    }
    fn default_max_rate(&self) -> Vec<f64> {
        self.max_rate.clone()
    }
    fn plan(&self, start: &State, goal: &State, limits: &Limits) -> Result<Plan, PlanError> {
        match &self.planner {
            Some(p) => crate::robots::declared::plan::plan(&self.model, start, goal, p, limits),
            None => Err(no_planner("declared")),
        }
    }
    fn goal_heading(&self, goal: &State) -> Option<f64> {
        self.heading.map(|i| goal[i])
    }
    /// The links and joints are checked by the physics, each error naming
    /// the `[model]` key that names it.
    fn urdf_names(&self) -> Vec<Named> {
        Vec::new()
    }
    fn physics(
        &self,
        robot: &urdf_rs::Robot,
        urdf_dir: &Path,
        start: &[f64],
        sim: &PhysicsSettings,
    ) -> Result<Box<dyn PhysicsSystem>, SetupError> {
        Ok(Box::new(DeclaredPhysics::new(
            robot,
            urdf_dir,
            &self.rig,
            &self.model,
            start,
            sim,
        )?))
    }
    /// Its wheels (driven joints rolling on the ground, or `[model] wheels`)
    /// can wear (`wheel_radius_scale`).
    fn exposure(&self, plan: &Plan) -> Exposure {
        Exposure {
            wheels: true,
            ..Exposure::of(plan)
        }
    }
}
