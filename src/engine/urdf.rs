//! URDF files: reading and validation, visual geometry for the logs. The
//! loader into a Rapier world is [`crate::engine::world`] (re-exported here).

use crate::error::SetupError;
use crate::record::{LinkVisual, Pose, Shape, Visual};
use nalgebra::UnitQuaternion;
use std::collections::{HashMap, HashSet};
use std::path::Path;
use urdf_rs::{Geometry, JointType, Robot};

pub use crate::engine::world::{Drive, RobotHandles, SimWorld, WorldOptions};

/// Where a scenario's robot description finds what it names: packages
/// (`[model] packages`), xacro arguments (`[model] xacro_args`) and what
/// an absent package expands to (`[model] missing_packages`).
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct Source {
    /// Package directories by name (resolved against the scenario's directory).
    pub packages: std::collections::BTreeMap<String, std::path::PathBuf>,
    /// `name:=value` arguments for xacro.
    pub xacro_args: std::collections::BTreeMap<String, String>,
    /// What xacro does with includes of packages that are not found.
    pub missing_packages: crate::engine::packages::MissingPackages,
}

/// Read and validate a URDF file. Errors are one-line, user-facing strings.
///
/// The loader ([`crate::engine::world`]) indexes links by name and places them from
/// the root down, so everything it cannot represent is rejected here:
/// dangling joint references, a graph that is not one tree, a body that
/// moves without mass ([`crate::engine::lump`]), a non-finite or negative inertia,
/// and moving joints without an axis. Meshes are not resolved here (the
/// validation pass does it, `crate::validate::urdf`).
pub fn read(path: &Path) -> Result<Robot, SetupError> {
    let robot = parse(path)?;
    validate(&robot)?;
    Ok(robot)
}

/// Read and parse a URDF file without [`validate`] (the validation pass checks
/// numbers first, to name the element and line).
pub fn parse(path: &Path) -> Result<Robot, SetupError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| SetupError::urdf(format!("cannot read URDF: {e}")))?;
    parse_text(&text)
}

/// Parse URDF text.
pub(crate) fn parse_text(text: &str) -> Result<Robot, SetupError> {
    urdf_rs::read_from_string(text).map_err(|e| {
        SetupError::urdf(format!(
            "URDF does not parse: {}",
            e.to_string().replace('\n', " ")
        ))
    })
}

/// The checks of [`read`] on an already parsed robot.
pub fn validate(robot: &Robot) -> Result<(), SetupError> {
    validate_tree(robot)?;
    validate_loadable(robot)
}

/// One tree of uniquely named links with finite, non-negative masses, where
/// every body that moves has mass: the first problem.
pub(crate) fn validate_tree(robot: &Robot) -> Result<(), SetupError> {
    match tree_problems(robot).into_iter().next() {
        Some(p) => Err(p),
        None => Ok(()),
    }
}

/// Every problem of [`validate_tree`]: [`structure_problems`], then (on a
/// tree) [`mass_problems`].
pub(crate) fn tree_problems(robot: &Robot) -> Vec<SetupError> {
    let out = structure_problems(robot);
    if out.is_empty() {
        mass_problems(robot)
    } else {
        out
    }
}

/// Why `robot` is not one tree of uniquely named links.
pub(crate) fn structure_problems(robot: &Robot) -> Vec<SetupError> {
    if robot.links.is_empty() {
        return vec![SetupError::urdf("URDF has no links")];
    }
    let mut out = Vec::new();
    let names: HashSet<&str> = robot.links.iter().map(|l| l.name.as_str()).collect();
    if names.len() != robot.links.len() {
        out.push(SetupError::urdf("URDF has duplicate link names"));
    }
    let mut has_parent = HashSet::new();
    for j in &robot.joints {
        for l in [&j.parent.link, &j.child.link] {
            if !names.contains(l.as_str()) {
                out.push(SetupError::urdf_at(
                    "joint",
                    &j.name,
                    format!(
                        "URDF joint `{}` names unknown link {}",
                        j.name,
                        crate::echo::code(l)
                    ),
                ));
            }
        }
        if !has_parent.insert(j.child.link.as_str()) {
            out.push(SetupError::urdf_at(
                "link",
                &j.child.link,
                format!("URDF link `{}` has two parent joints", j.child.link),
            ));
        }
    }
    if !out.is_empty() {
        return out;
    }
    let roots: Vec<&str> = robot
        .links
        .iter()
        .map(|l| l.name.as_str())
        .filter(|n| !has_parent.contains(n))
        .collect();
    match roots.len() {
        0 => return vec![SetupError::urdf("URDF kinematic graph has no root (cycle)")],
        1 => {}
        _ => {
            return vec![SetupError::urdf(format!(
                "URDF has {} root links ({}): it must be one tree",
                roots.len(),
                roots.join(", ")
            ))]
        }
    }
    // One root and one parent per link: a tree exactly when every link is reachable.
    let mut reached = HashSet::from([roots[0]]);
    let mut frontier = vec![roots[0]];
    while let Some(l) = frontier.pop() {
        for j in robot.joints.iter().filter(|j| j.parent.link == l) {
            if reached.insert(j.child.link.as_str()) {
                frontier.push(j.child.link.as_str());
            }
        }
    }
    if reached.len() != robot.links.len() {
        return vec![SetupError::urdf("URDF kinematic graph has a cycle")];
    }
    out
}

