//! `[model]` and `[planner]`: the kinds a scenario can name, each with the
//! typed parameters its system or planner owns, and the model/planner
//! matching that hands a system its own plain configuration.
//!
//! Configuration flows one way: the systems, planners, models and physics
//! define plain parameter structs and never see these enums (nor anything
//! else of `crate::scenario`); this module picks the system for a pair.

use super::schema::Schema;
use crate::physics::required::Required;
use crate::planner::dilf::DilfParams;
use crate::planner::endogenous::EndogenousParams;
use crate::planner::rover_primitives::RoverPrimitiveParams;
use crate::planner::sphere_geometric::SphereGeometricParams;
use crate::planner::sphere_triangle::SphereTriangleParams;
use crate::planner::stokes_disk::StokesDiskParams;
use crate::planner::stokes_space::StokesSpaceParams;
use crate::systems::dilf::MobileManipulatorConfig;
use crate::systems::disk::DiskModelConfig;
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
}

/// Which planners plan for which model (`model kind`, `planner kinds`).
pub const PAIRS: [(&str, &[&str]); 5] = [
    ("rolling_disk", &["stokes_disk"]),
    ("space_robot", &["stokes_space", "endogenous"]),
    ("rover", &["rover_primitives"]),
    ("rolling_sphere", &["sphere_geometric", "sphere_triangle"]),
    ("mobile_manipulator", &["dilf"]),
];

/// Typed parameters from a table (its `kind` already removed); serde errors
/// keep the document's spans, so they name the key and line inside the table.
fn de<T: DeserializeOwned>(v: Spanned<DeValue<'_>>) -> Result<T, toml::de::Error> {
    T::deserialize(ValueDeserializer::from(v))
}

impl ModelConfig {
    /// Every model `kind`.
    pub const KINDS: [&'static str; 5] = [
        "rolling_disk",
        "space_robot",
        "rover",
        "rolling_sphere",
        "mobile_manipulator",
    ];

    /// The `kind` string.
    pub fn kind(&self) -> &'static str {
        match self {
            ModelConfig::RollingDisk(_) => "rolling_disk",
            ModelConfig::SpaceRobot(_) => "space_robot",
            ModelConfig::Rover(_) => "rover",
            ModelConfig::RollingSphere(_) => "rolling_sphere",
            ModelConfig::MobileManipulator(_) => "mobile_manipulator",
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
        }
    }

    /// The schema of the `[model]` table of `kind` (its keys, defaults,
    /// ranges and docs): what the validation pass checks and `keys` prints.
    pub fn schema(kind: &str) -> Option<&'static Schema> {
        static CACHE: OnceLock<Vec<(&'static str, Schema)>> = OnceLock::new();
        let all = CACHE.get_or_init(|| {
            Self::KINDS
                .iter()
                .filter_map(|k| {
                    let s = match *k {
                        "rolling_disk" => Schema::of::<DiskModelConfig>(),
                        "space_robot" => Schema::of::<SpaceRobotConfig>(),
                        "rover" => Schema::of::<RoverConfig>(),
                        "rolling_sphere" => Schema::of::<SphereConfig>(),
                        "mobile_manipulator" => Schema::of::<MobileManipulatorConfig>(),
                        _ => return None,
                    };
                    Some((*k, s))
                })
                .collect()
        });
        all.iter().find(|(k, _)| *k == kind).map(|(_, s)| s)
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
            _ => return Ok(None),
        }))
    }
}

impl PlannerConfig {
    /// Every planner `kind`.
    pub const KINDS: [&'static str; 7] = [
        "stokes_disk",
        "stokes_space",
        "endogenous",
        "rover_primitives",
        "sphere_geometric",
        "sphere_triangle",
        "dilf",
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
        }
    }

    /// The schema of the `[planner]` table of `kind` (see [`ModelConfig::schema`]).
    pub fn schema(kind: &str) -> Option<&'static Schema> {
        static CACHE: OnceLock<Vec<(&'static str, Schema)>> = OnceLock::new();
        let all = CACHE.get_or_init(|| {
            Self::KINDS
                .iter()
                .filter_map(|k| {
                    let s = match *k {
                        "stokes_disk" => Schema::of::<StokesDiskParams>(),
                        "stokes_space" => Schema::of::<StokesSpaceParams>(),
                        "endogenous" => Schema::of::<EndogenousParams>(),
                        "rover_primitives" => Schema::of::<RoverPrimitiveParams>(),
                        "sphere_geometric" => Schema::of::<SphereGeometricParams>(),
                        "sphere_triangle" => Schema::of::<SphereTriangleParams>(),
                        "dilf" => Schema::of::<DilfParams>(),
                        _ => return None,
                    };
                    Some((*k, s))
                })
                .collect()
        });
        all.iter().find(|(k, _)| *k == kind).map(|(_, s)| s)
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
            _ => return Ok(None),
        }))
    }
}

/// The system for a model and planner: each system gets its own typed
/// configuration. A planner that does not fit the model is a user error
/// naming `planner.kind` and the planners that do fit.
pub fn build_system(
    model: &ModelConfig,
    planner: &PlannerConfig,
) -> Result<Box<dyn System>, String> {
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
        (m, p) => Err(mismatch(m.kind(), p.kind())),
    }
}

/// Whether the planner `kind` plans for the model `kind` (per [`PAIRS`]).
pub fn plans_for(model: &str, planner: &str) -> bool {
    PAIRS
        .iter()
        .any(|(m, p)| *m == model && p.contains(&planner))
}

/// The error for a planner that does not plan for the model.
pub(crate) fn mismatch(model: &str, planner: &str) -> String {
    let fits = PAIRS
        .iter()
        .find(|(m, _)| *m == model)
        .map(|(_, p)| p.join(" or "))
        .unwrap_or_default();
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
        let planners: Vec<PlannerConfig> = PlannerConfig::KINDS
            .iter()
            .map(|k| PlannerConfig::parse(k, table(k, "")).unwrap().unwrap())
            .collect();
        for m in &models {
            let fits = PAIRS.iter().find(|(k, _)| *k == m.kind()).unwrap().1;
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
