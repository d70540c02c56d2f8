//! `[model]` and `[planner]`: the kinds a scenario can name, each with the
//! typed parameters its system or planner owns, and the model/planner
//! matching that hands a system its own plain configuration.
//!
//! Configuration flows one way: the systems, planners, models and physics
//! define plain parameter structs and never see these enums (nor anything
//! else of `crate::scenario`); this module picks the system for a pair.

use crate::engine::required::Required;
use crate::error::SetupError;
use crate::planner::endogenous::EndogenousParams;
use crate::robots::car::CarConfig;
use crate::robots::declared::DeclaredConfig;
use crate::robots::diff_drive::DiffDriveConfig;
use crate::robots::mobile_manipulator::dilf::DilfParams;
use crate::robots::mobile_manipulator::MobileManipulatorConfig;
use crate::robots::rolling_disk::stokes::StokesDiskParams;
use crate::robots::rolling_disk::DiskModelConfig;
use crate::robots::rolling_sphere::geometric::SphereGeometricParams;
use crate::robots::rolling_sphere::triangle::SphereTriangleParams;
use crate::robots::rolling_sphere::{SphereConfig, SpherePlanner};
use crate::robots::rover::primitives::RoverPrimitiveParams;
use crate::robots::rover::RoverConfig;
use crate::robots::space_robot::stokes::StokesSpaceParams;
use crate::robots::space_robot::{SpacePlanner, SpaceRobotConfig};
use crate::robots::{self, System};
use crate::scenario::schema::{by_kind, Schema};
use crate::sources::external::ExternalParams;
use crate::sources::file::FilePlanParams;
use crate::sources::own_plan::{self, Source};
use serde::de::DeserializeOwned;
use serde::Serialize;
use std::path::Path;
use std::sync::OnceLock;
use toml::de::{DeValue, ValueDeserializer};
use toml::Spanned;

