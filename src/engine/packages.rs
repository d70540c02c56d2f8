//! The ROS packages a robot description names (`package://PKG/...` meshes,
//! xacro's `$(find PKG)`), found without ROS: the scenario's `[model]
//! packages`, the package the URDF itself is in (the `package.xml` in its
//! directory or the nearest one above it), then `ROS_PACKAGE_PATH` and
//! `AMENT_PREFIX_PATH` ([`crate::engine::mesh::Search`]). The same map
//! answers the meshes and xacro, so both see the same packages.

use std::path::{Path, PathBuf};

/// What xacro does with an include of a package that is not found.
#[derive(
    Debug,
    Clone,
    Copy,
    Default,
    PartialEq,
    Eq,
    serde::Deserialize,
    serde::Serialize,
    schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum MissingPackages {
    /// Refuse the description, naming every absent package and the file
    /// that includes it.
    #[default]
    Error,
    /// Expand each include of an absent package to nothing (and warn once,
    /// naming them): for accessories a description includes whether or not
    /// they are switched on.
    Empty,
}

impl MissingPackages {
    /// The name as written in scenario files.
    pub fn name(self) -> &'static str {
        match self {
            MissingPackages::Error => "error",
            MissingPackages::Empty => "empty",
        }
    }
}

/// Where xacro's `$(find PKG)` points for an absent package: a directory
/// that does not exist, the package's name in brackets. xacro reads an
/// include file name holding `[` as a pattern, and an include whose
/// pattern matches no file expands to nothing (with a warning), so one
/// expansion meets every absent package instead of stopping at the first.
pub const ABSENT_ROOT: &str = "/anholonomy-absent-package";

/// The absent package a path under [`ABSENT_ROOT`] names.
pub(crate) fn absent_package(path: &str) -> Option<&str> {
    let rest = path.strip_prefix(ABSENT_ROOT)?.strip_prefix("/[")?;
    rest.split_once(']').map(|(pkg, _)| pkg)
}

/// Largest `package.xml` read, bytes.
const PACKAGE_XML_MAX: u64 = 1 << 20;

/// The `<name>` of the ROS package manifest at `path`, if it has one.
pub(crate) fn manifest_name(path: &Path) -> Option<String> {
    use quick_xml::events::Event;
    use std::io::Read;
    let mut text = String::new();
    std::fs::File::open(path)
        .ok()?
        .take(PACKAGE_XML_MAX)
        .read_to_string(&mut text)
        .ok()?;
    let mut reader = quick_xml::Reader::from_str(&text);
    let mut path: Vec<Vec<u8>> = Vec::new();
    loop {
        match reader.read_event().ok()? {
            Event::Start(e) => path.push(e.name().as_ref().to_vec()),
            Event::End(_) => {
                path.pop();
            }
            Event::Text(t) if path == [b"package".to_vec(), b"name".to_vec()] => {
                let name = String::from_utf8_lossy(&t).trim().to_string();
                return (!name.is_empty()).then_some(name);
            }
            Event::Eof => return None,
            _ => {}
        }
    }
}

/// The package the file at `urdf` belongs to: the `package.xml` in its
/// directory, or the nearest one above it, with its name.
pub(crate) fn own_package(urdf: &Path) -> Option<(String, PathBuf)> {
    let abs = std::path::absolute(urdf).ok()?;
    let mut dir = abs.parent();
    while let Some(d) = dir {
        let manifest = d.join("package.xml");
        if manifest.is_file() {
            return manifest_name(&manifest).map(|n| (n, d.to_path_buf()));
        }
        dir = d.parent();
    }
    None
}

/// The subdirectories of `dir` by name (none when it cannot be read),
/// sorted.
pub(crate) fn subdirectories(dir: &Path) -> Vec<(String, PathBuf)> {
    let mut out: Vec<(String, PathBuf)> = std::fs::read_dir(dir)
        .map(|rd| {
            rd.flatten()
                .filter(|e| e.path().is_dir())
                .filter_map(|e| Some((e.file_name().into_string().ok()?, e.path())))
                .collect()
        })
        .unwrap_or_default();
    out.sort();
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_manifest_names_the_package_above_the_urdf() {
        let dir = tempfile::tempdir().unwrap();
        let pkg = dir.path().join("src/my_robot_description");
        std::fs::create_dir_all(pkg.join("urdf/parts")).unwrap();
        std::fs::write(
            pkg.join("package.xml"),
            "<?xml version=\"1.0\"?>\n<package format=\"3\">\n  <!-- <name>not this</name> -->\n  <name> my_robot_description </name>\n  <depend>urdf</depend>\n</package>\n",
        )
        .unwrap();
        let urdf = pkg.join("urdf/parts/robot.urdf.xacro");
        let (name, at) = own_package(&urdf).unwrap();
        assert_eq!(name, "my_robot_description");
        assert_eq!(at, pkg);
        // Beside the URDF.
        assert_eq!(own_package(&pkg.join("robot.urdf")).unwrap().1, pkg);
        // A manifest without a name names nothing.
        std::fs::write(pkg.join("package.xml"), "<package/>").unwrap();
        assert!(own_package(&urdf).is_none());
    }
}
