//! `[model]` and `[planner]`: the kinds a scenario can name, each with the
//! typed parameters its system or planner owns, and the model/planner
//! matching that hands a system its own plain configuration.
//!
//! Configuration flows one way: the systems, planners, models and physics
//! define plain parameter structs and never see these enums (nor anything
//! else of `crate::scenario`); this module picks the system for a pair.

use super::schema::{by_kind, Schema};
use crate::physics::required::Required;
use crate::planner::dilf::DilfParams;
use crate::planner::endogenous::EndogenousParams;
use crate::planner::external::ExternalParams;
use crate::planner::file::FilePlanParams;
use crate::planner::rover_primitives::RoverPrimitiveParams;
use crate::planner::sphere_geometric::SphereGeometricParams;
use crate::planner::sphere_triangle::SphereTriangleParams;
use crate::planner::stokes_disk::StokesDiskParams;
use crate::planner::stokes_space::StokesSpaceParams;
use crate::systems::car::CarConfig;
use crate::systems::diff_drive::DiffDriveConfig;
use crate::systems::dilf::MobileManipulatorConfig;
use crate::systems::disk::DiskModelConfig;
use crate::systems::own_plan::{self, Source};
use crate::systems::rover::RoverConfig;
use crate::systems::space_robot::{SpacePlanner, SpaceRobotConfig};
use crate::systems::sphere::{SphereConfig, SpherePlanner};
use crate::systems::{self, System};
use serde::de::DeserializeOwned;
use serde::Serialize;
use std::path::Path;
use std::sync::OnceLock;
use toml::de::{DeValue, ValueDeserializer};
use toml::Spanned;

/// `[model]`: the kinematic model and its rigid-body counterpart.
#[derive(Debug, Clone, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
// Parsed once per scenario: the size of the largest variant does not matter.
#[allow(clippy::large_enum_variant)]
pub enum ModelConfig {
    /// Seed 000 §4.2 disk rolling without slipping: state (x, y, θ, α), inputs (θ', α').
    RollingDisk(DiskModelConfig),
    /// Free-floating planar space robot (seeds 000 §4.1 and 001).
    SpaceRobot(SpaceRobotConfig),
    /// Overconstrained rover with feedback primitives (seed 002).
    Rover(RoverConfig),
    /// Sphere rolling on a plane (seed 003).
    RollingSphere(SphereConfig),
    /// Mobile manipulators among ellipsoid obstacles (seed 004).
    MobileManipulator(MobileManipulatorConfig),
    /// Differential drive: unicycle kinematics (x, y, θ), inputs (v, ω).
    DiffDrive(DiffDriveConfig),
    /// Car-like robot: kinematic bicycle (x, y, θ, φ), inputs (v, φ').
    Car(CarConfig),
}

/// `[planner]`: which planner, with its parameters.
#[derive(Debug, Clone, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum PlannerConfig {
    /// Seed 000 §4.2 Stokes planner for the rolling disk.
    StokesDisk(StokesDiskParams),
    /// Seed 000 §4.1 Stokes planner for the space robot.
    StokesSpace(StokesSpaceParams),
    /// Seed 001 endogenous-configuration-space Jacobian planner.
    Endogenous(EndogenousParams),
    /// Seed 002 feedback primitives P1–P3.
    RoverPrimitives(RoverPrimitiveParams),
    /// Seed 003 §3 geometric (A)-(B)-(A) planner.
    SphereGeometric(SphereGeometricParams),
    /// Seed 003 §4 spherical-triangle planner.
    SphereTriangle(SphereTriangleParams),
    /// Seed 004 dipolar inverse Lyapunov function, feedback law of Eq. 18.
    Dilf(DilfParams),
    /// A plan read from a CSV, JSON or MCAP file (any model).
    File(FilePlanParams),
    /// A feedback law in another process, spoken to over stdin/stdout (any model).
    External(ExternalParams),
}

/// Planner kinds that plan for every model: the plan comes from outside
/// the harness (see [`crate::systems::own_plan`]).
pub const OUTSIDE: [&str; 2] = ["file", "external"];

/// Which built-in planners plan for which model (`model kind`, `planner
/// kinds`); the [`OUTSIDE`] kinds plan for every model besides. A model
/// without a planner of its own has an empty list.
pub const PAIRS: [(&str, &[&str]); 7] = [
    ("rolling_disk", &["stokes_disk"]),
    ("space_robot", &["stokes_space", "endogenous"]),
    ("rover", &["rover_primitives"]),
    ("rolling_sphere", &["sphere_geometric", "sphere_triangle"]),
    ("mobile_manipulator", &["dilf"]),
    ("diff_drive", &[]),
    ("car", &[]),
];

