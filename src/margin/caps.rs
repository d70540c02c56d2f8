//! Where the torque caps a margin is measured against come from: a torque
//! or mass margin against a cap nobody chose (`[sim] motor_max_torque`'s
//! default, for joints the URDF gives no `<limit effort>`) says so in its
//! note, since "robust to 1 % of its torque" means nothing against an
//! invented 50 N·m.

use crate::engine::perturb::Dimension;
use crate::engine::reading::LimitSource;
use crate::validate::Prepared;
use serde::Serialize;

/// The drives of a run capped at the default `[sim] motor_max_torque`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DefaultCaps {
    /// The default cap, N·m.
    pub cap: f64,
    /// The joints capped there; empty: every drive of a model that caps
    /// all its drives at `[sim] motor_max_torque` (no per-joint reading).
    pub joints: Vec<String>,
}

impl DefaultCaps {
    /// The note's words.
    pub fn note(&self) -> String {
        let cap = crate::numfmt::readable(self.cap);
        if self.joints.is_empty() {
            format!("against the default cap [sim] motor_max_torque = {cap} N·m of every drive")
        } else {
            let names: Vec<String> = self.joints.iter().map(|j| crate::echo::code(j)).collect();
            format!(
                "against the default cap [sim] motor_max_torque = {cap} N·m of {} (no <limit effort>)",
                names.join(", ")
            )
        }
    }
}

/// The default caps a margin of `d` is measured against (`None`: every
/// cap is the URDF's, a model key's or the scenario's, or `d` is not a
/// torque or mass dimension).
pub fn default_caps(prep: &Prepared, d: Dimension) -> Option<DefaultCaps> {
    if !matches!(d, Dimension::TorqueScale | Dimension::MassScale) {
        return None;
    }
    let sc = &prep.scenario;
    if sc.has_key("sim.motor_max_torque") {
        return None;
    }
    let drives = &prep.reading.drives;
    let joints: Vec<String> = drives
        .iter()
        .filter(|x| x.source == LimitSource::Default)
        .map(|x| x.joint.clone())
        .collect();
    // A model that reads no drives caps them all at the settings' value.
    (!joints.is_empty() || drives.is_empty()).then_some(DefaultCaps {
        cap: sc.sim.motor_max_torque,
        joints,
    })
}
