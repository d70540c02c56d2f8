//! The `[model]` table of `kind = "mobile_manipulator"`: robots, the
//! carried beam, the arm servos and the obstacles, as written in scenario
//! files (validated where the system is built).

use crate::error::SetupError;
use crate::model::ellipsoid::Superellipsoid;
use crate::physics::beam::BeamOptions;
use crate::physics::mobile_manipulator::ArmServo;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// One obstacle as written in the scenario.
#[derive(Debug, Clone, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ObstacleConfig {
    /// Name (unique; used in messages and logs).
    pub name: String,
    /// Centre, m.
    pub center: [f64; 3],
    /// Semi-axes a, b, c, m (> 0).
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub semi_axes: [f64; 3],
    /// Exponent n ≥ ½ (1: ellipsoid; large: box-like).
    #[serde(default = "one")]
    #[schemars(range(min = 0.5, max = 32))]
    pub exponent: f64,
    /// Orientation, URDF roll-pitch-yaw in degrees.
    #[serde(default)]
    pub rpy_deg: [f64; 3],
}

fn one() -> f64 {
    1.0
}

impl ObstacleConfig {
    /// The shape (angles in radians).
    pub fn shape(&self) -> Superellipsoid {
        Superellipsoid {
            center: self.center,
            semi_axes: self.semi_axes,
            exponent: self.exponent,
            rpy: self.rpy_deg.map(f64::to_radians),
        }
    }
}

/// `model.beam.bound`: which admissible set enters b_f.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum BoundKind {
    /// Eq. 11's balls on the nodes of q_f (radius `max_deformation`).
    #[default]
    Printed,
    /// The grasp wrenches within `max_force` and `max_moment`.
    Wrench,
}

/// Default F_max of the wrench bound, N: about a fifth of the 282 N that
/// tips a platform at Table I's grasp height (1.06 m) in its weakest
/// direction (158 kg, its centre of mass 0.19 m inside the edge between a
/// drive wheel and the front caster), a margin for the platforms' rocking
/// under acceleration; with [`DEFAULT_MAX_MOMENT`] within the PUMA's wrist
/// torques (derived in docs/src/research/seed-004.md).
pub const DEFAULT_MAX_FORCE: f64 = 60.0;
/// Default M_max of the wrench bound, N m: with F_max at the 0.16 m from
/// the wrist centre to the grasp, M_max + 0.16 F_max = 17.6 N m stays below
/// the weakest wrist joint's 20.1 N m.
pub const DEFAULT_MAX_MOMENT: f64 = 8.0;

/// `[model.beam]`: the deformable beam two robots carry (seed 004 §II, §VI).
/// Defaults: a 10 mm pultruded GFRP rod ([`crate::model::beam::GFRP_ROD_10MM`]).
#[derive(Debug, Clone, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BeamConfig {
    /// Young's modulus E, Pa.
    #[serde(default = "default_e")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub youngs_modulus: f64,
    /// Shear modulus G, Pa.
    #[serde(default = "default_g")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub shear_modulus: f64,
    /// Density, kg/m³.
    #[serde(default = "default_rho")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub density: f64,
    /// Outer diameter of the solid round section, m.
    #[serde(default = "default_diameter")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub diameter: f64,
    /// Rest length between the grasps, m; default: their distance at the start
    /// (the beam is straight there). Given, it must match that distance.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub length: Option<f64>,
    /// The admissible set: `"printed"` (Eq. 11's balls on q_f, radius
    /// `max_deformation`) or `"wrench"` (the grasp wrenches within
    /// `max_force`, `max_moment`; ours).
    #[serde(default)]
    pub bound: BoundKind,
    /// q_F of Eq. 5, the bound on ‖q_f‖∞ (m and rad, SI reading of the
    /// paper's units); required with `bound = "printed"`.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub max_deformation: Option<f64>,
    /// F_max of the wrench bound: the force each gripper may apply to the
    /// beam, N (default 60: about a fifth of the 282 N that tips a
    /// platform at Table I's grasp height).
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub max_force: Option<f64>,
    /// M_max of the wrench bound: the moment each gripper may apply to the
    /// beam about the grasp point, N m (default 8: with F_max at 0.16 m it
    /// stays below the weakest wrist joint's 20.1 N m).
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub max_moment: Option<f64>,
    /// Bound on the grasps' stretch or shortening along the beam, m
    /// (ours; none by default: Eq. 5 alone). See `Carried::with_max_stretch`.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub max_stretch: Option<f64>,
    /// Ellipsoids along the beam (obstacles of the robot parts).
    #[serde(default = "default_segments")]
    #[schemars(range(min = 1, max = 64))]
    pub segments: usize,
    /// Their cross semi-axes, m (the rod's radius plus a margin).
    #[serde(default = "default_beam_radius")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub radius: f64,
    /// Compliant joints of the physics beam's chain (even, 2..=40; N + 1
    /// rigid segments, see `physics::beam`).
    #[serde(default = "default_physics_segments")]
    #[schemars(range(min = 2, max = 40))]
    pub physics_segments: usize,
}

