//! URDF checks of the validation pass: the file kind and size, the structure
//! ([`crate::physics::urdf::read`]: links, joints, a tree, positive masses)
//! and every number the physics will use: finite positive masses,
//! positive-definite inertias, finite origins, axes, limits and geometry.
//! A NaN or negative inertia would otherwise be accepted (a wheel that never
//! turns) and a NaN origin reported as a diverged simulation.
//!
//! Errors name the URDF file, the line of the element (located in the text:
//! urdf-rs keeps no positions) and the link or joint.

use crate::error::Error;
use crate::input::{read_text, URDF_MAX_BYTES};
use nalgebra::Matrix3;
use std::path::Path;
use urdf_rs::{Geometry, JointType, Pose, Robot};

/// Where a problem sits: an element (`link`/`joint`) by name, then nested
/// tags inside it (`inertial`, `inertia`; `visual#2`, `origin`).
#[derive(Debug, Clone, PartialEq)]
pub struct Place {
    elem: &'static str,
    name: String,
    inner: Vec<String>,
}

impl Place {
    fn new(elem: &'static str, name: &str, inner: &[&str]) -> Place {
        Place {
            elem,
            name: name.to_string(),
            inner: inner.iter().map(|s| s.to_string()).collect(),
        }
    }
}

/// Read, parse and check a URDF.
pub fn load(path: &Path) -> Result<Robot, Error> {
    let text = read_text(path, "URDF", URDF_MAX_BYTES)?;
    let to_error = |m: String| Error::Input {
        path: path.into(),
        line: line_of_message(&text, &m),
        message: m,
    };
    let robot = crate::physics::urdf::parse(path).map_err(to_error)?;
    crate::physics::urdf::validate_tree(&robot).map_err(to_error)?;
    // Numbers before the loader's own checks: their errors name the element.
    check_numbers(&robot).map_err(|(place, m)| Error::Input {
        path: path.into(),
        line: locate(&text, &place),
        message: m,
    })?;
    crate::physics::urdf::validate_loadable(&robot).map_err(to_error)?;
    Ok(robot)
}

/// A URDF error about the file at `path` (a message from physics setup that
/// starts with `URDF`), with the line of the link or joint it names.
pub fn error_in(path: &Path, message: &str) -> Error {
    let text = read_text(path, "URDF", URDF_MAX_BYTES).unwrap_or_default();
    Error::Input {
        path: path.into(),
        line: line_of_message(&text, message),
        message: message.to_string(),
    }
}

fn finite<const N: usize>(v: &[f64; N]) -> bool {
    v.iter().all(|x| x.is_finite())
}

fn check_pose(p: &Pose, place: &Place, what: &str) -> Result<(), (Place, String)> {
    if !finite(&p.xyz.0) || !finite(&p.rpy.0) {
        return Err((
            place.clone(),
            format!(
                "{what} <origin> needs finite xyz and rpy, got xyz {:?} rpy {:?}",
                p.xyz.0, p.rpy.0
            ),
        ));
    }
    Ok(())
}

/// The tag of a geometry (`box`, `cylinder`, ...).
fn shape_tag(g: &Geometry) -> &'static str {
    match g {
        Geometry::Box { .. } => "box",
        Geometry::Cylinder { .. } => "cylinder",
        Geometry::Capsule { .. } => "capsule",
        Geometry::Sphere { .. } => "sphere",
        Geometry::Mesh { .. } => "mesh",
    }
}

fn check_geometry(g: &Geometry, place: &Place, what: &str) -> Result<(), (Place, String)> {
    let positive = |v: &[f64]| v.iter().all(|x| x.is_finite() && *x > 0.0);
    let ok = match g {
        Geometry::Box { size } => positive(&size.0),
        Geometry::Cylinder { radius, length } | Geometry::Capsule { radius, length } => {
            positive(&[*radius, *length])
        }
        Geometry::Sphere { radius } => positive(&[*radius]),
        Geometry::Mesh { scale, .. } => scale
            .as_ref()
            .is_none_or(|s| finite(&s.0) && s.0.iter().all(|x| *x != 0.0)),
    };
    if ok {
        Ok(())
    } else {
        Err((
            place.clone(),
            format!("{what} <geometry> needs finite sizes > 0, got {g:?}"),
        ))
    }
}

