//! The package index xacro asks for `$(find PKG)`: a module named
//! `ament_index_python` (`ament_index_python.py` beside this file) in a
//! scratch directory put first on xacro's `PYTHONPATH`, answering from the
//! packages the harness finds, and noting every package it is asked for
//! and does not know.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The resolver module's source.
const MODULE: &str = include_str!("ament_index_python.py");

/// One absent package and the files that asked for it.
#[derive(Debug, Clone, PartialEq)]
pub struct Absent {
    /// The package name.
    pub package: String,
    /// The files xacro was reading when it asked, in order, each once.
    pub files: Vec<PathBuf>,
}

/// The scratch directory of one expansion (removed when dropped).
pub struct Resolver {
    dir: tempfile::TempDir,
}

impl Resolver {
    /// Write the module and the package map `known`.
    pub fn write(known: &BTreeMap<String, PathBuf>) -> std::io::Result<Resolver> {
        let dir = tempfile::Builder::new()
            .prefix("anholonomy-xacro-")
            .tempdir()?;
        let pkg = dir.path().join("ament_index_python");
        std::fs::create_dir(&pkg)?;
        std::fs::write(pkg.join("packages.py"), MODULE)?;
        std::fs::write(pkg.join("__init__.py"), "from .packages import *  # noqa\n")?;
        let mut map = String::new();
        for (name, d) in known {
            let d = std::path::absolute(d).unwrap_or_else(|_| d.clone());
            let d = d.to_string_lossy();
            // A name or path that would break the line format is no package.
            if !format!("{name}{d}").contains(['\t', '\n', '\r']) {
                map.push_str(&format!("{name}\t{d}\n"));
            }
        }
        std::fs::write(dir.path().join("packages.tsv"), map)?;
        std::fs::write(dir.path().join("absent.tsv"), "")?;
        Ok(Resolver { dir })
    }

    /// Point `cmd` (xacro) at the module and the map.
    pub fn configure(&self, cmd: &mut Command) {
        let mut paths = vec![self.dir.path().to_path_buf()];
        if let Some(old) = std::env::var_os("PYTHONPATH") {
            paths.extend(std::env::split_paths(&old));
        }
        if let Ok(joined) = std::env::join_paths(paths) {
            cmd.env("PYTHONPATH", joined);
        }
        cmd.env(
            "ANHOLONOMY_XACRO_PACKAGES",
            self.dir.path().join("packages.tsv"),
        )
        .env(
            "ANHOLONOMY_XACRO_ABSENT",
            self.dir.path().join("absent.tsv"),
        );
    }

    /// The packages xacro asked for and did not get, in the order asked.
    pub fn absent(&self) -> Vec<Absent> {
        let text = std::fs::read_to_string(self.dir.path().join("absent.tsv")).unwrap_or_default();
        let mut out: Vec<Absent> = Vec::new();
        for line in text.lines() {
            let (package, file) = line.split_once('\t').unwrap_or((line, ""));
            let i = match out.iter().position(|a| a.package == package) {
                Some(i) => i,
                None => {
                    out.push(Absent {
                        package: package.to_string(),
                        files: Vec::new(),
                    });
                    out.len() - 1
                }
            };
            let file = PathBuf::from(file);
            if !file.as_os_str().is_empty() && !out[i].files.contains(&file) {
                out[i].files.push(file);
            }
        }
        out
    }
}

/// `file` as the user knows it: relative to the directory of `urdf` when
/// it is in there.
fn shown(file: &Path, urdf: &Path) -> String {
    let base = std::path::absolute(urdf)
        .ok()
        .and_then(|u| u.parent().map(Path::to_path_buf));
    base.and_then(|b| file.strip_prefix(b).ok().map(Path::to_path_buf))
        .unwrap_or_else(|| file.to_path_buf())
        .display()
        .to_string()
}

/// `` `pkg` (in a.xacro, b.xacro), ... ``.
pub(crate) fn absent_list(absent: &[Absent], urdf: &Path) -> String {
    let items: Vec<String> = absent
        .iter()
        .map(|a| {
            let files: Vec<String> = a.files.iter().map(|f| shown(f, urdf)).collect();
            if files.is_empty() {
                format!("`{}`", a.package)
            } else {
                format!("`{}` (in {})", a.package, files.join(", "))
            }
        })
        .collect();
    items.join(", ")
}

/// The message naming every absent package at once.
pub(crate) fn absent_error(absent: &[Absent], urdf: &Path) -> String {
    let n = absent.len();
    let first = absent.first().map_or("PKG", |a| a.package.as_str());
    format!(
        "xacro needs {} ROS package{} not found in [model] packages, the package.xml above the URDF, ROS_PACKAGE_PATH or AMENT_PREFIX_PATH: {}: name {} directories in [model] packages = {{ {first} = \"DIR\" }}, or expand their includes to nothing with [model] missing_packages = \"empty\"",
        n,
        if n == 1 { "" } else { "s" },
        absent_list(absent, urdf),
        if n == 1 { "its" } else { "their" },
    )
}