fn default_physics_segments() -> usize {
    BeamOptions::default().segments
}

fn default_e() -> f64 {
    crate::model::beam::GFRP_ROD_10MM.0.youngs_modulus
}
fn default_g() -> f64 {
    crate::model::beam::GFRP_ROD_10MM.0.shear_modulus
}
fn default_rho() -> f64 {
    crate::model::beam::GFRP_ROD_10MM.0.density
}
fn default_diameter() -> f64 {
    crate::model::beam::GFRP_ROD_10MM.1.outer_diameter
}
fn default_segments() -> usize {
    8
}
fn default_beam_radius() -> f64 {
    0.02
}

impl BeamConfig {
    /// The beam (rest length filled in later) or the offending key.
    pub(super) fn beam(&self) -> Result<crate::model::beam::Beam, SetupError> {
        use crate::model::beam::{Beam, Material, Section};
        let b = Beam {
            material: Material {
                youngs_modulus: self.youngs_modulus,
                shear_modulus: self.shear_modulus,
                density: self.density,
            },
            section: Section {
                outer_diameter: self.diameter,
                inner_diameter: 0.0,
            },
            length: self.length.unwrap_or(1.0),
        };
        let pos = |v: f64| v.is_finite() && v > 0.0;
        for (key, v) in [
            ("youngs_modulus", Some(self.youngs_modulus)),
            ("shear_modulus", Some(self.shear_modulus)),
            ("density", Some(self.density)),
            ("diameter", Some(self.diameter)),
            ("radius", Some(self.radius)),
            ("max_deformation", self.max_deformation),
            ("max_force", self.max_force),
            ("max_moment", self.max_moment),
        ] {
            if let Some(v) = v.filter(|v| !pos(*v)) {
                return Err(SetupError::key(
                    format!("model.beam.{key}"),
                    format!("must be > 0, got {v}"),
                ));
            }
        }
        match self.bound {
            BoundKind::Printed => {
                if self.max_deformation.is_none() {
                    return Err(SetupError::key(
                        "model.beam.max_deformation",
                        "required with bound = \"printed\" (q_F of Eq. 5)",
                    ));
                }
                for (key, v) in [
                    ("max_force", self.max_force),
                    ("max_moment", self.max_moment),
                ] {
                    if v.is_some() {
                        return Err(SetupError::key(
                            format!("model.beam.{key}"),
                            "belongs to bound = \"wrench\" (this beam's bound is \"printed\")",
                        ));
                    }
                }
            }
            BoundKind::Wrench => {
                if self.max_deformation.is_some() {
                    return Err(SetupError::key(
                        "model.beam.max_deformation",
                        "q_F belongs to bound = \"printed\" (this beam's bound is \"wrench\": max_force, max_moment)",
                    ));
                }
            }
        }
        if let Some(e) = self.max_stretch.filter(|e| !pos(*e)) {
            return Err(SetupError::key(
                "model.beam.max_stretch",
                format!("must be > 0, got {e}"),
            ));
        }
        if let Some(l) = self.length.filter(|l| !pos(*l)) {
            return Err(SetupError::key(
                "model.beam.length",
                format!("must be > 0, got {l}"),
            ));
        }
        if !(1..=64).contains(&self.segments) {
            return Err(SetupError::key("model.beam.segments", "must be in 1..=64"));
        }
        let n = self.physics_segments;
        if !((2..=40).contains(&n) && n.is_multiple_of(2)) {
            return Err(SetupError::key(
                "model.beam.physics_segments",
                format!("must be even and in 2..=40, got {n}"),
            ));
        }
        Ok(b)
    }

    /// q_F (∞ with the wrench bound, where it plays no part).
    pub(super) fn q_max(&self) -> f64 {
        self.max_deformation.unwrap_or(f64::INFINITY)
    }