/// Masses of a tree: finite and ≥ 0, and every body that moves has some.
pub(crate) fn mass_problems(robot: &Robot) -> Vec<SetupError> {
    let mut out = Vec::new();
    for l in &robot.links {
        let m = l.inertial.mass.value;
        if !(m.is_finite() && m >= 0.0) {
            out.push(SetupError::urdf_at(
                "link",
                &l.name,
                format!(
                    "URDF link `{}` <mass> must be finite and ≥ 0 (0 or no <inertial>: a frame)",
                    l.name
                ),
            ));
        }
    }
    if out.is_empty() {
        // Frames (no mass) are lumped into the bodies they are fixed to; a
        // body that moves on its own needs mass.
        if let Err(e) = crate::engine::lump::lump(robot, &[]) {
            out.push(e);
        }
    }
    out
}

/// What the loader needs beyond a tree: the first problem of [`loadable_problems`].
pub(crate) fn validate_loadable(robot: &Robot) -> Result<(), SetupError> {
    match loadable_problems(robot).into_iter().next() {
        Some(p) => Err(p),
        None => Ok(()),
    }
}

/// What the loader needs beyond a tree: finite inertias of the bodies' links
/// (frames' are ignored), axes on moving joints.
pub(crate) fn loadable_problems(robot: &Robot) -> Vec<SetupError> {
    let mut out = Vec::new();
    for j in &robot.joints {
        let moving = !matches!(j.joint_type, JointType::Fixed | JointType::Floating);
        let a = j.axis.xyz.0;
        if moving && !(a.iter().all(|c| c.is_finite()) && a.iter().any(|c| *c != 0.0)) {
            out.push(SetupError::urdf_at(
                "joint",
                &j.name,
                format!("URDF joint `{}` needs a non-zero <axis>", j.name),
            ));
        }
    }
    for l in robot
        .links
        .iter()
        .filter(|l| !crate::engine::lump::is_frame(l))
    {
        let t = &l.inertial.inertia;
        let all = [t.ixx, t.ixy, t.ixz, t.iyy, t.iyz, t.izz];
        if all.iter().any(|v| !v.is_finite()) || t.ixx < 0.0 || t.iyy < 0.0 || t.izz < 0.0 {
            out.push(SetupError::urdf_at(
                "link",
                &l.name,
                format!(
                    "URDF link `{}` inertia must be finite with ixx, iyy, izz ≥ 0",
                    l.name
                ),
            ));
        }
    }
    out
}

/// The `<limit effort>` of a joint, when the URDF gives one (> 0).
pub fn effort(robot: &Robot, joint: &str) -> Option<f64> {
    robot
        .joints
        .iter()
        .find(|j| j.name == joint)
        .map(|j| j.limit.effort)
        .filter(|e| e.is_finite() && *e > 0.0)
}

/// Radius of the first sphere or cylinder collision of `link`, if any.
pub(crate) fn collision_radius(robot: &Robot, link: &str) -> Option<f64> {
    robot
        .links
        .iter()
        .find(|l| l.name == link)?
        .collision
        .iter()
        .find_map(|c| match c.geometry {
            urdf_rs::Geometry::Sphere { radius } | urdf_rs::Geometry::Cylinder { radius, .. } => {
                Some(radius)
            }
            _ => None,
        })
}

/// The radius of `link`'s first round collision (`what`, e.g. "the wheel",
/// names it in the error when it has none).
pub(crate) fn round_collision(robot: &Robot, link: &str, what: &str) -> Result<f64, SetupError> {
    if !robot.links.iter().any(|l| l.name == link) {
        return Err(SetupError::urdf(format!("URDF lacks link `{link}`")));
    }
    collision_radius(robot, link).ok_or_else(|| {
        SetupError::urdf_at(
            "link",
            link,
            format!("URDF link `{link}` needs a sphere or cylinder collision ({what})"),
        )
    })
}

/// Check that `link` has a round collision (`what`, e.g. "the wheel") of the
/// scenario's `radius`; the error names both values.
pub(crate) fn require_radius(
    robot: &Robot,
    link: &str,
    what: &str,
    radius: f64,
) -> Result<(), SetupError> {
    let r = round_collision(robot, link, what)?;
    if (r - radius).abs() > 1e-6 {
        return Err(SetupError::key(
            "model.radius",
            format!(
                "URDF radius of {what} ({} m) differs from the scenario's model.radius ({} m): \
                 the physics body comes from the URDF, so change the radius of link `{link}`'s \
                 collision (and its inertia) in a copy of the URDF too",
                crate::numfmt::shortest(r),
                crate::numfmt::shortest(radius)
            ),
        ));
    }
    Ok(())
}

