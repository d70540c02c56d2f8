//! Wheels nothing drives: continuous joints whose child link rolls on the
//! ground (a cylinder or sphere collision whose lowest point is the
//! robot's lowest, joints at zero) that the model neither drives nor names.
//! Driving two of a skid steer's four wheels, say, leaves the other two
//! dragging: the run fails with no word about why unless this is said.

use crate::engine::reading::UrdfReading;
use crate::engine::required::Named;
use urdf_rs::{Geometry, JointType, Robot};

/// How far above the robot's lowest point a wheel may reach down and still
/// touch the ground, m (the casters' tolerance).
const TOUCH: f64 = 2e-3;

/// The warning naming the undriven wheel joints of `robot`, if any: for a
/// model whose `reading` has drives and wheels, with the URDF names it uses.
pub(crate) fn undriven(robot: &Robot, reading: &UrdfReading, names: &[Named]) -> Option<String> {
    if reading.drives.is_empty() || reading.wheels.is_empty() {
        return None;
    }
    let frames = crate::robots::wheeled::link_frames(robot);
    let lowest = |link: &urdf_rs::Link, round_only: bool| -> Option<f64> {
        let at = frames.get(&link.name)?;
        link.collision
            .iter()
            .filter(|c| {
                !round_only
                    || matches!(
                        c.geometry,
                        Geometry::Cylinder { .. } | Geometry::Sphere { .. }
                    )
            })
            .filter_map(|c| {
                crate::engine::world::lowest_point(
                    &c.geometry,
                    &(*at * crate::engine::world::origin(&c.origin)),
                )
            })
            .reduce(f64::min)
    };
    let ground = robot
        .links
        .iter()
        .filter_map(|l| lowest(l, false))
        .reduce(f64::min)?;
    let known = |n: &str| {
        names.iter().any(|x| x.name == n)
            || reading.drives.iter().any(|d| d.joint == n)
            || reading.wheels.iter().any(|w| w.joint == n || w.link == n)
    };
    let mut found: Vec<&str> = Vec::new();
    for j in &robot.joints {
        if j.joint_type != JointType::Continuous || known(&j.name) || known(&j.child.link) {
            continue;
        }
        let Some(child) = robot.links.iter().find(|l| l.name == j.child.link) else {
            continue;
        };
        if lowest(child, true).is_some_and(|z| z - ground <= TOUCH) {
            found.push(&j.name);
        }
    }
    if found.is_empty() {
        return None;
    }
    let list: Vec<String> = found.iter().map(|n| format!("`{n}`")).collect();
    let mut keys: Vec<&str> = names
        .iter()
        .filter(|n| n.required.element == crate::engine::required::Element::Joint)
        .filter_map(|n| n.required.key)
        .collect();
    keys.dedup();
    let hint = if keys.contains(&"left_wheel_joint") {
        // A differential drive: a skid steer lists every wheel of a side.
        " (a skid steer lists every wheel of a side: [model] `left_wheel_joints`, `right_wheel_joints`)".to_string()
    } else if keys.is_empty() {
        String::new()
    } else {
        format!(
            " ([model] {})",
            keys.iter()
                .map(|k| format!("`{k}`"))
                .collect::<Vec<_>>()
                .join(", ")
        )
    };
    Some(if found.len() == 1 {
        format!(
            "continuous joint {} looks like a wheel (a round collision touching the ground) but no drive turns it: it rolls freely; to drive it, name it among the model's driven joints{hint}",
            list[0]
        )
    } else {
        format!(
            "continuous joints {} look like wheels (round collisions touching the ground) but no drive turns them: they roll freely; to drive them, name them among the model's driven joints{hint}",
            list.join(", ")
        )
    })
}
