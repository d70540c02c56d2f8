//! Meshes named by URDF `<mesh filename=...>`: where they are found and
//! what they hold.
//!
//! Robot descriptions name meshes as `package://PKG/path` (a ROS package),
//! `file:///abs/path`, or a path relative to the URDF. A package is looked
//! up in the scenario's `[model] packages` table (directories relative to
//! the scenario), then the URDF's own package (the nearest `package.xml`
//! above it names it), then `ROS_PACKAGE_PATH` (an entry is the package
//! itself, or holds it), then `AMENT_PREFIX_PATH` (`PREFIX/share/PKG`). STL, OBJ and
//! Collada files are read by `mesh-loader` (the loader urdf-viz uses); every
//! submesh of a file is merged, and the URDF's `scale` applied.
//!
//! Loaded meshes are kept for the process (by path), so the validation pass,
//! the physics (collision meshes become convex hulls) and the logs (visual
//! meshes are drawn) read each file once.

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, OnceLock};

pub use crate::record::TriMesh;

/// The file extensions read, lower case.
pub const FORMATS: [&str; 3] = ["stl", "obj", "dae"];

/// Where meshes are searched besides the URDF's directory: the scenario's
/// `[model] packages` (package name → directory, absolute or relative to
/// the current directory) and the environment's package paths.
#[derive(Debug, Clone, Default)]
pub struct Search {
    /// Package directories by name, from the scenario.
    pub packages: BTreeMap<String, PathBuf>,
    /// The package the URDF is in (its `package.xml`'s name, its directory).
    pub own: Option<(String, PathBuf)>,
    /// `ROS_PACKAGE_PATH` entries.
    pub ros_package_path: Vec<PathBuf>,
    /// `AMENT_PREFIX_PATH` entries.
    pub ament_prefix_path: Vec<PathBuf>,
}

impl Search {
    /// The scenario's packages and the process environment's paths.
    pub fn from_env(packages: BTreeMap<String, PathBuf>) -> Search {
        let split = |var: &str| -> Vec<PathBuf> {
            std::env::var_os(var)
                .map(|v| {
                    std::env::split_paths(&v)
                        .filter(|p| !p.as_os_str().is_empty())
                        .collect()
                })
                .unwrap_or_default()
        };
        Search {
            packages,
            own: None,
            ros_package_path: split("ROS_PACKAGE_PATH"),
            ament_prefix_path: split("AMENT_PREFIX_PATH"),
        }
    }

    /// [`Search::from_env`] for the URDF at `urdf`, which also finds the
    /// package it is in.
    pub fn for_urdf(packages: BTreeMap<String, PathBuf>, urdf: &Path) -> Search {
        Search {
            own: crate::engine::packages::own_package(urdf),
            ..Search::from_env(packages)
        }
    }

    /// Every package this search finds, by name, each at the directory
    /// [`Search::package`] gives it: the scenario's, the URDF's own, the
    /// subdirectories (and the entry itself) of each `ROS_PACKAGE_PATH`
    /// entry, each `AMENT_PREFIX_PATH` entry's `share/*`.
    pub fn known(&self) -> BTreeMap<String, PathBuf> {
        use crate::engine::packages::subdirectories;
        let mut out = BTreeMap::new();
        let mut add = |name: &str, dir: &Path| {
            if dir.is_dir() {
                out.entry(name.to_string())
                    .or_insert_with(|| dir.to_path_buf());
            }
        };
        for (name, dir) in &self.packages {
            add(name, dir);
        }
        if let Some((name, dir)) = &self.own {
            add(name, dir);
        }
        for e in &self.ros_package_path {
            for (name, dir) in subdirectories(e) {
                add(&name, &dir);
            }
            if let Some(name) = e.file_name().and_then(|n| n.to_str()) {
                add(name, e);
            }
        }
        for e in &self.ament_prefix_path {
            for (name, dir) in subdirectories(&e.join("share")) {
                add(&name, &dir);
            }
        }
        out
    }

