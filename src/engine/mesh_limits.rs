//! What a mesh file may cost: a binary STL's triangle count must agree with
//! its size, and a collision mesh above [`HULL_TRIANGLES`] triangles is
//! thinned before its convex hull is built.
//!
//! The hull of a mesh of n points takes time that grows faster than n (a
//! sphere of 100 000 triangles: 2.1 s; of 300 000: 37 s and 0.45 GB;
//! measured with `/usr/bin/time -v` on `anholonomy list`, 2 shared cores).
//! Above the budget the points are binned on a grid just fine enough to keep
//! at most [`HULL_POINTS`] of them, one per occupied cell: the one farthest
//! from the mesh's centre. Every vertex of the exact hull then lies within
//! one cell diagonal of a kept point, so the collision hull is within that
//! distance of the exact one (the validation pass's warning states it).

use crate::record::TriMesh;
use std::collections::HashMap;
use std::io::Read as _;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, OnceLock};

/// Most triangles of a collision mesh whose hull is built from every vertex.
pub const HULL_TRIANGLES: usize = 20_000;

/// Most points a thinned collision mesh keeps.
pub const HULL_POINTS: usize = 5_000;

/// A binary STL file that cannot hold what its header says, or cannot be read.
#[derive(Debug, thiserror::Error)]
pub enum StlSizeError {
    /// Opening or reading the file failed.
    #[error("{}: {source}", crate::echo::path(path))]
    Io {
        /// The file.
        path: PathBuf,
        /// The system's error.
        source: std::io::Error,
    },
    /// Shorter than a binary STL's header and count.
    #[error(
        "{}: {len} bytes: too short for a binary STL (84 bytes of header and triangle count)",
        crate::echo::path(path)
    )]
    TooShort {
        /// The file.
        path: PathBuf,
        /// Its size, bytes.
        len: u64,
    },
    /// The header's triangle count does not fit the file's size.
    #[error(
        "{}: binary STL whose header counts {count} triangles ({want} bytes), but the file has {len} bytes (room for {} triangles): a cut or damaged file",
        crate::echo::path(path),
        len.saturating_sub(84) / 50
    )]
    Count {
        /// The file.
        path: PathBuf,
        /// Triangles the header counts.
        count: u32,
        /// Bytes that count needs.
        want: u64,
        /// Bytes the file has.
        len: u64,
    },
}

/// A binary STL whose header counts other triangles than its size holds
/// (84 bytes of header and count, 50 bytes per triangle; a trailing newline
/// is tolerated, as `mesh-loader` does). ASCII STL (`solid ...` in text)
/// has no count.
pub(crate) fn check_stl_size(path: &Path) -> Result<(), StlSizeError> {
    let io = |source: std::io::Error| StlSizeError::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut f = std::fs::File::open(path).map_err(io)?;
    let len = f.metadata().map_err(io)?.len();
    let mut head = Vec::with_capacity(84);
    f.by_ref().take(84).read_to_end(&mut head).map_err(io)?;
    let text = head.trim_ascii_start();
    if text.starts_with(b"solid")
        && head
            .iter()
            .all(|b| b.is_ascii_graphic() || b.is_ascii_whitespace())
    {
        return Ok(());
    }
    if head.len() < 84 {
        return Err(StlSizeError::TooShort {
            path: path.to_path_buf(),
            len,
        });
    }
    let count = u32::from_le_bytes([head[80], head[81], head[82], head[83]]);
    let want = 84 + 50 * u64::from(count);
    if len == want || len == want + 1 || len == want + 2 {
        return Ok(());
    }
    Err(StlSizeError::Count {
        path: path.to_path_buf(),
        count,
        want,
        len,
    })
}

/// A collision mesh thinned for its hull: how many points it kept of how
/// many, and the grid cell's diagonal (the most the hull may lose), m.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Thinned {
    /// Points kept.
    pub kept: usize,
    /// The mesh's vertices.
    pub of: usize,
    /// Grid cell diagonal, m.
    pub within: f64,
}

/// The points a collision hull of `mesh` is built from: every vertex up to
/// [`HULL_TRIANGLES`] triangles, else one per occupied grid cell (see the
/// module docs), and how it was thinned.
pub fn hull_points(mesh: &TriMesh) -> (Vec<[f64; 3]>, Option<Thinned>) {
    let v = &mesh.vertices;
    if mesh.triangles.len() <= HULL_TRIANGLES || v.len() <= HULL_POINTS {
        return (v.clone(), None);
    }
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for p in v {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let centre: [f64; 3] = std::array::from_fn(|k| 0.5 * (lo[k] + hi[k]));
    let size = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max).max(1e-12);
    // A surface of g² cells per face: start near the budget, coarsen until it fits.
    let mut cells_per_side = ((HULL_POINTS as f64 / 6.0).sqrt() * 2.0).ceil();
    loop {
        let cell = size / cells_per_side;
        let mut best: HashMap<[i64; 3], (f64, usize)> = HashMap::new();
        for (i, p) in v.iter().enumerate() {
            let key = std::array::from_fn(|k| ((p[k] - lo[k]) / cell).floor() as i64);
            let d: f64 = (0..3).map(|k| (p[k] - centre[k]).powi(2)).sum();
            let e = best.entry(key).or_insert((d, i));
            // Ties keep the lower index: the same points on every run.
            if d > e.0 {
                *e = (d, i);
            }
        }
        if best.len() <= HULL_POINTS || cells_per_side <= 2.0 {
            let mut keep: Vec<usize> = best.into_values().map(|(_, i)| i).collect();
            keep.sort_unstable();
            let kept: Vec<[f64; 3]> = keep.iter().map(|&i| v[i]).collect();
            let t = Thinned {
                kept: kept.len(),
                of: v.len(),
                within: cell * 3f64.sqrt(),
            };
            return (kept, Some(t));
        }
        cells_per_side = (cells_per_side * 0.8).floor();
    }
}

