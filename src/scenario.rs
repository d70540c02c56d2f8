//! Scenario files (`scenarios/*.toml`): what to plan, how to simulate it and
//! which thresholds a run must meet.
//!
//! Parsing is strict: unknown keys, wrong types, NaN or infinite numbers and
//! missing files are errors that name the file, the line and the key.
//! Angular coordinates of `start` and `goal` are written in degrees.

use crate::error::Error;
use crate::{planner, systems};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// `[model]`: the kinematic model and its rigid-body counterpart.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum ModelConfig {
    /// Seed 000 §4.2 disk rolling without slipping: state (x, y, θ, α), inputs (θ', α').
    RollingDisk(systems::disk::DiskModelConfig),
    /// Free-floating planar space robot (seeds 000 §4.1 and 001).
    SpaceRobot(systems::space_robot::SpaceRobotConfig),
    /// Overconstrained rover with feedback primitives (seed 002).
    Rover(systems::rover::RoverConfig),
    /// Sphere rolling on a plane (seed 003).
    RollingSphere(systems::sphere::SphereConfig),
}

impl ModelConfig {
    /// The `kind` string.
    pub fn kind(&self) -> &'static str {
        match self {
            ModelConfig::RollingDisk(_) => "rolling_disk",
            ModelConfig::SpaceRobot(_) => "space_robot",
            ModelConfig::Rover(_) => "rover",
            ModelConfig::RollingSphere(_) => "rolling_sphere",
        }
    }

    /// The URDF path as written (relative to the scenario file).
    pub fn urdf(&self) -> &Path {
        match self {
            ModelConfig::RollingDisk(m) => &m.urdf,
            ModelConfig::SpaceRobot(m) => &m.urdf,
            ModelConfig::Rover(m) => &m.urdf,
            ModelConfig::RollingSphere(m) => &m.urdf,
        }
    }
}

/// `[planner]`: which planner, with its parameters.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum PlannerConfig {
    /// Seed 000 §4.2 Stokes planner for the rolling disk.
    StokesDisk(planner::stokes_disk::StokesDiskParams),
    /// Seed 000 §4.1 Stokes planner for the space robot.
    StokesSpace(planner::stokes_space::StokesSpaceParams),
    /// Seed 001 endogenous-configuration-space Jacobian planner.
    Endogenous(planner::endogenous::EndogenousParams),
    /// Seed 002 feedback primitives P1–P3.
    RoverPrimitives(planner::rover_primitives::RoverPrimitiveParams),
    /// Seed 003 §3 geometric (A)-(B)-(A) planner.
    SphereGeometric(planner::sphere_geometric::SphereGeometricParams),
    /// Seed 003 §4 spherical-triangle planner.
    SphereTriangle(planner::sphere_triangle::SphereTriangleParams),
}

impl PlannerConfig {
    /// The `kind` string.
    pub fn kind(&self) -> &'static str {
        match self {
            PlannerConfig::StokesDisk(_) => "stokes_disk",
            PlannerConfig::StokesSpace(_) => "stokes_space",
            PlannerConfig::Endogenous(_) => "endogenous",
            PlannerConfig::RoverPrimitives(_) => "rover_primitives",
            PlannerConfig::SphereGeometric(_) => "sphere_geometric",
            PlannerConfig::SphereTriangle(_) => "sphere_triangle",
        }
    }
}

/// `[limits]`: time parameterisation of open-loop plans.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct LimitsConfig {
    /// Per-input rate limit (rad/s or model units); default per model.
    pub max_rate: Option<Vec<f64>>,
    /// Cycloidal ramp time at both ends of each leg, s.
    pub ramp: f64,
}

impl Default for LimitsConfig {
    fn default() -> Self {
        Self {
            max_rate: None,
            ramp: 0.25,
        }
    }
}

