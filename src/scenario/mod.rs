//! Scenario files (`scenarios/*.toml`): what to plan, how to simulate it and
//! which thresholds a run must meet.
//!
//! Parsing is strict: unknown keys, wrong types, NaN or infinite numbers,
//! out-of-range values and missing files are errors that name the file, the
//! line and the key ([`doc::KeyIndex`] maps keys to lines). Angular
//! coordinates of `start` and `goal` are written in degrees.
//!
//! This is the top of the configuration flow: it owns the `[model]`,
//! `[planner]` and `[sweep]` tables, matches model and planner
//! ([`build_system`]) and hands each system its own typed configuration.
//! Nothing below (systems, planners, models) imports this module.

mod compare_config;
mod config;
pub mod doc;
pub mod keypath;
pub mod margins_config;
mod parse;
pub mod regression;
pub mod schema;
mod sweep_config;

pub use compare_config::CompareConfig;
pub(crate) use config::model_system;
pub use config::{build_system, planners_for, ModelConfig, PlannerConfig, OUTSIDE, PAIRS};
pub use keypath::KeyPath;
pub use margins_config::MarginsConfig;
pub use sweep_config::{
    sweep_metric_names, variant_seed, vary_key, Dist, SweepConfig, Variant, DEFAULT_TIME_METRIC,
};

pub use crate::engine::perturb::Perturbation;
use crate::error::Error;
use crate::input::{read_text, SCENARIO_MAX_BYTES};
use doc::KeyIndex;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use toml::de::{DeTable, DeValue, ValueDeserializer};
use toml::Spanned;

/// `[limits]`: time parameterisation of open-loop plans.
#[derive(Debug, Clone, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct LimitsConfig {
    /// Per-input rate limit (rad/s or model units); default per model.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub max_rate: Option<Vec<f64>>,
    /// Cycloidal ramp time at both ends of each leg, s.
    #[schemars(range(min = 0))]
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
#[derive(Debug, Clone, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct SimConfig {
    /// Physics (and ideal integration) step, s.
    #[schemars(range(max = 0.1), extend("exclusiveMinimum" = 0))]
    pub dt: f64,
    /// Rapier solver iterations (substeps) per step.
    #[schemars(range(min = 1, max = 1000))]
    pub solver_iterations: usize,
    /// Projected Gauss–Seidel sweeps per substep.
    #[schemars(range(min = 1, max = 1000))]
    pub solver_pgs_iterations: usize,
    /// Velocity relax pass after each substep; default: only with a ground plane.
    pub solver_relax_pass: Option<bool>,
    /// Coulomb friction coefficient between robot and ground (both sides set to it).
    #[schemars(range(min = 0))]
    pub friction: f64,
    /// Gravity, m/s².
    pub gravity: [f64; 3],
    /// Maximum torque of each velocity motor, N·m.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub motor_max_torque: f64,
    /// Velocity motor gain (Rapier's motor factor), 1/s-like; higher tracks tighter.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub motor_gain: f64,
    /// Rate (1/s) at which joint drives remove the error between joint angle and commanded
    /// angle ∫u dt (servo integral action); 0 = pure velocity motors.
    #[schemars(range(min = 0))]
    pub motor_angle_gain: f64,
    /// Extra simulated time after the plan ends, s (lets the body come to rest).
    #[schemars(range(min = 0))]
    pub settle: f64,
    /// `[sim.perturb]`: what reality adds to the physics replay (all off by default).
    pub perturb: Perturbation,
}

impl SimConfig {
    /// The physics layer's settings (everything but `settle` and the
    /// command and observation perturbations, which the replay takes), with
    /// the world perturbations of `[sim.perturb]` applied.
    pub fn physics(&self) -> crate::engine::PhysicsSettings {
        let p = &self.perturb;
        crate::engine::PhysicsSettings {
            dt: self.dt,
            solver_iterations: self.solver_iterations,
            pgs_iterations: self.solver_pgs_iterations,
            relax_pass: self.solver_relax_pass,
            friction: self.friction * p.friction_scale,
            gravity: self.gravity,
            motor_max_torque: self.motor_max_torque,
            torque_scale: p.torque_scale,
            motor_gain: self.motor_gain,
            motor_angle_gain: self.motor_angle_gain,
            mass_scale: p.mass_scale,
            wheel_radius_scale: p.wheel_radius_scale,
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
            perturb: Perturbation::default(),
        }
    }
}