/// Typed parameters from a table (its `kind` already removed); serde errors
/// keep the document's spans, so they name the key and line inside the table.
fn de<T: DeserializeOwned>(v: Spanned<DeValue<'_>>) -> Result<T, toml::de::Error> {
    T::deserialize(ValueDeserializer::from(v))
}

impl ModelConfig {
    /// Every model `kind`.
    pub const KINDS: [&'static str; 7] = [
        "rolling_disk",
        "space_robot",
        "rover",
        "rolling_sphere",
        "mobile_manipulator",
        "diff_drive",
        "car",
    ];

    /// The `kind` string.
    pub fn kind(&self) -> &'static str {
        match self {
            ModelConfig::RollingDisk(_) => "rolling_disk",
            ModelConfig::SpaceRobot(_) => "space_robot",
            ModelConfig::Rover(_) => "rover",
            ModelConfig::RollingSphere(_) => "rolling_sphere",
            ModelConfig::MobileManipulator(_) => "mobile_manipulator",
            ModelConfig::DiffDrive(_) => "diff_drive",
            ModelConfig::Car(_) => "car",
        }
    }

    /// The URDF path as written (relative to the scenario file).
    pub fn urdf(&self) -> &Path {
        match self {
            ModelConfig::RollingDisk(m) => &m.urdf,
            ModelConfig::SpaceRobot(m) => &m.urdf,
            ModelConfig::Rover(m) => &m.urdf,
            ModelConfig::RollingSphere(m) => &m.urdf,
            ModelConfig::MobileManipulator(m) => &m.urdf,
            ModelConfig::DiffDrive(m) => &m.urdf,
            ModelConfig::Car(m) => &m.urdf,
        }
    }

    /// The schema of the `[model]` table of `kind` (its keys, defaults,
    /// ranges and docs): what the validation pass checks and `keys` prints.
    pub fn schema(kind: &str) -> Option<&'static Schema> {
        static CACHE: OnceLock<Vec<(&'static str, Schema)>> = OnceLock::new();
        by_kind(&CACHE, &Self::KINDS, kind, |k| {
            let source = Schema::of::<super::UrdfSourceConfig>();
            Some(
                match k {
                    "rolling_disk" => Schema::of::<DiskModelConfig>(),
                    "space_robot" => Schema::of::<SpaceRobotConfig>(),
                    "rover" => Schema::of::<RoverConfig>(),
                    "rolling_sphere" => Schema::of::<SphereConfig>(),
                    "mobile_manipulator" => Schema::of::<MobileManipulatorConfig>(),
                    "diff_drive" => Schema::of::<DiffDriveConfig>(),
                    "car" => Schema::of::<CarConfig>(),
                    _ => return None,
                }
                .with_properties_of(&source),
            )
        })
    }

    /// The URDF links and joints the model `kind` looks up, as declared by
    /// its physics module (default names, renaming keys, roles): what the
    /// validation pass checks and the reference lists. `None` for an
    /// unknown kind.
    pub fn required_urdf(kind: &str) -> Option<&'static [Required]> {
        use crate::physics as p;
        Some(match kind {
            "rolling_disk" => &p::disk::REQUIRED,
            "space_robot" => &p::space_robot::REQUIRED,
            "rover" => &p::rover::REQUIRED,
            "rolling_sphere" => &p::sphere::REQUIRED,
            "mobile_manipulator" => &p::mobile_manipulator::REQUIRED,
            "diff_drive" => &p::diff_drive::REQUIRED,
            "car" => &p::car::REQUIRED,
            _ => return None,
        })
    }

    /// The model of `kind` from its table; `Ok(None)` for an unknown kind.
    pub(crate) fn parse(
        kind: &str,
        table: Spanned<DeValue<'_>>,
    ) -> Result<Option<Self>, toml::de::Error> {
        Ok(Some(match kind {
            "rolling_disk" => ModelConfig::RollingDisk(de(table)?),
            "space_robot" => ModelConfig::SpaceRobot(de(table)?),
            "rover" => ModelConfig::Rover(de(table)?),
            "rolling_sphere" => ModelConfig::RollingSphere(de(table)?),
            "mobile_manipulator" => ModelConfig::MobileManipulator(de(table)?),
            "diff_drive" => ModelConfig::DiffDrive(de(table)?),
            "car" => ModelConfig::Car(de(table)?),
            _ => return Ok(None),
        }))
    }
}

impl PlannerConfig {
    /// Every planner `kind`.
    pub const KINDS: [&'static str; 9] = [
        "stokes_disk",
        "stokes_space",
        "endogenous",
        "rover_primitives",
        "sphere_geometric",
        "sphere_triangle",
        "dilf",
        "file",
        "external",
    ];