/// `[sim]`: physics settings.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct SimConfig {
    /// Physics (and ideal integration) step, s.
    pub dt: f64,
    /// Rapier solver iterations (substeps) per step.
    pub solver_iterations: usize,
    /// Projected Gauss–Seidel sweeps per substep.
    pub solver_pgs_iterations: usize,
    /// Velocity relax pass after each substep; default: only with a ground plane.
    pub solver_relax_pass: Option<bool>,
    /// Coulomb friction coefficient between robot and ground (both sides set to it).
    pub friction: f64,
    /// Gravity, m/s².
    pub gravity: [f64; 3],
    /// Maximum torque of each velocity motor, N·m.
    pub motor_max_torque: f64,
    /// Velocity motor gain (Rapier's motor factor), 1/s-like; higher tracks tighter.
    pub motor_gain: f64,
    /// Rate (1/s) at which joint drives remove the error between joint angle and commanded
    /// angle ∫u dt (servo integral action); 0 = pure velocity motors.
    pub motor_angle_gain: f64,
    /// Extra simulated time after the plan ends, s (lets the body come to rest).
    pub settle: f64,
}

impl SimConfig {
    /// The physics layer's settings (everything but `settle`, which the replay takes).
    pub fn physics(&self) -> crate::physics::PhysicsSettings {
        crate::physics::PhysicsSettings {
            dt: self.dt,
            solver_iterations: self.solver_iterations,
            pgs_iterations: self.solver_pgs_iterations,
            relax_pass: self.solver_relax_pass,
            friction: self.friction,
            gravity: self.gravity,
            motor_max_torque: self.motor_max_torque,
            motor_gain: self.motor_gain,
            motor_angle_gain: self.motor_angle_gain,
        }
    }
}

impl Default for SimConfig {
    fn default() -> Self {
        Self {
            dt: 1e-3,
            solver_iterations: 1,
            solver_pgs_iterations: 4,
            solver_relax_pass: None,
            friction: 1.0,
            gravity: [0.0, 0.0, -9.81],
            motor_max_torque: 50.0,
            motor_gain: 1.0e6,
            motor_angle_gain: 1000.0,
            settle: 0.0,
        }
    }
}

/// The file as written.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct ScenarioFile {
    name: Option<String>,
    description: Option<String>,
    model: ModelConfig,
    start: Vec<f64>,
    goal: Vec<f64>,
    planner: PlannerConfig,
    #[serde(default)]
    limits: LimitsConfig,
    #[serde(default)]
    sim: SimConfig,
    #[serde(default)]
    thresholds: BTreeMap<String, f64>,
    sweep: Option<crate::sweep::SweepConfig>,
}

/// A validated scenario with resolved paths and SI units.
#[derive(Debug, Clone, Serialize)]
pub struct Scenario {
    /// Source file.
    pub path: PathBuf,
    /// Name (defaults to the file stem); also the log directory name.
    pub name: String,
    /// Free text.
    pub description: String,
    /// Model.
    pub model: ModelConfig,
    /// Resolved URDF path.
    pub urdf: PathBuf,
    /// Start state, SI (angles in rad).
    pub start: Vec<f64>,
    /// Goal state, SI.
    pub goal: Vec<f64>,
    /// Planner.
    pub planner: PlannerConfig,
    /// Rate limits (resolved defaults).
    pub max_rate: Vec<f64>,
    /// Ramp time, s.
    pub ramp: f64,
    /// Physics settings.
    pub sim: SimConfig,
    /// Metric name → maximum allowed value.
    pub thresholds: BTreeMap<String, f64>,
    /// Monte Carlo variants (`[sweep]`): `run`/`check` run the sweep instead of one run.
    pub sweep: Option<crate::sweep::SweepConfig>,
}

fn line_of(text: &str, offset: usize) -> usize {
    text[..offset.min(text.len())]
        .bytes()
        .filter(|&b| b == b'\n')
        .count()
        + 1
}