    /// The planner's admissible set.
    pub(super) fn bound(&self) -> crate::planner::dilf::object::Bound {
        use crate::planner::dilf::object::Bound;
        match self.bound {
            BoundKind::Printed => Bound::Printed,
            BoundKind::Wrench => Bound::Wrench {
                force: self.max_force.unwrap_or(DEFAULT_MAX_FORCE),
                moment: self.max_moment.unwrap_or(DEFAULT_MAX_MOMENT),
            },
        }
    }
}

/// `[model.wrist]`: the passive wrist between each flange and its gripper
/// (ours; see [`crate::model::mobile_manipulator::Wrist`]). Per-axis arrays
/// are in the tool frame at the grasp point: x, y, z then rotations about
/// x, y, z.
#[derive(Debug, Clone, Default, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum WristConfig {
    /// The gripper fixed to the flange (default: the paper's rigid grasp).
    #[default]
    Rigid,
    /// A spring–damper per axis with a hard stop at ± travel.
    Compliant {
        /// N/m (translations), N m/rad (rotations); > 0. Default
        /// [400, 400, 400, 50, 50, 50]: at F_max = 60 N a wrist deflects
        /// 15 cm, at M_max = 8 N m it turns 0.16 rad.
        #[serde(default = "default_wrist_stiffness")]
        #[schemars(extend("exclusiveMinimum" = 0))]
        stiffness: [f64; 6],
        /// N s/m, N m s/rad; ≥ 0. Default [25, 25, 25, 2, 2, 2] (about 0.7
        /// of critical for the gripper and half the rod).
        #[serde(default = "default_wrist_damping")]
        #[schemars(extend("minimum" = 0))]
        damping: [f64; 6],
        /// m, rad each way; > 0 (rotations below 90°). Default
        /// [0.2, 0.2, 0.2, 0.35, 0.35, 0.35].
        #[serde(default = "default_wrist_travel")]
        #[schemars(extend("exclusiveMinimum" = 0))]
        travel: [f64; 6],
    },
}

/// Default compliant wrist: at the wrench bound's default F_max = 60 N each
/// wrist deflects 15 cm (400 N/m), so the two in series give the grasps
/// up to 30 cm of distance change (stiffer wrists leave Eq. 18 too little
/// room: `dilf_table_i_rigid_goal` stalls at 1000 N/m, see the seed-004
/// docs); at M_max = 8 N m each turns 0.16 rad (50 N m/rad).
fn default_wrist_stiffness() -> [f64; 6] {
    [400.0, 400.0, 400.0, 50.0, 50.0, 50.0]
}
/// About 0.7 of critical damping for the gripper and half the rod (~0.8 kg)
/// on 400 N/m. The rotations' 2 N m s/rad: at 3 a fast in-place turn adds
/// the damper's moment to the spring's and the grasp moment overshoots its
/// bound; at 1 the wrist roll rings at the rod's first bending mode (~4 Hz).
fn default_wrist_damping() -> [f64; 6] {
    [25.0, 25.0, 25.0, 2.0, 2.0, 2.0]
}
/// The translations' deflection at the bound's default F_max plus a third;
/// the rotations' twice their deflection at M_max (0.16 rad): the spring
/// alone does not keep the arm's quick counter-rotations of the wrist roll
/// off the stop.
fn default_wrist_travel() -> [f64; 6] {
    [0.2, 0.2, 0.2, 0.35, 0.35, 0.35]
}

impl WristConfig {
    /// The model's wrist, or the offending key.
    pub fn wrist(&self) -> Result<crate::model::mobile_manipulator::Wrist, SetupError> {
        use crate::model::mobile_manipulator::{CompliantWrist, Wrist};
        match *self {
            WristConfig::Rigid => Ok(Wrist::Rigid),
            WristConfig::Compliant {
                stiffness,
                damping,
                travel,
            } => {
                let w = CompliantWrist {
                    stiffness,
                    damping,
                    travel,
                };
                w.validate()
                    .map_err(|(field, m)| SetupError::key(format!("model.wrist.{field}"), m))?;
                Ok(Wrist::Compliant(w))
            }
        }
    }
}

/// Mobile manipulators (seed 004): differential-drive platforms with PUMA 560
/// arms among superellipsoid obstacles; one robot, or two carrying a
/// deformable beam.
#[derive(Debug, Clone, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MobileManipulatorConfig {
    /// URDF file (one robot), relative to the scenario file.
    pub urdf: PathBuf,
    /// Number of robots (1, or 2 carrying `[model.beam]`).
    #[serde(default = "one_robot")]
    #[schemars(range(min = 1, max = 2))]
    pub robots: usize,
    /// The beam two robots carry (required with `robots = 2`).
    pub beam: Option<BeamConfig>,
    /// Obstacles.
    #[serde(default)]
    pub obstacles: Vec<ObstacleConfig>,
    /// How the arms' joints execute their rate commands in physics.
    #[serde(default)]
    pub arm_servo: ArmServoConfig,
    /// The wrists between flanges and grippers (planner and physics).
    #[serde(default)]
    pub wrist: WristConfig,
}

