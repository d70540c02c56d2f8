//! URDF checks of the validation pass: the file kind and size, the structure
//! ([`crate::engine::urdf::read`]: links, joints, a tree, positive masses)
//! and every number the physics will use: finite positive masses,
//! positive-definite inertias, finite origins, axes, limits and geometry.
//! A NaN or negative inertia would otherwise be accepted (a wheel that never
//! turns) and a NaN origin reported as a diverged simulation.
//!
//! Errors name the URDF file, the line of the element (located in the text:
//! urdf-rs keeps no positions) and the link or joint.

use crate::error::{About, Error, SetupError};
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

pub use crate::engine::urdf::Source;

/// A URDF as the physics takes it: parsed, checked, its mesh file names
/// resolved to files that load, with what the user should know.
#[derive(Debug, Clone)]
pub struct Loaded {
    /// The robot (mesh `filename`s are the resolved paths; visuals whose
    /// mesh is missing are dropped).
    pub robot: Robot,
    /// Visual meshes left out.
    pub warnings: Vec<String>,
    /// What was done to the file (xacro expanded).
    pub notes: Vec<String>,
}

/// Read, parse and check a URDF with the default [`Source`]: the first problem.
pub fn load(path: &Path) -> Result<Robot, Error> {
    load_from(path, &Source::default())
        .map(|l| l.robot)
        .map_err(|mut e| e.swap_remove(0))
}

/// Read, parse and check a URDF (expanding xacro, resolving meshes): every
/// problem at once, one error per problem, each with the line of the
/// element it names.
pub(crate) fn load_from(path: &Path, source: &Source) -> Result<Loaded, Vec<Error>> {
    let one = |line: Option<usize>, m: String| {
        vec![Error::Input {
            key: None,
            path: path.into(),
            line,
            message: m,
        }]
    };
    let mut text = read_text(path, "URDF", URDF_MAX_BYTES).map_err(|e| vec![e])?;
    let mut warnings = Vec::new();
    let mut notes = Vec::new();
    // Lines point into the file only when the file is what was parsed.
    let mut lines = true;
    use crate::validate::xacro::Markup;
    let search = crate::engine::mesh::Search::for_urdf(source.packages.clone(), path);
    let why = match crate::validate::xacro::markup(&text) {
        Some(Markup::Needed(why)) => Some(why),
        // Plain URDF under the namespace: expanded only where xacro is at hand.
        Some(Markup::Namespace) if crate::validate::xacro::available() => {
            Some("the xacro namespace")
        }
        _ => None,
    };
    if let Some(why) = why {
        let expanded = crate::validate::xacro::expand(path, why, source, &search)
            .map_err(|e| one(None, e.to_string()))?;
        text = expanded.text;
        notes.push(format!(
            "expanded with xacro ({why}); lines in messages are those of the expansion"
        ));
        if !expanded.absent.is_empty() {
            warnings.push(crate::validate::xacro::absent_warning(
                &expanded.absent,
                path,
            ));
        }
        lines = false;
    }
    let line_of = |e: &SetupError| lines.then(|| line_of_error(&text, e)).flatten();
    let mut robot =
        crate::engine::urdf::parse_text(&text).map_err(|e| one(line_of(&e), e.to_string()))?;
    let mut errors: Vec<Error> = Vec::new();
    let mut push = |line: Option<usize>, m: String| {
        errors.push(Error::Input {
            key: None,
            path: path.into(),
            line,
            message: m,
        })
    };
    let structure = crate::engine::urdf::structure_problems(&robot);
    if !structure.is_empty() {
        for e in structure {
            push(line_of(&e), e.to_string());
        }
        return Err(errors);
    }
    // Numbers before the loader's own checks: their errors name the element.
    let numbers = number_problems(&robot);
    let bad_numbers = !numbers.is_empty();
    for (place, m) in numbers {
        push(lines.then(|| locate(&text, &place)).flatten(), m);
    }
    if !bad_numbers {
        // Masses are numbers now: which bodies lack one.
        if let Err(e) = crate::engine::lump::lump(&robot, &[]) {
            push(line_of(&e), e.to_string());
        }
        for e in crate::engine::urdf::loadable_problems(&robot) {
            push(line_of(&e), e.to_string());
        }
    }
    let dir = path.parent().unwrap_or(Path::new("."));
    for (place, m, fatal) in resolve_meshes(&mut robot, dir, &search) {
        let line = lines.then(|| locate(&text, &place)).flatten();
        if fatal {
            push(line, m);
        } else {
            warnings.push(m);
        }
    }
    if errors.is_empty() {
        Ok(Loaded {
            robot,
            warnings,
            notes,
        })
    } else {
        Err(errors)
    }
}

