//! The `[model]` table of `kind = "mobile_manipulator"`: robots, the
//! carried beam, the arm servos and the obstacles, as written in scenario
//! files (validated where the system is built).

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
    /// q_F of Eq. 5, the bound on ‖q_f‖∞ (m and rad, SI reading of the paper's units).
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub max_deformation: f64,
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
    pub(super) fn beam(&self) -> Result<crate::model::beam::Beam, String> {
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
            ("youngs_modulus", self.youngs_modulus),
            ("shear_modulus", self.shear_modulus),
            ("density", self.density),
            ("diameter", self.diameter),
            ("radius", self.radius),
            ("max_deformation", self.max_deformation),
        ] {
            if !pos(v) {
                return Err(format!("key `model.beam.{key}`: must be > 0, got {v}"));
            }
        }
        if let Some(e) = self.max_stretch.filter(|e| !pos(*e)) {
            return Err(format!(
                "key `model.beam.max_stretch`: must be > 0, got {e}"
            ));
        }
        if let Some(l) = self.length.filter(|l| !pos(*l)) {
            return Err(format!("key `model.beam.length`: must be > 0, got {l}"));
        }
        if !(1..=64).contains(&self.segments) {
            return Err("key `model.beam.segments`: must be in 1..=64".into());
        }
        let n = self.physics_segments;
        if !((2..=40).contains(&n) && n.is_multiple_of(2)) {
            return Err(format!(
                "key `model.beam.physics_segments`: must be even and in 2..=40, got {n}"
            ));
        }
        Ok(b)
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
}

/// `[model.arm_servo]`: the arms' joint servos in physics (the planner is
/// kinematic and does not see them).
#[derive(Debug, Clone, Default, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum ArmServoConfig {
    /// Stiff position servos tracking the integral of the commanded rates
    /// (torque-limited at `sim.motor_max_torque`).
    #[default]
    Stiff,
    /// Joint-space impedance with gravity compensation.
    Impedance {
        /// K per joint, N m/rad (> 0).
        #[schemars(extend("exclusiveMinimum" = 0))]
        stiffness: [f64; 6],
        /// D per joint, N m s/rad (≥ 0).
        #[schemars(extend("minimum" = 0))]
        damping: [f64; 6],
    },
}

impl ArmServoConfig {
    /// The physics' servo, or the offending key.
    pub fn servo(&self) -> Result<ArmServo, String> {
        match *self {
            ArmServoConfig::Stiff => Ok(ArmServo::Stiff),
            ArmServoConfig::Impedance { stiffness, damping } => {
                if let Some(k) = stiffness.iter().find(|k| !(k.is_finite() && **k > 0.0)) {
                    return Err(format!(
                        "key `model.arm_servo.stiffness`: every joint's stiffness must be > 0 N m/rad, got {k}"
                    ));
                }
                if let Some(d) = damping.iter().find(|d| !(d.is_finite() && **d >= 0.0)) {
                    return Err(format!(
                        "key `model.arm_servo.damping`: every joint's damping must be ≥ 0 N m s/rad, got {d}"
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