    /// The directory of package `pkg`: the scenario's entry, then a
    /// `ROS_PACKAGE_PATH` entry that holds it or is it, then
    /// `AMENT_PREFIX_PATH`'s `share/PKG`; the first that exists.
    pub fn package(&self, pkg: &str) -> Option<PathBuf> {
        let mut candidates: Vec<PathBuf> = self.packages.get(pkg).cloned().into_iter().collect();
        if let Some((name, dir)) = &self.own {
            if name == pkg {
                candidates.push(dir.clone());
            }
        }
        for e in &self.ros_package_path {
            candidates.push(e.join(pkg));
            if e.file_name().is_some_and(|n| n == pkg) {
                candidates.push(e.clone());
            }
        }
        candidates.extend(
            self.ament_prefix_path
                .iter()
                .map(|e| e.join("share").join(pkg)),
        );
        candidates.into_iter().find(|d| d.is_dir())
    }

    /// The file a URDF mesh `filename` names, for a URDF in `urdf_dir`; the
    /// error says where it looked.
    pub fn resolve(&self, filename: &str, urdf_dir: &Path) -> Result<PathBuf, MeshError> {
        if let Some(rest) = filename.strip_prefix("package://") {
            let (pkg, rel) = rest.split_once('/').unwrap_or((rest, ""));
            let dir = self.package(pkg).ok_or_else(|| {
                let tried: Vec<&str> = [
                    ("[model] packages", !self.packages.is_empty()),
                    ("ROS_PACKAGE_PATH", !self.ros_package_path.is_empty()),
                    ("AMENT_PREFIX_PATH", !self.ament_prefix_path.is_empty()),
                ]
                .iter()
                .filter(|(_, set)| *set)
                .map(|(name, _)| *name)
                .collect();
                let looked = if let Some(d) = self.packages.get(pkg) {
                    format!(
                        "[model] packages sets it to {}, which is not a directory",
                        crate::echo::code(&crate::echo::path(d))
                    )
                } else if tried.is_empty() {
                    "no [model] packages entry, ROS_PACKAGE_PATH or AMENT_PREFIX_PATH names it"
                        .to_string()
                } else {
                    format!("not found through {}", tried.join(", "))
                };
                MeshError::Package {
                    pkg: pkg.to_string(),
                    filename: filename.to_string(),
                    looked,
                }
            })?;
            let path = dir.join(rel);
            return if path.is_file() {
                Ok(path)
            } else {
                Err(MeshError::NotInPackage {
                    filename: filename.to_string(),
                    rel: rel.to_string(),
                    pkg: pkg.to_string(),
                    dir,
                })
            };
        }
        if let Some(pkg) = crate::engine::packages::absent_package(filename) {
            return Err(MeshError::Absent {
                filename: filename.to_string(),
                pkg: pkg.to_string(),
            });
        }
        let path = match filename.strip_prefix("file://") {
            Some(p) => PathBuf::from(p),
            None => urdf_dir.join(filename),
        };
        if path.is_file() {
            Ok(path)
        } else {
            Err(MeshError::NoSuchFile {
                filename: filename.to_string(),
                path,
            })
        }
    }
}