/// Resolve and load every mesh of `robot`, rewriting each `filename` to the
/// file found. A collision mesh that cannot be had is a problem (`true`); a
/// visual one is a warning (`false`) and the visual is dropped.
fn resolve_meshes(
    robot: &mut Robot,
    urdf_dir: &Path,
    search: &crate::engine::mesh::Search,
) -> Vec<(Place, String, bool)> {
    use crate::engine::mesh;
    let mut out = Vec::new();
    for l in &mut robot.links {
        let name = l.name.clone();
        type Loaded = Option<std::sync::Arc<mesh::TriMesh>>;
        let fix = |g: &mut Geometry, tag: String, what: &str| -> Result<Loaded, (Place, String)> {
            let Geometry::Mesh { filename, scale } = g else {
                return Ok(None);
            };
            let at = Place::new("link", &name, &[&tag, "geometry", "mesh"]);
            let file = search
                .resolve(filename, urdf_dir)
                .map_err(|m| (at.clone(), format!("URDF link `{name}` {what} mesh: {m}")))?;
            let m = mesh::load(&file, mesh::scale_of(scale))
                .map_err(|m| (at.clone(), format!("URDF link `{name}` {what} mesh: {m}")))?;
            *filename = file.to_string_lossy().into_owned();
            Ok(Some(m))
        };
        for (k, c) in l.collision.iter_mut().enumerate() {
            match fix(&mut c.geometry, format!("collision#{k}"), "collision") {
                Err((place, m)) => out.push((place, m, true)),
                Ok(Some(m)) => {
                    if let (_, Some(t)) = crate::engine::mesh_limits::hull_with(&m) {
                        let at = Place::new("link", &name, &[&format!("collision#{k}")]);
                        out.push((at, thinned(&name, &m, &t), false));
                    }
                }
                Ok(None) => {}
            }
        }
        let mut keep = Vec::new();
        for (k, mut v) in std::mem::take(&mut l.visual).into_iter().enumerate() {
            match fix(&mut v.geometry, format!("visual#{k}"), "visual") {
                Ok(_) => keep.push(v),
                Err((place, m)) => {
                    out.push((place, format!("{m}: drawn without it"), false));
                }
            }
        }
        l.visual = keep;
    }
    out
}

/// The warning for a collision mesh thinned for its hull.
fn thinned(
    link: &str,
    m: &crate::record::TriMesh,
    t: &crate::engine::mesh_limits::Thinned,
) -> String {
    use crate::numfmt::readable;
    format!(
        "URDF link `{link}` collision mesh: {} triangles, over the budget of {} for a collision hull: its hull is built from {} of its {} points (one per {} mm grid cell), within {} mm of the exact hull",
        m.triangles.len(),
        crate::engine::mesh_limits::HULL_TRIANGLES,
        t.kept,
        t.of,
        readable(t.within / 3f64.sqrt() * 1e3),
        readable(t.within * 1e3)
    )
}

/// A URDF refusal of the physics about the file at `path`, with the line of
/// the element it is about.
pub(crate) fn error_in(path: &Path, e: &SetupError) -> Error {
    let text = read_text(path, "URDF", URDF_MAX_BYTES).unwrap_or_default();
    Error::Input {
        key: None,
        path: path.into(),
        line: line_of_error(&text, e),
        message: e.to_string(),
    }
}

/// The line of the URDF element a refusal is about, if it is in the text.
pub(crate) fn line_of_error(text: &str, e: &SetupError) -> Option<usize> {
    match &e.about {
        About::Urdf(Some((elem, name))) => locate(text, &Place::new(elem, name, &[])),
        _ => None,
    }
}

use crate::engine::urdf_text::numbers;
use crate::numfmt::shortest;

fn finite<const N: usize>(v: &[f64; N]) -> bool {
    v.iter().all(|x| x.is_finite())
}

fn check_pose(p: &Pose, place: &Place, what: &str) -> Result<(), (Place, String)> {
    if !finite(&p.xyz.0) || !finite(&p.rpy.0) {
        return Err((
            place.clone(),
            format!(
                "{what} <origin> needs finite xyz and rpy, got xyz=\"{}\" rpy=\"{}\"",
                numbers(&p.xyz.0),
                numbers(&p.rpy.0)
            ),
        ));
    }
    Ok(())
}

use crate::engine::urdf::shape_tag;

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
            format!(
                "{what} <geometry> needs finite sizes > 0, got {}",
                crate::engine::urdf_text::geometry(g)
            ),
        ))
    }
}

