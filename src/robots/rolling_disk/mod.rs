//! The rolling disk: seed 000 §4.2 Stokes planner, `models/rolling_disk.urdf`.

pub mod kinematics;
pub mod physics;
pub mod stokes;

use crate::engine::perturb::Exposure;
use crate::engine::PhysicsSettings;
use crate::engine::PhysicsSystem;
use crate::error::SetupError;
use crate::model::{KinematicModel, State};
use crate::paper::{rows_from, same, PaperRow};
use crate::plan::{Limits, Plan};
use crate::planner::PlanError;
use crate::robots::rolling_disk::kinematics::RollingDisk;
use crate::robots::rolling_disk::physics::DiskPhysics;
use crate::robots::rolling_disk::stokes::{Algorithm, StokesDiskParams};
use crate::robots::System;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// A disk rolling upright without slipping on a plane (seed 000 §4.2), replayed
/// on a wheel URDF in Rapier.
#[derive(Debug, Clone, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DiskModelConfig {
    /// Wheel radius, m (must match the URDF wheel).
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub radius: f64,
    /// URDF file, relative to the scenario file.
    pub urdf: PathBuf,
}

struct Disk {
    model: RollingDisk,
    params: StokesDiskParams,
}

/// Build the disk system.
pub fn build(
    cfg: &DiskModelConfig,
    params: &StokesDiskParams,
) -> Result<Box<dyn System>, SetupError> {
    // Written to also reject NaN (the scenario parser already rejects it).
    if cfg.radius.is_nan() || cfg.radius <= 0.0 {
        return Err(SetupError::key("model.radius", "must be > 0"));
    }
    Ok(Box::new(Disk {
        model: RollingDisk { r: cfg.radius },
        params: params.clone(),
    }))
}

impl System for Disk {
    /// The wheel rolls: its radius can wear (`wheel_radius_scale`).
    fn exposure(&self, plan: &Plan) -> Exposure {
        Exposure {
            wheels: true,
            ..Exposure::of(plan)
        }
    }
    fn model(&self) -> &dyn KinematicModel {
        &self.model
    }
    fn default_max_rate(&self) -> Vec<f64> {
        vec![4.0, 2.0]
    }
    fn plan(&self, start: &State, goal: &State, limits: &Limits) -> Result<Plan, PlanError> {
        stokes::plan(&self.model, start, goal, &self.params, limits)
    }
    fn goal_heading(&self, goal: &State) -> Option<f64> {
        // α is measured from +y towards +x.
        Some(std::f64::consts::FRAC_PI_2 - goal[3])
    }
    fn urdf_names(&self) -> Vec<crate::engine::required::Named> {
        crate::engine::required::defaults(&crate::robots::rolling_disk::physics::REQUIRED)
    }
    fn physics(
        &self,
        robot: &urdf_rs::Robot,
        urdf_dir: &Path,
        start: &[f64],
        sim: &PhysicsSettings,
    ) -> Result<Box<dyn PhysicsSystem>, SetupError> {
        let p = DiskPhysics::new(robot, urdf_dir, self.model.r, start, sim)?;
        Ok(Box::new(p))
    }
    /// Seed 000 §4.2's example (r = 0.25 m, (0, 0, 0, 0) → (−0.4, 1, π, π/8)): the
    /// singularity-avoiding plan (OPQROZ) or the singularity-free one with b = 60°.
    fn paper(&self, start: &State, goal: &State, plan: &Plan) -> Vec<PaperRow> {
        use std::f64::consts::PI;
        let task = (self.model.r - 0.25).abs() < 1e-12
            && same(start.as_slice(), &[0.0; 4], 1e-9)
            && same(goal.as_slice(), &[-0.4, 1.0, PI, PI / 8.0], 1e-9);
        if !task {
            return Vec::new();
        }
        let d = &plan.details;
        const DEG: f64 = 180.0 / PI;
        const ROUNDED: &str = "printed value follows from the drift rounded to (0.1522, 0.7654); this close to the singularity the 4th digit matters";
        let mut spec = vec![
            (
                "drift after OZ: x",
                "0.1522",
                "/drift_after_OP/0",
                1.0,
                "m",
                "",
            ),
            (
                "drift after OZ: y",
                "0.7654",
                "/drift_after_OP/1",
                1.0,
                "m",
                "",
            ),
        ];
        match (self.params.algorithm, self.params.b_first_deg) {
            (Algorithm::SingularityAvoiding, _) => spec.extend([
                (
                    "rejected loop (Eq. 25-26): b",
                    "0.01808",
                    "/rejected_loop/b",
                    1.0,
                    "rad",
                    ROUNDED,
                ),
                (
                    "rejected loop (Eq. 25-26): a",
                    "132.72",
                    "/rejected_loop/a",
                    1.0,
                    "rad",
                    ROUNDED,
                ),
                (
                    "detour loop at O: b",
                    "0.8034",
                    "/loops/0/b_rad",
                    1.0,
                    "rad",
                    "rounded drift, then truncated (0.80348)",
                ),
                (
                    "detour loop at O: b",
                    "46.03",
                    "/loops/0/b_deg",
                    1.0,
                    "deg",
                    "",
                ),
                (
                    "detour loop at O: a",
                    "3.068",
                    "/loops/0/a_rad",
                    1.0,
                    "rad",
                    "truncated",
                ),
                (
                    "detour loop at O: a",
                    "175.78",
                    "/loops/0/a_deg",
                    1.0,
                    "deg",
                    "175.78° is the truncated 3.068 rad converted",
                ),
            ]),
            (Algorithm::SingularityFree, Some(b)) if (b - 60.0).abs() < 1e-9 => spec.extend([
                (
                    "loop x (Eq. 23): b",
                    "1.047",
                    "/loops/0/b_rad",
                    1.0,
                    "rad",
                    "",
                ),
                (
                    "loop x (Eq. 23): a",
                    "3.628",
                    "/loops/0/a_rad",
                    1.0,
                    "rad",
                    "truncated",
                ),
                (
                    "loop x (Eq. 23): a",
                    "207.87",
                    "/loops/0/a_rad",
                    DEG,
                    "deg",
                    "truncation, then conversion",
                ),
                (
                    "loop y (Eq. 28): b",
                    "2.356",
                    "/loops/1/b_rad",
                    1.0,
                    "rad",
                    "",
                ),
                (
                    "loop y (Eq. 28): a",
                    "−1.05",
                    "/loops/1/a_rad",
                    1.0,
                    "rad",
                    "",
                ),
                (
                    "loop y (Eq. 28): a",
                    "60.15",
                    "/loops/1/a_deg",
                    1.0,
                    "deg",
                    "printed \"60.15 degrees\" lost its sign and uses the rounded y'_d = 1.485",
                ),
            ]),
            _ => {}
        }
        rows_from(d, &spec)
    }
}