    /// The `kind` string.
    pub fn kind(&self) -> &'static str {
        match self {
            PlannerConfig::StokesDisk(_) => "stokes_disk",
            PlannerConfig::StokesSpace(_) => "stokes_space",
            PlannerConfig::Endogenous(_) => "endogenous",
            PlannerConfig::RoverPrimitives(_) => "rover_primitives",
            PlannerConfig::SphereGeometric(_) => "sphere_geometric",
            PlannerConfig::SphereTriangle(_) => "sphere_triangle",
            PlannerConfig::Dilf(_) => "dilf",
            PlannerConfig::File(_) => "file",
            PlannerConfig::External(_) => "external",
        }
    }

    /// Paths in the planner's parameters are relative to `dir`, the
    /// scenario file's directory (a plan file, an external law's directory).
    pub(crate) fn set_base(&mut self, dir: &Path) {
        match self {
            PlannerConfig::File(p) => p.base = dir.to_path_buf(),
            PlannerConfig::External(p) => p.base = dir.to_path_buf(),
            _ => {}
        }
    }

    /// The schema of the `[planner]` table of `kind` (see [`ModelConfig::schema`]).
    pub fn schema(kind: &str) -> Option<&'static Schema> {
        static CACHE: OnceLock<Vec<(&'static str, Schema)>> = OnceLock::new();
        by_kind(&CACHE, &Self::KINDS, kind, |k| {
            Some(match k {
                "stokes_disk" => Schema::of::<StokesDiskParams>(),
                "stokes_space" => Schema::of::<StokesSpaceParams>(),
                "endogenous" => Schema::of::<EndogenousParams>(),
                "rover_primitives" => Schema::of::<RoverPrimitiveParams>(),
                "sphere_geometric" => Schema::of::<SphereGeometricParams>(),
                "sphere_triangle" => Schema::of::<SphereTriangleParams>(),
                "dilf" => Schema::of::<DilfParams>(),
                "file" => Schema::of::<FilePlanParams>(),
                "external" => Schema::of::<ExternalParams>(),
                _ => return None,
            })
        })
    }

    /// The planner of `kind` from its table; `Ok(None)` for an unknown kind.
    pub(crate) fn parse(
        kind: &str,
        table: Spanned<DeValue<'_>>,
    ) -> Result<Option<Self>, toml::de::Error> {
        Ok(Some(match kind {
            "stokes_disk" => PlannerConfig::StokesDisk(de(table)?),
            "stokes_space" => PlannerConfig::StokesSpace(de(table)?),
            "endogenous" => PlannerConfig::Endogenous(de(table)?),
            "rover_primitives" => PlannerConfig::RoverPrimitives(de(table)?),
            "sphere_geometric" => PlannerConfig::SphereGeometric(de(table)?),
            "sphere_triangle" => PlannerConfig::SphereTriangle(de(table)?),
            "dilf" => PlannerConfig::Dilf(de(table)?),
            "file" => PlannerConfig::File(de(table)?),
            "external" => PlannerConfig::External(de(table)?),
            _ => return Ok(None),
        }))
    }
}

/// The system for a model and planner: each system gets its own typed
/// configuration. A planner that does not fit the model is a user error
/// naming `planner.kind` and the planners that do fit. A plan file or an
/// external law wraps the model's own system ([`own_plan`]).
pub fn build_system(
    model: &ModelConfig,
    planner: &PlannerConfig,
) -> Result<Box<dyn System>, String> {
    let source = match planner {
        PlannerConfig::File(p) => Source::File(p.clone()),
        PlannerConfig::External(p) => Source::External(p.clone()),
        _ => return builtin_system(model, planner),
    };
    own_plan::wrap(model_system(model, planner)?, source)
}

/// The system of `model` for a plan from outside: built with its first
/// built-in planner (per [`PAIRS`]) at that planner's defaults; the wrapper
/// replaces only `plan` (metrics that read planner parameters, e.g. the
/// rover's ε in `*_time_to_goal`, see those defaults). A model without a
/// built-in planner is built with the `outside` planner itself: its arm in
/// [`builtin_system`] accepts any planner.
pub(crate) fn model_system(
    model: &ModelConfig,
    outside: &PlannerConfig,
) -> Result<Box<dyn System>, String> {
    let first = PAIRS
        .iter()
        .find(|(m, _)| *m == model.kind())
        .and_then(|(_, p)| p.first());
    let Some(kind) = first else {
        return builtin_system(model, outside);
    };
    let empty = Spanned::new(0..0, DeValue::Table(toml::de::DeTable::new()));
    let defaults = PlannerConfig::parse(kind, empty)
        .map_err(|e| format!("planner `{kind}` has no defaults: {e}"))?
        .ok_or_else(|| format!("unknown planner `{kind}` in PAIRS"))?;
    builtin_system(model, &defaults)
}