/// The kinds a scenario can name: one row per model and per planner.
///
/// A model row gives its `kind`, its variant and configuration type, the
/// URDF names its physics looks up (`REQUIRED`), and how its system is
/// built: with each of its own planners (`kind => |model, Variant(params)|
/// build`), and, for a model without planners of its own, with a plan from
/// outside (`outside: |model| build`). A planner row gives its `kind`, its
/// variant and parameter type. The enums, the kind lists, the schema
/// lookups, the required-URDF tables, [`PAIRS`] and the build arms are
/// generated from the rows: adding a model is a system module and one row.
macro_rules! registry {
    (
        models {
            $(
                $(#[doc = $mdoc:literal])*
                $mkind:literal => $MVar:ident($MCfg:ty) {
                    required: $req:expr,
                    planners: [ $( $pkindm:literal => |$m:ident, $PVm:ident($p:pat_param)| $build:expr ),* $(,)? ],
                    outside: $outside:expr $(,)?
                }
            )*
        }
        planners {
            $(
                $(#[doc = $pdoc:literal])*
                $pkind:literal => $PVar:ident($PCfg:ty)
            ),* $(,)?
        }
    ) => {
        /// `[model]`: the kinematic model and its rigid-body counterpart.
        #[derive(Debug, Clone, Serialize)]
        #[serde(tag = "kind", rename_all = "snake_case")]
        // Parsed once per scenario: the size of the largest variant does not matter.
        #[allow(clippy::large_enum_variant)]
        pub enum ModelConfig {
            $( $(#[doc = $mdoc])* $MVar($MCfg), )*
        }

        /// `[planner]`: which planner, with its parameters.
        #[derive(Debug, Clone, Serialize)]
        #[serde(tag = "kind", rename_all = "snake_case")]
        pub enum PlannerConfig {
            $( $(#[doc = $pdoc])* $PVar($PCfg), )*
        }

        /// Which built-in planners plan for which model (`model kind`,
        /// `planner kinds`); the [`OUTSIDE`] kinds plan for every model
        /// besides. A model without a planner of its own has an empty list.
        pub const PAIRS: &[(&str, &[&str])] = &[ $( ($mkind, &[ $( $pkindm ),* ]), )* ];

        impl ModelConfig {
            /// Every model `kind`.
            pub const KINDS: &'static [&'static str] = &[ $( $mkind ),* ];

            /// The `kind` string.
            pub fn kind(&self) -> &'static str {
                match self { $( ModelConfig::$MVar(_) => $mkind, )* }
            }

            /// The URDF path as written (relative to the scenario file).
            pub fn urdf(&self) -> &Path {
                match self { $( ModelConfig::$MVar(m) => &m.urdf, )* }
            }

            /// The schema of the `[model]` table of `kind` (its keys,
            /// defaults, ranges and docs, with the URDF source keys every
            /// model shares): what the validation pass checks and `keys` prints.
            pub fn schema(kind: &str) -> Option<&'static Schema> {
                static CACHE: OnceLock<Vec<(&'static str, Schema)>> = OnceLock::new();
                by_kind(&CACHE, Self::KINDS, kind, |k| {
                    let source = Schema::of::<crate::scenario::UrdfSourceConfig>();
                    Some(match k {
                        $( $mkind => Schema::of::<$MCfg>(), )*
                        _ => return None,
                    }
                    .with_properties_of(&source))
                })
            }

            /// The URDF links and joints the model `kind` looks up, as
            /// declared by its physics module (default names, renaming keys,
            /// roles): what the validation pass checks and the reference
            /// lists. `None` for an unknown kind.
            pub fn required_urdf(kind: &str) -> Option<&'static [Required]> {
                Some(match kind {
                    $( $mkind => &$req, )*
                    _ => return None,
                })
            }

            /// The model of `kind` from its table; `Ok(None)` for an unknown kind.
            pub(crate) fn parse(
                kind: &str,
                table: Spanned<DeValue<'_>>,
            ) -> Result<Option<Self>, toml::de::Error> {
                Ok(Some(match kind {
                    $( $mkind => ModelConfig::$MVar(de(table)?), )*
                    _ => return Ok(None),
                }))
            }
        }

        impl PlannerConfig {
            /// Every planner `kind`.
            pub const KINDS: &'static [&'static str] = &[ $( $pkind ),* ];

            /// The `kind` string.
            pub fn kind(&self) -> &'static str {
                match self { $( PlannerConfig::$PVar(_) => $pkind, )* }
            }

            /// The schema of the `[planner]` table of `kind` (see [`ModelConfig::schema`]).
            pub fn schema(kind: &str) -> Option<&'static Schema> {
                static CACHE: OnceLock<Vec<(&'static str, Schema)>> = OnceLock::new();
                by_kind(&CACHE, Self::KINDS, kind, |k| {
                    Some(match k {
                        $( $pkind => Schema::of::<$PCfg>(), )*
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
                    $( $pkind => PlannerConfig::$PVar(de(table)?), )*
                    _ => return Ok(None),
                }))
            }
        }

        /// The system for a model and one of its built-in planners, or (for
        /// a model without planners of its own) a plan from outside.
        #[allow(unreachable_patterns)]
        fn builtin_system(
            model: &ModelConfig,
            planner: &PlannerConfig,
        ) -> Result<Box<dyn System>, SetupError> {
            match (model, planner) {
                $(
                    $( (ModelConfig::$MVar($m), PlannerConfig::$PVm($p)) => $build, )*
                    (ModelConfig::$MVar(m), PlannerConfig::File(_) | PlannerConfig::External(_)) => {
                        match ($outside)(m) {
                            Some(built) => built,
                            None => Err(mismatch(model.kind(), planner.kind())),
                        }
                    }
                )*
                (m, p) => Err(mismatch(m.kind(), p.kind())),
            }
        }
    };
}

/// A model with planners of its own: plans from outside wrap its system
/// built with its first planner ([`model_system`]), never this.
fn own_planners<M>(_: &M) -> Option<Result<Box<dyn System>, SetupError>> {
    None
}

registry! {
    models {
        /// Seed 000 §4.2 disk rolling without slipping: state (x, y, θ, α), inputs (θ', α').
        "rolling_disk" => RollingDisk(DiskModelConfig) {
            required: crate::robots::rolling_disk::physics::REQUIRED,
            planners: ["stokes_disk" => |m, StokesDisk(p)| robots::rolling_disk::build(m, p)],
            outside: own_planners,
        }
        /// Free-floating planar space robot (seeds 000 §4.1 and 001).
        "space_robot" => SpaceRobot(SpaceRobotConfig) {
            required: crate::robots::space_robot::physics::REQUIRED,
            planners: [
                "stokes_space" => |m, StokesSpace(p)| robots::space_robot::build(m, SpacePlanner::Stokes(p.clone())),
                "endogenous" => |m, Endogenous(p)| robots::space_robot::build(m, SpacePlanner::Endogenous(p.clone())),
            ],
            outside: own_planners,
        }
        /// Overconstrained rover with feedback primitives (seed 002).
        "rover" => Rover(RoverConfig) {
            required: crate::robots::rover::physics::REQUIRED,
            planners: ["rover_primitives" => |m, RoverPrimitives(p)| robots::rover::build(m, p)],
            outside: own_planners,
        }
        /// Sphere rolling on a plane (seed 003).
        "rolling_sphere" => RollingSphere(SphereConfig) {
            required: crate::robots::rolling_sphere::physics::REQUIRED,
            planners: [
                "sphere_geometric" => |m, SphereGeometric(p)| robots::rolling_sphere::build(m, SpherePlanner::Geometric(p.clone())),
                "sphere_triangle" => |m, SphereTriangle(p)| robots::rolling_sphere::build(m, SpherePlanner::Triangle(p.clone())),
            ],
            outside: own_planners,
        }
        /// Mobile manipulators among ellipsoid obstacles (seed 004).
        "mobile_manipulator" => MobileManipulator(MobileManipulatorConfig) {
            required: crate::robots::mobile_manipulator::physics::REQUIRED,
            planners: ["dilf" => |m, Dilf(p)| robots::mobile_manipulator::build(m, p)],
            outside: own_planners,
        }
        /// Differential drive: unicycle kinematics (x, y, θ), inputs (v, ω).
        "diff_drive" => DiffDrive(DiffDriveConfig) {
            required: crate::robots::diff_drive::physics::REQUIRED,
            planners: [],
            outside: |m| Some(robots::diff_drive::build(m)),
        }
        /// Car-like robot: kinematic bicycle (x, y, θ, φ), inputs (v, φ'); steered by angle (x, y, θ), inputs (v, φ).
        "car" => Car(CarConfig) {
            required: crate::robots::car::physics::REQUIRED,
            planners: [],
            outside: |m| Some(robots::car::build(m)),
        }
        /// A model declared in the scenario: q' = f(q, u), its drives and read-back.
        "declared" => Declared(DeclaredConfig) {
            required: [],
            planners: [
                "endogenous" => |m, Endogenous(p)| robots::declared::build_planned(m, Some(p.clone())),
            ],
            outside: |m| Some(robots::declared::build(m)),
        }
    }
    planners {
        /// Seed 000 §4.2 Stokes planner for the rolling disk.
        "stokes_disk" => StokesDisk(StokesDiskParams),
        /// Seed 000 §4.1 Stokes planner for the space robot.
        "stokes_space" => StokesSpace(StokesSpaceParams),
        /// Seed 001 endogenous-configuration-space Jacobian planner.
        "endogenous" => Endogenous(EndogenousParams),
        /// Seed 002 feedback primitives P1–P3.
        "rover_primitives" => RoverPrimitives(RoverPrimitiveParams),
        /// Seed 003 §3 geometric (A)-(B)-(A) planner.
        "sphere_geometric" => SphereGeometric(SphereGeometricParams),
        /// Seed 003 §4 spherical-triangle planner.
        "sphere_triangle" => SphereTriangle(SphereTriangleParams),
        /// Seed 004 dipolar inverse Lyapunov function, feedback law of Eq. 18.
        "dilf" => Dilf(DilfParams),
        /// A plan read from a CSV, JSON or MCAP file, or a ROS 2 bag's command topic (any model).
        "file" => File(FilePlanParams),
        /// A feedback law in another process, spoken to over stdin/stdout (any model).
        "external" => External(ExternalParams),
    }
}

/// Planner kinds that plan for every model: the plan comes from outside
/// the harness (see [`crate::sources::own_plan`]).
pub const OUTSIDE: [&str; 2] = ["file", "external"];

/// Typed parameters from a table (its `kind` already removed); serde errors
/// keep the document's spans, so they name the key and line inside the table.
fn de<T: DeserializeOwned>(v: Spanned<DeValue<'_>>) -> Result<T, toml::de::Error> {
    T::deserialize(ValueDeserializer::from(v))
}

impl PlannerConfig {
    /// Paths in the planner's parameters are relative to `dir`, the
    /// scenario file's directory (a plan file, an external law's directory).
    pub(crate) fn set_base(&mut self, dir: &Path) {
        match self {
            PlannerConfig::File(p) => p.base = dir.to_path_buf(),
            PlannerConfig::External(p) => p.base = dir.to_path_buf(),
            _ => {}
        }
    }
}

/// The system for a model and planner: each system gets its own typed
/// configuration. A planner that does not fit the model is a user error
/// naming `planner.kind` and the planners that do fit. A plan file or an
/// external law wraps the model's own system ([`own_plan`]).
pub fn build_system(
    model: &ModelConfig,
    planner: &PlannerConfig,
) -> Result<Box<dyn System>, SetupError> {
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
) -> Result<Box<dyn System>, SetupError> {
    let first = PAIRS
        .iter()
        .find(|(m, _)| *m == model.kind())
        .and_then(|(_, p)| p.first());
    let Some(kind) = first else {
        return builtin_system(model, outside);
    };
    let empty = Spanned::new(0..0, DeValue::Table(toml::de::DeTable::new()));
    let defaults = PlannerConfig::parse(kind, empty)
        .map_err(|e| SetupError::other(format!("planner `{kind}` has no defaults: {e}")))?
        .ok_or_else(|| SetupError::other(format!("unknown planner `{kind}` in PAIRS")))?;
    builtin_system(model, &defaults)
}

/// Whether the planner `kind` plans for the model `kind` (per [`PAIRS`];
/// the [`OUTSIDE`] kinds plan for every model).
pub(crate) fn plans_for(model: &str, planner: &str) -> bool {
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
pub(crate) fn mismatch(model: &str, planner: &str) -> SetupError {
    let fits = planners_for(model);
    let fits = match fits.split_last() {
        Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
        _ => fits.join(""),
    };
    SetupError::key(
        "planner.kind",
        format!("`{planner}` does not plan for model `{model}` (use {fits})"),
    )
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
                } else if *k == "declared" {
                    "states = [\"x\"]\ninputs = [\"v\"]\nkinematics = { x = \"v\" }\nread = { x = \"base.x\" }\n"
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
                    assert!(e.to_string().starts_with("key `planner.kind`"), "{e}");
                }
            }
        }
        assert!(ModelConfig::parse("teleport", table("teleport", ""))
            .unwrap()
            .is_none());
    }
}