/// `[model.arm_servo]`: the arms' joint servos in physics (the planner is
/// kinematic and does not see them).
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum ArmServoConfig {
    /// Stiff position servos tracking the integral of the commanded rates
    /// (torque-limited at `max_torque`, or `sim.motor_max_torque`).
    Stiff {
        /// Largest torque per joint, N m (> 0); default: `sim.motor_max_torque`
        /// for every joint. The PUMA 560's published limits are
        /// `[97.6, 186.4, 89.4, 24.2, 20.1, 21.3]`.
        #[schemars(extend("exclusiveMinimum" = 0))]
        max_torque: Option<[f64; 6]>,
        /// Each joint's armature, kg m² (≥ 0; default 0): the motor rotor's
        /// inertia reflected through the gears, Jm·G², added to the joint's
        /// child link about the joint axis. The PUMA 560's published values
        /// are `[0.784, 2.325, 0.577, 0.191, 0.171, 0.194]`.
        #[schemars(extend("minimum" = 0))]
        armature: Option<[f64; 6]>,
    },
    /// Joint-space impedance with gravity compensation.
    Impedance {
        /// K per joint, N m/rad (> 0).
        #[schemars(extend("exclusiveMinimum" = 0))]
        stiffness: [f64; 6],
        /// D per joint, N m s/rad (≥ 0).
        #[schemars(extend("minimum" = 0))]
        damping: [f64; 6],
        /// As for `stiff`.
        #[schemars(extend("exclusiveMinimum" = 0))]
        max_torque: Option<[f64; 6]>,
        /// As for `stiff`.
        #[schemars(extend("minimum" = 0))]
        armature: Option<[f64; 6]>,
    },
}

impl Default for ArmServoConfig {
    fn default() -> Self {
        ArmServoConfig::Stiff {
            max_torque: None,
            armature: None,
        }
    }
}

impl ArmServoConfig {
    /// The arms' per-joint torque limits, if given.
    pub fn max_torque(&self) -> Option<[f64; 6]> {
        match *self {
            ArmServoConfig::Stiff { max_torque, .. }
            | ArmServoConfig::Impedance { max_torque, .. } => max_torque,
        }
    }

    /// The arms' per-joint armature, kg m² (zero unless given).
    pub fn armature(&self) -> [f64; 6] {
        match *self {
            ArmServoConfig::Stiff { armature, .. } | ArmServoConfig::Impedance { armature, .. } => {
                armature.unwrap_or([0.0; 6])
            }
        }
    }

    /// The physics' servo, or the offending key.
    pub fn servo(&self) -> Result<ArmServo, SetupError> {
        if let Some(a) = self
            .armature()
            .iter()
            .find(|a| !(a.is_finite() && **a >= 0.0))
        {
            return Err(SetupError::key(
                "model.arm_servo.armature",
                format!("every joint's armature must be ≥ 0 kg m², got {a}"),
            ));
        }
        let limits = match *self {
            ArmServoConfig::Stiff { max_torque, .. }
            | ArmServoConfig::Impedance { max_torque, .. } => max_torque,
        };
        if let Some(t) = limits
            .iter()
            .flatten()
            .find(|t| !(t.is_finite() && **t > 0.0))
        {
            return Err(SetupError::key(
                "model.arm_servo.max_torque",
                format!("every joint's limit must be > 0 N m, got {t}"),
            ));
        }
        match *self {
            ArmServoConfig::Stiff { .. } => Ok(ArmServo::Stiff),
            ArmServoConfig::Impedance {
                stiffness, damping, ..
            } => {
                if let Some(k) = stiffness.iter().find(|k| !(k.is_finite() && **k > 0.0)) {
                    return Err(SetupError::key(
                        "model.arm_servo.stiffness",
                        format!("every joint's stiffness must be > 0 N m/rad, got {k}"),
                    ));
                }
                if let Some(d) = damping.iter().find(|d| !(d.is_finite() && **d >= 0.0)) {
                    return Err(SetupError::key(
                        "model.arm_servo.damping",
                        format!("every joint's damping must be ≥ 0 N m s/rad, got {d}"),
                    ));
                }
                Ok(ArmServo::Impedance { stiffness, damping })
            }
        }
    }
}

fn one_robot() -> usize {
    1
}
