//! The rolling disk: seed 000 §4.2 Stokes planner, `models/rolling_disk.urdf`.

use super::{mismatch, System};
use crate::model::disk::RollingDisk;
use crate::model::{KinematicModel, State};
use crate::physics::disk::DiskPhysics;
use crate::physics::PhysicsSettings;
use crate::physics::PhysicsSystem;
use crate::plan::{Limits, Plan};
use crate::planner::stokes_disk::{self, StokesDiskParams};
use crate::planner::PlanError;
use crate::scenario::PlannerConfig;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// `[model] kind = "rolling_disk"`.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct DiskModelConfig {
    /// Wheel radius, m (must match the URDF wheel).
    pub radius: f64,
    /// URDF file, relative to the scenario file.
    pub urdf: PathBuf,
}

struct Disk {
    model: RollingDisk,
    params: StokesDiskParams,
}

/// Build the disk system.
pub fn build(cfg: &DiskModelConfig, planner: &PlannerConfig) -> Result<Box<dyn System>, String> {
    // Written to also reject NaN (the scenario parser already rejects it).
    if cfg.radius.is_nan() || cfg.radius <= 0.0 {
        return Err("key `model.radius`: must be > 0".into());
    }
    match planner {
        PlannerConfig::StokesDisk(p) => Ok(Box::new(Disk {
            model: RollingDisk { r: cfg.radius },
            params: p.clone(),
        })),
        other => Err(mismatch("rolling_disk", other, &["stokes_disk"])),
    }
}

impl System for Disk {
    fn model(&self) -> &dyn KinematicModel {
        &self.model
    }
    fn default_max_rate(&self) -> Vec<f64> {
        vec![4.0, 2.0]
    }
    fn plan(&self, start: &State, goal: &State, limits: &Limits) -> Result<Plan, PlanError> {
        stokes_disk::plan(&self.model, start, goal, &self.params, limits)
    }
    fn goal_heading(&self, goal: &State) -> Option<f64> {
        // α is measured from +y towards +x.
        Some(std::f64::consts::FRAC_PI_2 - goal[3])
    }
    fn physics(
        &self,
        robot: &urdf_rs::Robot,
        urdf_dir: &Path,
        start: &[f64],
        sim: &PhysicsSettings,
    ) -> Result<Box<dyn PhysicsSystem>, String> {
        let p = DiskPhysics::new(robot, urdf_dir, self.model.r, start, sim)?;
        Ok(Box::new(p))
    }
}