/// Reject NaN/inf anywhere in the document, naming the key and line.
fn check_finite(path: &Path, text: &str) -> Result<(), Error> {
    use toml::de::{DeTable, DeValue};
    fn walk(
        v: &toml::Spanned<DeValue<'_>>,
        key: &str,
        text: &str,
        path: &Path,
    ) -> Result<(), Error> {
        match v.get_ref() {
            DeValue::Float(f) => {
                let s = f.as_str().trim_start_matches(['+', '-']).replace('_', "");
                let finite = s.parse::<f64>().map(f64::is_finite).unwrap_or(false);
                if !finite {
                    return Err(Error::Input {
                        path: path.into(),
                        line: Some(line_of(text, v.span().start)),
                        message: format!("key `{key}`: {} is not a finite number", f.as_str()),
                    });
                }
            }
            DeValue::Array(items) => {
                for (i, item) in items.iter().enumerate() {
                    walk(item, &format!("{key}[{i}]"), text, path)?;
                }
            }
            DeValue::Table(t) => walk_table(t, key, text, path)?,
            _ => {}
        }
        Ok(())
    }
    fn walk_table(t: &DeTable<'_>, prefix: &str, text: &str, path: &Path) -> Result<(), Error> {
        for (k, v) in t.iter() {
            let key = if prefix.is_empty() {
                k.get_ref().to_string()
            } else {
                format!("{prefix}.{}", k.get_ref())
            };
            walk(v, &key, text, path)?;
        }
        Ok(())
    }
    match DeTable::parse(text) {
        Ok(t) => walk_table(t.get_ref(), "", text, path),
        Err(e) => Err(toml_error(path, text, &e)),
    }
}

fn toml_error(path: &Path, text: &str, e: &toml::de::Error) -> Error {
    let message = e.message().trim().replace('\n', " ");
    let mut line = e.span().map(|s| line_of(text, s.start));
    // serde reports unknown fields at the enclosing table (or its tag); point
    // at the key itself: search from the span to the end of that table.
    if let (Some(span), Some(key)) = (e.span(), message.split('`').nth(1)) {
        if message.starts_with("unknown field") {
            let start = text[..span.start.min(text.len())]
                .rfind('\n')
                .map_or(0, |i| i + 1);
            let mut offset = start;
            for (i, l) in text[start..].split('\n').enumerate() {
                let t = l.trim_start();
                if i > 0 && t.starts_with('[') {
                    break;
                }
                let k = t.split('=').next().unwrap_or("").trim().trim_matches('"');
                if t.contains('=') && k == key {
                    line = Some(line_of(text, offset));
                    break;
                }
                offset += l.len() + 1;
            }
        }
    }
    Error::Input {
        path: path.into(),
        line,
        message,
    }
}