/// Why a URDF mesh cannot be found or loaded (one line).
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// A `package://` URI whose package directory is not known.
    #[error(
        "package `{pkg}` of `{filename}`: {looked} (name its directory in [model] packages = {{ {pkg} = \"DIR\" }})"
    )]
    Package {
        /// The package.
        pkg: String,
        /// The URI as written.
        filename: String,
        /// Where it was looked for.
        looked: String,
    },
    /// The package's directory has no such file.
    #[error("`{filename}`: no file `{rel}` in package `{pkg}` ({})", dir.display())]
    NotInPackage {
        /// The URI as written.
        filename: String,
        /// The path inside the package.
        rel: String,
        /// The package.
        pkg: String,
        /// The package's directory.
        dir: PathBuf,
    },
    /// The file is in a package that xacro expanded as absent.
    #[error(
        "`{filename}` is in package `{pkg}`, which is absent (xacro expanded its `$(find {pkg})` as [model] missing_packages = \"empty\" says): name its directory in [model] packages = {{ {pkg} = \"DIR\" }}"
    )]
    Absent {
        /// The file name as written.
        filename: String,
        /// The absent package.
        pkg: String,
    },
    /// A plain or `file://` name with no file there.
    #[error("`{filename}`: no such file ({})", path.display())]
    NoSuchFile {
        /// The file name as written.
        filename: String,
        /// Where it was looked for.
        path: PathBuf,
    },
    /// The extension is not a mesh format read here.
    #[error("{}: unknown mesh format `.{ext}` (read: STL, OBJ, Collada .dae)", path.display())]
    Format {
        /// The file.
        path: PathBuf,
        /// Its extension, lower case.
        ext: String,
    },
    /// A binary STL cut or damaged, or a file that cannot be read.
    #[error(transparent)]
    StlSize(#[from] crate::engine::mesh_limits::StlSizeError),
    /// The mesh loader refused the file.
    #[error("{}: not a readable mesh: {message}", path.display())]
    Unreadable {
        /// The file.
        path: PathBuf,
        /// The loader's message, on one line.
        message: String,
    },
    /// The file holds no triangles.
    #[error("{}: the mesh has no triangles", path.display())]
    NoTriangles {
        /// The file.
        path: PathBuf,
    },
    /// Vertices that are not finite or faces that index past them.
    #[error("{}: the mesh has non-finite vertices or out-of-range faces", path.display())]
    BadGeometry {
        /// The file.
        path: PathBuf,
    },
}

type Cache = Mutex<HashMap<(PathBuf, [u64; 3]), Arc<TriMesh>>>;

fn cache() -> &'static Cache {
    static CACHE: OnceLock<Cache> = OnceLock::new();
    CACHE.get_or_init(Default::default)
}

/// Load the mesh file at `path` with `scale` (every submesh merged). The
/// error is one line: an unknown format, a file that does not parse, a
/// mesh without triangles.
pub fn load(path: &Path, scale: [f64; 3]) -> Result<Arc<TriMesh>, MeshError> {
    let key = (path.to_path_buf(), scale.map(f64::to_bits));
    if let Some(m) = cache().lock().ok().and_then(|c| c.get(&key).cloned()) {
        return Ok(m);
    }
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_lowercase())
        .unwrap_or_default();
    if !FORMATS.contains(&ext.as_str()) {
        return Err(MeshError::Format {
            path: path.to_path_buf(),
            ext,
        });
    }
    if ext == "stl" {
        crate::engine::mesh_limits::check_stl_size(path)?;
    }
    let scene = mesh_loader::Loader::default()
        .load(path)
        .map_err(|e| MeshError::Unreadable {
            path: path.to_path_buf(),
            message: one_line(&e.to_string()),
        })?;
    let mut out = TriMesh {
        vertices: Vec::new(),
        triangles: Vec::new(),
    };
    for m in &scene.meshes {
        let base = out.vertices.len() as u32;
        out.vertices.extend(
            m.vertices
                .iter()
                .map(|v| [0, 1, 2].map(|k| f64::from(v[k]) * scale[k])),
        );
        out.triangles
            .extend(m.faces.iter().map(|f| f.map(|i| base + i)));
    }
    if out.triangles.is_empty() {
        return Err(MeshError::NoTriangles {
            path: path.to_path_buf(),
        });
    }
    let bad = out.vertices.iter().flatten().any(|x| !x.is_finite())
        || out
            .triangles
            .iter()
            .flatten()
            .any(|&i| i as usize >= out.vertices.len());
    if bad {
        return Err(MeshError::BadGeometry {
            path: path.to_path_buf(),
        });
    }
    let m = Arc::new(out);
    if let Ok(mut c) = cache().lock() {
        c.insert(key, m.clone());
    }
    Ok(m)
}

/// A message on one line.
fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// The URDF `scale` of a mesh (1, 1, 1 when absent).
pub(crate) fn scale_of(scale: &Option<urdf_rs::Vec3>) -> [f64; 3] {
    scale.as_ref().map_or([1.0; 3], |s| s.0)
}
