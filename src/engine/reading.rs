//! What the physics took from a URDF, said back to the user: the rigid
//! bodies after lumping, the wheels and drives a model found, the geometry
//! it derived, and the defaults it had to fill in. `plan` prints it,
//! `summary.json` carries it (`model.read_from_urdf`), the report shows it.

use crate::engine::lump::Lumping;
use serde::Serialize;
use urdf_rs::Robot;

/// Where a drive's torque limit comes from.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum LimitSource {
    /// The joint's `<limit effort>`.
    Urdf,
    /// A `[model]` key.
    Model,
    /// `[sim] motor_max_torque` (the URDF gives none).
    Default,
    /// `[sim] motor_max_torque`, which the scenario sets (the URDF gives none).
    Scenario,
}

/// One driven joint.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DriveReading {
    /// The joint.
    pub joint: String,
    /// Its torque (or force) limit, N·m (N), before any `torque_scale`.
    pub torque_limit: f64,
    /// Where the limit comes from.
    pub source: LimitSource,
}

/// One wheel a model rolls on.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct WheelReading {
    /// The wheel's joint.
    pub joint: String,
    /// The wheel link.
    pub link: String,
    /// Radius of its round collision, m.
    pub radius: f64,
    /// Its centre in the body frame, m.
    pub center: [f64; 3],
    /// Its collision shape (`sphere`, `cylinder`).
    pub shape: &'static str,
}

/// One rigid body after lumping.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BodyReading {
    /// The link whose frame is the body's frame.
    pub link: String,
    /// Total mass, kg.
    pub mass: f64,
    /// The other links lumped into it (frames and fixed parts).
    pub lumped: Vec<String>,
}

/// Everything a physics counterpart read from its URDF.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct UrdfReading {
    /// Rigid bodies (every link of the URDF is in exactly one).
    pub bodies: Vec<BodyReading>,
    /// Wheels (wheeled models).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub wheels: Vec<WheelReading>,
    /// Driven joints.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub drives: Vec<DriveReading>,
    /// Derived geometry: name (with its unit) and value(s), in the order
    /// the model reads them (track, wheelbase, reference point, ...).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub geometry: Vec<(String, Vec<f64>)>,
    /// What the user should know: defaults filled in, parts left out.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// What was done to the file before reading it (xacro expanded).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
}

impl UrdfReading {
    /// The bodies of `robot` under `lumping`, in URDF order of their links.
    pub fn bodies_of(robot: &Robot, lumping: &Lumping) -> Vec<BodyReading> {
        (0..robot.links.len())
            .filter(|&i| lumping.is_body(i))
            .map(|i| {
                let members: Vec<usize> = (0..robot.links.len())
                    .filter(|&k| lumping.body[k] == i)
                    .collect();
                BodyReading {
                    link: robot.links[i].name.clone(),
                    mass: members
                        .iter()
                        .map(|&k| robot.links[k].inertial.mass.value)
                        .sum(),
                    lumped: members
                        .iter()
                        .filter(|&&k| k != i)
                        .map(|&k| robot.links[k].name.clone())
                        .collect(),
                }
            })
            .collect()
    }

    /// A drive's reading: the URDF's `effort`, else the default cap
    /// (see [`UrdfReading::settle_default_limits`]).
    pub fn drive(&mut self, joint: &str, effort: Option<f64>, default: f64) {
        let (torque_limit, source) = match effort {
            Some(e) => (e, LimitSource::Urdf),
            None => (default, LimitSource::Default),
        };
        self.drives.push(DriveReading {
            joint: joint.to_string(),
            torque_limit,
            source,
        });
    }

    /// The drives capped at `[sim] motor_max_torque` because their joints
    /// give no `<limit effort>`: when the scenario sets that key, the cap is
    /// its choice ([`LimitSource::Scenario`], no warning); otherwise one
    /// warning names them all.
    pub fn settle_default_limits(&mut self, scenario_sets_cap: bool) {
        let defaulted: Vec<&DriveReading> = self
            .drives
            .iter()
            .filter(|d| d.source == LimitSource::Default)
            .collect();
        let Some(first) = defaulted.first() else {
            return;
        };
        if scenario_sets_cap {
            for d in &mut self.drives {
                if d.source == LimitSource::Default {
                    d.source = LimitSource::Scenario;
                }
            }
            return;
        }
        let cap = crate::numfmt::readable(first.torque_limit);
        let names: Vec<String> = defaulted.iter().map(|d| format!("`{}`", d.joint)).collect();
        let warning = if names.len() == 1 {
            format!(
                "joint {} gives no <limit effort>: its drive is capped at [sim] motor_max_torque = {cap} N·m (set it to the motor's torque)",
                names[0]
            )
        } else {
            format!(
                "joints {} give no <limit effort>: their drives are capped at [sim] motor_max_torque = {cap} N·m (set it to the motors' torque)",
                names.join(", ")
            )
        };
        self.warnings.push(warning);
    }

    /// Lines for a terminal (`plan`), indented by two spaces.
    pub fn lines(&self) -> Vec<String> {
        use crate::numfmt::readable;
        let mut out = Vec::new();
        for b in &self.bodies {
            let lumped = if b.lumped.is_empty() {
                String::new()
            } else {
                format!(" (with {})", b.lumped.join(", "))
            };
            out.push(format!(
                "  body {}: {} kg{lumped}",
                b.link,
                readable(b.mass)
            ));
        }
        for w in &self.wheels {
            out.push(format!(
                "  wheel {} ({}): {} radius {} m at ({}, {}, {}) m",
                w.link,
                w.joint,
                w.shape,
                readable(w.radius),
                readable(w.center[0]),
                readable(w.center[1]),
                readable(w.center[2])
            ));
        }
        for d in &self.drives {
            let src = match d.source {
                LimitSource::Urdf => "URDF <limit effort>",
                LimitSource::Model => "[model]",
                LimitSource::Default => "default: [sim] motor_max_torque",
                LimitSource::Scenario => "[sim] motor_max_torque",
            };
            out.push(format!(
                "  drive {}: {} N·m ({src})",
                d.joint,
                readable(d.torque_limit)
            ));
        }
        for (name, v) in &self.geometry {
            let v: Vec<String> = v.iter().map(|x| readable(*x)).collect();
            let v = if v.len() == 1 {
                v[0].clone()
            } else {
                format!("({})", v.join(", "))
            };
            out.push(format!("  {name}: {v}"));
        }
        for n in &self.notes {
            out.push(format!("  note: {n}"));
        }
        for w in &self.warnings {
            out.push(format!("  warning: {w}"));
        }
        out
    }
}
