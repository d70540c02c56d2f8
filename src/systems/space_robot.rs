//! Placeholder: the space_robot system is being integrated (planner math lives in
//! crate::planner, model in crate::model).

use super::System;
use crate::scenario::PlannerConfig;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// `[model] kind = "space_robot"`.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SpaceRobotConfig {
    /// URDF file, relative to the scenario file.
    pub urdf: PathBuf,
}

/// Build the system.
pub fn build(_cfg: &SpaceRobotConfig, _planner: &PlannerConfig) -> Result<Box<dyn System>, String> {
    Err("model `space_robot` is not available yet".into())
}