impl Scenario {
    /// Read and validate a scenario file.
    pub fn load(path: &Path) -> Result<Scenario, Error> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| Error::input(path, format!("cannot read scenario: {e}")))?;
        Self::parse(path, &text)
    }

    /// Validate scenario text (`path` is used for messages and relative paths).
    pub fn parse(path: &Path, text: &str) -> Result<Scenario, Error> {
        check_finite(path, text)?;
        let file: ScenarioFile = toml::from_str(text).map_err(|e| toml_error(path, text, &e))?;
        let bad = |message: String| Error::input(path, message);
        let name = file.name.clone().unwrap_or_else(|| {
            path.file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default()
        });
        if name.is_empty() || name.contains(['/', '\\']) || name.starts_with('.') {
            return Err(bad(format!(
                "key `name`: `{name}` is not usable as a log directory name"
            )));
        }
        let base = path.parent().unwrap_or(Path::new("."));
        let system = systems::build(&file.model, &file.planner).map_err(&bad)?;
        // start/goal are written in the system's file chart (usually the model state).
        let model = system.file_model();
        let (n_state, n_input) = (model.state_names().len(), model.input_names().len());
        let angular = model.angular_states();
        let default_rate = system.default_max_rate();
        let urdf = base.join(file.model.urdf());
        if !urdf.is_file() {
            return Err(bad(format!(
                "key `model.urdf`: file not found: {}",
                urdf.display()
            )));
        }
        let to_si = |key: &str, v: &[f64]| -> Result<Vec<f64>, Error> {
            if v.len() != n_state {
                return Err(bad(format!(
                    "key `{key}`: expected {n_state} values, got {}",
                    v.len()
                )));
            }
            Ok(v.iter()
                .enumerate()
                .map(|(i, x)| {
                    if angular.contains(&i) {
                        x.to_radians()
                    } else {
                        *x
                    }
                })
                .collect())
        };
        let start = system.state_from_file(to_si("start", &file.start)?);
        let goal = system.state_from_file(to_si("goal", &file.goal)?);
        let max_rate = file.limits.max_rate.clone().unwrap_or(default_rate);
        if max_rate.len() != n_input {
            return Err(bad(format!(
                "key `limits.max_rate`: expected {n_input} values, got {}",
                max_rate.len()
            )));
        }
        if max_rate.iter().any(|r| *r <= 0.0) {
            return Err(bad("key `limits.max_rate`: rates must be > 0".into()));
        }
        if file.limits.ramp < 0.0 {
            return Err(bad("key `limits.ramp`: must be ≥ 0".into()));
        }
        let s = &file.sim;
        if !(s.dt > 0.0 && s.dt <= 0.1) {
            return Err(bad("key `sim.dt`: must be in (0, 0.1] s".into()));
        }
        if s.solver_iterations == 0 || s.solver_iterations > 1000 {
            return Err(bad(
                "key `sim.solver_iterations`: must be in 1..=1000".into()
            ));
        }
        if s.solver_pgs_iterations == 0 || s.solver_pgs_iterations > 1000 {
            return Err(bad(
                "key `sim.solver_pgs_iterations`: must be in 1..=1000".into()
            ));
        }
        if s.friction < 0.0 {
            return Err(bad("key `sim.friction`: must be ≥ 0".into()));
        }
        if s.motor_max_torque <= 0.0 || s.motor_gain <= 0.0 || s.settle < 0.0 {
            return Err(bad(
                "keys `sim.motor_max_torque`, `sim.motor_gain` must be > 0 and `sim.settle` ≥ 0"
                    .into(),
            ));
        }
        if s.motor_angle_gain < 0.0 {
            return Err(bad("key `sim.motor_angle_gain`: must be ≥ 0".into()));
        }
        if let Some(sw) = &file.sweep {
            sw.validate().map_err(&bad)?;
        }
        for (k, v) in &file.thresholds {
            if *v < 0.0 {
                return Err(bad(format!("key `thresholds.{k}`: must be ≥ 0")));
            }
        }
        Ok(Scenario {
            path: path.to_path_buf(),
            name,
            description: file.description.unwrap_or_default(),
            model: file.model,
            urdf,
            start,
            goal,
            planner: file.planner,
            max_rate,
            ramp: file.limits.ramp,
            sim: file.sim,
            thresholds: file.thresholds,
            sweep: file.sweep,
        })
    }
}

/// Expand files and directories (non-recursive, `*.toml`, sorted) into scenario paths.
pub fn collect(paths: &[PathBuf]) -> Result<Vec<PathBuf>, Error> {
    let mut out = Vec::new();
    for p in paths {
        if p.is_dir() {
            let rd = std::fs::read_dir(p)
                .map_err(|e| Error::input(p, format!("cannot list directory: {e}")))?;
            let mut files: Vec<PathBuf> = rd
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|f| f.extension().is_some_and(|x| x == "toml") && f.is_file())
                .collect();
            files.sort();
            if files.is_empty() {
                return Err(Error::input(p, "no *.toml scenario files in directory"));
            }
            out.extend(files);
        } else if p.is_file() {
            out.push(p.clone());
        } else {
            return Err(Error::input(p, "no such file or directory"));
        }
    }
    Ok(out)
}
