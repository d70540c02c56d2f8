//! Frames and fixed-joint lumping: which URDF links become one rigid body.
//!
//! Published robot descriptions hang massless frames (`base_footprint`,
//! `imu_link`, `*_optical_frame`) and rigidly mounted parts (casters,
//! lidars) on fixed joints. The loader merges each fixed-joint chain into one
//! rigid body, as Gazebo's URDF-to-SDF conversion and MuJoCo's `fusestatic`
//! do: collisions, visuals and inertia of every link in the chain move with
//! it, and the body's inertia is their sum. A link without `<inertial>` (or
//! with zero mass) is a frame; only a body that moves on its own (the root's
//! chain, or the chain under a non-fixed joint) must have mass.
//!
//! A body's frame is the frame of its first massive link (breadth first from
//! the top of the chain), so a massless `base_footprint` root is a frame on
//! `base_link`. A model that needs a fixed joint as a joint (the mobile
//! manipulator's compliant wrist) keeps it ([`lump`]'s `keep`).

use crate::engine::rapier::math::Pose as RPose;
use crate::engine::real::origin;
use crate::error::SetupError;
use urdf_rs::{JointType, Robot};

/// How the links of one URDF map onto rigid bodies.
#[derive(Debug, Clone)]
pub struct Lumping {
    /// Per URDF link (URDF order): the index of the link whose frame is its
    /// body's frame (itself for a body's own link).
    pub body: Vec<usize>,
    /// Per URDF link: its pose in its body's frame; `None` for the body's
    /// own link (no transform at all, so an unlumped robot loads exactly as
    /// before).
    pub offset: Vec<Option<RPose>>,
    /// Per URDF joint: whether it joins two bodies (false: lumped away).
    pub joint_kept: Vec<bool>,
}

impl Lumping {
    /// Whether link `i` carries its own body.
    pub fn is_body(&self, i: usize) -> bool {
        self.body[i] == i
    }

    /// The links lumped into another link's body: (link, body link).
    pub fn lumped(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        self.body
            .iter()
            .enumerate()
            .filter(|(i, b)| i != *b)
            .map(|(i, b)| (i, *b))
    }
}

/// Whether a link is a frame: no mass.
pub(crate) fn is_frame(l: &urdf_rs::Link) -> bool {
    l.inertial.mass.value == 0.0
}

