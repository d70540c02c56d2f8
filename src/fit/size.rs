//! The robot's size, the default length at which a heading error counts
//! as a position error: the farthest wheel centre (the child link of a
//! continuous joint) from the root link's origin, in the plane; without
//! wheels, the farthest link origin.

use nalgebra::{Isometry3, Translation3, UnitQuaternion};
use std::collections::HashMap;

/// The size of `robot`, m (None for a robot of one link).
pub(crate) fn robot_size(robot: &urdf_rs::Robot) -> Option<(f64, &'static str)> {
    let by_child: HashMap<&str, &urdf_rs::Joint> = robot
        .joints
        .iter()
        .map(|j| (j.child.link.as_str(), j))
        .collect();
    let pose = |link: &str| -> Isometry3<f64> {
        let mut chain = Vec::new();
        let mut at = link;
        while let Some(j) = by_child.get(at) {
            if chain.len() > robot.joints.len() {
                break;
            }
            chain.push(*j);
            at = j.parent.link.as_str();
        }
        chain.iter().rev().fold(Isometry3::identity(), |acc, j| {
            let o = &j.origin;
            let q = UnitQuaternion::from_euler_angles(o.rpy[0], o.rpy[1], o.rpy[2]);
            acc * Isometry3::from_parts(Translation3::new(o.xyz[0], o.xyz[1], o.xyz[2]), q)
        })
    };
    let planar = |link: &str| {
        let t = pose(link).translation.vector;
        t.x.hypot(t.y)
    };
    let farthest = |links: Vec<&str>| {
        links
            .into_iter()
            .map(planar)
            .filter(|d| *d > 0.0)
            .fold(None, |a: Option<f64>, d| Some(a.map_or(d, |a| a.max(d))))
    };
    let wheels: Vec<&str> = robot
        .joints
        .iter()
        .filter(|j| matches!(j.joint_type, urdf_rs::JointType::Continuous))
        .map(|j| j.child.link.as_str())
        .collect();
    if let Some(d) = farthest(wheels) {
        return Some((
            d,
            "the robot's size: its farthest wheel centre from the base link's origin",
        ));
    }
    farthest(robot.links.iter().map(|l| l.name.as_str()).collect()).map(|d| {
        (
            d,
            "the robot's size: its farthest link origin from the base link's origin",
        )
    })
}
