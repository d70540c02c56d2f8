//! Placeholder: the rolling_sphere system is being integrated (planner math lives in
//! crate::planner, model in crate::model).

use super::System;
use crate::scenario::PlannerConfig;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// `[model] kind = "rolling_sphere"`.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SphereConfig {
    /// URDF file, relative to the scenario file.
    pub urdf: PathBuf,
}

/// Build the system.
pub fn build(_cfg: &SphereConfig, _planner: &PlannerConfig) -> Result<Box<dyn System>, String> {
    Err("model `rolling_sphere` is not available yet".into())
}