/// A scenario file: what to plan, how to simulate it and which thresholds the
/// runs must meet. The keys of `[model]` and `[planner]` depend on their
/// `kind` and are on the model's and the planner's pages.
#[derive(Debug, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
struct ScenarioFile {
    /// Scenario name, also its log directory's name; default: the file name without `.toml`.
    name: Option<String>,
    /// One line shown by `anholonomy list`, the report and `summary.json`.
    description: Option<String>,
    /// `"fails"`: the scenario is meant to break a threshold (it shows a limit of the
    /// planner or of the model); its verdict is then XFAIL, and XPASS (a failure of
    /// `check`) when it meets every threshold. Needs `reason`.
    expect: Option<Expect>,
    /// Why the scenario is expected to fail (shown with its XFAIL or XPASS verdict).
    reason: Option<String>,
    /// Start state in the model's file coordinates: lengths in m, angles in degrees
    /// (the model's page lists them).
    start: Vec<f64>,
    /// Goal state, as `start`.
    goal: Vec<f64>,
    /// Rate limits and ramps of open-loop plans.
    #[serde(default)]
    limits: LimitsConfig,
    /// Physics settings of the replay (and the ideal run's step).
    #[serde(default)]
    sim: SimConfig,
    /// Metric name → largest allowed value; `check` exits 1 when one is broken.
    #[serde(default)]
    #[schemars(extend("minimum" = 0))]
    thresholds: BTreeMap<String, f64>,
    /// Metric name → smallest allowed value (a clearance, a success rate).
    #[serde(default)]
    minimums: BTreeMap<String, f64>,
    /// Monte Carlo variants: `run` and `check` run the sweep instead of one run.
    sweep: Option<SweepConfig>,
    /// Tolerances of the baseline comparison (`check --baseline`).
    #[serde(default)]
    regression: crate::scenario::regression::RegressionConfig,
    /// Least robustness margins `check` gates (searched after the nominal run).
    #[serde(default)]
    margins: MarginsConfig,
    /// A recording of the robot on this plan: a third run, with `real_*` metrics.
    compare: Option<CompareConfig>,
}

/// The verdict a scenario expects (`expect = "fails"`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum Expect {
    /// Meets every threshold (the default).
    Passes,
    /// Breaks a threshold on purpose.
    Fails,
}

/// The schema of the file's own keys (everything but `[model]` and `[planner]`).
pub(crate) fn file_schema() -> &'static schema::Schema {
    static SCHEMA: std::sync::OnceLock<schema::Schema> = std::sync::OnceLock::new();
    SCHEMA.get_or_init(schema::Schema::of::<ScenarioFile>)
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
    /// `expect = "fails"`: why the scenario is meant to break a threshold.
    pub expect_fails: Option<String>,
    /// Model.
    pub model: ModelConfig,
    /// Resolved URDF path.
    pub urdf: PathBuf,
    /// Where the URDF's meshes and xacro arguments come from (package
    /// directories resolved against the scenario's directory).
    pub urdf_source: crate::engine::urdf::Source,
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
    /// Metric name → minimum allowed value (`[minimums]`, e.g. a clearance).
    pub minimums: BTreeMap<String, f64>,
    /// Monte Carlo variants (`[sweep]`): `run`/`check` run the sweep instead of one run.
    pub sweep: Option<SweepConfig>,
    /// Baseline tolerance overrides (`[regression]`).
    pub regression: crate::scenario::regression::RegressionConfig,
    /// Margins `check` gates (`[margins]`) and how they are searched.
    pub margins: MarginsConfig,
    /// A recorded run to compare with (`[compare]`).
    pub compare: Option<CompareConfig>,
    /// Where each key is written, for errors found after parsing.
    #[serde(skip)]
    keys: Arc<KeyIndex>,
    /// The file's text (sweep variants are parsed from it, resumed sweeps check its hash).
    #[serde(skip)]
    text: Arc<str>,
    /// Values written over the file's ([`Scenario::replace`]), in order;
    /// variants are parsed with them.
    #[serde(skip)]
    edits: Arc<[Edit]>,
}

/// A value written over a scenario file's own: the key path and the value
/// as TOML text (`0.8`, `[1.0, 2.0]`, `"name"`, `{ a = 1 }`).
pub type Edit = (KeyPath, String);

/// Longest scenario name, bytes (it becomes a directory name, with room for
/// the staging suffix).
pub const MAX_NAME_BYTES: usize = 100;