type HullCache = Mutex<HashMap<usize, (Arc<TriMesh>, Hull)>>;
type Hull = (
    Option<crate::engine::rapier::prelude::SharedShape>,
    Option<Thinned>,
);

/// The convex hull collider of a loaded collision mesh (from
/// [`hull_points`]), built once per mesh for the process: the validation
/// pass, the start placement and the physics ask for it again.
pub fn hull(mesh: &Arc<TriMesh>) -> Option<crate::engine::rapier::prelude::SharedShape> {
    hull_with(mesh).0
}

/// [`hull`], and how the mesh was thinned for it.
pub(crate) fn hull_with(mesh: &Arc<TriMesh>) -> Hull {
    use crate::engine::rapier::prelude::SharedShape;
    static CACHE: OnceLock<HullCache> = OnceLock::new();
    let cache = CACHE.get_or_init(Default::default);
    // Keyed by the mesh's address; the entry holds the mesh, so the
    // address is not reused while it is cached.
    let key = Arc::as_ptr(mesh) as usize;
    if let Some((_, h)) = cache.lock().ok().and_then(|c| c.get(&key).cloned()) {
        return h;
    }
    let (points, thinned) = hull_points(mesh);
    let points: Vec<_> = points
        .iter()
        .map(|p| crate::engine::real::vector(p[0], p[1], p[2]))
        .collect();
    let h = (SharedShape::convex_hull(&points), thinned);
    if let Ok(mut c) = cache.lock() {
        c.insert(key, (mesh.clone(), h.clone()));
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sphere(n: usize) -> TriMesh {
        let mut vertices = Vec::new();
        let mut triangles = Vec::new();
        for i in 0..n {
            for j in 0..2 * n {
                let (th, ph) = (
                    std::f64::consts::PI * (i as f64 + 0.5) / n as f64,
                    std::f64::consts::PI * j as f64 / n as f64,
                );
                vertices.push([th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos()]);
            }
        }
        let m = vertices.len() as u32;
        for k in 0..m {
            triangles.push([k, (k + 1) % m, (k + 2) % m]);
        }
        TriMesh {
            vertices,
            triangles,
        }
    }

    #[test]
    fn a_big_collision_mesh_is_thinned_within_the_stated_distance() {
        let small = sphere(100);
        assert_eq!(hull_points(&small).0.len(), small.vertices.len());
        let big = sphere(400); // 320 000 points on the unit sphere
        let (kept, thin) = hull_points(&big);
        let thin = thin.expect("over the budget");
        assert!(
            kept.len() <= HULL_POINTS && kept.len() == thin.kept,
            "{thin:?}"
        );
        // At most 5 000 points on a sphere of radius 1: cells of about 7 cm.
        assert!(thin.within < 0.15, "{thin:?}");
        // Every point of the sphere is within `within` of a kept point (so
        // of the thinned hull): checked on a sample.
        for p in big.vertices.iter().step_by(997) {
            let d = kept
                .iter()
                .map(|q| (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>())
                .fold(f64::INFINITY, f64::min)
                .sqrt();
            assert!(d <= thin.within, "{d} > {}", thin.within);
        }
        // The same points on every call.
        assert_eq!(hull_points(&big).0, kept);
    }

    #[test]
    fn an_stl_count_that_disagrees_with_the_size_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("m.stl");
        let mut bin = vec![0u8; 80];
        bin.extend(4_000_000_000u32.to_le_bytes());
        bin.extend([0u8; 100]);
        std::fs::write(&p, &bin).unwrap();
        let e = check_stl_size(&p).unwrap_err().to_string();
        assert!(e.contains("counts 4000000000 triangles"), "{e}");
        assert!(e.contains("the file has 184 bytes"), "{e}");
        bin[80..84].copy_from_slice(&2u32.to_le_bytes());
        std::fs::write(&p, &bin).unwrap();
        assert!(check_stl_size(&p).is_ok());
        std::fs::write(&p, "solid x\nfacet normal 0 0 1\n").unwrap();
        assert!(check_stl_size(&p).is_ok());
    }
}