/// Group the links of `robot` (one validated tree) into bodies: every fixed
/// joint is lumped except those named in `keep`. The error names every
/// body without mass in one message.
pub fn lump(robot: &Robot, keep: &[&str]) -> Result<Lumping, SetupError> {
    let n = robot.links.len();
    let index = |name: &str| robot.links.iter().position(|l| l.name == name);
    let mut parent: Vec<Option<usize>> = vec![None; n];
    for (k, j) in robot.joints.iter().enumerate() {
        if let Some(c) = index(&j.child.link) {
            parent[c] = Some(k);
        }
    }
    let lumps = |k: usize| {
        let j = &robot.joints[k];
        j.joint_type == JointType::Fixed && !keep.contains(&j.name.as_str())
    };
    // The top of each link's chain, and the link's pose relative to it.
    let mut top = vec![usize::MAX; n];
    let mut in_top: Vec<Option<RPose>> = vec![None; n];
    for start in 0..n {
        let mut path = Vec::new();
        let mut at = start;
        while let Some(k) = parent[at].filter(|k| lumps(*k)) {
            if top[at] != usize::MAX {
                break;
            }
            path.push(at);
            at = index(&robot.joints[k].parent.link).unwrap_or(at);
            if path.len() > n {
                break; // not a tree: validation reports it
            }
        }
        if top[at] == usize::MAX {
            top[at] = at;
        }
        for &l in path.iter().rev() {
            let k = parent[l].expect("on the path");
            let p = index(&robot.joints[k].parent.link).unwrap_or(l);
            top[l] = top[p];
            let base = in_top[p].unwrap_or(RPose::IDENTITY);
            in_top[l] = Some(base * origin(&robot.joints[k].origin));
        }
    }
    // Each chain's body frame: its first massive link, breadth first.
    let mut body = vec![usize::MAX; n];
    let mut massless: Vec<(usize, bool)> = Vec::new();
    for t in (0..n).filter(|&t| top[t] == t) {
        let mut order = vec![t];
        let mut i = 0;
        while i < order.len() {
            let at = &robot.links[order[i]].name;
            for (k, j) in robot.joints.iter().enumerate() {
                if j.parent.link == *at && lumps(k) {
                    if let Some(c) = index(&j.child.link) {
                        order.push(c);
                    }
                }
            }
            i += 1;
        }
        let frame = order.iter().copied().find(|&l| !is_frame(&robot.links[l]));
        match frame {
            Some(f) => {
                for &l in &order {
                    body[l] = f;
                }
            }
            None => massless.push((t, parent[t].is_none())),
        }
    }
    if !massless.is_empty() {
        let names = |root: bool| -> Vec<String> {
            massless
                .iter()
                .filter(|(_, r)| *r == root)
                .map(|(t, _)| format!("`{}`", robot.links[*t].name))
                .collect()
        };
        let (moving, root) = (names(false), names(true));
        let mut parts = Vec::new();
        if !moving.is_empty() {
            let s = if moving.len() > 1 { "s" } else { "" };
            parts.push(format!(
                "link{s} {} move{} (child of a non-fixed joint) but neither {} nor anything fixed to {} has mass",
                moving.join(", "),
                if moving.len() > 1 { "" } else { "s" },
                if moving.len() > 1 { "they" } else { "it" },
                if moving.len() > 1 { "them" } else { "it" },
            ));
        }
        if !root.is_empty() {
            parts.push(format!(
                "root link {} has no mass and nothing fixed to it has",
                root.join(", ")
            ));
        }
        let (first, _) = massless[0];
        return Err(SetupError::urdf_at(
            "link",
            &robot.links[first].name,
            format!(
                "URDF {}: give a link of each an <inertial> with mass > 0",
                parts.join("; ")
            ),
        ));
    }
    let offset = (0..n)
        .map(|l| {
            let f = body[l];
            if f == l {
                return None;
            }
            let of = |x: usize| in_top[x].unwrap_or(RPose::IDENTITY);
            Some(of(f).inverse() * of(l))
        })
        .collect();
    let joint_kept = (0..robot.joints.len()).map(|k| !lumps(k)).collect();
    Ok(Lumping {
        body,
        offset,
        joint_kept,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn link(name: &str, mass: f64) -> String {
        if mass == 0.0 {
            return format!("<link name=\"{name}\"/>");
        }
        format!(
            "<link name=\"{name}\"><inertial><mass value=\"{mass}\"/><inertia ixx=\"1\" ixy=\"0\" ixz=\"0\" iyy=\"1\" iyz=\"0\" izz=\"1\"/></inertial></link>"
        )
    }

    fn joint(kind: &str, p: &str, c: &str, xyz: &str) -> String {
        format!(
            "<joint name=\"{p}_{c}\" type=\"{kind}\"><parent link=\"{p}\"/><child link=\"{c}\"/><origin xyz=\"{xyz}\"/><axis xyz=\"0 1 0\"/></joint>"
        )
    }

    fn robot(parts: &[String]) -> Robot {
        urdf_rs::read_from_string(&format!("<robot name=\"r\">{}</robot>", parts.concat())).unwrap()
    }

    #[test]
    fn a_massless_root_is_a_frame_on_its_first_massive_child() {
        let r = robot(&[
            link("base_footprint", 0.0),
            link("base_link", 2.0),
            link("imu_link", 0.0),
            link("caster", 0.5),
            link("wheel", 1.0),
            joint("fixed", "base_footprint", "base_link", "0 0 0.1"),
            joint("fixed", "base_link", "imu_link", "0.1 0 0.2"),
            joint("fixed", "base_link", "caster", "-0.2 0 -0.05"),
            joint("continuous", "base_link", "wheel", "0 0.2 0"),
        ]);
        let l = lump(&r, &[]).unwrap();
        assert_eq!(l.body, vec![1, 1, 1, 1, 4]);
        assert_eq!(l.joint_kept, vec![false, false, false, true]);
        let t = |i: usize| l.offset[i].unwrap().translation;
        assert!((t(0) - crate::engine::real::vector(0.0, 0.0, -0.1)).length() < 1e-15);
        assert!((t(2) - crate::engine::real::vector(0.1, 0.0, 0.2)).length() < 1e-15);
        assert!(l.offset[1].is_none() && l.offset[4].is_none());
        // Kept: the caster stays a body of its own.
        let k = lump(&r, &["base_link_caster"]).unwrap();
        assert_eq!(k.body, vec![1, 1, 1, 3, 4]);
    }

    #[test]
    fn every_massless_moving_link_is_named_once() {
        let r = robot(&[
            link("base", 1.0),
            link("left", 0.0),
            link("right", 0.0),
            link("right_tyre", 0.3),
            link("sensor_mount", 0.0),
            joint("continuous", "base", "left", "0 0.2 0"),
            joint("continuous", "base", "right", "0 -0.2 0"),
            joint("fixed", "right", "right_tyre", "0 0 0"),
            joint("revolute", "base", "sensor_mount", "0 0 0.3"),
        ]);
        let e = lump(&r, &[]).unwrap_err().to_string();
        assert_eq!(
            e,
            "URDF links `left`, `sensor_mount` move (child of a non-fixed joint) but neither they nor anything fixed to them has mass: give a link of each an <inertial> with mass > 0"
        );
        let root = robot(&[
            link("world", 0.0),
            link("frame", 0.0),
            joint("fixed", "world", "frame", "0 0 0"),
        ]);
        let e = lump(&root, &[]).unwrap_err().to_string();
        assert!(e.contains("root link `world` has no mass"), "{e}");
    }
}