/// The system for a model and one of its built-in planners.
fn builtin_system(model: &ModelConfig, planner: &PlannerConfig) -> Result<Box<dyn System>, String> {
    use ModelConfig as M;
    use PlannerConfig as P;
    match (model, planner) {
        (M::RollingDisk(m), P::StokesDisk(p)) => systems::disk::build(m, p),
        (M::SpaceRobot(m), P::StokesSpace(p)) => {
            systems::space_robot::build(m, SpacePlanner::Stokes(p.clone()))
        }
        (M::SpaceRobot(m), P::Endogenous(p)) => {
            systems::space_robot::build(m, SpacePlanner::Endogenous(p.clone()))
        }
        (M::Rover(m), P::RoverPrimitives(p)) => systems::rover::build(m, p),
        (M::RollingSphere(m), P::SphereGeometric(p)) => {
            systems::sphere::build(m, SpherePlanner::Geometric(p.clone()))
        }
        (M::RollingSphere(m), P::SphereTriangle(p)) => {
            systems::sphere::build(m, SpherePlanner::Triangle(p.clone()))
        }
        (M::MobileManipulator(m), P::Dilf(p)) => systems::dilf::build(m, p),
        // No planner of their own: only plans from outside, which wrap them.
        (M::DiffDrive(m), P::File(_) | P::External(_)) => systems::diff_drive::build(m),
        (M::Car(m), P::File(_) | P::External(_)) => systems::car::build(m),
        (m, p) => Err(mismatch(m.kind(), p.kind())),
    }
}

/// Whether the planner `kind` plans for the model `kind` (per [`PAIRS`];
/// the [`OUTSIDE`] kinds plan for every model).
pub fn plans_for(model: &str, planner: &str) -> bool {
    PAIRS
        .iter()
        .any(|(m, p)| *m == model && (p.contains(&planner) || OUTSIDE.contains(&planner)))
}

/// The planner kinds that plan for `model`: its own, then [`OUTSIDE`].
pub fn planners_for(model: &str) -> Vec<&'static str> {
    let own = PAIRS.iter().find(|(m, _)| *m == model).map(|(_, p)| *p);
    own.unwrap_or_default()
        .iter()
        .chain(OUTSIDE.iter())
        .copied()
        .collect()
}

/// The error for a planner that does not plan for the model.
pub(crate) fn mismatch(model: &str, planner: &str) -> String {
    let fits = planners_for(model);
    let fits = match fits.split_last() {
        Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
        _ => fits.join(""),
    };
    format!("key `planner.kind`: `{planner}` does not plan for model `{model}` (use {fits})")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table(kind: &str, extra: &str) -> Spanned<DeValue<'static>> {
        // Leaked: a test-only document must outlive the borrowed table.
        let text: &'static str = format!("kind = \"{kind}\"\n{extra}").leak();
        let mut t = toml::de::DeTable::parse(text).unwrap().into_inner();
        t.remove("kind");
        Spanned::new(0..0, DeValue::Table(t))
    }

    /// `PAIRS` (used in messages) agrees with what [`build_system`] accepts.
    #[test]
    fn pairs_table_matches_build_system() {
        let models: Vec<ModelConfig> = ModelConfig::KINDS
            .iter()
            .map(|k| {
                let radius = if k.starts_with("rolling") {
                    "radius = 1.0\n"
                } else {
                    ""
                };
                let v = table(k, &format!("urdf = \"x.urdf\"\n{radius}"));
                ModelConfig::parse(k, v).unwrap().unwrap()
            })
            .collect();
        // The outside kinds need a file / a program that exist.
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("p.csv"), "t,x\n").unwrap();
        let planners: Vec<PlannerConfig> = PlannerConfig::KINDS
            .iter()
            .map(|k| {
                let params = match *k {
                    "file" => "path = \"p.csv\"",
                    "external" => "command = [\"sh\"]\nperiod = 0.1\nhorizon = 1.0",
                    _ => "",
                };
                let mut p = PlannerConfig::parse(k, table(k, params)).unwrap().unwrap();
                p.set_base(dir.path());
                p
            })
            .collect();
        for m in &models {
            let fits = planners_for(m.kind());
            for p in &planners {
                let r = build_system(m, p);
                assert_eq!(
                    r.is_ok(),
                    fits.contains(&p.kind()),
                    "{} + {}: {:?}",
                    m.kind(),
                    p.kind(),
                    r.err()
                );
                if let Err(e) = r {
                    assert!(e.starts_with("key `planner.kind`"), "{e}");
                }
            }
        }
        assert!(ModelConfig::parse("teleport", table("teleport", ""))
            .unwrap()
            .is_none());
    }
}