/// The tag of a geometry (`box`, `cylinder`, ...).
pub(crate) fn shape_tag(g: &Geometry) -> &'static str {
    match g {
        Geometry::Box { .. } => "box",
        Geometry::Cylinder { .. } => "cylinder",
        Geometry::Capsule { .. } => "capsule",
        Geometry::Sphere { .. } => "sphere",
        Geometry::Mesh { .. } => "mesh",
    }
}

/// URDF pose (xyz, rpy) as a [`Pose`].
pub(crate) fn pose_of(p: &urdf_rs::Pose) -> Pose {
    let q = UnitQuaternion::from_euler_angles(p.rpy[0], p.rpy[1], p.rpy[2]);
    Pose {
        translation: [p.xyz[0], p.xyz[1], p.xyz[2]],
        rotation: [q.i, q.j, q.k, q.w],
    }
}

/// Visual geometry of every link, in URDF link order (meshes as loaded:
/// their file names resolved by the validation pass).
pub fn visuals(robot: &Robot) -> Vec<LinkVisual> {
    let named: HashMap<&str, [f64; 4]> = robot
        .materials
        .iter()
        .filter_map(|m| m.color.as_ref().map(|c| (m.name.as_str(), c.rgba.0)))
        .collect();
    robot
        .links
        .iter()
        .map(|l| LinkVisual {
            name: l.name.clone(),
            visuals: l
                .visual
                .iter()
                .filter_map(|v| {
                    let shape = match &v.geometry {
                        urdf_rs::Geometry::Box { size } => Shape::Box { size: size.0 },
                        urdf_rs::Geometry::Cylinder { radius, length } => Shape::Cylinder {
                            radius: *radius,
                            length: *length,
                        },
                        urdf_rs::Geometry::Sphere { radius } => Shape::Sphere { radius: *radius },
                        urdf_rs::Geometry::Capsule { radius, length } => Shape::Capsule {
                            radius: *radius,
                            length: *length,
                        },
                        // Resolved by the validation pass; one that does not load is left out.
                        urdf_rs::Geometry::Mesh { filename, scale } => Shape::Mesh {
                            file: filename.clone(),
                            mesh: crate::engine::mesh::load(
                                Path::new(filename),
                                crate::engine::mesh::scale_of(scale),
                            )
                            .ok()?,
                        },
                    };
                    let rgba = v
                        .material
                        .as_ref()
                        .and_then(|m| {
                            m.color
                                .as_ref()
                                .map(|c| c.rgba.0)
                                .or_else(|| named.get(m.name.as_str()).copied())
                        })
                        .unwrap_or([0.6, 0.6, 0.6, 1.0]);
                    Some(Visual {
                        shape,
                        origin: pose_of(&v.origin),
                        rgba: rgba.map(|c| c as f32),
                    })
                })
                .collect(),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    const LINK: &str = r#"<inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>"#;

    fn robot(links: &[&str], joints: &[(&str, &str, &str)], extra: &str) -> Result<(), String> {
        let mut s = String::from("<robot name=\"r\">");
        for l in links {
            s += &format!("<link name=\"{l}\">{LINK}</link>");
        }
        for (i, (t, p, c)) in joints.iter().enumerate() {
            s += &format!(
                "<joint name=\"j{i}\" type=\"{t}\"><parent link=\"{p}\"/><child link=\"{c}\"/><axis xyz=\"0 0 1\"/></joint>"
            );
        }
        s += extra;
        s += "</robot>";
        validate(&urdf_rs::read_from_string(&s).map_err(|e| e.to_string())?)
            .map_err(|e| e.to_string())
    }

    #[test]
    fn trees_pass_and_other_graphs_are_named() {
        let j = |p, c| ("continuous", p, c);
        robot(&["a", "b", "c"], &[j("a", "b"), j("a", "c")], "").unwrap();
        let e = robot(&["a", "b", "c"], &[j("a", "b")], "").unwrap_err();
        assert!(e.contains("2 root links (a, c)"), "{e}");
        let e = robot(&["a", "b", "c"], &[j("b", "c"), j("c", "b")], "").unwrap_err();
        assert!(e.contains("cycle"), "{e}");
        let e = robot(&["a", "b"], &[j("a", "b"), j("a", "b")], "").unwrap_err();
        assert!(e.contains("two parent joints"), "{e}");
        let e = robot(&["a"], &[j("a", "x")], "").unwrap_err();
        assert!(e.contains("unknown link `x`"), "{e}");
    }

    #[test]
    fn unsupported_content_is_rejected() {
        let neg = r#"<link name="n"><inertial><mass value="1"/><inertia ixx="-1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
            <joint name="jn" type="fixed"><parent link="a"/><child link="n"/></joint>"#;
        let e = robot(&["a"], &[], neg).unwrap_err();
        assert!(e.contains("`n` inertia"), "{e}");
        let axis = r#"<link name="z">"#.to_string()
            + LINK
            + r#"</link><joint name="jz" type="revolute"><parent link="a"/><child link="z"/><axis xyz="0 0 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>"#;
        let e = robot(&["a"], &[], &axis).unwrap_err();
        assert!(e.contains("`jz` needs a non-zero <axis>"), "{e}");
    }
}