/// Why `name` cannot be a log directory name, if it cannot.
pub(crate) fn name_problem(name: &str) -> Option<String> {
    if name.is_empty() {
        return Some("is empty".into());
    }
    if name.len() > MAX_NAME_BYTES {
        return Some(format!(
            "is {} bytes long (at most {MAX_NAME_BYTES})",
            name.len()
        ));
    }
    if let Some(c) = name.chars().find(|c| {
        c.is_control() || matches!(c, '/' | '\\' | ':' | '*' | '?' | '"' | '<' | '>' | '|')
    }) {
        return Some(format!("contains {}", crate::echo::code(&c.to_string())));
    }
    if name.starts_with('.') || name.starts_with(char::is_whitespace) {
        return Some("starts with a dot or a space".into());
    }
    if name.ends_with('.') || name.ends_with(char::is_whitespace) {
        return Some("ends with a dot or a space".into());
    }
    None
}

/// `[model] packages`, `xacro_args` and `missing_packages`: where every model's robot
/// description finds what it names. Read by the scenario layer (taken out
/// of `[model]` before the model's own keys), shown with each model's keys.
#[derive(Debug, Clone, Default, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct UrdfSourceConfig {
    /// ROS packages that `package://PKG/...` mesh URIs and xacro's `$(find PKG)`
    /// name: package name → directory, relative to the scenario file (searched
    /// before the package.xml above the URDF, `ROS_PACKAGE_PATH` and
    /// `AMENT_PREFIX_PATH`).
    #[serde(default)]
    pub packages: BTreeMap<String, PathBuf>,
    /// Arguments for xacro (`name:=value`), when the URDF holds xacro markup
    /// (the `xacro` command expands it: `pip install xacro`).
    #[serde(default)]
    pub xacro_args: BTreeMap<String, String>,
    /// What xacro makes of `$(find PKG)` for a package found nowhere.
    #[serde(default)]
    pub missing_packages: crate::engine::packages::MissingPackages,
}

impl Scenario {
    /// Read and validate a scenario file (a regular file of at most
    /// [`SCENARIO_MAX_BYTES`]).
    pub fn load(path: &Path) -> Result<Scenario, Error> {
        let text = read_text(path, "scenario", SCENARIO_MAX_BYTES)?;
        Self::parse(path, &text)
    }

    /// An input error about `key`, at its line: "key `key`: message".
    pub fn error_at(&self, key: &str, message: impl std::fmt::Display) -> Error {
        self.keys.error_at(&self.path, key, message)
    }

    /// A setup refusal (a system's, its physics') about this scenario: at
    /// the line of the key it is about.
    pub fn setup_error(&self, e: &crate::error::SetupError) -> Error {
        self.keys.setup_error(&self.path, e)
    }

    /// Whether `key` is written in the file.
    pub fn has_key(&self, key: &str) -> bool {
        self.keys.has(key)
    }

    /// Line of a key in the file (or of its table, when the key is defaulted).
    pub fn line_of(&self, key: &str) -> Option<usize> {
        self.keys.line_of(key)
    }

    /// The file's text as read.
    pub fn text(&self) -> &str {
        &self.text
    }

    /// Validate scenario text (`path` is used for messages and relative paths).
    pub fn parse(path: &Path, text: &str) -> Result<Scenario, Error> {
        let sc = Self::parse_with(path, text, &[], &[])?;
        if let Some(sw) = &sc.sweep {
            sc.check_vary(sw)?;
        }
        Ok(sc)
    }

    /// This scenario with values written over some keys (dotted key paths
    /// as in `[sweep.vary]`, each with its value as TOML text), parsed and
    /// checked like the file. Later changes of the same key win. Errors
    /// name the file, the line where the key is written (or its table's,
    /// when the file leaves it at its default) and the key.
    pub fn replace(&self, changes: &[(String, String)]) -> Result<Scenario, Error> {
        let mut edits: Vec<Edit> = self.edits.to_vec();
        for (key, value) in changes {
            let kp = KeyPath::parse(key).map_err(|e| Error::keyed(&self.path, None, key, e))?;
            edits.push((kp, value.clone()));
        }
        let sc = Self::parse_with(&self.path, &self.text, &edits, &[])?;
        if let Some(sw) = &sc.sweep {
            sc.check_vary(sw)?;
        }
        Ok(sc)
    }