/// Every number the physics uses, checked; the error says where.
pub fn check_numbers(robot: &Robot) -> Result<(), (Place, String)> {
    let colour_ok = |c: &urdf_rs::Color| c.rgba.0.iter().all(|x| (0.0..=1.0).contains(x));
    for m in &robot.materials {
        if let Some(c) = m.color.as_ref().filter(|c| !colour_ok(c)) {
            return Err((
                Place::new("material", &m.name, &["color"]),
                format!(
                    "URDF material `{}` <color> rgba must be in [0, 1], got {:?}",
                    m.name, c.rgba.0
                ),
            ));
        }
    }
    for l in &robot.links {
        let n = &l.name;
        let at = |inner: &[&str]| Place::new("link", n, inner);
        let m = l.inertial.mass.value;
        if !(m.is_finite() && m > 0.0) {
            return Err((
                at(&["inertial", "mass"]),
                format!("URDF link `{n}` <mass> must be finite and > 0, got {m}"),
            ));
        }
        let i = &l.inertial.inertia;
        let t = Matrix3::new(
            i.ixx, i.ixy, i.ixz, i.ixy, i.iyy, i.iyz, i.ixz, i.iyz, i.izz,
        );
        if !t.iter().all(|x| x.is_finite()) || t.cholesky().is_none() {
            return Err((
                at(&["inertial", "inertia"]),
                format!(
                    "URDF link `{n}` <inertia> must be finite and positive definite, got ixx {} ixy {} ixz {} iyy {} iyz {} izz {}",
                    i.ixx, i.ixy, i.ixz, i.iyy, i.iyz, i.izz
                ),
            ));
        }
        check_pose(
            &l.inertial.origin,
            &at(&["inertial", "origin"]),
            &format!("URDF link `{n}` inertial"),
        )?;
        for (k, v) in l.visual.iter().enumerate() {
            let tag = format!("visual#{k}");
            let what = format!("URDF link `{n}` visual {}", k + 1);
            check_pose(&v.origin, &at(&[&tag, "origin"]), &what)?;
            let shape = shape_tag(&v.geometry);
            check_geometry(&v.geometry, &at(&[&tag, "geometry", shape]), &what)?;
            if let Some(c) = v.material.as_ref().and_then(|m| m.color.as_ref()) {
                if !colour_ok(c) {
                    return Err((
                        at(&[&tag, "material"]),
                        format!("{what} <color> rgba must be in [0, 1], got {:?}", c.rgba.0),
                    ));
                }
            }
        }
        for (k, c) in l.collision.iter().enumerate() {
            let tag = format!("collision#{k}");
            let what = format!("URDF link `{n}` collision {}", k + 1);
            check_pose(&c.origin, &at(&[&tag, "origin"]), &what)?;
            let shape = shape_tag(&c.geometry);
            check_geometry(&c.geometry, &at(&[&tag, "geometry", shape]), &what)?;
        }
    }
    for j in &robot.joints {
        let n = &j.name;
        let at = |inner: &[&str]| Place::new("joint", n, inner);
        check_pose(&j.origin, &at(&["origin"]), &format!("URDF joint `{n}`"))?;
        let moves = !matches!(j.joint_type, JointType::Fixed | JointType::Floating);
        let a = j.axis.xyz.0;
        if moves && !(finite(&a) && a.iter().any(|x| *x != 0.0)) {
            return Err((
                at(&["axis"]),
                format!("URDF joint `{n}` <axis> must be finite and non-zero, got {a:?}"),
            ));
        }
        let lim = &j.limit;
        if matches!(j.joint_type, JointType::Revolute | JointType::Prismatic) {
            let vals = [lim.lower, lim.upper, lim.effort, lim.velocity];
            if !finite(&vals) || lim.lower > lim.upper || lim.effort < 0.0 || lim.velocity < 0.0 {
                return Err((
                    at(&["limit"]),
                    format!(
                        "URDF joint `{n}` <limit> needs finite lower ≤ upper and effort, velocity ≥ 0, got lower {} upper {} effort {} velocity {}",
                        lim.lower, lim.upper, lim.effort, lim.velocity
                    ),
                ));
            }
        }
        if let Some(d) = &j.dynamics {
            if !(d.damping.is_finite()
                && d.damping >= 0.0
                && d.friction.is_finite()
                && d.friction >= 0.0)
            {
                return Err((
                    at(&["dynamics"]),
                    format!(
                        "URDF joint `{n}` <dynamics> needs finite damping, friction ≥ 0, got {} and {}",
                        d.damping, d.friction
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// Byte offset of the first start tag `<tag` (not `<tagx`) in `text[from..to]`.
fn find_tag(text: &str, tag: &str, from: usize, to: usize) -> Option<usize> {
    let hay = &text[from..to];
    let pat = format!("<{tag}");
    hay.match_indices(&pat)
        .find(|(i, _)| {
            hay[i + pat.len()..]
                .chars()
                .next()
                .is_some_and(|c| c.is_whitespace() || c == '>' || c == '/')
        })
        .map(|(i, _)| from + i)
}

/// Where the element starting at `start` ends (after its closing tag, or
/// its own `/>`).
fn element_end(text: &str, start: usize, tag: &str) -> usize {
    let open_end = text[start..]
        .find('>')
        .map_or(text.len(), |i| start + i + 1);
    if text[..open_end].ends_with("/>") {
        return open_end;
    }
    let close = format!("</{tag}>");
    text[open_end..]
        .find(&close)
        .map_or(text.len(), |i| open_end + i + close.len())
}

/// Whether the start tag at `start` has `name="name"` (either quote).
fn has_name(text: &str, start: usize, name: &str) -> bool {
    let end = text[start..].find('>').map_or(text.len(), |i| start + i);
    let tag = &text[start..end];
    [format!("name=\"{name}\""), format!("name='{name}'")]
        .iter()
        .any(|p| tag.contains(p.as_str()))
}

/// 1-based line of a [`Place`] in the URDF text: the innermost tag found.
pub fn locate(text: &str, place: &Place) -> Option<usize> {
    let mut from = 0;
    let start = loop {
        let s = find_tag(text, place.elem, from, text.len())?;
        if has_name(text, s, &place.name) {
            break s;
        }
        from = s + 1;
    };
    let (mut at, mut end) = (start, element_end(text, start, place.elem));
    for inner in &place.inner {
        let (tag, nth) = match inner.split_once('#') {
            Some((t, k)) => (t, k.parse::<usize>().unwrap_or(0)),
            None => (inner.as_str(), 0),
        };
        let mut from = at + 1;
        let mut found = None;
        for _ in 0..=nth {
            match find_tag(text, tag, from.min(end), end) {
                Some(s) => {
                    found = Some(s);
                    from = s + 1;
                }
                None => {
                    found = None;
                    break;
                }
            }
        }
        match found {
            Some(s) => {
                end = element_end(text, s, tag).min(end);
                at = s;
            }
            None => break,
        }
    }
    Some(text[..at].matches('\n').count() + 1)
}

/// Line of the first link or joint a message names (`` link `x` ``,
/// `` joint `x` ``), if it is in the text.
pub fn line_of_message(text: &str, message: &str) -> Option<usize> {
    let mut best: Option<(usize, usize)> = None;
    for elem in ["link", "joint"] {
        let pat = format!("{elem} `");
        for (i, _) in message.match_indices(&pat) {
            let rest = &message[i + pat.len()..];
            let Some(name) = rest.split('`').next() else {
                continue;
            };
            let place = Place::new(elem, name, &[]);
            if let Some(line) = locate(text, &place) {
                if best.is_none_or(|(j, _)| i < j) {
                    best = Some((i, line));
                }
            }
        }
    }
    best.map(|(_, line)| line)
}

#[cfg(test)]
mod tests {
    use super::*;

    const URDF: &str = r#"<robot name="r">
  <link name="base">
    <inertial>
      <origin xyz="0 0 0"/>
      <mass value="1"/>
      <inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/>
    </inertial>
    <visual><geometry><box size="1 1 1"/></geometry></visual>
    <visual>
      <origin xyz="0 0 1"/>
      <geometry><sphere radius="0.1"/></geometry>
    </visual>
  </link>
  <link name='wheel'>
    <inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>
  </link>
  <joint name="j" type="continuous">
    <parent link="base"/>
    <child link="wheel"/>
    <axis xyz="0 0 1"/>
  </joint>
</robot>
"#;

    #[test]
    fn locates_elements_and_nested_tags() {
        let at = |elem, name, inner: &[&str]| locate(URDF, &Place::new(elem, name, inner));
        assert_eq!(at("link", "base", &[]), Some(2));
        assert_eq!(at("link", "base", &["inertial", "inertia"]), Some(6));
        assert_eq!(at("link", "base", &["visual#1", "origin"]), Some(10));
        assert_eq!(at("link", "wheel", &["inertial", "mass"]), Some(15));
        assert_eq!(at("joint", "j", &["axis"]), Some(20));
        // Missing nested tag: the innermost one found.
        assert_eq!(at("joint", "j", &["limit"]), Some(17));
        assert_eq!(at("link", "ghost", &[]), None);
        assert_eq!(
            line_of_message(URDF, "URDF joint `j` names unknown link `ghost`"),
            Some(17)
        );
    }

    #[test]
    fn shipped_models_pass_and_bad_numbers_fail() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("models");
        for f in ["rolling_disk", "rover", "space_robot", "sphere"] {
            load(&dir.join(format!("{f}.urdf"))).unwrap();
        }
        let robot = urdf_rs::read_from_string(URDF).unwrap();
        check_numbers(&robot).unwrap();
        let mut r = robot.clone();
        r.links[1].inertial.inertia.ixx = -1.0;
        let (place, m) = check_numbers(&r).unwrap_err();
        assert_eq!(locate(URDF, &place), Some(15));
        assert!(m.contains("positive definite"), "{m}");
        // Indefinite although every diagonal entry is positive.
        let mut r = robot.clone();
        r.links[0].inertial.inertia.ixy = 2.0;
        assert!(check_numbers(&r).is_err());
        let mut r = robot.clone();
        r.joints[0].origin.xyz.0[1] = f64::NAN;
        let (place, m) = check_numbers(&r).unwrap_err();
        assert!(m.contains("joint `j` <origin>"), "{m}");
        assert_eq!(locate(URDF, &place), Some(17));
        let mut r = robot;
        r.joints[0].axis.xyz.0 = [0.0; 3];
        assert!(check_numbers(&r).unwrap_err().1.contains("<axis>"));
    }
}