/// Every number the physics uses, checked; the first problem, saying where.
pub fn check_numbers(robot: &Robot) -> Result<(), (Place, String)> {
    match number_problems(robot).into_iter().next() {
        Some(p) => Err(p),
        None => Ok(()),
    }
}

/// Every problem with the numbers the physics uses, each saying where.
pub(crate) fn number_problems(robot: &Robot) -> Vec<(Place, String)> {
    let mut out = Vec::new();
    // Each check returns its first problem; `?` inside a closure per element
    // keeps the checks as they read, and every element is still checked.
    let mut each = |r: Result<(), (Place, String)>| {
        if let Err(p) = r {
            out.push(p);
        }
    };
    let colour_ok = |c: &urdf_rs::Color| c.rgba.0.iter().all(|x| (0.0..=1.0).contains(x));
    for m in &robot.materials {
        if let Some(c) = m.color.as_ref().filter(|c| !colour_ok(c)) {
            each(Err((
                Place::new("material", &m.name, &["color"]),
                format!(
                    "URDF material `{}` <color> rgba must be in [0, 1], got rgba=\"{}\"",
                    m.name,
                    numbers(&c.rgba.0)
                ),
            )));
        }
    }
    for l in &robot.links {
        each((|| {
            let n = &l.name;
            let at = |inner: &[&str]| Place::new("link", n, inner);
            let m = l.inertial.mass.value;
            if !(m.is_finite() && m >= 0.0) {
                return Err((
                    at(&["inertial", "mass"]),
                    format!("URDF link `{n}` <mass> must be finite and ≥ 0 (0: a frame), got value=\"{}\"", shortest(m)),
                ));
            }
            let i = &l.inertial.inertia;
            let t = Matrix3::new(
                i.ixx, i.ixy, i.ixz, i.ixy, i.iyy, i.iyz, i.ixz, i.iyz, i.izz,
            );
            // A frame's inertia is ignored (it is lumped: crate::engine::lump).
            let frame = m == 0.0;
            if !frame && (!t.iter().all(|x| x.is_finite()) || t.cholesky().is_none()) {
                return Err((
                at(&["inertial", "inertia"]),
                format!(
                    "URDF link `{n}` <inertia> must be finite and positive definite, got ixx=\"{}\" ixy=\"{}\" ixz=\"{}\" iyy=\"{}\" iyz=\"{}\" izz=\"{}\"",
                    shortest(i.ixx), shortest(i.ixy), shortest(i.ixz), shortest(i.iyy), shortest(i.iyz), shortest(i.izz)
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
                            format!(
                                "{what} <color> rgba must be in [0, 1], got rgba=\"{}\"",
                                numbers(&c.rgba.0)
                            ),
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
            Ok(())
        })());
    }
    for j in &robot.joints {
        each((|| {
            let n = &j.name;
            let at = |inner: &[&str]| Place::new("joint", n, inner);
            check_pose(&j.origin, &at(&["origin"]), &format!("URDF joint `{n}`"))?;
            let moves = !matches!(j.joint_type, JointType::Fixed | JointType::Floating);
            let a = j.axis.xyz.0;
            if moves && !(finite(&a) && a.iter().any(|x| *x != 0.0)) {
                return Err((
                    at(&["axis"]),
                    format!(
                        "URDF joint `{n}` <axis> must be finite and non-zero, got xyz=\"{}\"",
                        numbers(&a)
                    ),
                ));
            }
            let lim = &j.limit;
            if matches!(j.joint_type, JointType::Revolute | JointType::Prismatic) {
                let vals = [lim.lower, lim.upper, lim.effort, lim.velocity];
                if !finite(&vals) || lim.lower > lim.upper || lim.effort < 0.0 || lim.velocity < 0.0
                {
                    return Err((
                    at(&["limit"]),
                    format!(
                        "URDF joint `{n}` <limit> needs finite lower ≤ upper and effort, velocity ≥ 0, got lower=\"{}\" upper=\"{}\" effort=\"{}\" velocity=\"{}\"",
                        shortest(lim.lower), shortest(lim.upper), shortest(lim.effort), shortest(lim.velocity)
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
                        "URDF joint `{n}` <dynamics> needs finite damping, friction ≥ 0, got damping=\"{}\" friction=\"{}\"",
                        shortest(d.damping), shortest(d.friction)
                    ),
                ));
                }
            }
            Ok(())
        })());
    }
    out
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
pub(crate) fn locate(text: &str, place: &Place) -> Option<usize> {
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
        let e = SetupError::urdf_at("joint", "j", "URDF joint `j` names unknown link `ghost`");
        assert_eq!(line_of_error(URDF, &e), Some(17));
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