    /// A sweep variant: the file with the variant's numbers written in (and
    /// no `[sweep]`), parsed and checked like the file, with the rover's σ
    /// and the mass scale (`sim.perturb.mass_scale`) of the variant.
    pub fn variant(&self, v: &Variant) -> Result<Scenario, Error> {
        let overrides: Vec<(KeyPath, f64)> = v
            .params
            .iter()
            .map(|(k, x)| {
                KeyPath::parse(k)
                    .map(|p| (p, *x))
                    .map_err(|e| self.error_at(k, e))
            })
            .collect::<Result<_, _>>()?;
        let mut sc = if overrides.is_empty() {
            let mut sc = self.clone();
            sc.sweep = None;
            sc
        } else {
            Self::parse_with(&self.path, &self.text, &self.edits, &overrides)?
        };
        // `sweep.mass_scale` is shorthand for `sim.perturb.mass_scale`.
        sc.sim.perturb.mass_scale *= v.mass_scale;
        if let (Some(rate), ModelConfig::Rover(m)) = (v.sigma_rate, &mut sc.model) {
            m.switching = crate::robots::rover::SwitchingConfig::Telegraph { seed: v.seed, rate };
        }
        Ok(sc)
    }

    /// `[sweep.vary]` against the file: each path must lead to a number (or
    /// to a key the file leaves at its default), and every value the
    /// distribution can produce at its ends must pass the file's own checks.
    fn check_vary(&self, sw: &SweepConfig) -> Result<(), Error> {
        let mut root = DeTable::parse(&self.text)
            .map_err(|e| KeyIndex::syntax_error(&self.path, &self.text, &e))?;
        Self::apply_edits(&self.path, &self.text, &mut root, &self.edits)?;
        for (path, dist) in &sw.vary {
            let key = vary_key(path);
            let err = |m: String| self.error_at(&key, m);
            let kp = KeyPath::parse(path).map_err(|e| err(e.to_string()))?;
            match keypath::find(root.get_ref(), &kp) {
                keypath::Found::Number { integer } => {
                    if integer && dist.continuous() {
                        return Err(err(format!(
                            "`{kp}` is an integer: sweep it with `values` or `grid`"
                        )));
                    }
                }
                keypath::Found::NotNumber(t) => {
                    return Err(err(format!("`{kp}` is {t}, not a number")))
                }
                keypath::Found::Unreachable(why) => {
                    return Err(err(format!("no such number in the file: {why}")))
                }
                keypath::Found::Absent => {
                    if let Some(why) = keypath::undeclared(root.get_ref(), &kp) {
                        return Err(err(why));
                    }
                }
            }
            for x in dist.probes() {
                let probe = [(kp.clone(), x)];
                if let Err(e) = Self::parse_with(&self.path, &self.text, &self.edits, &probe) {
                    let inner = match e {
                        Error::Input { message, .. } => message,
                        other => other.to_string(),
                    };
                    return Err(err(format!(
                        "with `{kp}` = {}: {inner}",
                        crate::numfmt::readable(x)
                    )));
                }
            }
        }
        Ok(())
    }
}

/// Expand files and directories (non-recursive, `*.toml` except hidden
/// files, sorted) into scenario paths. Each entry is read later, so one that
/// is not a regular file is an error, not silently skipped.
pub fn collect(paths: &[PathBuf]) -> Result<Vec<PathBuf>, Vec<Error>> {
    let mut out = Vec::new();
    let mut errors = Vec::new();
    for p in paths {
        if p.is_dir() {
            let rd = match std::fs::read_dir(p) {
                Ok(rd) => rd,
                Err(e) => {
                    errors.push(Error::input(p, format!("cannot list directory: {e}")));
                    continue;
                }
            };
            let mut files: Vec<PathBuf> = rd
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|f| f.extension().is_some_and(|x| x == "toml"))
                // Hidden entries are editor locks and backups (`.#a.toml`).
                .filter(|f| {
                    !f.file_name()
                        .is_some_and(|n| n.to_string_lossy().starts_with('.'))
                })
                .collect();
            files.sort();
            if files.is_empty() {
                errors.push(Error::input(p, "no *.toml scenario files in directory"));
            }
            out.extend(files);
        } else if p.exists() {
            out.push(p.clone());
        } else {
            errors.push(Error::input(p, "no such file or directory"));
        }
    }
    if errors.is_empty() {
        Ok(out)
    } else {
        Err(errors)
    }
}
